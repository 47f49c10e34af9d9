//! One port's stream: which sender is heard, what it sends, and its units.
//!
//! **Choice.** A port hears one stream at a time. Until one is chosen, every datagram is
//! sniffed: a JPEG start (`FF D8 FF`) that is not RTP starts raw MJPEG; RTP version 2 with
//! payload type 26 is RTP/JPEG; a dynamic payload type (96–127) whose first byte is an
//! H.264 NAL header (single, STAP-A or FU-A) is RTP/H.264. An RTP stream is chosen after
//! two packets in sequence from one sender and SSRC (several candidates are followed at
//! once, so a sender of noise cannot keep a real stream out). With `source` (an address,
//! `HOST` or `HOST:PORT`) or `ssrc` configured, only that stream may be chosen. The chosen
//! stream holds the port while it sends **valid** packets; once it has been silent for
//! `silence` (on the DataServer's clock), the next valid stream is chosen. Everything else
//! is counted as `ignored`.
//!
//! **RTP.** Packets go through a reorder buffer ([`crate::jitter`]) before the
//! depacketizer; a restart of the chosen stream (same SSRC, sequence jump) is counted and
//! its depacketizer starts afresh.

use crate::codec::Codec;
use crate::jitter::{Pushed, Reorder, ReorderStats};
use crate::limits::Limits;
use crate::mjpeg::{MjpegReassembler, has_soi};
use crate::rtp::{H264Depacketizer, PT_JPEG, RtpPacket, Unit, looks_like_h264};
use crate::rtp_jpeg::JpegDepacketizer;
use std::collections::HashMap;
use std::net::{IpAddr, SocketAddr};
use std::time::{Duration, Instant};

/// Silence after which a stream is forgotten and the next sender may be heard.
pub const SILENCE: Duration = Duration::from_secs(2);

/// Which sender a port accepts.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SourceFilter {
    Any,
    Host(IpAddr),
    Addr(SocketAddr),
}

impl SourceFilter {
    /// `""` or `"any"`, `HOST`, or `HOST:PORT`.
    pub fn parse(text: &str) -> Option<SourceFilter> {
        match text.trim() {
            "" | "any" => Some(SourceFilter::Any),
            t => t
                .parse()
                .map(SourceFilter::Addr)
                .or_else(|_| t.parse().map(SourceFilter::Host))
                .ok(),
        }
    }

    fn accepts(&self, from: SocketAddr) -> bool {
        match self {
            SourceFilter::Any => true,
            SourceFilter::Host(h) => from.ip() == *h,
            SourceFilter::Addr(a) => from == *a,
        }
    }
}

/// How a port chooses and rebuilds its stream.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StreamConfig {
    pub source: SourceFilter,
    /// Only this RTP SSRC may be chosen (raw MJPEG has none and is then refused).
    pub ssrc: Option<u32>,
    /// Silence after which the chosen stream gives way.
    pub silence: Duration,
    /// Reorder buffer: packets held at most, and the longest wait for a missing one.
    pub reorder: usize,
    pub reorder_delay: Duration,
    pub limits: Limits,
}

impl Default for StreamConfig {
    fn default() -> StreamConfig {
        StreamConfig {
            source: SourceFilter::Any,
            ssrc: None,
            silence: SILENCE,
            reorder: 8,
            reorder_delay: Duration::from_millis(100),
            limits: Limits::default(),
        }
    }
}

/// What the stream on one port turned out to be.
enum Mode {
    Unknown,
    H264 { ssrc: u32, pt: u8, r: Reorder, d: H264Depacketizer },
    Jpeg { ssrc: u32, r: Reorder, d: JpegDepacketizer },
    Mjpeg(MjpegReassembler),
}

/// Counts of a port since it started (across the streams it chose).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct StreamStats {
    /// Units whose packets arrived (ended by a marker, a new timestamp or an EOI).
    pub sent: u64,
    /// Units handed on (to the decoder).
    pub units: u64,
    /// Units thrown away: a packet lost or malformed, over the size limit, or H.264 before
    /// the first parameter set.
    pub dropped: u64,
    /// Of those, units over the size limit.
    pub oversize: u64,
    /// Units handed on although packets of theirs were lost or cut (H.264: the decoder
    /// conceals what is missing).
    pub damaged: u64,
    /// RTP packets missing from the sequence.
    pub lost_packets: u64,
    pub reorder: ReorderStats,
    /// Datagrams not from the chosen stream (other senders, noise).
    pub ignored: u64,
}

