//! The fast parser (parser/fast.rs) against the reference parser (grammar.pest): for every
//! item it accepts, the same tree, spans included; and it never accepts an item the reference
//! refuses (ARCHITECTURE.md, "Architecture Invariants"). Every item of the shipped layouts and
//! of the speed benchmark's layout takes the fast path.

mod common;

use common::{NESTERS, TOKENS, corpus, floor_boundary};
use mocu_language::parser::{
    ChunkKind, ParseCounts, fast_item, parse_counted, reference_item, split_items,
};
use mocu_language::{Diagnostics, FileId};
use proptest::prelude::*;

#[path = "../../../benches/common/layout_corpus.rs"]
mod layout_corpus;

/// Compares the two parsers on every item of `text`; returns how many items the fast parser
/// read and how many there were.
fn same_trees(text: &str) -> (usize, usize) {
    let (mut fast, mut all) = (0, 0);
    for chunk in split_items(text) {
        if chunk.kind != ChunkKind::Item {
            continue;
        }
        all += 1;
        let src = &text[chunk.start..chunk.end];
        let Some(tree) = fast_item(FileId(0), src, chunk.start) else { continue };
        fast += 1;
        match reference_item(FileId(0), src, chunk.start) {
            Some(reference) => {
                assert!(
                    tree == reference,
                    "the trees differ for\n{src}\nfast: {tree:#?}\nreference: {reference:#?}"
                )
            }
            None => panic!("the fast parser accepts an item the reference refuses:\n{src}"),
        }
    }
    (fast, all)
}

#[test]
fn fast_parser_builds_the_reference_tree_for_every_item_of_every_mocu_file() {
    let mut items = 0;
    for text in corpus() {
        items += same_trees(text).1;
    }
    assert!(items > 300, "the corpus has only {items} items");
}

#[test]
fn fast_parser_reads_every_item_of_the_shipped_layouts_and_stdlib() {
    let mut texts = Vec::new();
    for dir in ["../../layouts", "../../stdlib"] {
        common::walk(std::path::Path::new(dir), &mut texts);
    }
    assert!(texts.len() >= 5, "layouts and stdlib are missing");
    for text in &texts {
        let (fast, all) = same_trees(text);
        assert_eq!(fast, all, "items left to pest in\n{text}");
    }
}

#[test]
fn parse_takes_the_fast_path_for_every_item_of_the_shipped_layouts() {
    let mut texts = Vec::new();
    common::walk(std::path::Path::new("../../layouts"), &mut texts);
    common::walk(std::path::Path::new("../../stdlib"), &mut texts);
    let mut total = ParseCounts::default();
    for text in &texts {
        let mut diags = Diagnostics::new();
        let (tree, counts) = parse_counted(FileId(0), text, &mut diags);
        assert!(!diags.has_errors(), "{:?}", diags.iter().next());
        assert_eq!(counts.fast, tree.items.len());
        total.fast += counts.fast;
        total.reference += counts.reference;
    }
    assert_eq!(total.reference, 0, "items of the shipped layouts parsed by pest");
    assert!(total.fast > 50, "only {} items", total.fast);
}

#[test]
fn parse_leaves_a_broken_item_to_pest_and_reads_the_rest_fast() {
    let text = "let a = 1\nwindow w { rect 0 0 }\nlet b = a + 1\n";
    let mut diags = Diagnostics::new();
    let (tree, counts) = parse_counted(FileId(0), text, &mut diags);
    assert_eq!(counts, ParseCounts { fast: 2, reference: 1 });
    assert_eq!(tree.items.len(), 2);
    let first = diags.iter().next().map(|d| d.message.clone()).unwrap_or_default();
    assert!(first.starts_with("expected"), "pest's message: {first}");
}

#[test]
fn fast_parser_reads_every_item_of_the_benchmark_layout() {
    let text = layout_corpus::generate(3000);
    let (fast, all) = same_trees(&text);
    assert!(all > 50);
    assert_eq!(fast, all);
}

