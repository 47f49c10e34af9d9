//! Recording overhead of the whole OCU (issue 18, docs/recording.md "Cost"): the `mocu`
//! binary, with and without `--record`, alternated, under the load — about 1,000
//! properties changing at 100 Hz and one 640×480 H.264 camera at 30 fps:
//!
//! - 53 MAVLink vehicles (this process, on loopback UDP), each sending GLOBAL_POSITION_INT,
//!   ATTITUDE, VFR_HUD and SYS_STATUS 100 times a second with every field moving (19
//!   properties a vehicle), and a HEARTBEAT a second;
//! - ffmpeg streaming testsrc2 at 640×480, 30 fps, H.264 over RTP (Debian `ffmpeg`);
//! - `mocu run benches/record_trial/project.toml --headless --frames N` (the paper's USV
//!   display at 1280×720, the simulator, the map; the camera full screen), and `mocu serve`
//!   on the same profile (no display: the headless adapter), each for the same wall time.
//!
//! The figure is the OCU process's CPU time (user + system of every thread, read from
//! `/proc/PID/stat` once it has exited and before it is reaped: the senders' CPU is not in
//! it). The recording is then read back: changes recorded per second (the load as it
//! arrived), video units, and bytes per minute.
//!
//! `cargo bench --bench record_trial` (10 s runs, three rounds); under `cargo test
//! --benches` one 2 s round, only to check that it runs and records the load.

#[path = "../runtime/video/tests/peer/mod.rs"]
mod peer;
#[path = "common/telemetry.rs"]
mod telemetry;

use mavlink::dialects::development::*;
use peer::{Ffmpeg, Kind};
use std::net::UdpSocket;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

const VEHICLES: u8 = 53;
const RATE_HZ: u32 = 100;
const FPS: u32 = 60;

/// This process's MAVLink vehicles: every tick each sends its four telemetry messages, all
/// fields moving; a heartbeat a second (three at the start: the link's proof of a new id).
fn send_telemetry(to: std::net::SocketAddr, stop: Arc<AtomicBool>) -> std::thread::JoinHandle<()> {
    std::thread::spawn(move || {
        let sock = UdpSocket::bind("127.0.0.1:0").unwrap();
        let mut seq = 0u8;
        let mut send = |sys: u8, m: MavMessage| {
            let _ = sock.send_to(&telemetry::datagram(sys, &mut seq, &m), to);
        };
        let heartbeat = telemetry::copter_heartbeat();
        for _ in 0..3 {
            for sys in 1..=VEHICLES {
                send(sys, heartbeat.clone());
            }
        }
        let period = Duration::from_secs(1) / RATE_HZ;
        let t0 = Instant::now();
        let mut tick = 0u32;
        while !stop.load(Ordering::Relaxed) {
            for sys in 1..=VEHICLES {
                if tick % RATE_HZ == u32::from(sys) % RATE_HZ {
                    send(sys, heartbeat.clone());
                }
                telemetry(tick, sys).into_iter().for_each(|m| send(sys, m));
            }
            tick += 1;
            let due = t0 + period * tick;
            if let Some(wait) = due.checked_duration_since(Instant::now()) {
                std::thread::sleep(wait);
            }
        }
    })
}

/// One vehicle's four messages at `tick`: every field the OCU shows moves.
fn telemetry(tick: u32, sys: u8) -> [MavMessage; 4] {
    let t = tick as i32 + i32::from(sys) * 7;
    let f = t as f32;
    let wave = (f * 0.05).sin();
    [
        MavMessage::GLOBAL_POSITION_INT(GLOBAL_POSITION_INT_DATA {
            time_boot_ms: tick * 10,
            lat: 327_157_000 + t * 3,
            lon: -1_171_611_000 + t * 5,
            alt: 100_000 + t,
            relative_alt: 10_000 + t,
            vx: 300 + (wave * 100.0) as i16,
            vy: 400 - (wave * 100.0) as i16,
            vz: (wave * 50.0) as i16,
            hdg: (9000 + tick * 3 % 27000) as u16,
        }),
        MavMessage::ATTITUDE(ATTITUDE_DATA {
            time_boot_ms: tick * 10,
            roll: 0.1 * wave,
            pitch: 0.05 * wave + 0.01,
            yaw: 1.5 + 0.5 * wave,
            ..ATTITUDE_DATA::default()
        }),
        MavMessage::VFR_HUD(VFR_HUD_DATA {
            airspeed: 10.0 + wave,
            groundspeed: 9.0 + wave,
            alt: 100.0 + f * 0.01,
            climb: 0.5 * wave,
            heading: (90 + tick % 90) as i16,
            throttle: (40 + tick % 50) as u16,
        }),
        MavMessage::SYS_STATUS(SYS_STATUS_DATA {
            voltage_battery: (12_600 - tick % 1000) as u16,
            battery_remaining: (90 - (tick % 80)) as i8,
            drop_rate_comm: (tick % 100) as u16,
            ..SYS_STATUS_DATA::default()
        }),
    ]
}

