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

/// The batch being gathered, in its columns as they are written (little endian): an entry
/// is three stores, and the message is the columns copied one after the other.
#[derive(Default)]
pub(crate) struct Batch {
    first_seq: u64,
    first_ns: u64,
    len: usize,
    ids: Vec<u8>,
    dts: Vec<u8>,
    values: Vec<u8>,
    /// Each entry's number less `first_seq`, kept only once an entry is not the one after
    /// the one before (`consecutive` false; filled in for those before then).
    seqs: Vec<u8>,
    /// Each entry's kind, kept only once an entry is not a float (`floats` false).
    kinds: Vec<u8>,
    consecutive: bool,
    floats: bool,
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

    fn start(&mut self, seq: u64, t: u64) {
        self.first_seq = seq;
        self.first_ns = t;
        self.consecutive = true;
        self.floats = true;
    }

    /// Adds an entry (call [`Batch::fits`] first).
    pub fn push(&mut self, id: u32, seq: u64, t: u64, kind: u8, value: f64) {
        if self.is_empty() {
            self.start(seq, t);
        }
        self.entry(id, seq, t, kind, value);
    }

    fn entry(&mut self, id: u32, seq: u64, t: u64, kind: u8, value: f64) {
        let off = seq.wrapping_sub(self.first_seq) as u32;
        if self.consecutive && off as usize != self.len {
            self.consecutive = false;
            self.seqs.extend((0..self.len as u32).flat_map(u32::to_le_bytes));
        }
        if !self.consecutive {
            self.seqs.extend_from_slice(&off.to_le_bytes());
        }
        if self.floats && kind != FLOAT {
            self.floats = false;
            self.kinds.resize(self.len, FLOAT);
        }
        if !self.floats {
            self.kinds.push(kind);
        }
        let dt = t.saturating_sub(self.first_ns) as u32;
        self.ids.extend_from_slice(&id.to_le_bytes());
        self.dts.extend_from_slice(&dt.to_le_bytes());
        self.values.extend_from_slice(&value.to_le_bytes());
        self.len += 1;
    }

    pub fn len(&self) -> usize {
        self.len
    }

    /// Adds a run of entries from the feed's numeric lane, property `n.id` as the recording's
    /// `ids[n.id]` (call [`Batch::fits`] for its last entry first: numbers and stamps grow
    /// along a run). One pass storing three columns; `seq` and `kind` only when needed.
    pub fn extend(&mut self, run: &[Numeric], ids: &[u32]) {
        let (Some(first), Some(last)) = (run.first(), run.last()) else { return };
        if self.is_empty() {
            self.start(first.seq, first.ns);
        }
        let (seq0, ns0, len) = (self.first_seq, self.first_ns, self.len);
        // Numbers grow along a run: its entries follow on from the batch's one by one when
        // its first and last numbers say so.
        let consecutive = first.seq.wrapping_sub(seq0) as usize == len
            && last.seq.wrapping_sub(seq0) as usize == len + run.len() - 1;
        if !(consecutive && self.consecutive) {
            if self.consecutive {
                self.consecutive = false;
                self.seqs.extend((0..len as u32).flat_map(u32::to_le_bytes));
            }
            let offs = grow(&mut self.seqs, 4 * run.len());
            for (n, o) in run.iter().zip(offs.chunks_exact_mut(4)) {
                o.copy_from_slice(&(n.seq.wrapping_sub(seq0) as u32).to_le_bytes());
            }
        }
        let floats = run.iter().all(|n| n.kind == NumKind::Float);
        if !(floats && self.floats) {
            if self.floats {
                self.floats = false;
                self.kinds.resize(len, FLOAT);
            }
            self.kinds.extend(run.iter().map(|n| match n.kind {
                NumKind::Float => FLOAT,
                NumKind::Int => INT,
                NumKind::Bool => BOOL,
            }));
        }
        let id_col = grow(&mut self.ids, 4 * run.len());
        for (n, o) in run.iter().zip(id_col.chunks_exact_mut(4)) {
            o.copy_from_slice(&ids[n.id as usize].to_le_bytes());
        }
        let dt_col = grow(&mut self.dts, 4 * run.len());
        for (n, o) in run.iter().zip(dt_col.chunks_exact_mut(4)) {
            o.copy_from_slice(&(n.ns.saturating_sub(ns0) as u32).to_le_bytes());
        }
        let value_col = grow(&mut self.values, 8 * run.len());
        for (n, o) in run.iter().zip(value_col.chunks_exact_mut(8)) {
            let bits = match n.kind {
                NumKind::Float => n.bits,
                NumKind::Int => (n.bits as i64 as f64).to_bits(),
                NumKind::Bool => (n.bits as f64).to_bits(),
            };
            o.copy_from_slice(&bits.to_le_bytes());
        }
        self.len += run.len();
    }

