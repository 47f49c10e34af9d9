//! `mocu check` (owned by the language front end work).
use std::process::ExitCode;

#[derive(clap::Args)]
pub struct CheckArgs {
    /// Files or folders to check.
    pub paths: Vec<std::path::PathBuf>,
}

pub fn main(_args: CheckArgs) -> ExitCode {
    eprintln!("mocu check: not built yet");
    ExitCode::from(2)
}
