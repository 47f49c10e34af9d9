//! `/world/values` (docs/recording.md): the numeric property changes — telemetry, almost
//! all of a busy trial — in batches, one message per batch, CDR-encoded against a ROS 2
//! message definition (`ros2msg`), which Foxglove and every MCAP tool with ROS 2 support
//! read. An entry is 16 bytes (id, time as an offset from the batch's, value) when the batch's
//! changes are numbered one after the other and all floats (the rule in a busy trial: its
//! `seq` and `kind` columns are then empty), 21 otherwise: no formatting, no record and no
//! index entry per change, and nothing for a compressor to do.

use crate::cdr::Cdr;
use mocu_dataserver::{NumKind, Numeric};

/// The schema's name and its `ros2msg` text.
pub(crate) const SCHEMA_NAME: &str = "mocu_msgs/msg/PropertyValues";
pub(crate) const SCHEMA: &str = "\
# Numeric property changes in a batch (docs/recording.md, /world/values).
# Entry i: property id[i] (declared on /world/property or in a /world/snapshot) took
# value[i] (kind[i]: 0 float, 1 int, 2 bool as 0 or 1) in change number
# first_seq + seq[i], at first_ns + dt_ns[i] (ns since the Unix epoch).
# seq empty: seq[i] = i (the changes numbered one after the other).
# kind empty: every entry a float.
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

/// Whether a batch holds integer `i` (a float64 holds it exactly).
pub(crate) fn exact(i: i64) -> bool {
    (-EXACT..=EXACT).contains(&i)
}

/// A value's entry form, for the kinds a batch holds.
pub(crate) fn numeric(v: &mocu_value::Value) -> Option<(u8, f64)> {
    use mocu_value::Value;
    match *v {
        Value::Float(x) => Some((FLOAT, x)),
        Value::Int(i) if exact(i) => Some((INT, i as f64)),
        Value::Bool(b) => Some((BOOL, if b { 1.0 } else { 0.0 })),
        _ => None,
    }
}

/// One entry, as gathered (the batch is laid out in columns when written).
#[derive(Clone, Copy)]
struct Entry {
    id: u32,
    seq: u32,
    dt: u32,
    kind: u8,
    value: f64,
}

/// The batch being gathered.
#[derive(Default)]
pub(crate) struct Batch {
    first_seq: u64,
    first_ns: u64,
    entries: Vec<Entry>,
    /// Whether entry `i` is change `first_seq + i` for every `i` so far.
    consecutive: bool,
    /// Whether every entry so far is a float.
    floats: bool,
}

impl Batch {
    pub fn is_empty(&self) -> bool {
        self.entries.is_empty()
    }

    pub fn first(&self) -> (u64, u64) {
        (self.first_seq, self.first_ns)
    }

    /// Whether an entry numbered `seq` at `t` fits (else: write this batch first).
    pub fn fits(&self, seq: u64, t: u64) -> bool {
        self.is_empty()
            || (self.entries.len() < MAX_ENTRIES
                && seq.wrapping_sub(self.first_seq) <= u64::from(u32::MAX)
                && t.wrapping_sub(self.first_ns) <= u64::from(u32::MAX))
    }

    /// Adds an entry (call [`Batch::fits`] first).
    pub fn push(&mut self, id: u32, seq: u64, t: u64, kind: u8, value: f64) {
        if self.is_empty() {
            self.first_seq = seq;
            self.first_ns = t;
            self.consecutive = true;
            self.floats = true;
        }
        let off = seq.wrapping_sub(self.first_seq) as u32;
        self.consecutive &= off as usize == self.entries.len();
        self.floats &= kind == FLOAT;
        let dt = t.saturating_sub(self.first_ns) as u32;
        self.entries.push(Entry { id, seq: off, dt, kind, value });
    }

    pub fn len(&self) -> usize {
        self.entries.len()
    }

