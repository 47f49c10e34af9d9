//! Video benchmarks (issue 9).
//!
//! 1. Decode time per frame, 640×480 and 1280×720, JPEG and H.264: the decoder crate alone
//!    (zune-jpeg; openh264 to YUV, and to YUV + RGBA) against the same unit sent through
//!    our plumbing (the camera's `encoded` listener → decoder node → camera listener → a
//!    receiver) — the difference is what the plumbing costs. Test frames are encoded once
//!    by ffmpeg at start (testsrc; H.264 one 30-frame GOP, decoded in order, cycling).
//! 2. Latency from packet arrival (the receiver's timestamp at UDP receive) to the
//!    composited display frame that shows it, with ffmpeg streaming 640×480 at 30 fps to
//!    loopback, a 1280×720 CPU display and one video window: event-driven frames (as the
//!    windowed display draws) and 60 Hz ticks (as `mocu run --headless` draws). Target:
//!    ≤ 50 ms. Printed as a table (median, p95, max).
//!
//! 3. The simulator's camera path at 640×480 (issue 16): a drive camera's picture drawn by
//!    the simulator, sent through the DataServer to the video painter, painted into a
//!    640×480 video window and composited — against a memcpy of the frame's bytes (the least
//!    a frame costs) and the simulator's picture alone, in the same run.
//!
//! `cargo bench --bench video [-- FILTER]`. Under `cargo test --benches` each decode
//! benchmark runs once and the latency runs shrink to 2 s. Needs ffmpeg (Debian `ffmpeg`).

#[path = "../runtime/video/tests/peer/mod.rs"]
mod peer;

mod common;
use common::filter;
use criterion::{BenchmarkId, Criterion};
use mocu_dataserver::{Call, DataServer, Guid, MethodSpec, ObjectInfo, Overflow, ParamSpec, Value};
use mocu_display::{BackendChoice, Display, DisplayOptions, Rect};
use mocu_host::{Module, ModuleContext};
use mocu_sim::camera::{Lens, Pose, Renderer};
use mocu_sim::{Sim, SimConfig, VehicleKind};
use mocu_video::codec::DecoderHandle;
use mocu_video::{
    EncodedUnit, ReceiverConfig, VideoReceiver, VideoWindows, attach_decoder, now_us,
};
use openh264::formats::YUVSource;
use peer::{Ffmpeg, Kind};
use std::hint::black_box;
use std::process::{Command, Stdio};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc;
use std::time::{Duration, Instant};

static QUICK: AtomicBool = AtomicBool::new(false);

fn encode(w: u32, h: u32, codec: &[&str], frames: u32) -> Vec<u8> {
    peer::require_ffmpeg();
    let out = Command::new("ffmpeg")
        .args(["-nostdin", "-loglevel", "error", "-f", "lavfi", "-i"])
        .arg(format!("testsrc=size={w}x{h}:rate=30"))
        .args(["-frames:v", &frames.to_string()])
        .args(codec)
        .arg("pipe:1")
        .stderr(Stdio::inherit())
        .output()
        .expect("ffmpeg runs");
    assert!(out.status.success() && !out.stdout.is_empty(), "ffmpeg could not encode");
    out.stdout
}

fn jpeg(w: u32, h: u32) -> Vec<u8> {
    encode(w, h, &["-c:v", "mjpeg", "-pix_fmt", "yuvj420p", "-q:v", "4", "-f", "mjpeg"], 1)
}

fn h264(w: u32, h: u32) -> Vec<Vec<u8>> {
    let es = encode(
        w,
        h,
        &[
            "-c:v",
            "libx264",
            "-preset",
            "ultrafast",
            "-tune",
            "zerolatency",
            "-g",
            "30",
            "-pix_fmt",
            "yuv420p",
            "-f",
            "h264",
        ],
        30,
    );
    let aus = mocu_video::rtp::access_units(&es);
    assert_eq!(aus.len(), 30, "one access unit per frame");
    aus
}

