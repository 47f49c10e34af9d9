//! Mirroring: other sites' shared subtrees written into the local world model through the
//! DataServer's API, as a protocol module writes its vehicles.
//!
//! One thread applies everything in arrival order (samples, snapshot replies, liveliness),
//! so the order per object is the publisher's. A site that appears (liveliness) is asked
//! for its snapshot; objects it no longer has are deleted when the snapshot is complete, the
//! others are found again by path: a returning site never leaves duplicates. A site that
//! disappears has its objects' `stale` and `link_lost` flags raised (the display's stale
//! veil, docs/display.md) until its snapshot lowers them again.

use crate::calls::CallJob;
use crate::keys::{self, Key};
use crate::payload;
use crossbeam_channel::{Receiver, Sender};
use mocu_dataserver::{
    Call, DataServer, Guid, LISTENER_TYPE, ObjectInfo, PropMeta, PropName, Value,
};
use parking_lot::{Condvar, Mutex};
use std::collections::{HashMap, HashSet};
use std::sync::Arc;
use std::sync::atomic::{AtomicU64, Ordering};
use zenoh::Wait;
use zenoh::query::ConsolidationMode;

/// What reaches the mirror thread.
pub(crate) enum Inbound {
    Sample { key: String, put: bool, bytes: Vec<u8> },
    Alive { site: String, up: bool },
    SnapshotDone { site: String, generation: u64 },
    Stop,
}

#[derive(Default)]
pub struct MirrorStats {
    pub applied: AtomicU64,
    pub malformed: AtomicU64,
    pub snapshots: AtomicU64,
}

/// Snapshots completed so far (a joiner waits on it).
#[derive(Default)]
pub(crate) struct Joined {
    pub count: Mutex<u64>,
    pub cv: Condvar,
}

struct Mirrored {
    local: Guid,
    owned: bool,
}

#[derive(Default)]
struct Site {
    alive: bool,
    generation: u64,
    pending: u32,
    objects: HashMap<Vec<String>, Mirrored>,
    /// The site's GUIDs of the objects mirrored here: a `guid` value is translated.
    guids: HashMap<u64, Guid>,
    confirmed: Option<HashSet<Vec<String>>>,
}

pub(crate) struct Mirror {
    pub ds: DataServer,
    pub session: zenoh::Session,
    pub me: String,
    pub tx: Sender<Inbound>,
    pub calls: Sender<CallJob>,
    pub stats: Arc<MirrorStats>,
    pub joined: Arc<Joined>,
    pub status: Option<Guid>,
    pub notify: Option<crate::Notify>,
    sites: HashMap<String, Site>,
}

impl Mirror {
    #[allow(clippy::too_many_arguments)]
    pub fn new(
        ds: DataServer,
        session: zenoh::Session,
        me: String,
        tx: Sender<Inbound>,
        calls: Sender<CallJob>,
        stats: Arc<MirrorStats>,
        joined: Arc<Joined>,
        status: Option<Guid>,
    ) -> Mirror {
        Mirror {
            ds,
            session,
            me,
            tx,
            calls,
            stats,
            joined,
            status,
            notify: None,
            sites: HashMap::new(),
        }
    }

    pub fn run(mut self, rx: Receiver<Inbound>) {
        for msg in rx.iter() {
            match msg {
                Inbound::Stop => break,
                Inbound::Sample { key, put, bytes } => {
                    if let Err(e) = self.sample(&key, put, &bytes) {
                        let n = self.stats.malformed.fetch_add(1, Ordering::Relaxed) + 1;
                        let (ds, notify) = (&self.ds, self.notify.as_ref());
                        crate::security::report_malformed(ds, self.status, notify, n, &key, &e.0);
                    } else {
                        self.stats.applied.fetch_add(1, Ordering::Relaxed);
                    }
                }
                Inbound::Alive { site, up } if site != self.me => {
                    if up {
                        self.site_up(&site)
                    } else {
                        self.site_down(&site)
                    }
                }
                Inbound::Alive { .. } => {}
                Inbound::SnapshotDone { site, generation } => self.snapshot_done(&site, generation),
            }
        }
    }

