//! The engine interface and the registry of engines by prefix (`#js:`, `#rhai:`).

use crate::api::{Api, CallbackId};
use crate::error::{ScriptError, Source};
use mocu_dataserver::Value;
use std::sync::Arc;

/// What a script may use. Every engine enforces the operation budget (a runaway script is
/// stopped) and has no file or network access unless `files` grants it.
#[derive(Clone, Debug, PartialEq)]
pub struct Limits {
    /// Operations one run or callback may take before it is stopped.
    pub operations: u64,
    /// Bytes of memory the script may hold (QuickJS's allocator limit; Rhai bounds strings,
    /// arrays and maps by it instead).
    pub memory: usize,
    /// Nesting of calls.
    pub call_depth: usize,
    /// Whether `import` may load other scripts from the script's own folder.
    pub files: bool,
}

impl Default for Limits {
    fn default() -> Limits {
        Limits { operations: 1_000_000, memory: 16 << 20, call_depth: 64, files: false }
    }
}

/// A scripting language.
pub trait Engine: Send + Sync {
    /// The prefix that selects it in a layout (`js` for `#js:`).
    fn prefix(&self) -> &'static str;
    /// The file extension of its script modules (`js`).
    fn extension(&self) -> &'static str;
    /// Parses without running: the syntax error at its file:line:col, if any.
    fn check(&self, source: &Source) -> Result<(), ScriptError>;
    /// Compiles a script against its API. Nothing runs until [`Instance::run`].
    fn load(
        &self,
        source: &Source,
        api: Api,
        limits: &Limits,
    ) -> Result<Box<dyn Instance>, ScriptError>;
}

/// A loaded script: its compiled text, its globals and the callbacks it handed out.
pub trait Instance: Send {
    /// Runs the script's text (a module's top level once; an action's body on each event).
    fn run(&mut self) -> Result<(), ScriptError>;
    /// Runs the script's text with these variables set (a layout action's `self`, `selected`,
    /// `input`; `None` is absent: `undefined` / `()`).
    fn run_with(&mut self, vars: &[(&str, Option<Value>)]) -> Result<(), ScriptError>;
    /// Calls a callback the script handed to the API; `None` arguments are absent values.
    /// A `once` callback is forgotten after it ran.
    fn invoke(
        &mut self,
        callback: CallbackId,
        args: &[Option<Value>],
        once: bool,
    ) -> Result<(), ScriptError>;
    /// Bytes the script holds now, where its engine counts them (QuickJS does, Rhai does not).
    fn memory(&self) -> Option<usize>;
}

/// Engines by prefix.
#[derive(Clone, Default)]
pub struct Registry {
    engines: Vec<Arc<dyn Engine>>,
}

impl Registry {
    pub fn new() -> Registry {
        Registry::default()
    }

    /// The engines Mocu ships: `js` (QuickJS) and `rhai`.
    pub fn standard() -> Registry {
        let mut r = Registry::new();
        r.register(Arc::new(crate::js::Js));
        r.register(Arc::new(crate::rhai::Rhai));
        r
    }

    /// Adds an engine; one with the same prefix is replaced.
    pub fn register(&mut self, engine: Arc<dyn Engine>) {
        self.engines.retain(|e| e.prefix() != engine.prefix());
        self.engines.push(engine);
    }

    /// The engine of a prefix (`js`, without `#` and `:`).
    pub fn get(&self, prefix: &str) -> Option<Arc<dyn Engine>> {
        self.engines.iter().find(|e| e.prefix() == prefix).cloned()
    }

    /// The engine of a script file, by its extension.
    pub fn for_file(&self, path: &str) -> Option<Arc<dyn Engine>> {
        let ext = std::path::Path::new(path).extension()?.to_str()?;
        self.engines.iter().find(|e| e.extension() == ext).cloned()
    }

    /// The prefixes known, for messages.
    pub fn prefixes(&self) -> Vec<&'static str> {
        self.engines.iter().map(|e| e.prefix()).collect()
    }
}
