//! What `mocu check` runs on a layout: the passes of [`crate::compile_modules`], with the
//! layout's own `in`, `bind`, `menu`, `watch` and `component` items read, checked and
//! dropped a batch at a time, so that the check holds the syntax tree and program of one batch
//! at a time (besides the items others name: `let`s, windows, templates, components'
//! parameters), not of the whole file (issue 13's memory figure; docs/diagnostics.md,
//! "Limits and cost"). Nothing is built for running: only the diagnostics come out, and they
//! are exactly those of [`crate::compile_layout`] (`tests/lint.rs` compares the two on every
//! file of the corpus, in batches of one item and of many).
//!
//! Why it can: nothing names an `in`, `bind`, `menu` or `watch` item, so once the names that
//! items use are collected (from the resident items), each of them is resolved, typed and
//! checked on its own; a component's body is checked where it is defined, and its uses need
//! only its parameters. What spans items is carried: the `let`s read so far (for W0001), the
//! watch names (E0203), the `mode` actions and declared modes (E0212).

use crate::ast::{Ident, Item, Stmt};
use crate::diagnostics::Diagnostics;
use crate::parser::{self, Deferred};
use crate::passes::collect_definitions::WatchNames;
use crate::passes::warn_outside_window::WindowSizes;
use crate::passes::*;
use crate::schema::Schema;
use crate::source::{SourceLoader, SourceMap};

/// Source bytes of the layout read, checked and dropped together: large enough that a
/// batch's fixed costs (a typer, the window table of W0002) are small against its items,
/// small enough that its trees are a small part of the check's memory.
pub const BATCH_BYTES: usize = 16 << 10;

/// Checks a layout (already read) and everything it uses, as [`crate::compile_layout`] does,
/// holding one batch of its items at a time; builds no program.
pub fn lint_layout(
    path: &str,
    text: String,
    loader: &dyn SourceLoader,
    schema: &Schema,
    config: &crate::Config,
    sources: &mut SourceMap,
    diags: &mut Diagnostics,
) {
    lint_layout_in_batches(path, text, loader, schema, config, sources, diags, BATCH_BYTES)
}

/// [`lint_layout`] with batches of about `batch_bytes` of source (at least one item each).
#[allow(clippy::too_many_arguments)]
pub fn lint_layout_in_batches(
    path: &str,
    text: String,
    loader: &dyn SourceLoader,
    schema: &Schema,
    config: &crate::Config,
    sources: &mut SourceMap,
    diags: &mut Diagnostics,
    batch_bytes: usize,
) {
    // 1. Parse the files; of the layout (module 0, parsed first), only the items others name.
    let mut later: Option<Deferred> = None;
    let modules = load_sources::load_sources_with(
        path,
        text,
        loader,
        sources,
        diags,
        &mut |_, file, text, diags| match later {
            None => {
                let (tree, deferred) = parser::parse_resident(file, text, diags);
                later = Some(deferred);
                tree
            }
            Some(_) => parser::parse(file, text, diags),
        },
    );
    let Some(later) = later else { return };
    // 2-6 over the resident items, as in `compile_modules`.
    let defs = collect_definitions::collect_definitions(&modules, diags);
    let mut used = resolve_names::resolve_resident(&modules, &defs, diags);
    let (mut resident, mut carry) =
        check_types::check_types_resident(&modules, &defs, schema, diags);
    resident.design = check_anchors::check_anchors(&modules, diags);
    check_program(&resident, schema, diags);
    warn_outside_window::warn_outside_window(&resident, config.screen, diags);
    // Of that program, the rest needs only this.
    let design = resident.design;
    let scale = crate::placement::scale(design, config.screen);
    let windows = WindowSizes::of(&resident.windows, config.screen, scale);
    let used_files_modes = check_types::declared_modes(&resident.bindings);
    drop(resident);
    // The rest of the layout, a batch at a time, through the same passes.
    let file = modules[0].file;
    let text = &sources.get(file).text;
    let mut watches = WatchNames::default();
    let mut makes_a_layout = false;
    let mut component_lets: Vec<Ident> = Vec::new();
    let mut modes = Vec::new();
    for batch in later.batches(batch_bytes) {
        let items = parser::parse_later(file, text, &later, batch, diags);
        for item in &items {
            check_anchors::anchors(item, diags);
            makes_a_layout |= warn_unused::makes_a_layout(item);
            match item {
                Item::Watch(w) => watches.add(&w.name, diags),
                Item::Component(c) => component_lets.extend(c.body.iter().filter_map(|s| {
                    if let Stmt::Let(l) = s { Some(l.name.clone()) } else { None }
                })),
                _ => {}
            }
        }
        resolve_names::resolve_items(&modules, &defs, &items, &mut used, diags);
        let mut program =
            check_types::check_types_items(&modules, &defs, schema, &mut carry, &items, diags);
        program.design = design;
        check_program(&program, schema, diags);
        windows.warn_widgets_outside(&program.widgets, config.screen, scale, diags);
        modes.extend(check_types::declared_modes(&program.bindings));
    }
    // What needed every batch: modes declared anywhere (the layout's first, as in the whole
    // program's bindings), `let`s read anywhere.
    modes.extend(used_files_modes);
    carry.report_unknown_modes(&modes, diags);
    for (m, module) in modules.iter().enumerate() {
        if warn_unused::has_syntax_errors(module.file, diags) {
            continue;
        }
        let items = &module.ast.items;
        let layout = items.iter().any(warn_unused::makes_a_layout) || (m == 0 && makes_a_layout);
        warn_unused::warn_unused_items(items, !layout, &used, diags);
        if m == 0 {
            component_lets.iter().for_each(|l| warn_unused::report(l, &used, diags));
        }
    }
}
