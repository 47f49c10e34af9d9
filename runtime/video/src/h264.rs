//! What the receiver reads of H.264 itself: the size a sequence parameter set declares
//! (checked against the camera's limits before anything is decoded) and one rewrite of it.
//!
//! The rewrite: openh264 refuses a stream with a missing frame (a `frame_num` gap) up to
//! the next IDR unless its SPS allows gaps (without concealment, as the registry `openh264`
//! crate runs it, every frame; `h264dec.rs` turns concealment on through the vendored
//! crate, and the rewrite stays so that a gap is never a reason to stop). An SPS that allows gaps (`gaps_in_frame_num_value_allowed_flag = 1`) lets
//! it go on from the frames it has: a lost unit costs that unit (and some drift until the
//! next key frame), not the rest of the group of pictures. [`allow_frame_num_gaps`] sets
//! the flag in every SPS of an access unit.

/// What an SPS says about the picture.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SpsInfo {
    /// Coded size in pixels (whole macroblocks, before cropping).
    pub width: u32,
    pub height: u32,
    /// Bit offset (in the RBSP, after the NAL header byte) of `gaps_in_frame_num_value_allowed_flag`.
    gaps_bit: usize,
}

/// Removes emulation prevention bytes (`00 00 03` → `00 00`).
fn rbsp(nal: &[u8]) -> Vec<u8> {
    let mut out = Vec::with_capacity(nal.len());
    let mut zeros = 0;
    for &b in nal {
        if zeros >= 2 && b == 3 {
            zeros = 0;
            continue;
        }
        zeros = if b == 0 { zeros + 1 } else { 0 };
        out.push(b);
    }
    out
}

/// Inserts emulation prevention bytes where the RBSP would make a start code.
fn escape(rbsp: &[u8]) -> Vec<u8> {
    let mut out = Vec::with_capacity(rbsp.len() + 4);
    let mut zeros = 0;
    for &b in rbsp {
        if zeros >= 2 && b <= 3 {
            out.push(3);
            zeros = 0;
        }
        zeros = if b == 0 { zeros + 1 } else { 0 };
        out.push(b);
    }
    out
}

struct Bits<'a> {
    d: &'a [u8],
    pos: usize,
}

impl Bits<'_> {
    fn bit(&mut self) -> Option<u32> {
        let byte = *self.d.get(self.pos / 8)?;
        let b = (byte >> (7 - self.pos % 8)) & 1;
        self.pos += 1;
        Some(b as u32)
    }

    fn bits(&mut self, n: u32) -> Option<u32> {
        (0..n).try_fold(0u32, |acc, _| Some(acc << 1 | self.bit()?))
    }

    /// Exp-Golomb `ue(v)`; at most 32 leading zeros.
    fn ue(&mut self) -> Option<u32> {
        let mut zeros = 0;
        while self.bit()? == 0 {
            zeros += 1;
            if zeros > 31 {
                return None;
            }
        }
        let rest = self.bits(zeros)?;
        Some(((1u64 << zeros) - 1 + rest as u64).min(u32::MAX as u64) as u32)
    }

    fn se(&mut self) -> Option<i64> {
        let k = self.ue()? as i64;
        Some(if k % 2 == 1 { (k + 1) / 2 } else { -(k / 2) })
    }
}

/// Parses a sequence parameter set NAL unit (with its header byte, escaped as sent).
pub fn parse_sps(nal: &[u8]) -> Option<SpsInfo> {
    if nal.first()? & 0x1f != 7 {
        return None;
    }
    let r = rbsp(&nal[1..]);
    let mut b = Bits { d: &r, pos: 0 };
    let profile = b.bits(8)?;
    b.bits(16)?; // constraint flags, level
    b.ue()?; // seq_parameter_set_id
    if matches!(profile, 100 | 110 | 122 | 244 | 44 | 83 | 86 | 118 | 128 | 138 | 139 | 134 | 135) {
        if b.ue()? == 3 {
            b.bit()?; // separate_colour_plane_flag
        }
        b.ue()?; // bit_depth_luma_minus8
        b.ue()?; // bit_depth_chroma_minus8
        b.bit()?; // qpprime_y_zero_transform_bypass_flag
        if b.bit()? == 1 {
            for i in 0..8 {
                if b.bit()? == 1 {
                    let size = if i < 6 { 16 } else { 64 };
                    let (mut last, mut next) = (8i64, 8i64);
                    for _ in 0..size {
                        if next != 0 {
                            next = (last + b.se()? + 256) % 256;
                        }
                        if next != 0 {
                            last = next;
                        }
                    }
                }
            }
        }
    }
    b.ue()?; // log2_max_frame_num_minus4
    match b.ue()? {
        0 => {
            b.ue()?;
        }
        1 => {
            b.bit()?;
            b.se()?;
            b.se()?;
            let n = b.ue()?;
            if n > 255 {
                return None;
            }
            for _ in 0..n {
                b.se()?;
            }
        }
        2 => {}
        _ => return None,
    }
    b.ue()?; // max_num_ref_frames
    let gaps_bit = b.pos;
    b.bit()?;
    let w_mbs = b.ue()? as u64 + 1;
    let h_units = b.ue()? as u64 + 1;
    let frame_mbs_only = b.bit()?;
    let h_mbs = h_units * (2 - frame_mbs_only as u64);
    let clamp = |v: u64| v.saturating_mul(16).min(u32::MAX as u64) as u32;
    Some(SpsInfo { width: clamp(w_mbs), height: clamp(h_mbs), gaps_bit })
}

