//! The input engine: devices in the world model, bindings matched to events (press,
//! release, hold, double press, shift layer, modes), axes shaped and rate-limited, and
//! every write bounded in rate and made only on change.
//!
//! The engine is a state machine over time: `handle(event)` and `tick(now)` take the time
//! from their caller and return when they next need a `tick`. The module drives it with
//! DataServer timers; tests drive it with a virtual clock (no sleeping, no timing in
//! asserts).

use crate::event::{DeviceType, EventKind, InputEvent};
use crate::shape::Shaping;
use mocu_dataserver::{CallOptions, DataServer, Guid, ObjectInfo, PropName, Value};
use std::collections::{HashMap, HashSet};
use std::time::{Duration, Instant};

/// How the engine runs (the module's settings).
#[derive(Clone, Debug, PartialEq)]
pub struct EngineConfig {
    /// At most this many writes per second of each goal (each axis binding) and of each
    /// device axis property.
    pub rate_hz: f64,
    /// Two presses closer than this are a double press.
    pub double: Duration,
}

impl Default for EngineConfig {
    fn default() -> EngineConfig {
        EngineConfig { rate_hz: 30.0, double: Duration::from_millis(300) }
    }
}

/// One binding as the layout published it under `root.display.bindings`.
#[derive(Clone, Debug, PartialEq)]
pub struct BindingDef {
    pub object: Guid,
    pub device: String,
    pub kind: String,
    pub input: String,
    /// `change`, `press`, `release`, `hold`, `double`.
    pub event: String,
    pub hold: Duration,
    pub mode: Option<String>,
    pub shift: bool,
    pub shift_input: Option<String>,
    pub shaping: Shaping,
}

/// Reads the binding objects under `container` (those whose `ready` is true).
pub fn scan_bindings(ds: &DataServer, container: Guid) -> Vec<BindingDef> {
    let mut out = Vec::new();
    for b in ds.children(container).unwrap_or_default() {
        let get = |k: &str| ds.try_get(b, PropName::new(k));
        if get("ready") != Some(Value::Bool(true)) {
            continue;
        }
        let s = |k: &str| get(k).and_then(|v| v.as_str().map(str::to_string)).unwrap_or_default();
        let f = |k: &str, d: f64| get(k).and_then(|v| v.as_f64()).unwrap_or(d);
        let flag = |k: &str| get(k) == Some(Value::Bool(true));
        let opt = |k: &str| Some(s(k)).filter(|x| !x.is_empty());
        out.push(BindingDef {
            object: b,
            device: s("device"),
            kind: s("kind"),
            input: s("input"),
            event: s("event"),
            hold: Duration::try_from_secs_f64(f("hold_ms", 0.0).max(0.0) / 1000.0)
                .unwrap_or(Duration::MAX),
            mode: opt("mode"),
            shift: flag("shift"),
            shift_input: opt("shift_input"),
            shaping: Shaping {
                deadzone: f("deadzone", 0.0),
                expo: f("expo", 0.0),
                scale: f("scale", 1.0),
                invert: flag("invert"),
                rate: f("rate", 0.0),
            },
        });
    }
    out
}

/// Counters (also published on the module's status object).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct EngineStats {
    pub events: u64,
    /// `fire` calls made (each may write a goal or call a method).
    pub fires: u64,
    /// Device axis and button property writes.
    pub prop_writes: u64,
    pub devices: u64,
}

#[derive(Debug, Default)]
struct BindingRt {
    // Axes: the shaped target, the rate-limited output, what was last sent and when.
    target: f64,
    output: f64,
    stepped_at: Option<Instant>,
    sent: Option<f64>,
    sent_at: Option<Instant>,
    // Buttons: when it went down (for hold), whether the hold fired, the last press.
    down_at: Option<Instant>,
    hold_done: bool,
    last_press: Option<Instant>,
}

struct Device {
    ty: DeviceType,
    object: Guid,
    axes: Guid,
    buttons: Guid,
    pressed: HashSet<String>,
    gates: HashMap<String, Gate>,
}

/// A value written at a bounded rate, only when it changed.
#[derive(Debug, Default)]
struct Gate {
    value: f64,
    written: Option<f64>,
    written_at: Option<Instant>,
}

