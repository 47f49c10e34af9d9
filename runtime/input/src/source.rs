//! Where events come from: the [`InputSource`] interface and the scripted source.
//! The gilrs source is in `gilrs_source.rs`; keyboard and mouse come from the window
//! through methods of `root.operator.inputs.keyboard` / `.mouse` (see `module.rs`).

use crate::event::{DeviceType, EventKind, InputEvent};
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

/// A source of input events, run on a thread of its own by the input module. `run` sends
/// every event to `out` and returns when `stop` is set (check it at least every 100 ms) or
/// when the source has nothing more to say. Devices present at the start are reported as
/// `Connected` first. A different joystick driver is another implementation of this.
pub trait InputSource: Send {
    /// A short name for messages (`gilrs`, `script`).
    fn name(&self) -> &str;
    fn run(&mut self, out: &mut dyn FnMut(InputEvent), stop: &AtomicBool) -> Result<(), String>;
}

/// One line of an input script: when (after the script starts), which device, what.
#[derive(Clone, Debug, PartialEq)]
pub struct ScriptStep {
    pub at: Duration,
    pub device: String,
    pub kind: EventKind,
}

/// Replays a recorded sequence with its timing: a virtual gamepad (or keyboard) for tests
/// and trials, above the kernel (this machine has no /dev/uinput).
///
/// The text format, one event per line (`#` starts a comment):
///
/// ```text
/// # ms    device  event
/// 0       pad1    connect gamepad "Scripted Pad" scripted
/// 100     pad1    axis left_y 0.8
/// 500     pad1    press south
/// 600     pad1    release south
/// 900     kb      connect keyboard "Keys"
/// 950     kb      press space
/// 1000    pad1    wheel vertical 1
/// 2000    pad1    disconnect
/// ```
pub struct ScriptedSource {
    steps: Vec<ScriptStep>,
}

impl ScriptedSource {
    pub fn new(steps: Vec<ScriptStep>) -> ScriptedSource {
        let mut steps = steps;
        steps.sort_by_key(|s| s.at);
        ScriptedSource { steps }
    }

    pub fn parse(text: &str) -> Result<ScriptedSource, String> {
        let mut steps = Vec::new();
        for (n, line) in text.lines().enumerate() {
            let line = line.split('#').next().unwrap_or("").trim();
            if line.is_empty() {
                continue;
            }
            let err = |m: &str| format!("input script line {}: {m}: `{line}`", n + 1);
            let words = split_words(line);
            let w = |i: usize| words.get(i).map(String::as_str);
            let at: f64 = w(0)
                .and_then(|t| t.trim_end_matches("ms").parse().ok())
                .ok_or_else(|| err("expected a time in ms first"))?;
            // A script's times are a trial's: at most a year (an `Instant` far beyond it
            // overflows when the script starts).
            if !(0.0..=MAX_SCRIPT_MS).contains(&at) {
                return Err(err("the time must be 0 to 31536000000 ms (a year)"));
            }
            let device = w(1).ok_or_else(|| err("expected a device id"))?.to_string();
            let num = |i: usize| -> Result<f64, String> {
                w(i).and_then(|x| x.parse::<f64>().ok())
                    .filter(|x| x.is_finite())
                    .ok_or_else(|| err("expected a number"))
            };
            let name = |i: usize| w(i).map(str::to_string).ok_or_else(|| err("expected a name"));
            let kind = match w(2) {
                Some("connect") => {
                    let device_type = match w(3) {
                        Some("gamepad") => DeviceType::Gamepad,
                        Some("keyboard") => DeviceType::Keyboard,
                        Some("mouse") => DeviceType::Mouse,
                        _ => return Err(err("connect needs gamepad, keyboard or mouse")),
                    };
                    EventKind::Connected {
                        device_type,
                        name: w(4).unwrap_or(&device).to_string(),
                        mapping: w(5).unwrap_or("scripted").to_string(),
                    }
                }
                Some("disconnect") => EventKind::Disconnected,
                Some("axis") => EventKind::Axis { axis: name(3)?, value: num(4)? },
                Some("press") => EventKind::Button { button: name(3)?, pressed: true },
                Some("release") => EventKind::Button { button: name(3)?, pressed: false },
                Some("wheel") => EventKind::Wheel { axis: name(3)?, delta: num(4)? },
                _ => {
                    return Err(err("expected connect, disconnect, axis, press, release or wheel"));
                }
            };
            steps.push(ScriptStep { at: Duration::from_secs_f64(at / 1000.0), device, kind });
        }
        Ok(ScriptedSource::new(steps))
    }

