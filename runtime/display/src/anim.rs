//! Animations of window rectangles (`swap a b 300ms`, `animate rect 250ms ease-out`):
//! driven by DataServer delayed calls at the frame rate while any is active, silent
//! otherwise. Each step writes the windows' `x`, `y`, `w`, `h`, which the window manager
//! sees like any other change; input is never blocked because nothing here waits.

use mocu_dataserver::{DataServer, Guid, Value};
use parking_lot::Mutex;
use std::sync::Arc;
use std::time::{Duration, Instant};

/// An easing curve over `t` in 0..=1.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Easing {
    Linear,
    EaseIn,
    EaseOut,
    #[default]
    EaseInOut,
}

impl Easing {
    /// `linear`, `ease-in`, `ease-out`, `ease-in-out` (also with underscores).
    pub fn parse(name: &str) -> Option<Easing> {
        match name.replace('_', "-").as_str() {
            "linear" => Some(Easing::Linear),
            "ease-in" => Some(Easing::EaseIn),
            "ease-out" => Some(Easing::EaseOut),
            "ease-in-out" | "ease" => Some(Easing::EaseInOut),
            _ => None,
        }
    }

    /// Cubic curves; `apply(0) == 0`, `apply(1) == 1`.
    pub fn apply(self, t: f64) -> f64 {
        let t = t.clamp(0.0, 1.0);
        match self {
            Easing::Linear => t,
            Easing::EaseIn => t * t * t,
            Easing::EaseOut => 1.0 - (1.0 - t).powi(3),
            Easing::EaseInOut => {
                if t < 0.5 {
                    4.0 * t * t * t
                } else {
                    1.0 - (-2.0 * t + 2.0).powi(3) / 2.0
                }
            }
        }
    }
}

/// Where animations read the time: `Real` is the DataServer's clock (the system clock, or
/// the `ManualClock` given to `DataServer::with_clock`) and the server's timers drive them;
/// `Manual` is a clock of the display's own that tests advance (and call
/// [`crate::Display::tick_animations`]).
#[derive(Clone, Debug)]
pub enum Clock {
    Real,
    Manual(Arc<Mutex<Instant>>),
}

impl Clock {
    pub fn manual() -> Clock {
        Clock::Manual(Arc::new(Mutex::new(Instant::now())))
    }

    pub fn now(&self) -> Instant {
        match self {
            Clock::Real => Instant::now(),
            Clock::Manual(t) => *t.lock(),
        }
    }

    /// Moves a manual clock forward (no effect on the real clock).
    pub fn advance(&self, d: Duration) {
        if let Clock::Manual(t) = self {
            *t.lock() += d;
        }
    }
}

const RECT: [&str; 4] = ["x", "y", "w", "h"];

#[derive(Debug)]
struct Anim {
    window: Guid,
    from: [f64; 4],
    to: [f64; 4],
    start: Instant,
    duration: Duration,
    easing: Easing,
}

/// A pending exchange of two windows' stacking (`layer`, `order`), due at a swap's
/// midpoint: before it the growing window (the smaller one) is on top, after it the
/// shrinking one, so that the inset always shows.
#[derive(Debug)]
struct ZSwap {
    a: Guid,
    b: Guid,
    due: Instant,
}

#[derive(Default)]
struct State {
    anims: Vec<Anim>,
    zswaps: Vec<ZSwap>,
    ticking: bool,
}

/// The running animations of one display.
pub struct Animator {
    ds: DataServer,
    clock: Clock,
    interval: Duration,
    state: Mutex<State>,
}

impl Animator {
    pub(crate) fn new(ds: DataServer, clock: Clock, interval: Duration) -> Arc<Animator> {
        Arc::new(Animator { ds, clock, interval, state: Mutex::default() })
    }

    /// The time animations run on (see [`Clock`]).
    fn now(&self) -> Instant {
        match &self.clock {
            Clock::Real => self.ds.now(),
            manual => manual.now(),
        }
    }

    /// The window's current rectangle as the world model has it.
    pub fn rect_of(&self, window: Guid) -> [f64; 4] {
        RECT.map(|p| self.ds.get(window, p).ok().and_then(|v| v.as_f64()).unwrap_or(0.0))
    }

