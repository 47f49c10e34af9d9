//! From the change feed and the trial's events to messages on the channels of
//! docs/recording.md.

use crate::file::{Dynamic, Out};
use crate::values::{self, Batch};
use crate::world::{self, World};
use crate::{Event, EventTopic, Totals, json, nanos};
use mocu_dataserver::{CallOutcome, Change, Guid, PropName, Stamped, Value};
use std::collections::{HashMap, HashSet};

mod lane;
mod place;

/// A keyframe at least this often (nanoseconds of `log_time`) …
const SNAPSHOT_NS: u64 = 10_000_000_000;
/// … or after this many `/world/*` changes, whichever comes first.
const SNAPSHOT_CHANGES: u64 = 200_000;

/// The most frames a second recorded of a camera that sends pixels (the simulator's):
/// a frame is written when at least 3/4 of this period has passed since the last one
/// written, so a 10 fps camera is recorded whole and a faster one thinned to about this.
pub(crate) const RAW_FPS: u64 = 10;
const RAW_GAP_NS: u64 = 1_000_000_000 / RAW_FPS * 3 / 4;

/// Methods that are not recorded: the display drawing itself, every frame (`paint`) and
/// asking for it (`invalidate`).
const UNRECORDED_METHODS: &[&str] = &["paint", "invalidate"];

pub(crate) struct Translator {
    out: Out,
    world: World,
    buf: Vec<u8>,
    /// The `/world/values` batch being gathered.
    batch: Batch,
    /// `lat`, `lon`, `alt`: the names a `/location/…` fix is made of.
    place_names: [PropName; 3],
    /// Calls not recorded, until their outcome comes.
    skipped: HashSet<u64>,
    /// Each object's last `lat`, `lon`, `alt` and its `/location/…` fixes (`place.rs`).
    places: HashMap<Guid, place::Place>,
    /// Objects whose last position waits for its fix.
    waiting_fixes: Vec<Guid>,
    /// Each property the feed's lane numbered (by that number): its object and name,
    /// asked of the feed once.
    numbered: Vec<Option<(Guid, PropName)>>,
    /// When each pixel camera's last recorded frame was sent.
    raw_last: HashMap<Guid, u64>,
    /// The recording's `id` of each property by the server's number for it in the feed's
    /// numeric lane (`lane::UNKNOWN` until met).
    lane: Vec<u32>,
    /// Listeners to mute (true) or unmute on the feed: cameras whose decoded frames are not
    /// recorded (their units are), so that the feed does not keep them alive.
    mute: Vec<(Guid, bool)>,
    last_seq: u64,
    last_time: u64,
    snapshot_time: u64,
    since_snapshot: u64,
    event_seq: u64,
}

impl Translator {
    pub fn new(out: Out, start: u64, existing: Vec<world::Existing>) -> Result<Translator, String> {
        let mut t = Translator {
            out,
            world: World::new(),
            buf: Vec::with_capacity(4096),
            batch: Batch::default(),
            place_names: [PropName::new("lat"), PropName::new("lon"), PropName::new("alt")],
            skipped: HashSet::new(),
            places: HashMap::new(),
            waiting_fixes: Vec::new(),
            numbered: Vec::new(),
            raw_last: HashMap::new(),
            lane: Vec::new(),
            mute: Vec::new(),
            last_seq: 0,
            last_time: start,
            snapshot_time: start,
            since_snapshot: 0,
            event_seq: 0,
        };
        // What existed before the recording: created at its start, number 0.
        for e in existing {
            let stamp = |change| Stamped {
                seq: 0,
                wall: std::time::UNIX_EPOCH + std::time::Duration::from_nanos(start),
                change,
            };
            if e.guid != Guid::ROOT {
                t.change(&stamp(Change::Created {
                    object: e.guid,
                    parent: e.parent,
                    index: e.index,
                    info: e.info,
                }))?;
            }
            for p in e.props {
                t.change(&stamp(Change::PropertySet {
                    object: e.guid,
                    name: p.name,
                    value: p.value,
                    meta: p.meta,
                    created: true,
                }))?;
            }
        }
        t.snapshot()?;
        Ok(t)
    }

    /// Writes the `/world/values` batch gathered so far, if any.
    pub fn write_values(&mut self) -> Result<(), String> {
        if self.batch.is_empty() {
            return Ok(());
        }
        let (seq, t) = self.batch.first();
        self.batch.encode(&mut self.buf);
        let ch = self.out.values;
        self.out.write(ch, seq, t, &self.buf)?;
        Ok(())
    }

