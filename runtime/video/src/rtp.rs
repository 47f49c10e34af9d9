//! RTP (RFC 3550) packets and the H.264 depacketizer (RFC 6184: single NAL unit, STAP-A,
//! FU-A; non-interleaved mode, which is what ffmpeg, GStreamer and cameras send).

/// One parsed RTP packet, borrowing the datagram.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct RtpPacket<'a> {
    pub marker: bool,
    pub payload_type: u8,
    pub sequence: u16,
    pub timestamp: u32,
    pub ssrc: u32,
    pub payload: &'a [u8],
}

impl<'a> RtpPacket<'a> {
    /// Parses a datagram as RTP version 2 (CSRCs, header extension and padding removed).
    /// `None` when it is not one.
    pub fn parse(d: &'a [u8]) -> Option<RtpPacket<'a>> {
        if d.len() < 12 || d[0] >> 6 != 2 {
            return None;
        }
        let cc = (d[0] & 0x0f) as usize;
        let mut start = 12 + cc * 4;
        if d[0] & 0x10 != 0 {
            let ext = d.get(start + 2..start + 4)?;
            start += 4 + u16::from_be_bytes([ext[0], ext[1]]) as usize * 4;
        }
        let mut end = d.len();
        if d[0] & 0x20 != 0 {
            let pad = *d.last()? as usize;
            end = end.checked_sub(pad)?;
        }
        if start > end {
            return None;
        }
        Some(RtpPacket {
            marker: d[1] & 0x80 != 0,
            payload_type: d[1] & 0x7f,
            sequence: u16::from_be_bytes([d[2], d[3]]),
            timestamp: u32::from_be_bytes([d[4], d[5], d[6], d[7]]),
            ssrc: u32::from_be_bytes([d[8], d[9], d[10], d[11]]),
            payload: &d[start..end],
        })
    }
}

/// The RTP payload type of JPEG (RFC 3551's static assignment).
pub const PT_JPEG: u8 = 26;

/// Whether an RTP payload plausibly starts an H.264 packet (RFC 6184): forbidden bit clear,
/// NAL type 1–23 (single), 24 (STAP-A) or 28 (FU-A).
pub fn looks_like_h264(payload: &[u8]) -> bool {
    match payload.first() {
        Some(&b) => b & 0x80 == 0 && matches!(b & 0x1f, 1..=24 | 28),
        None => false,
    }
}

/// Counts kept by a depacketizer.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct DepackStats {
    /// Packets missing from the sequence (gaps in sequence numbers).
    pub lost_packets: u64,
    /// Units (frames) thrown away: malformed, over the size limit, before the first
    /// parameter sets, or so damaged that no slice of theirs is left.
    pub dropped_units: u64,
    /// Units emitted although packets of theirs were lost or cut (also in `units`): the
    /// slices that arrived, a slice cut at the loss; the decoder conceals the rest.
    pub damaged_units: u64,
    /// Packets of kinds this depacketizer does not handle (STAP-B, MTAP, FU-B).
    pub unsupported: u64,
    /// Units seen (each ended by the marker bit or a new timestamp): emitted or dropped.
    pub units: u64,
    /// Units dropped because they grew over the size limit (also in `dropped_units`).
    pub oversize: u64,
}

/// One complete unit out of a depacketizer.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Unit {
    pub data: Vec<u8>,
    pub timestamp: u32,
    /// H.264: contains an IDR slice or a sequence parameter set.
    pub key: bool,
}

/// Sequence-number tracking shared by the depacketizers: reports a gap.
#[derive(Clone, Debug, Default)]
pub(crate) struct SeqTracker {
    last: Option<(u32, u16)>,
}

impl SeqTracker {
    /// Returns how many packets are missing before this one (0 when in order). A new SSRC
    /// starts afresh; a duplicate or reordered (older) packet reports `None`.
    pub(crate) fn next(&mut self, ssrc: u32, seq: u16) -> Option<u64> {
        let r = match self.last {
            Some((s, last)) if s == ssrc => {
                let d = seq.wrapping_sub(last);
                if d == 0 || d > 0x8000 {
                    return None;
                }
                (d - 1) as u64
            }
            _ => 0,
        };
        self.last = Some((ssrc, seq));
        Some(r)
    }
}

