//! Layouts running live against the DataServer through compiled code.
mod common;
use common::program;
use mocu_dataserver::*;
use mocu_layout::*;
use std::sync::Arc;
use std::time::Duration;

/// Checks a layout written in a temporary file (so `use "stdlib/…"` resolves).
fn config(jit: bool) -> LayoutConfig {
    LayoutConfig { tick: Duration::from_millis(1), jit, ..LayoutConfig::default() }
}

fn vehicle(ds: &DataServer, name: &str) -> (Guid, Guid) {
    let vs = ds.resolve(&["vehicles"]).unwrap_or_else(|| {
        ds.create_object(Guid::ROOT, ObjectInfo::new("vehicles", "folder")).unwrap()
    });
    let v = ds.create_object(vs, ObjectInfo::new(name, "usv")).unwrap();
    let nav = ds.create_object(v, ObjectInfo::new("nav", "nav")).unwrap();
    ds.set(v, "name", Value::str(name)).unwrap();
    (v, nav)
}

const GAUGE: &str = r#"
use "stdlib/gauges.mocu"
let usv = root.vehicles.usv1
window hud { layer 10 rect 0 0 100% 100% }
in hud {
  speed: Dial { at 40 40 160 160  value usv.nav.speed * 1.94384  range 0 .. 40  units "kn"  alarm value > 35 }
  heading: Label { at 220 40  text "HDG {usv.nav.heading:03.0}°" }
}
"#;

fn widget(ds: &DataServer, window: &str, name: &str) -> Guid {
    ds.resolve(&["display", window, name]).expect("widget published")
}

#[test]
fn a_gauge_follows_its_vehicle_property_through_compiled_code() {
    for jit in [true, false] {
        let ds = DataServer::default();
        let layout = Layout::load(&ds, &program(GAUGE), config(jit), Arc::new(NullSink)).unwrap();
        layout.settle();
        let dial = widget(&ds, "hud", "speed");
        assert_eq!(ds.try_get(dial, "value".into()), None, "absent before the vehicle exists");
        assert_eq!(ds.get(dial, "range.max").unwrap(), Value::Float(40.0));
        assert_eq!(ds.get(dial, "alarm").ok(), None, "alarm reads an absent value: absent");
        let (_v, nav) = vehicle(&ds, "usv1");
        ds.set(nav, "speed", Value::Float(10.0)).unwrap();
        ds.set(nav, "heading", Value::Float(7.4)).unwrap();
        layout.settle();
        assert_eq!(ds.get(dial, "value").unwrap(), Value::Float(10.0 * 1.94384));
        assert_eq!(ds.get(dial, "alarm").unwrap(), Value::Bool(false));
        let label = widget(&ds, "hud", "heading");
        assert_eq!(ds.get(label, "text").unwrap(), Value::str("HDG 007°"));
        ds.set(nav, "speed", Value::Float(20.0)).unwrap();
        layout.settle();
        assert_eq!(ds.get(dial, "alarm").unwrap(), Value::Bool(true));
    }
}

#[test]
fn windows_are_published_with_resolved_rectangles() {
    let ds = DataServer::default();
    let p = program("window map { type \"map\" layer 5 rect 75% 70% 24% 28% opacity 0.5 }");
    let _layout = Layout::load(&ds, &p, config(true), Arc::new(NullSink)).unwrap();
    let map = ds.resolve(&["display", "map"]).unwrap();
    assert_eq!(ds.info(map).unwrap().subtype.as_ref(), "map");
    assert_eq!(ds.get(map, "x").unwrap(), Value::Float(1440.0));
    assert_eq!(ds.get(map, "h").unwrap(), Value::Float(1080.0 * 0.28));
    assert_eq!(ds.get(map, "layer").unwrap(), Value::Float(5.0));
    assert_eq!(ds.get(map, "opacity").unwrap(), Value::Float(0.5));
    assert_eq!(ds.get(map, "visible").unwrap(), Value::Bool(true));
}

