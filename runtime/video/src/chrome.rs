//! What a video window draws around and over the picture: a border, a small title (the
//! camera and its vehicle), the frame rate and latency, the `STALE` badge and, without a
//! stream, "no video from <camera>" — never the raw world-model path. Text is at least
//! 12 px on a dark plate, readable over any picture.
//!
//! Also the window's `fit` (what the layout asked for) and its pointer method: a left press
//! raises the `press` event of the visible widgets under it.

use mocu_dataserver::{CallOutcome, DataServer};
use mocu_display::{
    Align, Baseline, Brush, Canvas, Color, ImageFit, Point, Rect, Stroke, TextStyle,
};
use mocu_value::{Guid, PropName, Value};

const TEXT: Color = Color::rgb(0xe8, 0xf0, 0xf8);
const DIM: Color = Color::rgb(0x8f, 0xa3, 0xb5);
const FRAME: Color = Color::rgb(0x3a, 0x4a, 0x5a);
const PLATE: Color = Color::rgba(0x05, 0x0a, 0x10, 0xb8);

/// The camera a window shows, named for the operator.
#[derive(Clone, Debug, PartialEq, Eq)]
pub(crate) struct Chrome {
    /// The camera's name (`drive`, `payload`, a network camera's name); empty without one.
    pub camera: String,
    /// The vehicle it is on, if it is a vehicle's camera.
    pub vehicle: Option<String>,
}

impl Chrome {
    /// From a window's `source` (`root.vehicles.usv1.cameras.drive`, `root.cameras.mast`).
    pub(crate) fn of(source: &str) -> Chrome {
        let segs = crate::path_segments(source);
        let vehicle = segs
            .iter()
            .position(|s| *s == "vehicles")
            .and_then(|i| segs.get(i + 1))
            .filter(|_| segs.len() > 2)
            .map(|s| s.to_string());
        let camera = segs.last().map(|s| s.to_string()).unwrap_or_default();
        Chrome { camera, vehicle }
    }

    /// "usv1 drive camera", "mast camera", or "camera" when the window names none.
    pub(crate) fn name(&self) -> String {
        match (&self.vehicle, self.camera.is_empty()) {
            (_, true) => "camera".to_string(),
            (Some(v), false) => format!("{v} {} camera", self.camera),
            (None, false) => format!("{} camera", self.camera),
        }
    }

    /// The title: "DRIVE · usv1".
    fn title(&self) -> String {
        let cam =
            if self.camera.is_empty() { "VIDEO".to_string() } else { self.camera.to_uppercase() };
        match &self.vehicle {
            Some(v) => format!("{cam} · {v}"),
            None => cam,
        }
    }

    /// The border and, in the bottom-left corner (clear of the HUD's usual top band and of
    /// the picture's own marks), the title and, for a live stream, its frame rate and latency
    /// (where the stream says when its frames arrived): "DRIVE · usv1  10 fps · 38 ms".
    pub(crate) fn draw(&self, c: &mut dyn Canvas, r: Rect, stats: Option<(f64, Option<f64>)>) {
        let size = text_size(r);
        let pad = (size * 0.4).round();
        let mut text = self.title();
        if let Some((fps, latency)) = stats {
            text += &match latency {
                Some(ms) => format!("   {fps:.0} fps · {ms:.0} ms"),
                None => format!("   {fps:.0} fps"),
            };
        }
        let style = TextStyle::new(size, TEXT).bold().baseline(Baseline::Middle);
        let bottom = r.y + r.h - pad - plate_height(size);
        plate(c, &text, Point::new(r.x + pad, bottom), &style, false);
        let b = 1.0f32.max((r.h / 360.0).round());
        c.stroke_rounded_rect(
            Rect::new(r.x + b / 2.0, r.y + b / 2.0, r.w - b, r.h - b),
            0.0,
            &Stroke::new(b),
            FRAME,
        );
    }

    /// "NO VIDEO" and, under it, "from usv1 drive camera", in the middle of the window.
    pub(crate) fn no_video(&self, c: &mut dyn Canvas, r: Rect) {
        let big = (r.h / 10.0).clamp(14.0, 36.0);
        let mid = Point::new(r.x + r.w / 2.0, r.y + r.h / 2.0);
        let style = TextStyle::new(big, DIM).align(Align::Center).baseline(Baseline::Middle);
        c.draw_text("NO VIDEO", mid, &style.bold());
        let small =
            TextStyle::new((big * 0.5).max(12.0), DIM).align(Align::Center).baseline(Baseline::Top);
        let line = format!("from {}", self.name());
        c.draw_text(&line, Point::new(mid.x, mid.y + big * 0.75), &small);
    }
}

