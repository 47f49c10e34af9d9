//! Text to syntax tree. The parser never fails: it returns the items it could read and a
//! diagnostic for every item it could not.
//!
//! pest stops at the first error, so recovery happens one level up: [`split_items`] cuts the
//! file into top-level items at item keywords that start a line outside braces (or at column 0,
//! which also recovers from a missing `}`), and each item is parsed on its own.

use crate::ast::*;
use crate::codes;
use crate::diagnostics::Diagnostics;
use crate::source::{FileId, Span};
use pest::Parser as _;

mod build;
mod fast;
mod report;
mod split;

use build::Ctx;
pub(crate) use build::MAX_DEPTH;
use report::report_pest_error;
pub use split::{Chunk, ChunkKind, split_items};

#[derive(pest_derive::Parser)]
#[grammar = "grammar.pest"]
struct Grammar;

/// Keywords that begin a top-level item.
pub const ITEM_KEYWORDS: &[&str] =
    &["use", "let", "window", "in", "component", "bind", "menu", "watch", "for", "design"];

/// Parses one file. Syntax errors go to `diags`; the tree holds every item that parsed.
pub fn parse(file: FileId, text: &str, diags: &mut Diagnostics) -> File {
    parse_counted(file, text, diags).0
}

/// How many items of a file each parser read: the fast parser (parser/fast.rs), and pest,
/// which reads what the fast parser leaves (every item with a syntax error among them).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct ParseCounts {
    pub fast: usize,
    pub reference: usize,
}

/// [`parse`], and which parser read how many items.
pub fn parse_counted(file: FileId, text: &str, diags: &mut Diagnostics) -> (File, ParseCounts) {
    // Lexical problems are reported once, at their start; the items they touch are skipped.
    let scan = crate::lexer::scan(file, text, diags);
    let mut counts = ParseCounts::default();
    let chunks = split_items(text);
    let mut items = Vec::with_capacity(chunks.len());
    for chunk in chunks {
        parse_chunk(file, text, &scan, &chunk, diags, &mut counts, &mut items);
    }
    (File { items }, counts)
}

/// The items of a file that [`parse_resident`] left for later, read in order by
/// [`parse_later`].
#[derive(Debug)]
pub struct Deferred {
    scan: crate::lexer::Scan,
    /// Their chunks, in file order.
    pub chunks: Vec<Chunk>,
}

impl Deferred {
    /// The chunks in runs of about `bytes` of source each (at least one chunk a run).
    pub fn batches(&self, bytes: usize) -> impl Iterator<Item = &[Chunk]> {
        let mut rest = &self.chunks[..];
        std::iter::from_fn(move || {
            let first = rest.first()?;
            let n = rest.iter().take_while(|c| c.end - first.start <= bytes).count().max(1);
            let (run, tail) = rest.split_at(n);
            rest = tail;
            Some(run)
        })
    }
}

/// [`parse`] for a check that reads a file in batches (`crate::lint`): the items that other
/// items name (`use`, `let`, `window`, `for each`, `design`) are read now; `in`, `bind`,
/// `menu` and `watch` items, which nothing names, are left for [`parse_later`]; a `component`
/// is read now without its body (its parameters are what widgets need) and again, whole,
/// later. Every syntax error is reported once, by whichever read comes first.
pub fn parse_resident(file: FileId, text: &str, diags: &mut Diagnostics) -> (File, Deferred) {
    let scan = crate::lexer::scan(file, text, diags);
    let mut counts = ParseCounts::default();
    let mut items = Vec::new();
    let mut later = Vec::new();
    for chunk in split_items(text) {
        let whole =
            matches!(chunk.kind, ChunkKind::Item) && !scan.is_broken(chunk.start..chunk.end);
        match first_word(&text[chunk.start..chunk.end]) {
            "in" | "bind" | "menu" | "watch" if whole => later.push(chunk),
            "component" if whole => {
                let n = items.len();
                parse_chunk(file, text, &scan, &chunk, diags, &mut counts, &mut items);
                if items.len() > n
                    && let Some(Item::Component(c)) = items.last_mut()
                {
                    c.body = Vec::new();
                    later.push(chunk);
                }
            }
            _ => parse_chunk(file, text, &scan, &chunk, diags, &mut counts, &mut items),
        }
    }
    items.shrink_to_fit();
    later.shrink_to_fit();
    (File { items }, Deferred { scan, chunks: later })
}

