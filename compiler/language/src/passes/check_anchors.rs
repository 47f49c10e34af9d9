//! Screen placement (see [`crate::placement`]): `anchor` names (E0213), the `design` size
//! (E0214: in the layout file, once, positive px), a `for each`'s `flow` (E0215: `down` or
//! `right`, a gap in px, windows to place), the display's limits (E0216: `rect`, `at` and
//! `design` numbers within mocu-value's `limits`, which the runtime enforces too) and, in a layout with a design, positions
//! computed from the screen's own size (W0005), which would be scaled twice.

use crate::ast::{self, ExprKind, Item, LitUnit};
use crate::codes;
use crate::diagnostics::Diagnostics;
use crate::passes::Modules;
use crate::placement::{ANCHORS, Anchor, Design};
use crate::program::{Bound, PathBase, Program};
use mocu_value::limits::{MAX_EXTENT, MIN_DESIGN_SIDE};

/// Checks every anchor and design of the layout and the files it uses; returns the design.
pub fn check_anchors(modules: &Modules, diags: &mut Diagnostics) -> Option<Design> {
    let mut design = None;
    let mut first: Option<crate::source::Span> = None;
    for (m, module) in modules.iter().enumerate() {
        for item in &module.ast.items {
            if let Item::Design(d) = item {
                if m != 0 {
                    diags
                        .error(codes::BAD_DESIGN, d.span, "`design` belongs in the layout file")
                        .label("in a used file")
                        .help("a used file's positions take the design of the layout that uses it");
                    continue;
                }
                if let Some(f) = first {
                    diags
                        .error(codes::BAD_DESIGN, d.span, "the layout declares `design` twice")
                        .related(f, "first declared here")
                        .help("one `design W x H` per layout");
                    continue;
                }
                first = Some(d.span);
                if let (Some(w), Some(h)) = (size(&d.width, diags), size(&d.height, diags)) {
                    design = Some(Design { width: w, height: h });
                }
            }
            anchors(item, diags);
        }
    }
    design
}

/// A design dimension: a positive number of px.
fn size(e: &ast::Expr, diags: &mut Diagnostics) -> Option<f64> {
    let ExprKind::Number { value, unit } = &e.kind else { return None };
    match unit {
        None | Some(LitUnit::Px) if (MIN_DESIGN_SIDE..=MAX_EXTENT).contains(value) => Some(*value),
        None | Some(LitUnit::Px) if *value > 0.0 => {
            diags
                .error(
                    codes::BEYOND_LIMIT,
                    e.span,
                    format!(
                        "a design side is {MIN_DESIGN_SIDE} to {MAX_EXTENT} px, not {value}"
                    ),
                )
                .help("the design's scale (screen / design) grows every px: write the screen size the layout was drawn for, `design 1280 x 720`");
            None
        }
        None | Some(LitUnit::Px) => {
            diags
                .error(codes::BAD_DESIGN, e.span, "a design size is more than 0 px")
                .help("write the screen size the layout was drawn for: `design 1280 x 720`");
            None
        }
        Some(_) => {
            diags
                .error(codes::BAD_DESIGN, e.span, "a design size is in px")
                .help("write the screen size the layout was drawn for: `design 1280 x 720`");
            None
        }
    }
}

/// E0213, E0215 and E0216 in one item: its anchors, its `flow` and its `rect`/`at`.
pub fn anchors(item: &Item, diags: &mut Diagnostics) {
    match item {
        Item::Window(w) => {
            anchor(w.anchor.as_ref(), diags);
            within_limits(w.rect.as_deref().unwrap_or_default(), "a window's `rect`", diags);
        }
        Item::In(b) => b.widgets.iter().for_each(|w| {
            anchor(w.anchor.as_ref(), diags);
            within_limits(w.at.as_ref().map_or(&[][..], |a| &a.0), "a widget's `at`", diags);
        }),
        Item::Each(e) => {
            if let Some(f) = &e.flow {
                within_limits(&f.rect, "a flow's `rect`", diags);
                anchor(f.anchor.as_ref(), diags);
                flow(f, e, diags);
            }
            e.items.iter().for_each(|i| anchors(i, diags))
        }
        _ => {}
    }
}

