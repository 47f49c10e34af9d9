//! Shared `let`s: a `let` that several functions of the layout read (two widgets, a widget
//! and another `let`, …) is compiled once, as a function of its own, and evaluated once per
//! change, by a cell whose output is a node of the graph; the functions that read it take
//! that node as an input (`mocu_lower::Source::Let`), as they take a path. So N widgets
//! showing the end of a chain of 5,000 `let`s lower, compile and evaluate the chain once,
//! not N times: what is compiled is as large as the source.
//!
//! A `let` read by one function only stays a local of that function (`mocu-lower`): no cell
//! of its own. Only `let`s whose value reads nothing but paths from the root are shared
//! (their value is the same for every reader: no template variable, parameter, input,
//! `self` or index). Semantics are unchanged: the node holds the value as the world model
//! would (absent stays absent; numbers, durations, booleans, strings and colours convert
//! back exactly, `mocu_lower::convert`), and cells run in order of their level — a `let`'s
//! cell before its readers — so a reader sees its inputs of one tick, evaluated once.

use super::{Builder, LoadError, Shared, State};
use crate::lower::{Lowerer, Scope, Source};
use mocu_jit as jit;
use mocu_language::program::{Expr, LetRef, Node, PathBase, Program, Read};
use std::collections::{HashMap, HashSet};
use std::sync::Arc;

/// A shared `let` read as a type: its number, digest and the type.
pub(crate) type LetKey = (u32, u64, jit::Ty);

/// The `let`s of `program` to share: those read by two or more functions or `let`s, whose
/// value (through every `let` it reads) reads only paths from the root, and which are more
/// than a path or a constant. Linear: each `let` and each function is walked once.
pub(crate) fn shared_lets(program: &Program) -> Arc<HashSet<(u32, u64)>> {
    let key = |l: &LetRef| (l.id, l.digest);
    // A `let` reads only `let`s before it: one pass in order decides which are global.
    let mut global: HashMap<(u32, u64), bool> = HashMap::new();
    let mut readers: HashMap<(u32, u64), u32> = HashMap::new();
    // A `let` that is a path or a constant costs its readers no more than a node would.
    let mut cheap: HashSet<(u32, u64)> = HashSet::new();
    for l in &program.lets.0 {
        if matches!(l.value.node, Node::Path(_)) || l.constant.is_some() {
            cheap.insert(key(l));
        }
        let mut ok = own_value_is_global(&l.value);
        for r in &l.reads {
            match r {
                Read::Path(p) => ok &= p.base == PathBase::Root,
                Read::Let(d) => {
                    ok &= global.get(&key(d)).copied().unwrap_or(false);
                    *readers.entry(key(d)).or_default() += 1;
                }
            }
        }
        global.insert(key(l), ok);
    }
    let mut function = |exprs: &mut dyn Iterator<Item = &Expr>| {
        let mut seen = HashSet::new();
        for e in exprs {
            for r in e.reads() {
                if let Read::Let(l) = r
                    && seen.insert(key(&l))
                {
                    *readers.entry(key(&l)).or_default() += 1;
                }
            }
        }
    };
    let windows = program.windows.iter().chain(program.templates.iter().flat_map(|t| &t.windows));
    for w in windows {
        let mut exprs = [&w.layer, &w.opacity, &w.visible]
            .into_iter()
            .chain(&w.rect)
            .chain(&w.source)
            .map(|b| &b.expr);
        function(&mut exprs);
    }
    let widgets = program.widgets.iter().chain(program.templates.iter().flat_map(|t| &t.widgets));
    for w in widgets {
        let mut exprs =
            w.at.iter().chain(&w.visible).chain(w.args.iter().map(|a| &a.value)).map(|b| &b.expr);
        function(&mut exprs);
    }
    let watches = program.watches.iter().chain(program.templates.iter().flat_map(|t| &t.watches));
    for w in watches {
        let mut exprs = std::iter::once(&w.when).chain(&w.clear).map(|b| &b.expr);
        function(&mut exprs);
    }
    let shared = readers
        .into_iter()
        .filter(|(k, n)| *n >= 2 && global.get(k).copied().unwrap_or(false) && !cheap.contains(k))
        .map(|(k, _)| k)
        .collect();
    Arc::new(shared)
}

/// Whether an expression, not counting the `let`s it reads, names nothing that differs
/// between readers (a parameter, a size, an input, an index; paths are checked apart).
fn own_value_is_global(e: &Expr) -> bool {
    let mut ok = true;
    e.walk(&mut |x| {
        if matches!(x.node, Node::Param(_) | Node::Size(_) | Node::Input(_) | Node::Index) {
            ok = false;
        }
    });
    ok
}

