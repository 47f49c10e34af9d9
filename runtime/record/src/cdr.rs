//! CDR (little endian), the encoding of ROS 2 messages, written straight into a message
//! buffer: the binary channels (`/world/values`, raw camera frames) are CDR against a
//! `ros2msg` schema, which Foxglove and every MCAP tool with ROS 2 support read.

/// A CDR message being written into a buffer: [`Cdr::start`] clears it and writes the
/// 4-byte encapsulation header; alignment counts from after it.
pub(crate) struct Cdr<'a>(pub &'a mut Vec<u8>);

impl<'a> Cdr<'a> {
    /// Clears `out` and starts a little-endian CDR message in it.
    pub fn start(out: &'a mut Vec<u8>) -> Cdr<'a> {
        out.clear();
        out.extend_from_slice(&[0, 1, 0, 0]);
        Cdr(out)
    }

    pub fn align(&mut self, n: usize) {
        let at = self.0.len() - 4;
        let pad = (n - at % n) % n;
        self.0.resize(self.0.len() + pad, 0);
    }

    pub fn u64(&mut self, x: u64) {
        self.align(8);
        self.0.extend_from_slice(&x.to_le_bytes());
    }

    pub fn i64(&mut self, x: i64) {
        self.align(8);
        self.0.extend_from_slice(&x.to_le_bytes());
    }

    pub fn u32(&mut self, x: u32) {
        self.align(4);
        self.0.extend_from_slice(&x.to_le_bytes());
    }

    /// A sequence's length (the elements follow, each aligned to its size).
    pub fn len(&mut self, n: usize) {
        self.u32(n as u32);
    }

    /// A string: its length with the terminating NUL, its bytes, the NUL.
    pub fn string(&mut self, s: &str) {
        self.len(s.len() + 1);
        self.0.extend_from_slice(s.as_bytes());
        self.0.push(0);
    }

    /// A `uint8[]`: its length, then the bytes as they are (one copy).
    pub fn bytes(&mut self, b: &[u8]) {
        self.len(b.len());
        self.0.extend_from_slice(b);
    }

    /// A `builtin_interfaces/Time` of `t` ns since the Unix epoch (`int32 sec`,
    /// `uint32 nanosec`).
    pub fn time(&mut self, t: u64) {
        self.u32((t / 1_000_000_000).min(i32::MAX as u64) as u32);
        self.u32((t % 1_000_000_000) as u32);
    }
}

#[cfg(test)]
mod tests {
    use super::Cdr;

    #[test]
    fn strings_and_byte_sequences_are_length_prefixed_and_aligned_after_the_header() {
        let mut out = Vec::new();
        let mut c = Cdr::start(&mut out);
        c.string("ab");
        c.bytes(&[7, 8, 9]);
        c.u32(5);
        // "ab\0" (4 + 3), then 4-aligned: 1 pad byte; [7,8,9] (4 + 3), 1 pad; 5.
        assert_eq!(
            out,
            [
                &[0, 1, 0, 0][..],
                &[3, 0, 0, 0, b'a', b'b', 0, 0],
                &[3, 0, 0, 0, 7, 8, 9, 0],
                &[5, 0, 0, 0]
            ]
            .concat()
        );
    }
}
