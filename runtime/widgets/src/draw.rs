//! Drawing primitives (rect, rounded, circle, arc, line, polyline, text, image) onto any
//! backend's [`Canvas`]. A primitive with an absent coordinate is skipped, not drawn at 0.

use crate::component::ShapeOut;
use mocu_display::{Align, Baseline, Brush, Canvas, Color, Path, Point, Rect, Stroke, TextStyle};
use mocu_value::Value;

/// `0xRRGGBBAA` as a colour.
pub fn color(rgba: i64) -> Color {
    let c = rgba as u32;
    Color::rgba((c >> 24) as u8, (c >> 16) as u8, (c >> 8) as u8, c as u8)
}

fn num(v: &Option<Value>) -> Option<f32> {
    v.as_ref().and_then(Value::as_f64).map(|x| x as f32)
}

/// Draws the shapes of one evaluated component.
pub fn draw_shapes(c: &mut dyn Canvas, shapes: &[ShapeOut], outs: &[Option<Value>]) {
    for s in shapes {
        let style = |name: &str| -> Option<&Value> {
            s.styles.iter().find(|(n, _)| n == name).and_then(|(_, i)| outs[*i].as_ref())
        };
        if style("visible").and_then(Value::as_bool) == Some(false) {
            continue;
        }
        let opacity =
            style("opacity").and_then(Value::as_f64).map_or(1.0, |o| o.clamp(0.0, 1.0) as f32);
        let paint = |name: &str| -> Option<Color> {
            style(name)
                .and_then(Value::as_i64)
                .map(color)
                .map(|c| c.with_alpha(c.a as f32 / 255.0 * opacity))
        };
        let args = &outs[s.first..s.first + s.args];
        let width = style("width").and_then(Value::as_f64).map_or(1.0, |w| w as f32);
        let fill = paint("fill");
        let stroke = paint("stroke").or_else(|| paint("colour").filter(|_| s.kind != "text"));
        let nums: Option<Vec<f32>> = args.iter().map(num).collect();
        let path = match (s.kind.as_str(), nums.as_deref()) {
            ("rect", Some([x, y, w, h])) => {
                Some(Path::rect(Rect::new(*x, *y, w.max(0.0), h.max(0.0))))
            }
            ("rounded", Some([x, y, w, h, r])) => {
                Some(Path::rounded_rect(Rect::new(*x, *y, w.max(0.0), h.max(0.0)), r.max(0.0)))
            }
            ("circle", Some([cx, cy, r])) => Some(Path::circle(Point::new(*cx, *cy), r.max(0.0))),
            ("arc", Some([cx, cy, r, start, sweep])) => Some(Path::arc(
                Point::new(*cx, *cy),
                r.max(0.0),
                start.to_radians(),
                sweep.to_radians(),
            )),
            ("line", Some([x1, y1, x2, y2])) => {
                Some(Path::line(Point::new(*x1, *y1), Point::new(*x2, *y2)))
            }
            ("polyline", Some(pts)) if pts.len() >= 4 => {
                let pts: Vec<Point> = pts.chunks_exact(2).map(|p| Point::new(p[0], p[1])).collect();
                Some(Path::polyline(&pts, false))
            }
            _ => None,
        };
        match (s.kind.as_str(), path) {
            // A stroked-only arc (a gauge scale) takes the canvas's arc fast path.
            ("arc", Some(_)) if fill.is_none() => {
                if let (Some([cx, cy, r, start, sweep]), Some(st)) = (nums.as_deref(), stroke) {
                    c.stroke_arc(
                        Point::new(*cx, *cy),
                        r.max(0.0),
                        start.to_radians(),
                        sweep.to_radians(),
                        &Stroke::new(width),
                        st,
                    );
                }
            }
            ("text", _) => {
                let (Some(x), Some(y)) = (num(&args[0]), num(&args[1])) else { continue };
                let Some(text) = args.get(2).and_then(|v| v.as_ref()).map(|v| v.to_string()) else {
                    continue;
                };
                let size = style("size").and_then(Value::as_f64).map_or(14.0, |s| s as f32);
                let col = paint("colour").or(paint("fill")).unwrap_or(Color::rgb(0xe8, 0xf0, 0xf8));
                let align = match style("align").and_then(Value::as_str) {
                    Some("center") | Some("centre") => Align::Center,
                    Some("right") => Align::Right,
                    _ => Align::Left,
                };
                let bold = style("font").and_then(Value::as_str) == Some("bold");
                let mut ts = TextStyle::new(size, col).align(align).baseline(Baseline::Middle);
                if bold {
                    ts = ts.bold();
                }
                c.draw_text(&text, Point::new(x, y), &ts);
            }
            (_, Some(path)) => {
                if let Some(f) = fill {
                    c.fill_path(&path, &Brush::Solid(f));
                }
                if let Some(st) = stroke {
                    c.stroke_path(&path, &Stroke::new(width), &Brush::Solid(st));
                }
            }
            _ => {}
        }
    }
}

