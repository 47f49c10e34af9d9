//! The `video` module: one UDP port, one stream. It tells RTP/H.264, RTP/JPEG and raw
//! MJPEG apart by their payload, rebuilds encoded units, and publishes them on the
//! camera's `encoded` listener; by default it also attaches a decoder (see
//! [`crate::codec`]).
//!
//! Sniffing: a datagram holding a JPEG start (`FF D8 FF`) that is not RTP starts raw MJPEG;
//! RTP version 2 with payload type 26 is RTP/JPEG; a dynamic payload type (96–127) whose
//! first byte is an H.264 NAL header (single, STAP-A or FU-A) is RTP/H.264. RTP needs two
//! packets in sequence from one SSRC before the stream is locked. The mode holds until the
//! sender is silent for 2 s (or, for RTP, the payload type or SSRC changes); then the
//! next sender may be heard.

use crate::codec::{Codec, DecoderHandle, Meter, attach_decoder};
use crate::frame::EncodedUnit;
use crate::mjpeg::{MjpegReassembler, has_soi};
use crate::now_us;
use crate::rtp::{H264Depacketizer, PT_JPEG, RtpPacket, Unit, looks_like_h264};
use crate::rtp_jpeg::JpegDepacketizer;
use mocu_dataserver::{DataServer, Guid, Value};
use mocu_host::world::ensure_path;
use mocu_host::{Level, Module, ModuleContext, ModuleSpec};
use std::net::{SocketAddr, UdpSocket};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

/// Where video is heard when nothing says otherwise (QGroundControl's convention).
pub const DEFAULT_ADDRESS: &str = "0.0.0.0:5600";

/// Silence after which a stream is forgotten and the next sender may be heard.
pub const SILENCE: Duration = Duration::from_secs(2);

/// Settings of the `video` module kind.
#[derive(Clone, Debug, PartialEq)]
pub struct ReceiverConfig {
    /// `address`: the UDP address to listen on (port 0: any free port, published as the
    /// camera's `port` property).
    pub address: SocketAddr,
    /// `camera`: the camera's name under `root.cameras` (default `udp<port>`).
    pub camera: Option<String>,
    /// `feeds`: the vehicle camera this stream stands for, as a path text
    /// (`root.vehicles.usv1.cameras.drive`), `auto` (the first vehicle's drive camera) or
    /// `none`. Windows showing that camera show this stream while it is live.
    pub feeds: String,
    /// `decode`: attach a decoder (default true); false leaves it to a `codec` module.
    pub decode: bool,
}

impl Default for ReceiverConfig {
    fn default() -> ReceiverConfig {
        ReceiverConfig {
            address: DEFAULT_ADDRESS.parse().expect("a valid address"),
            camera: None,
            feeds: "auto".into(),
            decode: true,
        }
    }
}

impl ReceiverConfig {
    pub fn from_spec(spec: &ModuleSpec) -> Result<ReceiverConfig, String> {
        let e = |x: mocu_host::SpecError| x.to_string();
        let addr = spec.str_or("address", DEFAULT_ADDRESS).map_err(e)?;
        let address = addr
            .parse()
            .map_err(|_| format!("module `{}`: `address` `{addr}` is not HOST:PORT", spec.name))?;
        let camera = spec.str_or("camera", "").map_err(e)?;
        Ok(ReceiverConfig {
            address,
            camera: (!camera.is_empty()).then_some(camera),
            feeds: spec.str_or("feeds", "auto").map_err(e)?,
            decode: spec.bool_or("decode", true).map_err(e)?,
        })
    }
}

/// The receiver module.
pub struct VideoReceiver {
    cfg: ReceiverConfig,
    stop: Arc<AtomicBool>,
    thread: Option<JoinHandle<()>>,
    decoder: Option<DecoderHandle>,
}

impl VideoReceiver {
    pub fn new(cfg: ReceiverConfig) -> VideoReceiver {
        VideoReceiver { cfg, stop: Arc::default(), thread: None, decoder: None }
    }
}

