//! A fuzz test of every decoder, run in CI: seeded mutations (bit flips, random bytes,
//! cuts, growth, splices) of real packets from ffmpeg go through the RTP parser, the
//! H.264 and RTP/JPEG depacketizers, the MJPEG reassembler, the reorder buffer, the stream
//! sniffer, the SPS and JPEG header readers and both decoders. Nothing may panic, and
//! what comes out must respect the limits and the counters must add up. The seed and the
//! number of iterations are fixed: each run tries the same cases.

mod peer;

use mocu_video::jitter::Reorder;
use mocu_video::mjpeg::MjpegReassembler;
use mocu_video::rtp::{H264Depacketizer, RtpPacket};
use mocu_video::rtp_jpeg::JpegDepacketizer;
use mocu_video::{Codec, DecodeError, Decoder, Limits, Stream, StreamConfig, h264, limits};
use peer::relay::Rng;
use std::net::UdpSocket;
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

/// What ffmpeg sends for 12 frames of testsrc (160×120) with these output options.
fn capture(output: &[&str]) -> Vec<Vec<u8>> {
    peer::require_ffmpeg();
    let sock = UdpSocket::bind("127.0.0.1:0").unwrap();
    let port = sock.local_addr().unwrap().port();
    let url = match output.last() {
        Some(&"mjpeg") => format!("udp://127.0.0.1:{port}?pkt_size=700"),
        _ => format!("rtp://127.0.0.1:{port}"),
    };
    let status = Command::new("timeout")
        .args(["-k", "2", "20", "ffmpeg", "-nostdin", "-loglevel", "error", "-f", "lavfi"])
        .args(["-i", "testsrc=size=160x120:rate=30", "-frames:v", "12", "-g", "5"])
        .args(output)
        .arg(url)
        .stdout(Stdio::null())
        .status()
        .unwrap();
    assert!(status.success());
    sock.set_nonblocking(true).unwrap();
    let mut out = Vec::new();
    let mut buf = vec![0u8; 65536];
    while let Ok(n) = sock.recv(&mut buf) {
        out.push(buf[..n].to_vec());
    }
    assert!(out.len() >= 12, "{} datagrams", out.len());
    out
}

fn h264_packets() -> Vec<Vec<u8>> {
    capture(&[
        "-c:v",
        "libx264",
        "-preset",
        "ultrafast",
        "-tune",
        "zerolatency",
        "-pix_fmt",
        "yuv420p",
        "-f",
        "rtp",
    ])
}

fn jpeg_packets() -> Vec<Vec<u8>> {
    capture(&["-c:v", "mjpeg", "-huffman", "0", "-pix_fmt", "yuvj420p", "-f", "rtp"])
}

fn mjpeg_datagrams() -> Vec<Vec<u8>> {
    capture(&["-c:v", "mjpeg", "-pix_fmt", "yuvj420p", "-f", "mjpeg"])
}

/// One to four mutations of `base`.
fn mutate(rng: &mut Rng, base: &[u8], other: &[u8]) -> Vec<u8> {
    let mut d = base.to_vec();
    for _ in 0..1 + rng.below(4) {
        let len = d.len().max(1);
        match rng.below(7) {
            0 => {
                let i = rng.below(len);
                if let Some(b) = d.get_mut(i) {
                    *b ^= 1 << rng.below(8);
                }
            }
            1 => {
                let i = rng.below(len.min(16)); // the headers
                if let Some(b) = d.get_mut(i) {
                    *b = rng.next_u64() as u8;
                }
            }
            2 => d.truncate(rng.below(len)),
            3 => d.extend((0..rng.below(64)).map(|_| rng.next_u64() as u8)),
            4 => {
                let i = rng.below(len);
                let j = rng.below(other.len().max(1));
                d.truncate(i);
                d.extend_from_slice(other.get(j..).unwrap_or_default());
            }
            5 => {
                let i = rng.below(len);
                if i < d.len() {
                    let v = [0x00, 0xff, 0x7f, 0x80][rng.below(4)];
                    let n = rng.below(8).min(d.len() - i);
                    d[i..i + n].fill(v);
                }
            }
            _ => {} // unchanged: valid packets keep the stream going
        }
    }
    d
}

/// A mutation of one of `set`, spliced with another where it splices.
fn mutant(rng: &mut Rng, set: &[Vec<u8>]) -> Vec<u8> {
    let (a, b) = (rng.below(set.len()), rng.below(set.len()));
    mutate(rng, &set[a], &set[b])
}

