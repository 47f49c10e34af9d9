//! Crafted datagrams against a running receiver: a JPEG that claims 16384×16384, an
//! RTP/JPEG frame of 2040×2040 garbage between good frames, datagrams of the largest UDP
//! size, frames over the configured size, and a 24-byte squatter beside a real stream.
//! Each must be refused or ignored and counted; good frames must still be shown. Waits
//! are on the camera's published counters, each bounded.

mod peer;

use mocu_dataserver::{Call, DataServer, Guid, MethodSpec, ObjectInfo, Overflow, ParamSpec, Topic};
use mocu_host::{Module, ModuleContext, ModuleSpec};
use mocu_video::{FrameMsg, ReceiverConfig, VideoReceiver};
use peer::relay::Rng;
use peer::{Ffmpeg, Kind, check_bars};
use std::net::UdpSocket;
use std::process::{Command, Stdio};
use std::sync::mpsc;
use std::time::Duration;

struct Running {
    ds: DataServer,
    module: VideoReceiver,
    camera: Guid,
    port: u16,
    frames: mpsc::Receiver<FrameMsg>,
}

/// A receiver with `settings` (module settings, as in a profile) and a sink of its frames.
fn receiver(settings: &[(&str, i64)]) -> Running {
    let ds = DataServer::default();
    let ctx = ModuleContext::detached("video", ds.clone());
    let mut spec = ModuleSpec::new("video")
        .named("video")
        .with("address", "127.0.0.1:0")
        .with("camera", "test");
    for (k, v) in settings {
        spec = spec.with(k, *v);
    }
    let mut module = VideoReceiver::new(ReceiverConfig::from_spec(&spec).unwrap());
    module.start(&ctx).expect("receiver starts");
    let camera = ds.resolve(&["cameras", "test"]).expect("root.cameras.test");
    let port = ds.get(camera, "port").unwrap().as_i64().unwrap() as u16;
    let (tx, frames) = mpsc::channel();
    let sink = ds.create_object(ds.root(), ObjectInfo::new("sink", "test")).unwrap();
    let spec = ["pixels", "width", "height", "frame", "arrival_us"]
        .iter()
        .fold(MethodSpec::new("frame"), |s, p| s.param(ParamSpec::any(p)));
    ds.publish_method(sink, spec, move |c: Call| {
        if let Some(f) = FrameMsg::from_values(&c.args) {
            let _ = tx.send(f);
        }
        c.responder.accept(vec![]);
    })
    .unwrap();
    ds.join(camera, sink, "frame", Overflow::DropOldest, 64).unwrap();
    Running { ds, module, camera, port, frames }
}

fn prop(r: &Running, k: &str) -> i64 {
    r.ds.get(r.camera, k).ok().and_then(|v| v.as_i64()).unwrap_or(0)
}

/// Waits (each wait for a change bounded) until `want` holds; `on_change` runs on each.
fn wait_until(r: &Running, keys: &[&str], want: impl Fn() -> bool, mut on_change: impl FnMut()) {
    let (tx, rx) = mpsc::channel();
    let sub =
        r.ds.subscribe(Topic::property_names(r.camera, keys), move |_| {
            let _ = tx.send(());
        })
        .unwrap();
    while !want() && rx.recv_timeout(Duration::from_secs(10)).is_ok() {
        on_change();
    }
    r.ds.unsubscribe(sub);
}

fn send(to: u16, datagrams: &[Vec<u8>]) -> UdpSocket {
    let s = UdpSocket::bind("127.0.0.1:0").unwrap();
    for d in datagrams {
        s.send_to(d, ("127.0.0.1", to)).unwrap();
    }
    s
}

/// What ffmpeg sends for `frames` frames of testsrc (320×240) with these output options,
/// caught on a local port.
fn capture(output: &[&str], frames: u32) -> Vec<Vec<u8>> {
    peer::require_ffmpeg();
    let sock = UdpSocket::bind("127.0.0.1:0").unwrap();
    let port = sock.local_addr().unwrap().port();
    let status = Command::new("timeout")
        .args(["-k", "2", "20", "ffmpeg", "-nostdin", "-loglevel", "error", "-f", "lavfi"])
        .args(["-i", "testsrc=size=320x240:rate=30", "-frames:v", &frames.to_string()])
        .args(output)
        .arg(format!("rtp://127.0.0.1:{port}"))
        .stdout(Stdio::null())
        .status()
        .unwrap();
    assert!(status.success(), "ffmpeg failed");
    sock.set_nonblocking(true).unwrap();
    let mut out = Vec::new();
    let mut buf = vec![0u8; 65536];
    while let Ok(n) = sock.recv(&mut buf) {
        out.push(buf[..n].to_vec());
    }
    out
}

