//! The layered display: window manager, compositing, damage, hit-testing, animation.
//! Golden images live in tests/golden (regenerate with `UPDATE_GOLDEN=1`); tolerance in
//! tests/common.rs.

mod common;
use common::*;
use mocu_dataserver::{CallOutcome, MethodSpec, ParamSpec, Value, ValueKind};
use mocu_display::demo::{self, palette};
use mocu_display::*;
use std::sync::Arc;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::Duration;

/// A map module and a HUD module that know nothing of each other, plus a translucent
/// alert box from a third.
fn two_modules(
    ds: &mocu_dataserver::DataServer,
    d: &Display,
) -> (mocu_dataserver::Guid, mocu_dataserver::Guid) {
    let map = window(ds, d, "map", "map", 0, Rect::new(0.0, 0.0, 640.0, 400.0));
    let hud = window(ds, d, "hud", "widgets", 10, Rect::new(0.0, 0.0, 640.0, 400.0));
    ds.set(hud, "opacity", Value::Float(0.9)).unwrap();
    claim_window(ds, map, |c, _| demo::sea_chart(c, Point::new(200.0, 260.0), 40.0)).unwrap();
    claim_window(ds, hud, |c, _| {
        demo::panel(c, Rect::new(12.0, 12.0, 200.0, 200.0), "PROPULSION");
        demo::gauge(c, Point::new(112.0, 122.0), 80.0, 23.0, 0.0, 40.0, "SPD", "kn");
        demo::panel(c, Rect::new(440.0, 12.0, 188.0, 64.0), "HEADING");
        c.draw_text(
            "HDG 040°",
            Point::new(534.0, 50.0),
            &TextStyle::new(22.0, palette::TEXT).align(Align::Center).bold(),
        );
    })
    .unwrap();
    (map, hud)
}

#[test]
fn overlapping_translucent_layers_from_independent_modules() {
    let (ds, mut d) = world(640, 400);
    two_modules(&ds, &d);
    let alert = window(&ds, &d, "alert", "alerts", 20, Rect::new(380.0, 280.0, 240.0, 90.0));
    ds.set(alert, "opacity", Value::Float(0.75)).unwrap();
    claim_window(&ds, alert, |c, _| {
        let s = c.size();
        c.fill_rounded_rect(
            Rect::new(0.0, 0.0, s.w, s.h),
            10.0,
            &Brush::Solid(Color::rgba(120, 0, 0, 200)),
        );
        c.draw_text(
            "FUEL LOW",
            Point::new(s.w / 2.0, s.h / 2.0),
            &TextStyle::new(28.0, palette::WARN)
                .align(Align::Center)
                .baseline(Baseline::Middle)
                .bold(),
        );
    })
    .unwrap();
    let st = frame(&ds, &mut d);
    assert!(st.drawn);
    assert_eq!(&*st.repainted, &["map".into(), "hud".into(), "alert".into()] as &[Arc<str>]);
    check_golden("layers", &d.read_frame());
}

#[test]
fn text_renders_with_the_bundled_font() {
    let (ds, mut d) = world(480, 240);
    let w = window(&ds, &d, "text", "widgets", 0, Rect::new(0.0, 0.0, 480.0, 240.0));
    claim_window(&ds, w, |c, _| {
        let t = palette::TEXT;
        c.line(Point::new(240.0, 0.0), Point::new(240.0, 240.0), 1.0, palette::DIM);
        c.draw_text("Left 14px", Point::new(240.0, 10.0), &TextStyle::new(14.0, t));
        c.draw_text(
            "Centre bold 20",
            Point::new(240.0, 40.0),
            &TextStyle::new(20.0, palette::EDGE).align(Align::Center).bold(),
        );
        c.draw_text(
            "Right 28",
            Point::new(240.0, 80.0),
            &TextStyle::new(28.0, palette::WARN).align(Align::Right),
        );
        c.draw_text("°C ±0.5 µs — ÄÖÜ", Point::new(10.0, 130.0), &TextStyle::new(18.0, t));
        let m = c.measure_text("measured", &TextStyle::new(16.0, t));
        c.fill_rect(Rect::new(10.0, 170.0, m.width, m.height), Color::rgba(0, 200, 230, 60));
        c.draw_text("measured", Point::new(10.0, 170.0), &TextStyle::new(16.0, t));
        c.save();
        c.translate(380.0, 180.0);
        c.rotate(-0.5);
        c.draw_text(
            "rotated",
            Point::new(0.0, 0.0),
            &TextStyle::new(18.0, palette::GOOD).align(Align::Center).baseline(Baseline::Middle),
        );
        c.restore();
    })
    .unwrap();
    frame(&ds, &mut d);
    check_golden("text", &d.read_frame());
}

