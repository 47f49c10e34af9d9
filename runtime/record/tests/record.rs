//! The recorder end to end on a manual clock: what happens in the DataServer lands on the
//! channels of docs/recording.md, stamped when it happened, read back with the `mcap` crate.
//! (The independent reader is the Python peer: tests/peers/read_recording.py.)

use mocu_dataserver::*;
use mocu_record::{Header, Recorder};
use serde_json::Value as Json;
use std::sync::Arc;
use std::time::{Duration, SystemTime};

const T0: u64 = 1_700_000_000;

fn manual() -> (DataServer, ManualClock) {
    let clock = ManualClock::new();
    clock.set_wall(SystemTime::UNIX_EPOCH + Duration::from_secs(T0));
    (DataServer::with_clock(Config::default(), Arc::new(clock.clone())), clock)
}

/// Every message: (topic, log_time in ns since T0, JSON); each entry of a `/world/values`
/// batch as a message of its own, `{"id", "seq", "kind", "value"}` at its own time.
fn read(path: &std::path::Path) -> Vec<(String, u64, Json)> {
    let bytes = std::fs::read(path).unwrap();
    let mut out = Vec::new();
    for m in mcap::MessageStream::new(&bytes).unwrap() {
        let m = m.unwrap();
        let topic = m.channel.topic.clone();
        if topic == "/world/values" {
            assert_eq!(m.channel.message_encoding, "cdr");
            for (t, j) in entries(&m.data) {
                out.push((topic.clone(), t - T0 * 1_000_000_000, j));
            }
            continue;
        }
        let json = if topic.starts_with("/camera/") {
            assert_eq!(m.channel.message_encoding, "cdr");
            assert_eq!(m.channel.schema.as_ref().unwrap().name, "foxglove_msgs/msg/RawImage");
            raw_image(&m.data)
        } else if topic.starts_with("/video/") || topic.starts_with("/image/") {
            assert_eq!(m.channel.message_encoding, "cdr");
            let schema = &m.channel.schema.as_ref().unwrap().name;
            assert!(schema.starts_with("foxglove_msgs/msg/Compressed"), "{schema}");
            compressed(&m.data)
        } else {
            serde_json::from_slice(&m.data).unwrap()
        };
        out.push((topic, m.log_time - T0 * 1_000_000_000, json));
    }
    out
}

/// Little-endian CDR, alignment counted from after the 4-byte header.
struct Cdr<'a>(&'a [u8], usize);

impl Cdr<'_> {
    fn new(d: &[u8]) -> Cdr<'_> {
        assert_eq!(&d[..4], &[0, 1, 0, 0], "little-endian CDR");
        Cdr(d, 4)
    }
    fn take(&mut self, align: usize, n: usize) -> &[u8] {
        self.1 += (align - (self.1 - 4) % align) % align;
        self.1 += n;
        &self.0[self.1 - n..self.1]
    }
    fn u32(&mut self) -> u32 {
        u32::from_le_bytes(self.take(4, 4).try_into().unwrap())
    }
    fn i64(&mut self) -> i64 {
        i64::from_le_bytes(self.take(8, 8).try_into().unwrap())
    }
    fn text(&mut self) -> String {
        let n = self.u32() as usize;
        let b = self.take(1, n);
        assert_eq!(b.last(), Some(&0), "a CDR string ends with NUL");
        String::from_utf8(b[..n - 1].to_vec()).unwrap()
    }
    fn bytes(&mut self) -> Vec<u8> {
        let n = self.u32() as usize;
        self.take(1, n).to_vec()
    }
}

/// A `foxglove_msgs/msg/RawImage` (CDR) as JSON: its fields, the pixels as a list.
fn raw_image(d: &[u8]) -> Json {
    let mut c = Cdr::new(d);
    let (sec, nsec) = (c.u32(), c.u32());
    let frame_id = c.text();
    let (width, height, encoding, step) = (c.u32(), c.u32(), c.text(), c.u32());
    let data = c.bytes();
    assert_eq!(c.1, d.len(), "nothing after the data");
    serde_json::json!({"timestamp": {"sec": sec, "nsec": nsec}, "frame_id": frame_id,
        "width": width, "height": height, "encoding": encoding, "step": step, "data": data})
}

