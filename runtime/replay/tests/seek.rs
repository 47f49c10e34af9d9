//! Seeking: the world at a trial time is the same whether the replay jumps there (the last
//! keyframe before it, then the changes after it) or plays there from the start, and the
//! same with or without keyframes.

mod support;

use mocu_replay::Player;
use support::{Synthetic, value, write};

const SMALL: Synthetic =
    Synthetic { seconds: 30, vehicles: 3, props: 4, hz: 10, keyframe_secs: 10, batch_steps: 0 };

/// As the recorder writes them: `/world/values` batches of three steps (0.3 s), so that
/// seeks and reads ahead fall inside batches.
const BATCHED: Synthetic = Synthetic { batch_steps: 3, ..SMALL };

/// `usv{v}.p{k}` in the replayed world.
fn prop(p: &Player, v: u64, k: u64) -> Option<f64> {
    let ds = p.ds();
    let g = ds.resolve(&["vehicles", &format!("usv{v}")])?;
    ds.try_get(g, format!("p{k}").as_str().into())?.as_f64()
}

fn world(p: &Player) -> Vec<Option<f64>> {
    (0..SMALL.vehicles)
        .flat_map(|v| (0..SMALL.props).map(move |k| (v, k)))
        .map(|(v, k)| prop(p, v, k))
        .collect()
}

#[test]
fn seeking_gives_the_world_that_playing_there_gives() {
    seeking_gives_the_world_that_playing_there_gives_in(SMALL);
}

#[test]
fn seeking_gives_the_world_that_playing_there_gives_with_values_in_batches() {
    seeking_gives_the_world_that_playing_there_gives_in(BATCHED);
}

fn seeking_gives_the_world_that_playing_there_gives_in(format: Synthetic) {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("trial.mcap");
    write(&path, format);
    for secs in [0.05, 9.95, 10.0, 12.34, 25.0, 30.0] {
        let mut played = Player::open(&path).unwrap();
        let t = played.at_secs(secs);
        played.advance_to(t).unwrap();
        let mut jumped = Player::open(&path).unwrap();
        jumped.seek(t).unwrap();
        assert_eq!(world(&jumped), world(&played), "at {secs} s");
        let step = (secs * SMALL.hz as f64 + 1e-9).floor() as u64;
        assert_eq!(prop(&jumped, 2, 3), Some(value(step, 3)), "at {secs} s");
    }
}

#[test]
fn seeking_back_and_forth_ends_where_a_fresh_seek_ends() {
    for format in [SMALL, BATCHED] {
        seeking_back_and_forth_ends_where_a_fresh_seek_ends_in(format);
    }
}

fn seeking_back_and_forth_ends_where_a_fresh_seek_ends_in(format: Synthetic) {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("trial.mcap");
    write(&path, format);
    let mut p = Player::open(&path).unwrap();
    for secs in [25.0, 3.0, 28.5, 11.2] {
        let t = p.at_secs(secs);
        p.seek(t).unwrap();
    }
    let mut fresh = Player::open(&path).unwrap();
    fresh.seek(fresh.at_secs(11.2)).unwrap();
    assert_eq!(world(&p), world(&fresh));
    assert_eq!(prop(&p, 0, 0), Some(value(112, 0)));
}

#[test]
fn a_recording_without_keyframes_seeks_by_playing_its_changes() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("trial.mcap");
    for format in [SMALL, BATCHED] {
        write(&path, Synthetic { keyframe_secs: 0, ..format });
        let mut p = Player::open(&path).unwrap();
        p.seek(p.at_secs(21.0)).unwrap();
        assert_eq!(prop(&p, 1, 2), Some(value(210, 2)));
    }
}

#[test]
fn a_recording_cut_short_replays_up_to_its_last_complete_chunk() {
    let dir = tempfile::tempdir().unwrap();
    let (whole, cut) = (dir.path().join("trial.mcap"), dir.path().join("cut.mcap"));
    write(&whole, Synthetic { seconds: 120, ..SMALL });
    let bytes = std::fs::read(&whole).unwrap();
    std::fs::write(&cut, &bytes[..bytes.len() * 3 / 5]).unwrap();
    let mut p = Player::open(&cut).unwrap();
    assert!(!p.recording().indexed(), "a killed recorder leaves no summary");
    let last = (p.end_ns() - p.start_ns()) as f64 / 1e9;
    assert!(last > 30.0 && last < 120.0, "{last} s kept");
    p.seek(p.at_secs(25.0)).unwrap();
    assert_eq!(prop(&p, 2, 1), Some(value(250, 1)));
}
