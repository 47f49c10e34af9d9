//! The storage of one object. Each object has its own lock; property writes and reads
//! touch only the object concerned (no global lock on the read or write path).

use crate::hash::IdMap;
use crate::meta::{ObjectInfo, PropMeta};
use crate::method::Method;
use crate::subscription::Sub;
use mocu_value::{Guid, PropName, Value};
use parking_lot::RwLock;
use std::sync::Arc;

pub(crate) struct Object {
    pub(crate) state: RwLock<ObjState>,
}

pub(crate) struct ObjState {
    pub(crate) self_guid: Guid,
    pub(crate) alive: bool,
    pub(crate) info: ObjectInfo,
    pub(crate) parent: Option<Guid>,
    pub(crate) children: Vec<Guid>,
    /// Properties in creation order (small objects dominate: a Vec beats a map below ~16).
    pub(crate) props: PropTable,
    pub(crate) methods: IdMap<PropName, Arc<Method>>,
    /// The serial executor of each ordered method published without one, kept for its
    /// next publication under the same name.
    pub(crate) ordered_executors: IdMap<PropName, crate::executor::Executor>,
    pub(crate) prop_subs: Vec<Arc<Sub>>,
    pub(crate) child_subs: Vec<Arc<Sub>>,
}

pub(crate) struct Prop {
    pub(crate) name: PropName,
    pub(crate) value: Value,
    pub(crate) meta: Option<Arc<PropMeta>>,
    /// When the last write arrived (on the server's clock), changing or not.
    pub(crate) received: std::time::Instant,
    /// Its number in the change feed's numeric lanes (0: not numbered yet).
    pub(crate) number: u32,
}

/// Properties kept in creation order, found by a linear scan while few and through an
/// index once many.
#[derive(Default)]
pub(crate) struct PropTable {
    list: Vec<Prop>,
    index: Option<IdMap<PropName, usize>>,
}

const INDEX_FROM: usize = 12;

impl PropTable {
    pub(crate) fn get(&self, name: PropName) -> Option<&Prop> {
        self.position(name).map(|i| &self.list[i])
    }

    pub(crate) fn get_mut(&mut self, name: PropName) -> Option<&mut Prop> {
        self.position(name).map(|i| &mut self.list[i])
    }

    fn position(&self, name: PropName) -> Option<usize> {
        match &self.index {
            Some(ix) => ix.get(&name).copied(),
            None => self.list.iter().position(|p| p.name == name),
        }
    }

    pub(crate) fn insert(&mut self, prop: Prop) {
        if let Some(ix) = &mut self.index {
            ix.insert(prop.name, self.list.len());
        }
        self.list.push(prop);
        if self.index.is_none() && self.list.len() >= INDEX_FROM {
            self.index = Some(self.list.iter().enumerate().map(|(i, p)| (p.name, i)).collect());
        }
    }

    pub(crate) fn remove(&mut self, name: PropName) -> Option<Prop> {
        let i = self.position(name)?;
        let p = self.list.remove(i);
        if self.index.is_some() {
            self.index = Some(self.list.iter().enumerate().map(|(i, p)| (p.name, i)).collect());
        }
        Some(p)
    }

    pub(crate) fn iter(&self) -> impl Iterator<Item = &Prop> {
        self.list.iter()
    }
}

impl Object {
    pub(crate) fn new(guid: Guid, info: ObjectInfo, parent: Option<Guid>) -> Arc<Object> {
        Arc::new(Object {
            state: RwLock::new(ObjState {
                self_guid: guid,
                alive: true,
                info,
                parent,
                children: Vec::new(),
                props: PropTable::default(),
                methods: IdMap::default(),
                ordered_executors: IdMap::default(),
                prop_subs: Vec::new(),
                child_subs: Vec::new(),
            }),
        })
    }
}
