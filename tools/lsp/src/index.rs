//! What names mean: every definition (`let`, window, component, parameter, watch, widget, a
//! component's or template's local) and every use of one, across a document and the files it
//! `use`s, resolved as the checker resolves them (`collect_definitions`' tables). Go to
//! definition, references, rename, hover and semantic tokens read it.

use mocu_language::ast::*;
use mocu_language::incremental::ItemCache;
use mocu_language::passes::{self, Definitions, ModuleId, Modules};
use mocu_language::{Diagnostics, SourceLoader, SourceMap};
use std::collections::HashMap;

/// What a name is.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Kind {
    Let,
    Window,
    Component,
    Param,
    Watch,
    Widget,
    /// A component's own `let`, or a `for each` variable.
    Local,
}

/// A definition: (file path, byte offset of its name).
pub type DefKey = (String, u32);

/// One definition.
#[derive(Clone, Debug)]
pub struct Def {
    pub kind: Kind,
    pub name: String,
    pub path: String,
    pub start: u32,
    pub end: u32,
    /// Where its value starts (`let`s), its component (parameters).
    pub value_start: Option<u32>,
    pub owner: Option<String>,
}

/// A name in the text: a definition or a use of one.
#[derive(Clone, Debug)]
pub struct Occurrence {
    pub path: String,
    pub start: u32,
    pub end: u32,
    pub def: DefKey,
    pub is_def: bool,
}

/// The names of a document and everything it uses.
#[derive(Default)]
pub struct Index {
    pub defs: HashMap<DefKey, Def>,
    pub occurrences: Vec<Occurrence>,
    pub modules: Modules,
    pub tables: Definitions,
    /// The texts of the files read.
    pub sources: SourceMap,
}

impl Index {
    /// Parses `path` (its text from `loader`) and its `use`s, reusing the trees in `cache`,
    /// and resolves every name.
    pub fn build(path: &str, loader: &dyn SourceLoader, cache: &mut ItemCache) -> Index {
        let Ok(text) = loader.read(path) else { return Index::default() };
        let mut sources = SourceMap::new();
        let mut diags = Diagnostics::new();
        let modules = cache.load_sources(path, text, loader, &mut sources, &mut diags);
        let tables = passes::collect_definitions::collect_definitions(&modules, &mut diags);
        let mut ix = Index { modules, tables, sources, ..Index::default() };
        for m in 0..ix.modules.len() {
            // A copy: resolving reads the modules' items while this module's are walked.
            let items = ix.modules[m].ast.items.clone();
            let scope = Scope { module: m, locals: Vec::new() };
            for item in &items {
                ix.item(item, &scope);
            }
        }
        ix
    }

    /// The occurrence at byte `offset` of `path` (touching its end counts).
    pub fn at(&self, path: &str, offset: usize) -> Option<&Occurrence> {
        let o = offset as u32;
        self.occurrences.iter().find(|x| x.path == path && x.start <= o && o <= x.end)
    }

    /// Every occurrence of a definition, the definition first.
    pub fn uses_of(&self, key: &DefKey) -> Vec<&Occurrence> {
        let mut v: Vec<&Occurrence> = self.occurrences.iter().filter(|o| &o.def == key).collect();
        v.sort_by_key(|o| (!o.is_def, o.path.clone(), o.start));
        v.dedup_by_key(|o| (o.path.clone(), o.start));
        v
    }

    /// The text of a file the index read.
    pub fn text(&self, path: &str) -> &str {
        self.sources.find(path).map_or("", |f| self.sources.get(f).text.as_str())
    }

    /// The top-level `let` named `name` seen from the document (module 0).
    pub fn visible_let(&self, name: &str) -> Option<&Def> {
        let id = self.tables.find_let(&self.modules, 0, name, None)?;
        self.defs.get(&self.key_of(id)?)
    }

    fn path(&self, m: ModuleId) -> String {
        self.modules[m].path.clone()
    }

    fn define(
        &mut self,
        m: ModuleId,
        kind: Kind,
        name: &Ident,
        value_start: Option<u32>,
        owner: Option<&str>,
    ) -> Option<DefKey> {
        if name.name.is_empty() {
            return None;
        }
        let path = self.path(m);
        let key = (path.clone(), name.span.start);
        self.defs.entry(key.clone()).or_insert(Def {
            kind,
            name: name.name.clone(),
            path: path.clone(),
            start: name.span.start,
            end: name.span.end,
            value_start,
            owner: owner.map(str::to_string),
        });
        self.occurrences.push(Occurrence {
            path,
            start: name.span.start,
            end: name.span.end,
            def: key.clone(),
            is_def: true,
        });
        Some(key)
    }

