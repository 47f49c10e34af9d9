//! RTP/JPEG (RFC 2435): rebuilds a complete JFIF file from the RTP/JPEG header, the
//! quantization tables (in-band for Q ≥ 128, the RFC's scaled defaults for Q < 128) and
//! the standard Huffman tables (JPEG Annex K.3 — RTP/JPEG senders must use them).

use crate::rtp::{DepackStats, RtpPacket, SeqTracker, Unit};
use std::collections::HashMap;

/// Rebuilds JPEG frames from RTP packets (payload type 26). A frame ends at the marker bit
/// or when the timestamp changes; a missing fragment (offsets that do not join up) throws
/// the frame away.
#[derive(Debug, Default)]
pub struct JpegDepacketizer {
    seq: SeqTracker,
    ts: Option<u32>,
    scan: Vec<u8>,
    header: Option<FrameHeader>,
    broken: bool,
    /// In-band tables by Q (a sender may send them once and then an empty table header).
    tables: HashMap<u8, Vec<u8>>,
    /// Largest scan kept (0: the default limit).
    max_bytes: usize,
    oversize: bool,
    pub stats: DepackStats,
}

#[derive(Clone, Debug, PartialEq, Eq)]
struct FrameHeader {
    kind: u8,
    q: u8,
    width: u16,
    height: u16,
    restart_interval: u16,
    qtables: Vec<u8>,
}

impl JpegDepacketizer {
    pub fn new() -> JpegDepacketizer {
        JpegDepacketizer::default()
    }

    /// A depacketizer that drops frames larger than `max_bytes`.
    pub fn with_limit(max_bytes: usize) -> JpegDepacketizer {
        JpegDepacketizer { max_bytes, ..JpegDepacketizer::default() }
    }

    /// The sender restarted: the frame in progress is dropped and sequence numbers start
    /// afresh.
    pub fn restart(&mut self) {
        self.broken |= self.header.is_some();
        self.flush(&mut |_| {});
        self.seq = SeqTracker::default();
    }

    pub fn push(&mut self, p: &RtpPacket, emit: &mut dyn FnMut(Unit)) {
        let Some(gap) = self.seq.next(p.ssrc, p.sequence) else { return };
        if gap > 0 {
            self.stats.lost_packets += gap;
            // The frame in progress lost packets (its end, if this one starts another);
            // a frame that lost its beginning is caught by its fragment offsets.
            self.broken |= self.ts.is_some();
        }
        if self.ts.is_some_and(|t| t != p.timestamp) {
            self.flush(emit);
        }
        self.ts = Some(p.timestamp);
        if self.packet(p.payload).is_none() {
            self.broken = true;
        }
        if p.marker {
            self.flush(emit);
        }
    }

    fn packet(&mut self, pl: &[u8]) -> Option<()> {
        let h = pl.get(..8)?;
        let offset = u32::from_be_bytes([0, h[1], h[2], h[3]]) as usize;
        let (kind, q) = (h[4], h[5]);
        let (width, height) = (h[6] as u16 * 8, h[7] as u16 * 8);
        let mut rest = &pl[8..];
        let mut restart_interval = 0;
        if (64..128).contains(&kind) {
            let r = rest.get(..4)?;
            restart_interval = u16::from_be_bytes([r[0], r[1]]);
            rest = &rest[4..];
        }
        if offset == 0 {
            let qtables = if q >= 128 {
                let t = rest.get(..4)?;
                let (precision, len) = (t[1], u16::from_be_bytes([t[2], t[3]]) as usize);
                let data = rest.get(4..4 + len)?;
                rest = &rest[4 + len..];
                if precision != 0 {
                    return None; // 16-bit tables: not used by baseline senders
                }
                if len > 0 {
                    self.tables.insert(q, data.to_vec());
                }
                self.tables.get(&q)?.clone()
            } else {
                default_tables(q)
            };
            if qtables.len() != 64 && qtables.len() != 128 {
                return None;
            }
            if !matches!(kind & !64, 0 | 1) || width == 0 || height == 0 {
                self.stats.unsupported += 1;
                return None;
            }
            self.scan.clear();
            self.header = Some(FrameHeader { kind, q, width, height, restart_interval, qtables });
        } else if self.header.is_none() || offset != self.scan.len() {
            return None;
        }
        if offset != self.scan.len() {
            return None;
        }
        let max =
            if self.max_bytes == 0 { crate::DEFAULT_LIMITS.max_unit_bytes } else { self.max_bytes };
        if self.scan.len() + rest.len() > max {
            self.scan = Vec::new();
            self.header = None;
            self.oversize = true;
            return None;
        }
        self.scan.extend_from_slice(rest);
        Some(())
    }

