//! Pass 4: types, and lowering to the checked [`Program`]. Every expression gets a
//! [`Type`]; paths are typed from the schema when one covers them. A `let` is checked once,
//! where it is defined, and becomes a [`Let`] of the program that its uses refer to
//! (`Node::Let`); one whose value is a path or a constant is copied into its uses instead,
//! where paths are extended (`v.nav.speed`) and constants folded. So checking is linear in
//! the source, however the `let`s name one another.
//! Reports a non-number used as a number (E0301), other mismatches (E0302), argument counts
//! (E0303), non-boolean conditions (E0304), unknown type names (E0305), misplaced method
//! calls (E0306), bad format specs (E0307), `set` of a non-path (E0308), unknown primitives
//! and styles (E0309), and unit mismatches (E0402, units come from the schema and literals).
//!
//! Runs after `resolve_names`: a name it cannot resolve was reported there, so here it just
//! becomes the `{error}` type, which is accepted everywhere (no cascades).

use super::check_durations::Use;
use super::{DefId, Definitions, ModuleId, Modules, component_item, let_item};
use crate::ast::{self, BinOp, ExprKind, Item, LitUnit, StrPart, UnOp};
use crate::builtins::{self, Returns};
use crate::codes;
use crate::diagnostics::Diagnostics;
use crate::program::*;
use crate::schema::{Lookup, Schema};
use crate::source::Span;
use crate::types::{Name, Type, TypeKind, literal_unit};

/// A component's parameters as (name, type, default), its events, and whether it is native.
/// Names are borrowed from the syntax trees (or built in).
type Signature<'a> = (Vec<(&'a str, Type, Option<Bound>)>, Vec<&'a str>, bool);
use super::FastMap;
use std::rc::Rc;

pub fn check_types(
    modules: &Modules,
    defs: &Definitions,
    schema: &Schema,
    diags: &mut Diagnostics,
) -> Program {
    let mut t = Typer {
        modules,
        defs,
        schema,
        diags,
        top_lets: FastMap::default(),
        lets_lowered: vec![0; modules.len()],
        lets: Vec::new(),
        program: Program::default(),
        mode_refs: Vec::new(),
        signatures: FastMap::default(),
    };
    t.program.files = modules.iter().map(|m| m.path.clone()).collect();
    for m in 0..modules.len() {
        t.module(m);
    }
    t.check_modes();
    t.program.lets = Lets(t.lets);
    t.program
}

#[derive(Clone, Default)]
struct Scope<'a> {
    module: ModuleId,
    limit: Option<usize>,
    /// Names in scope with their values (a `let`'s: what its uses get, see `bind_let`);
    /// names are borrowed from the syntax trees (or built in).
    locals: Vec<(&'a str, Expr)>,
    self_type: Option<Option<String>>,
}

impl<'a> Scope<'a> {
    fn with(&self, name: &'a str, e: Expr) -> Scope<'a> {
        let mut s = self.clone();
        s.locals.push((name, e));
        s
    }
}

struct Typer<'a, 'd> {
    modules: &'a Modules,
    defs: &'a Definitions,
    schema: &'a Schema,
    diags: &'d mut Diagnostics,
    /// Top-level `let`s, each checked once: what their uses get (see `bind_let`).
    top_lets: FastMap<DefId, Expr>,
    /// Per module, how many of its items have had their `let`s checked (in order).
    lets_lowered: Vec<usize>,
    /// The program's `let`s so far.
    lets: Vec<LetRef>,
    program: Program,
    /// `mode NAME` actions, checked against the declared modes at the end (E0212).
    mode_refs: Vec<(String, Span)>,
    /// Each component's signature, worked out once per module that uses it (its defaults
    /// lowered once, not once per widget).
    signatures: FastMap<(ModuleId, &'a str), Option<Rc<Signature<'a>>>>,
}

/// Where windows, widgets and watches go: the program, or a template.
#[derive(Default)]
struct Sink {
    windows: Vec<Window>,
    widgets: Vec<Widget>,
    watches: Vec<Watch>,
}

/// An unknown anchor name is reported by passes/check_anchors.rs; here it is the default.
fn anchor_of(name: Option<&ast::Ident>) -> crate::placement::Anchor {
    name.and_then(|n| crate::placement::Anchor::parse(&n.name)).unwrap_or_default()
}

/// What a value is for, in messages ("`value` of Dial"): formatted only when reported.
type What<'x> = &'x dyn std::fmt::Display;

fn mk(ty: Type, node: Node, span: Span) -> Expr {
    Expr { ty, node, span }
}

impl<'a> Typer<'a, '_> {
    fn module(&mut self, m: ModuleId) {
        let base = Scope { module: m, ..Scope::default() };
        let mut sink = Sink::default();
        let modules = self.modules;
        for (i, item) in modules[m].ast.items.iter().enumerate() {
            if let Item::Let(_) = item {
                // Checked even when unused; uses refer to this result.
                self.lower_top_let(DefId { module: m, item: i, inner: None });
            }
            self.item(item, &base, &mut sink);
        }
        self.program.windows.append(&mut sink.windows);
        self.program.widgets.append(&mut sink.widgets);
        self.program.watches.append(&mut sink.watches);
    }