const RTP_JPEG: &[&str] = &["-c:v", "mjpeg", "-huffman", "0", "-pix_fmt", "yuvj420p", "-f", "rtp"];

/// A JPEG file from ffmpeg (64×64 testsrc) whose frame header is rewritten to say
/// `w`×`h`, padded to `len` bytes inside a comment segment.
fn jpeg_claiming(w: u16, h: u16, len: usize) -> Vec<u8> {
    let out = Command::new("timeout")
        .args(["-k", "2", "20", "ffmpeg", "-nostdin", "-loglevel", "error", "-f", "lavfi"])
        .args(["-i", "testsrc=size=64x64", "-frames:v", "1", "-f", "mjpeg", "pipe:1"])
        .output()
        .unwrap();
    let mut j = out.stdout;
    let sof = j.windows(2).position(|m| m == [0xff, 0xc0]).expect("a baseline JPEG");
    j[sof + 5..sof + 7].copy_from_slice(&h.to_be_bytes());
    j[sof + 7..sof + 9].copy_from_slice(&w.to_be_bytes());
    let pad = len.saturating_sub(j.len() + 4).min(65533);
    let mut com = vec![0xff, 0xfe];
    com.extend_from_slice(&((pad + 2) as u16).to_be_bytes());
    com.extend(std::iter::repeat_n(b'x', pad));
    j.splice(2..2, com);
    j
}

#[test]
fn a_jpeg_claiming_16384_square_is_refused_before_decoding() {
    peer::require_ffmpeg();
    let mut r = receiver(&[]);
    let bomb = jpeg_claiming(16384, 16384, 9 * 1024);
    assert!(bomb.len() >= 9 * 1024 && bomb.len() < 10 * 1024);
    let _s = send(r.port, std::slice::from_ref(&bomb));
    wait_until(&r, &["refused"], || prop(&r, "refused") >= 1, || {});
    assert_eq!(prop(&r, "refused"), 1);
    assert_eq!((prop(&r, "frames"), prop(&r, "decode_errors")), (0, 0));
    r.module.stop();
}

#[test]
fn frames_over_the_configured_size_are_refused_and_smaller_ones_shown() {
    peer::require_ffmpeg();
    let mut r = receiver(&[("max_width", 100), ("max_height", 100)]);
    let small = jpeg_claiming(64, 64, 0);
    let big = jpeg_claiming(128, 64, 0);
    let _s = send(r.port, &[small.clone(), big, small]);
    wait_until(&r, &["frames", "refused"], || prop(&r, "frames") + prop(&r, "refused") >= 3, || {});
    assert_eq!((prop(&r, "frames"), prop(&r, "refused")), (2, 1));
    assert_eq!(prop(&r, "max_width"), 100, "the limits are published");
    r.module.stop();
}

#[test]
fn rtp_jpeg_garbage_of_2040_square_is_not_shown_and_the_good_frames_are() {
    let mut r = receiver(&[]);
    let good = capture(RTP_JPEG, 2);
    let (seq0, ts0) = (u16::from_be_bytes([good[0][2], good[0][3]]), 1000u32);
    let ssrc = good[0][8..12].to_vec();
    // Good frame 1, garbage claiming 2040×2040 (two fragments), good frame 2: one
    // sequence, one SSRC, three timestamps.
    let mut rng = Rng::new(2040);
    let mut garbage = Vec::new();
    for (i, offset) in [0u32, 1000].into_iter().enumerate() {
        let mut d = vec![0x80, if i == 1 { 0x80 | 26 } else { 26 }, 0, 0, 0, 0, 0, 0];
        d.extend_from_slice(&ssrc);
        let o = offset.to_be_bytes();
        d.extend_from_slice(&[0, o[1], o[2], o[3], 1, 50, 255, 255]);
        d.extend((0..1000).map(|_| rng.next_u64() as u8));
        garbage.push(d);
    }
    let ts_of = |d: &[u8]| u32::from_be_bytes([d[4], d[5], d[6], d[7]]);
    let first_ts = ts_of(&good[0]);
    let (one, two): (Vec<_>, Vec<_>) = good.iter().cloned().partition(|d| ts_of(d) == first_ts);
    let mut all: Vec<(u32, Vec<u8>)> = one.into_iter().map(|d| (ts0, d)).collect();
    all.extend(garbage.into_iter().map(|d| (ts0 + 3000, d)));
    all.extend(two.into_iter().map(|d| (ts0 + 6000, d)));
    let stream: Vec<Vec<u8>> = all
        .into_iter()
        .enumerate()
        .map(|(i, (ts, mut d))| {
            d[2..4].copy_from_slice(&seq0.wrapping_add(i as u16).to_be_bytes());
            d[4..8].copy_from_slice(&ts.to_be_bytes());
            d
        })
        .collect();
    let _s = send(r.port, &stream);
    let done = || prop(&r, "frames") + prop(&r, "decode_errors") + prop(&r, "dropped") >= 3;
    wait_until(&r, &["frames", "decode_errors", "dropped"], done, || {});
    assert_eq!((prop(&r, "frames"), prop(&r, "decode_errors")), (2, 1));
    for f in r.frames.try_iter() {
        assert_eq!((f.width, f.height), (320, 240), "only the good frames are shown");
        let c = f.channels();
        let px = |fx: f32, fy: f32| {
            let i = ((fy * 240.0) as usize * 320 + (fx * 320.0) as usize) * c;
            [f.pixels[i], f.pixels[i + 1], f.pixels[i + 2]]
        };
        assert!(check_bars(px).is_empty());
    }
    r.module.stop();
}