    /// The batch as one CDR message (little endian) into `out`; the batch is emptied.
    pub fn encode(&mut self, out: &mut Vec<u8>) {
        let n = self.len;
        out.clear();
        out.reserve(48 + n * 21);
        let mut c = Cdr::start(out);
        c.u64(self.first_seq);
        c.u64(self.first_ns);
        c.len(n);
        c.0.extend_from_slice(&self.ids);
        c.len(self.seqs.len() / 4);
        c.0.extend_from_slice(&self.seqs);
        c.len(n);
        c.0.extend_from_slice(&self.dts);
        c.len(self.kinds.len());
        c.0.extend_from_slice(&self.kinds);
        c.len(n);
        c.align(8);
        c.0.extend_from_slice(&self.values);
        self.len = 0;
        for column in [&mut self.ids, &mut self.dts, &mut self.values, &mut self.seqs] {
            column.clear();
        }
        self.kinds.clear();
    }
}

/// `column` grown by `n` bytes; the new bytes, to fill.
fn grow(column: &mut Vec<u8>, n: usize) -> &mut [u8] {
    let at = column.len();
    column.resize(at + n, 0);
    &mut column[at..]
}

#[cfg(test)]
mod tests {
    use super::*;
    use mocu_value::Value;

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
    fn runs_from_the_lane_encode_as_the_same_entries_pushed_one_by_one() {
        let n = |seq, ns, id, kind, bits| Numeric { seq, ns, bits, id, kind };
        let f = |x: f64| x.to_bits();
        let ids = [0, 10, 11, 12];
        let runs = [
            vec![n(5, 100, 1, NumKind::Float, f(1.5)), n(6, 110, 2, NumKind::Float, f(2.5))],
            vec![n(7, 120, 3, NumKind::Float, f(-1.0))],
            vec![n(9, 130, 1, NumKind::Int, (-7i64) as u64), n(10, 140, 2, NumKind::Bool, 1)],
            vec![n(11, 150, 3, NumKind::Float, f(0.25))],
        ];
        // Consecutive floats, then a gap in the numbers and other kinds: each column as
        // pushing the same entries lays it out.
        for upto in 1..=runs.len() {
            let (mut a, mut b) = (Batch::default(), Batch::default());
            for run in &runs[..upto] {
                a.extend(run, &ids);
                for e in run {
                    let v = Value::Float(f64::from_bits(e.bits));
                    let (kind, x) = match e.kind {
                        NumKind::Float => numeric(&v).unwrap(),
                        NumKind::Int => (INT, e.bits as i64 as f64),
                        NumKind::Bool => (BOOL, e.bits as f64),
                    };
                    b.push(ids[e.id as usize], e.seq, e.ns, kind, x);
                }
            }
            assert_eq!(a.len(), b.len());
            let (mut ea, mut eb) = (Vec::new(), Vec::new());
            a.encode(&mut ea);
            b.encode(&mut eb);
            assert_eq!(ea, eb, "after {upto} runs");
        }
    }

    #[test]
    fn only_integers_a_float64_holds_exactly_go_in_a_batch() {
        assert_eq!(numeric(&Value::Int(1 << 53)), Some((INT, 9_007_199_254_740_992.0)));
        assert_eq!(numeric(&Value::Int((1 << 53) + 1)), None);
        assert_eq!(numeric(&Value::str("x")), None);
    }
}
