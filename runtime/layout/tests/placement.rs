//! Screen placement: a layout's `design` size scales its px uniformly to the screen, and
//! anchors keep windows and widgets attached to the edges they are measured from
//! (docs/language.md, "Screen sizes").
mod common;
use common::program;
use mocu_dataserver::*;
use mocu_layout::*;
use std::sync::Arc;
use std::time::Duration;

fn run(text: &str, screen: (f64, f64), jit: bool) -> (DataServer, Layout) {
    let ds = DataServer::default();
    let config = LayoutConfig {
        screen,
        tick: Duration::from_millis(1),
        jit,
        alert_layer: false,
        ..LayoutConfig::default()
    };
    let layout = Layout::load(&ds, &program(text), config, Arc::new(NullSink)).unwrap();
    layout.settle();
    (ds, layout)
}

/// x, y, w, h of an object under `root.display`.
fn rect(ds: &DataServer, path: &[&str]) -> [f64; 4] {
    let g = ds.resolve(path).unwrap_or_else(|| panic!("{path:?} published"));
    ["x", "y", "w", "h"].map(|k| ds.get(g, k).ok().and_then(|v| v.as_f64()).unwrap_or(f64::NAN))
}

const ANCHORED: &str = r#"
design 1280 x 720
window hud  { layer 10  rect 0 0 100% 100% }
window side { layer 5   rect 16 16 320 200  anchor top-right }
window foot { layer 5   rect 0 0 100% 40  anchor bottom }
in hud {
  dial: Video { at 20 20 180 180  anchor bottom-left  source root.cameras.a }
  tape: Video { at 0 20 400 40  anchor top  source root.cameras.a }
  mid: Video { at 0 0 100 100  anchor centre  source root.cameras.a }
  corner: Video { at 10 10 100 50  source root.cameras.a }
}
in side {
  close: Video { at 8 8 32 32  anchor top-right  source root.cameras.a }
}
"#;

#[test]
fn design_px_scale_by_the_smaller_screen_ratio_and_anchors_keep_their_edges() {
    for jit in [true, false] {
        // 1920×1080 is 1.5× the design in both directions.
        let (ds, _l) = run(ANCHORED, (1920.0, 1080.0), jit);
        assert_eq!(rect(&ds, &["display", "side"]), [1920.0 - 24.0 - 480.0, 24.0, 480.0, 300.0]);
        assert_eq!(rect(&ds, &["display", "foot"]), [0.0, 1080.0 - 40.0 * 1.5, 1920.0, 60.0]);
        assert_eq!(
            rect(&ds, &["display", "hud", "dial"]),
            [30.0, 1080.0 - 30.0 - 270.0, 270.0, 270.0]
        );
        assert_eq!(
            rect(&ds, &["display", "hud", "tape"]),
            [(1920.0 - 600.0) / 2.0, 30.0, 600.0, 60.0]
        );
        assert_eq!(rect(&ds, &["display", "hud", "mid"]), [885.0, 465.0, 150.0, 150.0]);
        assert_eq!(rect(&ds, &["display", "hud", "corner"]), [15.0, 15.0, 150.0, 75.0]);
        // A widget's anchor measures from its window (480 px wide here).
        assert_eq!(
            rect(&ds, &["display", "side", "close"]),
            [480.0 - 12.0 - 48.0, 12.0, 48.0, 48.0]
        );
        let display = ds.resolve(&["display"]).unwrap();
        assert_eq!(ds.get(display, "scale").unwrap(), Value::Float(1.5));
        let dial = ds.resolve(&["display", "hud", "dial"]).unwrap();
        assert_eq!(ds.get(dial, "scale").unwrap(), Value::Float(1.5), "components draw at it");
    }
}

#[test]
fn on_a_screen_of_another_shape_the_spare_room_opens_between_opposite_edges() {
    // 800×480 is wider than 16:9 would need at its height ratio: the scale is 800 / 1280.
    let (ds, _l) = run(ANCHORED, (800.0, 480.0), true);
    let s = 0.625;
    let dial = rect(&ds, &["display", "hud", "dial"]);
    assert_eq!(dial, [20.0 * s, 480.0 - 200.0 * s, 180.0 * s, 180.0 * s]);
    let side = rect(&ds, &["display", "side"]);
    assert_eq!(side, [800.0 - 336.0 * s, 16.0 * s, 320.0 * s, 200.0 * s]);
    let dial = ds.resolve(&["display", "hud", "dial"]).unwrap();
    assert_eq!(
        ds.try_get(dial, "scale".into()),
        None,
        "below the design, components draw at their own size in the smaller box"
    );
    // 3840×2160: three times the design, still flush with the bottom-left corner.
    let (ds, _l) = run(ANCHORED, (3840.0, 2160.0), true);
    assert_eq!(rect(&ds, &["display", "hud", "dial"]), [60.0, 2160.0 - 600.0, 540.0, 540.0]);
}

#[test]
fn without_a_design_px_are_screen_px_and_anchors_still_measure_from_their_edge() {
    let text = r#"
window hud { layer 1  rect 0 0 100% 100% }
in hud { c: Video { at 16 8 200 100  anchor bottom-right  source root.cameras.a } }
"#;
    let (ds, _l) = run(text, (1280.0, 720.0), true);
    assert_eq!(rect(&ds, &["display", "hud", "c"]), [1280.0 - 216.0, 720.0 - 108.0, 200.0, 100.0]);
    let c = ds.resolve(&["display", "hud", "c"]).unwrap();
    assert_eq!(ds.try_get(c, "scale".into()), None, "no scale to draw at");
}

#[test]
fn a_template_widget_anchored_in_its_instance_window_follows_that_window() {
    let text = r#"
design 1280 x 720
for each v in root.vehicles {
  window strip { layer 2  rect 20 (20 + index * 100) 400 90  anchor top-right }
  in strip { stop: Video { at 4 4 90 24  anchor bottom-right  source v.cameras.a } }
}
"#;
    let ds = DataServer::default();
    let vs = ds.create_object(Guid::ROOT, ObjectInfo::new("vehicles", "folder")).unwrap();
    ds.create_object(vs, ObjectInfo::new("usv1", "usv")).unwrap();
    ds.create_object(vs, ObjectInfo::new("usv2", "usv")).unwrap();
    let config = LayoutConfig {
        screen: (2560.0, 1440.0),
        tick: Duration::from_millis(1),
        alert_layer: false,
        ..LayoutConfig::default()
    };
    let layout = Layout::load(&ds, &program(text), config, Arc::new(NullSink)).unwrap();
    layout.settle();
    // Scale 2: the second strip is 2 × (20 + 100·index) px down, 40 px from the right edge.
    assert_eq!(rect(&ds, &["display", "strip@usv2"]), [2560.0 - 840.0, 240.0, 800.0, 180.0]);
    assert_eq!(
        rect(&ds, &["display", "strip@usv2", "stop@usv2"]),
        [800.0 - 188.0, 180.0 - 56.0, 180.0, 48.0]
    );
}
