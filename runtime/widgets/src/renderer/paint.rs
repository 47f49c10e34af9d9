//! Painting a widget window: each widget's component (compiled shapes or native drawing),
//! then the overlays every widget gets (feedback, staleness, hover and press).

use super::native::draw_native;
use super::{MARGIN, Shared, inflate, union};
use crate::draw::draw_shapes;
use mocu_display::{
    Align, Baseline, Brush, Canvas, Color, PaintArgs, Path, Point, Rect, Stroke, TextStyle,
};
use mocu_value::{Guid, PropName, Value};
use std::collections::HashMap;
use std::time::Duration;

impl Shared {
    pub(super) fn paint(&self, window: Guid, c: &mut dyn Canvas, _a: &PaintArgs) {
        let Ok(mut widgets) = self.ds.children(window) else { return };
        widgets.sort_by_key(|w| {
            self.ds.try_get(*w, PropName::new("order")).and_then(|v| v.as_i64()).unwrap_or(0)
        });
        let damage = c.damage();
        for w in widgets {
            let props: HashMap<String, Value> = match self.ds.properties(w) {
                Ok(p) => p.into_iter().map(|(n, v)| (n.as_str().to_string(), v)).collect(),
                Err(_) => continue,
            };
            if props.get("visible").and_then(Value::as_bool) == Some(false) {
                continue;
            }
            let num = |k: &str| props.get(k).and_then(Value::as_f64).map(|x| x as f32);
            let (Some(x), Some(y)) = (num("x"), num("y")) else { continue };
            let bounds = match (num("w"), num("h")) {
                (Some(ww), Some(hh)) => Some(Rect::new(x, y, ww, hh)),
                _ => None,
            };
            if let Some(b) = bounds
                && !inflate(b).intersects(&damage)
            {
                continue;
            }
            let component = props.get("component").and_then(Value::as_str).unwrap_or("");
            c.save();
            c.translate(x, y);
            let lib = self.lib.lock().clone();
            let mut drawn = bounds.map(|b| Rect::new(0.0, 0.0, b.w, b.h));
            if let Some(comp) = lib.components.get(component) {
                // A layout with `design` draws its components at the design's scale: they
                // see their size in design px (docs/language.md, "Screen sizes").
                let scale = num("scale").filter(|s| *s > 0.0 && *s != 1.0);
                let prop = |name: &str| match (name, scale) {
                    ("w" | "h", Some(s)) => {
                        props.get(name).and_then(Value::as_f64).map(|v| Value::Float(v / s as f64))
                    }
                    _ => props.get(name).cloned(),
                };
                let outs = lib.evaluate(comp, &prop);
                let s = scale.unwrap_or(1.0);
                c.save();
                c.scale(s, s);
                draw_shapes(c, &comp.shapes, &outs);
                c.restore();
                if let (Some(d), Some(e)) = (drawn, crate::draw::extent(&comp.shapes, &outs)) {
                    drawn = Some(union(d, Rect::new(e.x * s, e.y * s, e.w * s, e.h * s)));
                }
            } else if let (Some(s), Some(b), "VehicleList") = (num("scale"), bounds, component) {
                // The vehicle list grows with a design's scale too (its rows: `pointer.rs`).
                c.save();
                c.scale(s, s);
                let b = Rect::new(b.x / s, b.y / s, b.w / s, b.h / s);
                draw_native(c, &self.ds, component, &props, Some(b));
                c.restore();
            } else {
                draw_native(c, &self.ds, component, &props, bounds);
            }
            let data = self.data_props(component);
            self.overlays(c, w, &props, &data, bounds, drawn);
            c.restore();
        }
    }