    fn snapshot(&mut self) -> Result<(), String> {
        // Every change before the keyframe is on the file before it.
        self.write_values()?;
        self.buf.clear();
        self.world.snapshot(self.last_seq, &mut self.buf);
        let ch = self.out.snapshot;
        self.out.write(ch, self.last_seq, self.last_time, &self.buf)?;
        self.snapshot_time = self.last_time;
        self.since_snapshot = 0;
        Ok(())
    }

    /// Whether a keyframe is due before a change at `t` (when there were changes since the
    /// last one).
    fn snapshot_due(&self, t: u64) -> bool {
        t.saturating_sub(self.snapshot_time) >= SNAPSHOT_NS
            || self.since_snapshot >= SNAPSHOT_CHANGES
    }

    /// Translates one change (by reference: a change is a hundred bytes, and most are
    /// only read).
    pub fn change(&mut self, s: &Stamped) -> Result<(), String> {
        let t = nanos(s.wall);
        if s.seq > 0 && self.since_snapshot > 0 && self.snapshot_due(t) {
            self.snapshot()?;
        }
        self.last_seq = s.seq;
        self.last_time = self.last_time.max(t);
        // Almost all of a busy trial: a known property takes a new number (not a position:
        // those also make a location fix, below).
        if let Change::PropertySet { object, name, value, meta: None, created: false } = &s.change
            && let Some((kind, x)) = values::numeric(value)
            && !self.place_names.contains(name)
            && let Some(id) = self.world.update(*object, *name, value)
        {
            self.since_snapshot += 1;
            if !self.batch.fits(s.seq, t) {
                self.write_values()?;
            }
            self.batch.push(id, s.seq, t, kind, x);
            return Ok(());
        }
        if let Change::Deleted { object } = s.change
            && !self.places.is_empty()
        {
            for g in self.world.subtree(object) {
                self.forget_place(g)?;
            }
        }
        let b = &mut self.buf;
        b.clear();
        let channel = match s.change.clone() {
            Change::Created { object, parent, index, info } => {
                self.world.create(object, parent, index, info.clone());
                b.extend_from_slice(b"{\"op\":\"created\",\"guid\":");
                json::uint(b, object.get());
                b.extend_from_slice(b",\"parent\":");
                json::uint(b, parent.get());
                b.extend_from_slice(b",\"index\":");
                json::uint(b, index as u64);
                b.extend_from_slice(b",\"path\":");
                json::string(b, &self.world.path(object));
                world::info(b, &info);
                b.push(b'}');
                self.since_snapshot += 1;
                self.out.object
            }
            Change::Renamed { object, info } => {
                self.world.rename(object, info.clone());
                b.extend_from_slice(b"{\"op\":\"changed\",\"guid\":");
                json::uint(b, object.get());
                b.extend_from_slice(b",\"path\":");
                json::string(b, &self.world.path(object));
                world::info(b, &info);
                b.push(b'}');
                self.since_snapshot += 1;
                self.out.object
            }
            Change::Moved { object, parent, index } => {
                self.world.moved(object, parent, index);
                b.extend_from_slice(b"{\"op\":\"changed\",\"guid\":");
                json::uint(b, object.get());
                b.extend_from_slice(b",\"parent\":");
                json::uint(b, parent.get());
                b.extend_from_slice(b",\"index\":");
                json::uint(b, index as u64);
                b.extend_from_slice(b",\"path\":");
                json::string(b, &self.world.path(object));
                if let Some(o) = self.world.get(object) {
                    world::info(b, &o.info);
                }
                b.push(b'}');
                self.since_snapshot += 1;
                self.out.object
            }
            Change::Deleted { object } => {
                if let Some(o) = self.world.get(object)
                    && &*o.info.name == "encoded"
                    && let Some(camera) = o.parent
                {
                    self.mute.push((camera, false));
                }
                b.extend_from_slice(b"{\"op\":\"deleted\",\"guid\":");
                json::uint(b, object.get());
                b.extend_from_slice(b",\"path\":");
                json::string(b, &self.world.path(object));
                b.push(b'}');
                self.world.delete(object);
                self.raw_last.remove(&object);
                self.since_snapshot += 1;
                self.out.object
            }
            Change::PropertySet { object, name, value, meta, created } => {
                let (id, new) = self.world.set(object, name, &value, &meta);
                self.since_snapshot += 1;
                let entry = if created || new { None } else { values::numeric(&value) };
                if let Some((kind, x)) = entry {
                    if !self.batch.fits(s.seq, t) {
                        self.write_values()?;
                    }
                    self.batch.push(id, s.seq, t, kind, x);
                } else {
                    let b = &mut self.buf;
                    b.clear();
                    b.extend_from_slice(if created {
                        b"{\"op\":\"created\",\"id\":"
                    } else {
                        b"{\"op\":\"set\",\"id\":"
                    });
                    json::uint(b, u64::from(id));
                    b.extend_from_slice(b",\"object\":");
                    json::uint(b, object.get());
                    b.extend_from_slice(b",\"path\":");
                    json::dotted(b, &self.world.path(object), name.as_str());
                    b.extend_from_slice(b",\"name\":");
                    json::string(b, name.as_str());
                    b.extend_from_slice(b",\"kind\":\"");
                    b.extend_from_slice(value.kind().name().as_bytes());
                    b.extend_from_slice(b"\",\"value\":");
                    json::value(b, &value);
                    let units = meta.as_deref().or_else(|| self.world.meta(id));
                    if let Some(units) = units.and_then(|m| m.units.as_deref()) {
                        b.extend_from_slice(b",\"unit\":");
                        json::string(b, units);
                    }
                    if created && let Some(m) = &meta {
                        b.extend_from_slice(b",\"meta\":");
                        world::meta(b, m);
                    }
                    b.push(b'}');
                    let ch = self.out.property;
                    self.out.write(ch, s.seq, t, &self.buf)?;
                }
                match self.place_names.iter().position(|&n| n == name) {
                    Some(i) => return self.place(object, i, value.as_f64(), s.seq, t),
                    None => return Ok(()),
                }
            }
            Change::PropertyDeleted { object, name } => {
                let id = self.world.delete_property(object, name);
                b.extend_from_slice(b"{\"op\":\"deleted\"");
                if let Some(id) = id {
                    b.extend_from_slice(b",\"id\":");
                    json::uint(b, u64::from(id));
                }
                b.extend_from_slice(b",\"object\":");
                json::uint(b, object.get());
                b.extend_from_slice(b",\"path\":");
                json::dotted(b, &self.world.path(object), name.as_str());
                b.extend_from_slice(b",\"name\":");
                json::string(b, name.as_str());
                b.push(b'}');
                self.since_snapshot += 1;
                self.out.property
            }
            Change::Called { call, object, method, args } => {
                if UNRECORDED_METHODS.contains(&method.as_str()) {
                    self.skipped.insert(call);
                    return Ok(());
                }
                b.extend_from_slice(b"{\"op\":\"call\",\"id\":");
                json::uint(b, call);
                b.extend_from_slice(b",\"object\":");
                json::uint(b, object.get());
                b.extend_from_slice(b",\"path\":");
                json::string(b, &self.world.path(object));
                b.extend_from_slice(b",\"method\":");
                json::string(b, method.as_str());
                b.extend_from_slice(b",\"args\":");
                json::typed_list(b, &args);
                b.push(b'}');
                self.out.calls
            }
            Change::Answered { call, outcome } => {
                if self.skipped.remove(&call) {
                    return Ok(());
                }
                b.extend_from_slice(b"{\"op\":\"outcome\",\"id\":");
                json::uint(b, call);
                b.extend_from_slice(b",\"outcome\":\"");
                b.extend_from_slice(outcome.label().as_bytes());
                b.extend_from_slice(b"\",\"reason\":");
                let (reason, results) = match &outcome {
                    CallOutcome::Refused(r) | CallOutcome::Failed(r) => (r.as_str(), &[][..]),
                    CallOutcome::Accepted(r) => ("", &r[..]),
                    _ => ("", &[][..]),
                };
                json::string(b, reason);
                b.extend_from_slice(b",\"results\":");
                json::typed_list(b, results);
                b.push(b'}');
                self.out.calls
            }
            Change::Sent { listener, message } => return self.video(listener, &message, s.seq, t),
        };
        self.out.write(channel, s.seq, t, &self.buf)?;
        Ok(())
    }

