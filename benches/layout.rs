//! Live layouts (issue 4): compile time, end-to-end latency and throughput, each against a
//! baseline measured in the same run.
//!
//! | figure      | ours                                                    | baseline                               | target   |
//! |-------------|---------------------------------------------------------|----------------------------------------|----------|
//! | compile     | 1,000 gauges: `load_target` (parse + check), then        | read the same file + `lines().count()` | ≤ 200 ms |
//! |             | `Layout::load` with the JIT (lower + Cranelift + bind +  | (and `Layout::load` with the           |          |
//! |             | publish + first evaluation)                              | interpreter: the JIT's share)          |          |
//! | latency     | vehicle property write → widget property under           | bare DataServer write → subscriber     | median   |
//! |             | `root.display` changed (tick 0 and 1 ms)                 | callback, same server, same signal     |          |
//! | throughput  | 1,000 properties written at 1 kHz each, 16 ms tick:      | the same writer, no layout loaded      | —        |
//! |             | evaluations/s and process CPU                            | (idle telemetry)                       |          |
//!
//! The layout: `use "stdlib/gauges.mocu"`, 10 windows, 1,000 `Dial`/`Bar`/`TextGauge`
//! widgets, each reading its own property `root.vehicles.v{i%50}.nav.s{i/50}`.
//!
//! Compile time is also given as the calling thread's CPU time (`/proc/thread-self/schedstat`):
//! parsing, checking, lowering and Cranelift all run there, and on a shared machine it is
//! the figure that does not count other people's work. Publishing's notifications, which
//! run on DataServer workers, are outside it.
//!
//! Criterion measures compile time and latency means (groups `compile_1000_gauges`,
//! `latency`); the `summary` section then measures every figure with `Instant`, baseline and
//! ours interleaved, and prints one table (stderr). CPU time is the process's utime + stime
//! from `/proc/self/stat`. `cargo bench --bench layout [-- FILTER]`: FILTER (a substring)
//! also selects among the `compile_1000_gauges`, `latency` and `throughput` sections. Under
//! `cargo test --benches` every size shrinks to a smoke run.

mod common;
use common::filter;
use criterion::{Criterion, criterion_group};
use crossbeam_channel::Receiver;
use mocu_dataserver::{DataServer, Guid, Kind, ObjectInfo, PropName, Topic, Value};
use mocu_layout::{Layout, LayoutConfig, NullSink};
use std::hint::black_box;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

static QUICK: AtomicBool = AtomicBool::new(false);

fn quick() -> bool {
    QUICK.load(Ordering::Relaxed)
}

fn size(full: usize, small: usize) -> usize {
    if quick() { small } else { full }
}

const VEHICLES: usize = 50;
const PER_WINDOW: usize = 100;

fn gauges() -> usize {
    size(1000, 60)
}

/// The property gauge `i` reads: `(vehicle, property)`.
fn path_of(i: usize) -> (usize, usize) {
    (i % VEHICLES, i / VEHICLES)
}

/// A layout of `n` gauges in windows of 100.
fn generate(n: usize) -> String {
    let mut s = String::from("use \"stdlib/gauges.mocu\"\n");
    for w in 0..n.div_ceil(PER_WINDOW) {
        s.push_str(&format!("window w{w} {{ layer {w}  rect 0 0 100% 100% }}\nin w{w} {{\n"));
        for i in w * PER_WINDOW..((w + 1) * PER_WINDOW).min(n) {
            let (v, p) = path_of(i);
            let path = format!("root.vehicles.v{v}.nav.s{p}");
            let (x, y) = ((i % 10) * 110, (i / 10 % 10) * 110);
            s.push_str(&match i % 3 {
                0 => format!(
                    "  g{i}: Dial {{ at {x} {y} 100 100  value {path} * 1.94384  range 0 .. 40  units \"kn\"  alarm value > 35 }}\n"
                ),
                1 => format!(
                    "  g{i}: Bar {{ at {x} {y} 100 16  value clamp({path} / 40, 0, 1)  label \"S{p}\"  warn value < 0.2 }}\n"
                ),
                _ => format!(
                    "  g{i}: TextGauge {{ at {x} {y} 200 26  label \"SPD\"  value {path} * 1.94384  units \"kn\"  alarm {path} > 35 }}\n"
                ),
            });
        }
        s.push_str("}\n");
    }
    s
}

/// The generated layout, written to a temporary file (so `use "stdlib/…"` resolves).
struct LayoutFile {
    dir: PathBuf,
    path: PathBuf,
}

