//! Fan-out (issue 17's figure): an adapter process writes 100 vehicles × 50 properties at
//! 10 Hz (every value changes every tick: 50,000 changes a second), three OCU processes
//! mirror it over loopback. Each OCU connects through a relay in this process that counts
//! the bytes on its link; each process reports its own CPU time (user + system, all
//! threads, from /proc/self/stat). Run it in release:
//!
//! ```sh
//! cargo run --release -p mocu-distrib --example fanout            # 10 s of traffic
//! cargo run --release -p mocu-distrib --example fanout -- 30      # 30 s
//! ```
//!
//! The figures are in docs/distribution.md ("Cost"). The same binary plays every role:
//! `fanout adapter PORT SECS` and `fanout ocu PORT NAME SECS` are its children.

use mocu_dataserver::{DataServer, Guid, ObjectInfo, PropMeta, PropName, Value, ValueKind};
use mocu_distrib::{Config, Distrib, payload};
use std::io::{BufRead, BufReader, Read, Write};
use std::net::{Shutdown, TcpListener, TcpStream};
use std::process::{Command, Stdio};
use std::sync::Arc;
use std::sync::atomic::{AtomicU64, Ordering};
use std::time::{Duration, Instant};
use zenoh::Wait;
use zenoh::qos::CongestionControl;

const VEHICLES: usize = 100;
const PROPS: usize = 50;
const HZ: f64 = 10.0;
const OCUS: usize = 3;

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    match args.first().map(String::as_str) {
        Some("adapter") => adapter(args[1].parse().unwrap(), args[2].parse().unwrap()),
        Some("ocu") => ocu(args[1].parse().unwrap(), &args[2], args[3].parse().unwrap()),
        Some("bare-adapter") => bare_adapter(args[1].parse().unwrap(), args[2].parse().unwrap()),
        Some("bare-ocu") => bare_ocu(args[1].parse().unwrap(), args[3].parse().unwrap()),
        secs => {
            let secs = secs.and_then(|s| s.parse().ok()).unwrap_or(10.0);
            let bare = lead(secs, "bare-");
            let ours = lead(secs, "");
            println!(
                "ratio to bare Zenoh (same payloads, same rate, same run): adapter {:.2}x, OCUs {:.2}x CPU; bytes {:.2}x",
                ours.adapter_cpu / bare.adapter_cpu,
                ours.ocu_cpu / bare.ocu_cpu,
                ours.bytes / bare.bytes,
            );
        }
    }
}

/// This process's CPU time so far (all threads), from /proc/self/stat (clock ticks of 10 ms).
fn cpu() -> Duration {
    let stat = std::fs::read_to_string("/proc/self/stat").unwrap_or_default();
    let after = stat.rsplit_once(") ").map_or("", |(_, r)| r);
    let f: Vec<&str> = after.split(' ').collect();
    // Fields 14 and 15 of the file (utime, stime); `after` starts at field 3 (the state).
    let field = |i: usize| f.get(i).and_then(|x| x.parse::<u64>().ok()).unwrap_or(0);
    let ticks = field(11) + field(12);
    Duration::from_millis(ticks * 10)
}

fn adapter(port: u16, secs: f64) {
    let ds = DataServer::default();
    let vs = ds.create_object(ds.root(), ObjectInfo::new("vehicles", "vehicles")).unwrap();
    let meta = PropMeta::typed(ValueKind::Float).units("m").rate(HZ);
    let mut props: Vec<(Guid, PropName)> = Vec::new();
    for v in 0..VEHICLES {
        let g = ds.create_object(vs, ObjectInfo::new(&format!("v{v}"), "usv")).unwrap();
        for p in 0..PROPS {
            let name = PropName::new(&format!("p{p}"));
            ds.create_property(g, name, Value::Float(0.0), meta.clone()).unwrap();
            props.push((g, name));
        }
    }
    let cfg = Config {
        site: "adapter".into(),
        listen: vec![format!("tcp/127.0.0.1:{port}")],
        share: vec!["vehicles".into()],
        ..Config::default()
    };
    let d = Distrib::start(&ds, &cfg, None).unwrap();
    println!("ready");
    // Wait for the OCUs' snapshots to be served before the clock starts.
    let mut line = String::new();
    let _ = std::io::stdin().read_line(&mut line);
    let (start, cpu0) = (Instant::now(), cpu());
    let ticks = (secs * HZ) as u64;
    for tick in 1..=ticks {
        for (i, (g, name)) in props.iter().enumerate() {
            let _ = ds.set(*g, *name, Value::Float(tick as f64 + i as f64 * 1e-6));
        }
        let due = start + Duration::from_secs_f64(tick as f64 / HZ);
        std::thread::sleep(due.saturating_duration_since(Instant::now()));
    }
    ds.quiesce();
    let wall = start.elapsed();
    let puts = d.publish_stats.puts.load(Ordering::Relaxed);
    println!("cpu {} wall {} puts {puts}", (cpu() - cpu0).as_secs_f64(), wall.as_secs_f64());
    // Let the OCUs drain before the session closes.
    let _ = std::io::stdin().read_line(&mut line);
    d.stop();
}

