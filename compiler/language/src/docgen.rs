//! The reference of the standard components (docs/components.md), generated from the stdlib
//! sources: each component's doc comment (the `//` lines right above `component`), its
//! parameters with their types and defaults, and its events; then the native components.
//!
//! In a doc comment, a line `// - name: meaning` documents the parameter `name` (it goes to
//! the table, not to the description); indented lines right after it go on with it. A test
//! (tests/components_doc.rs) fails when the page is stale;
//! `UPDATE_DOCS=1 cargo test -p mocu-language --test components_doc` rewrites it.

use crate::ast::{Item, Param};
use crate::builtins;
use crate::diagnostics::Diagnostics;
use crate::parser;
use crate::source::SourceMap;
use std::fmt::Write;

/// One component as the reference shows it (the language server's hover shows it too).
pub struct Entry {
    pub name: String,
    pub description: Vec<String>,
    /// (name, type, default, meaning)
    pub params: Vec<(String, String, String, String)>,
    pub events: Vec<String>,
}

/// The page for `files` (path, text), in the order given.
pub fn components_reference(files: &[(String, String)]) -> String {
    let mut out = String::new();
    out.push_str(HEADER);
    for (path, text) in files {
        let entries = entries(path, text);
        if entries.is_empty() {
            continue;
        }
        let title = text
            .lines()
            .next()
            .and_then(|l| l.strip_prefix("//"))
            .map(|l| l.trim().to_string())
            .unwrap_or_else(|| path.clone());
        let file = path.rsplit('/').next().unwrap_or(path);
        let _ =
            writeln!(out, "## {file}\n\n{}\n", title.split_once(" — ").map_or(&title[..], |t| t.1));
        let _ = writeln!(out, "Use it with `use \"stdlib/{file}\"`.\n");
        for e in entries {
            write_entry(&mut out, &e);
        }
    }
    out.push_str(
        "## Native components\n\nDrawn by the runtime, not from primitives; no `use` needed.\n\n",
    );
    for n in builtins::NATIVES {
        let _ = writeln!(out, "### {}\n\n{}.\n", n.name, capitalise(n.doc));
        if !n.params.is_empty() {
            out.push_str("| parameter | type | default | meaning |\n|---|---|---|---|\n");
            for (name, ty, has_default) in n.params {
                let d = if *has_default { "optional" } else { "required" };
                let _ = writeln!(out, "| `{name}` | {ty} | {d} | |");
            }
            out.push('\n');
        }
        if !n.events.is_empty() {
            let ev: Vec<String> = n.events.iter().map(|e| format!("`on {e}`")).collect();
            let _ = writeln!(out, "Events: {}.\n", ev.join(", "));
        }
    }
    out
}

const HEADER: &str = "# Standard components

