//! The operator's clock (`root.operator.clock`): the UTC time of day from the DataServer's
//! clock, written on each whole second while a layout reads it, and nothing at all when
//! none does.
mod common;
use common::{config, program};
use mocu_dataserver::{Config, DataServer, ManualClock, Value};
use mocu_layout::{Layout, NullSink};
use std::sync::Arc;
use std::time::{Duration, UNIX_EPOCH};

const WITH_CLOCK: &str = r#"
use "stdlib/gauges.mocu"
window hud { layer 10 rect 0 0 100% 100% }
in hud { time: Label { at 0 0 text "UTC {root.operator.clock.utc}" } }
"#;

const WITHOUT_CLOCK: &str = r#"
use "stdlib/gauges.mocu"
window hud { layer 10 rect 0 0 100% 100% }
in hud { name: Label { at 0 0 text "{root.vehicles.usv1.name}" } }
"#;

/// A DataServer on a manual clock reading 14:03:07.400 UTC.
fn at_14_03_07() -> (DataServer, ManualClock) {
    let clock = ManualClock::new();
    clock.set_wall(UNIX_EPOCH + Duration::from_millis((86_400 * 20_000 + 50_587) * 1000 + 400));
    (DataServer::with_clock(Config::default(), Arc::new(clock.clone())), clock)
}

fn utc(ds: &DataServer) -> Option<Value> {
    let g = ds.resolve(&["operator", "clock"])?;
    ds.try_get(g, "utc".into())
}

fn label(ds: &DataServer) -> Option<Value> {
    let g = ds.resolve(&["display", "hud", "time"])?;
    ds.try_get(g, "text".into())
}

#[test]
fn the_clock_shows_the_servers_utc_time_and_moves_on_each_whole_second() {
    let (ds, clock) = at_14_03_07();
    let layout = Layout::load(&ds, &program(WITH_CLOCK), config(), Arc::new(NullSink)).unwrap();
    layout.settle();
    assert_eq!(utc(&ds), Some(Value::str("14:03:07")));
    assert_eq!(label(&ds), Some(Value::str("UTC 14:03:07")));
    clock.advance(Duration::from_millis(599));
    layout.settle();
    assert_eq!(utc(&ds), Some(Value::str("14:03:07")), "not before the whole second");
    clock.advance(Duration::from_millis(1));
    layout.settle();
    assert_eq!(utc(&ds), Some(Value::str("14:03:08")));
    clock.advance(Duration::from_secs(1));
    layout.settle();
    assert_eq!(label(&ds), Some(Value::str("UTC 14:03:09")));
    let g = ds.resolve(&["operator", "clock"]).unwrap();
    let day = 86_400.0 * 20_000.0;
    assert_eq!(ds.try_get(g, "time".into()), Some(Value::Float(day + 50_589.0)));
}

#[test]
fn a_layout_that_shows_no_clock_runs_none() {
    let (ds, clock) = at_14_03_07();
    let layout = Layout::load(&ds, &program(WITHOUT_CLOCK), config(), Arc::new(NullSink)).unwrap();
    layout.settle();
    clock.advance(Duration::from_secs(3));
    layout.settle();
    assert_eq!(utc(&ds), None);
    assert_eq!(ds.pending_timers(), 0);
}

#[test]
fn the_clock_stops_when_a_reload_drops_it_or_the_layout_is_unloaded() {
    let (ds, clock) = at_14_03_07();
    let layout = Layout::load(&ds, &program(WITH_CLOCK), config(), Arc::new(NullSink)).unwrap();
    layout.settle();
    layout.reload(&program(WITHOUT_CLOCK)).unwrap();
    clock.advance(Duration::from_secs(1));
    layout.settle();
    assert_eq!(utc(&ds), Some(Value::str("14:03:07")), "no longer written");
    assert_eq!(ds.pending_timers(), 0);
    layout.reload(&program(WITH_CLOCK)).unwrap();
    layout.settle();
    assert_eq!(utc(&ds), Some(Value::str("14:03:08")), "back with the clock");
    drop(layout);
    clock.advance(Duration::from_secs(5));
    ds.quiesce();
    assert_eq!(utc(&ds), Some(Value::str("14:03:08")), "not after the unload");
    assert_eq!(ds.pending_timers(), 0);
}
