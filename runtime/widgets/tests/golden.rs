//! Golden images of the widgets and of the paper's displays, drawn by the CPU path
//! (tiny-skia) of a headless `Display` with the widget renderer, the map and a loaded
//! layout; the simulator is stepped explicitly under a fixed seed (no wall clock).
//!
//! `UPDATE_GOLDEN=1 cargo test -p mocu-widgets --test golden` rewrites tests/golden/*.png.
//! Tolerance: every channel of every pixel within `CHANNEL_TOL` (3) of the reference,
//! except at most `OUTLIER_FRACTION` (0.1%) of the pixels — anti-aliased edges whose
//! coverage may step differently on CPUs with other SIMD paths. A mismatching frame is
//! written to `target/tmp/golden-actual/` for inspection.

use mocu_dataserver::{Config, DataServer, Guid, ManualClock, Value};
use mocu_display::{Clock, Display, DisplayOptions, PointerEvent};
use mocu_host::ModuleContext;
use mocu_layout::{Layout, LayoutConfig, NullSink};
use mocu_sim::{Sim, SimConfig};
use mocu_widgets::{Library, MapModule, RendererConfig, WidgetRenderer};
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::Duration;

const CHANNEL_TOL: u8 = 3;
const OUTLIER_FRACTION: f64 = 0.001;

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../..")
}

/// A display running one layout: the display, the widget renderer, the map and the layout.
struct Rig {
    ds: DataServer,
    display: Display,
    layout: Layout,
    _renderer: WidgetRenderer,
    _map: MapModule,
}

impl Rig {
    fn new(file: &Path, size: (u32, u32), config: RendererConfig) -> Rig {
        let (bundle, _) = mocu_language::load_target(file)
            .unwrap_or_else(|e| panic!("{}: {e:?}", file.display()));
        let program = &bundle.layouts[0].program;
        // The server's clock reads 14:03:07 UTC (the status header's clock) and stands still.
        let clock = ManualClock::new();
        clock.set_wall(std::time::UNIX_EPOCH + Duration::from_secs(86_400 * 20_000 + 50_587));
        let ds = DataServer::with_clock(Config { workers: 2 }, Arc::new(clock));
        let display =
            Display::new(&ds, DisplayOptions::new(size.0, size.1).clock(Clock::manual())).unwrap();
        let lib = Library::compile(program, true).unwrap();
        let renderer = WidgetRenderer::start(&ds, lib, config).unwrap();
        let map = MapModule::start(&ds).unwrap();
        let lc = LayoutConfig { screen: (size.0 as f64, size.1 as f64), ..LayoutConfig::default() };
        let layout = Layout::load(&ds, program, lc, Arc::new(NullSink)).unwrap();
        Rig { ds, display, layout, _renderer: renderer, _map: map }
    }

    /// Lets every notification settle, then draws.
    fn frame(&mut self) -> tiny_skia::Pixmap {
        for _ in 0..3 {
            self.layout.settle();
            self.ds.quiesce();
            self.display.frame();
        }
        self.display.read_frame()
    }

    fn widget(&self, window: &str, name: &str) -> Guid {
        self.ds.resolve(&["display", window, name]).unwrap_or_else(|| panic!("no widget {name}"))
    }
}

fn sheet(config: RendererConfig) -> Rig {
    let file = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/sheet.mocu");
    Rig::new(&file, (960, 950), config)
}

/// Feedback outlines shown long enough that a slow test machine still sees them.
fn steady() -> RendererConfig {
    RendererConfig {
        accepted_for: Duration::from_secs(3600),
        refused_for: Duration::from_secs(3600),
        ..RendererConfig::default()
    }
}

