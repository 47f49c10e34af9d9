//! The README's first command, `./mocu run …`: on a fresh Debian machine it installs what
//! the build needs (saying so) and then runs cargo; on a machine that has everything it
//! goes straight to cargo. Run here against stand-in `pkg-config`, `apt-get`, `sudo`, `id`,
//! `c++` and `cargo` that record how they were called.

use std::os::unix::fs::PermissionsExt;
use std::path::Path;
use std::process::Command;

fn tool(dir: &Path, name: &str, body: &str) {
    let p = dir.join(name);
    std::fs::write(&p, format!("#!/bin/sh\n{body}\n")).unwrap();
    std::fs::set_permissions(&p, std::fs::Permissions::from_mode(0o755)).unwrap();
}

struct Machine {
    has_pkg_config: bool,
    has_libudev: bool,
    has_cxx: bool,
    root: bool,
}

/// Runs `./mocu run layouts/usv.mocu` on the pretend machine; returns (stderr, the calls
/// made, one per line).
fn launch(m: &Machine) -> (String, String) {
    let dir = tempfile::tempdir().unwrap();
    let bin = dir.path();
    let calls = bin.join("calls");
    let rec = |name: &str| format!("echo \"{name} $*\" >> {}", calls.display());
    if m.has_pkg_config {
        let answer = if m.has_libudev { 0 } else { 1 };
        tool(bin, "pkg-config", &format!("{}\nexit {answer}", rec("pkg-config")));
    }
    if m.has_cxx {
        tool(bin, "c++", "exit 0");
    }
    tool(bin, "id", &format!("echo {}", if m.root { 0 } else { 1000 }));
    tool(bin, "sudo", &format!("{}\nexec \"$@\"", rec("sudo")));
    tool(bin, "apt-get", &rec("apt-get"));
    tool(bin, "cargo", &rec("cargo"));
    // Only the stand-ins and the shell's own basics: no real pkg-config or compiler.
    let basics = bin.join("basics");
    std::fs::create_dir(&basics).unwrap();
    for b in ["env", "bash", "sh", "dirname", "cat"] {
        if let Some(p) =
            ["/usr/bin", "/bin"].iter().map(|d| Path::new(d).join(b)).find(|p| p.exists())
        {
            std::os::unix::fs::symlink(p, basics.join(b)).unwrap();
        }
    }
    let out = Command::new("/bin/bash")
        .arg("mocu")
        .args(["run", "layouts/usv.mocu"])
        .env("PATH", format!("{}:{}", bin.display(), basics.display()))
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let calls = std::fs::read_to_string(calls).unwrap_or_default();
    (String::from_utf8_lossy(&out.stderr).into_owned(), calls)
}

#[test]
fn the_first_command_installs_only_what_is_missing_then_runs_cargo() {
    let all = Machine { has_pkg_config: true, has_libudev: true, has_cxx: true, root: true };
    // (machine, the packages it must install, through sudo)
    let cases: Vec<(Machine, &[&str], bool)> = vec![
        (Machine { ..all }, &[], false),
        (Machine { has_libudev: false, ..all }, &["libudev-dev"], false),
        (Machine { has_libudev: false, root: false, ..all }, &["libudev-dev"], true),
        (
            Machine { has_pkg_config: false, has_libudev: false, has_cxx: false, root: true },
            &["pkg-config", "libudev-dev", "g++"],
            false,
        ),
    ];
    for (m, want, via_sudo) in cases {
        let (stderr, calls) = launch(&m);
        let last = calls.lines().last().unwrap_or_default();
        assert_eq!(last, "cargo run --release -- run layouts/usv.mocu", "{calls}");
        let install = calls.lines().find(|l| l.starts_with("apt-get install"));
        if want.is_empty() {
            assert!(!calls.contains("apt-get"), "nothing to install, nothing done: {calls}");
            assert!(stderr.is_empty(), "nothing said: {stderr}");
        } else {
            let install = install.unwrap_or_else(|| panic!("installs {want:?}: {calls}"));
            assert!(install.ends_with(&want.join(" ")), "{install}");
            assert!(calls.contains("apt-get update"), "{calls}");
            assert!(stderr.contains(&format!("mocu: installing {}", want.join(" "))), "{stderr}");
            assert_eq!(calls.contains("sudo env"), via_sudo, "{calls}");
        }
    }
}