/// A `foxglove_msgs/msg/CompressedVideo` or `…Image` with Mocu's `unit` and `arrival_us`
/// (CDR) as JSON, the data as a list.
fn compressed(d: &[u8]) -> Json {
    let mut c = Cdr::new(d);
    let (sec, nsec) = (c.u32(), c.u32());
    let frame_id = c.text();
    let data = c.bytes();
    let format = c.text();
    let (unit, arrival_us) = (c.i64(), c.i64());
    assert_eq!(c.1, d.len(), "nothing after arrival_us");
    serde_json::json!({"timestamp": {"sec": sec, "nsec": nsec}, "frame_id": frame_id,
        "data": data, "format": format, "unit": unit, "arrival_us": arrival_us})
}

/// A `mocu_msgs/msg/PropertyValues` batch (CDR, docs/recording.md), read as the doc lays it
/// out: (log time, entry).
fn entries(d: &[u8]) -> Vec<(u64, Json)> {
    assert_eq!(&d[..4], &[0, 1, 0, 0], "little-endian CDR");
    let mut at = 4;
    let mut take = |align: usize, n: usize| {
        at += (align - (at - 4) % align) % align;
        at += n;
        &d[at - n..at]
    };
    let u64_ = |b: &[u8]| u64::from_le_bytes(b.try_into().unwrap());
    let u32_ = |b: &[u8]| u32::from_le_bytes(b.try_into().unwrap());
    let (first_seq, first_ns) = (u64_(take(8, 8)), u64_(take(8, 8)));
    let mut cols: Vec<Vec<u8>> = Vec::new();
    for size in [4, 4, 4, 1, 8] {
        let n = u32_(take(4, 4)) as usize;
        cols.push(take(size, n * size).to_vec());
    }
    let n = cols[0].len() / 4;
    // `seq` empty: the entries are changes first_seq + i; `kind` empty: all floats.
    assert!(cols[1].is_empty() || cols[1].len() == 4 * n);
    assert!(cols[3].is_empty() || cols[3].len() == n);
    (0..n)
        .map(|i| {
            let w = |c: usize| u32_(&cols[c][4 * i..4 * i + 4]);
            let seq = if cols[1].is_empty() { i as u32 } else { w(1) };
            let x = f64::from_le_bytes(cols[4][8 * i..8 * i + 8].try_into().unwrap());
            let (kind, value) = match cols[3].get(i).copied().unwrap_or(0) {
                0 => ("float", Json::from(x)),
                1 => ("int", Json::from(x as i64)),
                2 => ("bool", Json::from(x != 0.0)),
                k => panic!("kind {k}"),
            };
            let j = serde_json::json!({"id": w(0), "seq": first_seq + u64::from(seq),
                                       "kind": kind, "value": value});
            (first_ns + u64::from(w(2)), j)
        })
        .collect()
}

fn on<'a>(msgs: &'a [(String, u64, Json)], topic: &str) -> Vec<&'a (String, u64, Json)> {
    msgs.iter().filter(|(t, _, _)| t == topic).collect()
}

fn ms(n: u64) -> Duration {
    Duration::from_millis(n)
}

#[test]
fn a_property_change_is_recorded_with_its_path_unit_kind_and_the_time_it_was_written() {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("t.mcap");
    let (ds, clock) = manual();
    let rec = Recorder::start(&ds, &file, Header::default()).unwrap();
    let v = ds.create_object(ds.root(), ObjectInfo::new("usv1", "vehicle")).unwrap();
    let nav = ds.create_object(v, ObjectInfo::new("nav", "nav")).unwrap();
    let meta = PropMeta::typed(ValueKind::Float).units("m/s");
    ds.create_property(nav, "speed", Value::Float(0.0), meta).unwrap();
    clock.advance(ms(1500));
    ds.set(nav, "speed", Value::Float(3.25)).unwrap();
    clock.advance(ms(500));
    ds.set(nav, "speed", Value::Float(3.25)).unwrap(); // no change: not recorded
    ds.set(nav, "mode", Value::str("auto")).unwrap();
    rec.finish().unwrap();

    let msgs = read(&file);
    let objects = on(&msgs, "/world/object");
    assert_eq!(objects.len(), 2);
    assert_eq!(objects[1].2["path"], "root.usv1.nav");
    assert_eq!(objects[1].2["parent"], v.get());
    let props = on(&msgs, "/world/property");
    let rows: Vec<(u64, String, String, Json)> = props
        .iter()
        .map(|(_, t, j)| (*t, j["op"].to_string(), j["path"].to_string(), j["value"].clone()))
        .collect();
    assert_eq!(
        rows,
        vec![
            (0, "\"created\"".into(), "\"root.usv1.nav.speed\"".into(), Json::from(0.0)),
            (
                2_000_000_000,
                "\"created\"".into(),
                "\"root.usv1.nav.mode\"".into(),
                Json::from("auto")
            ),
        ]
    );
    assert_eq!(props[0].2["unit"], "m/s");
    assert_eq!(props[0].2["kind"], "float");
    assert_eq!(props[0].2["meta"]["units"], "m/s");
    assert!(props[1].2.get("unit").is_none());
    assert_ne!(props[0].2["id"], props[1].2["id"]);
    // The numeric change goes in a batch, by the id `created` gave the property.
    let values = on(&msgs, "/world/values");
    assert_eq!(values.len(), 1, "{values:?}");
    assert_eq!(values[0].1, 1_500_000_000);
    assert_eq!(values[0].2["id"], props[0].2["id"]);
    assert_eq!((&values[0].2["kind"], &values[0].2["value"]), (&"float".into(), &3.25.into()));
}

