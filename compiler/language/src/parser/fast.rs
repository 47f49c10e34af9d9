//! The fast parser: a hand-written recursive descent over bytes that builds exactly the syntax
//! tree the reference parser (grammar.pest and the tree builder in parser.rs) builds, spans
//! included, for every item it accepts.
//!
//! It follows the grammar rule by rule as a PEG (ordered choice, backtracking, greedy
//! repetition), with pest's implicit whitespace in the same places: between the elements of a
//! sequence outside atomic rules (so a rule whose last element is an unmatched `x?` or `x*`
//! ends after the whitespace that follows it, as pest's does), and before every repetition
//! but the first. Whenever it is not sure — an item it cannot read, nesting past
//! [`NEST_LIMIT`], an expression deeper than the builder's limit — it gives up and the item is
//! parsed by pest, so every syntax error and its message come from the reference parser.
//! `tests/fast_parser.rs` holds the two to the same trees.

mod expr;
mod items;

use crate::ast::{Ident, Item};
use crate::source::{FileId, Span};

/// Nested expressions (brackets, `if`s, interpolations) read on the caller's stack; deeper
/// items go to pest, which parses them on a stack of their own.
const NEST_LIMIT: usize = 40;

/// A keyword, which is not a name (grammar.pest, `keyword`).
fn is_keyword(word: &[u8]) -> bool {
    match word.len() {
        2 => matches!(word, b"in" | b"if" | b"or" | b"as"),
        3 => matches!(word, b"use" | b"let" | b"for" | b"and" | b"not"),
        4 => matches!(word, b"bind" | b"menu" | b"each" | b"then" | b"else" | b"true" | b"self"),
        5 => matches!(word, b"watch" | b"false"),
        6 => word == b"window",
        9 => word == b"component",
        _ => false,
    }
}

/// Parses one item chunk (`src`, at `offset` in the file): the tree, or `None` where the
/// reference parser must decide.
pub fn parse_item(file: FileId, src: &str, offset: usize) -> Option<Item> {
    let mut p = Fast {
        s: src,
        b: src.as_bytes(),
        pos: 0,
        file,
        offset,
        nest: 0,
        depth: 0,
        bail: false,
        elems: Vec::new(),
    };
    let item = p.item();
    p.ws();
    match item {
        Some(item) if !p.bail && p.pos == p.b.len() => Some(item),
        _ => None,
    }
}

/// The parser's state: the item's text and the position in it.
pub(super) struct Fast<'a> {
    s: &'a str,
    b: &'a [u8],
    pos: usize,
    file: FileId,
    offset: usize,
    /// Nested expressions being read (bounded by [`NEST_LIMIT`]).
    nest: usize,
    /// A lower bound of the expression depth the tree builder counts at this point.
    depth: usize,
    /// Gave up: the item goes to pest whatever the rest says.
    bail: bool,
    /// The flat lists of the expressions being read (expr.rs).
    elems: Vec<expr::Elem>,
}

fn is_ident_byte(c: u8) -> bool {
    c.is_ascii_alphanumeric() || c == b'_'
}

impl<'a> Fast<'a> {
    fn span(&self, start: usize, end: usize) -> Span {
        Span::new(self.file, self.offset + start, self.offset + end)
    }

    fn peek(&self) -> u8 {
        self.b.get(self.pos).copied().unwrap_or(0)
    }

    fn at(&self, i: usize) -> u8 {
        self.b.get(i).copied().unwrap_or(0)
    }

    /// pest's implicit whitespace: blanks, line comments and closed block comments.
    fn ws(&mut self) {
        let b = self.b;
        loop {
            match b.get(self.pos) {
                Some(b' ' | b'\t' | b'\n' | b'\r') => self.pos += 1,
                Some(b'/') => match b.get(self.pos + 1) {
                    Some(b'/') => {
                        self.pos += 2;
                        while self.pos < b.len() && b[self.pos] != b'\n' {
                            self.pos += 1;
                        }
                    }
                    Some(b'*') => {
                        let body = &b[self.pos + 2..];
                        match body.windows(2).position(|w| w == b"*/") {
                            Some(n) => self.pos += 2 + n + 2,
                            None => return,
                        }
                    }
                    _ => return,
                },
                _ => return,
            }
        }
    }

    /// A literal (pest's `"text"`: a prefix, with no word boundary).
    fn lit(&mut self, text: &[u8]) -> bool {
        if self.b[self.pos..].starts_with(text) {
            self.pos += text.len();
            true
        } else {
            false
        }
    }

    fn byte(&mut self, c: u8) -> bool {
        if self.peek() == c {
            self.pos += 1;
            true
        } else {
            false
        }
    }

    /// A word (`text` and no name character after it) at `self.pos`, without moving.
    fn word_here(&self, text: &[u8]) -> bool {
        self.b[self.pos..].starts_with(text) && !is_ident_byte(self.at(self.pos + text.len()))
    }

    /// The end of the run of name characters from `i`.
    fn ident_end(&self, mut i: usize) -> usize {
        while i < self.b.len() && is_ident_byte(self.b[i]) {
            i += 1;
        }
        i
    }

    /// `ident`: a name that is not a keyword.
    fn ident(&mut self) -> Option<Ident> {
        let c = self.peek();
        if !(c.is_ascii_alphabetic() || c == b'_') {
            return None;
        }
        let end = self.ident_end(self.pos + 1);
        let word = &self.b[self.pos..end];
        if is_keyword(word) {
            return None;
        }
        let ident =
            Ident { name: self.s[self.pos..end].to_string(), span: self.span(self.pos, end) };
        self.pos = end;
        Some(ident)
    }

    /// An atomic keyword rule (`"name" ~ !ident_char`) among `words`: its text and span.
    fn key_of(&mut self, words: &[&str]) -> Option<Ident> {
        let w = words.iter().find(|w| self.word_here(w.as_bytes()))?;
        let start = self.pos;
        self.pos += w.len();
        Some(Ident { name: (*w).to_string(), span: self.span(start, self.pos) })
    }

    /// Runs `f`; where it fails, the position goes back to where it was.
    fn attempt<T>(&mut self, f: impl FnOnce(&mut Self) -> Option<T>) -> Option<T> {
        let start = self.pos;
        let r = f(self);
        if r.is_none() {
            self.pos = start;
        }
        r
    }

    /// pest's `x*` outside atomic rules: `x`, then (whitespace, `x`) while that matches.
    /// `one` reads one `x` and returns false (position unchanged) where it does not match.
    fn star(&mut self, mut one: impl FnMut(&mut Self) -> bool) {
        if !one(self) {
            return;
        }
        loop {
            let save = self.pos;
            self.ws();
            if !one(self) {
                self.pos = save;
                return;
            }
        }
    }

    /// Gives up on the item (always with `None`, for `?`).
    fn give_up<T>(&mut self) -> Option<T> {
        self.bail = true;
        None
    }
}
