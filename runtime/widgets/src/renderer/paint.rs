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
        for &w in &widgets {
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
            let mut texts = Vec::new();
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
                texts = crate::draw::text_rects(&comp.shapes, &outs)
                    .into_iter()
                    .map(|t| Rect::new(t.x * s, t.y * s, t.w * s, t.h * s))
                    .collect();
                if let Some(e) = crate::draw::extent(&comp.shapes, &outs) {
                    let e = Rect::new(e.x * s, e.y * s, e.w * s, e.h * s);
                    drawn = Some(drawn.map_or(e, |d| union(d, e)));
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
            // The other widgets' boxes, for a STALE tag that finds no room inside its own.
            let others = || -> Vec<Rect> {
                let shown = |o: &Guid| {
                    self.ds.try_get(*o, PropName::new("visible")).and_then(|v| v.as_bool())
                        != Some(false)
                };
                let boxes = widgets.iter().filter(|o| **o != w && shown(o));
                boxes.filter_map(|o| super::widget_bounds(&self.ds, *o)).collect()
            };
            self.overlays(c, w, &props, &data, bounds, (drawn, &texts, &others));
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
        (drawn, texts, others): (Option<Rect>, &[Rect], &dyn Fn() -> Vec<Rect>),
    ) {
        // A component with a `stale` parameter draws its own veil and state field (the
        // status header, stdlib/status.mocu): a tag here would sit on its text.
        let own_stale = props.get("component").and_then(Value::as_str).is_some_and(|c| {
            self.lib
                .lock()
                .components
                .get(c)
                .is_some_and(|c| c.slots.iter().any(|(n, _)| n == "stale"))
        });
        let stale = !own_stale
            && data.iter().any(|d| props.contains_key(d))
            && (props.get("stale").and_then(Value::as_bool) == Some(true)
                || props.get("aged").and_then(Value::as_bool) == Some(true));
        // The tag grows with a design's scale, like the widget it marks.
        let s = props.get("scale").and_then(Value::as_f64).map_or(1.0, |s| s.max(1.0)) as f32;
        let room = Room { texts, others, window: c.size(), boxed: bounds.is_some() };
        let Some(b) = bounds else {
            // A widget placed by a point (a label): the veil covers what it drew.
            let at = |k: &str| props.get(k).and_then(Value::as_f64).unwrap_or(0.0) as f32;
            if let (true, Some(d)) = (stale, drawn) {
                stale_veil(c, Rect::new(at("x"), at("y"), 0.0, 0.0), d, 4.0, s, &room);
            }
            return;
        };
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
        if stale {
            let area = drawn.unwrap_or(Rect::new(0.0, 0.0, b.w, b.h));
            stale_veil(c, b, area, radius, s, &room);
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
/// that drew nothing outside its box gets a round veil) and the STALE tag inside the veil,
/// where it covers none of the widget's text (`texts`: its caption, its value) if there is
/// such a place: it never covers a neighbour, nor what it marks.
fn stale_veil(c: &mut dyn Canvas, b: Rect, drawn: Rect, radius: f32, s: f32, room: &Room) {
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
    let size = if area.h >= 16.0 * s { 12.0 * s } else { (area.h - 2.0).max(8.0) };
    let tw = mocu_display::measure_text("STALE", size, true).width;
    let style = TextStyle::new(size, Color::rgb(0xf5, 0x9e, 0x0b))
        .align(Align::Center)
        .baseline(Baseline::Middle)
        .bold();
    let back =
        |mid: Point| Rect::new(mid.x - tw / 2.0 - 4.0, mid.y - size * 0.75, tw + 8.0, size * 1.5);
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
    let Some(mid) = tag_place(b, area, back(Point::new(0.0, 0.0)), room, s) else {
        // No place leaves the widget's text readable and no neighbour covered (a strip
        // scaled down to a small screen): an amber outline round the veil says it instead
        // of the word, over nothing the operator reads.
        let outline = Rect::new(area.x - 1.0, area.y - 1.0, area.w + 2.0, area.h + 2.0);
        let stroke = Stroke::new((1.5 * s).max(1.0));
        c.stroke_rounded_rect(outline, r, &stroke, Color::rgb(0xf5, 0x9e, 0x0b));
        return;
    };
    if tw + 8.0 <= area.w {
        c.fill_rounded_rect(back(mid), 3.0, &Brush::Solid(Color::rgba(0, 0, 0, 200)));
    }
    c.draw_text("STALE", mid, &style);
}

/// What a STALE tag must leave uncovered: the widget's own text (widget-local), the other
/// widgets' boxes (window px, asked for only when the tag goes outside) and the window.
struct Room<'a> {
    texts: &'a [Rect],
    others: &'a dyn Fn() -> Vec<Rect>,
    window: mocu_display::Size,
    /// The widget has a box, and a damage repaint redraws only around it (`inflate`); a
    /// widget placed by a point repaints its whole window.
    boxed: bool,
}

/// How much of `texts` the box `t` covers (px²).
fn covered(t: Rect, texts: &[Rect]) -> f32 {
    let over = |r: &Rect| {
        let w = (t.x + t.w).min(r.x + r.w) - t.x.max(r.x);
        let h = (t.y + t.h).min(r.y + r.h) - t.y.max(r.y);
        w.max(0.0) * h.max(0.0)
    };
    texts.iter().map(over).sum()
}

/// The middle of the STALE tag (its box `tag` centred on the origin) of the widget with box
/// `b` (window px) that drew `area` (widget-local): inside the area where it covers none of
/// the widget's text nor the 3 px (at the design's scale) beside it, nearest to where it hides the least in a gauge — the middle of a short,
/// wide widget, high in the middle of a tall one; where the area has no such place (a
/// short read-out whose caption and value fill it), just above or below it, on no other
/// widget, within the damage margin; `None` where there is no such place either (the
/// caller marks the veil instead of covering text).
fn tag_place(b: Rect, area: Rect, tag: Rect, room: &Room, s: f32) -> Option<Point> {
    let want = if area.h < 48.0 * s {
        Point::new(area.x + area.w * 0.5, area.y + area.h / 2.0)
    } else {
        Point::new(area.x + area.w / 2.0, area.y + (area.h * 0.25).max(-tag.y))
    };
    // The box stays in the area where it fits (a short widget: its height's middle).
    let span = |lo: f32, len: f32, half: f32| {
        if len >= 2.0 * half {
            (lo + half, lo + len - half)
        } else {
            (lo + len / 2.0, lo + len / 2.0)
        }
    };
    let at = |m: Point| Rect::new(m.x + tag.x, m.y + tag.y, tag.w, tag.h);
    // The texts kept clear of, with a gap beside each: a tag flush against a value reads
    // as one word with it ("STALE12.3 kn").
    let gap = 3.0 * s;
    let texts: Vec<Rect> =
        room.texts.iter().map(|r| Rect::new(r.x - gap, r.y, r.w + 2.0 * gap, r.h)).collect();
    let (x0, x1) = span(area.x, area.w, tag.w / 2.0);
    let best_in = |y0: f32, y1: f32| {
        let step = (2.0 * s).max(1.0);
        let mut best = (f32::MAX, f32::MAX, Point::new(want.x.clamp(x0, x1), y0));
        let mut y = y0;
        while y <= y1 + 0.01 {
            let mut x = x0;
            while x <= x1 + 0.01 {
                let m = Point::new(x, y);
                let d = (x - want.x).powi(2) + (y - want.y).powi(2);
                let k = covered(at(m), &texts);
                if (k, d) < (best.0, best.1) {
                    best = (k, d, m);
                }
                x += step;
            }
            y += step;
        }
        best
    };
    let (y0, y1) = span(area.y, area.h, tag.h / 2.0);
    let inside = best_in(y0, y1);
    let mut pick = Some(inside.2);
    if inside.0 > 0.0 {
        pick = None;
        // Just above the area (over its top edge by 2 px) or just below it, inside the
        // margin a damage repaint redraws (`inflate`).
        let above = area.y - tag.h / 2.0 + 2.0;
        let below = area.y + area.h + tag.h / 2.0 - 2.0;
        let window = Rect::new(-b.x, -b.y, room.window.w, room.window.h);
        let others: Vec<Rect> = (room.others)()
            .into_iter()
            .map(|o| Rect::new(o.x - b.x, o.y - b.y, o.w, o.h))
            .collect();
        // A widget placed by a point (a label): right after what it drew, first.
        let right = Point::new(area.x + area.w + tag.w / 2.0 + 4.0 * s, area.y + area.h / 2.0);
        let mut sides = Vec::with_capacity(3);
        if !room.boxed {
            sides.push((right, false));
        }
        sides.extend([(Point::new(0.0, above), true), (Point::new(0.0, below), true)]);
        for (side, slide) in sides {
            // Above or below, it slides along the area to the place nearest the middle.
            let (x, y, k) = if slide {
                let best = best_in(side.y, side.y);
                (best.2.x, side.y, best.0)
            } else {
                (side.x, side.y, covered(at(side), &texts))
            };
            let t = at(Point::new(x, y));
            let fits = k == 0.0
                && (!room.boxed
                    || (t.y >= -super::MARGIN && t.y + t.h <= b.h + super::MARGIN + super::BELOW))
                && t.x >= window.x
                && t.y >= window.y
                && t.x + t.w <= window.x + window.w
                && t.y + t.h <= window.y + window.h
                && !others.iter().any(|o| o.intersects(&t));
            if fits {
                pick = Some(Point::new(x, y));
                break;
            }
        }
    }
    // Whole pixels: a damage repaint draws the tag exactly as a full one does.
    pick.map(|p| Point::new(p.x.round(), p.y.round()))
}