#[test]
fn numbers_go_in_batches_with_their_kind_and_number_and_other_values_in_json_in_one_order() {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("t.mcap");
    let (ds, clock) = manual();
    let rec = Recorder::start(&ds, &file, Header::default()).unwrap();
    let o = ds.create_object(ds.root(), ObjectInfo::new("o", "thing")).unwrap();
    ds.set(o, "n", Value::Int(1)).unwrap();
    ds.set(o, "b", Value::Bool(false)).unwrap();
    ds.set(o, "s", Value::str("a")).unwrap();
    clock.advance(ms(10));
    ds.set(o, "n", Value::Int(-7)).unwrap();
    ds.set(o, "s", Value::str("b")).unwrap();
    ds.set(o, "b", Value::Bool(true)).unwrap();
    ds.set(o, "n", Value::Int(1 << 60)).unwrap(); // not exact as a float64: JSON
    rec.finish().unwrap();
    let msgs = read(&file);
    let mut changes: Vec<(u64, Json)> = msgs
        .iter()
        .filter(|(t, _, j)| t == "/world/values" || (t == "/world/property" && j["op"] == "set"))
        .map(|(_, _, j)| (j["seq"].as_u64().unwrap_or(0), j["value"].clone()))
        .collect();
    let json_sets = changes.iter().filter(|c| c.0 == 0).count();
    assert_eq!(json_sets, 2, "the string and the large integer: {changes:?}");
    changes.retain(|c| c.0 > 0);
    assert_eq!(changes, vec![(5, Json::from(-7)), (7, Json::from(true))]);
    let values = on(&msgs, "/world/values");
    assert_eq!((values[0].1, &values[0].2["kind"]), (10_000_000, &"int".into()));
}

#[test]
fn a_call_and_its_outcome_are_recorded_once_each_and_paint_calls_not_at_all() {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("t.mcap");
    let (ds, clock) = manual();
    let rec = Recorder::start(&ds, &file, Header::default()).unwrap();
    let o = ds.create_object(ds.root(), ObjectInfo::new("usv1", "vehicle")).unwrap();
    let spec = MethodSpec::new("goto")
        .param(ParamSpec::new("x", ValueKind::Float))
        .defaults(CallOptions::queued().timeout(ms(1000)));
    // Keeps the call unanswered: it times out.
    let pending = Arc::new(parking_lot::Mutex::new(Vec::new()));
    let p = pending.clone();
    ds.publish_method(o, spec, move |call: Call| p.lock().push(call)).unwrap();
    ds.publish_method_fn(o, MethodSpec::new("paint"), |_| CallOutcome::Accepted(vec![])).unwrap();
    let (tx, rx) = crossbeam_channel::bounded(1);
    ds.call(o, "goto", vec![Value::Float(10.0)], None, move |out| {
        let _ = tx.send(out);
    });
    let _ = ds.call_wait(o, "paint", vec![], None);
    ds.quiesce();
    clock.advance(ms(1000));
    assert_eq!(rx.recv_timeout(Duration::from_secs(10)).unwrap(), CallOutcome::TimedOut);
    rec.finish().unwrap();

    let msgs = read(&file);
    let calls = on(&msgs, "/calls");
    assert_eq!(calls.len(), 2, "{calls:?}");
    assert_eq!(calls[0].2["op"], "call");
    assert_eq!(calls[0].2["method"], "goto");
    assert_eq!(calls[0].2["path"], "root.usv1");
    assert_eq!(calls[0].2["args"][0], serde_json::json!({"kind": "float", "value": 10.0}));
    assert_eq!(
        (calls[1].1, &calls[1].2["op"], &calls[1].2["outcome"]),
        (1_000_000_000, &"outcome".into(), &"timed_out".into())
    );
    assert_eq!(calls[0].2["id"], calls[1].2["id"]);
}

