//! Stale means old, not unchanged: a widget is stale while a vehicle it reads from says its
//! data is old (`stale` / `link_lost`), whatever its values do.
mod common;
use common::{config, program};
use mocu_dataserver::*;
use mocu_layout::*;
use std::sync::Arc;
use std::time::Duration;

const STRIPS: &str = r#"
use "stdlib/gauges.mocu"
window hud { layer 10 rect 0 0 100% 100% }
in hud {
  speed: TextGauge { at 10 10 200 26  label "SPD"  value root.vehicles.usv1.nav.speed }
  both: TextGauge { at 10 40 200 26  label "SUM"  value root.vehicles.usv1.nav.speed + root.vehicles.usv2.nav.speed }
  fixed: TextGauge { at 10 70 200 26  label "K"  value 3 }
}
for each v in root.vehicles of type "usv" {
  window strip { layer 20  rect 300 (10 + index * 40) 200 30 }
  in strip { fuel: Bar { at 0 0 200 16  value v.fuel } }
}
"#;

fn usv(ds: &DataServer, name: &str) -> (Guid, Guid) {
    let vs = ds.resolve(&["vehicles"]).unwrap_or_else(|| {
        ds.create_object(Guid::ROOT, ObjectInfo::new("vehicles", "folder")).unwrap()
    });
    let v = ds.create_object(vs, ObjectInfo::new(name, "usv")).unwrap();
    let nav = ds.create_object(v, ObjectInfo::new("nav", "nav")).unwrap();
    ds.set(v, "stale", Value::Bool(false)).unwrap();
    ds.set(v, "link_lost", Value::Bool(false)).unwrap();
    ds.set(v, "fuel", Value::Float(0.5)).unwrap();
    ds.set(nav, "speed", Value::Float(0.0)).unwrap();
    (v, nav)
}

fn stale(ds: &DataServer, path: &[&str]) -> Option<Value> {
    ds.try_get(ds.resolve(path).expect("widget"), "stale".into())
}

#[test]
fn a_stopped_vehicle_with_a_good_link_is_never_stale_and_a_lost_link_makes_its_widgets_stale() {
    let ds = DataServer::default();
    let layout = Layout::load(&ds, &program(STRIPS), config(), Arc::new(NullSink)).unwrap();
    let (v1, nav1) = usv(&ds, "usv1");
    let (v2, _) = usv(&ds, "usv2");
    layout.settle();
    for _ in 0..5 {
        ds.set(nav1, "speed", Value::Float(0.0)).unwrap(); // the same value, again and again
        layout.settle();
    }
    let speed = ["display", "hud", "speed"];
    let both = ["display", "hud", "both"];
    assert_eq!(stale(&ds, &speed), Some(Value::Bool(false)));
    assert_eq!(stale(&ds, &["display", "hud", "fixed"]), None, "reads no vehicle");
    ds.set(v2, "link_lost", Value::Bool(true)).unwrap();
    layout.settle();
    assert_eq!(stale(&ds, &speed), Some(Value::Bool(false)), "usv2's link is not usv1's");
    assert_eq!(stale(&ds, &both), Some(Value::Bool(true)), "reads usv2 too");
    ds.set(v1, "stale", Value::Bool(true)).unwrap();
    layout.settle();
    assert_eq!(stale(&ds, &speed), Some(Value::Bool(true)));
    ds.set(v1, "stale", Value::Bool(false)).unwrap();
    layout.settle();
    assert_eq!(stale(&ds, &speed), Some(Value::Bool(false)), "fresh again when the link is back");
}

#[test]
fn a_template_instance_is_stale_with_its_own_vehicle_only() {
    let ds = DataServer::default();
    let layout = Layout::load(&ds, &program(STRIPS), config(), Arc::new(NullSink)).unwrap();
    let (_v1, _) = usv(&ds, "usv1");
    let (v2, _) = usv(&ds, "usv2");
    layout.settle();
    ds.set(v2, "stale", Value::Bool(true)).unwrap();
    layout.settle();
    assert_eq!(stale(&ds, &["display", "strip@usv1", "fuel@usv1"]), Some(Value::Bool(false)));
    assert_eq!(stale(&ds, &["display", "strip@usv2", "fuel@usv2"]), Some(Value::Bool(true)));
}

