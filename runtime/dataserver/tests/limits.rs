//! No argument makes the DataServer panic, and the edges of its promises hold: huge
//! durations saturate, NaN over NaN is no change, stream counters only go up, and a sender
//! blocked on a deleted receiver is let go.
mod common;
use common::{count_runs, manual, object};
use crossbeam_channel::{Receiver, unbounded};
use mocu_dataserver::*;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::{Arc, Barrier};
use std::time::Duration;

const EVENTUALLY: Duration = Duration::from_secs(20);

fn wait<T>(rx: &Receiver<T>, what: &str) -> T {
    rx.recv_timeout(EVENTUALLY).unwrap_or_else(|_| panic!("never happened: {what}"))
}

#[test]
fn duration_max_as_delay_or_timeout_saturates_instead_of_panicking() {
    let (ds, clock) = manual();
    let o = object(&ds, "o");
    let runs = count_runs(&ds, o);
    let r = runs.clone();
    ds.run_after(Duration::MAX, None, move || {
        r.fetch_add(1, Ordering::SeqCst);
    });
    ds.call(o, "m", vec![], Some(CallOptions::delayed(Duration::MAX)), |_| {});
    let slow = CallOptions::queued().timeout(Duration::MAX);
    assert!(ds.call_wait(o, "m", vec![], Some(slow)).is_accepted());
    clock.advance(Duration::from_secs(365 * 24 * 3600));
    clock.advance(Duration::MAX);
    ds.quiesce();
    assert!(runs.load(Ordering::SeqCst) >= 1, "the queued call ran");
}

#[test]
fn nan_written_over_nan_is_no_change_whatever_its_payload_or_sign() {
    let ds = DataServer::default();
    let o = object(&ds, "o");
    let nans = [
        f64::NAN,
        -f64::NAN,
        f64::from_bits(0x7ff8_0000_0000_0001),
        f64::from_bits(0xfff0_0000_0000_0002),
    ];
    ds.set(o, "x", Value::Float(nans[0])).unwrap();
    ds.set(o, "l", Value::list(vec![Value::Float(nans[0])])).unwrap();
    let changes = count_changes(&ds, o);
    for nan in nans {
        ds.set(o, "x", Value::Float(nan)).unwrap();
        ds.set(o, "l", Value::list(vec![Value::Float(nan)])).unwrap();
    }
    ds.quiesce();
    assert_eq!(changes.load(Ordering::SeqCst), 0);
    ds.set(o, "x", Value::Float(1.0)).unwrap();
    ds.quiesce();
    assert_eq!(changes.load(Ordering::SeqCst), 1, "a number over NaN is a change");
}

#[test]
fn a_set_is_unchanged_by_nans_that_differ_only_in_payload_or_sign() {
    let ds = DataServer::default();
    let o = object(&ds, "o");
    let f = |x: f64| Value::Float(x);
    let one_nan = f64::from_bits(0x7ff8_0000_0000_0001);
    ds.set(o, "s", Value::set(vec![f(1.0), f(f64::NAN)])).unwrap();
    let changes = count_changes(&ds, o);
    // Any NaN is the same element of a set, wherever its sign sorts it and however many.
    for same in [
        vec![f(-f64::NAN), f(1.0)],
        vec![f(1.0), f(one_nan)],
        vec![f(f64::NAN), f(-f64::NAN), f(1.0)],
    ] {
        ds.set(o, "s", Value::set(same)).unwrap();
    }
    ds.quiesce();
    assert_eq!(changes.load(Ordering::SeqCst), 0);
    ds.set(o, "s", Value::set(vec![f(1.0)])).unwrap();
    ds.quiesce();
    assert_eq!(changes.load(Ordering::SeqCst), 1, "dropping the NaN is a change");
}

/// A receiver whose method waits for a gate before each message.
fn gated_receiver(ds: &DataServer, name: &str) -> (Guid, crossbeam_channel::Sender<()>) {
    let o = object(ds, name);
    let (gate_tx, gate) = unbounded::<()>();
    ds.publish_method(o, MethodSpec::new("on").param(ParamSpec::any("m")), move |call| {
        let _ = gate.recv();
        call.responder.accept(vec![]);
    })
    .unwrap();
    (o, gate_tx)
}

#[test]
fn the_dropped_counter_never_goes_backwards_under_concurrent_senders() {
    let ds = DataServer::default();
    let l = ds.create_listener(ds.root(), "video").unwrap();
    let (r, gate) = gated_receiver(&ds, "window");
    let assoc = ds.join(l, r, "on", Overflow::DropOldest, 1).unwrap();
    let seen = Arc::new(parking_lot::Mutex::new(Vec::new()));
    let s = seen.clone();
    ds.subscribe(Topic::property_names(assoc, &["dropped"]), move |n| {
        s.lock().push(n.value().and_then(|v| v.as_i64()).unwrap());
    })
    .unwrap();
    let senders = 4;
    let barrier = Arc::new(Barrier::new(senders));
    let threads: Vec<_> = (0..senders)
        .map(|_| {
            let (ds, b) = (ds.clone(), barrier.clone());
            std::thread::spawn(move || {
                b.wait();
                for i in 0..500 {
                    ds.send(l, vec![Value::Int(i)]).unwrap();
                }
            })
        })
        .collect();
    for t in threads {
        t.join().unwrap();
    }
    drop(gate); // let the receiver drain
    ds.quiesce();
    let seen = seen.lock().clone();
    assert!(seen.windows(2).all(|w| w[0] < w[1]), "dropped went backwards: {seen:?}");
    let last = ds.get(assoc, "dropped").unwrap().as_i64().unwrap();
    assert_eq!(Some(&last), seen.last());
    assert!(last > 0);
}

#[test]
fn a_sender_blocked_on_a_full_queue_is_released_with_an_error_when_the_receiver_is_deleted() {
    let ds = DataServer::default();
    let l = ds.create_listener(ds.root(), "commands").unwrap();
    let (r, gate) = gated_receiver(&ds, "slow");
    let assoc = ds.join(l, r, "on", Overflow::Block, 1).unwrap();
    // One message is taken by the receiver (waiting at its gate), one fills the queue.
    ds.send(l, vec![Value::Int(0)]).unwrap();
    ds.send(l, vec![Value::Int(1)]).unwrap();
    let (done_tx, done) = unbounded();
    let ds2 = ds.clone();
    let sender =
        std::thread::spawn(move || done_tx.send(ds2.send(l, vec![Value::Int(2)])).unwrap());
    // Whether or not the sender is already waiting, deleting the receiver releases it.
    ds.delete_object(r).unwrap();
    let out = wait(&done, "the blocked sender returns");
    assert!(
        matches!(out, Err(DsError::NoSuchObject { .. }) | Ok(0)),
        "released with an error (or found the receiver gone): {out:?}"
    );
    sender.join().unwrap();
    drop(gate);
    ds.quiesce();
    assert!(!ds.exists(assoc), "the association goes with its receiver");
    assert_eq!(ds.receivers(l).unwrap(), Vec::<Guid>::new());
}

/// How many `Changed` notifications `o`'s properties have had since now.
fn count_changes(ds: &DataServer, o: Guid) -> Arc<AtomicUsize> {
    let changes = Arc::new(AtomicUsize::new(0));
    let c = changes.clone();
    ds.subscribe(Topic::properties(o), move |n| {
        if n.kind == Kind::Changed {
            c.fetch_add(1, Ordering::SeqCst);
        }
    })
    .unwrap();
    changes
}
