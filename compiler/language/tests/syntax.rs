//! Data-driven diagnostics tests. Every `.mocu` (and profile or schema `.toml`) file under
//! tests/syntax/ is checked; the expected diagnostics are comments under the offending line:
//!
//! ```text
//! let x = "a" * 2
//! //      ^^^ error[E0301]: a string is used as a number
//! ```
//!
//! A caret line starts with `//` (`#` in TOML) and puts the carets under the reported columns;
//! a diagnostic in column 1 or 2 is written `// @COL ^ …`. Layouts named by a profile in the
//! same folder are checked through that profile (with its schemas).
//! `UPDATE_EXPECT=1 cargo test -p mocu-language --test syntax` rewrites the expectations.

use mocu_language::{Diagnostics, FsLoader, SourceLoader, SourceMap, codes, render};
use std::collections::{BTreeMap, HashSet};
use std::path::Path;

const ROOT: &str = "tests/syntax";

fn files(dir: &Path, out: &mut Vec<String>) {
    let mut entries: Vec<_> = std::fs::read_dir(dir)
        .expect("tests/syntax exists")
        .filter_map(|e| e.ok().map(|e| e.path()))
        .collect();
    entries.sort();
    for p in entries {
        if p.is_dir() {
            files(&p, out);
        } else if p.extension().is_some_and(|e| e == "mocu" || e == "toml") {
            out.push(p.to_string_lossy().replace('\\', "/"));
        }
    }
}

fn is_expectation(line: &str, comment: &str) -> bool {
    let t = line.trim_start();
    t.strip_prefix(comment).is_some_and(|rest| {
        let rest = rest.trim_start();
        let rest = if let Some(r) = rest.strip_prefix('@') {
            r.trim_start_matches(|c: char| c.is_ascii_digit()).trim_start()
        } else {
            rest
        };
        rest.starts_with('^') && (rest.contains(" error[") || rest.contains(" warning["))
    })
}

/// Diagnostics of every test file, keyed by path: (line, column, width, rendered text).
fn run_all(paths: &[String]) -> BTreeMap<String, Vec<(usize, usize, usize, String)>> {
    let mut covered = HashSet::new();
    for p in paths.iter().filter(|p| p.ends_with(".toml")) {
        let text = std::fs::read_to_string(p).unwrap_or_default();
        if let Ok(prof) = toml::from_str::<mocu_language::profile::ProfileFile>(&text) {
            covered.extend(prof.profile.layouts.iter().filter_map(|l| FsLoader.resolve(p, l)));
        }
    }
    let mut sources = SourceMap::new();
    let mut diags = Diagnostics::new();
    for p in paths {
        if covered.contains(p) {
            continue;
        }
        let bytes = std::fs::read(p).unwrap_or_default();
        if let Some(text) = mocu_language::lexer::decode(p, bytes, &mut sources, &mut diags) {
            mocu_language::check_path(p, text, &FsLoader, &mut sources, &mut diags);
        }
    }
    diags.sort();
    let mut out: BTreeMap<String, Vec<_>> = BTreeMap::new();
    for d in diags.iter() {
        let l = d.locate(&sources);
        let file = sources.get(d.span.file);
        let line_len = file.line_text(l.line).chars().count();
        let end = if l.end_line == l.line { l.end_column } else { line_len + 1 };
        let width = end.saturating_sub(l.column).max(1);
        let mut text = format!("{}[{}]: {}", l.severity.as_str(), l.code, l.message);
        if let Some(h) = &l.help {
            text.push_str(&format!(" (help: {h})"));
        }
        out.entry(l.file.clone()).or_default().push((l.line, l.column, width, text));
    }
    let _ = render::human;
    out
}

fn expected_text(source: &str, comment: &str, diags: &[(usize, usize, usize, String)]) -> String {
    let mut out = String::new();
    for (i, line) in source.lines().enumerate() {
        if is_expectation(line, comment) {
            continue;
        }
        out.push_str(line);
        out.push('\n');
        for (_, col, width, text) in diags.iter().filter(|d| d.0 == i + 1) {
            let carets = "^".repeat(*width);
            if *col > comment.len() {
                out.push_str(&format!(
                    "{comment}{}{carets} {text}\n",
                    " ".repeat(col - 1 - comment.len())
                ));
            } else {
                out.push_str(&format!("{comment} @{col} {carets} {text}\n"));
            }
        }
    }
    out
}

#[test]
fn syntax_tests_report_exactly_the_expected_diagnostics() {
    let mut paths = Vec::new();
    files(Path::new(ROOT), &mut paths);
    assert!(paths.len() > 20, "the syntax tests are missing");
    let results = run_all(&paths);
    let update = std::env::var("UPDATE_EXPECT").is_ok_and(|v| v == "1");
    let mut failures = Vec::new();
    for p in &paths {
        let bytes = std::fs::read(p).expect("readable");
        let utf8 = std::str::from_utf8(&bytes).is_ok();
        let source = String::from_utf8_lossy(&bytes).into_owned();
        let comment = if p.ends_with(".toml") { "#" } else { "//" };
        let want = expected_text(&source, comment, results.get(p).map_or(&[][..], |v| &v[..]));
        if want != source {
            // A file that is not UTF-8 is never rewritten (its bad byte would be lost).
            if update && utf8 {
                std::fs::write(p, &want).expect("writable");
            } else {
                failures
                    .push(format!("=== {p}\n--- expected (file)\n{source}\n--- actual\n{want}"));
            }
        }
    }
    assert!(
        failures.is_empty(),
        "{} file(s) differ (UPDATE_EXPECT=1 rewrites them):\n{}",
        failures.len(),
        failures.join("\n")
    );
}

#[test]
fn every_code_has_a_syntax_test() {
    let mut paths = Vec::new();
    files(Path::new(ROOT), &mut paths);
    let all: String = paths
        .iter()
        .map(|p| String::from_utf8_lossy(&std::fs::read(p).unwrap_or_default()).into_owned())
        .collect();
    let missing: Vec<&str> =
        codes::ALL.iter().map(|(c, _)| *c).filter(|c| !all.contains(&format!("[{c}]"))).collect();
    assert!(missing.is_empty(), "codes without a syntax test: {missing:?}");
}

#[test]
fn every_code_is_documented_with_an_example() {
    let doc =
        std::fs::read_to_string("../../docs/diagnostics.md").expect("docs/diagnostics.md exists");
    let missing: Vec<&str> =
        codes::ALL.iter().map(|(c, _)| *c).filter(|c| !doc.contains(&format!("## {c}"))).collect();
    assert!(missing.is_empty(), "codes missing from docs/diagnostics.md: {missing:?}");
}
