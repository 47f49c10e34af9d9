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
    assert_eq!(ds.get(win, "w").unwrap(), Value::Float(1920.0), "the screen's width");
    let w = ds.resolve(&["display", "alert_layer", "alerts"]).expect("its widget");
    assert_eq!(ds.get(w, "component").unwrap(), Value::str("AlertLayer"));
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