fn test_image() -> Image {
    let (w, h) = (64u32, 40u32);
    let mut v = Vec::new();
    for y in 0..h {
        for x in 0..w {
            let check = ((x / 8) + (y / 8)) % 2 == 0;
            let (r, g) = ((x * 4) as u8, (y * 6) as u8);
            v.extend_from_slice(&if check { [r, g, 200, 255] } else { [20, 20, 20, 255] });
        }
    }
    Image::from_rgba8(w, h, v).unwrap()
}

#[test]
fn images_scale_keeping_their_aspect_ratio() {
    let (ds, mut d) = world(480, 240);
    let w = window(&ds, &d, "video", "video", 0, Rect::new(0.0, 0.0, 480.0, 240.0));
    let img = test_image();
    claim_window(&ds, w, move |c, _| {
        for (i, fit) in
            [ImageFit::Contain, ImageFit::Cover, ImageFit::Stretch].into_iter().enumerate()
        {
            let r = Rect::new(10.0 + i as f32 * 155.0, 10.0, 145.0, 220.0);
            c.fill_rect(r, Color::rgb(40, 0, 40));
            c.draw_image(&img, r, fit, 1.0);
        }
    })
    .unwrap();
    frame(&ds, &mut d);
    let f = d.read_frame();
    // Contain into 145x220: the image is 145 wide and 90.6 tall, centred: magenta bars
    // above and below, none at the sides.
    assert_eq!(pixel(&f, 80, 20), [40, 0, 40, 255]);
    assert_ne!(pixel(&f, 12, 120), [40, 0, 40, 255]);
    check_golden("image", &f);
}

/// Two windows exchange places (paper fig. 1); the manual clock makes the midpoint exact.
#[test]
fn swap_animates_rectangles_with_easing() {
    let (ds, mut d) = world(480, 270);
    let big = Rect::new(0.0, 0.0, 480.0, 270.0);
    let small = Rect::new(330.0, 170.0, 140.0, 90.0);
    let video = window(&ds, &d, "video", "video", 0, big);
    let map = window(&ds, &d, "map", "map", 5, small);
    claim_window(&ds, video, |c, _| demo::camera_view(c, "DRIVE CAM", Color::rgb(70, 90, 120)))
        .unwrap();
    claim_window(&ds, map, |c, _| {
        let s = c.size();
        demo::sea_chart(c, Point::new(s.w * 0.3, s.h * 0.6), 30.0)
    })
    .unwrap();
    frame(&ds, &mut d);
    let swap = ds.call_wait(
        d.display_object(),
        "swap",
        vec![Value::str("video"), Value::str("map"), Value::Int(300)],
        None,
    );
    assert_eq!(swap, CallOutcome::Accepted(vec![]));
    d.clock().advance(Duration::from_millis(150));
    assert!(d.tick_animations(), "still running at the midpoint");
    let st = frame(&ds, &mut d);
    assert_eq!(st.repainted.len(), 2, "both windows change size: {st:?}");
    // Ease-in-out at t=0.5 is exactly half way.
    assert_eq!(ds.get(video, "w").unwrap(), Value::Float((480.0 + 140.0) / 2.0));
    check_golden("swap_mid", &d.read_frame());
    d.clock().advance(Duration::from_millis(200));
    assert!(!d.tick_animations(), "done after 300 ms");
    assert_eq!(d.animator().active(), 0);
    frame(&ds, &mut d);
    for (g, r) in [(video, small), (map, big)] {
        let got: Vec<f64> =
            ["x", "y", "w", "h"].iter().map(|p| ds.get(g, *p).unwrap().as_f64().unwrap()).collect();
        assert_eq!(got, vec![r.x as f64, r.y as f64, r.w as f64, r.h as f64]);
    }
    assert_eq!(ds.get(video, "layer").unwrap(), Value::Int(5), "the inset stays on top");
    assert_eq!(ds.get(map, "layer").unwrap(), Value::Int(0));
    check_golden("swap_end", &d.read_frame());
}

