//! The change feed (what `--record` records): every change, call, outcome and stream
//! message, stamped on the server's clock when it happened and numbered in order.
mod common;
use common::{manual, object};
use mocu_dataserver::*;
use std::time::{Duration, SystemTime};

fn ms(n: u64) -> Duration {
    Duration::from_millis(n)
}

fn drain(feed: &ChangeFeed) -> Vec<Stamped> {
    feed.try_iter().collect()
}

#[test]
fn a_change_is_stamped_when_it_happened_not_when_the_feed_is_read() {
    let (ds, clock) = manual();
    let t0 = SystemTime::UNIX_EPOCH + Duration::from_secs(1_700_000_000);
    clock.set_wall(t0);
    let feed = ds.change_feed();
    let o = object(&ds, "usv1");
    clock.advance(ms(250));
    ds.set(o, "speed", Value::Float(1.0)).unwrap();
    clock.advance(ms(750));
    let got = drain(&feed);
    assert_eq!(got.len(), 2);
    assert_eq!(got[0].wall, t0);
    assert!(matches!(&got[0].change, Change::Created { object, info, .. }
        if *object == o && &*info.name == "usv1"));
    assert_eq!(got[1].wall, t0 + ms(250));
    match &got[1].change {
        Change::PropertySet { object, name, value, created, .. } => {
            assert_eq!(
                (*object, name.as_str(), value, *created),
                (o, "speed", &Value::Float(1.0), true)
            );
        }
        other => panic!("expected the speed, got {other:?}"),
    }
}

#[test]
fn a_write_equal_to_the_current_value_is_not_fed_and_metadata_comes_with_the_creation_only() {
    let (ds, _clock) = manual();
    let o = object(&ds, "nav");
    let meta = PropMeta::typed(ValueKind::Float).units("m/s");
    let feed = ds.change_feed();
    ds.create_property(o, "speed", Value::Float(0.0), meta).unwrap();
    let created = feed.take();
    let Some(Change::PropertySet { meta: Some(m), created: true, .. }) =
        created.first().map(|s| &s.change)
    else {
        panic!("expected the creation with its metadata, got {created:?}");
    };
    assert_eq!(m.units.as_deref(), Some("m/s"));
    ds.set(o, "speed", Value::Float(2.0)).unwrap();
    ds.set(o, "speed", Value::Float(2.0)).unwrap();
    ds.set(o, "speed", Value::Int(3)).unwrap();
    let got = drain(&feed);
    let values: Vec<(Value, Option<String>)> = got
        .iter()
        .map(|s| match &s.change {
            Change::PropertySet { value, meta, created: false, .. } => {
                (value.clone(), meta.as_ref().and_then(|m| m.units.as_deref().map(String::from)))
            }
            other => panic!("expected a set, got {other:?}"),
        })
        .collect();
    assert_eq!(values, vec![(Value::Float(2.0), None), (Value::Float(3.0), None)]);
}

#[test]
fn a_call_and_its_outcome_are_fed_once_each_under_one_number() {
    let (ds, _clock) = manual();
    let o = object(&ds, "usv1");
    let spec = MethodSpec::new("start").param(ParamSpec::new("n", ValueKind::Int));
    ds.publish_method_fn(o, spec, |_| CallOutcome::Refused("no fuel".into())).unwrap();
    let feed = ds.change_feed();
    let outcome = ds.call_wait(o, "start", vec![Value::Int(1)], None);
    assert_eq!(outcome, CallOutcome::Refused("no fuel".into()));
    let outcome = ds.call_wait(o, "stop", vec![], None);
    assert_eq!(outcome, CallOutcome::NoSuchMethod);
    let got: Vec<String> = drain(&feed)
        .into_iter()
        .map(|s| match s.change {
            Change::Called { call, method, args, .. } => format!("call {call} {method} {args:?}"),
            Change::Answered { call, outcome } => format!("outcome {call} {}", outcome.label()),
            other => panic!("expected calls only, got {other:?}"),
        })
        .collect();
    assert_eq!(
        got,
        ["call 1 start [1]", "outcome 1 refused", "call 2 stop []", "outcome 2 no_such_method"]
    );
}

#[test]
fn a_deleted_subtree_is_one_change_and_insert_between_feeds_the_new_object_then_the_move() {
    let (ds, _clock) = manual();
    let a = object(&ds, "a");
    let b = ds.create_object(a, ObjectInfo::new("b", "thing")).unwrap();
    let _c = ds.create_object(b, ObjectInfo::new("c", "thing")).unwrap();
    let feed = ds.change_feed();
    let mid = ds.insert_between(a, b, ObjectInfo::new("mid", "thing")).unwrap();
    ds.delete_object(a).unwrap();
    let got: Vec<String> = drain(&feed)
        .into_iter()
        .map(|s| match s.change {
            Change::Created { object, parent, index, .. } => {
                format!("created {} under {} at {index}", object.get(), parent.get())
            }
            Change::Moved { object, parent, index } => {
                format!("moved {} under {} at {index}", object.get(), parent.get())
            }
            Change::Deleted { object } => format!("deleted {}", object.get()),
            other => panic!("expected object changes only, got {other:?}"),
        })
        .collect();
    let (a, b, mid) = (a.get(), b.get(), mid.get());
    assert_eq!(
        got,
        [
            format!("created {mid} under {a} at 0"),
            format!("moved {b} under {mid} at 0"),
            format!("deleted {a}")
        ]
    );
}