/// The title's text size: 12 px in a thumbnail, up to 18 px in a large window.
fn text_size(r: Rect) -> f32 {
    (r.h / 30.0).clamp(12.0, 18.0).round()
}

fn plate_height(size: f32) -> f32 {
    (size * 1.5).round()
}

/// Text on a dark plate whose top-left (or top-right, `right`) corner is `at`.
fn plate(c: &mut dyn Canvas, text: &str, at: Point, style: &TextStyle, right: bool) {
    let m = c.measure_text(text, style);
    let pad = (style.size * 0.35).round();
    let (w, h) = (m.width + 2.0 * pad, plate_height(style.size));
    let x = if right { at.x - w } else { at.x };
    c.fill_rounded_rect(Rect::new(x, at.y, w, h), 3.0, &Brush::Solid(PLATE));
    c.draw_text(text, Point::new(x + pad, at.y + h / 2.0), style);
}

/// A label above the title: `STALE`.
pub(crate) fn badge(c: &mut dyn Canvas, r: Rect, text: &str, color: Color) {
    let size = text_size(r);
    let style = TextStyle::new(size, Color::rgb(0x10, 0x10, 0x10)).bold().baseline(Baseline::Top);
    let m = c.measure_text(text, &style);
    let pad = (size * 0.4).round();
    let (bw, bh) = (m.width + 2.0 * pad, size * 1.3 + pad);
    let top = r.y + r.h - 2.0 * pad - plate_height(size) - bh;
    let bg = Rect::new(r.x + pad, top, bw, bh);
    c.fill_rounded_rect(bg, 3.0, &Brush::Solid(color));
    c.draw_text(text, Point::new(bg.x + pad, bg.y + pad * 0.6), &style);
}

/// How window `g` shows its picture: its own `fit`, else its `Video` widget's, else filling
/// the window (cropped, centred). `"contain"` or `"letterbox"` keeps the whole picture.
pub(crate) fn fit_of(ds: &DataServer, g: Guid) -> ImageFit {
    let fit = |o: Guid| match ds.try_get(o, PropName::new("fit")) {
        Some(Value::Str(s)) => Some(s.to_string()),
        _ => None,
    };
    let asked = fit(g).or_else(|| {
        ds.children(g).unwrap_or_default().into_iter().find_map(|w| {
            let video = ds.try_get(w, PropName::new("component")) == Some(Value::str("Video"));
            if video { fit(w) } else { None }
        })
    });
    match asked.as_deref() {
        Some("contain" | "letterbox") => ImageFit::Contain,
        Some("stretch") => ImageFit::Stretch,
        _ => ImageFit::Cover,
    }
}

/// Publishes window `g`'s pointer method: a left press raises the `press` event of every
/// visible widget in the window under the pointer (widgets without a size cover the window).
pub(crate) fn publish_press(ds: &DataServer, g: Guid) {
    let d = ds.clone();
    let _ = ds.publish_method_fn(g, mocu_display::pointer_spec(), move |args| {
        let (kind, button) = (args[0].as_str().unwrap_or(""), args[1].as_i64().unwrap_or(-1));
        if (kind, button) != ("down", 0) {
            return CallOutcome::Accepted(vec![]);
        }
        let (x, y) = (args[2].as_f64().unwrap_or(0.0), args[3].as_f64().unwrap_or(0.0));
        for w in d.children(g).unwrap_or_default() {
            let n = |k: &str| d.try_get(w, PropName::new(k)).and_then(|v| v.as_f64());
            let visible = d.try_get(w, PropName::new("visible")) != Some(Value::Bool(false));
            let inside = match (n("x"), n("y"), n("w"), n("h")) {
                (Some(wx), Some(wy), Some(ww), Some(wh)) => {
                    x >= wx && y >= wy && x < wx + ww && y < wy + wh
                }
                _ => true,
            };
            let pressable =
                d.methods(w).is_ok_and(|m| m.iter().any(|m| m.name.as_str() == "press"));
            if visible && inside && pressable {
                d.call(w, "press", vec![], None, |_| {});
            }
        }
        CallOutcome::Accepted(vec![])
    });
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_vehicle_camera_is_named_by_its_vehicle_and_camera_not_its_path() {
        let c = Chrome::of("root.vehicles.usv1.cameras.drive");
        assert_eq!(c.name(), "usv1 drive camera");
        assert_eq!(c.title(), "DRIVE · usv1");
        assert_eq!(Chrome::of("root.cameras.mast").name(), "mast camera");
        assert_eq!(Chrome::of("").name(), "camera");
    }
}
