//! The DataServer under concurrent writers, many subscribers and a path rebuilt while it is
//! watched. Each test body runs on its own thread and fails if it does not finish within a
//! minute: a deadlock shows as a failure, not a hung test run.

use mocu_dataserver::{
    Config, DataServer, DottedPath, Executor, Guid, Kind, Notification, ObjectInfo, PathEvent,
    PropName, Subject, SubscriptionId, Topic, Value,
};
use parking_lot::Mutex;
use std::collections::HashMap;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Duration;

/// Runs `body` on a thread; fails if it takes longer than `limit` (a deadlock detector).
fn within(limit: Duration, body: impl FnOnce() + Send + 'static) {
    let (done, finished) = crossbeam_channel::bounded::<()>(1);
    let t = std::thread::spawn(move || {
        body();
        let _ = done.send(());
    });
    match finished.recv_timeout(limit) {
        Ok(()) => t.join().expect("the body finished"),
        // The body panicked: its sender is gone. Re-raise its panic here.
        Err(crossbeam_channel::RecvTimeoutError::Disconnected) => {
            if let Err(p) = t.join() {
                std::panic::resume_unwind(p)
            }
        }
        Err(crossbeam_channel::RecvTimeoutError::Timeout) => {
            panic!("not finished after {limit:?}: a deadlock or a lost wake-up")
        }
    }
}

/// A small deterministic generator (xorshift), so runs are repeatable without a crate.
struct Rng(u64);

impl Rng {
    fn below(&mut self, n: u64) -> u64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        self.0 % n
    }
}

// ----- many writers, many subscribers ------------------------------------------------------

const WRITERS: usize = 4;
const WRITES: i64 = 2_000;
const SUBSCRIBERS: usize = 200;

/// What one subscriber saw, and every rule its callback found broken.
#[derive(Default)]
struct Seen {
    last: HashMap<PropName, Value>,
    deleted: bool,
    violations: Vec<String>,
}

struct Subscriber {
    id: SubscriptionId,
    object: usize,
    seen: Arc<Mutex<Seen>>,
    /// Set right after `unsubscribe` returned.
    ended: Arc<AtomicBool>,
    unsubscribed: bool,
}

fn writer_prop(w: usize) -> PropName {
    PropName::new(&format!("w{w}"))
}

