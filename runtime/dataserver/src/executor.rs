//! Where DataServer work runs: an elastic worker pool and serial executors (strands) on top
//! of it (the timer is in `timer.rs`). Nothing here knows about objects or properties.

use crossbeam_channel::{Receiver, Sender};
use parking_lot::{Condvar, Mutex};
use std::collections::VecDeque;
use std::panic::{AssertUnwindSafe, catch_unwind};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, AtomicU64, AtomicUsize, Ordering};
use std::thread;
use std::time::Duration;

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
    /// Workers the pool added because all of them were stuck (see `docs/dataserver.md`).
    pub workers_added: AtomicU64,
}

/// The worker pool. It starts with `Config::workers` threads and grows when they are all
/// stuck: a watchdog thread, woken only when a job is queued while no worker is idle, looks
/// again after [`STALL`]; if the queue is still waiting, no worker is idle and no job has
/// started meanwhile, it adds one worker (up to [`MAX_EXTRA`] beyond the base). An extra
/// worker that finds nothing to do for [`RETIRE`] ends. So callbacks blocked in user code
/// delay only themselves: the rest of the process is served by the replacement.
pub(crate) struct Pool {
    tx: Sender<Job>,
    core: Arc<PoolCore>,
    pub(crate) inflight: Arc<Inflight>,
    pub(crate) stats: Arc<Stats>,
}

/// How long every worker may be busy, with work waiting, before the pool grows.
pub(crate) const STALL: Duration = Duration::from_millis(20);
/// How many workers the pool may add beyond its base.
pub(crate) const MAX_EXTRA: usize = 64;
/// How long an added worker waits for work before it ends.
const RETIRE: Duration = Duration::from_secs(5);

struct PoolCore {
    rx: Receiver<Job>,
    inflight: Arc<Inflight>,
    stats: Arc<Stats>,
    base: usize,
    /// Workers alive.
    workers: AtomicUsize,
    /// Workers waiting for a job.
    idle: AtomicUsize,
    /// Jobs taken by a worker so far (progress, for the watchdog).
    started: AtomicU64,
    /// The watchdog waits for a stall (a submit must wake it).
    armed: AtomicBool,
    watch: Mutex<bool>,
    wake: Condvar,
    next_name: AtomicUsize,
}

impl Pool {
    pub(crate) fn new(workers: usize) -> Arc<Pool> {
        let (tx, rx) = crossbeam_channel::unbounded::<Job>();
        let inflight = Arc::new(Inflight::default());
        let stats = Arc::new(Stats::default());
        let base = workers.max(1);
        let core = Arc::new(PoolCore {
            rx,
            inflight: inflight.clone(),
            stats: stats.clone(),
            base,
            workers: AtomicUsize::new(0),
            idle: AtomicUsize::new(0),
            started: AtomicU64::new(0),
            armed: AtomicBool::new(false),
            watch: Mutex::new(false),
            wake: Condvar::new(),
            next_name: AtomicUsize::new(0),
        });
        for _ in 0..base {
            PoolCore::spawn_worker(&core, false);
        }
        let c = core.clone();
        thread::Builder::new()
            .name("dataserver-watchdog".into())
            .spawn(move || PoolCore::watchdog(c))
            .expect("spawning the DataServer watchdog thread");
        Arc::new(Pool { tx, core, inflight, stats })
    }

    pub(crate) fn submit(&self, job: Job) {
        self.inflight.add();
        if self.tx.send(job).is_err() {
            // Workers are gone (shutting down): the job is dropped.
            self.inflight.done();
            return;
        }
        self.core.nudge();
    }

    /// Workers alive now (the base plus any added while others were stuck).
    pub(crate) fn workers(&self) -> usize {
        self.core.workers.load(Ordering::Relaxed)
    }
}

impl Drop for Pool {
    fn drop(&mut self) {
        *self.core.watch.lock() = true;
        self.core.wake.notify_all();
    }
}

