//! The live layout: compiled functions bound to the DataServer through shared path
//! subscriptions, evaluated once per tick for the cells whose inputs changed, with early
//! cutoff; outputs written under `root.display`.

use crate::actions::{self, CompiledAction};
use crate::convert::{to_slot, to_value};
use crate::events::EventSink;
use crate::lower::{Base, Lowerer, Scope, Source, value_ty};
use crate::watch::WatchRt;
use mocu_dataserver::{
    DataServer, DottedPath, Executor, Kind, ObjectInfo, PathEvent, PathWatch, Subject, Topic,
};
use mocu_jit::{self as jit, EvalCtx, Evaluate, Slot};
use mocu_language::program::{Program, Template, Widget, Window};
use mocu_language::types::TypeKind;
use mocu_value::{Guid, PropName, Value};
use parking_lot::Mutex;
use std::collections::HashMap;
use std::sync::{Arc, Weak};
use std::time::Duration;

/// How a layout runs.
#[derive(Clone)]
pub struct LayoutConfig {
    /// Screen size in px (windows given in % resolve against it).
    pub screen: (f64, f64),
    /// At most one evaluation per tick (changes that arrive together are evaluated once).
    pub tick: Duration,
    /// Compile with Cranelift (default) or run the reference interpreter.
    pub jit: bool,
    /// Name of the layout (its file), for the event log.
    pub name: String,
    /// Add the built-in alert window when the layout places no `AlertLayer` (see
    /// `alerts.rs`); off only for tests of a bare display.
    pub alert_layer: bool,
    /// Write each alert once on the terminal (stderr).
    pub alerts_to_terminal: bool,
}

impl Default for LayoutConfig {
    fn default() -> Self {
        LayoutConfig {
            screen: (1920.0, 1080.0),
            tick: Duration::from_millis(16),
            jit: true,
            name: "layout".into(),
            alert_layer: true,
            alerts_to_terminal: true,
        }
    }
}

/// Why a layout could not be loaded.
#[derive(Debug)]
pub enum LoadError {
    Lower(String),
    Compile(String),
    World(String),
}

impl std::fmt::Display for LoadError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            LoadError::Lower(e) => write!(f, "cannot lower the layout: {e}"),
            LoadError::Compile(e) => write!(f, "cannot compile the layout: {e}"),
            LoadError::World(e) => write!(f, "cannot publish the layout: {e}"),
        }
    }
}

impl std::error::Error for LoadError {}

/// A loaded layout. Dropping it (or `unload`) removes its objects and subscriptions.
pub struct Layout {
    pub(crate) shared: Arc<Shared>,
}

pub(crate) struct Shared {
    pub(crate) ds: DataServer,
    pub(crate) exec: Executor,
    pub(crate) sink: Arc<dyn EventSink>,
    pub(crate) config: LayoutConfig,
    pub(crate) state: Mutex<State>,
    /// Changes reported by path watches, applied at the next tick. A separate lock: watch
    /// callbacks never wait for an evaluation in progress.
    inbox: Mutex<Inbox>,
    /// Widgets whose data can age (see `stale.rs`); its own lock, taken after `state`.
    pub(crate) ages: Mutex<HashMap<Guid, crate::stale::Age>>,
}

#[derive(Default)]
struct Inbox {
    /// The latest value of each path that changed since the last tick: a path that
    /// changes a thousand times between two ticks costs one entry.
    values: HashMap<usize, Option<Value>>,
    events: Vec<InboxEvent>,
    tick_scheduled: bool,
}

enum InboxEvent {
    Node(usize, Option<Value>),
    TemplateSource(usize, Option<Guid>),
    TemplateChild(usize, Kind, Guid, Arc<str>),
}

/// Where a path starts once bound.
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub(crate) enum Start {
    Root,
    Object(Guid),
}

pub(crate) struct Node {
    watch: Option<PathWatch>,
    pub(crate) value: Option<Value>,
    deps: Vec<usize>,
    users: usize,
}

/// What a function's input slot reads.
#[derive(Clone, Debug)]
enum Input {
    Node(usize),
    Index(usize),
    Absent,
}

/// Where a function's output goes.
#[derive(Clone, Debug)]
pub(crate) enum Target {
    Prop(Guid, PropName),
    WatchWhen(usize),
    WatchClear(usize),
}

pub(crate) struct Cell {
    f: FnRef,
    inputs: Vec<(Input, jit::Ty)>,
    targets: Vec<Target>,
    last: Vec<Option<Value>>,
    dirty: bool,
    alive: bool,
}

/// A function before binding: its slots and output targets by name.
pub(crate) struct FuncInfo {
    pub(crate) slots: Vec<(Source, jit::Ty)>,
}

/// One template's compiled pieces, instantiated per matching object.
pub(crate) struct TemplateRt {
    pub(crate) alive: bool,
    source: Vec<String>,
    object_type: Option<String>,
    var: String,
    windows: Vec<CompiledWindow>,
    widgets: Vec<CompiledWidget>,
    watches: Vec<crate::watch::CompiledWatch>,
    pub(crate) source_watch: Option<PathWatch>,
    source_object: Option<Guid>,
    pub(crate) children_sub: Option<mocu_dataserver::SubscriptionId>,
}

