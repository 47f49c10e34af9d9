//! Script actions in a layout (`#js: { … }`, `#rhai: { … }`): wherever an action goes (widget
//! events, bindings, menu items, watch `then`), run on the layout's script executor with
//! `self`, `selected` and `input` set; their errors reach the operator with file:line:col;
//! a reload stops the old scripts.
mod common;
use common::{config, program};
use mocu_dataserver::*;
use mocu_layout::*;
use std::sync::Arc;

fn vehicle(ds: &DataServer, name: &str) -> Guid {
    let vs = ds.resolve(&["vehicles"]).unwrap_or_else(|| {
        ds.create_object(Guid::ROOT, ObjectInfo::new("vehicles", "folder")).unwrap()
    });
    let v = ds.create_object(vs, ObjectInfo::new(name, "usv")).unwrap();
    ds.set(v, "name", Value::str(name)).unwrap();
    ds.set(v, "note", Value::str("")).unwrap();
    ds.set(v, "fuel", Value::Float(1.0)).unwrap();
    v
}

fn note(ds: &DataServer, v: Guid) -> String {
    ds.get(v, "note").map(|v| v.to_string()).unwrap_or_default()
}

fn alert_texts(ds: &DataServer) -> Vec<String> {
    let Some(f) = ds.resolve(&["operator", "alerts"]) else { return vec![] };
    ds.children(f)
        .unwrap()
        .into_iter()
        .filter_map(|a| ds.get(a, "text").ok().map(|t| t.to_string()))
        .collect()
}

fn press(ds: &DataServer, path: &[&str]) {
    let w = ds.resolve(path).expect("the widget");
    assert!(ds.call_wait(w, "press", vec![], None).is_accepted());
}

const BUTTONS: &str = r#"
use "stdlib/controls.mocu"
window hud { layer 10 rect 0 0 100% 100% }
in hud {
  js: Button {
    at 10 10 100 30  label "JS"
    on press #js: {
      // a brace in a comment: }
      const s = "pressed {js}";
      mocu.write("vehicles.usv1.note", s + " by " + (selected ?? "nobody"));
    }
  }
  rhai: Button {
    at 10 50 100 30  label "RHAI"
    on press #rhai: { mocu::write("vehicles.usv1.note", "rhai " + (40 + 2)); }
  }
}
"#;

#[test]
fn a_button_press_runs_its_js_or_rhai_script_against_the_world_model() {
    let ds = DataServer::default();
    let usv1 = vehicle(&ds, "usv1");
    let layout = Layout::load(&ds, &program(BUTTONS), config(), Arc::new(NullSink)).unwrap();
    layout.settle();
    press(&ds, &["display", "hud", "js"]);
    layout.settle();
    assert_eq!(note(&ds, usv1), "pressed {js} by nobody");
    press(&ds, &["display", "hud", "rhai"]);
    layout.settle();
    assert_eq!(note(&ds, usv1), "rhai 42");
    assert!(alert_texts(&ds).is_empty(), "{:?}", alert_texts(&ds));
}

#[test]
fn a_menu_item_script_sees_self_and_a_binding_script_sees_its_input() {
    let ds = DataServer::default();
    let usv2 = vehicle(&ds, "usv2");
    let p = program(
        r#"
menu for type "usv" {
  item "Note" -> #js: { mocu.write(self + ".note", "menu on " + self); }
}
bind gamepad {
  axis left_y -> #rhai: { mocu::write("vehicles.usv2.fuel", input * 0.5); }
}
"#,
    );
    let layout = Layout::load(&ds, &p, config(), Arc::new(NullSink)).unwrap();
    layout.settle();
    let menu = ds.resolve(&["display", "menus", "usv"]).expect("the menu");
    let args = vec![Value::Int(0), Value::str("root.vehicles.usv2")];
    assert!(ds.call_wait(menu, "choose", args, None).is_accepted());
    layout.settle();
    assert_eq!(note(&ds, usv2), "menu on root.vehicles.usv2");
    let bindings = ds.resolve(&["display", "bindings"]).unwrap();
    let b = ds.children(bindings).unwrap()[0];
    assert!(ds.call_wait(b, "fire", vec![Value::Float(0.5)], None).is_accepted());
    layout.settle();
    assert_eq!(ds.get(usv2, "fuel").unwrap(), Value::Float(0.25));
}

#[test]
fn a_watch_then_script_runs_when_its_criterion_holds() {
    let ds = DataServer::default();
    let usv1 = vehicle(&ds, "usv1");
    let p = program(
        r#"
watch low {
  when root.vehicles.usv1.fuel < 0.2
  then #js: { mocu.write("vehicles.usv1.note", "fuel " + mocu.read("vehicles.usv1.fuel")); }
}
"#,
    );
    let layout = Layout::load(&ds, &p, config(), Arc::new(NullSink)).unwrap();
    layout.settle();
    assert_eq!(note(&ds, usv1), "");
    ds.set(usv1, "fuel", Value::Float(0.1)).unwrap();
    for _ in 0..20 {
        layout.settle();
        if !note(&ds, usv1).is_empty() {
            break;
        }
    }
    assert_eq!(note(&ds, usv1), "fuel 0.1");
}

