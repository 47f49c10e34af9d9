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
use pest::iterators::{Pair, Pairs};

mod fast;

#[derive(pest_derive::Parser)]
#[grammar = "grammar.pest"]
struct Grammar;

/// Keywords that begin a top-level item.
pub const ITEM_KEYWORDS: &[&str] =
    &["use", "let", "window", "in", "component", "bind", "menu", "watch", "for", "design"];

/// Parses one file. Syntax errors go to `diags`; the tree holds every item that parsed.
pub fn parse(file: FileId, text: &str, diags: &mut Diagnostics) -> File {
    // Lexical problems are reported once, at their start; the items they touch are skipped.
    let scan = crate::lexer::scan(file, text, diags);
    let mut items = Vec::new();
    for chunk in split_items(text) {
        if scan.is_broken(chunk.start..chunk.end) {
            items.extend(broken_let(file, text, &chunk));
            continue;
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
                    .error(
                        codes::UNCLOSED,
                        Span::new(file, open, open + 1),
                        "this `{` is never closed",
                    )
                    .label("unclosed")
                    .help("add the matching `}` before the next item");
            }
            ChunkKind::Item => {
                let src = &text[chunk.start..chunk.end];
                match parse_item(file, src, chunk.start) {
                    Parsed::Item(item) => items.push(*item),
                    Parsed::Nothing => {}
                    Parsed::TooDeep(span) => {
                        items.extend(broken_let(file, text, &chunk));
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
                        items.extend(broken_let(file, text, &chunk));
                    }
                }
            }
        }
    }
    File { items }
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
    while i < bytes.len() {
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
                stray.push((s, trim_end(text, s, i)));
            }
            if !starts.is_empty() {
                unclosed.push(depth_stack.first().copied());
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
                continue;
            }
            b'{' => depth_stack.push(i),
            b'}' => {
                item_closed = depth_stack.pop().is_some() && depth_stack.is_empty();
            }
            _ => {}
        }
        i += 1;
    }
    if let Some(s) = stray_start.take() {
        stray.push((s, trim_end(text, s, text.len())));
    }
    if !starts.is_empty() {
        unclosed.push(depth_stack.first().copied());
    }
    let mut chunks: Vec<Chunk> = stray
        .into_iter()
        .map(|(start, end)| Chunk { start, end, kind: ChunkKind::Stray })
        .collect();
    for (n, &start) in starts.iter().enumerate() {
        let end = trim_end(text, start, starts.get(n + 1).copied().unwrap_or(text.len()));
        let kind = match unclosed.get(n).copied().flatten() {
            Some(open) => ChunkKind::Unclosed(open),
            None => ChunkKind::Item,
        };
        chunks.push(Chunk { start, end, kind });
    }
    chunks.sort_by_key(|c| c.start);
    chunks
}

/// The end of the last code (not whitespace, not comment) in `text[start..end]`.
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

fn report_pest_error(
    file: FileId,
    text: &str,
    offset: usize,
    src: &str,
    e: &pest::error::Error<Rule>,
    diags: &mut Diagnostics,
) {
    use pest::error::{ErrorVariant, InputLocation};
    let pos = match e.location {
        InputLocation::Pos(p) => p,
        InputLocation::Span((s, _)) => s,
    };
    let found = found_token(&src[pos.min(src.len())..]);
    let span = Span::new(
        file,
        offset + pos,
        offset + pos + found.len().max(1).min(src.len().saturating_sub(pos).max(1)),
    );
    let (mut message, mut help) = match &e.variant {
        ErrorVariant::ParsingError { positives, .. } => describe_expected(positives, &found),
        ErrorVariant::CustomError { message } => (message.clone(), None),
    };
    let before = &src[..pos.min(src.len())];
    let after = &src[pos.min(src.len())..];
    let item = crate::syntax_hints::inner_item(first_word(src), before);
    if let Some((m, h)) = crate::syntax_hints::hint(item, before, &found, &message, after) {
        message = m.unwrap_or(message);
        help = Some(h);
    }
    let d = diags.error(codes::SYNTAX, span, message);
    if found.is_empty() {
        d.label("the item ends here");
    }
    if found == "}"
        && let Some(open) = crate::syntax_hints::opening_of(before)
    {
        let line = text[..offset + open].matches('\n').count() + 1;
        let head = before[..=open].rsplit('\n').next().unwrap_or("").trim();
        let note = format!("this `}}` closes `{head}` from line {line}");
        if d.help.is_none() {
            d.help(note.clone());
        }
        d.label(note);
    }
    if let Some(h) = help {
        d.help(h);
    }
}

