//! Object trees from recordings are rebuilt without recursion: a chain 100,000 deep
//! replays (created, then deleted), and many siblings replay with one lookup each of the
//! replay's own map (`World::taken`; DataServer::find_child still scans the parent's
//! children by name, so siblings cost that scan each).

use mcap::records::MessageHeader;
use mocu_replay::Player;
use std::collections::BTreeMap;
use std::path::Path;

/// A chain that would overflow a recursive rebuild; siblings kept few enough for a debug
/// build (see the module's note on find_child).
const DEEP: u64 = 100_000;
const WIDE: u64 = 3_000;

const START_NS: u64 = 1_763_875_200_000_000_000;

/// Objects 2..2+n, each under `parent(k)`; then object 2 deleted at one second.
fn write(path: &Path, n: u64, parent: impl Fn(u64) -> u64) {
    let f = std::fs::File::create(path).unwrap();
    let opts = mcap::WriteOptions::new().compression(None).profile("mocu");
    let mut w = opts.create(std::io::BufWriter::new(f)).unwrap();
    let meta = BTreeMap::from([
        ("format".to_string(), "1".to_string()),
        ("start_ns".to_string(), START_NS.to_string()),
    ]);
    w.write_metadata(&mcap::records::Metadata { name: "mocu".into(), metadata: meta }).unwrap();
    let none = BTreeMap::new();
    let s = w.add_schema("mocu.ObjectChange", "jsonschema", b"{}").unwrap();
    let objects = w.add_channel(s, "/world/object", "json", &none).unwrap();
    let mut seq = 0;
    let mut put = |w: &mut mcap::Writer<_>, log_time: u64, data: String| {
        seq += 1;
        let h =
            MessageHeader { channel_id: objects, sequence: seq, log_time, publish_time: log_time };
        w.write_to_known_channel(&h, data.as_bytes()).unwrap();
    };
    for k in 2..2 + n {
        let p = if k == 2 { 1 } else { parent(k) };
        put(
            &mut w,
            START_NS,
            format!(
                r#"{{"op":"created","guid":{k},"parent":{p},"index":0,"name":"o{k}","type":"thing"}}"#
            ),
        );
    }
    put(&mut w, START_NS + 1_000_000_000, r#"{"op":"deleted","guid":2}"#.to_string());
    w.finish().unwrap();
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
