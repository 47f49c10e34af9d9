//! The toast list: `root.operator.toasts` keeps the last outcomes of calls and writes
//! (`root.operator.feedback`) and the last alerts (`root.operator.alerts`), newest first,
//! as properties `t1…tN` (text), `s1…sN` (state: pending, accepted, refused, failed,
//! timed_out, or an alert's severity) and `n`. The stdlib `ToastList` shows `t1…t3`.

use mocu_dataserver::{
    DataServer, DottedPath, Executor, Kind, Notification, PathWatch, Subject, SubscriptionId, Topic,
};
use mocu_dataserver::{Guid, PropName, Value};
use parking_lot::Mutex;
use std::sync::Arc;

pub struct Toasts {
    shared: Arc<Shared>,
}

struct Shared {
    ds: DataServer,
    object: Guid,
    keep: usize,
    list: Mutex<Vec<(String, String, String)>>,
    /// The `time` of the last feedback record shown.
    shown: Mutex<f64>,
    subs: Mutex<Vec<SubscriptionId>>,
    watches: Mutex<Vec<PathWatch>>,
}

impl Toasts {
    /// Follows `root.operator.feedback` and `root.operator.alerts` (they may appear later)
    /// and keeps the last `keep` entries.
    pub fn start(ds: &DataServer, exec: &Executor, keep: usize) -> Result<Toasts, String> {
        let e = |e: mocu_dataserver::DsError| e.to_string();
        let op = crate::engine::child(ds, Guid::ROOT, "operator", "operator").map_err(e)?;
        let object = crate::engine::child(ds, op, "toasts", "toasts").map_err(e)?;
        let _ = ds.set(object, "n", Value::Int(0));
        let shared = Arc::new(Shared {
            ds: ds.clone(),
            object,
            keep: keep.clamp(1, 20),
            list: Mutex::new(Vec::new()),
            shown: Mutex::new(f64::NEG_INFINITY),
            subs: Mutex::new(Vec::new()),
            watches: Mutex::new(Vec::new()),
        });
        // Feedback: `time` is written last, so its change means the record is complete.
        let weak = Arc::downgrade(&shared);
        let path = DottedPath::parse("operator.feedback.time").map_err(e)?;
        let w = ds
            .watch_path(path, Some(exec), move |ev| {
                if let (Some(sh), true) = (weak.upgrade(), ev.kind != Kind::Deleted) {
                    sh.on_feedback();
                }
            })
            .map_err(e)?;
        shared.watches.lock().push(w);
        let weak = Arc::downgrade(&shared);
        let exec2 = exec.clone();
        let w = ds
            .watch_object(Guid::ROOT, &["operator", "alerts"], Some(exec), move |ev| {
                if let (Some(sh), true) = (weak.upgrade(), ev.kind != Kind::Deleted) {
                    sh.follow_alerts(ev.object, &exec2);
                }
            })
            .map_err(e)?;
        shared.watches.lock().push(w);
        Ok(Toasts { shared })
    }

    /// The entries now, newest first: (text, state).
    pub fn entries(&self) -> Vec<(String, String)> {
        self.shared.list.lock().iter().map(|(t, s, _)| (t.clone(), s.clone())).collect()
    }
}

impl Drop for Toasts {
    /// Takes the watches and subscriptions out, then ends them with no lock held: ending
    /// one waits for its running callback, which may push to `subs`. Rounds until none is
    /// left (a callback that was running may have added one).
    fn drop(&mut self) {
        loop {
            let watches = std::mem::take(&mut *self.shared.watches.lock());
            let subs = std::mem::take(&mut *self.shared.subs.lock());
            if watches.is_empty() && subs.is_empty() {
                break;
            }
            drop(watches);
            for s in subs {
                self.shared.ds.unsubscribe(s);
            }
        }
    }
}

impl Shared {
    fn on_feedback(&self) {
        let ds = &self.ds;
        let Some(f) = ds.resolve(&["operator", "feedback"]) else { return };
        let get = |k: &str| {
            ds.try_get(f, PropName::new(k))
                .and_then(|v| v.as_str().map(str::to_string))
                .unwrap_or_default()
        };
        // Each record once: a notification handled after a newer record was written reads
        // the newer one, and the newer one's own notification then has nothing new.
        let time = ds.try_get(f, PropName::new("time")).and_then(|v| v.as_f64());
        {
            let mut shown = self.shown.lock();
            match time {
                Some(t) if t > *shown => *shown = t,
                _ => return,
            }
        }
        let (target, state, reason) = (get("target"), get("state"), get("reason"));
        let short = target.strip_prefix("root.").unwrap_or(&target).to_string();
        let short = short.strip_prefix("vehicles.").unwrap_or(&short).to_string();
        let text = match (state.as_str(), reason.is_empty()) {
            (_, true) => format!("{short}: {state}"),
            (_, false) => format!("{short}: {state} — {reason}"),
        };
        self.push(text, state, target);
    }

    fn follow_alerts(self: &Arc<Self>, folder: Guid, exec: &Executor) {
        let weak = Arc::downgrade(self);
        let exec2 = exec.clone();
        let sub = self.ds.subscribe_on(exec, Topic::children(folder), move |n: &Notification| {
            if let (Some(sh), Kind::New, Subject::Child { guid, .. }) =
                (weak.upgrade(), n.kind, &n.subject)
            {
                sh.follow_alert(*guid, &exec2);
            }
        });
        if let Ok(s) = sub {
            self.subs.lock().push(s);
        }
    }

    /// An alert's `text` and `severity` may be written just after it appears: take them
    /// from its properties as they come, once.
    fn follow_alert(self: &Arc<Self>, alert: Guid, exec: &Executor) {
        let weak = Arc::downgrade(self);
        let mut done = false;
        let sub = self.ds.subscribe_on(exec, Topic::properties(alert), move |n: &Notification| {
            let Some(sh) = weak.upgrade() else { return };
            if done || n.property_name() != Some(PropName::new("text")) {
                return;
            }
            done = true;
            // A failed command is an alert too (mocu-layout): its feedback entry shows it.
            if sh.ds.try_get(alert, PropName::new("source")).as_ref().and_then(Value::as_str)
                == Some("command")
            {
                return;
            }
            let text = n.value().and_then(|v| v.as_str().map(str::to_string)).unwrap_or_default();
            let sev = sh
                .ds
                .try_get(alert, PropName::new("severity"))
                .and_then(|v| v.as_str().map(str::to_string))
                .unwrap_or_else(|| "info".into());
            sh.push(text, sev, String::new());
        });
        if let Ok(s) = sub {
            self.subs.lock().push(s);
        }
    }

    /// Adds an entry on top; the outcome of a call replaces its own `pending` entry.
    fn push(&self, text: String, state: String, target: String) {
        let mut list = self.list.lock();
        if !target.is_empty()
            && let Some(top) = list.first()
            && top.2 == target
            && top.1 == "pending"
        {
            list.remove(0);
        }
        list.insert(0, (text, state, target));
        list.truncate(self.keep);
        let ds = &self.ds;
        for i in 0..self.keep {
            match list.get(i) {
                Some((t, s, _)) => {
                    let _ = ds.set(self.object, format!("t{}", i + 1).as_str(), Value::str(t));
                    let _ = ds.set(self.object, format!("s{}", i + 1).as_str(), Value::str(s));
                }
                None => {
                    let _ = ds.delete_property(self.object, format!("t{}", i + 1).as_str());
                    let _ = ds.delete_property(self.object, format!("s{}", i + 1).as_str());
                }
            }
        }
        let _ = ds.set(self.object, "n", Value::Int(list.len() as i64));
    }
}
