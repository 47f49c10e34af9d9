//! The DataServer: the object tree, properties and subscriptions.

use crate::clock::{Clock, SystemClock};
use crate::error::{DsError, ObjRef};
use crate::executor::{Executor, Pool, Stats, Target};
use crate::feed::Change;
use crate::hash::BuildIdHasher;
use crate::meta::ObjectInfo;
use crate::notification::{Kind, Notification, Subject};
use crate::object::{ObjState, Object};
use crate::subscription::{Callback, Sub, SubscriptionId, Topic};
use crate::timer::Timer;
use mocu_value::Guid;
use parking_lot::Mutex;
use std::sync::Arc;
use std::sync::atomic::{AtomicU64, Ordering};

/// Settings of a DataServer.
#[derive(Clone, Debug)]
pub struct Config {
    /// Worker threads that deliver notifications and run queued calls.
    pub workers: usize,
}

impl Default for Config {
    fn default() -> Config {
        let cores = std::thread::available_parallelism().map_or(2, |n| n.get());
        Config { workers: cores.clamp(2, 8) }
    }
}

/// A handle on the shared-world model. Cheap to clone; every module holds one.
#[derive(Clone)]
pub struct DataServer {
    pub(crate) inner: Arc<Inner>,
}

pub(crate) struct Inner {
    pub(crate) objects: papaya::HashMap<Guid, Arc<Object>, BuildIdHasher>,
    /// Serialises changes to the tree's shape (create, delete, move). Property reads and
    /// writes never take it.
    structure: Mutex<()>,
    next_guid: AtomicU64,
    next_sub: AtomicU64,
    pub(crate) subs: papaya::HashMap<SubscriptionId, (Guid, Arc<Sub>), BuildIdHasher>,
    pub(crate) pool: Arc<Pool>,
    pub(crate) timer: Timer,
    pub(crate) streams: crate::stream::Streams,
    pub(crate) feeds: crate::feed::Feeds,
}

impl Default for DataServer {
    fn default() -> Self {
        DataServer::new(Config::default())
    }
}

impl DataServer {
    pub fn new(config: Config) -> DataServer {
        DataServer::with_clock(config, Arc::new(SystemClock))
    }

    /// A DataServer whose timers, delayed calls, timeouts and `received_at` read `clock`
    /// (a [`crate::ManualClock`] in tests: advancing it fires what falls due).
    pub fn with_clock(config: Config, clock: Arc<dyn Clock>) -> DataServer {
        let pool = Pool::new(config.workers);
        let timer = Timer::new(pool.stats.clone(), clock);
        let inner = Inner {
            objects: papaya::HashMap::builder().hasher(BuildIdHasher::default()).build(),
            structure: Mutex::new(()),
            next_guid: AtomicU64::new(Guid::ROOT.get() + 1),
            next_sub: AtomicU64::new(1),
            subs: papaya::HashMap::builder().hasher(BuildIdHasher::default()).build(),
            pool,
            timer,
            streams: Default::default(),
            feeds: Default::default(),
        };
        let root = Object::new(Guid::ROOT, ObjectInfo::new("root", "root"), None);
        inner.objects.pin().insert(Guid::ROOT, root);
        DataServer { inner: Arc::new(inner) }
    }

    pub fn root(&self) -> Guid {
        Guid::ROOT
    }

    /// The server's clock (the one given to `with_clock`, else the system clock).
    pub fn clock(&self) -> &Arc<dyn Clock> {
        self.inner.timer.clock()
    }

    /// The current time on the server's clock.
    pub fn now(&self) -> std::time::Instant {
        self.inner.timer.clock().now()
    }

    /// The time of day on the server's clock ([`Clock::wall`]).
    pub fn wall_time(&self) -> std::time::SystemTime {
        self.inner.timer.clock().wall()
    }

    /// [`DataServer::wall_time`] in seconds since the Unix epoch: what `time` properties hold
    /// (alerts, command feedback), so that they and their ages follow the server's clock.
    pub fn wall_secs(&self) -> f64 {
        let since = self.wall_time().duration_since(std::time::UNIX_EPOCH);
        since.map_or(0.0, |d| d.as_secs_f64())
    }

    // ----- objects -------------------------------------------------------------------

    pub(crate) fn object(&self, guid: Guid) -> Result<Arc<Object>, DsError> {
        self.inner
            .objects
            .pin()
            .get(&guid)
            .cloned()
            .ok_or(DsError::NoSuchObject { object: ObjRef::unnamed(guid) })
    }

