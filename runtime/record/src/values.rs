//! `/world/values` (docs/recording.md): the numeric property changes — telemetry, almost
//! all of a busy trial — in batches, one message per batch, CDR-encoded against a ROS 2
//! message definition (`ros2msg`), which Foxglove and every MCAP tool with ROS 2 support
//! read. Each entry is 21 bytes (id, change number and time as offsets from the batch's,
//! kind, value) instead of a JSON message of its own: no formatting, no record and no
//! index entry per change.

use crate::cdr::Cdr;

/// The schema's name and its `ros2msg` text.
pub(crate) const SCHEMA_NAME: &str = "mocu_msgs/msg/PropertyValues";
pub(crate) const SCHEMA: &str = "\
# Numeric property changes in a batch (docs/recording.md, /world/values).
# Entry i: property id[i] (declared on /world/property or in a /world/snapshot) took
# value[i] (kind[i]: 0 float, 1 int, 2 bool as 0 or 1) in change number
# first_seq + seq[i], at first_ns + dt_ns[i] (ns since the Unix epoch).
uint64 first_seq
uint64 first_ns
uint32[] id
uint32[] seq
uint32[] dt_ns
uint8[] kind
float64[] value
";

/// `kind[i]` codes.
pub(crate) const FLOAT: u8 = 0;
pub(crate) const INT: u8 = 1;
pub(crate) const BOOL: u8 = 2;

/// Entries at most per message (about 21 bytes each).
pub(crate) const MAX_ENTRIES: usize = 16_384;

/// Integers that go in a batch: those a float64 holds exactly.
const EXACT: i64 = 1 << 53;

/// A value's entry form, for the kinds a batch holds.
pub(crate) fn numeric(v: &mocu_value::Value) -> Option<(u8, f64)> {
    use mocu_value::Value;
    match *v {
        Value::Float(x) => Some((FLOAT, x)),
        Value::Int(i) if (-EXACT..=EXACT).contains(&i) => Some((INT, i as f64)),
        Value::Bool(b) => Some((BOOL, if b { 1.0 } else { 0.0 })),
        _ => None,
    }
}

/// The batch being gathered: its columns as the message lays them out, little endian
/// already, so that writing it is five copies.
#[derive(Default)]
pub(crate) struct Batch {
    first_seq: u64,
    first_ns: u64,
    len: usize,
    id: Vec<u8>,
    seq: Vec<u8>,
    dt: Vec<u8>,
    kind: Vec<u8>,
    value: Vec<u8>,
}

impl Batch {
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    pub fn first(&self) -> (u64, u64) {
        (self.first_seq, self.first_ns)
    }

    /// Whether an entry numbered `seq` at `t` fits (else: write this batch first).
    pub fn fits(&self, seq: u64, t: u64) -> bool {
        self.is_empty()
            || (self.len < MAX_ENTRIES
                && seq.wrapping_sub(self.first_seq) <= u64::from(u32::MAX)
                && t.wrapping_sub(self.first_ns) <= u64::from(u32::MAX))
    }

    /// Adds an entry (call [`Batch::fits`] first).
    pub fn push(&mut self, id: u32, seq: u64, t: u64, kind: u8, value: f64) {
        if self.is_empty() {
            self.first_seq = seq;
            self.first_ns = t;
        }
        self.len += 1;
        self.id.extend_from_slice(&id.to_le_bytes());
        self.seq.extend_from_slice(&(seq.wrapping_sub(self.first_seq) as u32).to_le_bytes());
        self.dt.extend_from_slice(&(t.saturating_sub(self.first_ns) as u32).to_le_bytes());
        self.kind.push(kind);
        self.value.extend_from_slice(&value.to_le_bytes());
    }

    /// The batch as one CDR message (little endian) into `out`; the batch is emptied.
    pub fn encode(&mut self, out: &mut Vec<u8>) {
        out.clear();
        out.reserve(48 + self.len * 21);
        let mut c = Cdr::start(out);
        c.u64(self.first_seq);
        c.u64(self.first_ns);
        for col in [&self.id, &self.seq, &self.dt] {
            c.len(self.len);
            c.0.extend_from_slice(col);
        }
        c.bytes(&self.kind);
        c.len(self.len);
        c.align(8);
        c.0.extend_from_slice(&self.value);
        self.len = 0;
        for col in [&mut self.id, &mut self.seq, &mut self.dt, &mut self.kind, &mut self.value] {
            col.clear();
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_batch_is_laid_out_as_cdr_aligned_from_after_its_header() {
        let mut b = Batch::default();
        b.push(7, 100, 5_000, FLOAT, 1.5);
        b.push(8, 102, 5_250, BOOL, 1.0);
        let mut out = Vec::new();
        b.encode(&mut out);
        let u32_at = |i: usize| u32::from_le_bytes(out[i..i + 4].try_into().unwrap());
        let u64_at = |i: usize| u64::from_le_bytes(out[i..i + 8].try_into().unwrap());
        assert_eq!(&out[..4], &[0, 1, 0, 0]);
        assert_eq!((u64_at(4), u64_at(12)), (100, 5_000));
        // id[], seq[], dt_ns[]: a length, then the elements.
        assert_eq!((u32_at(20), u32_at(24), u32_at(28)), (2, 7, 8));
        assert_eq!((u32_at(32), u32_at(36), u32_at(40)), (2, 0, 2));
        assert_eq!((u32_at(44), u32_at(48), u32_at(52)), (2, 0, 250));
        assert_eq!((u32_at(56), out[60], out[61]), (2, FLOAT, BOOL));
        // value[]: its length at 4-alignment (offset 60 after the header), then 8-aligned.
        assert_eq!(u32_at(64), 2);
        assert_eq!(out.len(), 4 + 64 + 16);
        assert_eq!(f64::from_le_bytes(out[68..76].try_into().unwrap()), 1.5);
        assert!(b.is_empty());
    }

    #[test]
    fn only_integers_a_float64_holds_exactly_go_in_a_batch() {
        use mocu_value::Value;
        assert_eq!(numeric(&Value::Int(1 << 53)), Some((INT, 9_007_199_254_740_992.0)));
        assert_eq!(numeric(&Value::Int((1 << 53) + 1)), None);
        assert_eq!(numeric(&Value::str("x")), None);
    }
}
