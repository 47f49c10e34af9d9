//! The headless frame loop of `mocu run`. Nothing polls: with `--frames N` the loop ticks
//! N times at the display rate (the command-line contract: N frames in real time); without
//! it the loop sleeps until the world model changes what the display shows, a module
//! reports, or a stop is asked for, and draws at most one frame per display period.
//!
//! A run with `--frames N` is clocked by its frames ([`Stepped`]): the DataServer's clock
//! moves one display period per frame, its timers firing one at a time in deadline order
//! (`DataServer::advance_settled`), so a seeded simulator under an input script ends in the
//! same state every run, whatever the machine's load.

use crossbeam_channel::{Receiver, Sender, bounded, never, select};
use mocu_dataserver::{Clock, DataServer, ManualClock};
use mocu_display::{ChangeWaiter, Display, FrameStats};
use mocu_host::HostEvent;
use std::time::{Duration, Instant};

/// A run's clock moved by its frames: the DataServer built on `clock` does not see the
/// system's time pass, only whole display periods, each settled in order.
#[derive(Clone)]
pub struct Stepped {
    pub ds: DataServer,
    pub clock: ManualClock,
}

impl Default for Stepped {
    fn default() -> Stepped {
        Stepped::new()
    }
}

impl Stepped {
    /// A DataServer on a clock of its own, standing still until [`Stepped::advance`].
    pub fn new() -> Stepped {
        let clock = ManualClock::new();
        let ds = DataServer::with_clock(Default::default(), std::sync::Arc::new(clock.clone()));
        Stepped { ds, clock }
    }

    /// Moves the run's clock `d` forward, firing what falls due one job at a time.
    pub fn advance(&self, d: Duration) {
        self.ds.advance_settled(&self.clock, self.clock.now() + d);
    }
}

/// How long the loop runs.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Pace {
    /// N frame ticks at the display rate, in real time.
    Frames(u64),
    /// Until a stop is asked for, drawing only when something changed.
    UntilStopped,
}

/// What the loop did (the idle test counts these).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct LoopCounters {
    /// Times the loop's thread woke up, for whatever reason.
    pub wakeups: u64,
    /// Frame ticks (`display.frame()` calls).
    pub ticks: u64,
    /// Ticks that drew something.
    pub drawn: u64,
}

/// Where the loop hears about things besides the display.
pub struct Inputs<'a> {
    /// A message (or a closed channel) asks the loop to end.
    pub stop: &'a Receiver<()>,
    /// The module host's reports.
    pub events: &'a Receiver<HostEvent>,
    /// The run's clock, when its frames move it (`--frames N` headless).
    pub stepped: Option<&'a Stepped>,
}

/// Runs frames on `display` until `pace` is done or a stop is asked for. `on_event` gets
/// each host report as it comes, `on_frame` each frame ticked.
/// The display of a headless run or replay: on the CPU, the window manager's behaviours
/// left to the `window_manager` module.
pub fn cpu_display(
    ds: &DataServer,
    (w, h): (u32, u32),
) -> Result<Display, mocu_display::DisplayError> {
    let options = mocu_display::DisplayOptions::new(w, h)
        .backend(mocu_display::BackendChoice::Cpu)
        .without_window_behaviours();
    Display::new(ds, options)
}

pub fn run(
    display: &mut Display,
    pace: Pace,
    inputs: Inputs<'_>,
    mut on_event: impl FnMut(HostEvent),
    mut on_frame: impl FnMut(&FrameStats),
) -> LoopCounters {
    let period = Duration::from_secs_f64(1.0 / mocu_display::DEFAULT_RATE);
    let mut c = LoopCounters::default();
    let mut events = inputs.events.clone();
    let stop = inputs.stop;
    let stepped = inputs.stepped;
    let mut tick = |display: &mut Display, c: &mut LoopCounters| {
        if let Some(s) = stepped {
            s.advance(period);
        }
        display.tick_animations();
        let st = display.frame();
        c.ticks += 1;
        c.drawn += st.drawn as u64;
        on_frame(&st);
    };
    match pace {
        Pace::Frames(n) => {
            let ticker = crossbeam_channel::tick(period);
            while c.ticks < n {
                select! {
                    recv(stop) -> _ => break,
                    recv(events) -> e => match e {
                        Ok(e) => on_event(e),
                        Err(_) => events = never(),
                    },
                    recv(ticker) -> _ => tick(display, &mut c),
                }
                c.wakeups += 1;
            }
        }
        Pace::UntilStopped => {
            let (changes, ack) = wake_on_change(display.change_waiter());
            // The first frame at once, whatever is there yet.
            tick(display, &mut c);
            let mut next = Instant::now() + period;
            'run: loop {
                select! {
                    recv(stop) -> _ => break,
                    recv(events) -> e => match e {
                        Ok(e) => on_event(e),
                        Err(_) => events = never(),
                    },
                    recv(changes) -> _ => {
                        // At most one frame per display period: a burst of changes waits
                        // for the next one (still ending at once when asked to).
                        let wait = next.saturating_duration_since(Instant::now());
                        if !wait.is_zero() {
                            select! {
                                recv(stop) -> _ => break 'run,
                                recv(crossbeam_channel::after(wait)) -> _ => {}
                            }
                            c.wakeups += 1;
                        }
                        tick(display, &mut c);
                        next = Instant::now() + period;
                        let _ = ack.send(());
                    },
                }
                c.wakeups += 1;
            }
            drop((changes, ack));
            // The waker sleeps until a change: one more ends it (it finds us gone).
            display.invalidate_all();
        }
    }
    c
}

