//! Items, their bodies and actions for the fast parser (grammar.pest from `item` to
//! `select_action`), built as parser.rs's tree builder builds them.

use super::Fast;
use super::expr::StrOut;
use crate::ast::*;
use crate::source::Span;

/// A list as long as its items: the tree is kept while the whole layout is checked, and the
/// room a growing vector keeps spare was a third of it (issue 13's memory figure).
fn tight<T>(mut v: Vec<T>) -> Vec<T> {
    v.shrink_to_fit();
    v
}

const STYLE_KEYS: &[&str] =
    &["fill", "font", "stroke", "size", "width", "color", "colour", "align", "visible", "opacity"];
const PRIMITIVE_NAMES: &[&str] =
    &["rect", "rounded", "circle", "arc", "line", "polyline", "text", "image"];
const OPT_KEYS: &[&str] =
    &["deadzone", "expo", "scale", "invert", "rate", "hold", "double", "release", "press"];
const BINDING_KINDS: &[&str] = &["axis", "button", "key", "wheel"];

impl<'a> Fast<'a> {
    /// `item`: the alternatives begin with different words, so at most one can match.
    pub(super) fn item(&mut self) -> Option<Item> {
        let b = &self.b[self.pos..];
        let start = self.pos;
        if b.starts_with(b"use") {
            self.attempt(Self::use_item)
        } else if b.starts_with(b"let") {
            self.attempt(|p| p.let_item(start)).map(Item::Let)
        } else if b.starts_with(b"window") {
            self.attempt(Self::window_item)
        } else if b.starts_with(b"in") {
            self.attempt(Self::in_item)
        } else if b.starts_with(b"component") {
            self.attempt(Self::component_item)
        } else if b.starts_with(b"bind") {
            self.attempt(Self::bind_item)
        } else if b.starts_with(b"menu") {
            self.attempt(Self::menu_item)
        } else if b.starts_with(b"watch") {
            self.attempt(Self::watch_item)
        } else if b.starts_with(b"for") {
            self.attempt(Self::each_item)
        } else if self.word_here(b"design") {
            self.attempt(Self::design_item)
        } else {
            None
        }
    }

    /// Whitespace, then `c`.
    fn then(&mut self, c: u8) -> Option<()> {
        self.ws();
        self.byte(c).then_some(())
    }

    /// Whitespace, then the literal `text`.
    fn then_lit(&mut self, text: &[u8]) -> Option<()> {
        self.ws();
        self.lit(text).then_some(())
    }

    /// Whitespace, then a name.
    fn then_ident(&mut self) -> Option<Ident> {
        self.ws();
        self.ident()
    }

    /// Whitespace, then an expression.
    fn then_expr(&mut self) -> Option<Expr> {
        self.ws();
        self.top_expr()
    }

    fn here(&self, start: usize) -> Span {
        self.span(start, self.pos)
    }

    fn use_item(&mut self) -> Option<Item> {
        let start = self.pos;
        self.pos += 3;
        self.ws();
        let (path, path_span) = self.plain_string()?;
        self.ws();
        let alias = self.attempt(|p| {
            p.lit(b"as").then_some(())?;
            p.then_ident()
        });
        Some(Item::Use(Use { path, path_span, alias, span: self.here(start) }))
    }

    fn plain_string(&mut self) -> Option<(String, Span)> {
        match self.string(true)? {
            (StrOut::Plain(s), _, span) => Some((s, span)),
            _ => None,
        }
    }

    /// `let NAME = expr`, from `start`.
    fn let_item(&mut self, start: usize) -> Option<Let> {
        self.lit(b"let").then_some(())?;
        let name = self.then_ident()?;
        self.then(b'=')?;
        let value = self.then_expr()?;
        Some(Let { name, value, span: self.here(start) })
    }

    fn design_item(&mut self) -> Option<Item> {
        let start = self.pos;
        self.pos += 6;
        self.ws();
        let width = self.number()?;
        self.then(b'x')?;
        self.ws();
        let height = self.number()?;
        Some(Item::Design(Design { width, height, span: self.here(start) }))
    }

