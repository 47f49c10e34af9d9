//! Methods: call feedback, immediate / queued / delayed calls, timeouts, periodic work.
mod common;
use common::manual;
use mocu_dataserver::*;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::{Arc, Mutex};
use std::time::Duration;

fn vehicle(ds: &DataServer) -> Guid {
    let v = ds.create_object(Guid::ROOT, ObjectInfo::new("usv1", "usv")).unwrap();
    ds.set(v, "engine", Value::Bool(false)).unwrap();
    let ds2 = ds.clone();
    ds.publish_method_fn(
        v,
        MethodSpec::new("start_engine").describe("Starts the engine"),
        move |_args| {
            if ds2.get(v, "engine") == Ok(Value::Bool(true)) {
                return CallOutcome::Refused("engine already running".into());
            }
            ds2.set(v, "engine", Value::Bool(true)).unwrap();
            CallOutcome::Accepted(vec![])
        },
    )
    .unwrap();
    ds.publish_method_fn(
        v,
        MethodSpec::new("arm").param(ParamSpec::new("on", ValueKind::Bool)),
        |args| CallOutcome::Accepted(vec![args[0].clone()]),
    )
    .unwrap();
    v
}

#[test]
fn a_call_is_accepted_then_refused_with_the_modules_reason() {
    let ds = DataServer::default();
    let v = vehicle(&ds);
    assert_eq!(ds.call_wait(v, "start_engine", vec![], None), CallOutcome::Accepted(vec![]));
    assert_eq!(
        ds.call_wait(v, "start_engine", vec![], None),
        CallOutcome::Refused("engine already running".into())
    );
    assert_eq!(
        ds.call_wait(v, "arm", vec![Value::Bool(true)], None),
        CallOutcome::Accepted(vec![Value::Bool(true)])
    );
}

#[test]
fn missing_objects_methods_and_bad_arguments_have_their_own_outcomes() {
    let ds = DataServer::default();
    let v = vehicle(&ds);
    assert_eq!(ds.call_wait(v, "fly", vec![], None), CallOutcome::NoSuchMethod);
    assert_eq!(
        ds.call_wait(Guid::new(999).unwrap(), "arm", vec![], None),
        CallOutcome::NoSuchObject
    );
    match ds.call_wait(v, "arm", vec![Value::Int(1)], None) {
        CallOutcome::Failed(why) => assert!(why.contains("`on`") && why.contains("bool"), "{why}"),
        other => panic!("{other:?}"),
    }
    match ds.call_wait(v, "arm", vec![], None) {
        CallOutcome::Failed(why) => assert!(why.contains("takes 1"), "{why}"),
        other => panic!("{other:?}"),
    }
}

#[test]
fn methods_are_listed_with_their_specs() {
    let ds = DataServer::default();
    let v = vehicle(&ds);
    let names: Vec<String> = ds.methods(v).unwrap().iter().map(|m| m.name.to_string()).collect();
    assert_eq!(names, ["arm", "start_engine"]);
    let arm = &ds.methods(v).unwrap()[0];
    assert_eq!(arm.params, vec![ParamSpec::new("on", ValueKind::Bool)]);
    let e = ds
        .publish_method_fn(v, MethodSpec::new("arm"), |_| CallOutcome::Accepted(vec![]))
        .unwrap_err();
    assert!(matches!(e, DsError::MethodExists { .. }));
}

#[test]
fn immediate_calls_run_on_the_callers_thread_and_queued_calls_do_not() {
    let ds = DataServer::default();
    let o = ds.create_object(Guid::ROOT, ObjectInfo::new("w", "window")).unwrap();
    let ran_on = Arc::new(Mutex::new(Vec::new()));
    let r = ran_on.clone();
    ds.publish_method(o, MethodSpec::new("paint"), move |call: Call| {
        r.lock().unwrap().push(std::thread::current().id());
        call.responder.accept(vec![]);
    })
    .unwrap();
    let me = std::thread::current().id();
    let done_on = Arc::new(Mutex::new(None));
    let d = done_on.clone();
    ds.call(o, "paint", vec![], Some(CallOptions::immediate()), move |out| {
        *d.lock().unwrap() = Some((std::thread::current().id(), out));
    });
    assert_eq!(
        *done_on.lock().unwrap(),
        Some((me, CallOutcome::Accepted(vec![]))),
        "answered before call() returned"
    );
    assert_eq!(
        ds.call_wait(o, "paint", vec![], Some(CallOptions::queued())),
        CallOutcome::Accepted(vec![])
    );
    let ran = ran_on.lock().unwrap();
    assert_eq!(ran[0], me);
    assert_ne!(ran[1], me);
}