/// A thread that sleeps until the display has something to draw, says so, and waits for
/// the frame to be drawn before it sleeps again: one message per frame to draw.
fn wake_on_change(waiter: ChangeWaiter) -> (Receiver<()>, Sender<()>) {
    let (changed_tx, changed_rx) = bounded(1);
    let (ack_tx, ack_rx) = bounded::<()>(1);
    let spawned = std::thread::Builder::new().name("mocu-frame-waker".into()).spawn(move || {
        loop {
            if waiter.wait(Duration::MAX)
                && (changed_tx.send(()).is_err() || ack_rx.recv().is_err())
            {
                return;
            }
        }
    });
    if let Err(e) = spawned {
        eprintln!("mocu: cannot start the frame waker ({e}); the display will not update");
    }
    (changed_rx, ack_tx)
}

#[cfg(test)]
mod tests {
    use super::*;
    use mocu_dataserver::DataServer;
    use mocu_display::{DisplayOptions, Rect, claim_window, invalidate, publish_window};

    /// A display with one window whose painter fills it, and the loop on a thread.
    struct Rig {
        ds: DataServer,
        window: mocu_dataserver::Guid,
        stop: Sender<()>,
        frames: Receiver<bool>,
        done: std::thread::JoinHandle<LoopCounters>,
        _events: Sender<HostEvent>,
    }

    fn rig(pace: Pace) -> Rig {
        let ds = DataServer::default();
        let (stop_tx, stop_rx) = bounded::<()>(1);
        let (ev_tx, ev_rx) = crossbeam_channel::unbounded();
        let (frame_tx, frame_rx) = crossbeam_channel::unbounded();
        let (ready_tx, ready_rx) = bounded(1);
        let ds2 = ds.clone();
        let done = std::thread::spawn(move || {
            let mut d = Display::new(&ds2, DisplayOptions::new(64, 48)).unwrap();
            let g = publish_window(
                &ds2,
                d.display_object(),
                "w",
                "test",
                0,
                Rect::new(0.0, 0.0, 64.0, 48.0),
            )
            .unwrap();
            claim_window(&ds2, g, |c, _| {
                c.fill_rect(Rect::new(0.0, 0.0, 64.0, 48.0), mocu_display::Color::rgb(200, 0, 0))
            })
            .unwrap();
            ready_tx.send(g).unwrap();
            ds2.quiesce(); // the window manager knows the window before the first frame
            let inputs = Inputs { stop: &stop_rx, events: &ev_rx, stepped: None };
            run(
                &mut d,
                pace,
                inputs,
                |_| {},
                |st| {
                    let _ = frame_tx.send(st.drawn);
                },
            )
        });
        let window = ready_rx.recv().unwrap();
        Rig { ds, window, stop: stop_tx, frames: frame_rx, done, _events: ev_tx }
    }

    /// Waits for the next frame that drew something.
    fn next_drawn(r: &Rig) {
        while !r.frames.recv().expect("the loop ended early") {}
    }

    #[test]
    fn an_idle_headless_run_wakes_only_for_changes_and_the_stop() {
        let r = rig(Pace::UntilStopped);
        next_drawn(&r); // the first frame
        for _ in 0..3 {
            invalidate(&r.ds, r.window).unwrap();
            next_drawn(&r);
        }
        let before = r.frames.try_iter().count();
        // Idle: nothing changes while time passes (the stimulus a poller reacts to: 18
        // frames at 60 Hz). The assertions count; none depends on how long this is.
        let _ = crossbeam_channel::after(Duration::from_millis(300)).recv();
        let idle = r.frames.try_iter().count();
        r.stop.send(()).unwrap();
        let c = r.done.join().unwrap();
        assert!(before + idle <= 1, "frames with nothing changed: {before} + {idle}, {c:?}");
        assert!(c.drawn >= 4, "one frame per change and the first: {c:?}");
        // Each frame: its wake-up and at most one paced wait; then the stop.
        assert!(c.wakeups <= 2 * c.ticks + 1, "woke with nothing to do: {c:?}");
    }

    #[test]
    fn frames_n_ticks_n_times_drawing_only_what_changed() {
        let r = rig(Pace::Frames(12));
        let c = r.done.join().unwrap();
        assert_eq!(c.ticks, 12);
        assert_eq!(c.drawn, 1, "only the first frame had anything to draw: {c:?}");
        drop(r.stop);
    }

    #[test]
    fn a_stop_ends_a_frames_run_early() {
        let r = rig(Pace::Frames(u64::MAX));
        next_drawn(&r);
        r.stop.send(()).unwrap();
        let c = r.done.join().unwrap();
        assert!(c.ticks >= 1 && c.ticks < u64::MAX, "{c:?}");
    }
}
