//! Bindings driven by a virtual gamepad on a virtual clock, through a real layout over the
//! simulator: shaping, bounded writes, events, shift layer, modes, selection, feedback.

mod common;
use common::*;
use mocu_dataserver::Value;
use mocu_input::{DeviceType, EventKind};
use mocu_layout::{JsonlLog, MemorySink, NullSink};
use std::sync::Arc;

const DRIVE: &str = r#"
bind gamepad {
  axis left_y deadzone 0.1 expo 0.5 scale 100 -> set selected.nav.goal_throttle = axis
  axis right_x invert scale 30 -> set selected.nav.goal_rudder = axis
}
"#;

fn sets(sink: &MemorySink) -> usize {
    sink.of("action")
        .iter()
        .filter(|f| f.iter().any(|(k, v)| k == "kind" && *v == Value::str("set")))
        .count()
}

fn calls(sink: &MemorySink) -> Vec<String> {
    sink.of("call")
        .iter()
        .filter_map(|f| f.iter().find(|(k, _)| k == "target").map(|(_, v)| v.to_string()))
        .collect()
}

#[test]
fn the_goal_follows_the_stick_through_deadzone_expo_scale_and_invert() {
    let mut r = rig(DRIVE, 30.0, Arc::new(NullSink));
    r.axis(0, "left_y", 0.08);
    assert_eq!(r.goal("usv1", "goal_throttle"), 0.0, "inside the deadzone");
    r.axis(100, "left_y", 0.55);
    // (0.55 - 0.1) / 0.9 = 0.5; expo 0.5: 0.5·0.5 + 0.5·0.125 = 0.3125; ×100
    assert!((r.goal("usv1", "goal_throttle") - 31.25).abs() < 1e-9);
    r.axis(200, "left_y", -1.0);
    assert_eq!(r.goal("usv1", "goal_throttle"), -100.0);
    r.axis(300, "right_x", 0.5);
    assert_eq!(r.goal("usv1", "goal_rudder"), -15.0, "inverted");
    assert_eq!(r.goal("usv2", "goal_throttle"), 0.0, "only the selected vehicle");
}

#[test]
fn a_moving_stick_writes_at_most_rate_hz_and_only_on_change() {
    let sink = Arc::new(MemorySink::default());
    let mut r = rig(DRIVE, 25.0, sink.clone());
    // One second of a stick sweeping, an event every 2 ms (500 events).
    for i in 0..500u64 {
        r.axis(i * 2, "left_y", 0.2 + 0.8 * (i as f64 / 499.0));
    }
    r.advance(1200);
    let n = sets(&sink);
    assert!(n <= 1 + 25 + 1, "{n} writes for 500 events at 25 Hz");
    assert!(n >= 20, "{n}: the goal kept following");
    assert_eq!(r.goal("usv1", "goal_throttle"), 100.0, "ends on the last position");
    // Holding still: no more writes, however many events repeat the same value.
    for i in 0..100u64 {
        r.axis(1300 + i * 10, "left_y", 1.0);
    }
    r.advance(3000);
    assert_eq!(sets(&sink), n, "equal values write nothing");
    assert_eq!(r.engine.stats().events, 1 + 500 + 100);
}

#[test]
fn a_rate_limit_ramps_the_goal() {
    let text =
        "bind gamepad { axis left_y scale 100 rate 100 -> set selected.nav.goal_throttle = axis }";
    let mut r = rig(text, 50.0, Arc::new(NullSink));
    r.axis(0, "left_y", 1.0);
    r.advance(500);
    let mid = r.goal("usv1", "goal_throttle");
    assert!((40.0..=60.0).contains(&mid), "half way after half a second: {mid}");
    r.advance(1500);
    assert_eq!(r.goal("usv1", "goal_throttle"), 100.0);
}

const BUTTONS: &str = r#"
bind gamepad {
  button south -> call selected.arm(true)
  button south double -> call selected.stop()
  button east hold 500ms -> call selected.start_engine()
  button east release -> call selected.return_home()
}
"#;

