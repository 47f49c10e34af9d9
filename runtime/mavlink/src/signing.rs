//! MAVLink 2 message signing (mavlink.io, "Message signing"): a frame with the SIGNED
//! incompatibility flag carries a link id, a 48-bit timestamp (10 µs units since
//! 2015-01-01) and the first 48 bits of SHA-256(secret key ‖ header ‖ payload ‖ CRC ‖ link id
//! ‖ timestamp). With a key configured, a link accepts only frames signed with it whose
//! timestamp moves forward on their stream (link id, system, component), and signs what it
//! sends.

use sha2::{Digest, Sha256};
use std::collections::HashMap;

/// Bytes after the CRC of a signed frame: link id, timestamp, signature.
pub const SIGNATURE_LEN: usize = 13;
/// A new stream may start at most this far (one minute, in 10 µs units) behind the newest
/// timestamp the link has accepted.
const NEW_STREAM_SLACK: u64 = 60 * 100_000;
/// Streams remembered per link (only frames with a good signature add one).
const MAX_STREAMS: usize = 4096;

/// A 32-byte secret key.
#[derive(Clone, PartialEq, Eq)]
pub struct Key(pub [u8; 32]);

impl std::fmt::Debug for Key {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("Key(…)")
    }
}

impl Key {
    /// 64 hexadecimal digits are the key itself; any other text is a passphrase whose
    /// SHA-256 is the key (as MAVProxy's `signing setup` and QGroundControl derive it).
    pub fn parse(text: &str) -> Result<Key, String> {
        let t = text.trim();
        if t.is_empty() {
            return Err("an empty signing key".into());
        }
        if t.len() == 64 && t.bytes().all(|b| b.is_ascii_hexdigit()) {
            let mut k = [0u8; 32];
            for (i, byte) in k.iter_mut().enumerate() {
                *byte = u8::from_str_radix(&t[2 * i..2 * i + 2], 16).map_err(|e| e.to_string())?;
            }
            return Ok(Key(k));
        }
        Ok(Key(Sha256::digest(t.as_bytes()).into()))
    }
}

/// Why a frame was refused by the signing check.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Refusal {
    /// No signature (or a MAVLink 1 frame) on a link that requires one.
    Unsigned,
    /// A signature that does not match the key.
    BadSignature,
    /// A timestamp not after the stream's last one (a replay), or a new stream too old.
    OldTimestamp,
}

/// The signing state of one link.
#[derive(Debug)]
pub struct Signing {
    key: Key,
    /// The link id put on what we send.
    link_id: u8,
    streams: HashMap<(u8, u32, u8), u64>,
    newest: u64,
    sent: u64,
}

/// The 48-bit signature of `signed` (a frame from its start byte up to and including the
/// timestamp).
fn signature(key: &Key, signed: &[u8]) -> [u8; 6] {
    let mut h = Sha256::new();
    h.update(key.0);
    h.update(signed);
    let d = h.finalize();
    [d[0], d[1], d[2], d[3], d[4], d[5]]
}

impl Signing {
    pub fn new(key: Key, link_id: u8) -> Signing {
        Signing { key, link_id, streams: HashMap::new(), newest: 0, sent: 0 }
    }

    /// Checks a whole MAVLink 2 frame whose CRC is good. `frame` ends with the signature
    /// when `signed`.
    pub fn verify(
        &mut self,
        frame: &[u8],
        signed: bool,
        system: u32,
        component: u8,
    ) -> Result<(), Refusal> {
        if !signed || frame.len() < SIGNATURE_LEN {
            return Err(Refusal::Unsigned);
        }
        let at = frame.len() - SIGNATURE_LEN;
        let link = frame[at];
        let mut ts = [0u8; 8];
        ts[..6].copy_from_slice(&frame[at + 1..at + 7]);
        let timestamp = u64::from_le_bytes(ts);
        if signature(&self.key, &frame[..at + 7]) != frame[at + 7..] {
            return Err(Refusal::BadSignature);
        }
        let stream = (link, system, component);
        match self.streams.get(&stream) {
            Some(last) if timestamp <= *last => return Err(Refusal::OldTimestamp),
            None if timestamp + NEW_STREAM_SLACK < self.newest => {
                return Err(Refusal::OldTimestamp);
            }
            None if self.streams.len() >= MAX_STREAMS => {
                // Forget the stream heard longest ago.
                if let Some(oldest) = self.streams.iter().min_by_key(|(_, t)| **t).map(|(k, _)| *k)
                {
                    self.streams.remove(&oldest);
                }
            }
            _ => {}
        }
        self.streams.insert(stream, timestamp);
        self.newest = self.newest.max(timestamp);
        Ok(())
    }

    /// Signs an unsigned MAVLink 2 frame in place: sets the SIGNED flag, recomputes the CRC
    /// with the message's `extra_crc`, and appends link id, timestamp and signature. `now` is
    /// the time in 10 µs units since 2015-01-01; timestamps never go backwards.
    pub fn sign(&mut self, frame: &mut Vec<u8>, extra_crc: u8, now: u64) {
        if frame.len() < 12 || frame[0] != 0xFD {
            return;
        }
        frame[2] |= crate::decode::IFLAG_SIGNED;
        let crc_at = frame.len() - 2;
        let crc = mavlink::calculate_crc(&frame[1..crc_at], extra_crc);
        frame[crc_at..].copy_from_slice(&crc.to_le_bytes());
        self.sent = (self.sent + 1).max(now).max(self.newest);
        frame.push(self.link_id);
        frame.extend_from_slice(&self.sent.to_le_bytes()[..6]);
        let sig = signature(&self.key, frame);
        frame.extend_from_slice(&sig);
    }
}

/// A signing timestamp: 10 µs units since 2015-01-01 00:00 UTC (1420070400 s after the
/// Unix epoch). The link reads the time of day from the DataServer's clock.
pub fn timestamp(wall: std::time::SystemTime) -> u64 {
    let unix = wall.duration_since(std::time::UNIX_EPOCH).unwrap_or_default();
    (unix.as_micros() as u64 / 10).saturating_sub(1_420_070_400 * 100_000)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sixty_four_hex_digits_are_the_key_and_other_text_is_a_passphrase() {
        let hex = "00".repeat(31) + "ff";
        assert_eq!(Key::parse(&hex).unwrap().0[31], 0xff);
        let k = Key::parse("secret").unwrap();
        assert_eq!(k.0, <[u8; 32]>::from(Sha256::digest(b"secret")));
        assert!(Key::parse("  ").is_err());
    }
}