fn found_token(rest: &str) -> String {
    let t = first_word(rest);
    t.to_string()
}

fn describe_expected(positives: &[Rule], found: &str) -> (String, Option<String>) {
    let mut names: Vec<&str> = Vec::new();
    let mut operator = false;
    for r in positives {
        let name = match r {
            Rule::EOI => "the end of the item",
            Rule::ident => "a name",
            Rule::expr
            | Rule::if_expr
            | Rule::paren
            | Rule::boolean
            | Rule::self_ref
            | Rule::colour => "an expression",
            Rule::number | Rule::geom => "a number",
            Rule::string => "a string",
            Rule::rect_prop => "`rect`",
            Rule::anchor_prop | Rule::anchor_key => "`anchor`",
            Rule::anchor_name => "an anchor (`top-left`, `bottom-right`, `centre`, …)",
            Rule::design_key => "`design`",
            Rule::named_prop => "a property",
            Rule::at_prop => "`at`",
            Rule::on_prop => "`on`",
            Rule::widget => "a widget",
            Rule::param | Rule::value_param | Rule::event_param => "a parameter",
            Rule::type_name => "a type",
            Rule::primitive | Rule::style | Rule::style_key => "a drawing primitive",
            Rule::binding => "a binding",
            Rule::input_name => "an input name",
            Rule::menu_entry => "`item`",
            Rule::set_action
            | Rule::call_action
            | Rule::swap_action
            | Rule::show_action
            | Rule::hide_action
            | Rule::alert_action
            | Rule::mode_action
            | Rule::select_action => {
                "an action (`set`, `call`, `swap`, `show`, `hide`, `alert`, `mode` or `select`)"
            }
            Rule::binding_opt | Rule::opt_key | Rule::opt_value => "a binding option or `->`",
            Rule::shift_decl | Rule::mode_block | Rule::shift_mark => "a binding",
            Rule::infix | Rule::field | Rule::index | Rule::call_args => {
                operator = true;
                continue;
            }
            Rule::neg | Rule::not_op | Rule::term | Rule::primary => "an expression",
            Rule::use_item
            | Rule::let_item
            | Rule::window_item
            | Rule::in_item
            | Rule::component_item
            | Rule::bind_item
            | Rule::menu_item
            | Rule::watch_item
            | Rule::each_item
            | Rule::design_item => "an item",
            Rule::str_text | Rule::str_escape | Rule::interp => "the end of the string (`\"`)",
            Rule::fmt_spec | Rule::fmt_body => "`}`",
            _ => "something else",
        };
        if !names.contains(&name) {
            names.push(name);
        }
    }
    if operator && names.is_empty() {
        names.push("an operator");
    }
    let expected = match names.len() {
        0 => "something else".to_string(),
        1 => names[0].to_string(),
        _ => format!("{} or {}", names[..names.len() - 1].join(", "), names[names.len() - 1]),
    };
    let found_text =
        if found.is_empty() { "the end of the item".to_string() } else { format!("`{found}`") };
    let help = if names.contains(&"the end of the item") {
        Some("is an operator or a `}` missing before this, or is this word misspelt?".to_string())
    } else if found.is_empty() {
        Some("the item is unfinished: something is missing before the next item".to_string())
    } else {
        None
    };
    (format!("expected {expected}, found {found_text}"), help)
}