fn check_golden(name: &str, frame: &tiny_skia::Pixmap) {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join(format!("tests/golden/{name}.png"));
    if std::env::var_os("UPDATE_GOLDEN").is_some() {
        frame.save_png(&path).unwrap();
        eprintln!("golden: wrote {}", path.display());
        return;
    }
    let want = tiny_skia::Pixmap::load_png(&path).unwrap_or_else(|e| {
        panic!("golden {} missing ({e}); run with UPDATE_GOLDEN=1 to create it", path.display())
    });
    assert_eq!((want.width(), want.height()), (frame.width(), frame.height()), "size of {name}");
    let (mut outliers, mut worst) = (0usize, 0u8);
    for (a, b) in frame.data().chunks_exact(4).zip(want.data().chunks_exact(4)) {
        let d = a.iter().zip(b).map(|(x, y)| x.abs_diff(*y)).max().unwrap();
        worst = worst.max(d);
        if d > CHANNEL_TOL {
            outliers += 1;
        }
    }
    let px = (frame.width() * frame.height()) as f64;
    if outliers as f64 > px * OUTLIER_FRACTION {
        let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("golden-actual");
        std::fs::create_dir_all(&dir).unwrap();
        let actual = dir.join(format!("{name}.png"));
        frame.save_png(&actual).unwrap();
        panic!(
            "{name}: {outliers} pixels differ by more than {CHANNEL_TOL} (worst {worst}); actual image in {}",
            actual.display()
        );
    }
}

#[test]
fn every_widget_nominal_caution_warning_and_no_data() {
    let mut rig = sheet(steady());
    let f = rig.frame();
    check_golden("widgets", &f);
}

/// Every widget marked stale (as the layout marks one whose vehicle lost its link): the
/// veil covers all it drew, read-outs below it included; the tag stays inside the veil.
#[test]
fn every_widget_stale() {
    let mut rig = sheet(steady());
    rig.frame();
    let window = rig.ds.resolve(&["display", "sheet"]).unwrap();
    for w in rig.ds.children(window).unwrap() {
        rig.ds.set(w, "stale", Value::Bool(true)).unwrap();
    }
    let f = rig.frame();
    check_golden("widgets_stale", &f);
}

/// Staleness follows what a widget shows: with usv1's link lost, the label and the read-out
/// of its data are veiled and tagged; the button its state enables and the alert banner
/// about its fuel look exactly as they did (actions and alerts are never veiled).
#[test]
fn a_stale_label_is_veiled_and_a_button_or_alert_banner_is_not() {
    use mocu_dataserver::ObjectInfo;
    let file = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/stale_label.mocu");
    let mut rig = Rig::new(&file, (480, 200), steady());
    let ds = rig.ds.clone();
    let vs = ds.create_object(Guid::ROOT, ObjectInfo::new("vehicles", "folder")).unwrap();
    let v = ds.create_object(vs, ObjectInfo::new("usv1", "usv")).unwrap();
    let nav = ds.create_object(v, ObjectInfo::new("nav", "nav")).unwrap();
    ds.set(v, "armed", Value::Bool(true)).unwrap();
    ds.set(v, "fuel", Value::Float(0.31)).unwrap();
    ds.set(nav, "heading", Value::Float(47.0)).unwrap();
    ds.set(nav, "speed", Value::Float(6.2)).unwrap();
    let fresh = rig.frame();
    ds.set(v, "link_lost", Value::Bool(true)).unwrap();
    ds.set(v, "stale", Value::Bool(true)).unwrap();
    let stale = rig.frame();
    check_golden("stale_label", &stale);
    let label = |f: &tiny_skia::Pixmap| crop(f, 10, 8, 200, 40);
    assert!(label(&fresh).data() != label(&stale).data(), "the label is veiled");
    let button = |f: &tiny_skia::Pixmap| crop(f, 0, 60, 480, 64);
    assert!(button(&fresh).data() == button(&stale).data(), "the button is not veiled");
    let banner = |f: &tiny_skia::Pixmap| crop(f, 0, 130, 480, 60);
    assert!(banner(&fresh).data() == banner(&stale).data(), "the banner is not veiled");
}

/// A part of a frame.
fn crop(f: &tiny_skia::Pixmap, x: u32, y: u32, w: u32, h: u32) -> tiny_skia::Pixmap {
    let mut out = tiny_skia::Pixmap::new(w, h).unwrap();
    for row in 0..h {
        let src = (((y + row) * f.width() + x) * 4) as usize;
        let dst = (row * w * 4) as usize;
        out.data_mut()[dst..dst + (w * 4) as usize]
            .copy_from_slice(&f.data()[src..src + (w * 4) as usize]);
    }
    out
}

