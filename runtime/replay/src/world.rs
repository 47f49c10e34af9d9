//! Applies recorded world-model changes to a DataServer: the recording's GUIDs mapped to
//! the new server's, the recorded `root.display` left out (the replayed layout draws its
//! own), listeners made listeners again (their receivers left out: the replay's modules
//! join them themselves), and keyframes synchronised in (what the keyframe lacks is
//! deleted).

use crate::message::{ObjectChange, PropertyChange, Snapshot};
use mocu_dataserver::{
    DataServer, Guid, LISTENER_TYPE, ObjectInfo, PropMeta, PropName, RECEIVER_TYPE, Value,
};
use std::collections::{HashMap, HashSet};

/// The root's GUID in every recording.
const ROOT: u64 = 1;

/// The world being replayed into one DataServer.
pub struct World {
    ds: DataServer,
    /// Recorded GUID → this server's.
    map: HashMap<u64, Guid>,
    /// This server's objects in `map` (so that each lookup is one probe, not a pass over
    /// `map`: 300,000 siblings rebuild in linear time).
    taken: HashSet<Guid>,
    /// Recorded objects left out (the recorded display and everything below it).
    skipped: HashSet<u64>,
    /// The properties `/world/values` entries name, by id: (recorded object, name).
    ids: HashMap<u32, (u64, PropName)>,
}

impl World {
    pub fn new(ds: &DataServer) -> World {
        World {
            ds: ds.clone(),
            map: HashMap::new(),
            taken: HashSet::new(),
            skipped: HashSet::new(),
            ids: HashMap::new(),
        }
    }

    /// This server's object for a recorded GUID.
    pub fn object(&self, recorded: u64) -> Option<Guid> {
        if recorded == ROOT { Some(Guid::ROOT) } else { self.map.get(&recorded).copied() }
    }

    /// Applies one `/world/object` change. Changes about unknown objects are skipped.
    pub fn apply_object(&mut self, c: &ObjectChange) {
        match c {
            ObjectChange::Created { guid, parent, index, info } => {
                self.create(*guid, *parent, *index, info);
            }
            ObjectChange::Changed { guid, info, to } => {
                let Some(g) = self.object(*guid) else { return };
                if let Some(info) = info {
                    let _ = self.ds.set_info(g, info.clone());
                }
                if let Some((parent, index)) = to
                    && self.object(*parent).is_none()
                {
                    // Moved where we do not follow (under the recorded display): gone.
                    let _ = index;
                    self.forget(*guid);
                }
            }
            ObjectChange::Deleted { guid } => {
                if let Some(g) = self.object(*guid) {
                    let _ = self.ds.delete_object(g);
                }
                self.forget(*guid);
            }
        }
    }

    /// Applies one `/world/property` change.
    pub fn apply_property(&mut self, c: &PropertyChange) {
        match c {
            PropertyChange::Created { id, object, name, value, meta } => {
                let name = PropName::new(name);
                if let Some(id) = id {
                    self.ids.insert(*id, (*object, name));
                }
                let Some(g) = self.object(*object) else { return };
                let value = self.map_value(value);
                let meta = meta.clone().map(replayed_meta).unwrap_or_default();
                if self.ds.create_property(g, name, value.clone(), meta).is_err() {
                    let _ = self.ds.set(g, name, value);
                }
            }
            PropertyChange::Set { id, object, name, value } => {
                let name = PropName::new(name);
                if let Some(id) = id {
                    self.ids.insert(*id, (*object, name));
                }
                let Some(g) = self.object(*object) else { return };
                let _ = self.ds.set(g, name, self.map_value(value));
            }
            PropertyChange::Deleted { id, object, name } => {
                if let Some(id) = id {
                    self.ids.remove(id);
                }
                let Some(g) = self.object(*object) else { return };
                let _ = self.ds.delete_property(g, PropName::new(name));
            }
        }
    }

    /// Applies one `/world/values` entry: property `id` takes `value`. An id not declared
    /// (on `/world/property` or in a keyframe) is skipped.
    pub fn apply_value(&mut self, id: u32, value: &Value) {
        let Some(&(object, name)) = self.ids.get(&id) else { return };
        let Some(g) = self.object(object) else { return };
        let _ = self.ds.set(g, name, value.clone());
    }