impl Module for VideoReceiver {
    fn start(&mut self, ctx: &ModuleContext) -> Result<(), String> {
        let sock = UdpSocket::bind(self.cfg.address)
            .map_err(|e| format!("cannot listen on {}: {e}", self.cfg.address))?;
        sock.set_read_timeout(Some(Duration::from_millis(100))).map_err(|e| e.to_string())?;
        let local = sock.local_addr().map_err(|e| e.to_string())?;
        let name = self.cfg.camera.clone().unwrap_or_else(|| format!("udp{}", local.port()));
        let ds = &ctx.ds;
        let (camera, encoded) =
            publish_camera(ds, &name, local, &self.cfg.feeds).map_err(|e| e.to_string())?;
        if self.cfg.decode {
            self.decoder = Some(
                attach_decoder(ds, &ds.serial_executor(), camera, encoded)
                    .map_err(|e| e.to_string())?,
            );
        }
        let _ = ds.set(ctx.status, "camera", Value::str(&format!("root.cameras.{name}")));
        let _ = ds.set(ctx.status, "address", Value::str(&local.to_string()));
        ctx.report(Level::Info, format!("video on udp://{local} → root.cameras.{name}"));
        let stop = self.stop.clone();
        let ds = ds.clone();
        self.thread = Some(
            ctx.spawn_thread("udp", move || receive(ds, sock, camera, encoded, stop))
                .map_err(|e| e.to_string())?,
        );
        Ok(())
    }

    fn stop(&mut self) {
        self.stop.store(true, Ordering::SeqCst);
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
        self.decoder = None;
    }
}

/// `root.cameras.<name>` (a listener: decoded frames) and its `encoded` child listener.
pub fn publish_camera(
    ds: &DataServer,
    name: &str,
    local: SocketAddr,
    feeds: &str,
) -> Result<(Guid, Guid), mocu_dataserver::DsError> {
    let cameras = ensure_path(ds, &["cameras"], "cameras")?;
    if let Some(old) = ds.find_child(cameras, name)? {
        ds.delete_object(old)?;
    }
    let camera = ds.create_listener(cameras, name)?;
    let encoded = ds.create_listener(camera, "encoded")?;
    let feeds = match feeds {
        "" | "none" | "auto" => feeds.to_string(),
        p => crate::normalize_path(p),
    };
    for (k, v) in [
        ("source", Value::str("network")),
        ("address", Value::str(&local.to_string())),
        ("port", Value::Int(local.port() as i64)),
        ("feeds", Value::str(&feeds)),
        ("transport", Value::str("")),
        ("codec", Value::str("")),
        ("format", Value::str("rgba8")),
        ("arrival", Value::Bool(true)),
        ("width", Value::Int(0)),
        ("height", Value::Int(0)),
        ("frames", Value::Int(0)),
        ("fps", Value::Float(0.0)),
        ("dropped", Value::Int(0)),
        ("dropped_network", Value::Int(0)),
        ("latency_ms", Value::Float(0.0)),
        ("packets", Value::Int(0)),
        ("bytes", Value::Int(0)),
        ("units", Value::Int(0)),
        ("last_frame_us", Value::Int(0)),
    ] {
        ds.set(camera, k, v)?;
    }
    Ok((camera, encoded))
}

/// What the stream on one port turned out to be.
enum Mode {
    Unknown { candidate: Option<(u32, u16, u8)> },
    H264 { ssrc: u32, pt: u8, d: H264Depacketizer },
    Jpeg { ssrc: u32, d: JpegDepacketizer },
    Mjpeg(MjpegReassembler),
}

impl Mode {
    fn transport(&self) -> &'static str {
        match self {
            Mode::Unknown { .. } => "",
            Mode::H264 { .. } => "rtp/h264",
            Mode::Jpeg { .. } => "rtp/jpeg",
            Mode::Mjpeg(_) => "mjpeg",
        }
    }

    fn dropped(&self) -> u64 {
        match self {
            Mode::Unknown { .. } => 0,
            Mode::H264 { d, .. } => d.stats.dropped_units,
            Mode::Jpeg { d, .. } => d.stats.dropped_units,
            Mode::Mjpeg(r) => r.dropped,
        }
    }
}

/// The payload sniffer and depacketizers of one port.
pub struct Stream {
    mode: Mode,
    from: Option<SocketAddr>,
    last: Option<Instant>,
    /// Units dropped by depacketizers of earlier modes (kept across a reset).
    dropped_before: u64,
    pub ignored: u64,
}

