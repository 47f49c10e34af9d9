//! Records a trial to an MCAP file (`mocu run --record`, docs/recording.md): the
//! DataServer's change feed (objects, properties with units, calls and outcomes, video units
//! as received), each stamped at its source, plus the trial's events (operator actions,
//! alerts, layout loads and diagnostics) handed in by the command line.
//!
//! One thread writes the file; writers never wait for it (the feed's queue is unbounded).
//!
//! Architecture invariant: depends on the DataServer and `mocu-value` only; knows nothing
//! of the layout, the renderer or the modules (they reach it through the DataServer, or
//! through [`Recorder::event`]).

#![forbid(unsafe_code)]

mod cdr;
mod file;
mod json;
mod schemas;
mod translate;
mod values;
mod world;

use crossbeam_channel::{Receiver, Sender};
use mocu_dataserver::{ChangeFeed, DataServer, FeedWaker, Value};
use std::collections::BTreeMap;
use std::path::Path;
use std::sync::Mutex;
use std::thread::JoinHandle;
use std::time::{Duration, Instant, SystemTime, UNIX_EPOCH};

/// The longest a recorded message waits in an open chunk before it is on disk.
pub const FLUSH_EVERY: Duration = Duration::from_secs(1);

/// What the file says about the trial (its `mocu` metadata record and attachment).
#[derive(Clone, Debug, Default)]
pub struct Header {
    /// The command line.
    pub command: String,
    /// The layout, profile or bundle run.
    pub target: String,
    /// The layout shown.
    pub layout: String,
    /// `system` or `manual`.
    pub clock: String,
    /// The checked bundle the run started with (`mocu build`'s format), attached as
    /// `bundle.mocub`.
    pub bundle: Option<Vec<u8>>,
}

/// Where an event goes: `/events` (the trial record) or `/layout` (loads, reloads,
/// diagnostics).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum EventTopic {
    Events,
    Layout,
}

impl EventTopic {
    /// The topic `--log`'s event of this name goes to.
    pub fn of(event: &str) -> EventTopic {
        match event {
            "load" | "reload" | "unload" | "diagnostic" | "instance" => EventTopic::Layout,
            _ => EventTopic::Events,
        }
    }
}

/// What the command line hands the writer thread.
enum Input {
    Event(Event),
    /// Answered once everything recorded before it is handed to the file.
    Sync(Sender<()>),
}

pub(crate) struct Event {
    pub at: SystemTime,
    pub source: String,
    pub event: String,
    pub fields: Vec<(String, Value)>,
}

/// What a finished recording holds.
#[derive(Clone, Copy, Debug, Default)]
pub struct Totals {
    pub messages: u64,
    /// Message bytes before compression.
    pub bytes: u64,
}

/// A recording in progress. Dropping it finishes the file (summary and footer).
pub struct Recorder {
    ds: DataServer,
    events: Mutex<Option<Sender<Input>>>,
    waker: FeedWaker,
    thread: Mutex<Option<JoinHandle<Result<Totals, String>>>>,
}

impl Recorder {
    /// Starts recording `ds` to `path` (created or truncated). Start it before the modules,
    /// so that everything they publish is on the record.
    pub fn start(ds: &DataServer, path: &Path, header: Header) -> Result<Recorder, String> {
        let mut out = file::Out::create(path)?;
        let now = nanos(ds.wall_time());
        let mut meta = BTreeMap::new();
        meta.insert("format".to_string(), "3".to_string());
        meta.insert("command".to_string(), header.command.clone());
        meta.insert("target".to_string(), header.target.clone());
        meta.insert("layout".to_string(), header.layout.clone());
        meta.insert("clock".to_string(), header.clock.clone());
        meta.insert("start_ns".to_string(), now.to_string());
        out.metadata("mocu", meta)?;
        if let Some(b) = &header.bundle {
            out.attach("bundle.mocub", "application/x-mocu-bundle", now, b)?;
        }
        out.flush()?;
        let feed = ds.change_feed_numeric();
        let waker = feed.waker();
        let existing = world::walk(ds);
        let (tx, rx) = crossbeam_channel::unbounded();
        let thread = std::thread::Builder::new()
            .name("mocu-record".into())
            .spawn(move || write_loop(out, feed, rx, now, existing))
            .map_err(|e| e.to_string())?;
        Ok(Recorder {
            ds: ds.clone(),
            events: Mutex::new(Some(tx)),
            waker,
            thread: Mutex::new(Some(thread)),
        })
    }

    /// Records an event now (on the DataServer's clock): `source` is `layout` or a module's
    /// name; `event` and `fields` as `--log` writes them.
    pub fn event(&self, source: &str, event: &str, fields: &[(&str, Value)]) {
        self.event_at(self.ds.wall_time(), source, event, fields);
    }