pub(crate) struct Instance {
    pub(crate) object: Guid,
    pub(crate) template: usize,
    index: usize,
    objects: Vec<Guid>,
    cells: Vec<usize>,
    watches: Vec<usize>,
}

#[derive(Clone)]
pub(crate) struct CompiledWindow {
    pub(crate) name: String,
    pub(crate) kind: String,
    pub(crate) f: FnRef,
    pub(crate) source: Option<(Base, Vec<String>)>,
}

#[derive(Clone)]
pub(crate) struct CompiledWidget {
    pub(crate) name: String,
    pub(crate) window: String,
    component: String,
    native: bool,
    f: FnRef,
    /// Output names, in function output order.
    outputs: Vec<String>,
    /// Object-typed arguments: published as dotted-path text.
    objects: Vec<(String, Base, Vec<String>)>,
    handlers: Vec<(String, Vec<CompiledAction>)>,
}

pub(crate) struct State {
    pub(crate) nodes: Vec<Node>,
    node_ix: HashMap<(Start, Vec<String>, String), usize>,
    pub(crate) cells: Vec<Cell>,
    dirty: Vec<usize>,
    pub(crate) display: Guid,
    owned: Vec<Guid>,
    pub(crate) templates: Vec<TemplateRt>,
    pub(crate) instances: Vec<Option<Instance>>,
    pub(crate) watches: Vec<WatchRt>,
    pub(crate) windows: HashMap<String, Guid>,
    pub(crate) bindings: Vec<(String, Vec<CompiledAction>)>,
    pub(crate) evaluations: u64,
    pub(crate) closed: bool,
    /// The top-level items now live, for incremental reload.
    pub(crate) items: Vec<crate::reload::ItemRec>,
}

/// Counters for tests and statistics.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct LayoutStats {
    /// Cell evaluations since load.
    pub evaluations: u64,
    /// Distinct paths subscribed now.
    pub paths: usize,
    /// Live cells.
    pub cells: usize,
    pub instances: usize,
}

fn lower_err(e: impl std::fmt::Display) -> LoadError {
    LoadError::Lower(e.to_string())
}

/// One compilation: functions compiled together into one evaluator (one code allocation).
/// Cells and actions keep their `Code` alive; code of replaced items is freed when the last
/// cell using it goes.
pub(crate) struct Code {
    eval: std::sync::OnceLock<Arc<dyn Evaluate>>,
    infos: std::sync::OnceLock<Vec<FuncInfo>>,
    ctx: Mutex<Option<EvalCtx>>,
}

/// A function of a compilation.
#[derive(Clone)]
pub(crate) struct FnRef {
    pub(crate) code: Arc<Code>,
    pub(crate) index: usize,
}

impl std::fmt::Debug for FnRef {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "fn#{}", self.index)
    }
}

impl FnRef {
    pub(crate) fn eval(&self) -> &Arc<dyn Evaluate> {
        self.code.eval.get().expect("a FnRef is used only after its Builder finished")
    }

    pub(crate) fn slots(&self) -> &[(Source, jit::Ty)] {
        &self.code.infos.get().expect("finished")[self.index].slots
    }
}

/// Collects functions while compiling a layout.
pub(crate) struct Builder {
    code: Arc<Code>,
    functions: Vec<jit::Function>,
    infos: Vec<FuncInfo>,
}

impl Builder {
    pub(crate) fn new() -> Builder {
        Builder {
            code: Arc::new(Code {
                eval: std::sync::OnceLock::new(),
                infos: std::sync::OnceLock::new(),
                ctx: Mutex::new(None),
            }),
            functions: Vec::new(),
            infos: Vec::new(),
        }
    }

    pub(crate) fn add(&mut self, lw: Lowerer, outputs: Vec<jit::Expr>) -> FnRef {
        let inputs = lw.slots.iter().map(|s| s.1).collect();
        self.functions.push(jit::Function { inputs, outputs });
        self.infos.push(FuncInfo { slots: lw.slots });
        FnRef { code: self.code.clone(), index: self.functions.len() - 1 }
    }

    /// Compiles everything added (Cranelift, or the interpreter).
    pub(crate) fn finish(self, use_jit: bool) -> Result<(), LoadError> {
        let eval: Arc<dyn Evaluate> = if use_jit {
            Arc::new(jit::compile(&self.functions).map_err(|e| LoadError::Compile(e.to_string()))?)
        } else {
            Arc::new(
                jit::Interpreter::new(&self.functions)
                    .map_err(|e| LoadError::Compile(e.to_string()))?,
            )
        };
        *self.code.ctx.lock() = Some(eval.context());
        let _ = self.code.eval.set(eval);
        let _ = self.code.infos.set(self.infos);
        Ok(())
    }
}