#[test]
fn video_units_are_recorded_as_received_and_the_frames_decoded_from_them_are_not() {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("t.mcap");
    let (ds, clock) = manual();
    let rec = Recorder::start(&ds, &file, Header::default()).unwrap();
    let cams = ds.create_object(ds.root(), ObjectInfo::new("cameras", "folder")).unwrap();
    let cam = ds.create_listener(cams, "udp5600").unwrap();
    let encoded = ds.create_listener(cam, "encoded").unwrap();
    let unit = |data: &[u8], codec: &str, n: i64| {
        vec![Value::Bytes(data.into()), Value::str(codec), Value::Int(n), Value::Int(42)]
    };
    ds.send(encoded, unit(&[0, 0, 0, 1, 0x67], "h264", 1)).unwrap();
    clock.advance(ms(33));
    ds.send(encoded, unit(&[0xff, 0xd8, 0xff], "jpeg", 2)).unwrap();
    ds.send(cam, vec![Value::Bytes(vec![0u8; 12].into()), Value::Int(2), Value::Int(2)]).unwrap();
    rec.finish().unwrap();

    let msgs = read(&file);
    let video = on(&msgs, "/video/root.cameras.udp5600");
    assert_eq!(video.len(), 1);
    assert_eq!(video[0].2["format"], "h264");
    assert_eq!(video[0].2["data"], serde_json::json!([0, 0, 0, 1, 0x67]));
    assert_eq!(video[0].2["frame_id"], "root.cameras.udp5600");
    assert_eq!(video[0].2["timestamp"], serde_json::json!({"sec": T0, "nsec": 0}));
    let image = on(&msgs, "/image/root.cameras.udp5600");
    assert_eq!(image.len(), 1);
    assert_eq!(
        (image[0].1, &image[0].2["data"]),
        (33_000_000, &serde_json::json!([0xff, 0xd8, 0xff]))
    );
    assert_eq!((&image[0].2["unit"], &image[0].2["arrival_us"]), (&2.into(), &42.into()));
    assert_eq!(
        msgs.iter().filter(|(t, _, _)| t.starts_with("/video") || t.starts_with("/image")).count(),
        2
    );
}

#[test]
fn a_camera_that_sends_pixels_is_recorded_as_raw_images_at_most_ten_a_second() {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("t.mcap");
    let (ds, clock) = manual();
    let rec = Recorder::start(&ds, &file, Header::default()).unwrap();
    let cams = ds.create_object(ds.root(), ObjectInfo::new("cameras", "folder")).unwrap();
    let drive = ds.create_listener(cams, "drive").unwrap();
    let frame = |px: Vec<u8>, w: i64, n: i64| {
        vec![Value::Bytes(px.into()), Value::Int(w), Value::Int(2), Value::Int(n)]
    };
    // 30 frames a second for 200 ms: 2×2 RGB, the first byte the frame's number.
    for n in 0..7u8 {
        let mut px = vec![n; 12];
        px[1] = 200;
        ds.send(drive, frame(px, 2, i64::from(n))).unwrap();
        clock.advance(Duration::from_nanos(33_333_333));
    }
    // Not a frame: the size does not match the pixels.
    ds.send(drive, frame(vec![0; 5], 2, 8)).unwrap();
    rec.finish().unwrap();

    let msgs = read(&file);
    let frames = on(&msgs, "/camera/root.cameras.drive");
    let got: Vec<(u64, u64)> =
        frames.iter().map(|(_, t, j)| (*t / 1_000_000, j["data"][0].as_u64().unwrap())).collect();
    // Frames 0, 3 and 6 (100 ms apart); those between are thinned out.
    assert_eq!(got, vec![(0, 0), (99, 3), (199, 6)]);
    let j = &frames[1].2;
    assert_eq!((j["width"].as_u64(), j["height"].as_u64()), (Some(2), Some(2)));
    assert_eq!((j["encoding"].as_str(), j["step"].as_u64()), (Some("rgb8"), Some(6)));
    assert_eq!(j["frame_id"], "root.cameras.drive");
    assert_eq!(j["data"].as_array().unwrap().len(), 12);
    assert_eq!(j["data"][1], 200);
    assert_eq!(j["timestamp"], serde_json::json!({"sec": T0, "nsec": 99_999_999}));
}

