//! The receiver and decoders against a real encoder written by others: ffmpeg streams its
//! testsrc pattern as RTP/H.264, RTP/JPEG and raw MJPEG to a loopback port; frames must
//! come out at the right size with the right picture.

mod peer;

use mocu_dataserver::{Call, MethodSpec, ObjectInfo, Overflow, ParamSpec, Topic, Value};
use mocu_host::Module;
use mocu_video::FrameMsg;
use peer::receiver::{Running, receiver};
use peer::{Ffmpeg, Kind, check_bars};
use std::sync::mpsc;
use std::time::{Duration, Instant};

/// Joins the camera and waits for `n` frames (at most `limit`).
fn frames(r: &Running, n: usize, limit: Duration) -> Vec<FrameMsg> {
    let (tx, rx) = mpsc::channel();
    let sink = r.ds.create_object(r.ds.root(), ObjectInfo::new("sink", "test")).unwrap();
    let spec = ["pixels", "width", "height", "frame", "arrival_us"]
        .iter()
        .fold(MethodSpec::new("frame_timed"), |s, p| s.param(ParamSpec::any(p)));
    r.ds.publish_method(sink, spec, move |c: Call| {
        let _ = tx.send(FrameMsg::from_values(&c.args));
        c.responder.accept(vec![]);
    })
    .unwrap();
    r.ds.join(r.camera, sink, "frame_timed", Overflow::DropOldest, 64).unwrap();
    let end = Instant::now() + limit;
    let mut out = Vec::new();
    while out.len() < n {
        let left = end.saturating_duration_since(Instant::now());
        match rx.recv_timeout(left) {
            Ok(Some(f)) => out.push(f),
            Ok(None) => panic!("a frame message of the wrong shape"),
            Err(_) => break,
        }
    }
    out
}

fn rgb(f: &FrameMsg, fx: f32, fy: f32) -> [u8; 3] {
    let (x, y) = ((fx * f.width as f32) as usize, (fy * f.height as f32) as usize);
    let c = f.channels();
    let i = (y * f.width as usize + x) * c;
    [f.pixels[i], f.pixels[i + 1], f.pixels[i + 2]]
}

/// Writes the frame as a PNG next to the test output when MOCU_VIDEO_DUMP names a folder.
fn dump(f: &FrameMsg, name: &str) {
    let Some(dir) = std::env::var_os("MOCU_VIDEO_DUMP") else { return };
    let raw = std::path::Path::new(&dir).join(format!("{name}.rgba"));
    std::fs::write(&raw, &f.pixels).unwrap();
    let _ = std::process::Command::new("ffmpeg")
        .args(["-loglevel", "error", "-y", "-f", "rawvideo", "-pix_fmt", "rgba", "-s"])
        .arg(format!("{}x{}", f.width, f.height))
        .arg("-i")
        .arg(&raw)
        .arg(std::path::Path::new(&dir).join(format!("{name}.png")))
        .status();
}

fn check_stream(kind: Kind, w: u32, h: u32, name: &str) {
    let mut r = receiver();
    let _ff = Ffmpeg::stream(kind, w, h, r.port, 8);
    let got = frames(&r, 10, Duration::from_secs(15));
    assert!(got.len() >= 10, "{name}: {} frames in 15 s", got.len());
    let last = got.last().unwrap();
    dump(last, name);
    assert_eq!((last.width, last.height), (w, h), "{name}: decoded size");
    assert_eq!(last.channels(), 4, "decoders send RGBA8");
    assert!(last.arrival_us.is_some(), "frames carry their arrival time");
    let bad = check_bars(|fx, fy| rgb(last, fx, fy));
    assert!(bad.is_empty(), "{name}: the test pattern is wrong:\n{}", bad.join("\n"));
    // Frame numbers increase; statistics are published on the camera.
    assert!(got.windows(2).all(|p| p[1].frame > p[0].frame));
    // Statistics reach the camera within a publishing period.
    let prop = |k: &str| r.ds.get(r.camera, k).unwrap();
    let (tx, published) = mpsc::channel();
    let sub =
        r.ds.subscribe(Topic::property_names(r.camera, &["frames"]), move |_| {
            let _ = tx.send(());
        })
        .unwrap();
    // The wait is on the publication; its bound only turns a hang into a failure.
    while prop("frames").as_i64().unwrap() < 10
        && published.recv_timeout(Duration::from_secs(15)).is_ok()
    {}
    r.ds.unsubscribe(sub);
    assert_eq!(prop("width"), Value::Int(w as i64));
    assert_eq!(prop("height"), Value::Int(h as i64));
    assert!(prop("frames").as_i64().unwrap() >= 10, "frames {:?}", prop("frames"));
    assert!(prop("fps").as_f64().unwrap() > 0.0, "fps {:?}", prop("fps"));
    assert!(prop("latency_ms").as_f64().unwrap() >= 0.0);
    assert!(prop("packets").as_i64().unwrap() >= 10);
    let transport = match kind {
        Kind::RtpH264 => "rtp/h264",
        Kind::RtpJpeg => "rtp/jpeg",
        Kind::RawMjpeg => "mjpeg",
    };
    assert_eq!(prop("transport"), Value::str(transport));
    r.module.stop();
}

#[test]
fn rtp_h264_from_ffmpeg_decodes_at_its_size_with_its_picture() {
    check_stream(Kind::RtpH264, 640, 480, "rtp-h264-640x480");
}

#[test]
fn rtp_jpeg_from_ffmpeg_decodes_at_its_size_with_its_picture() {
    check_stream(Kind::RtpJpeg, 640, 480, "rtp-jpeg-640x480");
}

#[test]
fn rtp_jpeg_at_720p_keeps_its_size() {
    check_stream(Kind::RtpJpeg, 1280, 720, "rtp-jpeg-1280x720");
}

#[test]
fn raw_mjpeg_over_udp_from_ffmpeg_decodes() {
    check_stream(Kind::RawMjpeg, 640, 480, "mjpeg-640x480");
}
