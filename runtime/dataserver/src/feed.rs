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

use crate::meta::{ObjectInfo, PropMeta};
use crate::method::CallOutcome;
use crate::server::DataServer;
use mocu_value::{Guid, PropName, Value};
use parking_lot::{Condvar, Mutex};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
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
    woken: bool,
}

impl Open {
    fn push(&mut self, s: Stamped) {
        let was_empty = self.changes.is_empty();
        self.changes.push(s);
        if was_empty {
            self.ready.notify_all();
        }
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
            st.queues.iter().find(|o| o.id == id).is_some_and(|o| o.changes.is_empty() && !o.woken)
        };
        if idle(&st) {
            let _ = self.q.ready.wait_for(&mut st, timeout);
        }
        let Some(o) = st.queues.iter_mut().find(|o| o.id == id) else { return false };
        o.woken = false;
        !o.changes.is_empty()
    }

    /// A handle that wakes [`ChangeFeed::wait`].
    pub fn waker(&self) -> FeedWaker {
        FeedWaker(self.q.clone())
    }

    /// How many changes are queued.
    pub fn len(&self) -> usize {
        self.q.with(|o| o.changes.len()).unwrap_or(0)
    }

    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
}

impl Drop for ChangeFeed {
    fn drop(&mut self) {
        let id = self.q.id;
        self.q.state.lock().queues.retain(|o| o.id != id);
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
    last: Option<SystemTime>,
    next_id: u64,
    queues: Vec<Open>,
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
        let feeds = &self.inner.feeds;
        let ready = Arc::new(Condvar::new());
        let mut st = feeds.state.lock();
        st.next_id += 1;
        let id = st.next_id;
        st.queues.push(Open { id, ready: ready.clone(), changes: Vec::new(), woken: false });
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
        let now = self.inner.timer.clock().wall_at(now);
        let wall = match st.last {
            Some(last) if last > now => last,
            _ => now,
        };
        st.last = Some(wall);
        st.seq += 1;
        let stamped = Stamped { seq: st.seq, wall, change: change() };
        // The last feed takes the change itself; others (rare: one recorder is the rule)
        // a copy.
        let (last, others) = st.queues.split_last_mut().expect("not empty: checked above");
        for o in others {
            o.push(stamped.clone());
        }
        last.push(stamped);
    }
}
