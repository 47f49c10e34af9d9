//! Publishing: the shared subtrees of the local world model, from the DataServer's change
//! feed, onto the key space; and the snapshot a late joiner asks for.
//!
//! One thread reads the feed in batches and keeps what it has published (objects,
//! properties, metadata, method lists): equal values are never sent twice, and a snapshot
//! query is answered from that same state on the same thread, so a joiner's snapshot and
//! the updates that follow it are in one order. Objects outside the shared subtrees (and not
//! on the way to one) are not even looked up.

use crate::keys;
use crate::payload::{self, ObjectRecord};
use crate::streams::{TAP_TYPE, Taps};
use crossbeam_channel::Receiver;
use mocu_dataserver::{
    Change, ChangeFeed, DataServer, Guid, LISTENER_TYPE, MethodSpec, ObjectInfo, PropMeta,
    PropName, RECEIVER_TYPE, Value,
};
use std::collections::{HashMap, HashSet};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::time::Duration;
use zenoh::Wait;
use zenoh::qos::CongestionControl;
use zenoh::query::Query;

/// A tracked object: on the way to a shared subtree, or in one (`shared`).
struct Node {
    path: Vec<String>,
    info: ObjectInfo,
    shared: bool,
    children: Vec<Guid>,
    props: Vec<(PropName, Value, Option<Arc<PropMeta>>)>,
    methods: Vec<MethodSpec>,
}

/// Counters a test or the status object reads.
#[derive(Default)]
pub struct PubStats {
    pub puts: AtomicU64,
    pub skipped_equal: AtomicU64,
    pub snapshots: AtomicU64,
    /// Stream messages put on the key space, and those the pace left out.
    pub stream_puts: AtomicU64,
    pub stream_paced: AtomicU64,
}

pub(crate) struct Publisher {
    pub ds: DataServer,
    pub session: zenoh::Session,
    pub site: String,
    /// Shared subtrees, as object paths from the root.
    pub share: Vec<Vec<String>>,
    pub stats: Arc<PubStats>,
    taps: Taps,
    nodes: HashMap<Guid, Node>,
    touched: HashSet<Guid>,
}

impl Publisher {
    pub fn new(
        ds: DataServer,
        session: zenoh::Session,
        site: String,
        share: Vec<Vec<String>>,
        stats: Arc<PubStats>,
        taps: Taps,
    ) -> Publisher {
        Publisher {
            ds,
            session,
            site,
            share,
            stats,
            taps,
            nodes: HashMap::new(),
            touched: HashSet::new(),
        }
    }

    /// Whether `path` is in a shared subtree, and whether it is on the way to one.
    fn relevance(&self, path: &[String]) -> (bool, bool) {
        let shared = self.share.iter().any(|s| path.starts_with(s));
        let on_way = self.share.iter().any(|s| s.starts_with(path));
        (shared, shared || on_way)
    }

    /// Runs until `stop`: the feed (opened before the walk, so nothing falls between) and
    /// the snapshot queries.
    pub fn run(mut self, feed: ChangeFeed, queries: Receiver<Query>, stop: Arc<AtomicBool>) {
        let root = self.ds.root();
        self.nodes.insert(
            root,
            Node {
                path: Vec::new(),
                info: ObjectInfo::new("root", "root"),
                shared: self.share.iter().any(Vec::is_empty),
                children: Vec::new(),
                props: Vec::new(),
                methods: Vec::new(),
            },
        );
        self.adopt_children(root);
        while !stop.load(Ordering::Relaxed) {
            for c in feed.take() {
                self.apply(c.change);
            }
            self.refresh_methods();
            for q in queries.try_iter() {
                self.answer(&q);
            }
            feed.wait(Duration::from_millis(500));
        }
    }

    /// Tracks (and publishes) every relevant child of a tracked object, as it is now.
    fn adopt_children(&mut self, parent: Guid) {
        for c in self.ds.children(parent).unwrap_or_default() {
            if let Ok(info) = self.ds.info(c) {
                self.adopt(c, parent, info);
            }
        }
    }

    fn adopt(&mut self, guid: Guid, parent: Guid, info: ObjectInfo) {
        if self.nodes.contains_key(&guid) {
            return;
        }
        let Some(p) = self.nodes.get(&parent) else { return };
        let mut path = p.path.clone();
        path.push(info.name.to_string());
        let (shared, relevant) = self.relevance(&path);
        // A stream's receivers and this site's taps are local plumbing, never shared.
        let plumbing = matches!(&*info.kind, RECEIVER_TYPE | TAP_TYPE);
        if !relevant || plumbing {
            return;
        }
        if let Some(p) = self.nodes.get_mut(&parent) {
            p.children.push(guid);
        }
        let methods = if shared { self.ds.methods(guid).unwrap_or_default() } else { Vec::new() };
        let listener = shared && &*info.kind == LISTENER_TYPE && self.taps.wanted(&path);
        let tap = listener.then(|| path.clone());
        self.nodes.insert(
            guid,
            Node { path, info, shared, children: Vec::new(), props: Vec::new(), methods },
        );
        if shared {
            self.put_object(guid);
            for (name, value) in self.ds.properties(guid).unwrap_or_default() {
                let meta = self.ds.meta(guid, name).ok().filter(|m| *m != PropMeta::default());
                self.set_prop(guid, name, value, meta.map(Arc::new), true);
            }
        }
        if let Some(path) = tap {
            self.taps.tap(guid, &path);
        }
        self.adopt_children(guid);
    }

