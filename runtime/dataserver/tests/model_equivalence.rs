//! The DataServer against a plain single-threaded model of it.
//!
//! Random sequences of tree, property and subscription operations run on both. After every
//! operation the trees must be equal, both must have answered the same `Ok`/`Err` (the same
//! typed error, and nothing changed on `Err`). With `quiesce()` after every operation each
//! subscription must have received exactly the model's notifications; without it (and with
//! callbacks held back so that changes pile up and coalesce) each stream must keep the
//! documented guarantees: a coalesced subsequence of the changes, the latest value always
//! delivered, nothing after `Deleted` of the object or after `unsubscribe` returns.

use mocu_dataserver::{
    Config, DataServer, DsError, Executor, Guid, Kind, Notification, ObjRef, ObjectInfo, PropMeta,
    PropName, Snapshot, Subject, SubscriptionId, Topic, Value, ValueKind,
};
use parking_lot::{Condvar, Mutex};
use proptest::prelude::*;
use std::collections::BTreeMap;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};

const PROP_NAMES: [&str; 4] = ["a", "b", "c", "d"];
const OBJ_NAMES: [&str; 3] = ["x", "y", "z"];
const OBJ_KINDS: [&str; 2] = ["robot", "sensor"];

// ----- operations --------------------------------------------------------------------------

/// One operation. Objects, children and subscriptions are chosen by selector bytes that are
/// resolved against the model's state when the operation runs (mostly live objects, now and
/// then a deleted or never-created one).
#[derive(Clone, Debug)]
enum Op {
    Create {
        parent: u8,
        info: ObjectInfo,
    },
    CreateAt {
        parent: u8,
        index: usize,
        info: ObjectInfo,
    },
    InsertBetween {
        parent: u8,
        child: u8,
        info: ObjectInfo,
    },
    Delete {
        obj: u8,
    },
    DeleteAndPromote {
        obj: u8,
        keep: u8,
    },
    SetInfo {
        obj: u8,
        info: ObjectInfo,
    },
    Set {
        obj: u8,
        prop: usize,
        value: Value,
    },
    CreateProperty {
        obj: u8,
        prop: usize,
        value: Value,
        meta: PropMeta,
    },
    Update {
        obj: u8,
        prop: usize,
        value: Value,
    },
    DeleteProperty {
        obj: u8,
        prop: usize,
    },
    SubscribeProperties {
        obj: u8,
        names: Option<Vec<usize>>,
        on: Option<usize>,
    },
    SubscribeChildren {
        obj: u8,
        on: Option<usize>,
    },
    Unsubscribe {
        sub: u8,
    },
    /// Holds every callback back at its next notification, so changes pile up (only in the
    /// variant without quiesce).
    Hold,
    Release,
}

fn info() -> impl Strategy<Value = ObjectInfo> {
    (0..OBJ_NAMES.len(), 0..OBJ_KINDS.len(), any::<bool>()).prop_map(|(n, k, sub)| {
        let i = ObjectInfo::new(OBJ_NAMES[n], OBJ_KINDS[k]);
        if sub { i.subtype("mk2") } else { i }
    })
}

fn value() -> impl Strategy<Value = Value> {
    prop_oneof![
        3 => (-3i64..=3).prop_map(Value::Int),
        2 => prop_oneof![
            Just(0.0),
            Just(-0.0),
            Just(1.5),
            Just(-2.5),
            Just(3.0),
            Just(f64::NAN),
            Just(f64::INFINITY),
        ]
        .prop_map(Value::Float),
        1 => any::<bool>().prop_map(Value::Bool),
        1 => prop_oneof![Just("up"), Just("down")].prop_map(Value::str),
    ]
}

fn meta() -> impl Strategy<Value = PropMeta> {
    let kind = prop::option::of(prop_oneof![
        Just(ValueKind::Int),
        Just(ValueKind::Float),
        Just(ValueKind::Bool),
        Just(ValueKind::String),
    ]);
    let range = prop::option::of(prop_oneof![Just((-2.0, 2.0)), Just((0.0, 3.0))]);
    (kind, range, any::<bool>()).prop_map(|(kind, range, units)| {
        let m = PropMeta { kind, range, ..PropMeta::default() };
        if units { m.units("m/s") } else { m }
    })
}

