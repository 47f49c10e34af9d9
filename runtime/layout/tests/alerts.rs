//! Alerts and failed commands always reach the operator: the world model, the log, and a
//! built-in alert window unless the layout places an `AlertLayer` itself.
mod common;
use common::{config, program};
use mocu_dataserver::*;
use mocu_layout::*;
use std::sync::Arc;

const STOP_BUTTON: &str = r#"
use "stdlib/controls.mocu"
window hud { layer 10 rect 0 0 100% 100% }
in hud { stop: Button { at 10 10 100 30  label "STOP"  on press call root.vehicles.usv1.stop() } }
"#;

fn alerts(ds: &DataServer) -> Vec<Guid> {
    ds.resolve(&["operator", "alerts"]).map(|f| ds.children(f).unwrap()).unwrap_or_default()
}

fn text(ds: &DataServer, g: Guid, prop: &str) -> String {
    ds.get(g, prop).map(|v| v.to_string()).unwrap_or_default()
}

fn unacknowledged(ds: &DataServer) -> Value {
    ds.get(ds.resolve(&["operator", "alerts"]).unwrap(), "unacknowledged").unwrap()
}

#[test]
fn a_layout_without_an_alert_layer_gets_the_built_in_one_on_top() {
    let ds = DataServer::default();
    let layout = Layout::load(&ds, &program(STOP_BUTTON), config(), Arc::new(NullSink)).unwrap();
    layout.settle();
    let win = ds.resolve(&["display", "alert_layer"]).expect("the built-in alert window");
    assert_eq!(ds.info(win).unwrap().subtype.as_ref(), "widgets");
    assert_eq!(ds.get(win, "layer").unwrap(), Value::Float(1000.0));
    // Nothing at the top centre: there, 680 px of rows and 8 px margins, four rows tall.
    let geometry = |g: Guid| ["x", "y", "w", "h"].map(|k| ds.get(g, k).unwrap());
    let f = Value::Float;
    assert_eq!(geometry(win), [f(612.0), f(0.0), f(696.0), f(200.0)]);
    let w = ds.resolve(&["display", "alert_layer", "alerts"]).expect("its widget");
    assert_eq!(ds.get(w, "component").unwrap(), Value::str("AlertLayer"));
    assert_eq!(geometry(w), [f(0.0), f(0.0), f(696.0), f(200.0)]);
    assert_eq!(ds.get(w, "scale").unwrap(), f(1.0));
    drop(layout);
    assert_eq!(ds.resolve(&["display", "alert_layer"]), None, "unloaded with the layout");
}

#[test]
fn a_layout_that_places_the_alert_layer_gets_no_second_one_and_a_reload_adds_it_back() {
    let ds = DataServer::default();
    let placed = format!("{STOP_BUTTON}\nin hud {{ mine: AlertLayer {{ at 0 400 600 200 }} }}");
    let layout = Layout::load(&ds, &program(&placed), config(), Arc::new(NullSink)).unwrap();
    layout.settle();
    assert_eq!(ds.resolve(&["display", "alert_layer"]), None);
    assert!(ds.resolve(&["display", "hud", "mine"]).is_some());
    layout.reload(&program(STOP_BUTTON)).unwrap();
    layout.settle();
    assert!(ds.resolve(&["display", "alert_layer"]).is_some(), "never lost silently");
}

#[test]
fn a_failed_command_is_an_unacknowledged_warning_until_acknowledged() {
    let ds = DataServer::default();
    let sink = Arc::new(MemorySink::default());
    let layout = Layout::load(&ds, &program(STOP_BUTTON), config(), sink.clone()).unwrap();
    layout.settle();
    let stop = ds.resolve(&["display", "hud", "stop"]).unwrap();
    assert!(matches!(ds.call_wait(stop, "press", vec![], None), CallOutcome::Accepted(_)));
    layout.settle();
    let list = alerts(&ds);
    assert_eq!(list.len(), 1, "one alert for the failed call");
    let a = list[0];
    assert_eq!(text(&ds, a, "severity"), "warning");
    assert_eq!(text(&ds, a, "source"), "command");
    assert!(text(&ds, a, "text").starts_with("usv1.stop: failed"), "{}", text(&ds, a, "text"));
    assert_eq!(unacknowledged(&ds), Value::Int(1));
    let logged = sink.of("alert");
    assert_eq!(logged.len(), 1, "logged once");
    assert!(matches!(ds.call_wait(a, "acknowledge", vec![], None), CallOutcome::Accepted(_)));
    assert_eq!(ds.get(a, "acknowledged").unwrap(), Value::Bool(true));
    assert_eq!(unacknowledged(&ds), Value::Int(0));
}