impl Default for Stream {
    fn default() -> Stream {
        Stream {
            mode: Mode::Unknown { candidate: None },
            from: None,
            last: None,
            dropped_before: 0,
            ignored: 0,
        }
    }
}

impl Stream {
    pub fn new() -> Stream {
        Stream::default()
    }

    /// `"rtp/h264"`, `"rtp/jpeg"`, `"mjpeg"`, or `""` while unknown.
    pub fn transport(&self) -> &'static str {
        self.mode.transport()
    }

    /// Units thrown away for lost or malformed packets, since the start.
    pub fn dropped(&self) -> u64 {
        self.dropped_before + self.mode.dropped()
    }

    fn reset(&mut self) {
        self.dropped_before += self.mode.dropped();
        self.mode = Mode::Unknown { candidate: None };
    }

    /// Feeds one datagram from `from`; `emit` gets each complete unit with its codec.
    pub fn datagram(
        &mut self,
        from: SocketAddr,
        d: &[u8],
        now: Instant,
        emit: &mut dyn FnMut(Codec, Unit),
    ) {
        let silent = self.last.is_none_or(|t| now.duration_since(t) >= SILENCE);
        if self.from != Some(from) {
            if !silent {
                self.ignored += 1;
                return;
            }
            self.from = Some(from);
            self.reset();
        } else if silent {
            self.reset();
        }
        self.last = Some(now);
        let rtp = RtpPacket::parse(d);
        // An RTP stream that changes its source or payload type is sniffed again.
        let changed = match (&self.mode, &rtp) {
            (Mode::H264 { ssrc, pt, .. }, Some(p)) => p.ssrc != *ssrc || p.payload_type != *pt,
            (Mode::Jpeg { ssrc, .. }, Some(p)) => p.ssrc != *ssrc || p.payload_type != PT_JPEG,
            (Mode::H264 { .. } | Mode::Jpeg { .. }, None) => true,
            _ => false,
        };
        if changed {
            self.reset();
        }
        if let Mode::Unknown { candidate } = &mut self.mode {
            let soi = d.starts_with(&[0xff, 0xd8]) || (rtp.is_none() && has_soi(d));
            if soi {
                self.mode = Mode::Mjpeg(MjpegReassembler::new());
            } else if let Some(p) = &rtp {
                let pt = p.payload_type;
                let plausible =
                    pt == PT_JPEG || ((96..=127).contains(&pt) && looks_like_h264(p.payload));
                if !plausible {
                    self.ignored += 1;
                    return;
                }
                let follows = candidate.is_some_and(|(s, q, t)| {
                    s == p.ssrc && t == pt && q.wrapping_add(1) == p.sequence
                });
                if !follows {
                    *candidate = Some((p.ssrc, p.sequence, pt));
                    return;
                }
                self.mode = if pt == PT_JPEG {
                    Mode::Jpeg { ssrc: p.ssrc, d: JpegDepacketizer::new() }
                } else {
                    Mode::H264 { ssrc: p.ssrc, pt, d: H264Depacketizer::new() }
                };
            } else {
                self.ignored += 1;
                return;
            }
        }
        match &mut self.mode {
            Mode::H264 { d: dp, .. } => {
                if let Some(p) = &rtp {
                    dp.push(p, &mut |u| emit(Codec::H264, u));
                }
            }
            Mode::Jpeg { d: dp, .. } => {
                if let Some(p) = &rtp {
                    dp.push(p, &mut |u| emit(Codec::Jpeg, u));
                }
            }
            Mode::Mjpeg(r) => {
                r.push(d, &mut |f| emit(Codec::Jpeg, Unit { data: f, timestamp: 0, key: true }))
            }
            Mode::Unknown { .. } => {}
        }
    }
}

