//! Subscriptions: initial values, delta isolation, ordering, the end of delivery.
mod common;
use common::*;
use mocu_dataserver::*;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::{Arc, Mutex};

fn setup() -> (DataServer, Guid) {
    let ds = DataServer::default();
    let o = ds.create_object(Guid::ROOT, ObjectInfo::new("usv1", "usv")).unwrap();
    (ds, o)
}

#[test]
fn a_new_subscription_receives_what_is_already_there_as_new() {
    let (ds, o) = setup();
    ds.set(o, "speed", Value::Float(1.0)).unwrap();
    ds.set(o, "heading", Value::Float(90.0)).unwrap();
    let (first, cb) = recorder();
    ds.subscribe(Topic::properties(o), cb).unwrap();
    ds.quiesce();
    // A second subscription of the same module still gets its own initial values.
    let (second, cb) = recorder();
    ds.subscribe(Topic::properties(o), cb).unwrap();
    ds.quiesce();
    let want = vec![
        (Kind::New, "speed".to_string(), Some(Value::Float(1.0))),
        (Kind::New, "heading".to_string(), Some(Value::Float(90.0))),
    ];
    assert_eq!(prop_events(&first), want);
    assert_eq!(prop_events(&second), want);
}

#[test]
fn changes_arrive_as_changed_and_deletions_as_deleted() {
    let (ds, o) = setup();
    let (log, cb) = recorder();
    ds.subscribe(Topic::properties(o), cb).unwrap();
    ds.set(o, "speed", Value::Float(1.0)).unwrap();
    ds.quiesce();
    ds.set(o, "speed", Value::Float(2.0)).unwrap();
    ds.quiesce();
    ds.set(o, "speed", Value::Float(2.0)).unwrap(); // equal: no notification
    ds.delete_property(o, "speed").unwrap();
    ds.quiesce();
    assert_eq!(
        prop_events(&log),
        vec![
            (Kind::New, "speed".into(), Some(Value::Float(1.0))),
            (Kind::Changed, "speed".into(), Some(Value::Float(2.0))),
            (Kind::Deleted, "speed".into(), None),
        ]
    );
}

#[test]
fn a_name_filter_delivers_only_the_named_properties() {
    let (ds, o) = setup();
    let (log, cb) = recorder();
    ds.subscribe(Topic::property_names(o, &["speed"]), cb).unwrap();
    ds.set(o, "heading", Value::Float(3.0)).unwrap();
    ds.set(o, "speed", Value::Float(1.0)).unwrap();
    ds.quiesce();
    assert_eq!(prop_events(&log), vec![(Kind::New, "speed".into(), Some(Value::Float(1.0)))]);
}

#[test]
fn writes_to_other_objects_are_not_delivered() {
    let (ds, o) = setup();
    let other = ds.create_object(Guid::ROOT, ObjectInfo::new("usv2", "usv")).unwrap();
    let (log, cb) = recorder();
    ds.subscribe(Topic::properties(o), cb).unwrap();
    for i in 0..100 {
        ds.set(other, "speed", Value::Int(i)).unwrap();
    }
    ds.quiesce();
    assert!(log.lock().unwrap().is_empty());
}

