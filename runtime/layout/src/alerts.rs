//! Alerts and command outcomes reach the operator, whatever the layout shows.
//!
//! Every alert — a watch's `alert`, and every call or write that was refused, failed or
//! timed out — is one object `root.operator.alerts.alertN` (type `alert`, subtype the
//! severity) with `severity`, `text`, `time`, `source` (`layout` or `command`), `active`
//! and `acknowledged`, and a method `acknowledge()`. The folder keeps `unacknowledged` (a
//! count) and has `acknowledge_all()`. Each alert is also recorded in the event log and, once,
//! written on the terminal (stderr).
//!
//! On screen: unless the layout places an `AlertLayer` widget itself, the runtime adds a
//! top window `root.display.alert_layer` (layer [`LAYER`]) holding one, drawn by the widget
//! renderer. The keyboard's Escape and the gamepad's `select` acknowledge every alert unless
//! the layout binds them to something else.

use crate::actions::{ActionCtx, CompiledAction, operator_child};
use crate::graph::{LoadError, Shared, State};
use mocu_dataserver::{CallOutcome, DataServer, MethodSpec, ObjectInfo, SubscriptionId, Topic};
use mocu_language::program::Program;
use mocu_value::{Guid, Value};
use std::sync::{Arc, OnceLock};

/// The built-in alert window's name under `root.display`.
pub const WINDOW: &str = "alert_layer";
/// Its layer: above every window a layout declares.
pub const LAYER: f64 = 1000.0;
/// The native component that shows the alerts.
pub const COMPONENT: &str = "AlertLayer";

/// Call outcomes the operator must see (a pending or accepted call is shown on its control).
pub(crate) fn is_failure(state: &str) -> bool {
    matches!(state, "refused" | "failed" | "timed_out" | "no_such_method" | "no_such_object")
}

/// Raises an alert: the world model, the event log and the terminal. Returns its object.
pub(crate) fn raise(sh: &Arc<Shared>, level: &str, text: &str, source: &str) -> Option<Guid> {
    if sh.config.alerts_to_terminal {
        eprintln!("mocu: {} {}", level.to_uppercase(), text);
    }
    sh.sink.record(
        "alert",
        &[
            ("severity", Value::str(level)),
            ("text", Value::str(text)),
            ("source", Value::str(source)),
        ],
    );
    let ds = &sh.ds;
    let folder = alerts_folder(sh)?;
    let n = ds.try_get(folder, "raised".into()).and_then(|v| v.as_i64()).unwrap_or(0) + 1;
    let _ = ds.set(folder, "raised", Value::Int(n));
    let g = ds
        .create_object(folder, ObjectInfo::new(&format!("alert{n}"), "alert").subtype(level))
        .ok()?;
    let _ = ds.set(g, "severity", Value::str(level));
    let _ = ds.set(g, "source", Value::str(source));
    let _ = ds.set(g, "time", Value::Float(ds.wall_secs()));
    let _ = ds.set(g, "acknowledged", Value::Bool(false));
    let _ = ds.set(g, "active", Value::Bool(true));
    // `text` last: whoever follows alerts may take a written text as a complete alert.
    let _ = ds.set(g, "text", Value::str(text));
    let ds2 = ds.clone();
    let _ = ds.publish_method_fn(g, MethodSpec::new("acknowledge"), move |_| {
        let _ = ds2.set(g, "acknowledged", Value::Bool(true));
        recount(&ds2, folder);
        CallOutcome::Accepted(vec![])
    });
    recount(ds, folder);
    Some(g)
}

/// `root.operator.alerts`, with its `acknowledge_all` method.
fn alerts_folder(sh: &Shared) -> Option<Guid> {
    let folder = operator_child(sh, "alerts", "alerts")?;
    let ds = &sh.ds;
    if !ds.methods(folder).is_ok_and(|m| m.iter().any(|m| m.name.as_str() == "acknowledge_all")) {
        let ds2 = ds.clone();
        let _ = ds.publish_method_fn(folder, MethodSpec::new("acknowledge_all"), move |_| {
            acknowledge_all(&ds2, folder);
            CallOutcome::Accepted(vec![])
        });
    }
    Some(folder)
}

fn acknowledge_all(ds: &DataServer, folder: Guid) {
    for a in ds.children(folder).unwrap_or_default() {
        if ds.try_get(a, "acknowledged".into()) == Some(Value::Bool(false)) {
            let _ = ds.set(a, "acknowledged", Value::Bool(true));
        }
    }
    recount(ds, folder);
}

