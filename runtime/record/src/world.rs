//! The recorder's mirror of the world model, kept from the change feed alone: each object's
//! parent, position, names and properties, and its dotted path. It names what a message
//! is about (`root.vehicles.usv1.nav.speed`), numbers each property (the `id` that
//! `/world/values` entries refer to), and is what a `/world/snapshot` keyframe writes, so a
//! keyframe is exactly consistent with the changes before it.

use crate::json;
use mocu_dataserver::{Guid, NumKind, ObjectInfo, PropMeta, PropName, Value};
use std::collections::HashMap;
use std::hash::{BuildHasherDefault, Hasher};
use std::sync::Arc;

pub(crate) struct Obj {
    pub parent: Option<Guid>,
    pub info: ObjectInfo,
    pub path: Arc<str>,
    pub children: Vec<Guid>,
    /// Its properties' ids, in the order they were created.
    pub props: Vec<u32>,
}

/// A property as read from the world when the recording started.
pub(crate) struct Prop {
    pub name: PropName,
    pub value: Value,
    pub meta: Option<Arc<PropMeta>>,
}

/// A property the recording knows, by its id.
pub(crate) struct Slot {
    pub name: PropName,
    pub value: Value,
    pub meta: Option<Arc<PropMeta>>,
}

/// An object as it existed when the recording started, with its properties.
pub(crate) struct Existing {
    pub guid: Guid,
    pub parent: Guid,
    pub index: usize,
    pub info: ObjectInfo,
    pub props: Vec<Prop>,
}

/// The world model as it is now (parents before children, root's properties first as
/// root's entry), read after the feed was opened: a change racing the walk shows in both.
pub(crate) fn walk(ds: &mocu_dataserver::DataServer) -> Vec<Existing> {
    let mut out = Vec::new();
    let props = |g: Guid| -> Vec<Prop> {
        ds.properties(g)
            .unwrap_or_default()
            .into_iter()
            .map(|(name, value)| {
                let meta =
                    ds.meta(g, name).ok().filter(|m| *m != PropMeta::default()).map(Arc::new);
                Prop { name, value, meta }
            })
            .collect()
    };
    out.push(Existing {
        guid: Guid::ROOT,
        parent: Guid::ROOT,
        index: 0,
        info: ObjectInfo::new("root", "root"),
        props: props(Guid::ROOT),
    });
    let mut stack: Vec<(Guid, Guid, usize)> = Vec::new();
    let push = |stack: &mut Vec<(Guid, Guid, usize)>, parent: Guid| {
        let children = ds.children(parent).unwrap_or_default();
        stack.extend(children.into_iter().enumerate().rev().map(|(i, c)| (c, parent, i)));
    };
    push(&mut stack, Guid::ROOT);
    while let Some((g, parent, index)) = stack.pop() {
        let Ok(info) = ds.info(g) else { continue };
        out.push(Existing { guid: g, parent, index, info, props: props(g) });
        push(&mut stack, g);
    }
    out
}

/// A multiply-rotate hash (rustc's FxHash) for the ids map: its keys are small integers
/// the recorder chose or interned, not attacker-controlled, and it is looked up once per
/// change.
#[derive(Default)]
pub(crate) struct Fx(u64);

impl Hasher for Fx {
    fn write(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.write_u64(u64::from(b));
        }
    }

    fn write_u32(&mut self, i: u32) {
        self.write_u64(u64::from(i));
    }

    fn write_u64(&mut self, i: u64) {
        self.0 = (self.0.rotate_left(5) ^ i).wrapping_mul(0x51_7c_c1_b7_27_22_0a_95);
    }

    fn finish(&self) -> u64 {
        self.0
    }
}

pub(crate) struct World {
    objects: HashMap<Guid, Obj>,
    /// Each live property's id (ids are never reused within a recording).
    ids: HashMap<(Guid, PropName), u32, BuildHasherDefault<Fx>>,
    /// By id; `None` once deleted.
    slots: Vec<Option<Slot>>,
}

impl World {
    pub fn new() -> World {
        let root = Obj {
            parent: None,
            info: ObjectInfo::new("root", "root"),
            path: "root".into(),
            children: Vec::new(),
            props: Vec::new(),
        };
        World {
            objects: HashMap::from([(Guid::ROOT, root)]),
            ids: HashMap::default(),
            slots: Vec::new(),
        }
    }

    pub fn get(&self, g: Guid) -> Option<&Obj> {
        self.objects.get(&g)
    }

    /// The object's path, or `#<guid>` for one the feed never showed.
    pub fn path(&self, g: Guid) -> Arc<str> {
        match self.objects.get(&g) {
            Some(o) => o.path.clone(),
            None => format!("#{}", g.get()).into(),
        }
    }