    /// A stream message: a unit on a camera's `encoded` listener, or a frame of pixels from
    /// a camera that has no `encoded` listener (the simulator's); others are not recorded.
    fn video(&mut self, listener: Guid, msg: &[Value], seq: u64, t: u64) -> Result<(), String> {
        let Some(l) = self.world.get(listener) else { return Ok(()) };
        if &*l.info.name != "encoded" {
            let decoded = l
                .children
                .iter()
                .any(|&c| self.world.get(c).is_some_and(|o| &*o.info.name == "encoded"));
            return match decoded {
                // A network camera's frames are decoded from its units, which are recorded.
                true => {
                    self.mute.push((listener, true));
                    Ok(())
                }
                false => self.raw_frame(listener, msg, seq, t),
            };
        }
        let (Some(Value::Bytes(data)), Some(Value::Str(codec))) = (msg.first(), msg.get(1)) else {
            return Ok(());
        };
        let camera = l.parent.map(|p| self.world.path(p)).unwrap_or_else(|| "root".into());
        let (kind, topic, format) = match &**codec {
            "h264" => (Dynamic::Video, format!("/video/{camera}"), "h264"),
            "jpeg" => (Dynamic::Image, format!("/image/{camera}"), "jpeg"),
            _ => return Ok(()),
        };
        let ch = self.out.dynamic(kind, &topic)?;
        let int = |i: usize| match msg.get(i) {
            Some(&Value::Int(x)) => x,
            _ => 0,
        };
        self.buf.reserve(data.len() + camera.len() + 64);
        let mut c = crate::cdr::Cdr::start(&mut self.buf);
        c.time(t);
        c.string(&camera);
        c.bytes(data);
        c.string(format);
        c.i64(int(2));
        c.i64(int(3));
        self.out.write(ch, seq, t, &self.buf)?;
        Ok(())
    }

