//! `mocu build PROFILE.toml -o BUNDLE`: check a project and write one versioned, checksummed
//! bundle that `mocu run BUNDLE` loads without the sources. Exit 0: written; 1: the project
//! has errors (nothing written); 2: usage or I/O error.

use mocu_language::{FsLoader, Severity, SourceMap, render};
use std::process::ExitCode;

#[derive(clap::Args)]
pub struct BuildArgs {
    /// The project profile (.toml); a lone layout (.mocu) also works.
    pub profile: std::path::PathBuf,
    /// Where to write the bundle.
    #[arg(short = 'o', long = "output")]
    pub output: std::path::PathBuf,
}

pub fn main(args: BuildArgs) -> ExitCode {
    let path = args.profile.to_string_lossy().replace('\\', "/");
    let text = match std::fs::read_to_string(&args.profile) {
        Ok(t) => t,
        Err(e) => {
            eprintln!("error: cannot read `{path}`: {e}");
            return ExitCode::from(2);
        }
    };
    let mut sources = SourceMap::new();
    let mut diags = mocu_language::Diagnostics::new();
    let bundle = mocu_language::check_path(&path, text, &FsLoader, &mut sources, &mut diags);
    diags.sort();
    let errors = diags.count(Severity::Error);
    let list = diags.into_vec();
    if !list.is_empty() {
        eprint!("{}", render::human(&sources, &list));
    }
    if errors > 0 {
        eprintln!("error: `{path}` has errors; no bundle written");
        return ExitCode::from(1);
    }
    let Some(mut bundle) = bundle else {
        eprintln!(
            "error: `{path}` is a schema; build a profile (.toml with [profile]) or a layout"
        );
        return ExitCode::from(2);
    };
    // The files its modules name (scripts, map overlays) go in with it.
    if let Err(e) = crate::bundle_files::collect(&args.profile, &mut bundle) {
        eprintln!("error: {e}; no bundle written");
        return ExitCode::from(2);
    }
    let bytes = mocu_language::bundle::write(&bundle);
    if let Err(e) = std::fs::write(&args.output, &bytes) {
        eprintln!("error: cannot write `{}`: {e}", args.output.display());
        return ExitCode::from(2);
    }
    eprintln!(
        "wrote {} ({} layout(s), {} bytes)",
        args.output.display(),
        bundle.layouts.len(),
        bytes.len()
    );
    ExitCode::SUCCESS
}
