//! Streams: listener objects, receivers in order, overflow policies.
use mocu_dataserver::*;
use std::sync::{Arc, Mutex};

/// A receiver object with a `frame` method. `gate`: each message first waits for the gate
/// (until its sender is dropped) — a receiver slower than its sender, without sleeping.
fn receiver(
    ds: &DataServer,
    name: &str,
    gate: Option<crossbeam_channel::Receiver<()>>,
) -> (Guid, Arc<Mutex<Vec<i64>>>) {
    let o = ds.create_object(Guid::ROOT, ObjectInfo::new(name, "window")).unwrap();
    let got = Arc::new(Mutex::new(Vec::new()));
    let g = got.clone();
    ds.publish_method_fn(
        o,
        MethodSpec::new("frame").param(ParamSpec::new("n", ValueKind::Int)),
        move |args| {
            if let Some(gate) = &gate {
                let _ = gate.recv();
            }
            g.lock().unwrap().push(args[0].as_i64().unwrap());
            CallOutcome::Accepted(vec![])
        },
    )
    .unwrap();
    (o, got)
}

#[test]
fn every_receiver_gets_every_message_in_order_with_block() {
    let ds = DataServer::default();
    let cam = ds.create_listener(Guid::ROOT, "drive").unwrap();
    let (a, got_a) = receiver(&ds, "a", None);
    // b takes one message per token: the sender must wait for it, many times.
    let (tokens, gate) = crossbeam_channel::unbounded();
    let (b, got_b) = receiver(&ds, "b", Some(gate));
    ds.join(cam, a, "frame", Overflow::Block, 4).unwrap();
    ds.join(cam, b, "frame", Overflow::Block, 4).unwrap();
    let feeder = std::thread::spawn(move || {
        for _ in 0..100 {
            tokens.send(()).unwrap();
            std::thread::yield_now();
        }
    });
    for i in 0..100 {
        assert_eq!(ds.send(cam, vec![Value::Int(i)]).unwrap(), 2);
    }
    feeder.join().unwrap();
    ds.quiesce();
    let want: Vec<i64> = (0..100).collect();
    assert_eq!(*got_a.lock().unwrap(), want);
    assert_eq!(*got_b.lock().unwrap(), want, "Block loses nothing, even for a slow receiver");
}

#[test]
fn drop_oldest_keeps_the_newest_and_counts_the_dropped_in_a_property() {
    let ds = DataServer::default();
    let cam = ds.create_listener(Guid::ROOT, "drive").unwrap();
    // The display is held on its first frame while the camera sends 50.
    let (hold, gate) = crossbeam_channel::unbounded::<()>();
    let (slow, got) = receiver(&ds, "video", Some(gate));
    let assoc = ds.join(cam, slow, "frame", Overflow::DropOldest, 2).unwrap();
    for i in 0..50 {
        ds.send(cam, vec![Value::Int(i)]).unwrap();
    }
    drop(hold);
    ds.quiesce();
    let got = got.lock().unwrap().clone();
    assert_eq!(*got.last().unwrap(), 49, "the newest frame is shown");
    assert!(got.windows(2).all(|w| w[0] < w[1]), "in order: {got:?}");
    let dropped = ds.get(assoc, "dropped").unwrap().as_i64().unwrap();
    assert_eq!(dropped as usize + got.len(), 50, "every frame is either shown or counted");
    assert!(dropped > 0);
}

#[test]
fn receivers_are_objects_under_the_listener_and_leaving_stops_delivery() {
    let ds = DataServer::default();
    let cam = ds.create_listener(Guid::ROOT, "drive").unwrap();
    let (a, got) = receiver(&ds, "a", None);
    let assoc = ds.join(cam, a, "frame", Overflow::Block, 8).unwrap();
    assert_eq!(ds.children(cam).unwrap(), [assoc]);
    assert_eq!(ds.info(assoc).unwrap().kind.as_ref(), RECEIVER_TYPE);
    assert_eq!(ds.get(assoc, "target").unwrap(), Value::Guid(a));
    ds.send(cam, vec![Value::Int(1)]).unwrap();
    ds.quiesce();
    ds.leave(assoc).unwrap();
    assert_eq!(ds.send(cam, vec![Value::Int(2)]).unwrap(), 0);
    ds.quiesce();
    assert_eq!(*got.lock().unwrap(), [1]);
}

#[test]
fn a_deleted_receiver_leaves_its_listeners() {
    let ds = DataServer::default();
    let cam = ds.create_listener(Guid::ROOT, "drive").unwrap();
    let (a, _got) = receiver(&ds, "a", None);
    ds.join(cam, a, "frame", Overflow::Block, 8).unwrap();
    ds.delete_object(a).unwrap();
    ds.send(cam, vec![Value::Int(1)]).unwrap();
    ds.quiesce();
    assert!(ds.receivers(cam).unwrap().is_empty());
    assert!(matches!(ds.send(a, vec![]), Err(DsError::NotAListener { .. })));
}

#[test]
fn a_receiver_published_again_on_another_executor_gets_its_messages_there() {
    let ds = DataServer::default();
    let (old, new) = (ds.serial_executor(), ds.serial_executor());
    let o = ds.create_object(Guid::ROOT, ObjectInfo::new("w", "window")).unwrap();
    let spec = MethodSpec::new("frame").param(ParamSpec::new("n", ValueKind::Int));
    ds.publish_method_on(&old, o, spec.clone(), |call| {
        call.responder.accept(vec![]);
    })
    .unwrap();
    let cam = ds.create_listener(Guid::ROOT, "cam").unwrap();
    ds.join(cam, o, "frame", Overflow::Block, 4).unwrap();
    ds.unpublish_method(o, "frame").unwrap();
    let (got_tx, got) = crossbeam_channel::unbounded();
    ds.publish_method_on(&new, o, spec, move |call| {
        let _ = got_tx.send(call.args[0].clone());
        call.responder.accept(vec![]);
    })
    .unwrap();
    // The old executor is busy until the message has arrived: it must not be needed.
    let (open_tx, open) = crossbeam_channel::bounded::<()>(1);
    old.spawn(move || {
        let _ = open.recv_timeout(std::time::Duration::from_secs(20));
    });
    ds.send(cam, vec![Value::Int(7)]).unwrap();
    let n = got.recv_timeout(std::time::Duration::from_secs(20));
    let _ = open_tx.send(());
    assert_eq!(n.ok(), Some(Value::Int(7)), "the message waited for the old executor");
}
