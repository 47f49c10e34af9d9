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
    let (program, carry) = type_modules(modules, defs, schema, None, diags);
    report_unknown_modes(carry.mode_refs, &declared_modes(&program.bindings), diags);
    program
}

/// What typing carries from one batch of the layout's items to the next (`crate::lint`):
/// the checked top-level `let`s, the program's `let`s, and the `mode` actions seen so far.
#[derive(Default)]
pub struct Carry {
    top_lets: FastMap<DefId, Expr>,
    lets_lowered: Vec<usize>,
    lets: Vec<LetRef>,
    mode_refs: Vec<(String, Span)>,
}

impl Carry {
    /// Reports the `mode` actions seen that no `bind` block declares (`declared`: every
    /// mode of the program's bindings, in program order).
    pub fn report_unknown_modes(self, declared: &[String], diags: &mut Diagnostics) {
        report_unknown_modes(self.mode_refs, declared, diags);
    }
}

/// [`check_types`] for a check in batches (`crate::lint`): the program of everything but the
/// layout's components and the items [`crate::parser::parse_resident`] left for later, which
/// [`check_types_items`] types; modes are reported by [`Carry::report_unknown_modes`].
pub fn check_types_resident(
    modules: &Modules,
    defs: &Definitions,
    schema: &Schema,
    diags: &mut Diagnostics,
) -> (Program, Carry) {
    let (program, mut carry) = type_modules(modules, defs, schema, Some(0), diags);
    // The batches number their `let`s after these.
    carry.lets = program.lets.0.clone();
    (program, carry)
}

/// Types items of the layout (module 0) that are not in its tree: the program of just these
/// (its `lets` are the `let`s they made), `carry` updated.
pub fn check_types_items(
    modules: &Modules,
    defs: &Definitions,
    schema: &Schema,
    carry: &mut Carry,
    items: &[Item],
    diags: &mut Diagnostics,
) -> Program {
    let before = carry.lets.len();
    let mut t = Typer::new(modules, defs, schema, diags, std::mem::take(carry));
    let base = Scope::default();
    let mut sink = Sink::default();
    for item in items {
        t.item(item, &base, &mut sink);
    }
    let (mut program, mut back) = t.finish();
    program.windows = sink.windows;
    program.widgets = sink.widgets;
    program.watches = sink.watches;
    program.lets = Lets(back.lets.split_off(before));
    *carry = back;
    program
}

/// The modes that `bind` blocks declare, in program order (with repeats).
pub fn declared_modes(bindings: &[Binding]) -> Vec<String> {
    bindings.iter().filter_map(|b| b.mode.clone()).collect()
}

