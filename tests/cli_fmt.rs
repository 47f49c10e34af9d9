//! `mocu fmt [--check] PATH...` end to end: exit codes, the diff `--check` prints, files
//! rewritten in place (and only those that change), files with syntax errors left as they are,
//! folders walked for `.mocu` files. The command-line contract is in docs/language.md.

mod cli_support;

use cli_support::mocu;
use std::path::{Path, PathBuf};

const MESSY: &str = "window w {  layer 1   opacity 0.5 }\nlet a=1 // one\n";
const TIDY: &str = "window w {\n    layer 1\n    opacity 0.5\n}\nlet a = 1 // one\n";

fn scratch_dir(name: &str) -> PathBuf {
    cli_support::scratch_dir("cli-fmt", name)
}

fn text(o: &[u8]) -> String {
    String::from_utf8_lossy(o).into_owned()
}

fn arg(p: &Path) -> &str {
    p.to_str().expect("utf-8 path")
}

fn read(p: &Path) -> String {
    std::fs::read_to_string(p).expect("readable")
}

#[test]
fn check_exits_0_and_prints_nothing_when_every_file_is_formatted() {
    let dir = scratch_dir("tidy");
    std::fs::write(dir.join("a.mocu"), TIDY).expect("write");
    let o = mocu(&["fmt", "--check", arg(&dir.join("a.mocu"))]);
    assert_eq!(o.status.code(), Some(0), "{}", text(&o.stderr));
    assert_eq!(text(&o.stdout), "");
}

#[test]
fn check_exits_1_with_a_unified_diff_of_each_file_to_change_and_writes_nothing() {
    let dir = scratch_dir("messy");
    let (messy, tidy) = (dir.join("messy.mocu"), dir.join("tidy.mocu"));
    std::fs::write(&messy, MESSY).expect("write");
    std::fs::write(&tidy, TIDY).expect("write");
    let o = mocu(&["fmt", "--check", arg(&messy), arg(&tidy)]);
    assert_eq!(o.status.code(), Some(1), "{}", text(&o.stderr));
    let m = arg(&messy);
    let expected = format!(
        "--- {m}\n+++ {m}\n@@ -1,2 +1,5 @@\n-window w {{  layer 1   opacity 0.5 }}\n-let a=1 // one\n\
         +window w {{\n+    layer 1\n+    opacity 0.5\n+}}\n+let a = 1 // one\n"
    );
    assert_eq!(text(&o.stdout), expected);
    assert!(text(&o.stderr).contains("1 of 2 file(s) not formatted"), "{}", text(&o.stderr));
    assert_eq!(read(&messy), MESSY, "--check wrote the file");
}

#[test]
fn without_check_it_rewrites_the_files_that_change_names_them_and_exits_0() {
    let dir = scratch_dir("write");
    let (messy, tidy) = (dir.join("messy.mocu"), dir.join("tidy.mocu"));
    std::fs::write(&messy, MESSY).expect("write");
    std::fs::write(&tidy, TIDY).expect("write");
    let o = mocu(&["fmt", arg(&messy), arg(&tidy)]);
    assert_eq!(o.status.code(), Some(0), "{}", text(&o.stderr));
    assert_eq!(text(&o.stdout), format!("formatted {}\n", arg(&messy)));
    assert_eq!(read(&messy), TIDY);
    assert_eq!(read(&tidy), TIDY);
    // No temporary file is left beside them.
    let names: Vec<_> =
        std::fs::read_dir(&dir).expect("dir").map(|e| e.expect("entry").file_name()).collect();
    assert_eq!(names.len(), 2, "{names:?}");
    let again = mocu(&["fmt", "--check", arg(&messy)]);
    assert_eq!(again.status.code(), Some(0), "{}", text(&again.stdout));
}

#[test]
fn a_file_with_syntax_errors_is_left_as_it_is_with_its_diagnostics_and_exit_1() {
    let dir = scratch_dir("broken");
    let (broken, messy) = (dir.join("broken.mocu"), dir.join("messy.mocu"));
    let src = "let a = (1 +\nwindow w {  layer 1 }\n";
    std::fs::write(&broken, src).expect("write");
    std::fs::write(&messy, MESSY).expect("write");
    let o = mocu(&["fmt", arg(&broken), arg(&messy)]);
    assert_eq!(o.status.code(), Some(1), "{}", text(&o.stderr));
    let err = text(&o.stderr);
    assert!(err.contains("error[E"), "the diagnostics: {err}");
    assert!(err.contains("broken.mocu"), "{err}");
    assert_eq!(read(&broken), src, "a broken file was rewritten");
    // The other files are still formatted.
    assert_eq!(read(&messy), TIDY);
}

#[test]
fn a_folder_is_walked_for_layout_files_and_other_files_are_left_alone() {
    let dir = scratch_dir("folder");
    std::fs::create_dir_all(dir.join("sub")).expect("mkdir");
    std::fs::write(dir.join("sub/a.mocu"), MESSY).expect("write");
    std::fs::write(dir.join("project.toml"), "[profile]\nname = \"x\"\n").expect("write");
    let o = mocu(&["fmt", "--check", arg(&dir)]);
    assert_eq!(o.status.code(), Some(1));
    assert!(text(&o.stdout).contains("sub/a.mocu"), "{}", text(&o.stdout));
    let o = mocu(&["fmt", arg(&dir)]);
    assert_eq!(o.status.code(), Some(0), "{}", text(&o.stderr));
    assert_eq!(read(&dir.join("sub/a.mocu")), TIDY);
    assert_eq!(read(&dir.join("project.toml")), "[profile]\nname = \"x\"\n");
}

#[test]
fn a_missing_path_or_a_folder_without_layouts_exits_2() {
    let dir = scratch_dir("missing");
    let o = mocu(&["fmt", "--check", arg(&dir.join("nope.mocu"))]);
    assert_eq!(o.status.code(), Some(2));
    assert!(text(&o.stderr).contains("no such file or folder"), "{}", text(&o.stderr));
    let o = mocu(&["fmt", arg(&dir)]);
    assert_eq!(o.status.code(), Some(2));
    assert!(text(&o.stderr).contains("no layouts (.mocu)"), "{}", text(&o.stderr));
    let o = mocu(&["fmt"]);
    assert_eq!(o.status.code(), Some(2), "no path is a usage error");
}
