//! `mocu check` at the file-system edge: folders (symbolic-link loops, no layouts), bytes that
//! are not UTF-8, I/O failures in SARIF, and no colour codes when the output is not a terminal.

mod cli_support;

use cli_support::mocu;
use std::path::{Path, PathBuf};

fn scratch_dir(name: &str) -> PathBuf {
    cli_support::scratch_dir("cli-io", name)
}

fn text(o: &[u8]) -> String {
    String::from_utf8_lossy(o).into_owned()
}

fn arg(p: &Path) -> &str {
    p.to_str().expect("utf-8 path")
}

#[cfg(unix)]
#[test]
fn a_folder_walk_does_not_follow_a_symbolic_link_loop() {
    let dir = scratch_dir("loop");
    std::fs::write(dir.join("a.mocu"), "window w { layer 1 }\n").expect("write");
    std::os::unix::fs::symlink(&dir, dir.join("again")).expect("symlink");
    let o = mocu(&["check", arg(&dir)]);
    assert_eq!(o.status.code(), Some(0), "{}{}", text(&o.stdout), text(&o.stderr));
}

#[test]
fn a_folder_without_layouts_says_so_and_exits_2() {
    let dir = scratch_dir("empty");
    std::fs::write(dir.join("notes.txt"), "nothing to check").expect("write");
    let o = mocu(&["check", arg(&dir)]);
    assert_eq!(o.status.code(), Some(2));
    assert!(text(&o.stderr).contains("no layouts (.mocu) or profiles (.toml) in the folder"));
}

#[test]
fn a_file_that_is_not_utf8_is_located_and_fails_the_check() {
    let dir = scratch_dir("latin1");
    let p = dir.join("latin1.mocu");
    std::fs::write(&p, b"window w { layer 1 }\nlet a = \"caf\xe9\"\n").expect("write");
    let o = mocu(&["check", arg(&p)]);
    assert_eq!(o.status.code(), Some(1));
    let out = text(&o.stdout);
    assert!(out.contains("error[E0107]: byte 0xE9 is not UTF-8 text"), "{out}");
    assert!(out.contains("latin1.mocu:2:13"), "{out}");
    assert!(out.contains("save the file as UTF-8"), "{out}");
}

#[test]
fn sarif_marks_an_unreadable_path_as_an_unsuccessful_invocation() {
    let o = mocu(&["check", "--format", "sarif", "no/such/layout.mocu"]);
    assert_eq!(o.status.code(), Some(2));
    let doc: serde_json::Value = serde_json::from_slice(&o.stdout).expect("SARIF on stdout");
    let inv = &doc["runs"][0]["invocations"][0];
    assert_eq!(inv["executionSuccessful"], false);
    let note = inv["toolExecutionNotifications"][0]["message"]["text"].as_str().unwrap_or("");
    assert!(note.contains("no/such/layout.mocu"), "{note}");
}

#[test]
fn output_to_a_pipe_has_no_colour_codes() {
    let dir = scratch_dir("colour");
    let p = dir.join("c.mocu");
    std::fs::write(&p, "let unused = 1\nwindow w { layer 1 }\n").expect("write");
    let o = mocu(&["check", "--deny", "warnings", arg(&p)]);
    assert_eq!(o.status.code(), Some(1));
    let out = text(&o.stdout);
    assert!(!out.contains('\x1b'), "{out}");
    assert!(out.contains("warnings denied by `--deny warnings`"), "{out}");
}