fn op() -> impl Strategy<Value = Op> {
    let prop = 0..PROP_NAMES.len();
    let on = prop::option::of(0..2usize);
    prop_oneof![
        5 => (any::<u8>(), info()).prop_map(|(parent, info)| Op::Create { parent, info }),
        2 => (any::<u8>(), 0..4usize, info())
            .prop_map(|(parent, index, info)| Op::CreateAt { parent, index, info }),
        2 => (any::<u8>(), any::<u8>(), info())
            .prop_map(|(parent, child, info)| Op::InsertBetween { parent, child, info }),
        2 => any::<u8>().prop_map(|obj| Op::Delete { obj }),
        2 => (any::<u8>(), any::<u8>()).prop_map(|(obj, keep)| Op::DeleteAndPromote { obj, keep }),
        3 => (any::<u8>(), info()).prop_map(|(obj, info)| Op::SetInfo { obj, info }),
        8 => (any::<u8>(), prop.clone(), value())
            .prop_map(|(obj, prop, value)| Op::Set { obj, prop, value }),
        3 => (any::<u8>(), prop.clone(), value(), meta())
            .prop_map(|(obj, prop, value, meta)| Op::CreateProperty { obj, prop, value, meta }),
        4 => (any::<u8>(), prop.clone(), value())
            .prop_map(|(obj, prop, value)| Op::Update { obj, prop, value }),
        2 => (any::<u8>(), prop.clone()).prop_map(|(obj, prop)| Op::DeleteProperty { obj, prop }),
        3 => (any::<u8>(), prop::option::of(prop::collection::vec(prop, 1..3)), on.clone())
            .prop_map(|(obj, names, on)| Op::SubscribeProperties { obj, names, on }),
        3 => (any::<u8>(), on).prop_map(|(obj, on)| Op::SubscribeChildren { obj, on }),
        1 => any::<u8>().prop_map(|sub| Op::Unsubscribe { sub }),
    ]
}

fn op_or_hold() -> impl Strategy<Value = Op> {
    prop_oneof![12 => op(), 2 => Just(Op::Hold), 1 => Just(Op::Release)]
}

// ----- the model ---------------------------------------------------------------------------

struct MObj {
    info: ObjectInfo,
    parent: Option<Guid>,
    children: Vec<Guid>,
    /// In creation order.
    props: Vec<MProp>,
}

struct MProp {
    name: PropName,
    value: Value,
    meta: PropMeta,
}

enum Watch {
    Properties(Option<Vec<PropName>>),
    Children,
}

struct MSub {
    object: Guid,
    watch: Watch,
    live: bool,
    unsubscribed: bool,
    /// Every notification the subscription is owed, uncoalesced.
    expected: Vec<Notification>,
}

impl MSub {
    fn wants(&self, name: PropName) -> bool {
        match &self.watch {
            Watch::Properties(None) => true,
            Watch::Properties(Some(ns)) => ns.contains(&name),
            Watch::Children => false,
        }
    }
}

/// The DataServer's documented behaviour, single-threaded, in plain maps.
struct Model {
    objects: BTreeMap<Guid, MObj>,
    /// GUIDs count up from 2.
    next: u64,
    subs: Vec<MSub>,
}

fn guid(raw: u64) -> Guid {
    Guid::new(raw).expect("non-zero")
}

fn no_such_object(g: Guid) -> DsError {
    DsError::NoSuchObject { object: ObjRef::unnamed(g) }
}

impl Model {
    fn new() -> Model {
        let root = MObj {
            info: ObjectInfo::new("root", "root"),
            parent: None,
            children: Vec::new(),
            props: Vec::new(),
        };
        Model { objects: BTreeMap::from([(Guid::ROOT, root)]), next: 2, subs: Vec::new() }
    }

    // -- choosing operands --

    fn pick(&self, sel: u8) -> Guid {
        if sel % 8 == 7 {
            let mut gone: Vec<Guid> =
                (2..self.next).map(guid).filter(|g| !self.objects.contains_key(g)).collect();
            gone.push(guid(self.next + 7));
            gone[(sel / 8) as usize % gone.len()]
        } else {
            let alive: Vec<Guid> = self.objects.keys().copied().collect();
            alive[sel as usize % alive.len()]
        }
    }

    /// Mostly a real child of `parent`.
    fn pick_child(&self, parent: Guid, sel: u8) -> Guid {
        match self.objects.get(&parent) {
            Some(p) if sel % 4 != 3 && !p.children.is_empty() => {
                p.children[(sel / 4) as usize % p.children.len()]
            }
            _ => self.pick(sel),
        }
    }

    // -- reading --

    fn named(&self, g: Guid) -> ObjRef {
        match self.objects.get(&g) {
            Some(o) => ObjRef { guid: g, name: Some(o.info.name.clone()) },
            None => ObjRef::unnamed(g),
        }
    }

