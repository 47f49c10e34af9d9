//! Real streams over a degraded link: ffmpeg sends RTP/H.264 and RTP/JPEG through a relay
//! that loses, reorders and truncates packets (seeded, so each run makes the same
//! decisions); the receiver's counters must add up and enough frames must be shown.
//! Nothing here reads the wall clock: frames are counted, and waits are on the camera's
//! published counters (each bounded, so that a hang is a failure).

mod peer;

use mocu_dataserver::Topic;
use mocu_host::Module;
use peer::receiver::{Running, receiver};
use peer::relay::{Impairment, Relay, RelayCounts};
use peer::{Ffmpeg, Kind};
use std::sync::mpsc;
use std::time::Duration;

/// The camera's counters.
#[derive(Clone, Debug, Default, PartialEq)]
struct Counters {
    sent: i64,
    units: i64,
    frames: i64,
    dropped: i64,
    dropped_network: i64,
    dropped_queue: i64,
    refused: i64,
    no_picture: i64,
    decode_errors: i64,
    lost_packets: i64,
    reordered: i64,
    late_packets: i64,
    restarts: i64,
    ignored: i64,
    recoveries: i64,
    concealed: i64,
    damaged: i64,
}

const NAMES: [&str; 17] = [
    "sent",
    "units",
    "frames",
    "dropped",
    "dropped_network",
    "dropped_queue",
    "refused",
    "no_picture",
    "decode_errors",
    "lost_packets",
    "reordered",
    "late_packets",
    "restarts",
    "ignored",
    "recoveries",
    "concealed",
    "damaged",
];

fn counters(r: &Running) -> Counters {
    let g = |k: &str| r.ds.get(r.camera, k).ok().and_then(|v| v.as_i64()).unwrap_or(0);
    Counters {
        sent: g("sent"),
        units: g("units"),
        frames: g("frames"),
        dropped: g("dropped"),
        dropped_network: g("dropped_network"),
        dropped_queue: g("dropped_queue"),
        refused: g("refused"),
        no_picture: g("no_picture"),
        decode_errors: g("decode_errors"),
        lost_packets: g("lost_packets"),
        reordered: g("reordered"),
        late_packets: g("late_packets"),
        restarts: g("restarts"),
        ignored: g("ignored"),
        recoveries: g("recoveries"),
        concealed: g("concealed"),
        damaged: g("damaged"),
    }
}

/// Every unit the receiver handed on was decoded, refused or failed, and the decoder's
/// `dropped` includes the network's latest count.
fn settled(c: &Counters) -> bool {
    let decoder = c.frames + c.dropped_queue + c.refused + c.no_picture + c.decode_errors;
    decoder == c.units
        && c.units + c.dropped_network == c.sent
        && c.dropped == c.dropped_network + c.dropped_queue + c.refused + c.no_picture
}

/// Waits until the counters settle with `want(c)` true; each wait for a change is bounded.
fn wait_for(r: &Running, want: impl Fn(&Counters) -> bool) -> Counters {
    let (tx, rx) = mpsc::channel();
    let sub =
        r.ds.subscribe(Topic::property_names(r.camera, &NAMES), move |_| {
            let _ = tx.send(());
        })
        .unwrap();
    let mut c = counters(r);
    while !(settled(&c) && want(&c)) && rx.recv_timeout(Duration::from_secs(10)).is_ok() {
        while rx.try_recv().is_ok() {}
        c = counters(r);
    }
    r.ds.unsubscribe(sub);
    counters(r)
}

/// Streams 4 s of testsrc (640×480, 30 fps) through a relay with `imp`; returns what the
/// relay counted and the camera's settled counters.
fn through_relay(kind: Kind, imp: Impairment, label: &str) -> (RelayCounts, Counters) {
    through_relay_from("testsrc=size=640x480:rate=30", kind, imp, label)
}

/// testsrc2 at 640×480: everything moves, about 8 RTP packets a frame (2.5 Mbit/s), so a
/// lost packet costs a frame 8 times as often as with testsrc.
const MOVING: &str = "testsrc2=size=640x480:rate=30";

fn through_relay_from(
    src: &str,
    kind: Kind,
    imp: Impairment,
    label: &str,
) -> (RelayCounts, Counters) {
    // One stream at a time: a decoder sharing the machine with several others would fall
    // behind and drop from its queue, which is not what these tests measure.
    let _one = ONE_AT_A_TIME.lock().unwrap_or_else(|e| e.into_inner());
    let imp = Impairment { clean_first_frame: true, ..imp };
    let mut r = receiver();
    let relay = Relay::start(r.port, imp);
    Ffmpeg::stream_source(src, kind, relay.port, 4, &[], "").wait();
    let link = relay.finish();
    let c = wait_for(&r, |c| c.sent + c.late_packets + c.ignored >= link.frames_reached as i64);
    r.module.stop();
    eprintln!(
        "FIGURE {label}: sent {} reached {} shown {} ({:.0}%) | {c:?} | {link:?}",
        link.frames_sent,
        link.frames_reached,
        c.frames,
        100.0 * c.frames as f64 / link.frames_sent.max(1) as f64
    );
    assert!(settled(&c), "{label}: the counters add up: {c:?}");
    assert!(link.frames_sent >= 60, "{label}: ffmpeg sent {} frames", link.frames_sent);
    (link, c)
}

static ONE_AT_A_TIME: std::sync::Mutex<()> = std::sync::Mutex::new(());

fn lossy(loss: f64, seed: u64) -> Impairment {
    Impairment { loss, seed, ..Impairment::default() }
}