#[test]
fn press_release_hold_and_double_press() {
    let sink = Arc::new(MemorySink::default());
    let mut r = rig(BUTTONS, 30.0, sink.clone());
    r.tap(0, "south");
    assert_eq!(calls(&sink), ["root.vehicles.usv1.arm"]);
    r.tap(200, "south");
    assert_eq!(
        calls(&sink)[1..],
        ["root.vehicles.usv1.arm", "root.vehicles.usv1.stop"],
        "second press within 300 ms"
    );
    r.tap(1000, "south");
    assert_eq!(calls(&sink).len(), 4, "a lone press is only a press");
    // A short press of east: release only. A long one: hold at 500 ms, then release.
    r.tap(2000, "east");
    assert_eq!(calls(&sink).last().unwrap(), "root.vehicles.usv1.return_home");
    r.press(3000, "east");
    r.advance(3499);
    assert_eq!(calls(&sink).len(), 5, "not yet held long enough");
    r.advance(3500);
    assert_eq!(calls(&sink).last().unwrap(), "root.vehicles.usv1.start_engine");
    r.advance(5000);
    r.release(5000, "east");
    let c = calls(&sink);
    assert_eq!(c.len(), 7, "the hold fires once: {c:?}");
    r.settle();
}

const LAYERS: &str = r#"
bind gamepad {
  shift left_bumper
  button west -> select next
  shift button west -> select prev
  button select -> mode payload
  button start -> mode drive
  mode drive {
    axis left_y scale 100 -> set selected.nav.goal_throttle = axis
  }
  mode payload {
    axis left_y scale 30 -> set selected.nav.goal_rudder = axis
  }
}
"#;

#[test]
fn shift_layer_modes_and_selection_by_button() {
    let mut r = rig(LAYERS, 30.0, Arc::new(NullSink));
    assert_eq!(r.operator("mode"), Some(Value::str("drive")), "the first mode declared");
    r.axis(0, "left_y", 0.5);
    assert_eq!(r.goal("usv1", "goal_throttle"), 50.0);
    r.tap(100, "select");
    assert_eq!(r.operator("mode"), Some(Value::str("payload")));
    r.axis(200, "left_y", 1.0);
    assert_eq!(r.goal("usv1", "goal_rudder"), 30.0, "payload mode: the same stick, another goal");
    assert_eq!(r.goal("usv1", "goal_throttle"), 50.0, "drive bindings are off");
    r.tap(300, "start");
    r.tap(400, "west");
    assert_eq!(r.selected_name(), "usv2", "select next");
    r.axis(500, "left_y", -0.25);
    assert_eq!(r.goal("usv2", "goal_throttle"), -25.0, "`selected` follows the selection");
    r.press(600, "left_bumper");
    r.tap(700, "west");
    r.release(800, "left_bumper");
    assert_eq!(r.selected_name(), "usv1", "shift + west: select prev");
    r.tap(900, "west");
    r.tap(1000, "west");
    assert_eq!(r.selected_name(), "usv1", "next wraps around");
    assert_eq!(r.operator("selected_name"), Some(Value::str("usv1")));
}