    fn obj(&self, g: Guid) -> Result<&MObj, DsError> {
        self.objects.get(&g).ok_or_else(|| no_such_object(g))
    }

    fn snapshot(&self, g: Guid) -> Snapshot {
        let o = &self.objects[&g];
        Snapshot {
            guid: g,
            name: o.info.name.to_string(),
            kind: o.info.kind.to_string(),
            subtype: o.info.subtype.to_string(),
            properties: o.props.iter().map(|p| (p.name.to_string(), p.value.clone())).collect(),
            methods: Vec::new(),
            children: o.children.iter().map(|c| self.snapshot(*c)).collect(),
        }
    }

    // -- notifying --

    fn notify_prop(&mut self, g: Guid, kind: Kind, name: PropName, value: Option<Value>) {
        for s in self.subs.iter_mut().filter(|s| s.live && s.object == g && s.wants(name)) {
            let subject = Subject::Property { name, value: value.clone() };
            s.expected.push(Notification { object: g, kind, subject });
        }
    }

    fn notify_child(&mut self, parent: Guid, kind: Kind, child: Guid, index: usize) {
        let n = child_note(parent, kind, child, &self.objects[&child].info, index);
        self.notify_child_note(n);
    }

    fn notify_child_note(&mut self, n: Notification) {
        let parent = n.object;
        let watchers = self.subs.iter_mut().filter(|s| s.live && s.object == parent);
        for s in watchers.filter(|s| matches!(s.watch, Watch::Children)) {
            s.expected.push(n.clone());
        }
    }

    /// Removes the subtree at `g` (already unlinked from its parent), parents first; every
    /// subscription on it ends with `Object` deleted.
    fn kill_subtree(&mut self, g: Guid) {
        let o = self.objects.remove(&g).expect("killing a live object");
        for s in self.subs.iter_mut().filter(|s| s.live && s.object == g) {
            s.expected.push(Notification {
                object: g,
                kind: Kind::Deleted,
                subject: Subject::Object,
            });
            s.live = false;
        }
        for c in o.children {
            self.kill_subtree(c);
        }
    }

    // -- the operations --

    fn create_object_at(
        &mut self,
        parent: Guid,
        index: usize,
        info: ObjectInfo,
    ) -> Result<Guid, DsError> {
        self.obj(parent)?;
        let g = guid(self.next);
        self.next += 1;
        self.objects.insert(
            g,
            MObj { info, parent: Some(parent), children: Vec::new(), props: Vec::new() },
        );
        let siblings = &mut self.objects.get_mut(&parent).expect("checked").children;
        let index = index.min(siblings.len());
        siblings.insert(index, g);
        self.notify_child(parent, Kind::New, g, index);
        Ok(g)
    }

    fn insert_between(
        &mut self,
        parent: Guid,
        child: Guid,
        info: ObjectInfo,
    ) -> Result<Guid, DsError> {
        self.obj(parent)?;
        self.obj(child)?;
        let Some(index) = self.objects[&parent].children.iter().position(|&c| c == child) else {
            return Err(DsError::NotAChild {
                parent: self.named(parent),
                child: self.named(child),
            });
        };
        let g = guid(self.next);
        self.next += 1;
        self.objects.insert(
            g,
            MObj { info, parent: Some(parent), children: vec![child], props: Vec::new() },
        );
        self.objects.get_mut(&child).expect("checked").parent = Some(g);
        self.objects.get_mut(&parent).expect("checked").children[index] = g;
        self.notify_child(parent, Kind::Deleted, child, index);
        self.notify_child(parent, Kind::New, g, index);
        Ok(g)
    }

    fn delete_object(&mut self, g: Guid) -> Result<(), DsError> {
        if g == Guid::ROOT {
            return Err(DsError::RootIsPermanent);
        }
        let parent = self.obj(g)?.parent.expect("only the root has no parent");
        let index = self.objects[&parent].children.iter().position(|&c| c == g).expect("linked");
        self.notify_child(parent, Kind::Deleted, g, index);
        self.objects.get_mut(&parent).expect("linked").children.remove(index);
        self.kill_subtree(g);
        Ok(())
    }

