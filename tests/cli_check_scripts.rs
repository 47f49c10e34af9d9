//! `mocu check PROFILE.toml` parses the profile's script modules and reports a script's
//! syntax error at its file, line and column (docs/scripting.md).

mod cli_support;

use cli_support::{mocu, scratch_dir};

#[test]
fn a_script_modules_syntax_error_is_reported_at_its_line_and_column() {
    for (ext, script) in
        [("js", "let a = 1;\nlet b = a +;\n"), ("rhai", "let a = 1;\nlet b = a +;\n")]
    {
        let dir = scratch_dir("check-scripts", ext);
        std::fs::write(dir.join(format!("ops.{ext}")), script).unwrap();
        let profile = dir.join("project.toml");
        std::fs::write(
            &profile,
            format!("[profile]\nname = \"p\"\nlayouts = []\n\n[modules.ops]\nkind = \"script\"\nfile = \"ops.{ext}\"\n"),
        )
        .unwrap();
        let out = mocu(&["check", "--format", "json", &profile.display().to_string()]);
        let text = String::from_utf8_lossy(&out.stdout);
        assert_eq!(out.status.code(), Some(1), "{ext}: {text}");
        let json: serde_json::Value = serde_json::from_str(&text).expect("json");
        let found = json.as_array().into_iter().flatten().find(|d| d["code"] == "E0101");
        let Some(d) = found else { panic!("{ext}: no E0101 in {text}") };
        assert!(
            d["file"].as_str().is_some_and(|f| f.ends_with(&format!("ops.{ext}"))),
            "{ext}: {d}"
        );
        assert_eq!((d["line"].as_u64(), d["column"].as_u64()), (Some(2), Some(12)), "{ext}: {d}");
    }
}

#[test]
fn a_profile_whose_scripts_parse_checks_clean() {
    let dir = scratch_dir("check-scripts", "clean");
    std::fs::write(dir.join("ops.js"), "mocu.write(\"out.x\", 1);\n").unwrap();
    let profile = dir.join("project.toml");
    std::fs::write(
        &profile,
        "[profile]\nname = \"p\"\nlayouts = []\n\n[modules.ops]\nkind = \"script\"\nfile = \"ops.js\"\n",
    )
    .unwrap();
    let out = mocu(&["check", &profile.display().to_string()]);
    assert_eq!(out.status.code(), Some(0), "{}", String::from_utf8_lossy(&out.stdout));
}
