//! The input module: sources on threads of their own, the engine behind a lock, DataServer
//! timers for what is due later, binding discovery, the window's keyboard and mouse, the
//! selection's default, and the toast list.

use crate::engine::{Engine, EngineConfig, scan_bindings};
use crate::event::{DeviceType, EventKind, InputEvent};
use crate::gilrs_source::GilrsSource;
use crate::source::{InputSource, ScriptedSource};
use crate::toasts::Toasts;
use mocu_dataserver::{
    CallOutcome, DottedPath, Kind, MethodSpec, Notification, ParamSpec, PathWatch, Subject,
    SubscriptionId, Topic, ValueKind,
};
use mocu_dataserver::{Guid, PropName, Value};
use mocu_host::{Level, Module, ModuleContext, ModuleSpec, Registry};
use parking_lot::Mutex;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

/// Settings of the module (`[modules.input]` in a profile).
#[derive(Clone, Debug, PartialEq)]
pub struct InputConfig {
    pub engine: EngineConfig,
    /// Listen for gamepads through gilrs.
    pub gilrs: bool,
    /// An input script to replay (`mocu run --input-script FILE`).
    pub script: Option<String>,
    /// How many entries `root.operator.toasts` keeps (0: no toast list).
    pub toasts: usize,
    /// Select the first vehicle under `root.vehicles` while nothing is selected.
    pub auto_select: bool,
}

impl Default for InputConfig {
    fn default() -> InputConfig {
        InputConfig {
            engine: EngineConfig::default(),
            gilrs: true,
            script: None,
            toasts: 5,
            auto_select: true,
        }
    }
}

impl InputConfig {
    pub fn from_spec(spec: &ModuleSpec) -> Result<InputConfig, String> {
        let d = InputConfig::default();
        let e = |e: mocu_host::SpecError| e.to_string();
        let rate_hz = spec.f64_or("rate_hz", d.engine.rate_hz).map_err(e)?;
        if !(1.0..=250.0).contains(&rate_hz) {
            return Err(format!(
                "module `{}`: `rate_hz` must be in 1..=250 (25–50 is usual)",
                spec.name
            ));
        }
        let double_ms = spec.f64_or("double_ms", 300.0).map_err(e)?;
        if !(10.0..=2000.0).contains(&double_ms) {
            return Err(format!("module `{}`: `double_ms` must be in 10..=2000", spec.name));
        }
        let script = spec.str_or("script", "").map_err(e)?;
        let toasts = spec.i64_or("toasts", d.toasts as i64).map_err(e)?;
        Ok(InputConfig {
            engine: EngineConfig { rate_hz, double: Duration::from_secs_f64(double_ms / 1000.0) },
            gilrs: spec.bool_or("gilrs", d.gilrs).map_err(e)?,
            script: (!script.is_empty()).then_some(script),
            toasts: toasts.clamp(0, 20) as usize,
            auto_select: spec.bool_or("auto_select", d.auto_select).map_err(e)?,
        })
    }
}

/// The input module. Other sources (a different joystick driver) are added with
/// [`InputModule::with_source`]; replacing the whole module is registering another `input`.
pub struct InputModule {
    cfg: InputConfig,
    sources: Vec<Box<dyn InputSource>>,
    shared: Option<Arc<Shared>>,
    threads: Vec<std::thread::JoinHandle<()>>,
}

struct Shared {
    ctx: ModuleContext,
    engine: Mutex<Engine>,
    scheduled: Mutex<Option<Instant>>,
    stop: Arc<AtomicBool>,
    /// Sources that wait for the layout's bindings.
    deferred: Mutex<Vec<Box<dyn InputSource>>>,
    /// The input script, played on the DataServer's clock from the first bindings.
    script: Mutex<Option<ScriptedSource>>,
    threads: Mutex<Vec<std::thread::JoinHandle<()>>>,
    watches: Mutex<Vec<PathWatch>>,
    subs: Mutex<Vec<SubscriptionId>>,
    toasts: Mutex<Option<Toasts>>,
    stats_at: Mutex<Option<Instant>>,
}

impl InputModule {
    pub fn new(cfg: InputConfig) -> InputModule {
        InputModule { cfg, sources: Vec::new(), shared: None, threads: Vec::new() }
    }

