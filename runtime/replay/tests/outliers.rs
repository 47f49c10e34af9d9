//! Log times far outside what a recording spans (a flipped bit, a crafted file) cannot make
//! a replay endless: a message outside its chunk's stated time range is dropped, and a trial
//! lasts at most `MAX_TRIAL` from its start (docs/recording.md, "Damaged recordings").

mod support;

use mocu_replay::{BEFORE_START_NS, MAX_TRIAL_NS, Player};
use std::path::Path;
use support::{Format1, START_NS};

/// usv0.speed set to 1.0 at one second, then `outlier` sets it to 9.0 at `outlier_at`.
fn write(path: &Path, outlier_at: u64, summary: bool) {
    let mut w = Format1::create(path);
    let (objects, props) = (w.objects, w.props);
    let mut put = |channel, log_time, data: &str| w.put(channel, log_time, data);
    put(
        objects,
        START_NS,
        r#"{"op":"created","guid":2,"parent":1,"index":0,"name":"vehicles","type":"vehicles"}"#,
    );
    put(
        objects,
        START_NS,
        r#"{"op":"created","guid":3,"parent":2,"index":0,"name":"usv0","type":"vehicle"}"#,
    );
    put(
        props,
        START_NS,
        r#"{"op":"created","object":3,"name":"speed","kind":"float","value":0.0}"#,
    );
    put(
        props,
        START_NS + 1_000_000_000,
        r#"{"op":"set","object":3,"name":"speed","kind":"float","value":1.0}"#,
    );
    put(props, outlier_at, r#"{"op":"set","object":3,"name":"speed","kind":"float","value":9.0}"#);
    w.finish();
    if !summary {
        // As a killed recorder leaves it: the data only, read linearly.
        let bytes = std::fs::read(path).unwrap();
        let start = u64::from_le_bytes(bytes[bytes.len() - 28..][..8].try_into().unwrap());
        std::fs::write(path, &bytes[..start as usize]).unwrap();
    }
}

fn speed(p: &Player) -> Option<f64> {
    let g = p.ds().resolve(&["vehicles", "usv0"])?;
    p.ds().try_get(g, "speed".into())?.as_f64()
}

fn replay_whole(outlier_at: u64, summary: bool) -> (Player, u64) {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("t.mcap");
    write(&path, outlier_at, summary);
    let mut p = Player::open(&path).unwrap();
    assert_eq!(p.recording().indexed(), summary);
    let end = p.end_ns();
    p.advance_to(end).unwrap();
    (p, end)
}

#[test]
fn a_message_logged_at_the_end_of_time_is_dropped_and_the_trial_ends() {
    for summary in [true, false] {
        let (p, end) = replay_whole(u64::MAX, summary);
        assert!(end <= START_NS + MAX_TRIAL_NS, "summary {summary}: ends at {end}");
        assert_eq!(speed(&p), Some(1.0), "summary {summary}");
        assert_eq!(p.start_ns(), START_NS);
    }
}

#[test]
fn a_message_logged_before_the_recording_started_does_not_stretch_the_trial_back() {
    for summary in [true, false] {
        let (p, _) = replay_whole(1, summary);
        let start = p.start_ns();
        assert!(start >= START_NS - BEFORE_START_NS, "summary {summary}: starts at {start}");
        assert_eq!(speed(&p), Some(1.0), "summary {summary}");
    }
}

#[test]
fn a_message_within_the_longest_trial_is_replayed_at_its_time_without_stepping_through_the_gap() {
    let at = START_NS + MAX_TRIAL_NS - 1;
    for summary in [true, false] {
        let (p, end) = replay_whole(at, summary);
        assert_eq!(end, at, "summary {summary}");
        assert_eq!(speed(&p), Some(9.0), "summary {summary}");
    }
}
