//! Two sites in one test process, each with its own DataServer and Zenoh session, on
//! loopback: what one publishes the other mirrors, calls come back with their outcomes, a
//! late joiner starts from a snapshot, a site that leaves shows stale. Every wait is on a
//! condition (a path watch's events), bounded so that a failure fails instead of hanging.

use crossbeam_channel::unbounded;
use mocu_dataserver::{
    CallOutcome, DataServer, Kind, MethodSpec, ObjectInfo, ParamSpec, PropMeta, Value, ValueKind,
};
use mocu_distrib::{Config, Distrib};
use std::time::Duration;

mod support;
use support::{PATIENCE, free_port, until, watch};

fn adapter(port: u16) -> Config {
    Config {
        site: "adapter".into(),
        listen: vec![format!("tcp/127.0.0.1:{port}")],
        share: vec!["root.vehicles".into()],
        ..Config::default()
    }
}

fn ocu(name: &str, port: u16) -> Config {
    Config {
        site: name.into(),
        operator: name.into(),
        connect: vec![format!("tcp/127.0.0.1:{port}")],
        call_timeout: Duration::from_secs(5),
        ..Config::default()
    }
}

/// A vehicle the way modules publish one: typed properties with metadata, a child, methods.
fn publish_vehicle(ds: &DataServer, name: &str) -> (mocu_dataserver::Guid, mocu_dataserver::Guid) {
    let vs = match ds.resolve(&["vehicles"]) {
        Some(g) => g,
        None => ds.create_object(ds.root(), ObjectInfo::new("vehicles", "vehicles")).unwrap(),
    };
    let v = ds.create_object(vs, ObjectInfo::new(name, "usv").subtype("catamaran")).unwrap();
    let nav = ds.create_object(v, ObjectInfo::new("nav", "nav")).unwrap();
    let speed = PropMeta::typed(ValueKind::Float).units("m/s").range(0.0, 20.0).rate(10.0);
    ds.create_property(nav, "speed", Value::Float(1.5), speed).unwrap();
    ds.set(v, "stale", Value::Bool(false)).unwrap();
    ds.set(v, "armed", Value::Bool(false)).unwrap();
    ds.set(v, "nav_object", Value::Guid(nav)).unwrap();
    let spec = MethodSpec::new("arm").param(ParamSpec::new("on", ValueKind::Bool));
    let d2 = ds.clone();
    ds.publish_method_fn(v, spec, move |args| match args.first() {
        Some(Value::Bool(true)) if d2.try_get(v, "armed".into()) == Some(Value::Bool(true)) => {
            CallOutcome::Refused("already armed".into())
        }
        Some(Value::Bool(on)) => {
            let _ = d2.set(v, "armed", Value::Bool(*on));
            CallOutcome::Accepted(vec![])
        }
        _ => CallOutcome::Failed("arm takes a bool".into()),
    })
    .unwrap();
    ds.publish_method_fn(v, MethodSpec::new("never"), |_| CallOutcome::TimedOut).unwrap();
    (v, nav)
}

fn call(ds: &DataServer, path: &[&str], method: &str, args: Vec<Value>) -> CallOutcome {
    let g = ds.resolve(path).expect("the mirrored object");
    ds.call_wait(g, method, args, None)
}