#[test]
fn coalesced_changes_still_deliver_the_latest_value_in_change_order() {
    let (ds, o) = setup();
    // A subscriber held busy on its first notification while many writes pile up.
    let gate = Arc::new(Mutex::new(()));
    let held = gate.lock().unwrap();
    let log = Arc::new(Mutex::new(Vec::new()));
    let (g, l) = (gate.clone(), log.clone());
    let (entered_tx, entered) = crossbeam_channel::unbounded();
    ds.subscribe(Topic::properties(o), move |n: &Notification| {
        let _ = entered_tx.send(());
        drop(g.lock().unwrap());
        l.lock().unwrap().push((n.property_name().unwrap().to_string(), n.value().cloned()));
    })
    .unwrap();
    ds.set(o, "a", Value::Int(0)).unwrap();
    // Delivery has started and blocks at the gate.
    entered.recv_timeout(std::time::Duration::from_secs(20)).expect("delivery starts");
    for i in 1..=1000 {
        ds.set(o, "a", Value::Int(i)).unwrap();
        if i == 500 {
            ds.set(o, "b", Value::Int(1)).unwrap();
        }
    }
    drop(held);
    ds.quiesce();
    let got = log.lock().unwrap().clone();
    assert_eq!(got.last().unwrap(), &("a".to_string(), Some(Value::Int(1000))));
    assert!(got.len() < 1000, "coalesced: {} deliveries", got.len());
    // b changed after a=500 and before a=1000: it arrives before the final a.
    let b = got.iter().position(|(n, _)| n == "b").unwrap();
    assert!(b < got.len() - 1);
    // Values of `a` never go backwards.
    let av: Vec<i64> = got
        .iter()
        .filter(|(n, _)| n == "a")
        .map(|(_, v)| v.clone().unwrap().as_i64().unwrap())
        .collect();
    assert!(av.windows(2).all(|w| w[0] < w[1]), "{av:?}");
}

#[test]
fn children_subscriptions_see_new_renamed_moved_and_deleted_children() {
    let ds = DataServer::default();
    let route = ds.create_object(Guid::ROOT, ObjectInfo::new("route", "route")).unwrap();
    let a = ds.create_object(route, ObjectInfo::new("a", "waypoint")).unwrap();
    let (log, cb) = recorder();
    ds.subscribe(Topic::children(route), cb).unwrap();
    ds.quiesce();
    let b = ds.create_object(route, ObjectInfo::new("b", "waypoint")).unwrap();
    ds.quiesce();
    ds.set_info(b, ObjectInfo::new("b2", "waypoint")).unwrap();
    ds.quiesce();
    let x = ds.insert_between(route, a, ObjectInfo::new("x", "waypoint")).unwrap();
    ds.quiesce();
    ds.delete_and_promote(x, a).unwrap();
    ds.quiesce();
    ds.delete_object(b).unwrap();
    ds.quiesce();
    ds.delete_object(route).unwrap();
    ds.quiesce();
    assert_eq!(
        child_events(&log),
        vec![
            (Kind::New, "a".into()),
            (Kind::New, "b".into()),
            (Kind::Changed, "b2".into()),
            (Kind::Deleted, "a".into()),
            (Kind::New, "x".into()),
            (Kind::Deleted, "x".into()),
            (Kind::New, "a".into()),
            (Kind::Deleted, "b2".into()),
            (Kind::Deleted, "<self>".into()),
        ]
    );
}

#[test]
fn nothing_arrives_after_the_object_is_deleted() {
    let (ds, o) = setup();
    let (log, cb) = recorder();
    ds.subscribe(Topic::properties(o), cb).unwrap();
    ds.set(o, "x", Value::Int(1)).unwrap();
    ds.delete_object(o).unwrap();
    assert!(ds.set(o, "x", Value::Int(2)).is_err());
    ds.quiesce();
    let got = log.lock().unwrap().clone();
    assert_eq!(got.last().unwrap().subject, Subject::Object);
    assert_eq!(got.last().unwrap().kind, Kind::Deleted);
    assert_eq!(ds.subscription_count(), 0, "a deleted object's subscriptions end");
}

#[test]
fn nothing_arrives_after_unsubscribe_returns() {
    let (ds, o) = setup();
    let after = Arc::new(AtomicBool::new(false));
    let late = Arc::new(AtomicUsize::new(0));
    let (a, l) = (after.clone(), late.clone());
    let id = ds
        .subscribe(Topic::properties(o), move |_n: &Notification| {
            std::hint::black_box((0..2_000u64).sum::<u64>()); // a callback that takes a while
            if a.load(Ordering::SeqCst) {
                l.fetch_add(1, Ordering::SeqCst);
            }
        })
        .unwrap();
    let writer = {
        let ds = ds.clone();
        std::thread::spawn(move || {
            for i in 0..5000 {
                ds.set(o, "x", Value::Int(i)).unwrap();
            }
        })
    };
    // Unsubscribe while the writer is still writing (or, at worst, right after).
    while ds.get(o, "x").map_or(true, |v| v.as_i64() < Some(100)) && !writer.is_finished() {
        std::thread::yield_now();
    }
    ds.unsubscribe(id);
    after.store(true, Ordering::SeqCst);
    writer.join().unwrap();
    ds.quiesce();
    assert_eq!(late.load(Ordering::SeqCst), 0);
    assert_eq!(ds.subscription_count(), 0);
    ds.unsubscribe(id); // twice is harmless
}