/// Writes the folder's `unacknowledged` count.
fn recount(ds: &DataServer, folder: Guid) {
    let n = ds
        .children(folder)
        .unwrap_or_default()
        .into_iter()
        .filter(|a| ds.try_get(*a, "acknowledged".into()) == Some(Value::Bool(false)))
        .count();
    let _ = ds.set(folder, "unacknowledged", Value::Int(n as i64));
}

/// Runs `acknowledge_all` (the built-in Escape / `select` bindings).
pub(crate) fn acknowledge(sh: &Arc<Shared>, cx: ActionCtx) {
    let _ = cx;
    if let Some(folder) = alerts_folder(sh) {
        acknowledge_all(&sh.ds, folder);
    }
    sh.sink.record("action", &[("kind", Value::str("acknowledge"))]);
}

/// Whether the program places an `AlertLayer` widget itself (at the top or in a template).
fn places_layer(program: &Program) -> bool {
    program.widgets.iter().any(|w| w.component == COMPONENT)
        || program.templates.iter().any(|t| t.widgets.iter().any(|w| w.component == COMPONENT))
}

/// Adds the built-in alert window when the program does not place the layer, removes it
/// when it does.
pub(crate) fn ensure_layer(sh: &Arc<Shared>, st: &mut State, program: &Program) {
    let ds = &sh.ds;
    let existing = ds.find_child(st.display, WINDOW).ok().flatten();
    if places_layer(program) || !sh.config.alert_layer {
        if let Some(g) = existing {
            let _ = ds.delete_object(g);
        }
        return;
    }
    if existing.is_some() {
        return;
    }
    if let Ok(g) = publish_layer(ds, st.display, sh.config.screen) {
        st.owned_push(g);
        let subs = follow(sh, st.display, g);
        st.subs.extend(subs);
    }
}

/// The built-in window: placed by [`place_layer`] once the widgets' positions are known;
/// what the layer does not draw stays transparent and lets the pointer through.
fn publish_layer(ds: &DataServer, display: Guid, screen: (f64, f64)) -> Result<Guid, LoadError> {
    let world = |e: mocu_dataserver::DsError| LoadError::World(e.to_string());
    let (w, h) = (screen.0, screen.1.min(ROWS_HEIGHT));
    let g = ds
        .create_object(display, ObjectInfo::new(WINDOW, "window").subtype("widgets"))
        .map_err(world)?;
    for (k, v) in [("layer", LAYER), ("x", 0.0), ("y", 0.0), ("w", w), ("h", h), ("opacity", 1.0)] {
        let _ = ds.set(g, k, Value::Float(v));
    }
    let _ = ds.set(g, "visible", Value::Bool(true));
    let _ = ds.set(g, "order", Value::Int(i32::MAX as i64));
    let _ = ds.set(g, "revision", Value::Int(0));
    let _ = ds.set(g, "clip", Value::Bool(true));
    let wg = ds
        .create_object(g, ObjectInfo::new("alerts", "widget").subtype(COMPONENT))
        .map_err(world)?;
    let _ = ds.set(wg, "component", Value::str(COMPONENT));
    let _ = ds.set(wg, "native", Value::Bool(true));
    let _ = ds.set(wg, "order", Value::Int(0));
    for (k, v) in [("x", 0.0), ("y", 0.0), ("w", w), ("h", h), ("scale", 1.0)] {
        let _ = ds.set(wg, k, Value::Float(v));
    }
    Ok(g)
}

/// The built-in window's geometry in the layer's own px (times its scale on screen): the
/// widest box (alert rows at most `MAX_W` wide, 8 px margins), the narrowest it may shrink
/// to, and its height: a count line and four rows, at least a count line and two rows.
const MAX_W: f64 = 696.0;
const MIN_W: f64 = 336.0;
const ROWS_HEIGHT: f64 = 200.0;
const MIN_HEIGHT: f64 = 128.0;

/// The top band kept clear when nothing else is free: the state header and the heading tape.
pub const BELOW: [&str; 2] = ["StatusHeader", "HeadingTape"];
/// Space between the window and what it avoids, px.
const BAND_GAP: f64 = 6.0;

/// A rectangle on the screen: x, y, w, h.
type Area = [f64; 4];

fn overlaps(a: Area, b: Area) -> bool {
    a[0] < b[0] + b[2] && b[0] < a[0] + a[2] && a[1] < b[1] + b[3] && b[1] < a[1] + a[3]
}