    /// Adds a run of entries from the feed's numeric lane, property `n.id` as the recording's
    /// `ids[n.id]` (call [`Batch::fits`] for its last entry first: numbers and stamps grow
    /// along a run).
    pub fn extend(&mut self, run: &[Numeric], ids: &[u32]) {
        let (Some(first), Some(last)) = (run.first(), run.last()) else { return };
        if self.is_empty() {
            self.first_seq = first.seq;
            self.first_ns = first.ns;
            self.consecutive = true;
            self.floats = true;
        }
        let (seq0, ns0) = (self.first_seq, self.first_ns);
        let last_at = self.entries.len() + run.len() - 1;
        self.consecutive &= last.seq.wrapping_sub(seq0) as usize == last_at
            && first.seq.wrapping_sub(seq0) as usize == self.entries.len();
        self.floats &= run.iter().all(|n| n.kind == NumKind::Float);
        self.entries.extend(run.iter().map(|n| {
            let (kind, value) = match n.kind {
                NumKind::Float => (FLOAT, f64::from_bits(n.bits)),
                NumKind::Int => (INT, n.bits as i64 as f64),
                NumKind::Bool => (BOOL, n.bits as f64),
            };
            let seq = n.seq.wrapping_sub(seq0) as u32;
            let dt = n.ns.saturating_sub(ns0) as u32;
            Entry { id: ids[n.id as usize], seq, dt, kind, value }
        }));
    }

    /// The batch as one CDR message (little endian) into `out`; the batch is emptied.
    pub fn encode(&mut self, out: &mut Vec<u8>) {
        let n = self.entries.len();
        out.clear();
        out.reserve(48 + n * 21);
        let mut c = Cdr::start(out);
        c.u64(self.first_seq);
        c.u64(self.first_ns);
        c.len(n);
        c.0.extend(self.entries.iter().flat_map(|e| e.id.to_le_bytes()));
        c.len(if self.consecutive { 0 } else { n });
        if !self.consecutive {
            c.0.extend(self.entries.iter().flat_map(|e| e.seq.to_le_bytes()));
        }
        c.len(n);
        c.0.extend(self.entries.iter().flat_map(|e| e.dt.to_le_bytes()));
        c.len(if self.floats { 0 } else { n });
        if !self.floats {
            c.0.extend(self.entries.iter().map(|e| e.kind));
        }
        c.len(n);
        c.align(8);
        c.0.extend(self.entries.iter().flat_map(|e| e.value.to_le_bytes()));
        self.entries.clear();
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
        // id[], seq[], dt_ns[]: a length, then the elements (seq: 100 and 102 are not one
        // after the other).
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
    fn a_batch_of_floats_numbered_one_after_the_other_leaves_out_seq_and_kind() {
        let mut b = Batch::default();
        b.push(7, 100, 5_000, FLOAT, 1.5);
        b.push(8, 101, 5_250, FLOAT, 2.5);
        let mut out = Vec::new();
        b.encode(&mut out);
        let u32_at = |i: usize| u32::from_le_bytes(out[i..i + 4].try_into().unwrap());
        assert_eq!((u32_at(20), u32_at(24), u32_at(28)), (2, 7, 8));
        assert_eq!(u32_at(32), 0, "no seq");
        assert_eq!((u32_at(36), u32_at(40), u32_at(44)), (2, 0, 250));
        assert_eq!(u32_at(48), 0, "no kind");
        // value[]: its length, then 8-aligned (offset 52 after the header: 4 bytes of padding).
        assert_eq!(u32_at(52), 2);
        assert_eq!(f64::from_le_bytes(out[60..68].try_into().unwrap()), 1.5);
        assert_eq!(out.len(), 4 + 56 + 16);
    }

    #[test]
    fn only_integers_a_float64_holds_exactly_go_in_a_batch() {
        use mocu_value::Value;
        assert_eq!(numeric(&Value::Int(1 << 53)), Some((INT, 9_007_199_254_740_992.0)));
        assert_eq!(numeric(&Value::Int((1 << 53) + 1)), None);
        assert_eq!(numeric(&Value::str("x")), None);
    }
}
