//! The registry of module kinds and the host that starts and stops them in order.

use crate::context::{HostEvent, ModuleContext, panic_message};
use crate::spec::ModuleSpec;
use crossbeam_channel::{Receiver, Sender};
use mocu_dataserver::{DataServer, Value};
use std::collections::BTreeMap;
use std::fmt;
use std::panic::{AssertUnwindSafe, catch_unwind};

/// The receiving end of the host's reports.
pub type Events = Receiver<HostEvent>;

/// A module: started once with its context, stopped once. `start` should return quickly:
/// periodic work goes to `ctx.ds.run_after` on `ctx.executor`, blocking I/O to
/// `ctx.spawn_thread`.
pub trait Module: Send {
    fn start(&mut self, ctx: &ModuleContext) -> Result<(), String>;
    /// Stops the module's work (timers, threads). Objects it published may stay.
    fn stop(&mut self) {}
}

/// Makes a module of one kind from its spec (settings are checked here or in `start`).
pub type Factory = Box<dyn Fn(&ModuleSpec) -> Result<Box<dyn Module>, String> + Send + Sync>;

/// Module kinds by name. Registering a kind again replaces it: a project can swap any core
/// piece (simulator, MAVLink, the widget renderer, the map view, the video windows, input)
/// for its own, or register a kind of its own and choose it in the profile
/// (`[modules.map_view] kind = "my_map"`; [`crate::fill_roles`]).
#[derive(Default)]
pub struct Registry {
    kinds: BTreeMap<String, Factory>,
}

impl Registry {
    pub fn new() -> Registry {
        Registry::default()
    }

    pub fn register(
        &mut self,
        kind: &str,
        factory: impl Fn(&ModuleSpec) -> Result<Box<dyn Module>, String> + Send + Sync + 'static,
    ) {
        self.kinds.insert(kind.to_string(), Box::new(factory));
    }

    pub fn kinds(&self) -> impl Iterator<Item = &str> {
        self.kinds.keys().map(|k| k.as_str())
    }

    /// Makes the module `spec` names from its settings, without starting it: the settings
    /// checked by the module's own factory, as `mocu check` does for a profile and the host
    /// does before `start`.
    pub fn make(&self, spec: &ModuleSpec) -> Result<Box<dyn Module>, StartError> {
        let Some(factory) = self.kinds.get(&spec.kind) else { return Err(self.unknown(spec)) };
        let module = spec.name.clone();
        match catch_unwind(AssertUnwindSafe(|| factory(spec))) {
            Ok(Ok(m)) => Ok(m),
            Ok(Err(reason)) => Err(StartError::Failed { module, reason }),
            Err(p) => Err(StartError::Panicked { module, message: panic_message(&*p) }),
        }
    }

    /// The error for a spec whose kind is not registered, listing the kinds that are.
    fn unknown(&self, spec: &ModuleSpec) -> StartError {
        let known = self.kinds().map(str::to_string).collect();
        StartError::UnknownKind { module: spec.name.clone(), kind: spec.kind.clone(), known }
    }
}

impl StartError {
    /// The module that did not start.
    pub fn module(&self) -> &str {
        match self {
            StartError::UnknownKind { module, .. }
            | StartError::DuplicateName { module }
            | StartError::Failed { module, .. }
            | StartError::Panicked { module, .. } => module,
        }
    }
}

/// Why a module did not start.
#[derive(Clone, Debug, PartialEq)]
pub enum StartError {
    /// No kind of that name is registered; `known` lists the kinds that are.
    UnknownKind {
        module: String,
        kind: String,
        known: Vec<String>,
    },
    DuplicateName {
        module: String,
    },
    Failed {
        module: String,
        reason: String,
    },
    Panicked {
        module: String,
        message: String,
    },
}

impl fmt::Display for StartError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            StartError::UnknownKind { module, kind, known } => write!(
                f,
                "module `{module}`: no module kind `{kind}` is registered (the kinds are: {})",
                known.join(", ")
            ),
            StartError::DuplicateName { module } => {
                write!(f, "module `{module}`: another module already has this name")
            }
            StartError::Failed { module, reason } => {
                write!(f, "module `{module}` failed to start: {reason}")
            }
            StartError::Panicked { module, message } => {
                write!(f, "module `{module}` panicked while starting: {message}")
            }
        }
    }
}

struct Running {
    module: Box<dyn Module>,
    ctx: ModuleContext,
}