/// Control feedback on gauges and controls (pending, accepted, refused with its reason cut
/// to fit), a hovered button, a pressed one; a disabled button ignores the pointer.
#[test]
fn feedback_hover_press_and_disabled() {
    let mut rig = sheet(steady());
    rig.frame();
    let set = |rig: &Rig, w: &str, state: &str, reason: Option<&str>| {
        let g = rig.widget("sheet", w);
        rig.ds.set(g, "feedback", Value::str(state)).unwrap();
        if let Some(r) = reason {
            rig.ds.set(g, "feedback_reason", Value::str(r)).unwrap();
        }
    };
    set(&rig, "dial_nominal", "pending", None);
    set(&rig, "bar_nominal", "accepted", None);
    set(&rig, "text_nominal", "refused", Some("not armed"));
    set(&rig, "toggle_on", "pending", None);
    set(&rig, "horizon_level", "failed", Some("no attitude source on this vehicle"));
    set(&rig, "button", "accepted", None);
    set(&rig, "button_disabled", "refused", Some("engine off"));
    // The disabled button: pointing at it changes nothing.
    let arm = |f: &tiny_skia::Pixmap| crop(f, 296, 700, 128, 48);
    let before = arm(&rig.frame());
    rig.display.pointer(360.0, 727.0, PointerEvent::Move);
    assert!(before.data() == arm(&rig.frame()).data(), "no hover on a disabled button");
    rig.display.pointer(80.0, 727.0, PointerEvent::Move);
    let f = rig.frame();
    check_golden("button_hover", &crop(&f, 0, 690, 440, 80));
    rig.display.pointer(220.0, 727.0, PointerEvent::Move);
    rig.display.pointer(220.0, 727.0, PointerEvent::Down(0));
    let f = rig.frame();
    check_golden("button_pressed", &crop(&f, 0, 690, 440, 80));
    check_golden("widgets_feedback", &f);
}

/// A paper layout against the built-in simulator (fixed seed, every vehicle started),
/// stepped explicitly for `seconds` of simulated time.
fn paper(layout: &str, size: (u32, u32), seconds: f64) -> (Rig, Sim) {
    let rig = Rig::new(&root().join("layouts").join(layout), size, steady());
    // The shipped profile's chart (layouts/project.toml `[modules.map]`): the harbour.
    let harbour = root().join("layouts/maps/harbour.geojson");
    let chart = mocu_mapdata::MapDataConfig { overlays: vec![harbour], ..Default::default() };
    let map_ctx = ModuleContext::detached("map", rig.ds.clone());
    mocu_host::Module::start(&mut mocu_mapdata::MapDataModule::new(chart), &map_ctx).unwrap();
    let ctx = ModuleContext::detached("sim", rig.ds.clone());
    let cfg = SimConfig { seed: 7, appear_every: 0.0, autostart: true, ..SimConfig::default() };
    let sim = Sim::new(ctx, cfg).unwrap();
    for _ in 0..(seconds * 20.0).round() as usize {
        sim.step(0.05);
    }
    (rig, sim)
}

#[test]
fn layout_usv() {
    let (mut rig, _sim) = paper("usv.mocu", (1920, 1080), 20.0);
    check_golden("layout_usv", &rig.frame());
}

#[test]
fn layout_fig2_handheld() {
    let (mut rig, _sim) = paper("fig2-handheld.mocu", (800, 480), 20.0);
    check_golden("layout_fig2", &rig.frame());
}

#[test]
fn layout_fig3_multi_usv() {
    let (mut rig, _sim) = paper("fig3-multi-usv.mocu", (1920, 1080), 20.0);
    check_golden("layout_fig3", &rig.frame());
}

