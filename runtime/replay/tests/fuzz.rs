//! A seeded fuzz of the recording reader, run in CI: the real recording `tests/data/trial.mcap`
//! mutated many ways (bit flips, bytes, 64-bit fields set to extremes, cuts), opened and
//! read whole. Nothing panics or aborts: every length the file states is bounded by what the
//! file holds (an allocation of a stated 2^40 or 2^63 bytes would abort the test), and what
//! cannot be read is a `ReplayError`.

use mocu_replay::{Player, Recording};
use std::path::Path;

const SEED: u64 = 0x5eed_0f3c_ab20_2600;
const ITERATIONS: usize = 300;

/// xorshift64*: the same sequence on every run.
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        self.0.wrapping_mul(0x2545_f491_4f6c_dd1d)
    }
    fn below(&mut self, n: usize) -> usize {
        (self.next() % n.max(1) as u64) as usize
    }
}

fn trial() -> Vec<u8> {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../tests/data/trial.mcap");
    std::fs::read(path).expect("tests/data/trial.mcap")
}

/// Extreme values for a 64-bit length, offset or time field.
const EXTREMES: [u64; 6] = [u64::MAX, 1 << 63, 1 << 40, 1 << 35, u32::MAX as u64, 0];

/// An offset to mutate: half of them in the summary and footer (the file's last 9 KiB: the
/// indexes, statistics and offsets), where one changed field reaches the most code.
fn offset(rng: &mut Rng, len: usize) -> usize {
    if rng.below(2) == 0 { len - 1 - rng.below(9000.min(len - 1)) } else { rng.below(len) }
}

fn mutate(rng: &mut Rng, base: &[u8]) -> Vec<u8> {
    let mut b = base.to_vec();
    let n = b.len();
    match rng.below(5) {
        0 => {
            for _ in 0..1 + rng.below(8) {
                let i = offset(rng, n);
                b[i] ^= 1 << rng.below(8);
            }
        }
        1 => {
            let i = offset(rng, n);
            b[i] = rng.next() as u8;
        }
        2 | 3 => {
            // A 64-bit little-endian field set to an extreme, at any offset: hits record,
            // chunk, index, metadata and attachment lengths, offsets and log times.
            let x = EXTREMES[rng.below(EXTREMES.len())];
            let i = offset(rng, n - 8);
            b[i..i + 8].copy_from_slice(&x.to_le_bytes());
        }
        _ => {
            b.truncate(rng.below(n));
            return b;
        }
    }
    // Mostly with the summary's CRC cleared (0: not checked), as a crafted file has it, so
    // that a changed summary is read rather than refused.
    if rng.below(4) != 0 {
        b[n - 12..n - 8].fill(0);
    }
    b
}

/// Everything the replay reads of a recording, read.
fn read_whole(path: &Path) {
    let Ok(mut rec) = Recording::open(path) else { return };
    let (lo, hi) = rec.span();
    let _ = rec.bundle();
    let _ = rec.messages(lo, hi, &["/world/object", "/world/property", "/world/values"]);
    let _ = rec.last_at_or_before("/world/snapshot", hi);
}

#[test]
fn mutated_recordings_are_refused_or_read_never_a_panic_or_an_unbounded_allocation() {
    let base = trial();
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("fuzzed.mcap");
    let mut rng = Rng(SEED);
    for i in 0..ITERATIONS {
        let bytes = mutate(&mut rng, &base);
        std::fs::write(&path, &bytes).unwrap();
        let r = std::panic::catch_unwind(|| read_whole(&path));
        assert!(r.is_ok(), "iteration {i}: reading a mutated recording panicked");
    }
}

#[test]
fn mutated_recordings_open_as_players_without_panicking() {
    let base = trial();
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("fuzzed.mcap");
    let mut rng = Rng(SEED ^ 0x9e37_79b9_7f4a_7c15);
    for i in 0..ITERATIONS / 6 {
        let bytes = mutate(&mut rng, &base);
        std::fs::write(&path, &bytes).unwrap();
        let r = std::panic::catch_unwind(|| {
            if let Ok(mut p) = Player::open(&path) {
                let to = p.at_secs(1.0);
                let _ = p.seek(to);
            }
        });
        assert!(r.is_ok(), "iteration {i}: opening a mutated recording panicked");
    }
}
