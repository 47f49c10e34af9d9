//! Plain geometry: points, rectangles and affine transforms, in pixels.

/// A point in pixels.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Point {
    pub x: f32,
    pub y: f32,
}

impl Point {
    pub const fn new(x: f32, y: f32) -> Point {
        Point { x, y }
    }
}

/// A width and a height in pixels.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Size {
    pub w: f32,
    pub h: f32,
}

impl Size {
    pub const fn new(w: f32, h: f32) -> Size {
        Size { w, h }
    }
}

/// An axis-aligned rectangle (`x`, `y` its top-left corner). A negative width or height
/// is an empty rectangle.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Rect {
    pub x: f32,
    pub y: f32,
    pub w: f32,
    pub h: f32,
}

impl Rect {
    pub const fn new(x: f32, y: f32, w: f32, h: f32) -> Rect {
        Rect { x, y, w, h }
    }

    pub fn from_size(s: Size) -> Rect {
        Rect::new(0.0, 0.0, s.w, s.h)
    }

    pub fn right(&self) -> f32 {
        self.x + self.w
    }

    pub fn bottom(&self) -> f32 {
        self.y + self.h
    }

    pub fn center(&self) -> Point {
        Point::new(self.x + self.w / 2.0, self.y + self.h / 2.0)
    }

    pub fn is_empty(&self) -> bool {
        !(self.w > 0.0 && self.h > 0.0)
    }

    pub fn contains(&self, p: Point) -> bool {
        p.x >= self.x && p.y >= self.y && p.x < self.right() && p.y < self.bottom()
    }

    pub fn intersect(&self, o: &Rect) -> Rect {
        let x = self.x.max(o.x);
        let y = self.y.max(o.y);
        Rect::new(x, y, self.right().min(o.right()) - x, self.bottom().min(o.bottom()) - y)
    }

    pub fn intersects(&self, o: &Rect) -> bool {
        !self.intersect(o).is_empty()
    }

    /// Shrinks (positive `d`) or grows (negative) on every side.
    pub fn inset(&self, d: f32) -> Rect {
        Rect::new(self.x + d, self.y + d, self.w - 2.0 * d, self.h - 2.0 * d)
    }
}

/// An integer pixel rectangle, for damage and compositing.
///
/// # Guarantees
/// Built by [`IRect::new`], `w` and `h` are never negative.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub struct IRect {
    pub x: i32,
    pub y: i32,
    pub w: i32,
    pub h: i32,
}

impl IRect {
    pub fn new(x: i32, y: i32, w: i32, h: i32) -> IRect {
        IRect { x, y, w: w.max(0), h: h.max(0) }
    }

    /// The smallest integer rectangle covering `r`.
    pub fn covering(r: Rect) -> IRect {
        if r.is_empty() {
            return IRect::default();
        }
        let x0 = r.x.floor() as i32;
        let y0 = r.y.floor() as i32;
        let x1 = r.right().ceil() as i32;
        let y1 = r.bottom().ceil() as i32;
        IRect::new(x0, y0, x1 - x0, y1 - y0)
    }

    pub fn is_empty(&self) -> bool {
        self.w <= 0 || self.h <= 0
    }

    pub fn right(&self) -> i32 {
        self.x.saturating_add(self.w)
    }

    pub fn bottom(&self) -> i32 {
        self.y.saturating_add(self.h)
    }

    pub fn area(&self) -> i64 {
        self.w as i64 * self.h as i64
    }

    /// The common part; when there is none, both sides are zero (never a rectangle with
    /// rows but no columns, whose row range a caller could walk).
    pub fn intersect(&self, o: &IRect) -> IRect {
        let x = self.x.max(o.x);
        let y = self.y.max(o.y);
        let w = self.right().min(o.right()).saturating_sub(x);
        let h = self.bottom().min(o.bottom()).saturating_sub(y);
        if w <= 0 || h <= 0 {
            return IRect::new(x, y, 0, 0);
        }
        IRect::new(x, y, w, h)
    }

    /// The bounding box of both (an empty side is ignored).
    pub fn union(&self, o: &IRect) -> IRect {
        if self.is_empty() {
            return *o;
        }
        if o.is_empty() {
            return *self;
        }
        let x = self.x.min(o.x);
        let y = self.y.min(o.y);
        IRect::new(x, y, self.right().max(o.right()) - x, self.bottom().max(o.bottom()) - y)
    }

    pub fn offset(&self, dx: i32, dy: i32) -> IRect {
        IRect::new(self.x + dx, self.y + dy, self.w, self.h)
    }

    pub fn to_rect(&self) -> Rect {
        Rect::new(self.x as f32, self.y as f32, self.w as f32, self.h as f32)
    }
}

/// A 2-D affine transform: `x' = sx*x + kx*y + tx`, `y' = ky*x + sy*y + ty`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Transform {
    pub sx: f32,
    pub ky: f32,
    pub kx: f32,
    pub sy: f32,
    pub tx: f32,
    pub ty: f32,
}

