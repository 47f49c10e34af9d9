//! The diagnostics banner: when a saved layout has errors, the operator's display keeps the
//! last good layout and shows, on top, which file, line and column is wrong. It goes when
//! the file is fixed. Its state lives in `root.operator.diagnostics` (`active`, `count`,
//! `text`), so any module (a remote tool, a HUD) can show it too.

use mocu_dataserver::{DataServer, ObjectInfo};
use mocu_display::{
    Align, Baseline, Brush, Canvas, Color, PaintArgs, Point, Rect, TextStyle, claim_window,
    invalidate,
};
use mocu_value::{Guid, PropName, Value};

const WINDOW: &str = "diagnostics";
const LINE: f32 = 20.0;

fn diagnostics_object(ds: &DataServer) -> Option<Guid> {
    let op = match ds.resolve(&["operator"]) {
        Some(g) => g,
        None => ds.create_object(Guid::ROOT, ObjectInfo::new("operator", "operator")).ok()?,
    };
    match ds.find_child(op, "diagnostics").ok()? {
        Some(g) => Some(g),
        None => {
            let g = ds.create_object(op, ObjectInfo::new("diagnostics", "diagnostics")).ok()?;
            let _ = ds.set(g, "active", Value::Bool(false));
            let _ = ds.set(g, "count", Value::Int(0));
            let _ = ds.set(g, "text", Value::str(""));
            Some(g)
        }
    }
}

/// Publishes the banner's window (hidden) and claims it.
pub(crate) fn start(ds: &DataServer, screen: (f64, f64)) {
    let Some(diag) = diagnostics_object(ds) else { return };
    let Ok(display) = mocu_display::ensure_display_object(ds, screen.0 as u32, screen.1 as u32)
    else {
        return;
    };
    if ds.find_child(display, WINDOW).ok().flatten().is_some() {
        return;
    }
    let rect = Rect::new(0.0, 0.0, screen.0 as f32, LINE + 12.0);
    let Ok(w) = mocu_display::publish_window(ds, display, WINDOW, "banner", 1_000_000, rect) else {
        return;
    };
    let _ = ds.set(w, "visible", Value::Bool(false));
    let ds2 = ds.clone();
    let _ = claim_window(ds, w, move |c: &mut dyn Canvas, _a: &PaintArgs| paint(&ds2, diag, c));
}

fn paint(ds: &DataServer, diag: Guid, c: &mut dyn Canvas) {
    let size = c.size();
    let text = ds
        .try_get(diag, PropName::new("text"))
        .and_then(|v| v.as_str().map(str::to_string))
        .unwrap_or_default();
    let count = ds.try_get(diag, PropName::new("count")).and_then(|v| v.as_i64()).unwrap_or(0);
    c.fill_rect(Rect::new(0.0, 0.0, size.w, size.h), Color::rgba(0x7f, 0x1d, 0x1d, 0xe8));
    c.fill_rect(Rect::new(0.0, size.h - 3.0, size.w, 3.0), Color::rgb(0xef, 0x44, 0x44));
    let white = Color::rgb(0xfe, 0xf2, 0xf2);
    let head = format!("LAYOUT NOT RELOADED — {count} error(s); the last good layout stays");
    c.draw_text(
        &head,
        Point::new(size.w - 10.0, 6.0),
        &TextStyle::new(12.0, white).align(Align::Right).baseline(Baseline::Top).bold(),
    );
    for (i, line) in text.lines().enumerate() {
        let style = TextStyle::new(14.0, white).baseline(Baseline::Top);
        c.draw_text(line, Point::new(10.0, 6.0 + i as f32 * LINE), &style);
    }
    let _ = Brush::Solid(white);
}

/// Shows the banner with up to five diagnostics (`file:line:col: message`).
pub(crate) fn show(ds: &DataServer, lines: &[String]) {
    let Some(diag) = diagnostics_object(ds) else { return };
    let shown: Vec<&str> = lines.iter().take(5).map(|s| s.as_str()).collect();
    let _ = ds.set(diag, "text", Value::str(&shown.join("\n")));
    let _ = ds.set(diag, "count", Value::Int(lines.len() as i64));
    let _ = ds.set(diag, "active", Value::Bool(true));
    if let Some(w) = ds.resolve(&["display", WINDOW]) {
        let _ = ds.set(w, "h", Value::Float((shown.len().max(1) as f32 * LINE + 12.0) as f64));
        let _ = ds.set(w, "visible", Value::Bool(true));
        let _ = invalidate(ds, w);
    }
}

/// Hides the banner (the file was fixed).
pub(crate) fn clear(ds: &DataServer) {
    if let Some(diag) = ds.resolve(&["operator", "diagnostics"]) {
        let _ = ds.set(diag, "active", Value::Bool(false));
        let _ = ds.set(diag, "count", Value::Int(0));
        let _ = ds.set(diag, "text", Value::str(""));
    }
    if let Some(w) = ds.resolve(&["display", WINDOW]) {
        let _ = ds.set(w, "visible", Value::Bool(false));
    }
}