/// Whether a path slot says something of a vehicle's data: what a reader of the `let` must
/// know of it to say when its data is stale or aged (`stale.rs`).
fn about_a_vehicle(src: &Source) -> bool {
    matches!(src, Source::Path { objects, .. } if objects.len() >= 2 && objects[0] == "vehicles")
}

/// A shared `let`'s function, compiled in a [`Builder`].
pub(crate) struct LetFn {
    /// Its index among the builder's functions.
    pub(crate) index: usize,
    /// The vehicle paths it reads, through its shared `let`s too (`stale.rs`).
    pub(crate) through: Arc<Vec<(Source, jit::Ty)>>,
}

impl Builder {
    /// A lowerer for a function of the layout's graph: it reads the shared `let`s through
    /// their nodes.
    pub(crate) fn lowerer<'a>(&self, scope: Scope<'a>, screen: (f64, f64)) -> Lowerer<'a> {
        Lowerer::new(scope, screen).sharing(self.shared.clone())
    }

    /// Compiles (once each) the function of every shared `let` that `lw` reads, and the
    /// functions of the shared `let`s those read, without recursion. Returns the vehicle
    /// paths `lw` reads through them.
    pub(crate) fn share(
        &mut self,
        lw: &Lowerer,
        screen: (f64, f64),
    ) -> Result<Vec<(Source, jit::Ty)>, LoadError> {
        type Lowered = (Lowerer<'static>, jit::Expr);
        let mut stack: Vec<(LetRef, jit::Ty, Option<Lowered>)> =
            lw.shared_reads.iter().map(|(l, t)| (l.clone(), *t, None)).collect();
        let mut started: HashSet<LetKey> = HashSet::new();
        while let Some((l, ty, lowered)) = stack.pop() {
            let key = (l.id, l.digest, ty);
            match lowered {
                None => {
                    if self.let_fns.contains_key(&key) || !started.insert(key) {
                        continue;
                    }
                    let mut inner = self.lowerer(Scope::Plain, screen);
                    let e = inner
                        .lower(&l.value, ty)
                        .map_err(|e| LoadError::Lower(format!("`let {}`: {e}", l.name)))?;
                    let deps: Vec<_> = inner.shared_reads.clone();
                    stack.push((l, ty, Some((inner, e))));
                    stack.extend(deps.into_iter().map(|(d, t)| (d, t, None)));
                }
                Some((inner, e)) => {
                    let mut through = self.through(&inner);
                    let index = self.push_fn(inner, vec![e], Some(key));
                    through.retain(|(s, _)| about_a_vehicle(s));
                    self.let_fns.insert(key, LetFn { index, through: Arc::new(through) });
                }
            }
        }
        Ok(self.through(lw))
    }

    /// The slots of `lw`, then the vehicle paths it reads through the shared `let`s it
    /// reads (each compiled already), each once.
    fn through(&self, lw: &Lowerer) -> Vec<(Source, jit::Ty)> {
        let mut out: Vec<(Source, jit::Ty)> = Vec::new();
        let mut seen = HashSet::new();
        let own = lw.slots.iter();
        let lets =
            lw.shared_reads.iter().filter_map(|(l, t)| self.let_fns.get(&(l.id, l.digest, *t)));
        for s in own.chain(lets.flat_map(|f| f.through.iter())) {
            if seen.insert(s.clone()) {
                out.push(s.clone());
            }
        }
        out
    }
}

impl Shared {
    /// Makes sure every shared `let` that function `f` reads has its node and its cell (and
    /// so on for the `let`s those read), without recursion: each `let`'s cell is bound after
    /// those of the `let`s it reads.
    pub(crate) fn bind_lets(self: &Arc<Self>, st: &mut State, f: &super::FnRef) {
        let mut stack = vec![(f.clone(), false)];
        while let Some((g, ready)) = stack.pop() {
            let info = &g.code.infos.get().expect("finished")[g.index];
            if !ready {
                let missing: Vec<usize> = info
                    .lets
                    .iter()
                    .filter(|(key, _)| !st.let_ix.contains_key(key))
                    .map(|(_, i)| *i)
                    .collect();
                stack.push((g.clone(), true));
                stack.extend(
                    missing
                        .into_iter()
                        .map(|index| (super::FnRef { code: g.code.clone(), index }, false)),
                );
                continue;
            }
            let Some(key) = info.produces else { continue };
            if st.let_ix.contains_key(&key) {
                continue;
            }
            let n = st.nodes.len();
            st.nodes.push(super::Node {
                watch: None,
                value: None,
                deps: Vec::new(),
                users: 0,
                producer: None,
            });
            st.let_ix.insert(key, n);
            let cell = self.bind_cell(st, &g, vec![super::Target::Node(n)], None);
            st.nodes[n].producer = Some(cell);
        }
    }
}
