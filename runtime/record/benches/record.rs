//! Recording overhead (issue 18): one simulated second of a busy trial — 1,000 properties
//! changing at 100 Hz and one 640×480 H.264 camera at 30 fps, decoded as the live OCU
//! decodes it — with and without `--record`, in the same run. The figure is CPU time (every
//! thread of the process: the writers, the DataServer's workers, the decoder, the
//! recorder's writer) per simulated second; target ≤ 1.1× the baseline. The summary also
//! prints the recording's size per minute.
//!
//! `cargo bench --bench record [-- --warm-up-time 1 --measurement-time 3]`. Under
//! `cargo test --benches` each runs once and the summary is one second long. Needs ffmpeg
//! (Debian `ffmpeg`) to encode the camera's frames once at start. `-- profile=baseline` or
//! `-- profile=recording` runs one of the two alone, for a profiler, with each thread's CPU.

#[path = "../../video/tests/peer/mod.rs"]
mod peer;

use cpu_time::ProcessTime;
use criterion::Criterion;
use mocu_dataserver::{Call, DataServer, Guid, MethodSpec, ObjectInfo, Overflow, ParamSpec, Value};
use mocu_record::{Header, Recorder};
use mocu_video::{EncodedUnit, attach_decoder, codec::DecoderHandle, now_us};
use std::process::{Command, Stdio};
use std::sync::Arc;
use std::sync::mpsc;
use std::time::Duration;

const OBJECTS: usize = 10;
const PROPS: usize = 100;
const TICKS: usize = 100;
const FPS: usize = 30;

/// Thirty 640×480 H.264 access units (one GOP of ffmpeg's testsrc2, which moves
/// everywhere: a realistic size for a camera), encoded once. (benches/video.rs encodes
/// its own the same way.)
fn h264_units() -> Vec<Arc<[u8]>> {
    peer::require_ffmpeg();
    let out = Command::new("ffmpeg")
        .args(["-nostdin", "-loglevel", "error", "-f", "lavfi", "-i"])
        .arg("testsrc2=size=640x480:rate=30")
        .args(["-frames:v", "30", "-c:v", "libx264", "-preset", "ultrafast"])
        .args(["-tune", "zerolatency", "-g", "30", "-pix_fmt", "yuv420p", "-f", "h264"])
        .arg("pipe:1")
        .stderr(Stdio::inherit())
        .output()
        .expect("ffmpeg runs");
    assert!(out.status.success() && !out.stdout.is_empty(), "ffmpeg could not encode");
    let aus = mocu_video::rtp::access_units(&out.stdout);
    assert_eq!(aus.len(), 30, "one access unit per frame");
    aus.into_iter().map(Arc::from).collect()
}

/// The trial's world: ten objects of a hundred float properties (with units, as telemetry
/// has), a network camera with its decoder, and a receiver told of each decoded frame.
struct Trial {
    ds: DataServer,
    objects: Vec<Guid>,
    names: Vec<String>,
    encoded: Guid,
    decoded: mpsc::Receiver<()>,
    _decoder: DecoderHandle,
    units: Vec<Arc<[u8]>>,
    second: u64,
}