/// A camera with a decoder attached and a receiver that signals each decoded frame.
struct Plumbing {
    ds: DataServer,
    encoded: Guid,
    rx: mpsc::Receiver<()>,
    _decoder: DecoderHandle,
}

fn plumbing() -> Plumbing {
    let ds = DataServer::default();
    let camera = ds.create_listener(ds.root(), "cam").unwrap();
    let encoded = ds.create_listener(camera, "encoded").unwrap();
    let decoder = attach_decoder(&ds, &ds.serial_executor(), camera, encoded).unwrap();
    let sink = ds.create_object(ds.root(), ObjectInfo::new("sink", "bench")).unwrap();
    let spec = ["pixels", "width", "height", "frame", "arrival_us"]
        .iter()
        .fold(MethodSpec::new("frame_timed"), |s, p| s.param(ParamSpec::any(p)));
    let (tx, rx) = mpsc::channel();
    ds.publish_method(sink, spec, move |c: Call| {
        let _ = tx.send(());
        c.responder.accept(vec![]);
    })
    .unwrap();
    ds.join(camera, sink, "frame_timed", Overflow::DropOldest, 64).unwrap();
    Plumbing { ds, encoded, rx, _decoder: decoder }
}

impl Plumbing {
    fn decode(&self, codec: &str, data: &std::sync::Arc<[u8]>, n: i64) {
        let u =
            EncodedUnit { data: data.clone(), codec: codec.into(), unit: n, arrival_us: now_us() };
        self.ds.send(self.encoded, u.to_values()).unwrap();
        self.rx.recv_timeout(Duration::from_secs(5)).expect("a decoded frame");
    }
}

fn decode_benches(c: &mut Criterion) {
    for (w, h) in [(640u32, 480u32), (1280, 720)] {
        let size = format!("{w}x{h}");
        let j = jpeg(w, h);
        let mut g = c.benchmark_group("decode/jpeg");
        g.bench_with_input(BenchmarkId::new("zune-jpeg alone", &size), &j, |b, j| {
            b.iter(|| mocu_video::codec::decode_jpeg(j).unwrap())
        });
        let p = plumbing();
        let ja: std::sync::Arc<[u8]> = j.clone().into();
        let mut n = 0;
        g.bench_function(BenchmarkId::new("mocu plumbing", &size), |b| {
            b.iter(|| {
                n += 1;
                p.decode("jpeg", &ja, n)
            })
        });
        g.finish();

        let aus = h264(w, h);
        let mut g = c.benchmark_group("decode/h264");
        let mut d = openh264::decoder::Decoder::new().unwrap();
        let mut i = 0;
        g.bench_function(BenchmarkId::new("openh264 alone (YUV)", &size), |b| {
            b.iter(|| {
                let r = d.decode(&aus[i % aus.len()]).unwrap().map(|y| y.dimensions());
                i += 1;
                r
            })
        });
        let mut d = openh264::decoder::Decoder::new().unwrap();
        let mut rgba = vec![0u8; (w * h * 4) as usize];
        let mut i = 0;
        g.bench_function(BenchmarkId::new("openh264 + RGBA", &size), |b| {
            b.iter(|| {
                if let Some(y) = d.decode(&aus[i % aus.len()]).unwrap() {
                    y.write_rgba8(&mut rgba);
                }
                i += 1;
            })
        });
        let p = plumbing();
        let arcs: Vec<std::sync::Arc<[u8]>> = aus.iter().map(|a| a.clone().into()).collect();
        let mut i = 0;
        g.bench_function(BenchmarkId::new("mocu plumbing", &size), |b| {
            b.iter(|| {
                p.decode("h264", &arcs[i % arcs.len()], i as i64 + 1);
                i += 1;
            })
        });
        g.finish();
    }
}

