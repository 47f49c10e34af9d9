//! The timeline: a fresh DataServer on a manual clock, moved by the replay. Trial time is
//! the recording's `log_time`; the clock's wall time reads it (what a layout shows as the
//! time of day), and its monotonic time only ever moves forward (timers stay ordered, even
//! across a seek back).

use crate::file::{RawMessage, Recording, ReplayError};
use crate::message::{Frame, ObjectChange, PropertyChange, Snapshot, Unit, values};
use crate::topics::{
    CAMERA_PREFIX, IMAGE_PREFIX, OBJECT, PROPERTY, SNAPSHOT, VALUES, VIDEO_PREFIX,
};
use crate::world::World;
use mocu_dataserver::{Clock, DataServer, Guid, ManualClock, Value};
use std::collections::{HashMap, HashSet, VecDeque};
use std::path::Path;
use std::sync::Arc;
use std::time::{Duration, Instant, UNIX_EPOCH};

/// How much of the recording is read ahead while playing (one indexed read each).
const READ_AHEAD: u64 = 1_000_000_000;

pub struct Player {
    rec: Recording,
    ds: DataServer,
    clock: ManualClock,
    world: World,
    /// Log time applied up to (inclusive).
    cursor: u64,
    /// Changes after `cursor`, in (log time, sequence) order: every message up to
    /// `loaded_to` (inclusive) and every entry of their batches (some of which may be later).
    ahead: VecDeque<Item>,
    loaded_to: u64,
    /// The clock's instant that stands for log time `anchor.1` (moved at each seek).
    anchor: (Instant, u64),
    /// The topics played: the world's, then each camera's (`/camera/…`).
    topics: Vec<Arc<str>>,
    /// Frames sent per camera path (the frame number of the next).
    frames: HashMap<String, i64>,
    /// Attaches a decoder to a network camera (its listener, its `encoded` listener) the
    /// first time a unit of it is played; the replay's decoders live in the caller.
    decoder: Option<DecoderHook>,
    decoded: HashSet<Guid>,
}

/// What attaches a decoder to a camera: `(server, camera, encoded)`.
pub type DecoderHook = Box<dyn FnMut(&DataServer, Guid, Guid) + Send>;

/// How far back a seek looks for the key unit a network camera's picture starts from.
const KEY_LOOKBACK: u64 = 10_000_000_000;

fn is_unit_topic(t: &str) -> bool {
    t.starts_with(VIDEO_PREFIX) || t.starts_with(IMAGE_PREFIX)
}

impl Player {
    /// Opens a recording and a fresh DataServer on a clock standing at its start.
    pub fn open(path: &Path) -> Result<Player, ReplayError> {
        let rec = Recording::open(path)?;
        let clock = ManualClock::new();
        let ds = DataServer::with_clock(Default::default(), Arc::new(clock.clone()));
        let start = rec.meta().start_ns.unwrap_or(rec.span().0).min(rec.span().0);
        let before = start.saturating_sub(1);
        clock.set_wall(UNIX_EPOCH + Duration::from_nanos(before));
        let world = World::new(&ds);
        let mut topics: Vec<Arc<str>> = [OBJECT, PROPERTY, VALUES].map(Arc::from).to_vec();
        topics.extend(rec.topics_starting(CAMERA_PREFIX));
        topics.extend(rec.topics_starting(VIDEO_PREFIX));
        topics.extend(rec.topics_starting(IMAGE_PREFIX));
        Ok(Player {
            topics,
            frames: HashMap::new(),
            decoder: None,
            decoded: HashSet::new(),
            rec,
            world,
            cursor: before,
            ahead: VecDeque::new(),
            loaded_to: before,
            anchor: (clock.now(), before),
            ds,
            clock,
        })
    }

    pub fn ds(&self) -> &DataServer {
        &self.ds
    }

    pub fn clock(&self) -> &ManualClock {
        &self.clock
    }

    pub fn recording(&self) -> &Recording {
        &self.rec
    }

    /// The screen the trial was shown on: `root.display`'s `width` and `height` as first
    /// recorded (in the first ten seconds).
    pub fn recorded_screen(&mut self) -> Option<(u32, u32)> {
        let from = self.rec.span().0;
        let msgs =
            self.rec.messages(from, from.saturating_add(10_000_000_000), &[PROPERTY]).ok()?;
        let side = |name: &str| {
            msgs.iter().find_map(|m| {
                let j: serde_json::Value = serde_json::from_slice(&m.data).ok()?;
                (j.get("path")?.as_str()?.strip_prefix("root.display.") == Some(name))
                    .then(|| j.get("value")?.as_f64())
                    .flatten()
            })
        };
        let (w, h) = (side("width")?, side("height")?);
        (w >= 1.0 && h >= 1.0 && w <= 16384.0 && h <= 16384.0).then_some((w as u32, h as u32))
    }

