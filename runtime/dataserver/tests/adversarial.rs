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

// ----- a blocked callback delays only itself -----------------------------------------

/// Two callbacks that block in user code until released (as many as the default pool has
/// workers on a 2-core machine).
fn block_two(ds: &DataServer) -> (crossbeam_channel::Sender<()>, Vec<Guid>) {
    let (release_tx, release) = unbounded::<()>();
    let (started_tx, started) = unbounded();
    let mut objs = Vec::new();
    for i in 0..2 {
        let o = object(ds, &format!("blocker{i}"));
        ds.set(o, "x", Value::Int(0)).unwrap();
        let (rel, st) = (release.clone(), started_tx.clone());
        ds.subscribe(Topic::properties(o), move |n| {
            // (A New not yet delivered absorbs the change: test the value, not the kind.)
            if n.value() == Some(&Value::Int(1)) {
                st.send(()).unwrap();
                let _ = rel.recv(); // blocked until the test ends
            }
        })
        .unwrap();
        objs.push(o);
    }
    for o in &objs {
        ds.set(*o, "x", Value::Int(1)).unwrap();
    }
    wait(&started, "the first blocker starts");
    wait(&started, "the second blocker starts");
    (release_tx, objs)
}

#[test]
fn two_blocked_callbacks_stop_no_other_subscription_queued_call_stream_or_timer() {
    let ds = DataServer::new(Config { workers: 2 });
    let (release, _) = block_two(&ds);
    // A subscription.
    let o = object(&ds, "unrelated");
    let (sub_tx, sub_rx) = unbounded();
    ds.subscribe(Topic::properties(o), move |n| {
        let _ = sub_tx.send(n.value().cloned());
    })
    .unwrap();
    ds.set(o, "y", Value::Int(7)).unwrap();
    assert_eq!(wait(&sub_rx, "the unrelated subscriber is served"), Some(Value::Int(7)));
    // A queued call.
    ds.publish_method_fn(o, MethodSpec::new("ping"), |_| CallOutcome::Accepted(vec![])).unwrap();
    let (call_tx, call_rx) = unbounded();
    ds.call(o, "ping", vec![], None, move |out| call_tx.send(out).unwrap());
    assert_eq!(wait(&call_rx, "a queued call runs"), CallOutcome::Accepted(vec![]));
    // A stream.
    let l = ds.create_listener(ds.root(), "l").unwrap();
    let (msg_tx, msg_rx) = unbounded();
    ds.publish_method(o, MethodSpec::new("on_msg").param(ParamSpec::any("m")), move |call| {
        msg_tx.send(call.args[0].clone()).unwrap();
        call.responder.accept(vec![]);
    })
    .unwrap();
    ds.join(l, o, "on_msg", Overflow::Block, 4).unwrap();
    ds.send(l, vec![Value::Int(3)]).unwrap();
    assert_eq!(wait(&msg_rx, "a stream message arrives"), Value::Int(3));
    // A timer.
    let (t_tx, t_rx) = unbounded();
    ds.run_after(Duration::ZERO, None, move || t_tx.send(()).unwrap());
    wait(&t_rx, "a timer fires");
    assert!(ds.worker_count() > 2, "the pool grew past its stuck workers");
    drop(release);
    ds.quiesce();
}

#[test]
fn two_callbacks_each_waiting_on_a_call_with_a_timeout_both_return_timed_out() {
    let ds = DataServer::new(Config { workers: 2 });
    let svc = object(&ds, "service");
    // A handler that never answers (keeps its responders).
    let kept = Arc::new(Mutex::new(Vec::new()));
    let k = kept.clone();
    ds.publish_method(svc, MethodSpec::new("never"), move |call| {
        k.lock().unwrap().push(call.responder)
    })
    .unwrap();
    let (out_tx, out_rx) = unbounded();
    for i in 0..2 {
        let o = object(&ds, &format!("caller{i}"));
        ds.set(o, "go", Value::Bool(false)).unwrap();
        let (ds2, tx) = (ds.clone(), out_tx.clone());
        ds.subscribe(Topic::properties(o), move |n| {
            if n.value() == Some(&Value::Bool(true)) {
                let opts = CallOptions::queued().timeout(Duration::from_millis(30));
                tx.send(ds2.call_wait(svc, "never", vec![], Some(opts))).unwrap();
            }
        })
        .unwrap();
        ds.set(o, "go", Value::Bool(true)).unwrap();
    }
    assert_eq!(wait(&out_rx, "the first call_wait returns"), CallOutcome::TimedOut);
    assert_eq!(wait(&out_rx, "the second call_wait returns"), CallOutcome::TimedOut);
    ds.quiesce();
    assert_eq!(ds.pending_timers(), 0);
}

