//! What the syntax tree tells the printer about the tokens: which token starts a line of its
//! own (an item, a property, a widget, a statement, a binding, a menu entry, a watch clause),
//! which `-` and `!` are prefixes, and which tokens are one word (`bottom-right`).
//!
//! Only the tree's spans are read, so the printer depends on the shape of the tree, not on
//! the grammar's rules.

use super::tokens::{Kind, Token};
use crate::ast::*;

/// Per token (by index into the token list).
pub struct Marks {
    /// Starts a line of its own.
    pub line_start: Vec<bool>,
    /// A binary operator (so a `-` or `!` not marked is a prefix).
    pub binary: Vec<bool>,
    /// Nothing between this token and the next (`bottom` `-` `right`).
    pub glue_next: Vec<bool>,
}

struct Walker<'a> {
    tokens: &'a [Token],
    /// The start of each token, for lookups by position.
    starts: Vec<usize>,
    marks: Marks,
}

pub fn marks(file: &File, tokens: &[Token]) -> Marks {
    let n = tokens.len();
    let mut w = Walker {
        tokens,
        starts: tokens.iter().map(|t| t.start).collect(),
        marks: Marks {
            line_start: vec![false; n],
            binary: vec![false; n],
            glue_next: vec![false; n],
        },
    };
    for item in &file.items {
        w.item(item);
    }
    w.marks
}

