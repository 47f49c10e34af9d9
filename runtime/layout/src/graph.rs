//! The live layout: compiled functions bound to the DataServer through shared path
//! subscriptions, evaluated once per tick for the cells whose inputs changed, with early
//! cutoff; outputs written under `root.display`.

use crate::actions::{self, CompiledAction};
use crate::convert::{to_slot, to_value};
use crate::events::EventSink;
use crate::lower::{Base, Source};
use crate::watch::WatchRt;
use mocu_dataserver::{
    DataServer, DottedPath, Executor, Kind, ObjectInfo, PathEvent, PathWatch, SubscriptionId,
};
use mocu_jit::{self as jit, Slot};
use mocu_language::program::Program;
use mocu_value::{Guid, PropName, Value};
use parking_lot::Mutex;
use std::cmp::Reverse;
use std::collections::{BinaryHeap, HashMap};
use std::sync::{Arc, Weak};
use std::time::Duration;

mod compile;
mod flow;
mod instances;
mod lets;
pub(crate) use compile::{
    Builder, CompiledWidget, CompiledWindow, FnRef, Frame, compile_template, compile_widget,
    compile_window,
};
pub(crate) use instances::{Instance, TemplateRt};

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
    /// How long a property stays fresh, by (object type, property): the schema's
    /// `stale_after` ([`LayoutConfig::stale_after_from`]); see `stale.rs` for the defaults.
    pub stale_after: HashMap<(String, String), Duration>,
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
            stale_after: HashMap::new(),
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
    /// Where the layout's script actions run (`scripts.rs`): serial, apart from evaluation.
    pub(crate) scripts: Executor,
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

/// A value cells read: a path's (kept by its watch) or a shared `let`'s (written by its
/// cell, the producer: `graph/lets.rs`).
pub(crate) struct Node {
    watch: Option<PathWatch>,
    pub(crate) value: Option<Value>,
    deps: Vec<usize>,
    users: usize,
    producer: Option<usize>,
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
    /// A shared `let`'s node.
    Node(usize),
    WatchWhen(usize),
    WatchClear(usize),
    /// A flowed window's `x`, `y`, `w`, `h` or `visible`, for its template's flow to place.
    FlowBox {
        instance: usize,
        window: usize,
        field: usize,
    },
    /// A flow's region (`graph/flow.rs`).
    FlowRegion {
        template: usize,
        field: usize,
    },
}

pub(crate) struct Cell {
    f: FnRef,
    inputs: Vec<(Input, jit::Ty)>,
    targets: Vec<Target>,
    last: Vec<Option<Value>>,
    dirty: bool,
    alive: bool,
    /// 0 for a cell reading no shared `let`; else one more than the highest level of the
    /// cells of the `let`s it reads: cells run in order of level, each once per tick.
    level: u32,
}