/// `child`'s state letter and its CPU clock ticks so far (user + system, every thread),
/// from `/proc/PID/stat`; `None` where there is no /proc.
fn proc_stat(child: &Child) -> Option<(char, u64)> {
    let s = std::fs::read_to_string(format!("/proc/{}/stat", child.id())).ok()?;
    // After the command name (which may hold spaces): the state, then fields 4 onwards.
    let f: Vec<&str> = s[s.rfind(')')? + 2..].split(' ').collect();
    let ticks = f.get(11)?.parse::<u64>().ok()? + f.get(12)?.parse::<u64>().ok()?;
    Some((f[0].chars().next()?, ticks))
}

/// CPU seconds of `child` once it has exited, read while it is a zombie (before `wait`
/// reaps it), and whether it exited successfully.
fn cpu_at_exit(child: &mut Child) -> (f64, bool) {
    let ticks = loop {
        match proc_stat(child).expect("/proc/PID/stat of the OCU") {
            ('Z', ticks) => break ticks,
            _ => std::thread::sleep(Duration::from_millis(5)),
        }
    };
    let ok = child.wait().is_ok_and(|s| s.success());
    (ticks as f64 / clock_ticks() as f64, ok)
}

/// The kernel's clock ticks a second (`getconf CLK_TCK`, asked once; 100 where it cannot
/// be asked).
fn clock_ticks() -> u64 {
    static TICKS: std::sync::OnceLock<u64> = std::sync::OnceLock::new();
    *TICKS.get_or_init(|| {
        Command::new("getconf")
            .arg("CLK_TCK")
            .output()
            .ok()
            .and_then(|o| String::from_utf8_lossy(&o.stdout).trim().parse().ok())
            .unwrap_or(100)
    })
}

#[derive(Clone, Copy, Debug, PartialEq)]
enum Ocu {
    /// `mocu run --headless --frames N`: the operator's OCU, display included.
    Run,
    /// `mocu serve`, ended by SIGTERM after the same time: the headless adapter.
    Serve,
}

struct Ports {
    mavlink: u16,
    video: u16,
}

/// One OCU run of `secs` seconds, recording to `record` if given: its CPU seconds and its
/// wall seconds (a run of N frames lasts longer than N display periods when it cannot keep
/// up).
fn ocu(which: Ocu, secs: u32, ports: &Ports, record: Option<&Path>, dir: &Path) -> (f64, f64) {
    let start = Instant::now();
    let profile = Path::new(env!("CARGO_MANIFEST_DIR")).join("benches/record_trial/project.toml");
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_mocu"));
    match which {
        Ocu::Run => {
            cmd.arg("run").arg(&profile).args(["--headless", "--size", "1280x720", "--no-watch"]);
            cmd.arg("--frames").arg((secs * FPS).to_string());
            // Kept, to look at: the display the figure is of.
            let shot = Path::new(env!("CARGO_TARGET_TMPDIR")).join("record_trial-last-frame.png");
            cmd.arg("--screenshot").arg(shot);
        }
        Ocu::Serve => {
            // Its Zenoh endpoint on a free port (not the default 7447 another run may hold).
            let tcp = std::net::TcpListener::bind("127.0.0.1:0").unwrap().local_addr().unwrap();
            cmd.arg("serve").arg(&profile).arg("--listen").arg(format!("tcp/{tcp}"));
        }
    }
    cmd.arg("--mavlink").arg(format!("127.0.0.1:{}", ports.mavlink));
    cmd.arg("--video").arg(format!("127.0.0.1:{}", ports.video));
    if let Some(r) = record {
        cmd.arg("--record").arg(r);
    }
    let mut child = cmd
        .current_dir(dir)
        .stdin(Stdio::null())
        .stdout(Stdio::null())
        .stderr(std::fs::File::create(dir.join("ocu-stderr.txt")).unwrap())
        .spawn()
        .expect("the mocu binary starts");
    if which == Ocu::Serve {
        std::thread::sleep(Duration::from_secs(secs.into()));
        let state = proc_stat(&child).map(|(state, _)| state);
        assert!(state.is_some_and(|s| s != 'Z'), "mocu serve ended before it was stopped");
        let _ = Command::new("kill").args(["-TERM", &child.id().to_string()]).status();
    }
    let (cpu, ok) = cpu_at_exit(&mut child);
    let said = std::fs::read_to_string(dir.join("ocu-stderr.txt")).unwrap_or_default();
    assert!(ok, "the OCU failed ({which:?}, recording: {}):\n{said}", record.is_some());
    (cpu, start.elapsed().as_secs_f64())
}

