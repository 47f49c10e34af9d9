//! `cargo run --release -p mocu-language --example check_speed -- LINES`: checks the generated
//! layout of benches/check.rs (LINES lines) and a byte scan of the same text, and prints the
//! median time of each and the node count. Peak memory: run it under `/usr/bin/time -v`.
//! (The criterion bench is `cargo bench --bench check`; this is the light, single-crate form.)
use std::time::Instant;

#[path = "../../../benches/common/layout_corpus.rs"]
mod layout_corpus;
use layout_corpus::generate;

fn main() {
    let lines: usize = std::env::args().nth(1).and_then(|a| a.parse().ok()).unwrap_or(10_000);
    let text = generate(lines);
    let loader = mocu_language::MemoryLoader::new()
        .with("stdlib/gauges.mocu", include_str!("../../../stdlib/gauges.mocu"))
        .with("stdlib/theme.mocu", include_str!("../../../stdlib/theme.mocu"));
    let runs = if lines > 50_000 { 3 } else { 11 };
    let mut scan = Vec::new();
    let mut check = Vec::new();
    let mut parse = Vec::new();
    for _ in 0..runs {
        let t = Instant::now();
        let n = text.bytes().fold(0usize, |a, b| a + usize::from(b == b'\n' || b == b'{'));
        std::hint::black_box(n);
        scan.push(t.elapsed().as_secs_f64() * 1e3);
        let t = Instant::now();
        let mut sources = mocu_language::SourceMap::new();
        let mut diags = mocu_language::Diagnostics::new();
        let b = mocu_language::check_path(
            "bench.mocu",
            text.clone(),
            &loader,
            &mut sources,
            &mut diags,
        );
        check.push(t.elapsed().as_secs_f64() * 1e3);
        assert!(!diags.has_errors(), "{:?}", diags.iter().next());
        std::hint::black_box(b);
        let t = Instant::now();
        let mut diags = mocu_language::Diagnostics::new();
        let tree = mocu_language::parser::parse(mocu_language::FileId(0), &text, &mut diags);
        parse.push(t.elapsed().as_secs_f64() * 1e3);
        std::hint::black_box(tree);
    }
    parse.sort_by(f64::total_cmp);
    scan.sort_by(f64::total_cmp);
    check.sort_by(f64::total_cmp);
    println!(
        "{lines} lines, {} bytes: byte scan {:.3} ms, check {:.1} ms (of which parsing {:.1} ms; median of {runs}), ratio {:.0}x",
        text.len(),
        scan[runs / 2],
        check[runs / 2],
        parse[runs / 2],
        check[runs / 2] / scan[runs / 2]
    );
}