/// Fig. 1: the payload camera animates into the large place; the midpoint and the end.
#[test]
fn layout_fig1_swap_animation() {
    let (mut rig, _sim) = paper("fig1-swap.mocu", (1920, 1080), 20.0);
    check_golden("layout_fig1", &rig.frame());
    let display = rig.display.display_object();
    let out = rig.ds.call_wait(
        display,
        "swap",
        vec![Value::str("main"), Value::str("chart"), Value::Int(400)],
        None,
    );
    assert!(out.is_accepted(), "{out:?}");
    rig.display.clock().advance(Duration::from_millis(200));
    rig.display.tick_animations();
    check_golden("layout_fig1_swap_mid", &rig.frame());
    rig.display.clock().advance(Duration::from_millis(250));
    rig.display.tick_animations();
    check_golden("layout_fig1_swap_end", &rig.frame());
}

/// §5.1: a click on a transparent pixel of the HUD (a full-screen layer above the map)
/// reaches the map below; a right-click there on a vehicle symbol opens the layout's
/// context menu for its type, whose items run with `self` bound to that vehicle.
#[test]
fn click_through_the_hud_reaches_the_map_and_opens_its_context_menu() {
    let (mut rig, sim) = paper("usv.mocu", (1920, 1080), 20.0);
    rig.frame();
    let map = rig.ds.resolve(&["display", "map"]).unwrap();
    let n = |k: &str| rig.ds.try_get(map, k.into()).and_then(|v| v.as_f64()).unwrap() as f32;
    let (mx, my) = (n("x"), n("y"));
    // The map draws usv1 somewhere in its window; the HUD is transparent there.
    let syms = match rig.ds.call_wait(map, "symbols", vec![], None) {
        mocu_dataserver::CallOutcome::Accepted(v) => v,
        other => panic!("{other:?}"),
    };
    let i = syms.iter().position(|v| v.as_str() == Some("usv1")).expect("usv1 on the map");
    let (sx, sy) = (syms[i + 1].as_f64().unwrap() as f32, syms[i + 2].as_f64().unwrap() as f32);
    let (x, y) = (mx + sx, my + sy);
    let hud = rig.ds.resolve(&["display", "hud"]).unwrap();
    assert_eq!(rig.display.hit_test(x, y).map(|h| h.window), Some(map), "passes the HUD");
    // A HUD widget's pixel (the middle of the speed dial) is the HUD's.
    let dial = rig.widget("hud", "speed");
    let d = |k: &str| rig.ds.try_get(dial, k.into()).and_then(|v| v.as_f64()).unwrap() as f32;
    let (dx, dy) = (d("x") + d("w") / 2.0, d("y") + d("h") / 2.0);
    assert_eq!(rig.display.hit_test(dx, dy).map(|h| h.window), Some(hud));
    rig.display.pointer(x, y, PointerEvent::Move);
    let hit = rig.display.pointer(x, y, PointerEvent::Down(1)).unwrap();
    assert_eq!(hit.window, map);
    rig.display.pointer(x, y, PointerEvent::Up(1));
    let f = rig.frame();
    let menu = rig.ds.resolve(&["display", "context_menu", "menu"]).expect("a context menu");
    let item = |k: &str| rig.ds.try_get(menu, k.into());
    assert_eq!(item("items"), Some(Value::Int(3)));
    assert_eq!(item("item2"), Some(Value::str("Stop")));
    // usv1 is armed (autostart): "Arm" greyed, "Disarm" enabled.
    assert_eq!(item("enabled0"), Some(Value::Bool(false)));
    assert_eq!(item("enabled1"), Some(Value::Bool(true)));
    let win = rig.ds.resolve(&["display", "context_menu"]).unwrap();
    let wn = |k: &str| rig.ds.try_get(win, k.into()).and_then(|v| v.as_f64()).unwrap() as f32;
    let (wx, wy) = (wn("x"), wn("y"));
    // Hover "Stop", then choose it.
    rig.display.pointer(wx + 40.0, wy + 26.0 + 2.5 * 26.0, PointerEvent::Move);
    let f2 = rig.frame();
    let crop_at =
        |f: &tiny_skia::Pixmap| crop(f, (wx as u32).saturating_sub(200), wy as u32 - 40, 400, 160);
    check_golden("context_menu", &crop_at(&f2));
    drop(f);
    rig.display.pointer(wx + 40.0, wy + 26.0 + 2.5 * 26.0, PointerEvent::Down(0));
    rig.display.pointer(wx + 40.0, wy + 26.0 + 2.5 * 26.0, PointerEvent::Up(0));
    rig.frame();
    sim.step(0.05);
    rig.ds.quiesce();
    assert!(rig.ds.resolve(&["display", "context_menu"]).is_none(), "closed after choosing");
    let nav = rig.ds.resolve(&["vehicles", "usv1", "nav"]).unwrap();
    assert_eq!(rig.ds.get(nav, "goal_throttle").unwrap(), Value::Float(0.0), "usv1 stopped");
}

