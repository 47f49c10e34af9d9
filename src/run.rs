//! `mocu run`: the OCU itself.
use std::process::ExitCode;

#[derive(clap::Args)]
pub struct RunArgs {
    pub target: Option<std::path::PathBuf>,
}

pub fn main(_args: RunArgs) -> ExitCode {
    ExitCode::SUCCESS
}
