//! Widgets drawn by Rust rather than compiled from a component: the vehicle list, the
//! video placeholder, the context menu and the frame of an unknown component.

use mocu_dataserver::DataServer;
use mocu_display::{Align, Baseline, Brush, Canvas, Color, Point, Rect, Stroke, TextStyle};
use mocu_value::{Guid, PropName, Value};
use std::collections::HashMap;

/// Widgets drawn by Rust: the vehicle list, a video placeholder (the video module claims
/// video windows); unknown components draw a labelled frame, never nothing. Public for
/// tests/contrast.rs, which measures the text they draw.
pub fn draw_native(
    c: &mut dyn Canvas,
    ds: &DataServer,
    component: &str,
    props: &HashMap<String, Value>,
    bounds: Option<Rect>,
) {
    let b = bounds.unwrap_or(Rect::new(0.0, 0.0, 160.0, 40.0));
    if component == "ContextMenu" {
        context_menu(c, props, b);
        return;
    }
    if component == crate::alerts::COMPONENT {
        let s = crate::alerts::scale_of(props.get("scale").and_then(Value::as_f64));
        crate::alerts::draw(c, ds, Rect::new(0.0, 0.0, b.w, b.h), s);
        return;
    }
    c.fill_rounded_rect(Rect::new(0.0, 0.0, b.w, b.h), 4.0, &Brush::Solid(theme::PANEL));
    c.stroke_rounded_rect(
        Rect::new(0.5, 0.5, b.w - 1.0, b.h - 1.0),
        4.0,
        &Stroke::new(1.0),
        theme::FRAME,
    );
    if component == "VehicleList" {
        let filter = props.get("filter").and_then(Value::as_str).filter(|f| !f.is_empty());
        vehicle_list(c, ds, filter, b);
        return;
    }
    if component == "FlowMore" {
        // A flowing template's "+N more" (mocu-layout's graph/flow.rs), at the design's
        // scale as the legend is.
        let s = props.get("scale").and_then(Value::as_f64).unwrap_or(1.0).max(1.0) as f32;
        let n = props.get("count").and_then(Value::as_i64).unwrap_or(0);
        let style = TextStyle::new(12.0 * s, theme::TEXT)
            .bold()
            .align(Align::Center)
            .baseline(Baseline::Middle);
        c.draw_text(&format!("+{n} more"), Point::new(b.w / 2.0, b.h / 2.0), &style);
        return;
    }
    if component == "BindingLegend" {
        // It grows with a design's scale, as the vehicle list does (`paint.rs`).
        let s = props.get("scale").and_then(Value::as_f64).unwrap_or(1.0).max(0.1) as f32;
        let device = props.get("device").and_then(Value::as_str).unwrap_or("gamepad");
        c.save();
        c.scale(s, s);
        binding_legend(c, ds, device, Rect::new(0.0, 0.0, b.w / s, b.h / s));
        c.restore();
        return;
    }
    let label = match component {
        "Video" => format!("no video from {}", camera_name(props.get("source"))),
        other => other.to_string(),
    };
    let style = TextStyle::new(12.0, theme::DIM).align(Align::Center).baseline(Baseline::Middle);
    c.draw_text(&label, Point::new(b.w / 2.0, b.h / 2.0), &style);
}

/// A `Video` widget's camera for the operator: "usv1 drive camera" for
/// `root.vehicles.usv1.cameras.drive`, never the raw path (the video painter names it alike).
fn camera_name(source: Option<&Value>) -> String {
    let text = source.map(|v| v.to_string()).unwrap_or_default();
    let segs: Vec<&str> = text.trim_matches('"').split('.').filter(|s| !s.is_empty()).collect();
    let vehicle = segs.iter().position(|s| *s == "vehicles").and_then(|i| segs.get(i + 1));
    match (vehicle, segs.last()) {
        (Some(v), Some(c)) if segs.len() > 3 => format!("{v} {c} camera"),
        (_, Some(c)) if *c != "root" => format!("{c} camera"),
        _ => "its camera".to_string(),
    }
}

/// The stdlib theme's colours, for what Rust draws (stdlib/theme.mocu).
mod theme {
    use mocu_display::Color;
    pub const PANEL: Color = Color::rgba(0x10, 0x18, 0x20, 0xe0);
    pub const TRACK: Color = Color::rgb(0x26, 0x32, 0x3e);
    pub const FRAME: Color = Color::rgb(0x3a, 0x4a, 0x5a);
    pub const ACCENT: Color = Color::rgb(0x38, 0xbd, 0xf8);
    pub const TEXT: Color = Color::rgb(0xe8, 0xf0, 0xf8);
    pub const DIM: Color = Color::rgb(0x8f, 0xa3, 0xb5);
    pub const GOOD: Color = Color::rgb(0x22, 0xc5, 0x5e);
    pub const CAUTION: Color = Color::rgb(0xf5, 0x9e, 0x0b);
    pub const ALARM: Color = Color::rgb(0xef, 0x44, 0x44);
    pub const NODATA: Color = Color::rgb(0x7d, 0x87, 0x94);
}