    /// Feedback, staleness, hover and press, drawn in widget-local coordinates.
    fn overlays(
        &self,
        c: &mut dyn Canvas,
        w: Guid,
        props: &HashMap<String, Value>,
        data: &[String],
        bounds: Option<Rect>,
        drawn: Option<Rect>,
    ) {
        let Some(b) = bounds else { return };
        // Round widgets (dials, compasses, horizons) get round overlays.
        let radius = if (b.w - b.h).abs() < 1.0 && b.w >= 48.0 { b.w / 2.0 } else { 4.0 };
        let r = Rect::new(-2.0, -2.0, b.w + 4.0, b.h + 4.0);
        let (hover, pressed, feedback_at) = {
            let st = self.state.lock();
            match st.widgets.get(&w) {
                Some(ws) => (ws.hover, ws.pressed, ws.feedback_at),
                None => (false, false, None),
            }
        };
        if pressed {
            c.fill_rounded_rect(
                Rect::new(0.0, 0.0, b.w, b.h),
                4.0,
                &Brush::Solid(Color::rgba(0, 0, 0, 90)),
            );
        } else if hover {
            c.fill_rounded_rect(
                Rect::new(0.0, 0.0, b.w, b.h),
                4.0,
                &Brush::Solid(Color::rgba(255, 255, 255, 28)),
            );
        }
        // A component with a `stale` parameter draws its own veil and state field (the
        // status header, stdlib/status.mocu): a tag here would sit on its text.
        let own_stale = props.get("component").and_then(Value::as_str).is_some_and(|c| {
            self.lib
                .lock()
                .components
                .get(c)
                .is_some_and(|c| c.slots.iter().any(|(n, _)| n == "stale"))
        });
        if !own_stale
            && data.iter().any(|d| props.contains_key(d))
            && (props.get("stale").and_then(Value::as_bool) == Some(true)
                || props.get("aged").and_then(Value::as_bool) == Some(true))
        {
            // The tag grows with a design's scale, like the widget it marks.
            let s = props.get("scale").and_then(Value::as_f64).map_or(1.0, |s| s.max(1.0));
            let area = drawn.unwrap_or(Rect::new(0.0, 0.0, b.w, b.h));
            stale_veil(c, b, area, radius, s as f32);
        }
        let state = props.get("feedback").and_then(Value::as_str).unwrap_or("");
        let age = feedback_at.map_or(Duration::MAX, |t| self.ds.now().saturating_duration_since(t));
        let (col, show_reason) = match state {
            "pending" => (Some(Color::rgb(0xf5, 0x9e, 0x0b)), false),
            "accepted" if age < self.config.accepted_for => {
                (Some(Color::rgb(0x22, 0xc5, 0x5e)), false)
            }
            "refused" | "failed" | "timed_out" | "no_such_method" | "no_such_object"
                if age < self.config.refused_for =>
            {
                (Some(Color::rgb(0xef, 0x44, 0x44)), true)
            }
            _ => (None, false),
        };
        if let Some(col) = col {
            let mut stroke = Stroke::new(2.0);
            if state == "pending" {
                stroke = stroke.dash(&[5.0, 3.0], 0.0);
            }
            let rr = if radius > 4.0 { radius + 2.0 } else { 5.0 };
            c.stroke_path(&Path::rounded_rect(r, rr), &stroke, &Brush::Solid(col));
            if show_reason {
                let reason = props.get("feedback_reason").and_then(Value::as_str).unwrap_or(state);
                let mut label = format!("{}: {reason}", state.replace('_', " ").to_uppercase());
                // Cut to the room there is (the widget and its margins), with an ellipsis.
                let room = b.w + MARGIN;
                let width = |t: &str| mocu_display::measure_text(t, 12.0, false).width;
                if width(&label) > room {
                    let mut chars: Vec<char> = label.chars().collect();
                    while chars.len() > 4
                        && width(&format!("{}…", chars.iter().collect::<String>())) > room
                    {
                        chars.pop();
                    }
                    label = format!("{}…", chars.iter().collect::<String>().trim_end());
                }
                let style = TextStyle::new(12.0, col).baseline(Baseline::Top);
                c.draw_text(&label, Point::new(0.0, b.h + 5.0), &style);
            }
        }
    }
}

/// The stale veil over everything a widget drew (`drawn`, widget-local; a round widget
/// that drew nothing outside its box gets a round veil) and the STALE tag in its middle,
/// inside the veil: it never covers a neighbour.
fn stale_veil(c: &mut dyn Canvas, b: Rect, drawn: Rect, radius: f32, s: f32) {
    let veil = Color::rgba(8, 10, 14, 170);
    let inside = drawn.x >= -0.5
        && drawn.y >= -0.5
        && drawn.x + drawn.w <= b.w + 0.5
        && drawn.y + drawn.h <= b.h + 0.5;
    let area = if inside { Rect::new(0.0, 0.0, b.w, b.h) } else { drawn };
    let r = if inside { radius } else { 4.0 };
    c.fill_rounded_rect(
        Rect::new(area.x - 1.0, area.y - 1.0, area.w + 2.0, area.h + 2.0),
        r,
        &Brush::Solid(veil),
    );
    // Where it hides the least: a short, wide widget's label (left), else high in the middle
    // (the value read-outs sit low or right).
    let size = if area.h >= 16.0 * s { 12.0 * s } else { (area.h - 2.0).max(8.0) };
    let tw = mocu_display::measure_text("STALE", size, true).width;
    let mid = if area.h < 48.0 * s && area.w >= tw + 12.0 * s {
        Point::new(area.x + 6.0 * s + tw / 2.0, area.y + area.h / 2.0)
    } else {
        Point::new(area.x + area.w / 2.0, area.y + (area.h * 0.25).max(size))
    };
    if tw + 8.0 <= area.w {
        c.fill_rounded_rect(
            Rect::new(mid.x - tw / 2.0 - 4.0, mid.y - size * 0.75, tw + 8.0, size * 1.5),
            3.0,
            &Brush::Solid(Color::rgba(0, 0, 0, 200)),
        );
    }
    let style = TextStyle::new(size, Color::rgb(0xf5, 0x9e, 0x0b))
        .align(Align::Center)
        .baseline(Baseline::Middle)
        .bold();
    if tw + 8.0 > area.w && tw + 8.0 <= area.h {
        // A tall, narrow widget (a vertical bar): the tag runs up its middle, inside it.
        let mid = Point::new(area.x + area.w / 2.0, area.y + area.h / 2.0);
        c.save();
        c.translate(mid.x, mid.y);
        c.rotate(-std::f32::consts::FRAC_PI_2);
        let back = Rect::new(-tw / 2.0 - 4.0, -size * 0.75, tw + 8.0, size * 1.5);
        c.fill_rounded_rect(back, 3.0, &Brush::Solid(Color::rgba(0, 0, 0, 200)));
        c.draw_text("STALE", Point::new(0.0, 0.0), &style);
        c.restore();
        return;
    }
    c.draw_text("STALE", mid, &style);
}
