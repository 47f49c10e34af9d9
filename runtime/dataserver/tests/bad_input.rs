//! Bad input: every refused operation answers with the right typed `DsError`, whose message
//! names the object and property, and changes nothing; calls with wrong arguments fail
//! naming the argument; a panicking callback or handler takes nothing down.

use mocu_dataserver::{
    CallOptions, CallOutcome, Config, DataServer, DottedPath, DsError, Guid, MethodSpec,
    Notification, ObjectInfo, Overflow, ParamSpec, PropMeta, Topic, Value, ValueKind,
};
use parking_lot::Mutex;
use std::sync::Arc;
use std::sync::atomic::{AtomicUsize, Ordering};

struct World {
    ds: DataServer,
    usv: Guid,
    nav: Guid,
    other: Guid,
    listener: Guid,
    gone: Guid,
}

/// root ─ usv1 (speed: float 0..=10 m/s, mode: string, count: int; method `start`)
///      │   └ nav
///      ├ other
///      └ video (a listener)
/// plus `gone`, created and deleted.
fn world() -> World {
    let ds = DataServer::new(Config { workers: 2 });
    let usv = ds.create_object(Guid::ROOT, ObjectInfo::new("usv1", "vehicle")).unwrap();
    let speed = PropMeta::typed(ValueKind::Float).range(0.0, 10.0).units("m/s");
    ds.create_property(usv, "speed", Value::Float(1.0), speed).unwrap();
    ds.create_property(usv, "mode", Value::str("idle"), PropMeta::typed(ValueKind::String))
        .unwrap();
    ds.set(usv, "count", Value::Int(3)).unwrap();
    ds.publish_method_fn(usv, MethodSpec::new("start"), |_| CallOutcome::Accepted(vec![])).unwrap();
    let nav = ds.create_object(usv, ObjectInfo::new("nav", "nav")).unwrap();
    let other = ds.create_object(Guid::ROOT, ObjectInfo::new("other", "thing")).unwrap();
    let listener = ds.create_listener(Guid::ROOT, "video").unwrap();
    let gone = ds.create_object(Guid::ROOT, ObjectInfo::new("gone", "thing")).unwrap();
    ds.delete_object(gone).unwrap();
    World { ds, usv, nav, other, listener, gone }
}

/// Runs a refused operation: checks the error's variant and that its message names what it
/// should, and that the tree, the subscriptions and the object count did not change.
fn refused<T: std::fmt::Debug>(
    w: &World,
    what: &str,
    op: impl FnOnce(&DataServer) -> Result<T, DsError>,
    variant: fn(&DsError) -> bool,
    names: &[&str],
) {
    let before = w.ds.snapshot(Guid::ROOT).unwrap();
    let (subs, objects) = (w.ds.subscription_count(), w.ds.object_count());
    let err = match op(&w.ds) {
        Ok(v) => panic!("{what}: accepted ({v:?})"),
        Err(e) => e,
    };
    assert!(variant(&err), "{what}: wrong error {err:?}");
    let text = err.to_string();
    for n in names {
        assert!(text.contains(n), "{what}: `{text}` does not name `{n}`");
    }
    w.ds.quiesce();
    assert_eq!(w.ds.snapshot(Guid::ROOT).unwrap(), before, "{what}: the tree changed");
    assert_eq!(w.ds.subscription_count(), subs, "{what}: subscriptions changed");
    assert_eq!(w.ds.object_count(), objects, "{what}: objects changed");
}

