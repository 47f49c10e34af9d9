//! The messages replay applies, parsed from their JSON (docs/recording.md, "Channels"),
//! and `/world/values` batches from their CDR.

use crate::value::decode;
use mocu_dataserver::{ObjectInfo, PropMeta, Value, ValueKind};
use serde_json::Value as Json;

/// `/world/object`: an object created, changed or deleted (GUIDs are the recording's).
#[derive(Clone, Debug, PartialEq)]
pub enum ObjectChange {
    Created {
        guid: u64,
        parent: u64,
        index: usize,
        info: ObjectInfo,
    },
    /// Renamed or retyped; moved when `to` is given (parent, index).
    Changed {
        guid: u64,
        info: Option<ObjectInfo>,
        to: Option<(u64, usize)>,
    },
    Deleted {
        guid: u64,
    },
}

/// `/world/property`: a property created (with its metadata), set or deleted. `id`: the
/// number `/world/values` entries refer to it by (absent in recordings before batches).
#[derive(Clone, Debug, PartialEq)]
pub enum PropertyChange {
    Created { id: Option<u32>, object: u64, name: String, value: Value, meta: Option<PropMeta> },
    Set { id: Option<u32>, object: u64, name: String, value: Value },
    Deleted { id: Option<u32>, object: u64, name: String },
}

/// One entry of a `/world/values` batch: property `id` took `value` in change `seq` at
/// `log_time`.
#[derive(Clone, Debug, PartialEq)]
pub struct ValueEntry {
    pub id: u32,
    pub seq: u64,
    pub log_time: u64,
    pub value: Value,
}

/// Reads CDR (little endian; alignment counted from after the 4-byte header).
struct Cdr<'a> {
    data: &'a [u8],
    at: usize,
}

impl<'a> Cdr<'a> {
    fn take(&mut self, align: usize, n: usize) -> Option<&'a [u8]> {
        let body = self.at - 4;
        self.at += (align - body % align) % align;
        let out = self.data.get(self.at..self.at.checked_add(n)?)?;
        self.at += n;
        Some(out)
    }

    fn u64(&mut self) -> Option<u64> {
        Some(u64::from_le_bytes(self.take(8, 8)?.try_into().ok()?))
    }

    fn u32(&mut self) -> Option<u32> {
        Some(u32::from_le_bytes(self.take(4, 4)?.try_into().ok()?))
    }

    /// A sequence of `size`-byte elements.
    fn seq(&mut self, size: usize) -> Option<&'a [u8]> {
        let n = self.u32()? as usize;
        self.take(size, n.checked_mul(size)?)
    }

    /// A string (its length counts the terminating NUL).
    fn string(&mut self) -> Option<&'a str> {
        let b = self.seq(1)?;
        std::str::from_utf8(b.strip_suffix(&[0])?).ok()
    }
}

/// A frame of a camera that sends pixels (`/camera/…`, `foxglove_msgs/msg/RawImage` in
/// CDR): its camera's path (`frame_id`), size and pixels, RGB8 or RGBA8 rows as sent.
#[derive(Clone, Debug, PartialEq)]
pub struct Frame {
    pub camera: String,
    pub width: u32,
    pub height: u32,
    pub pixels: Vec<u8>,
}

impl Frame {
    /// `None` when malformed, or in an encoding other than `rgb8`/`rgba8` with rows
    /// packed (`step` = width × channels).
    pub fn parse(data: &[u8]) -> Option<Frame> {
        if data.get(..2)? != [0, 1] {
            return None;
        }
        let mut c = Cdr { data, at: 4 };
        let (_sec, _nsec) = (c.u32()?, c.u32()?);
        let camera = c.string()?.to_string();
        let (width, height) = (c.u32()?, c.u32()?);
        let channels = match c.string()? {
            "rgb8" => 3,
            "rgba8" => 4,
            _ => return None,
        };
        let step = c.u32()?;
        let pixels = c.seq(1)?;
        let row = width.checked_mul(channels)?;
        let size = (row as usize).checked_mul(height as usize)?;
        (step == row && pixels.len() == size && size > 0).then(|| Frame {
            camera,
            width,
            height,
            pixels: pixels.to_vec(),
        })
    }
}

/// A network camera's unit as received (`/video/…`: H.264 Annex B; `/image/…`: one JPEG),
/// from its JSON message (`foxglove.CompressedVideo` / `foxglove.CompressedImage` with Mocu's
/// `unit` and `arrival_us`).
#[derive(Clone, Debug, PartialEq)]
pub struct Unit {
    /// The camera's path (`frame_id`), e.g. `root.cameras.front`.
    pub camera: String,
    /// `h264` or `jpeg`.
    pub format: String,
    pub unit: i64,
    pub arrival_us: i64,
    pub data: Vec<u8>,
}