    /// Forgets a subtree (its mirror is deleted with the object's key).
    fn retire(&mut self, guid: Guid, announce: bool) {
        let Some(n) = self.nodes.remove(&guid) else { return };
        self.taps.untap(guid);
        if announce && n.shared {
            let key = keys::object(&self.site, &n.path);
            let _ = self.session.delete(key).wait();
        }
        for c in n.children {
            self.retire(c, false);
        }
        for p in self.nodes.values_mut() {
            p.children.retain(|c| *c != guid);
        }
    }

    fn apply(&mut self, change: Change) {
        match change {
            Change::Created { object, parent, info, .. } => self.adopt(object, parent, info),
            Change::Renamed { object, info } => {
                if let Some(parent) = self.tracked_parent(object) {
                    self.retire(object, true);
                    self.adopt(object, parent, info);
                }
            }
            Change::Moved { object, parent, .. } => {
                if self.nodes.contains_key(&object) {
                    self.retire(object, true);
                }
                if let Ok(info) = self.ds.info(object) {
                    self.adopt(object, parent, info);
                }
            }
            Change::Deleted { object } => self.retire(object, true),
            Change::PropertySet { object, name, value, meta, created } => {
                self.set_prop(object, name, value, meta, created)
            }
            Change::PropertyDeleted { object, name } => {
                let Some(n) = self.nodes.get_mut(&object).filter(|n| n.shared) else { return };
                n.props.retain(|(p, _, _)| *p != name);
                let key = keys::property(&self.site, &n.path, name.as_str());
                let _ = self.session.delete(key).wait();
            }
            Change::Called { .. } | Change::Answered { .. } | Change::Sent { .. } => {}
        }
    }

    fn tracked_parent(&self, guid: Guid) -> Option<Guid> {
        self.nodes.iter().find(|(_, n)| n.children.contains(&guid)).map(|(g, _)| *g)
    }

    fn set_prop(
        &mut self,
        guid: Guid,
        name: PropName,
        value: Value,
        meta: Option<Arc<PropMeta>>,
        created: bool,
    ) {
        let Some(n) = self.nodes.get_mut(&guid).filter(|n| n.shared) else { return };
        let send_meta = match n.props.iter_mut().find(|(p, _, _)| *p == name) {
            Some((_, v, m)) => {
                let meta_changed = created && *m != meta;
                if v.total_cmp(&value).is_eq() && v.kind() == value.kind() && !meta_changed {
                    self.stats.skipped_equal.fetch_add(1, Ordering::Relaxed);
                    return;
                }
                *v = value.clone();
                if created {
                    *m = meta.clone();
                }
                meta_changed
            }
            None => {
                n.props.push((name, value.clone(), meta.clone()));
                true
            }
        };
        self.touched.insert(guid);
        let key = keys::property(&self.site, &n.path, name.as_str());
        let m = if send_meta { meta.as_deref() } else { None };
        let bytes = payload::property(guid, &value, m);
        // Blocking, never dropped under congestion: a lost update would leave the mirror
        // showing an old value, as fresh, until the property changes again.
        let put = self.session.put(key, bytes).congestion_control(CongestionControl::Block);
        if put.wait().is_ok() {
            self.stats.puts.fetch_add(1, Ordering::Relaxed);
        }
    }

    fn put_object(&self, guid: Guid) {
        let Some(n) = self.nodes.get(&guid) else { return };
        let rec =
            ObjectRecord { guid: guid.get(), info: n.info.clone(), methods: n.methods.clone() };
        let key = keys::object(&self.site, &n.path);
        let put = self.session.put(key, payload::object(&rec));
        let _ = put.congestion_control(CongestionControl::Block).wait();
    }

    /// Methods are not in the change feed: a shared object whose properties changed in
    /// this batch has its method list compared (names only) and republished if it differs.
    fn refresh_methods(&mut self) {
        for guid in std::mem::take(&mut self.touched) {
            let Ok(now) = self.ds.methods(guid) else { continue };
            let Some(n) = self.nodes.get_mut(&guid) else { continue };
            if payload::method_names(&now) != payload::method_names(&n.methods) {
                n.methods = now;
                self.put_object(guid);
            }
        }
    }

    /// A snapshot: every published object whose key the query's key expression meets
    /// (parents before children), then every published property the same way.
    fn answer(&mut self, q: &Query) {
        self.refresh_all_methods();
        self.stats.snapshots.fetch_add(1, Ordering::Relaxed);
        let ke = q.key_expr().clone();
        let mut order = Vec::new();
        let mut stack = vec![self.ds.root()];
        while let Some(g) = stack.pop() {
            let Some(n) = self.nodes.get(&g) else { continue };
            order.push(g);
            stack.extend(n.children.iter().rev());
        }
        let meets =
            |k: &str| zenoh::key_expr::KeyExpr::try_from(k).is_ok_and(|k| ke.intersects(&k));
        for &g in &order {
            let n = &self.nodes[&g];
            if !n.shared {
                continue;
            }
            let key = keys::object(&self.site, &n.path);
            if meets(&key) {
                let rec = ObjectRecord {
                    guid: g.get(),
                    info: n.info.clone(),
                    methods: n.methods.clone(),
                };
                let _ = q.reply(key, payload::object(&rec)).wait();
            }
        }
        for &g in &order {
            let n = &self.nodes[&g];
            if !n.shared {
                continue;
            }
            for (name, v, m) in &n.props {
                let key = keys::property(&self.site, &n.path, name.as_str());
                if meets(&key) {
                    let _ = q.reply(key, payload::property(g, v, m.as_deref())).wait();
                }
            }
        }
    }

    fn refresh_all_methods(&mut self) {
        let shared: Vec<Guid> =
            self.nodes.iter().filter(|(_, n)| n.shared).map(|(g, _)| *g).collect();
        self.touched.extend(shared);
        self.refresh_methods();
    }
}
