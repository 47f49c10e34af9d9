//! Object-type schemas (TOML): which properties, children and methods each object type has.
//!
//! ```toml
//! [[instances]]                 # where objects of a type live in the world model
//! path = "root.vehicles.usv*"   # `*` matches within the last segment
//! type = "usv"
//!
//! [types.usv]
//! description = "Unmanned surface vehicle"
//! children = { nav = "nav" }
//! [types.usv.properties.fuel]
//! type = "float"                # a mocu-value ValueKind: int, float, bool, string, …
//! range = [0, 1]
//! read_only = true
//! stale_after = 5               # seconds without a write before the value is stale
//! [types.usv.methods.arm]
//! params = ["bool"]
//! ```

use crate::codes;
use crate::diagnostics::Diagnostics;
use crate::source::{FileId, Span};
use crate::types::{Type, TypeKind};
use mocu_value::ValueKind;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Schema {
    #[serde(default)]
    pub instances: Vec<Instance>,
    #[serde(default)]
    pub types: BTreeMap<String, ObjectType>,
    /// The vehicles a profile's modules publish under `root.vehicles` (names and `*`
    /// patterns), when the profile says which; not part of a schema file.
    #[serde(skip)]
    pub vehicles: Option<Vec<String>>,
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Instance {
    pub path: String,
    #[serde(rename = "type")]
    pub object_type: String,
}

#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ObjectType {
    #[serde(default)]
    pub description: String,
    #[serde(default)]
    pub properties: BTreeMap<String, Property>,
    #[serde(default)]
    pub children: BTreeMap<String, String>,
    #[serde(default)]
    pub methods: BTreeMap<String, Method>,
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Property {
    #[serde(rename = "type")]
    pub kind: ValueKind,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub units: Option<String>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub range: Option<[f64; 2]>,
    #[serde(default)]
    pub description: String,
    #[serde(default)]
    pub read_only: bool,
    /// Seconds after its last write when the value is stale (shown veiled); `None`: the
    /// display's default. Positive.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub stale_after: Option<f64>,
}

#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Method {
    #[serde(default)]
    pub params: Vec<ValueKind>,
    #[serde(default)]
    pub description: String,
}