pub(crate) fn compile_window(
    b: &mut Builder,
    w: &Window,
    screen: (f64, f64),
) -> Result<CompiledWindow, LoadError> {
    let mut lw = Lowerer::new(Scope::Plain, screen);
    let mut outs = vec![lw.lower(&w.layer.expr, jit::Ty::Num).map_err(lower_err)?];
    for (i, r) in w.rect.iter().enumerate().take(4) {
        outs.push(lw.coordinate(&r.expr, i % 2 == 0).map_err(lower_err)?);
    }
    while outs.len() < 5 {
        outs.push(jit::Expr::Num(0.0));
    }
    outs.push(lw.lower(&w.opacity.expr, jit::Ty::Num).map_err(lower_err)?);
    outs.push(lw.lower(&w.visible.expr, jit::Ty::Bool).map_err(lower_err)?);
    let source = match &w.source {
        Some(s) => match &s.expr.node {
            mocu_language::program::Node::Path(p) => Some(lw.path_names(p).map_err(lower_err)?),
            _ => None,
        },
        None => None,
    };
    let f = b.add(lw, outs);
    Ok(CompiledWindow { name: w.name.clone(), kind: w.kind.clone(), f, source })
}

const WINDOW_OUTPUTS: [&str; 7] = ["layer", "x", "y", "w", "h", "opacity", "visible"];

pub(crate) fn compile_widget(
    b: &mut Builder,
    w: &Widget,
    n: usize,
    screen: (f64, f64),
) -> Result<CompiledWidget, LoadError> {
    let mut lw = Lowerer::new(Scope::Widget { args: &w.args, at: &w.at }, screen);
    let mut outs = Vec::new();
    let mut names = Vec::new();
    for (i, a) in w.at.iter().enumerate().take(4) {
        outs.push(lw.coordinate(&a.expr, i % 2 == 0).map_err(lower_err)?);
        names.push(["x", "y", "w", "h"][i].to_string());
    }
    if let Some(v) = &w.visible {
        outs.push(lw.lower(&v.expr, jit::Ty::Bool).map_err(lower_err)?);
        names.push("visible".into());
    }
    let mut objects = Vec::new();
    for a in &w.args {
        let e = &a.value.expr;
        match &e.ty.kind {
            TypeKind::Range { .. } => {
                for (end, max) in [("min", false), ("max", true)] {
                    let re = mocu_language::program::Expr {
                        ty: mocu_language::types::Type::number(),
                        node: mocu_language::program::Node::RangeEnd {
                            range: Box::new(e.clone()),
                            max,
                        },
                        span: e.span,
                    };
                    outs.push(lw.lower(&re, jit::Ty::Num).map_err(lower_err)?);
                    names.push(format!("{}.{end}", a.name));
                }
            }
            TypeKind::Object { .. } => {
                if let mocu_language::program::Node::Path(p) = &e.node {
                    let (base, objs) = lw.path_names(p).map_err(lower_err)?;
                    objects.push((a.name.clone(), base, objs));
                }
            }
            TypeKind::Void | TypeKind::Error => {}
            _ => {
                let ty = value_ty(&e.ty).unwrap_or(jit::Ty::Num);
                outs.push(lw.lower(e, ty).map_err(lower_err)?);
                names.push(a.name.clone());
            }
        }
    }
    if let Some(stale) = crate::stale::widget_stale(&mut lw) {
        outs.push(stale);
        names.push("stale".into());
    }
    let f = b.add(lw, outs);
    let mut handlers = Vec::new();
    for h in &w.handlers {
        let acts = actions::compile_actions(b, &h.actions, screen).map_err(lower_err)?;
        handlers.push((h.event.clone(), acts));
    }
    let name = w.name.clone().unwrap_or_else(|| format!("{}#{n}", w.component));
    Ok(CompiledWidget {
        name,
        window: w.window.clone(),
        component: w.component.clone(),
        native: w.native,
        f,
        outputs: names,
        objects,
        handlers,
    })
}

impl Layout {
    /// Compiles a checked program, publishes its display under `root.display`, binds its
    /// paths and evaluates it once. The program must have no errors.
    pub fn load(
        ds: &DataServer,
        program: &Program,
        config: LayoutConfig,
        sink: Arc<dyn EventSink>,
    ) -> Result<Layout, LoadError> {
        let display = ensure_object(ds, Guid::ROOT, "display", "display")?;
        let _ = ds.set(display, "width", Value::Float(config.screen.0));
        let _ = ds.set(display, "height", Value::Float(config.screen.1));
        let shared = Arc::new(Shared {
            ds: ds.clone(),
            exec: ds.serial_executor(),
            sink,
            config,
            state: Mutex::new(State {
                nodes: Vec::new(),
                node_ix: HashMap::new(),
                cells: Vec::new(),
                dirty: Vec::new(),
                display,
                owned: Vec::new(),
                templates: Vec::new(),
                instances: Vec::new(),
                watches: Vec::new(),
                windows: HashMap::new(),
                bindings: Vec::new(),
                evaluations: 0,
                closed: false,
                items: Vec::new(),
            }),
            inbox: Mutex::new(Inbox::default()),
            ages: Mutex::new(HashMap::new()),
        });
        {
            let mut st = shared.state.lock();
            shared.apply(&mut st, program)?;
            shared.evaluate(&mut st);
        }
        shared.sink.record("load", &[("layout", Value::str(&shared.config.name))]);
        Ok(Layout { shared })
    }

