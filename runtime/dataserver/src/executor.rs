//! Where DataServer work runs: a small worker pool, serial executors (strands) on top of
//! it, and a timer for delayed calls. Nothing here knows about objects or properties.

use crossbeam_channel::{Receiver, Sender};
use parking_lot::{Condvar, Mutex};
use std::cmp::Reverse;
use std::collections::{BinaryHeap, VecDeque};
use std::panic::{AssertUnwindSafe, catch_unwind};
use std::sync::Arc;
use std::sync::atomic::{AtomicU64, AtomicUsize, Ordering};
use std::thread;
use std::time::{Duration, Instant};

pub(crate) type Job = Box<dyn FnOnce() + Send + 'static>;

/// Counts jobs submitted and not yet finished, so tests can wait for quiet. The count is an
/// atomic so that submitting and finishing a job (every notification) take no lock; the
/// mutex is taken only to reach zero and to wait for it.
#[derive(Default)]
pub(crate) struct Inflight {
    count: AtomicUsize,
    lock: Mutex<()>,
    zero: Condvar,
}

impl Inflight {
    fn add(&self) {
        self.count.fetch_add(1, Ordering::AcqRel);
    }

    fn done(&self) {
        if self.count.fetch_sub(1, Ordering::AcqRel) == 1 {
            // Taking the lock orders this wake-up after a waiter's check (a waiter holds the
            // lock from its check until it sleeps), so no wake-up is lost.
            let _g = self.lock.lock();
            self.zero.notify_all();
        }
    }

    fn wait_zero(&self) {
        let mut g = self.lock.lock();
        while self.count.load(Ordering::Acquire) != 0 {
            self.zero.wait(&mut g);
        }
    }
}

/// Counters of the work done, for tests and the `root.dataserver` statistics.
#[derive(Default)]
pub struct Stats {
    pub jobs_run: AtomicU64,
    pub callbacks_run: AtomicU64,
    pub panics_caught: AtomicU64,
    pub timer_fired: AtomicU64,
}

pub(crate) struct Pool {
    tx: Sender<Job>,
    pub(crate) inflight: Arc<Inflight>,
    pub(crate) stats: Arc<Stats>,
}

impl Pool {
    pub(crate) fn new(workers: usize) -> Arc<Pool> {
        let (tx, rx) = crossbeam_channel::unbounded::<Job>();
        let inflight = Arc::new(Inflight::default());
        let stats = Arc::new(Stats::default());
        for i in 0..workers.max(1) {
            let rx: Receiver<Job> = rx.clone();
            let inflight = inflight.clone();
            let stats = stats.clone();
            thread::Builder::new()
                .name(format!("dataserver-{i}"))
                .spawn(move || {
                    while let Ok(job) = rx.recv() {
                        if catch_unwind(AssertUnwindSafe(job)).is_err() {
                            stats.panics_caught.fetch_add(1, Ordering::Relaxed);
                        }
                        stats.jobs_run.fetch_add(1, Ordering::Relaxed);
                        inflight.done();
                    }
                })
                .expect("spawning a DataServer worker thread");
        }
        Arc::new(Pool { tx, inflight, stats })
    }

    pub(crate) fn submit(&self, job: Job) {
        self.inflight.add();
        if self.tx.send(job).is_err() {
            // Workers are gone (shutting down): the job is dropped.
            self.inflight.done();
        }
    }
}

/// Where a piece of work runs: any worker of the pool, or in order on one serial executor.
#[derive(Clone)]
pub(crate) enum Target {
    Pool(Arc<Pool>),
    Serial(Executor),
}

impl Target {
    pub(crate) fn submit(&self, job: Job) {
        match self {
            Target::Pool(pool) => pool.submit(job),
            Target::Serial(ex) => ex.spawn_job(job),
        }
    }
}

/// A serial executor: jobs given to it run one at a time, in order, on the DataServer's
/// workers, so a module whose callbacks all run here need not be thread-safe. It owns no
/// thread.
#[derive(Clone)]
pub struct Executor {
    inner: Arc<SerialInner>,
}

struct SerialInner {
    pool: Arc<Pool>,
    state: Mutex<SerialState>,
}

#[derive(Default)]
struct SerialState {
    queue: VecDeque<Job>,
    scheduled: bool,
}

/// How many jobs a serial executor runs before giving its worker back to the pool.
const SERIAL_BATCH: usize = 64;

