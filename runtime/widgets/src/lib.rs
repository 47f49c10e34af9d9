//! Modules that draw layouts: the widget renderer (components drawn from primitives,
//! compiled once with the JIT) and the map; the module kinds `widgets` and `map_view`
//! (`register`).
//!
//! Architecture invariant: these modules read the display from the world model
//! (`root.display`) and draw through `mocu_display::Canvas`; they never talk to a layout.

#![forbid(unsafe_code)]

pub mod alerts;
pub mod component;
pub mod draw;
pub mod map;
pub mod menu;
mod module;
pub mod renderer;

pub use component::Library;
pub use map::MapModule;
pub use module::{Components, register};
pub use renderer::{RendererConfig, WidgetRenderer};
