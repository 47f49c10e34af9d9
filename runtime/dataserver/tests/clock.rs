//! Time under control: a DataServer on a `ManualClock` fires timers, delayed calls and
//! timeouts exactly when the clock is advanced past them, and stamps every write with the
//! clock's time (`received_at`).
mod common;
use common::manual;
use mocu_dataserver::*;
use std::sync::Arc;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::Duration;

fn ms(n: u64) -> Duration {
    Duration::from_millis(n)
}

#[test]
fn run_after_fires_when_the_manual_clock_passes_its_deadline_and_not_before() {
    let (ds, clock) = manual();
    let fired = Arc::new(AtomicUsize::new(0));
    let f = fired.clone();
    ds.run_after(ms(100), None, move || {
        f.fetch_add(1, Ordering::SeqCst);
    });
    clock.advance(ms(99));
    ds.quiesce();
    assert_eq!(fired.load(Ordering::SeqCst), 0);
    assert_eq!(ds.pending_timers(), 1);
    clock.advance(ms(1));
    ds.quiesce();
    assert_eq!(fired.load(Ordering::SeqCst), 1);
    assert_eq!(ds.pending_timers(), 0);
}

#[test]
fn timers_fire_in_deadline_order_whatever_order_they_were_set_in() {
    let (ds, clock) = manual();
    let order = Arc::new(parking_lot::Mutex::new(Vec::new()));
    let ex = ds.serial_executor();
    for d in [30u64, 10, 20] {
        let o = order.clone();
        ds.run_after(ms(d), Some(&ex), move || o.lock().push(d));
    }
    clock.advance(ms(30));
    ds.quiesce();
    assert_eq!(*order.lock(), vec![10, 20, 30]);
}

#[test]
fn a_call_times_out_exactly_when_the_clock_passes_its_timeout() {
    let (ds, clock) = manual();
    let o = ds.create_object(ds.root(), ObjectInfo::new("v", "v")).unwrap();
    // A handler that keeps its responder and never answers.
    let kept = Arc::new(parking_lot::Mutex::new(Vec::new()));
    let k = kept.clone();
    ds.publish_method(o, MethodSpec::new("slow"), move |call| k.lock().push(call.responder))
        .unwrap();
    let (tx, rx) = crossbeam_channel::unbounded();
    ds.call(o, "slow", vec![], Some(CallOptions::queued().timeout(ms(50))), move |out| {
        tx.send(out).unwrap();
    });
    clock.advance(ms(49));
    ds.quiesce();
    assert!(rx.try_recv().is_err(), "not answered before the timeout");
    clock.advance(ms(1));
    // `advance` answers TimedOut itself before it returns.
    assert_eq!(rx.try_recv(), Ok(CallOutcome::TimedOut));
    assert!(!kept.lock().pop().unwrap().accept(vec![]), "a late answer is refused");
}

#[test]
fn every_write_stamps_received_at_with_the_server_clock_even_an_unchanged_one() {
    let (ds, clock) = manual();
    let o = ds.create_object(ds.root(), ObjectInfo::new("v", "v")).unwrap();
    let t0 = ds.now();
    ds.set(o, "speed", Value::Float(1.0)).unwrap();
    assert_eq!(ds.received_at(o, "speed"), Ok(Some(t0)));
    let (log, cb) = {
        let log = Arc::new(AtomicUsize::new(0));
        let l = log.clone();
        (log, move |_: &Notification| {
            l.fetch_add(1, Ordering::SeqCst);
        })
    };
    ds.subscribe(Topic::properties(o), cb).unwrap();
    ds.quiesce();
    clock.advance(ms(250));
    ds.set(o, "speed", Value::Float(1.0)).unwrap(); // equal: no notification
    ds.update(o, "speed", Value::Float(1.0)).unwrap();
    ds.quiesce();
    assert_eq!(log.load(Ordering::SeqCst), 1, "only the initial New");
    assert_eq!(ds.received_at(o, "speed"), Ok(Some(t0 + ms(250))));
    let typed = PropMeta::typed(ValueKind::Int);
    ds.create_property(o, "mode", Value::Int(1), typed).unwrap();
    assert_eq!(ds.received_at(o, "mode"), Ok(Some(t0 + ms(250))));
}

#[test]
fn a_refused_write_does_not_count_as_received() {
    let (ds, clock) = manual();
    let o = ds.create_object(ds.root(), ObjectInfo::new("v", "v")).unwrap();
    let t0 = ds.now();
    ds.create_property(o, "pct", Value::Float(5.0), PropMeta::default().range(0.0, 10.0)).unwrap();
    clock.advance(ms(10));
    assert!(ds.set(o, "pct", Value::Float(50.0)).is_err());
    assert_eq!(ds.received_at(o, "pct"), Ok(Some(t0)));
}

#[test]
fn received_at_tells_an_absent_property_from_an_absent_object() {
    let (ds, _clock) = manual();
    let o = ds.create_object(ds.root(), ObjectInfo::new("v", "v")).unwrap();
    assert_eq!(ds.received_at(o, "nothing"), Ok(None));
    ds.delete_object(o).unwrap();
    assert!(matches!(ds.received_at(o, "nothing"), Err(DsError::NoSuchObject { .. })));
}