    /// Replaces the running program by `program`, incrementally: windows, widgets, watches
    /// and templates whose definitions did not change keep their objects, subscriptions and
    /// state (an animation in flight, a watch's hold timer, feedback); changed ones are
    /// republished, removed ones torn down. The world model's vehicles, goals and routes are
    /// never touched. On error nothing changes.
    pub fn reload(&self, program: &Program) -> Result<crate::reload::ReloadStats, LoadError> {
        let stats = {
            let mut st = self.shared.state.lock();
            let stats = self.shared.apply(&mut st, program)?;
            self.shared.evaluate(&mut st);
            stats
        };
        self.shared.sink.record(
            "reload",
            &[
                ("layout", Value::str(&self.shared.config.name)),
                ("kept", Value::Int(stats.kept as i64)),
                ("added", Value::Int(stats.added as i64)),
                ("changed", Value::Int(stats.changed as i64)),
                ("removed", Value::Int(stats.removed as i64)),
            ],
        );
        Ok(stats)
    }

    /// Applies pending changes and evaluates now (tests; `mocu run` relies on ticks).
    pub fn flush(&self) {
        self.shared.tick();
    }

    /// Waits for the DataServer to be quiet, then flushes, until nothing is left to do.
    pub fn settle(&self) {
        for _ in 0..8 {
            self.shared.ds.quiesce();
            self.shared.tick();
        }
        self.shared.ds.quiesce();
    }

    pub fn stats(&self) -> LayoutStats {
        let st = self.shared.state.lock();
        LayoutStats {
            evaluations: st.evaluations,
            paths: st.nodes.iter().filter(|n| n.watch.is_some()).count(),
            cells: st.cells.iter().filter(|c| c.alive).count(),
            instances: st.instances.iter().flatten().count(),
        }
    }

    /// The window objects this layout published, by name.
    pub fn window(&self, name: &str) -> Option<Guid> {
        self.shared.state.lock().windows.get(name).copied()
    }

    /// Removes every object and subscription the layout made.
    pub fn unload(self) {}
}

impl Drop for Layout {
    fn drop(&mut self) {
        let (watches, objects, subs) = {
            let mut st = self.shared.state.lock();
            st.closed = true;
            let mut watches: Vec<PathWatch> =
                st.nodes.iter_mut().filter_map(|n| n.watch.take()).collect();
            watches.extend(st.templates.iter_mut().filter_map(|t| t.source_watch.take()));
            let subs: Vec<_> =
                st.templates.iter_mut().filter_map(|t| t.children_sub.take()).collect();
            let mut objects = std::mem::take(&mut st.owned);
            for i in st.instances.iter_mut().filter_map(Option::take) {
                objects.extend(i.objects);
            }
            for w in &st.watches {
                objects.extend(w.object);
                objects.extend(w.alerts.iter().copied());
            }
            (watches, objects, subs)
        };
        drop(watches);
        for s in subs {
            self.shared.ds.unsubscribe(s);
        }
        for o in objects {
            let _ = self.shared.ds.delete_object(o);
        }
        self.shared.sink.record("unload", &[("layout", Value::str(&self.shared.config.name))]);
    }
}

pub(crate) fn compile_template(
    b: &mut Builder,
    t: &Template,
    screen: (f64, f64),
) -> Result<TemplateRt, LoadError> {
    let windows =
        t.windows.iter().map(|w| compile_window(b, w, screen)).collect::<Result<_, _>>()?;
    let widgets = t
        .widgets
        .iter()
        .enumerate()
        .map(|(i, w)| compile_widget(b, w, i, screen))
        .collect::<Result<_, _>>()?;
    let watches = t
        .watches
        .iter()
        .map(|w| crate::watch::compile_watch(b, w, screen))
        .collect::<Result<_, _>>()?;
    if t.source.base != mocu_language::program::PathBase::Root {
        return Err(LoadError::Lower(format!(
            "`for each` over `{}`: the source must start at root",
            t.source
        )));
    }
    Ok(TemplateRt {
        alive: true,
        source: t.source.segments.clone(),
        object_type: t.object_type.clone(),
        var: t.var.clone(),
        windows,
        widgets,
        watches,
        source_watch: None,
        source_object: None,
        children_sub: None,
    })
}

pub(crate) fn ensure_object(
    ds: &DataServer,
    parent: Guid,
    name: &str,
    kind: &str,
) -> Result<Guid, LoadError> {
    match ds.find_child(parent, name).map_err(|e| LoadError::World(e.to_string()))? {
        Some(g) => Ok(g),
        None => ds
            .create_object(parent, ObjectInfo::new(name, kind))
            .map_err(|e| LoadError::World(e.to_string())),
    }
}

impl Shared {
    fn weak(self: &Arc<Self>) -> Weak<Shared> {
        Arc::downgrade(self)
    }

    /// The start of a path for an instance (or the root).
    pub(crate) fn start_of(st: &State, base: &Base, instance: Option<usize>) -> Option<Start> {
        match base {
            Base::Root => Some(Start::Root),
            Base::Var(_) => {
                instance.and_then(|i| st.instances[i].as_ref()).map(|i| Start::Object(i.object))
            }
            Base::SelfObject | Base::Selected => None,
        }
    }