    /// Animates `window` from where it is now to `to`. Replaces any animation of it.
    pub fn start(self: &Arc<Self>, window: Guid, to: [f64; 4], duration: Duration, easing: Easing) {
        let from = self.rect_of(window);
        let start = self.now();
        let schedule = {
            let mut st = self.state.lock();
            st.anims.retain(|a| a.window != window);
            st.anims.push(Anim { window, from, to, start, duration, easing });
            let idle = !st.ticking;
            st.ticking = true;
            idle
        };
        // The first step now (a zero-length animation lands at once).
        if !self.tick() {
            return;
        }
        if schedule && matches!(self.clock, Clock::Real) {
            self.schedule();
        }
    }

    /// Exchanges the rectangles of two windows, animated (paper fig. 1). Their stacking
    /// (`layer` and `order`) is exchanged at the midpoint, when both have the same size.
    pub fn swap(self: &Arc<Self>, a: Guid, b: Guid, duration: Duration, easing: Easing) {
        let (ra, rb) = (self.rect_of(a), self.rect_of(b));
        {
            let mut st = self.state.lock();
            st.zswaps.retain(|z| ![z.a, z.b].iter().any(|g| *g == a || *g == b));
            st.zswaps.push(ZSwap { a, b, due: self.now() + duration / 2 });
        }
        self.start(a, rb, duration, easing);
        self.start(b, ra, duration, easing);
    }

    fn exchange_stacking(&self, a: Guid, b: Guid) {
        for p in ["layer", "order"] {
            let va = self.ds.get(a, p).unwrap_or(Value::Int(0));
            let vb = self.ds.get(b, p).unwrap_or(Value::Int(0));
            let _ = self.ds.set(a, p, vb);
            let _ = self.ds.set(b, p, va);
        }
    }

    /// How many animations are running.
    pub fn active(&self) -> usize {
        self.state.lock().anims.len()
    }

    /// Writes every animation's value for the clock's current time; drops finished ones.
    /// Returns whether any is still running.
    pub fn tick(&self) -> bool {
        let now = self.now();
        let mut writes = Vec::new();
        let mut zswaps = Vec::new();
        let running = {
            let mut st = self.state.lock();
            st.zswaps.retain(|z| {
                if now >= z.due {
                    zswaps.push((z.a, z.b));
                    false
                } else {
                    true
                }
            });
            st.anims.retain(|a| {
                let dt = now.saturating_duration_since(a.start);
                let t = if a.duration.is_zero() {
                    1.0
                } else {
                    dt.as_secs_f64() / a.duration.as_secs_f64()
                };
                let e = a.easing.apply(t);
                let v: [f64; 4] = std::array::from_fn(|i| a.from[i] + (a.to[i] - a.from[i]) * e);
                writes.push((a.window, if t >= 1.0 { a.to } else { v }));
                t < 1.0
            });
            if st.anims.is_empty() {
                st.ticking = false;
                st.zswaps.clear();
            }
            !st.anims.is_empty()
        };
        for (a, b) in zswaps {
            self.exchange_stacking(a, b);
        }
        for (w, v) in writes {
            for (p, x) in RECT.iter().zip(v) {
                let _ = self.ds.set(w, *p, Value::Float(x));
            }
        }
        running
    }

    fn schedule(self: &Arc<Self>) {
        let me = self.clone();
        self.ds.run_after(self.interval, None, move || {
            if me.tick() {
                me.schedule();
            }
        });
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn easings_start_at_zero_end_at_one_and_are_monotonic() {
        for e in [Easing::Linear, Easing::EaseIn, Easing::EaseOut, Easing::EaseInOut] {
            assert_eq!(e.apply(0.0), 0.0);
            assert!((e.apply(1.0) - 1.0).abs() < 1e-12);
            let mut last = 0.0;
            for i in 0..=100 {
                let v = e.apply(i as f64 / 100.0);
                assert!(v >= last - 1e-12, "{e:?} at {i}");
                last = v;
            }
        }
        assert_eq!(Easing::EaseInOut.apply(0.5), 0.5);
        assert_eq!(Easing::parse("ease_out"), Some(Easing::EaseOut));
    }
}
