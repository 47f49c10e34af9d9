//! Damage repaints draw what a full repaint draws: a widget redrawn alone (its value
//! changed) leaves every pixel of its neighbours as they were, labels overhanging their
//! box included (issue 14: a label within 16 px above a live gauge was erased).

use mocu_dataserver::{Config, DataServer, Guid, ObjectInfo, Value};
use mocu_display::{Clock, Display, DisplayOptions};
use mocu_layout::{Layout, LayoutConfig, NullSink};
use mocu_widgets::{Library, RendererConfig, WidgetRenderer};
use std::path::PathBuf;
use std::sync::Arc;
use std::time::Duration;

struct Rig {
    ds: DataServer,
    display: Display,
    layout: Layout,
    probe: Guid,
    _renderer: WidgetRenderer,
}

fn rig() -> Rig {
    let file = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/label_above_gauge.mocu");
    let (bundle, _) = mocu_language::load_target(&file).unwrap();
    let program = &bundle.layouts[0].program;
    let ds = DataServer::new(Config { workers: 2 });
    let probe = ds.create_object(ds.root(), ObjectInfo::new("probe", "probe")).unwrap();
    ds.set(probe, "speed", Value::Float(10.0)).unwrap();
    ds.set(probe, "fuel", Value::Float(0.5)).unwrap();
    let display = Display::new(&ds, DisplayOptions::new(400, 220).clock(Clock::manual())).unwrap();
    let lib = Library::compile(program, true).unwrap();
    let config = RendererConfig {
        stale_after: Duration::from_secs(3600),
        accepted_for: Duration::from_secs(3600),
        refused_for: Duration::from_secs(3600),
    };
    let renderer = WidgetRenderer::start(&ds, lib, config).unwrap();
    let lc = LayoutConfig { screen: (400.0, 220.0), ..LayoutConfig::default() };
    let layout = Layout::load(&ds, program, lc, Arc::new(NullSink)).unwrap();
    Rig { ds, display, layout, probe, _renderer: renderer }
}

impl Rig {
    fn frame(&mut self) -> tiny_skia::Pixmap {
        for _ in 0..3 {
            self.layout.settle();
            self.ds.quiesce();
            self.display.frame();
        }
        self.display.read_frame()
    }
}

/// The pixels of a frame that differ from another's, as (x, y) of the first few.
fn differing(a: &tiny_skia::Pixmap, b: &tiny_skia::Pixmap) -> Vec<(u32, u32)> {
    let w = a.width();
    a.pixels()
        .iter()
        .zip(b.pixels())
        .enumerate()
        .filter(|(_, (p, q))| p != q)
        .map(|(i, _)| (i as u32 % w, i as u32 / w))
        .take(8)
        .collect()
}

/// Whether the frame has any lit pixel inside a rectangle.
fn inked(f: &tiny_skia::Pixmap, x: u32, y: u32, w: u32, h: u32) -> bool {
    (y..y + h).any(|yy| (x..x + w).any(|xx| f.pixel(xx, yy).is_some_and(|p| p.red() > 100)))
}

#[test]
fn labels_above_a_gauge_survive_its_damage_repaint() {
    for (prop, value) in [("speed", 31.0), ("fuel", 0.9), ("speed", 2.5)] {
        let mut rig = rig();
        let before = rig.frame();
        assert!(inked(&before, 20, 2, 120, 18), "the title label is drawn at first");
        assert!(inked(&before, 220, 0, 100, 20), "the large label is drawn at first");
        rig.ds.set(rig.probe, prop, Value::Float(value)).unwrap();
        let partial = rig.frame();
        rig.display.invalidate_all();
        let full = rig.frame();
        assert_ne!(before.data(), full.data(), "{prop} = {value} changed the frame");
        let diff = differing(&partial, &full);
        assert!(diff.is_empty(), "{prop} = {value}: the damage repaint differs at {diff:?}");
    }
}
