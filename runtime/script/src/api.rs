//! The DataServer as a script sees it: read, write, subscribe, call with feedback, create
//! objects, delayed calls — through the DataServer's public API, with the rules a native
//! module has (the server checks writes and calls the same way). Callbacks a script hands
//! over are numbered by its engine; they run on the script's serial executor, one at a time,
//! never on the caller's thread (a call answered at once still comes back through the executor).

use crate::error::{ApiError, ScriptError};
use crate::script::Cell;
use mocu_dataserver::{
    CallOutcome, DataServer, DottedPath, Executor, Guid, ObjectInfo, PathWatch, Value,
};
use parking_lot::Mutex;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, OnceLock, Weak};
use std::time::Duration;

/// A callback a script handed to the API, numbered by its engine.
pub type CallbackId = u64;

/// Where a script's errors go (the module host's report, the layout's alerts and log).
pub type Reporter = Arc<dyn Fn(&ScriptError) + Send + Sync>;

/// One script's handle on the DataServer. Cheap to clone; every clone is the same script.
#[derive(Clone)]
pub struct Api {
    inner: Arc<Inner>,
}

struct Inner {
    ds: DataServer,
    executor: Executor,
    report: Reporter,
    owner: OnceLock<Weak<Cell>>,
    watches: Mutex<Vec<PathWatch>>,
    stopped: AtomicBool,
}

impl Api {
    /// A script's API over `ds`; its callbacks run on `executor`.
    pub fn new(ds: DataServer, executor: Executor, report: Reporter) -> Api {
        Api {
            inner: Arc::new(Inner {
                ds,
                executor,
                report,
                owner: OnceLock::new(),
                watches: Mutex::new(Vec::new()),
                stopped: AtomicBool::new(false),
            }),
        }
    }

    pub(crate) fn bind(&self, cell: &Arc<Cell>) {
        let _ = self.inner.owner.set(Arc::downgrade(cell));
    }

    pub fn dataserver(&self) -> &DataServer {
        &self.inner.ds
    }

    pub fn executor(&self) -> &Executor {
        &self.inner.executor
    }

    pub fn is_stopped(&self) -> bool {
        self.inner.stopped.load(Ordering::Acquire)
    }

    fn live(&self) -> Result<(), ApiError> {
        if self.is_stopped() { Err(ApiError::Stopped) } else { Ok(()) }
    }

    /// The value at `path` (`vehicles.usv1.nav.speed`, `root.` optional), or `None` while
    /// the object or the property is absent (a vehicle not discovered yet).
    pub fn read(&self, path: &str) -> Result<Option<Value>, ApiError> {
        self.live()?;
        let p = parse(path)?;
        let Some(object) = self.object(&p.objects) else { return Ok(None) };
        Ok(self.inner.ds.try_get(object, p.property))
    }

    /// Writes a property; the DataServer checks it as it checks a module's write.
    pub fn write(&self, path: &str, value: Value) -> Result<(), ApiError> {
        self.live()?;
        let p = parse(path)?;
        let object = self.object(&p.objects).ok_or_else(|| no_object(path))?;
        self.inner.ds.set(object, p.property, value).map_err(|e| refused(path, e))
    }

    /// Calls `callback` with each value of `path` (and `()`/`undefined` when it goes),
    /// first with the value there now. Follows discovery: the path may not exist yet.
    pub fn subscribe(&self, path: &str, callback: CallbackId) -> Result<(), ApiError> {
        self.live()?;
        let p = DottedPath::parse(path).map_err(|e| bad_path(path, e))?;
        let me = self.clone();
        let watch = self
            .inner
            .ds
            .watch_path(p, Some(&self.inner.executor), move |ev| {
                me.invoke(callback, vec![ev.value.clone()], false);
            })
            .map_err(|e| refused(path, e))?;
        self.inner.watches.lock().push(watch);
        Ok(())
    }

    /// Calls the method at `path` (`vehicles.usv1.arm`); `callback`, if any, gets the
    /// outcome's label (`accepted`, `refused`, …) and its results or reason.
    pub fn call(
        &self,
        path: &str,
        args: Vec<Value>,
        callback: Option<CallbackId>,
    ) -> Result<(), ApiError> {
        self.live()?;
        let p = parse(path)?;
        let object = self.object(&p.objects).ok_or_else(|| no_object(path))?;
        let me = self.clone();
        self.inner.ds.call(object, p.property, args, None, move |outcome| {
            if let Some(cb) = callback {
                let args = outcome_args(&outcome);
                let ex = me.inner.executor.clone();
                ex.spawn(move || me.invoke(cb, args, true));
            }
        });
        Ok(())
    }