#[test]
fn escape_and_the_gamepad_select_button_acknowledge_every_alert_unless_the_layout_binds_them() {
    let ds = DataServer::default();
    let layout = Layout::load(&ds, &program(STOP_BUTTON), config(), Arc::new(NullSink)).unwrap();
    layout.settle();
    let stop = ds.resolve(&["display", "hud", "stop"]).unwrap();
    for _ in 0..2 {
        ds.call_wait(stop, "press", vec![], None);
    }
    layout.settle();
    assert_eq!(unacknowledged(&ds), Value::Int(2));
    let bindings = ds.resolve(&["display", "bindings"]).expect("the built-in bindings");
    let inputs: Vec<(String, String)> = ds
        .children(bindings)
        .unwrap()
        .into_iter()
        .map(|b| (text(&ds, b, "device"), text(&ds, b, "input")))
        .collect();
    assert!(inputs.contains(&("keyboard".into(), "escape".into())), "{inputs:?}");
    assert!(inputs.contains(&("gamepad".into(), "select".into())), "{inputs:?}");
    let escape = ds
        .children(bindings)
        .unwrap()
        .into_iter()
        .find(|b| text(&ds, *b, "input") == "escape")
        .unwrap();
    ds.call_wait(escape, "fire", vec![Value::Float(1.0)], None);
    assert_eq!(unacknowledged(&ds), Value::Int(0));

    let own = format!("{STOP_BUTTON}\nbind keyboard {{ key escape -> hide hud }}");
    layout.reload(&program(&own)).unwrap();
    layout.settle();
    let bindings = ds.resolve(&["display", "bindings"]).unwrap();
    let escapes = ds
        .children(bindings)
        .unwrap()
        .into_iter()
        .filter(|b| text(&ds, *b, "input") == "escape")
        .count();
    assert_eq!(escapes, 1, "the layout's own Escape binding, no built-in one beside it");
}

#[test]
fn a_watch_alert_is_critical_in_the_world_model_with_its_text() {
    let ds = DataServer::default();
    let v = ds.create_object(Guid::ROOT, ObjectInfo::new("v", "folder")).unwrap();
    ds.set(v, "link", Value::Float(0.5)).unwrap();
    let text_src = "watch lost { when root.v.link < 0.1 then alert critical \"Link lost\" }";
    let layout = Layout::load(&ds, &program(text_src), config(), Arc::new(NullSink)).unwrap();
    layout.settle();
    assert!(alerts(&ds).is_empty());
    ds.set(v, "link", Value::Float(0.0)).unwrap();
    for _ in 0..100 {
        layout.settle();
        if !alerts(&ds).is_empty() {
            break;
        }
    }
    let a = alerts(&ds)[0];
    assert_eq!(text(&ds, a, "severity"), "critical");
    assert_eq!(text(&ds, a, "text"), "Link lost");
    assert_eq!(text(&ds, a, "source"), "layout");
    assert_eq!(unacknowledged(&ds), Value::Int(1));
}

/// The rectangles (x, y, w, h) of the built-in alert window and of widget `name` in `hud`.
fn layer_and(ds: &DataServer, name: &str) -> ([f64; 4], [f64; 4]) {
    let rect = |g: Guid| ["x", "y", "w", "h"].map(|k| ds.get(g, k).unwrap().as_f64().unwrap());
    let layer = ds.resolve(&["display", "alert_layer"]).expect("the built-in alert window");
    (rect(layer), rect(ds.resolve(&["display", "hud", name]).unwrap()))
}

fn overlap(a: [f64; 4], b: [f64; 4]) -> bool {
    a[0] < b[0] + b[2] && b[0] < a[0] + a[2] && a[1] < b[1] + b[3] && b[1] < a[1] + a[3]
}

#[test]
fn the_built_in_alert_window_moves_off_widgets_at_the_top_centre_and_shrinks_to_a_free_gap() {
    let ds = DataServer::default();
    // A readout at the top centre and panels down both sides leave a gap 800 px wide.
    let text = r#"
use "stdlib/gauges.mocu"
window hud { layer 10 rect 0 0 100% 100% }
in hud {
  readout: TextGauge { at 660 10 600 60  label "SPD"  value 3 }
  left: TextGauge { at 0 0 560 1080  label "L"  value 1 }
  right: TextGauge { at 1360 0 560 1080  label "R"  value 2 }
}
"#;
    let layout = Layout::load(&ds, &program(text), config(), Arc::new(NullSink)).unwrap();
    layout.settle();
    let (layer, readout) = layer_and(&ds, "readout");
    assert!(!overlap(layer, readout), "{layer:?} covers {readout:?}");
    assert!(layer[1] >= 70.0 && layer[1] <= 90.0, "just below the readout: {layer:?}");
    assert!(layer[0] >= 560.0 && layer[0] + layer[2] <= 1360.0, "in the gap: {layer:?}");
    assert_eq!(layer[3], 200.0, "four rows tall");
}

#[test]
fn with_a_design_the_built_in_alert_layer_grows_with_the_screen_but_never_below_one() {
    let text = "design 800 x 480\nwindow hud { layer 10 rect 0 0 100% 100% }\n";
    for (screen, scale) in [((3840.0, 2160.0), 4.5), ((1280.0, 720.0), 1.5), ((400.0, 240.0), 1.0)]
    {
        let ds = DataServer::default();
        let cfg = LayoutConfig { screen, ..config() };
        let layout = Layout::load(&ds, &program(text), cfg, Arc::new(NullSink)).unwrap();
        layout.settle();
        let w = ds.resolve(&["display", "alert_layer", "alerts"]).unwrap();
        assert_eq!(ds.get(w, "scale").unwrap(), Value::Float(scale), "{screen:?}");
        let win = ds.resolve(&["display", "alert_layer"]).unwrap();
        let n = |k: &str| ds.get(win, k).unwrap().as_f64().unwrap();
        assert_eq!(n("h"), (200.0 * scale).min(screen.1), "{screen:?}");
        assert!(n("x") >= 0.0 && n("x") + n("w") <= screen.0, "{screen:?}: on the screen");
    }
}
