//! Actions, and the checks every bound value goes through: fits the expected type and unit,
//! is a condition, can be shown; top-level `let`s checked once and shared (`bind_let`).

use super::*;

impl<'a> Typer<'a, '_> {
    pub(super) fn actions(&mut self, actions: &[ast::Action], scope: &Scope<'a>) -> Vec<Action> {
        let mut out = Vec::with_capacity(actions.len());
        for a in actions {
            let span = a.span;
            match &a.kind {
                ast::ActionKind::Set { target, value } => {
                    let t = self.lower(target, scope);
                    let v = self.lower(value, scope);
                    match t.node {
                        Node::Path(p) => {
                            self.check_fits(&v, &t.ty.present(), &"the value to `set`");
                            out.push(Action::Set { target: p, value: Bound::new(v), span });
                        }
                        _ => {
                            if t.ty.kind != TypeKind::Error {
                                self.diags
                                    .error(
                                        codes::NOT_A_PATH,
                                        target.span,
                                        "`set` needs a property path on its left",
                                    )
                                    .help("write `set vehicle.property = value`");
                            }
                        }
                    }
                }
                ast::ActionKind::Call { call } => {
                    if let ExprKind::Call(callee, args) = &call.kind
                        && !matches!(callee.kind, ExprKind::Name(_))
                    {
                        let c = self.lower(callee, scope);
                        let args: Vec<Bound> =
                            args.iter().map(|x| Bound::new(self.lower(x, scope))).collect();
                        if let Node::Path(p) = c.node {
                            out.push(Action::Call { target: p, args, span });
                            continue;
                        }
                        if c.ty.kind == TypeKind::Error {
                            continue;
                        }
                    }
                    self.diags
                        .error(codes::MISPLACED_CALL, call.span, "`call` needs a method call on an object")
                        .help("write `call vehicle.method(arguments)`, e.g. `call usv.start_engine()`");
                }
                ast::ActionKind::Swap { a, b, duration } => {
                    let duration_ms = duration
                        .as_ref()
                        .and_then(|d| {
                            let b = self.expect(d, scope, &Type::DURATION, &"a swap's duration");
                            crate::passes::check_durations::check_duration(
                                &b.expr,
                                Use::Swap,
                                self.diags,
                            )
                        })
                        .unwrap_or(250.0);
                    out.push(Action::Swap {
                        a: a.name.clone(),
                        b: b.name.clone(),
                        duration_ms,
                        span,
                    });
                }
                ast::ActionKind::Show { window } => {
                    out.push(Action::Show { window: window.name.clone(), span })
                }
                ast::ActionKind::Hide { window } => {
                    out.push(Action::Hide { window: window.name.clone(), span })
                }
                ast::ActionKind::Script { engine, body, body_span } => {
                    crate::passes::check_scripts::check_script(
                        &engine.name,
                        engine.span,
                        body,
                        *body_span,
                        self.diags,
                    );
                    out.push(Action::Script {
                        engine: engine.name.clone(),
                        body: body.clone(),
                        span: *body_span,
                        origin: None,
                    })
                }
                ast::ActionKind::Alert { level, message } => {
                    let m = self.expect(message, scope, &Type::STRING, &"an alert message");
                    out.push(Action::Alert { level: level.name.clone(), message: m, span });
                }
                ast::ActionKind::Mode { mode } => {
                    self.mode_refs.push((mode.name.clone(), mode.span));
                    out.push(Action::Mode { mode: mode.name.clone(), span });
                }
                ast::ActionKind::Select { target } => {
                    let target = match target {
                        ast::SelectTarget::Next => SelectTarget::Next,
                        ast::SelectTarget::Prev => SelectTarget::Prev,
                        ast::SelectTarget::Object(e) => {
                            let t = self.lower(e, scope);
                            match t.node {
                                Node::Path(p) if !matches!(t.ty.kind, TypeKind::Void) => {
                                    SelectTarget::Object(p)
                                }
                                _ => {
                                    if t.ty.kind != TypeKind::Error {
                                        self.diags
                                            .error(
                                                codes::NOT_A_PATH,
                                                e.span,
                                                "`select` needs the path of an object",
                                            )
                                            .help("write `select root.vehicles.usv2`, `select next` or `select prev`");
                                    }
                                    continue;
                                }
                            }
                        }
                    };
                    out.push(Action::Select { target, span });
                }
            }
        }
        out
    }

    pub(super) fn expect(
        &mut self,
        e: &ast::Expr,
        scope: &Scope<'a>,
        want: &Type,
        what: What,
    ) -> Bound {
        let b = self.lower(e, scope);
        self.check_fits(&b, want, what);
        Bound::new(b)
    }

    pub(super) fn check_fits(&mut self, b: &Expr, want: &Type, what: What) {
        if b.ty.fits(want) {
            if let (Some(have), Some(w)) = (b.ty.unit(), want.unit())
                && have != w
            {
                self.diags
                    .error(
                        codes::UNIT_MISMATCH,
                        b.span,
                        format!("{what} is in {w}, but this is in {have}"),
                    )
                    .label(format!("this is in {have}"));
            }
            return;
        }
        if want.is_numeric() && !want.is_lenient() {
            self.not_a_number(b, what);
            return;
        }
        let d = self.diags.error(
            codes::TYPE_MISMATCH,
            b.span,
            format!("{what} must be a {}, but this is a {}", (*want).present(), b.ty),
        );
        d.label(format!("this is a {}", b.ty));
        if want.kind == TypeKind::String && b.ty.is_numeric() {
            d.help("to show a number as text, interpolate it: \"{x}\"");
        }
        if matches!(want.kind, TypeKind::Range { .. }) && b.ty.is_numeric() {
            d.help("a range is written MIN `..` MAX: `range 0 .. 40`");
        }
    }

    pub(super) fn not_a_number(&mut self, b: &Expr, what: What) {
        let d = self.diags.error(
            codes::NOT_A_NUMBER,
            b.span,
            format!("a {} is used as a number", b.ty.present()),
        );
        d.label(format!("this is a {}", b.ty));
        let what = what.to_string();
        if what != "an operand" {
            d.message = format!("{what} must be a number, but this is a {}", b.ty.present());
        }
        if b.ty.kind == TypeKind::Bool {
            d.help("use `if … then 1 else 0` to turn a condition into a number");
        }
    }

    pub(super) fn condition(&mut self, e: &ast::Expr, scope: &Scope<'a>, what: What) -> Bound {
        let b = self.lower(e, scope);
        if !b.ty.is_bool() {
            self.diags
                .error(
                    codes::NOT_BOOL,
                    b.span,
                    format!("{what} must be a condition (bool), but this is a {}", b.ty),
                )
                .label(format!("this is a {}", b.ty))
                .help(if b.ty.is_numeric() {
                    "compare it, e.g. `x > 0`"
                } else {
                    "write a comparison or a boolean property"
                });
        }
        Bound::new(b)
    }

    pub(super) fn check_showable(&mut self, b: &Expr) {
        if matches!(b.ty.kind, TypeKind::Object { .. } | TypeKind::Range { .. } | TypeKind::Void) {
            self.diags
                .error(codes::TYPE_MISMATCH, b.span, format!("a {} cannot be shown as text", b.ty))
                .label("not a value");
        }
    }

    /// Checks a top-level `let` once, and before it the module's `let`s above it (those it
    /// may name), in order: naming a `let` of another module checks that module's `let`s up
    /// to it, so recursion through `let`s goes as deep as the chain of modules, not as the
    /// chain of `let`s. `None` if `id` is not a `let`, or is being checked (a `use` cycle).
    pub(super) fn lower_top_let(&mut self, id: DefId) -> Option<Expr> {
        while self.lets_lowered[id.module] <= id.item {
            let item = self.lets_lowered[id.module];
            self.lets_lowered[id.module] += 1;
            let at = DefId { module: id.module, item, inner: None };
            if let Some(l) = let_item(self.modules, at) {
                let scope = Scope { module: id.module, limit: Some(item), ..Scope::default() };
                let v = self.lower(&l.value, &scope);
                let v = self.bind_let(&l.name.name, v);
                self.top_lets.insert(at, v);
            }
        }
        self.top_lets.get(&id).cloned()
    }

    /// What the uses of a `let` with this checked value get: a path or a constant is copied
    /// (paths are extended and constants folded where they are used; copying them costs
    /// what their source does); anything else becomes a [`Let`] of the program, checked
    /// once and referred to by every use.
    pub(super) fn bind_let(&mut self, name: &str, value: Expr) -> Expr {
        let copied = match &value.node {
            Node::Number(_)
            | Node::Bool(_)
            | Node::Colour(_)
            | Node::Duration(_)
            | Node::Path(_)
            | Node::Param(_)
            | Node::Size(_)
            | Node::Input(_)
            | Node::Index
            | Node::Let(_) => true,
            Node::Str(s) => s.len() <= 64,
            _ => false,
        };
        if copied {
            return value;
        }
        let (ty, span) = (value.ty, value.span);
        let l = Let::shared(self.lets.len() as u32, name.to_string(), value);
        self.lets.push(l.clone());
        mk(ty, Node::Let(l), span)
    }

    /// A top-level `let` where it is used (`span`).
    pub(super) fn top_let(&mut self, id: DefId, span: Span) -> Option<Expr> {
        let e = self.lower_top_let(id)?;
        Some(Expr { span, ..e })
    }

    pub(super) fn path_type(&self, p: &Path) -> Type {
        let from_root = p.base == PathBase::Root;
        if from_root && p.segments.is_empty() {
            return Type::new(TypeKind::Object { object_type: None });
        }
        match self.schema.lookup(p.base_type.as_deref(), from_root, &p.segments) {
            Lookup::Property(prop) => prop.ty(),
            Lookup::Object(t) => {
                Type { kind: TypeKind::Object { object_type: Some(Name::new(t)) }, absent: true }
            }
            Lookup::Method(_) => Type::VOID,
            Lookup::Untyped | Lookup::Unknown { .. } => Type::DYNAMIC,
        }
    }
}