#[test]
fn a_script_error_is_an_alert_naming_the_file_line_and_column_of_the_script_in_the_layout() {
    let ds = DataServer::default();
    vehicle(&ds, "usv1");
    let sink = Arc::new(MemorySink::default());
    let text = "use \"stdlib/controls.mocu\"\nwindow hud { layer 10 }\nin hud {\n  b: Button {\n    at 10 10 100 30  label \"B\"\n    on press #js: {\n      let a = 1;\n      nosuch.call();\n    }\n  }\n}\n";
    let layout = Layout::load(&ds, &program(text), config(), sink.clone()).unwrap();
    layout.settle();
    press(&ds, &["display", "hud", "b"]);
    layout.settle();
    let alerts = alert_texts(&ds);
    assert_eq!(alerts.len(), 1, "{alerts:?}");
    assert!(alerts[0].contains("test.mocu:8:"), "line 8 of the layout: {}", alerts[0]);
    assert!(alerts[0].contains("nosuch"), "{}", alerts[0]);
    assert_eq!(sink.of("alert").len(), 1, "logged");
}

#[test]
fn a_runaway_script_is_stopped_and_reported_and_the_layout_goes_on() {
    let ds = DataServer::default();
    let usv1 = vehicle(&ds, "usv1");
    let text = r#"
use "stdlib/controls.mocu"
window hud { layer 10 }
in hud {
  spin: Button { at 10 10 100 30  label "SPIN"  on press #rhai: { loop { } } }
  ok: Button { at 10 50 100 30  label "OK"  on press #js: { mocu.write("vehicles.usv1.note", "still here"); } }
}
"#;
    let layout = Layout::load(&ds, &program(text), config(), Arc::new(NullSink)).unwrap();
    layout.settle();
    press(&ds, &["display", "hud", "spin"]);
    layout.settle();
    let alerts = alert_texts(&ds);
    assert_eq!(alerts.len(), 1, "{alerts:?}");
    assert!(alerts[0].contains("operation"), "{}", alerts[0]);
    press(&ds, &["display", "hud", "ok"]);
    layout.settle();
    assert_eq!(note(&ds, usv1), "still here");
}

#[test]
fn a_reload_stops_the_old_scripts_subscriptions_and_runs_the_new_text() {
    let ds = DataServer::default();
    let usv1 = vehicle(&ds, "usv1");
    let with = |word: &str| {
        format!(
            "use \"stdlib/controls.mocu\"\nwindow hud {{ layer 10 }}\nin hud {{ b: Button {{ at 10 10 100 30  label \"B\"  on press #js: {{ mocu.subscribe(\"vehicles.usv1.fuel\", f => mocu.write(\"vehicles.usv1.note\", \"{word} \" + f)); }} }} }}\n"
        )
    };
    let layout = Layout::load(&ds, &program(&with("old")), config(), Arc::new(NullSink)).unwrap();
    layout.settle();
    press(&ds, &["display", "hud", "b"]);
    layout.settle();
    assert_eq!(note(&ds, usv1), "old 1");
    layout.reload(&program(&with("new"))).unwrap();
    layout.settle();
    ds.set(usv1, "fuel", Value::Float(0.5)).unwrap();
    layout.settle();
    assert_eq!(note(&ds, usv1), "old 1", "the old script's subscription ended with it");
    press(&ds, &["display", "hud", "b"]);
    layout.settle();
    assert_eq!(note(&ds, usv1), "new 0.5");
}

#[test]
fn a_script_in_a_for_each_template_sees_its_instances_object_as_self() {
    let ds = DataServer::default();
    let usv1 = vehicle(&ds, "usv1");
    let usv2 = vehicle(&ds, "usv2");
    let p = program(
        r#"
use "stdlib/controls.mocu"
for each v in root.vehicles of type "usv" {
  window strip { layer 10 rect 0 (index * 40) 200 40 }
  in strip { mark: Button { at 0 0 100 30  label "MARK"  on press #js: { mocu.write(self + ".note", "marked " + self); } } }
}
"#,
    );
    let layout = Layout::load(&ds, &p, config(), Arc::new(NullSink)).unwrap();
    layout.settle();
    press(&ds, &["display", "strip@usv2", "mark@usv2"]);
    layout.settle();
    assert_eq!(note(&ds, usv2), "marked root.vehicles.usv2");
    assert_eq!(note(&ds, usv1), "", "only the pressed instance's vehicle");
}
