//! Where the DataServer reads the time: the system clock, or a manual clock that tests move
//! forward. Timers, delayed calls, call timeouts and `received_at` all read the server's
//! clock, so a test that advances a [`ManualClock`] controls every one of them and never
//! sleeps.

use parking_lot::Mutex;
use std::sync::atomic::{AtomicI64, Ordering};
use std::sync::{Arc, OnceLock, Weak};
use std::time::{Duration, Instant, SystemTime, UNIX_EPOCH};

/// A source of time for a DataServer. Times are `std::time::Instant`s, so they mix with the
/// display's and the input engine's times.
pub trait Clock: Send + Sync + 'static {
    /// The current time.
    fn now(&self) -> Instant;

    /// The time of day (wall time, for what the operator reads: a clock, time stamps). The
    /// system clock's is the system's; a manual clock's moves with it.
    fn wall(&self) -> SystemTime {
        SystemTime::now()
    }

    /// The time of day at `now`, an instant this clock gave a moment ago: what a change
    /// stamped when it happened reads (the change feed) without reading a clock twice. By
    /// default the time of day now; the system clock works it out from `now`, a manual clock
    /// exactly.
    fn wall_at(&self, now: Instant) -> SystemTime {
        let _ = now;
        self.wall()
    }

    /// [`Clock::wall_at`] in nanoseconds since the Unix epoch (0 before it): what the change
    /// feed stamps with, once per change (the system clock skips the `SystemTime` round trip).
    fn wall_ns_at(&self, now: Instant) -> u64 {
        self.wall_at(now).duration_since(UNIX_EPOCH).map_or(0, |d| {
            d.as_secs().saturating_mul(1_000_000_000).saturating_add(u64::from(d.subsec_nanos()))
        })
    }

    /// Called once by each DataServer built on this clock. A clock that moves only when
    /// told (a manual clock) keeps `fire` and calls it after every move, and returns true;
    /// the system clock ignores it and returns false (its timers wait on real time).
    fn on_advance(&self, fire: Weak<dyn Fn() + Send + Sync>) -> bool {
        let _ = fire;
        false
    }
}

/// The real, monotonic clock (the default).
#[derive(Clone, Copy, Debug, Default)]
pub struct SystemClock;

impl Clock for SystemClock {
    fn now(&self) -> Instant {
        Instant::now()
    }

    /// `now` plus the offset between the system's time of day and its monotonic clock, read
    /// again at most [`OFFSET_FOR`] after it was last read: so it follows the system's clock
    /// being set or slewed within that, and costs no system call otherwise.
    fn wall_at(&self, now: Instant) -> SystemTime {
        UNIX_EPOCH + Duration::from_nanos(self.wall_ns_at(now))
    }

    fn wall_ns_at(&self, now: Instant) -> u64 {
        let base = *BASE.get_or_init(Instant::now);
        let since = now.saturating_duration_since(base);
        let mono = (since.as_secs() as i64)
            .saturating_mul(1_000_000_000)
            .saturating_add(i64::from(since.subsec_nanos()));
        let read = OFFSET_READ_AT.load(Ordering::Relaxed);
        let offset = if read == i64::MIN || !(0..OFFSET_FOR).contains(&(mono - read)) {
            let wall = SystemTime::now().duration_since(UNIX_EPOCH).map_or(0, |d| d.as_nanos());
            let at = Instant::now().saturating_duration_since(base).as_nanos() as i64;
            let offset = wall as i64 - at;
            OFFSET.store(offset, Ordering::Relaxed);
            OFFSET_READ_AT.store(at, Ordering::Relaxed);
            offset
        } else {
            OFFSET.load(Ordering::Relaxed)
        };
        mono.saturating_add(offset).max(0) as u64
    }
}