#[test]
fn swap_on_the_real_clock_runs_off_timers_and_stops() {
    // "Real" is the DataServer's clock; a manual one here, so the timers fire when told.
    let clock = mocu_dataserver::ManualClock::new();
    let ds = mocu_dataserver::DataServer::with_clock(
        mocu_dataserver::Config::default(),
        Arc::new(clock.clone()),
    );
    let mut d = Display::new(&ds, DisplayOptions::new(200, 100)).unwrap();
    let a = window(&ds, &d, "a", "x", 0, Rect::new(0.0, 0.0, 100.0, 100.0));
    let b = window(&ds, &d, "b", "x", 0, Rect::new(100.0, 0.0, 100.0, 100.0));
    frame(&ds, &mut d);
    ds.call_wait(
        d.display_object(),
        "swap",
        vec![Value::str("a"), Value::str("b"), Value::Int(100)],
        None,
    );
    // The clock has not moved: the call returned without waiting for the animation.
    assert!(d.animator().active() > 0);
    assert!(ds.pending_timers() > 0, "the next step waits on a timer");
    for _ in 0..100 {
        clock.advance(Duration::from_millis(5));
        ds.quiesce();
    }
    assert_eq!(d.animator().active(), 0);
    assert_eq!(ds.pending_timers(), 0, "no timer left once done");
    assert_eq!(ds.get(a, "x").unwrap(), Value::Float(100.0));
    assert_eq!(ds.get(b, "x").unwrap(), Value::Float(0.0));
}

#[test]
fn a_click_on_a_transparent_hud_pixel_reaches_the_map_below() {
    let (ds, mut d) = world(640, 400);
    let (map, hud) = two_modules(&ds, &d);
    let clicks = Arc::new(parking_lot::Mutex::new(Vec::new()));
    // As a module does, on a serial executor: queued calls on the pool may run in any order
    // (docs/dataserver.md), and the order asserted here is the display's, in which it sends.
    let exec = ds.serial_executor();
    for (g, who) in [(map, "map"), (hud, "hud")] {
        let clicks = clicks.clone();
        ds.publish_method_on(&exec, g, pointer_spec(), move |call| {
            clicks.lock().push(format!("{who}:{}", call.args[0].as_str().unwrap()));
            call.responder.reply(CallOutcome::Accepted(vec![]));
        })
        .unwrap();
    }
    frame(&ds, &mut d);
    // (320, 300) is open sea under a transparent part of the HUD.
    let h = d.hit_test(320.0, 300.0).expect("the map is under the HUD");
    assert_eq!((h.window, &*h.name), (map, "map"));
    // (112, 122) is the speed gauge on the HUD.
    assert_eq!(d.hit_test(112.0, 122.0).unwrap().window, hud);
    d.pointer(320.0, 300.0, PointerEvent::Down(0));
    d.pointer(320.0, 300.0, PointerEvent::Up(0));
    d.pointer(112.0, 122.0, PointerEvent::Move);
    ds.quiesce();
    let got = clicks.lock().clone();
    assert!(got.starts_with(&["map:enter".into(), "map:down".into(), "map:up".into()]), "{got:?}");
    assert!(got.contains(&"map:leave".into()) && got.contains(&"hud:enter".into()), "{got:?}");
    // A hidden HUD passes everything through.
    ds.set(hud, "visible", Value::Bool(false)).unwrap();
    frame(&ds, &mut d);
    assert_eq!(d.hit_test(112.0, 122.0).unwrap().window, map);
}