    /// Trial time zero (log time, ns): when recording started.
    pub fn start_ns(&self) -> u64 {
        self.rec.meta().start_ns.unwrap_or(self.rec.span().0).min(self.rec.span().0)
    }

    /// The last message's log time.
    pub fn end_ns(&self) -> u64 {
        self.rec.span().1
    }

    /// The log time replayed up to.
    pub fn now_ns(&self) -> u64 {
        self.cursor
    }

    /// Seconds since the start of the trial, of the replay's position.
    pub fn trial_secs(&self) -> f64 {
        self.cursor.saturating_sub(self.start_ns()) as f64 / 1e9
    }

    /// The log time `secs` into the trial.
    pub fn at_secs(&self, secs: f64) -> u64 {
        self.start_ns().saturating_add((secs.max(0.0) * 1e9).round() as u64)
    }

    /// Jumps to log time `to`: the world as the last keyframe at or before it says, then
    /// the changes after the keyframe up to `to`, applied at once; the clock's wall time
    /// reads `to`. Forward jumps of under a second play instead.
    pub fn seek(&mut self, to: u64) -> Result<(), ReplayError> {
        if to >= self.cursor && to - self.cursor < READ_AHEAD {
            return self.advance_to(to);
        }
        self.ds.quiesce();
        let key = self.rec.last_at_or_before(SNAPSHOT, to)?;
        let snapshot = key.as_ref().and_then(|m| Snapshot::parse(&m.data)).unwrap_or_default();
        self.world.sync(&snapshot);
        let from = key.as_ref().map_or(0, |k| k.log_time);
        let after = |m: &RawMessage| match &key {
            None => true,
            Some(k) => m.log_time > k.log_time || (m.sequence.wrapping_sub(k.sequence) as i32) > 0,
        };
        let msgs = self.rec.messages(from, to, &[OBJECT, PROPERTY, VALUES])?;
        let mut items = Vec::with_capacity(msgs.len());
        for m in msgs {
            if &*m.topic == VALUES {
                // Entries after the keyframe (its `seq`), whatever their batch's time.
                let seq = snapshot.seq;
                let entries = values(&m.data).unwrap_or_default();
                items.extend(entries.into_iter().filter(|e| key.is_none() || e.seq > seq).map(
                    |e| Item::Value {
                        time: e.log_time,
                        seq: e.seq as u32,
                        id: e.id,
                        value: e.value,
                    },
                ));
            } else if after(&m) {
                items.push(Item::Message(m));
            }
        }
        items.sort_by_key(Item::key);
        // Entries of the batches read that come after `to` are played from there.
        let split = items.partition_point(|i| i.key().0 <= to);
        let later = items.split_off(split);
        for c in coalesce(items) {
            match c {
                Change::Object(c) => self.world.apply_object(&c),
                Change::Property(c) => self.world.apply_property(&c),
                Change::Value(id, v) => self.world.apply_value(id, &v),
            }
        }
        self.cursor = to;
        self.ahead = later.into();
        self.loaded_to = to;
        self.anchor = (self.clock.now(), to);
        self.clock.set_wall(UNIX_EPOCH + Duration::from_nanos(to));
        self.ds.advance_settled(&self.clock, self.clock.now());
        self.show_last_frames(to)?;
        Ok(())
    }

    /// Decodes network cameras' units (`/video/…`, `/image/…`) with what `hook` attaches;
    /// without one they are not played (their windows stay empty).
    pub fn set_decoder(&mut self, hook: DecoderHook) {
        self.decoder = Some(hook);
    }

    /// After a seek: each camera's last frame of the second before `to`, as its window
    /// showed it then; a network camera's picture decoded again from the last key unit
    /// before `to` (within 10 s) up to `to`.
    fn show_last_frames(&mut self, to: u64) -> Result<(), ReplayError> {
        let cameras: Vec<Arc<str>> =
            self.topics.iter().filter(|t| t.starts_with(CAMERA_PREFIX)).cloned().collect();
        for topic in cameras {
            if let Some(m) = self.rec.last_at_or_before(&topic, to)?
                && m.log_time.saturating_add(READ_AHEAD) > to
            {
                self.send_frame(&m.data);
            }
        }
        let units: Vec<Arc<str>> = match self.decoder {
            Some(_) => self.topics.iter().filter(|t| is_unit_topic(t)).cloned().collect(),
            None => Vec::new(),
        };
        for topic in &units {
            let from = to.saturating_sub(KEY_LOOKBACK);
            let msgs = self.rec.messages(from, to, &[&**topic])?;
            let parsed: Vec<Unit> = msgs.iter().filter_map(|m| Unit::parse(&m.data)).collect();
            if let Some(key) = parsed.iter().rposition(Unit::is_key) {
                for u in &parsed[key..] {
                    self.send_unit(u);
                }
            }
        }
        self.ds.quiesce();
        Ok(())
    }

