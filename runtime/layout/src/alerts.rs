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
use mocu_dataserver::{CallOutcome, DataServer, MethodSpec, ObjectInfo};
use mocu_language::program::Program;
use mocu_value::{Guid, Value};
use std::sync::Arc;

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
    }
}

/// The built-in window: the full width of the screen, as tall as five alert rows; what the
/// layer does not draw stays transparent and lets the pointer through.
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
    for (k, v) in [("x", 0.0), ("y", 0.0), ("w", w), ("h", h)] {
        let _ = ds.set(wg, k, Value::Float(v));
    }
    Ok(g)
}

/// Height of the built-in window: a count line and four alert rows.
const ROWS_HEIGHT: f64 = 200.0;

/// The top band the built-in window stays below: the state header and the heading tape.
pub const BELOW: [&str; 2] = ["StatusHeader", "HeadingTape"];
/// Space between the band and the window, px.
const BAND_GAP: f64 = 6.0;

/// Moves the built-in window below the top band — the lowest bottom edge of the evaluated
/// [`BELOW`] widgets in the top half of the screen — so that alerts never cover the state
/// header or the heading tape; it keeps [`ROWS_HEIGHT`] on screen. Runs after each load
/// and reload has evaluated the widgets' positions.
pub(crate) fn place_layer(sh: &Shared, st: &State) {
    let ds = &sh.ds;
    let Some(layer) = ds.find_child(st.display, WINDOW).ok().flatten() else { return };
    let screen_h = sh.config.screen.1;
    let num = |g: Guid, k: &str| ds.try_get(g, k.into()).and_then(|v| v.as_f64());
    let mut band: f64 = 0.0;
    for win in ds.children(st.display).unwrap_or_default() {
        if win == layer || ds.try_get(win, "visible".into()) == Some(Value::Bool(false)) {
            continue;
        }
        let wy = num(win, "y").unwrap_or(0.0);
        for w in ds.children(win).unwrap_or_default() {
            let comp = ds.try_get(w, "component".into());
            if !comp.as_ref().and_then(Value::as_str).is_some_and(|c| BELOW.contains(&c)) {
                continue;
            }
            let (Some(y), Some(h)) = (num(w, "y"), num(w, "h")) else { continue };
            if wy + y < screen_h / 2.0 {
                band = band.max(wy + y + h);
            }
        }
    }
    let y = if band > 0.0 { band + BAND_GAP } else { 0.0 };
    let y = y.min((screen_h - ROWS_HEIGHT).max(0.0)).round();
    let h = (screen_h - y).min(ROWS_HEIGHT);
    if num(layer, "y") != Some(y) || num(layer, "h") != Some(h) {
        let _ = ds.set(layer, "y", Value::Float(y));
        let _ = ds.set(layer, "h", Value::Float(h));
        if let Some(wg) = ds.find_child(layer, "alerts").ok().flatten() {
            let _ = ds.set(wg, "h", Value::Float(h));
        }
    }
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
