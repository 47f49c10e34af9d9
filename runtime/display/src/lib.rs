//! The layered display (paper §3.2, §5.1): a window-manager module that orders the windows
//! published under `root.display` and asks each window's module to paint its layer, a
//! backend-neutral [`Canvas`] every module paints through, and two compositors — tiny-skia
//! on the CPU and wgpu on the GPU — that blend the layers with their opacity.
//!
//! Architecture invariants:
//! - The window manager draws no content and knows no painter: it calls the `paint`
//!   method published under each window object (see [`paint`](crate::claim_window)).
//! - Painters see only [`Canvas`]; nothing they touch names tiny-skia or wgpu.
//! - Nothing is redrawn unless the world model says it changed: a quiet display does no
//!   work (see [`FrameStats::drawn`]).

#![forbid(unsafe_code)]

mod alloc;
mod anim;
mod behaviours;
mod canvas;
mod color;
mod compose;
pub mod demo;
mod display;
mod geom;
#[cfg(feature = "gpu")]
mod gpu;
mod image;
mod paint;
mod path;
pub mod pixel;
#[cfg(feature = "gpu")]
mod present;
mod skia;
mod text;
mod tiles;
pub mod touch;
#[cfg(feature = "gpu")]
mod window;
mod wm;

pub use anim::{Animator, Clock, Easing};
pub use behaviours::WindowBehaviours;
pub use canvas::{
    Align, Baseline, Brush, Canvas, ImageFit, LineCap, LineJoin, Stroke, TextMetrics, TextStyle,
    fit_rect, picture, picture_key,
};
pub use color::Color;
pub use compose::{CpuCompositor, LayerView};
pub use display::{
    BACKGROUND, BackendChoice, ChangeWaiter, Compositor, Counters, DEFAULT_RATE, Display,
    DisplayError, DisplayOptions, PointerEvent, ensure_display_object,
};
pub use geom::{IRect, Point, Rect, Size, Transform};
#[cfg(feature = "gpu")]
pub use gpu::GpuCompositor;
pub use image::Image;
pub use paint::{
    Coalesced, PaintArgs, claim_window, invalidate, invalidate_rect, paint_spec, pointer_spec,
    with_canvas,
};
pub use path::{Path, PathBuilder, PathEl};
#[cfg(feature = "gpu")]
pub use present::{WindowPath, choose_path};
pub use skia::SkiaCanvas;
pub use text::{FAMILY, measure as measure_text};
pub use tiles::Tiles;
#[cfg(feature = "gpu")]
pub use window::{WindowOptions, WindowStop, run_window};
pub use wm::{FrameStats, Hit, PAINT_ERROR, WINDOW_TYPE, WinProps, WindowManager};

/// Publishes a window object under `root.display` (what a compiled layout does): name,
/// subtype (who draws it), layer, declaration order and rectangle. For tests, demos and
/// modules that make their own windows.
pub fn publish_window(
    ds: &mocu_dataserver::DataServer,
    display: mocu_dataserver::Guid,
    name: &str,
    subtype: &str,
    layer: i64,
    rect: Rect,
) -> Result<mocu_dataserver::Guid, mocu_dataserver::DsError> {
    use mocu_dataserver::{ObjectInfo, Value};
    let order = ds.children(display)?.len() as i64;
    let g = ds.create_object(display, ObjectInfo::new(name, WINDOW_TYPE).subtype(subtype))?;
    for (p, v) in [
        ("layer", Value::Int(layer)),
        ("order", Value::Int(order)),
        ("x", Value::Float(rect.x as f64)),
        ("y", Value::Float(rect.y as f64)),
        ("w", Value::Float(rect.w as f64)),
        ("h", Value::Float(rect.h as f64)),
        ("opacity", Value::Float(1.0)),
        ("visible", Value::Bool(true)),
        ("clip", Value::Bool(true)),
        ("revision", Value::Int(0)),
    ] {
        ds.set(g, p, v)?;
    }
    Ok(g)
}