/// Raises an alert as `mocu-layout` does (docs/display.md): what the alert layer reads.
fn raise(ds: &DataServer, severity: &str, text: &str) {
    use mocu_dataserver::ObjectInfo;
    let child = |parent: Guid, name: &str| {
        ds.find_child(parent, name)
            .unwrap()
            .unwrap_or_else(|| ds.create_object(parent, ObjectInfo::new(name, name)).unwrap())
    };
    let folder = child(child(Guid::ROOT, "operator"), "alerts");
    let n = ds.children(folder).unwrap().len() + 1;
    let a = ds.create_object(folder, ObjectInfo::new(&format!("alert{n}"), "alert")).unwrap();
    let now = std::time::SystemTime::now().duration_since(std::time::UNIX_EPOCH).unwrap();
    ds.set(a, "severity", Value::str(severity)).unwrap();
    ds.set(a, "time", Value::Float(now.as_secs_f64())).unwrap();
    ds.set(a, "acknowledged", Value::Bool(false)).unwrap();
    ds.set(a, "text", Value::str(text)).unwrap();
    ds.set(folder, "raised", Value::Int(n as i64)).unwrap();
    ds.set(folder, "unacknowledged", Value::Int(n as i64)).unwrap();
}

/// Every shipped layout at 800×480, 1280×720 and 1920×1080 with alerts raised (the
/// built-in alert layer on top) and the data of a vehicle it shows stale (usv1, whose
/// gauges and header the usv and swap layouts show; ugv1 in the handheld layout; usv2, a
/// strip and a list row, in the multi-USV one): nothing critical off-screen, strips and
/// list within the screen, the veils on the stale vehicle's widgets only.
#[test]
fn every_shipped_layout_at_three_screen_sizes_with_alerts_and_stale_data() {
    // (file, golden name, the vehicle made stale, headers and heading tapes on screen)
    let layouts = [
        ("usv.mocu", "usv", "usv1", 2),
        ("fig1-swap.mocu", "fig1", "usv1", 0),
        ("fig2-handheld.mocu", "fig2", "ugv1", 1),
        ("fig3-multi-usv.mocu", "fig3", "usv2", 1),
    ];
    for (file, name, stale, band) in layouts {
        for size in [(800, 480), (1280, 720), (1920, 1080)] {
            screen_with_alerts_and_stale_data(file, name, stale, band, size);
        }
    }
}

/// The same at 3840×2160 for the layouts whose 4K frames screen_fit.rs does not draw (the
/// handheld and multi-USV ones it does), with the lead vehicle stale (usv1: the one their
/// gauges and header show): the alert layer, the veils, the STALE tags and the header's
/// STALE field grow with the screen.
#[test]
fn the_usv_and_swap_layouts_at_3840_by_2160_with_alerts_and_stale_data() {
    screen_with_alerts_and_stale_data("usv.mocu", "usv", "usv1", 2, (3840, 2160));
    screen_with_alerts_and_stale_data("fig1-swap.mocu", "fig1", "usv1", 0, (3840, 2160));
}

