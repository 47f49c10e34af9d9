//! Backend-neutral vector paths and the shape helpers every gauge needs (rounded
//! rectangles, circles, arcs, pie sectors), built from lines and Bézier curves.

use crate::geom::{Point, Rect};
use std::f32::consts::{FRAC_PI_2, TAU};

/// One path element.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum PathEl {
    MoveTo(Point),
    LineTo(Point),
    QuadTo(Point, Point),
    CubicTo(Point, Point, Point),
    Close,
}

/// A vector path: subpaths of lines and curves. Cheap to build, immutable once built.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Path {
    els: Vec<PathEl>,
}

impl Path {
    pub fn elements(&self) -> &[PathEl] {
        &self.els
    }

    pub fn is_empty(&self) -> bool {
        self.els.is_empty()
    }

    /// A rectangle.
    pub fn rect(r: Rect) -> Path {
        let mut b = PathBuilder::new();
        b.rect(r);
        b.finish()
    }

    /// A rectangle with corners of radius `radius` (clamped to half the shorter side).
    pub fn rounded_rect(r: Rect, radius: f32) -> Path {
        let mut b = PathBuilder::new();
        b.rounded_rect(r, radius);
        b.finish()
    }

    pub fn circle(center: Point, radius: f32) -> Path {
        let mut b = PathBuilder::new();
        b.circle(center, radius);
        b.finish()
    }

    /// An open arc (for strokes). Angles in radians, 0 pointing right (+x), positive
    /// clockwise on screen.
    pub fn arc(center: Point, radius: f32, start: f32, sweep: f32) -> Path {
        let mut b = PathBuilder::new();
        b.arc(center, radius, start, sweep, true);
        b.finish()
    }

    /// A closed pie sector from the centre.
    pub fn sector(center: Point, radius: f32, start: f32, sweep: f32) -> Path {
        let mut b = PathBuilder::new();
        b.move_to(center);
        b.arc(center, radius, start, sweep, false);
        b.close();
        b.finish()
    }

    /// A line segment.
    pub fn line(a: Point, b: Point) -> Path {
        Path { els: vec![PathEl::MoveTo(a), PathEl::LineTo(b)] }
    }

    /// A polyline through `pts`, closed when `close` is set.
    pub fn polyline(pts: &[Point], close: bool) -> Path {
        let mut b = PathBuilder::new();
        for (i, p) in pts.iter().enumerate() {
            if i == 0 {
                b.move_to(*p);
            } else {
                b.line_to(*p);
            }
        }
        if close {
            b.close();
        }
        b.finish()
    }

    /// The rectangle this path is, when it is exactly an axis-aligned rectangle.
    pub fn as_rect(&self) -> Option<Rect> {
        let [PathEl::MoveTo(a), PathEl::LineTo(b), PathEl::LineTo(c), PathEl::LineTo(d), rest @ ..] =
            self.els.as_slice()
        else {
            return None;
        };
        if !(rest.is_empty() || rest == [PathEl::Close]) {
            return None;
        }
        let horizontal_first = a.y == b.y && b.x == c.x && c.y == d.y && d.x == a.x;
        let vertical_first = a.x == b.x && b.y == c.y && c.x == d.x && d.y == a.y;
        if !(horizontal_first || vertical_first) {
            return None;
        }
        let (x0, x1) = (a.x.min(c.x), a.x.max(c.x));
        let (y0, y1) = (a.y.min(c.y), a.y.max(c.y));
        Some(Rect::new(x0, y0, x1 - x0, y1 - y0))
    }

    pub(crate) fn to_skia(&self) -> Option<tiny_skia::Path> {
        let mut pb = tiny_skia::PathBuilder::with_capacity(self.els.len(), self.els.len() * 3);
        for el in &self.els {
            match *el {
                PathEl::MoveTo(p) => pb.move_to(p.x, p.y),
                PathEl::LineTo(p) => pb.line_to(p.x, p.y),
                PathEl::QuadTo(c, p) => pb.quad_to(c.x, c.y, p.x, p.y),
                PathEl::CubicTo(c1, c2, p) => pb.cubic_to(c1.x, c1.y, c2.x, c2.y, p.x, p.y),
                PathEl::Close => pb.close(),
            }
        }
        pb.finish()
    }
}

/// Builds a [`Path`].
#[derive(Debug, Default)]
pub struct PathBuilder {
    els: Vec<PathEl>,
    /// Whether a subpath is open (a current point exists).
    open: bool,
}

impl PathBuilder {
    pub fn new() -> PathBuilder {
        PathBuilder::default()
    }

    pub fn move_to(&mut self, p: Point) -> &mut Self {
        self.els.push(PathEl::MoveTo(p));
        self.open = true;
        self
    }

    pub fn line_to(&mut self, p: Point) -> &mut Self {
        if !self.open {
            return self.move_to(p);
        }
        self.els.push(PathEl::LineTo(p));
        self
    }

    pub fn quad_to(&mut self, c: Point, p: Point) -> &mut Self {
        if !self.open {
            self.move_to(c);
        }
        self.els.push(PathEl::QuadTo(c, p));
        self
    }