impl Trial {
    fn new(units: &[Arc<[u8]>]) -> Trial {
        let ds = DataServer::default();
        let names: Vec<String> = (0..PROPS).map(|i| format!("p{i}")).collect();
        let meta = mocu_dataserver::PropMeta::typed(mocu_dataserver::ValueKind::Float).units("m/s");
        let objects = (0..OBJECTS)
            .map(|o| {
                let g = ds
                    .create_object(ds.root(), ObjectInfo::new(&format!("v{o}"), "vehicle"))
                    .unwrap();
                for n in &names {
                    ds.create_property(g, n.as_str(), Value::Float(0.0), meta.clone()).unwrap();
                }
                g
            })
            .collect();
        let cams = ds.create_object(ds.root(), ObjectInfo::new("cameras", "folder")).unwrap();
        let camera = ds.create_listener(cams, "cam").unwrap();
        let encoded = ds.create_listener(camera, "encoded").unwrap();
        let decoder = attach_decoder(&ds, &ds.serial_executor(), camera, encoded).unwrap();
        let sink = ds.create_object(ds.root(), ObjectInfo::new("sink", "bench")).unwrap();
        let spec = ["pixels", "width", "height", "frame", "arrival_us"]
            .iter()
            .fold(MethodSpec::new("frame"), |s, p| s.param(ParamSpec::any(p)));
        let (tx, decoded) = mpsc::channel();
        ds.publish_method(sink, spec, move |c: Call| {
            let _ = tx.send(());
            c.responder.accept(vec![]);
        })
        .unwrap();
        ds.join(camera, sink, "frame", Overflow::DropOldest, 64).unwrap();
        Trial {
            ds,
            objects,
            names,
            encoded,
            decoded,
            _decoder: decoder,
            units: units.to_vec(),
            second: 0,
        }
    }

    /// One simulated second, as fast as it goes: 100 rounds of 1,000 changed values, and a
    /// frame every 3⅓ rounds, each waited for until decoded.
    fn second(&mut self) {
        let mut frame = 0;
        for tick in 0..TICKS {
            let t = self.second as f64 + tick as f64 / TICKS as f64;
            for (o, &g) in self.objects.iter().enumerate() {
                for (i, n) in self.names.iter().enumerate() {
                    let v = (t * 0.5 + (o * PROPS + i) as f64 * 0.01).sin() * 10.0;
                    let _ = self.ds.set(g, n.as_str(), Value::Float(v));
                }
            }
            while frame * TICKS < (tick + 1) * FPS {
                let unit = EncodedUnit {
                    data: self.units[frame % self.units.len()].clone(),
                    codec: "h264".into(),
                    unit: (self.second as i64) * FPS as i64 + frame as i64 + 1,
                    arrival_us: now_us(),
                };
                self.ds.send(self.encoded, unit.to_values()).unwrap();
                self.decoded.recv_timeout(Duration::from_secs(5)).expect("a decoded frame");
                frame += 1;
            }
        }
        self.ds.quiesce();
        self.second += 1;
    }
}

/// CPU time of `seconds` simulated seconds, with everything they caused written.
fn cpu(trial: &mut Trial, rec: Option<&Recorder>, seconds: u64) -> Duration {
    let start = ProcessTime::now();
    for _ in 0..seconds {
        trial.second();
        if let Some(r) = rec {
            r.sync();
        }
    }
    start.elapsed()
}

fn benches(c: &mut Criterion, units: &[Arc<[u8]>]) {
    let dir = tempfile::tempdir().unwrap();
    let mut g = c.benchmark_group("record/one_simulated_second_cpu");
    g.sample_size(10);
    let mut base = Trial::new(units);
    g.bench_function("baseline", |b| b.iter_custom(|n| cpu(&mut base, None, n)));
    drop(base);
    let mut trial = Trial::new(units);
    let rec =
        Recorder::start(&trial.ds, &dir.path().join("bench.mcap"), Header::default()).unwrap();
    g.bench_function("recording", |b| b.iter_custom(|n| cpu(&mut trial, Some(&rec), n)));
    g.finish();
    drop(rec);
}