    fn window_item(&mut self) -> Option<Item> {
        let start = self.pos;
        self.pos += 6;
        let name = self.then_ident()?;
        self.then(b'{')?;
        self.ws();
        let (mut rect, mut anchor, mut props) = (None, None, Vec::new());
        self.star(|p| {
            if let Some(r) = p.attempt(Self::rect_prop) {
                rect = Some(r);
            } else if let Some(a) = p.attempt(Self::anchor_prop) {
                anchor = Some(a);
            } else if let Some(prop) = p.attempt(Self::named_prop) {
                props.push(prop);
            } else {
                return false;
            }
            true
        });
        self.then(b'}')?;
        Some(Item::Window(Window {
            name,
            rect,
            anchor,
            props: tight(props),
            span: self.here(start),
        }))
    }

    fn rect_prop(&mut self) -> Option<Vec<Expr>> {
        self.lit(b"rect").then_some(())?;
        let mut geoms = Vec::with_capacity(4);
        for _ in 0..4 {
            self.ws();
            geoms.push(self.geom()?);
        }
        Some(geoms)
    }

    /// `geom`: `-`? number, or `( expr )`.
    fn geom(&mut self) -> Option<Expr> {
        let start = self.pos;
        let number = self.attempt(|p| {
            let negative = p.byte(b'-');
            p.ws();
            p.number().map(|n| (negative, n))
        });
        if let Some((negative, e)) = number {
            let span = self.here(start);
            return Some(if negative {
                Expr { kind: ExprKind::Unary(UnOp::Neg, Box::new(e)), span }
            } else {
                Expr { span, ..e }
            });
        }
        self.attempt(|p| {
            p.byte(b'(').then_some(())?;
            let e = p.then_expr()?;
            p.then(b')')?;
            Some(Expr { span: p.here(start), ..e })
        })
    }

    /// `anchor NAME`: the name (`bottom-right`).
    fn anchor_prop(&mut self) -> Option<Ident> {
        if !self.word_here(b"anchor") {
            return None;
        }
        self.pos += 6;
        self.ws();
        let start = self.pos;
        let mut end = self.ident_end(start);
        if end == start {
            return None;
        }
        if self.at(end) == b'-' {
            let more = self.ident_end(end + 1);
            if more > end + 1 {
                end = more;
            }
        }
        self.pos = end;
        Some(Ident { name: self.s[start..end].to_string(), span: self.span(start, end) })
    }

    fn named_prop(&mut self) -> Option<Prop> {
        let start = self.pos;
        let name = self.ident()?;
        let value = self.then_expr()?;
        Some(Prop { name, value, span: self.here(start) })
    }

    fn in_item(&mut self) -> Option<Item> {
        let start = self.pos;
        self.pos += 2;
        let window = self.then_ident()?;
        self.then(b'{')?;
        self.ws();
        let mut widgets = Vec::new();
        self.star(|p| p.attempt(Self::widget).map(|w| widgets.push(w)).is_some());
        self.then(b'}')?;
        Some(Item::In(InBlock { window, widgets: tight(widgets), span: self.here(start) }))
    }

    fn widget(&mut self) -> Option<Widget> {
        let start = self.pos;
        let name = self.attempt(|p| {
            let n = p.ident()?;
            p.then(b':')?;
            Some(n)
        });
        self.ws();
        let component = self.ident()?;
        self.then(b'{')?;
        self.ws();
        let (mut at, mut anchor, mut args, mut handlers) = (None, None, Vec::new(), Vec::new());
        self.star(|p| {
            if let Some(a) = p.attempt(Self::at_prop) {
                at = Some(a);
            } else if let Some(a) = p.attempt(Self::anchor_prop) {
                anchor = Some(a);
            } else if let Some(h) = p.attempt(Self::on_prop) {
                handlers.push(h);
            } else if let Some(prop) = p.attempt(Self::named_prop) {
                args.push(prop);
            } else {
                return false;
            }
            true
        });
        self.then(b'}')?;
        let (args, handlers) = (tight(args), tight(handlers));
        Some(Widget { name, component, at, anchor, args, handlers, span: self.here(start) })
    }

    fn at_prop(&mut self) -> Option<(Vec<Expr>, Span)> {
        let start = self.pos;
        self.lit(b"at").then_some(())?;
        self.ws();
        let mut geoms = Vec::with_capacity(4);
        geoms.push(self.geom()?);
        self.ws();
        geoms.push(self.geom()?);
        self.ws();
        if let Some((c, d)) = self.attempt(|p| {
            let c = p.geom()?;
            p.ws();
            Some((c, p.geom()?))
        }) {
            geoms.push(c);
            geoms.push(d);
        }
        Some((geoms, self.here(start)))
    }

