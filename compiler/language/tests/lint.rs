//! Architecture Invariant: `mocu check`'s batched check (`mocu_language::lint`) reports exactly
//! what the whole compile (`compile_layout`) reports, for every file of the corpus and for
//! mutations of them, in batches of one item, of a few and of the default size; with and
//! without the shipped project's schemas.

use mocu_language::lint::{BATCH_BYTES, lint_layout_in_batches};
use mocu_language::{Config, Diagnostics, FsLoader, Schema, SourceMap, compile_layout};
use proptest::prelude::*;

mod common;
use common::{TOKENS, floor_boundary};
#[path = "../../../benches/common/layout_corpus.rs"]
mod layout_corpus;

/// Every `.mocu` file of the corpus (as `common::corpus`), with its path: `use`s are read
/// from the file system, relative to it.
fn files() -> &'static [(String, String)] {
    static FILES: std::sync::OnceLock<Vec<(String, String)>> = std::sync::OnceLock::new();
    FILES.get_or_init(|| {
        let mut out = Vec::new();
        for dir in [
            "../../layouts",
            "../../stdlib",
            "../../examples",
            "tests/syntax",
            "tests/format",
            "../../tests",
            "../../runtime/widgets/tests",
        ] {
            walk(std::path::Path::new(dir), "mocu", &mut out);
        }
        assert!(out.len() > 40, "the corpus is missing: {} files", out.len());
        out
    })
}

/// The files under `dir` whose extension is `ext`, with their paths, in path order.
fn walk(dir: &std::path::Path, ext: &str, out: &mut Vec<(String, String)>) {
    let Ok(rd) = std::fs::read_dir(dir) else { return };
    let mut paths: Vec<_> = rd.filter_map(|e| e.ok().map(|e| e.path())).collect();
    paths.sort();
    for p in paths {
        if p.is_dir() {
            walk(&p, ext, out);
        } else if p.extension().is_some_and(|e| e == ext) {
            let bytes = std::fs::read(&p).unwrap_or_default();
            let path = p.to_string_lossy().replace('\\', "/");
            out.push((path, String::from_utf8_lossy(&bytes).into_owned()));
        }
    }
}

/// The shipped project's schemas (layouts/project.toml).
fn project_schema() -> &'static Schema {
    static SCHEMA: std::sync::OnceLock<Schema> = std::sync::OnceLock::new();
    SCHEMA.get_or_init(|| {
        let mut sources = SourceMap::new();
        let mut diags = Diagnostics::new();
        let project = mocu_language::project_of(
            "../../layouts/x.mocu",
            None,
            &FsLoader,
            &mut sources,
            &mut diags,
        )
        .expect("layouts/project.toml");
        assert!(!project.schema.is_empty(), "the project's schema is empty");
        project.schema
    })
}

/// What a user would read: the diagnostics, sorted and without repeats, each in full.
fn seen(sources: &SourceMap, mut diags: Diagnostics) -> Vec<String> {
    diags.sort();
    let mut out: Vec<String> =
        diags.iter().map(|d| format!("{} {:?}", sources.get(d.span.file).path, d)).collect();
    out.sort();
    out.dedup();
    out
}

fn compiled(path: &str, text: &str, schema: &Schema) -> Vec<String> {
    let mut sources = SourceMap::new();
    let mut diags = Diagnostics::new();
    let config = Config::default();
    compile_layout(path, text.into(), &FsLoader, schema, &config, &mut sources, &mut diags);
    seen(&sources, diags)
}

fn linted(path: &str, text: &str, schema: &Schema, batch: usize) -> Vec<String> {
    let mut sources = SourceMap::new();
    let mut diags = Diagnostics::new();
    let config = Config::default();
    lint_layout_in_batches(
        path,
        text.into(),
        &FsLoader,
        schema,
        &config,
        &mut sources,
        &mut diags,
        batch,
    );
    seen(&sources, diags)
}

fn assert_same(path: &str, text: &str, schema: &Schema, batches: &[usize]) {
    let want = compiled(path, text, schema);
    for &batch in batches {
        let got = linted(path, text, schema, batch);
        assert_eq!(got, want, "{path}: in batches of {batch} bytes, `mocu check` differs");
    }
}

#[test]
fn check_in_batches_reports_what_the_whole_compile_reports_for_every_corpus_file() {
    let none = Schema::default();
    for (path, text) in files() {
        assert_same(path, text, &none, &[1, 300, BATCH_BYTES]);
        assert_same(path, text, project_schema(), &[1, BATCH_BYTES]);
    }
}

#[test]
fn checking_a_profile_in_batches_reports_what_compiling_it_reports() {
    let mut profiles = Vec::new();
    for dir in ["../../layouts", "../../examples", "tests/syntax", "../../tests"] {
        walk(std::path::Path::new(dir), "toml", &mut profiles);
    }
    let profiles: Vec<_> = profiles
        .into_iter()
        .filter(|(p, t)| mocu_language::file_kind(p, t) == mocu_language::FileKind::Profile)
        .collect();
    assert!(profiles.len() >= 5, "too few profiles: {}", profiles.len());
    for (path, text) in &profiles {
        let mut sources = SourceMap::new();
        let mut diags = Diagnostics::new();
        mocu_language::check_profile(path, text.clone(), &FsLoader, &mut sources, &mut diags);
        let want = seen(&sources, diags);
        let mut sources = SourceMap::new();
        let mut diags = Diagnostics::new();
        mocu_language::lint_profile(path, text.clone(), &FsLoader, &mut sources, &mut diags);
        assert_eq!(seen(&sources, diags), want, "{path}: `mocu check` differs");
    }
}

