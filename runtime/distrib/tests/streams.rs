//! Shared streams: an adapter shares the frames of the cameras its profile chooses, paced on
//! its DataServer's clock; an OCU's mirrored camera is a listener its video windows join,
//! and the frames arrive there whole, in order. Two sites in one process on loopback, every
//! wait on a condition, bounded so that a failure fails instead of hanging.

use mocu_dataserver::{
    CallOutcome, Config as DsConfig, DataServer, Guid, ManualClock, MethodSpec, ObjectInfo,
    Overflow, ParamSpec, Value,
};
use mocu_distrib::streams::StreamChoice;
use mocu_distrib::{Config, Distrib};
use std::sync::Arc;
use std::sync::atomic::Ordering::SeqCst;
use std::time::Duration;

mod support;
use support::{PATIENCE, free_port};

/// A vehicle with a drive and a payload camera, as the simulator publishes them.
fn cameras(ds: &DataServer) -> (Guid, Guid) {
    let vs = ds.create_object(ds.root(), ObjectInfo::new("vehicles", "vehicles")).unwrap();
    let v = ds.create_object(vs, ObjectInfo::new("usv1", "usv")).unwrap();
    let cams = ds.create_object(v, ObjectInfo::new("cameras", "cameras")).unwrap();
    let drive = ds.create_listener(cams, "drive").unwrap();
    let payload = ds.create_listener(cams, "payload").unwrap();
    ds.set(drive, "width", Value::Int(8)).unwrap();
    (drive, payload)
}

/// Frame `n` of an 8×6 RGB camera: bytes that say which frame they are.
fn frame(n: i64) -> Vec<Value> {
    let px: Vec<u8> = (0..8 * 6 * 3).map(|i| (i as i64 * 7 + n) as u8).collect();
    vec![Value::Bytes(px.into()), Value::Int(8), Value::Int(6), Value::Int(n)]
}

#[test]
fn the_chosen_cameras_frames_reach_the_other_site_whole_in_order_and_paced() {
    let port = free_port();
    let clock = ManualClock::new();
    let a = DataServer::with_clock(DsConfig::default(), Arc::new(clock.clone()));
    let (drive, payload) = cameras(&a);
    let adapter = Config {
        site: "adapter".into(),
        listen: vec![format!("tcp/127.0.0.1:{port}")],
        share: vec!["vehicles".into()],
        streams: StreamChoice::new(&["vehicles.*.cameras.drive".into()], 5.0),
        ..Config::default()
    };
    let da = Distrib::start(&a, &adapter, None).unwrap();

    let b = DataServer::default();
    let ocu = Config {
        site: "alice".into(),
        connect: vec![format!("tcp/127.0.0.1:{port}")],
        ..Config::default()
    };
    let db = Distrib::start(&b, &ocu, None).unwrap();
    assert!(db.wait_snapshots(1, PATIENCE), "the adapter's snapshot");

    // The adapter listens to the chosen camera only (so a simulator renders just that one),
    // and its tap is not part of what it shares.
    assert_eq!(a.receivers(drive).unwrap().len(), 1, "the drive camera is tapped");
    assert!(a.receivers(payload).unwrap().is_empty(), "the payload camera is not");

    // The OCU's mirrored camera is a listener: a video window joins it as it would locally.
    let bl = b.resolve(&["vehicles", "usv1", "cameras", "drive"]).expect("the mirrored camera");
    let window = b.create_object(b.root(), ObjectInfo::new("window", "window")).unwrap();
    let (tx, frames) = crossbeam_channel::unbounded();
    let spec = MethodSpec::new("frame")
        .param(ParamSpec::any("pixels"))
        .param(ParamSpec::any("w"))
        .param(ParamSpec::any("h"))
        .param(ParamSpec::any("n"));
    b.publish_method_fn(window, spec, move |args| {
        let _ = tx.send(args.to_vec());
        CallOutcome::Accepted(vec![])
    })
    .unwrap();
    b.join(bl, window, "frame", Overflow::DropOldest, 64).unwrap();
    assert_eq!(b.children(bl).unwrap().len(), 1, "only the OCU's own receiver");

    // Two seconds of a 30 Hz camera, and frames on the camera nobody chose.
    for n in 0..60 {
        a.send(drive, frame(n)).unwrap();
        let _ = a.send(payload, frame(1000 + n));
        a.quiesce();
        clock.advance(Duration::from_secs_f64(1.0 / 30.0));
    }
    let mut got = Vec::new();
    while got.last() != Some(&frame(54)) {
        let f = frames.recv_timeout(PATIENCE).unwrap_or_else(|_| {
            let ns: Vec<_> = got.iter().map(|f: &Vec<Value>| f[3].clone()).collect();
            panic!("frame 54 never came; got {ns:?}")
        });
        got.push(f);
    }
    // Five a second: every sixth frame, each as it was sent.
    assert_eq!(got, (0..60).step_by(6).map(frame).collect::<Vec<_>>());
    let s = &da.publish_stats;
    let (puts, paced) = (s.stream_puts.load(SeqCst), s.stream_paced.load(SeqCst));
    assert_eq!((puts, paced), (10, 50));
    db.stop();
    da.stop();
}
