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

/// The endpoints of the client's `initialize` parameters: what its `initializationOptions`
/// ask for (`{"live": {"connect": ["tcp/127.0.0.1:7447"]}}`), then what the project profile
/// of its workspace folder says in `[modules.distrib]` (`connect`, and `listen` as a local
/// client reaches it: the OCU that profile runs listens there).
pub fn endpoints_of(init: Option<&serde_json::Value>) -> Vec<String> {
    let mut out = asked_for(init.and_then(|i| i.get("initializationOptions")));
    let root = init.and_then(workspace_root);
    for e in root.map(|r| profile_endpoints(&r)).unwrap_or_default() {
        if !out.contains(&e) {
            out.push(e);
        }
    }
    out
}

/// The workspace folder of `initialize` (`workspaceFolders[0]`, else `rootUri`, else
/// `rootPath`), as a path.
fn workspace_root(init: &serde_json::Value) -> Option<std::path::PathBuf> {
    let uri = init
        .pointer("/workspaceFolders/0/uri")
        .or_else(|| init.get("rootUri"))
        .and_then(|u| u.as_str());
    match uri {
        Some(u) => u.strip_prefix("file://").map(|p| percent_decoded(p).into()),
        None => init.get("rootPath").and_then(|p| p.as_str()).map(Into::into),
    }
}

fn percent_decoded(s: &str) -> String {
    let b = s.as_bytes();
    let mut out = Vec::with_capacity(b.len());
    let mut i = 0;
    while i < b.len() {
        let hex = (b[i] == b'%').then(|| s.get(i + 1..i + 3)).flatten();
        match hex.and_then(|h| u8::from_str_radix(h, 16).ok()) {
            Some(x) => {
                out.push(x);
                i += 3;
            }
            None => {
                out.push(b[i]);
                i += 1;
            }
        }
    }
    String::from_utf8_lossy(&out).into_owned()
}

/// `[modules.distrib]` of the project profile in `root` (`project.toml` there, or in one of
/// its folders, `layouts/project.toml` in this repository): `connect`, and `listen` made
/// reachable from this machine.
fn profile_endpoints(root: &std::path::Path) -> Vec<String> {
    let mut candidates = vec![root.join("project.toml")];
    if let Ok(dir) = std::fs::read_dir(root) {
        let mut sub: Vec<_> = dir.flatten().map(|e| e.path().join("project.toml")).collect();
        sub.sort();
        candidates.extend(sub);
    }
    let Some(text) = candidates.iter().find_map(|p| std::fs::read_to_string(p).ok()) else {
        return Vec::new();
    };
    let Ok(profile) = text.parse::<toml::Table>() else { return Vec::new() };
    let distrib = profile.get("modules").and_then(|m| m.get("distrib"));
    let list = |key: &str| -> Vec<String> {
        match distrib.and_then(|d| d.get(key)) {
            Some(toml::Value::String(s)) => vec![s.clone()],
            Some(toml::Value::Array(xs)) => {
                xs.iter().filter_map(|x| x.as_str().map(String::from)).collect()
            }
            _ => Vec::new(),
        }
    };
    let listen = list("listen").into_iter().map(|e| crate::process_modules::reachable(&e));
    list("connect").into_iter().chain(listen).collect()
}

/// The endpoints the client asks for in its `initializationOptions`.
fn asked_for(options: Option<&serde_json::Value>) -> Vec<String> {
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
        let opts = |o| json!({ "initializationOptions": o });
        let one = opts(json!({"live": {"connect": "tcp/127.0.0.1:7447"}}));
        assert_eq!(endpoints_of(Some(&one)), vec!["tcp/127.0.0.1:7447"]);
        let two = opts(json!({"live": {"connect": ["tcp/a:1", "tcp/b:2"]}}));
        assert_eq!(endpoints_of(Some(&two)), vec!["tcp/a:1", "tcp/b:2"]);
        assert!(endpoints_of(Some(&opts(json!({"other": 1})))).is_empty());
        assert!(endpoints_of(None).is_empty());
    }

    #[test]
    fn the_workspaces_project_profile_says_where_its_ocu_is_without_any_option() {
        let dir = tempfile::tempdir().unwrap();
        let root = dir.path().join("work space");
        let layouts = root.join("my layouts");
        std::fs::create_dir_all(&layouts).unwrap();
        std::fs::write(
            layouts.join("project.toml"),
            "[profile]\nname = \"p\"\n[modules.distrib]\nconnect = [\"tcp/10.0.0.5:7447\"]\nlisten = \"tcp/0.0.0.0:7448\"\n",
        )
        .unwrap();
        let uri = format!("file://{}", root.display()).replace(' ', "%20");
        let init = json!({
            "workspaceFolders": [{"uri": uri, "name": "w"}],
            "initializationOptions": {"live": {"connect": "tcp/127.0.0.1:9"}},
        });
        assert_eq!(
            endpoints_of(Some(&init)),
            vec!["tcp/127.0.0.1:9", "tcp/10.0.0.5:7447", "tcp/127.0.0.1:7448"]
        );
        // A workspace without a profile, or a profile without distribution: nothing more.
        let bare = json!({"rootUri": "file:///nonexistent/folder"});
        assert!(endpoints_of(Some(&bare)).is_empty());
    }
}
