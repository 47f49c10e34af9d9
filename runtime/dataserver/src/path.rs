//! Dotted paths (`root.vehicles.usv1.nav.speed`): a subscription built level by level from
//! the root, re-binding as objects along the way appear, vanish, are renamed or replaced
//! (system discovery). The end property is reported New / Changed / Deleted as it becomes
//! reachable or not.

use crate::error::DsError;
use crate::executor::Executor;
use crate::notification::{Kind, Notification, Subject};
use crate::server::DataServer;
use crate::subscription::{SubscriptionId, Topic};
use mocu_value::{Guid, PropName, Value};
use parking_lot::Mutex;
use std::panic::{AssertUnwindSafe, catch_unwind};
use std::sync::Arc;

/// A path to a property: object names from the root, then the property name.
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub struct DottedPath {
    pub objects: Vec<Arc<str>>,
    pub property: PropName,
}

impl DottedPath {
    pub fn new(objects: &[&str], property: &str) -> DottedPath {
        DottedPath {
            objects: objects.iter().map(|s| Arc::from(*s)).collect(),
            property: PropName::new(property),
        }
    }

    /// Parses `root.a.b.prop` (the leading `root.` is optional). Names containing dots
    /// need [`DottedPath::new`].
    pub fn parse(text: &str) -> Result<DottedPath, DsError> {
        let bad = |reason| DsError::BadPath { path: text.to_string(), reason };
        let mut segs: Vec<&str> = text.split('.').collect();
        if segs.first() == Some(&"root") {
            segs.remove(0);
        }
        if segs.iter().any(|s| s.is_empty()) {
            return Err(bad("empty segment"));
        }
        let property = segs.pop().ok_or(bad("no property name"))?;
        Ok(DottedPath::new(&segs, property))
    }
}

impl std::fmt::Display for DottedPath {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("root")?;
        for o in &self.objects {
            write!(f, ".{o}")?;
        }
        write!(f, ".{}", self.property)
    }
}

/// What a path watch reports about its end property.
#[derive(Clone, Debug, PartialEq)]
pub struct PathEvent {
    /// New: became reachable; Changed: new value; Deleted: no longer reachable.
    pub kind: Kind,
    /// The object holding the property (the one that was reachable, for Deleted).
    pub object: Guid,
    /// The value (None for Deleted).
    pub value: Option<Value>,
}

type PathCallback = Box<dyn FnMut(&PathEvent) + Send + 'static>;

/// A live path subscription. Dropping it (or `cancel`) ends it and every subscription it
/// made; when that returns, its callback does not run again.
pub struct PathWatch {
    ds: DataServer,
    state: Arc<Mutex<State>>,
    nowait: bool,
}

struct State {
    path: DottedPath,
    /// bound[0] is the root; bound[j+1] is the child of bound[j] named path.objects[j].
    bound: Vec<Guid>,
    /// subs[j] watches bound[j]: its children, or its properties at the end.
    subs: Vec<(SubscriptionId, u64)>,
    generation: u64,
    reported: Option<(Guid, Value)>,
    closed: bool,
    executor: Executor,
    callback: Arc<Mutex<PathCallback>>,
    /// Watching the object at the end of the path, not a property of it.
    object_only: bool,
    /// Events found while the watch was set up, emitted by its first executor job.
    initial: Vec<PathEvent>,
    /// The thread running the callback now (it holds `callback`'s lock meanwhile): a drop
    /// from elsewhere waits for it, a drop from inside the callback does not.
    running_on: Option<std::thread::ThreadId>,
}

impl DataServer {
    /// Watches a dotted path from the root. The callback runs on `executor` (a new serial
    /// executor when `None`), in order.
    pub fn watch_path(
        &self,
        path: DottedPath,
        executor: Option<&Executor>,
        callback: impl FnMut(&PathEvent) + Send + 'static,
    ) -> Result<PathWatch, DsError> {
        self.watch_path_from(Guid::ROOT, path, executor, callback)
    }

    /// Watches a dotted path that starts at `start` instead of the root (a template
    /// instance's vehicle, a menu's `self`).
    pub fn watch_path_from(
        &self,
        start: Guid,
        path: DottedPath,
        executor: Option<&Executor>,
        callback: impl FnMut(&PathEvent) + Send + 'static,
    ) -> Result<PathWatch, DsError> {
        self.start_watch(start, path, false, executor, Box::new(callback))
    }

    /// Watches the object reached by `objects` (names from `start`): `New` when it becomes
    /// reachable (with its GUID in `object`), `Deleted` when it stops being reachable.
    pub fn watch_object(
        &self,
        start: Guid,
        objects: &[&str],
        executor: Option<&Executor>,
        callback: impl FnMut(&PathEvent) + Send + 'static,
    ) -> Result<PathWatch, DsError> {
        let path = DottedPath::new(objects, "");
        self.start_watch(start, path, true, executor, Box::new(callback))
    }

