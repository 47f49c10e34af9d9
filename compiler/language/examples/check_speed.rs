//! `cargo run --release -p mocu-language --example check_speed -- LINES`: checks the generated
//! layout of benches/check.rs (LINES lines) and a byte scan of the same text, and prints the
//! median CPU time of the check (this thread's run time from /proc/thread-self/schedstat on Linux,
//! so that other processes on the machine count less; wall time elsewhere), and the peak memory of one check (the rise of the resident set over
//! what the process held before it, read from /proc on Linux) against the file size.
//! (The criterion bench is `cargo bench --bench check`; this is the light, single-crate form.)
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
    let loader = mocu_language::MemoryLoader::new()
        .with("stdlib/gauges.mocu", include_str!("../../../stdlib/gauges.mocu"))
        .with("stdlib/theme.mocu", include_str!("../../../stdlib/theme.mocu"));
    // Memory first, in a process that has not checked anything yet (freed memory that the
    // allocator keeps would hide the rise).
    // The text handed in is the input, not the checker's memory.
    let input = text.clone();
    let peak = peak_rise(|| {
        let mut sources = mocu_language::SourceMap::new();
        let mut diags = mocu_language::Diagnostics::new();
        mocu_language::check_path("bench.mocu", input, &loader, &mut sources, &mut diags)
    });
    let runs = if lines > 50_000 { 3 } else { 11 };
    let mut scan = Vec::new();
    let mut check = Vec::new();
    let mut parse = Vec::new();
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
        let b = mocu_language::check_path(
            "bench.mocu",
            text.clone(),
            &loader,
            &mut sources,
            &mut diags,
        );
        check.push(clock() - t);
        assert!(!diags.has_errors(), "{:?}", diags.iter().next());
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
    println!(
        "{lines} lines, {} bytes: byte scan {:.3} ms, check {:.1} ms (of which parsing {:.1} ms; median of {runs}; fastest check {:.1} ms), ratio {:.0}x",
        text.len(),
        scan[runs / 2],
        check[runs / 2],
        parse[runs / 2],
        check[0],
        check[runs / 2] / scan[runs / 2]
    );
    if let Some(peak) = peak {
        println!(
            "peak memory of one check: {:.1} MB, {:.1}x the file",
            peak as f64 / 1e6,
            peak as f64 / text.len() as f64
        );
    }
}

/// How far the resident set rises above its level before `f` while `f` runs and its result
/// is alive, in bytes (Linux: resets the high-water mark through /proc/self/clear_refs).
fn peak_rise<T>(f: impl FnOnce() -> T) -> Option<u64> {
    let kb = |field: &str| -> Option<u64> {
        let status = std::fs::read_to_string("/proc/self/status").ok()?;
        let line = status.lines().find(|l| l.starts_with(field))?;
        line.split_whitespace().nth(1)?.parse().ok()
    };
    let before = kb("VmRSS:")?;
    std::fs::write("/proc/self/clear_refs", "5").ok()?;
    let result = f();
    let peak = kb("VmHWM:")?;
    drop(result);
    Some(peak.saturating_sub(before) * 1024)
}
