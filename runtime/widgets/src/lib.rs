//! Modules that draw layouts: the widget renderer (components drawn from primitives,
//! compiled once with the JIT) and the map.
//!
//! Architecture invariant: these modules read the display from the world model
//! (`root.display`) and draw through `mocu_display::Canvas`; they never talk to a layout.

#![forbid(unsafe_code)]

pub mod alerts;
pub mod component;
pub mod draw;
pub mod map;
pub mod menu;
pub mod renderer;

pub use component::Library;
pub use map::MapModule;
pub use renderer::{RendererConfig, WidgetRenderer};
