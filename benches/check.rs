//! Checking generated layouts of 1,000, 10,000 and 100,000 lines (issue 13 target: 10,000
//! lines in ≤ 50 ms), each against a baseline that scans every byte of the same text once
//! (the floor any checker pays), so the figures read as ratios.
//! `cargo bench --bench check`; criterion prints MB/s for both. Figures: docs/diagnostics.md ("Limits and cost").

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use mocu_language::{Diagnostics, MemoryLoader, SourceMap};
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
}

fn bench_size(c: &mut Criterion, lines: usize) {
    let text = generate(lines);
    let loader = MemoryLoader::new()
        .with("stdlib/gauges.mocu", include_str!("../stdlib/gauges.mocu"))
        .with("stdlib/theme.mocu", include_str!("../stdlib/theme.mocu"));
    let mut g = c.benchmark_group(format!("check_{}k_lines", lines / 1000));
    g.throughput(Throughput::Bytes(text.len() as u64));
    g.sample_size(10);
    g.bench_function("baseline_byte_scan", |b| b.iter(|| byte_scan(black_box(&text))));
    g.bench_function("check", |b| {
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
