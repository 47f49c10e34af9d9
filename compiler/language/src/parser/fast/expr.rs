//! Expressions and strings for the fast parser: grammar.pest's `expr` down to `string`, and
//! the tree the reference builder makes of them (precedence climbing over the flat
//! `prefix* term (infix prefix* term)*`).

use super::{Fast, NEST_LIMIT, is_ident_byte};
use crate::ast::{BinOp, Expr, ExprKind, LitUnit, StrPart, UnOp};
use crate::parser::MAX_DEPTH;
use crate::source::Span;

/// One element of an expression as pest reads it, flat.
pub(super) enum Elem {
    Prefix(UnOp, Span),
    Term(Expr),
    Infix(BinOp, u8, bool),
}

/// Binding power of the prefixes (parser.rs, `PREFIX`).
const PREFIX: u8 = 80;

/// A string literal as its users want it: the parts of an expression, or the plain text
/// (text, escapes and the raw text of interpolations: parser.rs, `plain_string`).
pub(super) enum StrOut {
    Parts(Vec<StrPart>),
    Plain(String),
}

impl<'a> Fast<'a> {
    /// An expression where an item, property or action holds one: refused (to pest) when the
    /// tree builder would find it deeper than [`MAX_DEPTH`].
    pub(super) fn top_expr(&mut self) -> Option<Expr> {
        let (e, need) = self.expr()?;
        if need > MAX_DEPTH {
            return self.give_up();
        }
        Some(e)
    }

    /// `expr`: the tree and its depth as the builder counts it (1 + operators + prefixes,
    /// plus the deepest term).
    pub(super) fn expr(&mut self) -> Option<(Expr, usize)> {
        if self.nest >= NEST_LIMIT {
            return self.give_up();
        }
        self.nest += 1;
        let depth = self.depth;
        self.depth += 1;
        let r = self.attempt(Self::expr_inner);
        self.depth = depth;
        self.nest -= 1;
        r
    }

    /// The flat list goes on [`Fast::elems`], shared by every expression (no list of its
    /// own for each), from `base` on.
    fn expr_inner(&mut self) -> Option<(Expr, usize)> {
        let base = self.elems.len();
        let r = self.expr_flat(base);
        self.elems.truncate(base);
        r
    }

    fn expr_flat(&mut self, base: usize) -> Option<(Expr, usize)> {
        let mut ops = 0usize;
        self.prefixes(&mut ops)?;
        self.ws();
        let (first, mut deepest) = self.term()?;
        self.ws();
        // The commonest case, a single term, goes on no list.
        let mut single = if self.elems.len() == base {
            Some(first)
        } else {
            self.elems.push(Elem::Term(first));
            None
        };
        loop {
            let save = self.pos;
            self.ws();
            let Some((op, power, right)) = self.infix() else {
                self.pos = save;
                break;
            };
            if let Some(t) = single.take() {
                self.elems.push(Elem::Term(t));
            }
            let (n, ops_before) = (self.elems.len(), ops);
            self.elems.push(Elem::Infix(op, power, right));
            ops += 1;
            self.deeper()?;
            self.ws();
            if self.prefixes(&mut ops).is_some() {
                self.ws();
                if let Some((t, need)) = self.term() {
                    deepest = deepest.max(need);
                    self.elems.push(Elem::Term(t));
                    continue;
                }
            }
            self.pos = save;
            self.elems.truncate(n);
            self.depth -= ops - ops_before;
            ops = ops_before;
            break;
        }
        let e = match single {
            Some(e) => e,
            None => climb(&mut self.elems.drain(base..).peekable(), 0),
        };
        Some((e, 1 + ops + deepest))
    }

    /// `prefix*`: `-`, `!` or `not`, each one more level (bounded: a longer run goes to pest,
    /// which refuses it).
    fn prefixes(&mut self, ops: &mut usize) -> Option<()> {
        let mut first = true;
        loop {
            let save = self.pos;
            if !first {
                self.ws();
            }
            let start = self.pos;
            let op = match self.peek() {
                b'-' => {
                    self.pos += 1;
                    UnOp::Neg
                }
                b'!' => {
                    self.pos += 1;
                    UnOp::Not
                }
                b'n' if self.word_here(b"not") => {
                    self.pos += 3;
                    UnOp::Not
                }
                _ => {
                    self.pos = save;
                    return Some(());
                }
            };
            first = false;
            self.elems.push(Elem::Prefix(op, self.span(start, self.pos)));
            *ops += 1;
            self.deeper()?;
        }
    }