    /// Adds a source, started when the layout's bindings are published (so that a
    /// scripted sequence is not lost before there is anything to bind it to).
    pub fn with_source(mut self, s: Box<dyn InputSource>) -> InputModule {
        self.sources.push(s);
        self
    }

    /// The engine's counters (after `start`).
    pub fn stats(&self) -> Option<crate::engine::EngineStats> {
        self.shared.as_ref().map(|s| s.engine.lock().stats())
    }
}

impl Module for InputModule {
    fn start(&mut self, ctx: &ModuleContext) -> Result<(), String> {
        let engine = Engine::new(&ctx.ds, self.cfg.engine.clone())?;
        let deferred = std::mem::take(&mut self.sources);
        let script = match &self.cfg.script {
            Some(path) => {
                let text = std::fs::read_to_string(path)
                    .map_err(|e| format!("input script {path}: {e}"))?;
                Some(ScriptedSource::parse(&text)?)
            }
            None => None,
        };
        let sh = Arc::new(Shared {
            ctx: ctx.clone(),
            engine: Mutex::new(engine),
            scheduled: Mutex::new(None),
            stop: Arc::new(AtomicBool::new(false)),
            deferred: Mutex::new(deferred),
            script: Mutex::new(script),
            threads: Mutex::new(Vec::new()),
            watches: Mutex::new(Vec::new()),
            subs: Mutex::new(Vec::new()),
            toasts: Mutex::new(None),
            stats_at: Mutex::new(None),
        });
        sh.window_devices();
        sh.follow_bindings()?;
        if self.cfg.auto_select {
            sh.follow_vehicles()?;
        }
        if self.cfg.toasts > 0 {
            *sh.toasts.lock() = Some(Toasts::start(&ctx.ds, &ctx.executor, self.cfg.toasts)?);
        }
        if self.cfg.gilrs {
            sh.spawn(Box::new(GilrsSource::new()));
        }
        let _ = ctx.ds.set(ctx.status, "rate_hz", Value::Float(self.cfg.engine.rate_hz));
        self.shared = Some(sh);
        Ok(())
    }

    fn stop(&mut self) {
        if let Some(sh) = self.shared.take() {
            sh.stop.store(true, Ordering::SeqCst);
            // Taken out, then ended with no lock held: ending one waits for its running
            // callback, which may take these locks. Rounds until a callback that was
            // running has nothing more to add.
            loop {
                let watches = std::mem::take(&mut *sh.watches.lock());
                let subs = std::mem::take(&mut *sh.subs.lock());
                if watches.is_empty() && subs.is_empty() {
                    break;
                }
                drop(watches);
                for s in subs {
                    sh.ctx.ds.unsubscribe(s);
                }
            }
            let toasts = sh.toasts.lock().take();
            drop(toasts);
            let threads: Vec<_> = sh.threads.lock().drain(..).collect();
            self.threads.extend(threads);
        }
        for t in self.threads.drain(..) {
            let _ = t.join();
        }
    }
}

impl Drop for InputModule {
    fn drop(&mut self) {
        self.stop();
    }
}

impl Shared {
    /// Hands one event to the engine and arms a timer for what is due next.
    fn feed(self: &Arc<Self>, ev: InputEvent) {
        match &ev.kind {
            EventKind::Connected { device_type, name, mapping } => {
                self.ctx.report(
                    Level::Info,
                    format!("{} connected: {name} ({mapping})", device_type.name()),
                );
                self.ctx.record(
                    "input",
                    vec![
                        ("device", Value::str(&ev.device)),
                        ("state", Value::str("connected")),
                        ("name", Value::str(name)),
                    ],
                );
            }
            EventKind::Disconnected => {
                self.ctx.report(Level::Info, format!("{} disconnected", ev.device));
                self.ctx.record(
                    "input",
                    vec![("device", Value::str(&ev.device)), ("state", Value::str("disconnected"))],
                );
            }
            _ => {}
        }
        let wake = self.engine.lock().handle(&ev);
        self.after(wake);
        self.publish_stats(ev.time);
    }