    /// Records an event stamped `at` (when it happened at its source).
    pub fn event_at(&self, at: SystemTime, source: &str, event: &str, fields: &[(&str, Value)]) {
        let fields = fields.iter().map(|(k, v)| (k.to_string(), v.clone())).collect();
        let e = Event { at, source: source.into(), event: event.into(), fields };
        if let Some(tx) = &*lock(&self.events) {
            let _ = tx.send(Input::Event(e));
            self.waker.wake();
        }
    }

    /// Returns once every change and event recorded before the call is handed to the file
    /// (in the writer's buffers; on disk at the next flush). For benchmarks and tests.
    pub fn sync(&self) {
        let (tx, rx) = crossbeam_channel::bounded(1);
        let sent = lock(&self.events).as_ref().is_some_and(|e| e.send(Input::Sync(tx)).is_ok());
        if sent {
            self.waker.wake();
            let _ = rx.recv();
        }
    }

    /// Writes what is queued, the summary and the footer; returns what the file holds.
    /// Later changes and events are not recorded; a second call returns empty totals.
    pub fn finish(&self) -> Result<Totals, String> {
        lock(&self.events).take();
        self.waker.wake();
        let thread = lock(&self.thread).take();
        match thread {
            Some(t) => t.join().map_err(|_| "the recorder panicked".to_string())?,
            None => Ok(Totals::default()),
        }
    }
}

fn lock<T>(m: &Mutex<T>) -> std::sync::MutexGuard<'_, T> {
    m.lock().unwrap_or_else(|e| e.into_inner())
}

impl Drop for Recorder {
    fn drop(&mut self) {
        if let Err(e) = self.finish() {
            eprintln!("mocu: recording: {e}");
        }
    }
}

/// Nanoseconds since the Unix epoch (0 before it; saturating in the year 2554). Once per
/// change: seconds and nanoseconds, not a 128-bit product.
pub(crate) fn nanos(t: SystemTime) -> u64 {
    t.duration_since(UNIX_EPOCH).map_or(0, |d| {
        d.as_secs().saturating_mul(1_000_000_000).saturating_add(u64::from(d.subsec_nanos()))
    })
}

/// How long the writer lets changes gather after it is woken, so that a busy world is
/// written in batches (one wake-up per batch, not per change; ten a second when busy).
const GATHER: Duration = Duration::from_millis(20);

/// The feed's buffers and the writer's, which trade places at each take: neither side
/// reallocates.
#[derive(Default)]
struct Taken {
    changes: Vec<mocu_dataserver::Stamped>,
    numeric: Vec<mocu_dataserver::Numeric>,
}

impl Taken {
    /// Writes every change queued now.
    fn write(&mut self, t: &mut translate::Translator, feed: &ChangeFeed) -> Result<(), String> {
        feed.swap_both(&mut self.changes, &mut self.numeric);
        let r = t.take(&self.changes, &self.numeric, feed);
        self.changes.clear();
        self.numeric.clear();
        r
    }
}

/// The writer thread: changes in batches and events as they come, a flush at most
/// [`FLUSH_EVERY`] after the first unflushed message; ends (finishing the file) when the
/// recorder is finished or dropped. An idle recording sleeps.
fn write_loop(
    out: file::Out,
    feed: ChangeFeed,
    events: Receiver<Input>,
    start: u64,
    existing: Vec<world::Existing>,
) -> Result<Totals, String> {
    let mut t = translate::Translator::new(out, start, existing)?;
    let mut dirty_since: Option<Instant> = None;
    let mut taken = Taken::default();
    loop {
        // Asleep until something comes, or until the open chunk is due on disk.
        let wait = dirty_since.map_or(Duration::from_secs(3600), |d| {
            (d + FLUSH_EVERY).saturating_duration_since(Instant::now())
        });
        if feed.wait(wait) {
            std::thread::sleep(GATHER);
        }
        let before = t.written();
        taken.write(&mut t, &feed)?;
        t.write_values()?;
        let mut open = true;
        loop {
            match events.try_recv() {
                Ok(Input::Event(e)) => t.event(e)?,
                Ok(Input::Sync(done)) => {
                    // Everything recorded before the sync is handed to the file.
                    taken.write(&mut t, &feed)?;
                    t.write_values()?;
                    let _ = done.send(());
                }
                Err(crossbeam_channel::TryRecvError::Empty) => break,
                Err(crossbeam_channel::TryRecvError::Disconnected) => {
                    open = false;
                    break;
                }
            }
        }
        if !open {
            break;
        }
        if t.written() > before && dirty_since.is_none() {
            dirty_since = Some(Instant::now());
        }
        if dirty_since.is_some_and(|d| d.elapsed() >= FLUSH_EVERY) {
            t.flush()?;
            dirty_since = None;
        }
    }
    taken.write(&mut t, &feed)?;
    t.finish()
}
