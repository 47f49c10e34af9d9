//! Frames drawn one after another, over layers that are reused (a repaint clears only the
//! tiles the last frame drew on, the compositor reads only drawn tiles and copies an
//! opaque bottom layer, shapes come from cached coverage masks), are the frames a fresh
//! display draws from scratch, pixel for pixel.

mod common;

use common::*;
use mocu_dataserver::{DataServer, Guid, Value};
use mocu_display::*;
use parking_lot::Mutex;
use std::sync::Arc;

const W: u32 = 960;
const H: u32 = 540;

/// What the painters draw.
#[derive(Clone)]
struct Look {
    values: Vec<f32>,
    texts: usize,
    /// A disc drawn over the gauges, moved between frames.
    blob: Point,
    vehicle: Point,
    hud_opacity: f64,
    camera: Rect,
}

fn first_look() -> Look {
    Look {
        values: (0..10).map(|i| i as f32 * 9.5).collect(),
        texts: 60,
        blob: Point::new(300.0, 120.0),
        vehicle: Point::new(300.0, 350.0),
        hud_opacity: 0.95,
        camera: Rect::new(40.0, 30.0, 300.0, 200.0),
    }
}

struct Scene {
    ds: DataServer,
    d: Display,
    look: Arc<Mutex<Look>>,
    map: Guid,
    hud: Guid,
    cam: Guid,
}

/// A chart, a translucent HUD of gauges, texts and a disc over it, and a translucent
/// camera window between them.
fn scene(look: Look) -> Scene {
    let (ds, mut d) = world(W, H);
    let full = Rect::new(0.0, 0.0, W as f32, H as f32);
    let map = window(&ds, &d, "map", "map", 0, full);
    let cam = window(&ds, &d, "cam", "video", 5, look.camera);
    let hud = window(&ds, &d, "hud", "widgets", 10, full);
    ds.set(cam, "opacity", Value::Float(0.8)).unwrap();
    ds.set(hud, "opacity", Value::Float(look.hud_opacity)).unwrap();
    let look = Arc::new(Mutex::new(look));
    let l = look.clone();
    claim_window(&ds, map, move |c, _| demo::sea_chart(c, l.lock().vehicle, 30.0)).unwrap();
    claim_window(&ds, cam, |c, _| demo::camera_view(c, "CAM", Color::rgb(90, 60, 40))).unwrap();
    let l = look.clone();
    claim_window(&ds, hud, move |c, _| {
        let l = l.lock().clone();
        demo::gauge_board(c, &l.values, l.texts);
        c.fill_circle(l.blob, 30.0, Color::rgba(255, 60, 60, 160));
        c.stroke_arc(l.blob, 40.0, 0.3, 2.0, &Stroke::new(5.0), Color::rgba(60, 230, 120, 200));
    })
    .unwrap();
    frame(&ds, &mut d);
    Scene { ds, d, look, map, hud, cam }
}

/// The frame a fresh display draws for `look`.
fn from_scratch(look: &Look) -> tiny_skia::Pixmap {
    scene(look.clone()).d.read_frame()
}

fn assert_same(step: &str, s: &mut Scene) {
    let fresh = from_scratch(&s.look.lock());
    let drawn = s.d.read_frame();
    let differ = drawn.pixels().iter().zip(fresh.pixels()).filter(|(a, b)| a != b).count();
    assert_eq!(differ, 0, "{step}: {differ} pixels differ from a frame drawn from scratch");
}

#[test]
fn reused_layers_draw_what_a_fresh_display_draws() {
    let mut s = scene(first_look());
    assert_same("first frame", &mut s);

    // The disc moves: where it was is cleared, where it is drawn.
    s.look.lock().blob = Point::new(620.0, 300.0);
    invalidate(&s.ds, s.hud).unwrap();
    frame(&s.ds, &mut s.d);
    assert_same("disc moved", &mut s);

    // Fewer texts and other values: the texts' tiles are cleared, the arcs redrawn.
    {
        let mut l = s.look.lock();
        l.texts = 10;
        l.values = (0..10).map(|i| 95.0 - i as f32 * 7.0).collect();
    }
    invalidate(&s.ds, s.hud).unwrap();
    frame(&s.ds, &mut s.d);
    assert_same("fewer texts, new values", &mut s);

    // The chart repaints under an unchanged HUD; the camera moves; the HUD fades.
    s.look.lock().vehicle = Point::new(700.0, 420.0);
    invalidate(&s.ds, s.map).unwrap();
    frame(&s.ds, &mut s.d);
    assert_same("chart repainted", &mut s);
    s.look.lock().camera = Rect::new(500.0, 250.0, 300.0, 200.0);
    s.ds.set(s.cam, "x", Value::Float(500.0)).unwrap();
    s.ds.set(s.cam, "y", Value::Float(250.0)).unwrap();
    frame(&s.ds, &mut s.d);
    assert_same("camera moved", &mut s);
    s.look.lock().hud_opacity = 0.6;
    s.ds.set(s.hud, "opacity", Value::Float(0.6)).unwrap();
    frame(&s.ds, &mut s.d);
    assert_same("HUD faded", &mut s);

    // The same frame twice over reused layers and cached masks.
    s.d.invalidate_all();
    frame(&s.ds, &mut s.d);
    assert_same("everything repainted", &mut s);
}

#[test]
fn a_damage_repaint_clears_and_redraws_only_inside_the_damage() {
    let mut s = scene(first_look());
    // The disc leaves a rectangle that is then repainted alone.
    let old = s.look.lock().blob;
    s.look.lock().blob = Point::new(800.0, 80.0);
    let r = Rect::new(old.x - 46.0, old.y - 46.0, 92.0, 92.0);
    invalidate_rect(&s.ds, s.hud, r).unwrap();
    let st = frame(&s.ds, &mut s.d);
    assert_eq!(st.partial.len(), 1, "{st:?}");
    // Inside the rectangle the disc is gone; outside it nothing changed (the disc's new
    // place is outside, so it is not drawn yet).
    let mut expect = s.look.lock().clone();
    expect.blob = Point::new(-500.0, -500.0);
    let without = from_scratch(&expect);
    let drawn = s.d.read_frame();
    let at = |p: &tiny_skia::Pixmap, x: u32, y: u32| pixel(p, x, y);
    assert_eq!(at(&drawn, old.x as u32, old.y as u32), at(&without, old.x as u32, old.y as u32));
    assert_eq!(
        at(&drawn, old.x as u32 + 20, old.y as u32),
        at(&without, old.x as u32 + 20, old.y as u32)
    );
    assert_ne!(at(&drawn, 800, 80), at(&from_scratch(&s.look.lock()), 800, 80), "not drawn yet");
}