    /// The node for a path, shared by every cell that reads it.
    fn node(
        self: &Arc<Self>,
        st: &mut State,
        start: Start,
        objects: &[String],
        property: &str,
    ) -> usize {
        let key = (start.clone(), objects.to_vec(), property.to_string());
        if let Some(&i) = st.node_ix.get(&key) {
            st.nodes[i].users += 1;
            return i;
        }
        let idx = st.nodes.len();
        let objs: Vec<&str> = objects.iter().map(|s| s.as_str()).collect();
        let path = DottedPath::new(&objs, property);
        let weak = self.weak();
        let cb = move |e: &PathEvent| {
            if let Some(sh) = weak.upgrade() {
                let v = if e.kind == Kind::Deleted { None } else { e.value.clone() };
                sh.post(InboxEvent::Node(idx, v));
            }
        };
        let watch = match start {
            Start::Root => self.ds.watch_path(path, Some(&self.exec), cb),
            Start::Object(g) => self.ds.watch_path_from(g, path, Some(&self.exec), cb),
        };
        st.nodes.push(Node { watch: watch.ok(), value: None, deps: Vec::new(), users: 1 });
        st.node_ix.insert(key, idx);
        idx
    }

    fn post(self: &Arc<Self>, e: InboxEvent) {
        let mut inbox = self.inbox.lock();
        match e {
            InboxEvent::Node(n, v) => {
                inbox.values.insert(n, v);
            }
            other => inbox.events.push(other),
        }
        if !inbox.tick_scheduled {
            inbox.tick_scheduled = true;
            let weak = self.weak();
            self.ds.run_after(self.config.tick, Some(&self.exec), move || {
                if let Some(sh) = weak.upgrade() {
                    sh.tick();
                }
            });
        }
    }

    /// Binds a function to nodes and targets: a live cell.
    pub(crate) fn add_cell(
        self: &Arc<Self>,
        st: &mut State,
        f: &FnRef,
        targets: Vec<Target>,
        instance: Option<usize>,
    ) -> usize {
        let idx = st.cells.len();
        let slots = f.slots().to_vec();
        let mut inputs = Vec::with_capacity(slots.len());
        for (src, ty) in slots {
            let input = match &src {
                Source::Path { base, objects, property } => {
                    match Self::start_of(st, base, instance) {
                        Some(start) => {
                            let n = self.node(st, start, objects, property);
                            st.nodes[n].deps.push(idx);
                            Input::Node(n)
                        }
                        None => Input::Absent,
                    }
                }
                Source::Index => instance.map_or(Input::Absent, Input::Index),
                Source::Input(_) | Source::Param(_) => Input::Absent,
            };
            inputs.push((input, ty));
        }
        let n = targets.len();
        st.cells.push(Cell {
            f: f.clone(),
            inputs,
            targets,
            last: vec![None; n],
            dirty: true,
            alive: true,
        });
        st.dirty.push(idx);
        idx
    }

    /// Ends a cell: it stops being evaluated and releases its paths.
    pub(crate) fn remove_cell(&self, st: &mut State, idx: usize) {
        let inputs = std::mem::take(&mut st.cells[idx].inputs);
        st.cells[idx].alive = false;
        for (input, _) in inputs {
            if let Input::Node(n) = input {
                let node = &mut st.nodes[n];
                node.deps.retain(|&d| d != idx);
                node.users -= 1;
                if node.users == 0 {
                    node.watch = None; // drops the watch: its subscriptions end
                    st.node_ix.retain(|_, v| *v != n);
                }
            }
        }
    }

    /// Applies what the watches reported, then evaluates the dirty cells.
    pub(crate) fn tick(self: &Arc<Self>) {
        let (values, events) = {
            let mut inbox = self.inbox.lock();
            inbox.tick_scheduled = false;
            (std::mem::take(&mut inbox.values), std::mem::take(&mut inbox.events))
        };
        let mut st = self.state.lock();
        if st.closed {
            return;
        }
        for (n, v) in values {
            if n < st.nodes.len() && st.nodes[n].watch.is_some() {
                st.nodes[n].value = v;
                for i in 0..st.nodes[n].deps.len() {
                    let d = st.nodes[n].deps[i];
                    mark(&mut st, d);
                }
            }
        }
        for e in events {
            match e {
                InboxEvent::Node(..) => {}
                InboxEvent::TemplateSource(t, _) | InboxEvent::TemplateChild(t, ..)
                    if !st.templates[t].alive => {}
                InboxEvent::TemplateSource(t, obj) => self.template_source(&mut st, t, obj),
                InboxEvent::TemplateChild(t, kind, g, ty) => {
                    self.template_child(&mut st, t, kind, g, &ty)
                }
            }
        }
        self.evaluate(&mut st);
    }

