//! `mocu check [--format human|json|sarif] [--deny warnings] [--profile FILE] PATH...`: lint
//! layouts, profiles and schemas, or folders of them; each layout against its project's
//! schemas (`--profile`, else the nearest `project.toml` above it). Exit 0: no errors; 1: errors (or warnings with
//! `--deny warnings`); 2: usage or I/O error. The contract is in docs/language.md.

mod scripts;
mod settings;

use mocu_language::project::{self, Project};
use mocu_language::{FileKind, FsLoader, Severity, SourceLoader, SourceMap, render};
use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum Format {
    Human,
    Json,
    Sarif,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum Deny {
    /// Treat warnings as errors for the exit code.
    Warnings,
}

#[derive(clap::Args)]
pub struct CheckArgs {
    /// Output format.
    #[arg(long, value_enum, default_value_t = Format::Human)]
    pub format: Format,
    /// `--deny warnings`: exit 1 when there are warnings.
    #[arg(long, value_enum)]
    pub deny: Vec<Deny>,
    /// The profile whose schemas and settings layouts are checked against (default: the
    /// nearest `project.toml` above each layout).
    #[arg(long, value_name = "FILE")]
    pub profile: Option<PathBuf>,
    /// Layout files (.mocu), profiles or schemas (.toml), or folders to search recursively.
    #[arg(required = true)]
    pub paths: Vec<PathBuf>,
}

pub fn main(args: CheckArgs) -> ExitCode {
    // I/O and usage failures: printed on stderr, and in SARIF's `invocations`.
    let mut failures: Vec<String> = Vec::new();
    let mut files: Vec<String> = Vec::new();
    for p in &args.paths {
        if p.is_dir() {
            let before = files.len();
            collect(p, &mut std::collections::HashSet::new(), &mut files);
            if files.len() == before {
                failures.push(format!(
                    "no layouts (.mocu) or profiles (.toml) in the folder `{}`",
                    p.display()
                ));
            }
        } else if p.is_file() {
            files.push(slashed(p));
        } else {
            failures.push(format!("cannot read `{}`: no such file or folder", p.display()));
        }
    }
    let mut sources = SourceMap::new();
    let mut diags = mocu_language::Diagnostics::new();
    let mut texts = Vec::new();
    for f in files {
        match std::fs::read(&f) {
            // Bytes in: a file that is not UTF-8 is a located finding (E0107), not an I/O error.
            Ok(bytes) => {
                if let Some(t) = mocu_language::lexer::decode(&f, bytes, &mut sources, &mut diags) {
                    texts.push((f, t));
                }
            }
            Err(e) => failures.push(format!("cannot read `{f}`: {e}")),
        }
    }
    for f in &failures {
        eprintln!("error: {f}");
    }
    let io_error = !failures.is_empty();
    // Layouts named by a profile in this run are checked through it (with its schemas) only.
    let mut covered = std::collections::HashSet::new();
    for (path, text) in &texts {
        if mocu_language::file_kind(path, text) == FileKind::Profile
            && let Ok(p) = toml::from_str::<mocu_language::profile::ProfileFile>(text)
        {
            covered.extend(p.profile.layouts.iter().filter_map(|l| FsLoader.resolve(path, l)));
        }
    }
    let explicit = args.profile.as_deref().map(slashed);
    if let Some(p) = &explicit
        && !Path::new(p).is_file()
    {
        eprintln!("error: cannot read the profile `{p}`: no such file");
        return ExitCode::from(2);
    }
    // Each layout is checked in its project (loaded once): --profile, else the nearest
    // project.toml above it. Those with none are named once at the end.
    let mut projects: HashMap<String, Option<Project>> = HashMap::new();
    let mut unchecked: Vec<String> = Vec::new();
    for (path, text) in texts {
        if path.ends_with(".mocu") && covered.contains(&path) {
            continue;
        }
        let kind = mocu_language::file_kind(&path, &text);
        if kind != FileKind::Layout {
            if kind == FileKind::Profile {
                scripts::check(&path, &text, &mut sources, &mut diags);
            }
            let errors = diags.count(Severity::Error);
            mocu_language::lint_path(&path, text.clone(), &FsLoader, &mut sources, &mut diags);
            // The modules' own rules, once the profile's shape and types hold (no error twice).
            if kind == FileKind::Profile && diags.count(Severity::Error) == errors {
                settings::check(&path, &text, &mut sources, &mut diags);
            }
            continue;
        }
        let profile = explicit.clone().or_else(|| project::discover(&path, &FsLoader));
        let project = match profile {
            Some(p) => projects
                .entry(p.clone())
                .or_insert_with(|| {
                    mocu_language::project_of(&path, Some(&p), &FsLoader, &mut sources, &mut diags)
                })
                .clone(),
            None => None,
        };
        if project.is_none() {
            unchecked.push(path.clone());
        }
        mocu_language::lint_in_project(
            &path,
            text,
            &FsLoader,
            project.as_ref(),
            &mut sources,
            &mut diags,
        );
    }
    if let Some(first) = unchecked.first() {
        let others = match unchecked.len() {
            1 => String::new(),
            n => format!(" and {} other layout(s)", n - 1),
        };
        eprintln!(
            "note: no project.toml above {first}{others}: property names were not checked against a schema (pass --profile FILE, or add a project.toml; docs/language.md, \"Profiles\")"
        );
    }
    diags.sort();
    let errors = diags.count(Severity::Error);
    let warnings = diags.count(Severity::Warning);
    let list = diags.into_vec();
    let deny_warnings = args.deny.contains(&Deny::Warnings);
    let out = match args.format {
        Format::Human => {
            let options = render::HumanOptions { colour: colour_wanted(), deny_warnings };
            render::human_with(&sources, &list, options)
        }
        Format::Json => render::json(&sources, &list),
        Format::Sarif => {
            let base = std::env::current_dir().ok().map(|d| slashed(&d));
            render::sarif_with(&sources, &list, &render::SarifOptions { base, failures })
        }
    };
    if !out.is_empty() {
        use std::io::Write;
        // A closed pipe (`mocu check … | head`) is not an error of the check.
        let _ = writeln!(std::io::stdout().lock(), "{}", out.trim_end());
    }
    if io_error {
        ExitCode::from(2)
    } else if errors > 0 || (warnings > 0 && deny_warnings) {
        ExitCode::from(1)
    } else {
        ExitCode::SUCCESS
    }
}

pub(crate) fn slashed(p: &Path) -> String {
    let s = p.to_string_lossy().replace('\\', "/");
    s.strip_prefix("./").map(str::to_string).unwrap_or(s)
}

/// Colour on a terminal only, and never when `NO_COLOR` is set (no-color.org) or the terminal
/// is dumb.
fn colour_wanted() -> bool {
    use std::io::IsTerminal;
    std::io::stdout().is_terminal()
        && std::env::var_os("NO_COLOR").is_none_or(|v| v.is_empty())
        && std::env::var("TERM").map_or(true, |t| t != "dumb")
}

/// Every `.mocu` and `.toml` under `dir`, sorted; hidden folders and build outputs skipped.
/// A folder already walked (through a symbolic link, or a link loop) is not walked again.
pub(crate) fn collect(
    dir: &Path,
    seen: &mut std::collections::HashSet<PathBuf>,
    out: &mut Vec<String>,
) {
    let Ok(real) = std::fs::canonicalize(dir) else { return };
    if !seen.insert(real) {
        return;
    }
    let Ok(rd) = std::fs::read_dir(dir) else { return };
    let mut entries: Vec<PathBuf> = rd.filter_map(|e| e.ok().map(|e| e.path())).collect();
    entries.sort();
    for p in entries {
        let name = p.file_name().map(|n| n.to_string_lossy().to_string()).unwrap_or_default();
        if p.is_dir() {
            if !name.starts_with('.') && !name.starts_with("target") {
                collect(&p, seen, out);
            }
        } else if name.ends_with(".mocu") || name.ends_with(".toml") {
            out.push(slashed(&p));
        }
    }
}
