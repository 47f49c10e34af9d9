//! Text drawn at any origin under any clip: no panic, and a clipped run paints exactly the
//! unclipped run's pixels inside the clip and nothing outside it. A run wholly beside the
//! clip but level with it once walked the clip's rows with a column offset past the end of
//! its coverage mask (the `strip@usv2` layer of fig3 lost every frame).

use mocu_display::*;
use tiny_skia::Pixmap;

const W: u32 = 48;
const H: u32 = 32;

/// Text samples: a cached coverage mask each (one glyph, several, one line and two).
const TEXTS: &[&str] = &["W", "USV2 12.4 kn", "ab\ncd"];

/// Origins in user (window) units: negative, partly and wholly outside the pixmap, on its
/// edges, and fractional.
fn origins() -> Vec<Point> {
    let xs = [-1000.0, -40.0, -7.5, -3.25, 0.0, 0.49, 0.5, 11.7, 23.0, 40.5, 47.0, 48.0, 60.0, 5e6];
    let ys = [-1000.0, -20.0, -6.5, -0.5, 0.0, 9.3, 16.5, 25.0, 31.0, 32.0, 45.0, 5e6];
    xs.iter().flat_map(|&x| ys.iter().map(move |&y| Point::new(x, y))).collect()
}

/// Clips in user units: the whole pixmap, inner bands, slivers, empty, and partly or
/// wholly beyond the pixmap on every side.
const CLIPS: &[(f32, f32, f32, f32)] = &[
    (0.0, 0.0, 48.0, 32.0),
    (30.0, 0.0, 18.0, 32.0),
    (0.0, 0.0, 8.0, 32.0),
    (10.0, 12.0, 5.0, 4.0),
    (20.0, 0.0, 1.0, 32.0),
    (0.0, 15.0, 48.0, 1.0),
    (12.0, 12.0, 0.0, 10.0),
    (12.0, 12.0, 10.0, 0.0),
    (-30.0, -30.0, 20.0, 20.0),
    (60.0, 0.0, 20.0, 32.0),
    (0.0, 40.0, 48.0, 10.0),
    (-10.0, -10.0, 100.0, 100.0),
    (40.0, 28.0, 30.0, 30.0),
    (10.4, 3.6, 7.2, 5.5),
];

/// Draws `text` at `at` on a fresh canvas whose pixmap starts at window pixel `origin`,
/// under `clip` when given; returns the pixmap's pixels.
fn draw(text: &str, at: Point, clip: Option<Rect>, origin: (i32, i32)) -> Vec<u8> {
    let pixmap = Pixmap::new(W, H).unwrap();
    let size = Size::new(W as f32 + 64.0, H as f32 + 64.0);
    let mut c = SkiaCanvas::new(pixmap, origin, size);
    if let Some(r) = clip {
        c.clip_rect(r);
    }
    c.draw_text(text, at, &TextStyle::new(14.0, Color::rgb(240, 200, 40)));
    c.into_pixmap().data().to_vec()
}

/// The clip in pixmap pixels (as `clip_rect` rounds it: in window pixels), with the
/// pixmap's bounds.
fn clip_pixels(r: Rect, origin: (i32, i32)) -> IRect {
    let (x0, y0) = (r.x.round() as i32, r.y.round() as i32);
    let (x1, y1) = (r.right().round() as i32, r.bottom().round() as i32);
    IRect::new(x0 - origin.0, y0 - origin.1, x1 - x0, y1 - y0)
        .intersect(&IRect::new(0, 0, W as i32, H as i32))
}

fn check(origin: (i32, i32)) -> usize {
    let mut painted_inside = 0;
    for text in TEXTS {
        for at in origins() {
            let full = draw(text, at, None, origin);
            for &(x, y, w, h) in CLIPS {
                let r = Rect::new(x, y, w, h);
                let px = clip_pixels(r, origin);
                let clipped = draw(text, at, Some(r), origin);
                for (i, (got, want)) in clipped.chunks(4).zip(full.chunks(4)).enumerate() {
                    let (cx, cy) = ((i as u32 % W) as i32, (i as u32 / W) as i32);
                    let inside = cx >= px.x && cx < px.right() && cy >= px.y && cy < px.bottom();
                    let expected = if inside { want } else { &[0, 0, 0, 0][..] };
                    assert_eq!(
                        got, expected,
                        "{text:?} at {at:?}, clip {r:?}, pixmap origin {origin:?}: pixel ({cx}, {cy})"
                    );
                    painted_inside += (inside && got[3] != 0) as usize;
                }
            }
        }
    }
    painted_inside
}

#[test]
fn text_at_any_origin_paints_only_inside_the_clip_and_all_of_it_there() {
    // Text does land inside some clips: the comparison is not between empty pixmaps.
    assert!(check((0, 0)) > 0);
}

#[test]
fn a_damage_pixmap_away_from_the_window_origin_clips_text_the_same_way() {
    for origin in [(13, 7), (-5, -9), (40, 30)] {
        assert!(check(origin) > 0, "pixmap origin {origin:?}");
    }
}

#[test]
fn text_whose_box_reaches_the_clip_but_whose_ink_is_beside_it_draws_nothing() {
    // The case that panicked: trailing spaces (or the visibility pad) carry the run's box
    // into a clip on the same rows while its coverage mask stops short of it.
    for (text, at, clip) in [
        ("W            ", Point::new(0.0, 8.0), Rect::new(40.0, 0.0, 8.0, 32.0)),
        ("W  ", Point::new(0.0, 8.0), Rect::new(18.0, 0.0, 30.0, 32.0)),
        ("W", Point::new(0.0, 0.0), Rect::new(0.0, 16.0, 48.0, 16.0)),
    ] {
        let px = draw(text, at, Some(clip), (0, 0));
        assert!(px.iter().all(|&b| b == 0), "{text:?} at {at:?} beside clip {clip:?}");
        let m = measure_text(text, 14.0, false);
        let line_box = Rect::new(at.x, at.y, m.width, m.height);
        assert!(line_box.intersects(&clip), "{text:?}: its box must reach the clip");
    }
}

#[test]
fn an_empty_intersection_has_no_rows_to_walk() {
    let a = IRect::new(0, 0, 10, 10);
    for b in [IRect::new(20, 2, 5, 5), IRect::new(2, 20, 5, 5), IRect::new(-9, -9, 4, 30)] {
        let r = a.intersect(&b);
        assert!(r.is_empty());
        assert!((r.y..r.bottom()).is_empty() && (r.x..r.right()).is_empty(), "{r:?}");
    }
}