impl Unit {
    /// A unit in CDR (format 3: `foxglove_msgs/msg/CompressedVideo` or `…Image` with
    /// `unit` and `arrival_us`) or JSON (formats 1 and 2, base64 `data`).
    pub fn parse(data: &[u8]) -> Option<Unit> {
        if data.get(..2)? == [0, 1] {
            let mut c = Cdr { data, at: 4 };
            let (_sec, _nsec) = (c.u32()?, c.u32()?);
            let camera = c.string()?.to_string();
            let bytes = c.seq(1)?.to_vec();
            let format = c.string()?.to_string();
            let unit = c.u64()? as i64;
            let arrival_us = c.u64()? as i64;
            return Some(Unit { camera, format, unit, arrival_us, data: bytes });
        }
        let j: serde_json::Value = serde_json::from_slice(data).ok()?;
        let s = |k: &str| j.get(k).and_then(|v| v.as_str());
        Some(Unit {
            camera: s("frame_id")?.to_string(),
            format: s("format")?.to_string(),
            unit: j.get("unit").and_then(|v| v.as_i64()).unwrap_or(0),
            arrival_us: j.get("arrival_us").and_then(|v| v.as_i64()).unwrap_or(0),
            data: crate::value::base64(s("data")?)?,
        })
    }

    /// Whether a decoder can start here: a JPEG always; an H.264 unit holding an IDR slice
    /// or a sequence parameter set (NAL types 5, 7).
    pub fn is_key(&self) -> bool {
        if self.format != "h264" {
            return true;
        }
        let d = &self.data;
        (0..d.len().saturating_sub(3)).any(|i| {
            let start = d[i] == 0 && d[i + 1] == 0 && d[i + 2] == 1;
            start && matches!(d[i + 3] & 0x1f, 5 | 7)
        })
    }
}

/// A `/world/values` batch (`mocu_msgs/msg/PropertyValues`, CDR), entry by entry; `None`
/// when it is malformed.
pub fn values(data: &[u8]) -> Option<Vec<ValueEntry>> {
    if data.get(..2)? != [0, 1] {
        return None; // not little-endian CDR
    }
    let mut c = Cdr { data, at: 4 };
    let (first_seq, first_ns) = (c.u64()?, c.u64()?);
    let ids = c.seq(4)?;
    let seqs = c.seq(4)?;
    let dts = c.seq(4)?;
    let kinds = c.seq(1)?;
    let vals = c.seq(8)?;
    let n = ids.len() / 4;
    // Format 3: `seq` empty when entry i is change first_seq + i, `kind` empty when all
    // are floats.
    let seq_ok = seqs.is_empty() || seqs.len() == 4 * n;
    let kind_ok = kinds.is_empty() || kinds.len() == n;
    if ids.len() != 4 * n || !seq_ok || !kind_ok || dts.len() != 4 * n || vals.len() != 8 * n {
        return None;
    }
    let u32_at = |b: &[u8], i: usize| u32::from_le_bytes(b[4 * i..4 * i + 4].try_into().unwrap());
    (0..n)
        .map(|i| {
            let x = f64::from_le_bytes(vals[8 * i..8 * i + 8].try_into().ok()?);
            let seq = if seqs.is_empty() { i as u32 } else { u32_at(seqs, i) };
            let value = match kinds.get(i).copied().unwrap_or(0) {
                0 => Value::Float(x),
                1 => Value::Int(x as i64),
                2 => Value::Bool(x != 0.0),
                _ => return None,
            };
            Some(ValueEntry {
                id: u32_at(ids, i),
                seq: first_seq.wrapping_add(u64::from(seq)),
                log_time: first_ns.saturating_add(u64::from(u32_at(dts, i))),
                value,
            })
        })
        .collect()
}

/// `/world/snapshot`: the whole world model as of change `seq` (a keyframe).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Snapshot {
    pub seq: u64,
    /// Parents before children.
    pub objects: Vec<SnapshotObject>,
}

#[derive(Clone, Debug, PartialEq)]
pub struct SnapshotObject {
    pub guid: u64,
    pub parent: u64,
    pub index: usize,
    pub info: ObjectInfo,
    pub properties: Vec<(String, Value, Option<PropMeta>)>,
    /// Each property's id (`/world/values`), beside `properties`; `None` in recordings
    /// before batches.
    pub ids: Vec<Option<u32>>,
}

fn text<'a>(j: &'a Json, k: &str) -> Option<&'a str> {
    j.get(k)?.as_str()
}

fn info(j: &Json) -> Option<ObjectInfo> {
    let i = ObjectInfo::new(text(j, "name")?, text(j, "type").unwrap_or(""));
    Some(i.subtype(text(j, "subtype").unwrap_or("")))
}