    fn delete_and_promote(&mut self, g: Guid, keep: Guid) -> Result<(), DsError> {
        if g == Guid::ROOT {
            return Err(DsError::RootIsPermanent);
        }
        self.obj(g)?;
        self.obj(keep)?;
        let Some(kidx) = self.objects[&g].children.iter().position(|&c| c == keep) else {
            return Err(DsError::NotAChild { parent: self.named(g), child: self.named(keep) });
        };
        let parent = self.objects[&g].parent.expect("not the root");
        self.notify_child(g, Kind::Deleted, keep, kidx);
        self.objects.get_mut(&g).expect("checked").children.remove(kidx);
        self.objects.get_mut(&keep).expect("checked").parent = Some(parent);
        let index = self.objects[&parent].children.iter().position(|&c| c == g).expect("linked");
        self.notify_child(parent, Kind::Deleted, g, index);
        self.objects.get_mut(&parent).expect("linked").children[index] = keep;
        self.notify_child(parent, Kind::New, keep, index);
        self.kill_subtree(g);
        Ok(())
    }

    fn set_info(&mut self, g: Guid, info: ObjectInfo) -> Result<(), DsError> {
        if g == Guid::ROOT {
            return Err(DsError::RootIsPermanent);
        }
        let o = self.obj(g)?;
        if o.info == info {
            return Ok(());
        }
        let parent = o.parent.expect("not the root");
        self.objects.get_mut(&g).expect("checked").info = info;
        let index = self.objects[&parent].children.iter().position(|&c| c == g).expect("linked");
        self.notify_child(parent, Kind::Changed, g, index);
        Ok(())
    }

    fn validate(
        &self,
        g: Guid,
        name: PropName,
        meta: &PropMeta,
        value: Value,
    ) -> Result<Value, DsError> {
        let object = self.named(g);
        let value = match (meta.kind, value) {
            (None, v) => v,
            (Some(ValueKind::Float), Value::Int(i)) => Value::Float(i as f64),
            (Some(k), v) if v.kind() == k => v,
            (Some(k), v) => {
                return Err(DsError::TypeMismatch {
                    object,
                    property: name,
                    expected: k,
                    got: v.kind(),
                });
            }
        };
        if let (Some((min, max)), Some(x)) = (meta.range, value.as_f64())
            && !(min <= x && x <= max)
        {
            return Err(DsError::OutOfRange { object, property: name, value: x, min, max });
        }
        Ok(value)
    }

    fn add_prop(&mut self, g: Guid, name: PropName, value: Value, meta: PropMeta) {
        let o = self.objects.get_mut(&g).expect("checked");
        o.props.push(MProp { name, value: value.clone(), meta });
        self.notify_prop(g, Kind::New, name, Some(value));
    }

    fn set(&mut self, g: Guid, name: PropName, value: Value) -> Result<(), DsError> {
        let o = self.obj(g)?;
        let Some(i) = o.props.iter().position(|p| p.name == name) else {
            self.add_prop(g, name, value, PropMeta::default());
            return Ok(());
        };
        let value = self.validate(g, name, &o.props[i].meta, value)?;
        let p = &mut self.objects.get_mut(&g).expect("checked").props[i];
        if p.value == value {
            return Ok(());
        }
        p.value = value.clone();
        self.notify_prop(g, Kind::Changed, name, Some(value));
        Ok(())
    }

    fn create_property(
        &mut self,
        g: Guid,
        name: PropName,
        value: Value,
        meta: PropMeta,
    ) -> Result<(), DsError> {
        let o = self.obj(g)?;
        if o.props.iter().any(|p| p.name == name) {
            return Err(DsError::PropertyExists { object: self.named(g), property: name });
        }
        let value = self.validate(g, name, &meta, value)?;
        self.add_prop(g, name, value, meta);
        Ok(())
    }

    fn update(&mut self, g: Guid, name: PropName, value: Value) -> Result<(), DsError> {
        if !self.obj(g)?.props.iter().any(|p| p.name == name) {
            return Err(DsError::NoSuchProperty { object: self.named(g), property: name });
        }
        self.set(g, name, value)
    }

    fn delete_property(&mut self, g: Guid, name: PropName) -> Result<(), DsError> {
        let Some(i) = self.obj(g)?.props.iter().position(|p| p.name == name) else {
            return Err(DsError::NoSuchProperty { object: self.named(g), property: name });
        };
        self.objects.get_mut(&g).expect("checked").props.remove(i);
        self.notify_prop(g, Kind::Deleted, name, None);
        Ok(())
    }