#[test]
fn changes_that_arrive_together_are_evaluated_once_per_tick() {
    let ds = DataServer::default();
    let (_v, nav) = vehicle(&ds, "usv1");
    let cfg = LayoutConfig { tick: Duration::from_millis(200), ..config(true) };
    let layout = Layout::load(&ds, &program(GAUGE), cfg, Arc::new(NullSink)).unwrap();
    layout.settle();
    let before = layout.stats().evaluations;
    for i in 0..500 {
        ds.set(nav, "speed", Value::Float(i as f64)).unwrap();
    }
    ds.quiesce();
    layout.flush();
    let evals = layout.stats().evaluations - before;
    assert_eq!(evals, 1, "500 writes, one evaluation of the one gauge that reads speed");
    assert_eq!(
        ds.get(widget(&ds, "hud", "speed"), "value").unwrap(),
        Value::Float(499.0 * 1.94384)
    );
}

#[test]
fn only_expressions_that_read_a_changed_path_are_evaluated() {
    let ds = DataServer::default();
    let (_v, nav) = vehicle(&ds, "usv1");
    let layout = Layout::load(&ds, &program(GAUGE), config(true), Arc::new(NullSink)).unwrap();
    ds.set(nav, "heading", Value::Float(1.0)).unwrap();
    layout.settle();
    let before = layout.stats().evaluations;
    ds.set(nav, "heading", Value::Float(2.0)).unwrap();
    layout.settle();
    assert_eq!(layout.stats().evaluations - before, 1, "the label, not the dial");
}

#[test]
fn an_equal_result_stops_there_and_notifies_nobody() {
    let ds = DataServer::default();
    let (_v, nav) = vehicle(&ds, "usv1");
    let p = program(
        "use \"stdlib/gauges.mocu\"\nwindow w { layer 1 rect 0 0 10 10 }\nin w { l: Label { at 0 0  text if root.vehicles.usv1.nav.speed > 5 then \"FAST\" else \"SLOW\" } }",
    );
    let layout = Layout::load(&ds, &p, config(true), Arc::new(NullSink)).unwrap();
    ds.set(nav, "speed", Value::Float(1.0)).unwrap();
    layout.settle();
    let label = widget(&ds, "w", "l");
    let changes = Arc::new(std::sync::atomic::AtomicUsize::new(0));
    let c = changes.clone();
    ds.subscribe(Topic::property_names(label, &["text"]), move |n: &Notification| {
        if n.kind == Kind::Changed {
            c.fetch_add(1, std::sync::atomic::Ordering::SeqCst);
        }
    })
    .unwrap();
    for s in [2.0, 3.0, 4.0] {
        ds.set(nav, "speed", Value::Float(s)).unwrap();
        layout.settle();
    }
    assert_eq!(changes.load(std::sync::atomic::Ordering::SeqCst), 0);
    ds.set(nav, "speed", Value::Float(9.0)).unwrap();
    layout.settle();
    assert_eq!(changes.load(std::sync::atomic::Ordering::SeqCst), 1);
}

#[test]
fn each_distinct_path_is_subscribed_once() {
    let ds = DataServer::default();
    let p = program(
        "use \"stdlib/gauges.mocu\"\nwindow w { layer 1 rect 0 0 10 10 }\nin w {\n a: Label { at 0 0 text \"{root.v.x}\" }\n b: Label { at 0 9 text \"{root.v.x} {root.v.y}\" }\n}",
    );
    let layout = Layout::load(&ds, &p, config(true), Arc::new(NullSink)).unwrap();
    assert_eq!(layout.stats().paths, 2);
}

#[test]
fn with_nothing_changing_the_runtime_does_no_work() {
    let clock = ManualClock::new();
    let ds = DataServer::with_clock(Config::default(), Arc::new(clock.clone()));
    let (_v, nav) = vehicle(&ds, "usv1");
    let p = program(&format!(
        "{GAUGE}\nwatch fast {{ when usv.nav.speed > 30 for 50ms then alert warning \"fast\" }}"
    ));
    let layout = Layout::load(&ds, &p, config(true), Arc::new(NullSink)).unwrap();
    ds.set(nav, "speed", Value::Float(1.0)).unwrap();
    layout.settle();
    clock.advance(Duration::from_millis(10)); // the tick already posted
    layout.settle();
    let (evals, fired, jobs) = (
        layout.stats().evaluations,
        ds.stats().timer_fired.load(std::sync::atomic::Ordering::SeqCst),
        ds.stats().jobs_run.load(std::sync::atomic::Ordering::SeqCst),
    );
    clock.advance(Duration::from_millis(300)); // fires whatever would be due by then
    ds.quiesce();
    assert_eq!(layout.stats().evaluations, evals, "no evaluation while idle");
    assert_eq!(
        ds.stats().timer_fired.load(std::sync::atomic::Ordering::SeqCst),
        fired,
        "no timer wake-up while idle"
    );
    assert_eq!(
        ds.stats().jobs_run.load(std::sync::atomic::Ordering::SeqCst),
        jobs,
        "no work at all"
    );
    assert_eq!(ds.pending_timers(), 0);
}