/// The ways a flow goes.
const DIRECTIONS: [&str; 2] = ["down", "right"];

/// E0215: a flow's direction, its gap's unit, and windows for it to place.
fn flow(f: &ast::Flow, e: &ast::Each, diags: &mut Diagnostics) {
    let dir = &f.direction;
    if !DIRECTIONS.contains(&dir.name.as_str()) {
        diags
            .error(codes::BAD_FLOW, dir.span, format!("unknown flow direction `{}`", dir.name))
            .help("a flow goes `down` (a column, then the next on its right) or `right` (a row, then the next below)")
            .suggest(&dir.name, DIRECTIONS.iter().copied());
    }
    if let Some(g) = &f.gap
        && let ExprKind::Number { unit: Some(u), .. } = &g.kind
        && *u != LitUnit::Px
    {
        diags
            .error(codes::BAD_FLOW, g.span, "a flow's gap is in px")
            .help("write the space between two instances in px of the design: `gap 8`");
    }
    if !e.items.iter().any(|i| matches!(i, Item::Window(_))) {
        diags
            .error(codes::BAD_FLOW, f.span, "`flow` places the template's windows, and it has none")
            .help("declare a `window` in the `for each` body, or leave `flow` out");
    }
}

/// E0216: a px number of a `rect` or an `at` beyond ±[`MAX_EXTENT`]: the display would hold
/// the window to its limits (and a window larger than the screen shows only its part on it).
fn within_limits(numbers: &[ast::Expr], what: &str, diags: &mut Diagnostics) {
    for e in numbers {
        let v = match &e.kind {
            ExprKind::Number { value, unit: None | Some(LitUnit::Px) } => *value,
            ExprKind::Unary(ast::UnOp::Neg, inner) => match &inner.kind {
                ExprKind::Number { value, unit: None | Some(LitUnit::Px) } => -*value,
                _ => continue,
            },
            _ => continue,
        };
        if v.abs() > MAX_EXTENT {
            diags
                .error(
                    codes::BEYOND_LIMIT,
                    e.span,
                    format!("{v} px is beyond the display's limit of ±{MAX_EXTENT} px"),
                )
                .help(format!("{what} stays within ±{MAX_EXTENT} px (design px with `design`); `100%` is the whole screen"));
        }
    }
}

fn anchor(name: Option<&ast::Ident>, diags: &mut Diagnostics) {
    let Some(n) = name else { return };
    if Anchor::parse(&n.name).is_some() {
        return;
    }
    let d = diags.error(codes::UNKNOWN_ANCHOR, n.span, format!("unknown anchor `{}`", n.name));
    d.help(format!("an anchor is one of {}", ANCHORS.join(", ")));
    d.suggest(&n.name, ANCHORS.iter().copied());
}

/// W0005: with a design, positions are in design px; the screen's size in px would be
/// scaled once more. Anchors and `%` say the same without it.
pub fn warn_screen_px(program: &Program, diags: &mut Diagnostics) {
    if program.design.is_none() {
        return;
    }
    let windows = program.windows.iter().chain(program.templates.iter().flat_map(|t| &t.windows));
    let widgets = program.widgets.iter().chain(program.templates.iter().flat_map(|t| &t.widgets));
    let flows = program.templates.iter().filter_map(|t| t.flow.as_ref());
    let bounds = windows
        .flat_map(|w| w.rect.iter())
        .chain(widgets.flat_map(|w| w.at.iter()))
        .chain(flows.flat_map(|f| f.rect.iter()));
    for b in bounds {
        if reads_screen_size(b) {
            diags
                .warning(
                    codes::SCREEN_PX_IN_DESIGN,
                    b.expr.span,
                    "with `design`, positions are design px, but this reads the screen's size",
                )
                .label("screen px, scaled again")
                .help("measure from an edge with `anchor` (`anchor bottom-right`), or use %");
        }
    }
}

fn reads_screen_size(b: &Bound) -> bool {
    b.paths.iter().any(|p| {
        p.base == PathBase::Root
            && p.segments.len() == 2
            && p.segments[0] == "display"
            && (p.segments[1] == "width" || p.segments[1] == "height")
    })
}
