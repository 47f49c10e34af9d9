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
    /// A property created (`created`) or changed; `meta` is its metadata, if any.
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
/// ([`ChangeFeed::take`]) and sleeps in [`ChangeFeed::wait`]: a writer wakes it only when it
/// queues onto an empty queue, so a busy world costs one wake-up per batch, not per change.
pub struct ChangeFeed {
    q: Arc<Queue>,
}

struct Queue {
    buf: Mutex<Pending>,
    ready: Condvar,
    closed: AtomicBool,
}

#[derive(Default)]
struct Pending {
    changes: Vec<Stamped>,
    woken: bool,
}

/// Wakes a reader waiting in [`ChangeFeed::wait`] (its other inputs have something).
#[derive(Clone)]
pub struct FeedWaker(Arc<Queue>);

impl FeedWaker {
    pub fn wake(&self) {
        self.0.buf.lock().woken = true;
        self.0.ready.notify_all();
    }
}

impl ChangeFeed {
    /// Every change queued now, taken off the queue.
    pub fn take(&self) -> Vec<Stamped> {
        std::mem::take(&mut self.q.buf.lock().changes)
    }

    /// Every change queued now, without waiting (as [`ChangeFeed::take`]).
    pub fn try_iter(&self) -> impl Iterator<Item = Stamped> {
        self.take().into_iter()
    }

    /// Waits until a change is queued, the feed is woken ([`FeedWaker`]) or `timeout`
    /// passes; returns whether a change is queued.
    pub fn wait(&self, timeout: Duration) -> bool {
        let mut p = self.q.buf.lock();
        if p.changes.is_empty() && !p.woken {
            let _ = self.q.ready.wait_for(&mut p, timeout);
        }
        p.woken = false;
        !p.changes.is_empty()
    }

    /// A handle that wakes [`ChangeFeed::wait`].
    pub fn waker(&self) -> FeedWaker {
        FeedWaker(self.q.clone())
    }

    /// How many changes are queued.
    pub fn len(&self) -> usize {
        self.q.buf.lock().changes.len()
    }

    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
}

impl Drop for ChangeFeed {
    fn drop(&mut self) {
        self.q.closed.store(true, Ordering::Relaxed);
    }
}

#[derive(Default)]
pub(crate) struct Feeds {
    open: AtomicBool,
    state: Mutex<FeedState>,
}

#[derive(Default)]
struct FeedState {
    seq: u64,
    calls: u64,
    last: Option<SystemTime>,
    queues: Vec<Arc<Queue>>,
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
        let q = Arc::new(Queue {
            buf: Mutex::new(Pending::default()),
            ready: Condvar::new(),
            closed: AtomicBool::new(false),
        });
        let feeds = &self.inner.feeds;
        let mut st = feeds.state.lock();
        st.queues.push(q.clone());
        feeds.open.store(true, Ordering::Relaxed);
        ChangeFeed { q }
    }

    /// Hands a change to every open feed; `change` is built only when one is open. Called
    /// under the lock that makes the change, so the order of numbers is the order of changes.
    pub(crate) fn emit(&self, change: impl FnOnce() -> Change) {
        let feeds = &self.inner.feeds;
        if !feeds.is_open() {
            return;
        }
        let mut st = feeds.state.lock();
        st.queues.retain(|q| !q.closed.load(Ordering::Relaxed));
        if st.queues.is_empty() {
            feeds.open.store(false, Ordering::Relaxed);
            return;
        }
        let now = self.wall_time();
        let wall = match st.last {
            Some(last) if last > now => last,
            _ => now,
        };
        st.last = Some(wall);
        st.seq += 1;
        let stamped = Stamped { seq: st.seq, wall, change: change() };
        for q in &st.queues {
            let mut p = q.buf.lock();
            let was_empty = p.changes.is_empty();
            p.changes.push(stamped.clone());
            drop(p);
            if was_empty {
                q.ready.notify_all();
            }
        }
    }
}
