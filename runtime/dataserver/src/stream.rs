//! Streams (paper §3.2): a listener object; receivers join it by associating an object and
//! a receiver method; a message sent to the listener reaches every receiver, in order.
//! Each receiver has a bounded queue with an explicit overflow policy.

use crate::error::{DsError, ObjRef};
use crate::executor::Target;
use crate::hash::BuildIdHasher;
use crate::meta::ObjectInfo;
use crate::method::{CallOptions, CallOutcome};
use crate::server::DataServer;
use mocu_value::{Guid, PropName, Value};
use parking_lot::{Condvar, Mutex, RwLock};
use std::collections::VecDeque;
use std::sync::Arc;

/// What a receiver's full queue does with a new message.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Overflow {
    /// The sender waits for room: no loss (commands). Never send with `Block` from the
    /// receiver's own serial executor: it would wait for itself.
    Block,
    /// The oldest queued message is dropped and counted in the association object's
    /// `dropped` property (video: the display never lags behind the camera).
    DropOldest,
}

/// The type name of listener objects and of receiver associations.
pub const LISTENER_TYPE: &str = "listener";
pub const RECEIVER_TYPE: &str = "receiver";

#[derive(Default)]
pub(crate) struct Streams {
    listeners: papaya::HashMap<Guid, Arc<Listener>, BuildIdHasher>,
    /// Association object → its listener.
    assocs: papaya::HashMap<Guid, Guid, BuildIdHasher>,
    /// Receiver object → its receivers (one per listener it joined), so deleting it
    /// releases senders blocked on its queues.
    targets: Mutex<crate::hash::IdMap<Guid, Vec<Joined>>>,
}

/// A receiver and the listener it joined.
type Joined = (Guid, Arc<Receiver>);

#[derive(Default)]
struct Listener {
    receivers: RwLock<Vec<Arc<Receiver>>>,
}

struct Receiver {
    assoc: Guid,
    target: Guid,
    method: PropName,
    overflow: Overflow,
    capacity: usize,
    /// Where its messages are drained: the method's executor, followed when the method is
    /// published again elsewhere.
    run_on: Mutex<Target>,
    queue: Mutex<RecvQueue>,
    room: Condvar,
    /// The highest `dropped` count written to the association object: concurrent senders
    /// write it in increasing order only.
    published: Mutex<u64>,
}

#[derive(Default)]
struct RecvQueue {
    buf: VecDeque<Arc<[Value]>>,
    scheduled: bool,
    dropped: u64,
    closed: bool,
    /// Closed because the receiver object was deleted (a sender waiting on it gets an error).
    target_gone: bool,
}

impl Receiver {
    fn close(&self, target_gone: bool) {
        let mut q = self.queue.lock();
        q.closed = true;
        q.target_gone |= target_gone;
        q.buf.clear();
        self.room.notify_all();
    }
}

impl Streams {
    /// Called when an object is deleted: a deleted listener closes its receivers, a deleted
    /// association leaves its listener, and a deleted receiver object closes its receivers
    /// (releasing blocked senders) and returns their association objects, for the caller
    /// to delete once it holds no lock.
    pub(crate) fn forget(&self, guid: Guid) -> Vec<Guid> {
        if let Some(l) = self.listeners.pin().remove(&guid) {
            let rs = l.receivers.read().clone();
            for r in &rs {
                r.close(false);
            }
            self.untarget(&rs);
        }
        if let Some(listener) = self.assocs.pin().remove(&guid)
            && let Some(l) = self.listeners.pin().get(listener)
        {
            let mut left = Vec::new();
            l.receivers.write().retain(|r| {
                if r.assoc == guid {
                    r.close(false);
                    left.push(r.clone());
                }
                r.assoc != guid
            });
            self.untarget(&left);
        }
        let gone = {
            let mut targets = self.targets.lock();
            if targets.is_empty() {
                return Vec::new();
            }
            targets.remove(&guid).unwrap_or_default()
        };
        let mut orphans = Vec::new();
        for (listener, r) in gone {
            r.close(true);
            if let Some(l) = self.listeners.pin().get(&listener) {
                l.receivers.write().retain(|x| !Arc::ptr_eq(x, &r));
            }
            orphans.push(r.assoc);
        }
        orphans
    }

    /// Forgets closed receivers in the by-target index.
    fn untarget(&self, closed: &[Arc<Receiver>]) {
        let mut targets = self.targets.lock();
        for r in closed {
            if let Some(rs) = targets.get_mut(&r.target) {
                rs.retain(|(_, x)| !Arc::ptr_eq(x, r));
                if rs.is_empty() {
                    targets.remove(&r.target);
                }
            }
        }
    }
}

impl DataServer {
    fn listener(&self, listener: Guid) -> Result<Arc<Listener>, DsError> {
        self.inner
            .streams
            .listeners
            .pin()
            .get(&listener)
            .cloned()
            .ok_or_else(|| DsError::NotAListener { object: self.obj_ref(listener) })
    }

    /// Publishes a listener object under `parent`.
    pub fn create_listener(&self, parent: Guid, name: &str) -> Result<Guid, DsError> {
        let g = self.create_object(parent, ObjectInfo::new(name, LISTENER_TYPE))?;
        self.inner.streams.listeners.pin().insert(g, Arc::new(Listener::default()));
        Ok(g)
    }