    /// `infix`: the operator, its binding power and whether it associates to the right.
    fn infix(&mut self) -> Option<(BinOp, u8, bool)> {
        let b0 = self.peek();
        let b1 = self.at(self.pos + 1);
        let (op, len) = match (b0, b1) {
            (b'?', b'?') => (BinOp::Coalesce, 2),
            (b'.', b'.') => (BinOp::Range, 2),
            (b'|', b'|') => (BinOp::Or, 2),
            (b'&', b'&') => (BinOp::And, 2),
            (b'=', b'=') => (BinOp::Eq, 2),
            (b'!', b'=') => (BinOp::Ne, 2),
            (b'<', b'=') => (BinOp::Le, 2),
            (b'>', b'=') => (BinOp::Ge, 2),
            (b'<', _) => (BinOp::Lt, 1),
            (b'>', _) => (BinOp::Gt, 1),
            (b'+', _) => (BinOp::Add, 1),
            (b'-', c) if c != b'>' => (BinOp::Sub, 1),
            (b'*', _) => (BinOp::Mul, 1),
            (b'/', _) => (BinOp::Div, 1),
            (b'o', b'r') if !is_ident_byte(self.at(self.pos + 2)) => (BinOp::Or, 2),
            (b'a', b'n') if self.word_here(b"and") => (BinOp::And, 3),
            _ => return None,
        };
        self.pos += len;
        let power = match op {
            BinOp::Range => 10,
            BinOp::Or => 20,
            BinOp::And => 30,
            BinOp::Eq | BinOp::Ne | BinOp::Lt | BinOp::Le | BinOp::Gt | BinOp::Ge => 40,
            BinOp::Coalesce => 50,
            BinOp::Add | BinOp::Sub => 60,
            BinOp::Mul | BinOp::Div => 70,
        };
        Some((op, power, op == BinOp::Coalesce))
    }

    /// `term`: a primary and its postfixes, with no space before them.
    fn term(&mut self) -> Option<(Expr, usize)> {
        let (mut lhs, mut deepest) = self.primary()?;
        let mut postfixes = 0usize;
        let depth = self.depth;
        loop {
            let start = self.pos;
            let kind = match self.peek() {
                b'.' if self.at(start + 1) != b'.' => {
                    self.pos += 1;
                    match self.ident() {
                        Some(name) => ExprKind::Field(Box::new(lhs), name),
                        None => {
                            self.pos = start;
                            break;
                        }
                    }
                }
                b'[' => match self.attempt(Self::index) {
                    Some(key) => ExprKind::Index(Box::new(lhs), key),
                    None => break,
                },
                b'(' => match self.attempt(Self::call_args) {
                    Some((args, need)) => {
                        deepest = deepest.max(need);
                        ExprKind::Call(Box::new(lhs), args)
                    }
                    None => break,
                },
                _ => break,
            };
            postfixes += 1;
            if self.deeper().is_none() {
                self.depth = depth;
                return None;
            }
            let span = self.span(start, self.pos);
            // `lhs` moved into `kind`: its span is the start of the whole term.
            let whole = match &kind {
                ExprKind::Field(l, _) | ExprKind::Index(l, _) | ExprKind::Call(l, _) => {
                    l.span.to(span)
                }
                _ => span,
            };
            lhs = Expr { kind, span: whole };
        }
        self.depth = depth;
        Some((lhs, postfixes + deepest))
    }

    /// One more level of the tree being built: past [`MAX_DEPTH`] (a lower bound of the depth
    /// the builder counts), the builder would refuse the item, so pest reads it.
    fn deeper(&mut self) -> Option<()> {
        self.depth += 1;
        if self.depth > MAX_DEPTH {
            return self.give_up();
        }
        Some(())
    }

    /// `index`: `[ "key" ]` (the key's plain text).
    fn index(&mut self) -> Option<String> {
        self.pos += 1;
        self.ws();
        let (key, _, _) = self.string(true)?;
        self.ws();
        self.byte(b']').then_some(())?;
        match key {
            StrOut::Plain(s) => Some(s),
            StrOut::Parts(_) => None,
        }
    }

