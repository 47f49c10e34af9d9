//! A handler on a property change: a script's (each engine) against a native closure, in the
//! same run. `v.x` is written; the handler writes `out.y = x * 2`; the write returns and the
//! DataServer is quiet again (`quiesce`) — the same path for every handler.
//!
//! Criterion gives the latency per change. With `--bench`, the run also prints the CPU time per
//! change of every thread of the process (schedstat), and the memory a script module holds
//! (QuickJS's own count; the resident-set growth over 100 loaded scripts for each engine).

use criterion::{Criterion, criterion_group, criterion_main};
use mocu_dataserver::{DataServer, Guid, ObjectInfo, PathEvent, Value};
use mocu_script::{Limits, Registry, Reporter, Script, Source};
use std::sync::Arc;

const JS: &str = r#"mocu.subscribe("v.x", function (x) { mocu.write("out.y", x * 2); });"#;
const RHAI: &str = r#"mocu::subscribe("v.x", |x| mocu::write("out.y", x * 2));"#;

struct World {
    ds: DataServer,
    v: Guid,
}

fn world() -> World {
    let ds = DataServer::default();
    let v = ds.create_object(Guid::ROOT, ObjectInfo::new("v", "thing")).unwrap();
    ds.set(v, "x", Value::Int(0)).unwrap();
    ds.create_object(Guid::ROOT, ObjectInfo::new("out", "thing")).unwrap();
    World { ds, v }
}

/// The handler of each kind, set up on `w`; what keeps it alive.
enum Handler {
    Native { _watch: mocu_dataserver::PathWatch },
    Script(Script),
}

fn handler(w: &World, kind: &str) -> Handler {
    if kind == "native" {
        let ds = w.ds.clone();
        let out = ds.resolve(&["out"]).unwrap();
        let ex = ds.serial_executor();
        let path = mocu_dataserver::DottedPath::parse("v.x").unwrap();
        let watch =
            w.ds.watch_path(path, Some(&ex), move |e: &PathEvent| {
                if let Some(Value::Int(x)) = e.value {
                    let _ = ds.set(out, "y", Value::Int(x * 2));
                }
            })
            .unwrap();
        return Handler::Native { _watch: watch };
    }
    let text = if kind == "js" { JS } else { RHAI };
    let engine = Registry::standard().get(kind).unwrap();
    let report: Reporter = Arc::new(|e| panic!("{e}"));
    let source = Source::file("bench", text);
    let s = Script::load(
        &*engine,
        &source,
        w.ds.clone(),
        w.ds.serial_executor(),
        &Limits::default(),
        report,
    )
    .unwrap();
    s.run_here().unwrap();
    Handler::Script(s)
}

fn change(w: &World, i: i64) {
    w.ds.set(w.v, "x", Value::Int(i)).unwrap();
    w.ds.quiesce();
}

/// CPU time of every thread of this process, in ns.
fn process_cpu_ns() -> u64 {
    let Ok(tasks) = std::fs::read_dir("/proc/self/task") else { return 0 };
    tasks
        .filter_map(|t| std::fs::read_to_string(t.ok()?.path().join("schedstat")).ok())
        .filter_map(|s| s.split_whitespace().next()?.parse::<u64>().ok())
        .sum()
}

fn resident_bytes() -> u64 {
    let statm = std::fs::read_to_string("/proc/self/statm").unwrap_or_default();
    let pages: u64 = statm.split_whitespace().nth(1).and_then(|p| p.parse().ok()).unwrap_or(0);
    pages * 4096
}

fn cpu_and_memory() {
    const N: i64 = 5_000;
    let mut native_ns = 0.0;
    for kind in ["native", "js", "rhai"] {
        let w = world();
        let _h = handler(&w, kind);
        change(&w, 1);
        let t = process_cpu_ns();
        for i in 0..N {
            change(&w, i + 2);
        }
        let per = (process_cpu_ns() - t) as f64 / N as f64;
        if kind == "native" {
            native_ns = per;
        }
        println!("cpu per change, {kind}: {per:.0} ns ({:.2}x native)", per / native_ns);
        let y = w.ds.get(w.ds.resolve(&["out"]).unwrap(), "y").ok();
        assert_eq!(y, Some(Value::Int((N + 1) * 2)), "{kind}: the handler ran for every change");
    }
    for kind in ["js", "rhai"] {
        let w = world();
        let before = resident_bytes();
        let scripts: Vec<Handler> = (0..100).map(|_| handler(&w, kind)).collect();
        let per = (resident_bytes().saturating_sub(before)) / 100;
        let own = match &scripts[0] {
            Handler::Script(s) => s.memory().map_or("not counted".into(), |m| format!("{m} B")),
            Handler::Native { .. } => unreachable!(),
        };
        println!(
            "memory per script module, {kind}: {} KiB resident, engine's own count {own}",
            per / 1024
        );
    }
}

fn bench(c: &mut Criterion) {
    if std::env::args().any(|a| a == "--bench") {
        cpu_and_memory();
    }
    let mut g = c.benchmark_group("property_change_handler");
    for kind in ["native", "js", "rhai"] {
        let w = world();
        let _h = handler(&w, kind);
        let mut i = 0;
        g.bench_function(kind, |b| {
            b.iter(|| {
                i += 1;
                change(&w, i);
            })
        });
    }
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