/// A vehicle that declares `stale_after` (its module's period): a widget is `aged` once a
/// number it reads has received no write for that long — an unchanged write keeps it fresh.
/// Time is the DataServer's manual clock.
#[test]
fn data_that_stops_arriving_ages_after_its_vehicles_declared_period_and_unchanged_writes_keep_or_make_it_fresh()
 {
    let clock = Arc::new(ManualClock::new());
    let ds = DataServer::with_clock(Config { workers: 2 }, clock.clone());
    let (v1, nav1) = usv(&ds, "usv1");
    ds.set(v1, "stale_after", Value::Float(1.0)).unwrap();
    let layout = Layout::load(&ds, &program(STRIPS), config(), Arc::new(NullSink)).unwrap();
    layout.settle();
    let speed = ["display", "hud", "speed"];
    let aged = |ds: &DataServer| ds.try_get(ds.resolve(&speed).unwrap(), "aged".into());
    assert_ne!(aged(&ds), Some(Value::Bool(true)));
    for _ in 0..4 {
        clock.advance(Duration::from_millis(600));
        ds.set(nav1, "speed", Value::Float(0.0)).unwrap(); // the same value: still received
        layout.settle();
        assert_ne!(aged(&ds), Some(Value::Bool(true)), "written every 0.6 s: fresh");
    }
    clock.advance(Duration::from_millis(1100));
    layout.settle();
    assert_eq!(aged(&ds), Some(Value::Bool(true)), "nothing for 1.1 s: aged");
    clock.advance(Duration::from_secs(60));
    layout.settle();
    assert_eq!(aged(&ds), Some(Value::Bool(true)), "still nothing: still aged");
    // The publisher resumes with the same value (a stopped boat whose writes came back):
    // no output changes, yet the widget is fresh again within one period.
    ds.set(nav1, "speed", Value::Float(0.0)).unwrap();
    layout.settle();
    clock.advance(Duration::from_millis(1000));
    ds.set(nav1, "speed", Value::Float(0.0)).unwrap();
    layout.settle();
    assert_eq!(aged(&ds), Some(Value::Bool(false)), "unchanged writes resumed: fresh again");
    clock.advance(Duration::from_millis(1100));
    layout.settle();
    assert_eq!(aged(&ds), Some(Value::Bool(true)), "and aged again when they stop");
    ds.set(nav1, "speed", Value::Float(2.0)).unwrap();
    layout.settle();
    assert_eq!(aged(&ds), Some(Value::Bool(false)), "a new value: fresh at once");
    clock.advance(Duration::from_millis(1100));
    layout.settle();
    assert_eq!(aged(&ds), Some(Value::Bool(true)), "and aged again after the period");
    assert_eq!(stale(&ds, &speed), Some(Value::Bool(false)), "the link was never lost");
}

/// A number whose publisher declares its rate (`PropMeta::rate_hz`) ages after three of its
/// periods without a write, with nothing declared on the vehicle or in the schema.
#[test]
fn without_a_stale_after_a_value_ages_after_three_periods_of_its_publishers_rate() {
    let clock = Arc::new(ManualClock::new());
    let ds = DataServer::with_clock(Config { workers: 2 }, clock.clone());
    let (_v1, nav1) = usv(&ds, "usv1");
    ds.delete_property(nav1, "speed").unwrap();
    let meta = PropMeta::typed(ValueKind::Float).rate(10.0); // every 0.1 s: stale after 0.3 s
    ds.create_property(nav1, "speed", Value::Float(0.0), meta).unwrap();
    let layout = Layout::load(&ds, &program(STRIPS), config(), Arc::new(NullSink)).unwrap();
    layout.settle();
    let speed = ["display", "hud", "speed"];
    let aged = |ds: &DataServer| ds.try_get(ds.resolve(&speed).unwrap(), "aged".into());
    for _ in 0..5 {
        clock.advance(Duration::from_millis(250));
        ds.set(nav1, "speed", Value::Float(0.0)).unwrap();
        layout.settle();
        assert_ne!(aged(&ds), Some(Value::Bool(true)), "written every 0.25 s: fresh");
    }
    clock.advance(Duration::from_millis(310));
    layout.settle();
    assert_eq!(aged(&ds), Some(Value::Bool(true)), "nothing for three periods: aged");
    // The fuel bars read `fuel`, whose publisher declared no rate: they never age.
    assert_ne!(
        ds.try_get(ds.resolve(&["display", "strip@usv1", "fuel@usv1"]).unwrap(), "aged".into()),
        Some(Value::Bool(true))
    );
}

