//! `mocu build` (owned by the language front end work).
use std::process::ExitCode;

#[derive(clap::Args)]
pub struct BuildArgs {
    pub profile: std::path::PathBuf,
    #[arg(short = 'o')]
    pub output: std::path::PathBuf,
}

pub fn main(_args: BuildArgs) -> ExitCode {
    eprintln!("mocu build: not built yet");
    ExitCode::from(2)
}
