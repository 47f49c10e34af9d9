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
            executor,
            callback: Arc::new(Mutex::new(callback)),
            object_only,
        }));
        let events = {
            let mut st = state.lock();
            rebuild(self, &state, &mut st, 0)
        };
        emit(&state, events);
        Ok(PathWatch { ds: self.clone(), state })
    }
}

impl PathWatch {
    pub fn cancel(self) {}

    /// The object the path currently reaches, if any.
    pub fn bound_object(&self) -> Option<Guid> {
        let st = self.state.lock();
        (st.bound.len() == st.path.objects.len() + 1).then(|| *st.bound.last().expect("root"))
    }
}

impl Drop for PathWatch {
    fn drop(&mut self) {
        let subs = {
            let mut st = self.state.lock();
            st.closed = true;
            std::mem::take(&mut st.subs)
        };
        for (id, _) in subs {
            self.ds.unsubscribe(id);
        }
    }
}

/// Drops the subscriptions from level `k` on and binds again from `bound[k]` downwards,
/// as far as the objects exist. Returns events to report.
fn rebuild(ds: &DataServer, me: &Arc<Mutex<State>>, st: &mut State, k: usize) -> Vec<PathEvent> {
    for (id, _) in st.subs.drain(k..) {
        ds.unsubscribe(id);
    }
    st.bound.truncate(k + 1);
    let mut events = Vec::new();
    let mut j = k;
    loop {
        let at = st.bound[j];
        st.generation += 1;
        let generation = st.generation;
        let at_end = j == st.path.objects.len();
        if at_end && st.object_only {
            if st.reported.as_ref().map(|r| r.0) != Some(at) {
                st.reported = Some((at, Value::Bool(true)));
                events.push(PathEvent { kind: Kind::New, object: at, value: None });
            }
            break;
        }
        let topic = if at_end {
            Topic::Properties { object: at, names: Some(vec![st.path.property]) }
        } else {
            Topic::Children { object: at }
        };
        let weak = Arc::downgrade(me);
        let ds2 = ds.clone();
        let sub = ds.subscribe_on(&st.executor.clone(), topic, move |n| {
            if let Some(me) = weak.upgrade() {
                let events = {
                    let mut st = me.lock();
                    on_notification(&ds2, &me, &mut st, j, generation, n)
                };
                emit(&me, events);
            }
        });
        match sub {
            Ok(id) => st.subs.push((id, generation)),
            Err(_) => break, // vanished meanwhile: its parent's watch will tell us
        }
        if at_end {
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
                _ => match st.reported.take() {
                    Some((o, _)) => vec![PathEvent { kind: Kind::Deleted, object: o, value: None }],
                    None => Vec::new(),
                },
            }
        }
        (Subject::Child { guid, name, .. }, false) => {
            let wanted = &*st.path.objects[level];
            let next = st.bound.get(level + 1).copied();
            let matches = &**name == wanted && n.kind != Kind::Deleted;
            match next {
                None if matches => {
                    st.bound.push(*guid);
                    rebuild(ds, me, st, level + 1)
                }
                Some(b) if b == *guid && !matches => {
                    // Our object went away or was renamed: look for another of that name.
                    match ds.find_child(st.bound[level], wanted) {
                        Ok(Some(other)) if other != *guid => {
                            let mut ev = drop_reported(st);
                            st.bound.truncate(level + 1);
                            st.bound.push(other);
                            ev.extend(rebuild(ds, me, st, level + 1));
                            ev
                        }
                        _ => {
                            // Nothing reachable below this level until a matching child
                            // appears (this level's subscription will tell us).
                            for (id, _) in st.subs.drain(level + 1..) {
                                ds.unsubscribe(id);
                            }
                            st.bound.truncate(level + 1);
                            drop_reported(st)
                        }
                    }
                }
                _ => Vec::new(),
            }
        }
        _ => Vec::new(),
    }
}

fn drop_reported(st: &mut State) -> Vec<PathEvent> {
    match st.reported.take() {
        Some((o, _)) => vec![PathEvent { kind: Kind::Deleted, object: o, value: None }],
        None => Vec::new(),
    }
}

fn emit(me: &Arc<Mutex<State>>, events: Vec<PathEvent>) {
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
    for e in &events {
        cb(e);
    }
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
