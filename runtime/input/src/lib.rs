//! Operator input (paper §5.2, fig. 3: most interaction is by a standard gamepad).
//!
//! - [`event`]: what sources report (devices, axes, buttons, keys, wheels, with times).
//! - [`source`]: the [`InputSource`] interface and the [`ScriptedSource`] (a virtual
//!   gamepad replaying a recorded sequence); [`GilrsSource`] for real gamepads.
//! - [`engine`]: bindings matched to events — press, release, hold, double press, a shift
//!   layer, modes — axes shaped (deadzone, expo, scale, invert) and rate-limited, every
//!   goal written at a bounded rate and only on change.
//! - [`InputModule`]: the module (`kind = "input"`): sources on threads, the engine on
//!   DataServer timers, `root.operator.inputs.<device>`, the window's keyboard and mouse
//!   as methods, the default selection, and the toast list ([`Toasts`]).
//!
//! Architecture invariant: like every module it talks only through the DataServer. It
//! finds the layout's bindings under `root.display.bindings` and fires them with their
//! `fire(value)` method; it knows nothing of the compiler, the layout runtime or the
//! window. Another module can replace it by publishing the same objects.

#![forbid(unsafe_code)]

pub mod engine;
pub mod event;
mod gilrs_source;
mod module;
pub mod shape;
pub mod source;
mod toasts;

pub use engine::{BindingDef, Engine, EngineConfig, EngineStats, scan_bindings};
pub use event::{DeviceType, EventKind, InputEvent};
pub use gilrs_source::{GilrsProbe, GilrsSource, axis_name, button_name};
pub use module::{InputConfig, InputModule, register};
pub use shape::Shaping;
pub use source::{InputSource, ScriptStep, ScriptedSource};
pub use toasts::Toasts;