const START: [u8; 4] = [0, 0, 0, 1];

/// Rebuilds H.264 access units (Annex B, a start code before each NAL unit) from RTP.
///
/// A unit ends at the marker bit, or when the timestamp changes. A unit that lost packets
/// is still emitted (counted in `damaged_units`) with what arrived: whole NAL units, and a
/// fragmented one cut where its first packet went missing (or was truncated); fragments
/// after the cut are skipped up to the next NAL unit. openh264's error concealment fills
/// in the rest of the picture. A damaged unit with no slice left is dropped. No unit is
/// emitted before the first whole one that carries a sequence parameter set (a decoder can
/// do nothing without it).
#[derive(Debug, Default)]
pub struct H264Depacketizer {
    seq: SeqTracker,
    au: Vec<u8>,
    ts: Option<u32>,
    key: bool,
    broken: bool,
    /// Packets of the unit in progress were lost or cut: what is kept may be incomplete.
    damaged: bool,
    in_fu: bool,
    /// A unit with a sequence parameter set was emitted (the decoder can start).
    seen_sps: bool,
    /// The unit in progress carries one.
    has_sps: bool,
    oversize: bool,
    /// Size of the current FU-A's first fragment.
    fu_size: usize,
    /// Where the NAL unit in progress starts in `au` (its start code).
    nal_start: usize,
    /// Largest access unit kept (0: the default limit).
    max_bytes: usize,
    pub stats: DepackStats,
}

impl H264Depacketizer {
    pub fn new() -> H264Depacketizer {
        H264Depacketizer::default()
    }

    /// A depacketizer that drops access units larger than `max_bytes`.
    pub fn with_limit(max_bytes: usize) -> H264Depacketizer {
        H264Depacketizer { max_bytes, ..H264Depacketizer::default() }
    }

    /// The sender restarted: the unit in progress is dropped and sequence numbers start
    /// afresh (the statistics and the parameter sets seen are kept).
    pub fn restart(&mut self) {
        self.broken |= !self.au.is_empty();
        self.flush(&mut |_| {});
        self.seq = SeqTracker::default();
    }

    /// Feeds one packet; `emit` gets each completed access unit.
    pub fn push(&mut self, p: &RtpPacket, emit: &mut dyn FnMut(Unit)) {
        let Some(gap) = self.seq.next(p.ssrc, p.sequence) else { return };
        if gap > 0 {
            self.stats.lost_packets += gap;
            // The unit in progress lost packets (its end, if this one starts another); a
            // fragmented NAL unit in progress ends where the loss cut it.
            self.damaged |= !self.au.is_empty() || self.in_fu;
            self.cut();
        }
        if self.ts.is_some_and(|t| t != p.timestamp) {
            self.flush(emit);
        }
        // Packets lost just before this one: this unit lost its beginning, unless this
        // packet starts an access unit (then only whole units were lost).
        if gap > 0 && self.au.is_empty() && !starts_access_unit(p.payload) {
            self.damaged = true;
        }
        self.ts = Some(p.timestamp);
        self.payload(p.payload);
        if p.marker {
            self.flush(emit);
        }
    }

    fn nal(&mut self, nal: &[u8]) {
        if nal.is_empty() {
            self.broken = true;
            return;
        }
        let t = nal[0] & 0x1f;
        self.key |= t == 5 || t == 7;
        self.has_sps |= t == 7;
        self.nal_start = self.au.len();
        self.au.extend_from_slice(&START);
        self.au.extend_from_slice(nal);
        self.bound();
    }

    /// A fragmented NAL unit in progress lost a fragment (or one was cut): it is left out
    /// (openh264 conceals a missing slice better than a truncated one, which it reports as
    /// a bitstream error with no picture), and its remaining fragments are skipped.
    fn cut(&mut self) {
        if self.in_fu {
            self.au.truncate(self.nal_start);
            self.in_fu = false;
        }
    }