    fn on_prop(&mut self) -> Option<Handler> {
        let start = self.pos;
        self.lit(b"on").then_some(())?;
        let event = self.then_ident()?;
        self.ws();
        let actions = self.actions()?;
        Some(Handler { event, actions, span: self.here(start) })
    }

    /// `action+`.
    fn actions(&mut self) -> Option<Vec<Action>> {
        let mut actions = vec![self.action()?];
        self.ws();
        self.star(|p| p.action().map(|a| actions.push(a)).is_some());
        Some(tight(actions))
    }

    fn component_item(&mut self) -> Option<Item> {
        let start = self.pos;
        self.pos += 9;
        let name = self.then_ident()?;
        self.then(b'(')?;
        self.ws();
        let mut params = Vec::new();
        if let Some(first) = self.param() {
            params.push(first);
            self.ws();
            self.star(|p| {
                p.attempt(|p| {
                    p.byte(b',').then_some(())?;
                    p.ws();
                    p.param()
                })
                .map(|x| params.push(x))
                .is_some()
            });
            self.ws();
            self.byte(b',');
        }
        self.then(b')')?;
        self.then(b'{')?;
        self.ws();
        let mut body = Vec::new();
        self.star(|p| {
            let at = p.pos;
            if let Some(l) = p.attempt(|p| p.let_item(at)) {
                body.push(Stmt::Let(l));
            } else if let Some(prim) = p.attempt(Self::primitive) {
                body.push(Stmt::Primitive(prim));
            } else {
                return false;
            }
            true
        });
        self.then(b'}')?;
        let (params, body) = (tight(params), tight(body));
        Some(Item::Component(Component { name, params, body, span: self.here(start) }))
    }

    /// `param`: `on NAME`, or `NAME (: type)? (= expr)?`.
    fn param(&mut self) -> Option<Param> {
        if let Some(name) = self.attempt(|p| {
            p.lit(b"on").then_some(())?;
            p.then_ident()
        }) {
            return Some(Param::Event { name });
        }
        self.attempt(|p| {
            let name = p.ident()?;
            p.ws();
            let ty = p.attempt(|p| {
                p.byte(b':').then_some(())?;
                p.ws();
                let name = p.ident()?;
                let optional = p.byte(b'?');
                Some(TypeName { name, optional })
            });
            p.ws();
            let default = p.attempt(|p| {
                p.byte(b'=').then_some(())?;
                p.then_expr()
            });
            Some(Param::Value { name, ty, default })
        })
    }

    /// `primitive`: a kind, arguments up to a style name or the next primitive, styles.
    fn primitive(&mut self) -> Option<Primitive> {
        let start = self.pos;
        let kind = self.ident()?;
        self.ws();
        let mut args = Vec::new();
        self.star(|p| {
            if p.peek().is_ascii_lowercase()
                && STYLE_KEYS.iter().chain(PRIMITIVE_NAMES).any(|k| p.word_here(k.as_bytes()))
            {
                return false;
            }
            p.top_expr().map(|e| args.push(e)).is_some()
        });
        self.ws();
        let mut styles = Vec::new();
        self.star(|p| {
            p.attempt(|p| {
                let s = p.pos;
                let name = p.key_of(STYLE_KEYS)?;
                let value = p.then_expr()?;
                Some(Prop { name, value, span: p.here(s) })
            })
            .map(|prop| styles.push(prop))
            .is_some()
        });
        Some(Primitive { kind, args: tight(args), styles: tight(styles), span: self.here(start) })
    }

    fn bind_item(&mut self) -> Option<Item> {
        let start = self.pos;
        self.pos += 4;
        let device = self.then_ident()?;
        self.then(b'{')?;
        self.ws();
        let (mut shift, mut bindings, mut modes) = (None, Vec::new(), Vec::new());
        self.star(|p| {
            if let Some(s) = p.attempt(Self::shift_decl) {
                shift = Some(s);
            } else if let Some(m) = p.attempt(Self::mode_block) {
                modes.push(m);
            } else if let Some(b) = p.attempt(Self::binding) {
                bindings.push(b);
            } else {
                return false;
            }
            true
        });
        self.then(b'}')?;
        let (bindings, modes) = (tight(bindings), tight(modes));
        Some(Item::Bind(Bind { device, shift, bindings, modes, span: self.here(start) }))
    }

