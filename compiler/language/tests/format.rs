//! `mocu fmt`'s formatter (docs/formatting.md).
//!
//! Data-driven: every `tests/format/NAME.mocu` formats to `tests/format/NAME.formatted.mocu`
//! (`UPDATE_EXPECT=1 cargo test -p mocu-language --test format` rewrites those). Over every
//! corpus (the layouts, the stdlib, the syntax tests, these cases, and mutations of them as in
//! the fuzz test): formatting twice changes nothing more, keeps every comment in order, keeps
//! the syntax tree (spans aside) and the checked program.

use mocu_language::format::{self, FormatError};
use mocu_language::{
    Config, Diagnostics, FileId, FsLoader, Schema, SourceLoader, SourceMap, compile_layout, parser,
};
use proptest::prelude::*;
use std::path::Path;

fn fmt(text: &str) -> Result<String, FormatError> {
    format::format_source(FileId(0), text, &mut Diagnostics::new())
}

fn walk(dir: &Path, out: &mut Vec<String>) {
    let Ok(rd) = std::fs::read_dir(dir) else { return };
    let mut paths: Vec<_> = rd.filter_map(|e| e.ok().map(|e| e.path())).collect();
    paths.sort();
    for p in paths {
        if p.is_dir() {
            walk(&p, out);
        } else if p.extension().is_some_and(|e| e == "mocu") {
            out.push(p.to_string_lossy().replace('\\', "/"));
        }
    }
}

/// Every layout file of the corpora (the fuzz test's seeds and these cases), by path.
fn corpus() -> &'static [(String, String)] {
    static CORPUS: std::sync::OnceLock<Vec<(String, String)>> = std::sync::OnceLock::new();
    CORPUS.get_or_init(|| {
        let mut paths = Vec::new();
        for dir in ["../../layouts", "../../stdlib", "tests/syntax", "tests/format"] {
            walk(Path::new(dir), &mut paths);
        }
        assert!(paths.len() > 40, "the corpus is missing");
        paths
            .into_iter()
            .map(|p| {
                let bytes = std::fs::read(&p).expect("readable");
                let text = String::from_utf8_lossy(&bytes).into_owned();
                (p, text)
            })
            .collect()
    })
}

/// The corpus files that parse (the others are not formatted), each with its formatting.
fn formatted() -> Vec<(&'static str, &'static str, String)> {
    let mut out = Vec::new();
    for (path, text) in corpus() {
        match fmt(text) {
            Ok(f) => out.push((path.as_str(), text.as_str(), f)),
            Err(FormatError::Syntax) => {}
            Err(e) => panic!("{path}: {e}"),
        }
    }
    assert!(out.len() > 30, "most of the corpus parses");
    out
}

#[test]
fn every_case_formats_to_its_expected_layout() {
    let update = std::env::var_os("UPDATE_EXPECT").is_some();
    let mut cases = 0;
    for (path, text) in corpus().iter().filter(|(p, _)| p.starts_with("tests/format/")) {
        let Some(stem) = path.strip_suffix(".mocu").filter(|s| !s.ends_with(".formatted")) else {
            continue;
        };
        cases += 1;
        let expected_path = format!("{stem}.formatted.mocu");
        let got = fmt(text).unwrap_or_else(|e| panic!("{path}: {e}"));
        if update {
            std::fs::write(&expected_path, &got).expect("writable");
            continue;
        }
        let expected = std::fs::read_to_string(&expected_path).expect("expected output");
        assert_eq!(got, expected, "{path} formats differently from {expected_path}");
    }
    assert!(cases >= 5, "the format cases are missing");
}

#[test]
fn formatting_twice_changes_nothing_more_over_every_corpus() {
    for (path, _, once) in formatted() {
        let twice = fmt(&once).unwrap_or_else(|e| panic!("{path}, formatted: {e}"));
        assert_eq!(twice, once, "{path}: formatting its formatted text changed it");
    }
}

#[test]
fn formatting_keeps_every_comment_in_order_over_every_corpus() {
    for (path, text, out) in formatted() {
        assert_eq!(format::comments(&out), format::comments(text), "{path}");
    }
}

#[test]
fn formatting_keeps_the_syntax_tree_over_every_corpus() {
    for (path, text, out) in formatted() {
        let before = parser::parse(FileId(0), text, &mut Diagnostics::new());
        let mut diags = Diagnostics::new();
        let after = parser::parse(FileId(0), &out, &mut diags);
        assert!(diags.is_empty(), "{path}: the formatted file has diagnostics");
        assert_eq!(format::tree_shape(&after), format::tree_shape(&before), "{path}");
    }
}