/// What a path names, as far as the schema knows.
#[derive(Debug)]
pub enum Lookup<'a> {
    /// No schema covers this path: accepted, discovered at run time.
    Untyped,
    Object(&'a str),
    Property(&'a Property),
    Method(&'a Method),
    /// Segment `index` is not a member of `object_type`.
    Unknown {
        object_type: &'a str,
        index: usize,
        candidates: Vec<&'a str>,
    },
}

impl Property {
    /// The language type of this property (always possibly absent).
    pub fn ty(&self) -> Type {
        let kind = match self.kind {
            ValueKind::Int | ValueKind::Float => {
                TypeKind::Number { unit: self.units.as_deref().map(crate::types::Name::new) }
            }
            ValueKind::Bool => TypeKind::Bool,
            ValueKind::String => TypeKind::String,
            _ => TypeKind::Dynamic,
        };
        Type { kind, absent: true }
    }
}

impl Schema {
    pub fn is_empty(&self) -> bool {
        self.types.is_empty()
    }

    /// Loads one schema file; problems are reported as E0405 and the file is skipped.
    pub fn parse(file: FileId, text: &str, diags: &mut Diagnostics) -> Option<Schema> {
        match toml::from_str::<Schema>(text) {
            Ok(s) => {
                for (name, t) in &s.types {
                    for (prop, p) in &t.properties {
                        if let Some(v) = p.stale_after.filter(|v| !(v.is_finite() && *v > 0.0)) {
                            let at = text.find("stale_after").unwrap_or(0);
                            diags
                                .error(codes::BAD_SCHEMA, Span::new(file, at, at + 11), format!("`stale_after` of `{name}.{prop}` is {v}: it must be more than 0 seconds"))
                                .help("e.g. `stale_after = 2.5` (seconds)");
                        }
                    }
                    for (child, ty) in &t.children {
                        if !s.types.contains_key(ty) {
                            let at = text.find(&format!("\"{ty}\"")).unwrap_or(0);
                            diags
                                .error(codes::BAD_SCHEMA, Span::new(file, at, at + ty.len() + 2), format!("child `{child}` of type `{name}` has the undeclared type `{ty}`"))
                                .suggest(ty, s.types.keys().map(String::as_str));
                        }
                    }
                }
                Some(s)
            }
            Err(e) => {
                let range = e.span().unwrap_or(0..0);
                diags
                    .error(
                        codes::BAD_SCHEMA,
                        Span::new(file, range.start, range.end),
                        format!("invalid schema: {}", e.message()),
                    )
                    .help("see docs/language.md, \"Schemas\", for the shape of a schema file");
                None
            }
        }
    }

    /// The schema as a bundle stores it (what the profile's modules publish is not kept).
    pub fn for_bundle(&self) -> Schema {
        Schema { vehicles: None, ..self.clone() }
    }

    /// Merges another schema into this one (later files add types and instances).
    pub fn merge(&mut self, other: Schema) {
        self.instances.extend(other.instances);
        self.types.extend(other.types);
    }

    /// Looks a path up. `base_type` is the type of the path's base when it is not `root`
    /// (`self` in a menu, a template variable); `segments` follow the base.
    pub fn lookup<'a>(
        &'a self,
        base_type: Option<&str>,
        from_root: bool,
        segments: &[String],
    ) -> Lookup<'a> {
        let (ty, start) = match (base_type, from_root) {
            (Some(t), _) => match self.types.get_key_value(t) {
                Some((k, _)) => (k.as_str(), 0),
                None => return Lookup::Untyped,
            },
            (None, true) => {
                // Every instance pattern matching a prefix, longest first: a member (property,
                // method) found through a shorter one wins over an object that a longer `*`
                // pattern makes of the same name (`routes.create_route` vs `routes.*`).
                let mut results: Vec<Lookup<'a>> = self
                    .instances_at(segments)
                    .into_iter()
                    .map(|(t, used)| self.walk(t, used, segments))
                    .collect();
                let pick = results
                    .iter()
                    .position(|l| matches!(l, Lookup::Property(_) | Lookup::Method(_)))
                    .or_else(|| results.iter().position(|l| matches!(l, Lookup::Object(_))))
                    .or((!results.is_empty()).then_some(0));
                return match pick {
                    Some(i) => results.swap_remove(i),
                    None => Lookup::Untyped,
                };
            }
            (None, false) => return Lookup::Untyped,
        };
        self.walk(ty, start, segments)
    }

    /// Follows `segments[start..]` from an object of type `ty`.
    fn walk<'a>(&'a self, mut ty: &'a str, start: usize, segments: &[String]) -> Lookup<'a> {
        if start == segments.len() {
            return Lookup::Object(ty);
        }
        for (i, seg) in segments.iter().enumerate().skip(start) {
            let Some(t) = self.types.get(ty) else { return Lookup::Untyped };
            let last = i + 1 == segments.len();
            if let Some(child) = t.children.get(seg) {
                ty = child;
                if last {
                    return Lookup::Object(ty);
                }
            } else if let (Some(p), true) = (t.properties.get(seg), last) {
                return Lookup::Property(p);
            } else if let (Some(m), true) = (t.methods.get(seg), last) {
                return Lookup::Method(m);
            } else {
                let candidates = t
                    .properties
                    .keys()
                    .chain(t.children.keys())
                    .chain(t.methods.keys())
                    .map(String::as_str)
                    .collect();
                return Lookup::Unknown { object_type: ty, index: i, candidates };
            }
        }
        Lookup::Object(ty)
    }

    /// The types of the objects at every instance pattern matching a prefix of `segments`
    /// (which follow `root`), with how many segments each used, longest first.
    fn instances_at(&self, segments: &[String]) -> Vec<(&str, usize)> {
        let mut out: Vec<(&str, usize)> = self
            .instances
            .iter()
            .filter_map(|inst| {
                let pat: Vec<&str> = inst.path.split('.').skip_while(|s| *s == "root").collect();
                (pat.len() <= segments.len() && pat.iter().zip(segments).all(|(p, s)| glob(p, s)))
                    .then_some((inst.object_type.as_str(), pat.len()))
            })
            .collect();
        out.sort_by_key(|(_, used)| std::cmp::Reverse(*used));
        out
    }

    /// Whether `object_type` is declared.
    pub fn has_type(&self, object_type: &str) -> bool {
        self.types.contains_key(object_type)
    }
}

fn glob(pattern: &str, s: &str) -> bool {
    match pattern.split_once('*') {
        None => pattern == s,
        Some((pre, post)) => {
            s.len() >= pre.len() + post.len() && s.starts_with(pre) && s.ends_with(post)
        }
    }
}