/// The share of the frames sent that were shown.
fn shown(link: &RelayCounts, c: &Counters) -> f64 {
    c.frames as f64 / link.frames_sent as f64
}

#[test]
fn h264_over_a_clean_link_shows_every_frame() {
    let (link, c) = through_relay_from(MOVING, Kind::RtpH264, lossy(0.0, 1), "h264 0%");
    assert_eq!(c.sent, link.frames_sent as i64);
    assert_eq!(c.frames + c.dropped_queue, c.sent, "{c:?}");
    assert_eq!((c.dropped_network, c.decode_errors, c.lost_packets), (0, 0, 0));
}

#[test]
fn h264_at_1_percent_loss_shows_at_least_85_percent_of_the_frames() {
    let (link, c) = through_relay_from(MOVING, Kind::RtpH264, lossy(0.01, 11), "h264 1%");
    assert!(shown(&link, &c) >= 0.85, "{c:?}");
}

#[test]
fn h264_at_2_percent_loss_shows_at_least_80_percent_of_the_frames() {
    let (link, c) = through_relay_from(MOVING, Kind::RtpH264, lossy(0.02, 22), "h264 2%");
    assert!(link.lost > 0 && c.lost_packets > 0, "{c:?}");
    assert!(shown(&link, &c) >= 0.8, "{c:?}");
}

#[test]
fn h264_at_5_percent_loss_keeps_showing_at_least_half_the_frames() {
    let (link, c) = through_relay_from(MOVING, Kind::RtpH264, lossy(0.05, 55), "h264 5%");
    assert!(link.lost > 0 && c.lost_packets > 0, "{c:?}");
    assert!(shown(&link, &c) >= 0.5, "{c:?}");
}

#[test]
fn h264_at_720p_and_2_percent_loss_shows_at_least_80_percent_of_the_frames() {
    // 22 packets a frame (two slices): a lost packet damages a frame 2.7 times as often as
    // at 640×480; the damaged frames are concealed by openh264, not dropped.
    let src = "testsrc2=size=1280x720:rate=30";
    let (link, c) = through_relay_from(src, Kind::RtpH264, lossy(0.02, 72), "h264 720p 2%");
    assert!(link.lost > 0 && c.damaged > 0, "{c:?}");
    assert!(c.concealed > 0 && c.concealed <= c.frames, "{c:?}");
    assert!(shown(&link, &c) >= 0.8, "{c:?}");
}

#[test]
fn h264_with_reordered_packets_loses_no_frame() {
    let imp = Impairment { reorder: 0.05, seed: 7, ..Impairment::default() };
    let (link, c) = through_relay_from(MOVING, Kind::RtpH264, imp, "h264 reorder 5%");
    assert!(link.reordered > 0 && c.reordered > 0, "{c:?}");
    assert_eq!((c.dropped_network, c.lost_packets, c.late_packets), (0, 0, 0), "{c:?}");
    assert_eq!(c.frames + c.dropped_queue, link.frames_sent as i64, "{c:?}");
}

#[test]
fn h264_with_truncated_packets_keeps_showing_frames() {
    let imp = Impairment { truncate: 0.05, seed: 5, ..Impairment::default() };
    let (link, c) = through_relay_from(MOVING, Kind::RtpH264, imp, "h264 truncate 5%");
    assert!(link.truncated > 0);
    assert!(c.damaged > 0, "truncated fragments noticed (their NAL units left out): {c:?}");
    assert!(c.concealed > 0, "{c:?}");
    assert!(shown(&link, &c) >= 0.5, "damaged frames are concealed: {c:?}");
}

#[test]
fn rtp_jpeg_at_2_percent_loss_drops_the_broken_frames_only() {
    let (link, c) = through_relay(Kind::RtpJpeg, lossy(0.02, 23), "rtp/jpeg 2%");
    assert!(c.dropped_network > 0, "{c:?}");
    assert_eq!(c.frames + c.dropped_queue + c.dropped_network, link.frames_reached as i64);
}

#[test]
fn rtp_jpeg_with_truncated_packets_shows_no_garbage() {
    let imp = Impairment { truncate: 0.05, seed: 9, ..Impairment::default() };
    let (_, c) = through_relay(Kind::RtpJpeg, imp, "rtp/jpeg truncate 5%");
    assert!(c.dropped_network + c.decode_errors > 0, "{c:?}");
    assert!(c.frames > 0, "{c:?}");
}

#[test]
fn a_restart_of_the_same_stream_is_counted_and_its_frames_shown() {
    let _one = ONE_AT_A_TIME.lock().unwrap_or_else(|e| e.into_inner());
    let mut r = receiver();
    // Both runs from the same address and SSRC; the sequence starts far apart.
    let from = std::net::UdpSocket::bind("127.0.0.1:0").unwrap().local_addr().unwrap().port();
    let query = format!("localport={from}");
    let run = |seq: &str| {
        let extra = ["-ssrc", "4242", "-seq", seq];
        Ffmpeg::stream_with(Kind::RtpH264, 320, 240, r.port, 2, &extra, &query).wait()
    };
    run("100");
    let first = wait_for(&r, |c| c.frames >= 30);
    run("40000");
    let c = wait_for(&r, |c| c.restarts >= 1 && c.frames >= first.frames + 30);
    r.module.stop();
    assert_eq!(c.restarts, 1, "{c:?}");
    assert!(c.frames >= first.frames + 30, "the second run's frames: {c:?}");
}
