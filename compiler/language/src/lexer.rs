//! The lexical pass, run on a whole file before the parser. One linear byte scan reports, each
//! once and at its start:
//! - an unclosed string, string interpolation or block comment (E0104), at its opening;
//! - a look-alike character (U+2212 minus, no-break space, smart quotes…) or a single quote
//!   outside strings and comments (E0105), naming the character to type instead;
//! - brackets nested deeper than [`MAX_NESTING`] (E0106), at the first opening past the limit.
//!
//! A script action's body (`#js: { … }`) is skipped whole ([`crate::script_text`]): its text is
//! the engine's; only a body, string or comment in it left open is reported (E0104).
//!
//! pest and the later passes recurse on nesting, so nothing deeper than the limit ever reaches
//! them. The byte ranges it returns are broken: the parser skips the items that overlap them
//! instead of reporting follow-on errors. A UTF-8 byte order mark is skipped.

use crate::codes;
use crate::diagnostics::Diagnostics;
use crate::script_text;
use crate::source::{FileId, SourceMap, Span};
use std::ops::Range;

/// Brackets (`(`, `[`, `{`, string interpolations) nested deeper than this are refused.
pub const MAX_NESTING: usize = 128;

/// Characters that look like a piece of syntax, and what to type instead.
const CONFUSABLES: &[(char, &str, &str)] = &[
    ('\u{2212}', "MINUS SIGN", "-"),
    ('\u{2013}', "EN DASH", "-"),
    ('\u{2014}', "EM DASH", "-"),
    ('\u{2010}', "HYPHEN", "-"),
    ('\u{00A0}', "NO-BREAK SPACE", " "),
    ('\u{202F}', "NARROW NO-BREAK SPACE", " "),
    ('\u{2009}', "THIN SPACE", " "),
    ('\u{200B}', "ZERO WIDTH SPACE", ""),
    ('\u{FEFF}', "ZERO WIDTH NO-BREAK SPACE", ""),
    ('\u{201C}', "LEFT DOUBLE QUOTATION MARK", "\""),
    ('\u{201D}', "RIGHT DOUBLE QUOTATION MARK", "\""),
    ('\u{201E}', "DOUBLE LOW-9 QUOTATION MARK", "\""),
    ('\u{00AB}', "LEFT-POINTING DOUBLE ANGLE QUOTATION MARK", "\""),
    ('\u{00BB}', "RIGHT-POINTING DOUBLE ANGLE QUOTATION MARK", "\""),
    ('\u{2018}', "LEFT SINGLE QUOTATION MARK", "\""),
    ('\u{2019}', "RIGHT SINGLE QUOTATION MARK", "\""),
    ('\u{00D7}', "MULTIPLICATION SIGN", "*"),
    ('\u{00F7}', "DIVISION SIGN", "/"),
    ('\u{2215}', "DIVISION SLASH", "/"),
    ('\u{2264}', "LESS-THAN OR EQUAL TO", "<="),
    ('\u{2265}', "GREATER-THAN OR EQUAL TO", ">="),
    ('\u{2260}', "NOT EQUAL TO", "!="),
    ('\u{2192}', "RIGHTWARDS ARROW", "->"),
    ('\u{2026}', "HORIZONTAL ELLIPSIS", ".."),
    ('\u{FF08}', "FULLWIDTH LEFT PARENTHESIS", "("),
    ('\u{FF09}', "FULLWIDTH RIGHT PARENTHESIS", ")"),
    ('\u{FF1A}', "FULLWIDTH COLON", ":"),
    ('\u{FF0C}', "FULLWIDTH COMMA", ","),
    ('\u{037E}', "GREEK QUESTION MARK", ";"),
];

/// What the scan found: the broken byte ranges (the parser skips items overlapping them).
#[derive(Debug, Default)]
pub struct Scan {
    pub broken: Vec<Range<usize>>,
}

impl Scan {
    pub fn is_broken(&self, range: Range<usize>) -> bool {
        self.broken.iter().any(|b| b.start < range.end.max(range.start + 1) && range.start < b.end)
    }
}

/// Where the scan is: in code, in a string, or in a string interpolation.
#[derive(Clone, Copy, Debug)]
enum Frame {
    /// An open `(`, `[` or `{` in code.
    Bracket,
    /// A string opened at this offset.
    Str(usize),
    /// An interpolation `{` opened at this offset (inside a string).
    Interp(usize),
}