/// The sniffer, stream choice and depacketizers of one port.
pub struct Stream {
    cfg: StreamConfig,
    mode: Mode,
    from: Option<SocketAddr>,
    last: Option<Instant>,
    /// RTP candidates: (sender, SSRC, payload type) → their last datagram.
    candidates: HashMap<(SocketAddr, u32, u8), Vec<u8>>,
    /// Counts of the streams chosen before this one.
    before: StreamStats,
    pub ignored: u64,
}

impl Default for Stream {
    fn default() -> Stream {
        Stream::with_config(StreamConfig::default())
    }
}

impl Stream {
    pub fn new() -> Stream {
        Stream::default()
    }

    pub fn with_config(cfg: StreamConfig) -> Stream {
        Stream {
            cfg,
            mode: Mode::Unknown,
            from: None,
            last: None,
            candidates: HashMap::new(),
            before: StreamStats::default(),
            ignored: 0,
        }
    }

    /// `"rtp/h264"`, `"rtp/jpeg"`, `"mjpeg"`, or `""` while unknown.
    pub fn transport(&self) -> &'static str {
        match self.mode {
            Mode::Unknown => "",
            Mode::H264 { .. } => "rtp/h264",
            Mode::Jpeg { .. } => "rtp/jpeg",
            Mode::Mjpeg(_) => "mjpeg",
        }
    }

    /// The chosen sender, if any.
    pub fn sender(&self) -> Option<SocketAddr> {
        self.from.filter(|_| !matches!(self.mode, Mode::Unknown))
    }

    /// Units thrown away for lost or malformed packets, since the start.
    pub fn dropped(&self) -> u64 {
        self.stats().dropped
    }

    /// The counts since the start.
    pub fn stats(&self) -> StreamStats {
        let mut s = self.before;
        let (d, r) = match &self.mode {
            Mode::Unknown => (None, None),
            Mode::H264 { r, d, .. } => (Some(d.stats), Some(r.stats)),
            Mode::Jpeg { r, d, .. } => (Some(d.stats), Some(r.stats)),
            Mode::Mjpeg(m) => {
                s.sent += m.emitted + m.dropped;
                s.units += m.emitted;
                s.dropped += m.dropped;
                s.oversize += m.oversize;
                (None, None)
            }
        };
        if let Some(d) = d {
            s.sent += d.units;
            s.units += d.units - d.dropped_units;
            s.dropped += d.dropped_units;
            s.oversize += d.oversize;
            s.lost_packets += d.lost_packets;
            s.damaged += d.damaged_units;
        }
        if let Some(r) = r {
            s.reorder.reordered += r.reordered;
            s.reorder.late += r.late;
            s.reorder.restarts += r.restarts;
        }
        s.ignored = self.ignored;
        s
    }

    /// Forgets the chosen stream (its counts are kept); what it still held is handed on.
    fn reset(&mut self, emit: &mut dyn FnMut(Codec, Unit)) {
        self.flush(emit);
        let ignored = self.ignored;
        self.before = self.stats();
        self.before.ignored = 0;
        self.ignored = ignored;
        self.mode = Mode::Unknown;
        self.from = None;
        self.candidates.clear();
    }

    /// Hands on what the reorder buffer holds.
    fn flush(&mut self, emit: &mut dyn FnMut(Codec, Unit)) {
        match &mut self.mode {
            Mode::H264 { r, d, .. } => r.drain(&mut |x| h264(d, x, emit)),
            Mode::Jpeg { r, d, .. } => r.drain(&mut |x| jpeg(d, x, emit)),
            _ => {}
        }
    }

    /// Releases packets whose wait for a missing one is over (call when no datagram came).
    pub fn tick(&mut self, now: Instant, emit: &mut dyn FnMut(Codec, Unit)) {
        match &mut self.mode {
            Mode::H264 { r, d, .. } => r.release(now, &mut |x| h264(d, x, emit)),
            Mode::Jpeg { r, d, .. } => r.release(now, &mut |x| jpeg(d, x, emit)),
            _ => {}
        }
    }

    fn silent(&self, now: Instant) -> bool {
        self.last.is_none_or(|t| now.saturating_duration_since(t) >= self.cfg.silence)
    }

    /// Feeds one datagram from `from` at `now` (the DataServer's clock); `emit` gets each
    /// complete unit with its codec.
    pub fn datagram(
        &mut self,
        from: SocketAddr,
        d: &[u8],
        now: Instant,
        emit: &mut dyn FnMut(Codec, Unit),
    ) {
        if !self.cfg.source.accepts(from) {
            self.ignored += 1;
            return;
        }
        let rtp = RtpPacket::parse(d);
        if !matches!(self.mode, Mode::Unknown) {
            let ours = self.from == Some(from)
                && match (&self.mode, &rtp) {
                    (Mode::H264 { ssrc, pt, .. }, Some(p)) => {
                        p.ssrc == *ssrc && p.payload_type == *pt
                    }
                    (Mode::Jpeg { ssrc, .. }, Some(p)) => {
                        p.ssrc == *ssrc && p.payload_type == PT_JPEG
                    }
                    (Mode::Mjpeg(_), _) => true,
                    _ => false,
                };
            if ours {
                self.last = Some(now);
                self.feed(d, rtp.as_ref(), now, emit);
                return;
            }
            if !self.silent(now) {
                self.ignored += 1;
                return;
            }
            self.reset(emit);
        }
        self.sniff(from, d, rtp.as_ref(), now, emit);
    }

    fn sniff(
        &mut self,
        from: SocketAddr,
        d: &[u8],
        rtp: Option<&RtpPacket>,
        now: Instant,
        emit: &mut dyn FnMut(Codec, Unit),
    ) {
        let max = self.cfg.limits.max_unit_bytes;
        let soi = d.starts_with(&[0xff, 0xd8]) || (rtp.is_none() && has_soi(d));
        if soi && self.cfg.ssrc.is_none() {
            self.mode = Mode::Mjpeg(MjpegReassembler::with_limit(max));
        } else if let Some(p) = rtp {
            let pt = p.payload_type;
            let plausible =
                pt == PT_JPEG || ((96..=127).contains(&pt) && looks_like_h264(p.payload));
            if !plausible || self.cfg.ssrc.is_some_and(|s| s != p.ssrc) {
                self.ignored += 1;
                return;
            }
            let key = (from, p.ssrc, pt);
            let before = self.candidates.remove(&key).filter(|q| {
                RtpPacket::parse(q).is_some_and(|q| q.sequence.wrapping_add(1) == p.sequence)
            });
            let Some(before) = before else {
                if self.candidates.len() >= 16 {
                    self.candidates.clear();
                }
                self.candidates.insert(key, d.to_vec());
                return;
            };
            let r = Reorder::new(self.cfg.reorder, self.cfg.reorder_delay);
            self.mode = if pt == PT_JPEG {
                Mode::Jpeg { ssrc: p.ssrc, r, d: JpegDepacketizer::with_limit(max) }
            } else {
                Mode::H264 { ssrc: p.ssrc, pt, r, d: H264Depacketizer::with_limit(max) }
            };
            self.candidates.clear();
            // The packet before, which made it a candidate, is the stream's first.
            self.feed(&before, RtpPacket::parse(&before).as_ref(), now, emit);
        } else {
            self.ignored += 1;
            return;
        }
        self.from = Some(from);
        self.last = Some(now);
        self.feed(d, rtp, now, emit);
    }

    fn feed(
        &mut self,
        d: &[u8],
        rtp: Option<&RtpPacket>,
        now: Instant,
        emit: &mut dyn FnMut(Codec, Unit),
    ) {
        match (&mut self.mode, rtp) {
            (Mode::H264 { r, d: dp, .. }, Some(p)) => {
                let pushed = r.push(p.sequence, now, d, &mut |x| h264(dp, x, emit));
                if pushed == Pushed::Restart {
                    dp.restart();
                    r.push(p.sequence, now, d, &mut |x| h264(dp, x, emit));
                }
            }
            (Mode::Jpeg { r, d: dp, .. }, Some(p)) => {
                let pushed = r.push(p.sequence, now, d, &mut |x| jpeg(dp, x, emit));
                if pushed == Pushed::Restart {
                    dp.restart();
                    r.push(p.sequence, now, d, &mut |x| jpeg(dp, x, emit));
                }
            }
            (Mode::Mjpeg(m), _) => {
                m.push(d, &mut |f| emit(Codec::Jpeg, Unit { data: f, timestamp: 0, key: true }))
            }
            _ => {}
        }
    }
}

fn h264(d: &mut H264Depacketizer, datagram: &[u8], emit: &mut dyn FnMut(Codec, Unit)) {
    if let Some(p) = RtpPacket::parse(datagram) {
        d.push(&p, &mut |u| emit(Codec::H264, u));
    }
}

fn jpeg(d: &mut JpegDepacketizer, datagram: &[u8], emit: &mut dyn FnMut(Codec, Unit)) {
    if let Some(p) = RtpPacket::parse(datagram) {
        d.push(&p, &mut |u| emit(Codec::Jpeg, u));
    }
}

#[cfg(test)]
mod tests;