    /// Sends a recorded unit on its camera's `encoded` listener, as the receiver sent it,
    /// a decoder attached to the camera first.
    fn send_unit(&mut self, u: &Unit) {
        let Some(hook) = self.decoder.as_mut() else { return };
        let path: Vec<&str> = u.camera.split('.').skip(1).collect();
        let Some(camera) = self.ds.resolve(&path) else { return };
        let Some(encoded) = self.ds.find_child(camera, "encoded").ok().flatten() else { return };
        if self.decoded.insert(camera) {
            hook(&self.ds, camera, encoded);
        }
        let msg = vec![
            Value::Bytes(u.data.clone().into()),
            Value::str(&u.format),
            Value::Int(u.unit),
            Value::Int(u.arrival_us),
        ];
        let _ = self.ds.send(encoded, msg);
    }

    /// Sends a recorded frame on its camera's listener: `[pixels, width, height, frame]`,
    /// as the camera sent it.
    fn send_frame(&mut self, data: &[u8]) {
        let Some(f) = Frame::parse(data) else { return };
        let path: Vec<&str> = f.camera.split('.').skip(1).collect();
        let Some(camera) = self.ds.resolve(&path) else { return };
        let n = self.frames.entry(f.camera.clone()).or_insert(0);
        *n += 1;
        let msg = vec![
            Value::Bytes(f.pixels.into()),
            Value::Int(i64::from(f.width)),
            Value::Int(i64::from(f.height)),
            Value::Int(*n),
        ];
        let _ = self.ds.send(camera, msg);
    }

    /// Plays forward to log time `to`: each change at its recorded time, the timers due
    /// between two changes fired in order first (`DataServer::advance_settled`).
    pub fn advance_to(&mut self, to: u64) -> Result<(), ReplayError> {
        if to <= self.cursor {
            return Ok(());
        }
        // How far each read reaches: doubled after a read that found nothing, so that a
        // long gap (or a chunk whose stated times span one) takes a few reads, not one a
        // second.
        let mut reach = READ_AHEAD;
        loop {
            // What is ahead up to `loaded_to` is complete: a message read later has a later
            // log time than that, and so have its entries.
            let ready = |i: &Item| i.key().0 <= self.loaded_to;
            if self.loaded_to < to && !self.ahead.front().is_some_and(ready) {
                // Nothing lies before the next message: a gap is skipped, not read a
                // second at a time.
                let next = self.rec.next_after(self.loaded_to);
                self.loaded_to = self.loaded_to.max(next.saturating_sub(1));
                let hi = self.loaded_to.saturating_add(reach);
                let topics: Vec<&str> = self.topics.iter().map(|t| &**t).collect();
                let msgs = self.rec.messages(self.loaded_to.saturating_add(1), hi, &topics)?;
                reach = if msgs.is_empty() { reach.saturating_mul(2) } else { READ_AHEAD };
                let mut items: Vec<Item> = self.ahead.drain(..).collect();
                items.extend(expand(msgs));
                items.sort_by_key(Item::key);
                self.ahead = items.into();
                // Past the last message there is nothing more to read.
                self.loaded_to = if hi >= self.end_ns() { u64::MAX } else { hi };
                continue;
            }
            match self.ahead.front() {
                Some(i) if i.key().0 <= to && ready(i) => {
                    let i = self.ahead.pop_front().expect("looked at above");
                    let t = i.key().0;
                    self.move_clock(t);
                    self.apply(i);
                    self.cursor = self.cursor.max(t);
                }
                _ => {
                    self.move_clock(to);
                    self.cursor = to;
                    break;
                }
            }
        }
        self.ds.quiesce();
        Ok(())
    }

    /// Plays forward by `d` of trial time.
    pub fn step(&mut self, d: Duration) -> Result<(), ReplayError> {
        self.advance_to(self.cursor.saturating_add(d.as_nanos() as u64))
    }

    /// Moves the clock to log time `t`: settled when a timer falls due on the way, else
    /// straight there (nothing to fire).
    fn move_clock(&mut self, t: u64) {
        let target = self.anchor.0 + Duration::from_nanos(t.saturating_sub(self.anchor.1));
        if self.ds.next_deadline().is_some_and(|d| d <= target) {
            self.ds.advance_settled(&self.clock, target);
        } else {
            let now = self.clock.now();
            self.clock.advance(target.saturating_duration_since(now));
        }
    }