    pub(crate) fn obj_ref(&self, guid: Guid) -> ObjRef {
        match self.inner.objects.pin().get(&guid) {
            Some(o) => ObjRef { guid, name: Some(o.state.read().info.name.clone()) },
            None => ObjRef::unnamed(guid),
        }
    }

    /// Publishes a new object as the last child of `parent`; returns its new GUID.
    pub fn create_object(&self, parent: Guid, info: ObjectInfo) -> Result<Guid, DsError> {
        self.create_object_at(parent, usize::MAX, info)
    }

    /// Publishes a new object at position `index` among `parent`'s children (clamped to the
    /// end).
    pub fn create_object_at(
        &self,
        parent: Guid,
        index: usize,
        info: ObjectInfo,
    ) -> Result<Guid, DsError> {
        let _shape = self.inner.structure.lock();
        let p = self.object(parent)?;
        let mut ps = p.state.write();
        if !ps.alive {
            return Err(DsError::NoSuchObject { object: ObjRef::unnamed(parent) });
        }
        let guid = self.new_guid();
        let obj = Object::new(guid, info.clone(), Some(parent));
        self.inner.objects.pin().insert(guid, obj);
        let index = index.min(ps.children.len());
        ps.children.insert(index, guid);
        self.emit(|| Change::Created { object: guid, parent, index, info: info.clone() });
        notify_child(&ps, Kind::New, guid, &info, index);
        Ok(guid)
    }

    /// Publishes a new object between `parent` and its child `child`: the new object takes
    /// the child's place in `parent`'s order and the child becomes its only child.
    pub fn insert_between(
        &self,
        parent: Guid,
        child: Guid,
        info: ObjectInfo,
    ) -> Result<Guid, DsError> {
        let _shape = self.inner.structure.lock();
        let p = self.object(parent)?;
        let c = self.object(child)?;
        let mut ps = p.state.write();
        let Some(index) = ps.children.iter().position(|&g| g == child) else {
            drop(ps);
            return Err(DsError::NotAChild {
                parent: self.obj_ref(parent),
                child: self.obj_ref(child),
            });
        };
        let guid = self.new_guid();
        let mid = Object::new(guid, info.clone(), Some(parent));
        let mut cs = c.state.write();
        let child_info = cs.info.clone();
        cs.parent = Some(guid);
        drop(cs);
        mid.state.write().children.push(child);
        self.inner.objects.pin().insert(guid, mid);
        ps.children[index] = guid;
        self.emit(|| Change::Created { object: guid, parent, index, info: info.clone() });
        self.emit(|| Change::Moved { object: child, parent: guid, index: 0 });
        notify_child(&ps, Kind::Deleted, child, &child_info, index);
        notify_child(&ps, Kind::New, guid, &info, index);
        Ok(guid)
    }

    /// Deletes an object and its whole subtree.
    pub fn delete_object(&self, guid: Guid) -> Result<(), DsError> {
        if guid == Guid::ROOT {
            return Err(DsError::RootIsPermanent);
        }
        let _shape = self.inner.structure.lock();
        let o = self.object(guid)?;
        let parent = o.state.read().parent;
        if let Some(parent) = parent {
            let p = self.object(parent)?;
            let mut ps = p.state.write();
            if let Some(index) = ps.children.iter().position(|&g| g == guid) {
                ps.children.remove(index);
                let info = o.state.read().info.clone();
                notify_child(&ps, Kind::Deleted, guid, &info, index);
            }
        }
        let removed = self.kill_subtree(guid);
        drop(_shape);
        // The subtree's handlers are the modules': dropped once no lock is held.
        drop(removed);
        Ok(())
    }