    /// A frame of pixels, `[pixels, width, height, frame, …]` (RGB8 or RGBA8 rows), as a
    /// `foxglove_msgs/msg/RawImage` on `/camera/<camera path>`, at most [`RAW_FPS`] a second.
    fn raw_frame(&mut self, camera: Guid, msg: &[Value], seq: u64, t: u64) -> Result<(), String> {
        let (Some(Value::Bytes(px)), Some(&Value::Int(w)), Some(&Value::Int(h))) =
            (msg.first(), msg.get(1), msg.get(2))
        else {
            return Ok(());
        };
        let (Ok(w), Ok(h)) = (u32::try_from(w), u32::try_from(h)) else { return Ok(()) };
        let pixels = w as usize * h as usize;
        let (encoding, step) = match px.len() {
            n if n > 0 && n == pixels * 3 => ("rgb8", w * 3),
            n if n > 0 && n == pixels * 4 => ("rgba8", w * 4),
            _ => return Ok(()),
        };
        if self.raw_last.get(&camera).is_some_and(|&last| t < last.saturating_add(RAW_GAP_NS)) {
            return Ok(());
        }
        self.raw_last.insert(camera, t);
        let path = self.world.path(camera);
        let ch = self.out.dynamic(Dynamic::RawImage, &format!("/camera/{path}"))?;
        self.buf.reserve(px.len() + path.len() + 64);
        let mut c = crate::cdr::Cdr::start(&mut self.buf);
        c.time(t);
        c.string(&path);
        c.u32(w);
        c.u32(h);
        c.string(encoding);
        c.u32(step);
        c.bytes(px);
        self.out.write(ch, seq, t, &self.buf)?;
        Ok(())
    }

    pub fn event(&mut self, e: Event) -> Result<(), String> {
        let t = nanos(e.at);
        let topic = EventTopic::of(&e.event);
        let b = &mut self.buf;
        b.clear();
        let layout = e.fields.iter().find(|(k, _)| k == "layout").map(|(_, v)| v.to_string());
        match topic {
            EventTopic::Events => {
                b.extend_from_slice(b"{\"source\":");
                json::string(b, &e.source);
                b.extend_from_slice(b",\"event\":");
                json::string(b, &e.event);
            }
            EventTopic::Layout => {
                b.extend_from_slice(b"{\"event\":");
                json::string(b, &e.event);
                if let Some(l) = &layout {
                    b.extend_from_slice(b",\"layout\":");
                    json::string(b, l);
                }
            }
        }
        b.extend_from_slice(b",\"fields\":{");
        for (i, (k, v)) in e.fields.iter().enumerate() {
            if i > 0 {
                b.push(b',');
            }
            json::string(b, k);
            b.push(b':');
            json::plain(b, v);
        }
        b.extend_from_slice(b"}}");
        self.event_seq += 1;
        let ch = match topic {
            EventTopic::Events => self.out.events,
            EventTopic::Layout => self.out.layout,
        };
        self.out.write(ch, self.event_seq, t, &self.buf)?;
        Ok(())
    }

    /// Messages written so far.
    pub fn written(&self) -> u64 {
        self.out.messages
    }

    pub fn flush(&mut self) -> Result<(), String> {
        self.write_values()?;
        self.out.flush()
    }

    pub fn finish(mut self) -> Result<Totals, String> {
        self.due_fixes(u64::MAX)?;
        self.write_values()?;
        let totals = Totals { messages: self.out.messages, bytes: self.out.bytes };
        self.out.finish()?;
        Ok(totals)
    }
}

/// `{"timestamp":{"sec":…,"nsec":…}` (the message's opening brace included).
fn timestamp(b: &mut Vec<u8>, t: u64) {
    b.extend_from_slice(b"{\"timestamp\":{\"sec\":");
    json::uint(b, t / 1_000_000_000);
    b.extend_from_slice(b",\"nsec\":");
    json::uint(b, t % 1_000_000_000);
    b.push(b'}');
}
