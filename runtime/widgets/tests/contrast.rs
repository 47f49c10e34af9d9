//! Text an operator can read: every text run the standard library and the native painters
//! draw is at least 12 px, and its WCAG 2 contrast ratio against what surrounds its glyphs
//! is at least 4.5:1 — measured on the pixels, not read from a table.
//!
//! The widgets of tests/sheet.mocu (every stdlib widget in every state) and
//! tests/contrast.mocu (the status header, labels over video, full and empty bars, disabled
//! controls) and the alert layer are drawn through a probe canvas. For each text run the
//! probe renders the glyphs alone to find their cores (coverage ≥ 60%) and the ring of
//! pixels just outside them (4-neighbours with no coverage), then reads the ring's pixels
//! from the picture as it was before the text was drawn: the text's real background,
//! including any outline or shadow drawn under it, fills, tracks and the "video" the test
//! paints under widgets named `video_*`. The ratio of a run is the 10th percentile over its
//! ring (a tick or needle crossing a sliver of it does not count). `CONTRAST_REPORT=1`
//! prints every run.

use mocu_dataserver::{Config, DataServer, Guid, ManualClock, ObjectInfo, Value};
use mocu_display::{
    Brush, Canvas, Color, Image, ImageFit, Path, Point, Rect, Size, SkiaCanvas, Stroke,
    TextMetrics, TextStyle, Transform,
};
use mocu_layout::{Layout, LayoutConfig, NullSink};
use mocu_widgets::Library;
use std::collections::HashMap;
use std::path::PathBuf;
use std::sync::Arc;
use std::time::Duration;

const MIN_RATIO: f64 = 4.5;
const MIN_SIZE: f32 = 12.0;
const W: u32 = 960;
const H: u32 = 950;

/// One text run as drawn: where, how big, and the measured contrast.
#[derive(Clone, Debug)]
struct Run {
    widget: String,
    text: String,
    size: f32,
    color: Color,
    /// Where it was drawn, in window pixels.
    at: Point,
    ratio: f64,
    /// Its outline: the copies drawn under it (offsets from it) and their colour.
    outline: Vec<(Point, Color)>,
}

impl Run {
    /// Outlined all round: a copy off to the left, the right, above and below.
    fn outlined(&self) -> bool {
        let o = &self.outline;
        o.iter().any(|(d, _)| d.x < 0.0)
            && o.iter().any(|(d, _)| d.x > 0.0)
            && o.iter().any(|(d, _)| d.y < 0.0)
            && o.iter().any(|(d, _)| d.y > 0.0)
    }

    /// The contrast of the text against its outline over the brightest video (white).
    fn against_outline(&self) -> f64 {
        let white = [255.0; 3];
        let halo = |c: Color| over(c, white);
        let worst =
            self.outline.iter().map(|(_, c)| halo(*c)).fold(None, |w: Option<[f64; 3]>, h| {
                Some(match w {
                    Some(w) if luminance(w) >= luminance(h) => w,
                    _ => h,
                })
            });
        worst.map_or(0.0, |h| ratio(over(self.color, h), h))
    }
}

/// A canvas that draws like the real one and measures each text run before drawing it.
struct Probe {
    main: SkiaCanvas,
    ink: SkiaCanvas,
    widget: String,
    runs: Vec<Run>,
}

fn canvas() -> SkiaCanvas {
    let pixmap = tiny_skia::Pixmap::new(W, H).expect("pixmap");
    SkiaCanvas::new(pixmap, (0, 0), Size::new(W as f32, H as f32))
}

/// WCAG 2 relative luminance of an sRGB colour.
fn luminance(rgb: [f64; 3]) -> f64 {
    let lin = |c: f64| {
        let c = c / 255.0;
        if c <= 0.04045 { c / 12.92 } else { ((c + 0.055) / 1.055).powf(2.4) }
    };
    0.2126 * lin(rgb[0]) + 0.7152 * lin(rgb[1]) + 0.0722 * lin(rgb[2])
}