/// The simulator with one USV whose drive camera (640×480, a frame every step) a 640×480
/// video window of a CPU display shows (`source` empty: no window watches it, so no picture
/// is drawn).
struct CameraPath {
    ds: DataServer,
    sim: Sim,
    display: Display,
    windows: VideoWindows,
    win: Guid,
}

impl CameraPath {
    fn new(source: &str) -> CameraPath {
        let (w, h) = (640u32, 480u32);
        let ds = DataServer::default();
        let cfg = SimConfig {
            usv: 1,
            ugv: 0,
            uav: 0,
            appear_every: 0.0,
            autostart: true,
            camera_fps: 20.0,
            camera_width: w,
            camera_height: h,
            ..SimConfig::default()
        };
        let sim = Sim::new(ModuleContext::detached("sim", ds.clone()), cfg).unwrap();
        let display = mocu_display::ensure_display_object(&ds, w, h).unwrap();
        let win = mocu_display::publish_window(
            &ds,
            display,
            "video",
            "video",
            0,
            Rect::new(0.0, 0.0, w as f32, h as f32),
        )
        .unwrap();
        ds.set(win, "source", Value::str(source)).unwrap();
        let windows = VideoWindows::start(&ds).unwrap();
        let display = Display::new(&ds, DisplayOptions::new(w, h).backend(BackendChoice::Cpu));
        let mut p = CameraPath { ds, sim, display: display.unwrap(), windows, win };
        p.sim.step(0.05);
        p.ds.quiesce();
        p.windows.refresh();
        p.step();
        p
    }

    /// One simulator step (drawing and sending the watched camera's picture), the frame
    /// delivered to the painter, the display drawn.
    fn step(&mut self) {
        self.sim.step(0.05);
        self.ds.quiesce();
        self.display.frame();
    }

    fn shown_frame(&self) -> Option<i64> {
        self.windows.shown(self.win).and_then(|s| s.frame)
    }
}

fn camera_path_benches(c: &mut Criterion) {
    let (w, h) = (640usize, 480usize);
    let mut g = c.benchmark_group("camera_path/640x480");
    let frame = vec![90u8; w * h * 3];
    g.bench_function("baseline: memcpy of the frame (RGB8)", |b| {
        b.iter(|| black_box(frame.clone()))
    });
    let r = Renderer::new(w as u32, h as u32, Lens::Drive, VehicleKind::Usv);
    let mut heading = 0.0;
    g.bench_function("sim drive camera render", |b| {
        b.iter(|| {
            heading = (heading + 1.7) % 360.0;
            black_box(r.render(Pose { heading, pitch: 2.0, roll: 6.0, ..Pose::default() }))
        })
    });
    let mut idle = CameraPath::new("");
    g.bench_function("sim step, no camera watched", |b| b.iter(|| idle.step()));
    let mut live = CameraPath::new("root.vehicles.usv1.cameras.drive");
    let before = live.shown_frame();
    live.step();
    assert!(
        live.shown_frame().is_some() && live.shown_frame() != before,
        "each step shows a new frame in the window"
    );
    g.bench_function("sim step + render + send + video window paint + composite", |b| {
        b.iter(|| live.step())
    });
    g.finish();
}