    fn flush(&mut self, emit: &mut dyn FnMut(Unit)) {
        let header = self.header.take();
        let scan = std::mem::take(&mut self.scan);
        let broken = std::mem::replace(&mut self.broken, false);
        let oversize = std::mem::take(&mut self.oversize);
        let ts = self.ts.take().unwrap_or(0);
        if header.is_none() && !broken {
            return;
        }
        self.stats.units += 1;
        self.stats.oversize += oversize as u64;
        match header {
            Some(h) if !broken && !scan.is_empty() => {
                emit(Unit { data: build_jfif(&h, &scan), timestamp: ts, key: true })
            }
            _ => self.stats.dropped_units += 1,
        }
    }
}

/// RFC 2435 appendix A: the luminance and chrominance tables of the JPEG standard
/// (Annex K.1, K.2), in zig-zag order.
const LUMA_Q: [u8; 64] = [
    16, 11, 12, 14, 12, 10, 16, 14, 13, 14, 18, 17, 16, 19, 24, 40, 26, 24, 22, 22, 24, 49, 35, 37,
    29, 40, 58, 51, 61, 60, 57, 51, 56, 55, 64, 72, 92, 78, 64, 68, 87, 69, 55, 56, 80, 109, 81,
    87, 95, 98, 103, 104, 103, 62, 77, 113, 121, 112, 100, 120, 92, 101, 103, 99,
];
const CHROMA_Q: [u8; 64] = [
    17, 18, 18, 24, 21, 24, 47, 26, 26, 47, 99, 66, 56, 66, 99, 99, 99, 99, 99, 99, 99, 99, 99, 99,
    99, 99, 99, 99, 99, 99, 99, 99, 99, 99, 99, 99, 99, 99, 99, 99, 99, 99, 99, 99, 99, 99, 99, 99,
    99, 99, 99, 99, 99, 99, 99, 99, 99, 99, 99, 99, 99, 99, 99, 99,
];

/// RFC 2435 `MakeTables`: the two default tables scaled for quality `q` (1–99), luminance
/// then chrominance, zig-zag order.
pub fn default_tables(q: u8) -> Vec<u8> {
    let factor = (q as i32).clamp(1, 99);
    let scale = if factor < 50 { 5000 / factor } else { 200 - factor * 2 };
    let mk = |t: &[u8; 64]| -> Vec<u8> {
        t.iter().map(|&v| ((v as i32 * scale + 50) / 100).clamp(1, 255) as u8).collect()
    };
    let mut out = mk(&LUMA_Q);
    out.extend(mk(&CHROMA_Q));
    out
}

