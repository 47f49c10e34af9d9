//! Cutting a file into top-level items, before any of them is parsed (parser.rs).

use super::ITEM_KEYWORDS;
use crate::script_text;

#[derive(Debug, PartialEq)]
pub enum ChunkKind {
    Item,
    Stray,
    /// An item whose braces never close; the offset of the unclosed `{`.
    Unclosed(usize),
}

#[derive(Debug)]
pub struct Chunk {
    pub start: usize,
    pub end: usize,
    pub kind: ChunkKind,
}

/// Cuts a file into top-level items (see the module comment). Comments, strings and
/// whitespace between items belong to no chunk.
///
/// Items are cut by brace depth, never by indentation: a `let` or `window` at column 0 inside
/// balanced braces (an unindented `for each` body) stays in its item. Only when some `{` is
/// never closed is the file cut again at item keywords in column 0, to recover from it.
pub fn split_items(text: &str) -> Vec<Chunk> {
    let by_depth = split_at(text, false);
    if by_depth.iter().all(|c| !matches!(c.kind, ChunkKind::Unclosed(_))) {
        return by_depth;
    }
    split_at(text, true)
}

fn split_at(text: &str, column0_splits: bool) -> Vec<Chunk> {
    let bytes = text.as_bytes();
    let mut starts: Vec<usize> = Vec::new();
    let mut unclosed: Vec<Option<usize>> = Vec::new();
    let mut depth_stack: Vec<usize> = Vec::new();
    let mut stray_start: Option<usize> = None;
    let mut stray: Vec<(usize, usize)> = Vec::new();
    // A UTF-8 byte order mark is not text.
    let mut i = if text.starts_with('\u{FEFF}') { 3 } else { 0 };
    let mut line_start = true;
    // The last code was the `}` that closed a top-level item: any item keyword may follow on
    // the same line (`window a { … } let x = 1`: whitespace is free).
    let mut item_closed = false;
    // The end of the last code (not whitespace, not comment) seen: where a chunk ends.
    let mut last_code = 0usize;
    let mut ends: Vec<usize> = Vec::new();
    while i < bytes.len() {
        if !column0_splits && !depth_stack.is_empty() {
            // Inside an item's braces no item starts: only strings, braces, comments and line
            // ends matter, so the names, numbers and operators between them are skipped.
            while i < bytes.len() {
                match bytes[i] {
                    b'"' | b'{' | b'}' | b'/' | b'\n' | b'#' => break,
                    b' ' | b'\t' | b'\r' => {}
                    _ => last_code = i + 1,
                }
                i += 1;
            }
            if i >= bytes.len() {
                break;
            }
        }
        let b = bytes[i];
        match b {
            b'\n' => {
                line_start = true;
                i += 1;
                continue;
            }
            b' ' | b'\t' | b'\r' => {
                i += 1;
                continue;
            }
            b'/' if bytes.get(i + 1) == Some(&b'/') => {
                while i < bytes.len() && bytes[i] != b'\n' {
                    i += 1;
                }
                continue;
            }
            b'/' if bytes.get(i + 1) == Some(&b'*') => {
                i += 2;
                while i < bytes.len() && !(bytes[i] == b'*' && bytes.get(i + 1) == Some(&b'/')) {
                    i += 1;
                }
                i = (i + 2).min(bytes.len());
                continue;
            }
            _ => {}
        }
        let at_line_start = line_start;
        line_start = false;
        let after_item = std::mem::take(&mut item_closed);
        let column0 = i == 0 || bytes[i - 1] == b'\n';
        let item_here = if depth_stack.is_empty() {
            // Mid-line, after an item's closing `}`, or at a keyword that cannot continue
            // an item (`let`, `window`, …: never part of an expression).
            at_line_start
                || after_item
                || (!starts.is_empty()
                    && !is_name_byte(bytes[i - 1])
                    && starts_keyword_in(MID_LINE_KEYWORDS, &bytes[i..]))
        } else {
            at_line_start && column0_splits && column0
        };
        if item_here && starts_keyword(&bytes[i..]) {
            if let Some(s) = stray_start.take() {
                stray.push((s, char_boundary(text, last_code.max(s))));
                debug_assert_eq!(stray.last().map(|x| x.1), Some(trim_end(text, s, i)));
            }
            if let Some(&previous) = starts.last() {
                unclosed.push(depth_stack.first().copied());
                ends.push(char_boundary(text, last_code.max(previous)));
            }
            depth_stack.clear();
            starts.push(i);
        } else if starts.is_empty() && stray_start.is_none() {
            stray_start = Some(i);
        }
        match b {
            b'"' => {
                i += 1;
                while i < bytes.len() && bytes[i] != b'"' && bytes[i] != b'\n' {
                    i += if bytes[i] == b'\\' { 2 } else { 1 };
                }
                i += 1;
                last_code = i.min(bytes.len());
                continue;
            }
            // A script's body is the engine's text: its braces, strings and comments are not
            // the language's (an unclosed one was reported by the lexer).
            b'#' if let Some(open) = script_text::body_open(bytes, i) => {
                i = script_text::body_end(bytes, open).unwrap_or(bytes.len());
                last_code = i;
                continue;
            }
            b'{' => depth_stack.push(i),
            b'}' => {
                item_closed = depth_stack.pop().is_some() && depth_stack.is_empty();
            }
            _ => {}
        }
        last_code = i + 1;
        i += 1;
    }
    if let Some(s) = stray_start.take() {
        stray.push((s, char_boundary(text, last_code.max(s))));
        debug_assert_eq!(stray.last().map(|x| x.1), Some(trim_end(text, s, text.len())));
    }
    if let Some(&last) = starts.last() {
        unclosed.push(depth_stack.first().copied());
        ends.push(char_boundary(text, last_code.max(last)));
    }
    let mut chunks: Vec<Chunk> = stray
        .into_iter()
        .map(|(start, end)| Chunk { start, end, kind: ChunkKind::Stray })
        .collect();
    for (n, &start) in starts.iter().enumerate() {
        let end = ends[n];
        debug_assert_eq!(
            end,
            trim_end(text, start, starts.get(n + 1).copied().unwrap_or(text.len()))
        );
        let kind = match unclosed.get(n).copied().flatten() {
            Some(open) => ChunkKind::Unclosed(open),
            None => ChunkKind::Item,
        };
        chunks.push(Chunk { start, end, kind });
    }
    chunks.sort_by_key(|c| c.start);
    chunks
}

