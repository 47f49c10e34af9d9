//! Gamepads through gilrs (evdev on Linux, XInput/WGI on Windows, IOKit on macOS).
//!
//! A thread blocks in `next_event_blocking` with a 100 ms timeout rather than polling
//! `next_event` at 250 Hz: an event is handed on the moment gilrs has it (no up-to-4 ms
//! polling delay added to every stick movement), an idle OCU wakes 10 times a second
//! instead of 250, and the timeout bounds how long `stop` waits. gilrs's own deadzone
//! filter is off (`set_update_state(false)`, raw events): shaping belongs to the bindings.

use crate::event::{DeviceType, EventKind, InputEvent};
use crate::source::InputSource;
use gilrs::{Axis, Button, EventType, GilrsBuilder, MappingSource};
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

/// The gilrs source. Starting with no gamepad attached (or no udev devices at all, as on
/// a build machine) is normal: 0 pads, no events, until one is plugged in.
#[derive(Default)]
pub struct GilrsSource;

/// What gilrs sees right now, without starting a thread.
#[derive(Clone, Debug, PartialEq)]
pub struct GilrsProbe {
    /// Connected gamepads: (gilrs id, name, mapping source).
    pub pads: Vec<(usize, String, String)>,
    /// Whether this platform has a gilrs backend (false: it runs and reports nothing).
    pub supported: bool,
}

fn open() -> Result<(gilrs::Gilrs, bool), String> {
    match GilrsBuilder::new().set_update_state(false).with_default_filters(false).build() {
        Ok(g) => Ok((g, true)),
        Err(gilrs::Error::NotImplemented(g)) => Ok((g, false)),
        Err(e) => Err(format!("gilrs: {e}")),
    }
}

fn mapping(m: MappingSource) -> &'static str {
    match m {
        MappingSource::SdlMappings => "sdl",
        MappingSource::Driver => "driver",
        MappingSource::None => "none",
    }
}

impl GilrsSource {
    pub fn new() -> GilrsSource {
        GilrsSource
    }

    /// Opens gilrs, lists the connected pads, closes it.
    pub fn probe() -> Result<GilrsProbe, String> {
        let (g, supported) = open()?;
        let pads = g
            .gamepads()
            .map(|(id, p)| {
                (usize::from(id), p.name().to_string(), mapping(p.mapping_source()).into())
            })
            .collect();
        Ok(GilrsProbe { pads, supported })
    }
}

/// The language's name of a gilrs button (`None`: not bindable).
pub fn button_name(b: Button) -> Option<&'static str> {
    Some(match b {
        Button::South => "south",
        Button::East => "east",
        Button::North => "north",
        Button::West => "west",
        Button::LeftTrigger => "left_bumper",
        Button::RightTrigger => "right_bumper",
        Button::LeftTrigger2 => "left_trigger",
        Button::RightTrigger2 => "right_trigger",
        Button::Select => "select",
        Button::Start => "start",
        Button::Mode => "mode",
        Button::LeftThumb => "left_stick",
        Button::RightThumb => "right_stick",
        Button::DPadUp => "dpad_up",
        Button::DPadDown => "dpad_down",
        Button::DPadLeft => "dpad_left",
        Button::DPadRight => "dpad_right",
        _ => return None,
    })
}

/// The language's name of a gilrs axis. gilrs's sticks are positive up (`LeftStickY`);
/// so are ours.
pub fn axis_name(a: Axis) -> Option<&'static str> {
    Some(match a {
        Axis::LeftStickX => "left_x",
        Axis::LeftStickY => "left_y",
        Axis::RightStickX => "right_x",
        Axis::RightStickY => "right_y",
        Axis::LeftZ => "left_trigger",
        Axis::RightZ => "right_trigger",
        _ => return None,
    })
}

impl InputSource for GilrsSource {
    fn name(&self) -> &str {
        "gilrs"
    }

    fn run(&mut self, out: &mut dyn FnMut(InputEvent), stop: &AtomicBool) -> Result<(), String> {
        let (mut g, supported) = open()?;
        if !supported {
            return Ok(());
        }
        let connected = |g: &gilrs::Gilrs, id: gilrs::GamepadId| {
            let p = g.gamepad(id);
            EventKind::Connected {
                device_type: DeviceType::Gamepad,
                name: p.name().to_string(),
                mapping: mapping(p.mapping_source()).to_string(),
            }
        };
        let now = Instant::now();
        let ids: Vec<gilrs::GamepadId> = g.gamepads().map(|(id, _)| id).collect();
        for id in ids {
            out(InputEvent::new(now, &format!("gilrs:{id}"), connected(&g, id)));
        }
        while !stop.load(Ordering::SeqCst) {
            let Some(ev) = g.next_event_blocking(Some(Duration::from_millis(100))) else {
                continue;
            };
            let device = format!("gilrs:{}", ev.id);
            let kind = match ev.event {
                EventType::Connected => connected(&g, ev.id),
                EventType::Disconnected => EventKind::Disconnected,
                EventType::ButtonPressed(b, _) => match button_name(b) {
                    Some(n) => EventKind::Button { button: n.into(), pressed: true },
                    None => continue,
                },
                EventType::ButtonReleased(b, _) => match button_name(b) {
                    Some(n) => EventKind::Button { button: n.into(), pressed: false },
                    None => continue,
                },
                // Analogue triggers: also an axis, 0..1.
                EventType::ButtonChanged(
                    b @ (Button::LeftTrigger2 | Button::RightTrigger2),
                    v,
                    _,
                ) => match button_name(b) {
                    Some(n) => EventKind::Axis { axis: n.into(), value: v as f64 },
                    None => continue,
                },
                EventType::AxisChanged(a, v, _) => match axis_name(a) {
                    Some(n) => EventKind::Axis { axis: n.into(), value: v as f64 },
                    None => continue,
                },
                _ => continue,
            };
            out(InputEvent::new(Instant::now(), &device, kind));
        }
        Ok(())
    }
}