    /// `call_args`: `( expr, expr, … )`, and the deepest argument.
    fn call_args(&mut self) -> Option<(Vec<Expr>, usize)> {
        self.pos += 1;
        self.ws();
        let mut args = Vec::new();
        let mut deepest = 0;
        if let Some((e, need)) = self.expr() {
            args.push(e);
            deepest = need;
            self.ws();
            loop {
                let save = self.pos;
                self.ws();
                if self.byte(b',') {
                    self.ws();
                    if let Some((e, need)) = self.expr() {
                        args.push(e);
                        deepest = deepest.max(need);
                        continue;
                    }
                }
                self.pos = save;
                break;
            }
            self.ws();
            self.byte(b',');
        }
        self.ws();
        args.shrink_to_fit();
        self.byte(b')').then_some((args, deepest))
    }

    /// `primary`, and the depth of the expressions inside it.
    fn primary(&mut self) -> Option<(Expr, usize)> {
        let start = self.pos;
        let c = self.peek();
        if c.is_ascii_alphabetic() || c == b'_' {
            if let Some(id) = self.ident() {
                return Some((Expr { kind: ExprKind::Name(id.name), span: id.span }, 0));
            }
            let end = self.ident_end(start);
            let kind = match &self.b[start..end] {
                b"if" => return self.attempt(Self::if_expr),
                b"true" => ExprKind::Bool(true),
                b"false" => ExprKind::Bool(false),
                b"self" => ExprKind::SelfRef,
                _ => return None,
            };
            self.pos = end;
            return Some((Expr { kind, span: self.span(start, end) }, 0));
        }
        match c {
            b'0'..=b'9' => self.number().map(|e| (e, 0)),
            b'(' => self.attempt(|p| {
                p.pos += 1;
                p.ws();
                let (e, need) = p.expr()?;
                p.ws();
                p.byte(b')').then_some(())?;
                Some((Expr { span: p.span(start, p.pos), ..e }, need))
            }),
            b'"' => {
                let (StrOut::Parts(parts), need, span) = self.string(false)? else { return None };
                Some((Expr { kind: ExprKind::Str(parts), span }, need))
            }
            b'#' => self.colour(),
            _ => None,
        }
    }

    /// `if c then a else b`.
    fn if_expr(&mut self) -> Option<(Expr, usize)> {
        let start = self.pos;
        self.pos += 2;
        self.ws();
        let (c, n1) = self.expr()?;
        self.ws();
        self.lit(b"then").then_some(())?;
        self.ws();
        let (a, n2) = self.expr()?;
        self.ws();
        self.lit(b"else").then_some(())?;
        self.ws();
        let (b, n3) = self.expr()?;
        let kind = ExprKind::If(Box::new(c), Box::new(a), Box::new(b));
        Some((Expr { kind, span: self.span(start, self.pos) }, n1.max(n2).max(n3)))
    }

    /// `number`: digits, maybe a fraction, maybe a unit, and no name character after.
    pub(super) fn number(&mut self) -> Option<Expr> {
        let start = self.pos;
        let mut i = start;
        while self.at(i).is_ascii_digit() {
            i += 1;
        }
        if i == start {
            return None;
        }
        if self.at(i) == b'.' && self.at(i + 1).is_ascii_digit() {
            i += 1;
            while self.at(i).is_ascii_digit() {
                i += 1;
            }
        }
        let digits_end = i;
        let rest = &self.b[i..];
        let unit = [
            (&b"ms"[..], LitUnit::Ms),
            (b"min", LitUnit::Min),
            (b"s", LitUnit::S),
            (b"px", LitUnit::Px),
            (b"deg", LitUnit::Deg),
            (b"%", LitUnit::Percent),
        ]
        .into_iter()
        .find(|(u, _)| rest.starts_with(u));
        if let Some((u, _)) = unit {
            i += u.len();
        }
        if is_ident_byte(self.at(i)) {
            return None;
        }
        let value = self.s[start..digits_end].parse::<f64>().unwrap_or(0.0);
        self.pos = i;
        let unit = unit.map(|(_, u)| u);
        Some(Expr { kind: ExprKind::Number { value, unit }, span: self.span(start, i) })
    }

    /// `colour`: `#rrggbb` or `#rrggbbaa`.
    fn colour(&mut self) -> Option<(Expr, usize)> {
        let start = self.pos;
        let hex = |i: usize| self.at(i).is_ascii_hexdigit();
        if !(1..=6).all(|k| hex(start + k)) {
            return None;
        }
        let mut end = start + 7;
        if hex(end) && hex(end + 1) {
            end += 2;
        }
        if is_ident_byte(self.at(end)) {
            return None;
        }
        let text = &self.s[start + 1..end];
        let v = u32::from_str_radix(text, 16).unwrap_or(0);
        let v = if text.len() == 6 { (v << 8) | 0xff } else { v };
        self.pos = end;
        Some((Expr { kind: ExprKind::Colour(v), span: self.span(start, end) }, 0))
    }

