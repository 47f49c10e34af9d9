//! `cargo run --release -p mocu-language --example check_memory -- LINES`: the peak memory of
//! one check of the generated layout of benches/check.rs (LINES lines) against the file size,
//! as `mocu check` does it (`lint_path`) and when the program is built too (`check_path`, as
//! `mocu run` and `mocu build` do): the heap's peak (bytes asked of the allocator and not yet
//! freed, counted by an allocator shim), and for the first check the rise of the resident set
//! over what the process held before it (read from /proc on Linux; it also counts the
//! allocator's own overhead and the checker's code, paged in by that first check). The text
//! handed in is the input, not the checker's memory: it is made before the measure starts.
//! CPU time: `examples/check_speed.rs`.
use peakmem_alloc::{INSTRUMENTED_SYSTEM, PeakMemAlloc, PeakMemAllocTrait};
use std::alloc::System;

#[global_allocator]
static HEAP: &PeakMemAlloc<System> = &INSTRUMENTED_SYSTEM;

#[path = "../../../benches/common/layout_corpus.rs"]
mod layout_corpus;
use layout_corpus::generate;

fn main() {
    let lines: usize = std::env::args().nth(1).and_then(|a| a.parse().ok()).unwrap_or(10_000);
    let text = generate(lines);
    let loader = layout_corpus::stdlib_loader();
    // `mocu check` first, in a process that has not checked anything yet (freed memory that
    // the allocator keeps would hide the resident set's rise).
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
    let mb = |b: u64| b as f64 / 1e6;
    let times = |b: u64| b as f64 / text.len() as f64;
    println!(
        "{lines} lines, {} bytes: peak memory of one check: heap {:.2} MB ({:.1}x the file), resident set {}",
        text.len(),
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
