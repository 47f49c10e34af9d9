//! Document symbols (the outline: windows and the widgets placed in them, lets, components
//! and their parameters, watches, menus, bindings, templates) and semantic tokens.

use crate::completion::KEYWORDS;
use crate::index::{Index, Kind};
use crate::text::LineIndex;
use lsp_types::{DocumentSymbol, SemanticToken, SemanticTokenType, SymbolKind};
use mocu_language::Span;
use mocu_language::ast::{Item, Param, Widget};

/// The outline of the document (module 0 of `index`).
pub fn document_symbols(index: &Index, path: &str) -> Vec<DocumentSymbol> {
    let text = index.text(path);
    let lines = LineIndex::new(text);
    let Some(m) = index.modules.first() else { return Vec::new() };
    m.ast.items.iter().filter_map(|i| item_symbol(&lines, i)).collect()
}

#[allow(deprecated)] // `DocumentSymbol::deprecated` must be written out.
fn symbol(
    lines: &LineIndex,
    name: String,
    detail: Option<String>,
    kind: SymbolKind,
    span: Span,
    sel: Span,
    children: Vec<DocumentSymbol>,
) -> DocumentSymbol {
    let range = lines.range(span.start as usize, span.end as usize);
    let mut selection_range = lines.range(sel.start as usize, sel.end as usize);
    if selection_range.start < range.start || selection_range.end > range.end {
        selection_range = range;
    }
    DocumentSymbol {
        name: if name.is_empty() { "?".into() } else { name },
        detail,
        kind,
        tags: None,
        deprecated: None,
        range,
        selection_range,
        children: (!children.is_empty()).then_some(children),
    }
}

fn item_symbol(lines: &LineIndex, item: &Item) -> Option<DocumentSymbol> {
    Some(match item {
        Item::Let(l) => symbol(
            lines,
            l.name.name.clone(),
            Some("let".into()),
            SymbolKind::VARIABLE,
            l.span,
            l.name.span,
            Vec::new(),
        ),
        Item::Window(w) => symbol(
            lines,
            w.name.name.clone(),
            Some("window".into()),
            SymbolKind::STRUCT,
            w.span,
            w.name.span,
            Vec::new(),
        ),
        Item::In(b) => {
            let widgets = b.widgets.iter().map(|w| widget_symbol(lines, w)).collect();
            symbol(
                lines,
                format!("in {}", b.window.name),
                None,
                SymbolKind::NAMESPACE,
                b.span,
                b.window.span,
                widgets,
            )
        }
        Item::Component(c) => {
            let params = c
                .params
                .iter()
                .map(|p| {
                    let n = p.name();
                    let (kind, detail) = match p {
                        Param::Value { ty, .. } => (
                            SymbolKind::PROPERTY,
                            ty.as_ref().map(|t| {
                                format!("{}{}", t.name.name, if t.optional { "?" } else { "" })
                            }),
                        ),
                        Param::Event { .. } => (SymbolKind::EVENT, Some("event".into())),
                    };
                    symbol(lines, n.name.clone(), detail, kind, n.span, n.span, Vec::new())
                })
                .collect();
            symbol(
                lines,
                c.name.name.clone(),
                Some("component".into()),
                SymbolKind::CLASS,
                c.span,
                c.name.span,
                params,
            )
        }
        Item::Watch(w) => symbol(
            lines,
            w.name.name.clone(),
            Some("watch".into()),
            SymbolKind::EVENT,
            w.span,
            w.name.span,
            Vec::new(),
        ),
        Item::Menu(m) => symbol(
            lines,
            format!("menu for type \"{}\"", m.object_type),
            None,
            SymbolKind::ENUM,
            m.span,
            m.type_span,
            Vec::new(),
        ),
        Item::Bind(b) => symbol(
            lines,
            format!("bind {}", b.device.name),
            None,
            SymbolKind::INTERFACE,
            b.span,
            b.device.span,
            Vec::new(),
        ),
        Item::Each(e) => {
            let inner = e.items.iter().filter_map(|i| item_symbol(lines, i)).collect();
            symbol(
                lines,
                format!("for each {}", e.var.name),
                None,
                SymbolKind::NAMESPACE,
                e.span,
                e.var.span,
                inner,
            )
        }
        Item::Use(u) => symbol(
            lines,
            format!("use \"{}\"", u.path),
            None,
            SymbolKind::FILE,
            u.span,
            u.path_span,
            Vec::new(),
        ),
        Item::Design(_) => return None,
    })
}

