//! The replay's controls and its timeline strip: what the keyboard asks for, and a window
//! along the bottom of the screen showing where the replay is, whether it plays, and how
//! fast; a press on its bar seeks there, and dragging along it scrubs. Shown only in a
//! window: headless frames (and golden frames) are the layout's alone.

use mocu_dataserver::{
    CallOutcome, DataServer, Guid, MethodSpec, ObjectInfo, ParamSpec, ValueKind,
};
use mocu_display::{Align, Baseline, Canvas, Color, Point, Rect, TextStyle};
use std::sync::Arc;
use std::sync::Mutex;
use std::sync::atomic::{AtomicBool, Ordering};

/// What a key asks the replay to do.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Control {
    PlayPause,
    Step,
    Slower,
    Faster,
    Start,
    End,
    /// Go to this trial time (seconds from the start): a press or a drag on the timeline.
    Seek(f64),
}

impl Control {
    /// The control a key press stands for (`space`, `right`, `[`, `]`, `home`, `end`).
    pub fn of_key(name: &str) -> Option<Control> {
        Some(match name {
            "space" => Control::PlayPause,
            "right" => Control::Step,
            "[" => Control::Slower,
            "]" => Control::Faster,
            "home" => Control::Start,
            "end" => Control::End,
            _ => return None,
        })
    }
}

/// What the strip shows.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Position {
    pub secs: f64,
    pub length: f64,
    pub playing: bool,
    pub speed: f64,
}

/// Height of the strip, in screen pixels.
pub const HEIGHT: f32 = 28.0;

/// Publishes `root.operator.inputs.keyboard.key(name, pressed)` (what the window calls for
/// each key) sending each press to `controls`.
pub fn keyboard(ds: &DataServer, controls: crossbeam_channel::Sender<Control>) -> Option<Guid> {
    let ensure = |parent: Guid, name: &str, kind: &str| {
        ds.find_child(parent, name)
            .ok()
            .flatten()
            .or_else(|| ds.create_object(parent, ObjectInfo::new(name, kind)).ok())
    };
    let op = ensure(Guid::ROOT, "operator", "operator")?;
    let inputs = ensure(op, "inputs", "inputs")?;
    let kb = ensure(inputs, "keyboard", "keyboard")?;
    let spec = MethodSpec::new("key")
        .param(ParamSpec::new("name", ValueKind::String))
        .param(ParamSpec::new("pressed", ValueKind::Bool))
        .ordered();
    let _ = ds.publish_method_fn(kb, spec, move |args| {
        let pressed = args.get(1).and_then(|v| v.as_bool()).unwrap_or(false);
        let name = args.first().and_then(|v| v.as_str()).unwrap_or("");
        if pressed && let Some(c) = Control::of_key(name) {
            let _ = controls.send(c);
        }
        CallOutcome::Accepted(vec![])
    });
    Some(kb)
}

/// The strip: a window over the bottom of the screen, painted from `position`; presses
/// and drags on it go to `controls` as [`Control::Seek`].
pub fn strip(
    ds: &DataServer,
    screen: (u32, u32),
    position: Arc<Mutex<Position>>,
    controls: crossbeam_channel::Sender<Control>,
) -> Option<Guid> {
    let display = mocu_display::ensure_display_object(ds, screen.0, screen.1).ok()?;
    let (w, h) = (screen.0 as f32, screen.1 as f32);
    let rect = Rect::new(0.0, h - HEIGHT, w, HEIGHT);
    let g =
        mocu_display::publish_window(ds, display, "replay_timeline", "replay", 1000, rect).ok()?;
    let shown = position.clone();
    mocu_display::claim_window(ds, g, move |c, _| {
        paint(c, w, &shown.lock().unwrap_or_else(|e| e.into_inner()))
    })
    .ok()?;
    let held = AtomicBool::new(false);
    ds.publish_method_fn(g, mocu_display::pointer_spec(), move |args| {
        let kind = args.first().and_then(|v| v.as_str()).unwrap_or("");
        let button = args.get(1).and_then(|v| v.as_i64()).unwrap_or(-1);
        let x = args.get(2).and_then(|v| v.as_f64()).unwrap_or(0.0) as f32;
        let seek = match (kind, button) {
            ("down", 0) => {
                held.store(true, Ordering::Relaxed);
                true
            }
            ("move", _) => held.load(Ordering::Relaxed),
            ("up" | "leave", _) => {
                held.store(false, Ordering::Relaxed);
                false
            }
            _ => false,
        };
        if seek {
            let length = position.lock().unwrap_or_else(|e| e.into_inner()).length;
            let _ = controls.send(Control::Seek(time_at(x, w, length)));
        }
        CallOutcome::Accepted(vec![])
    })
    .ok()?;
    Some(g)
}