#[test]
fn a_position_is_recorded_as_a_location_fix_once_both_lat_and_lon_are_known() {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("t.mcap");
    let (ds, _clock) = manual();
    let rec = Recorder::start(&ds, &file, Header::default()).unwrap();
    let nav = ds.create_object(ds.root(), ObjectInfo::new("nav", "nav")).unwrap();
    ds.set(nav, "lat", Value::Float(32.7)).unwrap();
    ds.set(nav, "lon", Value::Float(-117.2)).unwrap();
    ds.set(nav, "lat", Value::Float(32.8)).unwrap();
    rec.finish().unwrap();
    let msgs = read(&file);
    let fixes: Vec<(f64, f64)> = on(&msgs, "/location/root.nav")
        .iter()
        .map(|(_, _, j)| (j["latitude"].as_f64().unwrap(), j["longitude"].as_f64().unwrap()))
        .collect();
    assert_eq!(fixes, vec![(32.7, -117.2), (32.8, -117.2)]);
}

#[test]
fn a_moving_object_gets_a_location_fix_at_most_every_100_ms_and_always_its_last_position() {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("t.mcap");
    let (ds, clock) = manual();
    let rec = Recorder::start(&ds, &file, Header::default()).unwrap();
    let nav = ds.create_object(ds.root(), ObjectInfo::new("nav", "nav")).unwrap();
    let vehicle = ds.create_object(ds.root(), ObjectInfo::new("gone", "vehicle")).unwrap();
    let gone = ds.create_object(vehicle, ObjectInfo::new("nav", "nav")).unwrap();
    // 100 Hz for a quarter of a second, then still.
    let lat = |i: u64| 30.0 + i as f64 * 0.001;
    for i in 0..=25 {
        ds.set(nav, "lat", Value::Float(lat(i))).unwrap();
        ds.set(nav, "lon", Value::Float(-117.0)).unwrap();
        clock.advance(ms(10));
    }
    // A position that waits for its fix when the object above it is deleted: written first.
    ds.set(gone, "lat", Value::Float(1.0)).unwrap();
    ds.set(gone, "lon", Value::Float(2.0)).unwrap();
    ds.set(gone, "lat", Value::Float(1.5)).unwrap();
    ds.delete_object(vehicle).unwrap();
    rec.finish().unwrap();
    let msgs = read(&file);
    let fixes = |topic| -> Vec<(u64, f64, f64)> {
        on(&msgs, topic)
            .iter()
            .map(|(_, t, j)| {
                let deg = |k: &str| j[k].as_f64().unwrap();
                (t / 1_000_000, deg("latitude"), deg("longitude"))
            })
            .collect()
    };
    // At 0 ms (both known), then at the first change 100 ms after each fix, then the last
    // position (250 ms) when the recording ends.
    let want: Vec<_> = [0, 10, 20, 25].map(|i| (i * 10, lat(i), -117.0)).into();
    assert_eq!(fixes("/location/root.nav"), want);
    assert_eq!(fixes("/location/root.gone.nav"), vec![(260, 1.0, 2.0), (260, 1.5, 2.0)]);
    assert!(
        msgs.iter().all(|(topic, _, _)| !topic.starts_with("/location/#")),
        "no fix of a deleted object"
    );
    // Every position is recorded all the same: each property's first value where it is
    // created (`/world/property`), every later one in the batches.
    let later = on(&msgs, "/world/values").iter().filter(|(_, _, j)| j["kind"] == "float").count();
    assert_eq!(later, 25 + 1, "nav's 25 latitudes after its first, gone's second");
}