#[test]
fn operations_on_missing_objects_are_refused_as_no_such_object() {
    let w = world();
    let g = w.gone;
    let never = Guid::new(9_999).unwrap();
    let is = |e: &DsError| matches!(e, DsError::NoSuchObject { .. });
    let info = || ObjectInfo::new("n", "t");
    refused(&w, "set", |ds| ds.set(g, "x", Value::Int(1)), is, &["#"]);
    refused(&w, "set (never existed)", |ds| ds.set(never, "x", Value::Int(1)), is, &["#9999"]);
    refused(&w, "update", |ds| ds.update(g, "x", Value::Int(1)), is, &["#"]);
    refused(&w, "get", |ds| ds.get(g, "x"), is, &["does not exist"]);
    refused(
        &w,
        "create_property",
        |ds| ds.create_property(g, "x", Value::Int(1), PropMeta::default()),
        is,
        &["does not exist"],
    );
    refused(&w, "delete_property", |ds| ds.delete_property(g, "x"), is, &["does not exist"]);
    refused(&w, "create_object", |ds| ds.create_object(g, info()), is, &["does not exist"]);
    refused(&w, "create_object_at", |ds| ds.create_object_at(never, 0, info()), is, &["#9999"]);
    refused(&w, "insert_between", |ds| ds.insert_between(g, w.nav, info()), is, &["#"]);
    refused(&w, "delete_object", |ds| ds.delete_object(g), is, &["does not exist"]);
    refused(&w, "delete_and_promote", |ds| ds.delete_and_promote(g, w.nav), is, &["#"]);
    refused(&w, "set_info", |ds| ds.set_info(never, info()), is, &["#9999"]);
    refused(&w, "subscribe", |ds| ds.subscribe(Topic::properties(g), |_| {}), is, &["#"]);
    refused(&w, "subscribe children", |ds| ds.subscribe(Topic::children(g), |_| {}), is, &["#"]);
    refused(&w, "info", |ds| ds.info(never), is, &["#9999"]);
    refused(&w, "children", |ds| ds.children(never), is, &["#9999"]);
    refused(
        &w,
        "publish_method",
        |ds| ds.publish_method_fn(g, MethodSpec::new("m"), |_| CallOutcome::Accepted(vec![])),
        is,
        &["does not exist"],
    );
}

#[test]
fn missing_properties_are_refused_naming_the_object_and_the_property() {
    let w = world();
    let is = |e: &DsError| matches!(e, DsError::NoSuchProperty { .. });
    let names: &[&str] = &["usv1", "altitude"];
    refused(&w, "update", |ds| ds.update(w.usv, "altitude", Value::Int(1)), is, names);
    refused(&w, "get", |ds| ds.get(w.usv, "altitude"), is, names);
    refused(&w, "meta", |ds| ds.meta(w.usv, "altitude"), is, names);
    refused(&w, "delete_property", |ds| ds.delete_property(w.usv, "altitude"), is, names);
    // Joining a stream through a method the receiver does not have.
    refused(&w, "join", |ds| ds.join(w.listener, w.usv, "altitude", Overflow::Block, 4), is, names);
}

#[test]
fn writes_of_the_wrong_type_are_refused_as_type_mismatch() {
    let w = world();
    let is = |e: &DsError| matches!(e, DsError::TypeMismatch { .. });
    let speed: &[&str] = &["usv1", "speed", "float", "string"];
    refused(&w, "set", |ds| ds.set(w.usv, "speed", Value::str("fast")), is, speed);
    refused(&w, "update", |ds| ds.update(w.usv, "speed", Value::str("fast")), is, speed);
    refused(
        &w,
        "set a bool",
        |ds| ds.set(w.usv, "mode", Value::Bool(true)),
        is,
        &["usv1", "mode", "string", "bool"],
    );
    refused(
        &w,
        "create_property",
        |ds| {
            ds.create_property(w.usv, "heading", Value::Bool(true), PropMeta::typed(ValueKind::Int))
        },
        is,
        &["usv1", "heading", "int", "bool"],
    );
    // An int is accepted by a float property and stored as a float.
    w.ds.set(w.usv, "speed", Value::Int(2)).unwrap();
    assert_eq!(w.ds.get(w.usv, "speed").unwrap(), Value::Float(2.0));
}

#[test]
fn numbers_outside_the_declared_range_are_refused_as_out_of_range() {
    let w = world();
    let is = |e: &DsError| matches!(e, DsError::OutOfRange { .. });
    refused(
        &w,
        "above",
        |ds| ds.set(w.usv, "speed", Value::Float(10.5)),
        is,
        &["usv1", "speed", "10.5", "0", "10"],
    );
    refused(
        &w,
        "below, as an int",
        |ds| ds.update(w.usv, "speed", Value::Int(-1)),
        is,
        &["usv1", "speed", "-1"],
    );
    refused(&w, "NaN", |ds| ds.set(w.usv, "speed", Value::Float(f64::NAN)), is, &["NaN"]);
    refused(
        &w,
        "create_property",
        |ds| {
            ds.create_property(w.usv, "pct", Value::Int(101), PropMeta::default().range(0.0, 100.0))
        },
        is,
        &["usv1", "pct", "101"],
    );
    // The limits themselves are inside.
    w.ds.set(w.usv, "speed", Value::Float(10.0)).unwrap();
    w.ds.set(w.usv, "speed", Value::Int(0)).unwrap();
}