    pub fn create(&mut self, g: Guid, parent: Guid, index: usize, info: ObjectInfo) {
        if self.objects.contains_key(&g) {
            // Already read from the world when the recording started.
            return;
        }
        let path = format!("{}.{}", self.path(parent), info.name).into();
        if let Some(p) = self.objects.get_mut(&parent) {
            let i = index.min(p.children.len());
            p.children.insert(i, g);
        }
        let o = Obj { parent: Some(parent), info, path, children: Vec::new(), props: Vec::new() };
        self.objects.insert(g, o);
    }

    pub fn rename(&mut self, g: Guid, info: ObjectInfo) {
        if let Some(o) = self.objects.get_mut(&g) {
            o.info = info;
        }
        self.repath(g);
    }

    pub fn moved(&mut self, g: Guid, parent: Guid, index: usize) {
        let old = self.objects.get(&g).and_then(|o| o.parent);
        if let Some(p) = old.and_then(|p| self.objects.get_mut(&p)) {
            p.children.retain(|&c| c != g);
        }
        if let Some(p) = self.objects.get_mut(&parent) {
            let i = index.min(p.children.len());
            p.children.insert(i, g);
        }
        if let Some(o) = self.objects.get_mut(&g) {
            o.parent = Some(parent);
        }
        self.repath(g);
    }

    /// `g` and every object under it.
    pub fn subtree(&self, g: Guid) -> Vec<Guid> {
        let mut out = Vec::new();
        let mut stack = vec![g];
        while let Some(x) = stack.pop() {
            if let Some(o) = self.objects.get(&x) {
                out.push(x);
                stack.extend(o.children.iter().copied());
            }
        }
        out
    }

    pub fn delete(&mut self, g: Guid) {
        let parent = self.objects.get(&g).and_then(|o| o.parent);
        if let Some(p) = parent.and_then(|p| self.objects.get_mut(&p)) {
            p.children.retain(|&c| c != g);
        }
        let mut stack = vec![g];
        while let Some(x) = stack.pop() {
            if let Some(o) = self.objects.remove(&x) {
                for id in o.props {
                    if let Some(s) = self.slots.get_mut(id as usize).and_then(Option::take) {
                        self.ids.remove(&(x, s.name));
                    }
                }
                stack.extend(o.children);
            }
        }
    }

    /// Sets a property (`meta`: given on creation, `None` on later writes); returns its id
    /// and whether the recording did not know it before (a new id).
    pub fn set(
        &mut self,
        g: Guid,
        name: PropName,
        value: &Value,
        meta: &Option<Arc<PropMeta>>,
    ) -> (u32, bool) {
        if let Some(&id) = self.ids.get(&(g, name))
            && let Some(Some(s)) = self.slots.get_mut(id as usize)
        {
            s.value = value.clone();
            // A later write carries no metadata (it never changes after creation).
            if meta.is_some() && s.meta.as_ref().map(Arc::as_ptr) != meta.as_ref().map(Arc::as_ptr)
            {
                s.meta = meta.clone();
            }
            return (id, false);
        }
        let id = self.slots.len() as u32;
        self.slots.push(Some(Slot { name, value: value.clone(), meta: meta.clone() }));
        self.ids.insert((g, name), id);
        if let Some(o) = self.objects.get_mut(&g) {
            o.props.push(id);
        }
        (id, true)
    }

    /// A new value of a property the recording knows; its id, or `None` when unknown.
    pub fn update(&mut self, g: Guid, name: PropName, value: &Value) -> Option<u32> {
        let id = *self.ids.get(&(g, name))?;
        let s = self.slots.get_mut(id as usize)?.as_mut()?;
        s.value = value.clone();
        Some(id)
    }

    /// The id of a live property.
    pub fn id(&self, g: Guid, name: PropName) -> Option<u32> {
        self.ids.get(&(g, name)).copied()
    }

    /// A new number of live property `id` (from the feed's numeric lane): in place when
    /// it was a number of that kind already (no value dropped).
    #[inline]
    pub fn set_number(&mut self, id: u32, kind: NumKind, bits: u64) {
        let Some(Some(s)) = self.slots.get_mut(id as usize) else { return };
        match (&mut s.value, kind) {
            (Value::Float(x), NumKind::Float) => *x = f64::from_bits(bits),
            (Value::Int(i), NumKind::Int) => *i = bits as i64,
            (Value::Bool(b), NumKind::Bool) => *b = bits != 0,
            (v, NumKind::Float) => *v = Value::Float(f64::from_bits(bits)),
            (v, NumKind::Int) => *v = Value::Int(bits as i64),
            (v, NumKind::Bool) => *v = Value::Bool(bits != 0),
        }
    }