/// The SPS with `gaps_in_frame_num_value_allowed_flag` set (escaped again), or `None` when
/// it does not parse.
pub fn sps_allowing_gaps(nal: &[u8]) -> Option<Vec<u8>> {
    let info = parse_sps(nal)?;
    let mut r = rbsp(&nal[1..]);
    r[info.gaps_bit / 8] |= 0x80 >> (info.gaps_bit % 8);
    let mut out = vec![nal[0]];
    out.extend(escape(&r));
    Some(out)
}

/// The first SPS of an access unit (Annex B): its size, if one parses.
pub fn unit_size(annexb: &[u8]) -> Option<(u32, u32)> {
    crate::rtp::annexb_nals(annexb)
        .into_iter()
        .filter(|n| n.first().is_some_and(|h| h & 0x1f == 7))
        .find_map(parse_sps)
        .map(|s| (s.width, s.height))
}

/// The access unit with every SPS rewritten by [`sps_allowing_gaps`] (unchanged when it
/// holds none).
pub fn allow_frame_num_gaps(annexb: &[u8]) -> std::borrow::Cow<'_, [u8]> {
    let nals = crate::rtp::annexb_nals(annexb);
    if !nals.iter().any(|n| n.first().is_some_and(|h| h & 0x1f == 7)) {
        return annexb.into();
    }
    let mut out = Vec::with_capacity(annexb.len() + 8);
    for n in nals {
        out.extend_from_slice(&[0, 0, 0, 1]);
        match n.first() {
            Some(h) if h & 0x1f == 7 => match sps_allowing_gaps(n) {
                Some(s) => out.extend_from_slice(&s),
                None => out.extend_from_slice(n),
            },
            _ => out.extend_from_slice(n),
        }
    }
    out.into()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// x264's SPSs (ffmpeg `-c:v libx264`): 640×480 Constrained Baseline (`-preset
    /// ultrafast`), 1280×720 High (`-preset fast`).
    const SPS_640X480: &[u8] = &[
        0x67, 0x42, 0xc0, 0x1e, 0xda, 0x02, 0x80, 0xf6, 0xc0, 0x44, 0x00, 0x00, 0x03, 0x00, 0x04,
        0x00, 0x00, 0x03, 0x00, 0xf2, 0x3c, 0x58, 0xba, 0x80,
    ];
    const SPS_1280X720_HIGH: &[u8] = &[
        0x67, 0x64, 0x00, 0x1f, 0xac, 0xd9, 0x40, 0x50, 0x05, 0xbb, 0x01, 0x10, 0x00, 0x00, 0x03,
        0x00, 0x10, 0x00, 0x00, 0x03, 0x03, 0xc0, 0xf1, 0x83, 0x19, 0x60,
    ];

    #[test]
    fn an_sps_declares_its_size() {
        let s = parse_sps(SPS_640X480).unwrap();
        assert_eq!((s.width, s.height), (640, 480));
        let s = parse_sps(SPS_1280X720_HIGH).unwrap();
        assert_eq!((s.width, s.height), (1280, 720));
    }

    #[test]
    fn allowing_gaps_sets_one_bit_and_keeps_the_size() {
        for sps in [SPS_640X480, SPS_1280X720_HIGH] {
            gaps_set_in(sps);
        }
    }

    fn gaps_set_in(sps: &[u8]) {
        let before = parse_sps(sps).unwrap();
        let r = rbsp(&sps[1..]);
        assert_eq!(r[before.gaps_bit / 8] & (0x80 >> (before.gaps_bit % 8)), 0);
        let after = sps_allowing_gaps(sps).unwrap();
        let s = parse_sps(&after).unwrap();
        assert_eq!((s.width, s.height), (before.width, before.height));
        let r2 = rbsp(&after[1..]);
        assert_ne!(r2[s.gaps_bit / 8] & (0x80 >> (s.gaps_bit % 8)), 0);
        let differing = r.iter().zip(&r2).filter(|(a, b)| a != b).count();
        assert_eq!((differing, r.len()), (1, r2.len()));
    }

    #[test]
    fn escaping_undoes_rbsp() {
        for raw in [&[0u8, 0, 3, 1][..], &[0, 0, 3, 0, 0, 3, 0], &[1, 2, 0, 0, 3, 3]] {
            assert_eq!(escape(&rbsp(raw)), raw);
        }
    }

    #[test]
    fn garbage_is_not_an_sps() {
        assert_eq!(parse_sps(&[0x67]), None);
        assert_eq!(parse_sps(&[0x67, 0, 0, 0, 0, 0, 0, 0, 0]), None);
        assert_eq!(parse_sps(&[0x68, 0x64, 0, 0x1e]), None);
    }
}
