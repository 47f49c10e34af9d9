//! `mocu lsp`: the Language Server Protocol server for layouts, on stdin and stdout (the
//! `mocu-lsp` crate). Editors start it; docs/editors.md says how. Exit 0 when the client
//! ends the session (`shutdown`, `exit`); 2 on a protocol or I/O failure.

use std::process::ExitCode;

#[derive(clap::Args)]
pub struct LspArgs {
    /// Accepted for editors that pass it (VS Code's client does); stdio is the only transport.
    #[arg(long)]
    pub stdio: bool,
}

pub fn main(_args: LspArgs) -> ExitCode {
    match mocu_lsp::run_stdio() {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: mocu lsp: {e}");
            ExitCode::from(2)
        }
    }
}