    pub fn cubic_to(&mut self, c1: Point, c2: Point, p: Point) -> &mut Self {
        if !self.open {
            self.move_to(c1);
        }
        self.els.push(PathEl::CubicTo(c1, c2, p));
        self
    }

    pub fn close(&mut self) -> &mut Self {
        if self.open {
            self.els.push(PathEl::Close);
            self.open = false;
        }
        self
    }

    pub fn rect(&mut self, r: Rect) -> &mut Self {
        self.move_to(Point::new(r.x, r.y))
            .line_to(Point::new(r.right(), r.y))
            .line_to(Point::new(r.right(), r.bottom()))
            .line_to(Point::new(r.x, r.bottom()))
            .close()
    }

    /// A rounded rectangle, clockwise, each corner a cubic quarter circle.
    pub fn rounded_rect(&mut self, r: Rect, radius: f32) -> &mut Self {
        let rad = radius.min(r.w / 2.0).min(r.h / 2.0).max(0.0);
        if rad <= 0.0 {
            return self.rect(r);
        }
        // Control-point distance for a quarter circle with cubics.
        let k = rad * 0.552_284_8;
        let (x0, y0, x1, y1) = (r.x, r.y, r.right(), r.bottom());
        let p = Point::new;
        self.move_to(p(x0 + rad, y0))
            .line_to(p(x1 - rad, y0))
            .cubic_to(p(x1 - rad + k, y0), p(x1, y0 + rad - k), p(x1, y0 + rad))
            .line_to(p(x1, y1 - rad))
            .cubic_to(p(x1, y1 - rad + k), p(x1 - rad + k, y1), p(x1 - rad, y1))
            .line_to(p(x0 + rad, y1))
            .cubic_to(p(x0 + rad - k, y1), p(x0, y1 - rad + k), p(x0, y1 - rad))
            .line_to(p(x0, y0 + rad))
            .cubic_to(p(x0, y0 + rad - k), p(x0 + rad - k, y0), p(x0 + rad, y0))
            .close()
    }

    pub fn circle(&mut self, c: Point, radius: f32) -> &mut Self {
        self.ellipse(c, radius, radius)
    }

    pub fn ellipse(&mut self, c: Point, rx: f32, ry: f32) -> &mut Self {
        let kx = rx * 0.552_284_8;
        let ky = ry * 0.552_284_8;
        let p = Point::new;
        self.move_to(p(c.x + rx, c.y))
            .cubic_to(p(c.x + rx, c.y + ky), p(c.x + kx, c.y + ry), p(c.x, c.y + ry))
            .cubic_to(p(c.x - kx, c.y + ry), p(c.x - rx, c.y + ky), p(c.x - rx, c.y))
            .cubic_to(p(c.x - rx, c.y - ky), p(c.x - kx, c.y - ry), p(c.x, c.y - ry))
            .cubic_to(p(c.x + kx, c.y - ry), p(c.x + rx, c.y - ky), p(c.x + rx, c.y))
            .close()
    }

    /// Appends a circular arc of `sweep` radians from angle `start` (radians, 0 = +x,
    /// positive clockwise on screen), as cubics of at most a quarter turn each. With
    /// `new_subpath` the arc starts a subpath at its first point; otherwise a line joins
    /// the current point to it.
    pub fn arc(
        &mut self,
        c: Point,
        radius: f32,
        start: f32,
        sweep: f32,
        new_subpath: bool,
    ) -> &mut Self {
        let sweep = sweep.clamp(-TAU, TAU);
        let at = |a: f32| Point::new(c.x + radius * a.cos(), c.y + radius * a.sin());
        if new_subpath || !self.open {
            self.move_to(at(start));
        } else {
            self.line_to(at(start));
        }
        if sweep == 0.0 {
            return self;
        }
        let n = (sweep.abs() / FRAC_PI_2).ceil().max(1.0) as usize;
        let step = sweep / n as f32;
        let k = 4.0 / 3.0 * (step / 4.0).tan() * radius;
        let mut a0 = start;
        for _ in 0..n {
            let a1 = a0 + step;
            let (s0, c0) = a0.sin_cos();
            let (s1, c1) = a1.sin_cos();
            let p0 = at(a0);
            let p1 = at(a1);
            self.cubic_to(
                Point::new(p0.x - k * s0, p0.y + k * c0),
                Point::new(p1.x + k * s1, p1.y - k * c1),
                p1,
            );
            a0 = a1;
        }
        self
    }

    pub fn finish(self) -> Path {
        Path { els: self.els }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_arc_ends_where_its_angle_says() {
        let p = Path::arc(Point::new(0.0, 0.0), 10.0, 0.0, std::f32::consts::PI);
        let Some(PathEl::CubicTo(_, _, end)) = p.elements().last().copied() else { panic!() };
        assert!((end.x + 10.0).abs() < 1e-4 && end.y.abs() < 1e-3, "{end:?}");
        assert_eq!(p.elements().len(), 3, "two quarter-turn cubics after the move");
    }

    #[test]
    fn rounded_rect_radius_is_clamped() {
        let p = Path::rounded_rect(Rect::new(0.0, 0.0, 10.0, 4.0), 50.0);
        assert!(p.to_skia().is_some());
        let b = p.to_skia().unwrap().bounds();
        assert_eq!((b.width(), b.height()), (10.0, 4.0));
    }
}
