//! The DataServer against a plain single-threaded model of it.
//!
//! Random sequences of tree, property and subscription operations run on both. After every
//! operation the trees must be equal, both must have answered the same `Ok`/`Err` (the same
//! typed error, and nothing changed on `Err`). With `quiesce()` after every operation each
//! subscription must have received exactly the model's notifications; without it (and with
//! callbacks held back so that changes pile up and coalesce) each stream must keep the
//! documented guarantees: a coalesced subsequence of the changes, the latest value always
//! delivered, nothing after `Deleted` of the object or after `unsubscribe` returns.

mod harness;
mod model;
mod ops;
mod streams;

use harness::Harness;
use mocu_dataserver::{
    Config, DataServer, Guid, Kind, Notification, ObjectInfo, Subject, Topic, Value,
};
use ops::{op, op_or_hold};
use parking_lot::Mutex;
use proptest::prelude::*;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};

// ----- the properties ------------------------------------------------------------------------

proptest! {
    #![proptest_config(ProptestConfig { cases: 128, failure_persistence: None, ..ProptestConfig::default() })]

    #[test]
    fn quiesced_server_matches_the_model_notification_for_notification(
        ops in prop::collection::vec(op(), 1..40)
    ) {
        Harness::new(true).run(&ops);
    }

    #[test]
    fn unquiesced_streams_are_coalesced_subsequences_ending_in_the_final_state(
        ops in prop::collection::vec(op_or_hold(), 1..40)
    ) {
        Harness::new(false).run(&ops);
    }
}

// ----- fixed cases -------------------------------------------------------------------------

/// A callback held back at its first notification makes everything after it pile up.
fn held_children_subscription(
    ds: &DataServer,
    parent: Guid,
) -> (Arc<Mutex<Vec<Notification>>>, crossbeam_channel::Sender<()>) {
    let log = Arc::new(Mutex::new(Vec::new()));
    let (release, wait) = crossbeam_channel::unbounded::<()>();
    let (entered_tx, entered) = crossbeam_channel::bounded::<()>(1);
    let l = log.clone();
    let mut first = true;
    ds.subscribe(Topic::children(parent), move |n| {
        if std::mem::take(&mut first) {
            let _ = entered_tx.send(());
            let _ = wait.recv();
        }
        l.lock().push(n.clone());
    })
    .unwrap();
    entered.recv().expect("the first notification arrives");
    (log, release)
}

#[test]
fn child_positions_stay_valid_when_a_rename_coalesces_into_a_pending_new() {
    let ds = DataServer::new(Config { workers: 2 });
    let p = ds.create_object(Guid::ROOT, ObjectInfo::new("p", "group")).unwrap();
    let x = ds.create_object(p, ObjectInfo::new("x", "robot")).unwrap();
    let (log, release) = held_children_subscription(&ds, p);
    // While the subscriber is busy with x: a arrives first, then b between a and x, then a
    // is renamed (a Changed that coalesces with a's pending New).
    let a = ds.create_object_at(p, 0, ObjectInfo::new("a", "robot")).unwrap();
    let b = ds.create_object_at(p, 1, ObjectInfo::new("b", "robot")).unwrap();
    ds.set_info(a, ObjectInfo::new("a2", "robot")).unwrap();
    release.send(()).unwrap();
    ds.quiesce();
    let mut replica: Vec<Guid> = Vec::new();
    for n in log.lock().iter() {
        let Subject::Child { guid, index, .. } = n.subject else { unreachable!() };
        match n.kind {
            Kind::New => replica.insert(index.min(replica.len()), guid),
            Kind::Changed => assert_eq!(replica[index], guid, "{n:?}"),
            Kind::Deleted => assert_eq!(replica.remove(index), guid, "{n:?}"),
        }
    }
    assert_eq!(
        replica,
        vec![a, b, x],
        "the subscriber's order is not the tree's: {:#?}",
        log.lock()
    );
}

#[test]
fn unsubscribe_stops_delivery_even_after_the_object_was_deleted() {
    let ds = DataServer::new(Config { workers: 2 });
    let o = ds.create_object(Guid::ROOT, ObjectInfo::new("o", "robot")).unwrap();
    ds.set(o, "speed", Value::Int(1)).unwrap();
    // The subscription's executor is busy, so its notifications wait in its queue.
    let ex = ds.serial_executor();
    let (release, wait) = crossbeam_channel::bounded::<()>(0);
    ex.spawn(move || {
        let _ = wait.recv();
    });
    let ended = Arc::new(AtomicBool::new(false));
    let late = Arc::new(Mutex::new(Vec::new()));
    let (e, l) = (ended.clone(), late.clone());
    let id = ds
        .subscribe_on(&ex, Topic::properties(o), move |n| {
            if e.load(Ordering::SeqCst) {
                l.lock().push(n.clone());
            }
        })
        .unwrap();
    ds.delete_object(o).unwrap();
    ds.unsubscribe(id);
    ended.store(true, Ordering::SeqCst);
    release.send(()).unwrap();
    ds.quiesce();
    assert_eq!(*late.lock(), vec![], "delivered after unsubscribe returned");
    assert_eq!(ds.subscription_count(), 0);
}

#[test]
fn a_deleted_objects_subscriptions_leave_the_registry_once_told() {
    let ds = DataServer::new(Config { workers: 2 });
    let o = ds.create_object(Guid::ROOT, ObjectInfo::new("o", "robot")).unwrap();
    let c = ds.create_object(o, ObjectInfo::new("c", "robot")).unwrap();
    for g in [o, c] {
        ds.subscribe(Topic::properties(g), |_| {}).unwrap();
        ds.subscribe(Topic::children(g), |_| {}).unwrap();
    }
    ds.delete_object(o).unwrap();
    ds.quiesce();
    assert_eq!(ds.subscription_count(), 0);
}