#[test]
fn a_single_worker_blocked_for_good_still_lets_a_serial_executor_run() {
    let ds = DataServer::new(Config { workers: 1 });
    let (release_tx, release) = unbounded::<()>();
    let (started_tx, started) = unbounded();
    let ex = ds.serial_executor();
    ds.run_after(Duration::ZERO, None, move || {
        started_tx.send(()).unwrap();
        let _ = release.recv();
    });
    wait(&started, "the blocker starts");
    let (tx, rx) = unbounded();
    ex.spawn(move || tx.send(()).unwrap());
    wait(&rx, "the serial executor's job runs");
    drop(release_tx);
}

// ----- calls resolve their target when they run ----------------------------------------

/// An object with a method that counts its runs; the counter and the server's clock.
fn counted(ds: &DataServer) -> (Guid, Arc<AtomicUsize>) {
    let o = object(ds, "target");
    let runs = count_runs(ds, o);
    (o, runs)
}

#[test]
fn a_delayed_call_answers_what_it_finds_when_it_runs_and_never_runs_a_stale_handler() {
    type Change = fn(&DataServer, Guid);
    let cases: [(&str, Change, CallOutcome); 3] = [
        ("object deleted", |ds, o| ds.delete_object(o).unwrap(), CallOutcome::NoSuchObject),
        (
            "method unpublished",
            |ds, o| ds.unpublish_method(o, "m").unwrap(),
            CallOutcome::NoSuchMethod,
        ),
        ("nothing changed", |_, _| {}, CallOutcome::Accepted(vec![])),
    ];
    for (what, change, expected) in cases {
        let (ds, clock) = manual();
        let (o, runs) = counted(&ds);
        let (tx, rx) = unbounded();
        ds.call(o, "m", vec![], Some(CallOptions::delayed(Duration::from_secs(1))), move |out| {
            tx.send(out).unwrap()
        });
        change(&ds, o);
        clock.advance(Duration::from_secs(1));
        assert_eq!(wait(&rx, what), expected, "{what}");
        ds.quiesce();
        let ran = runs.load(Ordering::SeqCst);
        assert_eq!(ran, usize::from(expected.is_accepted()), "{what}: handler runs");
    }
}

#[test]
fn a_queued_call_to_an_object_deleted_before_it_runs_answers_no_such_object() {
    let ds = DataServer::new(Config { workers: 1 });
    let (o, runs) = counted(&ds);
    // Hold the only worker so the call stays queued while the object goes.
    let (release_tx, release) = unbounded::<()>();
    let (started_tx, started) = unbounded();
    let ex = ds.serial_executor();
    ex.spawn(move || {
        started_tx.send(()).unwrap();
        let _ = release.recv();
    });
    wait(&started, "the worker is held");
    let (tx, rx) = unbounded();
    ds.call(o, "m", vec![], None, move |out| tx.send(out).unwrap());
    ds.delete_object(o).unwrap();
    drop(release_tx);
    assert_eq!(wait(&rx, "the queued call is answered"), CallOutcome::NoSuchObject);
    ds.quiesce();
    assert_eq!(runs.load(Ordering::SeqCst), 0);
}

#[test]
fn a_call_answered_timed_out_before_it_runs_never_runs() {
    let (ds, clock) = manual();
    let (o, runs) = counted(&ds);
    let (tx, rx) = unbounded();
    let opts = CallOptions::delayed(Duration::from_secs(2)).timeout(Duration::from_secs(1));
    ds.call(o, "m", vec![], Some(opts), move |out| tx.send(out).unwrap());
    clock.advance(Duration::from_secs(1));
    assert_eq!(wait(&rx, "the timeout"), CallOutcome::TimedOut);
    clock.advance(Duration::from_secs(1));
    ds.quiesce();
    assert_eq!(runs.load(Ordering::SeqCst), 0, "the handler never runs after TimedOut");
    assert!(rx.try_recv().is_err(), "answered once");
}