    fn item(&mut self, item: &'a Item, scope: &Scope<'a>, sink: &mut Sink) {
        match item {
            Item::Use(_) | Item::Let(_) | Item::Design(_) => {}
            Item::Window(w) => {
                let win = self.window(w, scope);
                sink.windows.push(win);
            }
            Item::In(b) => {
                for w in &b.widgets {
                    if let Some(widget) = self.widget(w, &b.window.name, scope) {
                        sink.widgets.push(widget);
                    }
                }
            }
            Item::Component(c) => {
                let comp = self.component(c, scope.module);
                self.program.components.push(comp);
            }
            Item::Bind(b) => {
                let all = b.bindings.iter().map(|x| (None, x));
                let moded = b
                    .modes
                    .iter()
                    .flat_map(|(m, list)| list.iter().map(move |x| (Some(m.name.clone()), x)));
                for (mode, bnd) in all.chain(moded).collect::<Vec<_>>() {
                    let s = match builtins::binding_value(&bnd.kind.name) {
                        Some(v) => {
                            scope.with(v, mk(Type::number(), Node::Input(v.to_string()), bnd.span))
                        }
                        None => scope.clone(),
                    };
                    let actions = self.actions(&bnd.actions, &s);
                    let (event, hold_ms, shaping) = self.binding_options(bnd);
                    self.program.bindings.push(Binding {
                        device: b.device.name.clone(),
                        kind: bnd.kind.name.clone(),
                        input: bnd.input.name.clone(),
                        event,
                        hold_ms,
                        mode,
                        shift: bnd.shift,
                        shift_input: b.shift.as_ref().map(|i| i.name.clone()),
                        shaping,
                        actions,
                        span: bnd.span,
                    });
                }
            }
            Item::Menu(menu) => {
                let ty = (!menu.object_type.is_empty()).then(|| menu.object_type.clone());
                if let Some(t) = &ty
                    && !self.schema.is_empty()
                    && !self.schema.has_type(t)
                {
                    self.diags
                        .error(
                            codes::UNKNOWN_PROPERTY,
                            menu.type_span,
                            format!("the schema declares no object type \"{t}\""),
                        )
                        .suggest(t, self.schema.types.keys().map(String::as_str));
                }
                let s = Scope { self_type: Some(ty), ..scope.clone() };
                let items = menu
                    .entries
                    .iter()
                    .map(|e| {
                        let label =
                            self.expect(&e.label, &s, &Type::STRING, &"a menu item's label");
                        let enabled =
                            e.enabled.as_ref().map(|x| self.condition(x, &s, &"`enabled`"));
                        MenuItem { label, enabled, actions: self.actions(&e.actions, &s) }
                    })
                    .collect();
                self.program.menus.push(Menu {
                    object_type: menu.object_type.clone(),
                    items,
                    span: menu.span,
                });
            }
            Item::Watch(w) => {
                let when = self.condition(&w.when, scope, &"a watch's `when`");
                let hold_ms = w.hold.as_ref().and_then(|h| {
                    let b = self.expect(h, scope, &Type::DURATION, &"a hold time (`for 5s`)");
                    super::check_durations::check_duration(&b.expr, Use::Hold, self.diags)
                });
                let clear =
                    w.clear.as_ref().map(|c| self.condition(c, scope, &"a watch's `clear when`"));
                let repeat_ms = w.repeat.as_ref().and_then(|r| {
                    let b = self.expect(
                        r,
                        scope,
                        &Type::DURATION,
                        &"a repeat period (`repeat every 30s`)",
                    );
                    super::check_durations::check_duration(&b.expr, Use::Repeat, self.diags)
                });
                let actions = self.actions(&w.actions, scope);
                sink.watches.push(Watch {
                    name: w.name.name.clone(),
                    when,
                    hold_ms,
                    clear,
                    repeat_ms,
                    actions,
                    span: w.span,
                });
            }
            Item::Each(e) => {
                let source = self.lower(&e.source, scope);
                let source = match source.node {
                    Node::Path(p) => p,
                    _ => {
                        if source.ty.kind != TypeKind::Error {
                            self.diags.error(
                                codes::NOT_A_PATH,
                                e.source.span,
                                "`for each … in` needs the path of an object, e.g. `root.vehicles`",
                            );
                        }
                        Path { base: PathBase::Root, segments: vec![], base_type: None }
                    }
                };
                let object_type = e.object_type.as_ref().map(|(t, span)| {
                    if !self.schema.is_empty() && !self.schema.has_type(t) {
                        self.diags
                            .error(
                                codes::UNKNOWN_PROPERTY,
                                *span,
                                format!("the schema declares no object type \"{t}\""),
                            )
                            .suggest(t, self.schema.types.keys().map(String::as_str));
                    }
                    t.clone()
                });
                let var_ty = Type::new(TypeKind::Object {
                    object_type: object_type.as_deref().map(Name::new),
                });
                let var = mk(
                    var_ty,
                    Node::Path(Path {
                        base: PathBase::Var(e.var.name.clone()),
                        segments: vec![],
                        base_type: object_type.clone(),
                    }),
                    e.var.span,
                );
                let mut s = scope
                    .with(&e.var.name, var)
                    .with("index", mk(Type::number(), Node::Index, e.span));
                let mut inner = Sink::default();
                for it in &e.items {
                    if let Item::Let(l) = it {
                        let v = self.lower(&l.value, &s);
                        let v = self.bind_let(&l.name.name, v);
                        s.locals.push((&l.name.name, v));
                    } else {
                        self.item(it, &s, &mut inner);
                    }
                }
                self.program.templates.push(Template {
                    var: e.var.name.clone(),
                    source,
                    object_type,
                    windows: inner.windows,
                    widgets: inner.widgets,
                    watches: inner.watches,
                    span: e.span,
                });
            }
        }
    }

