//! Script actions: `on press #js: { … }`, `-> #rhai: { … }` wherever an action goes (widget
//! events, bindings, menu items, watch `then`), docs/scripting.md.
//!
//! Each action's body is loaded once, when it first runs, as a [`Script`] of the engine its
//! prefix names, on the layout's script executor (one serial executor for all the layout's
//! scripts: off the frame thread, never two at once). Each event runs the body again with
//! `self` (the object of a menu, of a `for each` instance: its path), `selected` (the
//! selected object's path) and `input` (a binding's shaped value) set; absent ones are
//! `undefined` / `()`. A script's error (a runtime error, a runaway past its budget: then it
//! is stopped) names its file:line:col in the layout and is raised as a warning alert — on
//! screen, on the terminal, in the log. When the layout is reloaded or unloaded, the old
//! actions' scripts are stopped (their subscriptions and timers end).

use crate::actions::ActionCtx;
use crate::graph::Shared;
use mocu_dataserver::Value;
use mocu_script::{Limits, Registry, Script, ScriptError, Source};
use std::sync::{Arc, OnceLock, Weak};

/// One script action: its source, and its script once loaded.
pub(crate) struct ScriptAction {
    engine: String,
    source: Source,
    loaded: OnceLock<Option<Script>>,
}

impl std::fmt::Debug for ScriptAction {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "#{}: at {}", self.engine, self.source.origin)
    }
}

impl Drop for ScriptAction {
    fn drop(&mut self) {
        if let Some(Some(s)) = self.loaded.get() {
            s.stop();
        }
    }
}

impl ScriptAction {
    pub(crate) fn new(
        engine: &str,
        body: &str,
        origin: Option<&mocu_language::program::ScriptOrigin>,
    ) -> Arc<ScriptAction> {
        let source = match origin {
            Some(o) => Source::embedded(&o.file, o.line, o.col, body),
            None => Source::embedded("(layout)", 1, 1, body),
        };
        Arc::new(ScriptAction { engine: engine.to_string(), source, loaded: OnceLock::new() })
    }

    /// For the bindings' legend: `js script`.
    pub(crate) fn describe(&self) -> String {
        format!("{} script", self.engine)
    }

    /// Runs the body for one event on the layout's script executor, compiling it there the
    /// first time: whatever thread fired the event pays neither.
    pub(crate) fn run(self: &Arc<Self>, sh: &Arc<Shared>, cx: ActionCtx) {
        let path = |g: Option<mocu_value::Guid>| g.map(|g| Value::str(&sh.ds.path_text(g)));
        let vars = vec![
            ("self", path(cx.self_obj.or(cx.instance_object))),
            ("selected", path(crate::actions::selected_object(&sh.ds))),
            ("input", cx.input.map(Value::Float)),
        ];
        sh.sink.record(
            "action",
            &[("kind", Value::str("script")), ("at", Value::str(&self.source.origin.to_string()))],
        );
        let (me, weak) = (self.clone(), Arc::downgrade(sh));
        sh.scripts.spawn(move || {
            let Some(sh) = weak.upgrade() else { return };
            let Some(script) = me.loaded.get_or_init(|| me.load(&sh)) else { return };
            if let Err(e) = script.run_here_with(&vars) {
                // A runaway is stopped already; the error goes where the script's go.
                script.api().report(&e);
            }
        });
    }

    fn load(&self, sh: &Arc<Shared>) -> Option<Script> {
        let registry = Registry::standard();
        let Some(engine) = registry.get(&self.engine) else {
            let known = registry.prefixes().join(", ");
            let text = format!(
                "{}: no script engine `#{}:` (engines: {known})",
                self.source.origin, self.engine
            );
            crate::alerts::raise(sh, "warning", &text, "script");
            return None;
        };
        let weak: Weak<Shared> = Arc::downgrade(sh);
        let report = Arc::new(move |e: &ScriptError| {
            if let Some(sh) = weak.upgrade() {
                crate::alerts::raise(&sh, "warning", &e.to_string(), "script");
            }
        });
        let exec = sh.scripts.clone();
        match Script::load(&*engine, &self.source, sh.ds.clone(), exec, &Limits::default(), report)
        {
            Ok(s) => Some(s),
            Err(e) => {
                crate::alerts::raise(sh, "warning", &e.to_string(), "script");
                None
            }
        }
    }
}

/// Installs the engines' syntax check for the script actions of every layout this process
/// checks (`mocu check`, `run`, `build`, `lsp`, hot reload): the compiler knows no engine
/// (`mocu_language::passes::check_scripts`), the layout runtime knows both.
pub fn install_script_checker() {
    mocu_language::passes::check_scripts::install_script_checker(Box::new(Engines(
        Registry::standard(),
    )));
}

struct Engines(Registry);

impl mocu_language::passes::check_scripts::ScriptChecker for Engines {
    fn engines(&self) -> Vec<String> {
        self.0.prefixes().into_iter().map(str::to_string).collect()
    }

    fn check(&self, engine: &str, body: &str) -> Result<(), (u32, u32, String)> {
        let Some(e) = self.0.get(engine) else { return Ok(()) };
        e.check(&Source::embedded("", 1, 1, body))
            .map_err(|err| (err.at.line, err.at.col, err.message))
    }
}
