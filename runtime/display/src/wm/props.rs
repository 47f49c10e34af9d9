//! A window's properties as the window manager reads them, and what a change of each does.

use super::*;
use mocu_value::limits::MAX_WINDOW_PX;

/// A window's properties as the window manager reads them.
#[derive(Clone, Debug, PartialEq)]
pub struct WinProps {
    pub name: Arc<str>,
    pub subtype: Arc<str>,
    pub layer: i64,
    pub order: i64,
    pub x: f64,
    pub y: f64,
    /// `None` until published: the display's width.
    pub w: Option<f64>,
    /// `None` until published: the display's height.
    pub h: Option<f64>,
    pub opacity: f64,
    pub visible: bool,
    pub clip: bool,
}

impl WinProps {
    pub(super) fn new(name: Arc<str>, subtype: Arc<str>) -> WinProps {
        WinProps {
            name,
            subtype,
            layer: 0,
            order: 0,
            x: 0.0,
            y: 0.0,
            w: None,
            h: None,
            opacity: 1.0,
            visible: true,
            clip: true,
        }
    }

    /// The window's pixel rectangle on the screen, each number within
    /// ±[`MAX_WINDOW_PX`] (what a checked layout reaches at any scale; sums stay in `i32`).
    pub fn rect(&self, display: (u32, u32)) -> IRect {
        let w = self.w.unwrap_or(display.0 as f64);
        let h = self.h.unwrap_or(display.1 as f64);
        let px = |v: f64, lo: f64| v.round().clamp(lo, MAX_WINDOW_PX as f64) as i32;
        let m = -(MAX_WINDOW_PX as f64);
        IRect::new(px(self.x, m), px(self.y, m), px(w, 0.0), px(h, 0.0))
    }
}

/// What a property change means for a window.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Effect {
    None,
    Recomposite,
    Repaint,
}

/// Applies one property value; returns what it changes.
pub(super) fn apply_prop(p: &mut WinProps, name: &str, v: Option<&Value>) -> Effect {
    let f = |v: Option<&Value>, d: f64| v.and_then(Value::as_f64).unwrap_or(d);
    let before = p.clone();
    let effect = match name {
        "x" => {
            p.x = f(v, 0.0);
            Effect::Recomposite
        }
        "y" => {
            p.y = f(v, 0.0);
            Effect::Recomposite
        }
        "w" => {
            p.w = v.and_then(Value::as_f64);
            Effect::Repaint
        }
        "h" => {
            p.h = v.and_then(Value::as_f64);
            Effect::Repaint
        }
        "layer" => {
            p.layer = v.and_then(Value::as_f64).unwrap_or(0.0) as i64;
            Effect::Recomposite
        }
        "order" => {
            p.order = v.and_then(Value::as_f64).unwrap_or(0.0) as i64;
            Effect::Recomposite
        }
        "opacity" => {
            p.opacity = f(v, 1.0).clamp(0.0, 1.0);
            Effect::Recomposite
        }
        "visible" => {
            p.visible = v.and_then(Value::as_bool).unwrap_or(true);
            Effect::Recomposite
        }
        "clip" => {
            p.clip = v.and_then(Value::as_bool).unwrap_or(true);
            Effect::Repaint
        }
        PAINT_ERROR | "frame" => return Effect::None,
        // `revision`, `source` and any property of the painter's own: new content.
        _ => return Effect::Repaint,
    };
    if *p == before { Effect::None } else { effect }
}