/// Places the built-in window where it covers nothing of the layout: the highest spot,
/// nearest the screen's centre line, where a box as wide as possible (shrinking to
/// [`MIN_W`]) and at least [`MIN_HEIGHT`] tall overlaps no widget of a full-screen window
/// (hidden widgets too: a banner may show later) and no smaller window (a strip, a
/// picture-in-picture video, a map); it then grows down to [`ROWS_HEIGHT`] while free. The
/// layer draws at the display's design scale, at least 1 (text stays ≥ 12 px). When no spot
/// is free it goes below the top band (the lowest [`BELOW`] widget in the top half), so
/// that it never covers the state header or the heading tape. Runs after each load and
/// reload has evaluated the widgets' positions.
pub(crate) fn place_layer(sh: &Shared, st: &State) {
    if let Some(layer) = sh.ds.find_child(st.display, WINDOW).ok().flatten() {
        place(&sh.ds, st.display, layer, sh.config.screen);
    }
}

/// Places the window again whenever an alert is raised or acknowledged and whenever a
/// window comes or goes (a vehicle's strip appears after the layout loaded), until the
/// window is gone. The layout ends the subscriptions it returns when it is unloaded.
fn follow(sh: &Arc<Shared>, display: Guid, layer: Guid) -> Vec<SubscriptionId> {
    let Some(folder) = alerts_folder(sh) else { return Vec::new() };
    let mut subs = Vec::new();
    let ds = &sh.ds;
    let exec = ds.serial_executor();
    let screen = sh.config.screen;
    for topic in [Topic::properties(folder), Topic::children(display)] {
        let id = Arc::new(OnceLock::<SubscriptionId>::new());
        let (ds2, id2, weak) = (ds.clone(), id.clone(), Arc::downgrade(sh));
        let sub = ds.subscribe_on(&exec, topic, move |_| {
            let Some(sh) = weak.upgrade().filter(|_| ds2.info(layer).is_ok()) else {
                if let Some(id) = id2.get() {
                    ds2.unsubscribe_nowait(*id);
                }
                return;
            };
            // Under the layout's lock: a window that has just appeared is placed and sized by
            // the evaluation that holds it, and read half-built (no size yet) it would not be
            // avoided — a placement from then, written last, covered a vehicle's strip.
            let _st = sh.state.lock();
            place(&ds2, display, layer, screen);
        });
        if let Ok(sub) = sub {
            let _ = id.set(sub);
            subs.push(sub);
        }
    }
    subs
}

fn place(ds: &DataServer, display: Guid, layer: Guid, screen: (f64, f64)) {
    let (sw, sh_) = screen;
    let num = |g: Guid, k: &str| ds.try_get(g, k.into()).and_then(|v| v.as_f64());
    let s = num(display, "scale").filter(|s| s.is_finite()).unwrap_or(1.0).max(1.0);
    let (obstacles, band) = obstacles(ds, display, layer, (sw, sh_));
    let step = 4.0;
    let widest = (MAX_W * s).min((sw * 0.6).max(436.0 * s)).min(sw);
    let narrowest = (MIN_W * s).min(sw);
    let (min_h, max_h) = ((MIN_HEIGHT * s).min(sh_), (ROWS_HEIGHT * s).min(sh_));
    let free = |a: Area| a[1] + a[3] <= sh_ && !obstacles.iter().any(|o| overlaps(a, *o));
    let mut spot = None;
    let mut w = widest;
    'width: while w >= narrowest - 0.5 {
        let mut y = 0.0;
        while y + min_h <= sh_ {
            if let Some(x) = free_x(&obstacles, y, min_h, w, sw) {
                spot = Some((x, y, w));
                break 'width;
            }
            y += step;
        }
        w -= 32.0 * s;
    }
    let (x, y, w, h) = match spot {
        Some((x, y, w)) => {
            let mut h = min_h;
            while h + step <= max_h && free([x, y, w, h + step]) {
                h += step;
            }
            (x, y, w, h)
        }
        None => {
            let y = if band > 0.0 { band + BAND_GAP } else { 0.0 };
            let y = y.min((sh_ - max_h).max(0.0));
            (((sw - widest) / 2.0).max(0.0), y, widest, (sh_ - y).min(max_h))
        }
    };
    let (x, y, w, h) = (x.round(), y.round(), w.round(), h.round());
    let wg = ds.find_child(layer, "alerts").ok().flatten();
    let same =
        [("x", x), ("y", y), ("w", w), ("h", h)].iter().all(|(k, v)| num(layer, k) == Some(*v))
            && wg.is_some_and(|g| num(g, "scale") == Some(s));
    if same {
        return;
    }
    for (k, v) in [("x", x), ("y", y), ("w", w), ("h", h)] {
        let _ = ds.set(layer, k, Value::Float(v));
    }
    if let Some(wg) = wg {
        for (k, v) in [("x", 0.0), ("y", 0.0), ("w", w), ("h", h), ("scale", s)] {
            let _ = ds.set(wg, k, Value::Float(v));
        }
    }
}