    /// Creates an object `name` of `kind` under the object at `parent` (`""` or `root`:
    /// the root); returns the new object's path.
    pub fn create(&self, parent: &str, name: &str, kind: &str) -> Result<String, ApiError> {
        self.live()?;
        let segs = object_segments(parent);
        let at = self.object(&segs).ok_or_else(|| no_object(parent))?;
        self.inner
            .ds
            .create_object(at, ObjectInfo::new(name, kind))
            .map_err(|e| refused(parent, e))?;
        Ok(segs.iter().copied().chain([name]).collect::<Vec<_>>().join("."))
    }

    /// Calls `callback` once after `ms` milliseconds of the DataServer's clock.
    pub fn after(&self, ms: f64, callback: CallbackId) -> Result<(), ApiError> {
        self.live()?;
        // NaN and negatives are now; past what a Duration holds, never (the timer saturates).
        let delay = Duration::try_from_secs_f64(ms.max(0.0) / 1000.0).unwrap_or(Duration::MAX);
        let me = self.clone();
        self.inner.ds.run_after(delay, Some(&self.inner.executor), move || {
            me.invoke(callback, Vec::new(), true);
        });
        Ok(())
    }

    /// Hands a script's error to its reporter.
    pub fn report(&self, e: &ScriptError) {
        (self.inner.report)(e);
    }

    /// Runs a callback in the script (on the executor this is called from); an error is
    /// reported, and one that stops the script stops it.
    fn invoke(&self, callback: CallbackId, args: Vec<Option<Value>>, once: bool) {
        if self.is_stopped() {
            return;
        }
        let Some(cell) = self.inner.owner.get().and_then(Weak::upgrade) else { return };
        if let Err(e) = cell.invoke(callback, &args, once) {
            self.fail(&e);
        }
    }

    /// Reports an error; stops the script when the error is one that stops it.
    pub(crate) fn fail(&self, e: &ScriptError) {
        self.report(e);
        if e.kind.stops() {
            self.stop();
        }
    }

    /// Ends the script's subscriptions; its timers and answers find it stopped and do
    /// nothing. Safe from inside one of its own callbacks.
    pub fn stop(&self) {
        self.inner.stopped.store(true, Ordering::Release);
        let watches = std::mem::take(&mut *self.inner.watches.lock());
        for w in watches {
            w.cancel_nowait();
        }
    }

    fn object<S: AsRef<str>>(&self, segs: &[S]) -> Option<Guid> {
        let names: Vec<&str> = segs.iter().map(|s| s.as_ref()).collect();
        self.inner.ds.resolve(&names)
    }
}

fn parse(path: &str) -> Result<DottedPath, ApiError> {
    DottedPath::parse(path).map_err(|e| bad_path(path, e))
}

fn object_segments(path: &str) -> Vec<&str> {
    let p = path.strip_prefix("root").map(|r| r.strip_prefix('.').unwrap_or(r)).unwrap_or(path);
    p.split('.').filter(|s| !s.is_empty()).collect()
}

fn bad_path(path: &str, e: impl std::fmt::Display) -> ApiError {
    ApiError::BadPath { path: path.to_string(), reason: e.to_string() }
}

fn no_object(path: &str) -> ApiError {
    ApiError::NoObject { path: path.to_string() }
}

fn refused(path: &str, e: impl std::fmt::Display) -> ApiError {
    ApiError::Refused { path: path.to_string(), reason: e.to_string() }
}

/// A call's outcome as a callback's two arguments: its label, then its results (a list) or
/// its reason (a string); nothing more for outcomes without either.
fn outcome_args(outcome: &CallOutcome) -> Vec<Option<Value>> {
    let label = Some(Value::str(outcome.label()));
    let detail = match outcome {
        CallOutcome::Accepted(results) => Some(Value::List(results.clone().into())),
        CallOutcome::Refused(why) | CallOutcome::Failed(why) => Some(Value::str(why)),
        _ => None,
    };
    vec![label, detail]
}
