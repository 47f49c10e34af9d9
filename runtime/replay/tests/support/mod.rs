//! A synthetic recording in the format of docs/recording.md, for the replay's tests and its
//! seek bench: `vehicles` objects under `root.vehicles`, each with `props` float properties
//! written `hz` times a second (property `pK` of step `i` holds `i + K / 1000`), keyframes
//! on `/world/snapshot` every `keyframe_secs` (none when 0), LZ4 chunks of 1 MiB. With
//! `batch_steps` > 0 the writes go as the recorder writes them: on `/world/values` in CDR
//! batches of that many steps (a batch written before each keyframe), properties declared
//! with their ids; with 0, one JSON `set` message each (recordings of format 1).
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
    pub batch_steps: u64,
}

/// Property `k` of vehicle `v`'s id.
fn id(s: Synthetic, v: u64, k: u64) -> u32 {
    (v * s.props + k) as u32
}

/// The `/world/values` batch gathered so far (columns), as one CDR message.
#[derive(Default)]
struct Batch {
    first: Option<(u64, u64)>,
    id: Vec<u32>,
    seq: Vec<u32>,
    dt: Vec<u32>,
    value: Vec<f64>,
}

impl Batch {
    fn push(&mut self, id: u32, seq: u64, t: u64, x: f64) {
        let (s0, t0) = *self.first.get_or_insert((seq, t));
        self.id.push(id);
        self.seq.push((seq - s0) as u32);
        self.dt.push((t - t0) as u32);
        self.value.push(x);
    }

