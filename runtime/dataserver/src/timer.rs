//! Delayed work: deadlines on the server's clock, served by one timer thread that sleeps
//! until the earliest one (no polling, no periodic wake-up when there is nothing to do).
//!
//! A due job either goes to its target (the pool or a serial executor) or, for call
//! timeouts, runs on the timer thread itself: a `TimedOut` answer never needs a free worker,
//! so timeouts fire whatever the workers are doing. With a manual clock the timer thread
//! only serves jobs that are already due; `ManualClock::advance` fires the rest on the
//! advancing thread before it returns.

use crate::clock::Clock;
use crate::executor::{Job, Stats, Target};
use parking_lot::{Condvar, Mutex};
use std::collections::BTreeMap;
use std::panic::{AssertUnwindSafe, catch_unwind};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::{Arc, Weak};
use std::thread;
use std::time::{Duration, Instant};

/// How far "never" is: a delay that does not fit an `Instant` is clamped to this.
const FAR: Duration = Duration::from_secs(100 * 365 * 24 * 3600);

/// `at + d`, saturating at a hundred years from `at`; `None` only where even that does not
/// fit (then the deadline is never reached).
pub(crate) fn saturating_add(at: Instant, d: Duration) -> Option<Instant> {
    at.checked_add(d).or_else(|| at.checked_add(FAR))
}

/// Where a due job runs.
pub(crate) enum Fire {
    /// On the timer thread (or the thread advancing a manual clock): only short, non-blocking
    /// work such as answering `TimedOut`.
    Inline,
    Submit(Target),
}

/// Names one scheduled job, to cancel it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct TimerKey {
    due: Instant,
    id: u64,
}

pub(crate) struct Timer {
    shared: Arc<TimerShared>,
    /// Kept alive for the manual clock, which holds it weakly.
    _fire: Arc<dyn Fn() + Send + Sync>,
}

struct TimerShared {
    state: Mutex<TimerState>,
    wake: Condvar,
    pending: AtomicUsize,
    clock: Arc<dyn Clock>,
    stats: Arc<Stats>,
    manual: std::sync::atomic::AtomicBool,
    /// While set (a manual clock stepped by `DataServer::advance_settled`), only the
    /// stepping thread fires jobs, one at a time.
    held: std::sync::atomic::AtomicBool,
    /// Jobs taken off the schedule and not yet handed to their executor (or still running
    /// inline): `DataServer::quiesce` waits for them too, or a job the timer thread had
    /// just taken could land after a quiesce that found the pool idle.
    firing: AtomicUsize,
}

#[derive(Default)]
struct TimerState {
    jobs: BTreeMap<(Instant, u64), (Fire, Job)>,
    seq: u64,
    stop: bool,
}

impl Timer {
    pub(crate) fn new(stats: Arc<Stats>, clock: Arc<dyn Clock>) -> Timer {
        let shared = Arc::new(TimerShared {
            state: Mutex::default(),
            wake: Condvar::new(),
            pending: AtomicUsize::new(0),
            clock: clock.clone(),
            stats,
            manual: false.into(),
            held: false.into(),
            firing: AtomicUsize::new(0),
        });
        let weak = Arc::downgrade(&shared);
        let fire: Arc<dyn Fn() + Send + Sync> = Arc::new(move || {
            if let Some(s) = weak.upgrade() {
                s.fire_due();
            }
        });
        let manual = clock.on_advance(Arc::downgrade(&fire));
        shared.manual.store(manual, Ordering::Relaxed);
        let s = shared.clone();
        thread::Builder::new()
            .name("dataserver-timer".into())
            .spawn(move || TimerShared::run(s))
            .expect("spawning the DataServer timer thread");
        Timer { shared, _fire: fire }
    }

    /// The server's clock.
    pub(crate) fn clock(&self) -> &Arc<dyn Clock> {
        &self.shared.clock
    }

    /// Runs `job` after `delay` on the server's clock. A delay too large for the clock is
    /// clamped (a hundred years); `None` when the job can never fire (it is dropped).
    pub(crate) fn schedule(&self, delay: Duration, fire: Fire, job: Job) -> Option<TimerKey> {
        let due = saturating_add(self.shared.clock.now(), delay)?;
        let mut st = self.shared.state.lock();
        if st.stop {
            return None;
        }
        st.seq += 1;
        let key = TimerKey { due, id: st.seq };
        let earliest = st.jobs.keys().next().map(|k| k.0);
        st.jobs.insert((due, key.id), (fire, job));
        self.shared.pending.fetch_add(1, Ordering::Relaxed);
        if earliest.is_none_or(|e| due < e) {
            self.shared.wake.notify_one();
        }
        Some(key)
    }