/// The timeline's bar in a strip `w` pixels wide (strip-local).
fn bar(w: f32) -> Rect {
    Rect::new(150.0, HEIGHT / 2.0 - 3.0, (w - 300.0).max(10.0), 6.0)
}

/// The trial time under `x` (strip-local) on the bar of a strip `w` wide, for a trial
/// `length` seconds long: the bar's ends outside it.
pub fn time_at(x: f32, w: f32, length: f64) -> f64 {
    let b = bar(w);
    (f64::from((x - b.x) / b.w)).clamp(0.0, 1.0) * length
}

fn paint(c: &mut dyn Canvas, w: f32, p: &Position) {
    c.fill_rect(Rect::new(0.0, 0.0, w, HEIGHT), Color::rgba(12, 16, 24, 230));
    let bar = bar(w);
    c.fill_rect(bar, Color::rgb(70, 78, 92));
    let done = if p.length > 0.0 { (p.secs / p.length).clamp(0.0, 1.0) as f32 } else { 0.0 };
    c.fill_rect(Rect::new(bar.x, bar.y, bar.w * done, bar.h), Color::rgb(56, 189, 248));
    c.fill_rect(Rect::new(bar.x + bar.w * done - 2.0, 5.0, 4.0, HEIGHT - 10.0), Color::WHITE);
    let text = TextStyle::new(14.0, Color::WHITE).baseline(Baseline::Middle);
    let state = if p.playing { "PLAYING" } else { "PAUSED" };
    c.draw_text(&format!("{state} ×{}", p.speed), Point::new(10.0, HEIGHT / 2.0), &text);
    c.draw_text(
        &format!("{:.1} / {:.1} s", p.secs, p.length),
        Point::new(w - 10.0, HEIGHT / 2.0),
        &text.clone().align(Align::Right),
    );
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn key_presses_in_the_window_reach_the_replay_as_controls() {
        let ds = DataServer::default();
        let (tx, rx) = crossbeam_channel::unbounded();
        let kb = keyboard(&ds, tx).expect("the keyboard object");
        assert_eq!(ds.resolve(&["operator", "inputs", "keyboard"]), Some(kb));
        for (key, pressed) in [("space", true), ("space", false), ("]", true), ("q", true)] {
            let args =
                vec![mocu_dataserver::Value::str(key), mocu_dataserver::Value::Bool(pressed)];
            let outcome = ds.call_wait(kb, "key", args, None);
            assert_eq!(outcome, CallOutcome::Accepted(vec![]));
        }
        assert_eq!(rx.try_iter().collect::<Vec<_>>(), vec![Control::PlayPause, Control::Faster]);
    }

    #[test]
    fn a_press_on_the_timeline_seeks_there_and_a_drag_scrubs() {
        use mocu_display::{Clock, Display, DisplayOptions, PointerEvent};
        let (w, h) = (800u32, 600u32);
        let ds = DataServer::default();
        let opts = DisplayOptions::new(w, h).clock(Clock::manual());
        let mut d = Display::new(&ds, opts).expect("a headless display");
        let (tx, rx) = crossbeam_channel::unbounded();
        let position = Arc::new(Mutex::new(Position { length: 60.0, ..Position::default() }));
        strip(&ds, (w, h), position, tx).expect("the strip");
        ds.quiesce();
        d.frame();
        // The bar runs from x 150 to 650 of an 800-wide strip; the strip is the screen's
        // bottom 28 pixels.
        let y = h as f32 - HEIGHT / 2.0;
        d.pointer(400.0, y, PointerEvent::Down(0));
        d.pointer(525.0, y, PointerEvent::Move);
        d.pointer(525.0, y, PointerEvent::Up(0));
        d.pointer(275.0, y, PointerEvent::Move);
        d.pointer(20.0, y, PointerEvent::Down(0));
        d.pointer(20.0, y, PointerEvent::Up(0));
        d.pointer(700.0, y, PointerEvent::Down(1));
        ds.quiesce();
        let got: Vec<_> = rx.try_iter().collect();
        // A press at the middle, a drag to three quarters, nothing after the release, the
        // bar's start left of it, and no seek from the right button.
        assert_eq!(got, vec![Control::Seek(30.0), Control::Seek(45.0), Control::Seek(0.0)]);
    }

    #[test]
    fn the_documented_keys_are_the_controls() {
        let keys = ["space", "right", "[", "]", "home", "end", "x"];
        let got: Vec<_> = keys.iter().map(|k| Control::of_key(k)).collect();
        use Control::*;
        assert_eq!(
            got,
            vec![
                Some(PlayPause),
                Some(Step),
                Some(Slower),
                Some(Faster),
                Some(Start),
                Some(End),
                None
            ]
        );
    }
}
