//! A loaded script and where it runs: its instance behind one lock, its API, its executor.

use crate::api::{Api, CallbackId, Reporter};
use crate::engine::{Engine, Instance, Limits};
use crate::error::{ScriptError, Source};
use mocu_dataserver::{DataServer, Executor, Value};
use parking_lot::Mutex;
use std::sync::Arc;

/// The instance, `None` once the script is stopped.
pub(crate) struct Cell {
    instance: Mutex<Option<Box<dyn Instance>>>,
}

impl Cell {
    pub(crate) fn invoke(
        &self,
        callback: CallbackId,
        args: &[Option<Value>],
        once: bool,
    ) -> Result<(), ScriptError> {
        match self.instance.lock().as_mut() {
            Some(i) => i.invoke(callback, args, once),
            None => Ok(()),
        }
    }
}

/// A script bound to the DataServer. Its runs and callbacks go to its serial executor.
#[derive(Clone)]
pub struct Script {
    cell: Arc<Cell>,
    api: Api,
}

impl Script {
    /// Compiles `source` with `engine`; callbacks will run on `executor`, errors go to
    /// `report`.
    pub fn load(
        engine: &dyn Engine,
        source: &Source,
        ds: DataServer,
        executor: Executor,
        limits: &Limits,
        report: Reporter,
    ) -> Result<Script, ScriptError> {
        let api = Api::new(ds, executor, report);
        let instance = engine.load(source, api.clone(), limits)?;
        let cell = Arc::new(Cell { instance: Mutex::new(Some(instance)) });
        api.bind(&cell);
        Ok(Script { cell, api })
    }

    /// Runs the script's text on its executor; an error is reported (and stops the script
    /// when it is a runaway).
    pub fn run(&self) {
        let me = self.clone();
        self.api.executor().spawn(move || {
            if let Err(e) = me.run_here() {
                me.api.fail(&e);
            }
        });
    }

    /// Runs the script's text on this thread (tests, benchmarks, a layout's action already
    /// on its executor); the caller gets the error (a runaway has stopped the script).
    pub fn run_here(&self) -> Result<(), ScriptError> {
        self.run_here_with(&[])
    }

    /// [`Script::run_here`] with variables set.
    pub fn run_here_with(&self, vars: &[(&str, Option<Value>)]) -> Result<(), ScriptError> {
        if self.api.is_stopped() {
            return Ok(());
        }
        let result = match self.cell.instance.lock().as_mut() {
            Some(i) if vars.is_empty() => i.run(),
            Some(i) => i.run_with(vars),
            None => Ok(()),
        };
        if let Err(e) = &result
            && e.kind.stops()
        {
            self.stop();
        }
        result
    }

    /// Stops the script: its subscriptions end, its pending timers and answers do nothing,
    /// its engine is dropped.
    pub fn stop(&self) {
        self.api.stop();
        if let Some(mut guard) = self.cell.instance.try_lock() {
            *guard = None;
        } else {
            // Running now (this is its own callback, or another thread's run): it is
            // dropped by the next stop or with the script.
        }
    }

    pub fn is_stopped(&self) -> bool {
        self.api.is_stopped()
    }

    /// Bytes the script's engine holds, where it counts them (`None` once stopped).
    pub fn memory(&self) -> Option<usize> {
        self.cell.instance.lock().as_ref().and_then(|i| i.memory())
    }

    pub fn api(&self) -> &Api {
        &self.api
    }
}
