//! The distributed world model's latency (issue 17): a property written in one DataServer →
//! the callback of a path watch on its mirror in another DataServer, across two Zenoh
//! sessions on loopback TCP, against the floor any Zenoh user pays: a bare `put` → a
//! subscriber's callback over the same loopback, with the same configuration. Target:
//! ≤ 1.5× the baseline. Both sides live in this process (two sessions, two TCP ends), so
//! the figure is the software path, not the network.
//!
//! `cargo bench --bench distrib [-- --warm-up-time 1 --measurement-time 3]`. After the
//! criterion groups, a summary measures both interleaved (round by round, so that noise of
//! a shared machine hits both alike) and prints medians, p99 and the ratio on stderr.

use criterion::Criterion;
use crossbeam_channel::{Receiver, unbounded};
use mocu_dataserver::{DataServer, DottedPath, Guid, ObjectInfo, PathWatch, Value};
use mocu_distrib::{Config, Distrib, zenoh_config};
use std::net::TcpListener;
use std::time::{Duration, Instant};
use zenoh::Wait;

fn free_port() -> u16 {
    TcpListener::bind("127.0.0.1:0").unwrap().local_addr().unwrap().port()
}

fn config(site: &str, listen: Option<u16>, connect: Option<u16>) -> Config {
    let ep = |p: u16| vec![format!("tcp/127.0.0.1:{p}")];
    Config {
        site: site.into(),
        listen: listen.map(ep).unwrap_or_default(),
        connect: connect.map(ep).unwrap_or_default(),
        share: vec!["vehicles".into()],
        ..Config::default()
    }
}

/// Two sites: `a` writes `vehicles.v1.x`, `b` watches its mirror.
struct Mocu {
    _sites: (Distrib, Distrib),
    a: DataServer,
    v: Guid,
    _watch: PathWatch,
    rx: Receiver<i64>,
    n: i64,
}

impl Mocu {
    fn new() -> Mocu {
        let port = free_port();
        let a = DataServer::default();
        let vs = a.create_object(a.root(), ObjectInfo::new("vehicles", "vehicles")).unwrap();
        let v = a.create_object(vs, ObjectInfo::new("v1", "usv")).unwrap();
        a.set(v, "x", Value::Int(0)).unwrap();
        let da = Distrib::start(&a, &config("a", Some(port), None), None).unwrap();
        let b = DataServer::default();
        let (tx, rx) = unbounded();
        let watch = b
            .watch_path(DottedPath::parse("vehicles.v1.x").unwrap(), None, move |e| {
                if let Some(x) = e.value.as_ref().and_then(Value::as_i64) {
                    let _ = tx.send(x);
                }
            })
            .unwrap();
        let db = Distrib::start(&b, &config("b", None, Some(port)), None).unwrap();
        assert!(db.wait_snapshots(1, Duration::from_secs(30)), "b mirrors a");
        let mut m = Mocu { _sites: (da, db), a, v, _watch: watch, rx, n: 0 };
        m.round(); // the mirror is live
        m
    }

    /// One write, waited for on the other side.
    fn round(&mut self) {
        self.n += 1;
        self.a.set(self.v, "x", Value::Int(self.n)).unwrap();
        while self.rx.recv_timeout(Duration::from_secs(10)).expect("the mirror's callback")
            != self.n
        {}
    }
}

/// Two bare sessions: a put of a payload of the same size, and a subscriber.
struct Bare {
    _sessions: (zenoh::Session, zenoh::Session),
    publisher: zenoh::pubsub::Publisher<'static>,
    rx: Receiver<i64>,
    n: i64,
}

impl Bare {
    fn new() -> Bare {
        let port = free_port();
        let a = zenoh::open(zenoh_config(&config("a", Some(port), None)).unwrap()).wait().unwrap();
        let b = zenoh::open(zenoh_config(&config("b", None, Some(port))).unwrap()).wait().unwrap();
        let (tx, rx) = unbounded();
        b.declare_subscriber("bench/x")
            .callback(move |s| {
                let text = s.payload().try_to_string().map(|t| t.into_owned()).unwrap_or_default();
                let n = text.split(|c: char| !c.is_ascii_digit()).find(|t| !t.is_empty());
                if let Some(n) = n.and_then(|t| t.parse().ok()) {
                    let _ = tx.send(n);
                }
            })
            .background()
            .wait()
            .unwrap();
        let publisher = a.declare_publisher("bench/x").wait().unwrap();
        let mut bare = Bare { _sessions: (a, b), publisher, rx, n: 0 };
        // Until the subscriber is known on the other side (declarations travel too).
        loop {
            bare.n += 1;
            let _ = bare.publisher.put(bare.payload()).wait();
            if bare.rx.recv_timeout(Duration::from_millis(100)).is_ok() {
                break;
            }
        }
        while bare.rx.try_recv().is_ok() {}
        bare
    }

    /// The same size as Mocu's sample of an int property.
    fn payload(&self) -> String {
        format!(r#"{{"object":3,"value":{{"kind":"int","value":{}}}}}"#, self.n)
    }

    fn round(&mut self) {
        self.n += 1;
        self.publisher.put(self.payload()).wait().unwrap();
        while self.rx.recv_timeout(Duration::from_secs(10)).expect("the subscriber's callback")
            < self.n
        {}
    }
}

fn percentile(sorted: &[Duration], p: f64) -> Duration {
    sorted[((sorted.len() - 1) as f64 * p).round() as usize]
}

fn summary(mocu: &mut Mocu, bare: &mut Bare, rounds: usize) {
    let (mut m, mut b) = (Vec::with_capacity(rounds), Vec::with_capacity(rounds));
    for _ in 0..rounds {
        let t = Instant::now();
        bare.round();
        b.push(t.elapsed());
        let t = Instant::now();
        mocu.round();
        m.push(t.elapsed());
    }
    m.sort();
    b.sort();
    let (mm, bm) = (percentile(&m, 0.5), percentile(&b, 0.5));
    eprintln!("\ndistrib summary ({rounds} interleaved rounds, loopback TCP):");
    eprintln!(
        "  property write -> mirror callback: median {:>8.1} us  p99 {:>8.1} us",
        mm.as_secs_f64() * 1e6,
        percentile(&m, 0.99).as_secs_f64() * 1e6
    );
    eprintln!(
        "  bare zenoh put -> subscriber:     median {:>8.1} us  p99 {:>8.1} us",
        bm.as_secs_f64() * 1e6,
        percentile(&b, 0.99).as_secs_f64() * 1e6
    );
    eprintln!("  ratio (median): {:.2}x (target <= 1.5x)", mm.as_secs_f64() / bm.as_secs_f64());
}

fn main() {
    let mut c = Criterion::default().configure_from_args();
    let mut mocu = Mocu::new();
    let mut bare = Bare::new();
    let mut g = c.benchmark_group("distrib_latency");
    g.bench_function("property_write_to_mirror_callback", |bn| bn.iter(|| mocu.round()));
    g.bench_function("bare_zenoh_put_to_subscriber", |bn| bn.iter(|| bare.round()));
    g.finish();
    let test_mode = std::env::args().any(|a| a == "--test");
    summary(&mut mocu, &mut bare, if test_mode { 10 } else { 2000 });
    c.final_summary();
}
