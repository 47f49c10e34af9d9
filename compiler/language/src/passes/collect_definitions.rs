//! Pass 2: the top-level names of every module (lets, components, windows, including the
//! windows of `for each` templates). Reports duplicates (E0203). Runs before name resolution,
//! which looks names up in these tables.

use super::{DefId, Definitions, Modules};
use crate::ast::{Ident, Item};
use crate::codes;
use crate::diagnostics::Diagnostics;
use std::collections::HashMap;

pub fn collect_definitions(modules: &Modules, diags: &mut Diagnostics) -> Definitions {
    let mut defs = Definitions::default();
    for (m, module) in modules.iter().enumerate() {
        let mut lets = HashMap::new();
        let mut components = HashMap::new();
        let mut windows = HashMap::new();
        let mut spans: HashMap<(u8, String), crate::source::Span> = HashMap::new();
        let mut add = |kind: u8,
                       table: &mut HashMap<String, DefId>,
                       name: &Ident,
                       id: DefId,
                       what: &str,
                       diags: &mut Diagnostics| {
            if name.name.is_empty() {
                return;
            }
            if let Some(first) = spans.get(&(kind, name.name.clone())) {
                diags
                    .error(
                        codes::DUPLICATE,
                        name.span,
                        format!("the {what} `{}` is defined twice", name.name),
                    )
                    .label("second definition")
                    .related(*first, "first defined here")
                    .help("rename one of them; the first definition is used");
                return;
            }
            spans.insert((kind, name.name.clone()), name.span);
            table.insert(name.name.clone(), id);
        };
        for (i, item) in module.ast.items.iter().enumerate() {
            let id = DefId { module: m, item: i, inner: None };
            match item {
                Item::Let(l) => add(0, &mut lets, &l.name, id, "name", diags),
                Item::Component(c) => add(1, &mut components, &c.name, id, "component", diags),
                Item::Window(w) => add(2, &mut windows, &w.name, id, "window", diags),
                Item::Watch(w) => add(3, &mut HashMap::new(), &w.name, id, "watch", diags),
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
