//! `mocu lsp`: the Language Server Protocol server for layouts, on stdin and stdout (the
//! `mocu-lsp` crate). Editors start it; docs/editors.md says how. Exit 0 when the client
//! ends the session (`shutdown`, `exit`); 2 on a protocol or I/O failure.
//!
//! Live values (completion of the objects that exist now, hover of a property's current
//! value): the server mirrors what the OCUs or adapters at `--connect` (or at the client's
//! `initializationOptions.live.connect`) share over the distributed world model
//! (`live_tree.rs`).

use crate::live_tree::{WorldMirror, endpoints_of};
use mocu_lsp::live::{LiveTree, NoLiveTree};
use std::process::ExitCode;

#[derive(clap::Args)]
pub struct LspArgs {
    /// Accepted for editors that pass it (VS Code's client does); stdio is the only transport.
    #[arg(long)]
    pub stdio: bool,
    /// Zenoh endpoint of a running OCU or adapter whose shared world model completion and
    /// hover read (repeatable); added to the client's `live.connect` initialization option.
    #[arg(long, value_name = "ENDPOINT")]
    pub connect: Vec<String>,
}

pub fn main(args: LspArgs) -> ExitCode {
    let flagged = args.connect;
    let live = move |init: Option<&serde_json::Value>| -> Box<dyn LiveTree> {
        let mut endpoints = flagged;
        endpoints.extend(endpoints_of(init));
        if endpoints.is_empty() {
            return Box::new(NoLiveTree);
        }
        match WorldMirror::connect(&endpoints) {
            Ok(m) => Box::new(m),
            Err(e) => {
                // Said on stderr (the editor's server log); the server goes on without live values.
                eprintln!("mocu lsp: no live values from {}: {e}", endpoints.join(", "));
                Box::new(NoLiveTree)
            }
        }
    };
    let options = mocu_lsp::Options { live: Box::new(live), ..mocu_lsp::Options::default() };
    match mocu_lsp::run_stdio(options) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: mocu lsp: {e}");
            ExitCode::from(2)
        }
    }
}
