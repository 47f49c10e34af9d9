//! pest's pairs to the syntax tree (the reference tree builder: the fast parser,
//! parser/fast.rs, builds the same trees without pest).

use super::Rule;
use crate::ast::*;
use crate::source::{FileId, Span};
use pest::iterators::{Pair, Pairs};

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

pub(super) struct Ctx {
    pub(super) file: FileId,
    pub(super) offset: usize,
    /// Current expression nesting, and where it first went past [`MAX_DEPTH`].
    pub(super) depth: std::cell::Cell<usize>,
    pub(super) too_deep: std::cell::Cell<Option<Span>>,
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

    pub(super) fn item(&self, p: Pair<Rule>) -> Item {
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
                Item::Watch(Box::new(Watch { name, when, hold, clear, repeat, actions, span }))
            }
            Rule::each_item => {
                let var = self.next_ident(&mut inner, span);
                let source = inner
                    .next()
                    .map_or(Expr { kind: ExprKind::Name("root".into()), span }, |e| self.expr(e));
                let mut object_type = None;
                let mut flow = None;
                let mut items = Vec::new();
                for q in inner {
                    match q.as_rule() {
                        Rule::string => {
                            let s = self.span(&q);
                            object_type = Some((self.plain_string(q), s));
                        }
                        Rule::flow_clause => flow = Some(self.flow(q)),
                        _ => items.push(self.item(q)),
                    }
                }
                Item::Each(Box::new(Each { var, source, object_type, flow, items, span }))
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

    /// `flow down rect X Y W H anchor NAME gap N` (the `flow` keyword's pair left out).
    fn flow(&self, p: Pair<Rule>) -> Flow {
        let span = self.span(&p);
        let mut direction = Ident { name: String::new(), span };
        let (mut rect, mut anchor, mut gap) = (Vec::new(), None, None);
        for q in p.into_inner() {
            match q.as_rule() {
                Rule::ident => direction = self.ident(q),
                Rule::rect_prop => rect = q.into_inner().map(|g| self.geom(g)).collect(),
                Rule::anchor_prop => anchor = self.anchor(q),
                Rule::flow_gap => {
                    gap =
                        q.into_inner().find(|x| x.as_rule() == Rule::number).map(|n| self.number(n))
                }
                _ => {}
            }
        }
        Flow { direction, rect, anchor, gap, span }
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
            Rule::script_action => {
                let (prefix, body) = (it.next(), it.next());
                let engine = prefix.map_or_else(
                    || Ident { name: String::new(), span },
                    |q| {
                        let name = q.as_str().trim_start_matches('#').trim_end_matches(':');
                        Ident { name: name.to_string(), span: self.span(&q) }
                    },
                );
                let (body, body_span) = body.map_or_else(
                    || (String::new(), span),
                    |q| {
                        let s = self.span(&q);
                        let text = q.as_str();
                        // The rule matched `{` … `}`: two one-byte braces.
                        let inner = &text[1..text.len() - 1];
                        (inner.to_string(), Span { start: s.start + 1, end: s.end - 1, ..s })
                    },
                );
                ActionKind::Script { engine, body, body_span }
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