impl LayoutFile {
    fn new(n: usize) -> LayoutFile {
        let dir = std::env::temp_dir().join(format!("mocu-bench-layout-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("gauges.mocu");
        std::fs::write(&path, generate(n)).unwrap();
        LayoutFile { dir, path }
    }
}

impl Drop for LayoutFile {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.dir);
    }
}

fn check(path: &Path) -> mocu_language::Program {
    match mocu_language::load_target(path) {
        Ok((bundle, _)) => bundle.layouts.into_iter().next().unwrap().program,
        Err(e) => panic!("the generated layout does not check:\n{e}"),
    }
}

fn config(tick: Duration, jit: bool) -> LayoutConfig {
    LayoutConfig { tick, jit, ..LayoutConfig::default() }
}

/// A world with the vehicles and every property the gauges read.
struct World {
    ds: DataServer,
    /// `nav` object of each vehicle.
    navs: Vec<Guid>,
    props: Vec<PropName>,
}

impl World {
    fn new(n: usize) -> World {
        let ds = DataServer::default();
        let vs = ds.create_object(Guid::ROOT, ObjectInfo::new("vehicles", "folder")).unwrap();
        let per = n.div_ceil(VEHICLES);
        let props: Vec<PropName> = (0..per).map(|p| PropName::new(&format!("s{p}"))).collect();
        let navs = (0..VEHICLES)
            .map(|v| {
                let g = ds.create_object(vs, ObjectInfo::new(&format!("v{v}"), "usv")).unwrap();
                let nav = ds.create_object(g, ObjectInfo::new("nav", "nav")).unwrap();
                for p in &props {
                    ds.set(nav, *p, Value::Float(1.0)).unwrap();
                }
                nav
            })
            .collect();
        ds.quiesce();
        World { ds, navs, props }
    }

    fn write(&self, i: usize, x: f64) {
        let (v, p) = path_of(i);
        self.ds.set(self.navs[v], self.props[p], Value::Float(x)).unwrap();
    }
}

// ----- compile time ----------------------------------------------------------------------

fn load(ds: &DataServer, program: &mocu_language::Program, jit: bool) -> Layout {
    Layout::load(ds, program, config(Duration::from_millis(16), jit), Arc::new(NullSink))
        .expect("the layout loads")
}

fn bench_compile(c: &mut Criterion) {
    let file = LayoutFile::new(gauges());
    let program = check(&file.path);
    let mut g = c.benchmark_group("compile_1000_gauges");
    g.sample_size(10);
    g.bench_function("baseline_read_and_count_lines", |b| {
        b.iter(|| std::fs::read_to_string(&file.path).unwrap().lines().count())
    });
    g.bench_function("parse_and_check", |b| b.iter(|| black_box(check(&file.path))));
    for (name, jit) in [("layout_load_jit", true), ("layout_load_interpreter", false)] {
        g.bench_function(name, |b| {
            b.iter_with_large_drop(|| {
                let ds = DataServer::default();
                let layout = load(&ds, &program, jit);
                (layout, ds)
            })
        });
    }
    g.finish();
}

// ----- latency: a vehicle write → the widget property under root.display ---------------

/// Writes gauge 0's property and waits for its widget's `value` to change.
struct E2e {
    world: World,
    _layout: Layout,
    back: Receiver<()>,
    next: f64,
}

impl E2e {
    fn new(tick: Duration) -> E2e {
        let file = LayoutFile::new(gauges());
        let world = World::new(gauges());
        let layout =
            Layout::load(&world.ds, &check(&file.path), config(tick, true), Arc::new(NullSink))
                .expect("the layout loads");
        layout.settle();
        let widget = world.ds.resolve(&["display", "w0", "g0"]).expect("gauge 0 published");
        let (tx, back) = crossbeam_channel::unbounded();
        world
            .ds
            .subscribe(Topic::property_names(widget, &["value"]), move |n| {
                if n.kind == Kind::Changed {
                    black_box(n.value());
                    let _ = tx.send(());
                }
            })
            .unwrap();
        world.ds.quiesce();
        E2e { world, _layout: layout, back, next: 2.0 }
    }

    fn round_trip(&mut self) {
        self.next += 1.0;
        self.world.write(0, self.next);
        self.back.recv().unwrap();
    }
}

/// Baseline: a write to a plain property of the same server, its subscriber signalling.
struct Bare {
    ds: DataServer,
    obj: Guid,
    name: PropName,
    back: Receiver<()>,
    next: f64,
}

