//! Every shipped layout on the screens an OCU meets, 800×480 to 3840×2160: what an operator
//! relies on — the alert layer, state headers, critical banners — lies wholly on the screen
//! and inside its window (docs/language.md, "Screen sizes"). Geometry as the layout runtime
//! publishes it, against the simulator under a fixed seed; at 3840×2160 the drawn frames of
//! the handheld and the multi-USV layouts are golden images.
//!
//! `UPDATE_GOLDEN=1 cargo test -p mocu-widgets --test screen_fit` rewrites their PNGs.

use mocu_dataserver::{Config, DataServer, Guid, ManualClock, ObjectInfo, Value};
use mocu_display::{Clock, Display, DisplayOptions};
use mocu_host::ModuleContext;
use mocu_layout::{Layout, LayoutConfig, NullSink};
use mocu_sim::{Sim, SimConfig};
use mocu_widgets::{Library, MapModule, RendererConfig, WidgetRenderer};
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::Duration;

mod shipped;
use shipped::layouts;

const SIZES: [(u32, u32); 4] = [(800, 480), (1280, 720), (1920, 1080), (3840, 2160)];

/// Components whose whole box must be on the screen.
const CRITICAL: [&str; 3] = ["AlertLayer", "StatusHeader", "AlertBanner"];

/// A layout running against the simulator for five simulated seconds, a critical alert
/// raised; with the display and the widget renderer when `draw`.
struct Run {
    ds: DataServer,
    layout: Layout,
    display: Option<(Display, WidgetRenderer, MapModule)>,
    _sim: Sim,
}

fn run(file: &Path, size: (u32, u32), draw: bool) -> Run {
    let (bundle, _) =
        mocu_language::load_target(file).unwrap_or_else(|e| panic!("{}: {e:?}", file.display()));
    let program = &bundle.layouts[0].program;
    let clock = ManualClock::new();
    clock.set_wall(std::time::UNIX_EPOCH + Duration::from_secs(86_400 * 20_000 + 50_587));
    let ds = DataServer::with_clock(Config { workers: 2 }, Arc::new(clock));
    let display = draw.then(|| {
        let opts = DisplayOptions::new(size.0, size.1).clock(Clock::manual());
        let display = Display::new(&ds, opts).unwrap();
        let lib = Library::compile(program, true).unwrap();
        let renderer = WidgetRenderer::start(&ds, lib, RendererConfig::default()).unwrap();
        (display, renderer, MapModule::start(&ds).unwrap())
    });
    let lc = LayoutConfig {
        screen: (size.0 as f64, size.1 as f64),
        alerts_to_terminal: false,
        ..LayoutConfig::default()
    };
    let layout = Layout::load(&ds, program, lc, Arc::new(NullSink)).unwrap();
    let ctx = ModuleContext::detached("sim", ds.clone());
    let cfg = SimConfig { seed: 7, appear_every: 0.0, autostart: true, ..SimConfig::default() };
    let sim = Sim::new(ctx, cfg).unwrap();
    for _ in 0..100 {
        sim.step(0.05);
    }
    raise_critical(&ds);
    layout.settle();
    ds.quiesce();
    Run { ds, layout, display, _sim: sim }
}

/// A critical alert, as `mocu-layout` raises one: what the alert layer shows.
fn raise_critical(ds: &DataServer) {
    let child = |parent: Guid, name: &str| {
        ds.find_child(parent, name)
            .unwrap()
            .unwrap_or_else(|| ds.create_object(parent, ObjectInfo::new(name, name)).unwrap())
    };
    let folder = child(child(Guid::ROOT, "operator"), "alerts");
    let a = ds.create_object(folder, ObjectInfo::new("alert1", "alert")).unwrap();
    ds.set(a, "severity", Value::str("critical")).unwrap();
    ds.set(a, "time", Value::Float(1_728_050_587.0)).unwrap();
    ds.set(a, "acknowledged", Value::Bool(false)).unwrap();
    ds.set(a, "text", Value::str("Link lost with usv2")).unwrap();
    ds.set(folder, "raised", Value::Int(1)).unwrap();
    ds.set(folder, "unacknowledged", Value::Int(1)).unwrap();
}

type Rect = [f64; 4];

fn rect(ds: &DataServer, g: Guid) -> Rect {
    ["x", "y", "w", "h"].map(|k| ds.try_get(g, k.into()).and_then(|v| v.as_f64()).unwrap_or(0.0))
}

