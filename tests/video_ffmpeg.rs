//! Video end to end, against ffmpeg (Debian package `ffmpeg`) streaming its testsrc pattern
//! to loopback: one stream in two windows of a headless display, a stalled stream marked
//! STALE then NO VIDEO, and `mocu run` showing a live stream in the paper's USV layout.

#[path = "../runtime/video/tests/peer/mod.rs"]
mod peer;

use mocu_dataserver::{DataServer, Guid, Value};
use mocu_display::{BackendChoice, Display, DisplayOptions, ImageFit, Rect, Size, fit_rect};
use mocu_host::{Module, ModuleContext};
use mocu_video::window::Status;
use mocu_video::{ReceiverConfig, VideoReceiver, VideoWindows, WindowsConfig};
use peer::{BARS, Ffmpeg, Kind, check_bars_at};
use std::process::Command;
use std::time::{Duration, Instant};

fn receiver(ds: &DataServer) -> (VideoReceiver, Guid, u16) {
    let ctx = ModuleContext::detached("video", ds.clone());
    let cfg = ReceiverConfig {
        address: "127.0.0.1:0".parse().unwrap(),
        camera: Some("test".into()),
        ..ReceiverConfig::default()
    };
    let mut m = VideoReceiver::new(cfg);
    m.start(&ctx).expect("receiver starts");
    let cam = ds.resolve(&["cameras", "test"]).unwrap();
    let port = ds.get(cam, "port").unwrap().as_i64().unwrap() as u16;
    (m, cam, port)
}

fn window(ds: &DataServer, display: Guid, name: &str, r: Rect) -> Guid {
    let w = mocu_display::publish_window(ds, display, name, "video", 0, r).unwrap();
    ds.set(w, "source", Value::str("root.cameras.test")).unwrap();
    w
}

/// The RGB of a display frame (premultiplied, opaque here) at integer coordinates.
fn px(frame: &[u8], width: u32, x: f32, y: f32) -> [u8; 3] {
    let i = ((y as usize) * width as usize + x as usize) * 4;
    [frame[i], frame[i + 1], frame[i + 2]]
}

#[test]
fn one_ffmpeg_stream_shows_in_two_windows() {
    let ds = DataServer::default();
    let (mut rx, cam, port) = receiver(&ds);
    let (sw, sh) = (900u32, 600u32);
    let display = mocu_display::ensure_display_object(&ds, sw, sh).unwrap();
    // A 4:3 window and a tall one (letterboxed, as asked: the picture keeps its aspect ratio).
    let ra = Rect::new(0.0, 0.0, 480.0, 360.0);
    let rb = Rect::new(560.0, 60.0, 300.0, 500.0);
    let a = window(&ds, display, "a", ra);
    let b = window(&ds, display, "b", rb);
    ds.set(b, "fit", Value::str("contain")).unwrap();
    let windows = VideoWindows::start(&ds).unwrap();
    let mut d = Display::new(&ds, DisplayOptions::new(sw, sh).backend(BackendChoice::Cpu)).unwrap();
    let _ff = Ffmpeg::stream(Kind::RtpH264, 640, 480, port, 10);
    let end = Instant::now() + Duration::from_secs(15);
    let live = |w| windows.shown(w).is_some_and(|s| s.status == Status::Live && s.frame > Some(5));
    while !(live(a) && live(b)) && Instant::now() < end {
        d.wait_for_change(Duration::from_millis(50));
        d.frame();
    }
    assert!(live(a) && live(b), "both windows live: {:?} {:?}", windows.shown(a), windows.shown(b));
    assert_eq!(windows.camera_of(a), Some(cam));
    assert_eq!(windows.camera_of(b), Some(cam));
    assert_eq!(ds.receivers(cam).unwrap().len(), 1, "one join serves both windows");
    let frame = d.read_frame();
    let data = frame.data().to_vec();
    if let Some(dir) = std::env::var_os("MOCU_VIDEO_DUMP") {
        let _ = frame.save_png(std::path::Path::new(&dir).join("two-windows.png"));
    }
    for (name, r) in [("a", ra), ("b", rb)] {
        let c = fit_rect(Size::new(640.0, 480.0), r, ImageFit::Contain);
        // The bottom-left corner carries the window's title plate (camera, fps, latency):
        // every bar but the one under it.
        let above_the_title = &BARS[..BARS.len() - 1];
        let bad =
            check_bars_at(above_the_title, |fx, fy| px(&data, sw, c.x + fx * c.w, c.y + fy * c.h));
        assert!(bad.is_empty(), "window {name}: {}", bad.join("\n"));
    }
    // Window b is letterboxed: black above and below the picture, inside the window.
    let c = fit_rect(Size::new(640.0, 480.0), rb, ImageFit::Contain);
    assert!(c.y > rb.y + 10.0);
    assert_eq!(px(&data, sw, rb.x + rb.w / 2.0, rb.y + 4.0), [0, 0, 0]);
    assert_eq!(px(&data, sw, rb.x + rb.w / 2.0, rb.y + rb.h - 4.0), [0, 0, 0]);
    // Statistics for HUD overlays.
    let fps = ds.get(cam, "fps").unwrap().as_f64().unwrap();
    assert!(fps > 0.0, "fps {fps}");
    // The shown latency is published with the statistics after frames were shown: give it
    // a few frames (bounded) rather than racing the first ones.
    let end = Instant::now() + Duration::from_secs(10);
    while !ds.get(cam, "shown_latency_ms").is_ok_and(|v| v.as_f64().is_some())
        && Instant::now() < end
    {
        d.wait_for_change(Duration::from_millis(50));
        d.frame();
    }
    assert!(ds.get(cam, "shown_latency_ms").is_ok_and(|v| v.as_f64().is_some()));
    drop(windows);
    rx.stop();
}

