//! `mocu fmt [--check] PATH...`: put layout files in the canonical layout
//! (docs/formatting.md). Without `--check` each file that changes is rewritten (a temporary
//! file renamed over it) and named on stdout; with `--check` nothing is written and each such
//! file's change is printed as a unified diff. Exit 0: every file is formatted (or was
//! rewritten); 1: `--check` found a file to change, or a file has syntax errors (it is left as
//! it is; its diagnostics go to stderr); 2: usage or I/O error. The contract is in
//! docs/language.md.

use mocu_language::format::{self, FormatError};
use mocu_language::{Diagnostics, SourceMap, render};
use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

#[derive(clap::Args)]
pub struct FmtArgs {
    /// Write nothing: print a diff for each file that is not formatted, and exit 1 if any is.
    #[arg(long)]
    pub check: bool,
    /// Layout files (.mocu), or folders to search recursively.
    #[arg(required = true)]
    pub paths: Vec<PathBuf>,
}

pub fn main(args: FmtArgs) -> ExitCode {
    let mut io_errors: Vec<String> = Vec::new();
    let mut files: Vec<String> = Vec::new();
    for p in &args.paths {
        if p.is_dir() {
            let mut found = Vec::new();
            crate::check::collect(p, &mut std::collections::HashSet::new(), &mut found);
            found.retain(|f| f.ends_with(".mocu"));
            if found.is_empty() {
                io_errors.push(format!("no layouts (.mocu) in the folder `{}`", p.display()));
            }
            files.extend(found);
        } else if p.is_file() {
            files.push(crate::check::slashed(p));
        } else {
            io_errors.push(format!("cannot read `{}`: no such file or folder", p.display()));
        }
    }
    let mut sources = SourceMap::new();
    let mut diags = Diagnostics::new();
    let mut unformatted = 0usize;
    let mut refused = 0usize;
    let stdout = std::io::stdout();
    let mut out = stdout.lock();
    for path in &files {
        let bytes = match std::fs::read(path) {
            Ok(b) => b,
            Err(e) => {
                io_errors.push(format!("cannot read `{path}`: {e}"));
                continue;
            }
        };
        let Some(text) = mocu_language::lexer::decode(path, bytes, &mut sources, &mut diags) else {
            refused += 1;
            continue;
        };
        let file = sources.add(path.clone(), text.clone());
        let formatted = match format::format_source(file, &text, &mut diags) {
            Ok(f) => f,
            Err(FormatError::Syntax) => {
                refused += 1;
                continue;
            }
            Err(e) => {
                eprintln!("error: {path}: {e}");
                refused += 1;
                continue;
            }
        };
        if formatted == text {
            continue;
        }
        unformatted += 1;
        // A closed pipe (`mocu fmt --check … | head`) is not an error of the run.
        if args.check {
            let _ = write!(out, "{}", format::diff::unified(&text, &formatted, path, path));
        } else {
            match write_atomically(Path::new(path), &formatted) {
                Ok(()) => {
                    let _ = writeln!(out, "formatted {path}");
                }
                Err(e) => io_errors.push(format!("cannot write `{path}`: {e}")),
            }
        }
    }
    drop(out);
    if !diags.is_empty() {
        diags.sort();
        let list = diags.into_vec();
        eprintln!("{}", render::human(&sources, &list).trim_end());
    }
    for e in &io_errors {
        eprintln!("error: {e}");
    }
    if refused > 0 {
        eprintln!("error: {refused} file(s) not formatted: fix their syntax errors first");
    }
    if args.check && unformatted > 0 {
        eprintln!(
            "error: {unformatted} of {} file(s) not formatted (run `mocu fmt` on them)",
            files.len()
        );
    }
    if !io_errors.is_empty() {
        ExitCode::from(2)
    } else if refused > 0 || (args.check && unformatted > 0) {
        ExitCode::from(1)
    } else {
        ExitCode::SUCCESS
    }
}

/// Replaces `path` with `text` in one step: a temporary file beside it (with its
/// permissions), then renamed over it, so a reader sees the old file or the new, never half.
fn write_atomically(path: &Path, text: &str) -> std::io::Result<()> {
    let name = path.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
    let tmp = path.with_file_name(format!(".{name}.mocu-fmt-{}", std::process::id()));
    let result = (|| {
        let mut f = std::fs::File::create(&tmp)?;
        f.write_all(text.as_bytes())?;
        f.sync_all()?;
        if let Ok(meta) = std::fs::metadata(path) {
            std::fs::set_permissions(&tmp, meta.permissions())?;
        }
        std::fs::rename(&tmp, path)
    })();
    if result.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    result
}