#[test]
fn unloading_removes_every_object_and_subscription_even_after_a_thousand_cycles() {
    let ds = DataServer::default();
    let (_v, nav) = vehicle(&ds, "usv1");
    ds.set(nav, "speed", Value::Float(3.0)).unwrap();
    let p = program(GAUGE);
    ds.quiesce();
    let subs = ds.subscription_count();
    for i in 0..1000 {
        let layout = Layout::load(&ds, &p, config(i % 2 == 0), Arc::new(NullSink)).unwrap();
        if i % 100 == 0 {
            layout.settle();
            assert!(ds.subscription_count() > subs);
        }
        layout.unload();
    }
    ds.quiesce();
    assert_eq!(ds.subscription_count(), subs);
    let display = ds.resolve(&["display"]).unwrap();
    assert!(ds.children(display).unwrap().is_empty());
}

#[test]
fn a_watch_fires_after_its_hold_time_and_clears_when_the_condition_ends() {
    let clock = ManualClock::new();
    let ds = DataServer::with_clock(Config::default(), Arc::new(clock.clone()));
    let (v, _nav) = vehicle(&ds, "usv1");
    ds.set(v, "fuel", Value::Float(0.9)).unwrap();
    let sink = Arc::new(MemorySink::default());
    let p = program(
        "let usv = root.vehicles.usv1\nwatch low_fuel { when usv.fuel < 0.15 for 150ms then alert warning \"Fuel low on {usv.name}\" }",
    );
    let layout = Layout::load(&ds, &p, config(true), sink.clone()).unwrap();
    layout.settle();
    let watch = ds.resolve(&["operator", "watches", "low_fuel"]).unwrap();
    ds.set(v, "fuel", Value::Float(0.1)).unwrap();
    layout.settle();
    assert_eq!(ds.get(watch, "state").unwrap(), Value::str("holding"));
    // A blip back above the threshold restarts the hold time.
    ds.set(v, "fuel", Value::Float(0.2)).unwrap();
    layout.settle();
    ds.set(v, "fuel", Value::Float(0.1)).unwrap();
    layout.settle();
    clock.advance(Duration::from_millis(80));
    layout.settle();
    assert!(sink.of("alert").is_empty(), "not before the hold time");
    clock.advance(Duration::from_millis(80));
    settle_until(&layout, || !sink.of("alert").is_empty());
    assert_eq!(sink.of("alert").len(), 1, "fired once the hold time is over");
    let alerts = ds.resolve(&["operator", "alerts"]).unwrap();
    let a = ds.children(alerts).unwrap()[0];
    assert_eq!(ds.get(a, "text").unwrap(), Value::str("Fuel low on usv1"));
    assert_eq!(ds.get(a, "severity").unwrap(), Value::str("warning"));
    assert_eq!(ds.get(a, "active").unwrap(), Value::Bool(true));
    assert!(ds.call_wait(a, "acknowledge", vec![], None).is_accepted());
    assert_eq!(ds.get(a, "acknowledged").unwrap(), Value::Bool(true));
    ds.set(v, "fuel", Value::Float(0.5)).unwrap();
    layout.settle();
    assert_eq!(ds.get(a, "active").unwrap(), Value::Bool(false));
    assert_eq!(sink.of("alert_cleared").len(), 1);
    assert_eq!(sink.of("alert").len(), 1, "edge-triggered: fired once");
}

