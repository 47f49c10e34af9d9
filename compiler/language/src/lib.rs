//! The Mocu layout language front end: text to a checked, typed program.
//!
//! The pipeline ([`compile_layout`]) is a list of passes in `passes/`, each reporting into a
//! [`Diagnostics`] sink and never stopping the others. The core does no I/O: files come through
//! a [`SourceLoader`]; [`FsLoader`] (in `fs`) is the file-system edge used by the CLI.
//!
//! Entry points:
//! - [`check_path`]: a `.mocu` layout, a profile `.toml` or a schema `.toml` → diagnostics and,
//!   for layouts and profiles, a [`Bundle`].
//! - [`load_target`]: what `mocu run` calls: a layout, profile or built bundle → a [`Bundle`]
//!   or the rendered diagnostics.
//! - [`bundle::write`] / [`bundle::read`].
#![forbid(unsafe_code)]

// The code pest_derive generates without its `std` feature names `::alloc`.
extern crate alloc;

pub mod ast;
pub mod builtins;
pub mod bundle;
pub mod codes;
pub mod diagnostics;
pub mod docgen;
pub mod format;
pub mod fs;
pub mod incremental;
pub mod lexer;
pub mod lint;
pub mod modules;
pub mod parser;
pub mod passes;
pub mod placement;
pub mod profile;
pub mod program;
pub mod project;
pub mod render;
pub mod schema;
pub mod script_text;
pub mod source;
pub mod syntax_hints;
pub mod types;

pub use bundle::{Bundle, BundleError, Layout};

/// Stack for a thread that checks, compiles or loads a layout: expressions up to
/// `passes::check_depth::MAX_DEPTH` levels recurse in the passes and the lowering, which
/// overflows a default 2 MiB thread stack (the main thread has 8 MiB). Spawn such threads
/// with `std::thread::Builder::new().stack_size(COMPILER_STACK)`.
pub const COMPILER_STACK: usize = 64 << 20;
pub use diagnostics::{Diagnostic, Diagnostics, Severity};
pub use fs::FsLoader;
pub use profile::Profile;
pub use program::Program;
pub use schema::Schema;
pub use source::{FileId, MemoryLoader, SourceLoader, SourceMap, Span};

use passes::*;

/// Settings of one check.
#[derive(Clone, Debug)]
pub struct Config {
    /// Screen size in px, to place windows given in % (for W0002).
    pub screen: (f64, f64),
}

impl Default for Config {
    fn default() -> Config {
        Config { screen: (1920.0, 1080.0) }
    }
}

/// Checks one layout file (already read) and everything it uses, and lowers it to a
/// [`Program`]. The program is returned even when there are errors (broken parts are left
/// out); look at `diags.has_errors()` before running it.
pub fn compile_layout(
    path: &str,
    text: String,
    loader: &dyn SourceLoader,
    schema: &Schema,
    config: &Config,
    sources: &mut SourceMap,
    diags: &mut Diagnostics,
) -> Program {
    // 1. Parse the file and everything it uses: later passes need all trees.
    let modules = load_sources::load_sources(path, text, loader, sources, diags);
    let mut program = compile_modules(&modules, schema, config, diags);
    locate_scripts(&mut program, sources);
    program
}

/// Script bodies learn where they are in their files, for the runtime's errors (the passes
/// see spans only).
pub fn locate_scripts(program: &mut Program, sources: &SourceMap) {
    for a in program.actions_mut() {
        if let program::Action::Script { span, origin, .. } = a {
            let f = sources.get(span.file);
            let lc = f.line_col(span.start as usize);
            *origin = Some(program::ScriptOrigin {
                file: f.path.clone(),
                line: lc.line as u32,
                col: lc.column as u32,
            });
        }
    }
}

/// The passes of [`compile_layout`] after parsing, over files already parsed (module 0 is the
/// layout): what [`incremental::ItemCache`] calls with the trees it reused.
pub fn compile_modules(
    modules: &Modules,
    schema: &Schema,
    config: &Config,
    diags: &mut Diagnostics,
) -> Program {
    // 2. Collect top-level names (and duplicates) before resolving any use of them.
    let defs = collect_definitions::collect_definitions(modules, diags);
    // 3. Resolve every name; unresolved names are reported here once, so the type pass
    //    can treat them as `{error}` silently.
    let used = resolve_names::resolve_names(modules, &defs, diags);
    // 4. Type and lower to the program; needs resolution and the schema's path types.
    let mut program = check_types::check_types(modules, &defs, schema, diags);
    program.design = check_anchors::check_anchors(modules, diags);
    // 5. Schema rules need complete, typed paths (after lets are inlined); warnings last:
    //    they only make sense on a program that resolved and typed.
    check_program(&program, schema, diags);
    warn_unused::warn_unused(modules, &used, diags);
    warn_outside_window::warn_outside_window(&program, config.screen, diags);
    program
}

