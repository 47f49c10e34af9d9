//! Fan-out in one process (issue 17): one tick of 100 vehicles × 50 properties (5,000
//! changes) written at an adapter until all three OCUs' mirrors hold the tick's last value
//! (`distrib/fanout_tick_to_three_mirrors`), against the baseline in the same run: the same
//! 5,000 JSON property payloads put by a bare Zenoh session until three subscriber sessions
//! have decoded the last one (`distrib/fanout_tick_bare_zenoh`). CPU per process and bytes on
//! the wire, with separate processes: `examples/fanout.rs` (docs/distribution.md, "Cost").

use criterion::{Criterion, criterion_group, criterion_main};
use crossbeam_channel::{Receiver, unbounded};
use mocu_dataserver::{DataServer, DottedPath, Guid, ObjectInfo, PathWatch, PropName, Value};
use mocu_distrib::{Config, Distrib, payload};
use std::net::TcpListener;
use std::time::{Duration, Instant};
use zenoh::Wait;
use zenoh::qos::CongestionControl;

const VEHICLES: usize = 100;
const PROPS: usize = 50;
const OCUS: usize = 3;
const PATIENCE: Duration = Duration::from_secs(60);

fn free_port() -> u16 {
    TcpListener::bind("127.0.0.1:0").unwrap().local_addr().unwrap().port()
}

/// Waits for `n` arrivals of `want` on `rx` (one per OCU).
fn all_have(rx: &Receiver<f64>, want: f64, n: usize, what: &str) {
    let start = Instant::now();
    let mut seen = 0;
    while seen < n {
        let left = PATIENCE.saturating_sub(start.elapsed());
        match rx.recv_timeout(left) {
            Ok(x) if x == want => seen += 1,
            Ok(_) => {}
            Err(_) => panic!("{what}: only {seen} of {n} had the tick's last value"),
        }
    }
}

fn value(tick: u64, i: usize) -> f64 {
    tick as f64 + i as f64 * 1e-6
}

fn bare_zenoh(c: &mut Criterion) {
    let port = free_port();
    let ep = format!("tcp/127.0.0.1:{port}");
    let open = |cfg: Config| zenoh::open(mocu_distrib::zenoh_config(&cfg).unwrap()).wait().unwrap();
    let a = open(Config { listen: vec![ep.clone()], ..Config::default() });
    let (tx, rx) = unbounded();
    let last_key = format!("mocu/bare/prop/vehicles/v{}/p{}", VEHICLES - 1, PROPS - 1);
    let subs: Vec<_> = (0..OCUS)
        .map(|_| {
            let s = open(Config { connect: vec![ep.clone()], ..Config::default() });
            let (tx, last) = (tx.clone(), last_key.clone());
            let sub = s
                .declare_subscriber("mocu/bare/prop/**")
                .callback(move |sample| {
                    let bytes = sample.payload().to_bytes();
                    if let Ok((Value::Float(x), _)) = payload::property_from(&bytes)
                        && sample.key_expr().as_str() == last
                    {
                        let _ = tx.send(x);
                    }
                })
                .wait()
                .unwrap();
            (s, sub)
        })
        .collect();
    let keys: Vec<String> = (0..VEHICLES * PROPS)
        .map(|i| format!("mocu/bare/prop/vehicles/v{}/p{}", i / PROPS, i % PROPS))
        .collect();
    let guid = Guid::new(4).unwrap();
    let tick = |t: u64| {
        for (i, k) in keys.iter().enumerate() {
            let v = Value::Float(value(t, i));
            let put = a.put(k.as_str(), payload::property(guid, &v, None));
            // As the publisher puts a property: blocking, never dropped.
            put.congestion_control(CongestionControl::Block).wait().unwrap();
        }
    };
    // Until every subscriber's declaration has reached the publisher.
    let start = Instant::now();
    let mut t = 0;
    loop {
        t += 1;
        tick(t);
        let want = value(t, keys.len() - 1);
        let mut got = 0;
        while let Ok(x) = rx.recv_timeout(Duration::from_millis(300)) {
            got += usize::from(x == want);
        }
        if got == OCUS {
            break;
        }
        assert!(start.elapsed() < PATIENCE, "bare zenoh: the subscribers never all heard");
    }
    c.bench_function("distrib/fanout_tick_bare_zenoh", |b| {
        b.iter(|| {
            t += 1;
            tick(t);
            all_have(&rx, value(t, keys.len() - 1), OCUS, "bare zenoh");
        })
    });
    drop(subs);
}

fn mirrored(c: &mut Criterion) {
    let port = free_port();
    let a = DataServer::default();
    let vs = a.create_object(a.root(), ObjectInfo::new("vehicles", "vehicles")).unwrap();
    let mut props: Vec<(Guid, PropName)> = Vec::new();
    for v in 0..VEHICLES {
        let g = a.create_object(vs, ObjectInfo::new(&format!("v{v}"), "usv")).unwrap();
        for p in 0..PROPS {
            let name = PropName::new(&format!("p{p}"));
            a.set(g, name, Value::Float(0.0)).unwrap();
            props.push((g, name));
        }
    }
    let ac = Config {
        site: "adapter".into(),
        listen: vec![format!("tcp/127.0.0.1:{port}")],
        share: vec!["vehicles".into()],
        ..Config::default()
    };
    let da = Distrib::start(&a, &ac, None).unwrap();
    let (tx, rx) = unbounded();
    let last = format!("vehicles.v{}.p{}", VEHICLES - 1, PROPS - 1);
    let ocus: Vec<(DataServer, Distrib, PathWatch)> = (0..OCUS)
        .map(|i| {
            let b = DataServer::default();
            let bc = Config {
                site: format!("ocu{i}"),
                connect: vec![format!("tcp/127.0.0.1:{port}")],
                ..Config::default()
            };
            let db = Distrib::start(&b, &bc, None).unwrap();
            assert!(db.wait_snapshots(1, PATIENCE), "ocu{i}: the adapter's snapshot");
            let tx = tx.clone();
            let w = b
                .watch_path(DottedPath::parse(&last).unwrap(), None, move |e| {
                    if let Some(Value::Float(x)) = &e.value {
                        let _ = tx.send(*x);
                    }
                })
                .unwrap();
            (b, db, w)
        })
        .collect();
    let mut t = 0;
    let tick = |t: u64| {
        for (i, (g, name)) in props.iter().enumerate() {
            a.set(*g, *name, Value::Float(value(t, i))).unwrap();
        }
    };
    c.bench_function("distrib/fanout_tick_to_three_mirrors", |b| {
        b.iter(|| {
            t += 1;
            tick(t);
            all_have(&rx, value(t, props.len() - 1), OCUS, "mirrors");
        })
    });
    drop((ocus, da));
}

criterion_group! {
    name = benches;
    config = Criterion::default().sample_size(10).measurement_time(Duration::from_secs(5));
    targets = bare_zenoh, mirrored
}
criterion_main!(benches);
