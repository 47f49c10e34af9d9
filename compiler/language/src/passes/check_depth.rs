//! Pass 5d: expressions nested deeper than the runtime lowers (E0106), counted the way the
//! lowering recurses: through a widget's arguments that refer to their siblings (`value x`,
//! `label "{value}"`), and through the `let`s that are put in place at their uses (a range,
//! an object or an untyped value: see [`Let::is_local`]). A `let` of a value type is
//! computed once, as a local of the function, so its uses are one level each and its value
//! is counted once, on its own: a chain of 50,000 `let`s, each adding to the one before,
//! is two levels deep. `mocu-lower` refuses what is deeper than [`MAX_DEPTH`]; this pass
//! refuses it first, with the place, so that what `check` passes `run` loads.

use crate::codes;
use crate::diagnostics::Diagnostics;
use crate::program::*;
use std::sync::Arc;

/// The deepest expression the runtime lowers (`mocu-lower` uses this bound).
pub const MAX_DEPTH: usize = 256;

/// A widget's arguments and position, which `Param` and `Size` nodes refer to.
type WidgetCtx<'a> = Option<(&'a [Arg], &'a [Bound])>;

pub fn check_depth(program: &Program, diags: &mut Diagnostics) {
    let mut heights = Heights::default();
    let mut report = |e: &Expr, ctx: WidgetCtx, diags: &mut Diagnostics| {
        let h = heights.height(e, ctx, MAX_DEPTH);
        if h > MAX_DEPTH {
            diags
                .error(
                    codes::TOO_DEEP,
                    e.span,
                    format!(
                        "this expression is nested more than {MAX_DEPTH} levels deep once the `let`s it names are put in place"
                    ),
                )
                .label("too deep to run")
                .help("shorten the chain of `let`s, each built on the one before, or split the expression");
        }
    };
    // Each `let` computed once (as a local of the functions that read it), on its own.
    for l in program.lets.0.iter().filter(|l| l.is_local()) {
        report(&l.value, None, diags);
    }
    let widgets = program.widgets.iter().chain(program.templates.iter().flat_map(|t| &t.widgets));
    for w in widgets {
        let ctx = Some((&w.args[..], &w.at[..]));
        for b in w.at.iter().chain(w.args.iter().map(|a| &a.value)).chain(w.visible.iter()) {
            report(&b.expr, ctx, diags);
        }
    }
    // Everything else (windows, actions, watches, bindings, component bodies): no siblings.
    for b in roots(program) {
        report(&b.expr, None, diags);
    }
}

/// Every bound expression of the program, widget arguments included (checked again without
/// their siblings: never deeper than with them).
fn roots(p: &Program) -> Vec<&Bound> {
    let mut out: Vec<&Bound> = Vec::new();
    fn acts<'a>(list: &'a [Action], out: &mut Vec<&'a Bound>) {
        for a in list {
            match a {
                Action::Set { value, .. } => out.push(value),
                Action::Call { args, .. } => out.extend(args),
                Action::Alert { message, .. } => out.push(message),
                _ => {}
            }
        }
    }
    let windows = p.windows.iter().chain(p.templates.iter().flat_map(|t| &t.windows));
    for w in windows {
        out.extend(w.rect.iter().chain([&w.layer, &w.opacity, &w.visible]).chain(w.source.iter()));
    }
    let widgets = p.widgets.iter().chain(p.templates.iter().flat_map(|t| &t.widgets));
    for w in widgets {
        for h in &w.handlers {
            acts(&h.actions, &mut out);
        }
    }
    for c in &p.components {
        for s in &c.shapes {
            out.extend(s.args.iter().chain(s.styles.iter().map(|a| &a.value)));
        }
    }
    for b in &p.bindings {
        acts(&b.actions, &mut out);
    }
    for m in &p.menus {
        for i in &m.items {
            out.push(&i.label);
            out.extend(i.enabled.iter());
            acts(&i.actions, &mut out);
        }
    }
    for w in p.watches.iter().chain(p.templates.iter().flat_map(|t| &t.watches)) {
        out.push(&w.when);
        out.extend(w.clear.iter());
        acts(&w.actions, &mut out);
    }
    out
}

/// Lowering depths, remembering those of the `let`s put in place at their uses (a `let`
/// named twice by the next, and that one twice by the next, … is counted once each).
#[derive(Default)]
struct Heights {
    /// Per `let` put in place: the depth of its value, at most `MAX_DEPTH + 1`.
    lets: super::FastMap<*const Let, usize>,
}

impl Heights {
    /// The lowering depth of `e`, or `budget + 1` when it is deeper than `budget`.
    fn height(&mut self, e: &Expr, ctx: WidgetCtx, budget: usize) -> usize {
        if budget == 0 {
            return 1;
        }
        let mut sub = |x: &Expr| self.height(x, ctx, budget - 1);
        let inner = match &e.node {
            Node::Let(l) if l.is_local() => 0,
            Node::Let(l) => {
                // Lowered in place: as deep as its value (height(v, b) = min(h(v), b + 1)).
                let key = Arc::as_ptr(&l.0);
                let h = match self.lets.get(&key) {
                    Some(h) => *h,
                    None => {
                        let h = self.height(&l.value, ctx, MAX_DEPTH);
                        self.lets.insert(key, h);
                        h
                    }
                };
                h.min(budget)
            }
            Node::Param(name) => ctx
                .and_then(|(args, _)| args.iter().find(|a| &a.name == name))
                .map_or(0, |a| sub(&a.value.expr)),
            Node::Size(n) => ctx
                .and_then(|(_, at)| at.get(if n == "w" { 2 } else { 3 }))
                .map_or(0, |b| sub(&b.expr)),
            Node::RangeEnd { range, .. } => sub(range),
            Node::Range { lo, hi } => sub(lo).max(sub(hi)),
            Node::Unary { arg, .. } => sub(arg),
            Node::Binary { lhs, rhs, .. } => sub(lhs).max(sub(rhs)),
            Node::If { cond, then, other } => sub(cond).max(sub(then)).max(sub(other)),
            Node::Call { args, .. } => args.iter().map(sub).max().unwrap_or(0),
            Node::Format(parts) => parts
                .iter()
                .map(|p| match p {
                    FormatPart::Value { expr, .. } => sub(expr),
                    FormatPart::Text(_) => 0,
                })
                .max()
                .unwrap_or(0),
            _ => 0,
        };
        1 + inner
    }
}