/// One layout on one screen with three alerts raised and `stale` (its vehicle made stale and
/// its link lost): `band` headers and heading tapes are left uncovered by the alert layer,
/// and the frame matches its golden.
fn screen_with_alerts_and_stale_data(
    file: &str,
    name: &str,
    stale: &str,
    band: usize,
    size: (u32, u32),
) {
    let (mut rig, _sim) = paper(file, size, 20.0);
    raise(&rig.ds, "critical", "Link lost with usv2");
    raise(&rig.ds, "warning", "usv1.start_engine: refused — engine already running");
    raise(&rig.ds, "info", "Fuel low on usv3");
    let v = rig.ds.resolve(&["vehicles", stale]).unwrap();
    rig.ds.set(v, "stale", Value::Bool(true)).unwrap();
    rig.ds.set(v, "link_lost", Value::Bool(true)).unwrap();
    let f = rig.frame();
    let what = format!("{name} {size:?}");
    assert_eq!(alerts_cover_neither_header_nor_tape(&rig.ds, &what), band, "{what}");
    check_golden(&format!("screen_{name}_{}x{}", size.0, size.1), &f);
}

/// A window's or widget's rectangle on the screen: x, y, w, h.
type ScreenRect = (f64, f64, f64, f64);

fn rect_of(ds: &DataServer, g: Guid, origin: (f64, f64)) -> ScreenRect {
    let n = |k: &str| ds.try_get(g, k.into()).and_then(|v| v.as_f64()).unwrap_or(0.0);
    (origin.0 + n("x"), origin.1 + n("y"), n("w"), n("h"))
}

fn overlap(a: ScreenRect, b: ScreenRect) -> bool {
    a.0 < b.0 + b.2 && b.0 < a.0 + a.2 && a.1 < b.1 + b.3 && b.1 < a.1 + a.3
}

/// The built-in alert layer's window overlaps no `StatusHeader` or `HeadingTape` of the
/// layout (the top band): alerts never cover the vehicle's state or its heading. Returns
/// how many of those it checked.
fn alerts_cover_neither_header_nor_tape(ds: &DataServer, what: &str) -> usize {
    let mut checked = 0;
    let display = ds.resolve(&["display"]).unwrap();
    let layer = ds.resolve(&["display", "alert_layer"]).expect("the built-in alert layer");
    let alerts = rect_of(ds, layer, (0.0, 0.0));
    for win in ds.children(display).unwrap() {
        if win == layer || ds.try_get(win, "visible".into()) == Some(Value::Bool(false)) {
            continue;
        }
        let origin = rect_of(ds, win, (0.0, 0.0));
        for w in ds.children(win).unwrap() {
            let comp = ds.try_get(w, "component".into());
            let comp = comp.as_ref().and_then(Value::as_str).unwrap_or_default();
            if comp == "StatusHeader" || comp == "HeadingTape" {
                let r = rect_of(ds, w, (origin.0, origin.1));
                assert!(
                    !overlap(alerts, r),
                    "{what}: the alert layer {alerts:?} covers {comp} {r:?}"
                );
                checked += 1;
            }
        }
    }
    checked
}