impl Bare {
    fn new(ds: &DataServer) -> Bare {
        let obj = ds.create_object(Guid::ROOT, ObjectInfo::new("bare", "bench")).unwrap();
        let name = PropName::new("x");
        ds.set(obj, name, Value::Float(0.0)).unwrap();
        let (tx, back) = crossbeam_channel::unbounded();
        ds.subscribe(Topic::property_names(obj, &["x"]), move |n| {
            if n.kind == Kind::Changed {
                black_box(n.value());
                let _ = tx.send(());
            }
        })
        .unwrap();
        ds.quiesce();
        Bare { ds: ds.clone(), obj, name, back, next: 0.0 }
    }

    fn round_trip(&mut self) {
        self.next += 1.0;
        self.ds.set(self.obj, self.name, Value::Float(self.next)).unwrap();
        self.back.recv().unwrap();
    }
}

fn bench_latency(c: &mut Criterion) {
    let mut g = c.benchmark_group("latency");
    g.sample_size(20);
    let (mut ours, mut bare) = (None, None);
    g.bench_function("write_to_widget_property_tick_0", |b| {
        let ours = ours.get_or_insert_with(|| E2e::new(Duration::ZERO));
        b.iter(|| ours.round_trip())
    });
    g.bench_function("baseline_write_to_callback", |b| {
        let bare = bare.get_or_insert_with(|| {
            let ours = ours.get_or_insert_with(|| E2e::new(Duration::ZERO));
            Bare::new(&ours.world.ds)
        });
        b.iter(|| bare.round_trip())
    });
    g.finish();
}

criterion_group! {
    name = groups;
    config = Criterion::default()
        .warm_up_time(Duration::from_millis(500))
        .measurement_time(Duration::from_secs(3));
    targets = bench_compile, bench_latency
}

// ----- summary ------------------------------------------------------------------------

fn median(v: &mut [f64]) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn p99(v: &mut [f64]) -> f64 {
    v.sort_by(f64::total_cmp);
    v[(v.len() * 99 / 100).min(v.len() - 1)]
}

struct Row {
    figure: String,
    ours: String,
    baseline: String,
    ratio: String,
    target: String,
}

fn row(figure: &str, ours: String, baseline: String, ratio: String, target: &str) -> Row {
    Row { figure: figure.into(), ours, baseline, ratio, target: target.into() }
}

fn compile_summary(rows: &mut Vec<Row>) {
    let n = gauges();
    let file = LayoutFile::new(n);
    let program = check(&file.path);
    let rounds = size(9, 1);
    // Wall time, and this thread's CPU time (the figure that survives a shared machine:
    // parsing, checking, lowering and Cranelift all run on the calling thread).
    let (mut base, mut checked, mut jit, mut interp) = (vec![], vec![], vec![], vec![]);
    let (mut checked_cpu, mut jit_cpu) = (vec![], vec![]);
    for _ in 0..rounds {
        let t = Instant::now();
        black_box(std::fs::read_to_string(&file.path).unwrap().lines().count());
        base.push(t.elapsed().as_secs_f64() * 1e3);
        let (t, c) = (Instant::now(), thread_cpu_ms());
        black_box(check(&file.path));
        checked.push(t.elapsed().as_secs_f64() * 1e3);
        checked_cpu.push(thread_cpu_ms() - c);
        for (jit_on, out) in [(true, &mut jit), (false, &mut interp)] {
            let ds = DataServer::default();
            let (t, c) = (Instant::now(), thread_cpu_ms());
            let layout = load(&ds, &program, jit_on);
            out.push(t.elapsed().as_secs_f64() * 1e3);
            if jit_on {
                jit_cpu.push(thread_cpu_ms() - c);
            }
            drop(layout);
        }
    }
    let (base, checked, jit, interp) =
        (median(&mut base), median(&mut checked), median(&mut jit), median(&mut interp));
    let (checked_cpu, jit_cpu) = (median(&mut checked_cpu), median(&mut jit_cpu));
    let total = checked + jit;
    let total_cpu = checked_cpu + jit_cpu;
    let ms = |x: f64| format!("{x:.1} ms");
    rows.push(row(
        &format!("compile {n} gauges: parse+check+JIT+bind"),
        ms(total),
        ms(base),
        format!("{:.0}×", total / base),
        if total <= 200.0 { "≤ 200 ms: met" } else { "≤ 200 ms: MISSED" },
    ));
    rows.push(row(
        "  the same, this thread's CPU time",
        ms(total_cpu),
        "".into(),
        format!("check {} + load {}", ms(checked_cpu), ms(jit_cpu)),
        if total_cpu <= 200.0 { "≤ 200 ms: met" } else { "≤ 200 ms: MISSED" },
    ));
    rows.push(row(
        "  parse + check (load_target)",
        ms(checked),
        ms(base),
        format!("{:.0}×", checked / base),
        "",
    ));
    rows.push(row(
        "  Layout::load, JIT",
        ms(jit),
        format!("{} interp.", ms(interp)),
        format!("JIT share ≈ {}", ms(jit - interp)),
        "",
    ));
}