/// Scans `text` (see the module comment). Never fails; reports into `diags`.
pub fn scan(file: FileId, text: &str, diags: &mut Diagnostics) -> Scan {
    let bytes = text.as_bytes();
    let mut out = Scan::default();
    let mut stack: Vec<Frame> = Vec::new();
    let mut too_deep_reported = false;
    let mut stray_brace: Option<usize> = None;
    let mut i = if text.starts_with('\u{FEFF}') { 3 } else { 0 };
    while i < bytes.len() {
        let b = bytes[i];
        let in_string = matches!(stack.last(), Some(Frame::Str(_)));
        // Most bytes (names, numbers, blanks, operators; a string's text) matter to no rule
        // below: runs of them are skipped in a tight loop.
        let plain = if in_string { &PLAIN_TEXT } else { &PLAIN_CODE };
        if plain[usize::from(b)] {
            i += 1;
            while i < bytes.len() && plain[usize::from(bytes[i])] {
                i += 1;
            }
            continue;
        }
        if in_string {
            match b {
                b'"' => {
                    stack.pop();
                    if let Some(at) = stray_brace.take() {
                        diags
                            .error(
                                codes::SYNTAX,
                                Span::new(file, at, at + 1),
                                "a `}` in a string closes nothing",
                            )
                            .label("no `{` before it")
                            .help("write `}}` for a literal `}` in a string");
                        out.broken.push(at..at + 1);
                    }
                }
                b'\\' => i += 1,
                b'{' if bytes.get(i + 1) == Some(&b'{') => i += 1,
                b'}' if bytes.get(i + 1) == Some(&b'}') => i += 1,
                b'{' => {
                    let refused =
                        push(&mut stack, Frame::Interp(i), file, i, diags, &mut too_deep_reported);
                    if refused {
                        out.broken.push(i..line_end(bytes, i));
                    }
                }
                // Reported when the string closes: an unclosed string explains it otherwise.
                b'}' => stray_brace = stray_brace.or(Some(i)),
                b'\n' => {
                    stray_brace = None;
                    report_unclosed_string(file, &stack, diags, &mut out, i);
                    stack.retain(|f| matches!(f, Frame::Bracket));
                }
                _ => {}
            }
            i += 1;
            continue;
        }
        match b {
            b'/' if bytes.get(i + 1) == Some(&b'/') => {
                i = line_end(bytes, i);
                continue;
            }
            b'/' if bytes.get(i + 1) == Some(&b'*') => {
                let start = i;
                i = script_text::comment_close(bytes, i).unwrap_or(bytes.len());
                if i >= bytes.len() {
                    diags
                        .error(
                            codes::UNCLOSED_TEXT,
                            Span::new(file, start, start + 2),
                            "this comment is never closed",
                        )
                        .label("unclosed comment")
                        .help("end it with `*` then `/`: until then the rest of the file is a comment");
                    out.broken.push(start..bytes.len());
                }
                i += 2;
                continue;
            }
            // `#js: { … }`: a script's body is the engine's text, skipped whole (its strings,
            // comments and quotes are the engine's); a colour is not a script.
            b'#' if let Some(open) = script_text::body_open(bytes, i) => {
                match script_text::body(bytes, open) {
                    Ok(script_text::Body { end, too_deep: None }) => i = end,
                    Ok(script_text::Body { end, too_deep: Some(at) }) => {
                        diags
                            .error(
                                codes::TOO_DEEP,
                                Span::new(file, at, at + 1),
                                format!(
                                    "braces nested deeper than {MAX_NESTING} levels in a script"
                                ),
                            )
                            .label("too deep")
                            .help(
                                "split the script into functions, or move it into a script module",
                            );
                        out.broken.push(i..end);
                        i = end;
                    }
                    Err(at) => {
                        let (what, label) = if at == open {
                            ("this script's `{` is never closed", "unclosed script")
                        } else {
                            ("this string or comment in a script is never closed", "unclosed")
                        };
                        diags
                            .error(codes::UNCLOSED_TEXT, Span::new(file, at, at + 1), what)
                            .label(label)
                            .help("a script's body runs from its `{` to the `}` that balances it; braces in the script's strings and comments do not count");
                        out.broken.push(i..bytes.len());
                        i = bytes.len();
                    }
                }
                continue;
            }
            b'"' => {
                let refused =
                    push(&mut stack, Frame::Str(i), file, i, diags, &mut too_deep_reported);
                if refused {
                    out.broken.push(i..line_end(bytes, i));
                }
            }
            b'(' | b'[' | b'{' => {
                let refused =
                    push(&mut stack, Frame::Bracket, file, i, diags, &mut too_deep_reported);
                if refused {
                    // Skipped whole: the stack stays balanced.
                    let end = closing(bytes, i);
                    out.broken.push(i..end);
                    i = end;
                    continue;
                }
            }
            b')' | b']' => {
                if matches!(stack.last(), Some(Frame::Bracket)) {
                    stack.pop();
                }
            }
            b'}' => match stack.last() {
                Some(Frame::Bracket) => {
                    stack.pop();
                }
                Some(Frame::Interp(_)) => {
                    stack.pop();
                }
                _ => {}
            },
            b'\n' if stack.iter().any(|f| matches!(f, Frame::Interp(_))) => {
                report_unclosed_string(file, &stack, diags, &mut out, i);
                stack.retain(|f| matches!(f, Frame::Bracket));
            }
            // `'text'`: one diagnostic for the pair, whose text is then skipped.
            b'\'' => {
                let close = quoted_until(text, i + 1, &['\'']);
                let end = close.map_or(i + 1, |c| c + 1);
                let d = diags
                    .error(
                        codes::CONFUSABLE,
                        Span::new(file, i, end),
                        "strings are written in double quotes",
                    )
                    .label("single quotes");
                match close {
                    Some(c) => d.help(format!("write \"{}\"", &text[i + 1..c])),
                    None => d.help("write \"…\" instead of '…'"),
                };
                out.broken.push(i..end);
                i = end;
                continue;
            }
            _ if b >= 0x80 => {
                let c = text[i..].chars().next().unwrap_or('\u{FFFD}');
                // A typographic quote and the one that closes it on the same line: one
                // diagnostic for the pair (an editor's "smart quotes").
                let pair = SMART_QUOTES.contains(&c).then(|| {
                    quoted_until(text, i + c.len_utf8(), SMART_QUOTES)
                        .map(|close| (close, text[close..].chars().next().unwrap_or(c)))
                });
                if let Some(Some((close, last))) = pair {
                    let end = close + last.len_utf8();
                    diags
                        .error(
                            codes::CONFUSABLE,
                            Span::new(file, i, end),
                            format!(
                                "`{c}` and `{last}` (U+{:04X}, U+{:04X}: typographic quotes) look like `\"` but are not part of the language",
                                c as u32, last as u32
                            ),
                        )
                        .label("typographic quotes")
                        .help(format!(
                            "write \"{}\" (an editor's \"smart quotes\" put them there)",
                            &text[i + c.len_utf8()..close]
                        ));
                    out.broken.push(i..end);
                    i = end;
                    continue;
                }
                if let Some((_, name, instead)) = CONFUSABLES.iter().find(|(x, _, _)| *x == c) {
                    let help = if instead.is_empty() {
                        "delete it: it is invisible and means nothing here".to_string()
                    } else if *instead == " " {
                        "replace it with an ordinary space".to_string()
                    } else {
                        format!("replace it with `{instead}`")
                    };
                    diags
                        .error(
                            codes::CONFUSABLE,
                            Span::new(file, i, i + c.len_utf8()),
                            format!(
                                "`{c}` (U+{:04X} {name}) looks like `{}` but is not part of the language",
                                c as u32,
                                if instead.is_empty() { " " } else { instead }
                            ),
                        )
                        .label("look-alike character")
                        .help(help);
                    out.broken.push(i..i + c.len_utf8());
                }
                i += c.len_utf8();
                continue;
            }
            _ => {}
        }
        i += 1;
    }
    report_unclosed_string(file, &stack, diags, &mut out, bytes.len());
    out
}