/// The schema's `stale_after` for a property comes before the vehicle's and the rate's.
#[test]
fn a_schema_stale_after_wins_over_the_publishers_rate() {
    let clock = Arc::new(ManualClock::new());
    let ds = DataServer::with_clock(Config { workers: 2 }, clock.clone());
    let (v1, nav1) = usv(&ds, "usv1");
    ds.set(v1, "stale_after", Value::Float(0.2)).unwrap();
    ds.delete_property(nav1, "speed").unwrap();
    let meta = PropMeta::typed(ValueKind::Float).rate(10.0);
    ds.create_property(nav1, "speed", Value::Float(0.0), meta).unwrap();
    let text = "[types.nav.properties]\nspeed = { type = \"float\", stale_after = 2 }";
    let mut sources = mocu_language::SourceMap::new();
    let file = sources.add("schema.toml".into(), text.into());
    let mut diags = mocu_language::Diagnostics::new();
    let schema = mocu_language::Schema::parse(file, text, &mut diags).expect("a schema");
    let config = LayoutConfig { stale_after: LayoutConfig::stale_after_from(&schema), ..config() };
    let layout = Layout::load(&ds, &program(STRIPS), config, Arc::new(NullSink)).unwrap();
    layout.settle();
    let speed = ["display", "hud", "speed"];
    let aged = |ds: &DataServer| ds.try_get(ds.resolve(&speed).unwrap(), "aged".into());
    clock.advance(Duration::from_millis(1900));
    layout.settle();
    assert_ne!(aged(&ds), Some(Value::Bool(true)), "1.9 s of the schema's 2 s: fresh");
    clock.advance(Duration::from_millis(200));
    layout.settle();
    assert_eq!(aged(&ds), Some(Value::Bool(true)), "2.1 s: aged");
}

/// Only what feeds a widget's data parameters (`mocu_lower::data_params`: no default; a
/// control's label and an alert's message are not data) makes it stale: a label showing a
/// vehicle's speed is, a button enabled by that vehicle's state is not, nor an alert
/// banner whose message and `active` read it, nor a gauge placed by it.
#[test]
fn only_the_data_a_widget_shows_makes_it_stale_never_its_settings_labels_or_actions() {
    let text = r#"
use "stdlib/gauges.mocu"
use "stdlib/controls.mocu"
use "stdlib/alerts.mocu"
window hud { layer 10 rect 0 0 100% 100% }
in hud {
  label: Label { at 10 10  text "SPD {root.vehicles.usv1.nav.speed:.1} kn" }
  button: Button { at 10 40 120 30  label "STOP {root.vehicles.usv1.nav.speed:.0}"  enabled root.vehicles.usv1.fuel > 0.1  on press call root.vehicles.usv1.stop() }
  banner: AlertBanner { at 0 80 400 30  message "FUEL {root.vehicles.usv1.fuel * 100:.0}%"  active root.vehicles.usv1.fuel < 0.9 }
  placed: TextGauge { at 10 (120 + root.vehicles.usv1.fuel) 200 26  label "K"  value 3 }
  toggle: Toggle { at 10 160 40 20  label "ENGINE {root.vehicles.usv1.nav.speed:.0}"  state root.vehicles.usv1.fuel > 0.1 }
}
"#;
    let clock = Arc::new(ManualClock::new());
    let ds = DataServer::with_clock(Config { workers: 2 }, clock.clone());
    let (v1, nav1) = usv(&ds, "usv1");
    ds.set(v1, "stale_after", Value::Float(1.0)).unwrap();
    let layout = Layout::load(&ds, &program(text), config(), Arc::new(NullSink)).unwrap();
    layout.settle();
    ds.set(v1, "link_lost", Value::Bool(true)).unwrap();
    clock.advance(Duration::from_secs(2));
    ds.set(nav1, "speed", Value::Float(0.0)).unwrap(); // fresh speed: only fuel ages
    layout.settle();
    fn at(w: &str) -> [&str; 3] {
        ["display", "hud", w]
    }
    assert_eq!(stale(&ds, &at("label")), Some(Value::Bool(true)), "a label of vehicle data");
    assert_eq!(stale(&ds, &at("toggle")), Some(Value::Bool(true)), "a toggle's state");
    for w in ["button", "banner", "placed"] {
        assert_eq!(stale(&ds, &at(w)), None, "{w}: reads the vehicle only in its settings");
        let g = ds.resolve(&at(w)).unwrap();
        assert_eq!(ds.try_get(g, "aged".into()), None, "{w}: its settings never age it");
    }
}