/// Property metadata as written on `created` (`{"kind", "units", …}`).
pub fn meta(j: &Json) -> PropMeta {
    let mut m =
        PropMeta { kind: text(j, "kind").and_then(ValueKind::parse), ..PropMeta::default() };
    if let Some(u) = text(j, "units") {
        m = m.units(u);
    }
    if let Some(r) = text(j, "representation") {
        m = m.representation(r);
    }
    if let Some(d) = text(j, "description") {
        m = m.describe(d);
    }
    if let Some([lo, hi]) = j.get("range").and_then(Json::as_array).map(Vec::as_slice)
        && let (Some(lo), Some(hi)) = (lo.as_f64(), hi.as_f64())
    {
        m = m.range(lo, hi);
    }
    if let Some(hz) = j.get("rate_hz").and_then(Json::as_f64) {
        m = m.rate(hz);
    }
    m
}

impl ObjectChange {
    pub fn parse(data: &[u8]) -> Option<ObjectChange> {
        let j: Json = serde_json::from_slice(data).ok()?;
        let guid = j.get("guid")?.as_u64()?;
        let place = || Some((j.get("parent")?.as_u64()?, j.get("index")?.as_u64()? as usize));
        Some(match text(&j, "op")? {
            "created" => {
                let (parent, index) = place()?;
                ObjectChange::Created { guid, parent, index, info: info(&j)? }
            }
            "changed" => ObjectChange::Changed { guid, info: info(&j), to: place() },
            "deleted" => ObjectChange::Deleted { guid },
            _ => return None,
        })
    }
}

impl PropertyChange {
    pub fn parse(data: &[u8]) -> Option<PropertyChange> {
        let j: Json = serde_json::from_slice(data).ok()?;
        let object = j.get("object")?.as_u64()?;
        let id = j.get("id").and_then(Json::as_u64).and_then(|i| u32::try_from(i).ok());
        let name = text(&j, "name")?.to_string();
        let value = || decode(text(&j, "kind")?, j.get("value")?);
        Some(match text(&j, "op")? {
            "created" => PropertyChange::Created {
                id,
                object,
                name,
                value: value()?,
                meta: j.get("meta").map(meta),
            },
            "set" => PropertyChange::Set { id, object, name, value: value()? },
            "deleted" => PropertyChange::Deleted { id, object, name },
            _ => return None,
        })
    }
}

impl Snapshot {
    pub fn parse(data: &[u8]) -> Option<Snapshot> {
        let j: Json = serde_json::from_slice(data).ok()?;
        let mut objects = Vec::new();
        for o in j.get("objects")?.as_array()? {
            let mut properties = Vec::new();
            let mut ids = Vec::new();
            for p in o.get("properties").and_then(Json::as_array).into_iter().flatten() {
                let Some(v) =
                    decode(text(p, "kind").unwrap_or(""), p.get("value").unwrap_or(&Json::Null))
                else {
                    continue;
                };
                properties.push((text(p, "name")?.to_string(), v, p.get("meta").map(meta)));
                ids.push(p.get("id").and_then(Json::as_u64).and_then(|i| u32::try_from(i).ok()));
            }
            objects.push(SnapshotObject {
                guid: o.get("guid")?.as_u64()?,
                parent: o.get("parent")?.as_u64()?,
                index: o.get("index").and_then(Json::as_u64).unwrap_or(u64::MAX) as usize,
                info: info(o)?,
                properties,
                ids,
            });
        }
        Some(Snapshot { seq: j.get("seq").and_then(Json::as_u64).unwrap_or(0), objects })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_documented_examples_parse() {
        let o = br#"{"op": "created", "guid": 12, "parent": 3, "index": 0, "path": "root.vehicles.usv1",
 "name": "usv1", "type": "vehicle", "subtype": "usv"}"#;
        assert_eq!(
            ObjectChange::parse(o),
            Some(ObjectChange::Created {
                guid: 12,
                parent: 3,
                index: 0,
                info: ObjectInfo::new("usv1", "vehicle").subtype("usv")
            })
        );
        let p = br#"{"op": "set", "object": 14, "path": "root.vehicles.usv1.nav.speed", "name": "speed",
 "kind": "float", "value": 3.25, "unit": "m/s"}"#;
        assert_eq!(
            PropertyChange::parse(p),
            Some(PropertyChange::Set {
                id: None,
                object: 14,
                name: "speed".into(),
                value: Value::Float(3.25)
            })
        );
        let c = br#"{"op": "created", "object": 14, "name": "speed", "kind": "float", "value": 0.0,
 "meta": {"kind": "float", "units": "m/s", "range": [0, 30], "rate_hz": 20}}"#;
        let Some(PropertyChange::Created { meta: Some(m), .. }) = PropertyChange::parse(c) else {
            panic!("not parsed");
        };
        assert_eq!(m.units.as_deref(), Some("m/s"));
        assert_eq!((m.range, m.rate_hz), (Some((0.0, 30.0)), Some(20.0)));
    }
}
