//! Completion: after a dot, what the project's schemas say may follow the path (objects,
//! properties with their types and units, methods); inside a widget, its component's
//! parameters (type, default, meaning) and events; elsewhere keywords, components, `let`s and
//! built-in functions.

use crate::check::Analysis;
use crate::hover::component_doc;
use crate::index::{Index, Kind};
use crate::live::LiveTree;
use crate::paths::{self, MemberKind};
use lsp_types::{CompletionItem, CompletionItemKind, Documentation, MarkupContent, MarkupKind};
use mocu_language::ast::Item;
use mocu_language::{builtins, docgen};

/// The layout language's words, with the item and clause words that are not reserved.
pub const KEYWORDS: &[&str] = &[
    "use",
    "as",
    "let",
    "design",
    "window",
    "in",
    "component",
    "bind",
    "menu",
    "watch",
    "for",
    "each",
    "of",
    "type",
    "when",
    "clear",
    "repeat",
    "every",
    "then",
    "on",
    "set",
    "call",
    "swap",
    "show",
    "hide",
    "alert",
    "mode",
    "select",
    "item",
    "enabled",
    "at",
    "anchor",
    "rect",
    "layer",
    "opacity",
    "visible",
    "source",
    "if",
    "else",
    "and",
    "or",
    "not",
    "true",
    "false",
    "self",
    "root",
];

pub fn complete(
    index: &Index,
    analysis: Option<&Analysis>,
    live: &dyn LiveTree,
    path: &str,
    offset: usize,
) -> Vec<CompletionItem> {
    let text = index.text(path);
    let before = &text[..offset.min(text.len())];
    // Inside `#js: { … }`: the script's language.
    if let Some(engine) = crate::script_completion::engine_at(text, offset) {
        return crate::script_completion::complete(engine, before);
    }
    // Inside `use "…`: files and folders.
    if let Some(typed) = crate::use_paths::typed(before) {
        let cursor = crate::text::LineIndex::new(text).position(offset);
        return crate::use_paths::complete(path, typed, cursor);
    }
    // After `a.b.`: the members of the path so far.
    let word_start = before.len()
        - before.bytes().rev().take_while(|b| b.is_ascii_alphanumeric() || *b == b'_').count();
    if before[..word_start].ends_with('.') {
        let Some((_, mut segs)) = paths::dotted_at(text, word_start - 1) else { return Vec::new() };
        segs.retain(|s| !s.is_empty());
        let segs = paths::expand(index, segs);
        let Some(a) = analysis else { return Vec::new() };
        if segs.first().map(String::as_str) != Some("root") {
            return Vec::new();
        }
        return crate::live::merge(live, &segs[1..], paths::members(&a.schema, &segs[1..]))
            .into_iter()
            .map(|m| CompletionItem {
                label: m.name,
                kind: Some(match m.kind {
                    MemberKind::Object => CompletionItemKind::MODULE,
                    MemberKind::Property => CompletionItemKind::FIELD,
                    MemberKind::Method => CompletionItemKind::METHOD,
                }),
                detail: Some(m.detail),
                ..CompletionItem::default()
            })
            .collect();
    }
    if let Some(inputs) = inputs_at(index, before, word_start, offset) {
        return inputs;
    }
    let mut out = Vec::new();
    if let Some((component, written)) = widget_at(index, offset) {
        out.extend(params_of(index, &component, &written));
    }
    for k in KEYWORDS {
        out.push(item(k, CompletionItemKind::KEYWORD, None, None));
    }
    for name in index.tables.visible_components(&index.modules, 0) {
        let doc = component_source(index, &name).and_then(|(p, t)| component_doc(&t, &p, &name));
        let native = builtins::native(&name).map(|n| n.doc.to_string());
        out.push(item(&name, CompletionItemKind::CLASS, Some("component".into()), doc.or(native)));
    }
    for def in index.defs.values().filter(|d| d.kind == Kind::Let) {
        if index.visible_let(&def.name).is_some_and(|v| v.start == def.start && v.path == def.path)
        {
            let ty = analysis
                .and_then(|a| a.let_types.get(&(def.path.clone(), def.value_start.unwrap_or(0))));
            out.push(item(&def.name, CompletionItemKind::VARIABLE, ty.cloned(), None));
        }
    }
    for f in builtins::FUNCTIONS {
        out.push(item(
            f.name,
            CompletionItemKind::FUNCTION,
            Some("built-in function".into()),
            Some(f.doc.to_string()),
        ));
    }
    out
}

