//! A rig for input tests: a real layout over a simulated fleet (stepped by hand), the
//! engine driven with a virtual clock, the event log in memory.

#![allow(dead_code)]

use mocu_dataserver::{DataServer, Guid, PropName, Value};
use mocu_host::ModuleContext;
use mocu_input::{Engine, EngineConfig, EventKind, InputEvent, scan_bindings};
use mocu_layout::{EventSink, Layout, LayoutConfig};
use mocu_sim::{Sim, SimConfig};
use std::sync::Arc;
use std::time::{Duration, Instant};

/// Checks a layout written in a temporary file (so `use "stdlib/…"` resolves).
pub fn program(text: &str) -> mocu_language::Program {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("test.mocu");
    std::fs::write(&path, text).unwrap();
    match mocu_language::load_target(&path) {
        Ok((bundle, _)) => bundle.layouts.into_iter().next().unwrap().program,
        Err(e) => panic!("layout does not check:\n{e}"),
    }
}

pub struct Rig {
    pub ds: DataServer,
    pub sim: Sim,
    pub layout: Layout,
    pub engine: Engine,
    pub t0: Instant,
    pub now: Instant,
}

/// Two USVs (not started: they wait for the operator), the layout, the engine at `rate_hz`.
pub fn rig(layout: &str, rate_hz: f64, sink: Arc<dyn EventSink>) -> Rig {
    let ds = DataServer::default();
    let cfg = SimConfig { usv: 2, ugv: 0, uav: 0, autostart: false, ..SimConfig::default() };
    let sim = Sim::new(ModuleContext::detached("sim", ds.clone()), cfg).unwrap();
    sim.step(0.5);
    sim.step(0.5);
    let layout = Layout::load(&ds, &program(layout), LayoutConfig::default(), sink).unwrap();
    layout.settle();
    let mut engine = Engine::new(&ds, EngineConfig { rate_hz, ..EngineConfig::default() }).unwrap();
    let bindings = ds.resolve(&["display", "bindings"]).expect("bindings published");
    engine.set_bindings(scan_bindings(&ds, bindings));
    let t0 = Instant::now();
    let mut r = Rig { ds, sim, layout, engine, t0, now: t0 };
    r.select("usv1");
    r.event(
        0,
        "pad",
        EventKind::Connected {
            device_type: mocu_input::DeviceType::Gamepad,
            name: "Virtual Pad".into(),
            mapping: "scripted".into(),
        },
    );
    r
}

impl Rig {
    /// Runs every tick due up to `ms` after the start (virtual time).
    pub fn advance(&mut self, ms: u64) {
        let t = self.t0 + Duration::from_millis(ms);
        while let Some(w) = self.engine.next_wake() {
            if w > t {
                break;
            }
            let w = w.max(self.now);
            self.now = w;
            self.engine.tick(w);
        }
        self.now = self.now.max(t);
    }

    pub fn event(&mut self, ms: u64, device: &str, kind: EventKind) {
        self.advance(ms);
        let t = self.t0 + Duration::from_millis(ms);
        self.engine.handle(&InputEvent::new(t, device, kind));
    }

    pub fn axis(&mut self, ms: u64, axis: &str, value: f64) {
        self.event(ms, "pad", EventKind::Axis { axis: axis.into(), value });
    }

    pub fn press(&mut self, ms: u64, button: &str) {
        self.event(ms, "pad", EventKind::Button { button: button.into(), pressed: true });
    }

    pub fn release(&mut self, ms: u64, button: &str) {
        self.event(ms, "pad", EventKind::Button { button: button.into(), pressed: false });
    }

    pub fn tap(&mut self, ms: u64, button: &str) {
        self.press(ms, button);
        self.release(ms + 50, button);
    }

    pub fn nav(&self, vehicle: &str) -> Guid {
        self.ds.resolve(&["vehicles", vehicle, "nav"]).unwrap()
    }

    pub fn goal(&self, vehicle: &str, prop: &str) -> f64 {
        self.ds.try_get(self.nav(vehicle), PropName::new(prop)).and_then(|v| v.as_f64()).unwrap()
    }

    pub fn select(&self, vehicle: &str) {
        let op = self.ds.resolve(&["operator"]).unwrap();
        let v = self.ds.resolve(&["vehicles", vehicle]).unwrap();
        self.ds.set(op, "selected", Value::Guid(v)).unwrap();
    }

    pub fn operator(&self, prop: &str) -> Option<Value> {
        let op = self.ds.resolve(&["operator"])?;
        self.ds.try_get(op, PropName::new(prop))
    }

    pub fn selected_name(&self) -> String {
        let g = self.operator("selected").and_then(|v| v.as_guid()).unwrap();
        self.ds.info(g).unwrap().name.to_string()
    }

    /// Lets queued method calls (the vehicles') answer.
    pub fn settle(&self) {
        self.ds.quiesce();
        self.layout.settle();
    }
}
