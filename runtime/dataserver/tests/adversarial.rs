//! The DataServer's promises, tried adversarially through the public API only: blocked and
//! panicking callbacks, calls racing deletes, writes racing deletes, abusive arguments.
//! Waiting for an event is always a bounded wait on that event (`wait`), never a sleep.
mod common;
#[allow(unused_imports)]
use common::*;
use crossbeam_channel::{Receiver, unbounded};
use mocu_dataserver::*;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::{Arc, Barrier, Mutex};
use std::time::Duration;

/// A generous bound on waiting for an event that must happen: a failing test fails instead
/// of hanging, and a passing one never waits this long.
const EVENTUALLY: Duration = Duration::from_secs(20);

fn wait<T>(rx: &Receiver<T>, what: &str) -> T {
    rx.recv_timeout(EVENTUALLY).unwrap_or_else(|_| panic!("never happened: {what}"))
}

fn object(ds: &DataServer, name: &str) -> Guid {
    ds.create_object(ds.root(), ObjectInfo::new(name, "thing")).unwrap()
}

#[test]
fn unsubscribe_nowait_returns_while_the_callback_waits_for_a_lock_the_caller_holds() {
    let ds = DataServer::default();
    let o = object(&ds, "o");
    ds.set(o, "x", Value::Int(0)).unwrap();
    let lock = Arc::new(Mutex::new(()));
    let calls = Arc::new(AtomicUsize::new(0));
    let (entered_tx, entered) = unbounded();
    let (l, c) = (lock.clone(), calls.clone());
    let id = ds
        .subscribe(Topic::properties(o), move |n| {
            if n.kind == Kind::Changed {
                c.fetch_add(1, Ordering::SeqCst);
                entered_tx.send(()).unwrap();
                drop(l.lock().unwrap()); // what a module's callback needing its state does
            }
        })
        .unwrap();
    ds.quiesce();
    let held = lock.lock().unwrap();
    ds.set(o, "x", Value::Int(1)).unwrap();
    wait(&entered, "the callback starts and waits for the lock");
    // A Drop impl holding its state's lock: the waiting form would deadlock here.
    ds.unsubscribe_nowait(id);
    ds.set(o, "x", Value::Int(2)).unwrap();
    drop(held);
    ds.quiesce();
    ds.set(o, "x", Value::Int(3)).unwrap();
    ds.quiesce();
    assert_eq!(calls.load(Ordering::SeqCst), 1, "the callback never starts again");
    assert_eq!(ds.subscription_count(), 0);
}

#[test]
fn unsubscribe_nowait_from_inside_its_own_callback_stops_the_rest_of_the_batch() {
    let ds = DataServer::new(Config { workers: 1 });
    let o = object(&ds, "o");
    let seen = Arc::new(Mutex::new(Vec::new()));
    let id_cell: Arc<Mutex<Option<SubscriptionId>>> = Arc::default();
    let (s, cell, ds2) = (seen.clone(), id_cell.clone(), ds.clone());
    let gate = Arc::new(Barrier::new(2));
    let g = gate.clone();
    let id = ds
        .subscribe(Topic::properties(o), move |n| {
            if n.kind == Kind::New && n.property_name().map(|p| p.as_str() == "a") == Some(true) {
                g.wait(); // the test queues b and c behind a before this goes on
            }
            s.lock().unwrap().push(n.property_name().unwrap().to_string());
            if let Some(id) = *cell.lock().unwrap() {
                ds2.unsubscribe_nowait(id);
            }
        })
        .unwrap();
    *id_cell.lock().unwrap() = Some(id);
    ds.set(o, "a", Value::Int(1)).unwrap();
    ds.set(o, "b", Value::Int(1)).unwrap();
    gate.wait();
    ds.set(o, "c", Value::Int(1)).unwrap();
    ds.quiesce();
    assert_eq!(*seen.lock().unwrap(), vec!["a".to_string()]);
}