    /// Joins `receiver`'s method `method` to a listener, with a queue of `capacity`
    /// messages. Returns the association object (a child of the listener, type
    /// `receiver`); delete it, or call `leave`, to stop receiving.
    pub fn join(
        &self,
        listener: Guid,
        receiver: Guid,
        method: &str,
        overflow: Overflow,
        capacity: usize,
    ) -> Result<Guid, DsError> {
        let method = PropName::new(method);
        let l = self.listener(listener)?;
        let run_on = {
            let o = self.object(receiver)?;
            let os = o.state.read();
            match os.methods.get(&method) {
                Some(m) => m.target(&self.inner.pool),
                None => {
                    return Err(DsError::NoSuchProperty {
                        object: ObjRef { guid: receiver, name: Some(os.info.name.clone()) },
                        property: method,
                    });
                }
            }
        };
        let name = format!("{}.{}", self.info(receiver)?.name, method);
        let assoc = self.create_object(listener, ObjectInfo::new(&name, RECEIVER_TYPE))?;
        self.set(assoc, "target", Value::Guid(receiver))?;
        self.set(assoc, "method", Value::str(method.as_str()))?;
        self.set(assoc, "capacity", Value::Int(capacity as i64))?;
        self.set(assoc, "dropped", Value::Int(0))?;
        let r = Arc::new(Receiver {
            assoc,
            target: receiver,
            method,
            overflow,
            capacity: capacity.max(1),
            run_on: Mutex::new(run_on),
            queue: Mutex::default(),
            room: Condvar::new(),
            published: Mutex::new(0),
        });
        self.inner.streams.targets.lock().entry(receiver).or_default().push((listener, r.clone()));
        l.receivers.write().push(r);
        if !self.exists(receiver) {
            // Deleted while joining: undo, as the deletion would have.
            let _ = self.delete_object(assoc);
            self.inner.streams.forget(receiver);
            return Err(DsError::NoSuchObject { object: ObjRef::unnamed(receiver) });
        }
        self.inner.streams.assocs.pin().insert(assoc, listener);
        Ok(assoc)
    }

    /// Leaves a listener (deletes the association object).
    pub fn leave(&self, assoc: Guid) -> Result<(), DsError> {
        self.delete_object(assoc)
    }

    /// Sends one message to every receiver of a listener, in order; returns how many
    /// receivers it was queued for. A `Block` receiver with a full queue makes the sender
    /// wait; if that receiver object is deleted meanwhile, the sender is released, the
    /// message still goes to the other receivers, and the result is `NoSuchObject` naming
    /// the deleted receiver.
    pub fn send(&self, listener: Guid, args: Vec<Value>) -> Result<usize, DsError> {
        let l = self.listener(listener)?;
        let msg: Arc<[Value]> = args.into();
        self.emit_sent(listener, &msg);
        let receivers = l.receivers.read().clone();
        let mut sent = 0;
        let mut lost = None;
        for r in receivers {
            let mut q = r.queue.lock();
            let mut dropped = None;
            while q.buf.len() >= r.capacity && !q.closed {
                match r.overflow {
                    Overflow::DropOldest => {
                        q.buf.pop_front();
                        q.dropped += 1;
                        dropped = Some(q.dropped);
                    }
                    Overflow::Block => r.room.wait(&mut q),
                }
            }
            if q.closed {
                if q.target_gone {
                    lost = Some(r.target);
                }
                continue;
            }
            q.buf.push_back(msg.clone());
            sent += 1;
            if !q.scheduled {
                q.scheduled = true;
                let ds = self.clone();
                let r2 = r.clone();
                drop(q);
                self.drain_target(&r2).submit(Box::new(move || ds.drain_receiver(r2)));
                q = r.queue.lock();
            }
            drop(q);
            if let Some(n) = dropped {
                let mut published = r.published.lock();
                if n > *published {
                    *published = n;
                    let _ = self.set(r.assoc, "dropped", Value::Int(n as i64));
                }
            }
        }
        match lost {
            Some(target) => Err(DsError::NoSuchObject { object: ObjRef::unnamed(target) }),
            None => Ok(sent),
        }
    }

    /// Where `r`'s messages are drained now: its method's executor as published now (it
    /// may have been published again elsewhere since `join`); whether that moved.
    fn follow_method(&self, r: &Receiver) -> (bool, Target) {
        let now = self.resolve_method(r.target, r.method).map(|m| m.target(&self.inner.pool));
        let mut run_on = r.run_on.lock();
        match now {
            Ok(now) if !now.same(&run_on) => {
                *run_on = now.clone();
                (true, now)
            }
            _ => (false, run_on.clone()),
        }
    }

    fn drain_target(&self, r: &Receiver) -> Target {
        self.follow_method(r).1
    }

    fn drain_receiver(&self, r: Arc<Receiver>) {
        loop {
            // The method published again on another executor: drain there from now on.
            let (moved, now) = self.follow_method(&r);
            if moved {
                let (ds, r2) = (self.clone(), r.clone());
                now.submit(Box::new(move || ds.drain_receiver(r2)));
                return;
            }
            let msg = {
                let mut q = r.queue.lock();
                match q.buf.pop_front() {
                    Some(m) => {
                        r.room.notify_one();
                        m
                    }
                    None => {
                        q.scheduled = false;
                        return;
                    }
                }
            };
            let ds = self.clone();
            let assoc = r.assoc;
            // Fed once, as the message sent (`Change::Sent`), not again as a call per receiver.
            self.call_unfed(
                r.target,
                r.method,
                msg.to_vec(),
                Some(CallOptions::immediate()),
                move |o| {
                    if matches!(o, CallOutcome::NoSuchObject | CallOutcome::NoSuchMethod) {
                        // The receiver is gone: the association goes with it.
                        let _ = ds.delete_object(assoc);
                    }
                },
            );
        }
    }

    /// The receivers of a listener (their association objects).
    pub fn receivers(&self, listener: Guid) -> Result<Vec<Guid>, DsError> {
        let l = self.listener(listener)?;
        Ok(l.receivers.read().iter().map(|r| r.assoc).collect())
    }
}