#[test]
fn a_subscription_may_end_itself_from_its_own_callback() {
    let (ds, o) = setup();
    let count = Arc::new(AtomicUsize::new(0));
    let slot: Arc<Mutex<Option<SubscriptionId>>> = Arc::default();
    let (c, s, ds2) = (count.clone(), slot.clone(), ds.clone());
    let id = ds
        .subscribe(Topic::properties(o), move |_n: &Notification| {
            c.fetch_add(1, Ordering::SeqCst);
            if let Some(id) = *s.lock().unwrap() {
                ds2.unsubscribe(id);
            }
        })
        .unwrap();
    *slot.lock().unwrap() = Some(id);
    ds.set(o, "x", Value::Int(1)).unwrap();
    ds.quiesce();
    ds.set(o, "x", Value::Int(2)).unwrap();
    ds.quiesce();
    assert_eq!(count.load(Ordering::SeqCst), 1);
}

#[test]
fn a_serial_executor_runs_a_modules_callbacks_one_at_a_time_in_order() {
    let ds = DataServer::default();
    let ex = ds.serial_executor();
    let objs: Vec<Guid> = (0..4)
        .map(|i| ds.create_object(Guid::ROOT, ObjectInfo::new(&format!("o{i}"), "t")).unwrap())
        .collect();
    let busy = Arc::new(AtomicBool::new(false));
    let overlaps = Arc::new(AtomicUsize::new(0));
    let seen = Arc::new(Mutex::new(Vec::new()));
    for &o in &objs {
        let (b, ov, s) = (busy.clone(), overlaps.clone(), seen.clone());
        ds.subscribe_on(&ex, Topic::properties(o), move |n: &Notification| {
            if b.swap(true, Ordering::SeqCst) {
                ov.fetch_add(1, Ordering::SeqCst);
            }
            s.lock().unwrap().push((n.object, n.value().cloned()));
            b.store(false, Ordering::SeqCst);
        })
        .unwrap();
    }
    for i in 0..200 {
        for &o in &objs {
            ds.set(o, "v", Value::Int(i)).unwrap();
        }
    }
    ds.quiesce();
    assert_eq!(overlaps.load(Ordering::SeqCst), 0);
    let seen = seen.lock().unwrap();
    for &o in &objs {
        let vals: Vec<i64> = seen
            .iter()
            .filter(|(g, _)| *g == o)
            .map(|(_, v)| v.clone().unwrap().as_i64().unwrap())
            .collect();
        assert!(vals.windows(2).all(|w| w[0] < w[1]));
        assert_eq!(*vals.last().unwrap(), 199);
    }
}

#[test]
fn a_slow_subscriber_does_not_block_writers_or_other_subscribers() {
    let (ds, o) = setup();
    let gate = Arc::new(Mutex::new(()));
    let held = gate.lock().unwrap();
    let g = gate.clone();
    ds.subscribe(Topic::properties(o), move |_n: &Notification| drop(g.lock().unwrap())).unwrap();
    // The fast subscriber reaches the last value while the slow one is still held.
    let (tx, rx) = crossbeam_channel::unbounded();
    ds.subscribe(Topic::properties(o), move |n: &Notification| {
        if n.value() == Some(&Value::Int(99)) {
            let _ = tx.send(());
        }
    })
    .unwrap();
    for i in 0..100 {
        ds.set(o, "x", Value::Int(i)).unwrap(); // would hang here if writers waited
    }
    rx.recv_timeout(std::time::Duration::from_secs(20))
        .expect("fast subscriber starved by a slow one");
    drop(held);
    ds.quiesce();
}