/// Loads and checks a schema file; problems are reported as E0405.
pub fn load_schema(
    path: &str,
    loader: &dyn SourceLoader,
    sources: &mut SourceMap,
    diags: &mut Diagnostics,
    at: Option<Span>,
) -> Option<Schema> {
    let text = match loader.read(path) {
        Ok(t) => t,
        Err(e) => {
            if let Some(span) = at {
                diags.error(
                    codes::FILE_NOT_FOUND,
                    span,
                    format!("cannot read schema `{path}`: {e}"),
                );
            }
            return None;
        }
    };
    let file = sources.find(path).unwrap_or_else(|| sources.add(path.to_string(), text.clone()));
    Schema::parse(file, &text, diags)
}

/// Checks a profile: its schemas and module settings, then each layout against them.
/// Returns the bundle.
pub fn check_profile(
    path: &str,
    text: String,
    loader: &dyn SourceLoader,
    sources: &mut SourceMap,
    diags: &mut Diagnostics,
) -> Bundle {
    let mut layouts = Vec::new();
    let project =
        with_profile_layouts(path, text, loader, sources, diags, &mut |l, p, t, pr, s, d| {
            let program = compile_layout(p, t, loader, &pr.schema, &pr.config, s, d);
            layouts.push(Layout { path: l.to_string(), program });
        });
    let Some(parsed) = &project.file else { return Bundle::default() };
    Bundle {
        profile: Some(parsed.to_profile()),
        schema: project.schema.for_bundle(),
        layouts,
        files: Default::default(),
    }
}

/// What `mocu check` runs on a profile: the diagnostics of [`check_profile`], each layout
/// checked by [`lint::lint_layout`] (no program built).
pub fn lint_profile(
    path: &str,
    text: String,
    loader: &dyn SourceLoader,
    sources: &mut SourceMap,
    diags: &mut Diagnostics,
) {
    with_profile_layouts(path, text, loader, sources, diags, &mut |_, p, t, pr, s, d| {
        lint::lint_layout(p, t, loader, &pr.schema, &pr.config, s, d);
    });
}

/// A layout of a profile: as the profile names it, its resolved path, its text, the project.
type ProfileLayout<'a> =
    dyn FnMut(&str, &str, String, &project::Project, &mut SourceMap, &mut Diagnostics) + 'a;

/// Loads and checks a profile (its schemas and module settings), then hands each layout it
/// names to `each`; a layout that cannot be found or read is reported. Returns the project.
fn with_profile_layouts(
    path: &str,
    text: String,
    loader: &dyn SourceLoader,
    sources: &mut SourceMap,
    diags: &mut Diagnostics,
    each: &mut ProfileLayout<'_>,
) -> project::Project {
    let project = project::load(path, &text, loader, sources, diags);
    let Some(parsed) = &project.file else { return project };
    let file = sources.find(path).unwrap_or_else(|| sources.add(path.to_string(), text.clone()));
    let span_of = |needle: &str| {
        let at = text.find(&format!("\"{needle}\"")).unwrap_or(0);
        Span::new(file, at, at + needle.len() + 2)
    };
    for l in &parsed.profile.layouts {
        let Some(p) = loader.resolve(path, l) else {
            diags
                .error(codes::FILE_NOT_FOUND, span_of(l), format!("cannot find the layout `{l}`"))
                .help("paths in a profile are relative to the profile");
            continue;
        };
        match loader.read(&p) {
            Ok(t) => each(l, &p, t, &project, sources, diags),
            Err(e) => {
                diags.error(
                    codes::FILE_NOT_FOUND,
                    span_of(l),
                    format!("cannot read the layout `{l}`: {e}"),
                );
            }
        }
    }
    project
}

/// Checks one layout against a project (its schemas and settings), or against none.
pub fn check_layout(
    path: &str,
    text: String,
    loader: &dyn SourceLoader,
    project: Option<&project::Project>,
    sources: &mut SourceMap,
    diags: &mut Diagnostics,
) -> Bundle {
    let default = project::Project::default();
    let p = project.unwrap_or(&default);
    let program = compile_layout(path, text, loader, &p.schema, &p.config, sources, diags);
    Bundle {
        profile: None,
        schema: p.schema.for_bundle(),
        layouts: vec![Layout { path: path.to_string(), program }],
        files: Default::default(),
    }
}

/// What `mocu check` runs on one layout: the diagnostics of [`check_layout`], without
/// building the program, holding one batch of the layout's items at a time
/// ([`lint::lint_layout`]).
pub fn lint_in_project(
    path: &str,
    text: String,
    loader: &dyn SourceLoader,
    project: Option<&project::Project>,
    sources: &mut SourceMap,
    diags: &mut Diagnostics,
) {
    let default = project::Project::default();
    let p = project.unwrap_or(&default);
    lint::lint_layout(path, text, loader, &p.schema, &p.config, sources, diags);
}

