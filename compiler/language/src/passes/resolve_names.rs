//! Pass 3: every name used resolves. Reports unknown names and functions (E0204), unknown
//! components (E0205), windows (E0206), input devices and inputs (E0207), parameters and
//! events (E0208) and missing required arguments (E0209). Records which `let`s are used, for
//! `warn_unused`. Runs after `collect_definitions` (it needs the tables) and before
//! `check_types`, which can then treat an unresolved name as already reported.

use super::{DefId, Definitions, ModuleId, Modules, component_item};
use crate::ast::*;
use crate::builtins;
use crate::codes;
use crate::diagnostics::Diagnostics;
use std::rc::Rc;

/// A component's parameter names with whether each is required, and its events.
type ParamsAndEvents<'a> = (Vec<(&'a str, bool)>, Vec<&'a str>);

/// The spans of `let` names that some expression reads.
pub type UsedLets = super::FastSet<crate::source::Span>;

pub fn resolve_names(modules: &Modules, defs: &Definitions, diags: &mut Diagnostics) -> UsedLets {
    resolve_modules(modules, defs, None, diags)
}

/// [`resolve_names`] for a check in batches (`crate::lint`): the layout's components (read
/// without bodies so far) are left for [`resolve_items`].
pub fn resolve_resident(
    modules: &Modules,
    defs: &Definitions,
    diags: &mut Diagnostics,
) -> UsedLets {
    resolve_modules(modules, defs, Some(0), diags)
}

fn resolve_modules(
    modules: &Modules,
    defs: &Definitions,
    skip_components_of: Option<ModuleId>,
    diags: &mut Diagnostics,
) -> UsedLets {
    let mut r = Resolver {
        modules,
        defs,
        diags,
        used: UsedLets::default(),
        signatures: Default::default(),
    };
    for m in 0..modules.len() {
        r.module(m, skip_components_of == Some(m));
    }
    r.used
}

/// Resolves items of the layout (module 0) that are not in its tree (a batch of
/// `crate::lint`), adding the `let`s they read to `used`.
pub fn resolve_items(
    modules: &Modules,
    defs: &Definitions,
    items: &[Item],
    used: &mut UsedLets,
    diags: &mut Diagnostics,
) {
    let mut r = Resolver {
        modules,
        defs,
        diags,
        used: std::mem::take(used),
        signatures: Default::default(),
    };
    let base = Scope::default();
    for item in items {
        r.item(item, &base, None);
    }
    *used = r.used;
}

struct Resolver<'a, 'd> {
    modules: &'a Modules,
    defs: &'a Definitions,
    diags: &'d mut Diagnostics,
    used: UsedLets,
    /// The signatures of the components used so far, by module and name.
    signatures: super::FastMap<(ModuleId, &'a str), Rc<ParamsAndEvents<'a>>>,
}

#[derive(Clone, Default)]
struct Scope<'a> {
    module: ModuleId,
    limit: Option<usize>,
    /// Names borrowed from the syntax trees (or built in): cloning a scope copies no text.
    locals: Vec<(&'a str, Option<crate::source::Span>)>,
    self_ok: bool,
    /// In an action: `selected` names the selected object.
    selected_ok: bool,
    /// In a `for each`'s `flow` region: that template's variable (not known there).
    flow_of: Option<&'a str>,
}

impl<'a> Scope<'a> {
    fn with(&self, name: &'a str, let_span: Option<crate::source::Span>) -> Scope<'a> {
        let mut s = self.clone();
        s.locals.push((name, let_span));
        s
    }
}

impl<'a> Resolver<'a, '_> {
    fn module(&mut self, m: ModuleId, skip_components: bool) {
        let base = Scope { module: m, ..Scope::default() };
        for (i, item) in self.modules[m].ast.items.iter().enumerate() {
            if !(skip_components && matches!(item, Item::Component(_))) {
                self.item(item, &base, Some(i));
            }
        }
    }