fn item(
    label: &str,
    kind: CompletionItemKind,
    detail: Option<String>,
    doc: Option<String>,
) -> CompletionItem {
    CompletionItem {
        label: label.to_string(),
        kind: Some(kind),
        detail,
        documentation: doc.map(|value| {
            Documentation::MarkupContent(MarkupContent { kind: MarkupKind::Markdown, value })
        }),
        ..CompletionItem::default()
    }
}

/// In a `bind DEVICE { … }` block right after a binding kind (`button `, `axis `, `key `):
/// the device's inputs of that kind.
fn inputs_at(
    index: &Index,
    before: &str,
    word_start: usize,
    offset: usize,
) -> Option<Vec<CompletionItem>> {
    let o = offset as u32;
    let device = index.modules.first()?.ast.items.iter().find_map(|i| match i {
        Item::Bind(b) if b.span.start < o && o < b.span.end => Some(b.device.name.clone()),
        _ => None,
    })?;
    let kind = before[..word_start].trim_end().rsplit(|c: char| c.is_whitespace()).next()?;
    let (_, kinds) = builtins::DEVICES.iter().find(|(d, _)| *d == device)?;
    let (_, names) = kinds.iter().find(|(k, _)| *k == kind)?;
    let names: &[&str] = if kind == "key" { builtins::NAMED_KEYS } else { names };
    let detail = format!("{device} {kind}");
    Some(
        names
            .iter()
            .map(|n| item(n, CompletionItemKind::ENUM_MEMBER, Some(detail.clone()), None))
            .collect(),
    )
}

/// The widget of the document whose braces hold `offset`: its component and the parameters
/// already written.
fn widget_at(index: &Index, offset: usize) -> Option<(String, Vec<String>)> {
    let o = offset as u32;
    let m = index.modules.first()?;
    let blocks = m.ast.items.iter().flat_map(|i| match i {
        Item::In(b) => vec![b],
        Item::Each(e) => e
            .items
            .iter()
            .filter_map(|i| if let Item::In(b) = i { Some(b) } else { None })
            .collect(),
        _ => Vec::new(),
    });
    for b in blocks {
        for w in &b.widgets {
            let brace = w.component.span.end;
            if brace < o && o < w.span.end {
                return Some((
                    w.component.name.clone(),
                    w.args.iter().map(|a| a.name.name.clone()).collect(),
                ));
            }
        }
    }
    None
}

/// The file (path, text) that defines the component `name`, seen from the document.
fn component_source(index: &Index, name: &str) -> Option<(String, String)> {
    let id = index.tables.find_component(&index.modules, 0, name)?;
    let path = index.modules[id.module].path.clone();
    let text = index.text(&path).to_string();
    Some((path, text))
}

/// A component's parameters not yet written, with their type, default and meaning, and its
/// events as `on …`.
fn params_of(index: &Index, component: &str, written: &[String]) -> Vec<CompletionItem> {
    let mut out = Vec::new();
    if let Some(n) = builtins::native(component) {
        for (name, ty, has_default) in n.params {
            let d = if *has_default { "optional" } else { "required" };
            out.push(item(name, CompletionItemKind::PROPERTY, Some(format!("{ty}, {d}")), None));
        }
        for e in n.events {
            out.push(item(&format!("on {e}"), CompletionItemKind::EVENT, None, None));
        }
        return out;
    }
    let Some((path, text)) = component_source(index, component) else { return out };
    let Some(entry) = docgen::entries(&path, &text).into_iter().find(|e| e.name == component)
    else {
        return out;
    };
    for (name, ty, default, meaning) in &entry.params {
        if written.contains(name) {
            continue;
        }
        let detail = format!("{ty}, default {default}");
        out.push(item(
            name,
            CompletionItemKind::PROPERTY,
            Some(detail),
            (!meaning.is_empty()).then(|| meaning.clone()),
        ));
    }
    for e in &entry.events {
        out.push(item(&format!("on {e}"), CompletionItemKind::EVENT, None, None));
    }
    out
}