    /// The metadata of property `id`, as it was created.
    pub fn meta(&self, id: u32) -> Option<&PropMeta> {
        self.slots.get(id as usize)?.as_ref()?.meta.as_deref()
    }

    /// Deletes a property; returns the id it had.
    pub fn delete_property(&mut self, g: Guid, name: PropName) -> Option<u32> {
        let id = self.ids.remove(&(g, name))?;
        if let Some(s) = self.slots.get_mut(id as usize) {
            *s = None;
        }
        if let Some(o) = self.objects.get_mut(&g) {
            o.props.retain(|&p| p != id);
        }
        Some(id)
    }

    /// Recomputes the paths of `g`'s subtree (after a rename or a move).
    fn repath(&mut self, g: Guid) {
        let mut stack = vec![g];
        while let Some(x) = stack.pop() {
            let Some(o) = self.objects.get(&x) else { continue };
            let path: Arc<str> = match o.parent {
                Some(p) => format!("{}.{}", self.path(p), o.info.name).into(),
                None => "root".into(),
            };
            let children = o.children.clone();
            if let Some(o) = self.objects.get_mut(&x) {
                o.path = path;
            }
            stack.extend(children);
        }
    }

    /// The whole world as a `mocu.WorldSnapshot` (parents before children, root left out).
    pub fn snapshot(&self, seq: u64, out: &mut Vec<u8>) {
        out.extend_from_slice(b"{\"seq\":");
        json::uint(out, seq);
        out.extend_from_slice(b",\"objects\":[");
        let mut first = true;
        let mut stack: Vec<Guid> = self
            .objects
            .get(&Guid::ROOT)
            .map(|r| r.children.iter().rev().copied().collect())
            .unwrap_or_default();
        while let Some(g) = stack.pop() {
            let Some(o) = self.objects.get(&g) else { continue };
            if !first {
                out.push(b',');
            }
            first = false;
            let parent = o.parent.unwrap_or(Guid::ROOT);
            let index =
                self.objects.get(&parent).and_then(|p| p.children.iter().position(|&c| c == g));
            out.extend_from_slice(b"{\"guid\":");
            json::uint(out, g.get());
            out.extend_from_slice(b",\"parent\":");
            json::uint(out, parent.get());
            out.extend_from_slice(b",\"index\":");
            json::uint(out, index.unwrap_or(0) as u64);
            info(out, &o.info);
            out.extend_from_slice(b",\"properties\":[");
            let live =
                o.props.iter().filter_map(|&id| Some((id, self.slots.get(id as usize)?.as_ref()?)));
            for (i, (id, p)) in live.enumerate() {
                if i > 0 {
                    out.push(b',');
                }
                out.extend_from_slice(b"{\"id\":");
                json::uint(out, u64::from(id));
                out.extend_from_slice(b",\"name\":");
                json::string(out, p.name.as_str());
                out.extend_from_slice(b",\"kind\":\"");
                out.extend_from_slice(p.value.kind().name().as_bytes());
                out.extend_from_slice(b"\",\"value\":");
                json::value(out, &p.value);
                if let Some(m) = &p.meta {
                    out.extend_from_slice(b",\"meta\":");
                    meta(out, m);
                }
                out.push(b'}');
            }
            out.extend_from_slice(b"]}");
            stack.extend(o.children.iter().rev().copied());
        }
        out.extend_from_slice(b"]}");
    }
}

/// `,"name":…,"type":…,"subtype":…`
pub(crate) fn info(out: &mut Vec<u8>, info: &ObjectInfo) {
    out.extend_from_slice(b",\"name\":");
    json::string(out, &info.name);
    out.extend_from_slice(b",\"type\":");
    json::string(out, &info.kind);
    out.extend_from_slice(b",\"subtype\":");
    json::string(out, &info.subtype);
}

/// A property's metadata, each field only when set.
pub(crate) fn meta(out: &mut Vec<u8>, m: &PropMeta) {
    out.push(b'{');
    let mut first = true;
    let mut key = |out: &mut Vec<u8>, k: &str| {
        if !first {
            out.push(b',');
        }
        first = false;
        json::string(out, k);
        out.push(b':');
    };
    if let Some(k) = m.kind {
        key(out, "kind");
        json::string(out, k.name());
    }
    for (k, v) in [
        ("units", &m.units),
        ("representation", &m.representation),
        ("description", &m.description),
    ] {
        if let Some(v) = v {
            key(out, k);
            json::string(out, v);
        }
    }
    if let Some((min, max)) = m.range {
        key(out, "range");
        out.push(b'[');
        json::float(out, min);
        out.push(b',');
        json::float(out, max);
        out.push(b']');
    }
    if let Some(hz) = m.rate_hz {
        key(out, "rate_hz");
        json::float(out, hz);
    }
    out.push(b'}');
}
