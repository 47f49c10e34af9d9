//! The seam for live world values: what a running OCU's world model holds, for completion
//! (the objects and properties that exist now, `usv3` included when only `usv*` is declared)
//! and hover (a property's current value).
//!
//! The source is made where the server is started ([`crate::Options::live`]): `mocu lsp`
//! mirrors the shared subtrees of the OCUs and adapters it is told to connect to over the
//! distributed world model (`src/live_tree.rs` of the `mocu` binary, over `runtime/distrib`);
//! without one the server has [`NoLiveTree`] and shows what the schemas declare. The server
//! depends only on this trait, so this crate keeps depending on `mocu-language` alone
//! (`tests/architecture.rs`).

use crate::paths::{Member, MemberKind};
use std::time::Duration;

/// A running OCU's world model as the editor sees it. Paths are dotted, from `root`
/// (`root.vehicles.usv1.nav`). Answers must be quick (they are asked on the request thread):
/// a source that talks to the network answers from a copy it keeps up to date.
pub trait LiveTree {
    /// The objects, properties and methods under the object at `path` now; `None` when the
    /// source cannot say (no OCU reachable, no such object).
    fn children(&self, path: &str) -> Option<Vec<LiveChild>>;
    /// The current value of the property at `path`; `None` when the source cannot say.
    fn value(&self, path: &str) -> Option<LiveValue>;
}

/// One member of a live object.
#[derive(Clone, Debug, PartialEq)]
pub struct LiveChild {
    pub name: String,
    pub kind: MemberKind,
    /// A property's current value, written out (`3.2`, `"usv1"`).
    pub value: Option<String>,
}

/// A property's current value.
#[derive(Clone, Debug, PartialEq)]
pub struct LiveValue {
    /// The value, written out.
    pub text: String,
    /// Its units, when the publisher gives them (`m/s`).
    pub units: Option<String>,
    /// How long ago it was written, when known.
    pub age: Option<Duration>,
    /// Where it was read (the OCU or adapter), for the hover's last line.
    pub source: String,
}

/// No running OCU: every question is answered "cannot say".
pub struct NoLiveTree;

impl LiveTree for NoLiveTree {
    fn children(&self, _: &str) -> Option<Vec<LiveChild>> {
        None
    }
    fn value(&self, _: &str) -> Option<LiveValue> {
        None
    }
}

/// The schema's members after `root.<segments>` with the live tree's: a live member the
/// schemas do not list is added, and a property's current value joins its detail.
pub fn merge(live: &dyn LiveTree, segments: &[String], mut members: Vec<Member>) -> Vec<Member> {
    let path = std::iter::once("root").chain(segments.iter().map(String::as_str));
    let Some(children) = live.children(&path.collect::<Vec<_>>().join(".")) else {
        return members;
    };
    for c in children {
        let now = c.value.as_ref().map(|v| format!("now {v}"));
        match members.iter_mut().find(|m| m.name == c.name) {
            Some(m) => {
                if let Some(now) = now {
                    m.detail = format!("{} · {now}", m.detail);
                }
            }
            None => members.push(Member {
                detail: now.unwrap_or_else(|| "live (not in the schemas)".into()),
                name: c.name,
                kind: c.kind,
            }),
        }
    }
    members
}

/// The hover's line for the current value of the property at `root.<segments>`.
pub fn value_line(live: &dyn LiveTree, segments: &[String]) -> Option<String> {
    let path = std::iter::once("root").chain(segments.iter().map(String::as_str));
    let v = live.value(&path.collect::<Vec<_>>().join("."))?;
    let age = v.age.map(|a| format!(", {:.1} s ago", a.as_secs_f64())).unwrap_or_default();
    let units = v.units.map(|u| format!(" {u}")).unwrap_or_default();
    Some(format!("current value: `{}{units}` (on {}{age})", v.text, v.source))
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::collections::BTreeMap;

    /// A world model held in a map: objects list their members, properties their value.
    struct Fixed(BTreeMap<&'static str, Vec<LiveChild>>);

    impl LiveTree for Fixed {
        fn children(&self, path: &str) -> Option<Vec<LiveChild>> {
            self.0.get(path).cloned()
        }
        fn value(&self, path: &str) -> Option<LiveValue> {
            let (parent, name) = path.rsplit_once('.')?;
            let c = self.0.get(parent)?.iter().find(|c| c.name == name)?;
            let text = c.value.clone()?;
            let units = Some("m/s".to_string());
            let age = Some(Duration::from_millis(200));
            Some(LiveValue { text, units, age, source: "ocu-1".into() })
        }
    }

    fn child(name: &str, kind: MemberKind, value: Option<&str>) -> LiveChild {
        LiveChild { name: name.into(), kind, value: value.map(str::to_string) }
    }

    fn fleet() -> Fixed {
        Fixed(BTreeMap::from([
            (
                "root.vehicles",
                vec![
                    child("usv1", MemberKind::Object, None),
                    child("usv3", MemberKind::Object, None),
                ],
            ),
            ("root.vehicles.usv1.nav", vec![child("speed", MemberKind::Property, Some("3.2"))]),
        ]))
    }

    fn segs(s: &[&str]) -> Vec<String> {
        s.iter().map(|x| x.to_string()).collect()
    }

    #[test]
    fn live_members_join_the_schemas_and_a_propertys_value_its_detail() {
        let declared =
            vec![Member { name: "usv1".into(), kind: MemberKind::Object, detail: "object".into() }];
        let got = merge(&fleet(), &segs(&["vehicles"]), declared);
        let names: Vec<&str> = got.iter().map(|m| m.name.as_str()).collect();
        assert_eq!(names, vec!["usv1", "usv3"]);
        assert_eq!(got[1].detail, "live (not in the schemas)");
        let speed = vec![Member {
            name: "speed".into(),
            kind: MemberKind::Property,
            detail: "float m/s".into(),
        }];
        let got = merge(&fleet(), &segs(&["vehicles", "usv1", "nav"]), speed);
        assert_eq!(got[0].detail, "float m/s · now 3.2");
    }

    #[test]
    fn hover_gets_the_current_value_and_without_an_ocu_nothing_changes() {
        let line = value_line(&fleet(), &segs(&["vehicles", "usv1", "nav", "speed"]));
        assert_eq!(line.as_deref(), Some("current value: `3.2 m/s` (on ocu-1, 0.2 s ago)"));
        assert_eq!(value_line(&NoLiveTree, &segs(&["vehicles", "usv1", "nav", "speed"])), None);
        let m = vec![Member { name: "a".into(), kind: MemberKind::Object, detail: "x".into() }];
        assert_eq!(merge(&NoLiveTree, &segs(&["vehicles"]), m).len(), 1);
    }
}