/// Fig. 3 with eight USVs on every screen from 800×480 to 3840×2160: the strips its flow
/// places above the dial (the others hidden and counted "+N more" under them), none over
/// another, over the dial, the horizon, the legend or the vehicle list, all on the screen;
/// the vehicle list ends with "+N more" too. The frame at 1280×720 is a golden image.
#[test]
fn fig3_with_eight_usvs_overlaps_nothing_at_any_screen_size() {
    for size in [(800, 480), (1280, 720), (1920, 1080), (3840, 2160)] {
        let rig = Rig::new(&root().join("layouts/fig3-multi-usv.mocu"), size, steady());
        let ctx = ModuleContext::detached("sim", rig.ds.clone());
        let cfg = SimConfig {
            seed: 7,
            usv: 8,
            appear_every: 0.0,
            autostart: true,
            ..SimConfig::default()
        };
        let sim = Sim::new(ctx, cfg).unwrap();
        for _ in 0..100 {
            sim.step(0.05);
        }
        let mut rig = rig;
        let f = rig.frame();
        let ds = &rig.ds;
        let screen = (0.0, 0.0, size.0 as f64, size.1 as f64);
        let others: Vec<(&str, ScreenRect)> = ["speed", "horizon", "legend", "fleet", "tape"]
            .into_iter()
            .map(|w| (w, rect_of(ds, rig.widget("overlay", w), (0.0, 0.0))))
            .collect();
        let display = ds.resolve(&["display"]).unwrap();
        let mut shown: Vec<(String, ScreenRect)> = Vec::new();
        for w in ds.children(display).unwrap() {
            let name = ds.info(w).unwrap().name.to_string();
            if name.starts_with("strip") && ds.get(w, "visible").unwrap() == Value::Bool(true) {
                shown.push((name, rect_of(ds, w, (0.0, 0.0))));
            }
        }
        let strips = shown.iter().filter(|(n, _)| n.starts_with("strip@")).count();
        assert!((3..8).contains(&strips), "{size:?}: {strips} strips shown");
        let more = ds.resolve(&["display", "strip+more"]).unwrap();
        assert_eq!(ds.get(more, "more").unwrap(), Value::Int(8 - strips as i64), "{size:?}");
        assert!(shown.iter().any(|(n, _)| n == "strip+more"), "{size:?}: no \"+N more\"");
        for (i, (a, ra)) in shown.iter().enumerate() {
            let on_screen = ra.0 >= 0.0 && ra.1 >= 0.0 && ra.0 + ra.2 <= screen.2;
            assert!(on_screen && ra.1 + ra.3 <= screen.3, "{size:?}: {a} {ra:?} off the screen");
            for (b, rb) in
                shown[i + 1..].iter().map(|(n, r)| (n.as_str(), *r)).chain(others.clone())
            {
                assert!(!overlap(*ra, rb), "{size:?}: {a} {ra:?} overlaps {b} {rb:?}");
            }
        }
        if size == (1280, 720) {
            check_golden("fig3_eight_usvs_1280x720", &f);
        }
    }
}

/// The built-in alert layer takes the pointer only where it draws: a press on a row
/// acknowledges that alert, on the count line all of them; the layer then draws nothing
/// and a press there reaches the window below.
#[test]
fn pressing_an_alert_row_acknowledges_it_and_the_count_line_acknowledges_all() {
    let (mut rig, _sim) = paper("usv.mocu", (1280, 720), 1.0);
    // Two refused commands (the engine runs already): alerts raised by the layout.
    let engine = rig.widget("hud", "engine");
    for _ in 0..2 {
        rig.ds.call_wait(engine, "press", vec![], None);
        rig.frame();
    }
    let layer = rig.ds.resolve(&["display", "alert_layer"]).expect("the built-in alert layer");
    let ds = rig.ds.clone();
    let n = |k: &str| ds.get(layer, k).unwrap().as_f64().unwrap() as f32;
    let widget = rig.ds.resolve(&["display", "alert_layer", "alerts"]).unwrap();
    let s = mocu_widgets::alerts::scale_of(rig.ds.get(widget, "scale").unwrap().as_f64());
    let plan =
        mocu_widgets::alerts::plan(&rig.ds, mocu_display::Rect::new(0.0, 0.0, n("w"), n("h")), s);
    assert_eq!(plan.unacknowledged, 2);
    let (first, r) = plan.rows[0].clone();
    assert_eq!(first.severity, "warning");
    assert!(first.text.contains("refused"), "{}", first.text);
    let (x, y) = (n("x") + r.x + r.w / 2.0, n("y") + r.y + r.h / 2.0);
    assert_eq!(rig.display.hit_test(x, y).map(|h| h.window), Some(layer));
    rig.display.pointer(x, y, PointerEvent::Down(0));
    rig.display.pointer(x, y, PointerEvent::Up(0));
    rig.frame();
    assert_eq!(rig.ds.get(first.object, "acknowledged").unwrap(), Value::Bool(true));
    let head = plan.head.unwrap();
    let (hx, hy) = (n("x") + head.x + 40.0, n("y") + head.y + head.h / 2.0);
    rig.display.pointer(hx, hy, PointerEvent::Down(0));
    rig.display.pointer(hx, hy, PointerEvent::Up(0));
    rig.frame();
    let folder = rig.ds.resolve(&["operator", "alerts"]).unwrap();
    assert_eq!(rig.ds.get(folder, "unacknowledged").unwrap(), Value::Int(0));
    assert_ne!(
        rig.display.hit_test(x, y).map(|h| h.window),
        Some(layer),
        "nothing drawn there now"
    );
}