impl PoolCore {
    fn spawn_worker(core: &Arc<PoolCore>, extra: bool) {
        core.workers.fetch_add(1, Ordering::AcqRel);
        let c = core.clone();
        let i = core.next_name.fetch_add(1, Ordering::Relaxed);
        let spawned = thread::Builder::new()
            .name(format!("dataserver-{i}"))
            .spawn(move || PoolCore::work(c, extra));
        if spawned.is_err() {
            core.workers.fetch_sub(1, Ordering::AcqRel);
        }
    }

    fn work(core: Arc<PoolCore>, extra: bool) {
        loop {
            core.idle.fetch_add(1, Ordering::SeqCst);
            let job = if extra {
                match core.rx.recv_timeout(RETIRE) {
                    Ok(job) => Some(job),
                    Err(crossbeam_channel::RecvTimeoutError::Timeout) => {
                        core.idle.fetch_sub(1, Ordering::SeqCst);
                        if core.retire() {
                            return;
                        }
                        continue;
                    }
                    Err(crossbeam_channel::RecvTimeoutError::Disconnected) => None,
                }
            } else {
                core.rx.recv().ok()
            };
            core.idle.fetch_sub(1, Ordering::SeqCst);
            // Taking the last idle worker with work still queued may start a stall.
            core.nudge();
            let Some(job) = job else {
                core.workers.fetch_sub(1, Ordering::AcqRel);
                return;
            };
            core.started.fetch_add(1, Ordering::Relaxed);
            if catch_unwind(AssertUnwindSafe(job)).is_err() {
                core.stats.panics_caught.fetch_add(1, Ordering::Relaxed);
            }
            core.stats.jobs_run.fetch_add(1, Ordering::Relaxed);
            core.inflight.done();
        }
    }

    /// An added worker leaves if the pool is above its base.
    fn retire(&self) -> bool {
        let mut n = self.workers.load(Ordering::Acquire);
        while n > self.base {
            match self.workers.compare_exchange(n, n - 1, Ordering::AcqRel, Ordering::Acquire) {
                Ok(_) => return true,
                Err(now) => n = now,
            }
        }
        false
    }

    fn stalled(&self) -> bool {
        self.idle.load(Ordering::SeqCst) == 0 && !self.rx.is_empty()
    }

    /// Wakes the watchdog if work waits while no worker is idle (two loads otherwise).
    fn nudge(&self) {
        if self.armed.load(Ordering::SeqCst) && self.stalled() {
            let _g = self.watch.lock();
            self.wake.notify_one();
        }
    }

    fn watchdog(core: Arc<PoolCore>) {
        let mut stop = core.watch.lock();
        loop {
            if *stop {
                return;
            }
            if !core.stalled() {
                core.armed.store(true, Ordering::SeqCst);
                // Re-checked under the lock a submit takes to wake us: no lost wake-up.
                if !core.stalled() {
                    core.wake.wait(&mut stop);
                }
                core.armed.store(false, Ordering::SeqCst);
                continue;
            }
            let seen = core.started.load(Ordering::Relaxed);
            core.wake.wait_for(&mut stop, STALL);
            if *stop {
                return;
            }
            let grown = core.workers.load(Ordering::Acquire) >= core.base + MAX_EXTRA;
            if core.stalled() && core.started.load(Ordering::Relaxed) == seen && !grown {
                core.stats.workers_added.fetch_add(1, Ordering::Relaxed);
                PoolCore::spawn_worker(&core, true);
            }
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
    /// Whether both run jobs in the same place (the same pool, or the same serial executor).
    pub(crate) fn same(&self, other: &Target) -> bool {
        match (self, other) {
            (Target::Pool(a), Target::Pool(b)) => Arc::ptr_eq(a, b),
            (Target::Serial(a), Target::Serial(b)) => Arc::ptr_eq(&a.inner, &b.inner),
            _ => false,
        }
    }

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

pub(crate) fn wait_quiet(pool: &Pool) {
    pool.inflight.wait_zero();
}

/// Whether nothing is pending or running on the pool now.
pub(crate) fn is_quiet(pool: &Pool) -> bool {
    pool.inflight.count.load(Ordering::Acquire) == 0
}