/// Where a vehicle list's rows start, and their height.
pub(super) const LIST_TOP: f32 = 28.0;
pub(super) const LIST_ROW: f32 = 26.0;

/// The vehicles a list shows, in order.
pub(super) fn listed_vehicles(
    ds: &DataServer,
    filter: Option<&str>,
) -> Vec<(Guid, mocu_dataserver::ObjectInfo)> {
    ds.resolve(&["vehicles"])
        .and_then(|f| ds.children(f).ok())
        .unwrap_or_default()
        .into_iter()
        .filter_map(|v| ds.info(v).ok().map(|i| (v, i)))
        .filter(|(_, i)| filter.is_none_or(|f| &*i.kind == f))
        .collect()
}

/// The context menu: a title and one row per item, the hovered row lit.
fn context_menu(c: &mut dyn Canvas, props: &HashMap<String, Value>, b: Rect) {
    let s = |k: &str| props.get(k).and_then(Value::as_str).unwrap_or("").to_string();
    c.fill_rounded_rect(
        Rect::new(0.0, 0.0, b.w, b.h),
        5.0,
        &Brush::Solid(Color::rgba(0x0d, 0x14, 0x1b, 0xf2)),
    );
    c.stroke_rounded_rect(
        Rect::new(0.75, 0.75, b.w - 1.5, b.h - 1.5),
        5.0,
        &Stroke::new(1.5),
        theme::ACCENT,
    );
    let head = TextStyle::new(12.0, theme::DIM).baseline(Baseline::Middle).bold();
    c.draw_text(&s("title"), Point::new(10.0, crate::menu::TITLE / 2.0), &head);
    c.line(
        Point::new(6.0, crate::menu::TITLE - 1.0),
        Point::new(b.w - 6.0, crate::menu::TITLE - 1.0),
        1.0,
        theme::FRAME,
    );
    let n = props.get("items").and_then(Value::as_i64).unwrap_or(0).max(0) as usize;
    let hover = props.get("hover_row").and_then(Value::as_i64).unwrap_or(-1);
    for i in 0..n {
        let y = crate::menu::TITLE + i as f32 * crate::menu::ROW;
        let enabled = props.get(&format!("enabled{i}")) == Some(&Value::Bool(true));
        if hover == i as i64 && enabled {
            c.fill_rounded_rect(
                Rect::new(3.0, y + 1.0, b.w - 6.0, crate::menu::ROW - 2.0),
                3.0,
                &Brush::Solid(Color::rgba(0x38, 0xbd, 0xf8, 0x40)),
            );
        }
        let label = props.get(&format!("item{i}")).map(|v| v.to_string()).unwrap_or_default();
        let st = TextStyle::new(14.0, if enabled { theme::TEXT } else { theme::NODATA })
            .baseline(Baseline::Middle);
        c.draw_text(&label, Point::new(14.0, y + crate::menu::ROW / 2.0), &st);
    }
}