/// The left edge nearest the screen's centre line of a free box `w` wide over rows
/// `y .. y + h`, if there is one.
fn free_x(obstacles: &[Area], y: f64, h: f64, w: f64, sw: f64) -> Option<f64> {
    let mut blocked: Vec<(f64, f64)> = obstacles
        .iter()
        .filter(|o| o[1] < y + h && y < o[1] + o[3])
        .map(|o| (o[0], o[0] + o[2]))
        .collect();
    blocked.sort_by(|a, b| a.0.total_cmp(&b.0));
    let centre = ((sw - w) / 2.0).round();
    let (mut best, mut from): (Option<f64>, f64) = (None, 0.0);
    let mut consider = |lo: f64, hi: f64| {
        if hi - lo >= w {
            let x = centre.clamp(lo, hi - w);
            if best.is_none_or(|b| (x - centre).abs() < (b - centre).abs()) {
                best = Some(x);
            }
        }
    };
    for (a, b) in blocked {
        consider(from, a.min(sw));
        from = from.max(b);
    }
    consider(from, sw);
    best
}

/// What the built-in window must not cover, on the screen (with [`BAND_GAP`] around each),
/// and the bottom of the top band ([`BELOW`] widgets in the top half; 0 without any).
fn obstacles(ds: &DataServer, display: Guid, layer: Guid, screen: (f64, f64)) -> (Vec<Area>, f64) {
    let num = |g: Guid, k: &str| ds.try_get(g, k.into()).and_then(|v| v.as_f64());
    let area = |g: Guid| -> Option<Area> {
        Some([num(g, "x")?, num(g, "y")?, num(g, "w").unwrap_or(0.0), num(g, "h").unwrap_or(0.0)])
    };
    let pad =
        |a: Area| [a[0] - BAND_GAP, a[1] - BAND_GAP, a[2] + 2.0 * BAND_GAP, a[3] + 2.0 * BAND_GAP];
    let (mut out, mut band) = (Vec::new(), 0.0_f64);
    for win in ds.children(display).unwrap_or_default() {
        if win == layer || ds.try_get(win, "visible".into()) == Some(Value::Bool(false)) {
            continue;
        }
        let Some(wr) = area(win) else { continue };
        let widgets: Vec<Guid> = ds
            .children(win)
            .unwrap_or_default()
            .into_iter()
            .filter(|w| ds.try_get(*w, "component".into()).is_some())
            .collect();
        // A window of less than half the screen is one piece; a larger one is a background
        // (a video, a map) or holds a HUD's widgets.
        if wr[2] * wr[3] < screen.0 * screen.1 * 0.5 {
            out.push(pad(wr));
        }
        for w in widgets {
            let Some(r) = area(w) else { continue };
            // A widget without a size (a label at a point): about a line of text.
            let r = if r[2] <= 0.0 || r[3] <= 0.0 { [r[0], r[1], 120.0, 24.0] } else { r };
            let on_screen = [wr[0] + r[0], wr[1] + r[1], r[2], r[3]];
            out.push(pad(on_screen));
            let comp = ds.try_get(w, "component".into());
            if comp.as_ref().and_then(Value::as_str).is_some_and(|c| BELOW.contains(&c))
                && on_screen[1] < screen.1 / 2.0
            {
                band = band.max(on_screen[1] + on_screen[3]);
            }
        }
    }
    (out, band)
}

/// Escape (keyboard) and `select` (gamepad) acknowledge every alert, unless the layout binds
/// those inputs itself: (binding key, actions) pairs as the layout's bindings are kept.
pub(crate) fn builtin_bindings(program: &Program) -> Vec<(String, Vec<CompiledAction>)> {
    let mut out = Vec::new();
    for (device, kind, input) in [("keyboard", "key", "escape"), ("gamepad", "button", "select")] {
        let taken = program
            .bindings
            .iter()
            .any(|b| b.device == device && b.kind == kind && b.input.eq_ignore_ascii_case(input));
        if !taken {
            let key = crate::actions::button_key(device, kind, input, "press");
            out.push((key, vec![CompiledAction::Acknowledge]));
        }
    }
    out
}
