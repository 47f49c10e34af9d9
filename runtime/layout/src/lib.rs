//! Live layouts: a checked [`Program`](mocu_language::Program) bound to the DataServer.
//!
//! - [`lower`] (the `mocu-lower` crate, shared with the widget renderer): typed expressions
//!   → the JIT's IR; each dotted path becomes an input slot.
//! - [`graph`]: functions compiled together (Cranelift), cells binding them to shared path
//!   subscriptions, evaluated once per tick with early cutoff; outputs under `root.display`.
//! - `stale`: each widget's `stale` output, from the link state of the vehicles it reads.
//! - `watch`: watches on delayed calls (hold, hysteresis, repeat, snooze).
//! - `actions`: set / call / swap / show / hide / alert, with control feedback.
//! - `scripts`: script actions (`#js: { … }`, `#rhai: { … }`) on the layout's script executor.
//! - `alerts`: alerts and failed commands always reach the operator (world model, log,
//!   terminal, and a built-in alert window unless the layout places an `AlertLayer`).
//! - `clock`: `root.operator.clock` (`utc`, `time`) on the DataServer's clock, while the
//!   layout reads it.
//! - [`events`]: the trial's event log.
//!
//! Architecture invariant: a layout talks to the rest of the OCU only through the
//! DataServer: it publishes windows and widgets under `root.display`, widget events and
//! bindings as methods, watches, feedback and alerts under `root.operator`.

#![forbid(unsafe_code)]

mod actions;
mod alerts;
mod clock;
pub mod events;
pub mod graph;
mod legend;
pub use mocu_lower as lower;
use mocu_lower::convert;
mod menu;
mod reload;
mod scripts;
mod stale;
mod watch;

pub use events::{EventSink, JsonlLog, MemorySink, NullSink};
pub use graph::{Layout, LayoutConfig, LayoutStats, LoadError};
pub use reload::ReloadStats;
pub use scripts::install_script_checker;
