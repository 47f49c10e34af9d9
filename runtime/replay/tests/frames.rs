//! Cameras that send pixels (the simulator's): their frames, recorded by `mocu-record`,
//! are sent again on the replayed camera at their recorded times, and a seek shows each
//! camera's last frame before it (docs/recording.md, "Replay").

use mocu_dataserver::{
    CallOutcome, Config, DataServer, Guid, ManualClock, MethodSpec, ObjectInfo, Overflow,
    ParamSpec, Value,
};
use mocu_record::{Header, Recorder};
use mocu_replay::Player;
use std::sync::{Arc, Mutex};
use std::time::{Duration, SystemTime};

/// Records a camera `root.vehicles.cameras.drive` (there before the recording, so in its
/// first keyframe) sending five 2×2 RGB frames, 100 ms apart from 100 ms on; frame `n`'s
/// pixels are all `n`.
fn record(file: &std::path::Path) {
    let clock = ManualClock::new();
    clock.set_wall(SystemTime::UNIX_EPOCH + Duration::from_secs(1_700_000_000));
    let ds = DataServer::with_clock(Config::default(), Arc::new(clock.clone()));
    let v = ds.create_object(ds.root(), ObjectInfo::new("vehicles", "folder")).unwrap();
    let cams = ds.create_object(v, ObjectInfo::new("cameras", "cameras")).unwrap();
    let drive = ds.create_listener(cams, "drive").unwrap();
    let rec = Recorder::start(&ds, file, Header::default()).unwrap();
    for n in 1..=5u8 {
        clock.advance(Duration::from_millis(100));
        let px = Value::Bytes(vec![n; 12].into());
        ds.send(drive, vec![px, Value::Int(2), Value::Int(2), Value::Int(i64::from(n))]).unwrap();
    }
    rec.finish().unwrap();
}

/// What a receiver was sent: each frame's first pixel byte, its size and its byte count.
type Received = Arc<Mutex<Vec<(u8, i64, i64, usize)>>>;

/// Joins a receiver to the replayed camera; returns what it is sent.
fn watch(p: &Player) -> Received {
    let ds = p.ds();
    let camera = ds.resolve(&["vehicles", "cameras", "drive"]).expect("the replayed camera");
    let sink = ds.create_object(Guid::ROOT, ObjectInfo::new("sink", "test")).unwrap();
    let got = Arc::new(Mutex::new(Vec::new()));
    let g = got.clone();
    let spec = ["pixels", "width", "height", "frame"]
        .iter()
        .fold(MethodSpec::new("frame"), |s, p| s.param(ParamSpec::any(p)));
    ds.publish_method_fn(sink, spec, move |a| {
        let Some(Value::Bytes(px)) = a.first() else { return CallOutcome::Failed("px".into()) };
        let (w, h) = (a[1].as_i64().unwrap(), a[2].as_i64().unwrap());
        g.lock().unwrap().push((px[0], w, h, px.len()));
        CallOutcome::Accepted(vec![])
    })
    .unwrap();
    ds.join(camera, sink, "frame", Overflow::DropOldest, 16).unwrap();
    got
}

/// A recording of the camera, replayed to its start, with a receiver joined; the folder
/// holding the file lives as long as the returned guard.
fn replaying() -> (tempfile::TempDir, Player, Received) {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("t.mcap");
    record(&file);
    let mut p = Player::open(&file).unwrap();
    p.advance_to(p.start_ns()).unwrap();
    let got = watch(&p);
    (dir, p, got)
}

fn firsts(got: &Received) -> Vec<u8> {
    got.lock().unwrap().iter().map(|f| f.0).collect()
}

#[test]
fn a_pixel_cameras_recorded_frames_are_sent_again_at_their_times() {
    let (_dir, mut p, got) = replaying();
    p.advance_to(p.at_secs(0.15)).unwrap();
    assert_eq!(firsts(&got), vec![1]);
    p.advance_to(p.at_secs(0.35)).unwrap();
    assert_eq!(firsts(&got), vec![1, 2, 3]);
    assert_eq!(got.lock().unwrap()[2], (3, 2, 2, 12), "the frame as the camera sent it");
}

#[test]
fn a_seek_shows_each_cameras_last_frame_before_it() {
    let (_dir, mut p, got) = replaying();
    // A jump back is a seek (keyframe, then the changes after it).
    p.advance_to(p.at_secs(0.5)).unwrap();
    got.lock().unwrap().clear();
    p.seek(p.at_secs(0.25)).unwrap();
    assert_eq!(firsts(&got), vec![2], "frame 2 (at 200 ms) is the last before 250 ms");
    p.advance_to(p.at_secs(0.45)).unwrap();
    assert_eq!(firsts(&got), vec![2, 3, 4]);
}
