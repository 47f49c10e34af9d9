//! The module host (paper §2, §3.2): every piece of the OCU that is not the DataServer is a
//! module — protocol modules, the simulator, input, the widget renderer, the map view and
//! the video windows — and they are all started the same way, from a list of [`ModuleSpec`]s that a
//! profile names in order.
//!
//! A module gets a [`ModuleContext`]: its DataServer handle, its own serial executor, its
//! settings and a status object `root.modules.<name>`. A module that fails to start is
//! reported and the others keep running; a module that panics (in `start`, `stop`, or a
//! thread started with [`ModuleContext::spawn_thread`]) is isolated and reported, never
//! fatal to the OCU. Panics in a module's DataServer callbacks are already caught by the
//! DataServer's executors.
//!
//! Architecture invariant: modules talk to each other only through the DataServer. This
//! crate hands out no module-to-module channel; the DataServer depends on none of this.

#![forbid(unsafe_code)]

mod context;
mod host;
mod process;
mod roles;
mod spec;
pub mod world;

pub use context::{HostEvent, Level, ModuleContext};
pub use host::{Events, Factory, Module, ModuleHost, Registry, StartError};
pub use process::{ProcessModule, register as register_process};
pub use roles::fill_roles;
pub use spec::{ModuleSpec, SpecError};
