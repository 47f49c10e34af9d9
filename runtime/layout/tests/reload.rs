//! Incremental reload: unchanged items keep their objects, subscriptions and state.
mod common;
use common::{config, program};
use mocu_dataserver::*;
use mocu_layout::*;
use std::sync::Arc;
use std::time::Duration;

const BASE: &str = r#"
use "stdlib/gauges.mocu"
use "stdlib/controls.mocu"
window hud { layer 10 rect 0 0 100% 100% }
window map { type "map" layer 5 rect 75% 70% 24% 28% }
in hud {
  speed: Dial { at 40 40 160 160  value root.v.speed  range 0 .. 40 }
  fuel: Bar { at 40 220 160 16  value root.v.fuel }
  arm: Button { at 40 260 120 32  label "ARM"  on press call root.v.arm() }
}
watch slow { when root.v.speed < 1 for 10s then alert warning "slow" }
"#;

fn setup() -> (DataServer, Guid, Layout) {
    let ds = DataServer::default();
    let v = ds.create_object(Guid::ROOT, ObjectInfo::new("v", "usv")).unwrap();
    ds.set(v, "speed", Value::Float(0.5)).unwrap();
    ds.set(v, "fuel", Value::Float(0.7)).unwrap();
    ds.publish_method_fn(v, MethodSpec::new("arm"), |_| CallOutcome::Refused("no".into())).unwrap();
    let layout = Layout::load(&ds, &program(BASE), config(), Arc::new(NullSink)).unwrap();
    layout.settle();
    (ds, v, layout)
}

fn find(ds: &DataServer, path: &[&str]) -> Guid {
    ds.resolve(path).unwrap_or_else(|| panic!("no {path:?}"))
}

#[test]
fn reloading_the_same_program_changes_nothing() {
    let (ds, _v, layout) = setup();
    let before = ds.snapshot(Guid::ROOT).unwrap();
    let subs = ds.subscription_count();
    let stats = layout.reload(&program(BASE)).unwrap();
    layout.settle();
    assert_eq!(stats, ReloadStats { kept: 7, ..ReloadStats::default() });
    assert_eq!(ds.snapshot(Guid::ROOT).unwrap(), before);
    assert_eq!(ds.subscription_count(), subs);
}

#[test]
fn a_changed_widget_is_republished_and_the_others_keep_their_objects_and_state() {
    let (ds, _v, layout) = setup();
    let speed = find(&ds, &["display", "hud", "speed"]);
    let arm = find(&ds, &["display", "hud", "arm"]);
    ds.call_wait(arm, "press", vec![], None);
    layout.settle();
    assert_eq!(ds.get(arm, "feedback").unwrap(), Value::str("refused"));
    // Moving lines around (new source positions) and changing only the bar.
    let edited = BASE
        .replace("value root.v.fuel }", "value root.v.fuel  label \"FUEL\" }")
        .replace("window hud", "\n\nwindow hud");
    let stats = layout.reload(&program(&edited)).unwrap();
    layout.settle();
    assert_eq!(stats, ReloadStats { kept: 6, changed: 1, ..ReloadStats::default() });
    assert_eq!(find(&ds, &["display", "hud", "speed"]), speed, "same object");
    assert_eq!(find(&ds, &["display", "hud", "arm"]), arm);
    assert_eq!(ds.get(arm, "feedback").unwrap(), Value::str("refused"), "state kept");
    let fuel = find(&ds, &["display", "hud", "fuel"]);
    assert_eq!(ds.get(fuel, "label").unwrap(), Value::str("FUEL"));
    assert_eq!(ds.get(fuel, "value").unwrap(), Value::Float(0.7), "bound at once");
}