    /// Removes a job that has not fired yet; returns whether it was still there.
    pub(crate) fn cancel(&self, key: TimerKey) -> bool {
        let gone = self.shared.state.lock().jobs.remove(&(key.due, key.id));
        match gone {
            Some(entry) => {
                self.shared.pending.fetch_sub(1, Ordering::Relaxed);
                drop(entry); // dropped outside the lock: it may own anything
                true
            }
            None => false,
        }
    }

    /// The deadline of the earliest job not yet fired.
    pub(crate) fn next_due(&self) -> Option<Instant> {
        self.shared.state.lock().jobs.keys().next().map(|k| k.0)
    }

    /// Fires every job that is due, on this thread, unless the timer is held.
    pub(crate) fn fire_due(&self) {
        self.shared.fire_due();
    }

    /// Whether a job is due and not held back (`DataServer::advance_settled` holds the
    /// timer and fires due jobs itself).
    pub(crate) fn has_due(&self) -> bool {
        if self.shared.held.load(Ordering::SeqCst) {
            return false;
        }
        let now = self.shared.clock.now();
        let st = self.shared.state.lock();
        !st.stop && st.jobs.keys().next().is_some_and(|k| k.0 <= now)
    }

    /// Fires the earliest job if it is due; returns whether one fired.
    pub(crate) fn fire_one(&self) -> bool {
        self.shared.fire_one()
    }

    /// Holds the timer thread (and `ManualClock::advance`) off firing, so that the caller
    /// alone fires due jobs with [`Timer::fire_one`]; releasing wakes the thread.
    pub(crate) fn hold(&self, on: bool) {
        self.shared.held.store(on, Ordering::SeqCst);
        if !on {
            let _st = self.shared.state.lock();
            self.shared.wake.notify_all();
        }
    }

    /// Jobs not yet due (cancelled ones do not count).
    pub(crate) fn pending(&self) -> usize {
        self.shared.pending.load(Ordering::Relaxed)
    }

    /// Jobs being handed over or run inline right now.
    pub(crate) fn firing(&self) -> usize {
        self.shared.firing.load(Ordering::SeqCst)
    }
}

impl TimerShared {
    /// Takes the earliest job if it is due.
    fn take_due(&self) -> Option<(Fire, Job)> {
        let now = self.clock.now();
        let mut st = self.state.lock();
        let (&(due, id), _) = st.jobs.iter().next()?;
        if due > now || st.stop {
            return None;
        }
        let entry = st.jobs.remove(&(due, id));
        self.pending.fetch_sub(1, Ordering::Relaxed);
        // Counted before the lock is released: nobody sees the job neither scheduled nor
        // firing.
        self.firing.fetch_add(1, Ordering::SeqCst);
        entry
    }

    /// Fires every due job, in deadline order (unless held).
    fn fire_due(&self) {
        loop {
            if self.held.load(Ordering::SeqCst) || !self.fire_one() {
                return;
            }
        }
    }

    /// Fires the earliest job if it is due.
    fn fire_one(&self) -> bool {
        let Some((fire, job)) = self.take_due() else { return false };
        self.stats.timer_fired.fetch_add(1, Ordering::Relaxed);
        match fire {
            Fire::Inline => {
                if catch_unwind(AssertUnwindSafe(job)).is_err() {
                    self.stats.panics_caught.fetch_add(1, Ordering::Relaxed);
                }
            }
            Fire::Submit(target) => target.submit(job),
        }
        self.firing.fetch_sub(1, Ordering::SeqCst);
        true
    }

    fn run(shared: Arc<TimerShared>) {
        let weak: Weak<TimerShared> = Arc::downgrade(&shared);
        drop(shared);
        loop {
            let Some(shared) = weak.upgrade() else { return };
            shared.fire_due();
            let mut st = shared.state.lock();
            if st.stop {
                return;
            }
            let earliest = st.jobs.keys().next().map(|k| k.0);
            match earliest {
                Some(due) if due <= shared.clock.now() && !shared.held.load(Ordering::SeqCst) => {
                    continue;
                }
                Some(due) if !shared.manual.load(Ordering::Relaxed) => {
                    shared.wake.wait_until(&mut st, due);
                }
                _ => shared.wake.wait(&mut st),
            }
        }
    }
}

impl Drop for Timer {
    fn drop(&mut self) {
        let jobs = {
            let mut st = self.shared.state.lock();
            st.stop = true;
            self.shared.wake.notify_all();
            std::mem::take(&mut st.jobs)
        };
        self.shared.pending.store(0, Ordering::Relaxed);
        drop(jobs);
    }
}
