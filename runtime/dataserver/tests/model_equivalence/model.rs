//! The DataServer's documented behaviour as a plain single-threaded model: the tree, the
//! properties, and every notification each subscription is owed.

use mocu_dataserver::{
    DsError, Guid, Kind, Notification, ObjRef, ObjectInfo, PropMeta, PropName, Snapshot, Subject,
    Value, ValueKind,
};
use std::collections::BTreeMap;

pub(crate) struct MObj {
    pub(crate) info: ObjectInfo,
    parent: Option<Guid>,
    pub(crate) children: Vec<Guid>,
    /// In creation order.
    pub(crate) props: Vec<MProp>,
}

pub(crate) struct MProp {
    pub(crate) name: PropName,
    pub(crate) value: Value,
    meta: PropMeta,
}

pub(crate) enum Watch {
    Properties(Option<Vec<PropName>>),
    Children,
}

pub(crate) struct MSub {
    pub(crate) object: Guid,
    pub(crate) watch: Watch,
    pub(crate) live: bool,
    pub(crate) unsubscribed: bool,
    /// Every notification the subscription is owed, uncoalesced.
    pub(crate) expected: Vec<Notification>,
}

impl MSub {
    pub(crate) fn wants(&self, name: PropName) -> bool {
        match &self.watch {
            Watch::Properties(None) => true,
            Watch::Properties(Some(ns)) => ns.contains(&name),
            Watch::Children => false,
        }
    }
}

/// The DataServer's documented behaviour, single-threaded, in plain maps.
pub(crate) struct Model {
    pub(crate) objects: BTreeMap<Guid, MObj>,
    /// GUIDs count up from 2.
    next: u64,
    pub(crate) subs: Vec<MSub>,
}

fn guid(raw: u64) -> Guid {
    Guid::new(raw).expect("non-zero")
}

fn no_such_object(g: Guid) -> DsError {
    DsError::NoSuchObject { object: ObjRef::unnamed(g) }
}

impl Model {
    pub(crate) fn new() -> Model {
        let root = MObj {
            info: ObjectInfo::new("root", "root"),
            parent: None,
            children: Vec::new(),
            props: Vec::new(),
        };
        Model { objects: BTreeMap::from([(Guid::ROOT, root)]), next: 2, subs: Vec::new() }
    }

    // -- choosing operands --

    pub(crate) fn pick(&self, sel: u8) -> Guid {
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
    pub(crate) fn pick_child(&self, parent: Guid, sel: u8) -> Guid {
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

    pub(crate) fn snapshot(&self, g: Guid) -> Snapshot {
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

    pub(crate) fn create_object_at(
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

    pub(crate) fn insert_between(
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

    pub(crate) fn delete_object(&mut self, g: Guid) -> Result<(), DsError> {
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

    pub(crate) fn delete_and_promote(&mut self, g: Guid, keep: Guid) -> Result<(), DsError> {
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

    pub(crate) fn set_info(&mut self, g: Guid, info: ObjectInfo) -> Result<(), DsError> {
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

    pub(crate) fn set(&mut self, g: Guid, name: PropName, value: Value) -> Result<(), DsError> {
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

    pub(crate) fn create_property(
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

    pub(crate) fn update(&mut self, g: Guid, name: PropName, value: Value) -> Result<(), DsError> {
        if !self.obj(g)?.props.iter().any(|p| p.name == name) {
            return Err(DsError::NoSuchProperty { object: self.named(g), property: name });
        }
        self.set(g, name, value)
    }

    pub(crate) fn delete_property(&mut self, g: Guid, name: PropName) -> Result<(), DsError> {
        let Some(i) = self.obj(g)?.props.iter().position(|p| p.name == name) else {
            return Err(DsError::NoSuchProperty { object: self.named(g), property: name });
        };
        self.objects.get_mut(&g).expect("checked").props.remove(i);
        self.notify_prop(g, Kind::Deleted, name, None);
        Ok(())
    }

    pub(crate) fn subscribe(&mut self, g: Guid, watch: Watch) -> Result<usize, DsError> {
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