fn receive(ds: DataServer, sock: UdpSocket, camera: Guid, encoded: Guid, stop: Arc<AtomicBool>) {
    let mut buf = vec![0u8; 65536];
    let mut stream = Stream::new();
    let (mut packets, mut bytes, mut units) = (0i64, 0i64, 0i64);
    let mut meter = Meter::default();
    let mut transport = "";
    let mut source = None;
    while !stop.load(Ordering::Relaxed) {
        let got = sock.recv_from(&mut buf);
        let arrival_us = now_us();
        let mut n_units = 0;
        if let Ok((n, from)) = got {
            packets += 1;
            bytes += n as i64;
            stream.datagram(from, &buf[..n], Instant::now(), &mut |codec, u| {
                n_units += 1;
                let unit = EncodedUnit {
                    data: u.data.into(),
                    codec: codec.name().into(),
                    unit: units + n_units,
                    arrival_us,
                };
                let _ = ds.send(encoded, unit.to_values());
            });
            units += n_units;
            if source != Some(from) && stream.from == Some(from) {
                source = Some(from);
                let _ = ds.set(camera, "sender", Value::str(&from.to_string()));
            }
        }
        if meter.tick(0) || n_units > 0 && units == n_units {
            if stream.transport() != transport {
                transport = stream.transport();
                let _ = ds.set(camera, "transport", Value::str(transport));
            }
            let _ = ds.set(camera, "packets", Value::Int(packets));
            let _ = ds.set(camera, "bytes", Value::Int(bytes));
            let _ = ds.set(camera, "units", Value::Int(units));
            let _ = ds.set(camera, "dropped_network", Value::Int(stream.dropped() as i64));
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn rtp(seq: u16, pt: u8, marker: bool, payload: &[u8]) -> Vec<u8> {
        let mut d = vec![0x80, pt | if marker { 0x80 } else { 0 }];
        d.extend_from_slice(&seq.to_be_bytes());
        d.extend_from_slice(&[0, 0, 0, 1, 0, 0, 0, 9]);
        d.extend_from_slice(payload);
        d
    }

    fn feed(s: &mut Stream, from: &str, ds: &[Vec<u8>], t: Instant) -> Vec<Codec> {
        let mut out = Vec::new();
        for d in ds {
            s.datagram(from.parse().unwrap(), d, t, &mut |c, _| out.push(c));
        }
        out
    }

    #[test]
    fn h264_is_locked_after_two_packets_in_sequence() {
        let mut s = Stream::new();
        let t = Instant::now();
        let sps = [0x78, 0, 2, 0x67, 1, 0, 2, 0x68, 2];
        let ps = vec![rtp(1, 96, true, &sps), rtp(2, 96, true, &sps), rtp(3, 96, true, &[0x41, 1])];
        let got = feed(&mut s, "127.0.0.1:9", &ps, t);
        assert_eq!(s.transport(), "rtp/h264");
        assert_eq!(got, vec![Codec::H264, Codec::H264]);
    }

    #[test]
    fn raw_mjpeg_is_told_by_its_soi_and_rtp_jpeg_by_its_payload_type() {
        let mut s = Stream::new();
        let t = Instant::now();
        feed(&mut s, "127.0.0.1:9", &[vec![0xff, 0xd8, 0xff, 0xe0, 0, 2]], t);
        assert_eq!(s.transport(), "mjpeg");
        let mut s = Stream::new();
        let jh = [0, 0, 0, 0, 1, 50, 2, 2, 1, 2];
        feed(&mut s, "127.0.0.1:9", &[rtp(7, 26, true, &jh), rtp(8, 26, true, &jh)], t);
        assert_eq!(s.transport(), "rtp/jpeg");
    }

    #[test]
    fn a_second_sender_is_ignored_until_the_first_is_silent() {
        let mut s = Stream::new();
        let t = Instant::now();
        let soi = vec![0xff, 0xd8, 0xff, 0xe0, 0, 2];
        feed(&mut s, "127.0.0.1:9", std::slice::from_ref(&soi), t);
        feed(&mut s, "127.0.0.1:10", std::slice::from_ref(&soi), t);
        assert_eq!(s.ignored, 1);
        let later = t + SILENCE + Duration::from_millis(1);
        let sps = [0x78, 0, 2, 0x67, 1];
        feed(&mut s, "127.0.0.1:10", &[rtp(1, 97, false, &sps), rtp(2, 97, false, &sps)], later);
        assert_eq!(s.transport(), "rtp/h264");
    }
}