    fn window(&mut self, w: &ast::Window, scope: &Scope<'a>) -> Window {
        let span = w.span;
        let konst = |n: f64| Bound::new(mk(Type::number(), Node::Number(n), span));
        let mut win = Window {
            name: w.name.name.clone(),
            kind: "layer".into(),
            layer: konst(0.0),
            rect: vec![
                konst(0.0),
                konst(0.0),
                Bound::new(mk(Type::number_in(Some(literal_unit("%"))), Node::Number(100.0), span)),
                Bound::new(mk(Type::number_in(Some(literal_unit("%"))), Node::Number(100.0), span)),
            ],
            anchor: anchor_of(w.anchor.as_ref()),
            opacity: konst(1.0),
            visible: Bound::new(mk(Type::BOOL, Node::Bool(true), span)),
            source: None,
            span,
        };
        if let Some(rect) = &w.rect {
            win.rect = rect.iter().map(|g| self.geometry(g, scope)).collect();
        }
        for p in &w.props {
            let Some(want) = builtins::window_prop_type(&p.name.name) else { continue };
            let b = if want.kind == TypeKind::Bool {
                self.condition(&p.value, scope, &"`visible`")
            } else {
                self.expect(&p.value, scope, &want, &format_args!("a window's `{}`", p.name.name))
            };
            match p.name.name.as_str() {
                "layer" => win.layer = b,
                "opacity" => win.opacity = b,
                "visible" => win.visible = b,
                "source" => win.source = Some(b),
                _ => {
                    if let Node::Str(s) = &b.expr.node {
                        win.kind = s.clone();
                    } else if b.expr.ty.kind == TypeKind::String {
                        self.diags.error(codes::TYPE_MISMATCH, p.value.span, "a window's `type` must be a constant string such as \"video\" or \"map\"");
                    }
                }
            }
        }
        win
    }

    fn geometry(&mut self, e: &ast::Expr, scope: &Scope<'a>) -> Bound {
        let b = self.lower(e, scope);
        if !b.ty.is_numeric() {
            self.not_a_number(&b, &"a position or size");
        } else if let Some(u) = b.ty.unit()
            && u != "%"
            && u != "px"
        {
            self.diags
                .error(
                    codes::UNIT_MISMATCH,
                    e.span,
                    format!("a position or size is in px or %, not {u}"),
                )
                .label(format!("this is in {u}"));
        }
        Bound::new(b)
    }