/// `at`, or the next character boundary after it.
fn char_boundary(text: &str, at: usize) -> usize {
    let mut at = at.min(text.len());
    while !text.is_char_boundary(at) {
        at += 1;
    }
    at
}

/// The end of the last code (not whitespace, not comment) in `text[start..end]`: the chunk
/// ends [`split_at`] finds as it goes, checked against this in debug builds.
fn trim_end(text: &str, start: usize, end: usize) -> usize {
    let b = text.as_bytes();
    let mut last = start;
    let mut i = start;
    while i < end {
        match b[i] {
            b' ' | b'\t' | b'\r' | b'\n' => i += 1,
            b'/' if b.get(i + 1) == Some(&b'/') => {
                while i < end && b[i] != b'\n' {
                    i += 1;
                }
            }
            b'/' if b.get(i + 1) == Some(&b'*') => {
                i += 2;
                while i < end && !(b[i] == b'*' && b.get(i + 1) == Some(&b'/')) {
                    i += 1;
                }
                i = (i + 2).min(end);
            }
            b'#' if let Some(open) = script_text::body_open(b, i) => {
                i = script_text::body_end(b, open).unwrap_or(b.len()).min(end);
                last = i;
            }
            b'"' => {
                i += 1;
                while i < end && b[i] != b'"' && b[i] != b'\n' {
                    i += if b[i] == b'\\' { 2 } else { 1 };
                }
                i = (i + 1).min(end);
                last = i;
            }
            _ => {
                i += 1;
                last = i;
            }
        }
    }
    // Stay on a character boundary.
    let mut last = last.min(end);
    while !text.is_char_boundary(last) {
        last += 1;
    }
    last
}

/// Item keywords that no item contains at its top level (`in` and `for` do: `for each v in
/// …`, `menu for type …`; `design` may be a name).
const MID_LINE_KEYWORDS: &[&str] = &["use", "let", "window", "component", "bind", "menu", "watch"];

fn starts_keyword(rest: &[u8]) -> bool {
    starts_keyword_in(ITEM_KEYWORDS, rest)
}

fn is_name_byte(b: u8) -> bool {
    b.is_ascii_alphanumeric() || b == b'_'
}

fn starts_keyword_in(keywords: &[&str], rest: &[u8]) -> bool {
    keywords.iter().any(|k| {
        rest.starts_with(k.as_bytes()) && rest.get(k.len()).is_none_or(|c| !is_name_byte(*c))
    })
}
