//! No input makes the checker panic, in the whole compile or in `mocu check`'s batched check:
//! random bytes, and soups of the language's own tokens (which reach far deeper into the passes
//! than random bytes do). Bounded for CI:
//! `PROPTEST_CASES` raises the count for a longer local run.

use mocu_language::{Diagnostics, MemoryLoader, SourceMap, check_path, lint_path, render};
use proptest::prelude::*;

mod common;
use common::{NESTERS, TOKENS, corpus, floor_boundary};

fn check(text: &str) {
    let loader = MemoryLoader::new()
        .with("lib.mocu", "use \"main.mocu\"\ncomponent Dial(value: number?, range: range = 0 .. 1) { circle 0 0 w }\nlet x = 1")
        .with("stdlib/gauges.mocu", "component Bar(value: number?) { rect 0 0 w h }");
    let mut sources = SourceMap::new();
    let mut diags = Diagnostics::new();
    check_path("main.mocu", text.to_string(), &loader, &mut sources, &mut diags);
    // `mocu check`'s own path (the layout read in batches) must not panic either.
    let mut lint_sources = SourceMap::new();
    let mut lint_diags = Diagnostics::new();
    lint_path("main.mocu", text.to_string(), &loader, &mut lint_sources, &mut lint_diags);
    diags.sort();
    let list = diags.into_vec();
    // Rendering walks every span: it must not panic either.
    let _ = render::human(&sources, &list);
    let _ = render::json(&sources, &list);
    let _ = render::sarif(&sources, &list);
    for d in &list {
        assert!(d.span.start <= d.span.end, "a span runs backwards: {d:?}");
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 2000, failure_persistence: None, ..ProptestConfig::default() })]

    #[test]
    fn checker_never_panics_on_random_bytes(bytes in proptest::collection::vec(any::<u8>(), 0..400)) {
        check(&String::from_utf8_lossy(&bytes));
    }

    #[test]
    fn checker_never_panics_on_token_soup(tokens in proptest::collection::vec(proptest::sample::select(TOKENS), 0..120)) {
        check(&tokens.join(" "));
    }

}

proptest! {
    // Whole files per case: fewer cases keep CI fast.
    #![proptest_config(ProptestConfig { cases: 300, failure_persistence: None, ..ProptestConfig::default() })]

    #[test]
    fn checker_never_panics_on_deep_nesting_or_long_chains(
        kind in 0usize..NESTERS.len(),
        n in 1usize..9000,
        tail in proptest::collection::vec(proptest::sample::select(TOKENS), 0..6),
    ) {
        let (open, close) = NESTERS[kind];
        check(&format!("let x = {}1{}{}\nwindow w {{ layer x }}", open.repeat(n), close.repeat(n), tail.join(" ")));
    }

    #[test]
    fn checker_never_panics_on_a_mutated_source_file(
        file in 0usize..corpus().len(),
        cut in 0usize..100_000,
        len in 0usize..40,
        insert in proptest::sample::select(TOKENS),
    ) {
        let base = &corpus()[file];
        let at = floor_boundary(base, cut % (base.len() + 1));
        let end = floor_boundary(base, (at + len).min(base.len()));
        // Delete a run of text and insert a token: unbalances brackets, strings and comments.
        check(&format!("{}{}{}", &base[..at], insert, &base[end..]));
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 2000, failure_persistence: None, ..ProptestConfig::default() })]

    #[test]
    fn checker_never_panics_on_a_mutated_layout(cut in 0usize..2000, insert in proptest::sample::select(TOKENS)) {
        let base = include_str!("../../../layouts/usv.mocu");
        let mut at = cut.min(base.len());
        while !base.is_char_boundary(at) { at -= 1; }
        check(&format!("{}{}{}", &base[..at], insert, &base[at..]));
    }
}

#[test]
fn checker_refuses_deep_nesting_without_overflowing_the_stack() {
    for text in [
        format!("let x = {}1{}", "(".repeat(3000), ")".repeat(3000)),
        format!("let x = {}1", "-".repeat(5000)),
        format!("let x = {}1", "1 + ".repeat(20000)),
        format!("let x = {}1{}", "f(".repeat(2000), ")".repeat(2000)),
        format!("let x = \"{}\"", "{\"{".repeat(500)),
        format!("let x = a{}", ".a".repeat(7000)),
        format!("let x = a{}", "[\"x\"]".repeat(7000)),
        format!("let x = f{}", "()".repeat(7000)),
        format!("let x = {}1{}", "[".repeat(100_000), "]".repeat(100_000)),
        format!("window w {{ layer {}", "{".repeat(100_000)),
        format!("let x = {}", "/*".repeat(10_000)),
        format!("let x = {}1{}", "if true then ".repeat(20_000), " else 0".repeat(20_000)),
        format!("let x = {}1", "if a then 1 else ".repeat(20_000)),
        // A script's body: its braces are the script's, and still bounded.
        format!(
            "bind keyboard {{ key n -> #js: {{ {}{} }} }}",
            "{".repeat(100_000),
            "}".repeat(100_000)
        ),
        format!("bind keyboard {{ key n -> #rhai: {{ {}", "{".repeat(100_000)),
        format!("bind keyboard {{ key n -> {}", "#js: { ".repeat(20_000)),
    ] {
        check(&text);
    }
}
