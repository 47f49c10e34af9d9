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

/// The JSON diagnostics of `mocu check` on a layout written to a scratch folder.
fn check_layout(name: &str, text: &str) -> (Option<i32>, Vec<serde_json::Value>) {
    let dir = scratch_dir("check-script-actions", name);
    let path = dir.join("l.mocu");
    std::fs::write(&path, text).unwrap();
    let out = mocu(&["check", "--format", "json", &path.display().to_string()]);
    let json: serde_json::Value =
        serde_json::from_str(&String::from_utf8_lossy(&out.stdout)).expect("json");
    (out.status.code(), json.as_array().cloned().unwrap_or_default())
}

#[test]
fn a_script_actions_syntax_error_is_reported_at_its_line_and_column_in_the_layout() {
    for engine in ["js", "rhai"] {
        let text = format!(
            "bind keyboard {{\n  key space -> #{engine}: {{\n    let a = 1;\n    let b = a +;\n  }}\n}}\n"
        );
        let (code, diags) = check_layout(engine, &text);
        assert_eq!(code, Some(1), "{engine}: {diags:?}");
        let d = diags.iter().find(|d| d["code"] == "E0101").expect("an E0101");
        assert_eq!(
            (d["line"].as_u64(), d["column"].as_u64()),
            (Some(4), Some(16)),
            "{engine}: {d}"
        );
        assert!(d["message"].as_str().unwrap().starts_with(&format!("{engine} script:")), "{d}");
        assert_eq!(diags.len(), 1, "one mistake, one diagnostic: {diags:?}");
    }
}

#[test]
fn an_unknown_script_engine_is_named_with_the_engines_there_are() {
    let (code, diags) = check_layout("py", "bind keyboard {\n  key space -> #jss: { x() }\n}\n");
    assert_eq!(code, Some(1));
    let d = &diags[0];
    assert_eq!(d["code"], "E0204");
    assert_eq!((d["line"].as_u64(), d["column"].as_u64()), (Some(2), Some(16)), "{d}");
    let help = d["help"].as_str().unwrap_or_default();
    assert!(help.contains("`js`"), "did you mean: {help}");
}

#[test]
fn script_actions_that_parse_check_clean_wherever_an_action_goes() {
    let text = r#"use "stdlib/controls.mocu"
window w { layer 1 }
in w { b: Button { at 0 0 80 20  label "B"  on press #js: { mocu.write("x.y", 1); } } }
bind keyboard { key space -> #rhai: { mocu::write("x.y", 2); } }
menu for type "usv" { item "Note" -> #js: { mocu.write(self + ".note", "n"); } }
watch w2 { when root.x.y > 1 then #js: { mocu.write("x.z", 3); } }
"#;
    let (code, diags) = check_layout("clean", text);
    assert_eq!(code, Some(0), "{diags:?}");
}
