//! Prints the tokens of a file in the canonical layout (docs/formatting.md): what goes
//! between two tokens is decided here, from the tokens, their [`Marks`] and the line breaks
//! the source had; the tokens themselves are printed as written.

use super::shape::Marks;
use super::tokens::{Kind, Token};

const INDENT: &str = "    ";

/// How a token is separated from the code before it.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Sep {
    /// On the same line: a space or nothing.
    Same,
    /// A line of its own at the block's indentation.
    Line,
    /// A continuation line: one level deeper than the block's indentation.
    Continuation,
}

struct Printer<'a> {
    text: &'a str,
    tokens: &'a [Token],
    marks: &'a Marks,
    out: String,
    depth: usize,
}

pub fn print(text: &str, tokens: &[Token], marks: &Marks) -> String {
    let mut p = Printer {
        text,
        tokens,
        marks,
        out: String::with_capacity(text.len() + text.len() / 8),
        depth: 0,
    };
    p.run();
    let mut out = p.out;
    let end = out.trim_end().len();
    out.truncate(end);
    if !out.is_empty() {
        out.push('\n');
    }
    out
}

impl Printer<'_> {
    fn src(&self, i: usize) -> &str {
        &self.text[self.tokens[i].start..self.tokens[i].end]
    }

    fn is(&self, i: usize, s: &str) -> bool {
        self.tokens[i].kind == Kind::Punct && self.src(i) == s
    }

    fn run(&mut self) {
        // The last token printed (code or comment), and the last code token printed.
        let mut last: Option<usize> = None;
        let mut last_code: Option<usize> = None;
        // A line comment, or a comment on its own line, was printed: the next code starts
        // a new line.
        let mut must_break = false;
        for i in 0..self.tokens.len() {
            let t = self.tokens[i];
            if t.is_comment() {
                if last.is_some() && t.breaks == 0 {
                    // A trailing comment stays on its line.
                    self.out.push(' ');
                } else if last.is_some() {
                    let next = (i + 1..self.tokens.len()).find(|&j| !self.tokens[j].is_comment());
                    let between = match (last_code, next) {
                        (Some(p), Some(j)) => self.sep(p, j) == Sep::Line,
                        _ => true,
                    };
                    let extra = usize::from(!between);
                    self.newline(self.blank_allowed(t, last), self.depth + extra);
                }
                self.comment(t);
                must_break |= t.kind == Kind::LineComment || t.breaks > 0 || last.is_none();
                last = Some(i);
                continue;
            }
            let sep = match last_code {
                None if last.is_none() => None,
                None => Some(Sep::Line),
                Some(p) => Some(self.sep(p, i)),
            };
            let closing = self.is(i, "}");
            if closing {
                self.depth = self.depth.saturating_sub(1);
            }
            match sep {
                None => {}
                Some(Sep::Line) => {
                    self.newline(!closing && self.blank_allowed(t, last), self.depth)
                }
                Some(Sep::Continuation) => self.newline(false, self.depth + 1),
                Some(Sep::Same) if must_break => self.newline(false, self.depth + 1),
                Some(Sep::Same) => {
                    if let Some(p) = last_code
                        && last == last_code
                        && self.space(p, i)
                    {
                        self.out.push(' ');
                    } else if last != last_code {
                        // After a trailing block comment.
                        self.out.push(' ');
                    }
                }
            }
            let (text, t) = (self.text, self.tokens[i]);
            let token = &text[t.start..t.end];
            match (t.kind, token.find('{')) {
                // `#js: { … }`: one space between the prefix and the body, whose text is
                // the engine's and stays as written.
                (Kind::Script, Some(open)) => {
                    self.out.push_str(token[..open].trim_end());
                    self.out.push(' ');
                    self.out.push_str(&token[open..]);
                }
                _ => self.out.push_str(token),
            }
            if self.is(i, "{") {
                self.depth += 1;
            }
            must_break = false;
            last = Some(i);
            last_code = Some(i);
        }
    }

    /// A blank line before `t` when the source had one, except first in a block or a file.
    fn blank_allowed(&self, t: Token, last: Option<usize>) -> bool {
        t.breaks >= 2 && last.is_some_and(|l| !self.is(l, "{")) && !self.out.is_empty()
    }

    fn newline(&mut self, blank: bool, depth: usize) {
        let end = self.out.trim_end_matches([' ', '\t']).len();
        self.out.truncate(end);
        if self.out.is_empty() {
            return;
        }
        self.out.push('\n');
        if blank {
            self.out.push('\n');
        }
        for _ in 0..depth {
            self.out.push_str(INDENT);
        }
    }

    fn comment(&mut self, t: Token) {
        let text = &self.text[t.start..t.end];
        match t.kind {
            Kind::LineComment => self.out.push_str(text.trim_end()),
            _ => self.out.push_str(&text.replace("\r\n", "\n")),
        }
    }

    /// Where code token `j` goes after code token `p`.
    fn sep(&self, p: usize, j: usize) -> Sep {
        if self.is(p, "{") || self.is(p, "}") || self.is(j, "}") || self.marks.line_start[j] {
            if self.is(p, "{") && self.is(j, "}") && j == p + 1 {
                // An empty block: `{}`.
                return Sep::Same;
            }
            return Sep::Line;
        }
        // Line breaks inside an item are kept (the tokens between them stay as they are),
        // except before the `{` that opens a block.
        let broke = self.tokens[p + 1..=j].iter().any(|t| t.breaks > 0);
        if broke && !self.is(j, "{") { Sep::Continuation } else { Sep::Same }
    }

    /// Whether a space goes between code tokens `p` and `j` on one line.
    fn space(&self, p: usize, j: usize) -> bool {
        if self.marks.glue_next[p] {
            return false;
        }
        let (ps, js) = (self.src(p), self.src(j));
        let (pk, jk) = (self.tokens[p].kind, self.tokens[j].kind);
        if jk == Kind::Punct && matches!(js, "," | ")" | "]" | "." | ":" | "?") {
            return false;
        }
        if pk == Kind::Punct && matches!(ps, "(" | "[" | "." | "{") {
            return false;
        }
        // A prefix `-` or `!`.
        if pk == Kind::Punct && matches!(ps, "-" | "!") && !self.marks.binary[p] {
            return false;
        }
        if jk == Kind::Punct && matches!(js, "(" | "[") {
            // `f(x)` is a call and `f (x)` two values: keep what was written.
            let value_end =
                matches!(pk, Kind::Word | Kind::Number | Kind::Str | Kind::Colour | Kind::Script)
                    || ps == ")"
                    || ps == "]";
            let keyword = matches!(ps, "if" | "then" | "else" | "not" | "and" | "or");
            if value_end && !keyword {
                return self.tokens[j].start > self.tokens[p].end;
            }
        }
        true
    }
}
