//! Pass 5d: expressions nested deeper than the runtime lowers (E0106), counted the way the
//! lowering recurses: once the `let`s an expression names are put in place, and through a
//! widget's arguments that refer to their siblings (`value x`, `label "{value}"`). A chain
//! of 80 `let`s, each adding to the one before, is 80 levels deep although no line is.
//! `mocu-lower` refuses what is deeper than [`MAX_DEPTH`]; this pass refuses it first, with
//! the place, so that what `check` passes `run` loads.

use crate::codes;
use crate::diagnostics::Diagnostics;
use crate::program::*;

/// The deepest expression the runtime lowers (`mocu-lower` uses this bound).
pub const MAX_DEPTH: usize = 256;

/// A widget's arguments and position, which `Param` and `Size` nodes refer to.
type WidgetCtx<'a> = Option<(&'a [Arg], &'a [Bound])>;

pub fn check_depth(program: &Program, diags: &mut Diagnostics) {
    let report = |b: &Bound, ctx: WidgetCtx, diags: &mut Diagnostics| {
        let h = height(&b.expr, ctx, MAX_DEPTH);
        if h > MAX_DEPTH {
            diags
                .error(
                    codes::TOO_DEEP,
                    b.expr.span,
                    format!(
                        "this expression is nested more than {MAX_DEPTH} levels deep once the `let`s it names are put in place"
                    ),
                )
                .label("too deep to run")
                .help("shorten the chain of `let`s, each built on the one before, or split the expression");
        }
    };
    let widgets = program.widgets.iter().chain(program.templates.iter().flat_map(|t| &t.widgets));
    for w in widgets {
        let ctx = Some((&w.args[..], &w.at[..]));
        for b in w.at.iter().chain(w.args.iter().map(|a| &a.value)).chain(w.visible.iter()) {
            report(b, ctx, diags);
        }
    }
    // Everything else (windows, actions, watches, bindings, component bodies): no siblings.
    for b in roots(program) {
        report(b, None, diags);
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

/// The lowering depth of `e`, or `budget + 1` when it is deeper than `budget`.
fn height(e: &Expr, ctx: WidgetCtx, budget: usize) -> usize {
    if budget == 0 {
        return 1;
    }
    let sub = |x: &Expr| height(x, ctx, budget - 1);
    let inner = match &e.node {
        Node::Param(name) => ctx
            .and_then(|(args, _)| args.iter().find(|a| &a.name == name))
            .map_or(0, |a| sub(&a.value.expr)),
        Node::Size(n) => {
            ctx.and_then(|(_, at)| at.get(if n == "w" { 2 } else { 3 })).map_or(0, |b| sub(&b.expr))
        }
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
