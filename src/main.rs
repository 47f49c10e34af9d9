//! `mocu`: the command-line OCU. The command-line contract (docs/language.md, end) is fixed:
//! commands, flags, exit codes and output formats are relied on by scripts and CI.

#![forbid(unsafe_code)]

use clap::{Parser, Subcommand};
use std::process::ExitCode;

mod build;
mod bundle_files;
mod check;
mod core_modules;
mod fmt;
mod frames;
mod golden;
mod live_tree;
mod logger;
mod lsp;
mod process_modules;
mod record;
mod registry;
mod replay;
mod run;
mod serve;
mod stop;

#[derive(Parser)]
#[command(name = "mocu", version, about = "Multi-robot Operator Control Unit")]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Lint layout files, folders or profiles.
    Check(check::CheckArgs),
    /// Compile a project profile into one validated bundle.
    Build(build::BuildArgs),
    /// Run the OCU on a layout, a profile or a bundle.
    Run(run::RunArgs),
    /// Put layout files in the canonical layout (`--check`: only show the diff).
    Fmt(fmt::FmtArgs),
    /// Serve the Language Server Protocol on stdin/stdout, for editors.
    Lsp(lsp::LspArgs),
    /// Replay a recorded trial (`mocu run --record`) through its layout or another.
    Replay(replay::ReplayArgs),
    /// The headless adapter: world model and vehicle/video modules shared over Zenoh.
    Serve(serve::ServeArgs),
}

fn main() -> ExitCode {
    logger::init();
    // Script actions in layouts are checked by the engines `mocu run` has.
    mocu_layout::install_script_checker();
    let cli = match Cli::try_parse() {
        Ok(cli) => cli,
        Err(e) => {
            let code = if e.use_stderr() { 2 } else { 0 };
            let _ = e.print();
            return ExitCode::from(code);
        }
    };
    match cli.command {
        Command::Check(args) => check::main(args),
        Command::Build(args) => build::main(args),
        Command::Run(args) => run::main(args),
        Command::Fmt(args) => fmt::main(args),
        Command::Lsp(args) => lsp::main(args),
        Command::Replay(args) => replay::main(args),
        Command::Serve(args) => serve::main(args),
    }
}