fn ratio(a: [f64; 3], b: [f64; 3]) -> f64 {
    let (la, lb) = (luminance(a), luminance(b));
    (la.max(lb) + 0.05) / (la.min(lb) + 0.05)
}

/// `fg` (with its alpha) over the opaque `bg`.
fn over(fg: Color, bg: [f64; 3]) -> [f64; 3] {
    let a = fg.a as f64 / 255.0;
    let f = [fg.r, fg.g, fg.b].map(f64::from);
    [0, 1, 2].map(|i| f[i] * a + bg[i] * (1.0 - a))
}

impl Probe {
    fn new() -> Probe {
        let mut main = canvas();
        main.clear(mocu_display::BACKGROUND);
        Probe { main, ink: canvas(), widget: String::new(), runs: Vec::new() }
    }

    /// The contrast of `text` drawn now with `style` at `at`: the 10th percentile over the
    /// ring around its glyph cores; `None` when it draws no glyph core (blank or clipped).
    fn measure(&mut self, text: &str, at: Point, style: &TextStyle) -> Option<f64> {
        let white = TextStyle { color: Color::WHITE, ..style.clone() };
        let m = self.ink.draw_text(text, at, &white);
        // The pixels the run can touch, whatever its alignment and baseline.
        let local = Rect::new(
            at.x - m.width - 4.0,
            at.y - m.height * 1.5 - 4.0,
            m.width * 2.0 + 8.0,
            m.height * 3.0 + 8.0,
        );
        let area = self.ink.current_transform().map_rect(local);
        let x0 = area.x.floor().max(0.0) as usize;
        let y0 = area.y.floor().max(0.0) as usize;
        let x1 = ((area.x + area.w).ceil() as usize).min(W as usize);
        let y1 = ((area.y + area.h).ceil() as usize).min(H as usize);
        let alpha: Vec<u8> = {
            let ink = self.ink.pixmap();
            (y0..y1)
                .flat_map(|y| (x0..x1).map(move |x| (x, y)))
                .map(|(x, y)| ink.pixel(x as u32, y as u32).map_or(0, |p| p.alpha()))
                .collect()
        };
        let cols = x1.saturating_sub(x0);
        let a = |x: usize, y: usize| alpha[(y - y0) * cols + (x - x0)];
        let mut ring = Vec::new();
        for y in y0..y1 {
            for x in x0..x1 {
                if a(x, y) != 0 {
                    continue;
                }
                let core = |dx: isize, dy: isize| {
                    let (nx, ny) = (x as isize + dx, y as isize + dy);
                    (x0 as isize..x1 as isize).contains(&nx)
                        && (y0 as isize..y1 as isize).contains(&ny)
                        && a(nx as usize, ny as usize) >= 153
                };
                if core(1, 0) || core(-1, 0) || core(0, 1) || core(0, -1) {
                    ring.push((x as u32, y as u32));
                }
            }
        }
        // Wipe the glyphs for the next run.
        self.ink.save();
        self.ink.clip_rect(local);
        self.ink.clear(Color::TRANSPARENT);
        self.ink.restore();
        let bg = self.main.pixmap();
        let mut ratios: Vec<f64> = ring
            .iter()
            .filter_map(|&(x, y)| bg.pixel(x, y))
            .map(|p| {
                let b = [p.red(), p.green(), p.blue()].map(f64::from);
                ratio(over(style.color, b), b)
            })
            .collect();
        if ratios.is_empty() {
            return None;
        }
        ratios.sort_by(f64::total_cmp);
        Some(ratios[ratios.len() / 10])
    }
}