    /// Makes the world what the keyframe says: its objects created or updated, its
    /// properties set, and every replayed object or property it does not have deleted.
    pub fn sync(&mut self, s: &Snapshot) {
        let keep: HashSet<u64> = s.objects.iter().map(|o| o.guid).collect();
        let gone: Vec<u64> = self.map.keys().copied().filter(|g| !keep.contains(g)).collect();
        for g in gone {
            if let Some(x) = self.map.get(&g).copied() {
                let _ = self.ds.delete_object(x);
            }
            self.forget(g);
        }
        self.ids.clear();
        for o in &s.objects {
            for ((name, _, _), id) in o.properties.iter().zip(&o.ids) {
                if let Some(id) = id {
                    self.ids.insert(*id, (o.guid, PropName::new(name)));
                }
            }
            let Some(g) = self.create(o.guid, o.parent, o.index, &o.info) else { continue };
            if self.ds.info(g).is_ok_and(|i| i != o.info) {
                let _ = self.ds.set_info(g, o.info.clone());
            }
            let names: HashSet<&str> = o.properties.iter().map(|p| p.0.as_str()).collect();
            for (n, _) in self.ds.properties(g).unwrap_or_default() {
                if !names.contains(n.as_str()) {
                    let _ = self.ds.delete_property(g, n);
                }
            }
            for (name, value, meta) in &o.properties {
                let value = self.map_value(value);
                let name = PropName::new(name);
                let meta = meta.clone().map(replayed_meta).unwrap_or_default();
                if self.ds.create_property(g, name, value.clone(), meta).is_err() {
                    let _ = self.ds.set(g, name, value);
                }
            }
        }
    }

    /// Creates (or finds: the replay's own modules may have made it already) the object
    /// for a recorded one; `None` when it is left out.
    fn create(&mut self, guid: u64, parent: u64, index: usize, info: &ObjectInfo) -> Option<Guid> {
        if let Some(g) = self.object(guid)
            && self.ds.exists(g)
        {
            return Some(g);
        }
        // A receiver is a listener's join: the replay's own modules join what they show.
        let left_out = self.skipped.contains(&parent)
            || (parent == ROOT && &*info.name == "display")
            || &*info.kind == RECEIVER_TYPE;
        let p = self.object(parent).filter(|_| !left_out);
        let Some(p) = p else {
            self.skipped.insert(guid);
            return None;
        };
        let found = self.ds.find_child(p, &info.name).ok().flatten();
        let g = match found.filter(|f| !self.taken.contains(f)) {
            Some(f) => f,
            // A listener, so that recorded frames can be sent on it again.
            None if &*info.kind == LISTENER_TYPE => self.ds.create_listener(p, &info.name).ok()?,
            None => self.ds.create_object_at(p, index, info.clone()).ok()?,
        };
        if let Some(old) = self.map.insert(guid, g) {
            self.taken.remove(&old);
        }
        self.taken.insert(g);
        Some(g)
    }

    fn forget(&mut self, guid: u64) {
        if let Some(g) = self.map.remove(&guid) {
            self.taken.remove(&g);
        }
        self.skipped.remove(&guid);
        // Descendants of a deleted object go with it; their entries are dropped when a
        // later keyframe or lookup finds them gone.
        let ds = &self.ds;
        let taken = &mut self.taken;
        self.map.retain(|_, g| {
            let keep = ds.exists(*g);
            if !keep {
                taken.remove(g);
            }
            keep
        });
    }

    /// Recorded GUIDs inside a value mapped to this server's (unknown ones kept).
    fn map_value(&self, v: &Value) -> Value {
        match v {
            Value::Guid(g) => Value::Guid(self.object(g.get()).unwrap_or(*g)),
            Value::List(xs) => Value::List(xs.iter().map(|x| self.map_value(x)).collect()),
            Value::Set(xs) => Value::Set(xs.iter().map(|x| self.map_value(x)).collect()),
            other => other.clone(),
        }
    }
}

/// Metadata as replayed: without `rate_hz`. The recording keeps changes, not the writes
/// of equal values (docs/recording.md), so a steady value would look stale after three
/// periods; staleness in a replay comes from the recorded `stale`/`link_lost` properties.
fn replayed_meta(mut m: PropMeta) -> PropMeta {
    m.rate_hz = None;
    m
}