#[test]
fn a_stalled_stream_is_marked_stale_then_no_video() {
    let ds = DataServer::default();
    let (mut rx, _cam, port) = receiver(&ds);
    let display = mocu_display::ensure_display_object(&ds, 320, 240).unwrap();
    let w = window(&ds, display, "v", Rect::new(0.0, 0.0, 320.0, 240.0));
    let cfg = WindowsConfig {
        stale_after: Duration::from_millis(400),
        no_video_after: Duration::from_millis(1200),
        tick: Duration::from_millis(50),
        ..WindowsConfig::default()
    };
    let windows = VideoWindows::start_with(&ds, cfg).unwrap();
    let mut d =
        Display::new(&ds, DisplayOptions::new(320, 240).backend(BackendChoice::Cpu)).unwrap();
    let status = |d: &mut Display| {
        d.wait_for_change(Duration::from_millis(30));
        d.frame();
        windows.shown(w).map(|s| s.status)
    };
    let end = Instant::now() + Duration::from_secs(5);
    while status(&mut d).is_none() && Instant::now() < end {}
    assert_eq!(status(&mut d), Some(Status::NoVideo), "no stream yet");
    let ff = Ffmpeg::stream(Kind::RtpJpeg, 320, 240, port, 10);
    let end = Instant::now() + Duration::from_secs(15);
    while status(&mut d) != Some(Status::Live) && Instant::now() < end {}
    assert_eq!(status(&mut d), Some(Status::Live));
    drop(ff);
    let mut seen = vec![Status::Live];
    let end = Instant::now() + Duration::from_secs(5);
    while Instant::now() < end && seen.last() != Some(&Status::NoVideo) {
        if let Some(s) = status(&mut d)
            && seen.last() != Some(&s)
        {
            seen.push(s);
            if let Some(dir) = std::env::var_os("MOCU_VIDEO_DUMP") {
                let _ =
                    d.read_frame().save_png(std::path::Path::new(&dir).join(format!("{s:?}.png")));
            }
        }
    }
    assert_eq!(seen, vec![Status::Live, Status::Stale, Status::NoVideo]);
    drop(windows);
    rx.stop();
}

#[test]
fn mocu_run_shows_a_live_ffmpeg_stream_in_the_usv_layout() {
    peer::require_ffmpeg();
    let port = std::net::UdpSocket::bind("127.0.0.1:0").unwrap().local_addr().unwrap().port();
    let dir = std::env::temp_dir().join(format!("mocu-video-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let shot = dir.join("usv.png");
    let _ff = Ffmpeg::stream(Kind::RtpH264, 640, 480, port, 20);
    let out = Command::new("timeout")
        .args(["-k", "5", "60", env!("CARGO_BIN_EXE_mocu"), "run", "layouts/usv.mocu"])
        .args(["--headless", "--frames", "150", "--size", "1280x720", "--mavlink", "off"])
        .arg("--video")
        .arg(format!("127.0.0.1:{port}"))
        .arg("--screenshot")
        .arg(&shot)
        .args(["--dump", "root.cameras"])
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "mocu run failed: {stderr}");
    let dump = String::from_utf8_lossy(&out.stdout);
    let name = format!("udp{port}");
    assert!(dump.contains(&name), "root.cameras has {name}: {dump}");
    // The screenshot, as RGB through ffmpeg (no PNG decoder needed here).
    let raw = Command::new("ffmpeg")
        .args(["-nostdin", "-loglevel", "error", "-i"])
        .arg(&shot)
        .args(["-f", "rawvideo", "-pix_fmt", "rgba", "pipe:1"])
        .output()
        .unwrap()
        .stdout;
    assert_eq!(raw.len(), 1280 * 720 * 4, "a 1280x720 screenshot");
    // The video window is the whole screen: a 4:3 picture 1280 px wide filling it, its top
    // and bottom cropped. The
    // points checked lie clear of the HUD (status header, heading tape, gauges, buttons)
    // and the map: the bars below the tape, clear of the "2" of the timer.
    let c = fit_rect(Size::new(640.0, 480.0), Rect::new(0.0, 0.0, 1280.0, 720.0), ImageFit::Cover);
    let clear_of_the_hud: &[((f32, f32), [u8; 3], &str)] = &[
        ((200.0 / 640.0, 200.0 / 480.0), [255, 0, 255], "magenta"),
        ((280.0 / 640.0, 200.0 / 480.0), [0, 0, 255], "blue"),
        ((360.0 / 640.0, 200.0 / 480.0), [255, 255, 0], "yellow"),
        ((440.0 / 640.0, 200.0 / 480.0), [0, 255, 0], "green"),
        ((520.0 / 640.0, 160.0 / 480.0), [255, 0, 0], "red"),
    ];
    let bad =
        check_bars_at(clear_of_the_hud, |fx, fy| px(&raw, 1280, c.x + fx * c.w, c.y + fy * c.h));
    assert!(bad.is_empty(), "the stream is not on screen: {}\n{stderr}", bad.join("\n"));
    let _ = std::fs::remove_dir_all(&dir);
}
