//! Latency over loopback (issue 17's target: ≤ 1.5× bare Zenoh). Two world models, each
//! with its own Zenoh session: a property written in the first, until the watch of its
//! mirror in the second has the value (`distrib/property_write_to_mirror_callback`),
//! against the baseline in the same run: a bare Zenoh put of the same payload reaching a
//! subscriber of a second session over the same loopback (`distrib/bare_zenoh_put_to_subscriber`).
//!
//! Both cases first wait until a write gets through (the subscriber's declaration must reach
//! the publisher before a put is routed), so each iteration, in criterion's test mode too,
//! measures one delivery, and a lost one fails with its name instead of hanging.

use criterion::{Criterion, criterion_group, criterion_main};
use crossbeam_channel::{Receiver, unbounded};
use mocu_dataserver::{DataServer, DottedPath, Guid, ObjectInfo, PathWatch, Value};
use mocu_distrib::{Config, Distrib, payload};
use std::net::TcpListener;
use std::time::{Duration, Instant};
use zenoh::Wait;

const PATIENCE: Duration = Duration::from_secs(20);

fn free_port() -> u16 {
    TcpListener::bind("127.0.0.1:0").unwrap().local_addr().unwrap().port()
}

/// Sends `write(i)` until one arrives on `rx` (bounded by [`PATIENCE`]).
fn until_through(what: &str, mut write: impl FnMut(f64), rx: &Receiver<f64>) {
    let start = Instant::now();
    let mut x = -1.0;
    loop {
        write(x);
        if rx.recv_timeout(Duration::from_millis(100)).is_ok() {
            while rx.try_recv().is_ok() {}
            return;
        }
        assert!(start.elapsed() < PATIENCE, "{what}: nothing got through in {PATIENCE:?}");
        x -= 1.0;
    }
}

fn recv(rx: &Receiver<f64>, what: &str) -> f64 {
    rx.recv_timeout(PATIENCE).unwrap_or_else(|_| panic!("{what}: a write was lost"))
}

fn bare_zenoh(c: &mut Criterion) {
    let port = free_port();
    let open = |listen: bool| {
        let ep = format!("tcp/127.0.0.1:{port}");
        let cfg = Config {
            listen: if listen { vec![ep.clone()] } else { vec![] },
            connect: if listen { vec![] } else { vec![ep] },
            ..Config::default()
        };
        zenoh::open(mocu_distrib::zenoh_config(&cfg).unwrap()).wait().unwrap()
    };
    let (a, b) = (open(true), open(false));
    let (tx, rx) = unbounded();
    let key = "mocu/bench/prop/vehicles/usv1/nav/speed";
    let _sub = b
        .declare_subscriber(key)
        .callback(move |s| {
            let bytes = s.payload().to_bytes();
            if let Ok((Value::Float(x), _)) = payload::property_from(&bytes) {
                let _ = tx.send(x);
            }
        })
        .wait()
        .unwrap();
    let guid = Guid::new(4).unwrap();
    let put = |x: f64| a.put(key, payload::property(guid, &Value::Float(x), None)).wait().unwrap();
    until_through("bare zenoh", put, &rx);
    let mut x = 0.0;
    c.bench_function("distrib/bare_zenoh_put_to_subscriber", |bn| {
        bn.iter(|| {
            x += 1.0;
            put(x);
            recv(&rx, "bare zenoh")
        })
    });
}

fn mirrored(c: &mut Criterion) {
    let port = free_port();
    let a = DataServer::default();
    let vs = a.create_object(a.root(), ObjectInfo::new("vehicles", "vehicles")).unwrap();
    let v = a.create_object(vs, ObjectInfo::new("usv1", "usv")).unwrap();
    let nav = a.create_object(v, ObjectInfo::new("nav", "nav")).unwrap();
    a.set(nav, "speed", Value::Float(0.0)).unwrap();
    let ac = Config {
        site: "adapter".into(),
        listen: vec![format!("tcp/127.0.0.1:{port}")],
        share: vec!["vehicles".into()],
        ..Config::default()
    };
    let da = Distrib::start(&a, &ac, None).unwrap();
    let b = DataServer::default();
    let bc = Config {
        site: "ocu".into(),
        connect: vec![format!("tcp/127.0.0.1:{port}")],
        ..Config::default()
    };
    let db = Distrib::start(&b, &bc, None).unwrap();
    assert!(db.wait_snapshots(1, PATIENCE), "the adapter's snapshot");
    let (tx, rx) = unbounded();
    let _w: PathWatch = b
        .watch_path(DottedPath::parse("vehicles.usv1.nav.speed").unwrap(), None, move |e| {
            if let Some(Value::Float(x)) = &e.value {
                let _ = tx.send(*x);
            }
        })
        .unwrap();
    let set = |x: f64| a.set(nav, "speed", Value::Float(x)).unwrap();
    until_through("mirror", set, &rx);
    let mut x = 0.0;
    c.bench_function("distrib/property_write_to_mirror_callback", |bn| {
        bn.iter(|| {
            x += 1.0;
            set(x);
            // The watch may also report the value it held: wait for this one.
            while recv(&rx, "mirror") != x {}
        })
    });
    drop((db, da));
}

criterion_group! {
    name = benches;
    config = Criterion::default().sample_size(30).measurement_time(Duration::from_secs(3));
    targets = bare_zenoh, mirrored
}
criterion_main!(benches);
