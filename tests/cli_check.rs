//! End-to-end tests of `mocu check` and `mocu build` through the built binary: the
//! command-line contract of docs/language.md (formats, exit codes, bundles).

mod cli_support;

use cli_support::mocu;
use std::path::PathBuf;
use std::process::Output;

fn scratch(name: &str, text: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("mocu-cli-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    let p = dir.join(name);
    std::fs::write(&p, text).expect("write");
    p
}

fn stdout(o: &Output) -> String {
    String::from_utf8_lossy(&o.stdout).into_owned()
}

#[test]
fn the_shipped_layouts_and_stdlib_check_clean() {
    let o = mocu(&["check", "--deny", "warnings", "layouts", "stdlib"]);
    assert_eq!(o.status.code(), Some(0), "{}{}", stdout(&o), String::from_utf8_lossy(&o.stderr));
    assert!(stdout(&o).trim().is_empty(), "{}", stdout(&o));
}

#[test]
fn a_broken_file_exits_1_with_json_diagnostics() {
    let p = scratch(
        "broken.mocu",
        "let name = \"x\"\nlet n = name * 2\nwindow w { layer n }\nlet bad = (1 +\n",
    );
    let o = mocu(&["check", "--format", "json", p.to_str().expect("utf-8 path")]);
    assert_eq!(o.status.code(), Some(1));
    let v: serde_json::Value = serde_json::from_str(&stdout(&o)).expect("one JSON array");
    let list = v.as_array().expect("an array");
    assert_eq!(list.len(), 2, "{v:#}");
    for d in list {
        for key in
            ["file", "line", "column", "end_line", "end_column", "severity", "code", "message"]
        {
            assert!(d.get(key).is_some(), "missing {key} in {d}");
        }
    }
    assert_eq!(list[0]["code"], "E0301");
    assert_eq!(list[0]["line"], 2);
    assert_eq!(list[0]["column"], 9);
    assert_eq!(list[0]["severity"], "error");
    assert_eq!(list[1]["code"], "E0101");
}

#[test]
fn human_output_shows_the_line_and_an_underline() {
    let p =
        scratch("human.mocu", "let speed = 1\nlet x = sped + 1\nwindow w { layer x + speed }\n");
    let o = mocu(&["check", p.to_str().expect("utf-8 path")]);
    assert_eq!(o.status.code(), Some(1));
    let out = stdout(&o);
    assert!(out.contains("error[E0204]: unknown name `sped`"), "{out}");
    assert!(out.contains("human.mocu:2:9"), "{out}");
    assert!(out.contains("2 | let x = sped + 1"), "{out}");
    assert!(out.contains("  |         ^^^^"), "{out}");
    assert!(out.contains("= help: did you mean `speed`?"), "{out}");
}

#[test]
fn warnings_fail_only_with_deny_warnings() {
    let p = scratch("warn.mocu", "let unused = 1\nwindow w { layer 1 }\n");
    let path = p.to_str().expect("utf-8 path");
    assert_eq!(mocu(&["check", path]).status.code(), Some(0));
    let o = mocu(&["check", "--deny", "warnings", path]);
    assert_eq!(o.status.code(), Some(1));
    assert!(stdout(&o).contains("warning[W0001]"));
}

#[test]
fn sarif_output_has_the_2_1_0_shape() {
    let p = scratch("sarif.mocu", "let x = \"a\" * 2\nwindow w { layer x }\n");
    let o = mocu(&["check", "--format", "sarif", p.to_str().expect("utf-8 path")]);
    assert_eq!(o.status.code(), Some(1));
    let v: serde_json::Value = serde_json::from_str(&stdout(&o)).expect("JSON");
    assert_eq!(v["version"], "2.1.0");
    assert!(v["$schema"].as_str().is_some_and(|s| s.contains("sarif")));
    let run = &v["runs"][0];
    assert_eq!(run["tool"]["driver"]["name"], "mocu");
    assert_eq!(run["tool"]["driver"]["rules"][0]["id"], "E0301");
    let r = &run["results"][0];
    assert_eq!(r["ruleId"], "E0301");
    assert_eq!(r["level"], "error");
    assert!(r["message"]["text"].as_str().is_some());
    let loc = &r["locations"][0]["physicalLocation"];
    assert!(loc["artifactLocation"]["uri"].as_str().is_some_and(|u| u.ends_with("sarif.mocu")));
    assert_eq!(loc["region"]["startLine"], 1);
    assert_eq!(loc["region"]["startColumn"], 9);
}

#[test]
fn a_missing_path_exits_2() {
    let o = mocu(&["check", "no/such/file.mocu"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("no/such/file.mocu"));
    assert_eq!(
        mocu(&["check", "--format", "xml", "layouts"]).status.code(),
        Some(2),
        "a bad flag is a usage error"
    );
}

#[test]
fn build_writes_a_bundle_that_reads_back_and_refuses_tampering() {
    let out = std::env::temp_dir().join(format!("mocu-cli-{}-project.bundle", std::process::id()));
    let o = mocu(&["build", "layouts/project.toml", "-o", out.to_str().expect("utf-8 path")]);
    assert_eq!(o.status.code(), Some(0), "{}", String::from_utf8_lossy(&o.stderr));
    let bytes = std::fs::read(&out).expect("bundle written");
    let b = mocu_language::bundle::read(&bytes).expect("reads back");
    assert_eq!(b.layouts.len(), 4);
    assert!(b.schema.types.contains_key("usv"));
    let fig3 =
        b.layouts.iter().find(|l| l.path == "fig3-multi-usv.mocu").expect("fig3 in the bundle");
    assert_eq!(fig3.program.templates.len(), 1, "one per-vehicle template");

    let mut tampered = bytes.clone();
    let i = tampered.len() / 2;
    tampered[i] ^= 0x20;
    assert!(mocu_language::bundle::read(&tampered).is_err());

    let foreign = String::from_utf8(bytes).expect("text").replacen(
        &format!("mocu {}", env!("CARGO_PKG_VERSION")),
        "mocu 9.9.9",
        1,
    );
    let e = mocu_language::bundle::read(foreign.as_bytes()).expect_err("foreign version refused");
    assert!(e.to_string().contains("9.9.9") && e.to_string().contains("mocu build"), "{e}");
    let _ = std::fs::remove_file(&out);
}

#[test]
fn build_refuses_a_project_with_errors() {
    let dir = std::env::temp_dir().join(format!("mocu-cli-{}-bad", std::process::id()));
    std::fs::create_dir_all(&dir).expect("dir");
    std::fs::write(dir.join("p.toml"), "[profile]\nlayouts = [\"a.mocu\"]\n").expect("write");
    std::fs::write(dir.join("a.mocu"), "window w { layer \"x\" }\n").expect("write");
    let out = dir.join("p.bundle");
    let o = mocu(&[
        "build",
        dir.join("p.toml").to_str().expect("utf-8"),
        "-o",
        out.to_str().expect("utf-8"),
    ]);
    assert_eq!(o.status.code(), Some(1));
    assert!(!out.exists());
    assert_eq!(
        mocu(&["build", "no/such.toml", "-o", out.to_str().expect("utf-8")]).status.code(),
        Some(2)
    );
}

/// A fresh folder of its own under the temp folder, with `files` written in it.
fn project_dir(name: &str, files: &[(&str, &str)]) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("mocu-cli-{}-{name}", std::process::id()));
    for (path, text) in files {
        let p = dir.join(path);
        std::fs::create_dir_all(p.parent().expect("a folder")).expect("temp dir");
        std::fs::write(&p, text).expect("write");
    }
    dir
}

