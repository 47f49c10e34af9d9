//! Object trees from recordings are rebuilt without recursion: a chain 100,000 deep
//! replays (created, then deleted), and many siblings replay with one lookup each of the
//! replay's own map (`World::taken`; DataServer::find_child still scans the parent's
//! children by name, so siblings cost that scan each).

mod support;

use mocu_replay::Player;
use std::path::Path;
use support::{Format1, START_NS};

/// A chain that would overflow a recursive rebuild; siblings kept few enough for a debug
/// build (see the module's note on find_child).
const DEEP: u64 = 100_000;
const WIDE: u64 = 3_000;

/// Objects 2..2+n, each under `parent(k)`; then object 2 deleted at one second.
fn write(path: &Path, n: u64, parent: impl Fn(u64) -> u64) {
    let mut w = Format1::create(path);
    let objects = w.objects;
    for k in 2..2 + n {
        let p = if k == 2 { 1 } else { parent(k) };
        w.put(
            objects,
            START_NS,
            &format!(
                r#"{{"op":"created","guid":{k},"parent":{p},"index":0,"name":"o{k}","type":"thing"}}"#
            ),
        );
    }
    w.put(objects, START_NS + 1_000_000_000, r#"{"op":"deleted","guid":2}"#);
    w.finish();
}

fn replay(n: u64, parent: impl Fn(u64) -> u64) {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("t.mcap");
    write(&path, n, parent);
    let mut p = Player::open(&path).unwrap();
    p.advance_to(START_NS).unwrap();
    let built = p.ds().resolve(&["o2"]).is_some();
    assert!(built, "the tree was not rebuilt");
    p.advance_to(p.end_ns()).unwrap();
    assert!(p.ds().resolve(&["o2"]).is_none(), "the tree was not deleted");
}

#[test]
fn a_chain_100000_deep_is_rebuilt_and_deleted_without_overflowing_the_stack() {
    replay(DEEP, |k| k - 1);
}

#[test]
fn thousands_of_siblings_are_rebuilt_and_deleted() {
    replay(WIDE, |_| 2);
}