    fn sample(&mut self, key: &str, put: bool, bytes: &[u8]) -> Result<(), payload::Malformed> {
        // `MOCU_DISTRIB_TRACE=1`: every sample received, on stderr (debugging peers).
        if std::env::var_os("MOCU_DISTRIB_TRACE").is_some() {
            eprintln!(
                "[{}] {} {key} {}",
                self.me,
                if put { "put" } else { "del" },
                String::from_utf8_lossy(bytes)
            );
        }
        let bad = || payload::Malformed(format!("not a key of the key space: {key}"));
        match keys::parse(key).ok_or_else(bad)? {
            Key::Object { site, path } if site != self.me && !path.is_empty() => {
                if put {
                    let rec = payload::object_from(bytes)?;
                    self.ensure(&site, &path, Some(&rec));
                } else {
                    self.delete(&site, &path);
                }
            }
            Key::Property { site, path, name } if site != self.me => {
                // Read first: a malformed sample leaves no object behind.
                let sample = if put { Some(payload::property_from(bytes)?) } else { None };
                let Some(local) = self.ensure(&site, &path, None) else { return Ok(()) };
                if let Some((v, meta)) = sample {
                    let v = self.local_value(&site, v);
                    self.write(local, &name, v, meta);
                } else {
                    let _ = self.ds.delete_property(local, name.as_str());
                }
                if let Some(c) = self.sites.get_mut(&site).and_then(|s| s.confirmed.as_mut()) {
                    c.insert(path);
                }
            }
            Key::Stream { site, path } if site != self.me && put => {
                // Sent again on the mirrored listener; before the listener is mirrored (a
                // frame overtaking the snapshot) there is nobody to show it to.
                let args = payload::stream_from(bytes)?;
                let local = self.sites.get(&site).and_then(|s| s.objects.get(&path));
                if let Some(m) = local {
                    let _ = self.ds.send(m.local, args);
                }
            }
            Key::Object { .. } | Key::Property { .. } | Key::Stream { .. } => {}
            Key::Call { .. } | Key::Alive { .. } => return Err(bad()),
        }
        Ok(())
    }

    /// The local object mirroring `path` of `site`: found, adopted (an object already at
    /// that path) or created, its ancestors first.
    fn ensure(
        &mut self,
        site: &str,
        path: &[String],
        rec: Option<&payload::ObjectRecord>,
    ) -> Option<Guid> {
        let s = self.sites.entry(site.to_string()).or_default();
        if let Some(c) = s.confirmed.as_mut() {
            c.insert(path.to_vec());
        }
        if let Some(m) = s.objects.get(path) {
            let local = m.local;
            let owned = m.owned;
            if !self.ds.exists(local) {
                s.objects.remove(path);
                return self.ensure(site, path, rec);
            }
            if let Some(rec) = rec {
                s.guids.insert(rec.guid, local);
                if owned && self.ds.info(local).ok().as_ref() != Some(&rec.info) {
                    let _ = self.ds.set_info(local, rec.info.clone());
                }
                self.proxy_methods(site, path, local, rec);
            }
            return Some(local);
        }
        let parent = match path.split_last() {
            Some((_, [])) => self.ds.root(),
            Some((_, up)) => self.ensure(site, up, None)?,
            None => return None,
        };
        let name = path.last()?;
        let (local, owned) = match self.ds.find_child(parent, name).ok().flatten() {
            Some(g) => (g, false),
            None => {
                let info = rec.map_or_else(|| ObjectInfo::new(name, "object"), |r| r.info.clone());
                // A listener is mirrored as a listener: local video windows join it, and a
                // shared stream's messages are sent on it.
                let local = if &*info.kind == LISTENER_TYPE {
                    let l = self.ds.create_listener(parent, name).ok()?;
                    let _ = self.ds.set_info(l, info);
                    l
                } else {
                    self.ds.create_object(parent, info).ok()?
                };
                (local, true)
            }
        };
        if owned {
            crate::writes::proxy(&self.ds, &self.calls, site, path, local);
        }
        let s = self.sites.entry(site.to_string()).or_default();
        s.objects.insert(path.to_vec(), Mirrored { local, owned });
        if let Some(rec) = rec {
            s.guids.insert(rec.guid, local);
        }
        if let Some(rec) = rec {
            self.proxy_methods(site, path, local, rec);
        }
        Some(local)
    }

