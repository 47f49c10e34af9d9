//! The times a trial can span (docs/recording.md, "Damaged recordings"): a log time far
//! outside them (a flipped bit, a crafted file) would otherwise make a whole-trial replay
//! step through years of empty time, or never end.

/// The longest trial replayed: a week from its start. Messages logged later are dropped.
pub const MAX_TRIAL_NS: u64 = 7 * 24 * 3600 * 1_000_000_000;

/// How long before the recording's `start_ns` a message may be logged (the recorder's
/// first keyframe and changes carry the start time itself; a clock step may put a few
/// earlier). Earlier ones are dropped.
pub const BEFORE_START_NS: u64 = 60 * 1_000_000_000;

/// The log times kept, first to last: from the recording's start (its `start_ns`, else its
/// first message `first`) to [`MAX_TRIAL_NS`] after.
pub fn window(start_ns: Option<u64>, first: u64) -> (u64, u64) {
    let start = start_ns.unwrap_or(first);
    (start.saturating_sub(BEFORE_START_NS), start.saturating_add(MAX_TRIAL_NS))
}