    /// Deletes `guid` and promotes its child `keep` into its place (same position in the
    /// parent's order). The object's other children are deleted with it.
    pub fn delete_and_promote(&self, guid: Guid, keep: Guid) -> Result<(), DsError> {
        if guid == Guid::ROOT {
            return Err(DsError::RootIsPermanent);
        }
        let _shape = self.inner.structure.lock();
        let o = self.object(guid)?;
        let k = self.object(keep)?;
        let mut os = o.state.write();
        let Some(kidx) = os.children.iter().position(|&g| g == keep) else {
            drop(os);
            return Err(DsError::NotAChild {
                parent: self.obj_ref(guid),
                child: self.obj_ref(keep),
            });
        };
        let parent = os.parent.ok_or(DsError::RootIsPermanent)?;
        os.children.remove(kidx);
        let keep_info = k.state.read().info.clone();
        notify_child(&os, Kind::Deleted, keep, &keep_info, kidx);
        let info = os.info.clone();
        drop(os);
        k.state.write().parent = Some(parent);
        let p = self.object(parent)?;
        let mut ps = p.state.write();
        if let Some(index) = ps.children.iter().position(|&g| g == guid) {
            ps.children[index] = keep;
            self.emit(|| Change::Moved { object: keep, parent, index });
            notify_child(&ps, Kind::Deleted, guid, &info, index);
            notify_child(&ps, Kind::New, keep, &keep_info, index);
        }
        drop(ps);
        let removed = self.kill_subtree(guid);
        drop(_shape);
        // The subtree's handlers are the modules': dropped once no lock is held.
        drop(removed);
        Ok(())
    }

    /// Renames an object (and/or changes its type); its parent's child subscribers see
    /// `Changed`.
    pub fn set_info(&self, guid: Guid, info: ObjectInfo) -> Result<(), DsError> {
        if guid == Guid::ROOT {
            return Err(DsError::RootIsPermanent);
        }
        let _shape = self.inner.structure.lock();
        let o = self.object(guid)?;
        let parent = {
            let mut os = o.state.write();
            if os.info == info {
                return Ok(());
            }
            os.info = info.clone();
            self.emit(|| Change::Renamed { object: guid, info: info.clone() });
            os.parent
        };
        if let Some(parent) = parent {
            let p = self.object(parent)?;
            let ps = p.state.read();
            if let Some(index) = ps.children.iter().position(|&g| g == guid) {
                notify_child(&ps, Kind::Changed, guid, &info, index);
            }
        }
        Ok(())
    }

    /// Marks every object of the subtree dead, tells each one's subscribers (parents
    /// first), feeds `Deleted` for `guid` and removes them from the table. Caller holds the
    /// structure lock and has already unlinked `guid` from its parent; it drops what this
    /// returns (the subtree's method handlers, which are the modules') after releasing it.
    ///
    /// `Deleted` is fed only once every object of the subtree is dead: a write checks
    /// `alive` and feeds itself under its object's lock, so no write to the subtree can be
    /// fed after the deletion that removed it.
    #[must_use = "the removed handlers must be dropped after the structure lock is released"]
    fn kill_subtree(&self, guid: Guid) -> Vec<Arc<crate::method::Method>> {
        let mut removed = Vec::new();
        let mut stack = vec![guid];
        let mut orphans = Vec::new();
        let mut dead = Vec::new();
        let objects = self.inner.objects.pin();
        while let Some(g) = stack.pop() {
            let Some(o) = objects.get(&g).cloned() else { continue };
            let mut guard = o.state.write();
            let os = &mut *guard;
            os.alive = false;
            stack.extend(os.children.iter().rev().copied());
            let gone = Notification { object: g, kind: Kind::Deleted, subject: Subject::Object };
            // Each subscription leaves the registry once this is delivered (or when
            // unsubscribed before that), so unsubscribe can still stop it until then.
            for s in os.prop_subs.drain(..).chain(os.child_subs.drain(..)) {
                s.enqueue(gone.clone());
            }
            removed.extend(std::mem::take(&mut os.methods).into_values());
            drop(guard);
            dead.push(g);
        }
        self.emit(|| Change::Deleted { object: guid });
        for g in dead {
            objects.remove(&g);
            orphans.extend(self.inner.streams.forget(g));
        }
        if !orphans.is_empty() {
            // Associations of a deleted receiver object go too, once no lock is held.
            let ds = self.clone();
            self.inner.pool.submit(Box::new(move || {
                for a in orphans {
                    let _ = ds.delete_object(a);
                }
            }));
        }
        removed
    }

    fn new_guid(&self) -> Guid {
        let raw = self.inner.next_guid.fetch_add(1, Ordering::Relaxed);
        Guid::new(raw).expect("GUIDs count up from 2 and never wrap in 2^64 publications")
    }

    pub fn exists(&self, guid: Guid) -> bool {
        self.inner.objects.pin().contains_key(&guid)
    }

    pub fn info(&self, guid: Guid) -> Result<ObjectInfo, DsError> {
        Ok(self.object(guid)?.state.read().info.clone())
    }

    pub fn parent(&self, guid: Guid) -> Result<Option<Guid>, DsError> {
        Ok(self.object(guid)?.state.read().parent)
    }

