//! Hot reload during trials: a human-factors engineer saves a layout and the display changes
//! in front of the operator, with nothing lost.
//!
//! - [`Reloader`] owns the running layout. `reload_now` re-checks the target and swaps the
//!   program in incrementally (`mocu_layout::Layout::reload`): unchanged windows, widgets and
//!   watches keep their objects, subscriptions and state. A target with errors never replaces
//!   the running layout: its diagnostics go to the terminal, the event log, and a banner on
//!   the operator's display (`root.operator.diagnostics`), which goes when the file is fixed.
//! - [`watch`](Reloader::watch) follows every file the target depends on with `notify`,
//!   watching their folders so editors that save by rename (vim, VS Code) or delete and
//!   recreate are seen, and coalesces an editor's burst of events into one reload, per file
//!   the layout depends on (other files' events never delay it: `debounce.rs`). Checking
//!   and compiling run off the frame thread; a check is bounded in time and source size
//!   (`ReloadLimits`) and refused like a broken layout past them.
//! - `root.operator.reload()` asks for a reload through the DataServer (a remote tool).
//!
//! Architecture invariant: the world model's vehicles, goals and routes are never touched
//! by a reload; only objects the layout published under `root.display` and `root.operator`.

#![forbid(unsafe_code)]

mod banner;
mod debounce;
mod limits;
mod reloader;
mod watcher;

pub use limits::ReloadLimits;
pub use reloader::{Outcome, Reloader, ReloaderOptions, choose};
