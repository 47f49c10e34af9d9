//! `cargo run --release -p mocu-language --example check_speed -- LINES`: checks the generated
//! layout of benches/check.rs (LINES lines) as `mocu check` does (`lint_path`) and a byte scan
//! of the same text, and prints the median CPU time of the check (this thread's run time from
//! /proc/thread-self/schedstat on Linux, so that other processes on the machine count less; wall
//! time elsewhere), and the peak memory of one check against the file size: the heap's peak
//! (bytes asked of the allocator and not yet freed, counted by an allocator shim), and the rise
//! of the resident set over what the process held before it (read from /proc on Linux; it also
//! counts the allocator's own overhead and the checker's code, paged in by the first check).
//! The same figures follow for `check_path`, which also builds the program (`mocu run`,
//! `mocu build`). (The criterion bench is `cargo bench --bench check`; this is the light,
//! single-crate form.)
use peakmem_alloc::{INSTRUMENTED_SYSTEM, PeakMemAlloc, PeakMemAllocTrait};
use std::alloc::System;
use std::time::Instant;

#[global_allocator]
static HEAP: &PeakMemAlloc<System> = &INSTRUMENTED_SYSTEM;

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
    let loader = mocu_language::MemoryLoader::new()
        .with("stdlib/gauges.mocu", include_str!("../../../stdlib/gauges.mocu"))
        .with("stdlib/theme.mocu", include_str!("../../../stdlib/theme.mocu"));
    // Memory first, in a process that has not checked anything yet (freed memory that the
    // allocator keeps would hide the rise).
    // The text handed in is the input, not the checker's memory.
    let input = text.clone();
    let (heap, rss) = peak_rise(|| {
        let mut sources = mocu_language::SourceMap::new();
        let mut diags = mocu_language::Diagnostics::new();
        mocu_language::lint_path("bench.mocu", input, &loader, &mut sources, &mut diags);
        assert!(!diags.has_errors(), "{:?}", diags.iter().next());
        (sources, diags)
    });
    let input = text.clone();
    let (compile_heap, _) = peak_rise(|| {
        let mut sources = mocu_language::SourceMap::new();
        let mut diags = mocu_language::Diagnostics::new();
        mocu_language::check_path("bench.mocu", input, &loader, &mut sources, &mut diags)
    });
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
    let mb = |b: u64| b as f64 / 1e6;
    let times = |b: u64| b as f64 / text.len() as f64;
    println!(
        "peak memory of one check: heap {:.2} MB ({:.1}x the file), resident set {}",
        mb(heap),
        times(heap),
        rss.map_or("(no /proc)".into(), |r| format!("{:.1} MB ({:.1}x)", mb(r), times(r)))
    );
    println!(
        "building the program too (check_path): heap {:.2} MB ({:.1}x the file)",
        mb(compile_heap),
        times(compile_heap)
    );
}

/// How far the heap and the resident set rise above their levels before `f` while `f` runs
/// and its result is alive, in bytes (the resident set on Linux only: it resets the high-water
/// mark through /proc/self/clear_refs).
fn peak_rise<T>(f: impl FnOnce() -> T) -> (u64, Option<u64>) {
    let kb = |field: &str| -> Option<u64> {
        let status = std::fs::read_to_string("/proc/self/status").ok()?;
        let line = status.lines().find(|l| l.starts_with(field))?;
        line.split_whitespace().nth(1)?.parse().ok()
    };
    let before = kb("VmRSS:");
    let cleared = std::fs::write("/proc/self/clear_refs", "5").is_ok();
    HEAP.reset_peak_memory();
    let result = f();
    let heap = HEAP.get_peak_memory() as u64;
    let peak = kb("VmHWM:");
    drop(result);
    let rss = match (before, peak, cleared) {
        (Some(b), Some(p), true) => Some(p.saturating_sub(b) * 1024),
        _ => None,
    };
    (heap, rss)
}
