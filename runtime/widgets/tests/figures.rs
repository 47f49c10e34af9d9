//! The paper's three displays (MOCU 3, figures 1–3) at their design sizes with live video:
//! the layout, the widget renderer, the map and the video painter on a headless CPU display,
//! against the simulator under a fixed seed, the DataServer's clock moved with every
//! simulation step (so the cameras' frames, the painter's ticks and the frame rates it shows
//! follow simulated time, the same on every machine).
//!
//! `UPDATE_GOLDEN=1 cargo test -p mocu-widgets --test figures` rewrites their PNGs (in
//! tests/golden/, compared as golden.rs compares).

use mocu_dataserver::{Config, DataServer, Guid, ManualClock, Value};
use mocu_display::touch::TouchPhase;
use mocu_display::{Clock, Display, DisplayOptions, PointerEvent};
use mocu_host::{Module, ModuleContext};
use mocu_layout::{Layout, LayoutConfig, NullSink};
use mocu_mapdata::{MapDataConfig, MapDataModule};
use mocu_sim::{Sim, SimConfig};
use mocu_video::VideoWindows;
use mocu_widgets::{Library, MapModule, RendererConfig, WidgetRenderer};
use std::path::PathBuf;
use std::sync::Arc;
use std::time::Duration;

const CHANNEL_TOL: u8 = 3;
const OUTLIER_FRACTION: f64 = 0.001;

struct Figure {
    ds: DataServer,
    clock: ManualClock,
    display: Display,
    layout: Layout,
    sim: Sim,
    _renderer: WidgetRenderer,
    _map: MapModule,
    _video: VideoWindows,
    _chart: MapDataModule,
}

impl Figure {
    /// `layouts/<file>` on a `size` screen, the simulator run for `seconds`.
    fn new(file: &str, size: (u32, u32), seconds: f64) -> Figure {
        let path = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../layouts").join(file);
        let (bundle, _) =
            mocu_language::load_target(&path).unwrap_or_else(|e| panic!("{file}: {e:?}"));
        let program = &bundle.layouts[0].program;
        // The server's clock reads 14:03:07 UTC at the start (the status header's clock).
        let clock = ManualClock::new();
        clock.set_wall(std::time::UNIX_EPOCH + Duration::from_secs(86_400 * 20_000 + 50_587));
        let ds = DataServer::with_clock(Config { workers: 2 }, Arc::new(clock.clone()));
        let opts = DisplayOptions::new(size.0, size.1).clock(Clock::manual());
        let display = Display::new(&ds, opts).unwrap();
        // The simulator's harbour, as the shipped profile names it (layouts/project.toml).
        let harbour =
            PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../layouts/maps/harbour.geojson");
        let mut chart =
            MapDataModule::new(MapDataConfig { overlays: vec![harbour], ..Default::default() });
        chart.start(&ModuleContext::detached("map", ds.clone())).unwrap();
        let lib = Library::compile(program, true).unwrap();
        let steady = RendererConfig {
            accepted_for: Duration::from_secs(3600),
            refused_for: Duration::from_secs(3600),
            ..RendererConfig::default()
        };
        let renderer = WidgetRenderer::start(&ds, lib, steady).unwrap();
        let map = MapModule::start(&ds).unwrap();
        let video = VideoWindows::start(&ds).unwrap();
        let lc = LayoutConfig {
            screen: (size.0 as f64, size.1 as f64),
            alerts_to_terminal: false,
            ..LayoutConfig::default()
        };
        let layout = Layout::load(&ds, program, lc, Arc::new(NullSink)).unwrap();
        let ctx = ModuleContext::detached("sim", ds.clone());
        let cfg = SimConfig { seed: 7, appear_every: 0.0, autostart: true, ..SimConfig::default() };
        let sim = Sim::new(ctx, cfg).unwrap();
        let mut f = Figure {
            ds,
            clock,
            display,
            layout,
            sim,
            _renderer: renderer,
            _map: map,
            _video: video,
            _chart: chart,
        };
        f.run(seconds);
        f
    }