const ITERATIONS: usize = 20_000;

fn limits() -> Limits {
    Limits { max_width: 1024, max_height: 1024, max_unit_bytes: 64 << 10 }
}

#[test]
fn rtp_and_the_depacketizers_survive_mutated_packets_and_keep_their_counts() {
    let (h, j) = (h264_packets(), jpeg_packets());
    let mut rng = Rng::new(0x5eed_0001);
    let max = limits().max_unit_bytes;
    let mut hd = H264Depacketizer::with_limit(max);
    let mut jd = JpegDepacketizer::with_limit(max);
    let (mut h_out, mut j_out) = (0u64, 0u64);
    for i in 0..ITERATIONS {
        let (set, dep_h) = if i % 2 == 0 { (&h, true) } else { (&j, false) };
        let d = mutant(&mut rng, set);
        let Some(p) = RtpPacket::parse(&d) else { continue };
        assert!(p.payload.len() <= d.len());
        if dep_h {
            hd.push(&p, &mut |u| {
                assert!(u.data.len() <= max);
                h_out += 1;
            });
        } else {
            jd.push(&p, &mut |u| {
                assert!(u.data.len() <= max + 1024, "scan plus the rebuilt headers");
                assert!(u.data.starts_with(&[0xff, 0xd8]));
                j_out += 1;
            });
        }
    }
    for (stats, out) in [(hd.stats, h_out), (jd.stats, j_out)] {
        assert_eq!(stats.units, out + stats.dropped_units, "{stats:?}");
        assert!(out > 0 && stats.dropped_units > 0, "both paths taken: {stats:?}");
    }
}

#[test]
fn the_mjpeg_reassembler_survives_mutated_datagrams() {
    let m = mjpeg_datagrams();
    let mut rng = Rng::new(0x5eed_0002);
    let max = 32 << 10;
    let mut r = MjpegReassembler::with_limit(max);
    let mut out = 0;
    for _ in 0..ITERATIONS {
        let d = mutant(&mut rng, &m);
        r.push(&d, &mut |f| {
            assert!(f.len() <= max + d.len() && f.starts_with(&[0xff, 0xd8]));
            out += 1;
        });
    }
    assert_eq!(r.emitted, out);
    assert!(out > 0 && r.dropped > 0);
}

#[test]
fn the_reorder_buffer_releases_in_order_and_holds_at_most_its_window() {
    let mut rng = Rng::new(0x5eed_0003);
    let t = Instant::now();
    let mut r = Reorder::new(8, Duration::from_millis(100));
    let mut seq = 60_000u16;
    let mut last: Option<u16> = None;
    let mut restarts = 0;
    for i in 0..ITERATIONS {
        let s = match rng.below(20) {
            0 => rng.next_u64() as u16,                      // anything
            1..=3 => seq.wrapping_sub(rng.below(10) as u16), // late or duplicate
            _ => {
                seq = seq.wrapping_add(1 + (rng.below(10) == 0) as u16);
                seq
            }
        };
        let now = t + Duration::from_millis(i as u64);
        let check = |out: Vec<u16>, last: &mut Option<u16>| {
            for o in out {
                if let Some(l) = *last {
                    let step = o.wrapping_sub(l) as i16;
                    assert!(step > 0, "in order: {l} then {o}");
                }
                *last = Some(o);
            }
        };
        let mut out = Vec::new();
        let p =
            r.push(s, now, &s.to_be_bytes(), &mut |d| out.push(u16::from_be_bytes([d[0], d[1]])));
        check(out, &mut last);
        if p == mocu_video::jitter::Pushed::Restart {
            restarts += 1;
            last = None;
            seq = s;
            let mut out = Vec::new();
            r.push(s, now, &s.to_be_bytes(), &mut |d| out.push(u16::from_be_bytes([d[0], d[1]])));
            check(out, &mut last);
        }
        assert!(r.held() < 8);
    }
    assert_eq!(r.stats.restarts, restarts);
    assert!(restarts > 0 && r.stats.late > 0 && r.stats.reordered > 0);
}

