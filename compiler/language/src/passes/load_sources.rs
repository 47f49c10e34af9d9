//! Pass 1: parse the layout and, depth first, every file it `use`s. Reports syntax errors
//! (from the parser), missing files (E0201) and `use` cycles (E0202). Runs first because
//! every later pass needs the trees of all files.

use super::{Module, Modules, UseEdge};
use crate::ast::{File, Item};
use crate::codes;
use crate::diagnostics::Diagnostics;
use crate::parser;
use crate::source::{FileId, SourceLoader, SourceMap, Span};

/// How a file's text becomes its tree: the parser, or a cache in front of it
/// (`incremental::ItemCache`). Arguments: the file's path, its id, its text.
pub type Parse<'a> = dyn FnMut(&str, FileId, &str, &mut Diagnostics) -> File + 'a;

/// Loads `path` (already resolved by the caller) and its uses. Module 0 is `path`.
/// Returns `None` when `path` itself cannot be read (the caller reports that).
pub fn load_sources(
    path: &str,
    text: String,
    loader: &dyn SourceLoader,
    sources: &mut SourceMap,
    diags: &mut Diagnostics,
) -> Modules {
    load_sources_with(path, text, loader, sources, diags, &mut |_, file, text, diags| {
        parser::parse(file, text, diags)
    })
}

/// [`load_sources`], each file parsed by `parse`.
pub fn load_sources_with(
    path: &str,
    text: String,
    loader: &dyn SourceLoader,
    sources: &mut SourceMap,
    diags: &mut Diagnostics,
    parse: &mut Parse<'_>,
) -> Modules {
    let mut modules: Modules = Vec::new();
    let mut stack: Vec<(usize, Option<Span>)> = Vec::new();
    load(path, text, loader, sources, diags, &mut modules, &mut stack, parse);
    modules
}

#[allow(clippy::too_many_arguments)]
fn load(
    path: &str,
    text: String,
    loader: &dyn SourceLoader,
    sources: &mut SourceMap,
    diags: &mut Diagnostics,
    modules: &mut Modules,
    // The files being loaded, each with the span of its `use` being followed.
    stack: &mut Vec<(usize, Option<Span>)>,
    parse: &mut Parse<'_>,
) -> usize {
    // The text is moved into the source map (not copied) and parsed from there.
    let file = match sources.find(path) {
        Some(f) => f,
        None => sources.add(path.to_string(), text),
    };
    let ast = parse(path, file, &sources.get(file).text, diags);
    let id = modules.len();
    let uses: Vec<_> = ast
        .items
        .iter()
        .filter_map(|i| if let Item::Use(u) = i { Some(u.clone()) } else { None })
        .collect();
    modules.push(Module { file, path: path.to_string(), ast, uses: Vec::new() });
    stack.push((id, None));
    let mut edges = Vec::new();
    for u in uses {
        let Some(target) = loader.resolve(path, &u.path) else {
            diags
                .error(codes::FILE_NOT_FOUND, u.path_span, format!("cannot find `{}`", u.path))
                .label("no such file")
                .help("a `use` path is relative to this file; `stdlib/…` also searches the standard library (docs/language.md, \"Files\")");
            continue;
        };
        if let Some(pos) = stack.iter().position(|&(m, _)| modules[m].path == target) {
            if let Some(top) = stack.last_mut() {
                top.1 = Some(u.span);
            }
            report_cycle(&stack[pos..], modules, diags);
            continue;
        }
        if let Some(top) = stack.last_mut() {
            top.1 = Some(u.span);
        }
        let existing = modules.iter().position(|m| m.path == target);
        let m = match existing {
            Some(m) => m,
            None => match loader.read(&target) {
                Ok(text) => load(&target, text, loader, sources, diags, modules, stack, parse),
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

/// Reports a `use` cycle (the files on the stack from its first member, each with the span of
/// its `use` of the next) once, whichever file of it is checked: at the `use` that leads into
/// the file with the smallest path, the chain starting there.
fn report_cycle(cycle: &[(usize, Option<Span>)], modules: &Modules, diags: &mut Diagnostics) {
    let Some(first) = (0..cycle.len()).min_by_key(|&k| modules[cycle[k].0].path.as_str()) else {
        return;
    };
    // The member before `first` (cyclically) holds the `use` that leads into it.
    let into = (first + cycle.len() - 1) % cycle.len();
    let Some(span) = cycle[into].1 else { return };
    let chain: Vec<&str> = (0..=cycle.len())
        .map(|k| modules[cycle[(first + k) % cycle.len()].0].path.as_str())
        .collect();
    diags
        .error(codes::USE_CYCLE, span, format!("`use` cycle: {}", chain.join(" → ")))
        .help("move the shared definitions into a third file that both use");
}