#[test]
fn datagrams_of_the_largest_udp_size_arrive_whole() {
    let mut r = receiver(&[]);
    let big = vec![0x17u8; 65_507]; // the largest IPv4 UDP payload
    let _s = send(r.port, &[big.clone(), big]);
    wait_until(&r, &["bytes"], || prop(&r, "bytes") >= 2 * 65_507, || {});
    assert_eq!(prop(&r, "bytes"), 2 * 65_507, "two datagrams, not truncated");
    assert_eq!(prop(&r, "ignored"), 2, "noise is ignored, not a malformed frame");
    r.module.stop();
}

#[test]
fn an_mjpeg_frame_over_max_unit_kb_is_dropped_as_oversize() {
    let mut r = receiver(&[("max_unit_kb", 64)]);
    // SOI, then APP1 segments of 60 KB each: the frame grows past 64 KiB without an end.
    let mut datagrams = vec![vec![0xff, 0xd8]];
    for _ in 0..3 {
        let mut d = vec![0xff, 0xe1, 0xea, 0x62];
        d.extend(std::iter::repeat_n(0u8, 0xea62 - 2));
        datagrams.push(d);
    }
    let _s = send(r.port, &datagrams);
    wait_until(&r, &["oversize"], || prop(&r, "oversize") >= 1, || {});
    assert_eq!(prop(&r, "oversize"), 1);
    assert_eq!(prop(&r, "dropped_network"), 1);
    r.module.stop();
}

#[test]
fn a_24_byte_squatter_does_not_keep_a_real_stream_out() {
    let mut r = receiver(&[]);
    let squatter = send(r.port, &[vec![0x42; 24]]);
    let mut squats = 1;
    let _ff = Ffmpeg::stream(Kind::RtpH264, 320, 240, r.port, 10);
    // The squatter sends again every time the camera's counters change.
    wait_until(
        &r,
        &["frames", "ignored"],
        || prop(&r, "frames") >= 20,
        || {
            squatter.send_to(&[0x42; 24], ("127.0.0.1", r.port)).unwrap();
            squats += 1;
        },
    );
    assert!(prop(&r, "frames") >= 20, "the real stream is shown");
    let sender = r.ds.get(r.camera, "sender").unwrap();
    let squatter_addr = squatter.local_addr().unwrap().to_string();
    assert_ne!(sender.as_str(), Some(squatter_addr.as_str()));
    wait_until(&r, &["ignored"], || prop(&r, "ignored") >= squats, || {});
    assert_eq!(prop(&r, "ignored"), squats, "every squatter datagram, and only those");
    r.module.stop();
}

#[test]
fn an_h264_stream_over_the_configured_size_is_refused_before_decoding() {
    let mut r = receiver(&[("max_width", 320), ("max_height", 240)]);
    let _ff = Ffmpeg::stream(Kind::RtpH264, 640, 480, r.port, 10);
    wait_until(&r, &["refused"], || prop(&r, "refused") >= 10, || {});
    assert!(prop(&r, "refused") >= 10, "every unit of a 640×480 stream");
    assert_eq!((prop(&r, "frames"), prop(&r, "decode_errors")), (0, 0));
    assert_eq!(r.frames.try_iter().count(), 0);
    r.module.stop();
}