    /// `shift NAME` (not followed by an input kind and name).
    fn shift_decl(&mut self) -> Option<Ident> {
        self.lit(b"shift").then_some(())?;
        self.ws();
        let save = self.pos;
        let kind_and_name = self.key_of(BINDING_KINDS).is_some() && {
            self.ws();
            self.input_name().is_some()
        };
        self.pos = save;
        if kind_and_name {
            return None;
        }
        self.ws();
        self.input_name()
    }

    /// `input_name`: a name, string or number, as its text without quotes.
    fn input_name(&mut self) -> Option<Ident> {
        let start = self.pos;
        let ok = self.ident().is_some() || self.plain_string().is_some() || self.number().is_some();
        ok.then(|| Ident {
            name: self.s[start..self.pos].trim_matches('"').to_string(),
            span: self.here(start),
        })
    }

    fn mode_block(&mut self) -> Option<(Ident, Vec<Binding>)> {
        self.lit(b"mode").then_some(())?;
        let name = self.then_ident()?;
        self.then(b'{')?;
        self.ws();
        let mut bindings = Vec::new();
        self.star(|p| p.attempt(Self::binding).map(|b| bindings.push(b)).is_some());
        self.then(b'}')?;
        Some((name, tight(bindings)))
    }

    fn binding(&mut self) -> Option<Binding> {
        let start = self.pos;
        let shift = self.word_here(b"shift");
        if shift {
            self.pos += 5;
        }
        self.ws();
        let kind = self.ident()?;
        self.ws();
        let input = self.input_name()?;
        self.ws();
        let mut options = Vec::new();
        self.star(|p| p.binding_opt().map(|o| options.push(o)).is_some());
        self.then_lit(b"->")?;
        self.ws();
        let actions = self.actions()?;
        Some(Binding {
            shift,
            kind,
            input,
            options: tight(options),
            actions,
            span: self.here(start),
        })
    }

    fn binding_opt(&mut self) -> Option<BindingOption> {
        let start = self.pos;
        let name = self.key_of(OPT_KEYS)?;
        self.ws();
        let value = self.attempt(|p| {
            let vs = p.pos;
            let negative = p.byte(b'-');
            p.ws();
            let num = p.number()?;
            Some(if negative {
                Expr { kind: ExprKind::Unary(UnOp::Neg, Box::new(num)), span: p.here(vs) }
            } else {
                num
            })
        });
        Some(BindingOption { name, value, span: self.here(start) })
    }

    fn menu_item(&mut self) -> Option<Item> {
        let start = self.pos;
        self.pos += 4;
        self.then_lit(b"for")?;
        self.then_lit(b"type")?;
        self.ws();
        let (object_type, type_span) = self.plain_string()?;
        self.then(b'{')?;
        self.ws();
        let mut entries = Vec::new();
        self.star(|p| p.attempt(Self::menu_entry).map(|e| entries.push(e)).is_some());
        self.then(b'}')?;
        Some(Item::Menu(Menu {
            object_type,
            type_span,
            entries: tight(entries),
            span: self.here(start),
        }))
    }

    fn menu_entry(&mut self) -> Option<MenuEntry> {
        let start = self.pos;
        self.lit(b"item").then_some(())?;
        let label = self.then_expr()?;
        self.ws();
        let enabled = self.attempt(|p| {
            p.lit(b"enabled").then_some(())?;
            p.then_expr()
        });
        self.then_lit(b"->")?;
        self.ws();
        let actions = self.actions()?;
        Some(MenuEntry { label, enabled, actions, span: self.here(start) })
    }

    fn watch_item(&mut self) -> Option<Item> {
        let start = self.pos;
        self.pos += 5;
        let name = self.then_ident()?;
        self.then(b'{')?;
        self.then_lit(b"when")?;
        let when = self.then_expr()?;
        self.ws();
        let hold = self.attempt(|p| {
            p.lit(b"for").then_some(())?;
            p.then_expr()
        });
        self.ws();
        let clear = self.attempt(|p| {
            p.lit(b"clear").then_some(())?;
            p.then_lit(b"when")?;
            p.then_expr()
        });
        self.ws();
        let repeat = self.attempt(|p| {
            p.lit(b"repeat").then_some(())?;
            p.then_lit(b"every")?;
            p.then_expr()
        });
        self.then_lit(b"then")?;
        self.ws();
        let actions = self.actions()?;
        self.then(b'}')?;
        let span = self.here(start);
        Some(Item::Watch(Box::new(Watch { name, when, hold, clear, repeat, actions, span })))
    }