    /// Drops the unit in progress when it grew over the limit.
    fn bound(&mut self) {
        let max =
            if self.max_bytes == 0 { crate::DEFAULT_LIMITS.max_unit_bytes } else { self.max_bytes };
        if self.au.len() > max {
            self.au = Vec::new();
            self.broken = true;
            self.oversize = true;
        }
    }

    fn payload(&mut self, pl: &[u8]) {
        let Some(&h) = pl.first() else {
            self.broken = true;
            return;
        };
        match h & 0x1f {
            1..=23 => {
                self.in_fu = false;
                self.nal(pl);
            }
            24 => {
                self.in_fu = false;
                let mut rest = &pl[1..];
                while rest.len() >= 2 {
                    let n = u16::from_be_bytes([rest[0], rest[1]]) as usize;
                    if rest.len() < 2 + n {
                        self.broken = true;
                        return;
                    }
                    self.nal(&rest[2..2 + n]);
                    rest = &rest[2 + n..];
                }
            }
            28 => {
                let Some(&fu) = pl.get(1) else {
                    self.broken = true;
                    return;
                };
                let (start, end) = (fu & 0x80 != 0, fu & 0x40 != 0);
                // Packetizers (ffmpeg, GStreamer, live555) fill every fragment but the last
                // to the same size: a shorter one, or a start shorter than what follows,
                // was cut on the way (a truncated datagram).
                let size = pl.len();
                if !start && self.in_fu {
                    let expected = self.fu_size;
                    if size > expected || (!end && size < expected) {
                        self.damaged = true;
                        self.cut();
                        return;
                    }
                }
                if start {
                    self.fu_size = size;
                    self.in_fu = true;
                    let header = (h & 0xe0) | (fu & 0x1f);
                    let mut first = Vec::with_capacity(pl.len() - 1);
                    first.push(header);
                    first.extend_from_slice(&pl[2..]);
                    self.nal(&first);
                } else if self.in_fu {
                    self.au.extend_from_slice(&pl[2..]);
                    self.bound();
                } else {
                    // A middle or end fragment whose start was lost (or cut): skipped.
                    self.damaged = true;
                }
                if end {
                    self.in_fu = false;
                }
            }
            _ => {
                self.stats.unsupported += 1;
                self.broken = true;
            }
        }
    }

    /// Ends the unit in progress: emitted, or counted as dropped (broken, over the limit,
    /// or before the first SPS). A unit of nothing is no unit.
    fn flush(&mut self, emit: &mut dyn FnMut(Unit)) {
        let (broken, key) = (self.broken, self.key);
        // A fragmented NAL unit not ended: the unit lost its end.
        let damaged = self.damaged || self.in_fu;
        self.cut();
        let au = std::mem::take(&mut self.au);
        let has_sps = std::mem::take(&mut self.has_sps);
        let oversize = std::mem::take(&mut self.oversize);
        self.broken = false;
        self.damaged = false;
        self.key = false;
        self.in_fu = false;
        let ts = self.ts.take();
        if au.is_empty() && !broken && !damaged {
            return;
        }
        self.stats.units += 1;
        self.stats.oversize += oversize as u64;
        if !broken && !damaged && !au.is_empty() {
            self.seen_sps |= has_sps;
        }
        let usable = if damaged { has_slice(&au) } else { !au.is_empty() };
        if broken || !usable || !self.seen_sps {
            self.stats.dropped_units += 1;
        } else {
            self.stats.damaged_units += damaged as u64;
            emit(Unit { data: au, timestamp: ts.unwrap_or(0), key });
        }
    }
}

/// Whether an Annex B unit holds a coded slice (NAL unit type 1 or 5).
fn has_slice(au: &[u8]) -> bool {
    annexb_nals(au).iter().any(|n| n.first().is_some_and(|h| matches!(h & 0x1f, 1 | 5)))
}

