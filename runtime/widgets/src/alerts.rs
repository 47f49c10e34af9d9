//! The alert layer (`AlertLayer`, a native widget): the alerts of `root.operator.alerts`
//! (watches' `alert`s, refused / failed / timed-out commands; see `mocu-layout`'s
//! `alerts.rs`), newest first, centred at the top of the widget.
//!
//! - Severity colours: critical red (the whole row), warning amber, info cyan (a stripe).
//! - A critical alert stays until it is acknowledged; the others show for [`SHOW_FOR`].
//! - A count line above the rows: how many alerts are not acknowledged, and how to.
//! - A press on a row acknowledges that alert, on the count line every alert (the keyboard's
//!   Escape and the gamepad's `select` do the same through the layout's bindings).
//! - Rows that do not fit are summed up as "+N more".
//! - It draws at the widget's `scale` (a layout's design scale; the runtime gives its
//!   built-in layer the display's), never below 1: alert text stays at least 12 px.

use mocu_dataserver::DataServer;
use mocu_display::{Align, Baseline, Brush, Canvas, Color, Point, Rect, TextStyle};
use mocu_value::{Guid, PropName, Value};
use std::time::Duration;

/// The native component's name.
pub const COMPONENT: &str = "AlertLayer";
/// How long an alert that is not critical shows.
pub const SHOW_FOR: Duration = Duration::from_secs(10);
/// Row geometry, px.
const ROW: f32 = 34.0;
const GAP: f32 = 4.0;
const HEAD: f32 = 26.0;
const MAX_W: f32 = 680.0;

const CRITICAL_BG: Color = Color::rgba(0x7f, 0x1d, 0x1d, 0xf2);
const PANEL: Color = Color::rgba(0x0d, 0x14, 0x1b, 0xf0);
const TEXT: Color = Color::rgb(0xf8, 0xfa, 0xfc);
const DIM: Color = Color::rgb(0xcb, 0xd5, 0xe1);
const ALARM: Color = Color::rgb(0xef, 0x44, 0x44);
const CAUTION: Color = Color::rgb(0xf5, 0x9e, 0x0b);
const INFO: Color = Color::rgb(0x38, 0xbd, 0xf8);

/// One alert as shown.
#[derive(Clone, Debug)]
pub struct Shown {
    pub object: Guid,
    pub severity: String,
    pub text: String,
}

/// What the layer shows now: the count of unacknowledged alerts, the rows and where each
/// is (widget-local), the count line's rectangle, and how many rows did not fit.
#[derive(Clone, Debug, Default)]
pub struct Plan {
    pub unacknowledged: usize,
    pub head: Option<Rect>,
    pub rows: Vec<(Shown, Rect)>,
    pub more: usize,
    /// Whether any shown alert is critical (the count line turns red).
    pub critical: bool,
}

/// The scale the layer draws at, from the widget's `scale` property: at least 1.
pub fn scale_of(scale: Option<f64>) -> f32 {
    scale.filter(|s| s.is_finite()).map_or(1.0, |s| s.max(1.0)) as f32
}

/// The alerts to show in a widget of size `b` (screen px) drawn at scale `s`, newest first;
/// the rectangles are widget-local screen px.
pub fn plan(ds: &DataServer, b: Rect, s: f32) -> Plan {
    let mut p = plan_unscaled(ds, Rect::new(0.0, 0.0, b.w / s, b.h / s));
    let up = |r: Rect| Rect::new(r.x * s, r.y * s, r.w * s, r.h * s);
    p.head = p.head.map(up);
    for (_, r) in &mut p.rows {
        *r = up(*r);
    }
    p
}

/// [`plan`] in the layer's own px (before its scale).
fn plan_unscaled(ds: &DataServer, b: Rect) -> Plan {
    let mut plan = Plan::default();
    let Some(folder) = ds.resolve(&["operator", "alerts"]) else { return plan };
    let t = ds.wall_secs();
    let mut list: Vec<(f64, Shown)> = Vec::new();
    for a in ds.children(folder).unwrap_or_default() {
        let get = |k: &str| ds.try_get(a, PropName::new(k));
        if get("acknowledged") != Some(Value::Bool(false)) {
            continue;
        }
        plan.unacknowledged += 1;
        let severity = get("severity").and_then(|v| v.as_str().map(str::to_string));
        let severity = severity.unwrap_or_else(|| "warning".into());
        let time = get("time").and_then(|v| v.as_f64()).unwrap_or(t);
        if severity != "critical" && t - time > SHOW_FOR.as_secs_f64() {
            continue;
        }
        let text = get("text").and_then(|v| v.as_str().map(str::to_string)).unwrap_or_default();
        list.push((time, Shown { object: a, severity, text }));
    }
    list.sort_by(|x, y| {
        let crit = |s: &Shown| s.severity == "critical";
        crit(&y.1).cmp(&crit(&x.1)).then(y.0.total_cmp(&x.0))
    });
    if plan.unacknowledged == 0 {
        return plan;
    }
    // At most MAX_W, centred, 8 px in from each side.
    let w = MAX_W.min(b.w - 16.0).max(120.0);
    let x = (b.w - w) / 2.0;
    plan.head = Some(Rect::new(x, 6.0, w, HEAD - 4.0));
    let mut y = 6.0 + HEAD;
    let n = list.len();
    for (i, (_, s)) in list.into_iter().enumerate() {
        // Keep room for the "+N more" line unless this is the last row.
        let need = if i + 1 < n { ROW + GAP + 18.0 } else { ROW };
        if y + need > b.h {
            plan.more = n - i;
            break;
        }
        plan.critical |= s.severity == "critical";
        plan.rows.push((s, Rect::new(x, y, w, ROW)));
        y += ROW + GAP;
    }
    plan
}