impl Canvas for Probe {
    fn size(&self) -> Size {
        self.main.size()
    }
    fn damage(&self) -> Rect {
        self.main.damage()
    }
    fn save(&mut self) {
        self.main.save();
        self.ink.save();
    }
    fn restore(&mut self) {
        self.main.restore();
        self.ink.restore();
    }
    fn transform(&mut self, t: Transform) {
        self.main.transform(t);
        self.ink.transform(t);
    }
    fn current_transform(&self) -> Transform {
        self.main.current_transform()
    }
    fn clip_rect(&mut self, r: Rect) {
        self.main.clip_rect(r);
        self.ink.clip_rect(r);
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
        // A transparent run (an outline colour turned off) is not text to read.
        if style.color.a > 0
            && !text.trim().is_empty()
            && let Some(ratio) = self.measure(text, at, style)
        {
            self.runs.push(Run {
                widget: self.widget.clone(),
                text: text.to_string(),
                size: style.size,
                color: style.color,
                at: self.main.current_transform().apply(at),
                ratio,
                outline: Vec::new(),
            });
        }
        self.main.draw_text(text, at, style)
    }
}

/// A bright, busy picture where video would be: white, yellow, grass green, sky, black.
fn paint_video(c: &mut Probe, b: Rect) {
    let stripes = [
        Color::rgb(0xff, 0xff, 0xff),
        Color::rgb(0xe8, 0xd4, 0x4d),
        Color::rgb(0x4c, 0x9a, 0x2a),
        Color::rgb(0x87, 0xce, 0xeb),
        Color::rgb(0x10, 0x10, 0x10),
        Color::rgb(0xb0, 0xb0, 0xb0),
    ];
    let band = 7.0;
    let mut x = b.x - 20.0;
    let mut i = 0;
    while x < b.x + b.w + 20.0 {
        c.main.fill_rect(Rect::new(x, b.y - 12.0, band, b.h + 24.0), stripes[i % stripes.len()]);
        x += band;
        i += 1;
    }
}