    fn each_item(&mut self) -> Option<Item> {
        let start = self.pos;
        self.pos += 3;
        self.then_lit(b"each")?;
        let var = self.then_ident()?;
        self.then_lit(b"in")?;
        let source = self.then_expr()?;
        self.ws();
        let object_type = self.attempt(|p| {
            p.lit(b"of").then_some(())?;
            p.then_lit(b"type")?;
            p.ws();
            p.plain_string()
        });
        self.ws();
        let flow = self.attempt(Self::flow_clause);
        self.then(b'{')?;
        self.ws();
        let mut items = Vec::new();
        self.star(|p| {
            let b = &p.b[p.pos..];
            let at = p.pos;
            let item = if b.starts_with(b"let") {
                p.attempt(|p| p.let_item(at)).map(Item::Let)
            } else if b.starts_with(b"window") {
                p.attempt(Self::window_item)
            } else if b.starts_with(b"in") {
                p.attempt(Self::in_item)
            } else if b.starts_with(b"watch") {
                p.attempt(Self::watch_item)
            } else {
                None
            };
            item.map(|i| items.push(i)).is_some()
        });
        self.then(b'}')?;
        Some(Item::Each(Box::new(Each {
            var,
            source,
            object_type,
            flow,
            items: tight(items),
            span: self.here(start),
        })))
    }

    /// `flow_clause`: `flow DIRECTION rect X Y W H (anchor NAME)? (gap N)?`; as pest, the
    /// whitespace before an absent option is the clause's.
    fn flow_clause(&mut self) -> Option<Flow> {
        let start = self.pos;
        if !self.word_here(b"flow") {
            return None;
        }
        self.pos += 4;
        let direction = self.then_ident()?;
        self.ws();
        let rect = self.rect_prop()?;
        self.ws();
        let anchor = self.attempt(Self::anchor_prop);
        self.ws();
        let gap = self.attempt(|p| {
            if !p.word_here(b"gap") {
                return None;
            }
            p.pos += 3;
            p.ws();
            p.number()
        });
        Some(Flow { direction, rect, anchor, gap, span: self.here(start) })
    }

    /// `action`: `set`, `call`, `swap`, `show`, `hide`, `alert`, `mode` or `select`.
    fn action(&mut self) -> Option<Action> {
        let start = self.pos;
        let b = &self.b[self.pos..];
        let kind = if b.starts_with(b"set") {
            self.attempt(|p| {
                p.pos += 3;
                let target = p.then_expr()?;
                p.then(b'=')?;
                let value = p.then_expr()?;
                Some(ActionKind::Set { target, value })
            })
        } else if b.starts_with(b"call") {
            self.attempt(|p| {
                p.pos += 4;
                Some(ActionKind::Call { call: p.then_expr()? })
            })
        } else if b.starts_with(b"swap") {
            self.attempt(|p| {
                p.pos += 4;
                let a = p.then_ident()?;
                let b = p.then_ident()?;
                p.ws();
                Some(ActionKind::Swap { a, b, duration: p.number() })
            })
        } else if b.starts_with(b"show") {
            self.attempt(|p| {
                p.pos += 4;
                Some(ActionKind::Show { window: p.then_ident()? })
            })
        } else if b.starts_with(b"hide") {
            self.attempt(|p| {
                p.pos += 4;
                Some(ActionKind::Hide { window: p.then_ident()? })
            })
        } else if b.starts_with(b"alert") {
            self.attempt(|p| {
                p.pos += 5;
                let level = p.then_ident()?;
                Some(ActionKind::Alert { level, message: p.then_expr()? })
            })
        } else if b.starts_with(b"mode") {
            self.attempt(|p| {
                p.pos += 4;
                let mode = p.then_ident()?;
                p.ws();
                (p.peek() != b'{').then_some(ActionKind::Mode { mode })
            })
        } else if b.starts_with(b"select") {
            self.attempt(|p| {
                p.pos += 6;
                p.ws();
                let target = if p.word_here(b"next") {
                    p.pos += 4;
                    SelectTarget::Next
                } else if p.word_here(b"prev") {
                    p.pos += 4;
                    SelectTarget::Prev
                } else {
                    SelectTarget::Object(p.top_expr()?)
                };
                Some(ActionKind::Select { target })
            })
        } else {
            None
        }?;
        Some(Action { kind, span: self.here(start) })
    }
}