impl Executor {
    pub(crate) fn new(pool: Arc<Pool>) -> Executor {
        Executor { inner: Arc::new(SerialInner { pool, state: Mutex::default() }) }
    }

    /// Runs `f` on this executor, after everything already given to it.
    pub fn spawn(&self, f: impl FnOnce() + Send + 'static) {
        self.spawn_job(Box::new(f))
    }

    pub(crate) fn spawn_job(&self, job: Job) {
        let mut st = self.inner.state.lock();
        st.queue.push_back(job);
        if !st.scheduled {
            st.scheduled = true;
            drop(st);
            let inner = self.inner.clone();
            self.inner.pool.submit(Box::new(move || SerialInner::drain(inner)));
        }
    }
}

impl SerialInner {
    fn drain(this: Arc<SerialInner>) {
        for _ in 0..SERIAL_BATCH {
            let job = {
                let mut st = this.state.lock();
                match st.queue.pop_front() {
                    Some(j) => j,
                    None => {
                        st.scheduled = false;
                        return;
                    }
                }
            };
            if catch_unwind(AssertUnwindSafe(job)).is_err() {
                this.pool.stats.panics_caught.fetch_add(1, Ordering::Relaxed);
            }
        }
        // Still work left: requeue behind other modules' work instead of hogging a worker.
        let pool = this.pool.clone();
        pool.submit(Box::new(move || SerialInner::drain(this)));
    }
}

/// Delayed work: a heap of deadlines served by one timer thread that sleeps until the
/// earliest one (no polling, no periodic wake-up when there is nothing to do).
pub(crate) struct Timer {
    shared: Arc<TimerShared>,
}

struct TimerShared {
    state: Mutex<TimerState>,
    wake: Condvar,
    pending: AtomicUsize,
}

#[derive(Default)]
struct TimerState {
    heap: BinaryHeap<Reverse<(Instant, u64)>>,
    jobs: std::collections::HashMap<u64, (Target, Job)>,
    seq: u64,
    stop: bool,
}

impl Timer {
    pub(crate) fn new(stats: Arc<Stats>) -> Timer {
        let shared = Arc::new(TimerShared {
            state: Mutex::default(),
            wake: Condvar::new(),
            pending: AtomicUsize::new(0),
        });
        let s = shared.clone();
        thread::Builder::new()
            .name("dataserver-timer".into())
            .spawn(move || Timer::run(s, stats))
            .expect("spawning the DataServer timer thread");
        Timer { shared }
    }

    pub(crate) fn schedule(&self, delay: Duration, target: Target, job: Job) {
        let mut st = self.shared.state.lock();
        st.seq += 1;
        let id = st.seq;
        let due = Instant::now() + delay;
        let earliest = st.heap.peek().map(|Reverse((t, _))| *t);
        st.heap.push(Reverse((due, id)));
        st.jobs.insert(id, (target, job));
        self.shared.pending.fetch_add(1, Ordering::Relaxed);
        if earliest.is_none_or(|e| due < e) {
            self.shared.wake.notify_one();
        }
    }

    /// Delayed jobs not yet due.
    pub(crate) fn pending(&self) -> usize {
        self.shared.pending.load(Ordering::Relaxed)
    }

    fn run(shared: Arc<TimerShared>, stats: Arc<Stats>) {
        let mut st = shared.state.lock();
        loop {
            if st.stop {
                return;
            }
            let now = Instant::now();
            match st.heap.peek().map(|Reverse(x)| *x) {
                Some((due, id)) if due <= now => {
                    st.heap.pop();
                    if let Some((target, job)) = st.jobs.remove(&id) {
                        shared.pending.fetch_sub(1, Ordering::Relaxed);
                        stats.timer_fired.fetch_add(1, Ordering::Relaxed);
                        drop(st);
                        target.submit(job);
                        st = shared.state.lock();
                    }
                }
                Some((due, _)) => {
                    shared.wake.wait_until(&mut st, due);
                }
                None => shared.wake.wait(&mut st),
            }
        }
    }
}

impl Drop for Timer {
    fn drop(&mut self) {
        let mut st = self.shared.state.lock();
        st.stop = true;
        st.jobs.clear();
        self.shared.wake.notify_all();
    }
}

pub(crate) fn wait_quiet(pool: &Pool) {
    pool.inflight.wait_zero();
}