#[test]
fn a_refused_call_shows_refused_with_the_vehicles_reason_on_the_control_in_the_toasts_and_in_the_log()
 {
    let dir = tempfile::tempdir().unwrap();
    let log = dir.path().join("trial.jsonl");
    let sink = Arc::new(JsonlLog::append(&log).unwrap());
    let text = "bind gamepad { button south -> call selected.start_engine() }";
    let mut r = rig(text, 30.0, sink);
    let toasts = mocu_input::Toasts::start(&r.ds, &r.ds.serial_executor(), 5).unwrap();
    r.tap(0, "south");
    r.settle();
    let b1 = r.ds.resolve(&["display", "bindings", "b1"]).unwrap();
    assert_eq!(r.ds.get(b1, "feedback").unwrap(), Value::str("refused"));
    let reason = r.ds.get(b1, "feedback_reason").unwrap().to_string();
    assert!(reason.contains("not armed"), "{reason}");
    let t1 = r.ds.get(r.ds.resolve(&["operator", "toasts"]).unwrap(), "t1").unwrap().to_string();
    assert!(t1.contains("usv1.start_engine: refused") && t1.contains("not armed"), "{t1}");
    assert_eq!(toasts.entries()[0].1, "refused");
    drop(r);
    let text = std::fs::read_to_string(&log).unwrap();
    assert!(text.contains(r#""event":"call""#), "{text}");
    assert!(text.contains(r#""outcome":"refused""#) && text.contains("not armed"), "{text}");
}

#[test]
fn several_gamepads_connect_and_disconnect_at_run_time() {
    let mut r = rig(DRIVE, 30.0, Arc::new(NullSink));
    r.event(
        10,
        "pad2",
        EventKind::Connected {
            device_type: DeviceType::Gamepad,
            name: "Second Pad".into(),
            mapping: "sdl".into(),
        },
    );
    let ds = r.ds.clone();
    let pad = |n: &str| ds.resolve(&["operator", "inputs", n]).unwrap();
    assert_eq!(ds.get(pad("gamepad1"), "name").unwrap(), Value::str("Virtual Pad"));
    assert_eq!(ds.get(pad("gamepad2"), "name").unwrap(), Value::str("Second Pad"));
    assert_eq!(ds.get(pad("gamepad2"), "mapping").unwrap(), Value::str("sdl"));
    r.event(20, "pad2", EventKind::Axis { axis: "left_y".into(), value: 1.0 });
    r.event(30, "pad2", EventKind::Button { button: "south".into(), pressed: true });
    let axes = ds.resolve(&["operator", "inputs", "gamepad2", "axes"]).unwrap();
    let buttons = ds.resolve(&["operator", "inputs", "gamepad2", "buttons"]).unwrap();
    assert_eq!(ds.get(axes, "left_y").unwrap(), Value::Float(1.0));
    assert_eq!(ds.get(buttons, "south").unwrap(), Value::Bool(true));
    assert_eq!(r.goal("usv1", "goal_throttle"), 100.0, "either pad drives");
    // The pad falls off with the stick forward: the goal goes back to 0, buttons up.
    r.event(100, "pad2", EventKind::Disconnected);
    r.advance(200);
    assert_eq!(ds.get(pad("gamepad2"), "connected").unwrap(), Value::Bool(false));
    assert_eq!(ds.get(buttons, "south").unwrap(), Value::Bool(false));
    assert_eq!(r.goal("usv1", "goal_throttle"), 0.0);
    // Reconnecting reuses its object.
    r.event(
        300,
        "pad2",
        EventKind::Connected {
            device_type: DeviceType::Gamepad,
            name: "Second Pad".into(),
            mapping: "sdl".into(),
        },
    );
    assert_eq!(ds.get(pad("gamepad2"), "connected").unwrap(), Value::Bool(true));
    assert!(ds.resolve(&["operator", "inputs", "gamepad3"]).is_none());
}

#[test]
fn with_nothing_selected_a_goal_write_is_refused_feedback_not_a_crash() {
    let sink = Arc::new(MemorySink::default());
    let mut r = rig(DRIVE, 30.0, sink.clone());
    let op = r.ds.resolve(&["operator"]).unwrap();
    r.ds.delete_property(op, "selected").unwrap();
    r.axis(0, "left_y", 1.0);
    let fb = sink.of("feedback");
    let text = format!("{fb:?}");
    assert!(text.contains("refused") && text.contains("nothing selected"), "{text}");
}

#[test]
fn the_stdlib_toast_list_shows_the_latest_outcomes_by_default() {
    let text = r#"
      use "stdlib/alerts.mocu"
      window hud { layer 10 rect 0 0 100% 100% }
      in hud { toasts: ToastList { at 20 160 560 96 } }
      bind gamepad { button south -> call selected.start_engine() }
    "#;
    let mut r = rig(text, 30.0, Arc::new(NullSink));
    let _toasts = mocu_input::Toasts::start(&r.ds, &r.ds.serial_executor(), 5).unwrap();
    r.tap(0, "south");
    r.settle();
    let w = r.ds.resolve(&["display", "hud", "toasts"]).unwrap();
    let props = r.ds.properties(w).unwrap();
    let first =
        r.ds.get(w, "first").map(|v| v.to_string()).unwrap_or_else(|_| format!("{props:?}"));
    assert!(first.contains("refused"), "{first}");
    assert_eq!(r.ds.get(w, "critical1").unwrap(), Value::Bool(true), "refused is red");
}
