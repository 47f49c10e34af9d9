//! A bundle runs without the sources: `mocu build` carries the text files the profile's
//! modules name (a script module's `file`, the map's `overlays`), and `mocu run BUNDLE`,
//! from any folder, hands them to the modules.

mod cli_support;

use cli_support::scratch_dir;
use std::process::{Command, Output};

/// `mocu ARGS` run from `dir` (not the repository: the sources are out of reach).
fn mocu_in(dir: &std::path::Path, args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_mocu")).args(args).current_dir(dir).output().expect("runs")
}

fn build(profile: &str, name: &str) -> (std::path::PathBuf, std::path::PathBuf) {
    let dir = scratch_dir("bundle-files", name);
    let bundle = dir.join("project.bundle");
    let repo = env!("CARGO_MANIFEST_DIR");
    let out = mocu_in(
        std::path::Path::new(repo),
        &["build", profile, "-o", &bundle.display().to_string()],
    );
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    (dir, bundle)
}

fn dump(dir: &std::path::Path, bundle: &std::path::Path, what: &str, extra: &[&str]) -> String {
    let b = bundle.display().to_string();
    let mut args = vec!["run", &b, "--headless", "--frames", "90", "--mavlink", "off"];
    args.extend(["--video", "off", "--no-watch", "--dump", what]);
    args.extend(extra);
    let out = mocu_in(dir, &args);
    let stderr = String::from_utf8_lossy(&out.stderr).to_string();
    assert!(out.status.success(), "{stderr}");
    assert!(!stderr.contains("failed to start") && !stderr.contains("error"), "{stderr}");
    String::from_utf8_lossy(&out.stdout).to_string()
}

#[test]
fn a_bundle_carries_its_script_modules_file_and_runs_it_from_any_folder() {
    let (dir, bundle) = build("examples/scripts/project.toml", "scripts");
    let script =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/scripts/note.script");
    let s = script.display().to_string();
    let operator = dump(&dir, &bundle, "root.operator", &["--input-script", &s]);
    assert!(operator.contains("\"note\": \"fastest: usv"), "{operator}");
}

#[test]
fn a_bundle_carries_the_maps_overlays() {
    let (dir, bundle) = build("layouts/project.toml", "map");
    let map = dump(&dir, &bundle, "root.map.features", &[]);
    assert!(map.contains("\"pier"), "the harbour's piers: {map}");
}
