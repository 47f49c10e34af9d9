//! Hover: a component's documentation (the stdlib's doc comments, as docs/components.md shows
//! them), a parameter's type, default and meaning, a `let`'s checked type, and what the
//! project's schemas say of a world-model path (type, units, range, description).
//!
//! A world-model path's current value comes from the server's [`LiveTree`] (a running OCU's
//! shared world model when `mocu lsp` is told where one is; without one hover shows what the
//! schemas declare).

use crate::check::Analysis;
use crate::index::{Def, Index, Kind};
use crate::live::LiveTree;
use crate::paths;
use mocu_language::{builtins, docgen};

/// The hover text (Markdown) at byte `offset` of `path`.
pub fn hover(
    index: &Index,
    analysis: Option<&Analysis>,
    live: &dyn LiveTree,
    path: &str,
    offset: usize,
) -> Option<String> {
    let text = index.text(path);
    if let Some(o) = index.at(path, offset)
        && let Some(def) = index.defs.get(&o.def)
    {
        let mut s = describe_def(index, analysis, def);
        if def.kind == Kind::Let
            && let Some(a) = analysis
            && let Some(p) = path_info(index, a, live, text, offset)
        {
            s.push_str(&format!("\n\n{p}"));
        }
        return Some(s);
    }
    // A native component (no source to point at).
    if let Some((_, segs)) = paths::dotted_at(text, offset)
        && let [one] = segs.as_slice()
        && let Some(n) = builtins::native(one)
    {
        return Some(format!("### {}\n\nNative component: {}.", n.name, n.doc));
    }
    if let Some((_, segs)) = paths::dotted_at(text, offset)
        && let [one] = segs.as_slice()
        && let Some(f) = builtins::function(one)
    {
        return Some(format!("`{}`: built-in function. {}", f.name, f.doc));
    }
    path_info(index, analysis?, live, text, offset)
}

/// What the schema says of the path under the cursor, when it reaches `root`.
fn path_info(
    index: &Index,
    analysis: &Analysis,
    live: &dyn LiveTree,
    text: &str,
    offset: usize,
) -> Option<String> {
    let (_, segs) = paths::dotted_at(text, offset)?;
    let segs = paths::expand(index, segs);
    if segs.first().map(String::as_str) != Some("root") || segs.len() < 2 {
        return None;
    }
    let declared = paths::describe(&analysis.schema, &segs[1..]);
    match (declared, crate::live::value_line(live, &segs[1..])) {
        (Some(d), Some(now)) => Some(format!("{d}\n\n{now}")),
        (d, now) => d.or(now),
    }
}

fn describe_def(index: &Index, analysis: Option<&Analysis>, def: &Def) -> String {
    let text = index.text(&def.path);
    let line = line_of(text, def.start as usize);
    match def.kind {
        Kind::Component => component_doc(text, &def.path, &def.name)
            .unwrap_or_else(|| format!("```mocu\n{line}\n```")),
        Kind::Param => {
            let owner = def.owner.as_deref().unwrap_or("");
            let entry = docgen::entries(&def.path, text).into_iter().find(|e| e.name == owner);
            let row = entry.as_ref().and_then(|e| e.params.iter().find(|p| p.0 == def.name));
            match row {
                Some((n, ty, default, meaning)) => {
                    let mut s = format!("`{n}`: parameter of `{owner}`, {ty}, default {default}");
                    if !meaning.is_empty() {
                        s.push_str(&format!("\n\n{meaning}"));
                    }
                    s
                }
                None => format!("`{}`: parameter of `{owner}`", def.name),
            }
        }
        Kind::Let | Kind::Local => {
            let ty = analysis
                .and_then(|a| a.let_types.get(&(def.path.clone(), def.value_start.unwrap_or(0))));
            let mut s = format!("```mocu\n{line}\n```");
            if let Some(t) = ty {
                s.push_str(&format!("\n\ntype: {t}"));
            }
            s
        }
        Kind::Window | Kind::Watch | Kind::Widget => format!("```mocu\n{line}\n```"),
    }
}

/// A component's reference section, from the doc comment above it.
pub fn component_doc(text: &str, path: &str, name: &str) -> Option<String> {
    docgen::entries(path, text).iter().find(|e| e.name == name).map(docgen::entry_markdown)
}

/// The line around `offset`, trimmed (at most 120 characters).
fn line_of(text: &str, offset: usize) -> String {
    let start = text[..offset.min(text.len())].rfind('\n').map_or(0, |i| i + 1);
    let end = text[start..].find('\n').map_or(text.len(), |i| start + i);
    text[start..end].trim().chars().take(120).collect()
}