    fn item(&mut self, item: &'a Item, scope: &Scope<'a>, index: Option<usize>) {
        match item {
            Item::Use(_) | Item::Design(_) => {}
            Item::Let(l) => {
                let s = Scope { limit: index, ..scope.clone() };
                self.expr(&l.value, &s);
            }
            Item::Window(w) => {
                w.rect.iter().flatten().for_each(|e| self.expr(e, scope));
                for p in &w.props {
                    if builtins::window_prop_type(&p.name.name).is_none() {
                        self.diags
                            .error(
                                codes::UNKNOWN_PARAM,
                                p.name.span,
                                format!("a window has no property `{}`", p.name.name),
                            )
                            .suggest(&p.name.name, builtins::WINDOW_PROPS.iter().copied());
                    }
                    self.expr(&p.value, scope);
                }
            }
            Item::In(b) => {
                self.window_ref(&b.window, scope.module);
                for w in &b.widgets {
                    self.widget(w, scope);
                }
            }
            Item::Component(c) => self.component(c, scope.module),
            Item::Bind(b) => self.bind(b, scope),
            Item::Menu(menu) => {
                let s = Scope { self_ok: true, ..scope.clone() };
                for e in &menu.entries {
                    self.expr(&e.label, &s);
                    if let Some(en) = &e.enabled {
                        self.expr(en, &s);
                    }
                    self.actions(&e.actions, &s);
                }
            }
            Item::Watch(w) => {
                self.expr(&w.when, scope);
                for e in [&w.hold, &w.clear, &w.repeat].into_iter().flatten() {
                    self.expr(e, scope);
                }
                self.actions(&w.actions, scope);
            }
            Item::Each(e) => {
                self.expr(&e.source, scope);
                // The flow's region is the template's: `v` and `index` are not known in it.
                let region = Scope { flow_of: Some(&e.var.name), ..scope.clone() };
                e.flow.iter().flat_map(|f| &f.rect).for_each(|x| self.expr(x, &region));
                let mut s = scope.with(&e.var.name, None).with("index", None);
                for inner in &e.items {
                    self.item(inner, &s, None);
                    if let Item::Let(l) = inner {
                        s.locals.push((&l.name.name, Some(l.name.span)));
                    }
                }
            }
        }
    }

    fn window_ref(&mut self, w: &Ident, m: ModuleId) {
        if self.defs.find_window(self.modules, m, &w.name).is_none() {
            self.diags
                .error(codes::UNKNOWN_WINDOW, w.span, format!("there is no window `{}`", w.name))
                .suggest(
                    &w.name,
                    self.defs.visible_windows(self.modules, m).iter().map(String::as_str),
                );
        }
    }

    fn widget(&mut self, w: &'a Widget, scope: &Scope<'a>) {
        if let Some((at, _)) = &w.at {
            at.iter().for_each(|e| self.expr(e, scope));
        }
        let m = scope.module;
        let signature = self.signature(w, m);
        self.widget_args(w, signature.as_deref(), scope);
    }

