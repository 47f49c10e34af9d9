// Shared helpers for the DataServer's integration tests.
#![allow(dead_code)]
use mocu_dataserver::*;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::{Arc, Mutex};

/// A subscription callback that records everything it is told.
pub fn recorder() -> (Arc<Mutex<Vec<Notification>>>, impl FnMut(&Notification) + Send + 'static) {
    let log = Arc::new(Mutex::new(Vec::new()));
    let l = log.clone();
    (log, move |n: &Notification| l.lock().unwrap().push(n.clone()))
}

pub fn prop_events(log: &Arc<Mutex<Vec<Notification>>>) -> Vec<(Kind, String, Option<Value>)> {
    log.lock()
        .unwrap()
        .iter()
        .filter_map(|n| match &n.subject {
            Subject::Property { name, value } => Some((n.kind, name.to_string(), value.clone())),
            _ => None,
        })
        .collect()
}

pub fn child_events(log: &Arc<Mutex<Vec<Notification>>>) -> Vec<(Kind, String)> {
    log.lock()
        .unwrap()
        .iter()
        .map(|n| match &n.subject {
            Subject::Child { name, .. } => (n.kind, name.to_string()),
            Subject::Object => (n.kind, "<self>".into()),
            Subject::Property { name, .. } => (n.kind, format!("prop {name}")),
        })
        .collect()
}

pub fn names(ds: &DataServer, parent: Guid) -> Vec<String> {
    ds.children(parent).unwrap().iter().map(|c| ds.info(*c).unwrap().name.to_string()).collect()
}

/// A server on a manual clock, and the clock.
pub fn manual() -> (DataServer, ManualClock) {
    let clock = ManualClock::new();
    (DataServer::with_clock(Config::default(), Arc::new(clock.clone())), clock)
}

/// A new object of type `thing` under the root.
pub fn object(ds: &DataServer, name: &str) -> Guid {
    ds.create_object(ds.root(), ObjectInfo::new(name, "thing")).unwrap()
}

/// Publishes a method `m` on `o` that counts its runs and accepts; the counter.
pub fn count_runs(ds: &DataServer, o: Guid) -> Arc<AtomicUsize> {
    let runs = Arc::new(AtomicUsize::new(0));
    let r = runs.clone();
    ds.publish_method_fn(o, MethodSpec::new("m"), move |_| {
        r.fetch_add(1, Ordering::SeqCst);
        CallOutcome::Accepted(vec![])
    })
    .unwrap();
    runs
}