#[test]
fn a_keyframe_holds_the_world_as_the_changes_before_it_left_it() {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("t.mcap");
    let (ds, clock) = manual();
    let rec = Recorder::start(&ds, &file, Header::default()).unwrap();
    let a = ds.create_object(ds.root(), ObjectInfo::new("a", "thing")).unwrap();
    let b = ds.create_object(a, ObjectInfo::new("b", "thing")).unwrap();
    ds.create_property(b, "x", Value::Int(1), PropMeta::typed(ValueKind::Int).units("m")).unwrap();
    ds.set(a, "y", Value::str("first")).unwrap();
    ds.set(a, "y", Value::str("second")).unwrap();
    clock.advance(Duration::from_secs(11));
    ds.set(b, "x", Value::Int(2)).unwrap(); // after the keyframe that this write makes due
    rec.finish().unwrap();

    let msgs = read(&file);
    let snaps = on(&msgs, "/world/snapshot");
    assert_eq!(snaps.len(), 2, "one at the start, one after 10 s");
    assert_eq!(snaps[0].2["objects"], serde_json::json!([]));
    let world = &snaps[1].2;
    assert_eq!(world["seq"], 5);
    assert_eq!(
        world["objects"],
        serde_json::json!([
            {"guid": a.get(), "parent": 1, "index": 0, "name": "a", "type": "thing", "subtype": "",
             "properties": [{"id": 1, "name": "y", "kind": "string", "value": "second"}]},
            {"guid": b.get(), "parent": a.get(), "index": 0, "name": "b", "type": "thing", "subtype": "",
             "properties": [{"id": 0, "name": "x", "kind": "int", "value": 1, "meta": {"kind": "int", "units": "m"}}]}
        ])
    );
}

#[test]
fn events_go_to_the_trial_record_or_the_layout_channel_by_their_name() {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("t.mcap");
    let (ds, clock) = manual();
    let rec = Recorder::start(&ds, &file, Header::default()).unwrap();
    rec.event("layout", "load", &[("layout", Value::str("usv.mocu"))]);
    clock.advance(ms(250));
    rec.event("layout", "action", &[("kind", Value::str("acknowledge"))]);
    rec.event(
        "sim",
        "alert",
        &[("severity", Value::str("warning")), ("n", Value::Float(f64::NAN))],
    );
    rec.finish().unwrap();
    let msgs = read(&file);
    let layout = on(&msgs, "/layout");
    assert_eq!(layout.len(), 1);
    assert_eq!(
        layout[0].2,
        serde_json::json!({"event": "load", "layout": "usv.mocu", "fields": {"layout": "usv.mocu"}})
    );
    let events = on(&msgs, "/events");
    assert_eq!(events.len(), 2);
    assert_eq!(events[0].1, 250_000_000);
    assert_eq!(
        events[0].2,
        serde_json::json!({"source": "layout", "event": "action", "fields": {"kind": "acknowledge"}})
    );
    assert_eq!(events[1].2["fields"]["n"], "NaN");
}

#[test]
fn what_existed_before_the_recording_started_is_its_first_records_and_first_keyframe() {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("t.mcap");
    let (ds, clock) = manual();
    let v = ds.create_object(ds.root(), ObjectInfo::new("usv1", "vehicle")).unwrap();
    ds.create_property(v, "fuel", Value::Float(0.5), PropMeta::typed(ValueKind::Float).units("%"))
        .unwrap();
    clock.advance(ms(100));
    let rec = Recorder::start(&ds, &file, Header::default()).unwrap();
    ds.set(v, "fuel", Value::Float(0.4)).unwrap();
    rec.finish().unwrap();
    let msgs = read(&file);
    let objects = on(&msgs, "/world/object");
    assert_eq!((objects[0].1, &objects[0].2["path"]), (100_000_000, &"root.usv1".into()));
    let fuel: Vec<(&str, f64)> = msgs
        .iter()
        .filter(|(t, _, _)| t.starts_with("/world/property") || t == "/world/values")
        .map(|(_, _, j)| (j["op"].as_str().unwrap_or("value"), j["value"].as_f64().unwrap()))
        .collect();
    assert_eq!(fuel, vec![("created", 0.5), ("value", 0.4)]);
    let snap = &on(&msgs, "/world/snapshot")[0].2;
    assert_eq!(snap["seq"], 0);
    assert_eq!(snap["objects"][0]["properties"][0]["value"], 0.5);
}