/// `at + d`, or the latest time of day a `SystemTime` holds where that does not fit.
fn saturating_wall(at: SystemTime, d: Duration) -> SystemTime {
    at.checked_add(d).unwrap_or_else(|| {
        static LATEST: OnceLock<SystemTime> = OnceLock::new();
        *LATEST.get_or_init(|| {
            // The platform's limit, found by halving steps up from the epoch.
            let mut t = UNIX_EPOCH;
            let mut step = Duration::MAX;
            while step > Duration::ZERO {
                match t.checked_add(step) {
                    Some(next) => t = next,
                    None => step /= 2,
                }
            }
            t
        })
    })
}

/// How long the system clock's [`Clock::wall_at`] trusts the offset it read (ns).
const OFFSET_FOR: i64 = 100_000_000;
/// The instant monotonic times count from.
static BASE: OnceLock<Instant> = OnceLock::new();
/// The time of day less the monotonic time since [`BASE`] (ns), and when it was read.
static OFFSET: AtomicI64 = AtomicI64::new(0);
static OFFSET_READ_AT: AtomicI64 = AtomicI64::new(i64::MIN);

/// A clock that stands still until [`ManualClock::advance`] moves it. Advancing fires every
/// timer, delayed call and timeout that falls due, before `advance` returns: their jobs are
/// queued (timeouts answered) by then, and `DataServer::quiesce` waits for the jobs to run.
/// Cheap to clone; clones are the same clock.
#[derive(Clone)]
pub struct ManualClock {
    inner: Arc<ManualInner>,
}

struct ManualInner {
    now: Mutex<Instant>,
    /// The wall time at `start` (then `wall` is `wall0 + (now - start)`).
    wall0: Mutex<SystemTime>,
    start: Instant,
    fire: Mutex<Vec<Weak<dyn Fn() + Send + Sync>>>,
}

impl Default for ManualClock {
    fn default() -> Self {
        ManualClock::new()
    }
}

impl std::fmt::Debug for ManualClock {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("ManualClock").field("now", &*self.inner.now.lock()).finish()
    }
}

impl ManualClock {
    /// A manual clock reading the real time of its creation.
    pub fn new() -> ManualClock {
        let start = Instant::now();
        ManualClock {
            inner: Arc::new(ManualInner {
                now: Mutex::new(start),
                wall0: Mutex::new(SystemTime::now()),
                start,
                fire: Mutex::default(),
            }),
        }
    }

    /// Sets the time of day that [`Clock::wall`] reads now (it moves on with `advance`):
    /// a test's fixed wall time.
    pub fn set_wall(&self, wall: SystemTime) {
        let since = *self.inner.now.lock() - self.inner.start;
        *self.inner.wall0.lock() = wall.checked_sub(since).unwrap_or(wall);
    }

    /// Moves the clock forward by `d` (saturating: a huge `d` moves it as far as an
    /// `Instant` goes) and fires what fell due.
    pub fn advance(&self, d: Duration) {
        {
            let mut now = self.inner.now.lock();
            *now = crate::timer::saturating_add(*now, d).unwrap_or(*now);
        }
        let fire: Vec<_> = {
            let mut fs = self.inner.fire.lock();
            fs.retain(|f| f.strong_count() > 0);
            fs.iter().filter_map(Weak::upgrade).collect()
        };
        for f in fire {
            f();
        }
    }
}

impl ManualClock {
    /// Sets the clock to `t` (never backwards) without firing anything: for
    /// [`crate::DataServer::advance_settled`], which fires what falls due itself.
    pub(crate) fn move_to(&self, t: Instant) {
        let mut now = self.inner.now.lock();
        *now = (*now).max(t);
    }
}

impl Clock for ManualClock {
    fn now(&self) -> Instant {
        *self.inner.now.lock()
    }

    fn wall(&self) -> SystemTime {
        self.wall_at(self.now())
    }

    /// Saturates where the clock has moved further than a `SystemTime` goes (it never
    /// panics, whatever `advance` was given).
    fn wall_at(&self, now: Instant) -> SystemTime {
        saturating_wall(*self.inner.wall0.lock(), now.saturating_duration_since(self.inner.start))
    }

    fn on_advance(&self, fire: Weak<dyn Fn() + Send + Sync>) -> bool {
        self.inner.fire.lock().push(fire);
        true
    }
}