#[test]
fn a_button_press_calls_the_method_and_shows_its_feedback() {
    let ds = DataServer::default();
    let (v, _nav) = vehicle(&ds, "usv1");
    let ds2 = ds.clone();
    ds.publish_method_fn(v, MethodSpec::new("start_engine"), move |_| {
        if ds2.try_get(v, "engine".into()) == Some(Value::Bool(true)) {
            CallOutcome::Refused("engine already running".into())
        } else {
            ds2.set(v, "engine", Value::Bool(true)).unwrap();
            CallOutcome::Accepted(vec![])
        }
    })
    .unwrap();
    let sink = Arc::new(MemorySink::default());
    let p = program(
        "use \"stdlib/controls.mocu\"\nwindow hud { layer 1 rect 0 0 100% 100% }\nin hud { engine: Button { at 0 0 100 30 label \"ENGINE\" on press call root.vehicles.usv1.start_engine() } }",
    );
    let layout = Layout::load(&ds, &p, config(true), sink.clone()).unwrap();
    layout.settle();
    let button = widget(&ds, "hud", "engine");
    assert!(ds.call_wait(button, "press", vec![], None).is_accepted());
    layout.settle();
    assert_eq!(ds.get(button, "feedback").unwrap(), Value::str("accepted"));
    ds.call_wait(button, "press", vec![], None);
    layout.settle();
    assert_eq!(ds.get(button, "feedback").unwrap(), Value::str("refused"));
    assert_eq!(ds.get(button, "feedback_reason").unwrap(), Value::str("engine already running"));
    let fb = ds.resolve(&["operator", "feedback"]).unwrap();
    assert_eq!(ds.get(fb, "state").unwrap(), Value::str("refused"));
    let outcomes: Vec<Value> = sink
        .of("feedback")
        .iter()
        .map(|f| f.iter().find(|(k, _)| k == "outcome").unwrap().1.clone())
        .collect();
    assert_eq!(outcomes, [Value::str("accepted"), Value::str("refused")]);
    assert_eq!(sink.of("call").len(), 2);
}

#[test]
fn a_binding_writes_a_goal_and_a_refused_write_becomes_feedback() {
    let ds = DataServer::default();
    let (_v, nav) = vehicle(&ds, "usv1");
    ds.create_property(
        nav,
        "goal_throttle",
        Value::Float(0.0),
        PropMeta::typed(ValueKind::Float).range(-100.0, 100.0),
    )
    .unwrap();
    let sink = Arc::new(MemorySink::default());
    let p = program(
        "bind gamepad { axis left_y -> set root.vehicles.usv1.nav.goal_throttle = deadzone(axis, 0.1) * 100 }\nbind keyboard { key w -> set root.vehicles.usv1.nav.goal_throttle = 500 }",
    );
    let layout = Layout::load(&ds, &p, config(true), sink.clone()).unwrap();
    let bindings = ds.resolve(&["display", "bindings"]).unwrap();
    // Each binding is an object (device, kind, input, …) with a `fire(value)` method.
    let binding = |input: &str| {
        ds.children(bindings)
            .unwrap()
            .into_iter()
            .find(|b| ds.try_get(*b, "input".into()) == Some(Value::str(input)))
            .unwrap()
    };
    assert!(ds.call_wait(binding("left_y"), "fire", vec![Value::Float(1.0)], None).is_accepted());
    assert_eq!(ds.get(nav, "goal_throttle").unwrap(), Value::Float(100.0));
    ds.call_wait(binding("w"), "fire", vec![Value::Float(1.0)], None);
    assert_eq!(ds.get(nav, "goal_throttle").unwrap(), Value::Float(100.0), "out of range: refused");
    let fb = sink.of("feedback");
    let reason = fb[0].iter().find(|(k, _)| k == "reason").unwrap().1.to_string();
    assert!(reason.contains("goal_throttle") && reason.contains("range"), "{reason}");
    drop(layout);
}

#[test]
fn a_template_gives_each_discovered_vehicle_its_own_strip() {
    let ds = DataServer::default();
    let p = program(
        "use \"stdlib/gauges.mocu\"\nfor each v in root.vehicles of type \"usv\" {\n  window strip { layer 30 rect 20 (20 + index * 130) 420 120 }\n  in strip { speed: TextGauge { at 8 28 200 26 label \"SPD\" value v.nav.speed } }\n}",
    );
    let layout = Layout::load(&ds, &p, config(true), Arc::new(NullSink)).unwrap();
    let (_a, nav_a) = vehicle(&ds, "usv1");
    let (_b, nav_b) = vehicle(&ds, "usv2");
    let vs = ds.resolve(&["vehicles"]).unwrap();
    ds.create_object(vs, ObjectInfo::new("uav1", "uav")).unwrap();
    ds.set(nav_a, "speed", Value::Float(1.0)).unwrap();
    ds.set(nav_b, "speed", Value::Float(2.0)).unwrap();
    layout.settle();
    assert_eq!(layout.stats().instances, 2, "usv1 and usv2, not the uav");
    let s2 = ds.resolve(&["display", "strip@usv2"]).unwrap();
    assert_eq!(ds.get(s2, "y").unwrap(), Value::Float(150.0), "second in order");
    let g = ds.resolve(&["display", "strip@usv2", "speed@usv2"]).unwrap();
    assert_eq!(ds.get(g, "value").unwrap(), Value::Float(2.0));
    let usv1 = ds.resolve(&["vehicles", "usv1"]).unwrap();
    ds.delete_object(usv1).unwrap();
    layout.settle();
    assert_eq!(layout.stats().instances, 1);
    assert!(ds.resolve(&["display", "strip@usv1"]).is_none());
    assert_eq!(ds.get(s2, "y").unwrap(), Value::Float(20.0), "moves up when the first goes");
}