    /// The component's parameter names, whether each is required, and its events: worked
    /// out once per module and component (an unknown component is reported at each use).
    fn signature(&mut self, w: &'a Widget, m: ModuleId) -> Option<Rc<ParamsAndEvents<'a>>> {
        if let Some(known) = self.signatures.get(&(m, w.component.name.as_str())) {
            return Some(known.clone());
        }
        let signature: Option<ParamsAndEvents<'a>> = if let Some(n) =
            builtins::native(&w.component.name)
        {
            Some((n.params.iter().map(|(p, _, d)| (*p, !d)).collect(), n.events.to_vec()))
        } else if let Some(id) = self.defs.find_component(self.modules, m, &w.component.name) {
            component_item(self.modules, id).map(|c| {
                let mut params = Vec::new();
                let mut events = Vec::new();
                for p in &c.params {
                    match p {
                        Param::Value { name, default, .. } => {
                            params.push((name.name.as_str(), default.is_none()))
                        }
                        Param::Event { name } => events.push(name.name.as_str()),
                    }
                }
                (params, events)
            })
        } else {
            let d = self.diags.error(
                codes::UNKNOWN_COMPONENT,
                w.component.span,
                format!("there is no component `{}`", w.component.name),
            );
            match stdlib_file_of(&w.component.name) {
                Some(file) => {
                    d.help(format!(
                        "`{}` is in {file}: add `use \"{file}\"` at the top of the file",
                        w.component.name
                    ));
                }
                None => {
                    let visible = self.defs.visible_components(self.modules, m);
                    let names = visible
                        .iter()
                        .map(String::as_str)
                        .chain(stdlib_components().map(|(_, c)| c));
                    match crate::diagnostics::did_you_mean(&w.component.name, names) {
                        Some(best) => match stdlib_file_of(&best).filter(|_| !visible.contains(&best)) {
                            Some(file) => d.help(format!("did you mean `{best}` (in {file}: add `use \"{file}\"`)?")),
                            None => d.help(format!("did you mean `{best}`?")),
                        },
                        None => d.help("define it with `component`, or `use` the file that defines it (e.g. \"stdlib/gauges.mocu\")"),
                    };
                }
            }
            None
        };
        let signature = signature.map(Rc::new);
        if let Some(s) = &signature {
            self.signatures.insert((m, &w.component.name), s.clone());
        }
        signature
    }

    /// A widget's arguments against its component's signature, then its handlers.
    fn widget_args(
        &mut self,
        w: &'a Widget,
        signature: Option<&ParamsAndEvents<'a>>,
        scope: &Scope<'a>,
    ) {
        let mut arg_scope = scope.clone();
        if signature.is_none() {
            // Unknown component: its arguments may name each other (`alarm value > 35`); no
            // follow-on "unknown name" for them.
            for a in &w.args {
                arg_scope.locals.push((&a.name.name, None));
            }
        }
        if let Some((params, _)) = &signature {
            for (p, _) in params {
                arg_scope.locals.push((p, None));
            }
        }
        for (i, a) in w.args.iter().enumerate() {
            // `range 0 to 40` where `range` is unknown too: that is the one diagnostic.
            let after_unknown = |p: &str| {
                i.checked_sub(1).is_some_and(|k| {
                    let prev = &w.args[k].name.name;
                    prev != "visible" && !params_has(signature, prev) && p == "to"
                })
            };
            if let Some((params, _)) = &signature
                && a.name.name != "visible"
                && !params.iter().any(|(p, _)| *p == a.name.name)
                && !after_unknown(&a.name.name)
            {
                let d = self.diags.error(
                    codes::UNKNOWN_PARAM,
                    a.name.span,
                    format!("`{}` has no parameter `{}`", w.component.name, a.name.name),
                );
                match i.checked_sub(1).map(|p| &w.args[p]) {
                    // `range 0 to 40`: the `to` reads as a parameter.
                    Some(prev) if a.name.name == "to" => {
                        let number = |e: &Expr| match &e.kind {
                            ExprKind::Number { value, .. } => value.to_string(),
                            ExprKind::Unary(crate::ast::UnOp::Neg, arg) => match arg.kind {
                                ExprKind::Number { value, .. } => format!("-{value}"),
                                _ => "MIN".into(),
                            },
                            _ => "MIN".into(),
                        };
                        let (min, max) = (number(&prev.value), number(&a.value));
                        d.help(crate::syntax_hints::range_help(&prev.name.name, &min, &max));
                    }
                    _ => {
                        d.suggest(&a.name.name, params.iter().map(|(p, _)| *p));
                    }
                }
            }
            self.expr(&a.value, &arg_scope);
        }
        if let Some((params, events)) = &signature {
            for (p, required) in params {
                if *required && !w.args.iter().any(|a| a.name.name == **p) {
                    self.diags
                        .error(
                            codes::MISSING_ARG,
                            w.component.span,
                            format!("`{}` needs the argument `{p}`", w.component.name),
                        )
                        .help(format!("add `{p} …` inside the braces"));
                }
            }
            for h in &w.handlers {
                if !events.contains(&h.event.name.as_str()) {
                    self.diags
                        .error(
                            codes::UNKNOWN_PARAM,
                            h.event.span,
                            format!("`{}` has no event `{}`", w.component.name, h.event.name),
                        )
                        .suggest(&h.event.name, events.iter().copied());
                }
            }
        }
        for h in &w.handlers {
            self.actions(&h.actions, scope);
        }
    }

    fn component(&mut self, c: &'a Component, m: ModuleId) {
        let mut s = Scope { module: m, ..Scope::default() }.with("w", None).with("h", None);
        for p in &c.params {
            if let Param::Value { default: Some(d), .. } = p {
                self.expr(d, &Scope { module: m, ..Scope::default() });
            }
            s.locals.push((&p.name().name, None));
        }
        for stmt in &c.body {
            match stmt {
                Stmt::Let(l) => {
                    self.expr(&l.value, &s);
                    s.locals.push((&l.name.name, Some(l.name.span)));
                }
                Stmt::Primitive(p) => {
                    p.args.iter().for_each(|e| self.expr(e, &s));
                    p.styles.iter().for_each(|st| self.expr(&st.value, &s));
                }
            }
        }
    }

    fn actions(&mut self, actions: &'a [Action], scope: &Scope<'a>) {
        let with_selected = Scope { selected_ok: true, ..scope.clone() };
        let scope = &with_selected;
        for a in actions {
            match &a.kind {
                ActionKind::Set { target, value } => {
                    self.expr(target, scope);
                    self.expr(value, scope);
                }
                ActionKind::Call { call } => self.expr(call, scope),
                ActionKind::Swap { a, b, duration } => {
                    self.window_ref(a, scope.module);
                    self.window_ref(b, scope.module);
                    if let Some(d) = duration {
                        self.expr(d, scope);
                    }
                }
                ActionKind::Show { window } | ActionKind::Hide { window } => {
                    self.window_ref(window, scope.module)
                }
                ActionKind::Mode { .. }
                | ActionKind::Script { .. }
                | ActionKind::Select { target: SelectTarget::Next }
                | ActionKind::Select { target: SelectTarget::Prev } => {}
                ActionKind::Select { target: SelectTarget::Object(e) } => self.expr(e, scope),
                ActionKind::Alert { level, message } => {
                    if !builtins::ALERT_LEVELS.contains(&level.name.as_str()) {
                        self.diags
                            .error(
                                codes::UNKNOWN_NAME,
                                level.span,
                                format!("there is no alert level `{}`", level.name),
                            )
                            .suggest(&level.name, builtins::ALERT_LEVELS.iter().copied())
                            .help
                            .get_or_insert_with(|| {
                                "alert levels are `info`, `warning` and `critical`".into()
                            });
                    }
                    self.expr(message, scope);
                }
            }
        }
    }

    fn name(&mut self, name: &str, span: crate::source::Span, scope: &Scope<'a>) {
        if let Some((_, let_span)) = scope.locals.iter().rev().find(|(n, _)| *n == name) {
            if let Some(s) = let_span {
                self.used.insert(*s);
            }
            return;
        }
        if let Some(id) = self.defs.find_let(self.modules, scope.module, name, scope.limit) {
            self.mark(id);
            return;
        }
        if name == "root" {
            return;
        }
        if name == "selected" {
            if !scope.selected_ok {
                self.diags
                    .error(codes::UNKNOWN_NAME, span, "`selected` is only known in actions")
                    .help("`selected` is the object in `root.operator.selected`: use it in `set`, `call` or `select`");
            }
            return;
        }
        if self.defs.namespace(self.modules, scope.module, name).is_some() {
            self.diags
                .error(codes::UNKNOWN_NAME, span, format!("`{name}` is a namespace, not a value"))
                .help(format!("name one of its definitions: `{name}.something`"));
            return;
        }
        let d = self.diags.error(codes::UNKNOWN_NAME, span, format!("unknown name `{name}`"));
        d.label("not found in this scope");
        if let Some(var) = scope.flow_of.filter(|v| name == *v || name == "index") {
            d.help(format!("a flow's region is the template's, placed once for all its instances: `{var}` and `index` are not known in it"));
            return;
        }
        if scope.limit.is_some() && self.defs.lets[scope.module].contains_key(name) {
            d.help(format!(
                "`{name}` is defined further down: a `let` can only use the lets above it"
            ));
            return;
        }
        let mut candidates = self.defs.visible_names(self.modules, scope.module);
        candidates.extend(scope.locals.iter().map(|(n, _)| n.to_string()));
        d.suggest(name, candidates.iter().map(String::as_str));
        if d.help.is_none() {
            d.help("world-model paths start at `root`, e.g. `root.vehicles.usv1.nav.speed`");
        }
    }

    fn mark(&mut self, id: DefId) {
        if let Some(l) = super::let_item(self.modules, id) {
            self.used.insert(l.name.span);
        }
    }

    fn expr(&mut self, e: &'a Expr, scope: &Scope<'a>) {
        match &e.kind {
            ExprKind::Name(n) => self.name(n, e.span, scope),
            ExprKind::SelfRef => {
                if !scope.self_ok {
                    self.diags
                        .error(codes::UNKNOWN_NAME, e.span, "`self` is only known inside a `menu`")
                        .help("`self` is the object the menu was opened on");
                }
            }
            ExprKind::Field(base, field) => {
                if let ExprKind::Name(ns) = &base.kind {
                    let shadowed = scope.locals.iter().any(|(n, _)| *n == ns)
                        || self
                            .defs
                            .find_let(self.modules, scope.module, ns, scope.limit)
                            .is_some();
                    if let (false, Some(target)) =
                        (shadowed, self.defs.namespace(self.modules, scope.module, ns))
                    {
                        match self.defs.lets[target].get(&field.name) {
                            Some(id) => self.mark(*id),
                            None => {
                                self.diags
                                    .error(
                                        codes::UNKNOWN_NAME,
                                        field.span,
                                        format!("`{ns}` has no `{}`", field.name),
                                    )
                                    .suggest(
                                        &field.name,
                                        self.defs.lets[target].keys().map(String::as_str),
                                    );
                            }
                        }
                        return;
                    }
                }
                self.expr(base, scope);
            }
            ExprKind::Index(base, _) => self.expr(base, scope),
            ExprKind::Call(callee, args) => {
                match &callee.kind {
                    ExprKind::Name(f) => {
                        if builtins::function(f).is_none() {
                            self.diags
                                .error(
                                    codes::UNKNOWN_NAME,
                                    callee.span,
                                    format!("unknown function `{f}`"),
                                )
                                .suggest(f, builtins::FUNCTIONS.iter().map(|f| f.name))
                                .help
                                .get_or_insert_with(|| {
                                    "see docs/language.md, \"Built-in functions\"".into()
                                });
                        }
                    }
                    _ => self.expr(callee, scope),
                }
                args.iter().for_each(|a| self.expr(a, scope));
            }
            ExprKind::Unary(_, a) => self.expr(a, scope),
            ExprKind::Binary(_, a, b) => {
                self.expr(a, scope);
                self.expr(b, scope);
            }
            ExprKind::If(c, a, b) => {
                self.expr(c, scope);
                self.expr(a, scope);
                self.expr(b, scope);
            }
            ExprKind::Str(parts) => {
                for p in parts {
                    if let StrPart::Interp { expr, .. } = p {
                        self.expr(expr, scope);
                    }
                }
            }
            ExprKind::Number { .. } | ExprKind::Colour(_) | ExprKind::Bool(_) | ExprKind::Error => {
            }
        }
    }
}

/// The standard library, read at build time: which file defines which component.
const STDLIB: &[(&str, &str)] = &[
    ("stdlib/alerts.mocu", include_str!("../../../../stdlib/alerts.mocu")),
    ("stdlib/controls.mocu", include_str!("../../../../stdlib/controls.mocu")),
    ("stdlib/frames.mocu", include_str!("../../../../stdlib/frames.mocu")),
    ("stdlib/gauges.mocu", include_str!("../../../../stdlib/gauges.mocu")),
    ("stdlib/manipulator.mocu", include_str!("../../../../stdlib/manipulator.mocu")),
    ("stdlib/status.mocu", include_str!("../../../../stdlib/status.mocu")),
    ("stdlib/theme.mocu", include_str!("../../../../stdlib/theme.mocu")),
];

/// Every (file, component) of the standard library.
fn stdlib_components() -> impl Iterator<Item = (&'static str, &'static str)> {
    STDLIB.iter().flat_map(|(file, text)| {
        text.lines().filter_map(|l| l.strip_prefix("component ")).map(move |rest| {
            let end = rest.find(|c: char| !(c.is_alphanumeric() || c == '_')).unwrap_or(rest.len());
            (*file, &rest[..end])
        })
    })
}

/// The standard-library file that defines a component, for "`Button` is in
/// stdlib/controls.mocu".
fn stdlib_file_of(component: &str) -> Option<&'static str> {
    stdlib_components().find(|(_, c)| *c == component).map(|(f, _)| f)
}

/// Whether a component's signature (when known) has parameter `name`.
fn params_has(signature: Option<&ParamsAndEvents>, name: &str) -> bool {
    signature.is_some_and(|(params, _)| params.iter().any(|(p, _)| *p == name))
}

mod bindings;