fn ocu(port: u16, name: &str, secs: f64) {
    let ds = DataServer::default();
    let cfg = Config {
        site: name.into(),
        connect: vec![format!("tcp/127.0.0.1:{port}")],
        ..Config::default()
    };
    let d = Distrib::start(&ds, &cfg, None).unwrap();
    assert!(d.wait_snapshots(1, Duration::from_secs(60)), "{name}: no snapshot");
    println!("ready");
    let cpu0 = cpu();
    let last_tick = (secs * HZ) as u64;
    let last = (VEHICLES - 1, PROPS - 1);
    let g = ds.resolve(&["vehicles", &format!("v{}", last.0)]).unwrap();
    let want = last_tick as f64 + ((VEHICLES * PROPS - 1) as f64) * 1e-6;
    let deadline = Instant::now() + Duration::from_secs_f64(secs + 60.0);
    while ds.try_get(g, format!("p{}", last.1).as_str().into()) != Some(Value::Float(want)) {
        assert!(Instant::now() < deadline, "{name}: the last tick never arrived");
        std::thread::sleep(Duration::from_millis(20));
    }
    let applied = d.mirror_stats.applied.load(Ordering::Relaxed);
    println!("cpu {} applied {applied}", (cpu() - cpu0).as_secs_f64());
    d.stop();
}

/// The baseline: the same JSON property payloads put on the same keys at the same rate by a
/// bare Zenoh session, no DataServer on either side.
fn bare_adapter(port: u16, secs: f64) {
    let cfg = Config { listen: vec![format!("tcp/127.0.0.1:{port}")], ..Config::default() };
    let session = zenoh::open(mocu_distrib::zenoh_config(&cfg).unwrap()).wait().unwrap();
    let guid = Guid::new(4).unwrap();
    let keys: Vec<String> = (0..VEHICLES * PROPS)
        .map(|i| format!("mocu/bare/prop/vehicles/v{}/p{}", i / PROPS, i % PROPS))
        .collect();
    println!("ready");
    let mut line = String::new();
    let _ = std::io::stdin().read_line(&mut line);
    let (start, cpu0) = (Instant::now(), cpu());
    let ticks = (secs * HZ) as u64;
    for tick in 1..=ticks {
        for (i, key) in keys.iter().enumerate() {
            let v = Value::Float(tick as f64 + i as f64 * 1e-6);
            let put = session.put(key.as_str(), payload::property(guid, &v, None));
            // As the publisher puts a property: blocking, never dropped.
            let _ = put.congestion_control(CongestionControl::Block).wait();
        }
        let due = start + Duration::from_secs_f64(tick as f64 / HZ);
        std::thread::sleep(due.saturating_duration_since(Instant::now()));
    }
    let wall = start.elapsed();
    println!(
        "cpu {} wall {} puts {}",
        (cpu() - cpu0).as_secs_f64(),
        wall.as_secs_f64(),
        ticks as usize * keys.len()
    );
    let _ = std::io::stdin().read_line(&mut line);
    let _ = session.close().wait();
}

fn bare_ocu(port: u16, secs: f64) {
    let cfg = Config { connect: vec![format!("tcp/127.0.0.1:{port}")], ..Config::default() };
    let session = zenoh::open(mocu_distrib::zenoh_config(&cfg).unwrap()).wait().unwrap();
    let last_tick = (secs * HZ) as u64;
    let want = last_tick as f64 + ((VEHICLES * PROPS - 1) as f64) * 1e-6;
    let (tx, rx) = std::sync::mpsc::channel();
    let got = Arc::new(AtomicU64::new(0));
    let g = got.clone();
    let _sub = session
        .declare_subscriber("mocu/bare/prop/**")
        .callback(move |s| {
            g.fetch_add(1, Ordering::Relaxed);
            // Decoded as a mirror decodes it, so both sides parse the same JSON.
            if let Ok((Value::Float(x), _)) = payload::property_from(&s.payload().to_bytes())
                && x == want
            {
                let _ = tx.send(());
            }
        })
        .wait()
        .unwrap();
    // The subscription must reach the publisher before the clock starts.
    std::thread::sleep(Duration::from_secs(1));
    println!("ready");
    let cpu0 = cpu();
    rx.recv_timeout(Duration::from_secs_f64(secs + 60.0)).expect("the last tick never arrived");
    println!("cpu {} applied {}", (cpu() - cpu0).as_secs_f64(), got.load(Ordering::Relaxed));
}