/// Reads chunks that [`parse_resident`] left (a component's again, whole).
pub fn parse_later(
    file: FileId,
    text: &str,
    deferred: &Deferred,
    chunks: &[Chunk],
    diags: &mut Diagnostics,
) -> Vec<Item> {
    let mut counts = ParseCounts::default();
    let mut items = Vec::with_capacity(chunks.len());
    for chunk in chunks {
        parse_chunk(file, text, &deferred.scan, chunk, diags, &mut counts, &mut items);
    }
    items
}

/// Reads one chunk of the file into `items` (none when it is broken or not an item; a
/// broken `let` still defines its name), reporting its syntax errors.
fn parse_chunk(
    file: FileId,
    text: &str,
    scan: &crate::lexer::Scan,
    chunk: &Chunk,
    diags: &mut Diagnostics,
    counts: &mut ParseCounts,
    items: &mut Vec<Item>,
) {
    if scan.is_broken(chunk.start..chunk.end) {
        items.extend(broken_let(file, text, chunk));
        return;
    }
    match chunk.kind {
        ChunkKind::Stray => {
            let word = first_word(&text[chunk.start..chunk.end]);
            diags
                .error(codes::STRAY_TEXT, Span::new(file, chunk.start, chunk.start + word.len()), format!("`{word}` is not the start of an item"))
                .label("expected an item here")
                .help(crate::syntax_hints::stray(word).unwrap_or_else(|| "a file is made of `use`, `let`, `window`, `in`, `component`, `bind`, `menu`, `watch` and `for each` items".into()));
        }
        // An unclosed comment or string after it took the rest of the file: said there.
        ChunkKind::Unclosed(open)
            if scan.broken.iter().any(|b| b.start > open && b.end >= text.len()) => {}
        ChunkKind::Unclosed(open) => {
            diags
                .error(codes::UNCLOSED, Span::new(file, open, open + 1), "this `{` is never closed")
                .label("unclosed")
                .help("add the matching `}` before the next item");
        }
        ChunkKind::Item => {
            let src = &text[chunk.start..chunk.end];
            if let Some(item) = fast::parse_item(file, src, chunk.start) {
                counts.fast += 1;
                items.push(item);
                return;
            }
            counts.reference += 1;
            match parse_item(file, src, chunk.start) {
                Parsed::Item(item) => items.push(*item),
                Parsed::Nothing => {}
                Parsed::TooDeep(span) => {
                    items.extend(broken_let(file, text, chunk));
                    diags
                        .error(
                            codes::TOO_DEEP,
                            span,
                            format!("this expression is nested deeper than {MAX_DEPTH} levels"),
                        )
                        .label("too deep")
                        .help("split it with `let`s");
                }
                Parsed::Error(e) => {
                    report_pest_error(file, text, chunk.start, src, &e, diags);
                    items.extend(broken_let(file, text, chunk));
                }
            }
        }
    }
}

/// One item chunk (`src`, at `offset` in the file) read by the fast parser (parser/fast.rs):
/// the tree, or `None` where it leaves the item to pest. Where it gives a tree, the tree is
/// the one [`reference_item`] gives (tests/fast_parser.rs).
pub fn fast_item(file: FileId, src: &str, offset: usize) -> Option<Item> {
    fast::parse_item(file, src, offset)
}

/// One item chunk read by the reference parser (grammar.pest): the tree, or `None` where it
/// refuses the item (a syntax error, or nesting past the limit).
pub fn reference_item(file: FileId, src: &str, offset: usize) -> Option<Item> {
    match parse_item(file, src, offset) {
        Parsed::Item(item) => Some(*item),
        _ => None,
    }
}

/// What one item chunk parsed to.
enum Parsed {
    Item(Box<Item>),
    /// Nothing to keep (an empty parse).
    Nothing,
    /// Parsed, but nested past [`MAX_DEPTH`] here.
    TooDeep(Span),
    Error(Box<pest::error::Error<Rule>>),
}

/// Nesting (brackets plus `if`s) up to which an item is parsed on the caller's stack.
const INLINE_NESTING: usize = 48;
/// Stack given per level of nesting to an item parsed on its own thread (generous: debug
/// builds use far more per level than release builds).
const STACK_PER_LEVEL: usize = 32 << 10;

