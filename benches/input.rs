//! Input event → goal property written, against a bare DataServer write → callback, in the
//! same run. The event goes through the whole path: the engine (shaping, rate gate), the
//! binding object's `fire` method, the layout's compiled `set` action, the DataServer
//! write, and the subscription callback that sees the new goal.
//!
//! `cargo bench --bench input`. Besides criterion's estimates it prints the medians of
//! 5000 single measurements of each.

use criterion::{Criterion, criterion_group, criterion_main};
use crossbeam_channel::{Receiver, bounded};
use mocu_dataserver::{DataServer, Guid, ObjectInfo, Topic, Value};
use mocu_input::{DeviceType, Engine, EngineConfig, EventKind, InputEvent, scan_bindings};
use mocu_layout::{Layout, LayoutConfig, NullSink};
use std::sync::Arc;
use std::time::{Duration, Instant};

struct Rig {
    ds: DataServer,
    nav: Guid,
    engine: Engine,
    rx: Receiver<()>,
    _layout: Layout,
    t: Instant,
    n: u64,
}

fn rig() -> Rig {
    let ds = DataServer::default();
    let vs = ds.create_object(Guid::ROOT, ObjectInfo::new("vehicles", "folder")).unwrap();
    let v = ds.create_object(vs, ObjectInfo::new("usv1", "usv")).unwrap();
    let nav = ds.create_object(v, ObjectInfo::new("nav", "nav")).unwrap();
    ds.set(nav, "goal_throttle", Value::Float(0.0)).unwrap();
    let op = ds.create_object(Guid::ROOT, ObjectInfo::new("operator", "operator")).unwrap();
    ds.set(op, "selected", Value::Guid(v)).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("bench.mocu");
    std::fs::write(
        &path,
        "bind gamepad { axis left_y scale 100 -> set selected.nav.goal_throttle = axis }",
    )
    .unwrap();
    let (bundle, _) = mocu_language::load_target(&path).map_err(|e| e.to_string()).unwrap();
    let program = &bundle.layouts[0].program;
    let layout = Layout::load(&ds, program, LayoutConfig::default(), Arc::new(NullSink)).unwrap();
    layout.settle();
    let mut engine =
        Engine::new(&ds, EngineConfig { rate_hz: 1000.0, ..EngineConfig::default() }).unwrap();
    engine.set_bindings(scan_bindings(&ds, ds.resolve(&["display", "bindings"]).unwrap()));
    let t = Instant::now();
    engine.handle(&InputEvent::new(
        t,
        "pad",
        EventKind::Connected {
            device_type: DeviceType::Gamepad,
            name: "bench".into(),
            mapping: "none".into(),
        },
    ));
    let (tx, rx) = bounded(1024);
    let mut first = true;
    ds.subscribe(Topic::property_names(nav, &["goal_throttle"]), move |_| {
        if !std::mem::take(&mut first) {
            let _ = tx.send(());
        }
    })
    .unwrap();
    ds.quiesce();
    Rig { ds, nav, engine, rx, _layout: layout, t, n: 0 }
}

impl Rig {
    /// One stick movement (a new value each time, 2 ms of event time apart so the 1 kHz
    /// gate is open) until the goal's subscriber has seen it.
    fn event_to_goal(&mut self) -> Duration {
        self.n += 1;
        self.t += Duration::from_millis(2);
        let value = 0.1 + 0.8 * ((self.n % 1000) as f64 / 1000.0);
        let ev = InputEvent::new(self.t, "pad", EventKind::Axis { axis: "left_y".into(), value });
        let start = Instant::now();
        self.engine.handle(&ev);
        self.rx.recv().unwrap();
        start.elapsed()
    }

    /// The baseline: a bare DataServer write until the same subscriber has seen it.
    fn write_to_callback(&mut self) -> Duration {
        self.n += 1;
        let start = Instant::now();
        self.ds.set(self.nav, "goal_throttle", Value::Float(self.n as f64 + 0.5)).unwrap();
        self.rx.recv().unwrap();
        start.elapsed()
    }
}

fn median(mut f: impl FnMut() -> Duration) -> Duration {
    let mut v: Vec<Duration> = (0..5000).map(|_| f()).collect();
    v.sort();
    v[v.len() / 2]
}

fn bench(c: &mut Criterion) {
    let mut r = rig();
    let mut g = c.benchmark_group("input");
    g.bench_function("event_to_goal_written", |b| {
        b.iter_custom(|n| (0..n).map(|_| r.event_to_goal()).sum())
    });
    g.bench_function("baseline_write_to_callback", |b| {
        b.iter_custom(|n| (0..n).map(|_| r.write_to_callback()).sum())
    });
    g.finish();
    let e = median(|| r.event_to_goal());
    let w = median(|| r.write_to_callback());
    eprintln!(
        "input: median event → goal written {:.1} µs; bare write → callback {:.1} µs ({:.2}×)",
        e.as_secs_f64() * 1e6,
        w.as_secs_f64() * 1e6,
        e.as_secs_f64() / w.as_secs_f64()
    );
}

criterion_group!(benches, bench);
criterion_main!(benches);
