//! The guarantees of a coalesced stream: a subsequence of the model's notifications that
//! leaves a replica in the object's final state.

use crate::model::{MSub, Model, Watch};
use mocu_dataserver::{Guid, Kind, Notification, PropName, Subject, Value};
use std::collections::BTreeMap;
use std::sync::Arc;

fn coalescable(n: &Notification) -> bool {
    matches!(n.kind, Kind::New | Kind::Changed) && !matches!(n.subject, Subject::Object)
}

/// `received` must be `expected` with some New/Changed entries left out (superseded by a
/// later one of the same key; a coalesced entry may keep the New-ness of the one it
/// replaced). A subscription ended by `unsubscribe` may also miss any tail.
pub(crate) fn check_stream(i: usize, received: &[Notification], s: &MSub, m: &Model) {
    // Unsubscribing may cut off any tail, even the object's pending Deleted.
    let ended_by_unsubscribe = s.unsubscribed;
    let mut e = 0;
    for (k, r) in received.iter().enumerate() {
        loop {
            let Some(x) = s.expected.get(e) else {
                panic!(
                    "subscription {i}: received #{k} {r:?} is not in the change order\n\
                     received: {received:#?}\nexpected: {:#?}",
                    s.expected
                );
            };
            e += 1;
            let same_kind = r.kind == x.kind || (r.kind == Kind::New && x.kind == Kind::Changed);
            if r.object == x.object && r.subject == x.subject && same_kind {
                break;
            }
            assert!(
                coalescable(x),
                "subscription {i}: {x:?} was never delivered\nreceived: {received:#?}\nexpected: {:#?}",
                s.expected
            );
        }
    }
    if !ended_by_unsubscribe {
        let lost: Vec<_> = s.expected[e..].iter().filter(|x| !coalescable(x)).collect();
        assert!(lost.is_empty(), "subscription {i}: never delivered {lost:?}");
    }
    if s.live {
        check_replica(i, received, s, m);
    }
}

/// Applying the stream to an empty replica gives the object's state now.
fn check_replica(i: usize, received: &[Notification], s: &MSub, m: &Model) {
    let o = &m.objects[&s.object];
    match s.watch {
        Watch::Properties(_) => {
            let mut replica = BTreeMap::new();
            for n in received {
                match (&n.subject, n.kind) {
                    (Subject::Property { name, value: Some(v) }, Kind::New | Kind::Changed) => {
                        replica.insert(*name, v.clone());
                    }
                    (Subject::Property { name, value: None }, Kind::Deleted) => {
                        assert!(
                            replica.remove(name).is_some(),
                            "subscription {i}: {n:?} of an unknown property"
                        );
                    }
                    _ => panic!("subscription {i}: unexpected {n:?}"),
                }
            }
            let now: BTreeMap<PropName, Value> = o
                .props
                .iter()
                .filter(|p| s.wants(p.name))
                .map(|p| (p.name, p.value.clone()))
                .collect();
            assert_eq!(replica, now, "subscription {i}: the replica is not the final state");
        }
        Watch::Children => {
            let mut replica: Vec<(Guid, Arc<str>, Arc<str>)> = Vec::new();
            for n in received {
                let Subject::Child { guid, name, kind, index } = &n.subject else {
                    panic!("subscription {i}: unexpected {n:?}");
                };
                let entry = (*guid, name.clone(), kind.clone());
                match n.kind {
                    Kind::New => {
                        assert!(
                            *index <= replica.len(),
                            "subscription {i}: {n:?} past the end of {replica:?}"
                        );
                        replica.insert(*index, entry);
                    }
                    Kind::Changed | Kind::Deleted => {
                        assert!(
                            replica.get(*index).is_some_and(|r| r.0 == *guid),
                            "subscription {i}: {n:?} does not match {replica:?}"
                        );
                        if n.kind == Kind::Changed {
                            replica[*index] = entry;
                        } else {
                            replica.remove(*index);
                        }
                    }
                }
            }
            let now: Vec<_> = o
                .children
                .iter()
                .map(|c| (*c, m.objects[c].info.name.clone(), m.objects[c].info.kind.clone()))
                .collect();
            assert_eq!(replica, now, "subscription {i}: the replica is not the final state");
        }
    }
}
