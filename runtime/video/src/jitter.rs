//! The reorder (jitter) buffer in front of the RTP depacketizers: radios and Wi-Fi deliver
//! packets out of order, and a depacketizer that takes them as they come throws a frame
//! away for every swap. Packets are held by their RTP sequence number (extended past the
//! 16-bit wrap-around) and handed on in order; a missing one is waited for until `window`
//! packets are held or the oldest has waited `max_delay`, then given up as lost.
//!
//! A jump of the sequence number by more than [`RESTART_GAP`] either way is not loss but a
//! **restart** of the sender (ffmpeg or a camera started again with the same SSRC): what is
//! held is handed on, counted, and the caller starts its depacketizer afresh.

use std::collections::BTreeMap;
use std::time::{Duration, Instant};

/// A sequence jump (either way) larger than this is a restart of the stream.
pub const RESTART_GAP: i32 = 1000;

/// Counts of a reorder buffer.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct ReorderStats {
    /// Packets that arrived after a later one and were put back in order.
    pub reordered: u64,
    /// Duplicates, and packets that came after their place was given up.
    pub late: u64,
    /// Restarts of the stream (sequence jumps).
    pub restarts: u64,
}

/// What [`Reorder::push`] saw.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Pushed {
    Held,
    Late,
    /// The stream restarted: what was held is handed on, and this datagram is **not**
    /// taken; push it again once the depacketizer has started afresh.
    Restart,
}

/// Holds datagrams by extended sequence number and releases them in order.
#[derive(Debug)]
pub struct Reorder {
    window: usize,
    max_delay: Duration,
    /// The extended sequence number expected next.
    next: Option<i64>,
    highest: i64,
    held: BTreeMap<i64, (Instant, Vec<u8>)>,
    pub stats: ReorderStats,
}

impl Reorder {
    /// `window` packets at most are held (1: no reordering); a gap is waited for
    /// `max_delay` at most.
    pub fn new(window: usize, max_delay: Duration) -> Reorder {
        Reorder {
            window: window.max(1),
            max_delay,
            next: None,
            highest: 0,
            held: BTreeMap::new(),
            stats: ReorderStats::default(),
        }
    }

    /// Takes the datagram with sequence number `seq`; `out` gets every datagram that can
    /// go on now, in order.
    pub fn push(
        &mut self,
        seq: u16,
        now: Instant,
        datagram: &[u8],
        out: &mut dyn FnMut(&[u8]),
    ) -> Pushed {
        let Some(next) = self.next else {
            self.next = Some(seq as i64);
            self.highest = seq as i64;
            out(datagram);
            self.next = Some(seq as i64 + 1);
            return Pushed::Held;
        };
        let delta = seq.wrapping_sub(next as u16) as i16 as i32;
        if delta.abs() > RESTART_GAP {
            self.drain(out);
            self.stats.restarts += 1;
            self.next = None;
            return Pushed::Restart;
        }
        let ext = next + delta as i64;
        if delta < 0 || self.held.contains_key(&ext) {
            self.stats.late += 1;
            return Pushed::Late;
        }
        if ext < self.highest {
            self.stats.reordered += 1;
        }
        self.highest = self.highest.max(ext);
        self.held.insert(ext, (now, datagram.to_vec()));
        self.release(now, out);
        Pushed::Held
    }

    /// Releases what is due at `now` (a gap waited for long enough).
    pub fn release(&mut self, now: Instant, out: &mut dyn FnMut(&[u8])) {
        let Some(mut next) = self.next else { return };
        loop {
            if let Some((_, d)) = self.held.remove(&next) {
                out(&d);
                next += 1;
                continue;
            }
            let Some((&first, (t, _))) = self.held.iter().next() else { break };
            let due = now.saturating_duration_since(*t) >= self.max_delay;
            if self.held.len() >= self.window || due {
                next = first; // the packets before it are lost
            } else {
                break;
            }
        }
        self.next = Some(next);
    }

    /// Hands on everything held, in order (gaps given up).
    pub fn drain(&mut self, out: &mut dyn FnMut(&[u8])) {
        let held = std::mem::take(&mut self.held);
        let mut last = None;
        for (k, (_, d)) in held {
            out(&d);
            last = Some(k);
        }
        if let Some(k) = last {
            self.next = Some(k + 1);
        }
    }

    /// How many datagrams are held.
    pub fn held(&self) -> usize {
        self.held.len()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn run(r: &mut Reorder, seqs: &[u16], t: Instant) -> Vec<u16> {
        let mut out = Vec::new();
        for &s in seqs {
            r.push(s, t, &s.to_be_bytes(), &mut |d| out.push(u16::from_be_bytes([d[0], d[1]])));
        }
        out
    }

    #[test]
    fn swapped_packets_come_out_in_order_across_the_wrap() {
        let t = Instant::now();
        let mut r = Reorder::new(4, Duration::from_millis(50));
        let got = run(&mut r, &[65533, 65535, 65534, 1, 0, 2], t);
        assert_eq!(got, vec![65533, 65534, 65535, 0, 1, 2]);
        assert_eq!(r.stats, ReorderStats { reordered: 2, late: 0, restarts: 0 });
    }

    #[test]
    fn a_lost_packet_is_given_up_when_the_window_fills_or_its_time_is_up() {
        let t = Instant::now();
        let mut r = Reorder::new(3, Duration::from_millis(50));
        assert_eq!(run(&mut r, &[10, 12, 13], t), vec![10]);
        assert_eq!(run(&mut r, &[14], t), vec![12, 13, 14], "three held: 11 is lost");
        assert_eq!(run(&mut r, &[11], t), Vec::<u16>::new(), "too late");
        assert_eq!(r.stats.late, 1);
        assert_eq!(run(&mut r, &[16], t), Vec::<u16>::new());
        let mut out = Vec::new();
        r.release(t + Duration::from_millis(50), &mut |d| out.push(d[1]));
        assert_eq!(out, vec![16]);
    }

    #[test]
    fn duplicates_are_late_and_a_big_jump_is_a_restart() {
        let t = Instant::now();
        let mut r = Reorder::new(4, Duration::from_millis(50));
        assert_eq!(run(&mut r, &[100, 101, 101], t), vec![100, 101]);
        assert_eq!(r.stats.late, 1);
        assert_eq!(run(&mut r, &[103], t), Vec::<u16>::new(), "102 is missing");
        let mut out = Vec::new();
        let p = r.push(40000, t, &40000u16.to_be_bytes(), &mut |d| out.push(d.to_vec()));
        assert_eq!((p, out.len(), r.stats.restarts), (Pushed::Restart, 1, 1), "103 handed on");
        assert_eq!(run(&mut r, &[40000, 40001], t), vec![40000, 40001]);
        let p = r.push(5, t, &[0, 5], &mut |_| {});
        assert_eq!((p, r.stats.restarts), (Pushed::Restart, 2), "backwards too");
    }
}