#[test]
fn check_in_batches_reports_what_the_whole_compile_reports_for_a_large_layout() {
    let text = layout_corpus::generate(2_000);
    // A few mistakes spread over the file, for diagnostics in many batches.
    let text = text
        .replace("let v7 = root", "let v7 = rot")
        .replace("watch low9 ", "watch low3 ")
        .replace("value v11.fuel ?? 0", "value v11.fuel ?? \"x\"")
        .replace("key f5 -> set", "key f5 -> mode nav  set");
    let dir = "../../layouts/generated.mocu";
    assert_same(dir, &text, &Schema::default(), &[1, 4096, BATCH_BYTES]);
    assert_same(dir, &text, project_schema(), &[BATCH_BYTES]);
    assert!(compiled(dir, &text, &Schema::default()).len() >= 4, "the mistakes were not seen");
}

#[test]
fn what_spans_batches_is_carried_from_one_to_the_next() {
    // Each item in its own batch: names used before they are defined, a watch named twice,
    // a mode used before the `bind` that declares it and one nobody declares, unused lets
    // in a component and at the top, a component used before its definition, a widget
    // outside its window.
    let text = r#"use "stdlib/gauges.mocu"
watch low { when v.fuel < 0.1 then mode nav }
in hud {
  Gauge2 { at 500 500 10 10  value v.fuel }
  Dial { at 0 0 10 10  value v.nav.speed  range 0 .. 40 }
}
menu for type "vehicle" { item "Stop" -> mode fast }
component Gauge2(value: number?) {
  let unused_inside = 1
  let f = value ?? 0
  rect 0 0 (w * f) h
}
watch low { when v.fuel < 0.2 then alert warning "twice" }
let v = root.vehicles.usv1
let never = 3
window hud { layer 1  rect 0 0 100 100 }
bind keyboard {
  mode nav { key n -> set v.nav.goal_throttle = 1 }
}
"#;
    let dir = "../../layouts/carried.mocu";
    let want = compiled(dir, text, &Schema::default());
    for needle in ["E0203", "E0212", "W0001", "W0002"] {
        assert!(want.iter().any(|d| d.contains(needle)), "no {needle} in {want:#?}");
    }
    assert_same(dir, text, &Schema::default(), &[1, 64, BATCH_BYTES]);
    assert_same(dir, text, project_schema(), &[1]);
}

#[test]
fn a_used_file_that_uses_the_layout_back_sees_its_components_and_lets() {
    // lib.mocu uses the layout back (a cycle, reported once); the layout's component takes
    // its default from lib.mocu's `let`, and its body, read only later by the batched
    // check, has an unused `let`; widgets use both files' components.
    let lib = "use \"main.mocu\"\ncomponent Pip(value: number?) { circle 0 0 (w * (value ?? 0)) }\nlet shared = 2\n";
    let main = "use \"lib.mocu\"\ncomponent Mark(value: number?, size: number = shared) {\n  let unused = 1\n  circle 0 0 (size)\n}\nwindow w { layer 1  rect 0 0 100 100 }\nin w { Pip { at 0 0 10 10  value 1 }  Mark { at 0 0 10 10  value \"x\" } }\n";
    let loader = mocu_language::MemoryLoader::new().with("lib.mocu", lib).with("main.mocu", main);
    let config = Config::default();
    let none = Schema::default();
    let mut sources = SourceMap::new();
    let mut diags = Diagnostics::new();
    compile_layout("main.mocu", main.into(), &loader, &none, &config, &mut sources, &mut diags);
    let want = seen(&sources, diags);
    for code in ["E0202", "E0301", "W0001"] {
        assert!(want.iter().any(|d| d.contains(code)), "no {code} in {want:#?}");
    }
    for batch in [1, BATCH_BYTES] {
        let mut sources = SourceMap::new();
        let mut diags = Diagnostics::new();
        lint_layout_in_batches(
            "main.mocu",
            main.into(),
            &loader,
            &none,
            &config,
            &mut sources,
            &mut diags,
            batch,
        );
        assert_eq!(seen(&sources, diags), want, "in batches of {batch} bytes");
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 200, failure_persistence: None, ..ProptestConfig::default() })]

    #[test]
    fn check_in_batches_agrees_with_the_whole_compile_on_mutated_files(
        file in 0usize..files().len(),
        cut in 0usize..100_000,
        len in 0usize..40,
        insert in proptest::sample::select(TOKENS),
        batch in proptest::sample::select(&[1usize, 64, BATCH_BYTES][..]),
        schema in any::<bool>(),
    ) {
        let (path, base) = &files()[file];
        let at = floor_boundary(base, cut % (base.len() + 1));
        let end = floor_boundary(base, (at + len).min(base.len()));
        let text = format!("{}{}{}", &base[..at], insert, &base[end..]);
        let none = Schema::default();
        let schema = if schema { project_schema() } else { &none };
        let want = compiled(path, &text, schema);
        let got = linted(path, &text, schema, batch);
        prop_assert_eq!(got, want);
    }
}
