//! Touch input as pointer input (the handheld OCU of the paper's figure 2): one finger is the
//! mouse, through the same routing and the same `bind mouse` bindings —
//!
//! - a tap (down and up without moving past [`TouchConfig::slop`]) is a left click where the
//!   finger went down;
//! - a drag (moving past the slop) is a left press where it went down, moves, and a release
//!   where it comes up;
//! - a long press (held still for [`TouchConfig::long_press`]) is a right click where it went
//!   down: the context menu. Lifting the finger afterwards does nothing more.
//!
//! A second finger is ignored while one is down. Time is an input ([`Touch::event`] and
//! [`Touch::tick`] take `now`); a window's event loop wakes at [`Touch::deadline`] to tick.

use crate::display::PointerEvent;
use std::time::{Duration, Instant};

/// What a touch does, from the OS (winit's `TouchPhase`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TouchPhase {
    Started,
    Moved,
    Ended,
    Cancelled,
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TouchConfig {
    /// Held still this long: a right click.
    pub long_press: Duration,
    /// Moved further than this (px): a drag, no longer a tap.
    pub slop: f32,
}

impl Default for TouchConfig {
    fn default() -> TouchConfig {
        TouchConfig { long_press: Duration::from_millis(500), slop: 10.0 }
    }
}

#[derive(Clone, Copy, Debug, PartialEq)]
enum State {
    /// Down, not moved: a tap or a long press yet.
    Still,
    Dragging,
    LongPressed,
}

#[derive(Clone, Copy, Debug)]
struct Finger {
    id: u64,
    start: (f32, f32),
    since: Instant,
    state: State,
}

/// Pointer input at a screen point.
pub type PointerInput = (f32, f32, PointerEvent);

/// The finger being followed, turned into pointer input.
#[derive(Debug, Default)]
pub struct Touch {
    cfg: TouchConfig,
    finger: Option<Finger>,
}

impl Touch {
    pub fn new(cfg: TouchConfig) -> Touch {
        Touch { cfg, finger: None }
    }

    /// One touch event: the pointer input it makes.
    pub fn event(
        &mut self,
        id: u64,
        phase: TouchPhase,
        x: f32,
        y: f32,
        now: Instant,
    ) -> Vec<PointerInput> {
        let mut out = self.tick(now);
        match (phase, self.finger) {
            (TouchPhase::Started, None) => {
                let state = State::Still;
                self.finger = Some(Finger { id, start: (x, y), since: now, state });
                out.push((x, y, PointerEvent::Move));
            }
            (_, Some(f)) if f.id != id => {}
            (TouchPhase::Moved, Some(mut f)) => {
                let (sx, sy) = f.start;
                let far = (x - sx).hypot(y - sy) > self.cfg.slop;
                if f.state == State::Still && far {
                    f.state = State::Dragging;
                    out.push((sx, sy, PointerEvent::Down(0)));
                }
                if f.state != State::Still {
                    out.push((x, y, PointerEvent::Move));
                }
                self.finger = Some(f);
            }
            (TouchPhase::Ended | TouchPhase::Cancelled, Some(f)) => {
                let (sx, sy) = f.start;
                match f.state {
                    State::Still if phase == TouchPhase::Ended => {
                        out.push((sx, sy, PointerEvent::Down(0)));
                        out.push((sx, sy, PointerEvent::Up(0)));
                    }
                    State::Dragging => out.push((x, y, PointerEvent::Up(0))),
                    _ => {}
                }
                out.push((x, y, PointerEvent::Leave));
                self.finger = None;
            }
            _ => {}
        }
        out
    }

    /// When a finger held still becomes a long press, if one is down.
    pub fn deadline(&self) -> Option<Instant> {
        self.finger.filter(|f| f.state == State::Still).map(|f| f.since + self.cfg.long_press)
    }

    /// The long press, once its time has come: a right click where the finger went down.
    pub fn tick(&mut self, now: Instant) -> Vec<PointerInput> {
        match &mut self.finger {
            Some(f) if f.state == State::Still && now >= f.since + self.cfg.long_press => {
                f.state = State::LongPressed;
                let (x, y) = f.start;
                vec![(x, y, PointerEvent::Down(1)), (x, y, PointerEvent::Up(1))]
            }
            _ => Vec::new(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use PointerEvent::{Down, Leave, Move, Up};
    use TouchPhase::{Ended, Moved, Started};

    fn ms(t0: Instant, n: u64) -> Instant {
        t0 + Duration::from_millis(n)
    }

    #[test]
    fn a_tap_is_a_left_click_where_the_finger_went_down() {
        let (mut t, t0) = (Touch::default(), Instant::now());
        assert_eq!(t.event(1, Started, 50.0, 60.0, t0), [(50.0, 60.0, Move)]);
        assert_eq!(t.event(1, Moved, 53.0, 62.0, ms(t0, 80)), [], "within the slop");
        assert_eq!(
            t.event(1, Ended, 53.0, 62.0, ms(t0, 120)),
            [(50.0, 60.0, Down(0)), (50.0, 60.0, Up(0)), (53.0, 62.0, Leave)]
        );
        assert_eq!(t.deadline(), None);
    }

    #[test]
    fn a_drag_presses_where_it_started_moves_and_releases_where_it_ends() {
        let (mut t, t0) = (Touch::default(), Instant::now());
        t.event(7, Started, 10.0, 10.0, t0);
        assert_eq!(
            t.event(7, Moved, 40.0, 10.0, ms(t0, 50)),
            [(10.0, 10.0, Down(0)), (40.0, 10.0, Move)]
        );
        assert_eq!(t.event(7, Moved, 80.0, 20.0, ms(t0, 900)), [(80.0, 20.0, Move)]);
        assert_eq!(t.tick(ms(t0, 1000)), [], "a drag never becomes a long press");
        assert_eq!(
            t.event(7, Ended, 80.0, 20.0, ms(t0, 950)),
            [(80.0, 20.0, Up(0)), (80.0, 20.0, Leave)]
        );
    }

    #[test]
    fn a_long_press_is_a_right_click_and_lifting_after_it_does_nothing_more() {
        let (mut t, t0) = (Touch::default(), Instant::now());
        t.event(3, Started, 100.0, 200.0, t0);
        assert_eq!(t.deadline(), Some(ms(t0, 500)));
        assert_eq!(t.tick(ms(t0, 499)), []);
        assert_eq!(t.tick(ms(t0, 500)), [(100.0, 200.0, Down(1)), (100.0, 200.0, Up(1))]);
        assert_eq!(t.tick(ms(t0, 900)), [], "once");
        assert_eq!(t.event(3, Ended, 100.0, 200.0, ms(t0, 1200)), [(100.0, 200.0, Leave)]);
    }

    #[test]
    fn a_second_finger_is_ignored_while_one_is_down() {
        let (mut t, t0) = (Touch::default(), Instant::now());
        t.event(1, Started, 10.0, 10.0, t0);
        assert_eq!(t.event(2, Started, 300.0, 300.0, ms(t0, 10)), []);
        assert_eq!(t.event(2, Ended, 300.0, 300.0, ms(t0, 20)), []);
        let up = t.event(1, Ended, 10.0, 10.0, ms(t0, 30));
        assert_eq!(up[..2], [(10.0, 10.0, Down(0)), (10.0, 10.0, Up(0))]);
    }
}
