//! `mocu run --record TRIAL.mcap` end to end, read back by an independent reader: the
//! Python `mcap` package (tests/peers/read_recording.py, pinned in .ci/run). A finished
//! recording has every channel of docs/recording.md with times that never go back on any
//! of them, the telemetry and the operator's calls once each; a recording killed with
//! SIGKILL opens up to its last complete chunk, with the video as it was received.

mod cli_support;
#[path = "../runtime/video/tests/peer/mod.rs"]
mod peer;

use cli_support::{count, read_recording as read};
use notify::Watcher;
use serde_json::Value as Json;
use std::process::{Command, Stdio};
use std::time::Duration;

const THROTTLE: &str = "root.vehicles.usv1.nav.goal_throttle";

#[test]
fn a_recorded_run_has_every_channel_in_order_and_each_call_and_its_outcome_once() {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("trial.mcap");
    let log = dir.path().join("trial.jsonl");
    let out = Command::new(env!("CARGO_BIN_EXE_mocu"))
        .args(["run", "tests/input/drive.mocu", "--headless", "--frames", "90"])
        .args(["--size", "640x400", "--mavlink", "off", "--video", "off", "--no-watch"])
        .args(["--input-script", "tests/input/drive.script"])
        .arg("--record")
        .arg(&file)
        .arg("--log")
        .arg(&log)
        .env_remove("DISPLAY")
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stderr}");

    let r = read(&file, &[THROTTLE]);
    assert_eq!((r["summary"].as_bool(), r["complete"].as_bool()), (Some(true), Some(true)), "{r}");
    assert_eq!(r["metadata"]["mocu"]["layout"], "tests/input/drive.mocu");
    assert_eq!(r["attachments"], serde_json::json!(["bundle.mocub"]));
    for (topic, schema) in [
        ("/world/object", "mocu.ObjectChange"),
        ("/world/property", "mocu.PropertyChange"),
        ("/world/snapshot", "mocu.WorldSnapshot"),
        ("/calls", "mocu.Call"),
        ("/events", "mocu.Event"),
        ("/layout", "mocu.LayoutEvent"),
        ("/location/root.vehicles.usv1.nav", "foxglove.LocationFix"),
    ] {
        let c = &r["channels"][topic];
        assert_eq!(c["schema"], schema, "{topic}: {r}");
        assert_eq!(
            (c["schema_encoding"].as_str(), c["encoding"].as_str()),
            (Some("jsonschema"), Some("json"))
        );
        assert!(c["count"].as_u64() > Some(0), "{topic} is empty");
    }
    let values = &r["channels"]["/world/values"];
    assert_eq!(values["schema"], "mocu_msgs/msg/PropertyValues", "{r}");
    assert_eq!(
        (values["schema_encoding"].as_str(), values["encoding"].as_str()),
        (Some("ros2msg"), Some("cdr"))
    );
    assert!(r["values"].as_u64() > Some(0), "no batch entries: {r}");
    for (topic, c) in r["channels"].as_object().unwrap() {
        assert_eq!(c["monotonic"], true, "log_time went back on {topic}");
        assert_eq!(c["decoded"], true, "{topic} has a message that does not decode");
    }
    // The stick's last position, as `tests/input_run.rs` works it out: 0.9 through deadzone
    // 0.1 and expo 0.3, ×100; recorded as a float, at increasing times.
    let x: f64 = 8.0 / 9.0;
    let want = 100.0 * (0.7 * x + 0.3 * x.powi(3));
    let throttle = r["properties"][THROTTLE].as_array().unwrap();
    let last = throttle.last().expect("the throttle was recorded");
    assert_eq!(last[1], "float");
    assert!((last[2].as_f64().unwrap() - want).abs() < 1e-9, "{throttle:?}");
    assert!(throttle.windows(2).all(|w| w[0][0].as_u64() <= w[1][0].as_u64()));
    // The operator's refused command: one call, one outcome.
    let calls: Vec<&Json> = r["calls"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|c| c[0] == "root.vehicles.usv1.start_engine")
        .collect();
    assert_eq!(
        calls,
        [
            &serde_json::json!(["root.vehicles.usv1.start_engine", "call", null]),
            &serde_json::json!(["root.vehicles.usv1.start_engine", "outcome", "refused"])
        ]
    );
    // `--log` has it once too (the simulator no longer writes a second copy).
    let log = std::fs::read_to_string(&log).unwrap();
    let lines = |event: &str| {
        log.lines()
            .filter(|l| l.contains(&format!(r#""event":"{event}""#)) && l.contains("start_engine"))
            .count()
    };
    assert_eq!((lines("call"), lines("feedback")), (1, 1), "{log}");
}

#[test]
fn a_killed_recording_opens_up_to_its_last_complete_chunk_with_the_video_as_received() {
    peer::require_ffmpeg();
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("trial.mcap");
    let port = std::net::UdpSocket::bind("127.0.0.1:0").unwrap().local_addr().unwrap().port();
    let (tx, changes) = crossbeam_channel::unbounded();
    let mut watcher = notify::recommended_watcher(tx).unwrap();
    watcher.watch(dir.path(), notify::RecursiveMode::NonRecursive).unwrap();
    let mut child = Command::new(env!("CARGO_BIN_EXE_mocu"))
        .args(["run", "tests/input/drive.mocu", "--headless", "--size", "640x400"])
        .args(["--mavlink", "off", "--no-watch"])
        .arg("--video")
        .arg(format!("127.0.0.1:{port}"))
        .arg("--record")
        .arg(&file)
        .env_remove("DISPLAY")
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    let _ff = peer::Ffmpeg::stream(peer::Kind::RtpH264, 640, 480, port, 30);
    // Wait for the file to hold flushed chunks with a few frames: on each change to the
    // file, read what is on disk so far (bounded: a minute without a change fails).
    let mut on_disk = Json::Null;
    loop {
        let frames: u64 = on_disk["frames"]
            .as_object()
            .map_or(0, |f| f.values().map(|v| v["count"].as_u64().unwrap_or(0)).sum());
        if frames >= 3 && count(&on_disk, "/world/property") > 0 {
            break;
        }
        let changed = changes.recv_timeout(Duration::from_secs(60));
        assert!(changed.is_ok(), "the recording stopped growing: {on_disk}");
        while changes.try_recv().is_ok() {}
        on_disk = read(&file, &[]);
    }
    child.kill().unwrap(); // SIGKILL: no footer, no summary, maybe a torn chunk
    child.wait().unwrap();

    let r = read(&file, &[]);
    assert_eq!(r["summary"], false, "a killed recording has no summary: {r}");
    assert!(count(&r, "/world/property") >= count(&on_disk, "/world/property"));
    for (topic, c) in r["channels"].as_object().unwrap() {
        assert_eq!(c["monotonic"], true, "log_time went back on {topic}");
        assert_eq!(c["decoded"], true, "{topic} has a message that does not decode");
    }
    let (topic, video) = r["frames"].as_object().unwrap().iter().next().expect("video recorded");
    assert_eq!(topic, &format!("/video/root.cameras.udp{port}"));
    assert_eq!(r["channels"][topic]["schema"], "foxglove_msgs/msg/CompressedVideo");
    assert_eq!(video["format"], "h264");
    // An access unit as received, in Annex B form: it starts with a start code.
    let head = video["first_bytes_hex"].as_str().unwrap();
    assert!(head == "00000001" || head.starts_with("000001"), "{video}");
    assert!(video["size"].as_u64() > Some(4));

    // Replayed, the units are decoded again: a video window on that camera shows ffmpeg's
    // test pattern (its colour bars), where it would say NO VIDEO without the decoder.
    let layout = dir.path().join("camera.mocu");
    let camera = format!("root.cameras.udp{port}");
    let text = format!(
        "window cam {{\n    type \"video\"\n    layer 0\n    rect 0 0 100% 100%\n    source {camera}\n}}\n"
    );
    std::fs::write(&layout, text).unwrap();
    // Trial time counts from the recording's first message (a killed file may have lost
    // the metadata's `start_ns` with its summary).
    let firsts = r["channels"].as_object().unwrap().values();
    let start = firsts.filter_map(|c| c["first_ns"].as_u64()).min().unwrap();
    let last = r["channels"][topic]["last_ns"].as_u64().unwrap();
    let at = format!("{:.3}s", (last - start) as f64 / 1e9);
    let shot = dir.path().join("replayed.png");
    let o = Command::new(env!("CARGO_BIN_EXE_mocu"))
        .args(["replay", file.to_str().unwrap(), "--at", &at, "--size", "640x480", "--layout"])
        .arg(&layout)
        .arg("--screenshot")
        .arg(&shot)
        .env_remove("DISPLAY")
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let p = tiny_skia::Pixmap::load_png(&shot).unwrap();
    let colourful = (0..p.height())
        .flat_map(|y| (0..p.width()).map(move |x| (x, y)))
        .filter(|&(x, y)| {
            let c = p.pixel(x, y).unwrap().demultiply();
            let (r, g, b) = (c.red(), c.green(), c.blue());
            r.max(g).max(b) - r.min(g).min(b) > 100
        })
        .count();
    let share = colourful as f64 / f64::from(p.width() * p.height());
    assert!(share > 0.3, "the replayed video window shows the test pattern: {share:.2} colourful");
}
