//! Script modules: `[modules.NAME] kind = "script"`, `file = "x.js"` in a profile. The
//! engine is chosen by the file's extension (`.js`, `.rhai`). The script's top level runs
//! once on the module's serial executor; what it subscribes to and schedules runs there too.
//!
//! `root.modules.NAME` shows `file`, `engine`, `generation` (loads so far) and `error` (the
//! last error, file:line:col, empty when none). Its method `reload()` reads the file again:
//! a script that does not compile is refused and the running one kept (as a broken layout
//! is); one that does replaces it. The same happens when the file is saved (`watch.rs`).

use crate::api::Reporter;
use crate::engine::{Limits, Registry};
use crate::error::{ScriptError, Source};
use crate::script::Script;
use mocu_dataserver::{CallOutcome, MethodSpec, Value};
use mocu_host::{Level, Module, ModuleContext, ModuleSpec};
use parking_lot::Mutex;
use std::sync::Arc;

/// Registers the `script` module kind with the standard engines.
pub fn register(r: &mut mocu_host::Registry) {
    r.register("script", |spec| Ok(Box::new(ScriptModule::from_spec(spec)?) as Box<dyn Module>));
}

/// A script module's settings and, once started, its running script.
pub struct ScriptModule {
    file: String,
    limits: Limits,
    engines: Registry,
    state: Arc<Mutex<Option<Running>>>,
    watcher: Option<notify::RecommendedWatcher>,
}

struct Running {
    script: Script,
    generation: i64,
}

impl ScriptModule {
    /// From the profile's settings: `file` (required), `operations`, `memory_kb`, `files`.
    pub fn from_spec(spec: &ModuleSpec) -> Result<ScriptModule, String> {
        let file = spec.str_or("file", "").map_err(|e| e.to_string())?;
        if file.is_empty() {
            return Err("a script module needs `file` (a .js or .rhai file)".into());
        }
        let d = Limits::default();
        let operations =
            spec.i64_or("operations", d.operations as i64).map_err(|e| e.to_string())?;
        let memory_kb =
            spec.i64_or("memory_kb", (d.memory / 1024) as i64).map_err(|e| e.to_string())?;
        if operations < 1 || !(64..=1 << 22).contains(&memory_kb) {
            return Err("`operations` must be at least 1 and `memory_kb` 64 to 4194304".into());
        }
        let limits = Limits {
            operations: operations as u64,
            memory: memory_kb as usize * 1024,
            call_depth: d.call_depth,
            files: spec.bool_or("files", false).map_err(|e| e.to_string())?,
        };
        Ok(ScriptModule {
            file,
            limits,
            engines: Registry::standard(),
            state: Arc::default(),
            watcher: None,
        })
    }

    /// Bytes its engine holds now, where the engine counts them.
    pub fn memory(&self) -> Option<usize> {
        self.state.lock().as_ref().and_then(|r| r.script.memory())
    }
}

impl Module for ScriptModule {
    fn start(&mut self, ctx: &ModuleContext) -> Result<(), String> {
        let _ = ctx.ds.set(ctx.status, "file", Value::str(&self.file));
        load(ctx, &self.file, &self.limits, &self.engines, &self.state)
            .map_err(|e| e.to_string())?;
        let (c, file, limits, engines, state) = (
            ctx.clone(),
            self.file.clone(),
            self.limits.clone(),
            self.engines.clone(),
            self.state.clone(),
        );
        let reload = Arc::new(move || load(&c, &file, &limits, &engines, &state));
        let (r, c) = (reload.clone(), ctx.clone());
        let on_save = move || {
            // Refused: the error is reported and shown, the running script kept.
            if let Err(e) = r() {
                c.report(Level::Error, e.to_string());
            }
        };
        self.watcher = Some(crate::watch::follow(ctx, &self.file, on_save)?);
        let spec = MethodSpec::new("reload").describe("Reads the script file again and runs it");
        ctx.ds
            .publish_method_fn(ctx.status, spec, move |_| match reload() {
                Ok(()) => CallOutcome::Accepted(Vec::new()),
                Err(e) => CallOutcome::Refused(e.to_string()),
            })
            .map_err(|e| e.to_string())
    }

    fn stop(&mut self) {
        self.watcher = None;
        if let Some(r) = self.state.lock().take() {
            r.script.stop();
        }
    }
}

/// Why a script module's file could not be loaded.
#[derive(Debug)]
enum LoadError {
    Read { file: String, reason: String },
    NoEngine { file: String, known: Vec<&'static str> },
    Script(ScriptError),
}

impl std::fmt::Display for LoadError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            LoadError::Read { file, reason } => write!(f, "{file}: cannot read: {reason}"),
            LoadError::NoEngine { file, known } => {
                write!(
                    f,
                    "{file}: no script engine for this extension (known: .{})",
                    known.join(", .")
                )
            }
            LoadError::Script(e) => write!(f, "{e}"),
        }
    }
}

/// Reads, compiles and starts the file; replaces the running script only when the new one
/// compiled. Its errors, now and later, go to the host's report (the terminal), the trial
/// record (`script_error`, the `--log` file) and `root.modules.NAME.error`.
fn load(
    ctx: &ModuleContext,
    file: &str,
    limits: &Limits,
    engines: &Registry,
    state: &Mutex<Option<Running>>,
) -> Result<(), LoadError> {
    let text = std::fs::read_to_string(file)
        .map_err(|e| LoadError::Read { file: file.to_string(), reason: e.to_string() })?;
    let engine = engines
        .for_file(file)
        .ok_or_else(|| LoadError::NoEngine { file: file.to_string(), known: engines.prefixes() })?;
    let c = ctx.clone();
    let report: Reporter = Arc::new(move |e: &ScriptError| {
        c.report(Level::Error, e.to_string());
        c.record(
            "script_error",
            vec![
                ("file", Value::str(&e.at.file)),
                ("line", Value::Int(e.at.line.into())),
                ("col", Value::Int(e.at.col.into())),
                ("kind", Value::str(e.kind.describe())),
                ("message", Value::str(&e.message)),
            ],
        );
        let _ = c.ds.set(c.status, "error", Value::str(&e.to_string()));
    });
    let source = Source::file(file, &text);
    let script =
        Script::load(&*engine, &source, ctx.ds.clone(), ctx.executor.clone(), limits, report)
            .map_err(|e| {
                let _ = ctx.ds.set(ctx.status, "error", Value::str(&e.to_string()));
                LoadError::Script(e)
            })?;
    let mut st = state.lock();
    let generation = st.as_ref().map_or(0, |r| r.generation) + 1;
    if let Some(old) = st.take() {
        old.script.stop();
    }
    let _ = ctx.ds.set(ctx.status, "engine", Value::str(engine.prefix()));
    let _ = ctx.ds.set(ctx.status, "generation", Value::Int(generation));
    let _ = ctx.ds.set(ctx.status, "error", Value::str(""));
    script.run();
    *st = Some(Running { script, generation });
    Ok(())
}
