//! Scripts by prefix (MOCU 3 paper §4.4): `#js:` and `#rhai:` actions and handlers in a
//! layout, and whole script modules listed in a profile (`kind = "script"`).
//!
//! A [`Registry`] maps a prefix to an [`Engine`]; an engine checks a script's syntax
//! ([`Engine::check`], what `mocu check` reports) and loads it against an [`Api`], the
//! DataServer as a script sees it. A loaded [`Script`] runs on its serial executor, never on
//! the frame thread. Every engine is sandboxed ([`Limits`]): no file or network access
//! unless granted, an operation budget per run (a runaway script is stopped and reported),
//! a memory limit. Every error names the file:line:col of the script in its file.
//!
//! Architecture invariant: scripts reach the OCU only through the DataServer's public API,
//! as native modules do; this crate knows nothing of the compiler, layouts or rendering.

#![forbid(unsafe_code)]

mod api;
mod engine;
mod error;
mod js;
mod module;
mod rhai;
mod script;
mod watch;

pub use api::{Api, CallbackId, Reporter};
pub use engine::{Engine, Instance, Limits, Registry};
pub use error::{ApiError, ErrorKind, Location, ScriptError, Source};
pub use js::Js;
pub use module::{ScriptModule, register};
pub use rhai::Rhai;
pub use script::Script;
