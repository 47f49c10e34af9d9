//! The formatter behind `mocu fmt`: one canonical layout for a layout file
//! (docs/formatting.md).
//!
//! It reads the file twice over: as tokens and comments ([`tokens`]), printed as written, and
//! as the parser's syntax tree, whose spans say which token starts a line and which `-` is a
//! prefix ([`shape`]). [`printer`] decides only what goes between tokens: spaces, line breaks
//! and indentation. Comments stay where they were, on their line or on a line of their own.
//!
//! A file with syntax errors is not formatted. The result is parsed again and its tree
//! compared with the original's (spans aside) before it is returned, so a formatting that
//! would change what the file means is refused instead of written.

pub mod diff;
mod printer;
pub mod range;
mod shape;
mod tokens;

use crate::ast;
use crate::diagnostics::{Diagnostics, Severity};
use crate::source::FileId;

/// Why a file was not formatted.
#[derive(Debug, PartialEq, Eq)]
pub enum FormatError {
    /// It has syntax errors, reported in the diagnostics.
    Syntax,
    /// Its formatted text would not parse to the same tree (a bug of the formatter, which
    /// this check keeps from doing harm); the message says where.
    WouldChangeMeaning(String),
}

impl std::fmt::Display for FormatError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            FormatError::Syntax => write!(f, "the file has syntax errors"),
            FormatError::WouldChangeMeaning(at) => write!(
                f,
                "formatting would change what the file means ({at}); it was left as it is \
                 (a bug of `mocu fmt`: please report it)"
            ),
        }
    }
}

const BOM: &str = "\u{FEFF}";

/// `text` (the layout file `file`) in the canonical layout. Syntax errors go to `diags`.
pub fn format_source(
    file: FileId,
    text: &str,
    diags: &mut Diagnostics,
) -> Result<String, FormatError> {
    let errors = diags.count(Severity::Error);
    let tree = crate::parser::parse(file, text, diags);
    if diags.count(Severity::Error) > errors {
        return Err(FormatError::Syntax);
    }
    let out = format_tree(text, &tree);
    if out == text {
        return Ok(out);
    }
    let mut again = Diagnostics::new();
    let tree2 = crate::parser::parse(file, &out, &mut again);
    if again.count(Severity::Error) > 0 {
        return Err(FormatError::WouldChangeMeaning("the result does not parse".into()));
    }
    if tree_hash(&tree) != tree_hash(&tree2) {
        // The slow path, only to say where.
        let (a, b) = (tree_shape(&tree), tree_shape(&tree2));
        let at = a.bytes().zip(b.bytes()).take_while(|(x, y)| x == y).count();
        let context = &a[floor(&a, at.saturating_sub(60))..floor(&a, (at + 60).min(a.len()))];
        return Err(FormatError::WouldChangeMeaning(format!("the trees differ near `{context}`")));
    }
    Ok(out)
}

/// `text`, already parsed to `tree`, in the canonical layout.
pub fn format_tree(text: &str, tree: &ast::File) -> String {
    let toks = tokens::tokenize(text);
    let marks = shape::marks(tree, &toks);
    let body = printer::print(text, &toks, &marks);
    if text.starts_with(BOM) { format!("{BOM}{body}") } else { body }
}

/// The syntax tree written out without its spans: two files with the same shape mean the
/// same thing (the checker sees nothing else of a file).
pub fn tree_shape(tree: &ast::File) -> String {
    without_spans(&format!("{tree:?}"))
}

/// A hash of [`tree_shape`], computed without writing the dump out (equal trees, spans aside,
/// hash equal).
fn tree_hash(tree: &ast::File) -> u64 {
    use std::fmt::Write as _;
    use std::hash::Hasher as _;
    let mut h = SpanlessHasher { hash: std::hash::DefaultHasher::new(), skipping: false };
    let _ = write!(h, "{tree:?}");
    h.hash.finish()
}

/// Hashes what `{:?}` writes, leaving out each `Span { … }` (the derived `Debug` writes the
/// name `Span` as one piece and ends the struct with ` }`; a span holds no other ` }`).
struct SpanlessHasher {
    hash: std::hash::DefaultHasher,
    skipping: bool,
}

impl std::fmt::Write for SpanlessHasher {
    fn write_str(&mut self, s: &str) -> std::fmt::Result {
        use std::hash::Hasher as _;
        if self.skipping {
            self.skipping = s != " }";
        } else if s == "Span" {
            self.skipping = true;
            self.hash.write(b"_");
        } else {
            self.hash.write(s.as_bytes());
        }
        Ok(())
    }
}

/// A `{:?}` dump with every [`crate::Span`] in it replaced by `_`: what two trees or programs
/// that differ only in where things were written have in common.
pub fn without_spans(debug: &str) -> String {
    // Spans, and where a script's body starts (a place in the file, as a span is).
    const PLACES: [&str; 2] = ["Span { file: ", "ScriptOrigin { file: "];
    let mut out = String::with_capacity(debug.len() / 2);
    let mut rest = debug;
    while let Some((at, _)) =
        PLACES.iter().filter_map(|p| rest.find(p).map(|at| (at, p))).min_by_key(|(at, _)| *at)
    {
        out.push_str(&rest[..at]);
        out.push('_');
        rest = &rest[at..];
        rest = rest.find('}').map_or("", |end| &rest[end + 1..]);
    }
    out.push_str(rest);
    out
}

/// The comments of `text`, in order, as the formatter prints them (line comments without
/// trailing white space).
pub fn comments(text: &str) -> Vec<String> {
    tokens::tokenize(text)
        .iter()
        .filter(|t| t.is_comment())
        .map(|t| {
            let c = &text[t.start..t.end];
            if t.kind == tokens::Kind::LineComment {
                c.trim_end().to_string()
            } else {
                c.replace("\r\n", "\n")
            }
        })
        .collect()
}

fn floor(s: &str, mut at: usize) -> usize {
    while !s.is_char_boundary(at) {
        at -= 1;
    }
    at
}

#[cfg(test)]
mod tests {
    use super::*;

    fn hash(text: &str) -> u64 {
        tree_hash(&crate::parser::parse(FileId(0), text, &mut Diagnostics::new()))
    }

    #[test]
    fn the_tree_hash_leaves_out_spans_and_sees_everything_else() {
        let a = "component C(f: number) {\n  text f (f) size 2\n}\n";
        let spaced = "component C( f : number ) {\n\n      text   f   (f)   size 2 }";
        let call = "component C(f: number) {\n  text f(f) size 2\n}\n";
        assert_eq!(hash(a), hash(spaced));
        assert_ne!(hash(a), hash(call));
        assert_ne!(hash("let a = 1"), hash("let a = 2"));
        assert_ne!(hash("let a = \"x\""), hash("let b = \"x\""));
    }

    #[test]
    fn a_formatted_file_comes_back_as_it_is() {
        let tidy = "let a = 1\n";
        assert_eq!(format_source(FileId(0), tidy, &mut Diagnostics::new()).as_deref(), Ok(tidy));
    }
}
