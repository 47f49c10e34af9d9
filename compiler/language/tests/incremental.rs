//! Parsing with reuse (`mocu_language::incremental`) gives what the parser gives, and checking
//! through it what the checker gives, over every layout of the repository, cold, warm, and
//! after random edits; and a keystroke parses only the item it changed.

#[path = "../../../benches/common/layout_corpus.rs"]
mod layout_corpus;

use mocu_language::incremental::ItemCache;
use mocu_language::passes::Module;
use mocu_language::{Config, Diagnostics, FileId, FsLoader, Schema, SourceMap, parser};
use proptest::prelude::*;
use std::path::Path;

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

/// Every layout file of the repository's corpora, by path, with its text.
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
                let text =
                    String::from_utf8_lossy(&std::fs::read(&p).expect("readable")).into_owned();
                (p, text)
            })
            .collect()
    })
}

/// The parser's tree and diagnostics of `text`, spans and all.
fn parsed(text: &str) -> (String, Vec<mocu_language::Diagnostic>) {
    let mut d = Diagnostics::new();
    let tree = parser::parse(FileId(0), text, &mut d);
    (format!("{:?}", tree.items), d.into_vec())
}

/// The same through `cache`, whose trees are given back afterwards.
fn reparsed(cache: &mut ItemCache, text: &str) -> (String, Vec<mocu_language::Diagnostic>) {
    let mut sources = SourceMap::new();
    let file = sources.add("/a.mocu".into(), text.into());
    let mut d = Diagnostics::new();
    let tree = cache.parse("/a.mocu", file, text, &mut d);
    let out = format!("{:?}", tree.items);
    let module = Module { file, path: "/a.mocu".into(), ast: tree, uses: vec![] };
    cache.recycle(vec![module], &sources);
    (out, d.into_vec())
}

#[test]
fn parse_with_reuse_equals_the_parser_on_every_corpus_file_cold_and_warm() {
    let mut cache = ItemCache::new();
    for (path, text) in corpus() {
        let want = parsed(text);
        assert_eq!(reparsed(&mut cache, text), want, "{path}, cold");
        assert_eq!(reparsed(&mut cache, text), want, "{path}, warm");
    }
}

#[test]
fn checking_through_the_cache_finds_what_the_checker_finds_in_every_layout() {
    let mut cache = ItemCache::new();
    let (schema, config) = (Schema::default(), Config::default());
    for (path, text) in corpus() {
        let (mut s1, mut d1) = (SourceMap::new(), Diagnostics::new());
        let want = mocu_language::compile_layout(
            path,
            text.clone(),
            &FsLoader,
            &schema,
            &config,
            &mut s1,
            &mut d1,
        );
        let want_diags = d1.into_vec();
        for round in ["cold", "warm"] {
            let (mut s2, mut d2) = (SourceMap::new(), Diagnostics::new());
            let got = cache.compile_layout(
                path,
                text.clone(),
                &FsLoader,
                &schema,
                &config,
                &mut s2,
                &mut d2,
            );
            assert_eq!(d2.into_vec(), want_diags, "{path}, {round}");
            assert!(got == want, "{path}, {round}: the programs differ");
        }
    }
}

#[test]
fn a_keystroke_in_a_generated_layout_parses_only_the_item_it_changed() {
    let text = layout_corpus::generate(2_000);
    let items = parser::split_items(&text).len();
    let mut cache = ItemCache::new();
    reparsed(&mut cache, &text);
    assert_eq!(cache.stats().parsed, items);
    // `let kn = 1.94384` → `let kn = 1.943845`: every item after it moves one byte.
    let edited = text.replacen("1.94384", "1.943845", 1);
    let before = cache.stats();
    assert_eq!(reparsed(&mut cache, &edited), parsed(&edited));
    let after = cache.stats();
    assert_eq!((after.parsed - before.parsed, after.reused - before.reused), (1, items - 1));
}