#[test]
fn the_stream_sniffer_survives_anything_and_its_counts_add_up() {
    let (h, j, m) = (h264_packets(), jpeg_packets(), mjpeg_datagrams());
    let mut rng = Rng::new(0x5eed_0004);
    let cfg = StreamConfig {
        limits: limits(),
        silence: Duration::from_millis(50),
        ..StreamConfig::default()
    };
    let mut s = Stream::with_config(cfg);
    let t = Instant::now();
    let mut units = 0;
    let senders = ["10.0.0.1:5000", "10.0.0.2:5000", "10.0.0.1:5001"];
    for i in 0..ITERATIONS {
        let set = [&h, &j, &m][(i / 500) % 3];
        let d = mutant(&mut rng, set);
        let from = senders[if rng.below(10) == 0 { rng.below(3) } else { 0 }];
        let now = t + Duration::from_millis(i as u64);
        s.datagram(from.parse().unwrap(), &d, now, &mut |_, u| {
            assert!(u.data.len() <= limits().max_unit_bytes + 1024);
            units += 1;
        });
    }
    let st = s.stats();
    assert_eq!(st.units, units);
    assert_eq!(st.sent, st.units + st.dropped, "{st:?}");
    assert!(st.ignored > 0 && st.dropped > 0 && units > 0, "{st:?}");
}

#[test]
fn the_header_readers_survive_mutations() {
    let h = h264_packets();
    // ffmpeg sends the parameter sets in a STAP-A: 0x78, then (length, NAL) pairs.
    let mut sps = Vec::new();
    for p in h.iter().filter_map(|d| RtpPacket::parse(d)) {
        let mut rest = p.payload.get(1..).unwrap_or_default();
        while p.payload.first().is_some_and(|b| b & 0x1f == 24) && rest.len() >= 2 {
            let n = u16::from_be_bytes([rest[0], rest[1]]) as usize;
            let Some(nal) = rest.get(2..2 + n) else { break };
            if nal.first().is_some_and(|b| b & 0x1f == 7) {
                sps.push(nal.to_vec());
            }
            rest = &rest[2 + n..];
        }
    }
    assert!(!sps.is_empty(), "ffmpeg's STAP-A carries the SPS");
    let jpeg = jpeg_file();
    let mut rng = Rng::new(0x5eed_0005);
    let mut parsed = 0;
    for _ in 0..ITERATIONS {
        let n = mutate(&mut rng, &sps[0], &jpeg);
        if let Some(info) = h264::parse_sps(&n) {
            parsed += 1;
            let again = h264::parse_sps(&h264::sps_allowing_gaps(&n).unwrap()).unwrap();
            assert_eq!((again.width, again.height), (info.width, info.height));
        }
        let _ = h264::allow_frame_num_gaps(&[&[0, 0, 0, 1][..], &n].concat());
        let _ = limits::jpeg_size(&mutate(&mut rng, &jpeg, &n));
    }
    assert!(parsed > 0);
}

/// One JPEG file (160×120) from ffmpeg.
fn jpeg_file() -> Vec<u8> {
    let out = Command::new("timeout")
        .args(["-k", "2", "20", "ffmpeg", "-nostdin", "-loglevel", "error", "-f", "lavfi"])
        .args(["-i", "testsrc=size=160x120", "-frames:v", "1", "-f", "mjpeg", "pipe:1"])
        .output()
        .unwrap();
    out.stdout
}

#[test]
fn the_decoders_survive_mutated_units_within_their_limits() {
    let jpeg = jpeg_file();
    let mut d = H264Depacketizer::new();
    let mut units = Vec::new();
    for p in h264_packets() {
        d.push(&RtpPacket::parse(&p).unwrap(), &mut |u| units.push(u.data));
    }
    assert!(units.len() >= 10);
    let mut rng = Rng::new(0x5eed_0006);
    let l = Limits { max_width: 320, max_height: 240, max_unit_bytes: 1 << 20 };
    let mut dec = Decoder::new();
    let (mut pictures, mut failures) = (0, 0);
    for i in 0..600 {
        let (codec, unit) = if i % 2 == 0 {
            (Codec::Jpeg, mutate(&mut rng, &jpeg, &jpeg))
        } else {
            let other = rng.below(units.len());
            (Codec::H264, mutate(&mut rng, &units[(i / 2) % units.len()], &units[other]))
        };
        match dec.decode_limited(codec, &unit, &l) {
            Ok(Some(f)) => {
                assert!(l.allows(f.width, f.height));
                assert_eq!(f.rgba.len(), f.width as usize * f.height as usize * 4);
                pictures += 1;
            }
            Ok(None) => {}
            Err(DecodeError::Refused { width, height }) => {
                assert!(!l.allows(width, height) || width == 0)
            }
            Err(DecodeError::Failed(_)) => failures += 1,
        }
    }
    assert!(pictures > 0 && failures > 0, "{pictures} pictures, {failures} failures");
}