    fn subscribe(&mut self, g: Guid, watch: Watch) -> Result<usize, DsError> {
        let o = self.obj(g)?;
        let mut sub =
            MSub { object: g, watch, live: true, unsubscribed: false, expected: Vec::new() };
        match &sub.watch {
            Watch::Properties(_) => {
                let wanted: Vec<&MProp> = o.props.iter().filter(|p| sub.wants(p.name)).collect();
                for p in wanted {
                    let subject = Subject::Property { name: p.name, value: Some(p.value.clone()) };
                    sub.expected.push(Notification { object: g, kind: Kind::New, subject });
                }
            }
            Watch::Children => {
                for (i, c) in o.children.iter().enumerate() {
                    sub.expected.push(child_note(g, Kind::New, *c, &self.objects[c].info, i));
                }
            }
        }
        self.subs.push(sub);
        Ok(self.subs.len() - 1)
    }
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

// ----- the harness -------------------------------------------------------------------------

/// Holds callbacks back while closed.
#[derive(Default)]
struct Gate {
    closed: Mutex<bool>,
    open: Condvar,
}

impl Gate {
    fn set_closed(&self, closed: bool) {
        *self.closed.lock() = closed;
        self.open.notify_all();
    }

    fn pass(&self) {
        let mut c = self.closed.lock();
        while *c {
            self.open.wait(&mut c);
        }
    }
}

/// What one real subscription received, and the broken rules its callback saw.
struct Watcher {
    id: SubscriptionId,
    received: Arc<Mutex<Vec<Notification>>>,
    /// Set right after `unsubscribe` returned.
    ended: Arc<AtomicBool>,
    violations: Arc<Mutex<Vec<String>>>,
}

struct Harness {
    ds: DataServer,
    model: Model,
    /// Parallel to `model.subs`.
    watchers: Vec<Watcher>,
    executors: [Executor; 2],
    gate: Arc<Gate>,
    quiesce_each: bool,
}

impl Drop for Harness {
    fn drop(&mut self) {
        // A failed case must not leave workers parked in a callback.
        self.gate.set_closed(false);
    }
}

/// An operation's answer, comparable across the two implementations (`Debug` text, so a
/// NaN in `OutOfRange` compares equal to itself).
fn answer<T: std::fmt::Debug>(r: &Result<T, DsError>) -> String {
    format!("{r:?}")
}

impl Harness {
    fn new(quiesce_each: bool) -> Harness {
        let ds = DataServer::new(Config { workers: 2 });
        let executors = [ds.serial_executor(), ds.serial_executor()];
        Harness {
            ds,
            model: Model::new(),
            watchers: Vec::new(),
            executors,
            gate: Arc::default(),
            quiesce_each,
        }
    }

    fn run(&mut self, ops: &[Op]) {
        for (step, op) in ops.iter().enumerate() {
            let before = self.ds.snapshot(Guid::ROOT).expect("the root exists");
            let (real, modelled) = self.apply(op);
            assert_eq!(real, modelled, "step {step}: {op:?} answered differently");
            let after = self.ds.snapshot(Guid::ROOT).expect("the root exists");
            if real.starts_with("Err") {
                assert_eq!(after, before, "step {step}: refused {op:?} changed the tree");
            }
            assert_eq!(
                after,
                self.model.snapshot(Guid::ROOT),
                "step {step}: trees differ after {op:?}"
            );
            if self.quiesce_each {
                self.ds.quiesce();
                for (i, (w, s)) in self.watchers.iter().zip(&self.model.subs).enumerate() {
                    assert_eq!(
                        *w.received.lock(),
                        s.expected,
                        "step {step}: subscription {i} on {:?} after {op:?}",
                        s.object
                    );
                }
            }
        }
        self.gate.set_closed(false);
        self.ds.quiesce();
        for (i, (w, s)) in self.watchers.iter().zip(&self.model.subs).enumerate() {
            let violations = w.violations.lock();
            assert!(violations.is_empty(), "subscription {i}: {violations:?}");
            let received = w.received.lock();
            if self.quiesce_each {
                assert_eq!(*received, s.expected, "subscription {i} at the end");
            } else {
                check_stream(i, &received, s, &self.model);
            }
        }
    }