    fn take(&mut self) -> Option<(u64, u64, Vec<u8>)> {
        let (s0, t0) = self.first.take()?;
        let mut d = vec![0, 1, 0, 0];
        d.extend_from_slice(&s0.to_le_bytes());
        d.extend_from_slice(&t0.to_le_bytes());
        for col in [&self.id, &self.seq, &self.dt] {
            d.extend_from_slice(&(col.len() as u32).to_le_bytes());
            col.iter().for_each(|x| d.extend_from_slice(&x.to_le_bytes()));
        }
        d.extend_from_slice(&(self.value.len() as u32).to_le_bytes());
        d.resize(d.len() + self.value.len(), 0); // kind[]: all float (0)
        while (d.len() - 4) % 4 != 0 {
            d.push(0);
        }
        d.extend_from_slice(&(self.value.len() as u32).to_le_bytes());
        while (d.len() - 4) % 8 != 0 {
            d.push(0);
        }
        self.value.iter().for_each(|x| d.extend_from_slice(&x.to_le_bytes()));
        let out = Some((s0, t0, d));
        *self = Batch::default();
        out
    }
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
    let sv = w.add_schema("mocu_msgs/msg/PropertyValues", "ros2msg", b"").unwrap();
    let values = w.add_channel(sv, "/world/values", "cdr", &none).unwrap();
    let batched = s.batch_steps > 0;
    let seq = std::cell::Cell::new(0u64);
    let put = |w: &mut mcap::Writer<_>, channel_id: u16, t: u64, data: &[u8]| {
        seq.set(seq.get() + 1);
        let sequence = seq.get() as u32;
        let h = MessageHeader { channel_id, sequence, log_time: t, publish_time: t };
        w.write_to_known_channel(&h, data).unwrap();
    };
    let write_batch = |w: &mut mcap::Writer<_>, b: &mut Batch| {
        if let Some((s0, t0, d)) = b.take() {
            let h = MessageHeader {
                channel_id: values,
                sequence: s0 as u32,
                log_time: t0,
                publish_time: t0,
            };
            w.write_to_known_channel(&h, &d).unwrap();
        }
    };
    let mut batch = Batch::default();
    put(
        &mut w,
        objects,
        START_NS,
        br#"{"op":"created","guid":2,"parent":1,"index":0,"path":"root.vehicles","name":"vehicles","type":"vehicles"}"#,
    );
    for v in 0..s.vehicles {
        let g = vehicle_guid(v);
        put(
            &mut w,
            objects,
            START_NS,
            format!(
                r#"{{"op":"created","guid":{g},"parent":2,"index":{v},"path":"root.vehicles.usv{v}","name":"usv{v}","type":"vehicle","subtype":"usv"}}"#
            ).as_bytes(),
        );
        for k in 0..s.props {
            put(
                &mut w,
                props,
                START_NS,
                format!(
                    r#"{{"op":"created",{}"object":{g},"name":"p{k}","kind":"float","value":{:?},"meta":{{"kind":"float","units":"m"}}}}"#,
                    if batched { format!(r#""id":{},"#, id(s, v, k)) } else { String::new() },
                    value(0, k)
                ).as_bytes(),
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
                if batched {
                    seq.set(seq.get() + 1);
                    batch.push(id(s, v, k), seq.get(), t, value(i, k));
                    continue;
                }
                put(
                    &mut w,
                    props,
                    t,
                    format!(
                        r#"{{"op":"set","object":{g},"path":"root.vehicles.usv{v}.p{k}","name":"p{k}","kind":"float","value":{:?}}}"#,
                        value(i, k)
                    ).as_bytes(),
                );
            }
        }
        let keyframe = every > 0 && i % every == 0;
        if batched && (keyframe || i % s.batch_steps == 0) {
            write_batch(&mut w, &mut batch);
        }
        if keyframe {
            let key = snapshot(i, s, seq.get());
            put(&mut w, snaps, t, key.as_bytes());
        }
    }
    write_batch(&mut w, &mut batch);
    w.finish().unwrap();
}

/// The world after step `i` (change `seq`), as a keyframe.
fn snapshot(i: u64, s: Synthetic, seq: u64) -> String {
    let mut objects = vec![
        r#"{"guid":2,"parent":1,"index":0,"name":"vehicles","type":"vehicles","properties":[]}"#
            .to_string(),
    ];
    for v in 0..s.vehicles {
        let ps: Vec<String> = (0..s.props)
            .map(|k| format!(r#"{{"id":{},"name":"p{k}","kind":"float","value":{:?},"meta":{{"kind":"float","units":"m"}}}}"#, id(s, v, k), value(i, k)))
            .collect();
        objects.push(format!(
            r#"{{"guid":{},"parent":2,"index":{v},"name":"usv{v}","type":"vehicle","subtype":"usv","properties":[{}]}}"#,
            vehicle_guid(v),
            ps.join(",")
        ));
    }
    format!(r#"{{"seq":{seq},"objects":[{}]}}"#, objects.join(","))
}

/// A recording of format 1, written message by message: uncompressed chunks, the `mocu`
/// metadata starting at [`START_NS`], and its `/world/object` and `/world/property` channels.
pub struct Format1 {
    pub w: mcap::Writer<BufWriter<std::fs::File>>,
    pub objects: u16,
    pub props: u16,
    seq: u32,
}

impl Format1 {
    pub fn create(path: &Path) -> Format1 {
        let f = std::fs::File::create(path).unwrap();
        let opts = mcap::WriteOptions::new().compression(None).profile("mocu");
        let mut w = opts.create(BufWriter::new(f)).unwrap();
        let meta = BTreeMap::from([
            ("format".to_string(), "1".to_string()),
            ("start_ns".to_string(), START_NS.to_string()),
        ]);
        w.write_metadata(&mcap::records::Metadata { name: "mocu".into(), metadata: meta }).unwrap();
        let none = BTreeMap::new();
        let s = w.add_schema("mocu.ObjectChange", "jsonschema", b"{}").unwrap();
        let objects = w.add_channel(s, "/world/object", "json", &none).unwrap();
        let props = w.add_channel(s, "/world/property", "json", &none).unwrap();
        Format1 { w, objects, props, seq: 0 }
    }

    /// One message on `channel_id` at `log_time`.
    pub fn put(&mut self, channel_id: u16, log_time: u64, data: &str) {
        self.seq += 1;
        let h = MessageHeader { channel_id, sequence: self.seq, log_time, publish_time: log_time };
        self.w.write_to_known_channel(&h, data.as_bytes()).unwrap();
    }

    pub fn finish(mut self) {
        self.w.finish().unwrap();
    }
}