    /// Evaluates every dirty cell once; writes only outputs that changed (early cutoff).
    pub(crate) fn evaluate(self: &Arc<Self>, st: &mut State) {
        let dirty = std::mem::take(&mut st.dirty);
        let mut slots = Vec::new();
        let mut outs = Vec::new();
        for c in dirty {
            if !st.cells[c].alive || !st.cells[c].dirty {
                continue;
            }
            st.cells[c].dirty = false;
            st.evaluations += 1;
            let State { cells, nodes, instances, .. } = &mut *st;
            let cell = &cells[c];
            let f = cell.f.clone();
            let mut guard = f.code.ctx.lock();
            let Some(ctx) = guard.as_mut() else { continue };
            slots.clear();
            for (input, ty) in &cell.inputs {
                slots.push(match input {
                    Input::Node(n) => to_slot(nodes[*n].value.as_ref(), *ty, ctx),
                    Input::Index(i) => {
                        instances[*i].as_ref().map_or(Slot::ABSENT, |i| Slot::num(i.index as f64))
                    }
                    Input::Absent => Slot::ABSENT,
                });
            }
            outs.clear();
            outs.resize(cell.targets.len(), Slot::ABSENT);
            f.eval().call(f.index, &slots, &mut outs, ctx);
            let types = f.eval().output_types(f.index);
            let values: Vec<Option<Value>> =
                outs.iter().zip(types).map(|(s, t)| to_value(s.decode(*t, ctx))).collect();
            ctx.reset();
            drop(guard);
            for (i, v) in values.into_iter().enumerate() {
                if st.cells[c].last[i] == v {
                    continue; // early cutoff: an equal result notifies nobody
                }
                st.cells[c].last[i] = v.clone();
                let target = st.cells[c].targets[i].clone();
                self.write_output(st, target, v);
            }
        }
    }

    fn write_output(self: &Arc<Self>, st: &mut State, target: Target, v: Option<Value>) {
        match target {
            Target::Prop(obj, name) => {
                let _ = match v {
                    Some(v) => self.ds.set(obj, name, v),
                    None => self.ds.delete_property(obj, name),
                };
                crate::stale::on_output(self, obj);
            }
            Target::WatchWhen(w) => crate::watch::on_when(self, st, w, v.and_then(|v| v.as_bool())),
            Target::WatchClear(w) => {
                crate::watch::on_clear(self, st, w, v.and_then(|v| v.as_bool()))
            }
        }
    }

    /// Template instances name their objects `name@object`.
    fn instance_suffix(&self, st: &State, instance: Option<usize>) -> Option<String> {
        instance
            .and_then(|i| st.instances[i].as_ref())
            .map(|i| self.ds.info(i.object).map(|inf| inf.name.to_string()).unwrap_or_default())
    }

    /// The dotted-path text of an object path from a base (`root.vehicles.usv1.cameras.drive`).
    fn path_from(
        &self,
        st: &State,
        base: &Base,
        objs: &[String],
        instance: Option<usize>,
    ) -> String {
        match Self::start_of(st, base, instance) {
            Some(Start::Object(o)) => format!("{}.{}", self.ds.path_text(o), objs.join(".")),
            _ => format!("root.{}", objs.join(".")),
        }
    }

    pub(crate) fn publish_windows(
        self: &Arc<Self>,
        st: &mut State,
        windows: &[CompiledWindow],
        instance: Option<usize>,
        first_order: usize,
    ) -> Result<Vec<(Guid, usize)>, LoadError> {
        let mut made = Vec::new();
        let suffix = self.instance_suffix(st, instance);
        for (order, w) in (first_order + st.windows.len()..).zip(windows) {
            let name = match &suffix {
                Some(s) => format!("{}@{s}", w.name),
                None => w.name.clone(),
            };
            let kind = if w.kind == "layer" { "widgets" } else { w.kind.as_str() };
            let g = self
                .ds
                .create_object(st.display, ObjectInfo::new(&name, "window").subtype(kind))
                .map_err(|e| LoadError::World(e.to_string()))?;
            let _ = self.ds.set(g, "order", Value::Int(order as i64));
            let _ = self.ds.set(g, "revision", Value::Int(0));
            let _ = self.ds.set(g, "clip", Value::Bool(true));
            if let Some((base, objs)) = &w.source {
                let text = self.path_from(st, base, objs, instance);
                let _ = self.ds.set(g, "source", Value::str(&text));
            }
            let targets =
                WINDOW_OUTPUTS.iter().map(|n| Target::Prop(g, PropName::new(n))).collect();
            let cell = self.add_cell(st, &w.f, targets, instance);
            made.push((g, cell));
            st.windows.insert(name.clone(), g);
            match instance {
                Some(i) => {
                    if let Some(inst) = st.instances[i].as_mut() {
                        inst.objects.push(g);
                        inst.cells.push(cell);
                    }
                }
                None => st.owned.push(g),
            }
        }
        Ok(made)
    }

    /// A changed top-level window keeps its object (and the widgets in it): new kind,
    /// source and cell.
    pub(crate) fn rebind_window(
        self: &Arc<Self>,
        st: &mut State,
        g: Guid,
        w: &CompiledWindow,
    ) -> usize {
        let kind = if w.kind == "layer" { "widgets" } else { w.kind.as_str() };
        if let Ok(info) = self.ds.info(g)
            && &*info.subtype != kind
        {
            let _ = self.ds.set_info(g, ObjectInfo::new(&info.name, "window").subtype(kind));
        }
        match &w.source {
            Some((_, objs)) => {
                let _ = self.ds.set(g, "source", Value::str(&format!("root.{}", objs.join("."))));
            }
            None => {
                let _ = self.ds.delete_property(g, "source");
            }
        }
        let targets = WINDOW_OUTPUTS.iter().map(|n| Target::Prop(g, PropName::new(n))).collect();
        self.add_cell(st, &w.f, targets, None)
    }

