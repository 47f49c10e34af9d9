//! A degraded link for tests: a UDP relay between a sender (ffmpeg) and Mocu's receiver
//! that drops, reorders and truncates datagrams, deciding with a seeded random generator
//! (the same seed makes the same decisions for the same packets). It counts the frames
//! the sender sent (distinct RTP timestamps) and the frames that reached the receiver
//! with at least one packet.

use std::collections::HashSet;
use std::net::{SocketAddr, UdpSocket};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};
use std::thread::JoinHandle;
use std::time::Duration;

/// SplitMix64: a small, well-mixed generator for test decisions.
#[derive(Clone, Debug)]
pub struct Rng(u64);

impl Rng {
    pub fn new(seed: u64) -> Rng {
        Rng(seed)
    }

    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    }

    /// True with probability `p`.
    pub fn chance(&mut self, p: f64) -> bool {
        ((self.next_u64() >> 11) as f64 / (1u64 << 53) as f64) < p
    }

    /// A number in `0..n` (n > 0).
    pub fn below(&mut self, n: usize) -> usize {
        (self.next_u64() % n as u64) as usize
    }
}

/// What the link does to each datagram.
#[derive(Clone, Copy, Debug, Default)]
pub struct Impairment {
    /// Probability that a datagram is lost.
    pub loss: f64,
    /// Probability that a datagram is held back and sent after the next 1–3.
    pub reorder: f64,
    /// Probability that a datagram is cut to a random shorter length (at least 12 bytes).
    pub truncate: f64,
    pub seed: u64,
    /// Pass the first frame (up to its RTP marker bit) untouched: the stream's first key
    /// frame (a receiver shows nothing before a whole sequence parameter set and IDR,
    /// whatever the link).
    pub clean_first_frame: bool,
}

/// What went through.
#[derive(Clone, Debug, Default)]
pub struct RelayCounts {
    pub datagrams: u64,
    pub lost: u64,
    pub reordered: u64,
    pub truncated: u64,
    /// Frames the sender sent (distinct RTP timestamps).
    pub frames_sent: u64,
    /// Frames of which at least one datagram was forwarded.
    pub frames_reached: u64,
}

/// A running relay; stops when dropped.
pub struct Relay {
    /// Where the sender should send.
    pub port: u16,
    stop: Arc<AtomicBool>,
    counts: Arc<Mutex<RelayCounts>>,
    thread: Option<JoinHandle<()>>,
}

impl Relay {
    pub fn start(to: u16, imp: Impairment) -> Relay {
        let sock = UdpSocket::bind("127.0.0.1:0").unwrap();
        sock.set_read_timeout(Some(Duration::from_millis(20))).unwrap();
        let port = sock.local_addr().unwrap().port();
        let stop = Arc::new(AtomicBool::new(false));
        let counts = Arc::new(Mutex::new(RelayCounts::default()));
        let (stop2, counts2) = (stop.clone(), counts.clone());
        let dest: SocketAddr = format!("127.0.0.1:{to}").parse().unwrap();
        let thread = std::thread::spawn(move || run(sock, dest, imp, &stop2, &counts2));
        Relay { port, stop, counts, thread: Some(thread) }
    }

    /// Stops forwarding (what is held back is sent) and returns the counts.
    pub fn finish(mut self) -> RelayCounts {
        self.stop.store(true, Ordering::SeqCst);
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
        self.counts.lock().unwrap().clone()
    }
}

impl Drop for Relay {
    fn drop(&mut self) {
        self.stop.store(true, Ordering::SeqCst);
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}

fn run(
    sock: UdpSocket,
    dest: SocketAddr,
    imp: Impairment,
    stop: &AtomicBool,
    counts: &Mutex<RelayCounts>,
) {
    let mut rng = Rng::new(imp.seed);
    let mut buf = vec![0u8; 65536];
    // Held-back datagrams with how many others must pass first.
    let mut held: Vec<(usize, Vec<u8>)> = Vec::new();
    let (mut sent_ts, mut reached_ts) = (HashSet::new(), HashSet::new());
    let mut first_frame_done = false;
    let ts = |d: &[u8]| (d.len() >= 12).then(|| u32::from_be_bytes([d[4], d[5], d[6], d[7]]));
    while !stop.load(Ordering::SeqCst) {
        let Ok((n, _)) = sock.recv_from(&mut buf) else { continue };
        let mut d = buf[..n].to_vec();
        let mut c = counts.lock().unwrap();
        c.datagrams += 1;
        sent_ts.extend(ts(&d));
        // Decisions are drawn in a fixed order for every datagram.
        let (lose, delay, cut) =
            (rng.chance(imp.loss), rng.chance(imp.reorder), rng.chance(imp.truncate));
        let (k, len) = (1 + rng.below(3), 12 + rng.below(d.len().saturating_sub(12).max(1)));
        let (lose, delay, cut) = if imp.clean_first_frame && !first_frame_done {
            first_frame_done = d.get(1).is_some_and(|b| b & 0x80 != 0);
            (false, false, false)
        } else {
            (lose, delay, cut)
        };
        if lose {
            c.lost += 1;
            continue;
        }
        if cut && len < d.len() {
            d.truncate(len);
            c.truncated += 1;
        }
        reached_ts.extend(ts(&d));
        if delay {
            c.reordered += 1;
            held.push((k, d));
            continue;
        }
        let _ = sock.send_to(&d, dest);
        for h in held.iter_mut() {
            h.0 -= 1;
        }
        for (_, h) in held.extract_if(.., |h| h.0 == 0) {
            let _ = sock.send_to(&h, dest);
        }
        c.frames_sent = sent_ts.len() as u64;
        c.frames_reached = reached_ts.len() as u64;
    }
    for (_, h) in held {
        let _ = sock.send_to(&h, dest);
    }
    let mut c = counts.lock().unwrap();
    c.frames_sent = sent_ts.len() as u64;
    c.frames_reached = reached_ts.len() as u64;
}