    /// Simulated time: a step of the simulator and of the DataServer's clock every 50 ms.
    fn run(&mut self, seconds: f64) {
        for _ in 0..(seconds * 20.0).round() as usize {
            self.sim.step(0.05);
            // Frames arrive at the step's time, before the clock moves on.
            self.ds.quiesce();
            self.clock.advance(Duration::from_millis(50));
            self.ds.quiesce();
        }
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

    /// A window's rectangle on the screen.
    fn rect(&self, path: &[&str]) -> [f64; 4] {
        let g = self.ds.resolve(path).unwrap_or_else(|| panic!("no {path:?}"));
        ["x", "y", "w", "h"].map(|k| self.num(g, k))
    }

    fn num(&self, g: Guid, k: &str) -> f64 {
        self.ds.try_get(g, k.into()).and_then(|v| v.as_f64()).unwrap_or(f64::NAN)
    }

    /// A tap (left press and release) in a window, at a fraction of its width and height.
    fn tap(&mut self, window: &str, at: (f64, f64)) {
        let [x, y, w, h] = self.rect(&["display", window]);
        let (x, y) = ((x + w * at.0) as f32, (y + h * at.1) as f32);
        self.display.pointer(x, y, PointerEvent::Move);
        self.display.pointer(x, y, PointerEvent::Down(0));
        self.display.pointer(x, y, PointerEvent::Up(0));
        self.ds.quiesce();
        self.layout.settle();
        self.ds.quiesce();
    }

    /// Moves the display's animations on by `ms`.
    fn animate(&mut self, ms: u64) {
        self.display.clock().advance(Duration::from_millis(ms));
        self.display.tick_animations();
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

const MIDDLE: (f64, f64) = (0.5, 0.5);

/// Which of fig. 1's windows is in the large place.
fn enlarged(f: &Figure) -> &'static str {
    let w = |n: &str| f.rect(&["display", n])[2];
    ["main", "payload", "chart"].into_iter().max_by(|a, b| w(a).total_cmp(&w(b))).unwrap()
}

/// The reticle's centre is the drive camera window's centre (within a pixel).
fn assert_reticle_centred(f: &Figure, when: &str) {
    let [mx, my, mw, mh] = f.rect(&["display", "main"]);
    let [ax, ay, _, _] = f.rect(&["display", "aim"]);
    let [cx, cy, cw, ch] = f.rect(&["display", "aim", "cross"]);
    let (rx, ry) = (ax + cx + cw / 2.0, ay + cy + ch / 2.0);
    let (wx, wy) = (mx + mw / 2.0, my + mh / 2.0);
    assert!(
        (rx - wx).abs() <= 1.0 && (ry - wy).abs() <= 1.0,
        "{when}: the reticle at ({rx}, {ry}), the drive camera's middle at ({wx}, {wy})"
    );
}

/// Fig. 1 on its 800×480 design: the drive camera large, the payload camera and the map
/// small. A tap on the payload camera exchanges it with the drive camera (animated: the
/// midpoint and the end are goldens); then a tap on the map enlarges the map, and a tap in the
/// middle of the small drive camera (where its reticle is) brings it back. The reticle stays
/// on the drive camera's middle at every size, and the payload picture (monochrome, narrow)
/// is not the drive picture.
#[test]
fn figure1_enlarges_any_window_and_the_reticle_stays_on_the_drive_camera() {
    let mut f = Figure::new("fig1-swap.mocu", (800, 480), 6.0);
    let first = f.frame();
    assert_eq!(enlarged(&f), "main");
    assert_reticle_centred(&f, "drive camera large");
    check_golden("figure1_drive_large", &first);
    f.tap("payload", MIDDLE);
    f.animate(200);
    let mid = f.frame();
    assert_reticle_centred(&f, "halfway");
    check_golden("figure1_swap_mid", &mid);
    f.animate(250);
    let end = f.frame();
    assert_eq!(enlarged(&f), "payload", "the payload camera in the large place");
    assert_reticle_centred(&f, "drive camera small");
    check_golden("figure1_payload_large", &end);
    // Clear of the vehicle the map follows (a tap on a symbol selects the vehicle).
    f.tap("chart", (0.85, 0.75));
    f.animate(450);
    f.frame();
    assert_eq!(enlarged(&f), "chart", "the map in the large place");
    assert_eq!(f.rect(&["display", "payload"])[2], 200.0, "the payload camera small again");
    // On the reticle: it takes the press its window would.
    f.tap("main", MIDDLE);
    f.animate(450);
    f.frame();
    assert_eq!(enlarged(&f), "main", "the drive camera back in the large place");
    assert_reticle_centred(&f, "drive camera large again");
}

/// Fig. 1 on screens other than its design, and by touch: each window in turn is tapped in
/// its middle (the drive camera's on its reticle) and grows into the large place, the one
/// there shrinking into its corner; the reticle is on the drive camera's middle before,
/// halfway through and after every exchange.
#[test]
fn figure1_by_touch_at_every_screen_size_the_tapped_window_is_enlarged_under_its_reticle() {
    for size in [(800, 480), (1280, 720), (1920, 1080), (1024, 768)] {
        let mut f = Figure::new("fig1-swap.mocu", size, 0.5);
        f.frame();
        let large = f.rect(&["display", "main"]);
        for (tap, why) in
            [("payload", "payload"), ("main", "drive"), ("chart", "map"), ("main", "drive")]
        {
            let [x, y, w, h] = f.rect(&["display", tap]);
            // The map is tapped clear of the vehicle it follows (a tap there selects it).
            let at = if tap == "chart" { (0.85, 0.75) } else { MIDDLE };
            let (px, py) = ((x + w * at.0) as f32, (y + h * at.1) as f32);
            f.display.touch(1, TouchPhase::Started, px, py);
            f.display.touch(1, TouchPhase::Ended, px, py);
            f.ds.quiesce();
            f.layout.settle();
            f.ds.quiesce();
            f.animate(200);
            f.frame();
            assert_reticle_centred(&f, &format!("{size:?}: halfway to the {why} enlarged"));
            f.animate(250);
            f.frame();
            assert_eq!(enlarged(&f), tap, "{size:?}: a tap on the {why} window enlarges it");
            assert_eq!(f.rect(&["display", tap]), large, "{size:?}: the whole large place");
            assert_reticle_centred(&f, &format!("{size:?}: the {why} enlarged"));
        }
    }
}

/// Fig. 2 on its 800×480 handheld design: the tracked UGV's drive camera large, its payload
/// camera and the map small on the left, the UGV's state; the arm's view is a temporary
/// overlay — there while the arm moves (the golden), gone once it has been still for 5 s.
/// Touch: a tap on the small map swaps it into the main area, a long press on the UGV there
/// opens its menu, a tap chooses an item, a tap on the payload camera swaps it in.
#[test]
fn figure2_shows_the_ugv_its_arm_overlay_while_it_moves_and_answers_touch() {
    let mut f = Figure::new("fig2-handheld.mocu", (800, 480), 8.0);
    f.frame();
    // The operator takes control of the UGV (its menu's "Take control"): the map marks it.
    let ugv = f.ds.resolve(&["vehicles", "ugv1"]).unwrap();
    let taken = f.ds.call_wait(ugv, "request_control", vec![Value::str("handheld")], None);
    assert!(taken.is_accepted(), "{taken:?}");
    let overlay = f.ds.resolve(&["display", "armview"]).unwrap();
    let shown = |f: &Figure| f.ds.try_get(overlay, "visible".into()) == Some(Value::Bool(true));
    assert!(!shown(&f), "the arm still: no overlay");
    let arm = f.ds.resolve(&["vehicles", "ugv1", "manipulator"]).unwrap();
    let args = vec![Value::Float(60.0), Value::Float(100.0), Value::Float(10.0)];
    assert!(f.ds.call_wait(arm, "move_joints", args, None).is_accepted());
    assert!(f.ds.call_wait(arm, "grip", vec![Value::Bool(true)], None).is_accepted());
    f.run(0.6);
    let frame = f.frame();
    assert!(shown(&f), "the arm moving: its view shows");
    let status = f.ds.resolve(&["display", "armview", "arm_status"]).unwrap();
    assert_eq!(f.ds.try_get(status, "moving".into()), Some(Value::Bool(true)));
    check_golden("figure2_handheld", &frame);
    f.run(8.0);
    f.frame();
    assert!(!shown(&f), "still for 5 s: the overlay is gone");
    // Touch: a tap on the small map brings it into the main area; a long press on the UGV
    // there opens the UGV's context menu.
    let touch_tap = |f: &mut Figure, id: u64, x: f32, y: f32| {
        f.display.touch(id, TouchPhase::Started, x, y);
        f.display.touch(id, TouchPhase::Ended, x, y);
        f.ds.quiesce();
        f.layout.settle();
        f.ds.quiesce();
    };
    let [tx, ty, tw, th] = f.rect(&["display", "thumb2"]);
    touch_tap(&mut f, 1, (tx + tw * 0.85) as f32, (ty + th * 0.75) as f32);
    f.animate(300);
    f.frame();
    assert!(f.rect(&["display", "thumb2"])[2] > 500.0, "the map in the main area");
    let map = f.ds.resolve(&["display", "thumb2"]).unwrap();
    let syms = match f.ds.call_wait(map, "symbols", vec![], None) {
        mocu_dataserver::CallOutcome::Accepted(v) => v,
        other => panic!("{other:?}"),
    };
    let i = syms.iter().position(|v| v.as_str() == Some("ugv1")).expect("ugv1 on the map");
    let [mx, my, _, _] = f.rect(&["display", "thumb2"]);
    let (sx, sy) = (syms[i + 1].as_f64().unwrap(), syms[i + 2].as_f64().unwrap());
    let (x, y) = ((mx + sx) as f32, (my + sy) as f32);
    f.display.touch(2, TouchPhase::Started, x, y);
    f.display.clock().advance(Duration::from_millis(600));
    f.display.touch_tick();
    f.display.touch(2, TouchPhase::Ended, x, y);
    f.ds.quiesce();
    f.frame();
    let menu = f.ds.resolve(&["display", "context_menu", "menu"]).expect("a context menu");
    let item = |k: &str| f.ds.try_get(menu, k.into());
    assert_eq!(
        item("item1"),
        Some(Value::str("Stow arm")),
        "{:?} {:?}",
        item("title"),
        item("item0")
    );
    // A tap on "Stow arm" (the second row) stows the arm.
    let [wx, wy, _, _] = f.rect(&["display", "context_menu"]);
    let (x, y) = ((wx + 40.0) as f32, (wy + 26.0 + 1.5 * 26.0) as f32);
    f.display.pointer(x, y, PointerEvent::Move);
    f.display.touch(3, TouchPhase::Started, x, y);
    f.display.touch(3, TouchPhase::Ended, x, y);
    f.ds.quiesce();
    f.run(0.2);
    f.frame();
    assert!(f.ds.resolve(&["display", "context_menu"]).is_none(), "closed after choosing");
    assert_eq!(f.ds.try_get(arm, "moving".into()), Some(Value::Bool(true)), "stowing");
    let [tx, ty, tw, th] = f.rect(&["display", "thumb1"]);
    touch_tap(&mut f, 4, (tx + tw / 2.0) as f32, (ty + th / 2.0) as f32);
    f.animate(300);
    f.frame();
    assert!(f.rect(&["display", "thumb1"])[2] > 500.0, "the payload camera in the main area");
    assert!(f.rect(&["display", "thumb2"])[2] < 300.0, "the map small again");
}

/// Fig. 3 on its 1280×720 design: the lead USV's video with gauges, the second USV's forward
/// view, the map, borders and titles, and the legend of the gamepad bindings in use.
#[test]
fn figure3_shows_the_second_usvs_forward_view_the_map_and_the_bindings() {
    let mut f = Figure::new("fig3-multi-usv.mocu", (1280, 720), 6.0);
    let frame = f.frame();
    let forward = f.ds.resolve(&["display", "forward"]).unwrap();
    assert_eq!(f.ds.try_get(forward, "visible".into()), Some(Value::Bool(true)));
    // The legend's rows: each gamepad binding of the layout with what it does.
    let bindings = f.ds.resolve(&["display", "bindings"]).unwrap();
    let text = |g: Guid, k: &str| match f.ds.try_get(g, k.into()) {
        Some(Value::Str(s)) => s.to_string(),
        _ => String::new(),
    };
    let row = |input: &str| {
        f.ds.children(bindings)
            .unwrap()
            .into_iter()
            .find(|b| text(*b, "device") == "gamepad" && text(*b, "input") == input)
            .map(|b| text(b, "action"))
    };
    assert_eq!(row("east").as_deref(), Some("swap video ⇄ forward"));
    assert_eq!(row("left_y").as_deref(), Some("usv1 throttle"));
    assert_eq!(row("start").as_deref(), Some("usv1 stop, usv2 stop"));
    check_golden("figure3_multi_usv", &frame);
}