impl Default for Transform {
    fn default() -> Self {
        Transform::IDENTITY
    }
}

impl Transform {
    pub const IDENTITY: Transform =
        Transform { sx: 1.0, ky: 0.0, kx: 0.0, sy: 1.0, tx: 0.0, ty: 0.0 };

    pub fn translate(tx: f32, ty: f32) -> Transform {
        Transform { tx, ty, ..Transform::IDENTITY }
    }

    pub fn scale(sx: f32, sy: f32) -> Transform {
        Transform { sx, sy, ..Transform::IDENTITY }
    }

    /// A rotation by `radians`, clockwise on screen (y grows downwards).
    pub fn rotate(radians: f32) -> Transform {
        let (s, c) = radians.sin_cos();
        Transform { sx: c, ky: s, kx: -s, sy: c, tx: 0.0, ty: 0.0 }
    }

    /// `self` then `next`: the transform that applies `self` first.
    pub fn then(&self, next: &Transform) -> Transform {
        let a = self;
        let b = next;
        Transform {
            sx: b.sx * a.sx + b.kx * a.ky,
            ky: b.ky * a.sx + b.sy * a.ky,
            kx: b.sx * a.kx + b.kx * a.sy,
            sy: b.ky * a.kx + b.sy * a.sy,
            tx: b.sx * a.tx + b.kx * a.ty + b.tx,
            ty: b.ky * a.tx + b.sy * a.ty + b.ty,
        }
    }

    /// `local` applied before `self` (how canvas operations compose: the newest
    /// operation acts on the coordinates first).
    pub fn pre(&self, local: &Transform) -> Transform {
        local.then(self)
    }

    pub fn apply(&self, p: Point) -> Point {
        Point::new(self.sx * p.x + self.kx * p.y + self.tx, self.ky * p.x + self.sy * p.y + self.ty)
    }

    /// No rotation or skew.
    pub fn is_axis_aligned(&self) -> bool {
        self.kx == 0.0 && self.ky == 0.0
    }

    /// Only a translation.
    pub fn is_translate(&self) -> bool {
        self.is_axis_aligned() && self.sx == 1.0 && self.sy == 1.0
    }

    /// The bounding box of `r` once transformed.
    pub fn map_rect(&self, r: Rect) -> Rect {
        let ps = [
            self.apply(Point::new(r.x, r.y)),
            self.apply(Point::new(r.right(), r.y)),
            self.apply(Point::new(r.x, r.bottom())),
            self.apply(Point::new(r.right(), r.bottom())),
        ];
        let (mut x0, mut y0, mut x1, mut y1) = (f32::MAX, f32::MAX, f32::MIN, f32::MIN);
        for p in ps {
            x0 = x0.min(p.x);
            y0 = y0.min(p.y);
            x1 = x1.max(p.x);
            y1 = y1.max(p.y);
        }
        Rect::new(x0, y0, x1 - x0, y1 - y0)
    }

    /// The inverse, when the transform is invertible.
    pub fn invert(&self) -> Option<Transform> {
        let det = self.sx * self.sy - self.kx * self.ky;
        if det.abs() < 1e-12 {
            return None;
        }
        let inv = 1.0 / det;
        let sx = self.sy * inv;
        let kx = -self.kx * inv;
        let ky = -self.ky * inv;
        let sy = self.sx * inv;
        Some(Transform {
            sx,
            kx,
            ky,
            sy,
            tx: -(sx * self.tx + kx * self.ty),
            ty: -(ky * self.tx + sy * self.ty),
        })
    }

    pub(crate) fn to_skia(self) -> tiny_skia::Transform {
        tiny_skia::Transform::from_row(self.sx, self.ky, self.kx, self.sy, self.tx, self.ty)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn transforms_compose_newest_first() {
        let t = Transform::translate(10.0, 0.0).pre(&Transform::scale(2.0, 2.0));
        assert_eq!(t.apply(Point::new(1.0, 1.0)), Point::new(12.0, 2.0));
        let r = Transform::rotate(std::f32::consts::FRAC_PI_2).apply(Point::new(1.0, 0.0));
        assert!((r.x).abs() < 1e-6 && (r.y - 1.0).abs() < 1e-6, "{r:?}");
        let inv = t.invert().unwrap();
        let p = inv.apply(t.apply(Point::new(3.0, -4.0)));
        assert!((p.x - 3.0).abs() < 1e-5 && (p.y + 4.0).abs() < 1e-5);
    }

    #[test]
    fn irect_union_ignores_empty_sides() {
        let a = IRect::new(0, 0, 10, 10);
        assert_eq!(a.union(&IRect::default()), a);
        assert_eq!(a.union(&IRect::new(20, 5, 5, 10)), IRect::new(0, 0, 25, 15));
        assert_eq!(IRect::covering(Rect::new(0.5, 0.5, 1.0, 1.0)), IRect::new(0, 0, 2, 2));
    }
}