// JPEG Annex K.3: the standard Huffman tables (bit counts, then values).
const DC_LUMA_BITS: [u8; 16] = [0, 1, 5, 1, 1, 1, 1, 1, 1, 0, 0, 0, 0, 0, 0, 0];
const DC_CHROMA_BITS: [u8; 16] = [0, 3, 1, 1, 1, 1, 1, 1, 1, 1, 1, 0, 0, 0, 0, 0];
const DC_VALS: [u8; 12] = [0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11];
const AC_LUMA_BITS: [u8; 16] = [0, 2, 1, 3, 3, 2, 4, 3, 5, 5, 4, 4, 0, 0, 1, 0x7d];
const AC_LUMA_VALS: [u8; 162] = [
    0x01, 0x02, 0x03, 0x00, 0x04, 0x11, 0x05, 0x12, 0x21, 0x31, 0x41, 0x06, 0x13, 0x51, 0x61, 0x07,
    0x22, 0x71, 0x14, 0x32, 0x81, 0x91, 0xa1, 0x08, 0x23, 0x42, 0xb1, 0xc1, 0x15, 0x52, 0xd1, 0xf0,
    0x24, 0x33, 0x62, 0x72, 0x82, 0x09, 0x0a, 0x16, 0x17, 0x18, 0x19, 0x1a, 0x25, 0x26, 0x27, 0x28,
    0x29, 0x2a, 0x34, 0x35, 0x36, 0x37, 0x38, 0x39, 0x3a, 0x43, 0x44, 0x45, 0x46, 0x47, 0x48, 0x49,
    0x4a, 0x53, 0x54, 0x55, 0x56, 0x57, 0x58, 0x59, 0x5a, 0x63, 0x64, 0x65, 0x66, 0x67, 0x68, 0x69,
    0x6a, 0x73, 0x74, 0x75, 0x76, 0x77, 0x78, 0x79, 0x7a, 0x83, 0x84, 0x85, 0x86, 0x87, 0x88, 0x89,
    0x8a, 0x92, 0x93, 0x94, 0x95, 0x96, 0x97, 0x98, 0x99, 0x9a, 0xa2, 0xa3, 0xa4, 0xa5, 0xa6, 0xa7,
    0xa8, 0xa9, 0xaa, 0xb2, 0xb3, 0xb4, 0xb5, 0xb6, 0xb7, 0xb8, 0xb9, 0xba, 0xc2, 0xc3, 0xc4, 0xc5,
    0xc6, 0xc7, 0xc8, 0xc9, 0xca, 0xd2, 0xd3, 0xd4, 0xd5, 0xd6, 0xd7, 0xd8, 0xd9, 0xda, 0xe1, 0xe2,
    0xe3, 0xe4, 0xe5, 0xe6, 0xe7, 0xe8, 0xe9, 0xea, 0xf1, 0xf2, 0xf3, 0xf4, 0xf5, 0xf6, 0xf7, 0xf8,
    0xf9, 0xfa,
];
const AC_CHROMA_BITS: [u8; 16] = [0, 2, 1, 2, 4, 4, 3, 4, 7, 5, 4, 4, 0, 1, 2, 0x77];
const AC_CHROMA_VALS: [u8; 162] = [
    0x00, 0x01, 0x02, 0x03, 0x11, 0x04, 0x05, 0x21, 0x31, 0x06, 0x12, 0x41, 0x51, 0x07, 0x61, 0x71,
    0x13, 0x22, 0x32, 0x81, 0x08, 0x14, 0x42, 0x91, 0xa1, 0xb1, 0xc1, 0x09, 0x23, 0x33, 0x52, 0xf0,
    0x15, 0x62, 0x72, 0xd1, 0x0a, 0x16, 0x24, 0x34, 0xe1, 0x25, 0xf1, 0x17, 0x18, 0x19, 0x1a, 0x26,
    0x27, 0x28, 0x29, 0x2a, 0x35, 0x36, 0x37, 0x38, 0x39, 0x3a, 0x43, 0x44, 0x45, 0x46, 0x47, 0x48,
    0x49, 0x4a, 0x53, 0x54, 0x55, 0x56, 0x57, 0x58, 0x59, 0x5a, 0x63, 0x64, 0x65, 0x66, 0x67, 0x68,
    0x69, 0x6a, 0x73, 0x74, 0x75, 0x76, 0x77, 0x78, 0x79, 0x7a, 0x82, 0x83, 0x84, 0x85, 0x86, 0x87,
    0x88, 0x89, 0x8a, 0x92, 0x93, 0x94, 0x95, 0x96, 0x97, 0x98, 0x99, 0x9a, 0xa2, 0xa3, 0xa4, 0xa5,
    0xa6, 0xa7, 0xa8, 0xa9, 0xaa, 0xb2, 0xb3, 0xb4, 0xb5, 0xb6, 0xb7, 0xb8, 0xb9, 0xba, 0xc2, 0xc3,
    0xc4, 0xc5, 0xc6, 0xc7, 0xc8, 0xc9, 0xca, 0xd2, 0xd3, 0xd4, 0xd5, 0xd6, 0xd7, 0xd8, 0xd9, 0xda,
    0xe2, 0xe3, 0xe4, 0xe5, 0xe6, 0xe7, 0xe8, 0xe9, 0xea, 0xf2, 0xf3, 0xf4, 0xf5, 0xf6, 0xf7, 0xf8,
    0xf9, 0xfa,
];

fn segment(out: &mut Vec<u8>, marker: u8, body: &[u8]) {
    out.extend_from_slice(&[0xff, marker]);
    out.extend_from_slice(&((body.len() + 2) as u16).to_be_bytes());
    out.extend_from_slice(body);
}

fn huffman(out: &mut Vec<u8>, class_id: u8, bits: &[u8; 16], vals: &[u8]) {
    let mut b = vec![class_id];
    b.extend_from_slice(bits);
    b.extend_from_slice(vals);
    segment(out, 0xc4, &b);
}