    pub(crate) fn publish_widgets(
        self: &Arc<Self>,
        st: &mut State,
        widgets: &[CompiledWidget],
        instance: Option<usize>,
        first_order: usize,
    ) -> Result<Vec<(Guid, usize)>, LoadError> {
        let mut made = Vec::new();
        let suffix = self.instance_suffix(st, instance);
        for (i, w) in widgets.iter().enumerate() {
            let order = first_order + i;
            let window_name = match &suffix {
                Some(s) if st.windows.contains_key(&format!("{}@{s}", w.window)) => {
                    format!("{}@{s}", w.window)
                }
                _ => w.window.clone(),
            };
            let Some(&win) = st.windows.get(&window_name) else {
                return Err(LoadError::World(format!(
                    "widget `{}` is in unknown window `{}`",
                    w.name, w.window
                )));
            };
            let name = match &suffix {
                Some(s) => format!("{}@{s}", w.name),
                None => w.name.clone(),
            };
            let g = self
                .ds
                .create_object(win, ObjectInfo::new(&name, "widget").subtype(&w.component))
                .map_err(|e| LoadError::World(e.to_string()))?;
            let _ = self.ds.set(g, "component", Value::str(&w.component));
            let _ = self.ds.set(g, "native", Value::Bool(w.native));
            let _ = self.ds.set(g, "order", Value::Int(order as i64));
            for (arg, base, objs) in &w.objects {
                let text = self.path_from(st, base, objs, instance);
                let _ = self.ds.set(g, arg.as_str(), Value::str(&text));
            }
            let targets = w.outputs.iter().map(|n| Target::Prop(g, PropName::new(n))).collect();
            let cell = self.add_cell(st, &w.f, targets, instance);
            made.push((g, cell));
            let object = instance.and_then(|i| st.instances[i].as_ref()).map(|i| i.object);
            crate::stale::register(self, g, w.f.slots(), object);
            actions::publish_handlers(self, g, &w.handlers, object);
            if let Some(i) = instance
                && let Some(inst) = st.instances[i].as_mut()
            {
                inst.cells.push(cell);
            }
        }
        Ok(made)
    }

    pub(crate) fn add_watch(
        self: &Arc<Self>,
        st: &mut State,
        w: crate::watch::CompiledWatch,
        instance: Option<usize>,
    ) -> usize {
        let idx = crate::watch::publish_watch(self, st, w, instance);
        if let Some(i) = instance
            && let Some(inst) = st.instances[i].as_mut()
        {
            inst.watches.push(idx);
        }
        idx
    }

    /// Starts following template `t`'s source object.
    pub(crate) fn start_template(self: &Arc<Self>, st: &mut State, t: usize) {
        let objs: Vec<&str> = st.templates[t].source.iter().map(|s| s.as_str()).collect();
        let weak = self.weak();
        let watch =
            self.ds.watch_object(Guid::ROOT, &objs, Some(&self.exec), move |e: &PathEvent| {
                if let Some(sh) = weak.upgrade() {
                    let obj = (e.kind != Kind::Deleted).then_some(e.object);
                    sh.post(InboxEvent::TemplateSource(t, obj));
                }
            });
        st.templates[t].source_watch = watch.ok();
    }

    /// Ends template `t`: its instances go, it follows nothing any more.
    pub(crate) fn stop_template(self: &Arc<Self>, st: &mut State, t: usize) {
        st.templates[t].alive = false;
        st.templates[t].source_watch = None;
        if let Some(id) = st.templates[t].children_sub.take() {
            self.ds.unsubscribe(id);
        }
        let old: Vec<usize> = (0..st.instances.len())
            .filter(|&i| st.instances[i].as_ref().is_some_and(|x| x.template == t))
            .collect();
        for i in old {
            self.remove_instance(st, i);
        }
    }

    fn template_source(self: &Arc<Self>, st: &mut State, t: usize, obj: Option<Guid>) {
        if let Some(id) = st.templates[t].children_sub.take() {
            self.ds.unsubscribe(id);
        }
        // Every instance of the old source goes.
        let old: Vec<usize> = (0..st.instances.len())
            .filter(|&i| st.instances[i].as_ref().is_some_and(|x| x.template == t))
            .collect();
        for i in old {
            self.remove_instance(st, i);
        }
        st.templates[t].source_object = obj;
        if let Some(obj) = obj {
            let weak = self.weak();
            let sub = self.ds.subscribe_on(&self.exec, Topic::children(obj), move |n| {
                if let (Some(sh), Subject::Child { guid, kind, .. }) = (weak.upgrade(), &n.subject)
                {
                    sh.post(InboxEvent::TemplateChild(t, n.kind, *guid, kind.clone()));
                }
            });
            st.templates[t].children_sub = sub.ok();
        }
    }

