//! The change feed: every change to the world model, every call and its outcome, every
//! stream message, stamped on the server's clock and numbered at the moment it happens
//! (under the lock that makes it happen), for recorders (`runtime/record`, docs/recording.md).
//!
//! - With no feed open, a change costs one relaxed atomic load here.
//! - The stamp, the number and the hand-over to every open feed happen in one step under
//!   the feed's lock, so numbers follow the order of the changes and the stamps never go
//!   back along them (a clock that steps back is held at the last stamp).
//! - A feed's queue is unbounded: a feed never slows or blocks a writer. Dropping the
//!   [`ChangeFeed`] closes it; the next change forgets it. A reader is woken only when a
//!   change lands on its empty queue, and takes the queue whole.
//! - A feed opened with [`DataServer::change_feed_numeric`] also has a numeric lane: a
//!   changed `float`, `int` or `bool` of an existing property comes as a 32-byte [`Numeric`]
//!   (the property by a number the server gives it once, [`ChangeFeed::numbered`]) instead of
//!   a [`Change`]: no value is cloned and nothing is dropped per change, and a recorder copies
//!   entries instead of translating changes. Both lanes share one numbering.

use crate::meta::{ObjectInfo, PropMeta};
use crate::method::CallOutcome;
use crate::server::DataServer;
use mocu_value::{Guid, PropName, Value};
use parking_lot::{Condvar, Mutex};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::UNIX_EPOCH;
use std::time::{Duration, SystemTime};

/// One change, as it happened.
#[derive(Clone, Debug)]
pub enum Change {
    /// An object published under `parent` at position `index`.
    Created {
        object: Guid,
        parent: Guid,
        index: usize,
        info: ObjectInfo,
    },
    /// An object renamed or retyped.
    Renamed {
        object: Guid,
        info: ObjectInfo,
    },
    /// An object moved under another parent (`insert_between`, `delete_and_promote`).
    Moved {
        object: Guid,
        parent: Guid,
        index: usize,
    },
    /// An object and its whole subtree deleted.
    Deleted {
        object: Guid,
    },
    /// A property created (`created`) or changed; `meta` is its metadata, if any, on
    /// creation only (metadata never changes after it; a later write carries `None`, so a
    /// busy writer and the feed's reader share no reference count).
    PropertySet {
        object: Guid,
        name: PropName,
        value: Value,
        meta: Option<Arc<PropMeta>>,
        created: bool,
    },
    PropertyDeleted {
        object: Guid,
        name: PropName,
    },
    /// A method call made (`call` numbers it; its outcome carries the same number).
    Called {
        call: u64,
        object: Guid,
        method: PropName,
        args: Vec<Value>,
    },
    /// A call answered (once).
    Answered {
        call: u64,
        outcome: CallOutcome,
    },
    /// A message sent to a listener's receivers.
    Sent {
        listener: Guid,
        message: Arc<[Value]>,
    },
}

/// A change with its number (counting from 1 across the server) and its time on the
/// server's clock ([`DataServer::wall_time`]).
#[derive(Clone, Debug)]
pub struct Stamped {
    pub seq: u64,
    pub wall: SystemTime,
    pub change: Change,
}

/// What a [`Numeric`] holds.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[repr(u8)]
pub enum NumKind {
    Float,
    Int,
    Bool,
}

/// A changed numeric value in a feed's numeric lane: property `id` ([`ChangeFeed::numbered`])
/// took the value in change number `seq` at `ns` (nanoseconds since the Unix epoch, the
/// server's clock: what a [`Stamped`] would read).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Numeric {
    pub seq: u64,
    pub ns: u64,
    /// The value's bits: an `f64`'s, an `i64`'s, or 0 / 1.
    pub bits: u64,
    pub id: u32,
    pub kind: NumKind,
}

impl Numeric {
    /// The kind and bits of a value the lane carries.
    fn of(v: &Value) -> Option<(NumKind, u64)> {
        match *v {
            Value::Float(x) => Some((NumKind::Float, x.to_bits())),
            Value::Int(i) => Some((NumKind::Int, i as u64)),
            Value::Bool(b) => Some((NumKind::Bool, u64::from(b))),
            _ => None,
        }
    }

    pub fn value(&self) -> Value {
        match self.kind {
            NumKind::Float => Value::Float(f64::from_bits(self.bits)),
            NumKind::Int => Value::Int(self.bits as i64),
            NumKind::Bool => Value::Bool(self.bits != 0),
        }
    }
}

