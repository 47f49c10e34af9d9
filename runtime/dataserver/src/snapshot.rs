//! A consistent-enough copy of a subtree, for `--dump`, tests and tools.

use crate::error::DsError;
use crate::server::DataServer;
use mocu_value::{Guid, Value};

/// An object and its subtree as plain data (`--dump` prints it as JSON).
#[derive(Clone, Debug, PartialEq)]
pub struct Snapshot {
    pub guid: Guid,
    pub name: String,
    pub kind: String,
    pub subtype: String,
    /// In creation order.
    pub properties: Vec<(String, Value)>,
    pub methods: Vec<String>,
    pub children: Vec<Snapshot>,
}

impl DataServer {
    /// Copies the subtree at `guid`. Each object is read under its own lock; a subtree that
    /// changes meanwhile may mix moments (quiesce first for an exact copy).
    pub fn snapshot(&self, guid: Guid) -> Result<Snapshot, DsError> {
        let info = self.info(guid)?;
        let properties =
            self.properties(guid)?.into_iter().map(|(n, v)| (n.as_str().to_string(), v)).collect();
        let methods =
            self.methods(guid)?.into_iter().map(|m| m.name.as_str().to_string()).collect();
        let mut children = Vec::new();
        for c in self.children(guid)? {
            if let Ok(s) = self.snapshot(c) {
                children.push(s);
            }
        }
        Ok(Snapshot {
            guid,
            name: info.name.to_string(),
            kind: info.kind.to_string(),
            subtype: info.subtype.to_string(),
            properties,
            methods,
            children,
        })
    }
}

impl Snapshot {
    /// JSON as the `--dump` contract says: `name`, `type`, `guid`, `properties`,
    /// `children` (plus `subtype` and `methods`).
    pub fn to_json(&self) -> String {
        let mut out = String::new();
        self.write_json(&mut out, 0);
        out
    }

    fn write_json(&self, out: &mut String, depth: usize) {
        use std::fmt::Write;
        let pad = "  ".repeat(depth + 1);
        let end = "  ".repeat(depth);
        let q = |s: &str| Value::str(s).to_json().to_string();
        let _ = write!(
            out,
            "{{\n{pad}\"name\": {},\n{pad}\"type\": {},\n",
            q(&self.name),
            q(&self.kind)
        );
        let _ = write!(
            out,
            "{pad}\"subtype\": {},\n{pad}\"guid\": {},\n",
            q(&self.subtype),
            self.guid.get()
        );
        out.push_str(&format!("{pad}\"properties\": {{"));
        for (i, (n, v)) in self.properties.iter().enumerate() {
            let _ = write!(out, "{}{}: {}", if i > 0 { ", " } else { "" }, q(n), v.to_json());
        }
        out.push_str("},\n");
        let ms: Vec<String> = self.methods.iter().map(|m| q(m)).collect();
        let _ = write!(out, "{pad}\"methods\": [{}],\n{pad}\"children\": [", ms.join(", "));
        for (i, c) in self.children.iter().enumerate() {
            out.push_str(if i > 0 { ", " } else { "" });
            c.write_json(out, depth + 1);
        }
        let _ = write!(out, "]\n{end}}}");
    }
}
