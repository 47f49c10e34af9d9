//! Cached pictures (`mocu_display::picture`): a drawing blitted from its sprite gives the
//! pixels drawing it shape by shape gives, wherever it lands (whole-pixel moves share a
//! sprite, sub-pixel ones do not), under a clip, over what was drawn before, and inside a
//! damage repaint.

use mocu_display::*;

const W: u32 = 400;
const H: u32 = 240;

/// A canvas that tracks what it drew on (as a layer repaint's does), so that blits onto
/// untouched pixels are copies.
fn canvas() -> SkiaCanvas {
    let pm = tiny_skia::Pixmap::new(W, H).unwrap();
    SkiaCanvas::reusing(pm, (0, 0), Size::new(W as f32, H as f32))
}

/// A dial face around `c`: disc, rim, track, ticks and a label.
fn face(c: &mut dyn Canvas, at: Point) {
    c.fill_circle(at, 50.0, Color::rgba(10, 16, 24, 200));
    c.stroke_circle(at, 49.0, 1.5, Color::rgba(0, 200, 230, 90));
    c.stroke_arc(at, 40.0, 2.4, 4.7, &Stroke::new(4.5), Color::rgba(90, 120, 135, 128));
    let mut ticks = PathBuilder::new();
    for i in 0..=10 {
        let a = 2.4 + 4.7 * i as f32 / 10.0;
        let (s, co) = a.sin_cos();
        ticks.move_to(Point::new(at.x + co * 30.0, at.y + s * 30.0));
        ticks.line_to(Point::new(at.x + co * 35.0, at.y + s * 35.0));
    }
    c.stroke_path(&ticks.finish(), &Stroke::new(1.5), &Brush::Solid(Color::WHITE));
    c.draw_text("kn", Point::new(at.x - 8.0, at.y + 20.0), &TextStyle::new(12.0, Color::WHITE));
}

fn bounds(at: Point) -> Rect {
    Rect::new(at.x - 52.0, at.y - 52.0, 104.5, 104.5)
}

fn cached_face(c: &mut dyn Canvas, key: u64, at: Point) {
    picture(c, key, bounds(at), |c| face(c, at));
}

/// The largest difference of any channel of any pixel.
fn worst(a: &tiny_skia::Pixmap, b: &tiny_skia::Pixmap) -> u8 {
    a.data().iter().zip(b.data()).map(|(x, y)| x.abs_diff(*y)).max().unwrap_or(0)
}

/// Draws `scene` directly and through pictures (twice: recorded, then from the cache).
fn compare(key: u64, scene: impl Fn(&mut dyn Canvas, &dyn Fn(&mut dyn Canvas, Point))) -> u8 {
    let mut direct = canvas();
    scene(&mut direct, &|c, at| face(c, at));
    let direct = direct.into_pixmap();
    let mut w = 0;
    for _ in 0..2 {
        let mut cached = canvas();
        scene(&mut cached, &|c, at| cached_face(c, key, at));
        w = w.max(worst(&direct, &cached.into_pixmap()));
    }
    w
}

#[test]
fn a_picture_on_a_transparent_area_is_the_drawing_pixel_for_pixel() {
    let key = picture_key("test face on transparent");
    let w = compare(key, |c, draw| {
        draw(c, Point::new(100.0, 100.0));
        // Moved by whole pixels: the same sprite.
        draw(c, Point::new(260.0, 120.0));
    });
    assert_eq!(w, 0, "a blit onto transparent pixels is a copy of what drawing gives");
}

#[test]
fn a_picture_over_other_drawings_is_within_a_rounding_step_of_the_drawing() {
    let key = picture_key("test face over a band");
    let w = compare(key, |c, draw| {
        c.fill_rect(Rect::new(0.0, 80.0, W as f32, 40.0), Color::rgba(200, 60, 20, 160));
        draw(c, Point::new(100.0, 100.0));
        // Overlapping the first face.
        draw(c, Point::new(150.0, 110.0));
    });
    assert!(w <= 2, "source-over of the sprite differs from shape by shape by {w}");
}

#[test]
fn sub_pixel_positions_get_their_own_sprites() {
    let key = picture_key("test face sub-pixel");
    let w = compare(key, |c, draw| {
        draw(c, Point::new(100.0, 100.0));
        draw(c, Point::new(260.25, 120.5));
    });
    assert_eq!(w, 0, "a face at a quarter pixel is not the whole-pixel face shifted");
}

#[test]
fn a_clipped_picture_draws_only_inside_the_clip() {
    let key = picture_key("test face clipped");
    let w = compare(key, |c, draw| {
        c.save();
        c.clip_rect(Rect::new(80.0, 70.0, 45.0, 200.0));
        draw(c, Point::new(100.0, 100.0));
        c.restore();
        draw(c, Point::new(300.0, 100.0));
    });
    assert_eq!(w, 0);
}

#[test]
fn a_damage_repaint_blits_the_part_of_the_picture_it_covers() {
    let key = picture_key("test face damage");
    let at = Point::new(120.0, 110.0);
    let mut full = canvas();
    cached_face(&mut full, key, at);
    let full = full.into_pixmap();
    // A scratch pixmap over part of the face, as a damage repaint draws.
    let d = IRect::new(90, 95, 60, 40);
    let pm = tiny_skia::Pixmap::new(d.w as u32, d.h as u32).unwrap();
    let mut part = SkiaCanvas::new(pm, (d.x, d.y), Size::new(W as f32, H as f32));
    cached_face(&mut part, key, at);
    let part = part.into_pixmap();
    for y in 0..d.h {
        for x in 0..d.w {
            let want = full.pixel((d.x + x) as u32, (d.y + y) as u32).unwrap();
            let got = part.pixel(x as u32, y as u32).unwrap();
            assert_eq!(got, want, "pixel ({}, {})", d.x + x, d.y + y);
        }
    }
}

#[test]
fn under_a_rotation_a_picture_is_drawn_directly() {
    let key = picture_key("test face rotated");
    let w = compare(key, |c, draw| {
        c.save();
        c.translate(200.0, 120.0);
        c.rotate(0.3);
        draw(c, Point::new(0.0, 0.0));
        c.restore();
    });
    assert_eq!(w, 0);
}

#[test]
fn a_picture_left_unfinished_gives_back_the_canvas_it_was_recorded_for() {
    // What a painter that panics inside a picture leaves behind.
    let mut c = canvas();
    c.fill_rect(Rect::new(0.0, 0.0, 10.0, 10.0), Color::WHITE);
    let at = Point::new(100.0, 100.0);
    assert!(c.begin_picture(picture_key("test face unfinished"), bounds(at)));
    face(&mut c, at);
    let pm = c.into_pixmap();
    assert_eq!((pm.width(), pm.height()), (W, H), "the layer's pixmap, not the sprite");
    assert_eq!(pm.pixel(5, 5).unwrap().alpha(), 255, "what was drawn before the picture");
}
