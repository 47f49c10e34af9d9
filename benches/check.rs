//! Checking generated layouts of 1,000, 10,000 and 100,000 lines (issue 13 target: 10,000
//! lines in ≤ 50 ms), each against a baseline that scans every byte of the same text once
//! (the floor any checker pays), so the figures read as ratios.
//! `cargo bench --bench check`; criterion prints MB/s for both. Figures: docs/diagnostics.md ("Limits and cost").

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use mocu_language::{Diagnostics, MemoryLoader, SourceMap};
use std::hint::black_box;

/// A layout of `lines` lines: stdlib-like components, windows, widgets, bindings, watches.
fn generate(lines: usize) -> String {
    let mut s = String::from("use \"stdlib/gauges.mocu\"\nlet kn = 1.94384\n");
    let mut i = 0;
    let mut count = 2;
    while count < lines {
        let block = format!(
            "let v{i} = root.vehicles.usv{i}\n\
             window w{i} {{ layer {i}  rect 0 0 400 300  opacity 0.9 }}\n\
             in w{i} {{\n\
             \x20 speed{i}: Dial {{ at 10 10 100 100  value v{i}.nav.speed * kn  range 0 .. 40  alarm value > 35 }}\n\
             \x20 fuel{i}: Bar {{ at 10 120 100 16  value v{i}.fuel ?? 0  warn value < 0.2 }}\n\
             \x20 hdg{i}: Label {{ at 10 140  text \"HDG {{v{i}.nav.heading:03.0}}° {{v{i}.name ?? \"?\"}}\" }}\n\
             }}\n\
             component C{i}(value: number?, max: number = 1) {{\n\
             \x20 let f = clamp((value ?? 0) / max, 0, 1)\n\
             \x20 rounded 0 0 w h 3  fill #141c24  stroke #3a4a5a\n\
             \x20 rect 1 1 ((w - 2) * f) (h - 2)  fill if f < 0.2 then #f59e0b else #22c55e\n\
             }}\n\
             watch low{i} {{ when v{i}.fuel < 0.15 for 5s then alert warning \"Fuel low on {{v{i}.name}}\" }}\n\
             bind keyboard {{ key f{k} -> set v{i}.nav.goal_throttle = 10  call v{i}.stop() }}\n",
            k = i % 12 + 1
        );
        count += block.lines().count();
        s.push_str(&block);
        i += 1;
    }
    s
}

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