#[test]
fn a_changed_window_keeps_its_object_and_its_widgets() {
    let (ds, _v, layout) = setup();
    let hud = find(&ds, &["display", "hud"]);
    let speed = find(&ds, &["display", "hud", "speed"]);
    let edited = BASE.replace("window hud { layer 10", "window hud { layer 12");
    let stats = layout.reload(&program(&edited)).unwrap();
    layout.settle();
    assert_eq!(stats.changed, 1);
    assert_eq!(find(&ds, &["display", "hud"]), hud);
    assert_eq!(find(&ds, &["display", "hud", "speed"]), speed);
    assert_eq!(ds.get(hud, "layer").unwrap(), Value::Float(12.0));
}

#[test]
fn removed_items_are_torn_down_with_their_subscriptions_and_added_ones_appear() {
    let (ds, v, layout) = setup();
    let edited = BASE.replace("  fuel: Bar { at 40 220 160 16  value root.v.fuel }\n", "").replace(
        "window map { type \"map\" layer 5 rect 75% 70% 24% 28% }",
        "window other { layer 20 rect 0 0 10 10 }",
    );
    let stats = layout.reload(&program(&edited)).unwrap();
    layout.settle();
    assert_eq!(stats, ReloadStats { kept: 5, added: 1, removed: 2, changed: 0 });
    assert!(ds.resolve(&["display", "hud", "fuel"]).is_none());
    assert!(ds.resolve(&["display", "map"]).is_none());
    assert!(ds.resolve(&["display", "other"]).is_some());
    // fuel is read by nobody now: its path watch is gone.
    assert_eq!(layout.stats().paths, 1, "only root.v.speed is still read");
    ds.set(v, "fuel", Value::Float(0.1)).unwrap();
    layout.settle();
}

#[test]
fn a_watch_that_did_not_change_keeps_its_hold_timer() {
    // The server's clock is manual: the hold timer fires exactly when the test says.
    let clock = ManualClock::new();
    let ds = DataServer::with_clock(Config::default(), Arc::new(clock.clone()));
    let v = ds.create_object(Guid::ROOT, ObjectInfo::new("v", "usv")).unwrap();
    ds.set(v, "speed", Value::Float(5.0)).unwrap();
    let sink = Arc::new(MemorySink::default());
    let text = "watch slow { when root.v.speed < 1 for 600ms then alert warning \"slow\" }\nwindow w { layer 1 rect 0 0 10 10 }";
    let layout = Layout::load(&ds, &program(text), config(), sink.clone()).unwrap();
    ds.set(v, "speed", Value::Float(0.5)).unwrap();
    layout.settle();
    let watch = find(&ds, &["operator", "watches", "slow"]);
    assert_eq!(ds.get(watch, "state").unwrap(), Value::str("holding"));
    clock.advance(Duration::from_millis(400));
    layout.settle();
    layout.reload(&program(&text.replace("rect 0 0 10 10", "rect 0 0 20 20"))).unwrap();
    layout.settle();
    assert_eq!(find(&ds, &["operator", "watches", "slow"]), watch, "the watch was kept");
    // The original timer has 200 ms left; a restarted one would need 600 ms.
    clock.advance(Duration::from_millis(199));
    layout.settle();
    assert!(sink.of("alert").is_empty(), "not before the original 600 ms");
    clock.advance(Duration::from_millis(1));
    layout.settle();
    assert!(!sink.of("alert").is_empty(), "fired on the original timer, not a restarted one");
}

#[test]
fn a_refused_reload_never_touches_the_world_model() {
    let (ds, _v, layout) = setup();
    let before = ds.snapshot(Guid::ROOT).unwrap();
    let mut bad = program(BASE);
    // A widget in a window that does not exist: refused at publication, before any change.
    bad.windows.retain(|w| w.name != "hud");
    let _ = layout.reload(&bad);
    layout.settle();
    let after = ds.snapshot(Guid::ROOT).unwrap();
    // Whatever was refused, the vehicle and its values are untouched.
    let v = |s: &Snapshot| s.children.iter().find(|c| c.name == "v").cloned();
    assert_eq!(v(&before), v(&after));
}