    fn refer(&mut self, m: ModuleId, start: u32, end: u32, def: Option<DefKey>) {
        if let Some(def) = def {
            self.occurrences.push(Occurrence {
                path: self.path(m),
                start,
                end,
                def,
                is_def: false,
            });
        }
    }

    /// The key of a top-level item's name.
    fn key_of(&self, id: passes::DefId) -> Option<DefKey> {
        let name = match passes::item(&self.modules, id)? {
            Item::Let(l) => &l.name,
            Item::Window(w) => &w.name,
            Item::Component(c) => &c.name,
            _ => return None,
        };
        Some((self.modules[id.module].path.clone(), name.span.start))
    }

    fn window(&self, m: ModuleId, name: &str) -> Option<DefKey> {
        self.tables.find_window(&self.modules, m, name).and_then(|id| self.key_of(id))
    }

    fn component(&self, m: ModuleId, name: &str) -> Option<passes::DefId> {
        self.tables.find_component(&self.modules, m, name)
    }

    fn item(&mut self, item: &Item, scope: &Scope) {
        let m = scope.module;
        match item {
            Item::Use(_) => {}
            Item::Design(d) => {
                self.expr(&d.width, scope);
                self.expr(&d.height, scope);
            }
            Item::Let(l) => {
                self.define(m, Kind::Let, &l.name, Some(l.value.span.start), None);
                self.expr(&l.value, scope);
            }
            Item::Window(w) => {
                self.define(m, Kind::Window, &w.name, None, None);
                w.rect.iter().flatten().for_each(|e| self.expr(e, scope));
                w.props.iter().for_each(|p| self.expr(&p.value, scope));
            }
            Item::In(b) => {
                let def = self.window(m, &b.window.name);
                self.refer(m, b.window.span.start, b.window.span.end, def);
                for w in &b.widgets {
                    self.widget(w, scope);
                }
            }
            Item::Component(c) => self.component_def(c, scope),
            Item::Bind(b) => {
                let all = b.bindings.iter().chain(b.modes.iter().flat_map(|(_, v)| v));
                for binding in all {
                    binding
                        .options
                        .iter()
                        .filter_map(|o| o.value.as_ref())
                        .for_each(|e| self.expr(e, scope));
                    binding.actions.iter().for_each(|a| self.action(a, scope));
                }
            }
            Item::Menu(menu) => {
                for e in &menu.entries {
                    self.expr(&e.label, scope);
                    e.enabled.iter().for_each(|x| self.expr(x, scope));
                    e.actions.iter().for_each(|a| self.action(a, scope));
                }
            }
            Item::Watch(w) => {
                self.define(m, Kind::Watch, &w.name, None, None);
                self.expr(&w.when, scope);
                [&w.hold, &w.clear, &w.repeat]
                    .into_iter()
                    .flatten()
                    .for_each(|e| self.expr(e, scope));
                w.actions.iter().for_each(|a| self.action(a, scope));
            }
            Item::Each(e) => {
                self.expr(&e.source, scope);
                let inner = match self.define(m, Kind::Local, &e.var, None, None) {
                    Some(k) => scope.with(&e.var.name, k),
                    None => scope.clone(),
                };
                for i in &e.items {
                    self.item(i, &inner);
                }
            }
        }
    }

    fn widget(&mut self, w: &Widget, scope: &Scope) {
        let m = scope.module;
        if let Some(n) = &w.name {
            self.define(m, Kind::Widget, n, None, Some(&w.component.name));
        }
        let comp = self.component(m, &w.component.name);
        let comp_key = comp.and_then(|id| self.key_of(id));
        self.refer(m, w.component.span.start, w.component.span.end, comp_key);
        if let Some((at, _)) = &w.at {
            at.iter().for_each(|e| self.expr(e, scope));
        }
        let params: Vec<(String, DefKey)> = comp
            .and_then(|id| {
                let c = passes::component_item(&self.modules, id)?;
                let path = self.modules[id.module].path.clone();
                Some(
                    c.params
                        .iter()
                        .map(|p| (p.name().name.clone(), (path.clone(), p.name().span.start)))
                        .collect(),
                )
            })
            .unwrap_or_default();
        let param = |name: &str| params.iter().find(|(n, _)| n == name).map(|(_, k)| k.clone());
        for a in &w.args {
            self.refer(m, a.name.span.start, a.name.span.end, param(&a.name.name));
            self.expr(&a.value, scope);
        }
        for h in &w.handlers {
            self.refer(m, h.event.span.start, h.event.span.end, param(&h.event.name));
            h.actions.iter().for_each(|a| self.action(a, scope));
        }
    }

