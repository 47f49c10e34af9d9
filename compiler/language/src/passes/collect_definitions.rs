//! Pass 2: the top-level names of every module (lets, components, windows, including the
//! windows of `for each` templates). Reports duplicates (E0203). Runs before name resolution,
//! which looks names up in these tables.

use super::{DefId, Definitions, FastMap, Modules};
use crate::ast::{Ident, Item};
use crate::codes;
use crate::diagnostics::Diagnostics;
use crate::source::Span;

pub fn collect_definitions<'a>(modules: &'a Modules, diags: &mut Diagnostics) -> Definitions {
    let mut defs = Definitions::default();
    for (m, module) in modules.iter().enumerate() {
        let mut lets = FastMap::default();
        let mut components = FastMap::default();
        let mut windows = FastMap::default();
        // Per kind (let, component, window, watch): where each name was first defined.
        let mut spans: [FastMap<&str, Span>; 4] = Default::default();
        let mut add = |kind: usize,
                       table: &mut FastMap<String, DefId>,
                       name: &'a Ident,
                       id: DefId,
                       what: &str,
                       diags: &mut Diagnostics| {
            add_name(&mut spans[kind], table, name, id, what, diags)
        };
        for (i, item) in module.ast.items.iter().enumerate() {
            let id = DefId { module: m, item: i, inner: None };
            match item {
                Item::Let(l) => add(0, &mut lets, &l.name, id, "name", diags),
                Item::Component(c) => add(1, &mut components, &c.name, id, "component", diags),
                Item::Window(w) => add(2, &mut windows, &w.name, id, "window", diags),
                Item::Watch(w) => add(3, &mut FastMap::default(), &w.name, id, "watch", diags),
                Item::Each(e) => {
                    for (j, inner) in e.items.iter().enumerate() {
                        if let Item::Window(w) = inner {
                            add(
                                2,
                                &mut windows,
                                &w.name,
                                DefId { module: m, item: i, inner: Some(j) },
                                "window",
                                diags,
                            );
                        }
                    }
                }
                _ => {}
            }
        }
        defs.lets.push(lets);
        defs.components.push(components);
        defs.windows.push(windows);
    }
    defs
}

/// Adds a top-level name to its table, or reports it as defined twice (`spans`: where each
/// name of its kind was first defined).
fn add_name<'a>(
    spans: &mut FastMap<&'a str, Span>,
    table: &mut FastMap<String, DefId>,
    name: &'a Ident,
    id: DefId,
    what: &str,
    diags: &mut Diagnostics,
) {
    if name.name.is_empty() {
        return;
    }
    if let Some(first) = spans.get(name.name.as_str()) {
        report_duplicate(name, *first, what, diags);
        return;
    }
    spans.insert(&name.name, name.span);
    table.insert(name.name.clone(), id);
}

fn report_duplicate(name: &Ident, first: Span, what: &str, diags: &mut Diagnostics) {
    diags
        .error(codes::DUPLICATE, name.span, format!("the {what} `{}` is defined twice", name.name))
        .label("second definition")
        .related(first, "first defined here")
        .help("rename one of them; the first definition is used");
}

/// The layout's watch names so far, for a check that reads its watches in batches
/// (`crate::lint`): [`collect_definitions`] sees no watch of the layout there.
#[derive(Default)]
pub struct WatchNames(FastMap<String, Span>);

impl WatchNames {
    /// Adds a watch's name, or reports it as defined twice.
    pub fn add(&mut self, name: &Ident, diags: &mut Diagnostics) {
        if name.name.is_empty() {
            return;
        }
        match self.0.get(name.name.as_str()) {
            Some(first) => report_duplicate(name, *first, "watch", diags),
            None => {
                self.0.insert(name.name.clone(), name.span);
            }
        }
    }
}