/// Draws every widget of the layout `file` through a probe, as the widget renderer does:
/// properties from the world model, components evaluated and drawn from their shapes.
fn draw_sheet(file: &str) -> Vec<Run> {
    // CONTRAST_SHEETS=DIR measures copies elsewhere (another stdlib beside them).
    let dir = std::env::var("CONTRAST_SHEETS").map(PathBuf::from);
    let path = dir.unwrap_or(PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests")).join(file);
    let (bundle, _) = mocu_language::load_target(&path).unwrap_or_else(|e| panic!("{file}: {e:?}"));
    let program = &bundle.layouts[0].program;
    let clock = ManualClock::new();
    clock.set_wall(std::time::UNIX_EPOCH + Duration::from_secs(86_400 * 20_000 + 50_587));
    let ds = DataServer::with_clock(Config { workers: 1 }, Arc::new(clock));
    mocu_display::ensure_display_object(&ds, W, H).expect("display object");
    let lc = LayoutConfig { screen: (W as f64, H as f64), ..LayoutConfig::default() };
    let layout = Layout::load(&ds, program, lc, Arc::new(NullSink)).expect("layout loads");
    layout.settle();
    ds.quiesce();
    let lib = Library::compile(program, false).expect("components compile");
    let window = ds.resolve(&["display", "sheet"]).expect("the sheet window");
    let mut widgets: Vec<Guid> = ds.children(window).expect("widgets");
    let order = |w: &Guid| ds.try_get(*w, "order".into()).and_then(|v| v.as_i64()).unwrap_or(0);
    widgets.sort_by_key(order);
    let mut probe = Probe::new();
    for w in widgets {
        let name = ds.info(w).map(|i| i.name.to_string()).unwrap_or_default();
        let props: HashMap<String, Value> = ds
            .properties(w)
            .expect("properties")
            .into_iter()
            .map(|(n, v)| (n.as_str().to_string(), v))
            .collect();
        let num = |k: &str| props.get(k).and_then(Value::as_f64).map(|x| x as f32);
        let (Some(x), Some(y)) = (num("x"), num("y")) else { continue };
        let component = props.get("component").and_then(Value::as_str).unwrap_or("");
        let comp = lib.components.get(component).unwrap_or_else(|| panic!("{component}"));
        if name.starts_with("video_") {
            let (w, h) = (num("w").unwrap_or(200.0), num("h").unwrap_or(20.0));
            paint_video(&mut probe, Rect::new(x, y, w.max(200.0), h.max(20.0)));
        }
        probe.widget = name;
        probe.save();
        probe.translate(x, y);
        let outs = lib.evaluate(comp, &|k: &str| props.get(k).cloned());
        mocu_widgets::draw::draw_shapes(&mut probe, &comp.shapes, &outs);
        probe.restore();
    }
    // The picture as measured, to look at: target/tmp/contrast/FILE.png.
    let out = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../target/tmp/contrast");
    if std::fs::create_dir_all(&out).is_ok() {
        let _ = probe.main.pixmap().save_png(out.join(file).with_extension("png"));
    }
    probe.runs
}

/// The alert layer with a critical, a warning and an info alert raised.
fn draw_alert_layer() -> Vec<Run> {
    let ds = DataServer::new(Config { workers: 1 });
    let folder = |parent: Guid, name: &str| {
        ds.create_object(parent, ObjectInfo::new(name, "folder")).expect("folder")
    };
    let alerts = folder(folder(Guid::ROOT, "operator"), "alerts");
    let now = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0.0, |d| d.as_secs_f64());
    for (i, (severity, text)) in [
        ("critical", "Link lost with usv2"),
        ("warning", "Fuel low on usv1"),
        ("info", "usv3 armed"),
    ]
    .into_iter()
    .enumerate()
    {
        let a = ds
            .create_object(alerts, ObjectInfo::new(&format!("alert{i}"), "alert"))
            .expect("alert");
        ds.set(a, "severity", Value::from(severity)).expect("set");
        ds.set(a, "text", Value::from(text)).expect("set");
        ds.set(a, "time", Value::Float(now - i as f64)).expect("set");
        ds.set(a, "acknowledged", Value::Bool(false)).expect("set");
    }
    ds.quiesce();
    let mut probe = Probe::new();
    probe.widget = "alert layer".into();
    mocu_widgets::alerts::draw(&mut probe, &ds, Rect::new(0.0, 0.0, 900.0, 300.0), 1.0);
    probe.runs
}

/// The widgets Rust draws: a vehicle list (healthy, weak link and low fuel, link lost, no
/// link data), one that matches no vehicle, a context menu with a disabled and a hovered
/// item, and a video placeholder.
fn draw_native_widgets() -> Vec<Run> {
    let ds = DataServer::new(Config { workers: 1 });
    let vehicles =
        ds.create_object(Guid::ROOT, ObjectInfo::new("vehicles", "folder")).expect("folder");
    let values: [(&str, Option<f64>, Option<f64>, bool); 4] = [
        ("usv1", Some(0.9), Some(0.7), false),
        ("usv2", Some(0.2), Some(0.15), false),
        ("usv3", None, Some(0.5), true),
        ("usv4", None, None, false),
    ];
    for (name, link, fuel, lost) in values {
        let v = ds.create_object(vehicles, ObjectInfo::new(name, "usv")).expect("vehicle");
        if let Some(l) = link {
            ds.set(v, "link", Value::Float(l)).expect("set");
        }
        if let Some(f) = fuel {
            ds.set(v, "fuel", Value::Float(f)).expect("set");
        }
        ds.set(v, "link_lost", Value::Bool(lost)).expect("set");
    }
    ds.quiesce();
    let props = |pairs: &[(&str, Value)]| -> HashMap<String, Value> {
        pairs.iter().map(|(k, v)| (k.to_string(), v.clone())).collect()
    };
    let menu = props(&[
        ("title", Value::from("USV1")),
        ("items", Value::Int(3)),
        ("item0", Value::from("Arm")),
        ("enabled0", Value::Bool(true)),
        ("item1", Value::from("Disarm")),
        ("enabled1", Value::Bool(false)),
        ("item2", Value::from("Stop")),
        ("enabled2", Value::Bool(true)),
        ("hover_row", Value::Int(0)),
    ]);
    let widgets = [
        ("vehicle_list", "VehicleList", props(&[]), Rect::new(10.0, 10.0, 440.0, 140.0)),
        ("vehicle_list_narrow", "VehicleList", props(&[]), Rect::new(10.0, 170.0, 300.0, 140.0)),
        (
            "vehicle_list_none",
            "VehicleList",
            props(&[("filter", Value::from("ugv"))]),
            Rect::new(10.0, 330.0, 300.0, 60.0),
        ),
        ("context_menu", "ContextMenu", menu, Rect::new(500.0, 10.0, 180.0, 110.0)),
        (
            "flow_more",
            "FlowMore",
            props(&[("count", Value::Int(5))]),
            Rect::new(500.0, 130.0, 112.0, 24.0),
        ),
        (
            "video",
            "Video",
            props(&[("source", Value::from("cam1"))]),
            Rect::new(500.0, 170.0, 320.0, 180.0),
        ),
    ];
    let mut probe = Probe::new();
    for (name, component, props, b) in widgets {
        probe.widget = name.into();
        probe.save();
        probe.translate(b.x, b.y);
        mocu_widgets::renderer::draw_native(
            &mut probe,
            &ds,
            component,
            &props,
            Some(Rect::new(0.0, 0.0, b.w, b.h)),
        );
        probe.restore();
    }
    probe.runs
}