#[test]
fn every_live_subscriber_ends_at_the_final_values_and_nothing_arrives_after_the_end() {
    within(Duration::from_secs(60), || {
        let ds = DataServer::new(Config { workers: 4 });
        // Four objects that live on, two that are deleted while the writers still write.
        let objects: Vec<Guid> = (0..6)
            .map(|i| ds.create_object(Guid::ROOT, ObjectInfo::new(&format!("o{i}"), "t")).unwrap())
            .collect();
        let doomed = [objects[4], objects[5]];
        let executors: Vec<Executor> = (0..8).map(|_| ds.serial_executor()).collect();
        let shared = PropName::new("shared");

        let mut subs: Vec<Subscriber> = (0..SUBSCRIBERS)
            .map(|i| {
                let object = i % objects.len();
                let seen = Arc::new(Mutex::new(Seen::default()));
                let ended = Arc::new(AtomicBool::new(false));
                let callback = {
                    let (seen, ended) = (seen.clone(), ended.clone());
                    move |n: &Notification| {
                        let mut s = seen.lock();
                        if ended.load(Ordering::SeqCst) {
                            s.violations.push(format!("{n:?} after unsubscribe returned"));
                        }
                        if s.deleted {
                            s.violations.push(format!("{n:?} after the object's Deleted"));
                        }
                        match &n.subject {
                            Subject::Object => s.deleted = true,
                            Subject::Property { name, value: Some(v) } => {
                                // Each writer's own counter only goes up: per-object order
                                // is a subsequence of the change order.
                                if *name != shared
                                    && let Some(old) = s.last.get(name)
                                    && old >= v
                                {
                                    let broken = format!("{name}: {v:?} after {old:?}");
                                    s.violations.push(broken);
                                }
                                s.last.insert(*name, v.clone());
                            }
                            other => s.violations.push(format!("unexpected {other:?}")),
                        }
                    }
                };
                let topic = if i % 3 == 0 {
                    Topic::Properties { object: objects[object], names: Some(vec![shared]) }
                } else {
                    Topic::properties(objects[object])
                };
                let id = if i % 2 == 0 {
                    ds.subscribe_on(&executors[i % executors.len()], topic, callback)
                } else {
                    ds.subscribe(topic, callback)
                }
                .unwrap();
                Subscriber { id, object, seen, ended, unsubscribed: false }
            })
            .collect();

        // Writer 0 says when it is halfway and three quarters through.
        let (progress_tx, progress) = crossbeam_channel::unbounded::<&str>();
        let writers: Vec<_> = (0..WRITERS)
            .map(|w| {
                let (ds, objects, progress_tx) = (ds.clone(), objects.clone(), progress_tx.clone());
                std::thread::spawn(move || {
                    let own = writer_prop(w);
                    for i in 0..WRITES {
                        let o = objects[(i as usize + w) % objects.len()];
                        let live = !doomed.contains(&o);
                        let r1 = ds.set(o, own, Value::Int(i));
                        let r2 = ds.set(o, "shared", Value::Int(i * WRITERS as i64 + w as i64));
                        if live {
                            r1.unwrap();
                            r2.unwrap();
                        }
                        if w == 0 && i == WRITES / 2 {
                            progress_tx.send("half").unwrap();
                        }
                        if w == 0 && i == WRITES * 3 / 4 {
                            progress_tx.send("three quarters").unwrap();
                        }
                    }
                })
            })
            .collect();
        drop(progress_tx);

        assert_eq!(progress.recv().unwrap(), "half");
        for s in subs.iter_mut().step_by(5) {
            ds.unsubscribe(s.id);
            s.ended.store(true, Ordering::SeqCst);
            s.unsubscribed = true;
        }
        assert_eq!(progress.recv().unwrap(), "three quarters");
        for d in doomed {
            ds.delete_object(d).unwrap();
        }
        for w in writers {
            w.join().expect("a writer panicked");
        }
        ds.quiesce();

        let mut live = 0;
        for (i, s) in subs.iter().enumerate() {
            let seen = s.seen.lock();
            assert!(seen.violations.is_empty(), "subscriber {i}: {:?}", seen.violations);
            if s.unsubscribed {
                continue;
            }
            let o = objects[s.object];
            if doomed.contains(&o) {
                assert!(seen.deleted, "subscriber {i} was not told its object was deleted");
                continue;
            }
            live += 1;
            for (name, value) in ds.properties(o).unwrap() {
                if i % 3 != 0 || name == shared {
                    assert_eq!(seen.last.get(&name), Some(&value), "subscriber {i}: `{name}`");
                }
            }
        }
        assert_eq!(ds.subscription_count(), live, "ended subscriptions left the registry");
        assert!(ds.stats().callbacks_run.load(Ordering::Relaxed) > 0);
    });
}

// ----- a watched path rebuilt concurrently -------------------------------------------------

/// What one path watch reported, and every rule its callback found broken.
#[derive(Default)]
struct PathLog {
    last: Option<PathEvent>,
    events: usize,
    violations: Vec<String>,
}

fn watch(
    ds: &DataServer,
    executor: Option<&Executor>,
) -> (mocu_dataserver::PathWatch, Arc<Mutex<PathLog>>, Arc<AtomicBool>) {
    let log = Arc::new(Mutex::new(PathLog::default()));
    let ended = Arc::new(AtomicBool::new(false));
    let (l, e) = (log.clone(), ended.clone());
    let path = DottedPath::parse("root.fleet.usv.nav.speed").unwrap();
    let w = ds
        .watch_path(path, executor, move |ev: &PathEvent| {
            let mut log = l.lock();
            if e.load(Ordering::SeqCst) {
                log.violations.push(format!("{ev:?} after cancel returned"));
            }
            // Changed only continues a value reported for the same object; New and
            // Changed carry a value, Deleted none.
            let continues = matches!(
                &log.last,
                Some(PathEvent { kind: Kind::New | Kind::Changed, object, .. }) if *object == ev.object
            );
            let consistent = match ev.kind {
                Kind::New => ev.value.is_some() && !continues,
                Kind::Changed => ev.value.is_some() && continues,
                Kind::Deleted => ev.value.is_none() && continues,
            };
            if !consistent {
                let broken = format!("{ev:?} after {:?}", log.last);
                log.violations.push(broken);
            }
            log.last = Some(ev.clone());
            log.events += 1;
        })
        .unwrap();
    (w, log, ended)
}