impl Walker<'_> {
    /// The token that starts at `pos`.
    fn at(&self, pos: u32) -> Option<usize> {
        self.starts.binary_search(&(pos as usize)).ok()
    }

    /// The first token (not a comment) at or after `pos`.
    fn from(&self, pos: u32) -> Option<usize> {
        let i = self.starts.partition_point(|&s| s < pos as usize);
        (i..self.tokens.len()).find(|&j| !self.tokens[j].is_comment())
    }

    /// The token `back` tokens (not comments) before the one at `pos`.
    fn before(&self, pos: u32, back: usize) -> Option<usize> {
        let mut i = self.at(pos)?;
        let mut left = back;
        while left > 0 {
            i = i.checked_sub(1)?;
            if !self.tokens[i].is_comment() {
                left -= 1;
            }
        }
        Some(i)
    }

    fn line(&mut self, i: Option<usize>) {
        if let Some(i) = i {
            self.marks.line_start[i] = true;
        }
    }

    fn line_at(&mut self, pos: u32) {
        let i = self.at(pos);
        self.line(i);
    }

    /// The keyword `back` tokens before `pos` starts a line (`rect` before its first number).
    fn line_before(&mut self, pos: u32, back: usize) {
        let i = self.before(pos, back);
        self.line(i);
    }

    /// The tokens of `span` are printed as one word.
    fn glue(&mut self, span: crate::source::Span) {
        let Some(first) = self.at(span.start) else { return };
        let mut i = first;
        while i + 1 < self.tokens.len() && self.tokens[i + 1].start < span.end as usize {
            self.marks.glue_next[i] = true;
            i += 1;
        }
    }

    fn item(&mut self, item: &Item) {
        match item {
            Item::Use(u) => self.line_at(u.span.start),
            Item::Design(d) => self.line_at(d.span.start),
            Item::Let(l) => self.let_(l),
            Item::Window(w) => {
                self.line_at(w.span.start);
                if let Some(rect) = &w.rect {
                    if let Some(first) = rect.first() {
                        self.line_before(first.span.start, 1);
                    }
                    rect.iter().for_each(|e| self.expr(e));
                }
                if let Some(a) = &w.anchor {
                    self.anchor(a);
                }
                for p in &w.props {
                    self.prop(p);
                }
            }
            Item::In(b) => {
                self.line_at(b.span.start);
                for w in &b.widgets {
                    self.widget(w);
                }
            }
            Item::Component(c) => {
                self.line_at(c.span.start);
                for p in &c.params {
                    if let Param::Value { default: Some(e), .. } = p {
                        self.expr(e);
                    }
                }
                for s in &c.body {
                    match s {
                        Stmt::Let(l) => self.let_(l),
                        Stmt::Primitive(p) => {
                            self.line_at(p.span.start);
                            p.args.iter().for_each(|e| self.expr(e));
                            p.styles.iter().for_each(|s| self.expr(&s.value));
                        }
                    }
                }
            }
            Item::Bind(b) => {
                self.line_at(b.span.start);
                if let Some(s) = &b.shift {
                    self.line_before(s.span.start, 1);
                }
                b.bindings.iter().for_each(|x| self.binding(x));
                for (name, bindings) in &b.modes {
                    self.line_before(name.span.start, 1);
                    bindings.iter().for_each(|x| self.binding(x));
                }
            }
            Item::Menu(m) => {
                self.line_at(m.span.start);
                for e in &m.entries {
                    self.line_at(e.span.start);
                    self.expr(&e.label);
                    if let Some(x) = &e.enabled {
                        self.expr(x);
                    }
                    self.actions(&e.actions);
                }
            }
            Item::Watch(w) => {
                self.line_at(w.span.start);
                self.line_before(w.when.span.start, 1);
                self.expr(&w.when);
                if let Some(h) = &w.hold {
                    self.expr(h);
                }
                for e in [&w.clear, &w.repeat].into_iter().flatten() {
                    self.line_before(e.span.start, 2);
                    self.expr(e);
                }
                if let Some(first) = w.actions.first() {
                    self.line_before(first.span.start, 1);
                }
                self.actions(&w.actions);
            }
            Item::Each(e) => {
                self.line_at(e.span.start);
                self.expr(&e.source);
                if let Some(flow) = &e.flow {
                    // On the header's line: `flow down rect … anchor bottom-left gap 8 {`.
                    flow.rect.iter().chain(&flow.gap).for_each(|x| self.expr(x));
                    if let Some(a) = &flow.anchor {
                        self.glue(a.span);
                    }
                }
                e.items.iter().for_each(|i| self.item(i));
            }
        }
    }

    fn let_(&mut self, l: &Let) {
        self.line_at(l.span.start);
        self.expr(&l.value);
    }

    fn prop(&mut self, p: &Prop) {
        self.line_at(p.span.start);
        self.expr(&p.value);
    }

    fn anchor(&mut self, a: &Ident) {
        self.line_before(a.span.start, 1);
        self.glue(a.span);
    }

    fn widget(&mut self, w: &Widget) {
        self.line_at(w.span.start);
        if let Some((at, span)) = &w.at {
            self.line_at(span.start);
            at.iter().for_each(|e| self.expr(e));
        }
        if let Some(a) = &w.anchor {
            self.anchor(a);
        }
        w.args.iter().for_each(|p| self.prop(p));
        for h in &w.handlers {
            self.line_at(h.span.start);
            self.actions(&h.actions);
        }
    }

    fn binding(&mut self, b: &Binding) {
        self.line_at(b.span.start);
        for o in &b.options {
            if let Some(v) = &o.value {
                self.expr(v);
            }
        }
        self.actions(&b.actions);
    }

    fn actions(&mut self, actions: &[Action]) {
        for a in actions {
            match &a.kind {
                ActionKind::Set { target, value } => {
                    self.expr(target);
                    self.expr(value);
                }
                ActionKind::Call { call } => self.expr(call),
                ActionKind::Swap { duration: Some(d), .. } => self.expr(d),
                ActionKind::Alert { message, .. } => self.expr(message),
                ActionKind::Select { target: SelectTarget::Object(e) } => self.expr(e),
                _ => {}
            }
        }
    }

    /// Marks the binary operators of `e` (with its own stack: trees may be deep).
    fn expr(&mut self, e: &Expr) {
        let mut stack = vec![e];
        while let Some(e) = stack.pop() {
            match &e.kind {
                ExprKind::Binary(_, l, r) => {
                    if let Some(op) = self.from(l.span.end)
                        && self.tokens[op].kind == Kind::Punct
                    {
                        self.marks.binary[op] = true;
                    }
                    stack.push(l);
                    stack.push(r);
                }
                ExprKind::Field(x, _) | ExprKind::Index(x, _) | ExprKind::Unary(_, x) => {
                    stack.push(x)
                }
                ExprKind::Call(f, args) => {
                    stack.push(f);
                    stack.extend(args.iter());
                }
                ExprKind::If(c, a, b) => stack.extend([&**c, &**a, &**b]),
                // Strings are printed as written, interpolations included.
                _ => {}
            }
        }
    }
}