/// An open feed: the changes since it was opened, in order. A reader takes them in batches
/// ([`ChangeFeed::take`], [`ChangeFeed::swap`]) and sleeps in [`ChangeFeed::wait`]: a writer
/// wakes it only when it queues onto an empty queue, so a busy world costs one wake-up per
/// batch, not per change.
pub struct ChangeFeed {
    q: Arc<Queue>,
}

/// A feed's handle on the server's feed state, where its queue is.
struct Queue {
    state: Arc<Mutex<FeedState>>,
    id: u64,
    ready: Arc<Condvar>,
}

/// A feed's queue, kept in the feed state: a change is numbered, stamped and queued under
/// one lock.
struct Open {
    id: u64,
    ready: Arc<Condvar>,
    changes: Vec<Stamped>,
    /// The numeric lane, when the feed has one.
    lane: Option<Vec<Numeric>>,
    /// Listeners whose messages this feed is not fed ([`ChangeFeed::mute`]).
    muted: Vec<Guid>,
    woken: bool,
}

impl Open {
    fn is_empty(&self) -> bool {
        self.changes.is_empty() && self.lane.as_ref().is_none_or(Vec::is_empty)
    }

    fn push(&mut self, s: Stamped) {
        let was_empty = self.is_empty();
        self.changes.push(s);
        if was_empty {
            self.ready.notify_all();
        }
    }

    fn push_numeric(lane: &mut Vec<Numeric>, changes: &[Stamped], ready: &Condvar, n: Numeric) {
        if lane.is_empty() && changes.is_empty() {
            ready.notify_all();
        }
        lane.push(n);
    }
}

/// Wakes a reader waiting in [`ChangeFeed::wait`] (its other inputs have something).
#[derive(Clone)]
pub struct FeedWaker(Arc<Queue>);

impl FeedWaker {
    pub fn wake(&self) {
        self.0.with(|o| o.woken = true);
        self.0.ready.notify_all();
    }
}

impl Queue {
    /// `f` on this feed's queue, under the feed state's lock (`None` once it is closed).
    fn with<R>(&self, f: impl FnOnce(&mut Open) -> R) -> Option<R> {
        let mut st = self.state.lock();
        st.queues.iter_mut().find(|o| o.id == self.id).map(f)
    }
}

impl ChangeFeed {
    /// Every change queued now, taken off the queue.
    pub fn take(&self) -> Vec<Stamped> {
        self.q.with(|o| std::mem::take(&mut o.changes)).unwrap_or_default()
    }

    /// Every change queued now, swapped into `buf` (which should be empty): the queue keeps
    /// `buf`'s capacity, so a reader that hands back its drained buffer each time costs the
    /// writers no reallocation.
    pub fn swap(&self, buf: &mut Vec<Stamped>) {
        self.q.with(|o| std::mem::swap(&mut o.changes, buf));
    }

    /// Every change queued now in both lanes, swapped into `changes` and `numeric` (which
    /// should be empty; see [`ChangeFeed::swap`]). Without a numeric lane, `numeric` stays
    /// empty.
    pub fn swap_both(&self, changes: &mut Vec<Stamped>, numeric: &mut Vec<Numeric>) {
        self.q.with(|o| {
            std::mem::swap(&mut o.changes, changes);
            if let Some(lane) = &mut o.lane {
                std::mem::swap(lane, numeric);
            }
        });
    }

    /// Messages sent on `listener` are no longer fed to this feed (`muted`), or are again.
    /// A reader that drops a listener's messages says so, so that they are not kept alive in
    /// its queue (a camera's decoded frames: the decoder's buffers are freed as without it).
    pub fn mute(&self, listener: Guid, muted: bool) {
        self.q.with(|o| {
            o.muted.retain(|&g| g != listener);
            if muted {
                o.muted.push(listener);
            }
        });
    }

    /// The property numbered `id` in numeric lanes ([`Numeric::id`]): its object and name.
    pub fn numbered(&self, id: u32) -> Option<(Guid, PropName)> {
        let st = self.q.state.lock();
        st.numbered.get((id as usize).checked_sub(1)?).copied()
    }

    /// Every change queued now, without waiting (as [`ChangeFeed::take`]).
    pub fn try_iter(&self) -> impl Iterator<Item = Stamped> {
        self.take().into_iter()
    }