/// The rectangle (component-local) that the shapes of one evaluated component cover, text
/// included: what the stale veil must cover. `None` when nothing is drawn.
pub fn extent(shapes: &[ShapeOut], outs: &[Option<Value>]) -> Option<Rect> {
    let mut acc: Option<(f32, f32, f32, f32)> = None;
    let mut add = |x0: f32, y0: f32, x1: f32, y1: f32| {
        if !(x0.is_finite() && y0.is_finite() && x1.is_finite() && y1.is_finite()) {
            return;
        }
        acc = Some(match acc {
            None => (x0, y0, x1, y1),
            Some((a, b, c, d)) => (a.min(x0), b.min(y0), c.max(x1), d.max(y1)),
        });
    };
    for s in shapes {
        let style = |name: &str| -> Option<&Value> {
            s.styles.iter().find(|(n, _)| n == name).and_then(|(_, i)| outs[*i].as_ref())
        };
        if style("visible").and_then(Value::as_bool) == Some(false) {
            continue;
        }
        let args = &outs[s.first..s.first + s.args];
        let half = style("width").and_then(Value::as_f64).map_or(0.5, |w| w as f32 / 2.0);
        let nums: Option<Vec<f32>> = args.iter().map(num).collect();
        match (s.kind.as_str(), nums.as_deref()) {
            ("rect" | "rounded" | "image", Some([x, y, w, h, ..])) => add(*x, *y, x + w, y + h),
            ("circle" | "arc", Some([cx, cy, r, ..])) => {
                add(cx - r - half, cy - r - half, cx + r + half, cy + r + half)
            }
            ("line", Some([x1, y1, x2, y2])) => {
                add(x1.min(*x2) - half, y1.min(*y2) - half, x1.max(*x2) + half, y1.max(*y2) + half)
            }
            ("polyline", Some(pts)) => {
                for p in pts.chunks_exact(2) {
                    add(p[0] - half, p[1] - half, p[0] + half, p[1] + half);
                }
            }
            ("text", _) => {
                if let Some(r) = text_rect(s, outs) {
                    add(r.x, r.y, r.x + r.w, r.y + r.h);
                }
            }
            _ => {}
        }
    }
    acc.map(|(x0, y0, x1, y1)| Rect::new(x0, y0, x1 - x0, y1 - y0))
}

/// Where the visible text of one evaluated component lies (component-local): what the
/// STALE tag must not cover.
pub fn text_rects(shapes: &[ShapeOut], outs: &[Option<Value>]) -> Vec<Rect> {
    let shown = |s: &&ShapeOut| {
        s.kind == "text"
            && outs[s.first..s.first + s.args]
                .get(2)
                .and_then(|v| v.as_ref())
                .is_some_and(|t| !t.to_string().trim().is_empty())
    };
    shapes.iter().filter(shown).filter_map(|s| text_rect(s, outs)).collect()
}

/// The box of a `text` shape's line (`None` when it is hidden or not placed).
fn text_rect(s: &ShapeOut, outs: &[Option<Value>]) -> Option<Rect> {
    let style = |name: &str| -> Option<&Value> {
        s.styles.iter().find(|(n, _)| n == name).and_then(|(_, i)| outs[*i].as_ref())
    };
    if style("visible").and_then(Value::as_bool) == Some(false) {
        return None;
    }
    let args = &outs[s.first..s.first + s.args];
    let (x, y) = (num(args.first()?)?, num(args.get(1)?)?);
    let text = args.get(2)?.as_ref()?.to_string();
    let size = style("size").and_then(Value::as_f64).map_or(14.0, |s| s as f32);
    let bold = style("font").and_then(Value::as_str) == Some("bold");
    let w = mocu_display::measure_text(&text, size, bold).width;
    let x0 = match style("align").and_then(Value::as_str) {
        Some("center") | Some("centre") => x - w / 2.0,
        Some("right") => x - w,
        _ => x,
    };
    Some(Rect::new(x0, y - size * 0.65, w, size * 1.3))
}