    /// The component's parameters as (name, type, default), its events, and whether native.
    fn signature(&mut self, module: ModuleId, name: &'a str) -> Option<Rc<Signature<'a>>> {
        if let Some(known) = self.signatures.get(&(module, name)) {
            return known.clone();
        }
        let sig = self.work_out_signature(module, name).map(Rc::new);
        self.signatures.insert((module, name), sig.clone());
        sig
    }

    fn work_out_signature(&mut self, module: ModuleId, name: &str) -> Option<Signature<'a>> {
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

    fn params(
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
    fn quiet<R>(&mut self, f: impl FnOnce(&mut Typer<'a, '_>) -> R) -> R {
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
        };
        let r = f(&mut t);
        self.signatures = t.signatures;
        self.top_lets = t.top_lets;
        self.lets_lowered = t.lets_lowered;
        self.lets = t.lets;
        r
    }

    fn widget(&mut self, w: &'a ast::Widget, window: &str, scope: &Scope<'a>) -> Option<Widget> {
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
        let mut args = Vec::new();
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

    fn component(&mut self, c: &'a ast::Component, module: ModuleId) -> Component {
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

    fn primitive(&mut self, p: &ast::Primitive, s: &Scope<'a>) -> Option<Shape> {
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
            styles.push(Arg { name: st.name.name.clone(), value: v });
        }
        Some(Shape { kind: def.name.to_string(), args, styles, span: p.span })
    }

    /// A binding's event and shaping from its options (their names and which inputs they
    /// fit were checked by `resolve_names`; here the numbers).
    fn binding_options(&mut self, bnd: &ast::Binding) -> (String, f64, Shaping) {
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

    /// Every `mode NAME` action names a mode some `bind` block declares.
    fn check_modes(&mut self) {
        let declared: Vec<String> =
            self.program.bindings.iter().filter_map(|b| b.mode.clone()).collect();
        for (m, span) in std::mem::take(&mut self.mode_refs) {
            if !declared.contains(&m) {
                let d = self.diags.error(
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

    fn actions(&mut self, actions: &[ast::Action], scope: &Scope<'a>) -> Vec<Action> {
        let mut out = Vec::new();
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
                            super::check_durations::check_duration(&b.expr, Use::Swap, self.diags)
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

    // ---- expressions ------------------------------------------------------------------

    fn expect(&mut self, e: &ast::Expr, scope: &Scope<'a>, want: &Type, what: What) -> Bound {
        let b = self.lower(e, scope);
        self.check_fits(&b, want, what);
        Bound::new(b)
    }

    fn check_fits(&mut self, b: &Expr, want: &Type, what: What) {
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

    fn not_a_number(&mut self, b: &Expr, what: What) {
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

    fn condition(&mut self, e: &ast::Expr, scope: &Scope<'a>, what: What) -> Bound {
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

    fn check_showable(&mut self, b: &Expr) {
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
    fn lower_top_let(&mut self, id: DefId) -> Option<Expr> {
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
    fn bind_let(&mut self, name: &str, value: Expr) -> Expr {
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
    fn top_let(&mut self, id: DefId, span: Span) -> Option<Expr> {
        let e = self.lower_top_let(id)?;
        Some(Expr { span, ..e })
    }

    fn path_type(&self, p: &Path) -> Type {
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

    fn lower(&mut self, e: &ast::Expr, scope: &Scope<'a>) -> Expr {
        // Nesting up to the depth limit takes ~9 KiB of stack a level in a debug build: more
        // than a 2 MiB thread has. Grow the stack when less than 64 KiB is left.
        stacker::maybe_grow(64 * 1024, 1024 * 1024, || self.lower_node(e, scope))
    }

    fn lower_node(&mut self, e: &ast::Expr, scope: &Scope<'a>) -> Expr {
        let span = e.span;
        match &e.kind {
            ExprKind::Number { value, unit } => match unit {
                Some(LitUnit::Ms) => mk(Type::DURATION, Node::Duration(*value), span),
                Some(LitUnit::S) => mk(Type::DURATION, Node::Duration(value * 1000.0), span),
                Some(LitUnit::Min) => mk(Type::DURATION, Node::Duration(value * 60_000.0), span),
                Some(LitUnit::Px) => {
                    mk(Type::number_in(Some(literal_unit("px"))), Node::Number(*value), span)
                }
                Some(LitUnit::Deg) => {
                    mk(Type::number_in(Some(literal_unit("deg"))), Node::Number(*value), span)
                }
                Some(LitUnit::Percent) => {
                    mk(Type::number_in(Some(literal_unit("%"))), Node::Number(*value), span)
                }
                None => mk(Type::number(), Node::Number(*value), span),
            },
            ExprKind::Bool(b) => mk(Type::BOOL, Node::Bool(*b), span),
            ExprKind::Error => mk(Type::ERROR, Node::Bool(false), span),
            ExprKind::Colour(c) => mk(Type::COLOUR, Node::Colour(*c), span),
            ExprKind::Str(parts) => self.string(parts, scope, span),
            ExprKind::SelfRef => match &scope.self_type {
                Some(t) => mk(
                    Type {
                        kind: TypeKind::Object { object_type: t.as_deref().map(Name::new) },
                        absent: true,
                    },
                    Node::Path(Path {
                        base: PathBase::SelfObject,
                        segments: vec![],
                        base_type: t.clone(),
                    }),
                    span,
                ),
                None => mk(Type::ERROR, Node::Bool(false), span),
            },
            ExprKind::Name(n) => {
                if let Some((_, local)) = scope.locals.iter().rev().find(|(name, _)| name == n) {
                    return Expr { span, ..local.clone() };
                }
                if let Some(id) = self.defs.find_let(self.modules, scope.module, n, scope.limit)
                    && let Some(v) = self.top_let(id, span)
                {
                    return v;
                }
                if n == "selected" {
                    return mk(
                        Type { kind: TypeKind::Object { object_type: None }, absent: true },
                        Node::Path(Path {
                            base: PathBase::Selected,
                            segments: vec![],
                            base_type: None,
                        }),
                        span,
                    );
                }
                if n == "root" {
                    return mk(
                        Type::new(TypeKind::Object { object_type: None }),
                        Node::Path(Path {
                            base: PathBase::Root,
                            segments: vec![],
                            base_type: None,
                        }),
                        span,
                    );
                }
                mk(Type::ERROR, Node::Bool(false), span)
            }
            ExprKind::Field(base, field) => {
                if let ExprKind::Name(ns) = &base.kind {
                    let shadowed = scope.locals.iter().any(|(n, _)| n == ns)
                        || self
                            .defs
                            .find_let(self.modules, scope.module, ns, scope.limit)
                            .is_some();
                    if let (false, Some(target)) =
                        (shadowed, self.defs.namespace(self.modules, scope.module, ns))
                    {
                        let id = self.defs.lets[target].get(&field.name).copied();
                        return match id.and_then(|id| self.top_let(id, span)) {
                            Some(v) => v,
                            None => mk(Type::ERROR, Node::Bool(false), span),
                        };
                    }
                }
                let b = self.lower(base, scope);
                self.member(b, field.name.clone(), span, field.span)
            }
            ExprKind::Index(base, key) => {
                let b = self.lower(base, scope);
                self.member(b, key.clone(), span, span)
            }
            ExprKind::Call(callee, args) => {
                let ExprKind::Name(f) = &callee.kind else {
                    let c = self.lower(callee, scope);
                    if c.ty.kind != TypeKind::Error {
                        self.diags
                            .error(codes::MISPLACED_CALL, span, "a method call can only be an action")
                            .help("methods act on the world: use them as `call obj.method(…)` in a button, binding, menu or watch");
                    }
                    return mk(Type::ERROR, Node::Bool(false), span);
                };
                let args: Vec<Expr> = args.iter().map(|a| self.lower(a, scope)).collect();
                self.builtin_call(f, args, span, callee.span)
            }
            ExprKind::Unary(op, a) => {
                let a = self.lower(a, scope);
                let ty = match op {
                    UnOp::Neg => {
                        if matches!(a.ty.kind, TypeKind::Duration) {
                            a.ty
                        } else {
                            if !a.ty.is_numeric() {
                                self.not_a_number(&a, &"an operand");
                            }
                            if a.ty.is_numeric() {
                                Type::number_in(unit_of(&a.ty)).maybe_absent(a.ty.absent)
                            } else {
                                Type::ERROR
                            }
                        }
                    }
                    UnOp::Not => {
                        if !a.ty.is_bool() {
                            self.diags
                                .error(
                                    codes::NOT_BOOL,
                                    a.span,
                                    format!("`!` needs a condition (bool), but this is a {}", a.ty),
                                )
                                .label(format!("this is a {}", a.ty));
                        }
                        Type::BOOL.maybe_absent(a.ty.absent)
                    }
                };
                mk(ty, Node::Unary { op: *op, arg: Box::new(a) }, span)
            }
            ExprKind::Binary(op, a, b) => {
                let a = self.lower(a, scope);
                let b = self.lower(b, scope);
                let ty = self.binary_type(*op, &a, &b);
                if *op == BinOp::Range {
                    return mk(ty, Node::Range { lo: Box::new(a), hi: Box::new(b) }, span);
                }
                mk(ty, Node::Binary { op: *op, lhs: Box::new(a), rhs: Box::new(b) }, span)
            }
            ExprKind::If(c, a, b) => {
                let c = self.lower(c, scope);
                if !c.ty.is_bool() {
                    self.diags
                        .error(
                            codes::NOT_BOOL,
                            c.span,
                            format!("the condition of `if` must be a bool, but this is a {}", c.ty),
                        )
                        .label(format!("this is a {}", c.ty));
                }
                let a = self.lower(a, scope);
                let b = self.lower(b, scope);
                let ty = if a.ty.is_lenient() {
                    b.ty.maybe_absent(a.ty.absent)
                } else if b.ty.is_lenient() || a.ty.fits(&b.ty) {
                    a.ty.maybe_absent(b.ty.absent)
                } else {
                    self.diags
                        .error(
                            codes::TYPE_MISMATCH,
                            b.span,
                            format!("the branches of `if` differ: {} and {}", a.ty, b.ty),
                        )
                        .label(format!("this is a {}", b.ty));
                    Type::ERROR
                };
                mk(ty, Node::If { cond: Box::new(c), then: Box::new(a), other: Box::new(b) }, span)
            }
        }
    }

    fn member(&mut self, base: Expr, name: String, span: Span, name_span: Span) -> Expr {
        match base.node {
            Node::Path(mut p) => {
                p.segments.push(name);
                let from_root = p.base == PathBase::Root;
                if from_root && p.segments.len() <= 2 {
                    super::check_paths::check_root_member(
                        self.schema,
                        &p.segments,
                        name_span,
                        self.diags,
                    );
                }
                // An unknown member is reported here, where the segment's own span is known.
                if let Lookup::Unknown { object_type, index, candidates } =
                    self.schema.lookup(p.base_type.as_deref(), from_root, &p.segments)
                    && index + 1 == p.segments.len()
                {
                    let seg = &p.segments[index];
                    self.diags
                        .error(
                            codes::UNKNOWN_PROPERTY,
                            name_span,
                            format!("an object of type \"{object_type}\" has no property `{seg}`"),
                        )
                        .label(format!("`{seg}` is not in the schema"))
                        .suggest(seg, candidates.iter().copied());
                }
                let ty = self.path_type(&p);
                mk(ty, Node::Path(p), span)
            }
            _ if matches!(base.ty.kind, TypeKind::Range { .. })
                && (name == "min" || name == "max") =>
            {
                let ty = Type::number_in(unit_of(&base.ty)).maybe_absent(base.ty.absent);
                let max = name == "max";
                mk(ty, Node::RangeEnd { range: Box::new(base), max }, span)
            }
            _ if base.ty.kind == TypeKind::Error => base,
            _ => {
                let d = self.diags.error(
                    codes::TYPE_MISMATCH,
                    name_span,
                    format!("a {} has no member `{name}`", base.ty),
                );
                if matches!(base.ty.kind, TypeKind::Range { .. }) {
                    d.help("a range has `.min` and `.max`");
                }
                mk(Type::ERROR, Node::Bool(false), span)
            }
        }
    }

    fn builtin_call(&mut self, f: &str, args: Vec<Expr>, span: Span, name_span: Span) -> Expr {
        let Some(def) = builtins::function(f) else {
            return mk(Type::ERROR, Node::Bool(false), span);
        };
        if args.len() != def.params.len() {
            self.diags
                .error(
                    codes::ARG_COUNT,
                    name_span,
                    format!(
                        "`{f}` takes {} argument{}, but {} {} given",
                        def.params.len(),
                        if def.params.len() == 1 { "" } else { "s" },
                        args.len(),
                        if args.len() == 1 { "was" } else { "were" }
                    ),
                )
                .help(format!("{f}: {}", def.doc));
        }
        let mut absent = false;
        for (a, kind) in args.iter().zip(def.params.bytes()) {
            absent |= a.ty.absent;
            match kind {
                b'n' if !a.ty.is_numeric() => {
                    self.not_a_number(a, &format_args!("an argument of `{f}`"))
                }
                b's' if !a.ty.fits(&Type::STRING) => {
                    self.diags.error(
                        codes::TYPE_MISMATCH,
                        a.span,
                        format!("an argument of `{f}` must be a string, but this is a {}", a.ty),
                    );
                }
                _ => {}
            }
        }
        if f == "format"
            && let Some(Expr { node: Node::Str(spec), span, .. }) = args.get(1)
            && parse_spec(spec).is_none()
        {
            self.bad_spec(*span, spec);
        }
        let first_unit = args.first().and_then(|a| unit_of(&a.ty));
        let ty = match def.returns {
            Returns::SameUnit => Type::number_in(first_unit),
            Returns::Unitless => Type::number(),
            Returns::Unit(u) => Type::number_in(Some(Name::new(u))),
            Returns::String => Type::STRING,
            Returns::Colour => Type::COLOUR,
            Returns::Bool => {
                absent = false;
                Type::BOOL
            }
        };
        mk(ty.maybe_absent(absent), Node::Call { function: f.to_string(), args }, span)
    }

    fn bad_spec(&mut self, span: Span, spec: &str) {
        self.diags
            .error(codes::BAD_FORMAT, span, format!("`{spec}` is not a format spec"))
            .help("a spec is `[0][width][.digits]`, e.g. `.1` (one decimal) or `03.0` (three digits, zero-padded)");
    }

    fn string(&mut self, parts: &[StrPart], scope: &Scope<'a>, span: Span) -> Expr {
        if let [StrPart::Text(t)] = parts {
            return mk(Type::STRING, Node::Str(t.clone()), span);
        }
        if parts.is_empty() {
            return mk(Type::STRING, Node::Str(String::new()), span);
        }
        let mut out = Vec::new();
        let mut absent = false;
        for p in parts {
            match p {
                StrPart::Text(t) => out.push(FormatPart::Text(t.clone())),
                StrPart::Interp { expr, spec } => {
                    let e = self.lower(expr, scope);
                    self.check_showable(&e);
                    absent |= e.ty.absent;
                    let spec = spec.as_ref().and_then(|(s, sp)| {
                        let parsed = parse_spec(s);
                        if parsed.is_none() {
                            self.bad_spec(*sp, s);
                        }
                        parsed
                    });
                    out.push(FormatPart::Value { expr: e, spec });
                }
            }
        }
        // An interpolated string is never absent: an absent value shows as "—".
        let _ = absent;
        mk(Type::STRING, Node::Format(out), span)
    }

    fn binary_type(&mut self, op: BinOp, a: &Expr, b: &Expr) -> Type {
        let absent = a.ty.absent || b.ty.absent;
        let lenient = a.ty.is_lenient() || b.ty.is_lenient();
        match op {
            BinOp::Coalesce => {
                if !lenient && !a.ty.fits(&b.ty) {
                    self.diags
                        .error(codes::TYPE_MISMATCH, b.span, format!("the default after `??` must be a {} like the value before it, but this is a {}", a.ty.present(), b.ty))
                        .label(format!("this is a {}", b.ty));
                    return Type::ERROR;
                }
                let base = if a.ty.is_lenient() { b.ty } else { a.ty };
                let mut t = base.present().maybe_absent(b.ty.absent);
                if let (TypeKind::Number { unit: None }, Some(u)) = (&t.kind, unit_of(&b.ty)) {
                    t.kind = TypeKind::Number { unit: Some(u) };
                }
                t
            }
            BinOp::And | BinOp::Or => {
                for x in [a, b] {
                    if !x.ty.is_bool() {
                        self.diags
                            .error(
                                codes::NOT_BOOL,
                                x.span,
                                format!(
                                    "`{}` needs conditions (bool), but this is a {}",
                                    op.symbol(),
                                    x.ty
                                ),
                            )
                            .label(format!("this is a {}", x.ty));
                    }
                }
                Type::BOOL.maybe_absent(absent)
            }
            BinOp::Eq | BinOp::Ne => {
                if !lenient && !a.ty.fits(&b.ty) {
                    self.diags.error(
                        codes::TYPE_MISMATCH,
                        op_span(a, b),
                        format!("cannot compare a {} with a {}", a.ty, b.ty),
                    );
                } else {
                    self.same_unit(op, a, b);
                }
                Type::BOOL.maybe_absent(absent)
            }
            BinOp::Lt | BinOp::Le | BinOp::Gt | BinOp::Ge => {
                let durations = a.ty.kind == TypeKind::Duration && b.ty.kind == TypeKind::Duration;
                if !durations {
                    self.numeric_operands(a, b);
                    self.same_unit(op, a, b);
                }
                Type::BOOL.maybe_absent(absent)
            }
            BinOp::Add | BinOp::Sub => {
                if a.ty.kind == TypeKind::Duration
                    && (b.ty.kind == TypeKind::Duration || b.ty.is_lenient())
                {
                    return Type::DURATION.maybe_absent(absent);
                }
                if a.ty.kind == TypeKind::String || b.ty.kind == TypeKind::String {
                    let s = if a.ty.kind == TypeKind::String { a } else { b };
                    self.diags
                        .error(
                            codes::NOT_A_NUMBER,
                            s.span,
                            format!("a string is used as a number in `{}`", op.symbol()),
                        )
                        .label("this is a string")
                        .help("to join text, interpolate: \"{a} {b}\"");
                    return Type::ERROR;
                }
                self.numeric_operands(a, b);
                let unit = self.same_unit(op, a, b);
                Type::number_in(unit).maybe_absent(absent)
            }
            BinOp::Mul | BinOp::Div => {
                if a.ty.kind == TypeKind::Duration && b.ty.is_numeric() {
                    return Type::DURATION.maybe_absent(absent);
                }
                self.numeric_operands(a, b);
                Type::number().maybe_absent(absent)
            }
            BinOp::Range => {
                self.numeric_operands(a, b);
                let unit = self.same_unit(op, a, b);
                Type::new(TypeKind::Range { unit }).maybe_absent(absent)
            }
        }
    }

    fn numeric_operands(&mut self, a: &Expr, b: &Expr) {
        for x in [a, b] {
            if !x.ty.is_numeric() {
                self.not_a_number(x, &"an operand");
            }
        }
    }

    /// Checks that both sides have the same unit when both have one; returns the result unit.
    fn same_unit(&mut self, op: BinOp, a: &Expr, b: &Expr) -> Option<Name> {
        match (unit_of(&a.ty), unit_of(&b.ty)) {
            (Some(x), Some(y)) if x != y => {
                self.diags
                    .error(
                        codes::UNIT_MISMATCH,
                        op_span(a, b),
                        format!("`{}` of {x} and {y}", op.symbol()),
                    )
                    .label(format!("{x} {} {y}", op.symbol()))
                    .help(format!(
                        "convert one side first, e.g. multiply by a factor, so both are in {x}"
                    ));
                None
            }
            (Some(x), _) | (_, Some(x)) => Some(x),
            _ => None,
        }
    }
}

fn op_span(a: &Expr, b: &Expr) -> Span {
    a.span.to(b.span)
}

/// Parses `[0][width][.precision]`.
pub fn parse_spec(s: &str) -> Option<FormatSpec> {
    let (int, prec) = match s.split_once('.') {
        Some((i, p)) => (i, Some(p)),
        None => (s, None),
    };
    if !int.chars().all(|c| c.is_ascii_digit())
        || prec.is_some_and(|p| p.is_empty() || !p.chars().all(|c| c.is_ascii_digit()))
    {
        return None;
    }
    Some(FormatSpec {
        zero: int.starts_with('0') && int.len() > 1,
        width: if int.is_empty() { None } else { int.parse().ok() },
        precision: match prec {
            Some(p) => Some(p.parse().ok()?),
            None => None,
        },
    })
}

fn want_text(t: &Type) -> &'static str {
    if t.kind == TypeKind::Duration { "a duration" } else { "a number" }
}

/// A path the schema does not type (dynamic), given to a parameter of a value type, is read
/// as that type (a `string?` parameter reads a string), absent when it is something else.
fn read_as(mut b: Bound, ty: &Type) -> Bound {
    let value = matches!(
        ty.kind,
        TypeKind::String | TypeKind::Number { .. } | TypeKind::Bool | TypeKind::Colour
    );
    if b.expr.ty.kind == TypeKind::Dynamic && value {
        b.expr.ty = Type { kind: ty.kind, absent: true };
    }
    b
}

/// The unit of a number or range type.
fn unit_of(t: &Type) -> Option<Name> {
    match t.kind {
        TypeKind::Number { unit } | TypeKind::Range { unit } => unit,
        _ => None,
    }
}