    /// Waits until a change is queued, the feed is woken ([`FeedWaker`]) or `timeout`
    /// passes; returns whether a change is queued.
    pub fn wait(&self, timeout: Duration) -> bool {
        let id = self.q.id;
        let mut st = self.q.state.lock();
        let idle = |st: &FeedState| {
            st.queues.iter().find(|o| o.id == id).is_some_and(|o| o.is_empty() && !o.woken)
        };
        if idle(&st) {
            let _ = self.q.ready.wait_for(&mut st, timeout);
        }
        let Some(o) = st.queues.iter_mut().find(|o| o.id == id) else { return false };
        o.woken = false;
        !o.is_empty()
    }

    /// A handle that wakes [`ChangeFeed::wait`].
    pub fn waker(&self) -> FeedWaker {
        FeedWaker(self.q.clone())
    }

    /// How many changes are queued (in both lanes).
    pub fn len(&self) -> usize {
        self.q.with(|o| o.changes.len() + o.lane.as_ref().map_or(0, Vec::len)).unwrap_or(0)
    }

    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
}

impl Drop for ChangeFeed {
    fn drop(&mut self) {
        let id = self.q.id;
        let mut st = self.q.state.lock();
        if let Some(i) = st.queues.iter().position(|o| o.id == id) {
            let o = st.queues.remove(i);
            st.lanes -= usize::from(o.lane.is_some());
        }
    }
}

#[derive(Default)]
pub(crate) struct Feeds {
    open: AtomicBool,
    state: Arc<Mutex<FeedState>>,
}

#[derive(Default)]
struct FeedState {
    seq: u64,
    calls: u64,
    /// The last stamp (ns since the Unix epoch): stamps never go back along the numbers.
    last: u64,
    next_id: u64,
    queues: Vec<Open>,
    /// How many open feeds have a numeric lane.
    lanes: usize,
    /// Each numbered property (number `i + 1`): numbers are given once per property (a
    /// property deleted and created again gets a new one) and never reused.
    numbered: Vec<(Guid, PropName)>,
}

impl FeedState {
    /// The next number and a stamp for a change that happened at `ns`.
    fn stamp(&mut self, ns: u64) -> (u64, u64) {
        let ns = ns.max(self.last);
        self.last = ns;
        self.seq += 1;
        (self.seq, ns)
    }
}

impl Feeds {
    /// Whether any feed is open (a hint: a feed opened meanwhile misses nothing it could
    /// have seen, since it sees only what happens after `open`).
    pub(crate) fn is_open(&self) -> bool {
        self.open.load(Ordering::Relaxed)
    }

    /// A number for a new call.
    pub(crate) fn next_call(&self) -> u64 {
        let mut st = self.state.lock();
        st.calls += 1;
        st.calls
    }
}

impl DataServer {
    /// Opens a change feed: from now on every change, call, outcome and stream message of
    /// this server is queued on it, stamped and numbered when it happened.
    pub fn change_feed(&self) -> ChangeFeed {
        self.open_feed(false)
    }

    /// A change feed with a numeric lane: a changed `float`, `int` or `bool` of an existing
    /// property comes as a [`Numeric`] ([`ChangeFeed::swap_both`]), everything else as a
    /// [`Change`]; a property's first value (its creation) is always a [`Change`].
    pub fn change_feed_numeric(&self) -> ChangeFeed {
        self.open_feed(true)
    }

    fn open_feed(&self, numeric: bool) -> ChangeFeed {
        let feeds = &self.inner.feeds;
        let ready = Arc::new(Condvar::new());
        let mut st = feeds.state.lock();
        st.next_id += 1;
        let id = st.next_id;
        let lane = numeric.then(Vec::new);
        st.lanes += usize::from(numeric);
        let changes = Vec::new();
        let muted = Vec::new();
        st.queues.push(Open { id, ready: ready.clone(), changes, lane, muted, woken: false });
        feeds.open.store(true, Ordering::Relaxed);
        ChangeFeed { q: Arc::new(Queue { state: feeds.state.clone(), id, ready }) }
    }

    /// Hands a change to every open feed; `change` is built only when one is open. Called
    /// under the lock that makes the change, so the order of numbers is the order of changes.
    pub(crate) fn emit(&self, change: impl FnOnce() -> Change) {
        if self.inner.feeds.is_open() {
            self.emit_at(self.inner.timer.clock().now(), change);
        }
    }