pub struct Engine {
    ds: DataServer,
    cfg: EngineConfig,
    period: Duration,
    inputs: Guid,
    operator: Guid,
    devices: HashMap<String, Device>,
    counts: HashMap<DeviceType, usize>,
    defs: Vec<BindingDef>,
    rt: Vec<BindingRt>,
    stats: EngineStats,
}

impl Engine {
    /// Publishes `root.operator.inputs` (if absent).
    pub fn new(ds: &DataServer, cfg: EngineConfig) -> Result<Engine, String> {
        let e = |e: mocu_dataserver::DsError| e.to_string();
        let operator = child(ds, Guid::ROOT, "operator", "operator").map_err(e)?;
        let inputs = child(ds, operator, "inputs", "inputs").map_err(e)?;
        let period = Duration::from_secs_f64(1.0 / cfg.rate_hz.clamp(1.0, 1000.0));
        Ok(Engine {
            ds: ds.clone(),
            cfg,
            period,
            inputs,
            operator,
            devices: HashMap::new(),
            counts: HashMap::new(),
            defs: Vec::new(),
            rt: Vec::new(),
            stats: EngineStats::default(),
        })
    }

    pub fn stats(&self) -> EngineStats {
        self.stats
    }

    /// The world-model object of a device (`root.operator.inputs.gamepad1`).
    pub fn device_object(&self, device: &str) -> Option<Guid> {
        self.devices.get(device).map(|d| d.object)
    }

    /// Replaces the bindings (the layout published new ones). Held buttons stay held;
    /// axis outputs start again from 0.
    pub fn set_bindings(&mut self, defs: Vec<BindingDef>) {
        self.rt = defs.iter().map(|_| BindingRt::default()).collect();
        self.defs = defs;
    }

    pub fn bindings(&self) -> &[BindingDef] {
        &self.defs
    }

    /// Handles one event at its own time; returns when the engine next needs a `tick`.
    pub fn handle(&mut self, ev: &InputEvent) -> Option<Instant> {
        self.stats.events += 1;
        let t = ev.time;
        match &ev.kind {
            EventKind::Connected { device_type, name, mapping } => {
                self.connect(&ev.device, *device_type, name, mapping)
            }
            EventKind::Disconnected => self.disconnect(&ev.device, t),
            EventKind::Axis { axis, value } => {
                let Some(ty) = self.ensure(&ev.device) else { return self.next_wake() };
                if let Some(d) = self.devices.get_mut(&ev.device) {
                    d.gates.entry(axis.clone()).or_default().value = *value;
                }
                self.flush_device(&ev.device, t);
                for i in self.matching(ty, "axis", axis, None) {
                    let sh = self.defs[i].shaping;
                    let r = &mut self.rt[i];
                    r.target = sh.apply(*value);
                    if r.stepped_at.is_none() {
                        r.stepped_at = Some(t);
                    }
                    self.step_axis(i, t);
                }
            }
            EventKind::Wheel { axis, delta } => {
                let Some(ty) = self.ensure(&ev.device) else { return self.next_wake() };
                for i in self.matching(ty, "wheel", axis, None) {
                    let v =
                        self.defs[i].shaping.apply(delta.clamp(-1.0, 1.0)) * delta.abs().max(1.0);
                    self.fire(i, v);
                }
            }
            EventKind::Button { button, pressed } => {
                let Some(ty) = self.ensure(&ev.device) else { return self.next_wake() };
                self.button(&ev.device, ty, button, *pressed, t)
            }
        }
        self.next_wake()
    }

    /// Advances time: rate-limited axes, pending writes, holds.
    pub fn tick(&mut self, now: Instant) -> Option<Instant> {
        let ids: Vec<String> = self.devices.keys().cloned().collect();
        for d in ids {
            self.flush_device(&d, now);
        }
        for i in 0..self.defs.len() {
            match self.defs[i].event.as_str() {
                "change" if self.defs[i].kind == "axis" => self.step_axis(i, now),
                "hold" => {
                    let r = &mut self.rt[i];
                    if let Some(d) = r.down_at
                        && !r.hold_done
                        && now >= d + self.defs[i].hold
                    {
                        r.hold_done = true;
                        self.fire(i, 1.0);
                    }
                }
                _ => {}
            }
        }
        self.next_wake()
    }