/// Bytes that [`scan`] passes over outside strings, and inside them.
static PLAIN_CODE: [bool; 256] = plain_bytes(b"/\"([{)]}\n'#", true);
static PLAIN_TEXT: [bool; 256] = plain_bytes(b"\"\\{}\n", false);

const fn plain_bytes(special: &[u8], non_ascii_special: bool) -> [bool; 256] {
    let mut table = [true; 256];
    let mut i = 0;
    while i < special.len() {
        table[special[i] as usize] = false;
        i += 1;
    }
    if non_ascii_special {
        let mut b = 0x80;
        while b < 256 {
            table[b] = false;
            b += 1;
        }
    }
    table
}

/// Typographic quotes, opening or closing.
const SMART_QUOTES: &[char] =
    &['\u{201C}', '\u{201D}', '\u{201E}', '\u{00AB}', '\u{00BB}', '\u{2018}', '\u{2019}'];

/// The offset of the first of `quotes` at or after `from` on the same line.
fn quoted_until(text: &str, from: usize, quotes: &[char]) -> Option<usize> {
    let line = &text[from..line_end(text.as_bytes(), from)];
    line.char_indices().find(|(_, ch)| quotes.contains(ch)).map(|(k, _)| from + k)
}

/// Pushes a frame; past [`MAX_NESTING`] reports E0106 once and returns true (not pushed).
fn push(
    stack: &mut Vec<Frame>,
    frame: Frame,
    file: FileId,
    at: usize,
    diags: &mut Diagnostics,
    reported: &mut bool,
) -> bool {
    if stack.len() < MAX_NESTING {
        stack.push(frame);
        return false;
    }
    if !*reported {
        *reported = true;
        diags
            .error(
                codes::TOO_DEEP,
                Span::new(file, at, at + 1),
                format!("nesting deeper than {MAX_NESTING} levels"),
            )
            .label("too deep")
            .help("split the expression with `let`s");
    }
    true
}