#[test]
fn the_system_clock_is_the_default_and_received_at_follows_it() {
    let ds = DataServer::default();
    let o = ds.create_object(ds.root(), ObjectInfo::new("v", "v")).unwrap();
    let before = ds.now();
    ds.set(o, "x", Value::Int(1)).unwrap();
    let at = ds.received_at(o, "x").unwrap().unwrap();
    assert!(at >= before && at <= ds.now());
}

#[test]
fn the_wall_time_of_a_manual_clock_is_the_one_set_and_moves_with_advance() {
    let (ds, clock) = manual();
    let noon = std::time::UNIX_EPOCH + Duration::from_secs(86_400 * 20_000 + 12 * 3600);
    clock.advance(ms(500));
    clock.set_wall(noon);
    assert_eq!(ds.wall_time(), noon);
    clock.advance(ms(1_250));
    assert_eq!(ds.wall_time(), noon + ms(1_250));
}

#[test]
fn advance_settled_fires_each_job_at_its_deadline_after_the_work_of_the_one_before() {
    let (ds, clock) = manual();
    let t0 = ds.now();
    let seen = Arc::new(parking_lot::Mutex::new(Vec::new()));
    let value = Arc::new(AtomicUsize::new(0));
    // Two jobs due at once on two executors: the first starts work on a third executor
    // that the second must see finished; a later one reads the clock.
    let (a, b, c) = (ds.serial_executor(), ds.serial_executor(), ds.serial_executor());
    let v = value.clone();
    ds.run_after(ms(20), Some(&a), move || {
        c.spawn(move || {
            std::thread::yield_now();
            v.store(7, Ordering::SeqCst);
        });
    });
    let (v, s, ds2) = (value.clone(), seen.clone(), ds.clone());
    ds.run_after(ms(20), Some(&b), move || {
        s.lock().push((ds2.now() - t0, v.load(Ordering::SeqCst)));
    });
    let (s, ds2) = (seen.clone(), ds.clone());
    ds.run_after(ms(35), None, move || s.lock().push((ds2.now() - t0, 0)));
    ds.run_after(ms(90), None, || {});
    ds.advance_settled(&clock, t0 + ms(50));
    assert_eq!(*seen.lock(), vec![(ms(20), 7), (ms(35), 0)]);
    assert_eq!(ds.now(), t0 + ms(50));
    assert_eq!(ds.next_deadline(), Some(t0 + ms(90)));
}

#[test]
fn quiesce_waits_for_a_timer_job_that_is_already_due() {
    let (manual_ds, _clock) = manual();
    for ds in [DataServer::default(), manual_ds] {
        let fired = Arc::new(AtomicUsize::new(0));
        for i in 1..=300 {
            let f = fired.clone();
            ds.run_after(Duration::ZERO, None, move || {
                f.fetch_add(1, Ordering::SeqCst);
            });
            ds.quiesce();
            assert_eq!(fired.load(Ordering::SeqCst), i, "try {i}: quiesce returned first");
        }
    }
}

#[test]
fn a_manual_clock_moved_as_far_as_an_instant_goes_still_tells_the_time_of_day() {
    let (ds, clock) = manual();
    let feed = ds.change_feed();
    let o = ds.create_object(ds.root(), ObjectInfo::new("o", "thing")).unwrap();
    let before = ds.wall_time();
    // As far as an `Instant` goes (each `advance` alone stops at a hundred years).
    let mut step = Duration::MAX;
    while step > Duration::ZERO {
        match ds.now().checked_add(step) {
            Some(_) => clock.advance(step),
            None => step /= 2,
        }
    }
    assert!(ds.now().checked_add(Duration::from_nanos(1)).is_none());
    let after = ds.wall_time();
    assert!(after >= before, "the time of day went back");
    assert!(ds.wall_secs() > 0.0);
    ds.set(o, "x", Value::Int(1)).unwrap();
    let got: Vec<Stamped> = feed.try_iter().collect();
    let last = got.last().expect("the write is fed");
    assert!(matches!(last.change, Change::PropertySet { object, .. } if object == o));
    // The feed stamps in nanoseconds since the epoch (u64): it saturates there, sooner.
    assert!(got[0].wall <= last.wall && last.wall <= after, "the feed's stamps went back");
}

#[test]
fn one_manual_clock_shared_by_two_servers_fires_the_due_jobs_of_both() {
    let clock = ManualClock::new();
    let a = DataServer::with_clock(Config::default(), Arc::new(clock.clone()));
    let b = DataServer::with_clock(Config::default(), Arc::new(clock.clone()));
    let fired = Arc::new(std::sync::Mutex::new(Vec::new()));
    for (ds, name, after) in [(&a, "a1", 10), (&b, "b1", 10), (&a, "a2", 30), (&b, "b2", 30)] {
        let f = fired.clone();
        ds.run_after(ms(after), None, move || f.lock().unwrap().push(name));
    }
    // `advance` fires what fell due on every server built on the clock.
    clock.advance(ms(10));
    a.quiesce();
    b.quiesce();
    let mut got = std::mem::take(&mut *fired.lock().unwrap());
    got.sort();
    assert_eq!(got, ["a1", "b1"]);
    // `advance_settled` steps one server's jobs; the other's, due by then, fire no later
    // than its `quiesce` (or the clock's next `advance`).
    a.advance_settled(&clock, a.now() + ms(20));
    assert!(fired.lock().unwrap().contains(&"a2"));
    b.quiesce();
    let mut got = std::mem::take(&mut *fired.lock().unwrap());
    got.sort();
    assert_eq!(got, ["a2", "b2"]);
}
