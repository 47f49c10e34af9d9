//! Pass 1: parse the layout and, depth first, every file it `use`s. Reports syntax errors
//! (from the parser), missing files (E0201) and `use` cycles (E0202). Runs first because
//! every later pass needs the trees of all files.

use super::{Module, Modules, UseEdge};
use crate::ast::Item;
use crate::codes;
use crate::diagnostics::Diagnostics;
use crate::parser;
use crate::source::{SourceLoader, SourceMap};

/// Loads `path` (already resolved by the caller) and its uses. Module 0 is `path`.
/// Returns `None` when `path` itself cannot be read (the caller reports that).
pub fn load_sources(
    path: &str,
    text: String,
    loader: &dyn SourceLoader,
    sources: &mut SourceMap,
    diags: &mut Diagnostics,
) -> Modules {
    let mut modules: Modules = Vec::new();
    let mut stack: Vec<usize> = Vec::new();
    load(path, text, loader, sources, diags, &mut modules, &mut stack);
    modules
}

fn load(
    path: &str,
    text: String,
    loader: &dyn SourceLoader,
    sources: &mut SourceMap,
    diags: &mut Diagnostics,
    modules: &mut Modules,
    stack: &mut Vec<usize>,
) -> usize {
    let file = sources.find(path).unwrap_or_else(|| sources.add(path.to_string(), text.clone()));
    let ast = parser::parse(file, &text, diags);
    let id = modules.len();
    let uses: Vec<_> = ast
        .items
        .iter()
        .filter_map(|i| if let Item::Use(u) = i { Some(u.clone()) } else { None })
        .collect();
    modules.push(Module { file, path: path.to_string(), ast, uses: Vec::new() });
    stack.push(id);
    let mut edges = Vec::new();
    for u in uses {
        let Some(target) = loader.resolve(path, &u.path) else {
            diags
                .error(codes::FILE_NOT_FOUND, u.path_span, format!("cannot find `{}`", u.path))
                .label("no such file")
                .help("a `use` path is relative to this file; `stdlib/…` also searches the standard library (docs/language.md, \"Files\")");
            continue;
        };
        if let Some(pos) = stack.iter().position(|&m| modules[m].path == target) {
            let chain: Vec<&str> = stack[pos..]
                .iter()
                .map(|&m| modules[m].path.as_str())
                .chain([target.as_str()])
                .collect();
            diags
                .error(codes::USE_CYCLE, u.span, format!("`use` cycle: {}", chain.join(" → ")))
                .help("move the shared definitions into a third file that both use");
            continue;
        }
        let existing = modules.iter().position(|m| m.path == target);
        let m = match existing {
            Some(m) => m,
            None => match loader.read(&target) {
                Ok(text) => load(&target, text, loader, sources, diags, modules, stack),
                Err(e) => {
                    diags.error(
                        codes::FILE_NOT_FOUND,
                        u.path_span,
                        format!("cannot read `{}`: {e}", u.path),
                    );
                    continue;
                }
            },
        };
        edges.push(UseEdge { target: m, alias: u.alias.as_ref().map(|a| a.name.clone()) });
    }
    stack.pop();
    modules[id].uses = edges;
    id
}