/// Whether an RTP/H.264 payload starts an access unit: a parameter set, SEI or delimiter,
/// or the first slice of a picture (`first_mb_in_slice` = 0), alone, first in a STAP-A, or
/// in a FU-A's first fragment.
pub fn starts_access_unit(payload: &[u8]) -> bool {
    let starts = |nal_type: u8, first_byte: Option<&u8>| match nal_type {
        6..=9 => true,
        1 | 5 => first_byte.is_some_and(|b| b & 0x80 != 0),
        _ => false,
    };
    match payload.first().map(|h| h & 0x1f) {
        Some(t @ 1..=23) => starts(t, payload.get(1)),
        Some(24) => payload.get(3).is_some_and(|h| starts(h & 0x1f, payload.get(4))),
        Some(28) => {
            payload.get(1).is_some_and(|fu| fu & 0x80 != 0 && starts(fu & 0x1f, payload.get(2)))
        }
        _ => false,
    }
}

/// Splits an Annex B byte stream into NAL units (without start codes). For tests and
/// for packetizing.
pub fn annexb_nals(data: &[u8]) -> Vec<&[u8]> {
    let mut starts = Vec::new();
    let mut i = 0;
    while i + 3 <= data.len() {
        if data[i] == 0 && data[i + 1] == 0 && data[i + 2] == 1 {
            starts.push((i, i + 3));
            i += 3;
        } else {
            i += 1;
        }
    }
    let mut out = Vec::new();
    for (k, &(_, s)) in starts.iter().enumerate() {
        let mut e = starts.get(k + 1).map(|n| n.0).unwrap_or(data.len());
        while e > s && data[e - 1] == 0 && k + 1 < starts.len() {
            e -= 1;
        }
        out.push(&data[s..e]);
    }
    out
}