    /// [`DataServer::emit`] for a change that happened at `now` (the clock's instant the
    /// caller read already: the time of day is worked out from it, not read again).
    pub(crate) fn emit_at(&self, now: std::time::Instant, change: impl FnOnce() -> Change) {
        let feeds = &self.inner.feeds;
        if !feeds.is_open() {
            return;
        }
        let mut st = feeds.state.lock();
        if st.queues.is_empty() {
            feeds.open.store(false, Ordering::Relaxed);
            return;
        }
        let (seq, ns) = st.stamp(self.inner.timer.clock().wall_ns_at(now));
        let wall = UNIX_EPOCH + Duration::from_nanos(ns);
        let stamped = Stamped { seq, wall, change: change() };
        // The last feed takes the change itself; others (rare: one recorder is the rule)
        // a copy.
        let (last, others) = st.queues.split_last_mut().expect("not empty: checked above");
        for o in others {
            o.push(stamped.clone());
        }
        last.push(stamped);
    }
}

impl DataServer {
    /// A message sent on `listener`, to every feed that has not muted it (none: not numbered).
    pub(crate) fn emit_sent(&self, listener: Guid, message: &Arc<[Value]>) {
        let feeds = &self.inner.feeds;
        if !feeds.is_open() {
            return;
        }
        let now = self.inner.timer.clock().now();
        let mut st = feeds.state.lock();
        if st.queues.iter().all(|o| o.muted.contains(&listener)) {
            return;
        }
        let (seq, ns) = st.stamp(self.inner.timer.clock().wall_ns_at(now));
        let wall = UNIX_EPOCH + Duration::from_nanos(ns);
        for o in st.queues.iter_mut().filter(|o| !o.muted.contains(&listener)) {
            let change = Change::Sent { listener, message: message.clone() };
            o.push(Stamped { seq, wall, change });
        }
    }

    /// A changed value of an existing property, under the object's lock: to numeric lanes
    /// as a [`Numeric`] (numbering the property in `number` the first time), to other feeds
    /// as a [`Change::PropertySet`]. The rule (a number, every open feed with a lane: a
    /// recorder) is a short path; the rest goes through [`DataServer::emit_value_mixed`].
    pub(crate) fn emit_value(
        &self,
        now: std::time::Instant,
        object: Guid,
        name: PropName,
        number: &mut u32,
        value: &Value,
    ) {
        let feeds = &self.inner.feeds;
        if !feeds.is_open() {
            return;
        }
        let Some((kind, bits)) = Numeric::of(value) else {
            return self.emit_value_mixed(now, object, name, number, value);
        };
        let ns = self.inner.timer.clock().wall_ns_at(now);
        let mut st = feeds.state.lock();
        if st.queues.is_empty() || st.lanes != st.queues.len() || *number == 0 {
            drop(st);
            return self.emit_value_mixed(now, object, name, number, value);
        }
        let (seq, ns) = st.stamp(ns);
        let n = Numeric { seq, ns, bits, id: *number, kind };
        for o in &mut st.queues {
            if let Some(lane) = &mut o.lane {
                Open::push_numeric(lane, &o.changes, &o.ready, n);
            }
        }
    }

    #[cold]
    #[inline(never)]
    fn emit_value_mixed(
        &self,
        now: std::time::Instant,
        object: Guid,
        name: PropName,
        number: &mut u32,
        value: &Value,
    ) {
        let feeds = &self.inner.feeds;
        let numeric = Numeric::of(value);
        let mut st = feeds.state.lock();
        if st.queues.is_empty() {
            feeds.open.store(false, Ordering::Relaxed);
            return;
        }
        let (seq, ns) = st.stamp(self.inner.timer.clock().wall_ns_at(now));
        let mut slow = st.queues.len();
        if let Some((kind, bits)) = numeric
            && st.lanes > 0
        {
            if *number == 0 {
                st.numbered.push((object, name));
                *number = st.numbered.len() as u32;
            }
            let n = Numeric { seq, ns, bits, id: *number, kind };
            for o in &mut st.queues {
                if let Some(lane) = &mut o.lane {
                    Open::push_numeric(lane, &o.changes, &o.ready, n);
                    slow -= 1;
                }
            }
        }
        if slow == 0 {
            return;
        }
        let wall = UNIX_EPOCH + Duration::from_nanos(ns);
        for o in &mut st.queues {
            if numeric.is_none() || o.lane.is_none() {
                let change = Change::PropertySet {
                    object,
                    name,
                    value: value.clone(),
                    meta: None,
                    created: false,
                };
                o.push(Stamped { seq, wall, change });
            }
        }
    }
}
