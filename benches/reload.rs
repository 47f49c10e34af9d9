//! Hot reload figures (issue 6), each with its baseline in the same run:
//! - file write → first composited frame showing the change, p50 and p95, through the real
//!   watcher (notify), checker, incremental reload, widget renderer and CPU compositor;
//!   baseline: the bare notify write → event latency on the same folder.
//! - reloading a 1,000-widget layout in which one widget changed, against loading it whole.
//!
//! `cargo bench --bench reload`. Without `--bench` (as under `cargo test --benches`) it runs
//! a few iterations only, as a smoke test.
use criterion::Criterion;
use mocu_dataserver::DataServer;
use mocu_display::{BackendChoice, Display, DisplayOptions};
use mocu_hotreload::{Reloader, ReloaderOptions};
use mocu_layout::{Layout, LayoutConfig, NullSink};
use mocu_widgets::{Library, RendererConfig, WidgetRenderer};
use notify::Watcher;
use std::sync::Arc;
use std::time::{Duration, Instant};

fn layout_text(colour: &str, widgets: usize) -> String {
    let mut s = String::from(
        "component Box(c: colour) { rect 0 0 w h  fill c }\nwindow hud { layer 10 rect 0 0 100% 100% }\nin hud {\n",
    );
    s.push_str(&format!("  a: Box {{ at 10 60 100 40  c {colour} }}\n"));
    for i in 0..widgets {
        s.push_str(&format!(
            "  w{i}: Box {{ at {} {} 8 8  c #202020 }}\n",
            120 + (i % 40) * 10,
            60 + (i / 40) * 10
        ));
    }
    s.push_str("}\n");
    s
}

fn pct(v: &mut [f64], p: f64) -> f64 {
    v.sort_by(|a, b| a.total_cmp(b));
    v[((v.len() - 1) as f64 * p).round() as usize]
}

fn write_to_frame(rounds: usize) {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("hud.mocu");
    std::fs::write(&path, layout_text("#ff0000", 20)).unwrap();
    let ds = DataServer::default();
    let mut display =
        Display::new(&ds, DisplayOptions::new(640, 360).backend(BackendChoice::Cpu)).unwrap();
    let (bundle, _) = mocu_language::load_target(&path).unwrap();
    let renderer = Arc::new(
        WidgetRenderer::start(
            &ds,
            Library::compile(&bundle.layouts[0].program, true).unwrap(),
            RendererConfig::default(),
        )
        .unwrap(),
    );
    let r2 = renderer.clone();
    let options = ReloaderOptions {
        config: LayoutConfig { screen: (640.0, 360.0), ..LayoutConfig::default() },
        layout: None,
        on_components: Some(Arc::new(move |p| {
            if let Ok(l) = Library::compile(p, true) {
                r2.replace_library(l)
            }
        })),
    };
    let reloader = Reloader::start(&ds, &path, &bundle, options, Arc::new(NullSink)).unwrap();
    reloader.watch().unwrap();
    let mut lat = Vec::new();
    let colours = [("#00ff00", (0, 255, 0)), ("#ff0000", (255, 0, 0))];
    for i in 0..rounds {
        let (c, rgb) = colours[i % 2];
        std::thread::sleep(Duration::from_millis(60));
        let text = layout_text(c, 20);
        let t0 = Instant::now();
        std::fs::write(&path, &text).unwrap();
        loop {
            display.frame();
            let f = display.read_frame();
            let p = f.pixel(20, 70).unwrap();
            if (p.red(), p.green(), p.blue()) == rgb {
                break;
            }
            assert!(t0.elapsed() < Duration::from_secs(10), "the change never showed");
            std::thread::sleep(Duration::from_micros(500));
        }
        lat.push(t0.elapsed().as_secs_f64() * 1000.0);
    }
    // Baseline: a bare notify watcher on the same folder.
    let (tx, rx) = crossbeam_channel::unbounded();
    let mut w = notify::recommended_watcher(tx).unwrap();
    w.watch(dir.path(), notify::RecursiveMode::NonRecursive).unwrap();
    let probe = dir.path().join("probe.txt");
    let mut base = Vec::new();
    for i in 0..rounds {
        while rx.try_recv().is_ok() {}
        let t0 = Instant::now();
        std::fs::write(&probe, format!("{i}")).unwrap();
        let _ = rx.recv_timeout(Duration::from_secs(5));
        base.push(t0.elapsed().as_secs_f64() * 1000.0);
        std::thread::sleep(Duration::from_millis(5));
    }
    let (p50, p95) = (pct(&mut lat.clone(), 0.5), pct(&mut lat, 0.95));
    let (b50, b95) = (pct(&mut base.clone(), 0.5), pct(&mut base, 0.95));
    eprintln!("hot reload, file write → first frame showing the change ({rounds} saves):");
    eprintln!("  mocu:           p50 {p50:8.2} ms   p95 {p95:8.2} ms   (target p95 ≤ 100 ms)");
    eprintln!("  bare notify:    p50 {b50:8.2} ms   p95 {b95:8.2} ms   (write → event)");
    drop(reloader);
}

fn reload_vs_load(c: &mut Criterion, quick: bool) {
    let n = if quick { 50 } else { 1000 };
    let dir = tempfile::tempdir().unwrap();
    let load = |text: &str| {
        let p = dir.path().join(format!("l{}.mocu", text.len() % 7919));
        std::fs::write(&p, text).unwrap();
        mocu_language::load_target(&p).unwrap().0.layouts.remove(0).program
    };
    let a = load(&layout_text("#ff0000", n));
    let b = load(&layout_text("#00ff00", n));
    let ds = DataServer::default();
    let layout = Layout::load(&ds, &a, LayoutConfig::default(), Arc::new(NullSink)).unwrap();
    let mut g = c.benchmark_group(format!("reload_{n}_widgets"));
    g.sample_size(10);
    let mut flip = false;
    g.bench_function("one_widget_changed", |bch| {
        bch.iter(|| {
            flip = !flip;
            layout.reload(if flip { &b } else { &a }).unwrap()
        })
    });
    drop(layout);
    g.bench_function("full_load_baseline", |bch| {
        bch.iter(|| {
            let l = Layout::load(&ds, &a, LayoutConfig::default(), Arc::new(NullSink)).unwrap();
            drop(l);
        })
    });
    g.finish();
}

fn main() {
    let quick = !std::env::args().any(|a| a == "--bench");
    write_to_frame(if quick { 3 } else { 40 });
    let mut c = Criterion::default().configure_from_args();
    reload_vs_load(&mut c, quick);
    c.final_summary();
}
