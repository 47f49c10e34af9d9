//! Tearing things down never runs a module's code under the DataServer's locks: a method
//! handler (or anything it owns) removed by `unpublish_method` or by deleting its object is
//! dropped after every lock is released, so its `Drop` may use the DataServer — for example
//! `unsubscribe_nowait` on a subscription of the same object, as docs/dataserver.md tells
//! module authors to — without deadlocking. Hangs are turned into failures by a bounded
//! wait on a channel, never measured.
mod common;
use common::*;
use crossbeam_channel::bounded;
use mocu_dataserver::*;
use std::time::Duration;

const EVENTUALLY: Duration = Duration::from_secs(20);

/// What a module's handler owns: its subscription on the object, ended from `Drop`, and a
/// write to the object (refused or not, it must return).
struct Owned {
    ds: DataServer,
    object: Guid,
    sub: SubscriptionId,
}

impl Drop for Owned {
    fn drop(&mut self) {
        self.ds.unsubscribe_nowait(self.sub);
        let _ = self.ds.set(self.object, "dropped", Value::Bool(true));
    }
}

/// Runs `scenario` on a thread; fails (instead of hanging) if it does not finish.
fn finishes(what: &str, scenario: impl FnOnce() + Send + 'static) {
    let (tx, rx) = bounded(1);
    std::thread::spawn(move || {
        scenario();
        let _ = tx.send(());
    });
    rx.recv_timeout(EVENTUALLY).unwrap_or_else(|_| panic!("deadlocked: {what}"));
}

fn publish_owning_handler(ds: &DataServer, o: Guid) {
    let sub = ds.subscribe(Topic::properties(o), |_| {}).unwrap();
    let owned = Owned { ds: ds.clone(), object: o, sub };
    ds.publish_method_fn(o, MethodSpec::new("m"), move |_| {
        let _ = &owned;
        CallOutcome::Accepted(vec![])
    })
    .unwrap();
}

#[test]
fn unpublishing_a_method_drops_its_handler_after_releasing_the_objects_lock() {
    let ds = DataServer::default();
    let o = object(&ds, "o");
    publish_owning_handler(&ds, o);
    let d = ds.clone();
    finishes("unpublish_method dropping a handler that uses its object", move || {
        d.unpublish_method(o, "m").unwrap();
    });
    assert_eq!(ds.get(o, "dropped").unwrap(), Value::Bool(true));
    assert!(ds.methods(o).unwrap().is_empty());
}

#[test]
fn deleting_an_object_drops_its_handlers_after_releasing_every_lock() {
    let ds = DataServer::default();
    for (parent_deleted, label) in [(false, "the object"), (true, "its parent")] {
        let parent = object(&ds, "parent");
        let o = ds.create_object(parent, ObjectInfo::new("o", "thing")).unwrap();
        publish_owning_handler(&ds, o);
        let d = ds.clone();
        finishes(&format!("deleting {label} of a handler that uses the object"), move || {
            d.delete_object(if parent_deleted { parent } else { o }).unwrap();
            // The structure lock is free again: creating an object returns.
            d.create_object(d.root(), ObjectInfo::new("after", "thing")).unwrap();
        });
        assert!(!ds.exists(o));
    }
}

#[test]
fn delete_and_promote_drops_the_deleted_objects_handlers_after_releasing_every_lock() {
    let ds = DataServer::default();
    let o = object(&ds, "o");
    let keep = ds.create_object(o, ObjectInfo::new("keep", "thing")).unwrap();
    publish_owning_handler(&ds, o);
    let d = ds.clone();
    finishes("delete_and_promote dropping a handler that uses the object", move || {
        d.delete_and_promote(o, keep).unwrap();
        d.create_object(d.root(), ObjectInfo::new("after", "thing")).unwrap();
    });
    assert!(ds.exists(keep));
}

#[test]
fn dropping_an_object_watch_waits_for_its_first_callback() {
    use std::sync::Arc;
    use std::sync::atomic::{AtomicBool, Ordering};
    let ds = DataServer::default();
    object(&ds, "a");
    let (entered_tx, entered) = bounded(1);
    let (release_tx, release) = bounded::<()>(1);
    let running = Arc::new(AtomicBool::new(false));
    let r = running.clone();
    let w = ds
        .watch_object(ds.root(), &["a"], None, move |_| {
            r.store(true, Ordering::SeqCst);
            let _ = entered_tx.send(());
            let _ = release.recv_timeout(EVENTUALLY);
            r.store(false, Ordering::SeqCst);
        })
        .unwrap();
    entered.recv_timeout(EVENTUALLY).expect("the first callback runs");
    // Released from another thread, which the drop below must wait for.
    let releaser = std::thread::spawn(move || {
        for _ in 0..100 {
            std::thread::yield_now();
        }
        let _ = release_tx.send(());
    });
    drop(w);
    assert!(!running.load(Ordering::SeqCst), "drop returned while the first callback ran");
    releaser.join().unwrap();
}

#[test]
fn no_watch_callback_starts_after_cancel_nowait_returned_even_within_one_batch() {
    use std::sync::{Arc, Mutex};
    let ds = DataServer::default();
    let a = object(&ds, "a");
    let b = object(&ds, "a");
    let slot: Arc<Mutex<Option<PathWatch>>> = Arc::default();
    let log = Arc::new(Mutex::new(Vec::new()));
    let (s, l) = (slot.clone(), log.clone());
    let w = ds
        .watch_object(ds.root(), &["a"], None, move |e: &PathEvent| {
            l.lock().unwrap().push((e.kind, e.object));
            if e.kind == Kind::Deleted
                && let Some(w) = s.lock().unwrap().take()
            {
                w.cancel_nowait();
            }
        })
        .unwrap();
    *slot.lock().unwrap() = Some(w);
    ds.quiesce();
    // The watch follows the first `a`; deleting it moves the watch to the second: one batch
    // [Deleted a, New b], cancelled after its first event.
    ds.delete_object(a).unwrap();
    ds.quiesce();
    assert_eq!(*log.lock().unwrap(), vec![(Kind::New, a), (Kind::Deleted, a)]);
    assert!(ds.exists(b));
}

/// Signals when dropped.
struct Guard(crossbeam_channel::Sender<()>);

impl Drop for Guard {
    fn drop(&mut self) {
        let _ = self.0.send(());
    }
}

#[test]
fn a_server_whose_path_watch_was_dropped_is_freed_with_its_last_handle() {
    let ds = DataServer::default();
    let o = object(&ds, "a");
    ds.set(o, "x", Value::Int(1)).unwrap();
    let (freed_tx, freed) = bounded(1);
    let guard = Guard(freed_tx);
    // Freed only with the server: the subscription stays until then.
    ds.subscribe(Topic::properties(ds.root()), move |_| {
        let _ = &guard;
    })
    .unwrap();
    let w = ds.watch_path(DottedPath::parse("root.a.x").unwrap(), None, |_| {}).unwrap();
    ds.quiesce();
    drop(w);
    ds.quiesce();
    drop(ds);
    freed.recv_timeout(EVENTUALLY).expect("the server was never freed");
}