    /// The children of an object, in order.
    pub fn children(&self, guid: Guid) -> Result<Vec<Guid>, DsError> {
        Ok(self.object(guid)?.state.read().children.clone())
    }

    /// The first child of `parent` named `name`.
    pub fn find_child(&self, parent: Guid, name: &str) -> Result<Option<Guid>, DsError> {
        let p = self.object(parent)?;
        let ps = p.state.read();
        let objects = self.inner.objects.pin();
        Ok(ps
            .children
            .iter()
            .copied()
            .find(|c| objects.get(c).is_some_and(|o| &*o.state.read().info.name == name)))
    }

    /// Resolves `root.a.b` (object segments only) to an object, if it exists now.
    pub fn resolve(&self, path: &[&str]) -> Option<Guid> {
        let mut at = Guid::ROOT;
        for seg in path {
            at = self.find_child(at, seg).ok()??;
        }
        Some(at)
    }

    /// How many objects exist, root included.
    pub fn object_count(&self) -> usize {
        self.inner.objects.len()
    }

    // ----- subscriptions -------------------------------------------------------------

    /// Subscribes; the callback runs on the DataServer's workers, one notification at a
    /// time for this subscription. Everything already there arrives first, as `New`.
    pub fn subscribe(
        &self,
        topic: Topic,
        callback: impl FnMut(&Notification) + Send + 'static,
    ) -> Result<SubscriptionId, DsError> {
        self.subscribe_with(topic, None, Box::new(callback))
    }

    /// Subscribes with the callback running on a module's serial executor, in order with
    /// everything else given to that executor.
    pub fn subscribe_on(
        &self,
        executor: &Executor,
        topic: Topic,
        callback: impl FnMut(&Notification) + Send + 'static,
    ) -> Result<SubscriptionId, DsError> {
        self.subscribe_with(topic, Some(executor), Box::new(callback))
    }

    fn subscribe_with(
        &self,
        topic: Topic,
        executor: Option<&Executor>,
        callback: Callback,
    ) -> Result<SubscriptionId, DsError> {
        let guid = topic.object();
        let o = self.object(guid)?;
        let id = SubscriptionId(self.inner.next_sub.fetch_add(1, Ordering::Relaxed));
        let target = match executor {
            Some(ex) => Target::Serial(ex.clone()),
            None => Target::Pool(self.inner.pool.clone()),
        };
        let names = match &topic {
            Topic::Properties { names, .. } => names.as_ref().map(|n| n.clone().into_boxed_slice()),
            Topic::Children { .. } => None,
        };
        let registry = Arc::downgrade(&self.inner);
        let on_end = Box::new(move || {
            if let Some(inner) = registry.upgrade() {
                inner.subs.pin().remove(&id);
            }
        });
        let sub = Sub::new(id, names, target, callback, self.inner.pool.stats.clone(), on_end);
        // Children change shape under the structure lock; take it so the initial list and
        // later changes cannot interleave.
        let _shape = matches!(topic, Topic::Children { .. }).then(|| self.inner.structure.lock());
        let mut os = o.state.write();
        if !os.alive {
            return Err(DsError::NoSuchObject { object: ObjRef::unnamed(guid) });
        }
        match topic {
            Topic::Properties { .. } => {
                for p in os.props.iter().filter(|p| sub.wants(p.name)) {
                    sub.enqueue(Notification {
                        object: guid,
                        kind: Kind::New,
                        subject: Subject::Property { name: p.name, value: Some(p.value.clone()) },
                    });
                }
                os.prop_subs.push(sub.clone());
            }
            Topic::Children { .. } => {
                let objects = self.inner.objects.pin();
                for (index, c) in os.children.iter().enumerate() {
                    if let Some(child) = objects.get(c) {
                        let info = child.state.read().info.clone();
                        sub.enqueue(child_note(guid, Kind::New, *c, &info, index));
                    }
                }
                os.child_subs.push(sub.clone());
            }
        }
        // Registered before the object's lock is released, so a delete that follows
        // cannot end the subscription before it is in the registry.
        self.inner.subs.pin().insert(id, (guid, sub));
        drop(os);
        Ok(id)
    }

    /// Ends a subscription. When it returns, its callback is not running and will not run
    /// again (unless called from that very callback, which then finishes). Unknown or
    /// already-ended ids are ignored: ending twice is harmless.
    pub fn unsubscribe(&self, id: SubscriptionId) {
        if let Some(sub) = self.end_subscription(id) {
            sub.wait_idle();
        }
    }