#[test]
fn an_unclosed_string_is_parsed_whole_and_the_trees_before_it_are_still_reused_after() {
    let text = layout_corpus::generate(300);
    let items = parser::split_items(&text).len();
    let mut cache = ItemCache::new();
    reparsed(&mut cache, &text);
    let broken = text.replacen("\"SPD\"", "\"SPD", 1).replacen("let kn", "let kn = \"", 1);
    assert_eq!(reparsed(&mut cache, &broken), parsed(&broken));
    assert_eq!(cache.stats().whole, 1);
    let before = cache.stats();
    assert_eq!(reparsed(&mut cache, &text), parsed(&text));
    assert_eq!(cache.stats().reused - before.reused, items);
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 300, failure_persistence: None, ..ProptestConfig::default() })]

    /// A file is parsed, edited (a piece of text put in place of a few bytes), parsed again
    /// with the first parse's trees, then put back and parsed a third time: each time as the
    /// parser parses it.
    #[test]
    fn an_edited_corpus_file_parses_with_reuse_as_the_parser_parses_it(
        file in 0usize..400,
        cut in 0usize..4000,
        len in 0usize..12,
        piece in proptest::sample::select(PIECES),
    ) {
        let (_, base) = &corpus()[file % corpus().len()];
        let at = floor(base, cut.min(base.len()));
        let end = floor(base, (at + len).min(base.len()));
        let text = format!("{}{piece}{}", &base[..at], &base[end..]);
        let mut cache = ItemCache::new();
        prop_assert_eq!(reparsed(&mut cache, base), parsed(base));
        prop_assert_eq!(reparsed(&mut cache, &text), parsed(&text));
        prop_assert_eq!(reparsed(&mut cache, base), parsed(base));
    }
}

const PIECES: &[&str] = &[
    "",
    "}",
    "{",
    "(",
    ")",
    "\"",
    "\n",
    " ",
    "x",
    "1",
    "// c\n",
    "/* c",
    "let a = 1\n",
    "window w { layer 1 }\n",
    "\n}\nlet",
    "if a then b else c",
    "’",
];

fn floor(s: &str, mut at: usize) -> usize {
    while !s.is_char_boundary(at) {
        at -= 1;
    }
    at
}

/// `path`'s diagnostics and program from a fresh check of `text`.
fn checked(path: &str, text: &str) -> (Vec<mocu_language::Diagnostic>, mocu_language::Program) {
    let (mut sources, mut d) = (SourceMap::new(), Diagnostics::new());
    let (schema, config) = (Schema::default(), Config::default());
    let p = mocu_language::compile_layout(
        path,
        text.into(),
        &FsLoader,
        &schema,
        &config,
        &mut sources,
        &mut d,
    );
    (d.into_vec(), p)
}

/// The same through `cache`.
fn rechecked(
    cache: &mut ItemCache,
    path: &str,
    text: &str,
) -> (Vec<mocu_language::Diagnostic>, mocu_language::Program) {
    let (mut sources, mut d) = (SourceMap::new(), Diagnostics::new());
    let (schema, config) = (Schema::default(), Config::default());
    let p =
        cache.compile_layout(path, text.into(), &FsLoader, &schema, &config, &mut sources, &mut d);
    (d.into_vec(), p)
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 64, failure_persistence: None, ..ProptestConfig::default() })]

    /// A sequence of edits (each a piece of text put in place of a few bytes of the text
    /// before it), checked one after the other through one cache as the language server
    /// checks keystrokes, gives after each edit exactly the diagnostics and the program of a
    /// fresh check of that text.
    #[test]
    fn a_sequence_of_edits_checked_through_the_cache_gives_what_a_fresh_check_gives(
        file in 0usize..400,
        edits in proptest::collection::vec(
            (0usize..4000, 0usize..8, proptest::sample::select(PIECES)),
            1..6,
        ),
    ) {
        let (path, base) = &corpus()[file % corpus().len()];
        let mut cache = ItemCache::new();
        let mut text = base.clone();
        let (d, p) = rechecked(&mut cache, path, &text);
        let (want_d, want_p) = checked(path, &text);
        prop_assert_eq!(d, want_d);
        prop_assert!(p == want_p, "{}: the programs differ before any edit", path);
        for (cut, len, piece) in edits {
            let at = floor(&text, cut.min(text.len()));
            let end = floor(&text, (at + len).min(text.len()));
            text = format!("{}{piece}{}", &text[..at], &text[end..]);
            let (d, p) = rechecked(&mut cache, path, &text);
            let (want_d, want_p) = checked(path, &text);
            prop_assert_eq!(d, want_d, "{} after an edit at {}", path, at);
            prop_assert!(p == want_p, "{}: the programs differ after an edit at {}", path, at);
        }
    }
}
