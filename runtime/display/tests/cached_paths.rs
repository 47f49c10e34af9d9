//! Small solid fills and strokes are drawn through coverage masks, cached from their
//! second drawing: the first time, the second and from the cache they give tiny-skia's
//! own pixels within a rounding step. The
//! reference is the same drawing in a gradient whose stops are one colour, which
//! tiny-skia rasterises and blends directly.

use mocu_display::*;

const W: u32 = 200;
const H: u32 = 160;

fn canvas() -> SkiaCanvas {
    let pm = tiny_skia::Pixmap::new(W, H).unwrap();
    SkiaCanvas::reusing(pm, (0, 0), Size::new(W as f32, H as f32))
}

/// A needle, an outline and a dashed route, over a translucent band.
fn scene(c: &mut dyn Canvas, brush: &dyn Fn(Color) -> Brush) {
    c.fill_rect(Rect::new(0.0, 60.0, W as f32, 40.0), Color::rgba(40, 90, 160, 150));
    c.save();
    c.translate(100.0, 80.0);
    c.rotate(0.7);
    let needle = Path::polyline(
        &[Point::new(-10.0, -3.0), Point::new(66.0, 0.0), Point::new(-10.0, 3.0)],
        true,
    );
    c.fill_path(&needle, &brush(Color::rgba(255, 176, 0, 230)));
    c.restore();
    let outline = Path::rounded_rect(Rect::new(12.5, 10.5, 80.0, 30.0), 6.0);
    c.stroke_path(&outline, &Stroke::new(1.5), &brush(Color::rgba(0, 200, 230, 160)));
    let route = Path::polyline(
        &[Point::new(20.0, 140.0), Point::new(90.0, 110.0), Point::new(180.0, 150.0)],
        false,
    );
    c.stroke_path(&route, &Stroke::new(2.0).dash(&[10.0, 6.0], 0.0), &brush(Color::WHITE));
}

fn solid(c: Color) -> Brush {
    Brush::Solid(c)
}

fn one_colour_gradient(c: Color) -> Brush {
    Brush::Linear {
        start: Point::new(0.0, 0.0),
        end: Point::new(0.0, 1.0),
        stops: vec![(0.0, c), (1.0, c)],
    }
}

#[test]
fn cached_fills_and_strokes_are_tiny_skias_pixels_within_a_rounding_step() {
    let mut reference = canvas();
    scene(&mut reference, &one_colour_gradient);
    let reference = reference.into_pixmap();
    assert!(reference.data().iter().any(|b| *b != 0), "the scene draws something");
    for pass in ["drawn once", "drawn again (kept)", "from the cache"] {
        let mut cached = canvas();
        scene(&mut cached, &solid);
        let cached = cached.into_pixmap();
        let worst = reference
            .data()
            .iter()
            .zip(cached.data())
            .map(|(a, b)| a.abs_diff(*b))
            .max()
            .unwrap_or(0);
        assert!(worst <= 2, "{pass}: differs from tiny-skia by {worst}");
    }
}
