//! Where a script action's text is: `#js: { … }`, `#rhai: { … }` (docs/scripting.md).
//!
//! A script's body is one raw token of the layout language: from its `{` to the `}` that
//! balances it, the script's own strings (`"…"`, `'…'`, `` `…` ``) and comments (`//`, `/* */`)
//! respected, so a brace inside them balances nothing. Every scan of a layout's text (the
//! lexical pass, the item splitter, the hand-written parser, the formatter) skips a body with
//! these two functions, so they all agree with `grammar.pest`'s `script_body`.

/// At a `#` that starts a script action (`#` name `:` blanks `{`), the offset of the body's
/// `{`; `None` when the `#` starts anything else (a colour).
pub fn body_open(bytes: &[u8], hash: usize) -> Option<usize> {
    if bytes.get(hash) != Some(&b'#') || !bytes.get(hash + 1)?.is_ascii_alphabetic() {
        return None;
    }
    let mut i = hash + 2;
    while bytes.get(i).is_some_and(|b| b.is_ascii_alphanumeric() || *b == b'_') {
        i += 1;
    }
    if bytes.get(i) != Some(&b':') {
        return None;
    }
    i += 1;
    while bytes.get(i).is_some_and(|b| matches!(b, b' ' | b'\t' | b'\n' | b'\r')) {
        i += 1;
    }
    (bytes.get(i) == Some(&b'{')).then_some(i)
}

/// The engine's prefix of a script action starting at `hash` (`js` for `#js: {`).
pub fn prefix(text: &str, hash: usize) -> &str {
    let rest = &text[hash + 1..];
    &rest[..rest.find(':').unwrap_or(0)]
}

/// The offset just after the `}` that closes the body opened at `open`; `Err` with the offset
/// of what is never closed (the body's `{`, or a string or comment inside it) at the end of
/// the text.
pub fn body_end(bytes: &[u8], open: usize) -> Result<usize, usize> {
    body(bytes, open).map(|b| b.end)
}

/// A script body's extent, as [`body_end`] finds it.
pub struct Body {
    /// Just after its closing `}`.
    pub end: usize,
    /// The first `{` nested deeper than [`crate::lexer::MAX_NESTING`] levels in it (the
    /// body's own braces counted), if any: the parser's rule for a body recurses on them.
    pub too_deep: Option<usize>,
}

/// [`body_end`], with where its braces first nest too deep.
pub fn body(bytes: &[u8], open: usize) -> Result<Body, usize> {
    let mut depth = 0usize;
    let mut too_deep = None;
    let mut i = open;
    while i < bytes.len() {
        match bytes[i] {
            b'{' => {
                depth += 1;
                if depth > crate::lexer::MAX_NESTING && too_deep.is_none() {
                    too_deep = Some(i);
                }
            }
            b'}' => {
                depth -= 1;
                if depth == 0 {
                    return Ok(Body { end: i + 1, too_deep });
                }
            }
            q @ (b'"' | b'\'' | b'`') => {
                let start = i;
                i += 1;
                while i < bytes.len() && bytes[i] != q {
                    i += if bytes[i] == b'\\' { 2 } else { 1 };
                }
                if i >= bytes.len() {
                    return Err(start);
                }
            }
            b'/' if bytes.get(i + 1) == Some(&b'/') => {
                i = crate::lexer::line_end(bytes, i);
                continue;
            }
            b'/' if bytes.get(i + 1) == Some(&b'*') => {
                i = comment_close(bytes, i).ok_or(i)? + 1;
            }
            _ => {}
        }
        i += 1;
    }
    Err(open)
}

/// At the `/*` at `open`, the offset of the `*` of the `*/` that ends the comment; `None`
/// when it is never closed (the lexer's comments and a script's are ended alike).
pub fn comment_close(bytes: &[u8], open: usize) -> Option<usize> {
    let mut i = open + 2;
    while i < bytes.len() {
        if bytes[i] == b'*' && bytes.get(i + 1) == Some(&b'/') {
            return Some(i);
        }
        i += 1;
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;

    fn end(text: &str) -> Result<usize, usize> {
        let open = body_open(text.as_bytes(), 0).expect("a script");
        body_end(text.as_bytes(), open)
    }

    #[test]
    fn a_body_ends_at_the_brace_that_balances_its_opening() {
        let t = "#js: { if (a) { b() } } rest";
        assert_eq!(end(t), Ok(t.find(" rest").unwrap()));
    }

    #[test]
    fn braces_in_the_scripts_strings_and_comments_balance_nothing() {
        let t = "#js: { let s = \"}\"; let c = '}'; let t = `}`; // }\n /* } */ } x";
        assert_eq!(end(t), Ok(t.len() - 2));
    }

    #[test]
    fn an_unclosed_body_or_string_is_found_where_it_opens() {
        assert_eq!(end("#rhai:\n{ let x = 1;"), Err(7));
        assert_eq!(end("#js: { let s = \"ab }"), Err(15));
    }

    #[test]
    fn braces_nested_past_the_limit_are_found_at_the_first_too_deep() {
        let n = crate::lexer::MAX_NESTING;
        let t = format!("#js: {}{}", "{".repeat(n + 2), "}".repeat(n + 2));
        let b = body(t.as_bytes(), 5).expect("closed");
        assert_eq!((b.end, b.too_deep), (t.len(), Some(5 + n)));
        let ok = format!("#js: {}{}", "{".repeat(n), "}".repeat(n));
        assert_eq!(body(ok.as_bytes(), 5).ok().and_then(|b| b.too_deep), None);
    }

    #[test]
    fn a_colour_is_not_a_script() {
        assert_eq!(body_open(b"#ff0000", 0), None);
        assert_eq!(body_open(b"#js x", 0), None);
        assert_eq!(prefix("#rhai: {}", 0), "rhai");
    }
}