    fn start_watch(
        &self,
        start: Guid,
        path: DottedPath,
        object_only: bool,
        executor: Option<&Executor>,
        callback: PathCallback,
    ) -> Result<PathWatch, DsError> {
        if !self.exists(start) {
            return Err(DsError::NoSuchObject { object: self.obj_ref(start) });
        }
        let executor = executor.cloned().unwrap_or_else(|| self.serial_executor());
        let state = Arc::new(Mutex::new(State {
            path,
            bound: vec![start],
            subs: Vec::new(),
            generation: 0,
            reported: None,
            closed: false,
            executor: executor.clone(),
            callback: Arc::new(Mutex::new(callback)),
            object_only,
            initial: Vec::new(),
            running_on: None,
        }));
        let mut st = state.lock();
        // The first events go out on the executor, before anything the subscriptions made
        // below deliver there (this job is queued first), never on the caller's thread.
        let (me, ds) = (state.clone(), self.clone());
        executor.spawn(move || {
            let events = std::mem::take(&mut me.lock().initial);
            emit(&ds, &me, events);
        });
        st.initial = rebuild(self, &state, &mut st, 0);
        drop(st);
        Ok(PathWatch { ds: self.clone(), state, nowait: false })
    }
}

impl PathWatch {
    pub fn cancel(self) {}

    /// Ends the watch without waiting for a callback that is running now (see
    /// `DataServer::unsubscribe_nowait`): for `Drop` impls and code holding a lock the
    /// callback may need. No callback starts after this returns.
    pub fn cancel_nowait(mut self) {
        self.nowait = true;
    }

    /// The object the path currently reaches, if any.
    pub fn bound_object(&self) -> Option<Guid> {
        let st = self.state.lock();
        (st.bound.len() == st.path.objects.len() + 1).then(|| *st.bound.last().expect("root"))
    }
}

impl Drop for PathWatch {
    fn drop(&mut self) {
        let (subs, callback, inside) = {
            let mut st = self.state.lock();
            st.closed = true;
            let inside = st.running_on == Some(std::thread::current().id());
            (std::mem::take(&mut st.subs), st.callback.clone(), inside)
        };
        for (id, _) in subs {
            if self.nowait {
                self.ds.unsubscribe_nowait(id);
            } else {
                self.ds.unsubscribe(id);
            }
        }
        if !self.nowait && !inside {
            // A callback may run outside every subscription (the first events go out in a
            // plain executor job): wait for it too. It holds the lock while it runs, and
            // sees `closed` before it would start another.
            drop(callback.lock());
        }
    }
}

/// Drops the subscriptions from level `k` on and binds again from `bound[k]` downwards,
/// as far as the objects exist. Returns events to report.
fn rebuild(ds: &DataServer, me: &Arc<Mutex<State>>, st: &mut State, k: usize) -> Vec<PathEvent> {
    for (id, _) in st.subs.drain(k..) {
        ds.unsubscribe_nowait(id);
    }
    st.bound.truncate(k + 1);
    let mut events = Vec::new();
    let mut j = k;
    loop {
        let at = st.bound[j];
        st.generation += 1;
        let generation = st.generation;
        let at_end = j == st.path.objects.len();
        let topic = match (at_end, st.object_only) {
            // No property: only the object's own Deleted reaches this subscription.
            (true, true) => Topic::Properties { object: at, names: Some(Vec::new()) },
            (true, false) => Topic::Properties { object: at, names: Some(vec![st.path.property]) },
            (false, _) => Topic::Children { object: at },
        };
        let weak = Arc::downgrade(me);
        // The server only weakly: the subscription lives in the server's registry (and,
        // once ended, in its deferred reclamation), so a strong handle here would keep the
        // server, and its threads, alive for ever.
        let server = Arc::downgrade(&ds.inner);
        let sub = ds.subscribe_on(&st.executor.clone(), topic, move |n| {
            if let (Some(me), Some(inner)) = (weak.upgrade(), server.upgrade()) {
                let ds2 = DataServer { inner };
                let events = {
                    let mut st = me.lock();
                    on_notification(&ds2, &me, &mut st, j, generation, n)
                };
                emit(&ds2, &me, events);
            }
        });
        match sub {
            Ok(id) => st.subs.push((id, generation)),
            Err(_) => break, // vanished meanwhile: its parent's watch will tell us
        }
        if at_end {
            if st.object_only && st.reported.as_ref().map(|r| r.0) != Some(at) {
                st.reported = Some((at, Value::Bool(true)));
                events.push(PathEvent { kind: Kind::New, object: at, value: None });
            }
            break;
        }
        match ds.find_child(at, &st.path.objects[j]) {
            Ok(Some(child)) => {
                st.bound.push(child);
                j += 1;
            }
            _ => break,
        }
    }
    if st.bound.len() < st.path.objects.len() + 1
        && let Some((obj, _)) = st.reported.take()
    {
        events.push(PathEvent { kind: Kind::Deleted, object: obj, value: None });
    }
    events
}

