//! `mocu check` refuses a module's settings exactly when `mocu run` could not start the
//! module: both ask the module kind's own factory (`Registry::make`). Each row is a setting
//! a CI pipeline met that checked clean and then left the OCU without its module; each is
//! written into a profile of its own and given to both commands. A module that cannot start
//! makes `mocu run` exit 1 unless the profile marks it `optional = true`.

mod cli_support;

use cli_support::{mocu, scratch_dir};
use std::path::Path;

/// (module table, settings): each one the module refuses.
const REFUSED: &[(&str, &str)] = &[
    ("sim", "rate_hz = 0"),
    ("sim", "camera_width = 5000"),
    ("sim", "origin_lat = 500"),
    ("mavlink", "address = \"not-an-address\""),
    ("video", "address = \"localhost\""),
    ("map", "origin_lat = 95"),
    ("input", "double_ms = 5"),
    ("input", "rate_hz = nan"),
    ("widgets", "accepted_ms = -1"),
    ("s", "kind = \"script\"\nfile = \"ok.js\"\nmemory_kb = 1"),
    ("p", "kind = \"process\"\ncommand = []"),
    ("p", "kind = \"process\"\ncommand = [\"pythno3\", \"x.py\"]"),
    ("distrib", "listen = [\"garbage\"]"),
    ("distrib", "takeover = \"maybe\""),
    ("distrib", "lease_ms = 0"),
    ("distrib", "tls_cert = \"missing.pem\"\ntls_key = \"missing.pem\"\ntls_ca = \"missing.pem\""),
];

fn project(dir: &Path, module: &str, settings: &str) -> String {
    std::fs::write(dir.join("a.mocu"), "window w {\n  rect 0 0 100 100\n}\n").unwrap();
    std::fs::write(dir.join("ok.js"), "mocu.read(\"modules.s.kind\");\n").unwrap();
    let profile = dir.join("project.toml");
    let text = format!(
        "[profile]\nlayouts = [\"a.mocu\"]\n\n[modules.sim]\nvehicles = [\"usv1\"]\n\n[modules.{module}]\n{settings}\n"
    );
    // The sim row replaces the table above rather than repeating it.
    let text = if module == "sim" {
        format!("[profile]\nlayouts = [\"a.mocu\"]\n\n[modules.sim]\n{settings}\n")
    } else {
        text
    };
    std::fs::write(&profile, text).unwrap();
    profile.display().to_string()
}

fn run(profile: &str) -> std::process::Output {
    mocu(&["run", profile, "--headless", "--frames", "1", "--no-watch", "--size", "320x200"])
}

#[test]
fn check_names_the_module_and_its_table_for_every_setting_the_module_refuses() {
    for (i, (module, settings)) in REFUSED.iter().enumerate() {
        let dir = scratch_dir("module-settings", &format!("check{i}"));
        let profile = project(&dir, module, settings);
        let out = mocu(&["check", &profile]);
        let stdout = String::from_utf8_lossy(&out.stdout);
        assert_eq!(out.status.code(), Some(1), "[modules.{module}] {settings}: {stdout}");
        assert!(
            stdout.contains(&format!("error[E0210]: module `{module}` would not start")),
            "[modules.{module}] {settings}: {stdout}"
        );
        assert!(stdout.contains(&format!("[modules.{module}]")), "points at the table: {stdout}");
    }
}

#[test]
fn what_check_refuses_run_cannot_start_and_run_then_exits_1() {
    // A sample of the rows through `mocu run` too (each starts a whole OCU).
    for (i, (module, settings)) in REFUSED.iter().enumerate().filter(|(i, _)| i % 3 == 0) {
        let dir = scratch_dir("module-settings", &format!("run{i}"));
        let profile = project(&dir, module, settings);
        let out = run(&profile);
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(1), "[modules.{module}] {settings}: {stderr}");
        assert!(stderr.contains("failed to start"), "{stderr}");
        assert!(stderr.contains("did not start (mark a module `optional = true`"), "{stderr}");
    }
}

#[test]
fn a_module_marked_optional_that_cannot_start_lets_the_run_exit_0() {
    let dir = scratch_dir("module-settings", "optional");
    let profile = project(&dir, "video", "address = \"localhost\"\noptional = true");
    let out = run(&profile);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(0), "{stderr}");
    assert!(stderr.contains("module `video` failed to start"), "still said: {stderr}");
}

#[test]
fn good_settings_check_clean_and_run_exits_0() {
    let dir = scratch_dir("module-settings", "good");
    let profile = project(&dir, "video", "address = \"127.0.0.1:0\"");
    let out = mocu(&["check", &profile]);
    assert_eq!(out.status.code(), Some(0), "{}", String::from_utf8_lossy(&out.stdout));
    let out = run(&profile);
    assert_eq!(out.status.code(), Some(0), "{}", String::from_utf8_lossy(&out.stderr));
}