/// What a recording holds, a second of its span: changed values, video units, bytes.
fn read_back(path: &Path) -> String {
    let bytes = std::fs::metadata(path).map(|m| m.len()).unwrap_or(0);
    let mut r = mocu_replay::Recording::open(path).expect("the recording opens");
    let (first, last) = r.span();
    let secs = (last.saturating_sub(first) as f64 / 1e9).max(1e-3);
    let values: usize = r
        .messages(0, u64::MAX, &["/world/values"])
        .unwrap()
        .iter()
        .filter_map(|m| mocu_replay::values(&m.data))
        .map(|v| v.len())
        .sum();
    let video: Vec<String> = r.topics_starting("/video/").iter().map(|t| t.to_string()).collect();
    let topics: Vec<&str> = video.iter().map(String::as_str).collect();
    let units = r.messages(0, u64::MAX, &topics).unwrap().len();
    assert!(values > 0, "{}: no telemetry recorded", path.display());
    assert!(units > 0, "{}: no video recorded", path.display());
    format!(
        "{secs:.1} s: {:.0} changed values/s, {:.1} video units/s, {:.1} MB per minute",
        values as f64 / secs,
        units as f64 / secs,
        bytes as f64 / secs * 60.0 / 1e6
    )
}

fn free_port() -> u16 {
    UdpSocket::bind("127.0.0.1:0").unwrap().local_addr().unwrap().port()
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    if args.iter().any(|a| a == "--list") {
        return;
    }
    // `cargo bench` passes --bench; `cargo test --benches` does not (a quick run).
    let full = args.iter().any(|a| a == "--bench");
    let (secs, rounds) = if full { (10, 3) } else { (2, 1) };
    let only: Option<Ocu> = args.iter().find_map(|a| match a.as_str() {
        "run" => Some(Ocu::Run),
        "serve" => Some(Ocu::Serve),
        _ => None,
    });
    // `with` or `without`: only those runs (for a profiler: `perf record -- BENCH --bench
    // run with`).
    let only_recording: Option<bool> = args.iter().find_map(|a| match a.as_str() {
        "with" => Some(true),
        "without" => Some(false),
        _ => None,
    });
    let dir = tempfile::tempdir().unwrap();
    let ports = Ports { mavlink: free_port(), video: free_port() };
    // Streams until the bench ends (it is stopped when dropped), however slow the runs.
    let _camera = Ffmpeg::stream_source(
        "testsrc2=size=640x480:rate=30",
        Kind::RtpH264,
        ports.video,
        3600,
        &[],
        "",
    );
    let stop = Arc::new(AtomicBool::new(false));
    let sender =
        send_telemetry(format!("127.0.0.1:{}", ports.mavlink).parse().unwrap(), stop.clone());
    if !full {
        eprintln!(
            "\n(test mode: one short round, only to check that it runs; the figures: `cargo bench --bench record_trial`)"
        );
    }
    eprintln!(
        "\nrecording overhead of the OCU: {VEHICLES} MAVLink vehicles x 19 properties at {RATE_HZ} Hz + one 640x480 H.264 camera at 30 fps, {secs} s runs, {rounds} round(s):"
    );
    for which in [Ocu::Run, Ocu::Serve] {
        if only.is_some_and(|o| o != which) {
            continue;
        }
        let name = if which == Ocu::Run { "mocu run" } else { "mocu serve" };
        let (mut base, mut rec) = ((0.0, 0.0), (0.0, 0.0));
        let add = |sum: &mut (f64, f64), (cpu, wall): (f64, f64)| {
            sum.0 += cpu;
            sum.1 += wall;
        };
        let mut recorded = String::new();
        let mut rounds_ratio: Vec<String> = Vec::new();
        for round in 0..rounds {
            let file: PathBuf = dir.path().join(format!("trial{round}.mcap"));
            // Alternated, and in turn first: a drift of the machine's load weighs on both.
            let mut this = [(0.0, 0.0); 2];
            for recording in [round % 2 == 1, round % 2 == 0] {
                if only_recording.is_some_and(|r| r != recording) {
                    continue;
                }
                let run = ocu(which, secs, &ports, recording.then_some(&*file), dir.path());
                add(if recording { &mut rec } else { &mut base }, run);
                this[usize::from(recording)] = run;
            }
            let [(b_cpu, b_wall), (r_cpu, r_wall)] = this;
            if b_cpu > 0.0 && r_cpu > 0.0 {
                rounds_ratio.push(format!("{:.3}", (r_cpu / r_wall) / (b_cpu / b_wall)));
            }
            if only_recording == Some(false) {
                continue;
            }
            recorded = read_back(&file);
            if std::env::var_os("MOCU_KEEP_TRIAL").is_some() {
                let kept = Path::new(env!("CARGO_TARGET_TMPDIR")).join("record_trial.mcap");
                let _ = std::fs::copy(&file, kept);
            }
            let _ = std::fs::remove_file(&file);
        }
        // CPU per second of the run's wall time.
        let per_s = |(cpu, wall): (f64, f64)| cpu / wall * 1e3;
        eprintln!(
            "  {name:10}  without {:7.1} ms CPU/s ({:.1} s)   with --record {:7.1} ms CPU/s ({:.1} s)   ratio {:.3}x (target <= 1.1x)",
            per_s(base),
            base.1 / f64::from(rounds),
            per_s(rec),
            rec.1 / f64::from(rounds),
            per_s(rec) / per_s(base)
        );
        eprintln!("  {name:10}  each round: {}x", rounds_ratio.join("x, "));
        eprintln!("  {name:10}  recorded: {recorded}");
    }
    stop.store(true, Ordering::Relaxed);
    let _ = sender.join();
}
