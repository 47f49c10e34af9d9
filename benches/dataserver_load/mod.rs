//! DataServer figures under load (part of `benches/dataserver.rs`), each against a baseline
//! in the same run, interleaved in blocks so both see the same machine:
//!
//! | figure            | ours                                         | baseline                    | target |
//! |-------------------|----------------------------------------------|-----------------------------|--------|
//! | busy neighbour    | write → callback → signal, a spinning thread | crossbeam hop, same thread  | ≤ 2×   |
//! | blocked neighbour | the same on the default pool, while another  | the same, nobody blocked    | ≤ 1.2× |
//! |                   | subscriber blocks 100 ms at a time           |                             |        |

use crossbeam_channel::Receiver;
use mocu_dataserver::{Config, DataServer, Guid, Kind, ObjectInfo, PropName, Topic, Value};
use std::hint::black_box;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::thread::JoinHandle;
use std::time::Duration;

/// A thread that computes until dropped (another module busy on the same machine).
pub struct Spinner {
    stop: Arc<AtomicBool>,
    thread: Option<JoinHandle<()>>,
}

impl Spinner {
    pub fn start() -> Spinner {
        let stop = Arc::new(AtomicBool::new(false));
        let s = stop.clone();
        let thread = std::thread::spawn(move || {
            let mut x = 1u64;
            while !s.load(Ordering::Relaxed) {
                for _ in 0..10_000 {
                    x = black_box(x.wrapping_mul(6364136223846793005).wrapping_add(1));
                }
            }
        });
        Spinner { stop, thread: Some(thread) }
    }
}

impl Drop for Spinner {
    fn drop(&mut self) {
        self.stop.store(true, Ordering::Relaxed);
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}

/// Write → subscriber callback → signal back, on a server with the default pool; with
/// `blocked`, another subscriber of another object blocks for 100 ms at a time, again and
/// again (it re-triggers itself), so one worker is always stuck in user code.
pub struct PoolHop {
    ds: DataServer,
    obj: Guid,
    name: PropName,
    back: Receiver<()>,
    next: i64,
    stop: Arc<AtomicBool>,
}

impl PoolHop {
    pub fn new(blocked: bool) -> PoolHop {
        let ds = DataServer::new(Config::default());
        let obj = ds.create_object(ds.root(), ObjectInfo::new("robot", "robot")).unwrap();
        let name = PropName::new("speed");
        ds.set(obj, name, Value::Int(0)).unwrap();
        let (tx, back) = crossbeam_channel::unbounded();
        ds.subscribe(Topic::property_names(obj, &["speed"]), move |n| {
            if n.kind == Kind::Changed {
                black_box(n.value());
                tx.send(()).unwrap();
            }
        })
        .unwrap();
        let stop = Arc::new(AtomicBool::new(false));
        if blocked {
            let slow = ds.create_object(ds.root(), ObjectInfo::new("slow", "module")).unwrap();
            ds.set(slow, "tick", Value::Int(0)).unwrap();
            let (ds2, s) = (ds.clone(), stop.clone());
            let mut n = 0;
            ds.subscribe(Topic::properties(slow), move |_| {
                if s.load(Ordering::Relaxed) {
                    return;
                }
                std::thread::sleep(Duration::from_millis(100)); // user code that blocks
                n += 1;
                let _ = ds2.set(slow, "tick", Value::Int(n));
            })
            .unwrap();
            // Wait until the blocker has started blocking.
            while ds.get(slow, "tick") == Ok(Value::Int(0)) {
                std::thread::yield_now();
            }
        }
        if !blocked {
            ds.quiesce();
        }
        PoolHop { ds, obj, name, back, next: 0, stop }
    }

    pub fn round_trip(&mut self) {
        self.next += 1;
        self.ds.set(self.obj, self.name, Value::Int(self.next)).unwrap();
        self.back.recv().unwrap();
    }
}

impl Drop for PoolHop {
    fn drop(&mut self) {
        self.stop.store(true, Ordering::Relaxed);
    }
}