/// Starts modules in order, isolates their failures, stops them in reverse order.
pub struct ModuleHost {
    ds: DataServer,
    registry: Registry,
    running: Vec<Running>,
    tx: Sender<HostEvent>,
    rx: Receiver<HostEvent>,
}

impl ModuleHost {
    pub fn new(ds: DataServer, registry: Registry) -> ModuleHost {
        let (tx, rx) = crossbeam_channel::unbounded();
        ModuleHost { ds, registry, running: Vec::new(), tx, rx }
    }

    pub fn dataserver(&self) -> &DataServer {
        &self.ds
    }

    /// The host's and the modules' reports, in order. Every clone sees each event once.
    pub fn events(&self) -> Events {
        self.rx.clone()
    }

    /// Starts each module in order. One that fails is reported (an event and an entry in
    /// the returned list) and the rest still start.
    pub fn start_all(&mut self, specs: &[ModuleSpec]) -> Vec<StartError> {
        specs.iter().filter_map(|s| self.start(s).err()).collect()
    }

    /// Starts one module.
    pub fn start(&mut self, spec: &ModuleSpec) -> Result<(), StartError> {
        let result = self.try_start(spec);
        if let Err(e) = &result {
            let event = match e {
                StartError::Panicked { module, message } => {
                    HostEvent::Panicked { module: module.clone(), message: message.clone() }
                }
                other => HostEvent::Failed { module: spec.name.clone(), reason: other.to_string() },
            };
            let _ = self.tx.send(event);
        }
        result
    }

    fn try_start(&mut self, spec: &ModuleSpec) -> Result<(), StartError> {
        let module = spec.name.clone();
        if self.running.iter().any(|r| *r.ctx.name == *spec.name) {
            return Err(StartError::DuplicateName { module });
        }
        if !self.registry.kinds.contains_key(&spec.kind) {
            return Err(self.registry.unknown(spec));
        }
        let status = crate::world::ensure_path(&self.ds, &["modules", &spec.name], "module")
            .map_err(|e| StartError::Failed { module: module.clone(), reason: e.to_string() })?;
        let _ = self.ds.set(status, "kind", Value::str(&spec.kind));
        let _ = self.ds.set(status, "state", Value::str("starting"));
        let ctx = ModuleContext::new(
            &spec.name,
            self.ds.clone(),
            self.ds.serial_executor(),
            status,
            self.tx.clone(),
        );
        let fail = |state: &str, why: &str| {
            let _ = self.ds.set(status, "state", Value::str(state));
            let _ = self.ds.set(status, "error", Value::str(why));
        };
        let mut m = match self.registry.make(spec) {
            Ok(m) => m,
            Err(e) => {
                match &e {
                    StartError::Failed { reason, .. } => fail("failed", reason),
                    StartError::Panicked { message, .. } => fail("panicked", message),
                    _ => {}
                }
                return Err(e);
            }
        };
        match catch_unwind(AssertUnwindSafe(|| m.start(&ctx))) {
            Ok(Ok(())) => {}
            Ok(Err(reason)) => {
                fail("failed", &reason);
                stop_quietly(&mut m);
                return Err(StartError::Failed { module, reason });
            }
            Err(p) => {
                let message = panic_message(&*p);
                fail("panicked", &message);
                stop_quietly(&mut m);
                return Err(StartError::Panicked { module, message });
            }
        }
        ctx.mark_running();
        let _ = self.tx.send(HostEvent::Started { module, kind: spec.kind.clone() });
        self.running.push(Running { module: m, ctx });
        Ok(())
    }

    /// Names of the modules that started, in start order.
    pub fn running(&self) -> Vec<String> {
        self.running.iter().map(|r| r.ctx.name.to_string()).collect()
    }

    /// Stops every module, last started first. A panic in one `stop` is reported and the
    /// others still stop.
    pub fn stop_all(&mut self) {
        while let Some(mut r) = self.running.pop() {
            let ok = r.ctx.guard(|| r.module.stop());
            if ok {
                let _ = self.ds.set(r.ctx.status, "state", Value::str("stopped"));
                let _ = self.tx.send(HostEvent::Stopped { module: r.ctx.name.to_string() });
            }
        }
    }
}

impl Drop for ModuleHost {
    fn drop(&mut self) {
        self.stop_all();
    }
}

fn stop_quietly(m: &mut Box<dyn Module>) {
    let _ = catch_unwind(AssertUnwindSafe(|| m.stop()));
}