/// How tightly a binary operator (the text of an `infix` pair) binds, and how it associates:
/// `..` < `or` < `and` < comparisons < `??` (right) < `+ -` < `* /` < prefixes (`-`, `not`).
fn binary(op: &str) -> (BinOp, u8, Assoc) {
    match op {
        ".." => (BinOp::Range, 10, Assoc::Left),
        "||" | "or" => (BinOp::Or, 20, Assoc::Left),
        "&&" | "and" => (BinOp::And, 30, Assoc::Left),
        "==" => (BinOp::Eq, 40, Assoc::Left),
        "!=" => (BinOp::Ne, 40, Assoc::Left),
        "<" => (BinOp::Lt, 40, Assoc::Left),
        "<=" => (BinOp::Le, 40, Assoc::Left),
        ">" => (BinOp::Gt, 40, Assoc::Left),
        ">=" => (BinOp::Ge, 40, Assoc::Left),
        "??" => (BinOp::Coalesce, 50, Assoc::Right),
        "+" => (BinOp::Add, 60, Assoc::Left),
        "-" => (BinOp::Sub, 60, Assoc::Left),
        "*" => (BinOp::Mul, 70, Assoc::Left),
        _ => (BinOp::Div, 70, Assoc::Left),
    }
}

/// Binding power of the prefixes, above every binary operator.
const PREFIX: u8 = 80;

#[derive(Clone, Copy)]
enum Assoc {
    Left,
    Right,
}

struct Ctx {
    file: FileId,
    offset: usize,
    /// Current expression nesting, and where it first went past [`MAX_DEPTH`].
    depth: std::cell::Cell<usize>,
    too_deep: std::cell::Cell<Option<Span>>,
}

/// The deepest expression tree accepted (E0106): every operator, prefix, field, index, call
/// and bracket counts one level. Deeper ones are refused instead of risking the stack in the
/// later, recursive passes; the lexer ([`crate::lexer`]) already refused deep brackets.
pub(crate) const MAX_DEPTH: usize = 256;

impl Ctx {
    fn span(&self, p: &Pair<Rule>) -> Span {
        let s = p.as_span();
        Span::new(self.file, self.offset + s.start(), self.offset + s.end())
    }

    fn ident(&self, p: Pair<Rule>) -> Ident {
        Ident { span: self.span(&p), name: p.as_str().to_string() }
    }