/// Baseline and recording alternated, `seconds` simulated seconds each, three times: the
/// ratio of their CPU times and the recording's bytes per minute.
fn summary(units: &[Arc<[u8]>], seconds: u64) {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("summary.mcap");
    let (mut base_cpu, mut rec_cpu) = (Duration::ZERO, Duration::ZERO);
    let mut recorded = 0;
    let mut totals = mocu_record::Totals::default();
    for round in 0..3 {
        let mut base = Trial::new(units);
        base_cpu += cpu(&mut base, None, seconds);
        drop(base);
        let mut trial = Trial::new(units);
        let path = dir.path().join(format!("r{round}.mcap"));
        let rec = Recorder::start(&trial.ds, &path, Header::default()).unwrap();
        rec_cpu += cpu(&mut trial, Some(&rec), seconds);
        totals = rec.finish().unwrap();
        recorded = std::fs::metadata(&path).unwrap().len();
        let _ = std::fs::rename(&path, &file);
    }
    let per_s = |d: Duration| d.as_secs_f64() / (3 * seconds) as f64;
    eprintln!(
        "\nrecording overhead, 1,000 properties at 100 Hz + one 640x480 H.264 camera at 30 fps:"
    );
    eprintln!("  baseline   {:8.1} ms CPU per simulated second", per_s(base_cpu) * 1e3);
    eprintln!("  recording  {:8.1} ms CPU per simulated second", per_s(rec_cpu) * 1e3);
    eprintln!(
        "  ratio      {:8.2}x (target <= 1.1x)",
        rec_cpu.as_secs_f64() / base_cpu.as_secs_f64()
    );
    eprintln!(
        "  file       {:8.1} MB per minute ({} messages, {:.1} MB of messages per minute)",
        recorded as f64 / seconds as f64 * 60.0 / 1e6,
        totals.messages,
        totals.bytes as f64 / seconds as f64 * 60.0 / 1e6
    );
}

/// One of the two alone (`-- profile=baseline` or `-- profile=recording`), five simulated
/// seconds, for a profiler (`valgrind --tool=callgrind --separate-threads=yes`, `perf`): the
/// process's CPU per simulated second and, on Linux, each thread's.
fn profile(units: &[Arc<[u8]>], record: bool) {
    const SECONDS: u64 = 5;
    let dir = tempfile::tempdir().unwrap();
    let mut trial = Trial::new(units);
    let rec = record.then(|| {
        Recorder::start(&trial.ds, &dir.path().join("p.mcap"), Header::default()).unwrap()
    });
    let before = threads();
    let d = cpu(&mut trial, rec.as_ref(), SECONDS);
    let per_s = |ns: u64| ns as f64 / 1e6 / SECONDS as f64;
    for (name, ns) in threads() {
        let ran = ns - before.get(&name).copied().unwrap_or(0);
        if ran > 0 {
            eprint!("{name} {:.1} ms  ", per_s(ran));
        }
    }
    eprintln!();
    if let Some(r) = rec {
        r.finish().unwrap();
    }
    eprintln!("{:.1} ms CPU per simulated second", per_s(d.as_nanos() as u64));
}

/// Each thread's run time (ns, `/proc/self/task/*/schedstat`), by name and id; empty where
/// there is no /proc.
fn threads() -> std::collections::BTreeMap<String, u64> {
    let mut out = std::collections::BTreeMap::new();
    for t in std::fs::read_dir("/proc/self/task").into_iter().flatten().flatten() {
        let read = |f: &str| std::fs::read_to_string(t.path().join(f)).unwrap_or_default();
        let ns = read("schedstat").split(' ').next().and_then(|n| n.parse().ok());
        let name = format!("{}/{}", read("comm").trim(), t.file_name().to_string_lossy());
        out.insert(name, ns.unwrap_or(0));
    }
    out
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    if args.iter().any(|a| a == "--list") {
        return;
    }
    // `cargo bench` passes --bench; `cargo test --benches` does not (criterion's test mode).
    let quick = !args.iter().any(|a| a == "--bench");
    let units = h264_units();
    if let Some(which) = args.iter().find_map(|a| a.strip_prefix("profile=")) {
        profile(&units, which == "recording");
        return;
    }
    let mut c = Criterion::default().configure_from_args();
    benches(&mut c, &units);
    summary(&units, if quick { 1 } else { 5 });
    c.final_summary();
}