#[test]
fn a_hit_method_overrides_the_alpha_test() {
    let (ds, mut d) = world(200, 100);
    let (map, hud) = two_modules(&ds, &d);
    ds.publish_method_fn(
        hud,
        MethodSpec::new("hit")
            .param(ParamSpec::new("x", ValueKind::Float))
            .param(ParamSpec::new("y", ValueKind::Float)),
        |a| CallOutcome::Accepted(vec![Value::Bool(a[0].as_f64().unwrap() > 150.0)]),
    )
    .unwrap();
    frame(&ds, &mut d);
    assert_eq!(d.hit_test(160.0, 90.0).unwrap().window, hud, "the HUD claims its right side");
    assert_eq!(d.hit_test(112.0 - 80.0, 95.0).unwrap().window, map);
}

#[test]
fn nothing_changed_means_nothing_drawn() {
    let (ds, mut d) = world(320, 200);
    let calls = Arc::new(AtomicUsize::new(0));
    let w = window(&ds, &d, "w", "x", 0, Rect::new(0.0, 0.0, 320.0, 200.0));
    let c2 = calls.clone();
    claim_window(&ds, w, move |c, _| {
        c2.fetch_add(1, Ordering::SeqCst);
        c.fill_rect(Rect::new(10.0, 10.0, 50.0, 50.0), palette::EDGE);
    })
    .unwrap();
    assert!(frame(&ds, &mut d).drawn);
    let before = d.counters();
    for _ in 0..10 {
        let st = frame(&ds, &mut d);
        assert!(!st.drawn && st.repainted.is_empty() && st.damage.is_empty(), "{st:?}");
    }
    let after = d.counters();
    assert_eq!(after.frames_drawn, before.frames_drawn);
    assert_eq!(after.frames_skipped, before.frames_skipped + 10);
    assert_eq!(calls.load(Ordering::SeqCst), 1, "painted once");
    // A write of an equal value is no change either.
    ds.set(w, "x", Value::Float(0.0)).unwrap();
    assert!(!frame(&ds, &mut d).drawn);
    // Once every notification is delivered, the idle display has nothing to wake for
    // (asked without waiting)...
    ds.quiesce();
    assert!(!d.wait_for_change(Duration::ZERO));
    invalidate(&ds, w).unwrap();
    // ...and wakes on a change (a bounded wait on the change itself).
    assert!(d.wait_for_change(Duration::from_secs(20)));
    let st = frame(&ds, &mut d);
    assert_eq!(&*st.repainted, &["w".into()] as &[Arc<str>]);
    assert_eq!(calls.load(Ordering::SeqCst), 2);
}

#[test]
fn moving_a_window_recomposites_without_repainting() {
    let (ds, mut d) = world(320, 200);
    let bg = window(&ds, &d, "bg", "x", 0, Rect::new(0.0, 0.0, 320.0, 200.0));
    let w = window(&ds, &d, "box", "x", 1, Rect::new(10.0, 10.0, 40.0, 40.0));
    claim_window(&ds, bg, |c, _| c.clear(Color::rgb(0, 0, 80))).unwrap();
    claim_window(&ds, w, |c, _| c.clear(Color::rgb(255, 0, 0))).unwrap();
    frame(&ds, &mut d);
    assert_eq!(pixel(&d.read_frame(), 20, 20), [255, 0, 0, 255]);
    ds.set(w, "x", Value::Float(200.0)).unwrap();
    let st = frame(&ds, &mut d);
    assert!(st.drawn);
    assert!(st.repainted.is_empty(), "{st:?}");
    assert_eq!(st.damage, IRect::new(10, 10, 230, 40), "old and new place");
    let f = d.read_frame();
    assert_eq!(pixel(&f, 20, 20), [0, 0, 80, 255]);
    assert_eq!(pixel(&f, 210, 20), [255, 0, 0, 255]);
    // Opacity too is compositing only.
    ds.set(w, "opacity", Value::Float(0.5)).unwrap();
    let st = frame(&ds, &mut d);
    assert!(st.repainted.is_empty() && st.drawn);
    let p = pixel(&d.read_frame(), 210, 20);
    assert!((p[0] as i32 - 128).abs() <= 1 && (p[2] as i32 - 40).abs() <= 1, "{p:?}");
    // Resizing repaints.
    ds.set(w, "w", Value::Float(60.0)).unwrap();
    assert_eq!(&*frame(&ds, &mut d).repainted, &["box".into()] as &[Arc<str>]);
}

