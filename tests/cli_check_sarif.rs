//! `mocu check --format sarif` is valid SARIF 2.1.0: its output for a clean file, for errors
//! and warnings with help and related locations, for several files (paths that need
//! percent-encoding) and for an I/O failure is validated against the OASIS schema
//! (tests/data/sarif-schema-2.1.0.json) by Python's `jsonschema` (tests/peers/validate_sarif.py;
//! CI pins it in .ci/run). The validator is shown to reject a document with a required
//! property removed, so a pass means something.

mod cli_support;

use cli_support::mocu;
use std::path::{Path, PathBuf};
use std::process::Command;

const SCHEMA: &str = "tests/data/sarif-schema-2.1.0.json";
const VALIDATOR: &str = "tests/peers/validate_sarif.py";

fn scratch_dir(name: &str) -> PathBuf {
    cli_support::scratch_dir("sarif", name)
}

fn arg(p: &Path) -> &str {
    p.to_str().expect("utf-8 path")
}

/// The SARIF document `mocu check --format sarif ARGS` prints, with its exit code.
fn sarif(args: &[&str]) -> (Option<i32>, serde_json::Value) {
    let mut all = vec!["check", "--format", "sarif"];
    all.extend_from_slice(args);
    let o = mocu(&all);
    let doc = serde_json::from_slice(&o.stdout).unwrap_or_else(|e| {
        panic!(
            "not JSON ({e}): {}{}",
            String::from_utf8_lossy(&o.stdout),
            String::from_utf8_lossy(&o.stderr)
        )
    });
    (o.status.code(), doc)
}

/// The schema violations the validator finds in `doc` (empty when valid).
fn violations(doc: &serde_json::Value, name: &str) -> Vec<String> {
    let dir = scratch_dir(&format!("doc-{name}"));
    let file = dir.join(format!("{name}.sarif"));
    std::fs::write(&file, serde_json::to_string_pretty(doc).expect("serialises")).expect("write");
    let root = env!("CARGO_MANIFEST_DIR");
    let o = Command::new("python3")
        .arg(Path::new(root).join(VALIDATOR))
        .arg(Path::new(root).join(SCHEMA))
        .arg(&file)
        .output()
        .expect("python3 runs (CI installs it)");
    let out = String::from_utf8_lossy(&o.stdout).into_owned();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        !err.contains("No module named 'jsonschema'"),
        "this test needs python3 with jsonschema: `python3 -m pip install jsonschema==4.26.0`"
    );
    match o.status.code() {
        Some(0) => Vec::new(),
        Some(1) if !out.is_empty() => out.lines().map(str::to_string).collect(),
        _ => panic!("the validator failed: {out}{err}"),
    }
}

fn assert_valid(doc: &serde_json::Value, name: &str) {
    let v = violations(doc, name);
    assert!(v.is_empty(), "{name}: not valid SARIF 2.1.0:\n{}", v.join("\n"));
}

#[test]
fn sarif_for_a_clean_file_is_valid_and_has_no_results() {
    let dir = scratch_dir("clean");
    let p = dir.join("clean.mocu");
    std::fs::write(&p, "window w { layer 1 }\n").expect("write");
    let (code, doc) = sarif(&[arg(&p)]);
    assert_eq!(code, Some(0));
    assert_eq!(doc["runs"][0]["results"].as_array().map(Vec::len), Some(0));
    assert_eq!(doc["runs"][0]["invocations"][0]["executionSuccessful"], true);
    assert_valid(&doc, "clean");
}

#[test]
fn sarif_for_errors_with_help_and_related_locations_is_valid() {
    let dir = scratch_dir("errors");
    let p = dir.join("errors.mocu");
    std::fs::write(
        &p,
        "window w { layer 1 }\nwindow w { layer 2 }\nlet unused = 1\nlet s = \"a\" * 2\n\
         in w { d: Dail { at 0 0 10 10 } }\n",
    )
    .expect("write");
    let (code, doc) = sarif(&[arg(&p)]);
    assert_eq!(code, Some(1));
    let results = doc["runs"][0]["results"].as_array().expect("results");
    assert!(results.len() >= 4, "{doc:#}");
    assert!(results.iter().any(|r| r["level"] == "warning"), "a warning is among them");
    assert!(results.iter().any(|r| r["relatedLocations"].is_array()), "a duplicate's first site");
    assert!(
        results.iter().any(|r| r["message"]["text"].as_str().is_some_and(|t| t.contains("help:"))),
        "help is part of the message"
    );
    assert_valid(&doc, "errors");
}

#[test]
fn sarif_for_several_files_with_paths_to_percent_encode_is_valid() {
    let dir = scratch_dir("several");
    let a = dir.join("with space é.mocu");
    let b = dir.join("b#1.mocu");
    std::fs::write(&a, "watch x { when 1 > 2 for 5 seconds then hide w }\n").expect("write");
    std::fs::write(&b, "window w { layer \"x\" * 2 }\n").expect("write");
    let (code, doc) = sarif(&[arg(&dir)]);
    assert_eq!(code, Some(1));
    let uris: Vec<&str> = doc["runs"][0]["results"]
        .as_array()
        .expect("results")
        .iter()
        .filter_map(|r| r["locations"][0]["physicalLocation"]["artifactLocation"]["uri"].as_str())
        .collect();
    assert!(uris.iter().any(|u| u.ends_with("with%20space%20%C3%A9.mocu")), "{uris:?}");
    assert!(uris.iter().any(|u| u.ends_with("b%231.mocu")), "{uris:?}");
    assert_valid(&doc, "several");
}

#[test]
fn sarif_for_an_unreadable_path_is_valid_and_marks_the_invocation_unsuccessful() {
    let (code, doc) = sarif(&["no/such/layout.mocu"]);
    assert_eq!(code, Some(2));
    let inv = &doc["runs"][0]["invocations"][0];
    assert_eq!(inv["executionSuccessful"], false);
    assert_eq!(inv["toolExecutionNotifications"].as_array().map(Vec::len), Some(1));
    assert_valid(&doc, "unreadable");
}

#[test]
fn the_validator_rejects_sarif_missing_a_required_property() {
    let (_, doc) = sarif(&["no/such/layout.mocu"]);
    assert_valid(&doc, "before_removal");
    // (the object, as a JSON pointer, and the required property taken from it)
    let cases = [
        ("", "version"),
        ("/runs/0/tool/driver", "name"),
        ("/runs/0/invocations/0", "executionSuccessful"),
    ];
    for (object, property) in cases {
        let mut broken = doc.clone();
        let parent = broken.pointer_mut(object).and_then(|o| o.as_object_mut());
        assert!(parent.expect(object).remove(property).is_some(), "{object} has {property}");
        let v = violations(&broken, &format!("without_{property}"));
        assert!(
            v.iter().any(|l| l.contains(&format!("'{property}' is a required property"))),
            "removing `{property}` went unnoticed: {v:?}"
        );
    }
}