/// Splits an H.264 Annex B elementary stream (`ffmpeg -f h264`) into access units, each
/// in Annex B form: a unit starts at an access unit delimiter, SEI or parameter set that
/// follows a slice, or at a slice whose `first_mb_in_slice` is 0.
pub fn access_units(stream: &[u8]) -> Vec<Vec<u8>> {
    let mut out: Vec<Vec<u8>> = Vec::new();
    let mut cur: Vec<u8> = Vec::new();
    let mut has_slice = false;
    for nal in annexb_nals(stream) {
        let Some(&h) = nal.first() else { continue };
        let t = h & 0x1f;
        let is_slice = t == 1 || t == 5;
        let starts = match t {
            6..=9 => has_slice,
            1 | 5 => has_slice && nal.get(1).is_some_and(|b| b & 0x80 != 0),
            _ => false,
        };
        if starts && !cur.is_empty() {
            out.push(std::mem::take(&mut cur));
            has_slice = false;
        }
        has_slice |= is_slice;
        cur.extend_from_slice(&START);
        cur.extend_from_slice(nal);
    }
    if !cur.is_empty() {
        out.push(cur);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn pkt(seq: u16, ts: u32, marker: bool, payload: &[u8]) -> Vec<u8> {
        let mut d = vec![0x80, if marker { 0xe0 } else { 0x60 }];
        d.extend_from_slice(&seq.to_be_bytes());
        d.extend_from_slice(&ts.to_be_bytes());
        d.extend_from_slice(&7u32.to_be_bytes());
        d.extend_from_slice(payload);
        d
    }

    fn run(packets: &[Vec<u8>]) -> (Vec<Unit>, DepackStats) {
        let mut d = H264Depacketizer::new();
        let mut out = Vec::new();
        for p in packets {
            d.push(&RtpPacket::parse(p).unwrap(), &mut |u| out.push(u));
        }
        (out, d.stats)
    }

    const SPS: &[u8] = &[0x67, 1, 2, 3];
    const PPS: &[u8] = &[0x68, 4];

    fn stap(nals: &[&[u8]]) -> Vec<u8> {
        let mut v = vec![0x78];
        for n in nals {
            v.extend_from_slice(&(n.len() as u16).to_be_bytes());
            v.extend_from_slice(n);
        }
        v
    }

    #[test]
    fn parses_header_with_csrc_extension_and_padding() {
        let mut d = vec![0xb1, 0x9a, 0, 5, 0, 0, 0, 9, 0, 0, 0, 1];
        d.extend_from_slice(&[0xde, 0xad, 0xbe, 0xef]); // one CSRC
        d.extend_from_slice(&[0xbe, 0xde, 0, 1, 1, 2, 3, 4]); // extension, one word
        d.extend_from_slice(&[0x65, 0x88]);
        d.extend_from_slice(&[0, 0, 3]); // padding
        let p = RtpPacket::parse(&d).unwrap();
        assert_eq!((p.marker, p.payload_type, p.sequence, p.timestamp), (true, 26, 5, 9));
        assert_eq!(p.payload, &[0x65, 0x88]);
        assert!(RtpPacket::parse(&[0xff, 0xd8, 0xff, 0xe0, 0, 0, 0, 0, 0, 0, 0, 0]).is_none());
    }

    #[test]
    fn stap_a_single_and_fu_a_make_one_access_unit() {
        let idr_a = [0x65u8, 10, 11, 12];
        let packets = vec![
            pkt(1, 100, false, &stap(&[SPS, PPS])),
            pkt(2, 100, false, &[0x7c, 0x85, 10, 11]), // FU-A start, type 5
            pkt(3, 100, false, &[0x7c, 0x05, 12, 12]), // as long as the start
            pkt(4, 100, true, &[0x7c, 0x45, 13]),      // end
            pkt(5, 200, true, &[0x41, 9, 9]),          // single NAL, P slice
        ];
        let (units, stats) = run(&packets);
        assert_eq!(units.len(), 2);
        assert!(units[0].key && !units[1].key);
        let nals = annexb_nals(&units[0].data);
        assert_eq!(nals, vec![SPS, PPS, &[0x65, 10, 11, 12, 12, 13][..]]);
        assert_eq!(&idr_a[..3], &nals[2][..3]);
        assert_eq!(annexb_nals(&units[1].data), vec![&[0x41, 9, 9][..]]);
        assert_eq!(stats, DepackStats { units: 2, ..DepackStats::default() });
    }

    #[test]
    fn a_lost_fragment_leaves_its_nal_unit_out_and_the_next_one_is_whole() {
        let packets = vec![
            pkt(1, 100, true, &stap(&[SPS, PPS])),
            pkt(2, 200, false, &[0x7c, 0x85, 10]),
            // seq 3 lost
            pkt(4, 200, false, &[0x7c, 0x05, 12]), // skipped: after the cut
            pkt(5, 200, false, &[0x7c, 0x45, 13]), // skipped
            pkt(6, 200, true, &[0x41, 0x40, 7]),   // the next slice, whole
            pkt(7, 300, true, &[0x41, 1]),
        ];
        let (units, stats) = run(&packets);
        assert_eq!(units.len(), 3, "SPS unit, the damaged unit and the P slice");
        assert_eq!(annexb_nals(&units[1].data), vec![&[0x41, 0x40, 7][..]]);
        assert_eq!(stats.lost_packets, 1);
        assert_eq!((stats.dropped_units, stats.damaged_units), (0, 1));
    }

    #[test]
    fn a_unit_that_lost_its_beginning_or_its_end_is_handed_on_damaged() {
        let slice = |first_mb_zero: bool| [0x41, if first_mb_zero { 0x80 } else { 0x40 }, 1];
        let packets = vec![
            pkt(1, 100, true, &stap(&[SPS, PPS])),
            pkt(2, 200, false, &slice(true)),
            // seq 3 lost: the end of unit 200
            pkt(4, 300, false, &slice(true)),
            pkt(5, 300, true, &slice(false)),
            // seq 6 lost: the beginning of unit 400
            pkt(7, 400, true, &slice(false)),
            // seq 8 lost: a whole unit
            pkt(9, 600, true, &slice(true)),
        ];
        let (units, stats) = run(&packets);
        let ts: Vec<u32> = units.iter().map(|u| u.timestamp).collect();
        assert_eq!(ts, vec![100, 200, 300, 400, 600]);
        assert_eq!((stats.units, stats.dropped_units, stats.lost_packets), (5, 0, 3));
        assert_eq!(stats.damaged_units, 2);
    }

    #[test]
    fn a_damaged_unit_with_no_slice_left_is_dropped() {
        let slice = |first_mb_zero: bool| [0x41, if first_mb_zero { 0x80 } else { 0x40 }, 1];
        let packets = vec![
            pkt(1, 100, true, &stap(&[SPS, PPS])),
            // seq 2 lost: the start of unit 200's only slice
            pkt(3, 200, true, &[0x7c, 0x45, 13]),
            pkt(4, 300, true, &slice(true)),
        ];
        let (units, stats) = run(&packets);
        let ts: Vec<u32> = units.iter().map(|u| u.timestamp).collect();
        assert_eq!(ts, vec![100, 300]);
        assert_eq!((stats.dropped_units, stats.damaged_units), (1, 0));
    }

    #[test]
    fn a_fragment_shorter_than_its_siblings_was_truncated_and_its_nal_unit_left_out() {
        let packets = vec![
            pkt(1, 100, true, &stap(&[SPS, PPS])),
            pkt(2, 200, false, &[0x7c, 0x85, 1, 2, 3]),
            pkt(3, 200, false, &[0x7c, 0x05, 4, 5]), // cut
            pkt(4, 200, false, &[0x7c, 0x45, 6]),    // skipped
            pkt(5, 200, true, &[0x41, 0x40, 7]),     // a second slice, whole
            pkt(6, 300, false, &[0x7c, 0x85, 1, 2, 3]),
            pkt(7, 300, true, &[0x7c, 0x45, 4, 5, 6, 7]), // longer than the start: it was cut
        ];
        let (units, stats) = run(&packets);
        assert_eq!(units.len(), 2, "the SPS unit and unit 200");
        assert_eq!(annexb_nals(&units[1].data), vec![&[0x41, 0x40, 7][..]]);
        assert_eq!((stats.dropped_units, stats.damaged_units), (1, 1), "unit 300: no slice left");
    }

    #[test]
    fn access_unit_starts_are_told_by_first_mb_or_parameter_sets() {
        assert!(starts_access_unit(&[0x65, 0x88]));
        assert!(!starts_access_unit(&[0x41, 0x40]), "a second slice");
        assert!(starts_access_unit(&stap(&[SPS, PPS])));
        assert!(starts_access_unit(&[0x7c, 0x85, 0x88]));
        assert!(!starts_access_unit(&[0x7c, 0x05, 0x88]), "a middle fragment");
        assert!(!starts_access_unit(&[]));
    }

    #[test]
    fn a_broken_unit_with_the_sps_does_not_start_the_stream() {
        let packets = vec![
            pkt(1, 100, false, &stap(&[SPS, PPS])),
            // seq 2 lost: the IDR's slice
            pkt(3, 200, true, &[0x41, 0x80]), // a P slice: nothing to decode it from
            pkt(4, 300, true, &stap(&[SPS, PPS])),
            pkt(5, 400, true, &[0x41, 0x80]),
        ];
        let (units, stats) = run(&packets);
        let ts: Vec<u32> = units.iter().map(|u| u.timestamp).collect();
        assert_eq!(ts, vec![300, 400]);
        assert_eq!(stats.dropped_units, 2);
    }

    #[test]
    fn nothing_before_the_first_sps_and_timestamp_change_ends_a_unit() {
        let packets = vec![
            pkt(1, 100, true, &[0x41, 1]),
            pkt(2, 200, false, &stap(&[SPS, PPS])),
            pkt(3, 200, false, &[0x65, 1]),
            pkt(4, 300, false, &[0x41, 2]), // no marker on the previous unit
            pkt(5, 300, true, &[0x41, 3]),
        ];
        let (units, _) = run(&packets);
        assert_eq!(units.len(), 2);
        assert_eq!(units[0].timestamp, 200);
        assert_eq!(annexb_nals(&units[1].data).len(), 2);
    }

    #[test]
    fn sequence_wraps_and_duplicates_are_ignored() {
        let mut s = SeqTracker::default();
        assert_eq!(s.next(1, 65534), Some(0));
        assert_eq!(s.next(1, 65535), Some(0));
        assert_eq!(s.next(1, 0), Some(0));
        assert_eq!(s.next(1, 0), None);
        assert_eq!(s.next(1, 3), Some(2));
        assert_eq!(s.next(2, 100), Some(0), "a new source starts afresh");
    }
}
