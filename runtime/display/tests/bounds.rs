//! A window's layer costs at most the screen: a window far larger than the screen, or with
//! absurd coordinates, allocates only its visible part and still draws that part right.

mod common;
use common::*;
use mocu_dataserver::Value;
use mocu_display::*;

const RED: Color = Color::rgb(255, 0, 0);
const BLUE: Color = Color::rgb(0, 0, 255);

/// Clears the window blue and marks its window-local (100, 100) with a red square.
fn claim_marked(ds: &mocu_dataserver::DataServer, w: mocu_dataserver::Guid) {
    claim_window(ds, w, |c, _| {
        c.clear(BLUE);
        c.fill_rect(Rect::new(100.0, 100.0, 20.0, 20.0), RED);
    })
    .unwrap();
}

#[test]
fn a_window_a_hundred_million_px_wide_costs_one_screen_and_draws_its_visible_part() {
    let (ds, mut d) = world(800, 480);
    let w = window(&ds, &d, "huge", "x", 0, Rect::new(0.0, 0.0, 1e8, 1e8));
    claim_marked(&ds, w);
    let st = frame(&ds, &mut d);
    assert_eq!(&*st.repainted, &["huge".into()] as &[std::sync::Arc<str>]);
    assert_eq!(d.window_manager().layer_size(w), Some((800, 480)));
    let f = d.read_frame();
    assert_eq!(pixel(&f, 110, 110), [255, 0, 0, 255]);
    assert_eq!(pixel(&f, 10, 10), [0, 0, 255, 255]);
    assert_eq!(pixel(&f, 799, 479), [0, 0, 255, 255]);
}

#[test]
fn a_window_hanging_off_the_screen_holds_only_its_part_on_it() {
    let (ds, mut d) = world(800, 480);
    let w = window(&ds, &d, "off", "x", 0, Rect::new(-90.0, -95.0, 300.0, 200.0));
    claim_marked(&ds, w);
    frame(&ds, &mut d);
    assert_eq!(d.window_manager().layer_size(w), Some((210, 105)));
    let f = d.read_frame();
    // Window-local (100, 100) is screen (10, 5).
    assert_eq!(pixel(&f, 15, 10), [255, 0, 0, 255]);
    assert_eq!(pixel(&f, 5, 2), [0, 0, 255, 255]);
    assert_eq!(pixel(&f, 209, 104), [0, 0, 255, 255]);
    assert_ne!(pixel(&f, 210, 105), [0, 0, 255, 255], "beyond the window: not the window");
    // Brought wholly on screen, it is repainted whole and the mark moves with it.
    ds.set(w, "x", Value::Float(0.0)).unwrap();
    ds.set(w, "y", Value::Float(0.0)).unwrap();
    let st = frame(&ds, &mut d);
    assert_eq!(&*st.repainted, &["off".into()] as &[std::sync::Arc<str>]);
    assert_eq!(d.window_manager().layer_size(w), Some((300, 200)));
    let f = d.read_frame();
    assert_eq!(pixel(&f, 110, 110), [255, 0, 0, 255]);
    assert_eq!(pixel(&f, 15, 10), [0, 0, 255, 255]);
}

#[test]
fn a_window_moved_wholly_on_screen_is_still_not_repainted() {
    let (ds, mut d) = world(320, 200);
    let w = window(&ds, &d, "box", "x", 0, Rect::new(10.0, 10.0, 150.0, 150.0));
    claim_marked(&ds, w);
    frame(&ds, &mut d);
    ds.set(w, "x", Value::Float(100.0)).unwrap();
    let st = frame(&ds, &mut d);
    assert!(st.repainted.is_empty(), "{st:?}");
    assert_eq!(pixel(&d.read_frame(), 205, 115), [255, 0, 0, 255]);
}

#[test]
fn absurd_coordinates_show_nothing_and_allocate_nothing() {
    let (ds, mut d) = world(320, 200);
    let far = window(&ds, &d, "far", "x", 0, Rect::new(1e30, -1e30, 1e30, 1e30));
    let nan = window(&ds, &d, "nan", "x", 1, Rect::new(0.0, 0.0, 10.0, 10.0));
    ds.set(nan, "w", Value::Float(f64::NAN)).unwrap();
    claim_marked(&ds, far);
    claim_marked(&ds, nan);
    let st = frame(&ds, &mut d);
    assert!(st.failed.is_empty(), "{st:?}");
    assert_eq!(d.window_manager().layer_size(far), None);
    assert_eq!(d.window_manager().layer_size(nan), None);
    assert_ne!(pixel(&d.read_frame(), 5, 5), [0, 0, 255, 255]);
}

#[test]
fn a_screen_size_beyond_the_limit_is_held_to_it() {
    let (ds, mut d) = world(320, 200);
    let w = window(&ds, &d, "all", "x", 0, Rect::new(0.0, 0.0, 1e9, 1e9));
    claim_marked(&ds, w);
    frame(&ds, &mut d);
    ds.set(d.display_object(), "width", Value::Float(1e12)).unwrap();
    ds.set(d.display_object(), "height", Value::Float(4.0)).unwrap();
    frame(&ds, &mut d);
    let side = mocu_value::limits::MAX_SCREEN_SIDE;
    assert_eq!(d.window_manager().size(), (side, 4));
    assert_eq!(d.window_manager().layer_size(w), Some((side, 4)));
}

#[test]
fn a_damage_repaint_of_a_window_hanging_off_the_screen_lands_on_its_visible_part() {
    let (ds, mut d) = world(320, 200);
    let w = window(&ds, &d, "off", "x", 0, Rect::new(-90.0, -95.0, 300.0, 200.0));
    let mark = std::sync::Arc::new(parking_lot::Mutex::new(RED));
    let m2 = mark.clone();
    claim_window(&ds, w, move |c, _| {
        c.clear(BLUE);
        c.fill_rect(Rect::new(100.0, 100.0, 20.0, 20.0), *m2.lock());
    })
    .unwrap();
    frame(&ds, &mut d);
    *mark.lock() = Color::rgb(0, 255, 0);
    // Half of the damage is off the screen (window-local y 90..95 is above it).
    invalidate_rect(&ds, w, Rect::new(95.0, 90.0, 30.0, 30.0)).unwrap();
    let st = frame(&ds, &mut d);
    assert_eq!(&*st.partial, &["off".into()] as &[std::sync::Arc<str>]);
    assert_eq!(st.damage, IRect::new(5, 0, 30, 25));
    let f = d.read_frame();
    assert_eq!(pixel(&f, 15, 10), [0, 255, 0, 255]);
    assert_eq!(pixel(&f, 7, 2), [0, 0, 255, 255]);
    assert_eq!(pixel(&f, 40, 10), [0, 0, 255, 255], "outside the damage: untouched");
}