#[test]
fn numbers_follow_the_order_of_changes_and_stamps_never_go_back_under_concurrent_writers() {
    let ds = DataServer::default();
    let feed = ds.change_feed();
    let objects: Vec<Guid> = (0..4).map(|i| object(&ds, &format!("o{i}"))).collect();
    std::thread::scope(|s| {
        for &o in &objects {
            let ds = &ds;
            s.spawn(move || {
                for i in 0..500 {
                    ds.set(o, "x", Value::Int(i)).unwrap();
                }
            });
        }
    });
    let got = drain(&feed);
    assert_eq!(got.len(), 4 + 4 * 500);
    for w in got.windows(2) {
        assert_eq!(w[1].seq, w[0].seq + 1);
        assert!(w[1].wall >= w[0].wall, "stamp went back at {}", w[1].seq);
    }
    // Per object, the values arrive in the order they were written.
    for &o in &objects {
        let xs: Vec<i64> = got
            .iter()
            .filter_map(|s| match &s.change {
                Change::PropertySet { object, value, .. } if *object == o => value.as_i64(),
                _ => None,
            })
            .collect();
        assert_eq!(xs, (0..500).collect::<Vec<_>>());
    }
}

#[test]
fn a_stream_message_is_fed_once_not_again_as_a_call_to_each_receiver() {
    let (ds, _clock) = manual();
    let cam = ds.create_listener(ds.root(), "cam").unwrap();
    let sink = object(&ds, "sink");
    let spec =
        MethodSpec::new("frame").param(ParamSpec::any("data")).param(ParamSpec::any("codec"));
    ds.publish_method_fn(sink, spec, |_| CallOutcome::Accepted(vec![])).unwrap();
    ds.join(cam, sink, "frame", Overflow::DropOldest, 4).unwrap();
    let feed = ds.change_feed();
    ds.send(cam, vec![Value::Bytes(vec![1u8, 2, 3].into()), Value::str("h264")]).unwrap();
    ds.quiesce();
    let sent: Vec<_> = drain(&feed)
        .into_iter()
        .filter_map(|s| match s.change {
            Change::Sent { listener, message } => Some((listener, message.to_vec())),
            Change::Called { .. } | Change::Answered { .. } => {
                panic!("a delivery was fed as a call")
            }
            _ => None,
        })
        .collect();
    assert_eq!(sent, vec![(cam, vec![Value::Bytes(vec![1u8, 2, 3].into()), Value::str("h264")])]);
}

#[test]
fn a_dropped_feed_is_forgotten_and_a_later_one_sees_only_what_follows() {
    let (ds, _clock) = manual();
    let o = object(&ds, "o");
    drop(ds.change_feed());
    ds.set(o, "x", Value::Int(1)).unwrap();
    let feed = ds.change_feed();
    ds.set(o, "x", Value::Int(2)).unwrap();
    let got = drain(&feed);
    assert_eq!(got.len(), 1);
    assert!(matches!(&got[0].change, Change::PropertySet { value: Value::Int(2), .. }));
}

#[test]
fn no_write_to_an_object_is_fed_after_the_deletion_of_its_ancestor() {
    use std::sync::Arc;
    use std::sync::atomic::{AtomicBool, Ordering};
    let ds = DataServer::default();
    let parent = object(&ds, "parent");
    let children: Arc<Vec<Guid>> = Arc::new(
        (0..3000)
            .map(|i| ds.create_object(parent, ObjectInfo::new(&format!("c{i}"), "thing")).unwrap())
            .collect(),
    );
    let feed = ds.change_feed();
    let done = Arc::new(AtomicBool::new(false));
    let (started_tx, started) = crossbeam_channel::unbounded();
    let writers: Vec<_> = (0..2)
        .map(|w| {
            let (ds, children, done, started) =
                (ds.clone(), children.clone(), done.clone(), started_tx.clone());
            std::thread::spawn(move || {
                let mut n = 0i64;
                while !done.load(Ordering::SeqCst) {
                    // From the last child back: the ones a delete reaches last.
                    for &c in children.iter().rev().skip(w).step_by(2) {
                        let _ = ds.set(c, "x", Value::Int(n));
                        n += 1;
                    }
                    let _ = started.send(());
                }
            })
        })
        .collect();
    for _ in 0..2 {
        started.recv_timeout(Duration::from_secs(20)).expect("the writers run");
    }
    ds.delete_object(parent).unwrap();
    done.store(true, Ordering::SeqCst);
    for w in writers {
        w.join().unwrap();
    }
    let got = drain(&feed);
    let deleted = got
        .iter()
        .position(|s| matches!(s.change, Change::Deleted { object } if object == parent))
        .expect("the deletion is fed");
    let late = got[deleted..]
        .iter()
        .filter(|s| matches!(&s.change, Change::PropertySet { object, .. } if children.contains(object)))
        .count();
    assert_eq!(late, 0, "writes fed after the Deleted of their parent");
}
