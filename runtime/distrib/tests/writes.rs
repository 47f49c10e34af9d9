//! Forwarded writes across sites in one test process (docs/distribution.md, "Forwarded
//! writes"): an adapter arbitrating usv1, whose `goal_speed` is a float in 0..10, and two
//! OCUs, alice and bob, mirroring it over loopback Zenoh. A write to the mirror goes to the
//! adapter as `write_at_owner(name, value)`; the adapter screens it like a command and
//! writes through its DataServer's checked write; the value comes back by replication.

use crossbeam_channel::{Receiver, unbounded};
use mocu_dataserver::{
    CallOutcome, DataServer, ObjectInfo, PropMeta, Value, ValueKind, WRITE_AT_OWNER,
};
use mocu_distrib::arbiter::Settings;
use mocu_distrib::{Config, Distrib};

mod sites;
mod support;
use sites::ocu;
use support::{PATIENCE, free_port, until, watch};

const USV1: [&str; 2] = ["vehicles", "usv1"];
const ARB: [&str; 3] = ["vehicles", "usv1", "arbitration"];

fn adapter(port: u16) -> (DataServer, Distrib) {
    let ds = DataServer::default();
    let vs = ds.create_object(ds.root(), ObjectInfo::new("vehicles", "vehicles")).unwrap();
    let v = ds.create_object(vs, ObjectInfo::new("usv1", "usv")).unwrap();
    let meta = PropMeta::typed(ValueKind::Float).range(0.0, 10.0).units("m/s");
    ds.create_property(v, "goal_speed", Value::Float(1.0), meta).unwrap();
    let config = Config {
        site: "adapter".into(),
        listen: vec![format!("tcp/127.0.0.1:{port}")],
        share: vec!["vehicles".into()],
        control: Some(Settings::default()),
        ..Config::default()
    };
    let d = Distrib::start(&ds, &config, None).unwrap();
    (ds, d)
}

fn call(ds: &DataServer, path: &[&str], method: &str, args: Vec<Value>) -> CallOutcome {
    let g = ds.resolve(path).unwrap_or_else(|| panic!("{path:?} mirrored"));
    let (tx, rx): (_, Receiver<CallOutcome>) = unbounded();
    ds.call(g, method, args, None, move |o| {
        let _ = tx.send(o);
    });
    rx.recv_timeout(PATIENCE).expect("an outcome")
}

/// Writes usv1's `name` from an OCU the way the layout's `set` does on a mirror.
fn write(ds: &DataServer, name: &str, value: Value) -> CallOutcome {
    call(ds, &USV1, WRITE_AT_OWNER, vec![Value::str(name), value])
}

fn goal(ds: &DataServer) -> Option<Value> {
    ds.try_get(ds.resolve(&USV1).unwrap(), "goal_speed".into())
}

#[test]
fn a_holders_goal_write_reaches_the_owner_and_comes_back_by_replication() {
    let port = free_port();
    let (a, _da) = adapter(port);
    let (alice, _dal) = ocu("alice", port);
    let (_w, mirrored) = watch(&alice, "vehicles.usv1.goal_speed");
    assert_eq!(call(&alice, &ARB, "request", vec![]), CallOutcome::Accepted(vec![]));

    assert_eq!(write(&alice, "goal_speed", Value::Float(4.5)), CallOutcome::Accepted(vec![]));
    assert_eq!(goal(&a), Some(Value::Float(4.5)), "written at the adapter");
    until(&mirrored, "alice's mirror of goal_speed", &Value::Float(4.5));
}

#[test]
fn a_non_holders_goal_write_is_refused_naming_the_holder_and_leaves_both_copies_alone() {
    let port = free_port();
    let (a, _da) = adapter(port);
    let (alice, _dal) = ocu("alice", port);
    let (bob, _dbo) = ocu("bob", port);
    assert_eq!(call(&alice, &ARB, "request", vec![]), CallOutcome::Accepted(vec![]));

    assert_eq!(
        write(&bob, "goal_speed", Value::Float(9.0)),
        CallOutcome::Refused("usv1 is controlled by alice: request a takeover first".into())
    );
    assert_eq!(goal(&a), Some(Value::Float(1.0)), "the adapter's value");
    assert_eq!(goal(&bob), Some(Value::Float(1.0)), "bob's mirror never shows the refused value");
}

#[test]
fn a_write_the_owners_dataserver_refuses_is_answered_with_its_reason() {
    let port = free_port();
    let (a, _da) = adapter(port);
    let (alice, _dal) = ocu("alice", port);
    assert_eq!(call(&alice, &ARB, "request", vec![]), CallOutcome::Accepted(vec![]));
    let v = a.resolve(&USV1).unwrap();

    for bad in [Value::str("fast"), Value::Float(42.0)] {
        let reason = a.set(v, "goal_speed", bad.clone()).unwrap_err().to_string();
        assert_eq!(
            write(&alice, "goal_speed", bad.clone()),
            CallOutcome::Refused(reason),
            "{bad:?}"
        );
    }
    assert_eq!(goal(&a), Some(Value::Float(1.0)));
}

#[test]
fn the_arbitration_state_and_object_references_are_not_writable_from_another_site() {
    let port = free_port();
    let (_a, _da) = adapter(port);
    let (alice, _dal) = ocu("alice", port);
    let arb = alice.resolve(&ARB).unwrap();
    assert_eq!(
        call(&alice, &ARB, WRITE_AT_OWNER, vec![Value::str("holder"), Value::str("alice")]),
        CallOutcome::Refused(
            "usv1.arbitration changes only through its methods (request, release, takeover, \
             answer)"
                .into()
        )
    );
    assert_eq!(
        write(&alice, "target", Value::Guid(arb)),
        CallOutcome::Refused(
            "an object reference cannot be written to another site's object".into()
        )
    );
}