const SCHEMA: &str = "[[instances]]\npath = \"root.vehicles.usv*\"\ntype = \"usv\"\n[types.usv.properties]\nfuel = { type = \"float\" }\n";
const MISSPELT: &str = "window w { layer 1  visible root.vehicles.usv1.fule > 0 }\n";

#[test]
fn a_layout_is_checked_against_the_nearest_project_toml_above_it() {
    let dir = project_dir(
        "walk",
        &[
            ("project.toml", "[profile]\nlayouts = []\nschemas = [\"s.toml\"]\n"),
            ("s.toml", SCHEMA),
            ("screens/deep/a.mocu", MISSPELT),
        ],
    );
    let layout = dir.join("screens/deep/a.mocu");
    let o = mocu(&["check", "--format", "json", layout.to_str().expect("utf-8 path")]);
    assert_eq!(o.status.code(), Some(1), "{}", stdout(&o));
    assert!(stdout(&o).contains("E0401") && stdout(&o).contains("fuel"), "{}", stdout(&o));
    assert!(!String::from_utf8_lossy(&o.stderr).contains("not checked"));
}

#[test]
fn profile_names_the_project_of_layouts_outside_it() {
    let dir = project_dir(
        "flag",
        &[
            ("p/profile.toml", "[profile]\nlayouts = []\nschemas = [\"s.toml\"]\n"),
            ("p/s.toml", SCHEMA),
            ("a.mocu", MISSPELT),
        ],
    );
    let (layout, profile) = (dir.join("a.mocu"), dir.join("p/profile.toml"));
    let args =
        ["check", "--profile", profile.to_str().expect("utf-8"), layout.to_str().expect("utf-8")];
    let o = mocu(&args);
    assert_eq!(o.status.code(), Some(1), "{}", stdout(&o));
    assert!(stdout(&o).contains("has no property `fule`"), "{}", stdout(&o));
    let missing =
        mocu(&["check", "--profile", "no/such/profile.toml", layout.to_str().expect("utf-8")]);
    assert_eq!(missing.status.code(), Some(2));
}

