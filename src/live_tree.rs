//! The language server's live world values (`mocu_lsp::live::LiveTree`) from running OCUs and
//! adapters over the distributed world model (docs/distribution.md): a DataServer of this
//! process that `runtime/distrib` fills with the subtrees the sites it connects to share. The
//! language server only reads it; it shares nothing and listens nowhere. Completion offers the
//! objects and properties that exist in it now, hover a property's value, units and age.

use mocu_dataserver::{DataServer, Guid, PropName};
use mocu_distrib::{Config, Distrib};
use mocu_lsp::live::{LiveChild, LiveTree, LiveValue};
use mocu_lsp::paths::MemberKind;

/// A mirror of what the sites at some Zenoh endpoints share.
pub struct WorldMirror {
    ds: DataServer,
    /// Where the values come from, for hover (`tcp/127.0.0.1:7447`).
    source: String,
    _distrib: Distrib,
}

impl WorldMirror {
    /// Connects to `endpoints` (Zenoh locators); the mirror fills as their snapshots arrive
    /// and follows their changes from then on.
    pub fn connect(endpoints: &[String]) -> Result<WorldMirror, String> {
        let ds = DataServer::default();
        let config = Config {
            site: format!("lsp-{}", std::process::id()),
            connect: endpoints.to_vec(),
            ..Config::default()
        };
        let distrib = Distrib::start(&ds, &config, None)?;
        Ok(WorldMirror { ds, source: endpoints.join(", "), _distrib: distrib })
    }

    /// The object at the dotted `path` (`root.vehicles.usv1`).
    fn object(&self, path: &str) -> Option<Guid> {
        let segs = mocu_distrib::object_path(path);
        self.ds.resolve(&segs.iter().map(String::as_str).collect::<Vec<_>>())
    }
}

impl LiveTree for WorldMirror {
    fn children(&self, path: &str) -> Option<Vec<LiveChild>> {
        let at = self.object(path)?;
        let mut out = Vec::new();
        for c in self.ds.children(at).ok()? {
            if let Ok(info) = self.ds.info(c) {
                out.push(LiveChild {
                    name: info.name.to_string(),
                    kind: MemberKind::Object,
                    value: None,
                });
            }
        }
        for (name, v) in self.ds.properties(at).ok()? {
            let value = Some(v.to_string());
            out.push(LiveChild {
                name: name.as_str().to_string(),
                kind: MemberKind::Property,
                value,
            });
        }
        // `write_at_owner` is the mirror's plumbing for `set` (docs/distribution.md), not
        // a method a layout calls.
        let methods = self.ds.methods(at).ok()?;
        for m in methods.iter().filter(|m| m.name.as_str() != mocu_dataserver::WRITE_AT_OWNER) {
            out.push(LiveChild {
                name: m.name.as_str().to_string(),
                kind: MemberKind::Method,
                value: None,
            });
        }
        Some(out)
    }

    fn value(&self, path: &str) -> Option<LiveValue> {
        let (object, name) = path.rsplit_once('.')?;
        let at = self.object(object)?;
        let name = PropName::from(name);
        let text = self.ds.try_get(at, name)?.to_string();
        let units = self.ds.meta(at, name).ok().and_then(|m| m.units).map(|u| u.to_string());
        let received = self.ds.received_at(at, name).ok().flatten();
        let age = received.map(|t| self.ds.now().saturating_duration_since(t));
        Some(LiveValue { text, units, age, source: self.source.clone() })
    }
}

/// The endpoints the client asks for in its `initializationOptions`
/// (`{"live": {"connect": ["tcp/127.0.0.1:7447"]}}`).
pub fn endpoints_of(options: Option<&serde_json::Value>) -> Vec<String> {
    let list = options.and_then(|o| o.pointer("/live/connect"));
    match list {
        Some(serde_json::Value::String(s)) => vec![s.clone()],
        Some(serde_json::Value::Array(xs)) => {
            xs.iter().filter_map(|x| x.as_str().map(String::from)).collect()
        }
        _ => Vec::new(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;

    #[test]
    fn the_endpoints_come_from_the_live_connect_initialization_option() {
        let one = json!({"live": {"connect": "tcp/127.0.0.1:7447"}});
        assert_eq!(endpoints_of(Some(&one)), vec!["tcp/127.0.0.1:7447"]);
        let two = json!({"live": {"connect": ["tcp/a:1", "tcp/b:2"]}});
        assert_eq!(endpoints_of(Some(&two)), vec!["tcp/a:1", "tcp/b:2"]);
        assert!(endpoints_of(Some(&json!({"other": 1}))).is_empty());
        assert!(endpoints_of(None).is_empty());
    }
}