/// The file system, with one file's text replaced.
struct Overlay<'a> {
    path: &'a str,
    text: &'a str,
}

impl SourceLoader for Overlay<'_> {
    fn resolve(&self, from: &str, spec: &str) -> Option<String> {
        FsLoader.resolve(from, spec)
    }
    fn read(&self, path: &str) -> Result<String, String> {
        if path == self.path { Ok(self.text.to_string()) } else { FsLoader.read(path) }
    }
}

/// The checked program of `path` written as `text` (spans aside), and its diagnostics' codes
/// and messages.
fn checked(path: &str, text: &str) -> (String, Vec<String>) {
    let mut sources = SourceMap::new();
    let mut diags = Diagnostics::new();
    let loader = Overlay { path, text };
    let program = compile_layout(
        path,
        text.to_string(),
        &loader,
        &Schema::default(),
        &Config::default(),
        &mut sources,
        &mut diags,
    );
    let mut found: Vec<String> =
        diags.into_vec().iter().map(|d| format!("{} {}", d.code, d.message)).collect();
    found.sort();
    (format::without_spans(&format!("{program:?}")), found)
}

#[test]
fn formatting_keeps_the_checked_program_and_its_findings_over_every_corpus() {
    for (path, text, out) in formatted() {
        let before = checked(path, text);
        let after = checked(path, &out);
        assert_eq!(after.1, before.1, "{path}: other diagnostics");
        assert!(after.0 == before.0, "{path}: another checked program");
    }
}

#[test]
fn a_file_with_syntax_errors_is_not_formatted_and_its_errors_are_reported() {
    let mut diags = Diagnostics::new();
    let got = format::format_source(FileId(0), "let a = (1 +\nwindow w {  }\n", &mut diags);
    assert_eq!(got, Err(FormatError::Syntax));
    assert!(diags.count(mocu_language::Severity::Error) > 0);
}

#[test]
fn an_empty_file_stays_empty_and_a_file_ends_with_one_line_break() {
    assert_eq!(fmt("").unwrap(), "");
    assert_eq!(fmt("\n\n  \n").unwrap(), "");
    assert_eq!(fmt("let a = 1\n\n\n").unwrap(), "let a = 1\n");
}

#[test]
fn a_byte_order_mark_is_kept_and_windows_line_ends_become_unix_ones() {
    let got = fmt("\u{FEFF}let a = 1\r\n\r\n\r\n/* x\r\n y */\r\nlet b = 2\r\n").unwrap();
    assert_eq!(got, "\u{FEFF}let a = 1\n\n/* x\n y */\nlet b = 2\n");
}

#[test]
fn a_call_and_a_value_followed_by_parentheses_stay_apart() {
    // `f(x)` calls f; in a primitive's arguments `f (x)` is two arguments.
    let src = "component C(f: number) {\n  text f (f) f(1)   size 2\n}\n";
    assert_eq!(fmt(src).unwrap(), "component C(f: number) {\n    text f (f) f(1) size 2\n}\n");
}

// Mutations of corpus files, as in tests/fuzz.rs: whatever still parses formats to a file
// that parses to the same tree, and formatting it again changes nothing.
const PIECES: &[&str] = &[
    "{",
    "}",
    "(",
    ")",
    "\n",
    " ",
    "-",
    "!",
    "// c\n",
    "/* c */",
    ",",
    "->",
    "..",
    "\"s {x}\"",
    "let a = 1\n",
    "if a then b else c",
    "x",
    "1",
    "#ff0000",
    "on press call x()",
];

proptest! {
    #![proptest_config(ProptestConfig { cases: 300, failure_persistence: None, ..ProptestConfig::default() })]

    #[test]
    fn a_mutated_corpus_file_that_parses_formats_idempotently_and_keeps_its_tree(
        file in 0usize..400,
        cut in 0usize..4000,
        len in 0usize..12,
        piece in proptest::sample::select(PIECES),
    ) {
        let (_, base) = &corpus()[file % corpus().len()];
        let at = floor(base, cut.min(base.len()));
        let end = floor(base, (at + len).min(base.len()));
        let text = format!("{}{piece}{}", &base[..at], &base[end..]);
        match fmt(&text) {
            Ok(once) => {
                prop_assert_eq!(fmt(&once), Ok(once.clone()));
                prop_assert_eq!(format::comments(&once), format::comments(&text));
            }
            Err(FormatError::Syntax) => {}
            Err(e) => prop_assert!(false, "{e}\n--- input ---\n{text}"),
        }
    }
}

fn floor(s: &str, mut at: usize) -> usize {
    while !s.is_char_boundary(at) {
        at -= 1;
    }
    at
}
