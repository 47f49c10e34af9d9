//! Components and widgets: signatures (worked out once per module and shared), parameters,
//! arguments checked against them, drawing primitives; binding options and modes.

use super::*;

impl<'a> Typer<'a, '_> {
    /// The component's parameters as (name, type, default), its events, and whether native.
    pub(super) fn signature(
        &mut self,
        module: ModuleId,
        name: &'a str,
    ) -> Option<Rc<Signature<'a>>> {
        if let Some(known) = self.signatures.get(&(module, name)) {
            return known.clone();
        }
        let sig = self.work_out_signature(module, name).map(Rc::new);
        self.signatures.insert((module, name), sig.clone());
        sig
    }

    pub(super) fn work_out_signature(
        &mut self,
        module: ModuleId,
        name: &str,
    ) -> Option<Signature<'a>> {
        if let Some(n) = builtins::native(name) {
            let params = n
                .params
                .iter()
                .map(|(p, t, d)| {
                    let ty = Type::parse_name(t).unwrap_or(Type::DYNAMIC).maybe_absent(*d);
                    (*p, ty, None)
                })
                .collect();
            return Some((params, n.events.to_vec(), true));
        }
        let id = self.defs.find_component(self.modules, module, name)?;
        let c = component_item(self.modules, id)?;
        let (params, events) = self.params(c, id.module, false);
        let names = c.params.iter().filter_map(|p| match p {
            ast::Param::Value { name, .. } => Some(name.name.as_str()),
            ast::Param::Event { .. } => None,
        });
        let params = names.zip(params).map(|(n, p)| (n, p.ty, p.default)).collect();
        Some((params, events.iter().map(|e| e.as_str()).collect(), false))
    }

    pub(super) fn params(
        &mut self,
        c: &'a ast::Component,
        module: ModuleId,
        report: bool,
    ) -> (Vec<Param>, Vec<&'a String>) {
        let scope = Scope { module, ..Scope::default() };
        let mut params = Vec::new();
        let mut events = Vec::new();
        for p in &c.params {
            match p {
                ast::Param::Event { name } => events.push(&name.name),
                ast::Param::Value { name, ty, default } => {
                    let declared = ty.as_ref().map(|t| match Type::parse_name(&t.name.name) {
                        Some(ty) => ty.maybe_absent(t.optional),
                        None => {
                            if report {
                                self.diags
                                    .error(codes::UNKNOWN_TYPE, t.name.span, format!("unknown type `{}`", t.name.name))
                                    .suggest(&t.name.name, ["number", "bool", "string", "colour", "duration", "range", "object"])
                                    .help
                                    .get_or_insert_with(|| "types are number, bool, string, colour, duration, range and object; add `?` when it may be absent".into());
                            }
                            Type::ERROR
                        }
                    });
                    let default = default.as_ref().map(|d| {
                        let b = if report {
                            self.lower(d, &scope)
                        } else {
                            self.quiet(|t| t.lower(d, &scope))
                        };
                        if report && let Some(want) = &declared {
                            self.check_fits(
                                &b,
                                want,
                                &format_args!("the default of `{}`", name.name),
                            );
                        }
                        Bound::new(b)
                    });
                    let ty = declared
                        .or_else(|| default.as_ref().map(|d| d.expr.ty))
                        .unwrap_or(Type::DYNAMIC);
                    params.push(Param { name: name.name.clone(), ty, default });
                }
            }
        }
        (params, events)
    }

    /// Runs `f` with diagnostics discarded (re-lowering something already checked).
    pub(super) fn quiet<R>(&mut self, f: impl FnOnce(&mut Typer<'a, '_>) -> R) -> R {
        let mut scratch = Diagnostics::new();
        let mut t = Typer {
            modules: self.modules,
            defs: self.defs,
            schema: self.schema,
            diags: &mut scratch,
            top_lets: std::mem::take(&mut self.top_lets),
            lets_lowered: std::mem::take(&mut self.lets_lowered),
            lets: std::mem::take(&mut self.lets),
            program: Program::default(),
            mode_refs: Vec::new(),
            signatures: std::mem::take(&mut self.signatures),
            skip_components_of: self.skip_components_of,
        };
        let r = f(&mut t);
        self.signatures = t.signatures;
        self.top_lets = t.top_lets;
        self.lets_lowered = t.lets_lowered;
        self.lets = t.lets;
        r
    }

    pub(super) fn widget(
        &mut self,
        w: &'a ast::Widget,
        window: &str,
        scope: &Scope<'a>,
    ) -> Option<Widget> {
        let at =
            w.at.as_ref()
                .map(|(a, _)| a.iter().map(|g| self.geometry(g, scope)).collect())
                .unwrap_or_default();
        let sig = self.signature(scope.module, &w.component.name)?;
        let (params, events, native) = &*sig;
        let mut arg_scope = scope.clone();
        for (name, ty, _) in params {
            arg_scope.locals.push((name, mk(*ty, Node::Param(name.to_string()), w.span)));
        }
        let mut args = Vec::with_capacity(params.len());
        let mut visible = None;
        for (i, a) in w.args.iter().enumerate() {
            if a.name.name == "visible" {
                visible = Some(self.condition(&a.value, &arg_scope, &"`visible`"));
                continue;
            }
            let Some((_, ty, _)) = params.iter().find(|(n, ..)| *n == a.name.name) else {
                continue;
            };
            // `range 0 to 40`: the `to 40` that follows is the one diagnostic (resolve_names).
            if matches!(ty.kind, TypeKind::Range { .. })
                && w.args.get(i + 1).is_some_and(|n| {
                    n.name.name == "to" && !params.iter().any(|(p, ..)| *p == "to")
                })
            {
                self.lower(&a.value, &arg_scope);
                continue;
            }
            let b = if ty.kind == TypeKind::Bool {
                self.condition(&a.value, &arg_scope, &format_args!("`{}`", a.name.name))
            } else {
                self.expect(
                    &a.value,
                    &arg_scope,
                    ty,
                    &format_args!("`{}` of {}", a.name.name, w.component.name),
                )
            };
            args.push(Arg { name: a.name.name.clone(), value: read_as(b, ty) });
        }
        for (name, ty, default) in params {
            if !args.iter().any(|a: &Arg| a.name == *name)
                && let Some(d) = default
            {
                args.push(Arg { name: name.to_string(), value: read_as(d.clone(), ty) });
            }
        }
        let handlers = w
            .handlers
            .iter()
            .filter(|h| events.contains(&h.event.name.as_str()))
            .map(|h| Handler {
                event: h.event.name.clone(),
                actions: self.actions(&h.actions, scope),
            })
            .collect();
        Some(Widget {
            name: w.name.as_ref().map(|n| n.name.clone()),
            window: window.to_string(),
            component: w.component.name.clone(),
            native: *native,
            at,
            anchor: anchor_of(w.anchor.as_ref()),
            args,
            visible,
            handlers,
            span: w.span,
        })
    }

    pub(super) fn component(&mut self, c: &'a ast::Component, module: ModuleId) -> Component {
        let (params, events) = self.params(c, module, true);
        let mut s = Scope { module, ..Scope::default() }
            .with("w", mk(Type::number(), Node::Size("w".into()), c.span))
            .with("h", mk(Type::number(), Node::Size("h".into()), c.span));
        let names = c.params.iter().filter_map(|p| match p {
            ast::Param::Value { name, .. } => Some(name.name.as_str()),
            ast::Param::Event { .. } => None,
        });
        for (name, p) in names.zip(&params) {
            let node = if matches!(p.ty.kind, TypeKind::Object { .. }) {
                Node::Path(Path {
                    base: PathBase::Param(p.name.clone()),
                    segments: vec![],
                    base_type: None,
                })
            } else {
                Node::Param(p.name.clone())
            };
            s.locals.push((name, mk(p.ty, node, c.span)));
        }
        let mut shapes = Vec::new();
        for stmt in &c.body {
            match stmt {
                ast::Stmt::Let(l) => {
                    let v = self.lower(&l.value, &s);
                    let v = self.bind_let(&l.name.name, v);
                    s.locals.push((&l.name.name, v));
                }
                ast::Stmt::Primitive(p) => {
                    if let Some(shape) = self.primitive(p, &s) {
                        shapes.push(shape);
                    }
                }
            }
        }
        let events = events.into_iter().cloned().collect();
        Component { name: c.name.name.clone(), params, events, shapes, span: c.span }
    }

    pub(super) fn primitive(&mut self, p: &ast::Primitive, s: &Scope<'a>) -> Option<Shape> {
        let Some(def) = builtins::primitive(&p.kind.name) else {
            self.diags
                .error(
                    codes::UNKNOWN_PRIMITIVE,
                    p.kind.span,
                    format!("there is no drawing primitive `{}`", p.kind.name),
                )
                .suggest(&p.kind.name, builtins::PRIMITIVES.iter().map(|d| d.name))
                .help
                .get_or_insert_with(|| {
                    "primitives: rect, rounded, circle, arc, line, polyline, text, image".into()
                });
            return None;
        };
        let n = def.args.len();
        let count_ok = if def.variadic {
            p.args.len() >= 2 * n && p.args.len().is_multiple_of(n)
        } else {
            p.args.len() == n
        };
        if !count_ok {
            let want = if def.variadic {
                format!("pairs of numbers (at least {})", 2 * n)
            } else {
                format!("{n}")
            };
            self.diags
                .error(codes::ARG_COUNT, p.kind.span, format!("`{}` takes {want} arguments, not {}", def.name, p.args.len()))
                .help("a negative number in an argument list needs parentheses: `(-5)`, or `a - b` is read as one subtraction");
        }
        let args = p
            .args
            .iter()
            .enumerate()
            .map(|(i, a)| match def.args.as_bytes()[i % n] {
                b'n' => self.expect(
                    a,
                    s,
                    &Type::number(),
                    &format_args!("an argument of `{}`", def.name),
                ),
                b's' => {
                    self.expect(a, s, &Type::STRING, &format_args!("an argument of `{}`", def.name))
                }
                _ => {
                    let b = self.lower(a, s);
                    self.check_showable(&b);
                    Bound::new(b)
                }
            })
            .collect();
        let mut styles = Vec::new();
        for st in &p.styles {
            let Some(want) = builtins::style_type(&st.name.name) else {
                self.diags
                    .error(
                        codes::UNKNOWN_PRIMITIVE,
                        st.name.span,
                        format!("unknown style `{}`", st.name.name),
                    )
                    .suggest(&st.name.name, builtins::STYLES.iter().copied());
                continue;
            };
            let v = if want.kind == TypeKind::Bool {
                self.condition(&st.value, s, &"`visible`")
            } else {
                self.expect(&st.value, s, &want, &format_args!("`{}`", st.name.name))
            };
            let max = mocu_value::limits::MAX_FONT_PX;
            if st.name.name == "size"
                && let Some(n) = v.expr.constant().and_then(|c| c.number())
                && n > max
            {
                self.diags
                    .error(
                        codes::BEYOND_LIMIT,
                        st.value.span,
                        format!("a text size of {n} px is beyond the display's limit of {max} px"),
                    )
                    .help(format!("the display draws text of at most {max} px"));
            }
            styles.push(Arg { name: st.name.name.clone(), value: v });
        }
        Some(Shape { kind: def.name.to_string(), args, styles, span: p.span })
    }

    /// A binding's event and shaping from its options (their names and which inputs they
    /// fit were checked by `resolve_names`; here the numbers).
    pub(super) fn binding_options(&mut self, bnd: &ast::Binding) -> (String, f64, Shaping) {
        let mut event = if builtins::binding_value(&bnd.kind.name).is_some() {
            "change".to_string()
        } else {
            "press".to_string()
        };
        let mut hold_ms = 0.0;
        let mut sh = Shaping::default();
        for o in &bnd.options {
            let number = |t: &mut Self, want: &Type, lo: f64, hi: f64| -> f64 {
                let Some(v) = &o.value else { return lo };
                let b = t.lower(v, &Scope::default());
                let n = b.constant().and_then(|c| c.number()).unwrap_or(lo);
                if !b.ty.fits(want) || !(lo..=hi).contains(&n) {
                    t.diags
                        .error(
                            codes::BAD_BINDING,
                            v.span,
                            format!(
                                "`{}` takes {} from {lo} to {hi}",
                                o.name.name,
                                want_text(want)
                            ),
                        )
                        .label("out of range");
                    return lo;
                }
                n
            };
            match o.name.name.as_str() {
                "deadzone" => sh.deadzone = number(self, &Type::number(), 0.0, 0.99),
                "expo" => sh.expo = number(self, &Type::number(), 0.0, 1.0),
                "scale" => sh.scale = number(self, &Type::number(), -1e9, 1e9),
                "rate" => sh.rate = number(self, &Type::number(), 0.0, 1e9),
                "invert" => sh.invert = true,
                "hold" => {
                    event = "hold".into();
                    hold_ms = number(self, &Type::DURATION, 1.0, 60_000.0);
                }
                other => event = other.to_string(),
            }
        }
        (event, hold_ms, sh)
    }
}

/// E0212: `mode NAME` actions (`refs`) that no `bind` block declares.
pub(super) fn report_unknown_modes(
    refs: Vec<(String, Span)>,
    declared: &[String],
    diags: &mut Diagnostics,
) {
    for (m, span) in refs {
        if !declared.contains(&m) {
            let d = diags.error(
                codes::UNKNOWN_MODE,
                span,
                format!("no `bind` block declares a mode `{m}`"),
            );
            d.suggest(&m, declared.iter().map(String::as_str));
            if d.help.is_none() {
                d.help("declare it with `mode NAME { bindings… }` inside a `bind` block");
            }
        }
    }
}