fn latency_summary(rows: &mut Vec<Row>) {
    let (blocks, per) = (size(40, 2), size(100, 10));
    for tick in [Duration::ZERO, Duration::from_millis(1)] {
        let mut ours = E2e::new(tick);
        let mut bare = Bare::new(&ours.world.ds);
        for _ in 0..per {
            ours.round_trip();
            bare.round_trip();
        }
        let (mut a, mut b) = (Vec::new(), Vec::new());
        for _ in 0..blocks {
            for _ in 0..per {
                let t = Instant::now();
                ours.round_trip();
                a.push(t.elapsed().as_secs_f64() * 1e6);
            }
            for _ in 0..per {
                let t = Instant::now();
                bare.round_trip();
                b.push(t.elapsed().as_secs_f64() * 1e6);
            }
        }
        let (ma, mb, pa, pb) = (median(&mut a), median(&mut b), p99(&mut a), p99(&mut b));
        let us = |x: f64| format!("{x:.1} µs");
        rows.push(row(
            &format!("write → widget, tick {} ms, median", tick.as_millis()),
            us(ma),
            us(mb),
            format!("{:.1}×", ma / mb),
            "(median reported)",
        ));
        rows.push(row(
            &format!("write → widget, tick {} ms, p99", tick.as_millis()),
            us(pa),
            us(pb),
            format!("{:.1}×", pa / pb),
            &format!("n = {}", a.len()),
        ));
    }
}

/// CPU time of the calling thread in ms, from `/proc/thread-self/schedstat` (ns on CPU).
fn thread_cpu_ms() -> f64 {
    std::fs::read_to_string("/proc/thread-self/schedstat")
        .ok()
        .and_then(|s| s.split_whitespace().next()?.parse::<f64>().ok())
        .map_or(0.0, |ns| ns / 1e6)
}

/// CPU time of the whole process (all threads), from `/proc/self/stat`.
fn cpu_seconds() -> Option<f64> {
    let s = std::fs::read_to_string("/proc/self/stat").ok()?;
    // Fields after the command name (which is in parentheses and may contain spaces).
    let rest = &s[s.rfind(')')? + 2..];
    let f: Vec<&str> = rest.split_whitespace().collect();
    // utime and stime are fields 14 and 15 of the file: 12 and 13 after the name.
    let ticks: f64 = f.get(11)?.parse::<f64>().ok()? + f.get(12)?.parse::<f64>().ok()?;
    Some(ticks / 100.0) // USER_HZ is 100 on Linux
}

struct Run {
    wall: f64,
    cpu: f64,
    writes: u64,
    evaluations: u64,
    /// Time after the writer stopped until the layout had caught up.
    drain: f64,
}

/// One writer thread writes every property round-robin, `rate` rounds per second, paced
/// by a deadline per round, for `secs`.
fn drive(world: &World, layout: Option<&Layout>, secs: f64, rate: f64) -> Run {
    let n = gauges();
    world.ds.quiesce();
    if let Some(l) = layout {
        l.settle();
    }
    let evals0 = layout.map_or(0, |l| l.stats().evaluations);
    let cpu0 = cpu_seconds().unwrap_or(0.0);
    let t0 = Instant::now();
    let period = Duration::from_secs_f64(1.0 / rate);
    let mut writes = 0u64;
    let mut round = 0u32;
    let mut x = 0.0;
    while t0.elapsed().as_secs_f64() < secs {
        round += 1;
        x += 0.001;
        for i in 0..n {
            world.write(i, x + i as f64 * 1e-3);
        }
        writes += n as u64;
        let due = t0 + period * round;
        let now = Instant::now();
        if due > now {
            std::thread::sleep(due - now);
        }
    }
    let wall = t0.elapsed().as_secs_f64();
    let evaluations = layout.map_or(0, |l| l.stats().evaluations) - evals0;
    world.ds.quiesce();
    if let Some(l) = layout {
        l.flush();
        world.ds.quiesce();
    }
    let drain = t0.elapsed().as_secs_f64() - wall;
    let cpu = cpu_seconds().unwrap_or(0.0) - cpu0;
    Run { wall, cpu, writes, evaluations, drain }
}