    fn item(&self, p: Pair<Rule>) -> Item {
        let span = self.span(&p);
        let rule = p.as_rule();
        let mut inner = p.into_inner().peekable();
        match rule {
            Rule::design_item => {
                let mut n = inner.filter(|q| q.as_rule() == Rule::number).map(|q| self.number(q));
                let zero = Expr { kind: ExprKind::Number { value: 0.0, unit: None }, span };
                let width = n.next().unwrap_or_else(|| zero.clone());
                let height = n.next().unwrap_or(zero);
                Item::Design(Design { width, height, span })
            }
            Rule::use_item => {
                let s = inner.next().map(|s| (self.span(&s), self.plain_string(s)));
                let (path_span, path) = s.unwrap_or((span, String::new()));
                let alias = inner.next().map(|a| self.ident(a));
                Item::Use(Use { path, path_span, alias, span })
            }
            Rule::let_item => Item::Let(self.let_(span, inner)),
            Rule::window_item => {
                let name = self.next_ident(&mut inner, span);
                let mut rect = None;
                let mut anchor = None;
                let mut props = Vec::new();
                for q in inner {
                    match q.as_rule() {
                        Rule::rect_prop => {
                            rect = Some(q.into_inner().map(|g| self.geom(g)).collect())
                        }
                        Rule::anchor_prop => anchor = self.anchor(q),
                        _ => props.push(self.prop(q)),
                    }
                }
                Item::Window(Window { name, rect, anchor, props, span })
            }
            Rule::in_item => {
                let window = self.next_ident(&mut inner, span);
                let widgets = inner.map(|w| self.widget(w)).collect();
                Item::In(InBlock { window, widgets, span })
            }
            Rule::component_item => {
                let name = self.next_ident(&mut inner, span);
                let mut params = Vec::new();
                let mut body = Vec::new();
                for q in inner {
                    match q.as_rule() {
                        Rule::param => {
                            if let Some(x) = q.into_inner().next() {
                                params.push(self.param(x));
                            }
                        }
                        Rule::let_item => {
                            let s = self.span(&q);
                            body.push(Stmt::Let(self.let_(s, q.into_inner().peekable())));
                        }
                        _ => body.push(Stmt::Primitive(self.primitive(q))),
                    }
                }
                Item::Component(Component { name, params, body, span })
            }
            Rule::bind_item => {
                let device = self.next_ident(&mut inner, span);
                let mut shift = None;
                let mut bindings = Vec::new();
                let mut modes = Vec::new();
                for q in inner {
                    match q.as_rule() {
                        Rule::shift_decl => {
                            let s = self.span(&q);
                            shift = q.into_inner().next().map(|n| self.input_name(n, s));
                        }
                        Rule::mode_block => {
                            let s = self.span(&q);
                            let mut it = q.into_inner();
                            let name = self.next_ident(&mut it, s);
                            modes.push((name, it.map(|b| self.binding(b)).collect()));
                        }
                        _ => bindings.push(self.binding(q)),
                    }
                }
                Item::Bind(Bind { device, shift, bindings, modes, span })
            }
            Rule::menu_item => {
                let (type_span, object_type) = match inner.next() {
                    Some(s) => (self.span(&s), self.plain_string(s)),
                    None => (span, String::new()),
                };
                let entries = inner
                    .map(|e| {
                        let espan = self.span(&e);
                        let mut label = None;
                        let mut enabled = None;
                        let mut actions = Vec::new();
                        for q in e.into_inner() {
                            match q.as_rule() {
                                Rule::expr if label.is_none() => label = Some(self.expr(q)),
                                Rule::expr => enabled = Some(self.expr(q)),
                                _ => actions.push(self.action(q)),
                            }
                        }
                        let label =
                            label.unwrap_or(Expr { kind: ExprKind::Str(Vec::new()), span: espan });
                        MenuEntry { label, enabled, actions, span: espan }
                    })
                    .collect();
                Item::Menu(Menu { object_type, type_span, entries, span })
            }
            Rule::watch_item => {
                let name = self.next_ident(&mut inner, span);
                let mut when = None;
                let (mut hold, mut clear, mut repeat) = (None, None, None);
                let mut actions = Vec::new();
                for q in inner {
                    match q.as_rule() {
                        Rule::expr => when = Some(self.expr(q)),
                        Rule::watch_hold | Rule::watch_clear | Rule::watch_repeat => {
                            let rule = q.as_rule();
                            let e = q.into_inner().next().map(|e| self.expr(e));
                            match rule {
                                Rule::watch_hold => hold = e,
                                Rule::watch_clear => clear = e,
                                _ => repeat = e,
                            }
                        }
                        _ => actions.push(self.action(q)),
                    }
                }
                let when = when.unwrap_or(Expr { kind: ExprKind::Bool(false), span });
                Item::Watch(Watch { name, when, hold, clear, repeat, actions, span })
            }
            Rule::each_item => {
                let var = self.next_ident(&mut inner, span);
                let source = inner
                    .next()
                    .map_or(Expr { kind: ExprKind::Name("root".into()), span }, |e| self.expr(e));
                let mut object_type = None;
                let mut items = Vec::new();
                for q in inner {
                    if q.as_rule() == Rule::string {
                        let s = self.span(&q);
                        object_type = Some((self.plain_string(q), s));
                    } else {
                        items.push(self.item(q));
                    }
                }
                Item::Each(Each { var, source, object_type, items, span })
            }
            _ => Item::Let(Let {
                name: Ident { name: String::new(), span },
                value: Expr { kind: ExprKind::Bool(false), span },
                span,
            }),
        }
    }