#[test]
fn a_delayed_call_runs_after_its_delay_and_not_before() {
    let (ds, clock) = manual();
    let v = vehicle(&ds);
    let (tx, rx) = crossbeam_channel::unbounded();
    ds.call(
        v,
        "arm",
        vec![Value::Bool(false)],
        Some(CallOptions::delayed(Duration::from_millis(60))),
        move |out| tx.send(out).unwrap(),
    );
    clock.advance(Duration::from_millis(59));
    ds.quiesce();
    assert!(rx.try_recv().is_err(), "not before its delay");
    clock.advance(Duration::from_millis(1));
    ds.quiesce();
    assert!(rx.try_recv().unwrap().is_accepted());
}

#[test]
fn a_handler_may_answer_later_from_another_thread_or_time_out() {
    let (ds, clock) = manual();
    let o = ds.create_object(Guid::ROOT, ObjectInfo::new("mav1", "uav")).unwrap();
    // Answers when the vehicle "acknowledges", from a protocol thread; `arm(false)` is
    // acknowledged only when the test says so.
    let (ack_tx, ack) = crossbeam_channel::unbounded::<()>();
    ds.publish_method(
        o,
        MethodSpec::new("arm").param(ParamSpec::new("on", ValueKind::Bool)),
        move |call: Call| {
            let on = call.args[0].as_bool().unwrap();
            let (responder, ack) = (call.responder, ack.clone());
            std::thread::spawn(move || {
                if !on {
                    let _ = ack.recv();
                }
                responder.accept(vec![])
            });
        },
    )
    .unwrap();
    assert!(ds.call_wait(o, "arm", vec![Value::Bool(true)], None).is_accepted());
    let (tx, rx) = crossbeam_channel::unbounded();
    ds.call(
        o,
        "arm",
        vec![Value::Bool(false)],
        Some(CallOptions::queued().timeout(Duration::from_millis(50))),
        move |out| tx.send(out).unwrap(),
    );
    clock.advance(Duration::from_millis(50));
    // The timeout is answered on the timer thread: wait for that answer (bounded only so that
    // a lost answer fails instead of hanging).
    assert_eq!(rx.recv_timeout(Duration::from_secs(30)), Ok(CallOutcome::TimedOut));
    ack_tx.send(()).unwrap();
    ds.quiesce();
    assert!(rx.try_recv().is_err(), "the late acknowledgement answers nobody");
}

#[test]
fn a_handler_that_drops_its_call_or_panics_answers_failed() {
    let ds = DataServer::default();
    let o = ds.create_object(Guid::ROOT, ObjectInfo::new("m", "t")).unwrap();
    ds.publish_method(o, MethodSpec::new("forget"), |_call: Call| {}).unwrap();
    ds.publish_method(o, MethodSpec::new("boom"), |_call: Call| panic!("module bug")).unwrap();
    assert!(matches!(ds.call_wait(o, "forget", vec![], None), CallOutcome::Failed(_)));
    assert!(matches!(ds.call_wait(o, "boom", vec![], None), CallOutcome::Failed(_)));
    assert!(matches!(
        ds.call_wait(o, "boom", vec![], Some(CallOptions::immediate())),
        CallOutcome::Failed(_)
    ));
    assert!(
        ds.call_wait(o, "forget", vec![], None) != CallOutcome::NoSuchObject,
        "the server lives on"
    );
}

