//! The output forms: human snippets (carets under the right characters, long lines cut,
//! colour only when asked, the deny summary) and SARIF fit for code scanning.

use mocu_language::render::{self, HumanOptions, SarifOptions};
use mocu_language::{Diagnostics, MemoryLoader, SourceMap, check_path};

fn check(text: &str) -> (SourceMap, Vec<mocu_language::Diagnostic>) {
    let mut sources = SourceMap::new();
    let mut diags = Diagnostics::new();
    check_path("main.mocu", text.to_string(), &MemoryLoader::new(), &mut sources, &mut diags);
    diags.sort();
    (sources, diags.into_vec())
}

/// The source line and the caret line of the first snippet, without the gutter.
fn snippet(out: &str) -> (String, String) {
    let lines: Vec<&str> = out.lines().collect();
    let at = lines.iter().position(|l| l.contains("-->")).expect("a location line");
    let strip = |l: &str| l.split_once("| ").map_or(String::new(), |(_, r)| r.to_string());
    (strip(lines[at + 2]), strip(lines[at + 3]))
}

/// The display column where `needle` starts in `line` (wide characters count two).
fn column_of(line: &str, needle: &str) -> usize {
    let byte = line.find(needle).expect("needle shown");
    line[..byte].chars().map(|c| if ('\u{1100}'..).contains(&c) && c != '…' { 2 } else { 1 }).sum()
}

#[test]
fn carets_sit_under_the_error_after_tabs_and_wide_characters() {
    for text in
        ["let a = \"x\"\nlet _b =\t\t1 +\ta * 2", "let a = \"x\"\nlet _b = \"漢字漢字🚁 {a * 2}\""]
    {
        let (sources, list) = check(text);
        let out = render::human(&sources, &list);
        let (line, carets) = snippet(&out);
        assert!(!line.contains('\t'), "tabs are expanded: {line:?}");
        let caret = carets.find('^').expect("carets");
        assert_eq!(caret, column_of(&line, "a * 2"), "in:\n{out}");
    }
}

#[test]
fn a_long_line_is_cut_around_the_error() {
    let text = format!(
        "let _a = \"{}\" == \"\" or \"x\" * 2 > 1 {}",
        "a".repeat(2_000_000),
        "or true ".repeat(100)
    );
    let (sources, list) = check(&text);
    assert!(!list.is_empty());
    let out = render::human(&sources, &list);
    assert!(out.len() < 2000, "the snippet is cut, not {} bytes", out.len());
    let (line, carets) = snippet(&out);
    assert!(line.starts_with('…') && line.ends_with('…'), "{line}");
    assert_eq!(carets.find('^'), Some(column_of(&line, "\"x\"")), "{out}");
}

#[test]
fn colour_only_when_asked_and_the_summary_says_warnings_are_denied() {
    let (sources, list) = check("let unused = 1\nwindow w { layer 1 }");
    let plain = render::human(&sources, &list);
    assert!(!plain.contains('\x1b'));
    assert!(plain.ends_with("0 error(s), 1 warning(s)\n"), "{plain}");
    let coloured =
        render::human_with(&sources, &list, HumanOptions { colour: true, deny_warnings: true });
    assert!(coloured.contains("\x1b[1;33mwarning[W0001]"), "{coloured}");
    assert!(coloured.contains("warnings denied by `--deny warnings`"), "{coloured}");
}

#[test]
fn a_duplicate_points_at_the_first_definition() {
    let (sources, list) = check("let a = 1\nlet a = 2\nwindow w { layer a }");
    let out = render::human(&sources, &list);
    assert!(out.contains("::: main.mocu:1:5"), "{out}");
    assert!(out.contains("- first defined here"), "{out}");
}

fn field<'a>(v: &'a serde_json::Value, path: &[&str]) -> &'a serde_json::Value {
    path.iter().fold(v, |v, k| &v[*k])
}