    /// Publishes, on the local object, each of the record's methods it lacks: a call is
    /// forwarded as a query to the site and answered with the site's outcome.
    fn proxy_methods(&self, site: &str, path: &[String], local: Guid, rec: &payload::ObjectRecord) {
        let have = self.ds.methods(local).unwrap_or_default();
        for spec in &rec.methods {
            if have.iter().any(|m| m.name == spec.name) {
                continue;
            }
            let key = keys::call(site, path, spec.name.as_str());
            let jobs = self.calls.clone();
            let _ = self.ds.publish_method(local, spec.clone(), move |call: Call| {
                let _ = jobs.send(CallJob::Forward {
                    key: key.clone(),
                    args: call.args.to_vec(),
                    responder: call.responder,
                });
            });
        }
    }

    /// `v` with the site's GUIDs of mirrored objects replaced by the local ones (a GUID of
    /// an object not mirrored here stays the site's number).
    fn local_value(&self, site: &str, v: Value) -> Value {
        let Some(s) = self.sites.get(site) else { return v };
        fn tr(s: &Site, v: Value) -> Value {
            match v {
                Value::Guid(g) => Value::Guid(s.guids.get(&g.get()).copied().unwrap_or(g)),
                Value::List(xs) => Value::list(xs.iter().cloned().map(|x| tr(s, x))),
                Value::Set(xs) => Value::set(xs.iter().cloned().map(|x| tr(s, x))),
                other => other,
            }
        }
        tr(s, v)
    }

    fn write(&self, local: Guid, name: &str, v: Value, meta: Option<PropMeta>) {
        let name = PropName::new(name);
        let exists = self.ds.try_get(local, name).is_some();
        if let Some(mut m) = meta {
            // Staleness across the network is liveliness's job: a mirror receives no
            // equal writes, so the publisher's rate would age every steady value.
            m.rate_hz = None;
            // A value can arrive before the record that carries its metadata (an update
            // overtaking a late joiner's snapshot): the metadata, when it comes, replaces
            // what the bare value was created with, so units are never lost for good.
            if self.ds.meta(local, name).ok().as_ref() != Some(&m) {
                if exists {
                    let _ = self.ds.delete_property(local, name);
                }
                if self.ds.create_property(local, name, v.clone(), m).is_ok() {
                    return;
                }
            }
        }
        if self.ds.set(local, name, v.clone()).is_err() {
            // Retyped at the source: take the source's kind.
            let _ = self.ds.delete_property(local, name);
            let _ = self.ds.set(local, name, v);
        }
    }

    fn delete(&mut self, site: &str, path: &[String]) {
        let Some(s) = self.sites.get_mut(site) else { return };
        if let Some(m) = s.objects.get(path)
            && m.owned
        {
            let _ = self.ds.delete_object(m.local);
        }
        s.objects.retain(|p, _| !p.starts_with(path));
    }

    fn say(&self, text: String) {
        if let Some(n) = &self.notify {
            n(&text);
        }
    }