    /// The earliest time something is due (a pending write, a rate-limited axis moving,
    /// a hold).
    pub fn next_wake(&self) -> Option<Instant> {
        let mut best: Option<Instant> = None;
        let mut at = |t: Instant| best = Some(best.map_or(t, |b| b.min(t)));
        for d in self.devices.values() {
            for g in d.gates.values() {
                if g.written != Some(g.value) {
                    at(g.written_at.map_or_else(|| self.ds.now(), |w| w + self.period));
                }
            }
        }
        for (def, r) in self.defs.iter().zip(&self.rt) {
            if def.kind == "axis" {
                if r.output != r.target {
                    at(r.stepped_at.map_or_else(|| self.ds.now(), |s| s + self.period));
                }
                if r.sent.map_or(r.output != 0.0, |s| s != r.output) {
                    at(r.sent_at.map_or_else(|| self.ds.now(), |s| s + self.period));
                }
            }
            if def.event == "hold"
                && let Some(d) = r.down_at
                && !r.hold_done
            {
                at(d + def.hold);
            }
        }
        best
    }

    // ----- devices --------------------------------------------------------------------

    fn connect(&mut self, id: &str, ty: DeviceType, name: &str, mapping: &str) {
        if !self.devices.contains_key(id) {
            let n = self.counts.entry(ty).or_insert(0);
            *n += 1;
            let obj_name = match (ty, *n) {
                (DeviceType::Gamepad, n) => format!("gamepad{n}"),
                (t, 1) => t.name().to_string(),
                (t, n) => format!("{}{n}", t.name()),
            };
            let ds = &self.ds;
            let Ok(object) = child(ds, self.inputs, &obj_name, ty.name()) else { return };
            let (Ok(axes), Ok(buttons)) =
                (child(ds, object, "axes", "axes"), child(ds, object, "buttons", "buttons"))
            else {
                return;
            };
            self.devices.insert(
                id.to_string(),
                Device {
                    ty,
                    object,
                    axes,
                    buttons,
                    pressed: HashSet::new(),
                    gates: HashMap::new(),
                },
            );
            self.stats.devices += 1;
        }
        let Some(d) = self.devices.get(id) else { return };
        let ds = &self.ds;
        let _ = ds.set(d.object, "name", Value::str(name));
        let _ = ds.set(d.object, "mapping", Value::str(mapping));
        let _ = ds.set(d.object, "device", Value::str(id));
        let _ = ds.set(d.object, "connected", Value::Bool(true));
    }

    /// An event from a device never announced: a gamepad, unless the id says otherwise.
    fn ensure(&mut self, id: &str) -> Option<DeviceType> {
        if !self.devices.contains_key(id) {
            let ty = if id.starts_with("keyboard") {
                DeviceType::Keyboard
            } else if id.starts_with("mouse") {
                DeviceType::Mouse
            } else {
                DeviceType::Gamepad
            };
            self.connect(id, ty, id, "none");
        }
        self.devices.get(id).map(|d| d.ty)
    }

    /// A disconnected device releases what it held and centres its axes (a vehicle must
    /// not keep the throttle of a pad that fell off); its object stays, `connected` false.
    fn disconnect(&mut self, id: &str, t: Instant) {
        let Some(d) = self.devices.get(id) else { return };
        let ty = d.ty;
        let held: Vec<String> = d.pressed.iter().cloned().collect();
        let axes: Vec<String> = d.gates.keys().cloned().collect();
        for b in held {
            self.button(id, ty, &b, false, t);
        }
        for a in axes {
            self.handle(&InputEvent::new(t, id, EventKind::Axis { axis: a, value: 0.0 }));
        }
        if let Some(d) = self.devices.get(id) {
            let _ = self.ds.set(d.object, "connected", Value::Bool(false));
        }
    }

    fn flush_device(&mut self, id: &str, now: Instant) {
        let period = self.period;
        let Some(d) = self.devices.get_mut(id) else { return };
        for (name, g) in d.gates.iter_mut() {
            if g.written != Some(g.value) && g.written_at.is_none_or(|w| now >= w + period) {
                let _ = self.ds.set(d.axes, name.as_str(), Value::Float(g.value));
                g.written = Some(g.value);
                g.written_at = Some(now);
                self.stats.prop_writes += 1;
            }
        }
    }

    // ----- bindings -------------------------------------------------------------------

