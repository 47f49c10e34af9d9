//! Control arbitration across sites in one test process (docs/distribution.md, "Control
//! arbitration"): an adapter arbitrating its vehicle and two OCUs, alice and bob, each with
//! its own DataServer and Zenoh session on loopback. The operator travels with each call;
//! a takeover the holder is asked for is answered from the holder's screen; the adapter's
//! release timer runs on its ManualClock. Every wait is on a condition (a path watch's
//! events), bounded so that a failure fails instead of hanging.

use crossbeam_channel::{Receiver, unbounded};
use mocu_dataserver::{
    CallOutcome, Clock, Config as DsConfig, DataServer, ManualClock, MethodSpec, ObjectInfo, Value,
};
use mocu_distrib::arbiter::Settings;
use mocu_distrib::control::Takeover;
use mocu_distrib::{Config, Distrib};
use std::collections::HashMap;
use std::sync::Arc;
use std::time::Duration;

const RELEASE: Duration = Duration::from_secs(5);

mod sites;
mod support;
use sites::ocu;
use support::{PATIENCE, free_port, until, watch};

/// The adapter: usv1, whose holder is asked for a takeover, with a `stop` method.
fn adapter(port: u16) -> (DataServer, ManualClock, Distrib) {
    let clock = ManualClock::new();
    let ds = DataServer::with_clock(DsConfig::default(), Arc::new(clock.clone()));
    let vs = ds.create_object(ds.root(), ObjectInfo::new("vehicles", "vehicles")).unwrap();
    let v = ds.create_object(vs, ObjectInfo::new("usv1", "usv")).unwrap();
    ds.publish_method_fn(v, MethodSpec::new("stop"), |_| CallOutcome::Accepted(vec![])).unwrap();
    let config = Config {
        site: "adapter".into(),
        listen: vec![format!("tcp/127.0.0.1:{port}")],
        share: vec!["vehicles".into()],
        control: Some(Settings {
            vehicles: HashMap::from([("usv1".to_string(), Takeover::Ask)]),
            release_after: RELEASE,
            ..Settings::default()
        }),
        ..Config::default()
    };
    let d = Distrib::start(&ds, &config, None).unwrap();
    (ds, clock, d)
}

/// Calls a method of a mirrored object; the outcome arrives on the receiver.
fn call(ds: &DataServer, path: &[&str], method: &str, args: Vec<Value>) -> Receiver<CallOutcome> {
    let g = ds.resolve(path).unwrap_or_else(|| panic!("{path:?} mirrored"));
    let (tx, rx) = unbounded();
    ds.call(g, method, args, None, move |o| {
        let _ = tx.send(o);
    });
    rx
}

fn outcome(rx: Receiver<CallOutcome>) -> CallOutcome {
    rx.recv_timeout(PATIENCE).expect("an outcome")
}

const USV1: [&str; 2] = ["vehicles", "usv1"];
const ARB: [&str; 3] = ["vehicles", "usv1", "arbitration"];

#[test]
fn the_operator_travels_with_each_call_and_a_takeover_is_answered_from_the_holders_screen() {
    let port = free_port();
    let (_a, _clock, _da) = adapter(port);
    let (alice, _dal) = ocu("alice", port);
    let (bob, _dbo) = ocu("bob", port);
    let (_w, holder) = watch(&bob, "vehicles.usv1.arbitration.holder");

    assert_eq!(outcome(call(&alice, &ARB, "request", vec![])), CallOutcome::Accepted(vec![]));
    until(&holder, "usv1's holder on bob's screen", &Value::str("alice"));
    assert_eq!(
        outcome(call(&bob, &USV1, "stop", vec![])),
        CallOutcome::Refused("usv1 is controlled by alice: request a takeover first".into())
    );
    assert_eq!(outcome(call(&alice, &USV1, "stop", vec![])), CallOutcome::Accepted(vec![]));

    // bob asks; alice's screen shows it; her answer decides bob's call.
    let (_w2, asking) = watch(&alice, "vehicles.usv1.arbitration.requested_by");
    let bobs = call(&bob, &ARB, "takeover", vec![]);
    until(&asking, "bob's request on alice's screen", &Value::str("bob"));
    assert_eq!(
        outcome(call(&bob, &ARB, "answer", vec![Value::Bool(true)])),
        CallOutcome::Refused("only alice can answer for usv1".into()),
        "bob cannot answer for alice"
    );
    assert_eq!(
        outcome(call(&alice, &ARB, "answer", vec![Value::Bool(true)])),
        CallOutcome::Accepted(vec![])
    );
    assert_eq!(outcome(bobs), CallOutcome::Accepted(vec![]));
    until(&holder, "usv1's holder after the handover", &Value::str("bob"));
    assert_eq!(outcome(call(&bob, &USV1, "stop", vec![])), CallOutcome::Accepted(vec![]));
}

#[test]
fn a_holder_whose_ocu_leaves_loses_control_when_the_adapters_clock_passes_the_timeout() {
    let port = free_port();
    let (a, clock, _da) = adapter(port);
    let (alice, dal) = ocu("alice", port);
    let (_wh, holder) = watch(&a, "vehicles.usv1.arbitration.holder");
    let (_wc, connected) = watch(&a, "vehicles.usv1.arbitration.holder_connected");
    assert_eq!(outcome(call(&alice, &ARB, "request", vec![])), CallOutcome::Accepted(vec![]));
    until(&holder, "alice holding usv1", &Value::str("alice"));
    until(&connected, "alice connected", &Value::Bool(true));
    dal.stop();
    until(&connected, "alice gone (liveliness)", &Value::Bool(false));
    a.advance_settled(&clock, clock.now() + RELEASE - Duration::from_millis(1));
    let g = a.resolve(&ARB).unwrap();
    assert_eq!(a.get(g, "holder").unwrap(), Value::str("alice"), "not yet");
    a.advance_settled(&clock, clock.now() + Duration::from_millis(1));
    assert_eq!(a.get(g, "holder").unwrap(), Value::str(""), "released at the timeout");
}
