//! The change feed: every change to the world model, every call and its outcome, every
//! stream message, stamped on the server's clock and numbered at the moment it happens
//! (under the lock that makes it happen), for recorders (`runtime/record`, docs/recording.md).
//!
//! - With no feed open, a change costs one relaxed atomic load here.
//! - The stamp, the number and the hand-over to every open feed happen in one step under
//!   the feed's lock, so numbers follow the order of the changes and the stamps never go
//!   back along them (a clock that steps back is held at the last stamp).
//! - A feed's queue is unbounded: a feed never slows or blocks a writer. Dropping the
//!   [`ChangeFeed`] closes it; the next change forgets it.

use crate::meta::{ObjectInfo, PropMeta};
use crate::method::CallOutcome;
use crate::server::DataServer;
use mocu_value::{Guid, PropName, Value};
use parking_lot::Mutex;
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

/// An open feed: the changes since it was opened, in order.
pub struct ChangeFeed {
    rx: crossbeam_channel::Receiver<Stamped>,
}

impl ChangeFeed {
    /// The next change; waits at most `timeout` (`None` when nothing came or the server is
    /// gone).
    pub fn next_timeout(&self, timeout: Duration) -> Option<Stamped> {
        self.rx.recv_timeout(timeout).ok()
    }

    /// Every change queued now, without waiting.
    pub fn try_iter(&self) -> impl Iterator<Item = Stamped> + '_ {
        self.rx.try_iter()
    }

    /// The queue itself, to wait on it beside other channels (`crossbeam_channel::select!`).
    pub fn receiver(&self) -> &crossbeam_channel::Receiver<Stamped> {
        &self.rx
    }

    /// How many changes are queued.
    pub fn len(&self) -> usize {
        self.rx.len()
    }

    pub fn is_empty(&self) -> bool {
        self.rx.is_empty()
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
    senders: Vec<crossbeam_channel::Sender<Stamped>>,
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
        let (tx, rx) = crossbeam_channel::unbounded();
        let feeds = &self.inner.feeds;
        let mut st = feeds.state.lock();
        st.senders.push(tx);
        feeds.open.store(true, Ordering::Relaxed);
        ChangeFeed { rx }
    }

    /// Hands a change to every open feed; `change` is built only when one is open. Called
    /// under the lock that makes the change, so the order of numbers is the order of changes.
    pub(crate) fn emit(&self, change: impl FnOnce() -> Change) {
        let feeds = &self.inner.feeds;
        if !feeds.is_open() {
            return;
        }
        let mut st = feeds.state.lock();
        if st.senders.is_empty() {
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
        st.senders.retain(|tx| tx.send(stamped.clone()).is_ok());
        if st.senders.is_empty() {
            feeds.open.store(false, Ordering::Relaxed);
        }
    }
}