/// Draws the layer (widget-local coordinates, `b` in screen px) at scale `s`.
pub fn draw(c: &mut dyn Canvas, ds: &DataServer, b: Rect, s: f32) {
    c.save();
    c.scale(s, s);
    draw_unscaled(c, ds, Rect::new(0.0, 0.0, b.w / s, b.h / s));
    c.restore();
}

fn draw_unscaled(c: &mut dyn Canvas, ds: &DataServer, b: Rect) {
    let p = plan_unscaled(ds, b);
    let Some(head) = p.head else { return };
    let ink = if p.critical { ALARM } else { CAUTION };
    c.fill_rounded_rect(head, 4.0, &Brush::Solid(PANEL));
    c.fill_circle(Point::new(head.x + 12.0, head.y + head.h / 2.0), 4.5, ink);
    let count = TextStyle::new(12.0, TEXT).baseline(Baseline::Middle).bold();
    let plural = if p.unacknowledged == 1 { "ALERT" } else { "ALERTS" };
    let line = format!("{} UNACKNOWLEDGED {plural}", p.unacknowledged);
    c.draw_text(&line, Point::new(head.x + 24.0, head.y + head.h / 2.0), &count);
    let hint = TextStyle::new(12.0, DIM).baseline(Baseline::Middle).align(Align::Right);
    let hint_text = "click or Esc to acknowledge";
    if mocu_display::measure_text(&line, 12.0, true).width
        + mocu_display::measure_text(hint_text, 12.0, false).width
        + 48.0
        < head.w
    {
        c.draw_text(hint_text, Point::new(head.x + head.w - 10.0, head.y + head.h / 2.0), &hint);
    }
    for (s, r) in &p.rows {
        let critical = s.severity == "critical";
        let (bg, stripe, tag) = match s.severity.as_str() {
            "critical" => (CRITICAL_BG, ALARM, "CRITICAL"),
            "info" => (PANEL, INFO, "INFO"),
            _ => (PANEL, CAUTION, "WARNING"),
        };
        c.fill_rounded_rect(*r, 4.0, &Brush::Solid(bg));
        c.fill_rect(Rect::new(r.x, r.y, 6.0, r.h), stripe);
        let tag_ink = if critical { TEXT } else { stripe };
        let tag_style = TextStyle::new(12.0, tag_ink).baseline(Baseline::Middle).bold();
        let mid = r.y + r.h / 2.0;
        c.draw_text(tag, Point::new(r.x + 16.0, mid), &tag_style);
        let tx = r.x + 16.0 + 78.0;
        let text = fit(&s.text, 15.0, r.x + r.w - 10.0 - tx);
        let style = TextStyle::new(15.0, TEXT).baseline(Baseline::Middle).bold();
        c.draw_text(&text, Point::new(tx, mid), &style);
    }
    if p.more > 0
        && let Some((_, last)) = p.rows.last()
    {
        let st = TextStyle::new(12.0, TEXT).baseline(Baseline::Top).bold();
        let at = Point::new(last.x + 8.0, last.y + last.h + GAP);
        let box_w = mocu_display::measure_text(&format!("+{} more", p.more), 12.0, true).width;
        c.fill_rounded_rect(
            Rect::new(at.x - 6.0, at.y - 1.0, box_w + 12.0, 17.0),
            3.0,
            &Brush::Solid(PANEL),
        );
        c.draw_text(&format!("+{} more", p.more), at, &st);
    }
}

/// `text` cut to `room` px at `size`, with an ellipsis.
pub fn fit(text: &str, size: f32, room: f32) -> String {
    let width = |t: &str| mocu_display::measure_text(t, size, true).width;
    if width(text) <= room {
        return text.to_string();
    }
    let mut chars: Vec<char> = text.chars().collect();
    while chars.len() > 1 && width(&format!("{}…", chars.iter().collect::<String>())) > room {
        chars.pop();
    }
    format!("{}…", chars.iter().collect::<String>().trim_end())
}

/// A press at widget-local `p` on a layer drawn at scale `s`: a row acknowledges its alert,
/// the count line all of them. Returns whether it hit something.
pub fn press(ds: &DataServer, b: Rect, p: Point, s: f32) -> bool {
    let plan = plan(ds, b, s);
    if let Some((s, _)) = plan.rows.iter().find(|(_, r)| r.contains(p)) {
        ds.call(s.object, "acknowledge", vec![], None, |_| {});
        return true;
    }
    if plan.head.is_some_and(|h| h.contains(p))
        && let Some(folder) = ds.resolve(&["operator", "alerts"])
    {
        ds.call(folder, "acknowledge_all", vec![], None, |_| {});
        return true;
    }
    false
}