#[test]
fn a_damage_rectangle_repaints_only_that_part() {
    let (ds, mut d) = world(320, 200);
    let w = window(&ds, &d, "board", "widgets", 0, Rect::new(0.0, 0.0, 320.0, 200.0));
    let damages = Arc::new(parking_lot::Mutex::new(Vec::new()));
    let value = Arc::new(parking_lot::Mutex::new(Color::rgb(0, 255, 0)));
    let (d2, v2) = (damages.clone(), value.clone());
    claim_window(&ds, w, move |c, _| {
        d2.lock().push(c.damage());
        c.fill_rect(Rect::new(0.0, 0.0, 320.0, 200.0), Color::rgb(0, 0, 60));
        c.fill_rect(Rect::new(100.0, 50.0, 20.0, 20.0), *v2.lock());
    })
    .unwrap();
    frame(&ds, &mut d);
    *value.lock() = Color::rgb(255, 0, 0);
    invalidate_rect(&ds, w, Rect::new(95.0, 45.0, 30.0, 30.0)).unwrap();
    let st = frame(&ds, &mut d);
    assert_eq!(&*st.partial, &["board".into()] as &[Arc<str>]);
    assert!(st.repainted.is_empty());
    assert_eq!(st.damage, IRect::new(95, 45, 30, 30));
    assert_eq!(damages.lock().last().copied(), Some(Rect::new(95.0, 45.0, 30.0, 30.0)));
    let f = d.read_frame();
    assert_eq!(pixel(&f, 110, 60), [255, 0, 0, 255]);
    assert_eq!(pixel(&f, 10, 10), [0, 0, 60, 255], "outside the damage is untouched");
}

#[test]
fn a_panicking_painter_loses_its_layer_not_the_frame() {
    let (ds, mut d) = world(320, 200);
    let good = window(&ds, &d, "good", "x", 0, Rect::new(0.0, 0.0, 320.0, 200.0));
    let bad = window(&ds, &d, "bad", "x", 1, Rect::new(0.0, 0.0, 160.0, 100.0));
    claim_window(&ds, good, |c, _| c.clear(Color::rgb(0, 80, 0))).unwrap();
    let boom = Arc::new(std::sync::atomic::AtomicBool::new(true));
    let b2 = boom.clone();
    claim_window(&ds, bad, move |c, _| {
        c.clear(Color::rgb(255, 0, 0));
        if b2.load(Ordering::SeqCst) {
            panic!("painter bug");
        }
    })
    .unwrap();
    let st = frame(&ds, &mut d);
    assert!(st.drawn);
    assert_eq!(st.failed.len(), 1);
    assert_eq!(&*st.failed[0].0, "bad");
    assert_eq!(pixel(&d.read_frame(), 10, 10), [0, 80, 0, 255], "the failed layer is skipped");
    assert_eq!(d.counters().paint_failures, 1);
    assert!(ds.get(bad, PAINT_ERROR).unwrap().as_str().unwrap().contains("without answering"));
    // The failure is not retried every frame...
    assert!(!frame(&ds, &mut d).drawn);
    // ...but on the next change.
    boom.store(false, Ordering::SeqCst);
    invalidate(&ds, bad).unwrap();
    let st = frame(&ds, &mut d);
    assert!(st.failed.is_empty());
    assert_eq!(pixel(&d.read_frame(), 10, 10), [255, 0, 0, 255]);
    assert_eq!(ds.get(bad, PAINT_ERROR).unwrap(), Value::str(""));
}

