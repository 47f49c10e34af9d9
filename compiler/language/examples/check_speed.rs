//! `cargo run --release -p mocu-language --example check_speed -- LINES`: checks the generated
//! layout of benches/check.rs (LINES lines) as `mocu check` does (`lint_path`), builds its
//! program as `mocu run` and `mocu build` do (`check_path`), and scans the same text byte by
//! byte, alternately, and prints the median CPU time of each (this thread's run time from
//! /proc/thread-self/schedstat on Linux, so that other processes on the machine count less;
//! wall time elsewhere). Peak memory: `examples/check_memory.rs` (its allocator shim would
//! slow these). (The criterion bench is `cargo bench --bench check`; this is the light,
//! single-crate form.)
use std::time::Instant;

/// Milliseconds of CPU this thread has used (wall-clock milliseconds where /proc has none).
fn now_ms(start: Instant) -> f64 {
    std::fs::read_to_string("/proc/thread-self/schedstat")
        .ok()
        .and_then(|s| s.split_whitespace().next()?.parse::<f64>().ok())
        .map_or_else(|| start.elapsed().as_secs_f64() * 1e3, |ns| ns / 1e6)
}

#[path = "../../../benches/common/layout_corpus.rs"]
mod layout_corpus;
use layout_corpus::generate;

fn main() {
    let lines: usize = std::env::args().nth(1).and_then(|a| a.parse().ok()).unwrap_or(10_000);
    let text = generate(lines);
    let loader = layout_corpus::stdlib_loader();
    let runs = if lines > 50_000 { 3 } else { 11 };
    let mut scan = Vec::new();
    let mut check = Vec::new();
    let mut parse = Vec::new();
    let mut compile = Vec::new();
    let origin = Instant::now();
    let clock = || now_ms(origin);
    for _ in 0..runs {
        // Far shorter than the CPU clock's tick: wall time.
        let t = Instant::now();
        let n = text.bytes().fold(0usize, |a, b| a + usize::from(b == b'\n' || b == b'{'));
        std::hint::black_box(n);
        scan.push(t.elapsed().as_secs_f64() * 1e3);
        let t = clock();
        let mut sources = mocu_language::SourceMap::new();
        let mut diags = mocu_language::Diagnostics::new();
        mocu_language::lint_path("bench.mocu", text.clone(), &loader, &mut sources, &mut diags);
        check.push(clock() - t);
        assert!(!diags.has_errors(), "{:?}", diags.iter().next());
        std::hint::black_box((sources, diags));
        let t = clock();
        let mut sources = mocu_language::SourceMap::new();
        let mut diags = mocu_language::Diagnostics::new();
        let b = mocu_language::check_path(
            "bench.mocu",
            text.clone(),
            &loader,
            &mut sources,
            &mut diags,
        );
        compile.push(clock() - t);
        std::hint::black_box(b);
        let t = clock();
        let mut diags = mocu_language::Diagnostics::new();
        let tree = mocu_language::parser::parse(mocu_language::FileId(0), &text, &mut diags);
        parse.push(clock() - t);
        std::hint::black_box(tree);
    }
    parse.sort_by(f64::total_cmp);
    scan.sort_by(f64::total_cmp);
    check.sort_by(f64::total_cmp);
    compile.sort_by(f64::total_cmp);
    println!(
        "{lines} lines, {} bytes: byte scan {:.3} ms, check {:.1} ms (of which parsing {:.1} ms; median of {runs}; fastest check {:.1} ms), ratio {:.0}x",
        text.len(),
        scan[runs / 2],
        check[runs / 2],
        parse[runs / 2],
        check[0],
        check[runs / 2] / scan[runs / 2]
    );
    println!("building the program too (check_path): {:.1} ms (median)", compile[runs / 2]);
}