pub(crate) struct State {
    pub(crate) nodes: Vec<Node>,
    node_ix: HashMap<(Start, Vec<String>, String), usize>,
    /// The node of each shared `let` live now.
    let_ix: HashMap<lets::LetKey, usize>,
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
    /// IR nodes compiled since load (see [`LayoutStats::ir_nodes`]).
    pub(crate) ir_nodes: usize,
    pub(crate) closed: bool,
    /// Subscriptions of the layout's own machinery (the alert window following alerts and
    /// windows), ended when the layout is unloaded.
    pub(crate) subs: Vec<SubscriptionId>,
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
    /// Shared `let`s live now: each a node computed by a cell of its own (`graph/lets.rs`).
    pub shared_lets: usize,
    /// IR nodes compiled since load (every function lowered for the JIT or the
    /// interpreter, summed): as large as the source, however many functions read a `let`.
    pub ir_nodes: usize,
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
            scripts: ds.serial_executor(),
            sink,
            config,
            state: Mutex::new(State {
                nodes: Vec::new(),
                node_ix: HashMap::new(),
                let_ix: HashMap::new(),
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
                ir_nodes: 0,
                closed: false,
                subs: Vec::new(),
                items: Vec::new(),
            }),
            inbox: Mutex::new(Inbox::default()),
            ages: Mutex::new(HashMap::new()),
        });
        {
            let mut st = shared.state.lock();
            shared.apply(&mut st, program)?;
            shared.evaluate(&mut st);
            crate::alerts::place_layer(&shared, &st);
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
            crate::alerts::place_layer(&self.shared, &st);
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
            shared_lets: st.let_ix.len(),
            ir_nodes: st.ir_nodes,
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
            let mut subs: Vec<_> =
                st.templates.iter_mut().filter_map(|t| t.children_sub.take()).collect();
            subs.append(&mut st.subs);
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
        st.nodes.push(Node {
            watch: watch.ok(),
            value: None,
            deps: Vec::new(),
            users: 1,
            producer: None,
        });
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

    /// Binds a function to nodes and targets: a live cell (and the cells of the shared
    /// `let`s it reads, when they are not live yet).
    pub(crate) fn add_cell(
        self: &Arc<Self>,
        st: &mut State,
        f: &FnRef,
        targets: Vec<Target>,
        instance: Option<usize>,
    ) -> usize {
        self.bind_lets(st, f);
        self.bind_cell(st, f, targets, instance)
    }

    /// [`Shared::add_cell`] once the shared `let`s `f` reads are live.
    fn bind_cell(
        self: &Arc<Self>,
        st: &mut State,
        f: &FnRef,
        targets: Vec<Target>,
        instance: Option<usize>,
    ) -> usize {
        let idx = st.cells.len();
        let slots = f.slots().to_vec();
        let mut inputs = Vec::with_capacity(slots.len());
        let mut level = 0;
        for (src, ty) in slots {
            let input = match &src {
                Source::Let { id, digest } => match st.let_ix.get(&(*id, *digest, ty)) {
                    Some(&n) => {
                        let node = &mut st.nodes[n];
                        node.users += 1;
                        node.deps.push(idx);
                        if let Some(p) = node.producer {
                            level = level.max(st.cells[p].level + 1);
                        }
                        Input::Node(n)
                    }
                    None => Input::Absent, // `bind_lets` made them all
                },
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
            level,
        });
        st.dirty.push(idx);
        idx
    }

    /// Ends a cell: it stops being evaluated and releases its paths, and the shared
    /// `let`s no other cell reads (their cells too, without recursion).
    pub(crate) fn remove_cell(&self, st: &mut State, idx: usize) {
        let mut ending = vec![idx];
        while let Some(idx) = ending.pop() {
            let inputs = std::mem::take(&mut st.cells[idx].inputs);
            st.cells[idx].alive = false;
            for (input, _) in inputs {
                if let Input::Node(n) = input {
                    let node = &mut st.nodes[n];
                    node.deps.retain(|&d| d != idx);
                    node.users -= 1;
                    if node.users > 0 {
                        continue;
                    }
                    match node.producer.take() {
                        Some(p) => {
                            st.let_ix.retain(|_, v| *v != n);
                            node.value = None;
                            ending.push(p);
                        }
                        None => {
                            node.watch = None; // drops the watch: its subscriptions end
                            st.node_ix.retain(|_, v| *v != n);
                        }
                    }
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
        // A template's instance came or went (a vehicle's strip): the built-in alert window
        // is placed again once the new widgets have their positions.
        let templated = events.iter().any(|e| !matches!(e, InboxEvent::Node(..)));
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
        if templated {
            crate::alerts::place_layer(self, &st);
        }
    }

    /// Evaluates every dirty cell once, in order of level (a shared `let`'s cell before its
    /// readers); writes only outputs that changed (early cutoff).
    pub(crate) fn evaluate(self: &Arc<Self>, st: &mut State) {
        let mut queue: BinaryHeap<Reverse<(u32, usize)>> = BinaryHeap::new();
        let mut slots = Vec::new();
        let mut outs = Vec::new();
        loop {
            for c in std::mem::take(&mut st.dirty) {
                queue.push(Reverse((st.cells[c].level, c)));
            }
            let Some(Reverse((_, c))) = queue.pop() else { break };
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
        self.place_flows(st);
    }

    fn write_output(self: &Arc<Self>, st: &mut State, target: Target, v: Option<Value>) {
        match target {
            Target::Node(n) => {
                st.nodes[n].value = v;
                for i in 0..st.nodes[n].deps.len() {
                    let d = st.nodes[n].deps[i];
                    mark(st, d);
                }
            }
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
            Target::FlowBox { instance, window, field } => {
                flow::on_box(st, instance, window, field, v)
            }
            Target::FlowRegion { template, field } => flow::on_region(st, template, field, v),
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
            // One-shot functions are lowered without shared `let`s (`Builder::lowerer`).
            Source::Index | Source::Param(_) | Source::Let { .. } => Slot::ABSENT,
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