/// Makes level `level + 1` follow the first child of `bound[level]` with the wanted name, as
/// the tree is now (a sibling created or renamed before the followed one takes over).
fn relink(ds: &DataServer, me: &Arc<Mutex<State>>, st: &mut State, level: usize) -> Vec<PathEvent> {
    let first = ds.find_child(st.bound[level], &st.path.objects[level]).ok().flatten();
    if first == st.bound.get(level + 1).copied() {
        return Vec::new();
    }
    let mut ev = drop_reported(st);
    for (id, _) in st.subs.drain(level + 1..) {
        ds.unsubscribe_nowait(id);
    }
    st.bound.truncate(level + 1);
    if let Some(first) = first {
        st.bound.push(first);
        ev.extend(rebuild(ds, me, st, level + 1));
    }
    ev
}

fn on_notification(
    ds: &DataServer,
    me: &Arc<Mutex<State>>,
    st: &mut State,
    level: usize,
    generation: u64,
    n: &Notification,
) -> Vec<PathEvent> {
    if st.closed || st.subs.get(level).map(|s| s.1) != Some(generation) {
        return Vec::new(); // a notification from a level we have since re-bound
    }
    let at_end = level == st.path.objects.len();
    match (&n.subject, at_end) {
        (Subject::Object, _) => {
            // The object at this level is gone (its subscription ended with this).
            let mut ev = drop_reported(st);
            for (id, _) in st.subs.drain(level..) {
                ds.unsubscribe_nowait(id);
            }
            if level == 0 {
                // The start object itself: nothing can be reached from it again.
                st.bound.truncate(1);
                return ev;
            }
            st.bound.truncate(level);
            // Its parent's watch is still there: follow another child of that name now.
            let first = ds.find_child(st.bound[level - 1], &st.path.objects[level - 1]);
            if let Ok(Some(other)) = first {
                st.bound.push(other);
                ev.extend(rebuild(ds, me, st, level));
            }
            ev
        }
        (Subject::Property { value, .. }, true) => {
            let obj = st.bound[level];
            match (n.kind, value) {
                (Kind::New | Kind::Changed, Some(v)) => {
                    let kind = match &st.reported {
                        Some((o, old)) if *o == obj && old == v => return Vec::new(),
                        Some((o, _)) if *o == obj => Kind::Changed,
                        _ => Kind::New,
                    };
                    st.reported = Some((obj, v.clone()));
                    vec![PathEvent { kind, object: obj, value: Some(v.clone()) }]
                }
                _ => drop_reported(st),
            }
        }
        (Subject::Child { .. }, false) => relink(ds, me, st, level),
        _ => Vec::new(),
    }
}

fn drop_reported(st: &mut State) -> Vec<PathEvent> {
    match st.reported.take() {
        Some((o, _)) => vec![PathEvent { kind: Kind::Deleted, object: o, value: None }],
        None => Vec::new(),
    }
}

/// Runs the callback for each event until the watch is closed; one that panics is caught
/// and counted, and the events after it are still delivered.
fn emit(ds: &DataServer, me: &Arc<Mutex<State>>, events: Vec<PathEvent>) {
    if events.is_empty() {
        return;
    }
    let cb = {
        let st = me.lock();
        if st.closed {
            return;
        }
        st.callback.clone()
    };
    let mut cb = cb.lock();
    me.lock().running_on = Some(std::thread::current().id());
    for e in &events {
        // Checked before each event: a cancel during the batch (from its own callback
        // included) stops the rest.
        if me.lock().closed {
            break;
        }
        if catch_unwind(AssertUnwindSafe(|| cb(e))).is_err() {
            ds.stats().panics_caught.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        }
    }
    me.lock().running_on = None;
}

impl DataServer {
    /// The dotted path of an object from the root (`root.vehicles.usv1`): the inverse of
    /// [`DataServer::resolve`], for events, logs and method arguments that name an object.
    /// An object deleted meanwhile ends the path where it was lost.
    pub fn path_text(&self, mut guid: Guid) -> String {
        let mut names = Vec::new();
        while guid != Guid::ROOT {
            let Ok(info) = self.info(guid) else { break };
            names.push(info.name.to_string());
            match self.parent(guid) {
                Ok(Some(p)) => guid = p,
                _ => break,
            }
        }
        names.push("root".into());
        names.reverse();
        names.join(".")
    }
}

#[cfg(test)]
mod path_text_tests {
    use crate::{DataServer, ObjectInfo};
    use mocu_value::Guid;

    #[test]
    fn path_text_names_an_object_from_the_root_and_resolves_back() {
        let ds = DataServer::default();
        let v = ds.create_object(Guid::ROOT, ObjectInfo::new("vehicles", "folder")).unwrap();
        let u = ds.create_object(v, ObjectInfo::new("usv1", "usv")).unwrap();
        assert_eq!(ds.path_text(u), "root.vehicles.usv1");
        assert_eq!(ds.path_text(Guid::ROOT), "root");
        assert_eq!(ds.resolve(&["vehicles", "usv1"]), Some(u));
    }
}