fn widget_symbol(lines: &LineIndex, w: &Widget) -> DocumentSymbol {
    let (name, sel) = match &w.name {
        Some(n) => (n.name.clone(), n.span),
        None => (w.component.name.clone(), w.component.span),
    };
    symbol(lines, name, Some(w.component.name.clone()), SymbolKind::OBJECT, w.span, sel, Vec::new())
}

/// The token types, in the legend's order.
pub const TOKEN_TYPES: &[SemanticTokenType] = &[
    SemanticTokenType::KEYWORD,
    SemanticTokenType::VARIABLE,
    SemanticTokenType::CLASS,
    SemanticTokenType::PARAMETER,
    SemanticTokenType::FUNCTION,
    SemanticTokenType::STRUCT,
    SemanticTokenType::EVENT,
    SemanticTokenType::STRING,
    SemanticTokenType::NUMBER,
    SemanticTokenType::COMMENT,
    SemanticTokenType::PROPERTY,
];

fn type_index(t: SemanticTokenType) -> u32 {
    TOKEN_TYPES.iter().position(|x| *x == t).unwrap_or(0) as u32
}

/// Semantic tokens of the document: comments, strings, numbers, keywords, and names by what
/// they resolve to (lets, components, parameters, windows, watches, functions).
pub fn semantic_tokens(index: &Index, path: &str) -> Vec<SemanticToken> {
    let text = index.text(path);
    let lines = LineIndex::new(text);
    let mut names: std::collections::HashMap<u32, Kind> = std::collections::HashMap::new();
    for o in index.occurrences.iter().filter(|o| o.path == path) {
        if let Some(d) = index.defs.get(&o.def) {
            names.insert(o.start, d.kind);
        }
    }
    let mut raw: Vec<(usize, usize, u32)> = Vec::new();
    let b = text.as_bytes();
    let mut i = 0;
    while i < b.len() {
        let c = b[i];
        let start = i;
        if c == b'/' && b.get(i + 1) == Some(&b'/') {
            while i < b.len() && b[i] != b'\n' {
                i += 1;
            }
            raw.push((start, i, type_index(SemanticTokenType::COMMENT)));
        } else if c == b'"' {
            i += 1;
            while i < b.len() && b[i] != b'"' && b[i] != b'\n' {
                i += if b[i] == b'\\' { 2 } else { 1 };
            }
            i = (i + 1).min(b.len());
            raw.push((start, i, type_index(SemanticTokenType::STRING)));
        } else if c.is_ascii_digit() {
            while i < b.len() && (b[i].is_ascii_alphanumeric() || b[i] == b'.' || b[i] == b'%') {
                i += 1;
            }
            raw.push((start, i, type_index(SemanticTokenType::NUMBER)));
        } else if c.is_ascii_alphabetic() || c == b'_' {
            while i < b.len() && (b[i].is_ascii_alphanumeric() || b[i] == b'_') {
                i += 1;
            }
            let word = &text[start..i];
            let after_dot = start > 0 && b[start - 1] == b'.';
            let ty = match names.get(&(start as u32)) {
                Some(Kind::Let | Kind::Local | Kind::Widget) => Some(SemanticTokenType::VARIABLE),
                Some(Kind::Component) => Some(SemanticTokenType::CLASS),
                Some(Kind::Param) => Some(SemanticTokenType::PARAMETER),
                Some(Kind::Window) => Some(SemanticTokenType::STRUCT),
                Some(Kind::Watch) => Some(SemanticTokenType::EVENT),
                None if !after_dot && KEYWORDS.contains(&word) => Some(SemanticTokenType::KEYWORD),
                None if b.get(i) == Some(&b'(') => Some(SemanticTokenType::FUNCTION),
                None if after_dot => Some(SemanticTokenType::PROPERTY),
                None => None,
            };
            if let Some(t) = ty {
                raw.push((start, i, type_index(t)));
            }
        } else {
            i += if c < 0x80 { 1 } else { text[i..].chars().next().map_or(1, char::len_utf8) };
        }
    }
    let mut out = Vec::with_capacity(raw.len());
    let (mut line, mut col) = (0, 0);
    for (s, e, t) in raw {
        let p = lines.position(s);
        let q = lines.position(e);
        if q.line != p.line {
            continue;
        }
        let delta_line = p.line - line;
        let delta_start = if delta_line == 0 { p.character - col } else { p.character };
        out.push(SemanticToken {
            delta_line,
            delta_start,
            length: q.character - p.character,
            token_type: t,
            token_modifiers_bitset: 0,
        });
        (line, col) = (p.line, p.character);
    }
    out
}