#[test]
fn layers_stack_by_layer_then_declaration_order() {
    let (ds, mut d) = world(100, 100);
    let full = Rect::new(0.0, 0.0, 100.0, 100.0);
    // Declared top first, but on a lower layer number: it is drawn first.
    let a = window(&ds, &d, "a", "x", 5, full);
    let b = window(&ds, &d, "b", "x", 1, full);
    let c = window(&ds, &d, "c", "x", 1, full);
    for (g, col) in
        [(a, Color::rgb(255, 0, 0)), (b, Color::rgb(0, 255, 0)), (c, Color::rgb(0, 0, 255))]
    {
        claim_window(&ds, g, move |cv, _| cv.fill_rect(Rect::new(0.0, 0.0, 100.0, 100.0), col))
            .unwrap();
    }
    let st = frame(&ds, &mut d);
    assert_eq!(&*st.repainted, &["b".into(), "c".into(), "a".into()] as &[Arc<str>]);
    assert_eq!(pixel(&d.read_frame(), 50, 50), [255, 0, 0, 255]);
    ds.set(a, "layer", Value::Int(0)).unwrap();
    let st = frame(&ds, &mut d);
    assert!(st.repainted.is_empty());
    assert_eq!(pixel(&d.read_frame(), 50, 50), [0, 0, 255, 255], "c is on top of b by order");
    // Deleting the top window uncovers the one below.
    ds.delete_object(c).unwrap();
    frame(&ds, &mut d);
    assert_eq!(pixel(&d.read_frame(), 50, 50), [0, 255, 0, 255]);
}

#[test]
fn an_unclaimed_window_is_an_empty_layer_until_a_module_claims_it() {
    let (ds, mut d) = world(100, 100);
    let w = window(&ds, &d, "later", "video", 0, Rect::new(0.0, 0.0, 100.0, 100.0));
    frame(&ds, &mut d);
    assert_eq!(pixel(&d.read_frame(), 5, 5), [8, 10, 14, 255], "background");
    assert!(d.hit_test(5.0, 5.0).is_none());
    claim_window(&ds, w, |c, _| c.clear(Color::rgb(1, 2, 3))).unwrap();
    frame(&ds, &mut d);
    assert_eq!(pixel(&d.read_frame(), 5, 5), [1, 2, 3, 255]);
}

#[test]
fn a_screenshot_is_a_png_of_the_last_frame() {
    let (ds, mut d) = world(64, 32);
    let w = window(&ds, &d, "w", "x", 0, Rect::new(0.0, 0.0, 64.0, 32.0));
    claim_window(&ds, w, |c, _| c.clear(Color::rgb(200, 100, 50))).unwrap();
    frame(&ds, &mut d);
    let path = std::path::PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("shot.png");
    d.screenshot(&path).unwrap();
    let back = tiny_skia::Pixmap::load_png(&path).unwrap();
    assert_eq!((back.width(), back.height()), (64, 32));
    assert_eq!(pixel(&back, 3, 3), [200, 100, 50, 255]);
}

/// Every painter that takes pointer input sees a window's events in the order the window
/// manager sent them, whoever publishes the method and however (the spec is ordered: the
/// DataServer gives a handler published without an executor one of its own).
#[test]
fn pointer_events_reach_every_painter_in_the_order_they_were_sent() {
    assert!(pointer_spec().ordered, "pointer_spec() must stay an ordered spec");
    let (ds, mut d) = world(640, 400);
    let (map, _hud) = two_modules(&ds, &d);
    let seen = Arc::new(parking_lot::Mutex::new(Vec::new()));
    let s2 = seen.clone();
    // The first press is slow to handle (it waits until every event is sent): on the bare
    // pool the others would overtake it.
    let (go, wait) = std::sync::mpsc::sync_channel::<()>(1);
    let wait = parking_lot::Mutex::new(Some(wait));
    // Published the plain way, on the pool, as a hurried painter would.
    ds.publish_method_fn(map, pointer_spec(), move |args| {
        let kind = args[0].as_str().unwrap().to_string();
        if kind == "down"
            && let Some(w) = wait.lock().take()
        {
            let _ = w.recv();
        }
        s2.lock().push(kind);
        CallOutcome::Accepted(vec![])
    })
    .unwrap();
    frame(&ds, &mut d);
    for _ in 0..50 {
        d.pointer(320.0, 300.0, PointerEvent::Down(0));
        d.pointer(330.0, 300.0, PointerEvent::Move);
        d.pointer(330.0, 300.0, PointerEvent::Up(0));
    }
    go.send(()).unwrap();
    ds.quiesce();
    let got: Vec<String> = seen.lock().iter().filter(|k| *k != "enter").cloned().collect();
    let want: Vec<String> =
        (0..50).flat_map(|_| ["down", "move", "up"]).map(String::from).collect();
    assert_eq!(got, want);
}