    fn apply(&mut self, i: Item) {
        let m = match i {
            Item::Value { id, value, .. } => return self.world.apply_value(id, &value),
            Item::Message(m) => m,
        };
        match &*m.topic {
            OBJECT => {
                if let Some(c) = ObjectChange::parse(&m.data) {
                    self.world.apply_object(&c);
                }
            }
            PROPERTY => {
                if let Some(c) = PropertyChange::parse(&m.data) {
                    self.world.apply_property(&c);
                }
            }
            t if t.starts_with(CAMERA_PREFIX) => self.send_frame(&m.data),
            t if is_unit_topic(t) => {
                if let Some(u) = Unit::parse(&m.data) {
                    self.send_unit(&u);
                }
            }
            _ => {}
        }
    }
}

/// A change to play: a message, or one entry of a `/world/values` batch.
enum Item {
    Message(RawMessage),
    Value { time: u64, seq: u32, id: u32, value: Value },
}

impl Item {
    /// (log time, sequence): the order changes happened in.
    fn key(&self) -> (u64, u32) {
        match self {
            Item::Message(m) => (m.log_time, m.sequence),
            Item::Value { time, seq, .. } => (*time, *seq),
        }
    }
}

/// Messages as items, each batch as its entries.
fn expand(msgs: Vec<RawMessage>) -> Vec<Item> {
    let mut out = Vec::with_capacity(msgs.len());
    for m in msgs {
        if &*m.topic == VALUES {
            let entries = values(&m.data).unwrap_or_default();
            out.extend(entries.into_iter().map(|e| Item::Value {
                time: e.log_time,
                seq: e.seq as u32,
                id: e.id,
                value: e.value,
            }));
        } else {
            out.push(Item::Message(m));
        }
    }
    out
}

/// A parsed change.
enum Change {
    Object(ObjectChange),
    Property(PropertyChange),
    Value(u32, Value),
}

/// The changes of a seek, with the writes of one property between two changes of the world's
/// shape folded into the last of them: a seek lands on the same world, and the server (and
/// everyone subscribed to it) sees one write per property instead of every step between.
fn coalesce(items: Vec<Item>) -> Vec<Change> {
    let mut out: Vec<Change> = Vec::with_capacity(items.len().min(1 << 16));
    let mut last: HashMap<(u64, String), usize> = HashMap::new();
    let mut last_value: HashMap<u32, usize> = HashMap::new();
    for i in items {
        let m = match i {
            Item::Value { id, value, .. } => {
                fold(&mut out, &mut last_value, id, Change::Value(id, value));
                continue;
            }
            Item::Message(m) => m,
        };
        match &*m.topic {
            OBJECT => {
                if let Some(c) = ObjectChange::parse(&m.data) {
                    last.clear();
                    last_value.clear();
                    out.push(Change::Object(c));
                }
            }
            PROPERTY => match PropertyChange::parse(&m.data) {
                Some(c @ PropertyChange::Set { id: Some(id), .. }) => {
                    fold(&mut out, &mut last_value, id, Change::Property(c));
                }
                Some(PropertyChange::Set { id: None, object, name, value }) => {
                    let key = (object, name);
                    match last.get(&key) {
                        Some(&i) => {
                            out[i] = Change::Property(PropertyChange::Set {
                                id: None,
                                object,
                                name: key.1,
                                value,
                            })
                        }
                        None => {
                            out.push(Change::Property(PropertyChange::Set {
                                id: None,
                                object,
                                name: key.1.clone(),
                                value,
                            }));
                            last.insert(key, out.len() - 1);
                        }
                    }
                }
                Some(c) => {
                    last.clear();
                    last_value.clear();
                    out.push(Change::Property(c));
                }
                None => {}
            },
            _ => {}
        }
    }
    out
}

/// `c`, the latest write of property `id`, in the place of its earlier one if any (a
/// `/world/property` write keeps its form: it may be what declares the id).
fn fold(out: &mut Vec<Change>, last: &mut HashMap<u32, usize>, id: u32, c: Change) {
    match last.get(&id) {
        Some(&i) => {
            out[i] = match (&out[i], c) {
                (
                    Change::Property(PropertyChange::Set { id, object, name, .. }),
                    Change::Value(_, v),
                ) => Change::Property(PropertyChange::Set {
                    id: *id,
                    object: *object,
                    name: name.clone(),
                    value: v,
                }),
                (_, c) => c,
            }
        }
        None => {
            out.push(c);
            last.insert(id, out.len() - 1);
        }
    }
}