    /// `string`: its parts (or plain text), the depth of its interpolations, and its span.
    pub(super) fn string(&mut self, plain: bool) -> Option<(StrOut, usize, Span)> {
        let start = self.pos;
        if !self.byte(b'"') {
            return None;
        }
        let mut parts: Vec<StrPart> = Vec::new();
        let mut text = String::new();
        let mut deepest = 0;
        loop {
            let at = self.pos;
            if at >= self.b.len() {
                return self.fail_at(start);
            }
            match self.b[at] {
                b'"' => break,
                b'\\' => {
                    let un = match self.at(at + 1) {
                        b'n' => "\n",
                        b't' => "\t",
                        b'\\' => "\\",
                        b'"' => "\"",
                        b'{' => "{",
                        b'}' => "}",
                        _ => return self.fail_at(start),
                    };
                    self.pos += 2;
                    text.push_str(un);
                }
                b'{' if self.at(at + 1) == b'{' => {
                    self.pos += 2;
                    text.push('{');
                }
                b'}' if self.at(at + 1) == b'}' => {
                    self.pos += 2;
                    text.push('}');
                }
                b'{' => {
                    let Some((expr, spec, need)) = self.attempt(Self::interp) else {
                        return self.fail_at(start);
                    };
                    deepest = deepest.max(need);
                    if plain {
                        text.push_str(&self.s[at..self.pos]);
                    } else {
                        if !text.is_empty() {
                            parts.push(StrPart::Text(std::mem::take(&mut text)));
                        }
                        parts.push(StrPart::Interp { expr, spec });
                    }
                }
                b'}' | b'\n' => return self.fail_at(start),
                _ => {
                    let mut i = at + 1;
                    while i < self.b.len()
                        && !matches!(self.b[i], b'"' | b'\\' | b'{' | b'}' | b'\n')
                    {
                        i += 1;
                    }
                    self.pos = i;
                    text.push_str(&self.s[at..i]);
                }
            }
        }
        self.pos += 1;
        let span = self.span(start, self.pos);
        let out = if plain {
            StrOut::Plain(text)
        } else {
            if !text.is_empty() {
                parts.push(StrPart::Text(text));
            }
            parts.shrink_to_fit();
            StrOut::Parts(parts)
        };
        Some((out, deepest, span))
    }

    fn fail_at<T>(&mut self, start: usize) -> Option<T> {
        self.pos = start;
        None
    }

    /// `interp`: `{ expr :spec }`.
    #[allow(clippy::type_complexity)]
    fn interp(&mut self) -> Option<(Expr, Option<(String, Span)>, usize)> {
        self.pos += 1;
        self.ws();
        let (expr, need) = self.expr()?;
        self.ws();
        let mut spec = None;
        if self.peek() == b':' {
            let start = self.pos;
            let mut i = start + 1;
            while i < self.b.len() && !matches!(self.b[i], b'}' | b'"') {
                i += 1;
            }
            self.pos = i;
            let text = self.s[start..i].trim_start_matches(':').to_string();
            spec = Some((text, self.span(start, i)));
        }
        self.ws();
        self.byte(b'}').then_some((expr, spec, need))
    }
}

type Elems<'e> = std::iter::Peekable<std::vec::Drain<'e, Elem>>;

/// Precedence climbing, as parser.rs's `climb` and `operand` do it over pest's pairs.
fn climb(it: &mut Elems, floor: u8) -> Expr {
    let mut lhs = operand(it);
    while let Some(&Elem::Infix(op, power, right)) = it.peek() {
        if power <= floor {
            break;
        }
        it.next();
        let rhs = climb(it, if right { power - 1 } else { power });
        let span = lhs.span.to(rhs.span);
        lhs = Expr { kind: ExprKind::Binary(op, Box::new(lhs), Box::new(rhs)), span };
    }
    lhs
}

fn operand(it: &mut Elems) -> Expr {
    match it.next() {
        Some(Elem::Prefix(op, span)) => {
            let rhs = climb(it, PREFIX - 1);
            let span = span.to(rhs.span);
            Expr { kind: ExprKind::Unary(op, Box::new(rhs)), span }
        }
        Some(Elem::Term(e)) => e,
        // Never: the list alternates prefixes and terms with operators, and ends on a term.
        Some(Elem::Infix(..)) | None => {
            Expr { kind: ExprKind::Error, span: Span::new(crate::source::FileId(0), 0, 0) }
        }
    }
}