    pub fn steps(&self) -> &[ScriptStep] {
        &self.steps
    }

    /// The events stamped as if the script started at `t0` (tests drive an engine with
    /// these and a virtual clock).
    pub fn events_from(&self, t0: Instant) -> Vec<InputEvent> {
        self.steps
            .iter()
            .map(|s| InputEvent { time: t0 + s.at, device: s.device.clone(), kind: s.kind.clone() })
            .collect()
    }
}

/// The latest time an input script may give, in ms: a year.
const MAX_SCRIPT_MS: f64 = 365.0 * 24.0 * 3600.0 * 1000.0;

/// Words separated by spaces; `"quoted text"` is one word.
fn split_words(line: &str) -> Vec<String> {
    let mut out = Vec::new();
    let mut cur = String::new();
    let mut quoted = false;
    let mut had = false;
    for c in line.chars() {
        match c {
            '"' => {
                quoted = !quoted;
                had = true;
            }
            c if c.is_whitespace() && !quoted => {
                if had || !cur.is_empty() {
                    out.push(std::mem::take(&mut cur));
                    had = false;
                }
            }
            c => cur.push(c),
        }
    }
    if had || !cur.is_empty() {
        out.push(cur);
    }
    out
}

impl InputSource for ScriptedSource {
    fn name(&self) -> &str {
        "script"
    }

    /// Sends each event at its time after the start, stamped with that time (not with the
    /// moment it was sent): hold and double-press decisions follow the script even when
    /// the thread runs late.
    fn run(&mut self, out: &mut dyn FnMut(InputEvent), stop: &AtomicBool) -> Result<(), String> {
        let t0 = Instant::now();
        for s in &self.steps {
            let due = t0 + s.at;
            loop {
                if stop.load(Ordering::SeqCst) {
                    return Ok(());
                }
                let left = due.saturating_duration_since(Instant::now());
                if left.is_zero() {
                    break;
                }
                std::thread::sleep(left.min(Duration::from_millis(50)));
            }
            out(InputEvent { time: due, device: s.device.clone(), kind: s.kind.clone() });
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_every_event_and_sorts_by_time() {
        let s = ScriptedSource::parse(
            "# a comment\n200 p axis left_y -0.5\n0 p connect gamepad \"Virtual Pad\"\n\
             300 p press south # trailing\n400 p release south\n500 m wheel vertical 2\n600 p disconnect\n",
        )
        .unwrap();
        let st = s.steps();
        assert_eq!(st.len(), 6);
        assert_eq!(
            st[0].kind,
            EventKind::Connected {
                device_type: DeviceType::Gamepad,
                name: "Virtual Pad".into(),
                mapping: "scripted".into()
            }
        );
        assert_eq!(st[1].kind, EventKind::Axis { axis: "left_y".into(), value: -0.5 });
        assert_eq!(st[1].at, Duration::from_millis(200));
        assert_eq!(st[5].kind, EventKind::Disconnected);
    }

    #[test]
    fn reports_the_line_of_a_mistake() {
        let e =
            ScriptedSource::parse("0 p connect gamepad\n10 p axis left_y lots\n").err().unwrap();
        assert!(e.contains("line 2"), "{e}");
        assert!(ScriptedSource::parse("x p press south").is_err());
        assert!(ScriptedSource::parse("0 p jump").is_err());
    }

    #[test]
    fn a_time_that_is_not_a_number_negative_or_past_a_year_is_an_error_of_its_line() {
        for t in ["1e30", "nan", "-1", "inf", "31536000001"] {
            let text = format!("0 p connect gamepad\n{t} p press south\n");
            let e = ScriptedSource::parse(&text).err().unwrap_or_else(|| panic!("{t} taken"));
            assert!(e.contains("line 2") && e.contains("the time must be"), "{t}: {e}");
        }
        let last = ScriptedSource::parse("31536000000 p press south\n").unwrap();
        let t0 = Instant::now();
        assert_eq!(last.events_from(t0)[0].time - t0, Duration::from_secs(31_536_000));
    }
}
