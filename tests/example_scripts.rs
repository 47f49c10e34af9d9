//! examples/scripts: a script module (`fleet_watch.js`) and a script action (`key n -> #js:`)
//! in a project, end to end with the built binary: the profile checks clean, the module
//! publishes what it computes from the simulator, and the keyboard's `N` runs the layout's
//! script, which reads the module's output (docs/scripting.md).

mod cli_support;

use cli_support::mocu;

#[test]
fn the_scripts_example_checks_clean() {
    let out = mocu(&["check", "--deny", "warnings", "examples/scripts/project.toml"]);
    assert_eq!(out.status.code(), Some(0), "{}", String::from_utf8_lossy(&out.stdout));
}

#[test]
fn the_script_module_publishes_the_fastest_boat_and_the_n_key_notes_it() {
    let out = mocu(&[
        "run",
        "examples/scripts/project.toml",
        "--headless",
        "--frames",
        "90",
        "--mavlink",
        "off",
        "--video",
        "off",
        "--no-watch",
        "--input-script",
        "examples/scripts/note.script",
        "--dump",
        "root",
    ]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stderr}");
    let root: serde_json::Value = serde_json::from_slice(&out.stdout).expect("--dump is JSON");
    let child = |v: &serde_json::Value, name: &str| {
        v["children"].as_array().and_then(|c| c.iter().find(|x| x["name"] == name)).cloned()
    };
    let watch = child(&root, "fleet_watch").expect("the script module's object");
    let fastest = watch["properties"]["fastest"].as_str().unwrap_or_default().to_string();
    assert!(["usv1", "usv2"].contains(&fastest.as_str()), "{watch}");
    assert_eq!(watch["properties"]["reporting"], 2, "{watch}");
    assert!(watch["properties"]["top_speed"].as_f64().is_some_and(|s| s > 0.0), "{watch}");
    let operator = child(&root, "operator").expect("root.operator");
    assert_eq!(operator["properties"]["note"], format!("fastest: {fastest}"), "{stderr}");
}
