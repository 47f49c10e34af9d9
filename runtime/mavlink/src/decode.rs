//! Splits a UDP datagram into MAVLink 1/2 frames, checks each CRC (and, on a link with a
//! key, each signature), and decodes the known ones. Malformed bytes (bad CRC, truncated
//! frames, payloads that do not parse), unknown message ids, unknown incompatibility flags
//! and refused signatures are counted and skipped; nothing here can fail the caller. Enum
//! values newer than the dialect do not make a message malformed (`lenient.rs`).

use crate::lenient::{self, Msg};
use crate::signing::{self, Signing};
use mavlink::dialects::development::MavMessage;
use mavlink::{MavHeader, MavlinkVersion, Message};

/// What one datagram held.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct DecodeCounts {
    pub decoded: u64,
    /// Bad CRC, truncated frame, garbage between frames, or a payload that does not parse.
    pub malformed: u64,
    /// A well-framed message whose id this dialect does not know.
    pub unknown: u64,
    /// Frames with incompatibility flags we do not know (the protocol says: drop them).
    pub incompatible: u64,
    /// Unsigned frames (or MAVLink 1) on a link that requires a signature.
    pub unsigned: u64,
    /// Signatures that do not match the link's key.
    pub bad_signature: u64,
    /// Signed frames whose timestamp does not move forward (replays).
    pub old_timestamp: u64,
}

const V1_STX: u8 = 0xFE;
const V2_STX: u8 = 0xFD;
pub(crate) const IFLAG_SIGNED: u8 = 0x01;
/// The `mavlink` crate's extension for 32-bit system ids.
const IFLAG_SYSID32: u8 = 0x02;
const KNOWN_IFLAGS: u8 = IFLAG_SIGNED | IFLAG_SYSID32;

/// Decodes every frame of `buf` without signature checks, calling `each` with the decoded
/// ones in order.
pub fn decode_datagram(buf: &[u8], each: impl FnMut(MavHeader, Msg)) -> DecodeCounts {
    decode_checked(buf, None, each)
}

/// Decodes every frame of `buf`; with `signing`, only frames signed with its key pass.
pub fn decode_checked(
    buf: &[u8],
    mut signing: Option<&mut Signing>,
    mut each: impl FnMut(MavHeader, Msg),
) -> DecodeCounts {
    let mut counts = DecodeCounts::default();
    let mut i = 0;
    let mut skipped_garbage = false;
    while i < buf.len() {
        let frame = match buf[i] {
            V2_STX => parse_v2(&buf[i..]),
            V1_STX => parse_v1(&buf[i..]),
            _ => {
                if !skipped_garbage {
                    counts.malformed += 1;
                    skipped_garbage = true;
                }
                i += 1;
                continue;
            }
        };
        skipped_garbage = false;
        match frame {
            Frame::Truncated => {
                counts.malformed += 1;
                break;
            }
            Frame::Complete { len, version, iflags, header, msgid, payload, body, crc } => {
                let extra = MavMessage::extra_crc(msgid);
                let known = extra != 0 || MavMessage::default_message_from_id(msgid).is_some();
                let verdict = |s: &mut Signing| {
                    let signed = version == MavlinkVersion::V2 && iflags & IFLAG_SIGNED != 0;
                    s.verify(&buf[i..i + len], signed, header.system_id, header.component_id)
                };
                if iflags & !KNOWN_IFLAGS != 0 {
                    counts.incompatible += 1;
                } else if !known {
                    counts.unknown += 1;
                } else if mavlink::calculate_crc(body, extra) != crc {
                    counts.malformed += 1;
                } else if let Some(Err(r)) = signing.as_deref_mut().map(verdict) {
                    match r {
                        signing::Refusal::Unsigned => counts.unsigned += 1,
                        signing::Refusal::BadSignature => counts.bad_signature += 1,
                        signing::Refusal::OldTimestamp => counts.old_timestamp += 1,
                    }
                } else {
                    match lenient::parse(version, msgid, payload) {
                        Ok(msg) => {
                            counts.decoded += 1;
                            each(header, msg);
                        }
                        Err(mavlink::error::ParserError::UnknownMessage { .. }) => {
                            counts.unknown += 1
                        }
                        Err(_) => counts.malformed += 1,
                    }
                }
                i += len;
            }
        }
    }
    counts
}

enum Frame<'a> {
    Truncated,
    Complete {
        len: usize,
        version: MavlinkVersion,
        iflags: u8,
        header: MavHeader,
        msgid: u32,
        payload: &'a [u8],
        body: &'a [u8],
        crc: u16,
    },
}

fn parse_v2(b: &[u8]) -> Frame<'_> {
    if b.len() < 3 {
        return Frame::Truncated;
    }
    let plen = b[1] as usize;
    let iflags = b[2];
    let hlen = if iflags & IFLAG_SYSID32 != 0 { 12 } else { 9 };
    let sig = if iflags & IFLAG_SIGNED != 0 { 13 } else { 0 };
    let total = 1 + hlen + plen + 2 + sig;
    if b.len() < total {
        return Frame::Truncated;
    }
    let (system_id, component_id, id_at) = if iflags & IFLAG_SYSID32 != 0 {
        (u32::from_le_bytes([b[5], b[6], b[7], b[8]]), b[9], 10)
    } else {
        (b[5] as u32, b[6], 7)
    };
    let msgid = u32::from_le_bytes([b[id_at], b[id_at + 1], b[id_at + 2], 0]);
    let header = MavHeader { system_id, component_id, sequence: b[4] };
    let body = &b[1..1 + hlen + plen];
    let crc = u16::from_le_bytes([b[1 + hlen + plen], b[2 + hlen + plen]]);
    Frame::Complete {
        len: total,
        version: MavlinkVersion::V2,
        iflags,
        header,
        msgid,
        payload: &b[1 + hlen..1 + hlen + plen],
        body,
        crc,
    }
}

fn parse_v1(b: &[u8]) -> Frame<'_> {
    if b.len() < 2 {
        return Frame::Truncated;
    }
    let plen = b[1] as usize;
    let total = 1 + 5 + plen + 2;
    if b.len() < total {
        return Frame::Truncated;
    }
    let header = MavHeader { system_id: b[3] as u32, component_id: b[4], sequence: b[2] };
    let body = &b[1..6 + plen];
    let crc = u16::from_le_bytes([b[6 + plen], b[7 + plen]]);
    Frame::Complete {
        len: total,
        version: MavlinkVersion::V1,
        iflags: 0,
        header,
        msgid: b[5] as u32,
        payload: &b[6..6 + plen],
        body,
        crc,
    }
}

/// Encodes one message as a MAVLink 2 frame.
pub fn encode_v2(header: MavHeader, msg: &MavMessage) -> Vec<u8> {
    let mut out = Vec::with_capacity(64);
    let _ = mavlink::write_v2_msg(&mut out, header, msg);
    out
}

/// Encodes one message as a MAVLink 2 frame signed by `signing` at `timestamp` (10 µs units
/// since 2015-01-01; see [`signing::timestamp`]).
pub fn encode_v2_signed(
    header: MavHeader,
    msg: &MavMessage,
    signing: &mut Signing,
    timestamp: u64,
) -> Vec<u8> {
    let mut out = encode_v2(header, msg);
    signing.sign(&mut out, MavMessage::extra_crc(msg.message_id()), timestamp);
    out
}