/// The JFIF file for one frame: SOI, DQT, SOF0, DHT ×4, DRI, SOS, the scan, EOI.
fn build_jfif(h: &FrameHeader, scan: &[u8]) -> Vec<u8> {
    let mut out = Vec::with_capacity(scan.len() + 700);
    out.extend_from_slice(&[0xff, 0xd8]);
    let (luma, chroma) = h.qtables.split_at(64.min(h.qtables.len()));
    let chroma = if chroma.is_empty() { luma } else { &chroma[..64] };
    let mut dqt = vec![0u8];
    dqt.extend_from_slice(luma);
    dqt.push(1);
    dqt.extend_from_slice(chroma);
    segment(&mut out, 0xdb, &dqt);
    // Type 0: 4:2:2 (Y sampled 2×1), type 1: 4:2:0 (2×2); +64: with restart markers.
    let y_sampling = if h.kind & !64 == 0 { 0x21 } else { 0x22 };
    let [wh, wl] = h.width.to_be_bytes();
    let [hh, hl] = h.height.to_be_bytes();
    segment(&mut out, 0xc0, &[8, hh, hl, wh, wl, 3, 1, y_sampling, 0, 2, 0x11, 1, 3, 0x11, 1]);
    huffman(&mut out, 0x00, &DC_LUMA_BITS, &DC_VALS);
    huffman(&mut out, 0x10, &AC_LUMA_BITS, &AC_LUMA_VALS);
    huffman(&mut out, 0x01, &DC_CHROMA_BITS, &DC_VALS);
    huffman(&mut out, 0x11, &AC_CHROMA_BITS, &AC_CHROMA_VALS);
    if h.restart_interval > 0 {
        segment(&mut out, 0xdd, &h.restart_interval.to_be_bytes());
    }
    segment(&mut out, 0xda, &[3, 1, 0x00, 2, 0x11, 3, 0x11, 0, 63, 0]);
    out.extend_from_slice(scan);
    if !scan.ends_with(&[0xff, 0xd9]) {
        out.extend_from_slice(&[0xff, 0xd9]);
    }
    let _ = h.q;
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn huffman_tables_have_as_many_values_as_their_bit_counts_say() {
        let sum = |b: &[u8; 16]| b.iter().map(|&x| x as usize).sum::<usize>();
        assert_eq!(sum(&DC_LUMA_BITS), 12);
        assert_eq!(sum(&DC_CHROMA_BITS), 12);
        assert_eq!(sum(&AC_LUMA_BITS), AC_LUMA_VALS.len());
        assert_eq!(sum(&AC_CHROMA_BITS), AC_CHROMA_VALS.len());
    }

    #[test]
    fn default_tables_follow_rfc_2435_make_tables() {
        let t = default_tables(50);
        assert_eq!(&t[..64], &LUMA_Q[..], "q = 50 is the standard table");
        assert_eq!(&t[64..], &CHROMA_Q[..]);
        let t = default_tables(99);
        assert!(t.iter().all(|&v| v == 1 || v == 2));
        let t = default_tables(1);
        assert_eq!(t[0], 255, "clamped to 255");
    }

    fn pkt(seq: u16, marker: bool, offset: u32, q: u8, extra: &[u8], data: &[u8]) -> Vec<u8> {
        let mut d = vec![0x80, if marker { 0x80 | 26 } else { 26 }];
        d.extend_from_slice(&seq.to_be_bytes());
        d.extend_from_slice(&1000u32.to_be_bytes());
        d.extend_from_slice(&5u32.to_be_bytes());
        let o = offset.to_be_bytes();
        d.extend_from_slice(&[0, o[1], o[2], o[3], 1, q, 80, 60]);
        d.extend_from_slice(extra);
        d.extend_from_slice(data);
        d
    }

    #[test]
    fn fragments_join_into_one_jfif_with_in_band_tables() {
        let mut qt = vec![0, 0, 0, 128];
        qt.extend((0..128).map(|i| (i % 50 + 1) as u8));
        let ps = [pkt(1, false, 0, 255, &qt, &[1, 2, 3]), pkt(2, true, 3, 255, &[], &[4, 5])];
        let mut d = JpegDepacketizer::new();
        let mut out = Vec::new();
        for p in &ps {
            d.push(&RtpPacket::parse(p).unwrap(), &mut |u| out.push(u));
        }
        assert_eq!(out.len(), 1);
        let f = &out[0].data;
        assert_eq!(&f[..2], &[0xff, 0xd8]);
        assert!(f.ends_with(&[1, 2, 3, 4, 5, 0xff, 0xd9]));
        let sof = f.windows(2).position(|w| w == [0xff, 0xc0]).unwrap();
        assert_eq!(&f[sof + 5..sof + 9], &[1, 224, 2, 128], "480 rows, 640 columns");
        assert_eq!(f[sof + 11], 0x22, "type 1 is 4:2:0");
    }

    #[test]
    fn a_missing_fragment_drops_the_frame() {
        let ps = [
            pkt(1, false, 0, 50, &[], &[1, 2, 3]),
            pkt(3, true, 6, 50, &[], &[4, 5]),
            pkt(4, false, 0, 50, &[], &[1, 2, 3]),
            pkt(5, true, 3, 50, &[], &[4]),
        ];
        let mut d = JpegDepacketizer::new();
        let mut out = Vec::new();
        for p in &ps {
            d.push(&RtpPacket::parse(p).unwrap(), &mut |u| out.push(u));
        }
        assert_eq!(out.len(), 1);
        assert_eq!(d.stats.lost_packets, 1);
        assert_eq!(d.stats.dropped_units, 1);
    }
}