    fn template_child(self: &Arc<Self>, st: &mut State, t: usize, kind: Kind, g: Guid, ty: &str) {
        let existing = st
            .instances
            .iter()
            .position(|i| i.as_ref().is_some_and(|i| i.template == t && i.object == g));
        match kind {
            Kind::Deleted => {
                if let Some(i) = existing {
                    self.remove_instance(st, i);
                    self.reindex(st, t);
                }
            }
            Kind::New | Kind::Changed => {
                let wanted = st.templates[t].object_type.as_deref().is_none_or(|w| w == ty);
                match (existing, wanted) {
                    (None, true) => {
                        self.add_instance(st, t, g);
                        self.reindex(st, t);
                    }
                    (Some(i), false) => {
                        self.remove_instance(st, i);
                        self.reindex(st, t);
                    }
                    _ => {}
                }
            }
        }
    }

    fn add_instance(self: &Arc<Self>, st: &mut State, t: usize, object: Guid) {
        let idx = st.instances.len();
        st.instances.push(Some(Instance {
            object,
            template: t,
            index: 0,
            objects: vec![],
            cells: vec![],
            watches: vec![],
        }));
        let tpl = std::mem::replace(
            &mut st.templates[t],
            TemplateRt {
                alive: true,
                source: vec![],
                object_type: None,
                var: String::new(),
                windows: vec![],
                widgets: vec![],
                watches: vec![],
                source_watch: None,
                source_object: None,
                children_sub: None,
            },
        );
        let r = self
            .publish_windows(st, &tpl.windows, Some(idx), 1000)
            .and_then(|_| self.publish_widgets(st, &tpl.widgets, Some(idx), 0));
        if let Err(e) = r {
            self.sink.record("diagnostic", &[("message", Value::str(&e.to_string()))]);
        }
        for w in &tpl.watches {
            self.add_watch(st, w.clone(), Some(idx));
        }
        self.sink.record(
            "instance",
            &[
                ("template", Value::str(&tpl.var)),
                ("object", Value::str(&self.ds.path_text(object))),
            ],
        );
        st.templates[t] = tpl;
    }

    fn remove_instance(self: &Arc<Self>, st: &mut State, i: usize) {
        let Some(inst) = st.instances[i].take() else { return };
        for c in inst.cells {
            self.remove_cell(st, c);
        }
        for w in inst.watches {
            crate::watch::remove_watch(self, st, w);
        }
        st.windows.retain(|_, g| !inst.objects.contains(g));
        for o in inst.objects {
            let _ = self.ds.delete_object(o);
        }
    }

    /// Instance indexes follow the order of the source's children.
    fn reindex(self: &Arc<Self>, st: &mut State, t: usize) {
        let Some(src) = st.templates[t].source_object else { return };
        let order = self.ds.children(src).unwrap_or_default();
        let mut mine: Vec<usize> = (0..st.instances.len())
            .filter(|&i| st.instances[i].as_ref().is_some_and(|x| x.template == t))
            .collect();
        mine.sort_by_key(|&i| {
            let o = st.instances[i].as_ref().map(|x| x.object);
            order.iter().position(|c| Some(*c) == o).unwrap_or(usize::MAX)
        });
        for (n, i) in mine.into_iter().enumerate() {
            let cells = match st.instances[i].as_mut() {
                Some(inst) if inst.index != n => {
                    inst.index = n;
                    inst.cells.clone()
                }
                _ => continue,
            };
            for c in cells {
                mark(st, c);
            }
        }
    }
}

impl State {
    pub(crate) fn owned_objects(&mut self) -> &mut Vec<Guid> {
        &mut self.owned
    }
}

fn mark(st: &mut State, c: usize) {
    if st.cells[c].alive && !st.cells[c].dirty {
        st.cells[c].dirty = true;
        st.dirty.push(c);
    }
}

/// Evaluates a one-shot function (actions, menus, bindings) reading inputs from the
/// DataServer now. `self_obj` binds `self`; `input` the binding's value.
pub(crate) fn eval_once(
    sh: &Shared,
    f: &FnRef,
    instance_object: Option<Guid>,
    self_obj: Option<Guid>,
    input: Option<f64>,
) -> Vec<Option<Value>> {
    let eval = f.eval();
    let mut ctx = eval.context();
    let slots: Vec<Slot> = f
        .slots()
        .iter()
        .map(|(src, ty)| match src {
            Source::Path { base, objects, property } => {
                let start = match base {
                    Base::Root => Some(Guid::ROOT),
                    Base::Var(_) => instance_object,
                    Base::SelfObject => self_obj,
                    Base::Selected => actions::selected_object(&sh.ds),
                };
                let v = start
                    .and_then(|s| resolve(&sh.ds, s, objects))
                    .and_then(|o| sh.ds.try_get(o, PropName::new(property)));
                to_slot(v.as_ref(), *ty, &mut ctx)
            }
            Source::Input(_) => input.map_or(Slot::ABSENT, Slot::num),
            Source::Index | Source::Param(_) => Slot::ABSENT,
        })
        .collect();
    let types = eval.output_types(f.index).to_vec();
    let mut outs = vec![Slot::ABSENT; types.len()];
    eval.call(f.index, &slots, &mut outs, &mut ctx);
    outs.iter().zip(&types).map(|(s, t)| to_value(s.decode(*t, &ctx))).collect()
}

/// Follows object names from `start`.
pub(crate) fn resolve(ds: &DataServer, start: Guid, names: &[String]) -> Option<Guid> {
    let mut at = start;
    for n in names {
        at = ds.find_child(at, n).ok()??;
    }
    Some(at)
}
