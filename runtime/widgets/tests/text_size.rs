//! Text on the smallest screen an OCU meets: every shipped layout on 800×480 draws no text
//! run under 12 px. A layout with `design` shrinks its boxes there, never its components'
//! text (the scale components draw at is never below 1; docs/language.md, "Screen sizes").
//!
//! Every widget of every window is drawn through a canvas that records each text run's
//! height on the screen (its size times the canvas transform's vertical scale): components
//! from their shapes, as the widget renderer draws them, and native widgets by their
//! painters. The layout runs against the simulator under a fixed seed (templates filled).

use mocu_dataserver::{Config, DataServer, ManualClock, Value};
use mocu_display::{
    Brush, Canvas, Color, Image, ImageFit, Path, Point, Rect, Size, SkiaCanvas, Stroke,
    TextMetrics, TextStyle, Transform,
};
use mocu_host::ModuleContext;
use mocu_layout::{Layout, LayoutConfig, NullSink};
use mocu_sim::{Sim, SimConfig};
use mocu_widgets::Library;
use std::collections::HashMap;
use std::sync::Arc;
use std::time::Duration;

mod shipped;
use shipped::layouts;

const MIN_SIZE: f32 = 12.0;
const SCREEN: (u32, u32) = (800, 480);

/// A canvas that draws as the CPU path does and records every visible text run's height.
struct Sizes {
    main: SkiaCanvas,
    widget: String,
    runs: Vec<(String, String, f32)>,
}

impl Canvas for Sizes {
    fn size(&self) -> Size {
        self.main.size()
    }
    fn damage(&self) -> Rect {
        self.main.damage()
    }
    fn save(&mut self) {
        self.main.save();
    }
    fn restore(&mut self) {
        self.main.restore();
    }
    fn transform(&mut self, t: Transform) {
        self.main.transform(t);
    }
    fn current_transform(&self) -> Transform {
        self.main.current_transform()
    }
    fn clip_rect(&mut self, r: Rect) {
        self.main.clip_rect(r);
    }
    fn clear(&mut self, color: Color) {
        self.main.clear(color);
    }
    fn fill_path(&mut self, path: &Path, brush: &Brush) {
        self.main.fill_path(path, brush);
    }
    fn stroke_path(&mut self, path: &Path, stroke: &Stroke, brush: &Brush) {
        self.main.stroke_path(path, stroke, brush);
    }
    fn draw_image(&mut self, image: &Image, dst: Rect, fit: ImageFit, opacity: f32) {
        self.main.draw_image(image, dst, fit, opacity);
    }
    fn draw_text(&mut self, text: &str, at: Point, style: &TextStyle) -> TextMetrics {
        if style.color.a > 0 && !text.trim().is_empty() {
            let t = self.main.current_transform();
            let scale = (t.kx * t.kx + t.sy * t.sy).sqrt();
            self.runs.push((self.widget.clone(), text.to_string(), style.size * scale));
        }
        self.main.draw_text(text, at, style)
    }
}

/// Every text run of `file` on an 800×480 screen: (widget, text, height in px).
fn text_runs(file: &std::path::Path) -> Vec<(String, String, f32)> {
    let (bundle, _) =
        mocu_language::load_target(file).unwrap_or_else(|e| panic!("{}: {e:?}", file.display()));
    let program = &bundle.layouts[0].program;
    let clock = ManualClock::new();
    clock.set_wall(std::time::UNIX_EPOCH + Duration::from_secs(86_400 * 20_000 + 50_587));
    let ds = DataServer::with_clock(Config { workers: 1 }, Arc::new(clock));
    mocu_display::ensure_display_object(&ds, SCREEN.0, SCREEN.1).expect("display object");
    let lc = LayoutConfig {
        screen: (SCREEN.0 as f64, SCREEN.1 as f64),
        alerts_to_terminal: false,
        ..LayoutConfig::default()
    };
    let layout = Layout::load(&ds, program, lc, Arc::new(NullSink)).expect("layout loads");
    let ctx = ModuleContext::detached("sim", ds.clone());
    let cfg = SimConfig { seed: 7, appear_every: 0.0, autostart: true, ..SimConfig::default() };
    let sim = Sim::new(ctx, cfg).unwrap();
    for _ in 0..100 {
        sim.step(0.05);
    }
    layout.settle();
    ds.quiesce();
    let lib = Library::compile(program, false).expect("components compile");
    let mut c = Sizes {
        main: SkiaCanvas::new(
            tiny_skia::Pixmap::new(SCREEN.0, SCREEN.1).expect("pixmap"),
            (0, 0),
            Size::new(SCREEN.0 as f32, SCREEN.1 as f32),
        ),
        widget: String::new(),
        runs: Vec::new(),
    };
    let display = ds.resolve(&["display"]).expect("root.display");
    for window in ds.children(display).expect("windows") {
        for w in ds.children(window).unwrap_or_default() {
            let props: HashMap<String, Value> = ds
                .properties(w)
                .expect("properties")
                .into_iter()
                .map(|(n, v)| (n.as_str().to_string(), v))
                .collect();
            if props.get("visible").and_then(Value::as_bool) == Some(false) {
                continue;
            }
            let num = |k: &str| props.get(k).and_then(Value::as_f64).map(|x| x as f32);
            let (Some(x), Some(y)) = (num("x"), num("y")) else { continue };
            let bounds = match (num("w"), num("h")) {
                (Some(ww), Some(hh)) => Some(Rect::new(x, y, ww, hh)),
                _ => None,
            };
            let component = props.get("component").and_then(Value::as_str).unwrap_or("");
            c.widget = ds.info(w).map(|i| i.name.to_string()).unwrap_or_default();
            c.save();
            c.translate(x, y);
            if let Some(comp) = lib.components.get(component) {
                // As the renderer does (renderer/paint.rs): at the widget's scale, with `w`
                // and `h` in design px.
                let s = num("scale").filter(|s| *s > 0.0).unwrap_or(1.0);
                let prop = |name: &str| match name {
                    "w" | "h" => {
                        props.get(name).and_then(Value::as_f64).map(|v| Value::Float(v / s as f64))
                    }
                    _ => props.get(name).cloned(),
                };
                let outs = lib.evaluate(comp, &prop);
                c.scale(s, s);
                mocu_widgets::draw::draw_shapes(&mut c, &comp.shapes, &outs);
            } else {
                mocu_widgets::renderer::draw_native(&mut c, &ds, component, &props, bounds);
            }
            c.restore();
        }
    }
    drop(sim);
    c.runs
}

/// On 800×480 — a 1280×720 design drawn at 0.625 — no shipped layout draws text under
/// 12 px: the boxes shrink, the text does not.
#[test]
fn every_shipped_layout_on_800_by_480_draws_no_text_under_12_px() {
    for file in layouts() {
        let runs = text_runs(&file);
        assert!(runs.len() >= 5, "{}: too few text runs ({})", file.display(), runs.len());
        let small: Vec<String> = runs
            .iter()
            .filter(|(_, _, px)| *px < MIN_SIZE - 0.01)
            .map(|(w, t, px)| format!("{w} {t:?}: {px:.1} px"))
            .collect();
        assert!(
            small.is_empty(),
            "{}: text under {MIN_SIZE} px on 800×480:\n{}",
            file.display(),
            small.join("\n")
        );
    }
}