/// One row per vehicle: a link-state dot, the name, its type, link and fuel as small bars.
fn vehicle_list(c: &mut dyn Canvas, ds: &DataServer, filter: Option<&str>, b: Rect) {
    let head = TextStyle::new(12.0, theme::DIM).baseline(Baseline::Middle).bold();
    c.draw_text("VEHICLES", Point::new(10.0, 13.0), &head);
    c.line(Point::new(6.0, 25.0), Point::new(b.w - 6.0, 25.0), 1.0, theme::FRAME);
    let vehicles = listed_vehicles(ds, filter);
    if vehicles.is_empty() {
        let st = TextStyle::new(12.0, theme::NODATA).baseline(Baseline::Middle);
        c.draw_text("— no vehicles —", Point::new(10.0, 40.0), &st);
        return;
    }
    let row_h = LIST_ROW;
    // Two labelled bars after the name and type, within the list's width.
    // A narrow list leaves the type out.
    let first = if b.w < 320.0 { 86.0 } else { 130.0 };
    let bar_w = ((b.w - first - 2.0 * 42.0 - 8.0) / 2.0).clamp(16.0, 90.0);
    // The rows that fit; with more vehicles than that, the last row says how many are left.
    let fit = (((b.h - LIST_TOP) / row_h).floor().max(0.0)) as usize;
    let shown = if vehicles.len() > fit { fit.saturating_sub(1) } else { vehicles.len() };
    if shown < vehicles.len() && fit > 0 {
        let y = LIST_TOP + shown as f32 * row_h + row_h / 2.0;
        let st = TextStyle::new(12.0, theme::TEXT).baseline(Baseline::Middle).bold();
        c.draw_text(&format!("+{} more", vehicles.len() - shown), Point::new(26.0, y), &st);
    }
    for (i, (v, info)) in vehicles.iter().take(shown).enumerate() {
        let y = LIST_TOP + i as f32 * row_h + row_h / 2.0;
        let num = |k: &str| ds.try_get(*v, PropName::new(k)).and_then(|x| x.as_f64());
        let flag = |k: &str| ds.try_get(*v, PropName::new(k)) == Some(Value::Bool(true));
        let lost = flag("link_lost") || flag("stale");
        let link = num("link");
        let fuel = num("fuel");
        let dot = if lost {
            theme::ALARM
        } else if link.is_some_and(|l| l < 0.3) {
            theme::CAUTION
        } else if link.is_some() {
            theme::GOOD
        } else {
            theme::NODATA
        };
        c.fill_circle(Point::new(14.0, y), 4.5, dot);
        let name = TextStyle::new(13.0, if lost { theme::DIM } else { theme::TEXT })
            .baseline(Baseline::Middle)
            .bold();
        c.draw_text(&info.name, Point::new(26.0, y), &name);
        let kind = TextStyle::new(12.0, theme::DIM).baseline(Baseline::Middle);
        if first > 86.0 {
            c.draw_text(&info.kind.to_uppercase(), Point::new(86.0, y), &kind);
        }
        let mut x = first;
        for (label, value, warn, alarm) in [("LNK", link, 0.3, 0.1), ("FUEL", fuel, 0.2, 0.1)] {
            let small = TextStyle::new(12.0, theme::DIM).baseline(Baseline::Middle);
            c.draw_text(label, Point::new(x, y), &small);
            let bx = x + 32.0;
            let track = Rect::new(bx, y - 4.0, bar_w, 8.0);
            c.fill_rounded_rect(track, 2.0, &Brush::Solid(theme::TRACK));
            match value {
                Some(f) => {
                    let col = if f < alarm {
                        theme::ALARM
                    } else if f < warn {
                        theme::CAUTION
                    } else {
                        theme::GOOD
                    };
                    let fw = (bar_w * f.clamp(0.0, 1.0) as f32).max(0.0);
                    if fw > 0.5 {
                        c.fill_rounded_rect(
                            Rect::new(bx, y - 4.0, fw, 8.0),
                            2.0,
                            &Brush::Solid(col),
                        );
                    }
                }
                None => c.stroke_rounded_rect(track, 2.0, &Stroke::new(1.0), theme::NODATA),
            }
            x = bx + bar_w + 10.0;
        }
    }
}

/// The bindings in use on `device` (the layout publishes them under `root.display.bindings`,
/// each with its `action` described): one row per input, the input then what it does; in a
/// mode, that mode's bindings and those of every mode.
fn binding_legend(c: &mut dyn Canvas, ds: &DataServer, device: &str, b: Rect) {
    let head = TextStyle::new(12.0, theme::DIM).baseline(Baseline::Middle).bold();
    c.draw_text(&device.to_uppercase(), Point::new(10.0, 13.0), &head);
    c.line(Point::new(6.0, 25.0), Point::new(b.w - 6.0, 25.0), 1.0, theme::FRAME);
    let rows = legend_rows(ds, device);
    let fit = (((b.h - LIST_TOP) / 20.0).floor().max(0.0)) as usize;
    let key = TextStyle::new(12.0, theme::ACCENT).baseline(Baseline::Middle).bold();
    let what = TextStyle::new(12.0, theme::TEXT).baseline(Baseline::Middle);
    let col = (b.w * 0.36).clamp(70.0, 130.0);
    for (i, (input, action)) in rows.iter().take(fit).enumerate() {
        let y = LIST_TOP + i as f32 * 20.0 + 10.0;
        c.draw_text(input, Point::new(10.0, y), &key);
        c.draw_text(action, Point::new(10.0 + col, y), &what);
    }
    if rows.is_empty() {
        let st = TextStyle::new(12.0, theme::NODATA).baseline(Baseline::Middle);
        c.draw_text("— no bindings —", Point::new(10.0, 40.0), &st);
    }
}

/// (input, action) of each binding of `device` in use now, in the layout's order.
pub(super) fn legend_rows(ds: &DataServer, device: &str) -> Vec<(String, String)> {
    let text = |g: Guid, k: &str| match ds.try_get(g, PropName::new(k)) {
        Some(Value::Str(s)) => s.to_string(),
        _ => String::new(),
    };
    let mode = ds.resolve(&["operator"]).map(|op| text(op, "mode")).unwrap_or_default();
    let Some(folder) = ds.resolve(&["display", "bindings"]) else { return Vec::new() };
    let mut rows = Vec::new();
    for g in ds.children(folder).unwrap_or_default() {
        let action = text(g, "action");
        let m = text(g, "mode");
        if text(g, "device") != device || action.is_empty() || !(m.is_empty() || m == mode) {
            continue;
        }
        let mut input = text(g, "input").replace('_', " ");
        if ds.try_get(g, PropName::new("shift")) == Some(Value::Bool(true)) {
            input = format!("shift+{input}");
        }
        rows.push((input, action));
    }
    rows
}