#[test]
fn a_joiner_mirrors_objects_properties_metadata_and_methods_and_calls_come_back_with_their_outcome()
{
    let port = free_port();
    let a = DataServer::default();
    let (v, nav) = publish_vehicle(&a, "usv1");
    let da = Distrib::start(&a, &adapter(port), None).unwrap();

    let b = DataServer::default();
    let (_w, speed) = watch(&b, "vehicles.usv1.nav.speed");
    let db = Distrib::start(&b, &ocu("alice", port), None).unwrap();
    assert!(db.wait_snapshots(1, PATIENCE), "the adapter's snapshot");
    until(&speed, "usv1.nav.speed (snapshot)", &Value::Float(1.5));

    // Names, types and metadata (the publisher's rate is left to liveliness).
    let bv = b.resolve(&["vehicles", "usv1"]).unwrap();
    let info = b.info(bv).unwrap();
    assert_eq!((&*info.kind, &*info.subtype), ("usv", "catamaran"));
    let bnav = b.resolve(&["vehicles", "usv1", "nav"]).unwrap();
    let m = b.meta(bnav, "speed").unwrap();
    assert_eq!(
        (m.kind, m.units.as_deref(), m.range, m.rate_hz),
        (Some(ValueKind::Float), Some("m/s"), Some((0.0, 20.0)), None)
    );

    // A GUID value names the mirror's own object.
    assert_eq!(b.get(bv, "nav_object").unwrap(), Value::Guid(bnav));

    // Updates, in order.
    for x in [2.0, 3.0, 4.5] {
        a.set(nav, "speed", Value::Float(x)).unwrap();
    }
    until(&speed, "usv1.nav.speed (update)", &Value::Float(4.5));

    // Calls: accepted (and its effect mirrored back), refused with the reason, failed,
    // no such method at the source.
    let (_w2, armed) = watch(&b, "vehicles.usv1.armed");
    assert_eq!(
        call(&b, &["vehicles", "usv1"], "arm", vec![Value::Bool(true)]),
        CallOutcome::Accepted(vec![])
    );
    until(&armed, "usv1.armed", &Value::Bool(true));
    assert_eq!(
        call(&b, &["vehicles", "usv1"], "arm", vec![Value::Bool(true)]),
        CallOutcome::Refused("already armed".into())
    );
    // A bool parameter given an int: failed at the source, with its reason.
    let failed = call(&b, &["vehicles", "usv1"], "arm", vec![Value::Int(3)]);
    assert!(matches!(&failed, CallOutcome::Failed(why) if !why.is_empty()), "{failed:?}");
    a.unpublish_method(v, "never").unwrap();
    assert_eq!(call(&b, &["vehicles", "usv1"], "never", vec![]), CallOutcome::NoSuchMethod);

    // Deletes.
    let (tx, gone) = unbounded();
    let _w3 = b
        .watch_object(b.root(), &["vehicles", "usv1"], None, move |e| {
            let _ = tx.send(e.clone());
        })
        .unwrap();
    a.delete_object(v).unwrap();
    let mut deleted = false;
    while let Ok(e) = gone.recv_timeout(PATIENCE) {
        if e.kind == Kind::Deleted {
            deleted = true;
            break;
        }
    }
    assert!(deleted, "usv1 deleted on the mirror");
    drop(db);
    drop(da);
}

#[test]
fn equal_writes_are_not_resent() {
    let port = free_port();
    let a = DataServer::default();
    let (_, nav) = publish_vehicle(&a, "usv1");
    let da = Distrib::start(&a, &adapter(port), None).unwrap();
    let b = DataServer::default();
    let (_w, speed) = watch(&b, "vehicles.usv1.nav.speed");
    let db = Distrib::start(&b, &ocu("bob", port), None).unwrap();
    until(&speed, "snapshot", &Value::Float(1.5));
    let before = da.publish_stats.puts.load(std::sync::atomic::Ordering::Relaxed);
    for _ in 0..10 {
        a.set(nav, "speed", Value::Float(1.5)).unwrap();
    }
    a.set(nav, "speed", Value::Float(2.5)).unwrap();
    until(&speed, "update", &Value::Float(2.5));
    let after = da.publish_stats.puts.load(std::sync::atomic::Ordering::Relaxed);
    assert_eq!(after - before, 1, "ten equal writes and one change: one put");
    drop(db);
    drop(da);
}

#[test]
fn a_site_that_leaves_shows_stale_and_returns_without_duplicates() {
    let port = free_port();
    let b = DataServer::default();
    let (_w, stale) = watch(&b, "vehicles.usv1.stale");
    let db = Distrib::start(&b, &ocu("carol", port), None).unwrap();

    let a = DataServer::default();
    publish_vehicle(&a, "usv1");
    let da = Distrib::start(&a, &adapter(port), None).unwrap();
    until(&stale, "usv1.stale (joined)", &Value::Bool(false));
    da.stop();
    until(&stale, "usv1.stale (adapter gone)", &Value::Bool(true));

    // The adapter comes back (a new process: new GUIDs, same paths).
    let a2 = DataServer::default();
    publish_vehicle(&a2, "usv1");
    publish_vehicle(&a2, "usv2");
    let da2 = Distrib::start(&a2, &adapter(port), None).unwrap();
    until(&stale, "usv1.stale (adapter back)", &Value::Bool(false));
    let (_w2, usv2) = watch(&b, "vehicles.usv2.nav.speed");
    until(&usv2, "usv2 after the return", &Value::Float(1.5));
    let vs = b.resolve(&["vehicles"]).unwrap();
    let names: Vec<String> =
        b.children(vs).unwrap().into_iter().map(|g| b.info(g).unwrap().name.to_string()).collect();
    assert_eq!(names, ["usv1", "usv2"]);
    drop(da2);
    drop(db);
}