#[test]
fn without_a_profile_check_says_once_that_property_names_were_not_checked() {
    let dir = project_dir("none", &[("a.mocu", MISSPELT), ("b.mocu", MISSPELT)]);
    let o = mocu(&["check", "--format", "json", dir.to_str().expect("utf-8 path")]);
    assert_eq!(o.status.code(), Some(0), "exit codes are unchanged: {}", stdout(&o));
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(err.matches("were not checked").count(), 1, "{err}");
    assert!(err.contains("1 other layout"), "{err}");
    let v: serde_json::Value = serde_json::from_str(&stdout(&o)).expect("JSON stays clean");
    assert_eq!(v.as_array().map(Vec::len), Some(0));
}

#[test]
fn the_shipped_profile_sets_only_settings_its_modules_accept() {
    let bad = project_dir(
        "settings",
        &[(
            "project.toml",
            "[profile]\nlayouts = []\n[modules.sim]\nvehicles = [\"usv1\"]\nspeed = 3\n",
        )],
    );
    let o = mocu(&["check", bad.join("project.toml").to_str().expect("utf-8")]);
    assert_eq!(o.status.code(), Some(1));
    assert!(
        stdout(&o).contains("no setting `speed`") && stdout(&o).contains("`vehicles`"),
        "{}",
        stdout(&o)
    );
    let shipped = mocu(&["check", "--deny", "warnings", "layouts/project.toml"]);
    assert_eq!(shipped.status.code(), Some(0), "{}", stdout(&shipped));
}

#[test]
fn the_tutorials_whole_file_checks_clean_in_the_shipped_project() {
    let doc = std::fs::read_to_string("docs/tutorial.md").expect("docs/tutorial.md");
    let at = doc.find("## The whole file").expect("the tutorial ends with the whole file");
    let start = doc[at..].find("```mocu\n").expect("a mocu block") + at + 8;
    let end = doc[start..].find("```").expect("closed") + start;
    let p = project_dir("tutorial", &[("my.mocu", &doc[start..end])]).join("my.mocu");
    let o = mocu(&[
        "check",
        "--deny",
        "warnings",
        "--profile",
        "layouts/project.toml",
        p.to_str().expect("utf-8"),
    ]);
    assert_eq!(o.status.code(), Some(0), "{}", stdout(&o));
    assert!(!doc[start..end].contains("?? 0"), "the tutorial advises against false zeros");
}
