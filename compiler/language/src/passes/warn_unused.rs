//! Warning W0001: a `let` that nothing reads. A file without windows, widgets or bindings is a
//! library (like stdlib/theme.mocu): its top-level lets are exports and are not reported.
//! Runs after `resolve_names`, which records the uses.

use super::Modules;
use super::resolve_names::UsedLets;
use crate::ast::{Item, Stmt};
use crate::codes;
use crate::diagnostics::Diagnostics;
use crate::source::FileId;

pub fn warn_unused(modules: &Modules, used: &UsedLets, diags: &mut Diagnostics) {
    for module in modules {
        // A use may sit in the item that did not parse: no guesses after a syntax error.
        if has_syntax_errors(module.file, diags) {
            continue;
        }
        let library = !module.ast.items.iter().any(makes_a_layout);
        warn_unused_items(&module.ast.items, library, used, diags);
    }
}

/// Whether the file has a syntax error (E01…) so far.
pub fn has_syntax_errors(file: FileId, diags: &Diagnostics) -> bool {
    diags.iter().any(|d| d.span.file == file && d.code.starts_with("E01"))
}

/// Whether the item makes its file a layout rather than a library.
pub fn makes_a_layout(item: &Item) -> bool {
    matches!(item, Item::Window(_) | Item::In(_) | Item::Bind(_) | Item::Each(_) | Item::Watch(_))
}

/// W0001 for the `let`s of `items` (top-level ones unless `library`) that nothing reads.
pub fn warn_unused_items(items: &[Item], library: bool, used: &UsedLets, diags: &mut Diagnostics) {
    let mut seen = std::collections::HashSet::new();
    for item in items {
        match item {
            // A duplicate is reported as E0203 already.
            Item::Let(l) if !library && seen.insert(l.name.name.as_str()) => {
                report(&l.name, used, diags)
            }
            Item::Component(c) => {
                for s in &c.body {
                    if let Stmt::Let(l) = s {
                        report(&l.name, used, diags);
                    }
                }
            }
            Item::Each(e) => {
                for i in &e.items {
                    if let Item::Let(l) = i {
                        report(&l.name, used, diags);
                    }
                }
            }
            _ => {}
        }
    }
}

/// W0001 for one `let` name, unless something reads it or it starts with `_`.
pub fn report(name: &crate::ast::Ident, used: &UsedLets, diags: &mut Diagnostics) {
    if !used.contains(&name.span) && !name.name.starts_with('_') {
        diags
            .warning(codes::UNUSED_LET, name.span, format!("`{}` is never used", name.name))
            .label("unused")
            .help(format!("remove it, or name it `_{}` to keep it", name.name));
    }
}
