//! One subscription: its pending changes (coalesced, in order), its callback, and the
//! rules that make delivery safe: one batch at a time, nothing after `Deleted`, nothing
//! after `unsubscribe` returns.

use crate::executor::{Stats, Target};
use crate::notification::{CoalesceKey, Kind, Notification, Subject};
use mocu_value::{Guid, PropName};
use parking_lot::{Condvar, Mutex};
use std::collections::{HashMap, VecDeque};
use std::panic::{AssertUnwindSafe, catch_unwind};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::thread::ThreadId;

/// Identifies a subscription for `unsubscribe`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct SubscriptionId(pub(crate) u64);

/// What a subscription watches.
#[derive(Clone, Debug, PartialEq)]
pub enum Topic {
    /// The properties of an object: all of them (`names: None`) or only those named.
    Properties { object: Guid, names: Option<Vec<PropName>> },
    /// The children of an object.
    Children { object: Guid },
}

impl Topic {
    pub fn properties(object: Guid) -> Topic {
        Topic::Properties { object, names: None }
    }

    pub fn property_names(object: Guid, names: &[&str]) -> Topic {
        Topic::Properties { object, names: Some(names.iter().map(|n| PropName::new(n)).collect()) }
    }

    pub fn children(object: Guid) -> Topic {
        Topic::Children { object }
    }

    pub fn object(&self) -> Guid {
        match self {
            Topic::Properties { object, .. } | Topic::Children { object } => *object,
        }
    }
}

pub(crate) type Callback = Box<dyn FnMut(&Notification) + Send + 'static>;

pub(crate) struct Sub {
    pub(crate) id: SubscriptionId,
    /// Property names this subscription wants; `None` for all (property subscriptions).
    pub(crate) names: Option<Box<[PropName]>>,
    active: AtomicBool,
    target: Target,
    queue: Mutex<Pending>,
    idle: Condvar,
    callback: Mutex<Callback>,
    stats: Arc<Stats>,
    /// Runs once the object's `Deleted` has been delivered: the subscription leaves the
    /// registry only then, so `unsubscribe` can still stop the notifications before it.
    on_end: Mutex<Option<Box<dyn FnOnce() + Send>>>,
}

#[derive(Default)]
struct Pending {
    items: VecDeque<Option<Notification>>,
    /// Absolute sequence number of `items[0]`.
    head: u64,
    /// Where the latest coalescable notification of each key sits (absolute sequence).
    index: HashMap<CoalesceKey, u64, crate::hash::BuildIdHasher>,
    scheduled: bool,
    running_on: Option<ThreadId>,
}

impl Pending {
    fn push(&mut self, n: Notification) {
        if n.kind == Kind::Changed
            && let Some(key) = n.coalesce_key()
            && let Some(&seq) = self.index.get(&key)
            && !self.is_pending_child_new(key, seq)
        {
            // Coalesce: the earlier undelivered entry goes, the latest value moves to the
            // back (after every change that happened before it), keeping its New-ness.
            let slot = &mut self.items[(seq - self.head) as usize];
            let kind = slot.as_ref().map_or(Kind::Changed, |old| old.kind);
            *slot = None;
            let seq = self.head + self.items.len() as u64;
            self.items.push_back(Some(Notification { kind, ..n }));
            self.index.insert(key, seq);
            return;
        }
        let seq = self.head + self.items.len() as u64;
        match n.coalesce_key() {
            Some(key) => {
                self.index.insert(key, seq);
            }
            None => {
                // A Deleted ends coalescing for that key: a later New must not merge into
                // anything before it.
                if let Subject::Property { name, .. } = n.subject {
                    self.index.remove(&CoalesceKey::Property(name));
                }
                if let Subject::Child { guid, .. } = n.subject {
                    self.index.remove(&CoalesceKey::Child(guid));
                }
            }
        }
        self.items.push_back(Some(n));
    }

    /// A child's undelivered New must stay where it is: the positions in the child
    /// notifications queued after it count that child, so moving it to the back would
    /// make them wrong. A rename behind it is queued as a Changed of its own.
    fn is_pending_child_new(&self, key: CoalesceKey, seq: u64) -> bool {
        matches!(key, CoalesceKey::Child(_))
            && self.items[(seq - self.head) as usize].as_ref().is_some_and(|n| n.kind == Kind::New)
    }