/// The SARIF 2.1.0 schema's required properties and value rules for what we emit, checked by
/// hand (sarifLog: version, runs; run: tool.driver.name; result: message.text; region: 1-based
/// lines and columns; artifactLocation.uri: a URI; reportingDescriptor: id, helpUri absolute;
/// invocation: executionSuccessful).
fn assert_valid_sarif(doc: &serde_json::Value) {
    assert_eq!(doc["version"], "2.1.0");
    let runs = doc["runs"].as_array().expect("runs");
    assert_eq!(runs.len(), 1);
    let run = &runs[0];
    assert!(field(run, &["tool", "driver", "name"]).is_string());
    assert!(
        ["unicodeCodePoints", "utf16CodeUnits"].contains(&run["columnKind"].as_str().unwrap_or(""))
    );
    for rule in field(run, &["tool", "driver", "rules"]).as_array().expect("rules") {
        assert!(rule["id"].is_string());
        let uri = rule["helpUri"].as_str().expect("helpUri");
        assert!(uri.starts_with("https://") && uri.contains('#'), "absolute helpUri: {uri}");
    }
    for inv in run["invocations"].as_array().expect("invocations") {
        assert!(inv["executionSuccessful"].is_boolean());
        for n in inv["toolExecutionNotifications"].as_array().expect("notifications") {
            assert!(field(n, &["message", "text"]).is_string());
        }
    }
    let rules = field(run, &["tool", "driver", "rules"]).as_array().expect("rules");
    for r in run["results"].as_array().expect("results") {
        assert!(field(r, &["message", "text"]).is_string());
        assert!(["error", "warning", "note", "none"].contains(&r["level"].as_str().unwrap_or("")));
        let index = r["ruleIndex"].as_u64().expect("ruleIndex") as usize;
        assert_eq!(rules[index]["id"], r["ruleId"]);
        let locations = r["locations"].as_array().expect("locations");
        let related = r["relatedLocations"].as_array().cloned().unwrap_or_default();
        for l in locations.iter().chain(&related) {
            let uri =
                field(l, &["physicalLocation", "artifactLocation", "uri"]).as_str().expect("uri");
            assert!(uri.starts_with("file:///"), "absolute file URI: {uri}");
            assert!(!uri.contains(' '), "percent-encoded: {uri}");
            let region = field(l, &["physicalLocation", "region"]);
            for k in ["startLine", "startColumn", "endLine", "endColumn"] {
                assert!(region[k].as_u64().expect(k) >= 1, "{k} is 1-based");
            }
        }
    }
}

#[test]
fn sarif_has_absolute_uris_help_links_column_kind_and_invocations() {
    let mut sources = SourceMap::new();
    let mut diags = Diagnostics::new();
    let loader = MemoryLoader::new();
    check_path(
        "my layouts/main é.mocu",
        "let a = 1\nlet a = 2\nwindow w { layer a }".into(),
        &loader,
        &mut sources,
        &mut diags,
    );
    let list = diags.into_vec();
    let options = SarifOptions { base: Some("/home/op".into()), failures: vec![] };
    let doc: serde_json::Value =
        serde_json::from_str(&render::sarif_with(&sources, &list, &options)).expect("JSON");
    assert_valid_sarif(&doc);
    let uri = field(&doc["runs"][0]["results"][0], &["locations"]);
    assert_eq!(
        field(&uri[0], &["physicalLocation", "artifactLocation", "uri"]),
        "file:///home/op/my%20layouts/main%20%C3%A9.mocu"
    );
    assert!(doc["runs"][0]["invocations"][0]["executionSuccessful"].as_bool().expect("bool"));
}

#[test]
fn sarif_reports_unreadable_files_as_an_unsuccessful_invocation() {
    let options = SarifOptions {
        base: Some("/w".into()),
        failures: vec!["cannot read `gone.mocu`: no such file".into()],
    };
    let doc: serde_json::Value =
        serde_json::from_str(&render::sarif_with(&SourceMap::new(), &[], &options)).expect("JSON");
    assert_valid_sarif(&doc);
    let inv = &doc["runs"][0]["invocations"][0];
    assert_eq!(inv["executionSuccessful"], false);
    assert_eq!(
        field(&inv["toolExecutionNotifications"][0], &["message", "text"]),
        "cannot read `gone.mocu`: no such file"
    );
}