    fn next_ident<'a>(&self, it: &mut impl Iterator<Item = Pair<'a, Rule>>, span: Span) -> Ident {
        it.next().map_or(Ident { name: String::new(), span }, |p| self.ident(p))
    }

    fn let_<'a>(&self, span: Span, mut inner: impl Iterator<Item = Pair<'a, Rule>>) -> Let {
        let name = self.next_ident(&mut inner, span);
        let value =
            inner.next().map_or(Expr { kind: ExprKind::Bool(false), span }, |e| self.expr(e));
        Let { name, value, span }
    }

    fn prop(&self, p: Pair<Rule>) -> Prop {
        let span = self.span(&p);
        let mut it = p.into_inner();
        let name = self.next_ident(&mut it, span);
        let value = it.next().map_or(Expr { kind: ExprKind::Bool(false), span }, |e| self.expr(e));
        Prop { name, value, span }
    }

    fn geom(&self, p: Pair<Rule>) -> Expr {
        let span = self.span(&p);
        let negative = p.as_str().trim_start().starts_with('-');
        let Some(inner) = p.into_inner().next() else {
            return Expr { kind: ExprKind::Number { value: 0.0, unit: None }, span };
        };
        let e = match inner.as_rule() {
            Rule::number => self.number(inner),
            _ => self.expr(inner),
        };
        if negative {
            Expr { kind: ExprKind::Unary(UnOp::Neg, Box::new(e)), span }
        } else {
            Expr { span, ..e }
        }
    }

    fn widget(&self, p: Pair<Rule>) -> Widget {
        let span = self.span(&p);
        let mut idents = Vec::new();
        let mut at = None;
        let mut anchor = None;
        let mut args = Vec::new();
        let mut handlers = Vec::new();
        for q in p.into_inner() {
            match q.as_rule() {
                Rule::ident => idents.push(self.ident(q)),
                Rule::at_prop => {
                    let s = self.span(&q);
                    at = Some((q.into_inner().map(|g| self.geom(g)).collect(), s));
                }
                Rule::anchor_prop => anchor = self.anchor(q),
                Rule::on_prop => {
                    let s = self.span(&q);
                    let mut it = q.into_inner();
                    let event = self.next_ident(&mut it, s);
                    handlers.push(Handler {
                        event,
                        actions: it.map(|a| self.action(a)).collect(),
                        span: s,
                    });
                }
                _ => args.push(self.prop(q)),
            }
        }
        let component = idents.pop().unwrap_or(Ident { name: String::new(), span });
        Widget { name: idents.pop(), component, at, anchor, args, handlers, span }
    }

    /// `anchor bottom-right`: the name, checked later (passes/check_anchors.rs).
    fn anchor(&self, p: Pair<Rule>) -> Option<Ident> {
        p.into_inner().find(|q| q.as_rule() == Rule::anchor_name).map(|q| self.ident(q))
    }

    fn input_name(&self, n: Pair<Rule>, _span: Span) -> Ident {
        let s = self.span(&n);
        Ident { name: n.as_str().trim_matches('"').to_string(), span: s }
    }

    fn binding(&self, b: Pair<Rule>) -> Binding {
        let bspan = self.span(&b);
        let mut shift = false;
        let mut kind = None;
        let mut input = None;
        let mut options = Vec::new();
        let mut actions = Vec::new();
        for q in b.into_inner() {
            match q.as_rule() {
                Rule::shift_mark => shift = true,
                Rule::ident if kind.is_none() => kind = Some(self.ident(q)),
                Rule::input_name => input = Some(self.input_name(q, bspan)),
                Rule::binding_opt => {
                    let s = self.span(&q);
                    let mut it = q.into_inner();
                    let name = self.next_ident(&mut it, s);
                    let value = it.next().map(|v| {
                        let vs = self.span(&v);
                        let negative = v.as_str().trim_start().starts_with('-');
                        let num = v.into_inner().find(|x| x.as_rule() == Rule::number).map_or(
                            Expr { kind: ExprKind::Number { value: 0.0, unit: None }, span: vs },
                            |n| self.number(n),
                        );
                        if negative {
                            Expr { kind: ExprKind::Unary(UnOp::Neg, Box::new(num)), span: vs }
                        } else {
                            num
                        }
                    });
                    options.push(BindingOption { name, value, span: s });
                }
                _ => actions.push(self.action(q)),
            }
        }
        Binding {
            shift,
            kind: kind.unwrap_or(Ident { name: String::new(), span: bspan }),
            input: input.unwrap_or(Ident { name: String::new(), span: bspan }),
            options,
            actions,
            span: bspan,
        }
    }

    fn param(&self, p: Pair<Rule>) -> Param {
        let span = self.span(&p);
        let rule = p.as_rule();
        let mut it = p.into_inner();
        let name = self.next_ident(&mut it, span);
        if rule == Rule::event_param {
            return Param::Event { name };
        }
        let mut ty = None;
        let mut default = None;
        for q in it {
            match q.as_rule() {
                Rule::type_name => {
                    let optional = q.as_str().ends_with('?');
                    let mut t = q.into_inner();
                    let n = self.next_ident(&mut t, span);
                    ty = Some(TypeName { name: n, optional });
                }
                _ => default = Some(self.expr(q)),
            }
        }
        Param::Value { name, ty, default }
    }

    fn primitive(&self, p: Pair<Rule>) -> Primitive {
        let span = self.span(&p);
        let mut it = p.into_inner();
        let kind = self.next_ident(&mut it, span);
        let mut args = Vec::new();
        let mut styles = Vec::new();
        for q in it {
            match q.as_rule() {
                Rule::style => {
                    let s = self.span(&q);
                    let mut si = q.into_inner();
                    let key =
                        si.next().map_or(Ident { name: String::new(), span: s }, |k| self.ident(k));
                    let value = si
                        .next()
                        .map_or(Expr { kind: ExprKind::Bool(false), span: s }, |e| self.expr(e));
                    styles.push(Prop { name: key, value, span: s });
                }
                _ => args.push(self.expr(q)),
            }
        }
        Primitive { kind, args, styles, span }
    }

    fn action(&self, p: Pair<Rule>) -> Action {
        let span = self.span(&p);
        let rule = p.as_rule();
        let mut it = p.into_inner();
        let dummy = || Expr { kind: ExprKind::Bool(false), span };
        let kind = match rule {
            Rule::set_action => {
                let target = it.next().map_or_else(dummy, |e| self.expr(e));
                let value = it.next().map_or_else(dummy, |e| self.expr(e));
                ActionKind::Set { target, value }
            }
            Rule::call_action => {
                ActionKind::Call { call: it.next().map_or_else(dummy, |e| self.expr(e)) }
            }
            Rule::swap_action => {
                let a = self.next_ident(&mut it, span);
                let b = self.next_ident(&mut it, span);
                ActionKind::Swap { a, b, duration: it.next().map(|n| self.number(n)) }
            }
            Rule::show_action => ActionKind::Show { window: self.next_ident(&mut it, span) },
            Rule::hide_action => ActionKind::Hide { window: self.next_ident(&mut it, span) },
            Rule::mode_action => ActionKind::Mode { mode: self.next_ident(&mut it, span) },
            Rule::select_action => {
                let target = match it.next() {
                    Some(q) if q.as_rule() == Rule::select_step => {
                        if q.as_str() == "next" {
                            SelectTarget::Next
                        } else {
                            SelectTarget::Prev
                        }
                    }
                    Some(q) => SelectTarget::Object(self.expr(q)),
                    None => SelectTarget::Next,
                };
                ActionKind::Select { target }
            }
            _ => {
                let level = self.next_ident(&mut it, span);
                ActionKind::Alert { level, message: it.next().map_or_else(dummy, |e| self.expr(e)) }
            }
        };
        Action { kind, span }
    }

    fn plain_string(&self, p: Pair<Rule>) -> String {
        let mut out = String::new();
        for q in p.into_inner() {
            match q.as_rule() {
                Rule::str_text => out.push_str(q.as_str()),
                Rule::str_escape => out.push_str(&unescape(q.as_str())),
                _ => out.push_str(q.as_str()),
            }
        }
        out
    }

    fn number(&self, p: Pair<Rule>) -> Expr {
        let span = self.span(&p);
        let text = p.as_str();
        let split = text.find(|c: char| !(c.is_ascii_digit() || c == '.')).unwrap_or(text.len());
        let value = text[..split].parse::<f64>().unwrap_or(0.0);
        let unit = match &text[split..] {
            "ms" => Some(LitUnit::Ms),
            "s" => Some(LitUnit::S),
            "min" => Some(LitUnit::Min),
            "px" => Some(LitUnit::Px),
            "deg" => Some(LitUnit::Deg),
            "%" => Some(LitUnit::Percent),
            _ => None,
        };
        Expr { kind: ExprKind::Number { value, unit }, span }
    }

    pub fn expr(&self, p: Pair<Rule>) -> Expr {
        let span = self.span(&p);
        let inner = p.into_inner();
        let depth = self.depth.get();
        // Operators and prefixes: each one level of the tree this builds.
        let cost = 1 + inner.clone().filter(|q| q.as_rule() != Rule::term).count();
        if self.refuse_deeper(depth + cost, span) {
            return Expr { kind: ExprKind::Bool(false), span };
        }
        self.depth.set(depth + cost);
        let e = self.expr_pairs(inner);
        self.depth.set(depth);
        e
    }

    /// True (and the first such place remembered) when `depth` passes [`MAX_DEPTH`].
    fn refuse_deeper(&self, depth: usize, span: Span) -> bool {
        if depth <= MAX_DEPTH && self.too_deep.get().is_none() {
            return false;
        }
        if self.too_deep.get().is_none() {
            self.too_deep.set(Some(Span { end: span.start + 1, ..span }));
        }
        true
    }

    fn expr_pairs(&self, pairs: Pairs<Rule>) -> Expr {
        self.climb(&mut pairs.peekable(), 0)
    }

    /// Precedence climbing over `prefix* term (infix prefix* term)*`: the operators that bind
    /// tighter than `floor` (Pratt's algorithm).
    fn climb(&self, pairs: &mut std::iter::Peekable<Pairs<Rule>>, floor: u8) -> Expr {
        let mut lhs = self.operand(pairs);
        while let Some(op) = pairs.peek().filter(|op| op.as_rule() == Rule::infix) {
            let (bin, power, assoc) = binary(op.as_str());
            if power <= floor {
                break;
            }
            pairs.next();
            let rhs = self.climb(pairs, if let Assoc::Right = assoc { power - 1 } else { power });
            let span = lhs.span.to(rhs.span);
            lhs = Expr { kind: ExprKind::Binary(bin, Box::new(lhs), Box::new(rhs)), span };
        }
        lhs
    }

    /// A term and the prefixes before it.
    fn operand(&self, pairs: &mut std::iter::Peekable<Pairs<Rule>>) -> Expr {
        let Some(p) = pairs.next() else {
            let at = Span::new(self.file, self.offset, self.offset);
            return Expr { kind: ExprKind::Bool(false), span: at };
        };
        match p.as_rule() {
            Rule::neg | Rule::not_op => {
                let rhs = self.climb(pairs, PREFIX - 1);
                let span = self.span(&p).to(rhs.span);
                let op = if p.as_rule() == Rule::neg { UnOp::Neg } else { UnOp::Not };
                Expr { kind: ExprKind::Unary(op, Box::new(rhs)), span }
            }
            _ => self.term(p),
        }
    }

    /// A primary and its postfixes (field, index, call).
    fn term(&self, p: Pair<Rule>) -> Expr {
        let span = self.span(&p);
        let mut it = p.into_inner();
        // Each postfix (`.a`, `["x"]`, `()`) is one level around the primary.
        let depth = self.depth.get();
        let postfixes = it.len().saturating_sub(1);
        if self.refuse_deeper(depth + postfixes, span) {
            return Expr { kind: ExprKind::Bool(false), span };
        }
        self.depth.set(depth + postfixes);
        let e = self.term_pairs(&mut it);
        self.depth.set(depth);
        e
    }

    fn term_pairs(&self, it: &mut Pairs<Rule>) -> Expr {
        let Some(first) = it.next() else {
            return Expr {
                kind: ExprKind::Bool(false),
                span: Span::new(self.file, self.offset, self.offset),
            };
        };
        let mut lhs = match first.into_inner().next() {
            Some(prim) => self.primary(prim),
            None => {
                return Expr {
                    kind: ExprKind::Bool(false),
                    span: Span::new(self.file, self.offset, self.offset),
                };
            }
        };
        for op in it {
            let span = lhs.span.to(self.span(&op));
            let kind = match op.as_rule() {
                Rule::field => {
                    let s = self.span(&op);
                    let name = op
                        .into_inner()
                        .next()
                        .map_or(Ident { name: String::new(), span: s }, |i| self.ident(i));
                    ExprKind::Field(Box::new(lhs), name)
                }
                Rule::index => {
                    let key =
                        op.into_inner().next().map(|s| self.plain_string(s)).unwrap_or_default();
                    ExprKind::Index(Box::new(lhs), key)
                }
                _ => ExprKind::Call(Box::new(lhs), op.into_inner().map(|a| self.expr(a)).collect()),
            };
            lhs = Expr { kind, span };
        }
        lhs
    }

    fn primary(&self, p: Pair<Rule>) -> Expr {
        let span = self.span(&p);
        let kind = match p.as_rule() {
            Rule::number => return self.number(p),
            Rule::paren => {
                return p.into_inner().next().map_or(
                    Expr { kind: ExprKind::Bool(false), span },
                    |e| Expr { span, ..self.expr(e) },
                );
            }
            Rule::if_expr => {
                let mut parts = p.into_inner().map(|e| Box::new(self.expr(e)));
                let dummy = || Box::new(Expr { kind: ExprKind::Bool(false), span });
                let c = parts.next().unwrap_or_else(dummy);
                let a = parts.next().unwrap_or_else(dummy);
                let b = parts.next().unwrap_or_else(dummy);
                ExprKind::If(c, a, b)
            }
            Rule::string => {
                let mut parts = Vec::new();
                for q in p.into_inner() {
                    match q.as_rule() {
                        Rule::str_text => push_text(&mut parts, q.as_str()),
                        Rule::str_escape => push_text(&mut parts, &unescape(q.as_str())),
                        _ => {
                            let mut it = q.into_inner();
                            let Some(e) = it.next() else { continue };
                            let expr = self.expr(e);
                            let spec = it.next().map(|s| {
                                let sp = self.span(&s);
                                (s.as_str().trim_start_matches(':').to_string(), sp)
                            });
                            parts.push(StrPart::Interp { expr, spec });
                        }
                    }
                }
                ExprKind::Str(parts)
            }
            Rule::colour => {
                let hex = &p.as_str()[1..];
                let v = u32::from_str_radix(hex, 16).unwrap_or(0);
                ExprKind::Colour(if hex.len() == 6 { (v << 8) | 0xff } else { v })
            }
            Rule::boolean => ExprKind::Bool(p.as_str() == "true"),
            Rule::self_ref => ExprKind::SelfRef,
            _ => ExprKind::Name(p.as_str().to_string()),
        };
        Expr { kind, span }
    }
}

fn push_text(parts: &mut Vec<StrPart>, s: &str) {
    if let Some(StrPart::Text(t)) = parts.last_mut() {
        t.push_str(s);
    } else {
        parts.push(StrPart::Text(s.to_string()));
    }
}

fn unescape(s: &str) -> String {
    match s {
        "{{" | "\\{" => "{".into(),
        "}}" | "\\}" => "}".into(),
        "\\n" => "\n".into(),
        "\\t" => "\t".into(),
        "\\\\" => "\\".into(),
        "\\\"" => "\"".into(),
        other => other.to_string(),
    }
}