    /// Runs one operation on both; returns both answers.
    fn apply(&mut self, op: &Op) -> (String, String) {
        let (ds, m) = (&self.ds, &mut self.model);
        let name = |i: usize| PropName::new(PROP_NAMES[i]);
        match op.clone() {
            Op::Create { parent, info } => {
                let p = m.pick(parent);
                (
                    answer(&ds.create_object(p, info.clone())),
                    answer(&m.create_object_at(p, usize::MAX, info)),
                )
            }
            Op::CreateAt { parent, index, info } => {
                let p = m.pick(parent);
                (
                    answer(&ds.create_object_at(p, index, info.clone())),
                    answer(&m.create_object_at(p, index, info)),
                )
            }
            Op::InsertBetween { parent, child, info } => {
                let p = m.pick(parent);
                let c = m.pick_child(p, child);
                (
                    answer(&ds.insert_between(p, c, info.clone())),
                    answer(&m.insert_between(p, c, info)),
                )
            }
            Op::Delete { obj } => {
                let g = m.pick(obj);
                (answer(&ds.delete_object(g)), answer(&m.delete_object(g)))
            }
            Op::DeleteAndPromote { obj, keep } => {
                let g = m.pick(obj);
                let k = m.pick_child(g, keep);
                (answer(&ds.delete_and_promote(g, k)), answer(&m.delete_and_promote(g, k)))
            }
            Op::SetInfo { obj, info } => {
                let g = m.pick(obj);
                (answer(&ds.set_info(g, info.clone())), answer(&m.set_info(g, info)))
            }
            Op::Set { obj, prop, value } => {
                let g = m.pick(obj);
                (
                    answer(&ds.set(g, name(prop), value.clone())),
                    answer(&m.set(g, name(prop), value)),
                )
            }
            Op::CreateProperty { obj, prop, value, meta } => {
                let g = m.pick(obj);
                let real = ds.create_property(g, name(prop), value.clone(), meta.clone());
                (answer(&real), answer(&m.create_property(g, name(prop), value, meta)))
            }
            Op::Update { obj, prop, value } => {
                let g = m.pick(obj);
                (
                    answer(&ds.update(g, name(prop), value.clone())),
                    answer(&m.update(g, name(prop), value)),
                )
            }
            Op::DeleteProperty { obj, prop } => {
                let g = m.pick(obj);
                (
                    answer(&ds.delete_property(g, name(prop))),
                    answer(&m.delete_property(g, name(prop))),
                )
            }
            Op::SubscribeProperties { obj, names, on } => {
                let g = m.pick(obj);
                let names: Option<Vec<PropName>> =
                    names.map(|ns| ns.into_iter().map(name).collect());
                let topic = Topic::Properties { object: g, names: names.clone() };
                self.subscribe(topic, Watch::Properties(names), on)
            }
            Op::SubscribeChildren { obj, on } => {
                let g = m.pick(obj);
                self.subscribe(Topic::children(g), Watch::Children, on)
            }
            Op::Unsubscribe { sub } => {
                if !self.watchers.is_empty() {
                    let i = sub as usize % self.watchers.len();
                    // Unsubscribing waits for a running callback: let held ones finish.
                    let held = std::mem::replace(&mut *self.gate.closed.lock(), false);
                    self.gate.open.notify_all();
                    self.ds.unsubscribe(self.watchers[i].id);
                    self.watchers[i].ended.store(true, Ordering::SeqCst);
                    self.model.subs[i].live = false;
                    self.model.subs[i].unsubscribed = true;
                    self.gate.set_closed(held);
                }
                ("unsubscribed".into(), "unsubscribed".into())
            }
            Op::Hold => {
                self.gate.set_closed(!self.quiesce_each);
                ("held".into(), "held".into())
            }
            Op::Release => {
                self.gate.set_closed(false);
                ("released".into(), "released".into())
            }
        }
    }