#[test]
fn periodic_work_rearms_a_delayed_call_without_a_thread_of_its_own() {
    fn tick(ds: DataServer, ex: Executor, n: Arc<AtomicUsize>) {
        if n.fetch_add(1, Ordering::SeqCst) + 1 < 5 {
            let (d, e) = (ds.clone(), ex.clone());
            ds.run_after(Duration::from_millis(5), Some(&ex), move || tick(d, e, n));
        }
    }
    let (ds, clock) = manual();
    let ex = ds.serial_executor();
    let n = Arc::new(AtomicUsize::new(0));
    tick(ds.clone(), ex, n.clone());
    for expected in 2..=5 {
        ds.quiesce();
        clock.advance(Duration::from_millis(5));
        ds.quiesce();
        assert_eq!(n.load(Ordering::SeqCst), expected);
    }
    clock.advance(Duration::from_secs(60));
    ds.quiesce();
    assert_eq!(n.load(Ordering::SeqCst), 5, "stops when no longer re-armed");
    assert_eq!(ds.pending_timers(), 0);
}

#[test]
fn an_ordered_method_published_again_keeps_the_order_of_calls_made_before_and_after() {
    let ds = DataServer::default();
    let v = ds.create_object(Guid::ROOT, ObjectInfo::new("window", "window")).unwrap();
    let spec = MethodSpec::new("key").param(ParamSpec::new("n", ValueKind::Int)).ordered();
    let (entered_tx, entered) = crossbeam_channel::bounded::<()>(1);
    let (release_tx, release) = crossbeam_channel::bounded::<()>(1);
    let release = Mutex::new(release);
    ds.publish_method_fn(v, spec.clone(), move |_| {
        let _ = entered_tx.send(());
        let _ = release.lock().unwrap().recv_timeout(Duration::from_secs(20));
        CallOutcome::Accepted(vec![])
    })
    .unwrap();
    ds.call(v, "key", vec![Value::Int(1)], None, |_| {});
    entered.recv_timeout(Duration::from_secs(20)).expect("the first call runs");
    ds.call(v, "key", vec![Value::Int(2)], None, |_| {}); // queued behind the first
    ds.unpublish_method(v, "key").unwrap();
    let seen = Arc::new(Mutex::new(Vec::new()));
    let s = seen.clone();
    ds.publish_method_fn(v, spec, move |args| {
        s.lock().unwrap().push(args[0].as_i64().unwrap());
        CallOutcome::Accepted(vec![])
    })
    .unwrap();
    ds.call(v, "key", vec![Value::Int(3)], None, |_| {});
    release_tx.send(()).unwrap();
    ds.quiesce();
    assert_eq!(*seen.lock().unwrap(), [2, 3], "a call made later overtook one made earlier");
}

#[test]
fn an_ordered_methods_queued_calls_run_one_at_a_time_in_the_order_they_were_made() {
    // Pointer and key input: a release that overtook its press would be another gesture.
    // The first call blocks until every other one is queued; on the bare pool the others
    // would run meanwhile, on the spec's own serial executor they wait their turn.
    let ds = DataServer::default();
    let v = ds.create_object(Guid::ROOT, ObjectInfo::new("window", "window")).unwrap();
    let seen = Arc::new(Mutex::new(Vec::new()));
    let (release_tx, release_rx) = crossbeam_channel::bounded::<()>(1);
    let (seen2, release_rx) = (seen.clone(), Mutex::new(release_rx));
    let spec = MethodSpec::new("pointer").param(ParamSpec::new("n", ValueKind::Int)).ordered();
    ds.publish_method_fn(v, spec, move |args| {
        let n = args[0].as_i64().unwrap();
        if n == 0 {
            let _ = release_rx.lock().unwrap().recv();
        }
        seen2.lock().unwrap().push(n);
        CallOutcome::Accepted(vec![])
    })
    .unwrap();
    for n in 0..64 {
        ds.call(v, "pointer", vec![Value::Int(n)], None, |_| {});
    }
    release_tx.send(()).unwrap();
    ds.quiesce();
    assert_eq!(*seen.lock().unwrap(), (0..64).collect::<Vec<_>>());
}