#[test]
fn an_answered_call_releases_its_timeout_timer_at_once() {
    let (ds, _clock) = manual();
    let (o, _runs) = counted(&ds);
    for _ in 0..100 {
        let opts = CallOptions::queued().timeout(Duration::from_secs(3600));
        assert!(ds.call_wait(o, "m", vec![], Some(opts)).is_accepted());
    }
    let opts = CallOptions::immediate().timeout(Duration::from_secs(3600));
    assert!(ds.call_wait(o, "m", vec![], Some(opts)).is_accepted());
    assert_eq!(ds.pending_timers(), 0);
}

// ----- watches follow the tree exactly -----------------------------------------------

type Events = Arc<Mutex<Vec<(Kind, Guid)>>>;

fn events_of(ds: &DataServer, log: &Events) -> Vec<(Kind, Guid)> {
    ds.quiesce();
    std::mem::take(&mut *log.lock().unwrap())
}

fn logger(log: &Events) -> impl FnMut(&PathEvent) + Send + 'static {
    let l = log.clone();
    move |e: &PathEvent| l.lock().unwrap().push((e.kind, e.object))
}

#[test]
fn watches_started_from_an_object_report_deleted_when_that_object_is_deleted() {
    let ds = DataServer::default();
    let v = object(&ds, "usv1");
    let nav = ds.create_object(v, ObjectInfo::new("nav", "nav")).unwrap();
    ds.set(nav, "speed", Value::Float(1.0)).unwrap();
    let log: Events = Arc::default();
    let _a = ds.watch_path_from(v, DottedPath::parse("nav.speed").unwrap(), None, logger(&log));
    let _b = ds.watch_object(v, &[], None, logger(&log)).unwrap();
    let _c = ds.watch_object(v, &["nav"], None, logger(&log)).unwrap();
    let mut first = events_of(&ds, &log);
    first.sort_by_key(|e| e.1);
    assert_eq!(first, vec![(Kind::New, v), (Kind::New, nav), (Kind::New, nav)]);
    ds.delete_object(v).unwrap();
    let mut gone = events_of(&ds, &log);
    gone.sort_by_key(|e| e.1);
    assert_eq!(gone, vec![(Kind::Deleted, v), (Kind::Deleted, nav), (Kind::Deleted, nav)]);
}

#[test]
fn a_watch_follows_the_first_sibling_of_that_name_as_siblings_come_and_get_renamed() {
    let ds = DataServer::default();
    let b = object(&ds, "v");
    ds.set(b, "x", Value::Int(2)).unwrap();
    let log: Events = Arc::default();
    let _w = ds.watch_path(DottedPath::parse("v.x").unwrap(), None, logger(&log)).unwrap();
    assert_eq!(events_of(&ds, &log), vec![(Kind::New, b)]);
    // An earlier sibling of the same name is created: it is now the first.
    let a = ds.create_object_at(ds.root(), 0, ObjectInfo::new("v", "thing")).unwrap();
    ds.set(a, "x", Value::Int(1)).unwrap();
    assert_eq!(ds.resolve(&["v"]), Some(a));
    let ev = events_of(&ds, &log);
    assert_eq!(ev.last(), Some(&(Kind::New, a)), "{ev:?}");
    // It is renamed away: back to the later one.
    ds.set_info(a, ObjectInfo::new("w", "thing")).unwrap();
    assert_eq!(events_of(&ds, &log), vec![(Kind::Deleted, a), (Kind::New, b)]);
    // An earlier sibling is renamed to the name: it takes over.
    ds.set_info(a, ObjectInfo::new("v", "thing")).unwrap();
    assert_eq!(events_of(&ds, &log), vec![(Kind::Deleted, b), (Kind::New, a)]);
}

#[test]
fn a_watchs_first_callback_runs_on_its_executor_never_on_the_callers_thread() {
    let ds = DataServer::default();
    let v = object(&ds, "usv1");
    ds.set(v, "speed", Value::Float(1.0)).unwrap();
    let me = std::thread::current().id();
    let ex = ds.serial_executor();
    let (tx, rx) = unbounded();
    let tx2 = tx.clone();
    let _p = ds
        .watch_path(DottedPath::parse("usv1.speed").unwrap(), Some(&ex), move |_| {
            tx.send(std::thread::current().id()).unwrap()
        })
        .unwrap();
    let _o = ds
        .watch_object(ds.root(), &["usv1"], Some(&ex), move |_| {
            tx2.send(std::thread::current().id()).unwrap()
        })
        .unwrap();
    assert_ne!(wait(&rx, "the path watch's first event"), me);
    assert_ne!(wait(&rx, "the object watch's first event"), me);
}