    fn subscribe(&mut self, topic: Topic, watch: Watch, on: Option<usize>) -> (String, String) {
        let object = topic.object();
        let received = Arc::new(Mutex::new(Vec::new()));
        let ended = Arc::new(AtomicBool::new(false));
        let violations = Arc::new(Mutex::new(Vec::new()));
        let callback = {
            let (received, ended, violations) =
                (received.clone(), ended.clone(), violations.clone());
            let gate = self.gate.clone();
            move |n: &Notification| {
                gate.pass();
                if ended.load(Ordering::SeqCst) {
                    violations.lock().push(format!("{n:?} after unsubscribe returned"));
                }
                let mut r = received.lock();
                if r.last().is_some_and(|l: &Notification| l.subject == Subject::Object) {
                    violations.lock().push(format!("{n:?} after the object's Deleted"));
                }
                r.push(n.clone());
            }
        };
        let real = match on {
            Some(e) => self.ds.subscribe_on(&self.executors[e], topic, callback),
            None => self.ds.subscribe(topic, callback),
        };
        let modelled = self.model.subscribe(object, watch);
        let answers = (answer(&real.clone().map(|_| ())), answer(&modelled.clone().map(|_| ())));
        if let (Ok(id), Ok(_)) = (real, modelled) {
            self.watchers.push(Watcher { id, received, ended, violations });
        }
        answers
    }
}

// ----- the guarantees of a coalesced stream -------------------------------------------------

fn coalescable(n: &Notification) -> bool {
    matches!(n.kind, Kind::New | Kind::Changed) && !matches!(n.subject, Subject::Object)
}

/// `received` must be `expected` with some New/Changed entries left out (superseded by a
/// later one of the same key; a coalesced entry may keep the New-ness of the one it
/// replaced). A subscription ended by `unsubscribe` may also miss any tail.
fn check_stream(i: usize, received: &[Notification], s: &MSub, m: &Model) {
    // Unsubscribing may cut off any tail, even the object's pending Deleted.
    let ended_by_unsubscribe = s.unsubscribed;
    let mut e = 0;
    for (k, r) in received.iter().enumerate() {
        loop {
            let Some(x) = s.expected.get(e) else {
                panic!(
                    "subscription {i}: received #{k} {r:?} is not in the change order\n\
                     received: {received:#?}\nexpected: {:#?}",
                    s.expected
                );
            };
            e += 1;
            let same_kind = r.kind == x.kind || (r.kind == Kind::New && x.kind == Kind::Changed);
            if r.object == x.object && r.subject == x.subject && same_kind {
                break;
            }
            assert!(
                coalescable(x),
                "subscription {i}: {x:?} was never delivered\nreceived: {received:#?}\nexpected: {:#?}",
                s.expected
            );
        }
    }
    if !ended_by_unsubscribe {
        let lost: Vec<_> = s.expected[e..].iter().filter(|x| !coalescable(x)).collect();
        assert!(lost.is_empty(), "subscription {i}: never delivered {lost:?}");
    }
    if s.live {
        check_replica(i, received, s, m);
    }
}

/// Applying the stream to an empty replica gives the object's state now.
fn check_replica(i: usize, received: &[Notification], s: &MSub, m: &Model) {
    let o = &m.objects[&s.object];
    match s.watch {
        Watch::Properties(_) => {
            let mut replica = BTreeMap::new();
            for n in received {
                match (&n.subject, n.kind) {
                    (Subject::Property { name, value: Some(v) }, Kind::New | Kind::Changed) => {
                        replica.insert(*name, v.clone());
                    }
                    (Subject::Property { name, value: None }, Kind::Deleted) => {
                        assert!(
                            replica.remove(name).is_some(),
                            "subscription {i}: {n:?} of an unknown property"
                        );
                    }
                    _ => panic!("subscription {i}: unexpected {n:?}"),
                }
            }
            let now: BTreeMap<PropName, Value> = o
                .props
                .iter()
                .filter(|p| s.wants(p.name))
                .map(|p| (p.name, p.value.clone()))
                .collect();
            assert_eq!(replica, now, "subscription {i}: the replica is not the final state");
        }
        Watch::Children => {
            let mut replica: Vec<(Guid, Arc<str>, Arc<str>)> = Vec::new();
            for n in received {
                let Subject::Child { guid, name, kind, index } = &n.subject else {
                    panic!("subscription {i}: unexpected {n:?}");
                };
                let entry = (*guid, name.clone(), kind.clone());
                match n.kind {
                    Kind::New => {
                        assert!(
                            *index <= replica.len(),
                            "subscription {i}: {n:?} past the end of {replica:?}"
                        );
                        replica.insert(*index, entry);
                    }
                    Kind::Changed | Kind::Deleted => {
                        assert!(
                            replica.get(*index).is_some_and(|r| r.0 == *guid),
                            "subscription {i}: {n:?} does not match {replica:?}"
                        );
                        if n.kind == Kind::Changed {
                            replica[*index] = entry;
                        } else {
                            replica.remove(*index);
                        }
                    }
                }
            }
            let now: Vec<_> = o
                .children
                .iter()
                .map(|c| (*c, m.objects[c].info.name.clone(), m.objects[c].info.kind.clone()))
                .collect();
            assert_eq!(replica, now, "subscription {i}: the replica is not the final state");
        }
    }
}

// ----- the properties ------------------------------------------------------------------------

proptest! {
    #![proptest_config(ProptestConfig { cases: 128, failure_persistence: None, ..ProptestConfig::default() })]

    #[test]
    fn quiesced_server_matches_the_model_notification_for_notification(
        ops in prop::collection::vec(op(), 1..40)
    ) {
        Harness::new(true).run(&ops);
    }

    #[test]
    fn unquiesced_streams_are_coalesced_subsequences_ending_in_the_final_state(
        ops in prop::collection::vec(op_or_hold(), 1..40)
    ) {
        Harness::new(false).run(&ops);
    }
}

// ----- fixed cases -------------------------------------------------------------------------

/// A callback held back at its first notification makes everything after it pile up.
fn held_children_subscription(
    ds: &DataServer,
    parent: Guid,
) -> (Arc<Mutex<Vec<Notification>>>, crossbeam_channel::Sender<()>) {
    let log = Arc::new(Mutex::new(Vec::new()));
    let (release, wait) = crossbeam_channel::unbounded::<()>();
    let (entered_tx, entered) = crossbeam_channel::bounded::<()>(1);
    let l = log.clone();
    let mut first = true;
    ds.subscribe(Topic::children(parent), move |n| {
        if std::mem::take(&mut first) {
            let _ = entered_tx.send(());
            let _ = wait.recv();
        }
        l.lock().push(n.clone());
    })
    .unwrap();
    entered.recv().expect("the first notification arrives");
    (log, release)
}

#[test]
fn child_positions_stay_valid_when_a_rename_coalesces_into_a_pending_new() {
    let ds = DataServer::new(Config { workers: 2 });
    let p = ds.create_object(Guid::ROOT, ObjectInfo::new("p", "group")).unwrap();
    let x = ds.create_object(p, ObjectInfo::new("x", "robot")).unwrap();
    let (log, release) = held_children_subscription(&ds, p);
    // While the subscriber is busy with x: a arrives first, then b between a and x, then a
    // is renamed (a Changed that coalesces with a's pending New).
    let a = ds.create_object_at(p, 0, ObjectInfo::new("a", "robot")).unwrap();
    let b = ds.create_object_at(p, 1, ObjectInfo::new("b", "robot")).unwrap();
    ds.set_info(a, ObjectInfo::new("a2", "robot")).unwrap();
    release.send(()).unwrap();
    ds.quiesce();
    let mut replica: Vec<Guid> = Vec::new();
    for n in log.lock().iter() {
        let Subject::Child { guid, index, .. } = n.subject else { unreachable!() };
        match n.kind {
            Kind::New => replica.insert(index.min(replica.len()), guid),
            Kind::Changed => assert_eq!(replica[index], guid, "{n:?}"),
            Kind::Deleted => assert_eq!(replica.remove(index), guid, "{n:?}"),
        }
    }
    assert_eq!(
        replica,
        vec![a, b, x],
        "the subscriber's order is not the tree's: {:#?}",
        log.lock()
    );
}

#[test]
fn unsubscribe_stops_delivery_even_after_the_object_was_deleted() {
    let ds = DataServer::new(Config { workers: 2 });
    let o = ds.create_object(Guid::ROOT, ObjectInfo::new("o", "robot")).unwrap();
    ds.set(o, "speed", Value::Int(1)).unwrap();
    // The subscription's executor is busy, so its notifications wait in its queue.
    let ex = ds.serial_executor();
    let (release, wait) = crossbeam_channel::bounded::<()>(0);
    ex.spawn(move || {
        let _ = wait.recv();
    });
    let ended = Arc::new(AtomicBool::new(false));
    let late = Arc::new(Mutex::new(Vec::new()));
    let (e, l) = (ended.clone(), late.clone());
    let id = ds
        .subscribe_on(&ex, Topic::properties(o), move |n| {
            if e.load(Ordering::SeqCst) {
                l.lock().push(n.clone());
            }
        })
        .unwrap();
    ds.delete_object(o).unwrap();
    ds.unsubscribe(id);
    ended.store(true, Ordering::SeqCst);
    release.send(()).unwrap();
    ds.quiesce();
    assert_eq!(*late.lock(), vec![], "delivered after unsubscribe returned");
    assert_eq!(ds.subscription_count(), 0);
}

#[test]
fn a_deleted_objects_subscriptions_leave_the_registry_once_told() {
    let ds = DataServer::new(Config { workers: 2 });
    let o = ds.create_object(Guid::ROOT, ObjectInfo::new("o", "robot")).unwrap();
    let c = ds.create_object(o, ObjectInfo::new("c", "robot")).unwrap();
    for g in [o, c] {
        ds.subscribe(Topic::properties(g), |_| {}).unwrap();
        ds.subscribe(Topic::children(g), |_| {}).unwrap();
    }
    ds.delete_object(o).unwrap();
    ds.quiesce();
    assert_eq!(ds.subscription_count(), 0);
}