    /// Ends a subscription without waiting: when it returns, the callback will not start
    /// again, but a call already running (on another thread) may still finish. Never
    /// blocks on the callback, so it is the form for `Drop` impls and for code that holds a
    /// lock the callback may need (waiting `unsubscribe` there can deadlock). Unknown or
    /// already-ended ids are ignored.
    pub fn unsubscribe_nowait(&self, id: SubscriptionId) {
        self.end_subscription(id);
    }

    fn end_subscription(&self, id: SubscriptionId) -> Option<Arc<Sub>> {
        let (guid, sub) = self.inner.subs.pin().remove(&id).cloned()?;
        sub.stop();
        if let Ok(o) = self.object(guid) {
            let mut os = o.state.write();
            os.prop_subs.retain(|s| s.id != id);
            os.child_subs.retain(|s| s.id != id);
        }
        Some(sub)
    }

    /// Live subscriptions (for leak tests and statistics).
    pub fn subscription_count(&self) -> usize {
        self.inner.subs.len()
    }

    // ----- executors -----------------------------------------------------------------

    /// A new serial executor for a module: everything given to it runs in order, one at a
    /// time, on the DataServer's workers.
    pub fn serial_executor(&self) -> Executor {
        Executor::new(self.inner.pool.clone())
    }

    /// Waits until no notification or queued call is pending or running (delayed calls
    /// that are not yet due do not count). For tests and orderly shutdown.
    pub fn quiesce(&self) {
        // A due job still on the schedule (the timer thread not yet woken) or taken but not
        // yet submitted is in neither count: fire what is due here (unless
        // `advance_settled` holds the timer, and fires it itself), and wait until the pool
        // is idle with no job due or in the timer's hands.
        let timer = &self.inner.timer;
        loop {
            timer.fire_due();
            crate::executor::wait_quiet(&self.inner.pool);
            if timer.firing() == 0
                && !timer.has_due()
                && crate::executor::is_quiet(&self.inner.pool)
            {
                return;
            }
            std::thread::yield_now();
        }
    }

    /// Moves `clock` (this server's clock) forward to `to` one timer job at a time: the jobs
    /// due by then fire in deadline order (equal deadlines in the order they were
    /// scheduled), the clock set to each one's deadline, and the work each one causes runs
    /// to quiet before the next fires. A run driven this way ends in the same state every
    /// time its inputs are the same (deterministic runs and replay, `docs/dataserver.md`).
    pub fn advance_settled(&self, clock: &crate::ManualClock, to: std::time::Instant) {
        let timer = &self.inner.timer;
        timer.hold(true);
        loop {
            self.quiesce();
            match timer.next_due() {
                Some(due) if due <= to => {
                    clock.move_to(due);
                    timer.fire_one();
                }
                _ => break,
            }
        }
        clock.move_to(to);
        timer.hold(false);
        self.quiesce();
    }

    /// The deadline of the earliest timer job not yet fired.
    pub fn next_deadline(&self) -> Option<std::time::Instant> {
        self.inner.timer.next_due()
    }

    /// Worker threads alive now: `Config::workers`, plus any the pool added while all of
    /// them were stuck (see `docs/dataserver.md`).
    pub fn worker_count(&self) -> usize {
        self.inner.pool.workers()
    }

    /// Timers not yet due: delayed calls, `run_after` jobs and call timeouts (an answered
    /// call's timeout is released at once and does not count).
    pub fn pending_timers(&self) -> usize {
        self.inner.timer.pending()
    }

    /// Counters of work done.
    pub fn stats(&self) -> &Stats {
        &self.inner.pool.stats
    }
}

pub(crate) fn obj_ref_of(guid: Guid, os: &ObjState) -> ObjRef {
    ObjRef { guid, name: Some(os.info.name.clone()) }
}

fn child_note(
    parent: Guid,
    kind: Kind,
    child: Guid,
    info: &ObjectInfo,
    index: usize,
) -> Notification {
    Notification {
        object: parent,
        kind,
        subject: Subject::Child {
            guid: child,
            name: info.name.clone(),
            kind: info.kind.clone(),
            index,
        },
    }
}

fn notify_child(ps: &ObjState, kind: Kind, child: Guid, info: &ObjectInfo, index: usize) {
    if ps.child_subs.is_empty() {
        return;
    }
    let parent = ps.self_guid;
    let n = child_note(parent, kind, child, info, index);
    for s in &ps.child_subs {
        s.enqueue(n.clone());
    }
}