/// Makes random structural changes along `root.fleet.usv.nav` (creating, deleting,
/// renaming, inserting and promoting objects on the path or beside it) and writes `speed`
/// where the path currently leads.
fn churn(ds: &DataServer, seed: u64, rounds: usize) {
    let mut rng = Rng(seed);
    let path = ["fleet", "usv", "nav"];
    for i in 0..rounds {
        // An object along the path, as far as it resolves now, or now and then any object.
        let level = rng.below(4) as usize;
        let at = match rng.below(5) {
            0 => {
                let all = tree(ds, Guid::ROOT);
                all[rng.below(all.len() as u64) as usize]
            }
            _ => ds.resolve(&path[..level]).unwrap_or(Guid::ROOT),
        };
        let child_name = if rng.below(3) == 0 { "other" } else { path.get(level).unwrap_or(&"x") };
        let own_name = if level > 0 && rng.below(2) == 0 { path[level - 1] } else { "other" };
        let first_child = ds.children(at).unwrap_or_default().first().copied();
        // Each operation may lose a race with the other churner: errors are expected.
        match rng.below(10) {
            0 | 1 => {
                let _ = ds.create_object(at, ObjectInfo::new(child_name, "t"));
            }
            2 if rng.below(3) == 0 => {
                let _ = ds.delete_object(at);
            }
            3 | 4 => {
                let _ = ds.set_info(at, ObjectInfo::new(own_name, "t"));
            }
            5 => {
                if let Some(c) = first_child {
                    let _ = ds.insert_between(at, c, ObjectInfo::new(child_name, "t"));
                }
            }
            6 => {
                if let Some(c) = first_child {
                    let _ = ds.delete_and_promote(at, c);
                }
            }
            _ => {
                if let Some(nav) = ds.resolve(&path) {
                    let _ = ds.set(nav, "speed", Value::Int(i as i64));
                }
            }
        }
    }
}

fn tree(ds: &DataServer, at: Guid) -> Vec<Guid> {
    let mut out = vec![at];
    for c in ds.children(at).unwrap_or_default() {
        out.extend(tree(ds, c));
    }
    out
}

#[test]
fn path_watches_settle_on_the_final_value_while_the_path_is_rebuilt_concurrently() {
    within(Duration::from_secs(60), || {
        let ds = DataServer::new(Config { workers: 4 });
        let shared = ds.serial_executor();
        let mut watches: Vec<_> =
            (0..6).map(|i| watch(&ds, (i % 2 == 0).then_some(&shared))).collect();
        let churners: Vec<_> = (0..2)
            .map(|t| {
                let ds = ds.clone();
                std::thread::spawn(move || churn(&ds, 0x9e37_79b9 + t, 4_000))
            })
            .collect();
        // More watches join while the churn runs; some leave.
        for i in 0..6 {
            watches.push(watch(&ds, (i % 2 == 1).then_some(&shared)));
        }
        let mut cancelled = Vec::new();
        for _ in 0..3 {
            let (w, log, ended) = watches.remove(0);
            w.cancel();
            ended.store(true, Ordering::SeqCst);
            cancelled.push(log);
        }
        for c in churners {
            c.join().expect("a churner panicked");
        }

        // A known end: exactly one root.fleet.usv.nav, reached through a rename.
        for c in ds.children(Guid::ROOT).unwrap() {
            ds.delete_object(c).unwrap();
        }
        let fleet = ds.create_object(Guid::ROOT, ObjectInfo::new("fleet", "t")).unwrap();
        let usv = ds.create_object(fleet, ObjectInfo::new("usv2", "t")).unwrap();
        let nav = ds.create_object(usv, ObjectInfo::new("nav", "t")).unwrap();
        ds.set(nav, "speed", Value::Int(7)).unwrap();
        ds.set_info(usv, ObjectInfo::new("usv", "t")).unwrap();
        ds.set(nav, "speed", Value::Int(42)).unwrap();
        ds.quiesce();

        for (i, (w, log, _)) in watches.iter().enumerate() {
            let log = log.lock();
            assert!(log.violations.is_empty(), "watch {i}: {:?}", log.violations);
            let last = log.last.clone().expect("something was reported");
            assert_eq!((last.object, last.value), (nav, Some(Value::Int(42))), "watch {i}");
            assert_eq!(w.bound_object(), Some(nav), "watch {i}");
        }
        for (i, log) in cancelled.iter().enumerate() {
            assert!(
                log.lock().violations.is_empty(),
                "cancelled watch {i}: {:?}",
                log.lock().violations
            );
        }

        // And a known unreachable end: every live watch reports the loss.
        ds.set_info(usv, ObjectInfo::new("usv-retired", "t")).unwrap();
        ds.quiesce();
        for (i, (w, log, _)) in watches.iter().enumerate() {
            let last = log.lock().last.clone().expect("reported before");
            assert_eq!(
                (last.kind, last.object, last.value),
                (Kind::Deleted, nav, None),
                "watch {i}"
            );
            assert_eq!(w.bound_object(), None, "watch {i}");
        }
        drop(watches);
        ds.quiesce();
        assert_eq!(ds.subscription_count(), 0, "dropped watches left subscriptions behind");
    });
}
