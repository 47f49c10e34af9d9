//! `mocu fmt` on generated layouts of 1,000 and 10,000 lines (the check bench's corpus), each
//! against parsing the same text once: the formatter parses twice (to read the file, and to
//! prove that its output parses to the same tree), so about twice the parse is its floor.
//! `format_tidy`: the same layout already formatted (what `mocu fmt --check` meets in CI).
//! `cargo bench --bench fmt`; figures: docs/formatting.md ("Speed").

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use mocu_language::format::{FormatError, format_source};
use mocu_language::{Diagnostics, FileId, parser};
use std::hint::black_box;

#[path = "common/layout_corpus.rs"]
mod layout_corpus;
use layout_corpus::generate;

fn fmt(text: &str) -> Result<String, FormatError> {
    format_source(FileId(0), text, &mut Diagnostics::new())
}

fn bench(c: &mut Criterion) {
    for lines in [1_000, 10_000] {
        let text = generate(lines);
        let tidy = fmt(&text).expect("the generated layout formats");
        assert_eq!(fmt(&tidy).as_ref(), Ok(&tidy), "formatting is idempotent");
        let mut g = c.benchmark_group(format!("fmt_{lines}_lines"));
        g.throughput(Throughput::Bytes(text.len() as u64));
        g.bench_function("format", |b| b.iter(|| black_box(fmt(black_box(&text)))));
        g.bench_function("format_tidy", |b| b.iter(|| black_box(fmt(black_box(&tidy)))));
        g.bench_function("parse_once", |b| {
            b.iter(|| {
                black_box(parser::parse(FileId(0), black_box(&text), &mut Diagnostics::new()))
            })
        });
        g.finish();
    }
}

criterion_group!(benches, bench);
criterion_main!(benches);
