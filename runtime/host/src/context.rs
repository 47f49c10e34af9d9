//! What a running module is given, and what it tells the host.

use crossbeam_channel::Sender;
use mocu_dataserver::{DataServer, Executor, Guid, Value};
use std::panic::{AssertUnwindSafe, catch_unwind};
use std::sync::Arc;

/// How much a message matters.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Level {
    Info,
    Warning,
    Error,
}

/// What the host and its modules report, in order, to whoever runs the OCU (`mocu run`
/// prints them and writes the `Record`s to the `--log` file).
#[derive(Clone, Debug, PartialEq)]
pub enum HostEvent {
    Started {
        module: String,
        kind: String,
    },
    /// `start` returned an error (or the kind is unknown): the module is not running.
    Failed {
        module: String,
        reason: String,
    },
    /// The module panicked (in `start`, `stop` or one of its threads); it is isolated.
    Panicked {
        module: String,
        message: String,
    },
    Stopped {
        module: String,
    },
    Message {
        module: String,
        level: Level,
        text: String,
    },
    /// A trial-record event (`call`, `feedback`, …) with its fields, for `--log`.
    Record {
        module: String,
        event: String,
        fields: Vec<(String, Value)>,
    },
}

/// A module's view of the OCU: its DataServer handle, its own serial executor (run its
/// subscriptions and methods there and it need not be thread-safe), its status object
/// `root.modules.<name>`, and a line to the host.
#[derive(Clone)]
pub struct ModuleContext {
    pub name: Arc<str>,
    pub ds: DataServer,
    pub executor: Executor,
    /// `root.modules.<name>`: the host sets `kind` and `state` there; a module may add its
    /// own statistics.
    pub status: Guid,
    events: Sender<HostEvent>,
    /// Whether the module panicked, held while `state` is written: a thread of the module
    /// that panics during `start` is never reported `running` after (see [`Self::mark_running`]).
    panicked: Arc<parking_lot::Mutex<bool>>,
}

impl ModuleContext {
    pub(crate) fn new(
        name: &str,
        ds: DataServer,
        executor: Executor,
        status: Guid,
        events: Sender<HostEvent>,
    ) -> ModuleContext {
        let panicked = Arc::default();
        ModuleContext { name: name.into(), ds, executor, status, events, panicked }
    }

    /// A context outside any host (tests, benchmarks): events are dropped.
    pub fn detached(name: &str, ds: DataServer) -> ModuleContext {
        let executor = ds.serial_executor();
        let status = crate::world::ensure_path(&ds, &["modules", name], "module")
            .expect("root exists, so root.modules.<name> can be created");
        let (tx, _rx) = crossbeam_channel::unbounded();
        ModuleContext::new(name, ds, executor, status, tx)
    }

    /// Tells the host something worth showing the operator.
    pub fn report(&self, level: Level, text: impl Into<String>) {
        let _ = self.events.send(HostEvent::Message {
            module: self.name.to_string(),
            level,
            text: text.into(),
        });
    }

    /// Adds an event to the trial record (`--log`, `--record`): `input`, … Stamped now, on
    /// the DataServer's clock (a `time` field, seconds since the Unix epoch), not when the
    /// host's events are drained.
    pub fn record(&self, event: &str, fields: Vec<(&str, Value)>) {
        let time = ("time".to_string(), Value::Float(self.ds.wall_secs()));
        let fields = fields.into_iter().map(|(k, v)| (k.to_string(), v));
        let _ = self.events.send(HostEvent::Record {
            module: self.name.to_string(),
            event: event.to_string(),
            fields: std::iter::once(time).chain(fields).collect(),
        });
    }

    /// Runs `f`, catching a panic: the module is marked `panicked` and the host told.
    /// Returns false when `f` panicked.
    pub fn guard(&self, f: impl FnOnce()) -> bool {
        match catch_unwind(AssertUnwindSafe(f)) {
            Ok(()) => true,
            Err(p) => {
                self.panicked(panic_message(&*p));
                false
            }
        }
    }

    /// Starts a thread for blocking I/O at the module's edge (a socket reader). A panic
    /// there is caught and reported; the OCU goes on.
    pub fn spawn_thread(
        &self,
        what: &str,
        f: impl FnOnce() + Send + 'static,
    ) -> std::io::Result<std::thread::JoinHandle<()>> {
        let me = self.clone();
        std::thread::Builder::new().name(format!("{}-{what}", self.name)).spawn(move || {
            me.guard(f);
        })
    }

    pub(crate) fn panicked(&self, message: String) {
        {
            let mut panicked = self.panicked.lock();
            *panicked = true;
            let _ = self.ds.set(self.status, "state", Value::str("panicked"));
        }
        let _ = self.ds.set(self.status, "error", Value::str(&message));
        let _ = self.events.send(HostEvent::Panicked { module: self.name.to_string(), message });
    }
}

impl ModuleContext {
    /// Marks the module `running` once its `start` returned, unless one of its threads
    /// panicked meanwhile (then `panicked` stays).
    pub(crate) fn mark_running(&self) {
        let panicked = self.panicked.lock();
        if !*panicked {
            let _ = self.ds.set(self.status, "state", Value::str("running"));
        }
    }
}

pub(crate) fn panic_message(p: &(dyn std::any::Any + Send)) -> String {
    if let Some(s) = p.downcast_ref::<&str>() {
        (*s).to_string()
    } else if let Some(s) = p.downcast_ref::<String>() {
        s.clone()
    } else {
        "a panic with a non-text payload".to_string()
    }
}
