//! World-model paths under the cursor, and what the project's schemas say of them.

use crate::index::Index;
use mocu_language::schema::{Lookup, Schema};

fn is_word(b: u8) -> bool {
    b.is_ascii_alphanumeric() || b == b'_'
}

/// The dotted name around byte `offset` (`usv.nav.speed`), cut after the segment the cursor
/// is in: (its start, its segments).
pub fn dotted_at(text: &str, offset: usize) -> Option<(usize, Vec<String>)> {
    let b = text.as_bytes();
    let offset = offset.min(b.len());
    let mut start = offset;
    while start > 0 && (is_word(b[start - 1]) || b[start - 1] == b'.') {
        start -= 1;
    }
    let mut end = offset;
    while end < b.len() && is_word(b[end]) {
        end += 1;
    }
    let s = text.get(start..end)?.trim_start_matches('.');
    if s.is_empty() || s.as_bytes()[0].is_ascii_digit() {
        return None;
    }
    Some((start, s.split('.').map(str::to_string).collect()))
}

/// `segments` with a leading `let` that names a path replaced by that path (followed through
/// lets naming lets), so `usv.nav` reads `root.vehicles.usv1.nav`.
pub fn expand(index: &Index, mut segments: Vec<String>) -> Vec<String> {
    for _ in 0..16 {
        let Some(first) = segments.first() else { break };
        if first == "root" {
            break;
        }
        let Some(def) = index.visible_let(first) else { break };
        let Some(value) = let_path(index.text(&def.path), def.value_start.unwrap_or(0) as usize)
        else {
            break;
        };
        segments.splice(0..1, value);
    }
    segments
}

/// The value of a `let` when it is a bare dotted path (`root.vehicles.usv1`).
fn let_path(text: &str, start: usize) -> Option<Vec<String>> {
    let rest = text.get(start..)?;
    let len = rest.bytes().take_while(|&b| is_word(b) || b == b'.').count();
    let after = rest[len..].trim_start_matches([' ', '\t']);
    let ends = after.is_empty() || after.starts_with(['\n', '\r']) || after.starts_with("//");
    (len > 0 && ends).then(|| rest[..len].split('.').map(str::to_string).collect())
}

/// What the schema says of a path from `root` (segments after `root`), in Markdown.
pub fn describe(schema: &Schema, segments: &[String]) -> Option<String> {
    let name = format!("root.{}", segments.join("."));
    Some(match schema.lookup(None, true, segments) {
        Lookup::Property(p) => {
            let mut s = format!("`{name}`: property, {}", p.ty());
            if let Some(u) = &p.units {
                s.push_str(&format!(", in {u}"));
            }
            if let Some([lo, hi]) = p.range {
                s.push_str(&format!(", from {lo} to {hi}"));
            }
            if p.read_only {
                s.push_str(", read-only");
            }
            if let Some(a) = p.stale_after {
                s.push_str(&format!(", stale after {a} s"));
            }
            if !p.description.is_empty() {
                s.push_str(&format!("\n\n{}", p.description));
            }
            s
        }
        Lookup::Object(t) => {
            let d = schema.types.get(t).map(|t| t.description.as_str()).unwrap_or("");
            format!(
                "`{name}`: object of type `{t}`{}",
                if d.is_empty() { String::new() } else { format!("\n\n{d}") }
            )
        }
        Lookup::Method(m) => {
            let params: Vec<String> =
                m.params.iter().map(|k| format!("{k:?}").to_lowercase()).collect();
            format!(
                "`{name}({})`: method{}",
                params.join(", "),
                if m.description.is_empty() {
                    String::new()
                } else {
                    format!("\n\n{}", m.description)
                }
            )
        }
        Lookup::Untyped => {
            format!("`{name}`: not in the project's schemas (its type is known at run time)")
        }
        Lookup::Unknown { object_type, .. } => {
            format!("`{name}`: no such member of `{object_type}`")
        }
    })
}

/// A name that may follow `segments` (after `root`): (name, what it is, detail).
pub struct Member {
    pub name: String,
    pub kind: MemberKind,
    pub detail: String,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MemberKind {
    Object,
    Property,
    Method,
}

/// What may follow `segments` (after `root`): objects the schema's instances place there,
/// and the members of the object's type.
pub fn members(schema: &Schema, segments: &[String]) -> Vec<Member> {
    let mut out: Vec<Member> = Vec::new();
    let mut add = |name: &str, kind, detail: String| {
        if !name.is_empty() && !name.contains('*') && !out.iter().any(|m| m.name == name) {
            out.push(Member { name: name.to_string(), kind, detail });
        }
    };
    for inst in &schema.instances {
        let pat: Vec<&str> = inst.path.split('.').skip_while(|s| *s == "root").collect();
        if pat.len() <= segments.len() || !pat.iter().zip(segments).all(|(p, s)| glob(p, s)) {
            continue;
        }
        let next = pat[segments.len()];
        let last = pat.len() == segments.len() + 1;
        let detail =
            if last { format!("object of type {}", inst.object_type) } else { "object".into() };
        if next.contains('*') {
            for v in schema.vehicles.iter().flatten().filter(|v| glob(next, v)) {
                add(v, MemberKind::Object, detail.clone());
            }
        } else {
            add(next, MemberKind::Object, detail);
        }
    }
    if let Lookup::Object(t) = schema.lookup(None, true, segments)
        && let Some(ty) = schema.types.get(t)
    {
        for (n, c) in &ty.children {
            add(n, MemberKind::Object, format!("object of type {c}"));
        }
        for (n, p) in &ty.properties {
            let units = p.units.as_ref().map(|u| format!(" ({u})")).unwrap_or_default();
            add(n, MemberKind::Property, format!("{}{units}", p.ty()));
        }
        for (n, m) in &ty.methods {
            let params: Vec<String> =
                m.params.iter().map(|k| format!("{k:?}").to_lowercase()).collect();
            add(n, MemberKind::Method, format!("method({})", params.join(", ")));
        }
    }
    out
}

fn glob(pattern: &str, s: &str) -> bool {
    match pattern.split_once('*') {
        None => pattern == s,
        Some((pre, post)) => {
            s.len() >= pre.len() + post.len() && s.starts_with(pre) && s.ends_with(post)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_dotted_name_under_the_cursor_stops_after_its_segment() {
        let t = "  value usv.nav.speed * 2";
        let at = t.find("nav").unwrap() + 1;
        assert_eq!(dotted_at(t, at), Some((8, vec!["usv".into(), "nav".into()])));
        assert_eq!(dotted_at("x 12.5", 4), None);
    }
}