    fn publish_stats(&self, now: Instant) {
        let mut at = self.stats_at.lock();
        if at.is_some_and(|t| now.saturating_duration_since(t) < Duration::from_secs(1)) {
            return;
        }
        *at = Some(now);
        let s = self.engine.lock().stats();
        let ds = &self.ctx.ds;
        let _ = ds.set(self.ctx.status, "events", Value::Int(s.events as i64));
        let _ = ds.set(self.ctx.status, "fires", Value::Int(s.fires as i64));
        let _ = ds.set(self.ctx.status, "devices", Value::Int(s.devices as i64));
    }

    /// Arms one DataServer timer for `wake` unless an earlier one is armed.
    fn after(self: &Arc<Self>, wake: Option<Instant>) {
        let Some(w) = wake else { return };
        {
            let mut s = self.scheduled.lock();
            if s.is_some_and(|x| x <= w) {
                return;
            }
            *s = Some(w);
        }
        let weak = Arc::downgrade(self);
        let delay = w.saturating_duration_since(self.ctx.ds.now());
        self.ctx.ds.run_after(delay, Some(&self.ctx.executor), move || {
            let Some(sh) = weak.upgrade() else { return };
            if sh.stop.load(Ordering::SeqCst) {
                return;
            }
            {
                let mut s = sh.scheduled.lock();
                if s.is_some_and(|x| x <= sh.ctx.ds.now()) {
                    *s = None;
                }
            }
            let now = sh.ctx.ds.now();
            let next = sh.engine.lock().tick(now);
            sh.after(next);
        });
    }

    /// Plays an input script on the DataServer's clock: each step is a timer of its own,
    /// due its time after now and stamped with that time, so a run on a stepped clock
    /// (`DataServer::advance_settled`) sees the same events at the same times every run.
    fn play(self: &Arc<Self>, script: ScriptedSource) {
        let t0 = self.ctx.ds.now();
        for ev in script.events_from(t0) {
            let weak = Arc::downgrade(self);
            let delay = ev.time.saturating_duration_since(t0);
            self.ctx.ds.run_after(delay, Some(&self.ctx.executor), move || {
                if let Some(sh) = weak.upgrade()
                    && !sh.stop.load(Ordering::SeqCst)
                {
                    sh.feed(ev);
                }
            });
        }
    }

    fn spawn(self: &Arc<Self>, mut src: Box<dyn InputSource>) {
        let weak = Arc::downgrade(self);
        let stop = self.stop.clone();
        let ctx = self.ctx.clone();
        let name = src.name().to_string();
        let r = self.ctx.spawn_thread(&name, move || {
            let mut out = |ev: InputEvent| {
                if let Some(sh) = weak.upgrade() {
                    sh.feed(ev);
                }
            };
            if let Err(e) = src.run(&mut out, &stop) {
                ctx.report(Level::Warning, format!("{}: {e} (no events from it)", src.name()));
            }
        });
        match r {
            Ok(t) => self.threads.lock().push(t),
            Err(e) => {
                self.ctx.report(Level::Warning, format!("cannot start the {name} source: {e}"))
            }
        }
    }

    /// `root.operator.inputs.keyboard` and `.mouse`, fed by whoever has a window:
    /// `keyboard.key(name, pressed)`, `mouse.button(name, pressed)`, `mouse.wheel(axis,
    /// delta)`.
    fn window_devices(self: &Arc<Self>) {
        let now = self.ctx.ds.now();
        for (id, ty) in [("keyboard", DeviceType::Keyboard), ("mouse", DeviceType::Mouse)] {
            let kind = EventKind::Connected {
                device_type: ty,
                name: format!("window {id}"),
                mapping: "window".into(),
            };
            self.engine.lock().handle(&InputEvent::new(now, id, kind));
        }
        let ds = &self.ctx.ds;
        let (kb, mouse) = {
            let e = self.engine.lock();
            (e.device_object("keyboard"), e.device_object("mouse"))
        };
        let p = ParamSpec::new;
        let methods: [(Option<Guid>, &str, &str, MethodSpec); 3] = [
            (
                kb,
                "keyboard",
                "key",
                MethodSpec::new("key")
                    .param(p("name", ValueKind::String))
                    .param(p("pressed", ValueKind::Bool))
                    .ordered(),
            ),
            (
                mouse,
                "mouse",
                "button",
                MethodSpec::new("button")
                    .param(p("name", ValueKind::String))
                    .param(p("pressed", ValueKind::Bool))
                    .ordered(),
            ),
            (
                mouse,
                "mouse",
                "wheel",
                MethodSpec::new("wheel")
                    .param(p("axis", ValueKind::String))
                    .param(p("delta", ValueKind::Float))
                    .ordered(),
            ),
        ];
        for (obj, device, method, spec) in methods {
            let Some(obj) = obj else { continue };
            let weak = Arc::downgrade(self);
            let _ = ds.publish_method_fn(obj, spec, move |args| {
                let Some(sh) = weak.upgrade() else {
                    return CallOutcome::Failed("input stopped".into());
                };
                let name = args[0].as_str().unwrap_or("").to_ascii_lowercase();
                let kind = if method == "wheel" {
                    EventKind::Wheel { axis: name, delta: args[1].as_f64().unwrap_or(0.0) }
                } else {
                    EventKind::Button { button: name, pressed: args[1].as_bool().unwrap_or(false) }
                };
                sh.feed(InputEvent::new(sh.ctx.ds.now(), device, kind));
                CallOutcome::Accepted(vec![])
            });
        }
    }

