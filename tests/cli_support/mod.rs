//! What the `mocu check`/`mocu build` end-to-end tests share: running the built binary from
//! the repository root, and a fresh scratch folder per test.
#![allow(dead_code)]

use std::path::PathBuf;
use std::process::{Command, Output};

/// Runs the built `mocu` with `args` in the repository root and waits for it.
pub fn mocu(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_mocu"))
        .args(args)
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output()
        .expect("mocu runs")
}

/// An empty folder of its own for one test of one suite (`suite`, `name`): emptied first.
pub fn scratch_dir(suite: &str, name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("mocu-{suite}-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("temp dir");
    dir
}