// ----- no race bypasses the type and range rules -------------------------------------

#[test]
fn update_racing_delete_property_never_creates_an_untyped_out_of_range_property() {
    let ds = DataServer::default();
    let o = object(&ds, "o");
    let meta = PropMeta::typed(ValueKind::Float).range(0.0, 1.0);
    for round in 0..300 {
        ds.create_property(o, "p", Value::Float(0.5), meta.clone()).unwrap();
        let barrier = Arc::new(Barrier::new(2));
        let (ds2, b2) = (ds.clone(), barrier.clone());
        let deleter = std::thread::spawn(move || {
            b2.wait();
            let _ = ds2.delete_property(o, "p");
        });
        barrier.wait();
        // In range for the metadata, so only a racing delete can make it refused.
        let _ = ds.update(o, "p", Value::Float(0.75));
        let _ = ds.update(o, "p", Value::Int(99)); // out of range: always refused
        deleter.join().unwrap();
        if let Ok(v) = ds.get(o, "p") {
            assert_eq!(
                ds.meta(o, "p").unwrap(),
                meta,
                "round {round}: the property kept its rules"
            );
            assert!(v == Value::Float(0.5) || v == Value::Float(0.75), "round {round}: {v:?}");
            ds.delete_property(o, "p").unwrap();
        }
    }
}

// ----- delivery goes on ------------------------------------------------------------

#[test]
fn a_callback_that_panics_on_deleted_still_gets_the_rest_of_its_batch() {
    let ds = DataServer::new(Config { workers: 1 });
    let o = object(&ds, "o");
    let (log, mut rec) = recorder();
    // Hold the worker so that the whole sequence arrives as one batch.
    let (release_tx, release) = unbounded::<()>();
    let (started_tx, started) = unbounded();
    ds.serial_executor().spawn(move || {
        started_tx.send(()).unwrap();
        let _ = release.recv();
    });
    wait(&started, "the worker is held");
    ds.subscribe(Topic::properties(o), move |n| {
        rec(n);
        if n.kind == Kind::Deleted {
            panic!("a module's bug on Deleted");
        }
    })
    .unwrap();
    ds.set(o, "a", Value::Int(1)).unwrap();
    ds.delete_property(o, "a").unwrap();
    ds.set(o, "b", Value::Int(2)).unwrap();
    ds.delete_property(o, "b").unwrap();
    ds.set(o, "c", Value::Int(3)).unwrap();
    drop(release_tx);
    ds.quiesce();
    let got: Vec<_> = prop_events(&log).into_iter().map(|(k, n, _)| (k, n)).collect();
    let want = [
        (Kind::New, "a"),
        (Kind::Deleted, "a"),
        (Kind::New, "b"),
        (Kind::Deleted, "b"),
        (Kind::New, "c"),
    ];
    assert_eq!(got, want.map(|(k, n)| (k, n.to_string())).to_vec());
    assert_eq!(ds.stats().panics_caught.load(Ordering::Relaxed), 2);
}

#[test]
fn a_path_callback_that_panics_on_deleted_still_gets_the_new_binding_after_it() {
    let ds = DataServer::default();
    let a = object(&ds, "v");
    ds.set(a, "x", Value::Int(1)).unwrap();
    let b = object(&ds, "v");
    ds.set(b, "x", Value::Int(2)).unwrap();
    let log: Events = Arc::default();
    let mut inner = logger(&log);
    let _w = ds
        .watch_path(DottedPath::parse("v.x").unwrap(), None, move |e: &PathEvent| {
            inner(e);
            if e.kind == Kind::Deleted {
                panic!("a module's bug on Deleted");
            }
        })
        .unwrap();
    assert_eq!(events_of(&ds, &log), vec![(Kind::New, a)]);
    ds.delete_object(a).unwrap();
    assert_eq!(events_of(&ds, &log), vec![(Kind::Deleted, a), (Kind::New, b)]);
}