#[test]
fn duplicate_properties_and_methods_are_refused() {
    let w = world();
    refused(
        &w,
        "create_property",
        |ds| ds.create_property(w.usv, "speed", Value::Float(2.0), PropMeta::default()),
        |e| matches!(e, DsError::PropertyExists { .. }),
        &["usv1", "speed"],
    );
    refused(
        &w,
        "publish_method",
        |ds| {
            ds.publish_method_fn(w.usv, MethodSpec::new("start"), |_| {
                CallOutcome::Refused("no".into())
            })
        },
        |e| matches!(e, DsError::MethodExists { .. }),
        &["usv1", "start"],
    );
    // The original method still answers.
    assert_eq!(w.ds.call_wait(w.usv, "start", vec![], None), CallOutcome::Accepted(vec![]));
}

#[test]
fn tree_operations_on_a_non_child_are_refused_as_not_a_child() {
    let w = world();
    let is = |e: &DsError| matches!(e, DsError::NotAChild { .. });
    refused(
        &w,
        "insert_between",
        |ds| ds.insert_between(Guid::ROOT, w.nav, ObjectInfo::new("mid", "t")),
        is,
        &["nav", "root"],
    );
    refused(
        &w,
        "delete_and_promote",
        |ds| ds.delete_and_promote(w.usv, w.other),
        is,
        &["usv1", "other"],
    );
    refused(
        &w,
        "insert_between itself",
        |ds| ds.insert_between(w.usv, w.usv, ObjectInfo::new("mid", "t")),
        is,
        &["usv1"],
    );
}

#[test]
fn the_root_cannot_be_deleted_renamed_or_promoted_away() {
    let w = world();
    let is = |e: &DsError| matches!(e, DsError::RootIsPermanent);
    let text: &[&str] = &["root"];
    refused(&w, "delete_object", |ds| ds.delete_object(Guid::ROOT), is, text);
    refused(&w, "set_info", |ds| ds.set_info(Guid::ROOT, ObjectInfo::new("r", "t")), is, text);
    refused(&w, "delete_and_promote", |ds| ds.delete_and_promote(Guid::ROOT, w.usv), is, text);
}

#[test]
fn stream_operations_on_an_ordinary_object_are_refused_as_not_a_listener() {
    let w = world();
    let is = |e: &DsError| matches!(e, DsError::NotAListener { .. });
    let names: &[&str] = &["usv1", "listener"];
    refused(&w, "send", |ds| ds.send(w.usv, vec![Value::Int(1)]), is, names);
    refused(&w, "receivers", |ds| ds.receivers(w.usv), is, names);
    refused(&w, "join", |ds| ds.join(w.usv, w.usv, "start", Overflow::DropOldest, 1), is, names);
    refused(&w, "send to a deleted object", |ds| ds.send(w.gone, vec![]), is, &["listener"]);
}

#[test]
fn malformed_dotted_paths_are_refused_as_bad_path() {
    for text in ["", "root", "root.", "root..speed", "a..b", ".speed", "usv1.nav."] {
        match DottedPath::parse(text) {
            Err(e @ DsError::BadPath { .. }) => {
                assert!(e.to_string().contains(&format!("`{text}`")), "{e} does not quote it");
            }
            other => panic!("`{text}`: {other:?}"),
        }
    }
    let p = DottedPath::parse("root.usv1.nav.speed").unwrap();
    assert_eq!(p.to_string(), "root.usv1.nav.speed");
}

// ----- method arguments --------------------------------------------------------------------