fn report(runs: &[Run]) {
    if std::env::var("CONTRAST_REPORT").is_ok_and(|v| v == "1") {
        for r in runs {
            let c = r.color;
            let outline = if r.outline.is_empty() {
                String::new()
            } else {
                let all_round = if r.outlined() { "all round" } else { "partial" };
                format!("  outline {all_round}, {:.2}:1 over white", r.against_outline())
            };
            println!(
                "{:5.2}:1  {:4.1} px  #{:02x}{:02x}{:02x}{:02x}  {:<18} {:?}{outline}",
                r.ratio, r.size, c.r, c.g, c.b, c.a, r.widget, r.text
            );
        }
    }
}

/// The runs an operator reads. An outline copy — a run followed, in the same widget, by one
/// with the same text and size in another colour within 2 px — is part of that later run's
/// background, and is listed as its outline.
fn read(runs: &[Run]) -> Vec<Run> {
    let copy_of = |r: &Run, l: &Run| {
        l.widget == r.widget
            && l.text == r.text
            && l.size == r.size
            && l.color != r.color
            && (l.at.x - r.at.x).abs() <= 2.0
            && (l.at.y - r.at.y).abs() <= 2.0
    };
    let mut out = Vec::new();
    for (i, r) in runs.iter().enumerate() {
        if runs[i + 1..].iter().any(|l| copy_of(r, l)) {
            continue;
        }
        let mut r = r.clone();
        r.outline = runs[..i]
            .iter()
            .filter(|c| copy_of(c, &r))
            .map(|c| (Point::new(c.at.x - r.at.x, c.at.y - r.at.y), c.color))
            .collect();
        out.push(r);
    }
    out
}

/// Readable: 4.5:1 against what surrounds the glyphs, or, over video (widgets named
/// `video_*`), outlined all round with 4.5:1 against the outline over white.
fn readable(r: &Run) -> bool {
    r.ratio >= MIN_RATIO
        || (r.widget.starts_with("video_") && r.outlined() && r.against_outline() >= MIN_RATIO)
}

