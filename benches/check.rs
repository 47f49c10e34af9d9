//! Checking generated layouts of 1,000, 10,000 and 100,000 lines as `mocu check` does
//! (`lint_path`; issue 13 target: 10,000 lines in ≤ 50 ms), and building their programs too as
//! `mocu run` and `mocu build` do (`check_path`), each against a baseline that scans every
//! byte of the same text once (the floor any checker pays), so the figures read as ratios.
//! `cargo bench --bench check`; criterion prints MB/s for both. Figures: docs/diagnostics.md ("Limits and cost").
//!
//! `lets_*`: `let`s are shared, not copied (issue 13): chains of 5,000 and 50,000 `let`s each
//! built on the one before, and 60 doubling ones (`let a1 = a0 + a0`, …), each against a
//! baseline of as many independent `let`s (each built on `a0` only), in the same run.

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use mocu_language::{Diagnostics, SourceMap};
use std::hint::black_box;

#[path = "common/layout_corpus.rs"]
mod layout_corpus;
use layout_corpus::generate;

/// The baseline: one pass over every byte (newlines and brackets counted).
fn byte_scan(text: &str) -> (usize, usize) {
    text.bytes().fold((0, 0), |(lines, brackets), b| {
        (lines + usize::from(b == b'\n'), brackets + usize::from(matches!(b, b'{' | b'(')))
    })
}

fn bench(c: &mut Criterion) {
    for lines in [1_000, 10_000, 100_000] {
        bench_size(c, lines);
    }
    for (name, n, twice) in
        [("chain_5k", 5_000, false), ("chain_50k", 50_000, false), ("doubling_60", 60, true)]
    {
        bench_lets(c, name, n, twice);
    }
}

/// `n` `let`s after `a0`, each naming the one before (twice when `twice`), or (`chained`
/// false) each naming `a0` only; a label shows the last.
fn lets_layout(n: usize, chained: bool, twice: bool) -> String {
    let mut t = String::from("use \"stdlib/gauges.mocu\"\nlet a0 = root.vehicles.usv1.nav.speed\n");
    for i in 1..=n {
        let prev = if chained { format!("a{}", i - 1) } else { "a0".into() };
        let rhs = if twice { prev.clone() } else { "1".into() };
        t.push_str(&format!("let a{i} = {prev} + {rhs}\n"));
    }
    t.push_str("window hud { layer 1  rect 0 0 100 100 }\n");
    t.push_str(&format!("in hud {{ Label {{ at 0 0  text \"{{a{n}}}\" }} }}\n"));
    t
}

fn bench_lets(c: &mut Criterion, name: &str, n: usize, twice: bool) {
    let loader = layout_corpus::stdlib_loader();
    let check = |text: &String| {
        let mut sources = SourceMap::new();
        let mut diags = Diagnostics::new();
        let bundle =
            mocu_language::check_path("lets.mocu", text.clone(), &loader, &mut sources, &mut diags);
        assert!(!diags.has_errors(), "{:?}", diags.iter().next());
        black_box(bundle)
    };
    let (baseline, lets) = (lets_layout(n, false, twice), lets_layout(n, true, twice));
    let mut g = c.benchmark_group(format!("lets_{name}"));
    g.sample_size(10);
    g.bench_function("baseline_independent_lets", |b| b.iter(|| check(&baseline)));
    g.bench_function("check", |b| b.iter(|| check(&lets)));
    g.finish();
}

fn bench_size(c: &mut Criterion, lines: usize) {
    let text = generate(lines);
    let loader = layout_corpus::stdlib_loader();
    let mut g = c.benchmark_group(format!("check_{}k_lines", lines / 1000));
    g.throughput(Throughput::Bytes(text.len() as u64));
    g.sample_size(10);
    g.bench_function("baseline_byte_scan", |b| b.iter(|| byte_scan(black_box(&text))));
    g.bench_function("check", |b| {
        b.iter(|| {
            let mut sources = SourceMap::new();
            let mut diags = Diagnostics::new();
            mocu_language::lint_path("bench.mocu", text.clone(), &loader, &mut sources, &mut diags);
            assert!(!diags.has_errors());
            black_box((sources, diags))
        })
    });
    g.bench_function("compile", |b| {
        b.iter(|| {
            let mut sources = SourceMap::new();
            let mut diags = Diagnostics::new();
            let bundle = mocu_language::check_path(
                "bench.mocu",
                text.clone(),
                &loader,
                &mut sources,
                &mut diags,
            );
            assert!(!diags.has_errors());
            black_box(bundle)
        })
    });
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
