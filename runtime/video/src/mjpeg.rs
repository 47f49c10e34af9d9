//! Raw MJPEG over UDP: concatenated JPEG files cut into datagrams anywhere (ffmpeg's
//! `-f mjpeg udp://…`), so frames are found in the byte stream by walking JPEG markers:
//! SOI, marker segments by their lengths, entropy-coded data up to the next marker that
//! is not a stuffed byte or a restart, … EOI.

/// Reassembles JPEG files from a byte stream delivered in pieces.
#[derive(Debug, Default)]
pub struct MjpegReassembler {
    buf: Vec<u8>,
    /// Where parsing resumes in `buf` (inside a frame that started at 0).
    pos: usize,
    in_frame: bool,
    in_scan: bool,
    /// Frames thrown away (malformed, or longer than the limit).
    pub dropped: u64,
    /// Frames emitted.
    pub emitted: u64,
    /// Frames thrown away for being longer than the limit (also in `dropped`).
    pub oversize: u64,
    /// Longest frame kept (0: the default limit).
    max_bytes: usize,
}

impl MjpegReassembler {
    pub fn new() -> MjpegReassembler {
        MjpegReassembler::default()
    }

    /// A reassembler that throws away frames longer than `max_bytes` (and resynchronises
    /// at the next SOI).
    pub fn with_limit(max_bytes: usize) -> MjpegReassembler {
        MjpegReassembler { max_bytes, ..MjpegReassembler::default() }
    }

    /// Appends `data`; `emit` gets every JPEG file completed by it.
    pub fn push(&mut self, data: &[u8], emit: &mut dyn FnMut(Vec<u8>)) {
        self.buf.extend_from_slice(data);
        loop {
            if !self.in_frame {
                match find_soi(&self.buf) {
                    Some(i) => {
                        self.buf.drain(..i);
                        self.in_frame = true;
                        self.in_scan = false;
                        self.pos = 2;
                    }
                    None => {
                        // Keep a possible partial SOI (FF D8 split across datagrams).
                        let keep = self.buf.len().min(2);
                        self.buf.drain(..self.buf.len() - keep);
                        return;
                    }
                }
            }
            match self.walk() {
                Walk::More => {
                    let max = match self.max_bytes {
                        0 => crate::DEFAULT_LIMITS.max_unit_bytes,
                        m => m,
                    };
                    if self.buf.len() > max {
                        self.oversize += 1;
                        self.resync(1);
                    }
                    return;
                }
                Walk::End(end) => {
                    let rest = self.buf.split_off(end);
                    let frame = std::mem::replace(&mut self.buf, rest);
                    self.in_frame = false;
                    self.emitted += 1;
                    emit(frame);
                }
                Walk::Bad(at) => self.resync(at),
            }
        }
    }

    /// Drops the current frame and looks for the next SOI after `at`.
    fn resync(&mut self, at: usize) {
        self.dropped += 1;
        self.buf.drain(..at.min(self.buf.len()));
        self.in_frame = false;
    }

    fn walk(&mut self) -> Walk {
        let b = &self.buf;
        loop {
            if self.in_scan {
                // Entropy-coded data: FF 00 is a stuffed byte, FF D0–D7 a restart marker.
                let mut i = self.pos;
                loop {
                    if i + 1 >= b.len() {
                        self.pos = i;
                        return Walk::More;
                    }
                    if b[i] == 0xff && b[i + 1] != 0 && !(0xd0..=0xd7).contains(&b[i + 1]) {
                        if b[i + 1] == 0xff {
                            i += 1; // fill byte
                            continue;
                        }
                        break;
                    }
                    i += 1;
                }
                self.pos = i;
                self.in_scan = false;
            }
            let i = self.pos;
            if i + 1 >= b.len() {
                return Walk::More;
            }
            if b[i] != 0xff {
                return Walk::Bad(i);
            }
            let m = b[i + 1];
            match m {
                0xff => self.pos += 1,
                0xd9 => return Walk::End(i + 2),
                0xd8 => return Walk::Bad(i), // a new SOI inside a frame: the last was cut
                0x01 | 0xd0..=0xd7 => self.pos += 2,
                _ => {
                    if i + 3 >= b.len() {
                        return Walk::More;
                    }
                    let len = u16::from_be_bytes([b[i + 2], b[i + 3]]) as usize;
                    if len < 2 {
                        return Walk::Bad(i);
                    }
                    if i + 2 + len > b.len() {
                        return Walk::More;
                    }
                    self.pos = i + 2 + len;
                    if m == 0xda {
                        self.in_scan = true;
                    }
                }
            }
        }
    }
}

enum Walk {
    More,
    End(usize),
    Bad(usize),
}

fn find_soi(b: &[u8]) -> Option<usize> {
    b.windows(3).position(|w| w == [0xff, 0xd8, 0xff])
}

/// Whether a datagram carries the start of a JPEG file (raw MJPEG).
pub fn has_soi(d: &[u8]) -> bool {
    find_soi(d).is_some()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A syntactically plausible JPEG: SOI, an APP0 whose body holds FF D9, SOS, entropy
    /// data with a stuffed FF 00 and a restart marker, EOI.
    fn fake(tag: u8) -> Vec<u8> {
        let mut v = vec![0xff, 0xd8, 0xff, 0xe0, 0, 6, 0xff, 0xd9, tag, 0];
        v.extend_from_slice(&[0xff, 0xda, 0, 4, 1, 2]);
        v.extend_from_slice(&[tag, 0xff, 0x00, 7, 0xff, 0xd3, 8, 9]);
        v.extend_from_slice(&[0xff, 0xd9]);
        v
    }

    #[test]
    fn frames_split_anywhere_come_out_whole() {
        let mut stream = vec![1, 2, 3];
        for t in 0..5 {
            stream.extend(fake(t));
        }
        for chunk in [1, 2, 3, 7, 1316] {
            let mut r = MjpegReassembler::new();
            let mut out = Vec::new();
            for c in stream.chunks(chunk) {
                r.push(c, &mut |f| out.push(f));
            }
            assert_eq!(out.len(), 5, "chunk {chunk}");
            for (t, f) in out.iter().enumerate() {
                assert_eq!(f, &fake(t as u8), "chunk {chunk}");
            }
            assert_eq!(r.dropped, 0);
        }
    }

    #[test]
    fn a_cut_frame_is_dropped_and_the_next_one_found() {
        let mut stream = fake(1);
        stream.truncate(17); // cut inside the entropy-coded data
        stream.extend(fake(2));
        let mut r = MjpegReassembler::new();
        let mut out = Vec::new();
        r.push(&stream, &mut |f| out.push(f));
        assert_eq!(out, vec![fake(2)]);
        assert_eq!(r.dropped, 1);
    }
}