    /// Rescans `root.display.bindings` whenever its `revision` changes; starts the
    /// deferred sources at the first bindings.
    fn follow_bindings(self: &Arc<Self>) -> Result<(), String> {
        let weak = Arc::downgrade(self);
        let path = DottedPath::parse("display.bindings.revision").map_err(|e| e.to_string())?;
        let w = self
            .ctx
            .ds
            .watch_path(path, Some(&self.ctx.executor), move |ev| {
                let Some(sh) = weak.upgrade() else { return };
                let defs = match ev.kind {
                    Kind::Deleted => Vec::new(),
                    _ => scan_bindings(&sh.ctx.ds, ev.object),
                };
                let n = defs.len();
                sh.engine.lock().set_bindings(defs);
                let _ = sh.ctx.ds.set(sh.ctx.status, "bindings", Value::Int(n as i64));
                if n > 0 {
                    let waiting: Vec<_> = sh.deferred.lock().drain(..).collect();
                    for s in waiting {
                        sh.spawn(s);
                    }
                    let script = sh.script.lock().take();
                    if let Some(script) = script {
                        sh.play(script);
                    }
                }
            })
            .map_err(|e| e.to_string())?;
        self.watches.lock().push(w);
        Ok(())
    }

    /// While nothing (or something gone) is selected, the first vehicle is.
    fn follow_vehicles(self: &Arc<Self>) -> Result<(), String> {
        let weak = Arc::downgrade(self);
        let w = self
            .ctx
            .ds
            .watch_object(Guid::ROOT, &["vehicles"], Some(&self.ctx.executor), move |ev| {
                let Some(sh) = weak.upgrade() else { return };
                if ev.kind == Kind::Deleted {
                    return;
                }
                let weak = Arc::downgrade(&sh);
                let sub = sh.ctx.ds.subscribe_on(
                    &sh.ctx.executor,
                    Topic::children(ev.object),
                    move |n: &Notification| {
                        if let (Some(sh), Subject::Child { guid, name, .. }, Kind::New) =
                            (weak.upgrade(), &n.subject, n.kind)
                        {
                            sh.select_if_none(*guid, name);
                        }
                    },
                );
                if let Ok(s) = sub {
                    sh.subs.lock().push(s);
                }
            })
            .map_err(|e| e.to_string())?;
        self.watches.lock().push(w);
        Ok(())
    }

    fn select_if_none(&self, g: Guid, name: &str) {
        let ds = &self.ctx.ds;
        let Some(op) = ds.resolve(&["operator"]) else { return };
        let current = ds.try_get(op, PropName::new("selected")).and_then(|v| v.as_guid());
        if current.is_some_and(|c| ds.exists(c)) {
            return;
        }
        let _ = ds.set(op, "selected", Value::Guid(g));
        let _ = ds.set(op, "selected_name", Value::str(name));
    }
}

/// Registers the kind `input`.
pub fn register(registry: &mut Registry) {
    registry.register("input", |spec| {
        let cfg = InputConfig::from_spec(spec)?;
        Ok(Box::new(InputModule::new(cfg)) as Box<dyn Module>)
    });
}