/// Parses one item chunk (`src`, at `offset` in the file).
///
/// pest recurses once per bracket and per `if` (`if a then 1 else if b then …` nests without
/// brackets), and pest's own stack probe costs about a fifth of the parse, so it is off (no
/// `std` feature) and the depth is bounded here instead: the lexer refuses brackets deeper
/// than [`crate::lexer::MAX_NESTING`], and an item with more nesting than [`INLINE_NESTING`]
/// is parsed on a thread whose stack fits it. The syntax tree builder then refuses what is
/// deeper than [`MAX_DEPTH`].
fn parse_item(file: FileId, src: &str, offset: usize) -> Parsed {
    let nesting = nesting_bound(src);
    if nesting <= INLINE_NESTING {
        return parse_item_here(file, src, offset);
    }
    let stack = (1 << 20) + nesting.saturating_mul(STACK_PER_LEVEL);
    std::thread::scope(|scope| {
        std::thread::Builder::new()
            .name("mocu-parse-deep".into())
            .stack_size(stack)
            .spawn_scoped(scope, || parse_item_here(file, src, offset))
            .ok()
            .and_then(|handle| handle.join().ok())
            .unwrap_or(Parsed::TooDeep(Span::new(file, offset, offset + 1)))
    })
}

/// An upper bound of how deeply pest will recurse in `src`: the deepest bracket nesting plus
/// every `if` (each could nest in the one before).
fn nesting_bound(src: &str) -> usize {
    let b = src.as_bytes();
    let (mut depth, mut deepest, mut ifs) = (0usize, 0usize, 0usize);
    for (i, &c) in b.iter().enumerate() {
        match c {
            b'(' | b'[' | b'{' => {
                depth += 1;
                deepest = deepest.max(depth);
            }
            b')' | b']' | b'}' => depth = depth.saturating_sub(1),
            b'i' if b.get(i + 1) == Some(&b'f')
                && (i == 0 || !is_ident_byte(b[i - 1]))
                && b.get(i + 2).is_none_or(|&n| !is_ident_byte(n)) =>
            {
                ifs += 1
            }
            _ => {}
        }
    }
    deepest + ifs
}

fn is_ident_byte(c: u8) -> bool {
    c.is_ascii_alphanumeric() || c == b'_'
}

fn parse_item_here(file: FileId, src: &str, offset: usize) -> Parsed {
    let mut pairs = match Grammar::parse(Rule::item_only, src) {
        Ok(pairs) => pairs,
        Err(e) => return Parsed::Error(Box::new(e)),
    };
    let ctx = Ctx { file, offset, depth: 0.into(), too_deep: None.into() };
    let Some(top) = pairs.next() else { return Parsed::Nothing };
    let Some(item) = top.into_inner().find(|p| p.as_rule() != Rule::EOI) else {
        return Parsed::Nothing;
    };
    let item = ctx.item(item);
    match ctx.too_deep.get() {
        None => Parsed::Item(Box::new(item)),
        Some(span) => Parsed::TooDeep(span),
    }
}

/// A `let NAME` item whose value did not parse (already reported) still defines `NAME`, with
/// an error value, so that its uses do not report it unknown.
fn broken_let(file: FileId, text: &str, chunk: &Chunk) -> Option<Item> {
    let src = &text[chunk.start..chunk.end];
    let rest = src.strip_prefix("let")?;
    let trimmed = rest.trim_start();
    if trimmed.len() == rest.len() {
        return None;
    }
    let name_at = chunk.start + 3 + (rest.len() - trimmed.len());
    let len =
        trimmed.find(|c: char| !(c.is_ascii_alphanumeric() || c == '_')).unwrap_or(trimmed.len());
    let name = &trimmed[..len];
    if name.is_empty() || name.starts_with(|c: char| c.is_ascii_digit()) {
        return None;
    }
    let span = Span::new(file, chunk.start, chunk.end);
    Some(Item::Let(Let {
        name: Ident { name: name.to_string(), span: Span::new(file, name_at, name_at + len) },
        value: Expr { kind: ExprKind::Error, span },
        span,
    }))
}

fn first_word(s: &str) -> &str {
    let s = s.trim_start();
    let end = s
        .char_indices()
        .find(|(i, c)| c.is_whitespace() || (*i > 0 && !c.is_alphanumeric() && *c != '_'))
        .map_or(s.len(), |(i, _)| i);
    if end == 0 {
        s.get(..s.chars().next().map_or(0, char::len_utf8)).unwrap_or("")
    } else {
        &s[..end]
    }
}