#[test]
fn fast_parser_agrees_on_pest_quirks() {
    // Spans that end after whitespace (a rule ending in an unmatched `x?` or `x*`), literals
    // with no word boundary, postfixes after an `if`, comments everywhere.
    for text in [
        "in hud { w: Dial { at 1 2 /* c */ on press set a = 1 \n value 3 } }",
        "component C(a, b: int?, c = 3 , on press,) { circle 0 0 1 // x\n rect 0 0 1 1 fill #ff0000 }",
        "watch w { whenx > 3 for 5s then alert warning \"x{a:.1}\" }",
        "let a = if a then b else c .x",
        "let a = - - not !x.y[\"k\"](1, 2,) ?? b ?? c + 1 * 2 .. 3 or d and e == f",
        "let a = 5.x + 1..2 + 3min + #ff00ff80 + \"a{{b}}\\n{c}\"",
        "bind pad { shift left_bumper axis left_y deadzone 0.1 invert -> set a = 1 mode drive { shift button west hold -5 -> mode x } }",
        "menu for type \"usv\" { item \"Arm\" enabled a -> call arm() select next item \"b\" -> swap a b 5s }",
        "for each v in root.vehicles of type \"usv\" { window w { rect 0 0 -5 (10) anchor bottom-right layer 1 } in w { Label { } } }",
        "for each v in root.x flow down rect 1 2 -3 (4) { window w { } }",
        "for each v in root.x of type \"usv\" flow right rect 0 8 100% 120 anchor bottom /* c */ gap 8px{ }",
        "for each v in root.x flow down rect 1 2 3 4 gap 10 { }",
        "for each flow in root.x flow flow rect 1 2 3 4 anchor top-left{ }",
        "use \"x{y}.mocu\" assoc",
        "design 1280 x 720",
        "window w { rectangle 5 at 1 }",
    ] {
        let (fast, all) = same_trees(text);
        assert_eq!((fast, all), (1, 1), "not read by the fast parser: {text}");
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 1000, failure_persistence: None, ..ProptestConfig::default() })]

    #[test]
    fn fast_parser_agrees_on_token_soup(tokens in proptest::collection::vec(proptest::sample::select(TOKENS), 0..60)) {
        same_trees(&tokens.join(" "));
    }

    #[test]
    fn fast_parser_agrees_on_a_mutated_file(
        file in 0usize..corpus().len(),
        cut in 0usize..100_000,
        len in 0usize..40,
        insert in proptest::sample::select(TOKENS),
    ) {
        let base = &corpus()[file];
        let at = floor_boundary(base, cut % (base.len() + 1));
        let end = floor_boundary(base, (at + len).min(base.len()));
        same_trees(&format!("{}{}{}", &base[..at], insert, &base[end..]));
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 200, failure_persistence: None, ..ProptestConfig::default() })]

    #[test]
    fn fast_parser_agrees_on_deep_nesting_and_long_chains(
        kind in 0usize..NESTERS.len(),
        n in 1usize..600,
        tail in proptest::collection::vec(proptest::sample::select(TOKENS), 0..6),
    ) {
        let (open, close) = NESTERS[kind];
        same_trees(&format!("let x = {}1{}{}\nwindow w {{ layer x }}", open.repeat(n), close.repeat(n), tail.join(" ")));
    }
}

#[test]
fn fast_parser_leaves_long_chains_to_pest_without_overflowing() {
    for text in [
        format!("let x = a{}", ".a".repeat(7000)),
        format!("let x = {}1", "not ".repeat(7000)),
        format!("let x = {}1", "-".repeat(7000)),
        format!("let x = {}1", "1 + ".repeat(7000)),
        format!("let x = {}1", "if a then 1 else ".repeat(7000)),
        format!("let x = f{}", "()".repeat(7000)),
    ] {
        assert!(fast_item(FileId(0), &text, 0).is_none());
    }
    // At the limit of the tree builder: read, and the same tree.
    let text = format!("let x = a{}", ".a".repeat(255));
    assert_eq!(same_trees(&text), (1, 1));
}
