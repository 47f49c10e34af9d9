//! The change feed's numeric lane (`change_feed_numeric`) and muted listeners: what a
//! recorder reads instead of one `Change` per telemetry write, numbered with everything else.
mod common;
use common::{manual, object};
use mocu_dataserver::*;
use std::time::{Duration, SystemTime};

/// Both lanes of a feed, taken at once.
fn both(feed: &ChangeFeed) -> (Vec<Stamped>, Vec<Numeric>) {
    let (mut changes, mut numeric) = (Vec::new(), Vec::new());
    feed.swap_both(&mut changes, &mut numeric);
    (changes, numeric)
}

#[test]
fn a_changed_number_comes_in_the_lane_stamped_and_numbered_with_the_other_changes() {
    let (ds, clock) = manual();
    let t0 = SystemTime::UNIX_EPOCH + Duration::from_secs(1_700_000_000);
    clock.set_wall(t0);
    let o = object(&ds, "nav");
    ds.set(o, "speed", Value::Float(1.0)).unwrap();
    let feed = ds.change_feed_numeric();
    clock.advance(Duration::from_millis(250));
    ds.set(o, "speed", Value::Float(2.5)).unwrap();
    ds.set(o, "mode", Value::str("auto")).unwrap();
    ds.set(o, "armed", Value::Bool(true)).unwrap();
    ds.set(o, "armed", Value::Bool(false)).unwrap();
    ds.set(o, "count", Value::Int(-7)).unwrap();
    ds.set(o, "count", Value::Int(-8)).unwrap();
    ds.set(o, "speed", Value::Float(2.5)).unwrap(); // no change: not fed
    let (changes, numeric) = both(&feed);
    // The first value of a property (its creation) is a change; later ones numbers.
    let created: Vec<&str> = changes
        .iter()
        .map(|s| match &s.change {
            Change::PropertySet { name, created: true, .. } => name.as_str(),
            other => panic!("{other:?}"),
        })
        .collect();
    assert_eq!(created, ["mode", "armed", "count"]);
    let values: Vec<(u64, Value)> = numeric.iter().map(|n| (n.seq, n.value())).collect();
    let first = numeric[0].seq;
    assert_eq!(
        values,
        vec![
            (first, Value::Float(2.5)),
            (first + 3, Value::Bool(false)),
            (first + 5, Value::Int(-8)),
        ]
    );
    assert_eq!(
        changes.iter().map(|s| s.seq).collect::<Vec<_>>(),
        [first + 1, first + 2, first + 4]
    );
    let ns = |t: SystemTime| t.duration_since(SystemTime::UNIX_EPOCH).unwrap().as_nanos() as u64;
    assert!(numeric.iter().all(|n| n.ns == ns(t0 + Duration::from_millis(250))));
    // Each property by the number the server gave it once.
    assert_eq!(feed.numbered(numeric[0].id), Some((o, PropName::new("speed"))));
    assert_eq!(feed.numbered(numeric[2].id), Some((o, PropName::new("count"))));
    assert_ne!(numeric[0].id, numeric[1].id);
    ds.set(o, "speed", Value::Float(3.0)).unwrap();
    assert_eq!(both(&feed).1[0].id, numeric[0].id);
    assert_eq!(feed.numbered(0), None);
}

#[test]
fn a_feed_without_the_lane_still_gets_every_change_and_a_property_created_again_is_numbered_anew() {
    let (ds, _clock) = manual();
    let o = object(&ds, "nav");
    ds.set(o, "x", Value::Float(0.0)).unwrap();
    let plain = ds.change_feed();
    let lane = ds.change_feed_numeric();
    ds.set(o, "x", Value::Float(1.0)).unwrap();
    let (changes, numeric) = both(&plain);
    assert!(numeric.is_empty());
    assert!(matches!(
        &changes[..],
        [Stamped { change: Change::PropertySet { value: Value::Float(1.0), .. }, .. }]
    ));
    let (_, first) = both(&lane);
    assert_eq!((first.len(), first[0].seq), (1, changes[0].seq));
    ds.delete_property(o, "x").unwrap();
    ds.set(o, "x", Value::Float(5.0)).unwrap();
    ds.set(o, "x", Value::Float(6.0)).unwrap();
    let (_, again) = both(&lane);
    assert_ne!(again[0].id, first[0].id, "a new property, a new number");
    assert_eq!(lane.numbered(again[0].id), Some((o, PropName::new("x"))));
}

#[test]
fn a_muted_listener_is_not_fed_to_that_feed_and_is_again_once_unmuted() {
    let (ds, _clock) = manual();
    let cam = ds.create_listener(ds.root(), "cam").unwrap();
    let muting = ds.change_feed_numeric();
    let other = ds.change_feed();
    muting.mute(cam, true);
    ds.send(cam, vec![Value::Int(1)]).unwrap();
    muting.mute(cam, false);
    ds.send(cam, vec![Value::Int(2)]).unwrap();
    let sent = |feed: &ChangeFeed| -> Vec<Value> {
        both(feed)
            .0
            .into_iter()
            .filter_map(|s| match s.change {
                Change::Sent { message, .. } => Some(message[0].clone()),
                _ => None,
            })
            .collect()
    };
    assert_eq!(sent(&muting), [Value::Int(2)]);
    assert_eq!(sent(&other), [Value::Int(1), Value::Int(2)]);
}