/// [`check_path`]'s diagnostics, layouts checked by [`lint::lint_layout`] (what `mocu check
/// FILE` does).
pub fn lint_path(
    path: &str,
    text: String,
    loader: &dyn SourceLoader,
    sources: &mut SourceMap,
    diags: &mut Diagnostics,
) {
    match file_kind(path, &text) {
        FileKind::Layout => {
            let project = project_of(path, None, loader, sources, diags);
            lint_in_project(path, text, loader, project.as_ref(), sources, diags);
        }
        FileKind::Profile => lint_profile(path, text, loader, sources, diags),
        FileKind::Schema | FileKind::OtherToml => {
            check_path(path, text, loader, sources, diags);
        }
    }
}

/// The project a layout is checked in: the profile at `profile` when given, else the
/// nearest `project.toml` above the layout ([`project::discover`]); `None` when there is none.
/// Problems of the profile itself are reported.
pub fn project_of(
    layout: &str,
    profile: Option<&str>,
    loader: &dyn SourceLoader,
    sources: &mut SourceMap,
    diags: &mut Diagnostics,
) -> Option<project::Project> {
    let path = match profile {
        Some(p) => p.to_string(),
        None => project::discover(layout, loader)?,
    };
    match loader.read(&path) {
        Ok(text) => Some(project::load(&path, &text, loader, sources, diags)),
        Err(_) => None,
    }
}

/// What kind of file a path holds, judged by its extension and, for `.toml`, its shape.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FileKind {
    Layout,
    Profile,
    Schema,
    /// A `.toml` that is neither (e.g. Cargo.toml in a checked folder): skipped.
    OtherToml,
}

pub fn file_kind(path: &str, text: &str) -> FileKind {
    if !path.ends_with(".toml") {
        FileKind::Layout
    } else if profile::looks_like_profile(text) {
        FileKind::Profile
    } else if profile::looks_like_schema(text) || text.trim().is_empty() {
        FileKind::Schema
    } else if toml::from_str::<toml::Table>(text).is_err() || text.contains("[profile]") {
        // Broken TOML: checked as a profile so the error is reported.
        FileKind::Profile
    } else {
        FileKind::OtherToml
    }
}

/// Checks one file of any kind (text already read). Layouts and profiles give a bundle; a
/// layout is checked in the project of the nearest `project.toml` above it, if any.
pub fn check_path(
    path: &str,
    text: String,
    loader: &dyn SourceLoader,
    sources: &mut SourceMap,
    diags: &mut Diagnostics,
) -> Option<Bundle> {
    match file_kind(path, &text) {
        FileKind::Layout => {
            let project = project_of(path, None, loader, sources, diags);
            Some(check_layout(path, text, loader, project.as_ref(), sources, diags))
        }
        FileKind::Profile => Some(check_profile(path, text, loader, sources, diags)),
        FileKind::Schema => {
            let file =
                sources.find(path).unwrap_or_else(|| sources.add(path.to_string(), text.clone()));
            Schema::parse(file, &text, diags);
            None
        }
        FileKind::OtherToml => None,
    }
}

/// Why [`load_target`] gave no bundle.
#[derive(Debug)]
pub enum LoadError {
    Io(String),
    Bundle(BundleError),
    /// The sources have errors; `rendered` is the human report.
    Diagnostics {
        rendered: String,
        errors: usize,
    },
}

impl std::fmt::Display for LoadError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            LoadError::Io(e) => f.write_str(e),
            LoadError::Bundle(e) => write!(f, "{e}"),
            LoadError::Diagnostics { rendered, .. } => f.write_str(rendered),
        }
    }
}

/// What `mocu run TARGET` loads: a built bundle (by its header), a profile `.toml` or a
/// layout. Sources are checked; errors refuse the load, warnings are returned rendered.
pub fn load_target(path: &std::path::Path) -> Result<(Bundle, String), LoadError> {
    let bytes = fs::read_bytes(path)
        .map_err(|e| LoadError::Io(format!("cannot read {}: {e}", path.display())))?;
    if bundle::is_bundle(&bytes) {
        return bundle::read(&bytes).map(|b| (b, String::new())).map_err(LoadError::Bundle);
    }
    let text = String::from_utf8(bytes)
        .map_err(|_| LoadError::Io(format!("{} is not UTF-8 text", path.display())))?;
    let p = path.to_string_lossy().replace('\\', "/");
    let mut sources = SourceMap::new();
    let mut diags = Diagnostics::new();
    let bundle = check_path(&p, text, &FsLoader, &mut sources, &mut diags);
    diags.sort();
    let errors = diags.count(Severity::Error);
    let list = diags.into_vec();
    let rendered = render::human(&sources, &list);
    match bundle {
        Some(b) if errors == 0 => Ok((b, rendered)),
        Some(_) => Err(LoadError::Diagnostics { rendered, errors }),
        None => {
            Err(LoadError::Io(format!("{} is a schema, not a layout or profile", path.display())))
        }
    }
}