    fn peer_status(&self, site: &str, alive: bool) {
        let Some(status) = self.status else { return };
        let find = |parent: Guid, name: &str, kind: &str| -> Option<Guid> {
            match self.ds.find_child(parent, name).ok()? {
                Some(g) => Some(g),
                None => self.ds.create_object(parent, ObjectInfo::new(name, kind)).ok(),
            }
        };
        if let Some(peers) = find(status, "peers", "peers")
            && let Some(p) = find(peers, site, "peer")
        {
            let _ = self.ds.set(p, "alive", Value::Bool(alive));
        }
    }

    fn site_up(&mut self, site: &str) {
        let s = self.sites.entry(site.to_string()).or_default();
        if s.alive {
            return;
        }
        s.alive = true;
        s.generation += 1;
        s.pending = 2;
        s.confirmed = Some(HashSet::new());
        let generation = s.generation;
        self.peer_status(site, true);
        self.ask_snapshot(site, "obj", generation);
    }

    /// Asks `site` for its objects (`obj`) or properties (`prop`): the properties only when
    /// the objects are in, so that a `guid` value finds the object it names.
    fn ask_snapshot(&self, site: &str, what: &str, generation: u64) {
        let tx = self.tx.clone();
        let done = Done { tx: tx.clone(), site: site.to_string(), generation };
        let _ = self
            .session
            .get(keys::state_of(Some(site), what))
            .consolidation(ConsolidationMode::None)
            .callback(move |reply| {
                let _keep = &done;
                if let Ok(s) = reply.result() {
                    let _ = tx.send(Inbound::Sample {
                        key: s.key_expr().as_str().to_string(),
                        put: s.kind() == zenoh::sample::SampleKind::Put,
                        bytes: s.payload().to_bytes().into_owned(),
                    });
                }
            })
            .wait();
    }

    fn site_down(&mut self, site: &str) {
        let Some(s) = self.sites.get_mut(site) else { return };
        if !s.alive {
            return;
        }
        s.alive = false;
        s.confirmed = None;
        let locals: Vec<Guid> = s.objects.values().map(|m| m.local).collect();
        let mut flagged = 0;
        for g in locals {
            let mut any = false;
            for flag in ["stale", "link_lost"] {
                let name = PropName::new(flag);
                if self.ds.try_get(g, name).is_some() {
                    any |= self.ds.set(g, name, Value::Bool(true)).is_ok();
                }
            }
            flagged += usize::from(any);
        }
        self.peer_status(site, false);
        self.say(format!("site `{site}` is gone: {flagged} of its objects shown stale"));
    }

    fn snapshot_done(&mut self, site: &str, generation: u64) {
        let Some(s) = self.sites.get_mut(site) else { return };
        if s.generation != generation || s.pending == 0 {
            return;
        }
        s.pending -= 1;
        if s.pending > 0 {
            self.ask_snapshot(site, "prop", generation);
            return;
        }
        if let Some(seen) = s.confirmed.take() {
            let gone: Vec<Vec<String>> = s
                .objects
                .keys()
                .filter(|p| !seen.iter().any(|q| q.starts_with(p)))
                .cloned()
                .collect();
            for p in gone {
                if let Some(m) = s.objects.remove(&p)
                    && m.owned
                {
                    let _ = self.ds.delete_object(m.local);
                }
            }
        }
        self.stats.snapshots.fetch_add(1, Ordering::Relaxed);
        let n = self.sites.get(site).map_or(0, |s| s.objects.len());
        self.say(format!("site `{site}` joined: {n} objects mirrored from its snapshot"));
        *self.joined.count.lock() += 1;
        self.joined.cv.notify_all();
    }
}

/// Tells the mirror a snapshot query is complete (zenoh drops the callback then).
struct Done {
    tx: Sender<Inbound>,
    site: String,
    generation: u64,
}

impl Drop for Done {
    fn drop(&mut self) {
        let _ = self.tx.send(Inbound::SnapshotDone {
            site: std::mem::take(&mut self.site),
            generation: self.generation,
        });
    }
}
