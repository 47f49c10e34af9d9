//! A synthetic recording in the format of docs/recording.md, for the replay's tests and its
//! seek bench: `vehicles` objects under `root.vehicles`, each with `props` float properties
//! written `hz` times a second (property `pK` of step `i` holds `i + K / 1000`), keyframes
//! on `/world/snapshot` every `keyframe_secs` (none when 0), LZ4 chunks of 1 MiB.
#![allow(dead_code)]

use mcap::records::MessageHeader;
use std::collections::BTreeMap;
use std::io::BufWriter;
use std::path::Path;

pub const START_NS: u64 = 1_763_875_200_000_000_000;

#[derive(Clone, Copy)]
pub struct Synthetic {
    pub seconds: u64,
    pub vehicles: u64,
    pub props: u64,
    pub hz: u64,
    pub keyframe_secs: u64,
}

/// The value property `k` holds after step `i`.
pub fn value(i: u64, k: u64) -> f64 {
    i as f64 + k as f64 / 1000.0
}

/// GUIDs: root 1, `vehicles` 2, vehicle `v` (from 0) `3 + v`.
pub fn vehicle_guid(v: u64) -> u64 {
    3 + v
}

pub fn write(path: &Path, s: Synthetic) {
    let f = BufWriter::new(std::fs::File::create(path).unwrap());
    let opts = mcap::WriteOptions::new()
        .compression(Some(mcap::Compression::Lz4))
        .chunk_size(Some(1 << 20))
        .profile("mocu");
    let mut w = opts.create(f).unwrap();
    let meta = BTreeMap::from([
        ("format".to_string(), "1".to_string()),
        ("start_ns".to_string(), START_NS.to_string()),
        ("clock".to_string(), "manual".to_string()),
    ]);
    w.write_metadata(&mcap::records::Metadata { name: "mocu".into(), metadata: meta }).unwrap();
    let schema = |w: &mut mcap::Writer<_>, name: &str| {
        w.add_schema(name, "jsonschema", b"{\"type\": \"object\"}").unwrap()
    };
    let none = BTreeMap::new();
    let so = schema(&mut w, "mocu.ObjectChange");
    let sp = schema(&mut w, "mocu.PropertyChange");
    let ss = schema(&mut w, "mocu.WorldSnapshot");
    let objects = w.add_channel(so, "/world/object", "json", &none).unwrap();
    let props = w.add_channel(sp, "/world/property", "json", &none).unwrap();
    let snaps = w.add_channel(ss, "/world/snapshot", "json", &none).unwrap();
    let mut seq: u32 = 0;
    let mut put = |w: &mut mcap::Writer<_>, channel_id: u16, t: u64, data: String| {
        seq = seq.wrapping_add(1);
        let h = MessageHeader { channel_id, sequence: seq, log_time: t, publish_time: t };
        w.write_to_known_channel(&h, data.as_bytes()).unwrap();
    };
    put(
        &mut w,
        objects,
        START_NS,
        r#"{"op":"created","guid":2,"parent":1,"index":0,"path":"root.vehicles","name":"vehicles","type":"vehicles"}"#.into(),
    );
    for v in 0..s.vehicles {
        let g = vehicle_guid(v);
        put(
            &mut w,
            objects,
            START_NS,
            format!(
                r#"{{"op":"created","guid":{g},"parent":2,"index":{v},"path":"root.vehicles.usv{v}","name":"usv{v}","type":"vehicle","subtype":"usv"}}"#
            ),
        );
        for k in 0..s.props {
            put(
                &mut w,
                props,
                START_NS,
                format!(
                    r#"{{"op":"created","object":{g},"name":"p{k}","kind":"float","value":{:?},"meta":{{"kind":"float","units":"m"}}}}"#,
                    value(0, k)
                ),
            );
        }
    }
    let step_ns = 1_000_000_000 / s.hz;
    let steps = s.seconds * s.hz;
    let every = s.keyframe_secs * s.hz;
    for i in 1..=steps {
        let t = START_NS + i * step_ns;
        for v in 0..s.vehicles {
            let g = vehicle_guid(v);
            for k in 0..s.props {
                put(
                    &mut w,
                    props,
                    t,
                    format!(
                        r#"{{"op":"set","object":{g},"path":"root.vehicles.usv{v}.p{k}","name":"p{k}","kind":"float","value":{:?}}}"#,
                        value(i, k)
                    ),
                );
            }
        }
        if every > 0 && i % every == 0 {
            put(&mut w, snaps, t, snapshot(i, s));
        }
    }
    w.finish().unwrap();
}

/// The world after step `i`, as a keyframe.
fn snapshot(i: u64, s: Synthetic) -> String {
    let mut objects = vec![
        r#"{"guid":2,"parent":1,"index":0,"name":"vehicles","type":"vehicles","properties":[]}"#
            .to_string(),
    ];
    for v in 0..s.vehicles {
        let ps: Vec<String> = (0..s.props)
            .map(|k| format!(r#"{{"name":"p{k}","kind":"float","value":{:?},"meta":{{"kind":"float","units":"m"}}}}"#, value(i, k)))
            .collect();
        objects.push(format!(
            r#"{{"guid":{},"parent":2,"index":{v},"name":"usv{v}","type":"vehicle","subtype":"usv","properties":[{}]}}"#,
            vehicle_guid(v),
            ps.join(",")
        ));
    }
    format!(r#"{{"seq":0,"objects":[{}]}}"#, objects.join(","))
}