/// Latencies (ms) from packet arrival to the composited frame showing it.
fn latency(kind: Kind, secs: u32, tick: Option<Duration>) -> (Vec<f64>, u64) {
    let ds = DataServer::default();
    let ctx = ModuleContext::detached("video", ds.clone());
    let cfg = ReceiverConfig {
        address: "127.0.0.1:0".parse().unwrap(),
        camera: Some("bench".into()),
        ..ReceiverConfig::default()
    };
    let mut rx = VideoReceiver::new(cfg);
    rx.start(&ctx).unwrap();
    let camera = ds.resolve(&["cameras", "bench"]).unwrap();
    let port = ds.get(camera, "port").unwrap().as_i64().unwrap() as u16;
    let (sw, sh) = (1280u32, 720u32);
    let display = mocu_display::ensure_display_object(&ds, sw, sh).unwrap();
    let win = mocu_display::publish_window(
        &ds,
        display,
        "video",
        "video",
        0,
        Rect::new(0.0, 0.0, sw as f32, sh as f32),
    )
    .unwrap();
    ds.set(win, "source", Value::str("root.cameras.bench")).unwrap();
    let windows = VideoWindows::start(&ds).unwrap();
    let mut d = Display::new(&ds, DisplayOptions::new(sw, sh).backend(BackendChoice::Cpu)).unwrap();
    let ff = Ffmpeg::stream(kind, 640, 480, port, secs + 1);
    let start = Instant::now();
    let warm = Duration::from_millis(1000);
    let end = start + Duration::from_secs(secs as u64);
    let mut last = None;
    let mut out = Vec::new();
    let mut next = Instant::now();
    while Instant::now() < end {
        match tick {
            None => {
                d.wait_for_change(Duration::from_millis(50));
            }
            Some(p) => {
                next += p;
                std::thread::sleep(next.saturating_duration_since(Instant::now()));
            }
        }
        d.frame();
        let now = now_us();
        if let Some(s) = windows.shown(win)
            && s.frame.is_some()
            && s.frame != last
        {
            last = s.frame;
            if start.elapsed() > warm
                && let Some(t) = s.arrival_us
            {
                out.push((now - t) as f64 / 1000.0);
            }
        }
    }
    drop(ff);
    let frames = ds.get(camera, "frames").unwrap().as_i64().unwrap_or(0) as u64;
    rx.stop();
    drop(windows);
    (out, frames)
}

fn pct(v: &[f64], p: f64) -> f64 {
    if v.is_empty() {
        return f64::NAN;
    }
    let mut s = v.to_vec();
    s.sort_by(|a, b| a.total_cmp(b));
    s[((s.len() - 1) as f64 * p).round() as usize]
}

fn latency_table(filter: Option<&str>) {
    let secs = if QUICK.load(Ordering::Relaxed) { 2 } else { 8 };
    let mut rows = Vec::new();
    for (kind, kname) in [(Kind::RtpH264, "rtp/h264"), (Kind::RtpJpeg, "rtp/jpeg")] {
        for (tick, tname) in
            [(None, "event-driven"), (Some(Duration::from_micros(16_667)), "60 Hz ticks")]
        {
            let name = format!("latency/{kname}/640x480@30 → 1280x720 display/{tname}");
            if filter.is_some_and(|f| !name.contains(f)) {
                continue;
            }
            let (l, decoded) = latency(kind, secs, tick);
            rows.push((name, l, decoded));
        }
    }
    if rows.is_empty() {
        return;
    }
    println!("\npacket arrival → composited frame (ms), ffmpeg testsrc streaming to loopback");
    println!(
        "{:<62} {:>6} {:>8} {:>7} {:>7} {:>7}",
        "", "shown", "decoded", "median", "p95", "max"
    );
    for (name, l, decoded) in rows {
        println!(
            "{:<62} {:>6} {:>8} {:>7.1} {:>7.1} {:>7.1}",
            name,
            l.len(),
            decoded,
            pct(&l, 0.5),
            pct(&l, 0.95),
            pct(&l, 1.0)
        );
    }
}

fn main() {
    QUICK.store(!std::env::args().any(|a| a == "--bench"), Ordering::Relaxed);
    let filter = filter();
    let mut c = Criterion::default().configure_from_args();
    if filter.as_deref().is_none_or(|f| "decode".contains(f) || f.contains("decode")) {
        decode_benches(&mut c);
    }
    if filter.as_deref().is_none_or(|f| "camera_path".contains(f) || f.contains("camera_path")) {
        camera_path_benches(&mut c);
    }
    let table = filter.as_deref().filter(|f| !f.contains("decode") && !f.contains("camera_path"));
    latency_table(table);
    c.final_summary();
}