<!-- Generated from stdlib/*.mocu by `UPDATE_DOCS=1 cargo test -p mocu-language --test components_doc`; edit the doc comments there, not this page. -->

Every widget of a layout is one of these components, placed in a window:

```mocu
use \"stdlib/gauges.mocu\"
in hud {
  speed: Dial { at 40 40 160 160  value usv.nav.speed  range 0 .. 30  units \"m/s\" }
}
```

**How `at` places a widget.** `at X Y W H`: X and Y are the widget's top-left corner, measured
from the top-left corner of its window, W and H its width and height; each is in px, or in %
of the screen (`at 2% 5% 20% 10%`). Inside a component, `w` and `h` are that size. A widget
that has no size of its own, like `Label`, takes `at X Y` only. `anchor bottom-right` (or
`top`, `centre`, …) measures X and Y from that point of the window instead, and in a layout
with `design W x H` the px are design px, scaled to the screen (docs/language.md, \"Screen
sizes\").

**Parameters.** Each parameter is written `name value` after `at`. A parameter with a default
may be left out; one marked *required* may not. A type ending in `?` may be absent (no data):
the component then shows its grey \"no data\" look (`—`), never a false zero.

**Events.** `on press` (or another event) followed by actions: `on press call usv.stop()`.

";

/// The components of one stdlib file (path, text), with their doc comments.
pub fn entries(path: &str, text: &str) -> Vec<Entry> {
    let mut sources = SourceMap::new();
    let file = sources.add(path.to_string(), text.to_string());
    let mut diags = Diagnostics::new();
    let ast = parser::parse(file, text, &mut diags);
    let mut out = Vec::new();
    for item in &ast.items {
        let Item::Component(c) = item else { continue };
        let (description, docs) = doc_comment(text, c.span.start as usize);
        let mut params = Vec::new();
        let mut events = Vec::new();
        for p in &c.params {
            match p {
                Param::Value { name, ty, default } => {
                    let ty_text = match ty {
                        Some(t) => format!("{}{}", t.name.name, if t.optional { "?" } else { "" }),
                        None => "(from the default)".to_string(),
                    };
                    let d = match default {
                        Some(e) => format!(
                            "`{}`",
                            one_line(&text[e.span.start as usize..e.span.end as usize])
                        ),
                        None => "required".to_string(),
                    };
                    let meaning = docs
                        .iter()
                        .find(|(n, _)| *n == name.name)
                        .map(|(_, m)| m.clone())
                        .unwrap_or_default();
                    params.push((name.name.clone(), ty_text, d, meaning));
                }
                Param::Event { name } => events.push(name.name.clone()),
            }
        }
        out.push(Entry { name: c.name.name.clone(), description, params, events });
    }
    out
}

/// The `//` lines right above byte `start`: description lines, and `- name: meaning` lines.
fn doc_comment(text: &str, start: usize) -> (Vec<String>, Vec<(String, String)>) {
    let before = &text[..start];
    let mut lines: Vec<&str> = Vec::new();
    for l in before.lines().rev() {
        match l.trim().strip_prefix("//") {
            Some(rest) => lines.push(rest.strip_prefix(' ').unwrap_or(rest)),
            None if lines.is_empty() && l.trim().is_empty() => {}
            None => break,
        }
    }
    lines.reverse();
    let mut description = Vec::new();
    let mut params = Vec::new();
    let mut in_param = false;
    for l in lines {
        match l.strip_prefix("- ").and_then(|r| r.split_once(": ")) {
            Some((name, meaning)) if !name.contains(' ') => {
                params.push((name.trim_matches('`').to_string(), meaning.to_string()));
                in_param = true;
            }
            // An indented line right after a parameter's line goes on with its meaning.
            _ if in_param && l.starts_with("  ") && !l.trim().is_empty() => {
                if let Some((_, meaning)) = params.last_mut() {
                    meaning.push(' ');
                    meaning.push_str(l.trim());
                }
            }
            _ => {
                description.push(l.to_string());
                in_param = false;
            }
        }
    }
    (description, params)
}

/// One component's section of the reference, in Markdown.
pub fn entry_markdown(e: &Entry) -> String {
    let mut out = String::new();
    write_entry(&mut out, e);
    out
}

fn write_entry(out: &mut String, e: &Entry) {
    let _ = writeln!(out, "### {}\n", e.name);
    if !e.description.is_empty() {
        let _ = writeln!(out, "{}\n", e.description.join("\n"));
    }
    if !e.params.is_empty() {
        out.push_str("| parameter | type | default | meaning |\n|---|---|---|---|\n");
        for (n, t, d, m) in &e.params {
            let _ = writeln!(out, "| `{n}` | {t} | {d} | {} |", m.replace('|', "\\|"));
        }
        out.push('\n');
    }
    if !e.events.is_empty() {
        let ev: Vec<String> = e.events.iter().map(|n| format!("`on {n}`")).collect();
        let _ = writeln!(out, "Events: {}.\n", ev.join(", "));
    }
}

fn one_line(s: &str) -> String {
    s.split_whitespace().collect::<Vec<_>>().join(" ").replace('|', "\\|")
}

fn capitalise(s: &str) -> String {
    let mut c = s.chars();
    c.next().map_or(String::new(), |f| f.to_uppercase().collect::<String>() + c.as_str())
}
