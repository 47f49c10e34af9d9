//! `cargo run --release -p mocu-language --example pass_speed -- LINES`: the CPU time of each
//! pass that `compile_layout` runs after parsing, on the generated layout of benches/check.rs
//! (median of several runs over one parsed copy), to see where the checker's own time goes.
use mocu_language::passes::*;

/// Milliseconds of CPU this thread has used (from /proc/thread-self/schedstat on Linux, so
/// that other processes on the machine count less; wall time elsewhere).
fn cpu_ms(start: Instant) -> f64 {
    std::fs::read_to_string("/proc/thread-self/schedstat")
        .ok()
        .and_then(|s| s.split_whitespace().next()?.parse::<f64>().ok())
        .map_or_else(|| start.elapsed().as_secs_f64() * 1e3, |ns| ns / 1e6)
}
use std::time::Instant;

#[path = "../../../benches/common/layout_corpus.rs"]
mod layout_corpus;

fn main() {
    if std::env::var("SIZES").is_ok() {
        sizes();
    }
    let lines: usize = std::env::args().nth(1).and_then(|a| a.parse().ok()).unwrap_or(10_000);
    let runs: usize = std::env::args().nth(2).and_then(|a| a.parse().ok()).unwrap_or(11);
    let text = layout_corpus::generate(lines);
    let loader = layout_corpus::stdlib_loader();
    let mut sources = mocu_language::SourceMap::new();
    let mut diags = mocu_language::Diagnostics::new();
    let modules = load_sources::load_sources("bench.mocu", text, &loader, &mut sources, &mut diags);
    let schema = mocu_language::Schema::default();
    let config = mocu_language::Config::default();
    let names = [
        "collect_definitions",
        "resolve_names",
        "check_types",
        "check_anchors",
        "check_schema+method_args",
        "check_depth",
        "warnings",
        "drop",
        "total",
    ];
    // Wall time with WALL=1 (finer than the CPU clock's tick; report the fastest run).
    let wall = std::env::var("WALL").is_ok();
    let mut times = vec![Vec::new(); names.len()];
    for _ in 0..runs {
        let mut d = mocu_language::Diagnostics::new();
        let mut lap = Vec::new();
        let origin = Instant::now();
        let cpu_ms = |o: Instant| if wall { o.elapsed().as_secs_f64() * 1e3 } else { cpu_ms(o) };
        let t0 = cpu_ms(origin);
        let mut t = t0;
        let mut mark = |lap: &mut Vec<f64>| {
            let now = cpu_ms(origin);
            lap.push(now - t);
            t = now;
        };
        let defs = collect_definitions::collect_definitions(&modules, &mut d);
        mark(&mut lap);
        let used = resolve_names::resolve_names(&modules, &defs, &mut d);
        mark(&mut lap);
        let mut program = check_types::check_types(&modules, &defs, &schema, &mut d);
        mark(&mut lap);
        program.design = check_anchors::check_anchors(&modules, &mut d);
        mark(&mut lap);
        check_schema::check_schema(&program, &schema, &mut d);
        check_method_args::check_method_args(&program, &schema, &mut d);
        mark(&mut lap);
        check_depth::check_depth(&program, &mut d);
        mark(&mut lap);
        warn_unused::warn_unused(&modules, &used, &mut d);
        warn_outside_window::warn_outside_window(&program, config.screen, &mut d);
        check_anchors::warn_screen_px(&program, &mut d);
        warn_constant_watch::warn_constant_watch(&program, &mut d);
        mark(&mut lap);
        drop((program, defs, used));
        mark(&mut lap);
        lap.push(cpu_ms(origin) - t0);
        assert!(!d.has_errors(), "{:?}", d.iter().next());
        for (i, x) in lap.into_iter().enumerate() {
            times[i].push(x);
        }
    }
    for (n, mut v) in names.iter().zip(times) {
        v.sort_by(f64::total_cmp);
        println!("{n:>26}: {:7.2} ms (fastest {:.2} ms)", v[v.len() / 2], v[0]);
    }
}
#[allow(dead_code)]
fn sizes() {
    use mocu_language::program::*;
    use std::mem::size_of;
    println!(
        "Expr {} Node {} Type {} Bound {} Path {} Widget {} Window {} Arg {} Action {} Component {} Shape {} Watch {} Binding {}",
        size_of::<Expr>(),
        size_of::<Node>(),
        size_of::<mocu_language::types::Type>(),
        size_of::<Bound>(),
        size_of::<Path>(),
        size_of::<Widget>(),
        size_of::<Window>(),
        size_of::<Arg>(),
        size_of::<Action>(),
        size_of::<Component>(),
        size_of::<Shape>(),
        size_of::<Watch>(),
        size_of::<Binding>()
    );
    use mocu_language::ast;
    println!(
        "ast Expr {} Item {} Widget {}",
        size_of::<ast::Expr>(),
        size_of::<ast::Item>(),
        size_of::<ast::Widget>()
    );
}