fn check(runs: &[Run], what: &str) {
    let runs = &read(runs);
    report(runs);
    assert!(runs.len() > 10, "{what}: too few text runs measured ({})", runs.len());
    let low: Vec<String> = runs
        .iter()
        .filter(|r| !readable(r))
        .map(|r| format!("{} {:?}: {:.2}:1", r.widget, r.text, r.ratio))
        .collect();
    assert!(
        low.is_empty(),
        "{what}: text below {MIN_RATIO}:1 against its background:\n{}",
        low.join("\n")
    );
    let small: Vec<String> = runs
        .iter()
        .filter(|r| r.size < MIN_SIZE)
        .map(|r| format!("{} {:?}: {} px", r.widget, r.text, r.size))
        .collect();
    assert!(small.is_empty(), "{what}: text under {MIN_SIZE} px:\n{}", small.join("\n"));
}

#[test]
fn every_stdlib_widget_in_every_state_draws_readable_text() {
    check(&draw_sheet("sheet.mocu"), "tests/sheet.mocu");
}

#[test]
fn status_headers_labels_over_video_bars_and_disabled_controls_draw_readable_text() {
    check(&draw_sheet("contrast.mocu"), "tests/contrast.mocu");
}

#[test]
fn labels_over_video_are_outlined_all_round() {
    let runs = read(&draw_sheet("contrast.mocu"));
    let video: Vec<&Run> = runs.iter().filter(|r| r.widget.starts_with("video_")).collect();
    assert_eq!(video.len(), 3, "{runs:?}");
    for r in video {
        assert!(r.outlined(), "{} {:?}: outline {:?}", r.widget, r.text, r.outline);
        assert!(r.against_outline() >= MIN_RATIO, "{} {:?}", r.widget, r.text);
    }
}

#[test]
fn the_alert_layer_draws_readable_text() {
    let runs = read(&draw_alert_layer());
    report(&runs);
    assert!(runs.len() >= 5, "the count line and three rows: {runs:?}");
    check_all(&runs);
}

fn check_all(runs: &[Run]) {
    for r in runs {
        assert!(readable(r), "{} {:?}: {:.2}:1", r.widget, r.text, r.ratio);
        assert!(r.size >= MIN_SIZE, "{} {:?}: {} px", r.widget, r.text, r.size);
    }
}

#[test]
fn the_vehicle_list_context_menu_and_video_placeholder_draw_readable_text() {
    let runs = read(&draw_native_widgets());
    report(&runs);
    for text in ["VEHICLES", "usv2", "LNK", "FUEL", "— no vehicles —", "Disarm", "USV1"] {
        assert!(runs.iter().any(|r| r.text == text), "{text} is measured: {runs:?}");
    }
    check_all(&runs);
}

#[test]
fn the_probe_tells_low_contrast_from_high() {
    // The measurement itself: white on the bar's green alone is about 2:1, on its dark
    // outline far more; grey #5b6470 on the panel about 3:1.
    let mut p = Probe::new();
    p.main.fill_rect(Rect::new(0.0, 0.0, 300.0, 100.0), Color::rgb(0x22, 0xc5, 0x5e));
    let white = TextStyle::new(14.0, Color::rgb(0xe8, 0xf0, 0xf8));
    let on_green = p.measure("FUEL 72%", Point::new(10.0, 10.0), &white).expect("glyphs");
    assert!((1.8..2.2).contains(&on_green), "{on_green}");
    p.main.fill_rect(Rect::new(0.0, 40.0, 300.0, 40.0), Color::rgba(0, 0, 0, 0xa0));
    let on_dark = p.measure("FUEL 72%", Point::new(10.0, 50.0), &white).expect("glyphs");
    assert!(on_dark > 7.0, "{on_dark}");
    let mut p = Probe::new();
    p.main.fill_rect(Rect::new(0.0, 0.0, 300.0, 100.0), Color::rgb(0x0f, 0x17, 0x1f));
    let grey = TextStyle::new(14.0, Color::rgb(0x5b, 0x64, 0x70));
    let nodata = p.measure("—  NO DATA", Point::new(10.0, 10.0), &grey).expect("glyphs");
    assert!((2.8..3.2).contains(&nodata), "{nodata}");
}