fn type_modules(
    modules: &Modules,
    defs: &Definitions,
    schema: &Schema,
    skip_components_of: Option<ModuleId>,
    diags: &mut Diagnostics,
) -> (Program, Carry) {
    let carry = Carry { lets_lowered: vec![0; modules.len()], ..Carry::default() };
    let mut t = Typer::new(modules, defs, schema, diags, carry);
    t.skip_components_of = skip_components_of;
    t.program.files = modules.iter().map(|m| m.path.clone()).collect();
    for m in 0..modules.len() {
        t.module(m);
    }
    let (mut program, mut carry) = t.finish();
    program.lets = Lets(std::mem::take(&mut carry.lets));
    program.windows.shrink_to_fit();
    program.widgets.shrink_to_fit();
    program.components.shrink_to_fit();
    program.bindings.shrink_to_fit();
    program.watches.shrink_to_fit();
    (program, carry)
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
    /// A module whose components are typed elsewhere ([`check_types_items`]).
    skip_components_of: Option<ModuleId>,
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

impl<'a, 'd> Typer<'a, 'd> {
    fn new(
        modules: &'a Modules,
        defs: &'a Definitions,
        schema: &'a Schema,
        diags: &'d mut Diagnostics,
        carry: Carry,
    ) -> Typer<'a, 'd> {
        Typer {
            modules,
            defs,
            schema,
            diags,
            top_lets: carry.top_lets,
            lets_lowered: carry.lets_lowered,
            lets: carry.lets,
            program: Program::default(),
            mode_refs: carry.mode_refs,
            signatures: FastMap::default(),
            skip_components_of: None,
        }
    }

    /// The program so far, and what the next batch needs.
    fn finish(self) -> (Program, Carry) {
        let carry = Carry {
            top_lets: self.top_lets,
            lets_lowered: self.lets_lowered,
            lets: self.lets,
            mode_refs: self.mode_refs,
        };
        (self.program, carry)
    }
}

impl<'a> Typer<'a, '_> {
    fn module(&mut self, m: ModuleId) {
        let base = Scope { module: m, ..Scope::default() };
        let modules = self.modules;
        // The program's lists, reserved to what this module adds: they are alive (with the
        // syntax trees) until the end of the check, so no room is left spare and nothing is
        // copied from a list of the module's own (issue 13's memory figure).
        let p = &mut self.program;
        let mut sink = Sink {
            windows: std::mem::take(&mut p.windows),
            widgets: std::mem::take(&mut p.widgets),
            watches: std::mem::take(&mut p.watches),
        };
        let items = &modules[m].ast.items;
        let count = |f: fn(&Item) -> usize| items.iter().map(f).sum::<usize>();
        sink.windows.reserve_exact(count(|i| usize::from(matches!(i, Item::Window(_)))));
        sink.widgets
            .reserve_exact(count(|i| if let Item::In(b) = i { b.widgets.len() } else { 0 }));
        sink.watches.reserve_exact(count(|i| usize::from(matches!(i, Item::Watch(_)))));
        let skip = self.skip_components_of == Some(m);
        if !skip {
            p.components.reserve_exact(count(|i| usize::from(matches!(i, Item::Component(_)))));
        }
        p.menus.reserve_exact(count(|i| usize::from(matches!(i, Item::Menu(_)))));
        p.bindings.reserve_exact(count(|i| match i {
            Item::Bind(b) => b.bindings.len() + b.modes.iter().map(|m| m.1.len()).sum::<usize>(),
            _ => 0,
        }));
        for (i, item) in items.iter().enumerate() {
            if let Item::Let(_) = item {
                // Checked even when unused; uses refer to this result.
                self.lower_top_let(DefId { module: m, item: i, inner: None });
            }
            if !(skip && matches!(item, Item::Component(_))) {
                self.item(item, &base, &mut sink);
            }
        }
        self.program.windows = sink.windows;
        self.program.widgets = sink.widgets;
        self.program.watches = sink.watches;
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
                // The region is the template's, not an instance's: read without `v`, `index`.
                let flow = e.flow.as_ref().map(|f| self.flow(f, scope));
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
                    flow,
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
            rect: match &w.rect {
                Some(rect) => rect.iter().map(|g| self.geometry(g, scope)).collect(),
                None => {
                    let full = || {
                        let ty = Type::number_in(Some(literal_unit("%")));
                        Bound::new(mk(ty, Node::Number(100.0), span))
                    };
                    vec![konst(0.0), konst(0.0), full(), full()]
                }
            },
            anchor: anchor_of(w.anchor.as_ref()),
            opacity: konst(1.0),
            visible: Bound::new(mk(Type::BOOL, Node::Bool(true), span)),
            source: None,
            span,
        };
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

    /// A `flow` clause; its direction and gap are checked in passes/check_flows.rs.
    fn flow(&mut self, f: &ast::Flow, scope: &Scope<'a>) -> crate::program::Flow {
        let gap = match f.gap.as_ref().map(|g| &g.kind) {
            Some(ast::ExprKind::Number { value, .. }) => *value,
            _ => 0.0,
        };
        crate::program::Flow {
            down: f.direction.name != "right",
            rect: f.rect.iter().map(|g| self.geometry(g, scope)).collect(),
            anchor: anchor_of(f.anchor.as_ref()),
            gap,
            span: f.span,
        }
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
}

mod actions;
mod components;
mod exprs;
use components::report_unknown_modes;
pub use exprs::parse_spec;
use exprs::{read_as, want_text};
