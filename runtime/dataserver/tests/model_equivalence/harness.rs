//! Drives the real DataServer and the model side by side and compares their answers,
//! trees and notification streams.

use crate::model::{Model, Watch};
use crate::ops::{Op, PROP_NAMES};
use crate::streams::check_stream;
use mocu_dataserver::{
    Config, DataServer, DsError, Executor, Guid, Notification, PropName, Subject, SubscriptionId,
    Topic,
};
use parking_lot::{Condvar, Mutex};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};

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

pub(crate) struct Harness {
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
    pub(crate) fn new(quiesce_each: bool) -> Harness {
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

    pub(crate) fn run(&mut self, ops: &[Op]) {
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