fn throughput_summary(rows: &mut Vec<Row>) {
    let n = gauges();
    let secs = if quick() { 0.1 } else { 2.0 };
    let file = LayoutFile::new(n);
    let program = check(&file.path);
    // Baseline: idle telemetry, no layout; then the same with the layout, then idle again.
    let world = World::new(n);
    let idle = drive(&world, None, secs, 1000.0);
    let layout = Layout::load(&world.ds, &program, LayoutConfig::default(), Arc::new(NullSink))
        .expect("the layout loads");
    let live = drive(&world, Some(&layout), secs, 1000.0);
    // The layout loaded, nothing written: what it costs at rest.
    let cpu0 = cpu_seconds().unwrap_or(0.0);
    std::thread::sleep(Duration::from_secs_f64(secs / 2.0));
    let rest = cpu_seconds().unwrap_or(0.0) - cpu0;
    drop(layout);
    let idle2 = drive(&world, None, secs, 1000.0);
    let idle_cpu = (idle.cpu / idle.wall + idle2.cpu / idle2.wall) / 2.0;
    let idle_rate = (idle.writes as f64 / idle.wall + idle2.writes as f64 / idle2.wall) / 2.0;
    let eps = live.evaluations as f64 / live.wall;
    rows.push(row(
        &format!("{n} props × 1 kHz, 16 ms tick: writes/s"),
        format!("{:.0}", live.writes as f64 / live.wall),
        format!("{idle_rate:.0}"),
        format!("{:.2}×", live.writes as f64 / live.wall / idle_rate),
        &format!("asked: {}/s", n * 1000),
    ));
    rows.push(row(
        "  evaluations/s",
        format!("{eps:.0}"),
        format!("≤ {:.0} (1/cell/tick)", n as f64 * 1000.0 / 16.0),
        format!("{:.2}", eps / (n as f64 * 1000.0 / 16.0)),
        "",
    ));
    let live_cpu = live.cpu / live.wall;
    rows.push(row(
        "  process CPU (cores)",
        format!("{live_cpu:.2}"),
        format!("{idle_cpu:.2}"),
        format!("{:.2}×", live_cpu / idle_cpu),
        &format!("drain after writer: {:.0} ms", live.drain * 1e3),
    ));
    if live.evaluations > 0 {
        let extra_us = (live.cpu - idle_cpu * live.wall) / live.evaluations as f64 * 1e6;
        let extra_per_write_ns = (live.cpu - idle_cpu * live.wall) / live.writes as f64 * 1e9;
        rows.push(row(
            "  extra CPU per evaluation / per write",
            format!("{extra_us:.1} µs / {extra_per_write_ns:.0} ns"),
            "—".into(),
            "".into(),
            "",
        ));
    }
    rows.push(row(
        "  layout loaded, no writes (CPU cores)",
        format!("{:.3}", rest / (secs / 2.0)),
        "0".into(),
        "".into(),
        "",
    ));
}

fn print_table(rows: &[Row]) {
    let w = rows.iter().map(|r| r.figure.chars().count()).max().unwrap_or(0);
    eprintln!("\nlayout benchmarks (baseline in the same run):");
    eprintln!("{:<w$}  {:>18}  {:>24}  {:>16}  target", "figure", "ours", "baseline", "ratio");
    for r in rows {
        eprintln!(
            "{:<w$}  {:>18}  {:>24}  {:>16}  {}",
            r.figure, r.ours, r.baseline, r.ratio, r.target
        );
    }
    eprintln!();
}

fn main() {
    QUICK.store(!std::env::args().any(|a| a == "--bench"), Ordering::Relaxed);
    let filter = filter();
    let selected = |section: &str| filter.as_deref().is_none_or(|f| section.contains(f));
    groups();
    let mut rows = Vec::new();
    if selected("compile_1000_gauges") {
        compile_summary(&mut rows);
    }
    if selected("latency") {
        latency_summary(&mut rows);
    }
    if selected("throughput") {
        throughput_summary(&mut rows);
    }
    if !rows.is_empty() {
        print_table(&rows);
    }
    Criterion::default().configure_from_args().final_summary();
}