/// Settles (a bounded number of rounds, no clock) until `f` holds: actions of a watch run
/// on the layout's executor after the evaluation that fired it.
fn settle_until(layout: &Layout, mut f: impl FnMut() -> bool) {
    for _ in 0..50 {
        if f() {
            return;
        }
        layout.settle();
    }
    assert!(f(), "still not so after 50 settles");
}

#[test]
fn a_watch_with_clear_when_stays_active_until_the_clear_condition_holds() {
    let ds = DataServer::default();
    let (v, _nav) = vehicle(&ds, "usv1");
    ds.set(v, "temp", Value::Float(50.0)).unwrap();
    let sink = Arc::new(MemorySink::default());
    let p = program(
        "watch hot { when root.vehicles.usv1.temp > 90 clear when root.vehicles.usv1.temp < 70 then alert warning \"hot\" }",
    );
    let layout = Layout::load(&ds, &p, config(true), sink.clone()).unwrap();
    let watch = ds.resolve(&["operator", "watches", "hot"]).unwrap();
    for t in [95.0, 85.0, 91.0, 80.0] {
        ds.set(v, "temp", Value::Float(t)).unwrap();
        layout.settle();
    }
    assert_eq!(ds.get(watch, "state").unwrap(), Value::str("active"), "85 and 80 are in the band");
    assert_eq!(sink.of("alert").len(), 1, "no chattering around the threshold");
    ds.set(v, "temp", Value::Float(60.0)).unwrap();
    layout.settle();
    assert_eq!(ds.get(watch, "state").unwrap(), Value::str("idle"));
    ds.set(v, "temp", Value::Float(95.0)).unwrap();
    layout.settle();
    settle_until(&layout, || sink.of("alert").len() == 2);
}

// Repeats and snooze on a manual clock: tests/snooze.rs.

#[test]
fn an_interpolated_label_shows_a_dash_for_each_absent_part_and_keeps_the_rest() {
    for jit in [true, false] {
        let ds = DataServer::default();
        let p = program(
            "use \"stdlib/gauges.mocu\"\nlet usv = root.vehicles.usv1\nwindow w { layer 1 rect 0 0 10 10 }\nin w {\n hdg: Label { at 0 0 text \"HDG {usv.nav.heading:03.0}° {usv.name}\" }\n sum: Label { at 0 20 text \"{usv.nav.heading + 1:.1}\" }\n}",
        );
        let layout = Layout::load(&ds, &p, config(jit), Arc::new(NullSink)).unwrap();
        layout.settle();
        let hdg = widget(&ds, "w", "hdg");
        let sum = widget(&ds, "w", "sum");
        assert_eq!(ds.get(hdg, "text").unwrap(), Value::str("HDG —° —"), "jit {jit}");
        assert_eq!(ds.get(sum, "text").unwrap(), Value::str("—"), "jit {jit}");
        let (_v, nav) = vehicle(&ds, "usv1");
        layout.settle();
        assert_eq!(ds.get(hdg, "text").unwrap(), Value::str("HDG —° usv1"), "jit {jit}");
        ds.set(nav, "heading", Value::Float(7.4)).unwrap();
        layout.settle();
        assert_eq!(ds.get(hdg, "text").unwrap(), Value::str("HDG 007° usv1"), "jit {jit}");
        assert_eq!(ds.get(sum, "text").unwrap(), Value::str("8.4"), "jit {jit}");
    }
}