    fn current_mode(&self) -> Option<String> {
        self.ds
            .try_get(self.operator, PropName::new("mode"))
            .and_then(|v| v.as_str().map(str::to_string))
    }

    /// Whether the shift input of `device_type`'s bindings is held on any such device.
    fn shift_held(&self, ty: DeviceType, shift_input: &str) -> bool {
        self.devices.values().any(|d| d.ty == ty && d.pressed.contains(shift_input))
    }

    /// Bindings for this input, active in the current mode and shift layer; `event`
    /// filters by event when given.
    fn matching(&self, ty: DeviceType, kind: &str, input: &str, event: Option<&str>) -> Vec<usize> {
        let mode =
            if self.defs.iter().any(|d| d.mode.is_some()) { self.current_mode() } else { None };
        (0..self.defs.len())
            .filter(|&i| {
                let d = &self.defs[i];
                d.device == ty.name()
                    && d.kind == kind
                    && d.input == input
                    && event.is_none_or(|e| d.event == e)
                    && d.mode.as_ref().is_none_or(|m| mode.as_ref() == Some(m))
                    && d.shift == d.shift_input.as_deref().is_some_and(|s| self.shift_held(ty, s))
            })
            .collect()
    }

    fn button(&mut self, id: &str, ty: DeviceType, button: &str, pressed: bool, t: Instant) {
        let Some(d) = self.devices.get_mut(id) else { return };
        let changed =
            if pressed { d.pressed.insert(button.to_string()) } else { d.pressed.remove(button) };
        if !changed {
            return; // a repeat or a release of something not held
        }
        let _ = self.ds.set(d.buttons, button, Value::Bool(pressed));
        self.stats.prop_writes += 1;
        let kind = ty.button_kind();
        if pressed {
            for i in self.matching(ty, kind, button, None) {
                match self.defs[i].event.as_str() {
                    "press" => self.fire(i, 1.0),
                    "hold" => {
                        self.rt[i].down_at = Some(t);
                        self.rt[i].hold_done = false;
                    }
                    "double" => {
                        let r = &mut self.rt[i];
                        if r.last_press
                            .is_some_and(|p| t.saturating_duration_since(p) <= self.cfg.double)
                        {
                            r.last_press = None;
                            self.fire(i, 1.0);
                        } else {
                            r.last_press = Some(t);
                        }
                    }
                    _ => {}
                }
            }
        } else {
            // Holds end whatever the mode or layer now is.
            for i in 0..self.defs.len() {
                let d = &self.defs[i];
                if d.event == "hold" && d.device == ty.name() && d.kind == kind && d.input == button
                {
                    self.rt[i].down_at = None;
                }
            }
            for i in self.matching(ty, kind, button, Some("release")) {
                self.fire(i, 0.0);
            }
        }
    }

    /// Moves a rate-limited output towards its target and sends it when the gate allows.
    fn step_axis(&mut self, i: usize, now: Instant) {
        let sh = self.defs[i].shaping;
        let period = self.period;
        let r = &mut self.rt[i];
        let dt = r.stepped_at.map_or(0.0, |s| now.saturating_duration_since(s).as_secs_f64());
        r.output = sh.limit(r.output, r.target, dt);
        r.stepped_at = Some(now);
        let changed = r.sent.map_or(r.output != 0.0, |s| s != r.output);
        if changed && r.sent_at.is_none_or(|s| now >= s + period) {
            r.sent = Some(r.output);
            r.sent_at = Some(now);
            let v = r.output;
            self.fire(i, v);
        }
    }

    fn fire(&mut self, i: usize, value: f64) {
        self.stats.fires += 1;
        let obj = self.defs[i].object;
        // Immediate: the actions run here, in event order (a later stick position can
        // never overtake an earlier one on another worker).
        self.ds.call(
            obj,
            "fire",
            vec![Value::Float(value)],
            Some(CallOptions::immediate()),
            |_| {},
        );
    }
}

pub(crate) fn child(
    ds: &DataServer,
    parent: Guid,
    name: &str,
    kind: &str,
) -> Result<Guid, mocu_dataserver::DsError> {
    match ds.find_child(parent, name)? {
        Some(g) => Ok(g),
        None => ds.create_object(parent, ObjectInfo::new(name, kind)),
    }
}