/// `inner` (relative to `outer`'s corner) lies within `outer`'s size, to half a pixel.
fn within(inner: Rect, outer_w: f64, outer_h: f64) -> bool {
    let e = 0.5;
    inner[0] >= -e
        && inner[1] >= -e
        && inner[0] + inner[2] <= outer_w + e
        && inner[1] + inner[3] <= outer_h + e
}

/// Every critical widget (and the built-in alert window) of a running layout, checked;
/// returns how many were found.
fn check_critical(ds: &DataServer, size: (u32, u32), what: &str) -> usize {
    let (sw, sh) = (size.0 as f64, size.1 as f64);
    let display = ds.resolve(&["display"]).unwrap();
    let mut found = 0;
    for win in ds.children(display).unwrap() {
        if ds.try_get(win, "visible".into()) == Some(Value::Bool(false)) {
            continue;
        }
        let name = ds.info(win).unwrap().name;
        let wr = rect(ds, win);
        if &*name == "alert_layer" {
            found += 1;
            assert!(within(wr, sw, sh), "{what}: the alert window {wr:?} leaves the screen");
        }
        for w in ds.children(win).unwrap() {
            let comp = ds.try_get(w, "component".into());
            let comp = comp.as_ref().and_then(Value::as_str).unwrap_or_default();
            if !CRITICAL.contains(&comp) {
                continue;
            }
            found += 1;
            let r = rect(ds, w);
            assert!(within(r, wr[2], wr[3]), "{what}: {comp} {r:?} leaves its window {wr:?}");
            let on_screen = [wr[0] + r[0], wr[1] + r[1], r[2], r[3]];
            assert!(within(on_screen, sw, sh), "{what}: {comp} at {on_screen:?} leaves the screen");
        }
    }
    found
}

#[test]
fn the_alert_layer_status_headers_and_banners_of_every_shipped_layout_are_on_every_screen() {
    for file in layouts() {
        let name = file.file_name().unwrap().to_string_lossy().to_string();
        for size in SIZES {
            let r = run(&file, size, false);
            let found = check_critical(&r.ds, size, &format!("{name} at {}×{}", size.0, size.1));
            assert!(found >= 1, "{name}: the alert layer at least");
            drop(r.layout);
        }
    }
}

fn check_golden(name: &str, frame: &tiny_skia::Pixmap) {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join(format!("tests/golden/{name}.png"));
    if std::env::var_os("UPDATE_GOLDEN").is_some() {
        frame.save_png(&path).unwrap();
        return;
    }
    let want = tiny_skia::Pixmap::load_png(&path)
        .unwrap_or_else(|e| panic!("golden {} missing ({e}); UPDATE_GOLDEN=1", path.display()));
    assert_eq!((want.width(), want.height()), (frame.width(), frame.height()), "size of {name}");
    let differ = frame
        .data()
        .chunks_exact(4)
        .zip(want.data().chunks_exact(4))
        .filter(|(a, b)| a.iter().zip(b.iter()).any(|(x, y)| x.abs_diff(*y) > 3))
        .count();
    if differ as f64 > (frame.width() * frame.height()) as f64 * 0.001 {
        let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("golden-actual");
        std::fs::create_dir_all(&dir).unwrap();
        frame.save_png(dir.join(format!("{name}.png"))).unwrap();
        panic!("{name}: {differ} pixels differ; actual image in {}", dir.display());
    }
}

/// At 3840×2160 a layout drawn for a smaller screen grows with it (it does not sit in a
/// corner) and its critical widgets stay whole: the drawn frames.
#[test]
fn on_a_3840_by_2160_screen_the_handheld_and_multi_usv_layouts_fill_it() {
    for (file, golden) in [
        ("fig2-handheld.mocu", "screen_fig2_3840x2160"),
        ("fig3-multi-usv.mocu", "screen_fig3_3840x2160"),
    ] {
        let path = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../layouts").join(file);
        let size = (3840, 2160);
        let mut r = run(&path, size, true);
        assert!(check_critical(&r.ds, size, file) >= 1);
        let (display, ..) = r.display.as_mut().unwrap();
        for _ in 0..3 {
            r.layout.settle();
            r.ds.quiesce();
            display.frame();
        }
        check_golden(golden, &display.read_frame());
    }
}