/// A TCP relay to `target` that counts the bytes it carries towards the connecting side.
fn relay(target: u16, down: Arc<AtomicU64>) -> u16 {
    let listener = TcpListener::bind("127.0.0.1:0").unwrap();
    let port = listener.local_addr().unwrap().port();
    std::thread::spawn(move || {
        for inbound in listener.incoming().flatten() {
            let Ok(outbound) = TcpStream::connect(("127.0.0.1", target)) else { continue };
            let none = Arc::new(AtomicU64::new(0));
            for (from, to, count) in [
                (inbound.try_clone().unwrap(), outbound.try_clone().unwrap(), none),
                (outbound, inbound, down.clone()),
            ] {
                std::thread::spawn(move || pump(from, to, &count));
            }
        }
    });
    port
}

fn pump(mut from: TcpStream, mut to: TcpStream, count: &AtomicU64) {
    let mut buf = vec![0u8; 64 * 1024];
    while let Ok(n) = from.read(&mut buf) {
        if n == 0 || to.write_all(&buf[..n]).is_err() {
            break;
        }
        count.fetch_add(n as u64, Ordering::Relaxed);
    }
    let _ = to.shutdown(Shutdown::Both);
}

struct Child {
    proc: std::process::Child,
    out: BufReader<std::process::ChildStdout>,
}

impl Child {
    fn start(args: &[String]) -> Child {
        let exe = std::env::current_exe().unwrap();
        let mut proc = Command::new(exe)
            .args(args)
            .stdin(Stdio::piped())
            .stdout(Stdio::piped())
            .spawn()
            .unwrap();
        let out = BufReader::new(proc.stdout.take().unwrap());
        Child { proc, out }
    }

    fn line(&mut self) -> String {
        let mut l = String::new();
        self.out.read_line(&mut l).unwrap();
        l.trim().to_string()
    }

    fn tell(&mut self) {
        let _ = writeln!(self.proc.stdin.as_mut().unwrap());
    }

    fn figure(line: &str, key: &str) -> f64 {
        let mut it = line.split_whitespace();
        while let Some(k) = it.next() {
            if k == key {
                return it.next().and_then(|v| v.parse().ok()).unwrap_or(f64::NAN);
            }
        }
        f64::NAN
    }
}

/// What one run measured: CPU seconds (adapter; OCUs summed) and bytes on the OCUs' links.
struct Run {
    adapter_cpu: f64,
    ocu_cpu: f64,
    bytes: f64,
}

fn lead(secs: f64, role: &str) -> Run {
    let port = TcpListener::bind("127.0.0.1:0").unwrap().local_addr().unwrap().port();
    let s = secs.to_string();
    let mut adapter = Child::start(&[format!("{role}adapter"), port.to_string(), s.clone()]);
    assert_eq!(adapter.line(), "ready");
    let counts: Vec<Arc<AtomicU64>> = (0..OCUS).map(|_| Arc::new(AtomicU64::new(0))).collect();
    let mut ocus: Vec<Child> = counts
        .iter()
        .enumerate()
        .map(|(i, c)| {
            let via = relay(port, c.clone());
            Child::start(&[format!("{role}ocu"), via.to_string(), format!("ocu{i}"), s.clone()])
        })
        .collect();
    for o in &mut ocus {
        assert_eq!(o.line(), "ready");
    }
    let before: Vec<u64> = counts.iter().map(|c| c.load(Ordering::Relaxed)).collect();
    adapter.tell();
    let a = adapter.line();
    let reports: Vec<String> = ocus.iter_mut().map(Child::line).collect();
    adapter.tell();
    let _ = adapter.proc.wait();
    for o in &mut ocus {
        let _ = o.proc.wait();
    }
    let wall = Child::figure(&a, "wall");
    let changes = (secs * HZ) as usize * VEHICLES * PROPS;
    let what =
        if role.is_empty() { "the distributed world model" } else { "bare Zenoh (baseline)" };
    println!(
        "{what}: {VEHICLES} vehicles x {PROPS} properties at {HZ} Hz to {OCUS} OCUs, {secs} s ({changes} changes)"
    );
    println!(
        "adapter: CPU {:.2} s in {wall:.2} s = {:.0}% of a core; {} puts",
        Child::figure(&a, "cpu"),
        100.0 * Child::figure(&a, "cpu") / wall,
        Child::figure(&a, "puts"),
    );
    for (i, r) in reports.iter().enumerate() {
        let bytes = counts[i].load(Ordering::Relaxed) - before[i];
        println!(
            "ocu{i}: CPU {:.2} s = {:.0}% of a core; {} samples applied; link {:.2} MB/s = {:.1} kB/s per vehicle = {:.0} B per change",
            Child::figure(r, "cpu"),
            100.0 * Child::figure(r, "cpu") / wall,
            Child::figure(r, "applied"),
            bytes as f64 / wall / 1e6,
            bytes as f64 / wall / 1e3 / VEHICLES as f64,
            bytes as f64 / changes as f64,
        );
    }
    let total: u64 = counts.iter().zip(&before).map(|(c, b)| c.load(Ordering::Relaxed) - b).sum();
    Run {
        adapter_cpu: Child::figure(&a, "cpu"),
        ocu_cpu: reports.iter().map(|r| Child::figure(r, "cpu")).sum(),
        bytes: total as f64,
    }
}
