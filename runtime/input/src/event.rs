//! What input sources report: devices appearing and going, axes moving, buttons and keys
//! going down and up, wheels turning — each with the time it happened.

use std::time::Instant;

/// The kind of device, as the layout language names it in `bind gamepad { … }`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum DeviceType {
    Gamepad,
    Keyboard,
    Mouse,
}

impl DeviceType {
    pub fn name(self) -> &'static str {
        match self {
            DeviceType::Gamepad => "gamepad",
            DeviceType::Keyboard => "keyboard",
            DeviceType::Mouse => "mouse",
        }
    }

    /// What the language calls this device's buttons: `key` on a keyboard, else `button`.
    pub fn button_kind(self) -> &'static str {
        if self == DeviceType::Keyboard { "key" } else { "button" }
    }
}

/// One input event. `device` is the source's own stable id for the device (`gilrs:0`,
/// `script:1`, `keyboard`); names of axes, buttons and keys are the language's
/// (`left_y`, `south`, `space`).
#[derive(Clone, Debug, PartialEq)]
pub struct InputEvent {
    pub time: Instant,
    pub device: String,
    pub kind: EventKind,
}

#[derive(Clone, Debug, PartialEq)]
pub enum EventKind {
    /// A device appeared: its type, its name (`Xbox Wireless Controller`) and how its
    /// inputs are mapped (`sdl`, `driver`, `none`, `scripted`, `window`).
    Connected {
        device_type: DeviceType,
        name: String,
        mapping: String,
    },
    Disconnected,
    /// An axis moved to `value` (−1..1; triggers 0..1).
    Axis {
        axis: String,
        value: f64,
    },
    /// A button or key went down or up.
    Button {
        button: String,
        pressed: bool,
    },
    /// A wheel turned by `delta` steps.
    Wheel {
        axis: String,
        delta: f64,
    },
}

impl InputEvent {
    pub fn new(time: Instant, device: &str, kind: EventKind) -> InputEvent {
        InputEvent { time, device: device.to_string(), kind }
    }
}
