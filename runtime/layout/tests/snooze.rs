//! Watches on the DataServer's manual clock: repeat and snooze fire exactly when the clock
//! says, and no snooze length — infinite, NaN, negative — panics.
mod common;
use common::program;
use mocu_dataserver::*;
use mocu_layout::*;
use std::sync::Arc;
use std::time::Duration;

const LOST: &str =
    "watch lost { when root.v.link < 0.1 repeat every 40ms then alert critical \"link\" }";

/// A repeating watch that is active, on a manual clock; returns the watch object.
fn active_watch() -> (DataServer, ManualClock, Layout, Arc<MemorySink>, Guid) {
    let clock = ManualClock::new();
    let ds = DataServer::with_clock(Config::default(), Arc::new(clock.clone()));
    let v = ds.create_object(Guid::ROOT, ObjectInfo::new("v", "usv")).unwrap();
    ds.set(v, "link", Value::Float(1.0)).unwrap();
    let sink = Arc::new(MemorySink::default());
    let config = LayoutConfig { tick: Duration::from_millis(1), ..LayoutConfig::default() };
    let layout = Layout::load(&ds, &program(LOST), config, sink.clone()).unwrap();
    ds.set(v, "link", Value::Float(0.0)).unwrap();
    layout.settle();
    let watch = ds.resolve(&["operator", "watches", "lost"]).unwrap();
    (ds, clock, layout, sink, watch)
}

fn step(clock: &ManualClock, layout: &Layout, ms: u64) {
    clock.advance(Duration::from_millis(ms));
    layout.settle();
}

#[test]
fn a_repeating_watch_repeats_on_the_clock_and_a_snooze_holds_it_off_exactly_that_long() {
    let (ds, clock, layout, sink, watch) = active_watch();
    assert_eq!(sink.of("alert").len(), 1);
    step(&clock, &layout, 40);
    assert_eq!(sink.of("alert").len(), 2, "one repeat per 40 ms");
    assert!(ds.call_wait(watch, "snooze", vec![Value::Float(300.0)], None).is_accepted());
    layout.settle();
    step(&clock, &layout, 299);
    assert_eq!(sink.of("alert").len(), 2, "snoozed: no repeats");
    step(&clock, &layout, 1);
    assert_eq!(sink.of("alert").len(), 3, "fires again when the snooze ends");
}

#[test]
fn no_snooze_length_panics_and_an_infinite_one_holds_for_ever() {
    for ms in [f64::INFINITY, f64::MAX, 1e300, f64::NAN, -5.0, 0.0] {
        let (ds, clock, layout, sink, watch) = active_watch();
        let out = ds.call_wait(watch, "snooze", vec![Value::Float(ms)], None);
        assert!(out.is_accepted(), "snooze({ms}): {out:?}");
        layout.settle();
        let before = sink.of("alert").len();
        step(&clock, &layout, 3_600_000);
        let after = sink.of("alert").len();
        if ms >= 1e300 {
            assert_eq!(after, before, "snooze({ms}) holds off for an hour and more");
        } else {
            assert!(after > before, "snooze({ms}) is over at once");
        }
        assert_eq!(ds.stats().panics_caught.load(std::sync::atomic::Ordering::Relaxed), 0);
    }
}