/// Reports the string or interpolation left open at a line end (or the end of the file):
/// the innermost open interpolation when there is one (its `}` is missing), else the string.
fn report_unclosed_string(
    file: FileId,
    stack: &[Frame],
    diags: &mut Diagnostics,
    out: &mut Scan,
    end: usize,
) {
    let interp = stack.iter().rev().find_map(|f| match f {
        Frame::Interp(o) => Some(*o),
        _ => None,
    });
    let string = stack.iter().find_map(|f| match f {
        Frame::Str(o) => Some(*o),
        _ => None,
    });
    let Some(first) = string else { return };
    match interp {
        Some(o) => {
            diags
                .error(
                    codes::UNCLOSED_TEXT,
                    Span::new(file, o, o + 1),
                    "this `{` in a string is never closed",
                )
                .label("unclosed interpolation")
                .help("close it with `}` before the string ends, or write `{{` for a literal `{`");
        }
        None => {
            diags
                .error(
                    codes::UNCLOSED_TEXT,
                    Span::new(file, first, first + 1),
                    "this string is never closed",
                )
                .label("unclosed string")
                .help("close it with `\"` on the same line: a string cannot span lines");
        }
    }
    out.broken.push(first..end);
}

pub(crate) fn line_end(bytes: &[u8], from: usize) -> usize {
    bytes[from..].iter().position(|&b| b == b'\n').map_or(bytes.len(), |p| from + p)
}

/// The offset after the bracket matching the one at `open` (or the end of the file).
fn closing(bytes: &[u8], open: usize) -> usize {
    let mut depth = 0usize;
    for (k, &b) in bytes.iter().enumerate().skip(open) {
        match b {
            b'(' | b'[' | b'{' => depth += 1,
            b')' | b']' | b'}' => {
                depth -= 1;
                if depth == 0 {
                    return k + 1;
                }
            }
            _ => {}
        }
    }
    bytes.len()
}

/// Decodes a file's bytes. Text that is not UTF-8 is added to `sources` (lossily) and reported
/// at the first bad byte (E0107), and `None` is returned: the file is not checked further.
pub fn decode(
    path: &str,
    bytes: Vec<u8>,
    sources: &mut SourceMap,
    diags: &mut Diagnostics,
) -> Option<String> {
    match String::from_utf8(bytes) {
        Ok(t) => Some(t),
        Err(e) => {
            let at = e.utf8_error().valid_up_to();
            let bad = e.as_bytes()[at];
            let valid = String::from_utf8_lossy(&e.as_bytes()[..at]).len();
            let lossy = String::from_utf8_lossy(e.as_bytes()).into_owned();
            let file = sources.add(path.to_string(), lossy);
            diags
                .error(
                    codes::NOT_UTF8,
                    Span::new(file, valid, valid + '\u{FFFD}'.len_utf8()),
                    format!("byte 0x{bad:02X} is not UTF-8 text"),
                )
                .label("not UTF-8")
                .help("save the file as UTF-8 (in most editors: \"Save with encoding\" → UTF-8)");
            None
        }
    }
}

/// Where the first non-UTF-8 byte of `bytes` is, as "line L, column C", for loaders that
/// report read errors as text.
pub fn describe_bad_utf8(bytes: &[u8]) -> Option<String> {
    let e = std::str::from_utf8(bytes).err()?;
    let at = e.valid_up_to();
    let before = String::from_utf8_lossy(&bytes[..at]);
    let line = before.matches('\n').count() + 1;
    let column = before.rsplit('\n').next().map_or(0, |l| l.chars().count()) + 1;
    Some(format!(
        "line {line}, column {column}: byte 0x{:02X} is not UTF-8 text; save the file as UTF-8",
        bytes[at]
    ))
}
