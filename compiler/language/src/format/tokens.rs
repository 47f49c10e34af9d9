//! The formatter's view of a source file: its tokens and comments, in order, each with its
//! byte range and the line breaks before it. Only files that parsed are tokenised, so this
//! scanner can be lenient: it never fails, it only cuts the text where the grammar would.
//!
//! Every token's text is printed as written: numbers keep their digits and units, strings
//! their escapes and interpolations, colours their case. The formatter decides only what
//! goes between tokens.

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Kind {
    /// A name or keyword.
    Word,
    /// A number with its unit (`12`, `1.5`, `300ms`, `75%`).
    Number,
    /// A string, interpolations included.
    Str,
    /// `#rrggbb` or `#rrggbbaa`.
    Colour,
    /// A script action, prefix and body (`#js: { … }`): the engine's text, printed as written.
    Script,
    /// An operator or bracket.
    Punct,
    LineComment,
    BlockComment,
}

#[derive(Clone, Copy, Debug)]
pub struct Token {
    pub kind: Kind,
    pub start: usize,
    pub end: usize,
    /// Line breaks in the white space before this token.
    pub breaks: u32,
}

impl Token {
    pub fn is_comment(&self) -> bool {
        matches!(self.kind, Kind::LineComment | Kind::BlockComment)
    }
}

/// Operators of two characters, matched before their first character alone.
const PAIRS: &[&[u8; 2]] = &[b"->", b"??", b"..", b"||", b"&&", b"==", b"!=", b"<=", b">="];

fn is_ident(c: u8) -> bool {
    c.is_ascii_alphanumeric() || c == b'_'
}

/// The tokens and comments of `text`, in order.
pub fn tokenize(text: &str) -> Vec<Token> {
    let b = text.as_bytes();
    let mut out = Vec::with_capacity(text.len() / 4);
    // A byte order mark is not text (the formatter puts it back).
    let mut i = if text.starts_with('\u{FEFF}') { 3 } else { 0 };
    let mut breaks = 0u32;
    while i < b.len() {
        let c = b[i];
        let start = i;
        let kind = match c {
            b'\n' => {
                breaks += 1;
                i += 1;
                continue;
            }
            _ if c.is_ascii_whitespace() => {
                i += 1;
                continue;
            }
            b'/' if b.get(i + 1) == Some(&b'/') => {
                while i < b.len() && b[i] != b'\n' {
                    i += 1;
                }
                Kind::LineComment
            }
            b'/' if b.get(i + 1) == Some(&b'*') => {
                i += 2;
                while i < b.len() && !(b[i] == b'*' && b.get(i + 1) == Some(&b'/')) {
                    i += 1;
                }
                i = (i + 2).min(b.len());
                Kind::BlockComment
            }
            b'"' => {
                i = string_end(b, i);
                Kind::Str
            }
            b'#' if let Some(open) = crate::script_text::body_open(b, i) => {
                i = crate::script_text::body_end(b, open).unwrap_or(b.len());
                Kind::Script
            }
            b'#' => {
                i += 1;
                while i < b.len() && is_ident(b[i]) {
                    i += 1;
                }
                Kind::Colour
            }
            b'0'..=b'9' => {
                i = number_end(b, i);
                Kind::Number
            }
            _ if is_ident(c) => {
                while i < b.len() && is_ident(b[i]) {
                    i += 1;
                }
                Kind::Word
            }
            _ => {
                let two = b.get(i..i + 2);
                i += if two.is_some_and(|t| PAIRS.iter().any(|p| &p[..] == t)) {
                    2
                } else {
                    // One character, whole (the parser refused anything else outside strings
                    // and comments, but stay on a character boundary whatever comes).
                    text[i..].chars().next().map_or(1, char::len_utf8)
                };
                Kind::Punct
            }
        };
        out.push(Token { kind, start, end: i, breaks });
        breaks = 0;
    }
    out
}

/// The end of the number starting at `i`: digits, a fraction (`1.5`, not the `..` of
/// `0..40`), then its unit (letters or `%`).
fn number_end(b: &[u8], mut i: usize) -> usize {
    while i < b.len() && b[i].is_ascii_digit() {
        i += 1;
    }
    if b.get(i) == Some(&b'.') && b.get(i + 1).is_some_and(u8::is_ascii_digit) {
        i += 1;
        while i < b.len() && b[i].is_ascii_digit() {
            i += 1;
        }
    }
    while i < b.len() && (is_ident(b[i]) || b[i] == b'%') {
        i += 1;
    }
    i
}

/// The end of the string starting at the `"` at `i` (past its closing `"`), across
/// interpolations, which may hold strings of their own.
fn string_end(b: &[u8], mut i: usize) -> usize {
    // Each entry: an open string (true) or an open interpolation (false).
    let mut stack = vec![true];
    i += 1;
    while i < b.len() {
        let in_string = *stack.last().unwrap_or(&true);
        let c = b[i];
        if in_string {
            match c {
                b'\\' => i += 1,
                b'{' if b.get(i + 1) == Some(&b'{') => i += 1,
                b'}' if b.get(i + 1) == Some(&b'}') => i += 1,
                b'{' => stack.push(false),
                b'"' | b'\n' => {
                    stack.pop();
                    if stack.is_empty() {
                        return i + 1;
                    }
                }
                _ => {}
            }
        } else {
            match c {
                b'"' => stack.push(true),
                b'}' => {
                    stack.pop();
                }
                // A format spec (`{x:.1}`) runs to the closing brace.
                b':' => {
                    while i + 1 < b.len() && !matches!(b[i + 1], b'}' | b'"') {
                        i += 1;
                    }
                }
                _ => {}
            }
        }
        i += 1;
    }
    b.len()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn texts(s: &str) -> Vec<&str> {
        tokenize(s).iter().map(|t| &s[t.start..t.end]).collect()
    }

    #[test]
    fn numbers_keep_their_units_and_ranges_split_at_the_dots() {
        assert_eq!(texts("0..40 1.5s 75% 300ms"), ["0", "..", "40", "1.5s", "75%", "300ms"]);
    }

    #[test]
    fn a_string_with_interpolations_and_nested_strings_is_one_token() {
        let s = r#""a {f("}", x):.1} {{b}} \" c" d"#;
        assert_eq!(texts(s), [r#""a {f("}", x):.1} {{b}} \" c""#, "d"]);
    }

    #[test]
    fn comments_are_tokens_and_line_breaks_are_counted() {
        let toks = tokenize("a // x\n\n/* y\n */ b->c");
        let kinds: Vec<Kind> = toks.iter().map(|t| t.kind).collect();
        assert_eq!(
            kinds,
            [
                Kind::Word,
                Kind::LineComment,
                Kind::BlockComment,
                Kind::Word,
                Kind::Punct,
                Kind::Word
            ]
        );
        assert_eq!(toks[2].breaks, 2);
        assert_eq!(toks[3].breaks, 0);
    }
}
