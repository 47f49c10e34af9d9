//! One monotonic clock for the whole process, so that a packet's arrival time can travel
//! with its frame (as an integer) and be compared where the frame is painted.

use std::sync::OnceLock;
use std::time::Instant;

static EPOCH: OnceLock<Instant> = OnceLock::new();

/// Microseconds since the first call in this process (monotonic).
pub fn now_us() -> i64 {
    let e = *EPOCH.get_or_init(Instant::now);
    e.elapsed().as_micros() as i64
}