    /// Takes everything pending, in order (coalesced-away slots are `None`), leaving the
    /// queue empty. The buffer moves out instead of being copied into a new one (and comes
    /// back through `recycle`), so a delivery allocates nothing; a coalescing index grown
    /// by a burst is dropped, so an idle subscription does not keep a burst's memory.
    fn take_all(&mut self) -> VecDeque<Option<Notification>> {
        self.head += self.items.len() as u64;
        if self.index.capacity() > KEEP {
            self.index = Default::default();
        } else {
            self.index.clear();
        }
        std::mem::take(&mut self.items)
    }

    /// Gives a delivered batch's buffer back for the next batch, if it is small and no new
    /// batch has started meanwhile; otherwise it is freed.
    fn recycle(&mut self, batch: VecDeque<Option<Notification>>) {
        if self.items.capacity() == 0 && batch.is_empty() && batch.capacity() <= KEEP {
            self.items = batch;
        }
    }
}

/// Queue capacity an idle subscription keeps for reuse (beyond it, memory goes back).
const KEEP: usize = 8;

impl Sub {
    pub(crate) fn new(
        id: SubscriptionId,
        names: Option<Box<[PropName]>>,
        target: Target,
        callback: Callback,
        stats: Arc<Stats>,
        on_end: Box<dyn FnOnce() + Send>,
    ) -> Arc<Sub> {
        Arc::new(Sub {
            id,
            names,
            active: AtomicBool::new(true),
            target,
            queue: Mutex::default(),
            idle: Condvar::new(),
            callback: Mutex::new(callback),
            stats,
            on_end: Mutex::new(Some(on_end)),
        })
    }

    pub(crate) fn wants(&self, name: PropName) -> bool {
        self.names.as_ref().is_none_or(|ns| ns.contains(&name))
    }

    pub(crate) fn is_active(&self) -> bool {
        self.active.load(Ordering::Acquire)
    }

    /// Queues a notification; the caller holds the lock of the object it is about, so the
    /// notifications of one object are queued in the order of its changes.
    pub(crate) fn enqueue(self: &Arc<Self>, n: Notification) {
        if !self.is_active() {
            return;
        }
        let mut q = self.queue.lock();
        q.push(n);
        if !q.scheduled {
            q.scheduled = true;
            drop(q);
            let me = self.clone();
            self.target.submit(Box::new(move || me.deliver()));
        }
    }

    /// Delivers what is pending, one batch, on the subscription's executor.
    fn deliver(self: Arc<Self>) {
        let mut batch = {
            let mut q = self.queue.lock();
            if !self.is_active() {
                q.take_all();
                q.scheduled = false;
                self.idle.notify_all();
                return;
            }
            q.running_on = Some(std::thread::current().id());
            q.take_all()
        };
        {
            let mut cb = self.callback.lock();
            for n in batch.iter().flatten() {
                if !self.is_active() {
                    break;
                }
                let last = matches!(n.subject, Subject::Object);
                if catch_unwind(AssertUnwindSafe(|| cb(n))).is_err() {
                    self.stats.panics_caught.fetch_add(1, Ordering::Relaxed);
                }
                self.stats.callbacks_run.fetch_add(1, Ordering::Relaxed);
                if last {
                    // The object is gone: this subscription ends here.
                    self.active.store(false, Ordering::Release);
                    if let Some(end) = self.on_end.lock().take() {
                        end();
                    }
                }
            }
        }
        // Values are dropped outside the lock.
        batch.clear();
        let mut q = self.queue.lock();
        q.running_on = None;
        if self.is_active() && !q.items.is_empty() {
            drop(q);
            let me = self.clone();
            self.target.submit(Box::new(move || me.deliver()));
        } else {
            q.take_all();
            q.recycle(batch);
            q.scheduled = false;
            self.idle.notify_all();
        }
    }

    /// Stops delivery without waiting: no callback starts after this returns (one already
    /// running may finish). Pending notifications are dropped.
    pub(crate) fn stop(&self) {
        self.active.store(false, Ordering::SeqCst);
        let pending = self.queue.lock().take_all();
        drop(pending);
    }

    /// Waits until the callback is not running — except when called from inside this
    /// subscription's own callback, which then finishes normally.
    pub(crate) fn wait_idle(&self) {
        let me = std::thread::current().id();
        let mut q = self.queue.lock();
        while q.running_on.is_some() && q.running_on != Some(me) {
            self.idle.wait(&mut q);
        }
    }
}