#[test]
fn calls_with_wrong_arguments_fail_naming_the_argument_and_never_reach_the_handler() {
    let w = world();
    let ran = Arc::new(AtomicUsize::new(0));
    let r = ran.clone();
    let spec = MethodSpec::new("goto")
        .param(ParamSpec::new("lat", ValueKind::Float))
        .param(ParamSpec::new("lon", ValueKind::Float))
        .param(ParamSpec::any("label"));
    w.ds.publish_method_fn(w.usv, spec, move |args| {
        r.fetch_add(1, Ordering::SeqCst);
        CallOutcome::Accepted(args.to_vec())
    })
    .unwrap();
    let fails_naming = |args: Vec<Value>, names: &[&str]| {
        for options in [None, Some(CallOptions::immediate())] {
            match w.ds.call_wait(w.usv, "goto", args.clone(), options) {
                CallOutcome::Failed(why) => {
                    for n in names {
                        assert!(why.contains(n), "`{why}` does not name `{n}`");
                    }
                }
                other => panic!("{args:?}: {other:?}"),
            }
        }
    };
    fails_naming(vec![Value::Float(1.0)], &["goto", "3", "lat, lon, label", "got 1"]);
    fails_naming(vec![], &["goto", "got 0"]);
    fails_naming(
        vec![Value::Float(1.0), Value::str("east"), Value::Int(1)],
        &["`lon`", "goto", "float", "string"],
    );
    fails_naming(vec![Value::Bool(true), Value::Float(1.0), Value::Int(1)], &["`lat`", "bool"]);
    assert_eq!(ran.load(Ordering::SeqCst), 0, "the handler ran for a refused call");
    // Ints are widened for float parameters; `any` takes anything.
    let ok = w.ds.call_wait(
        w.usv,
        "goto",
        vec![Value::Int(1), Value::Float(2.5), Value::Bool(true)],
        None,
    );
    assert_eq!(
        ok,
        CallOutcome::Accepted(vec![Value::Float(1.0), Value::Float(2.5), Value::Bool(true)])
    );
    assert_eq!(w.ds.call_wait(w.usv, "stop", vec![], None), CallOutcome::NoSuchMethod);
    assert_eq!(w.ds.call_wait(w.gone, "goto", vec![], None), CallOutcome::NoSuchObject);
}

// ----- panics ------------------------------------------------------------------------------

#[test]
fn a_panicking_subscriber_is_counted_and_later_deliveries_still_arrive() {
    let w = world();
    let ds = &w.ds;
    let ex = ds.serial_executor();
    let mut logs = Vec::new();
    for on_executor in [false, true] {
        let log = Arc::new(Mutex::new(Vec::new()));
        let l = log.clone();
        let callback = move |n: &Notification| {
            if n.value() == Some(&Value::Int(2)) {
                panic!("a module bug");
            }
            l.lock().push(n.value().cloned());
        };
        let topic = Topic::property_names(w.usv, &["count"]);
        if on_executor {
            ds.subscribe_on(&ex, topic, callback)
        } else {
            ds.subscribe(topic, callback)
        }
        .unwrap();
        logs.push(log);
    }
    ds.quiesce();
    let before = ds.stats().panics_caught.load(Ordering::SeqCst);
    for v in 1..=4 {
        ds.set(w.usv, "count", Value::Int(v)).unwrap();
        ds.quiesce();
    }
    assert_eq!(ds.stats().panics_caught.load(Ordering::SeqCst) - before, 2);
    for log in logs {
        let want: Vec<Option<Value>> = [3, 1, 3, 4].iter().map(|i| Some(Value::Int(*i))).collect();
        assert_eq!(*log.lock(), want);
    }
    // The executor goes on with other work too.
    let (tx, rx) = crossbeam_channel::bounded(1);
    ex.spawn(move || tx.send(()).unwrap());
    rx.recv().unwrap();
}

#[test]
fn a_panicking_method_handler_yields_failed_and_is_counted() {
    let w = world();
    let ds = &w.ds;
    let ex = ds.serial_executor();
    let calls = Arc::new(AtomicUsize::new(0));
    let c = calls.clone();
    let handler = move |call: mocu_dataserver::Call| {
        if c.fetch_add(1, Ordering::SeqCst).is_multiple_of(2) {
            panic!("a module bug");
        }
        call.responder.accept(vec![]);
    };
    ds.publish_method(w.usv, MethodSpec::new("flaky"), handler.clone()).unwrap();
    ds.publish_method_on(&ex, w.nav, MethodSpec::new("flaky"), handler).unwrap();
    let before = ds.stats().panics_caught.load(Ordering::SeqCst);
    for g in [w.usv, w.nav] {
        for options in [None, Some(CallOptions::immediate())] {
            assert!(
                matches!(ds.call_wait(g, "flaky", vec![], options), CallOutcome::Failed(_)),
                "a panicking handler must answer Failed"
            );
            assert_eq!(ds.call_wait(g, "flaky", vec![], options), CallOutcome::Accepted(vec![]));
        }
    }
    ds.quiesce();
    assert_eq!(ds.stats().panics_caught.load(Ordering::SeqCst) - before, 4);
    // Everything else still works.
    ds.set(w.usv, "count", Value::Int(9)).unwrap();
    assert_eq!(ds.get(w.usv, "count").unwrap(), Value::Int(9));
}