    fn component_def(&mut self, c: &Component, scope: &Scope) {
        let m = scope.module;
        self.define(m, Kind::Component, &c.name, None, None);
        let mut inner = scope.clone();
        for p in &c.params {
            if let Param::Value { default: Some(d), .. } = p {
                self.expr(d, &inner);
            }
            if let Some(k) = self.define(m, Kind::Param, p.name(), None, Some(&c.name.name)) {
                inner = inner.with(&p.name().name, k);
            }
        }
        for s in &c.body {
            match s {
                Stmt::Let(l) => {
                    self.expr(&l.value, &inner);
                    if let Some(k) = self.define(
                        m,
                        Kind::Local,
                        &l.name,
                        Some(l.value.span.start),
                        Some(&c.name.name),
                    ) {
                        inner = inner.with(&l.name.name, k);
                    }
                }
                Stmt::Primitive(p) => {
                    p.args.iter().for_each(|e| self.expr(e, &inner));
                    p.styles.iter().for_each(|s| self.expr(&s.value, &inner));
                }
            }
        }
    }

    fn action(&mut self, a: &Action, scope: &Scope) {
        let m = scope.module;
        match &a.kind {
            ActionKind::Set { target, value } => {
                self.expr(target, scope);
                self.expr(value, scope);
            }
            ActionKind::Call { call } => self.expr(call, scope),
            ActionKind::Swap { a, b, duration } => {
                for w in [a, b] {
                    let def = self.window(m, &w.name);
                    self.refer(m, w.span.start, w.span.end, def);
                }
                duration.iter().for_each(|d| self.expr(d, scope));
            }
            ActionKind::Show { window } | ActionKind::Hide { window } => {
                let def = self.window(m, &window.name);
                self.refer(m, window.span.start, window.span.end, def);
            }
            ActionKind::Alert { message, .. } => self.expr(message, scope),
            ActionKind::Mode { .. } | ActionKind::Script { .. } => {}
            ActionKind::Select { target } => {
                if let SelectTarget::Object(e) = target {
                    self.expr(e, scope);
                }
            }
        }
    }

    /// Walks an expression with an explicit stack (expressions nest up to the checker's
    /// depth limit, deeper than a thread's stack would like).
    fn expr(&mut self, root: &Expr, scope: &Scope) {
        let m = scope.module;
        let mut stack = vec![root];
        while let Some(e) = stack.pop() {
            match &e.kind {
                ExprKind::Name(n) => {
                    let def = scope.local(n).or_else(|| {
                        let id = self.tables.find_let(&self.modules, m, n, None)?;
                        self.key_of(id)
                    });
                    self.refer(m, e.span.start, e.span.end, def);
                }
                ExprKind::Field(base, field) => {
                    if let ExprKind::Name(ns) = &base.kind
                        && scope.local(ns).is_none()
                        && let Some(target) = self.tables.namespace(&self.modules, m, ns)
                    {
                        let def = self.tables.lets[target]
                            .get(&field.name)
                            .copied()
                            .and_then(|id| self.key_of(id));
                        self.refer(m, field.span.start, field.span.end, def);
                    } else {
                        stack.push(base);
                    }
                }
                ExprKind::Index(base, _) => stack.push(base),
                ExprKind::Call(f, args) => {
                    stack.push(f);
                    stack.extend(args.iter());
                }
                ExprKind::Unary(_, x) => stack.push(x),
                ExprKind::Binary(_, a, b) => {
                    stack.push(a);
                    stack.push(b);
                }
                ExprKind::If(c, a, b) => {
                    stack.extend([&**c, &**a, &**b]);
                }
                ExprKind::Str(parts) => {
                    for p in parts {
                        if let StrPart::Interp { expr, .. } = p {
                            stack.push(expr);
                        }
                    }
                }
                ExprKind::Number { .. }
                | ExprKind::Colour(_)
                | ExprKind::Bool(_)
                | ExprKind::SelfRef
                | ExprKind::Error => {}
            }
        }
    }
}

/// Names in scope besides the top-level ones: parameters, local lets, template variables.
#[derive(Clone)]
struct Scope {
    module: ModuleId,
    locals: Vec<(String, DefKey)>,
}

impl Scope {
    fn with(&self, name: &str, key: DefKey) -> Scope {
        let mut s = self.clone();
        s.locals.push((name.to_string(), key));
        s
    }
    fn local(&self, name: &str) -> Option<DefKey> {
        self.locals.iter().rev().find(|(n, _)| n == name).map(|(_, k)| k.clone())
    }
}
