//! What the map draws over the chart: vehicle symbols by type (USV a hull, UGV a tracked
//! body, UAV a quadrotor), heading lines, trails, the selected and controlled vehicle's
//! marks, routes in the vehicle's colour with the active leg and next waypoint, labels
//! that never overlap, a scale bar and a north arrow. Sizes are in pixels times the
//! design scale `u`: a larger map window shows more ground, not larger symbols.

use super::view::{View, nice_below};
use mocu_display::{
    Align, Baseline, Brush, Canvas, Color, Path, PathBuilder, Point, Rect, Stroke, TextStyle,
};

pub const TEXT: Color = Color::rgb(0xe8, 0xf0, 0xf8);
const HALO: Color = Color::rgb(0x06, 0x0c, 0x14);
pub const SELECTED: Color = Color::rgb(0xfd, 0xe0, 0x47);
pub const CONTROLLED: Color = Color::rgb(0x4a, 0xde, 0x80);
pub const STALE: Color = Color::rgb(0x6b, 0x74, 0x80);

/// Vehicle colours, in the order vehicles appear (routes and trails take the same one).
const PALETTE: [Color; 6] = [
    Color::rgb(0x38, 0xbd, 0xf8),
    Color::rgb(0xfb, 0x92, 0x3c),
    Color::rgb(0xa3, 0xe6, 0x35),
    Color::rgb(0xc0, 0x84, 0xfc),
    Color::rgb(0xf4, 0x72, 0xb6),
    Color::rgb(0x2d, 0xd4, 0xbf),
];

pub fn vehicle_colour(index: usize) -> Color {
    PALETTE[index % PALETTE.len()]
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum VehicleType {
    Usv,
    Ugv,
    Uav,
    Other,
}

impl VehicleType {
    /// From the object's kind (`usv`, `ugv`, `uav`; MAVLink's classification gives the same).
    pub fn of(kind: &str) -> VehicleType {
        match kind {
            "usv" | "boat" | "surface" => VehicleType::Usv,
            "ugv" | "rover" | "ground" => VehicleType::Ugv,
            "uav" | "copter" | "plane" | "air" => VehicleType::Uav,
            _ => VehicleType::Other,
        }
    }
}

/// A point `r` px from `p` along bearing `h` + `a` (radians; 0 = north, clockwise).
fn polar(p: Point, h: f32, a: f32, r: f32) -> Point {
    Point::new(p.x + (h + a).sin() * r, p.y - (h + a).cos() * r)
}

/// A point at (`right`, `ahead`) px in the frame of a symbol heading `h`.
fn body(p: Point, h: f32, right: f32, ahead: f32) -> Point {
    let (s, c) = h.sin_cos();
    Point::new(p.x + right * c + ahead * s, p.y + right * s - ahead * c)
}

fn shape(p: Point, h: f32, pts: &[(f32, f32)], u: f32) -> Path {
    let pts: Vec<Point> = pts.iter().map(|(x, y)| body(p, h, x * u, y * u)).collect();
    Path::polyline(&pts, true)
}

/// A vehicle's symbol at `p`, pointing along `heading_deg`, in `fill` with a light rim.
pub fn draw_vehicle(
    c: &mut dyn Canvas,
    t: VehicleType,
    p: Point,
    heading_deg: f64,
    fill: Color,
    u: f32,
) {
    let h = (heading_deg as f32).to_radians();
    let rim = Brush::Solid(TEXT);
    let dark = Brush::Solid(HALO);
    // Heading line, ahead of the symbol.
    c.line(polar(p, h, 0.0, 10.0 * u), polar(p, h, 0.0, 26.0 * u), 2.0 * u, fill);
    match t {
        VehicleType::Usv => {
            // A hull: pointed bow, square stern.
            let hull =
                shape(p, h, &[(0.0, 12.0), (5.5, 3.0), (5.5, -9.0), (-5.5, -9.0), (-5.5, 3.0)], u);
            c.stroke_path(&hull, &Stroke::new(3.0 * u), &dark);
            c.fill_path(&hull, &Brush::Solid(fill));
            c.stroke_path(&hull, &Stroke::new(u), &rim);
        }
        VehicleType::Ugv => {
            // A tracked body: a box with its two tracks and a chevron at the front.
            let hull = shape(p, h, &[(-7.0, 8.0), (7.0, 8.0), (7.0, -8.0), (-7.0, -8.0)], u);
            c.stroke_path(&hull, &Stroke::new(3.0 * u), &dark);
            c.fill_path(&hull, &Brush::Solid(fill));
            for side in [-1.0f32, 1.0] {
                let track = shape(
                    p,
                    h,
                    &[(side * 7.0, 8.0), (side * 4.0, 8.0), (side * 4.0, -8.0), (side * 7.0, -8.0)],
                    u,
                );
                c.fill_path(&track, &dark);
            }
            let chevron = [
                body(p, h, -3.0 * u, 1.0 * u),
                body(p, h, 0.0, 5.0 * u),
                body(p, h, 3.0 * u, 1.0 * u),
            ];
            c.stroke_path(&Path::polyline(&chevron, false), &Stroke::new(1.5 * u), &dark);
            c.stroke_path(&hull, &Stroke::new(u), &rim);
        }
        VehicleType::Uav => {
            // A quadrotor: two arms in an X, a rotor disc at each end, a nose triangle.
            for a in [45.0f32, 135.0] {
                let a = a.to_radians();
                let (p1, p2) =
                    (polar(p, h, a, 10.0 * u), polar(p, h, a + std::f32::consts::PI, 10.0 * u));
                c.line(p1, p2, 4.0 * u, HALO);
                c.line(p1, p2, 2.0 * u, fill);
            }
            for a in [45.0f32, 135.0, 225.0, 315.0] {
                let q = polar(p, h, a.to_radians(), 10.0 * u);
                c.fill_circle(q, 4.5 * u, HALO);
                c.fill_circle(q, 3.5 * u, fill);
                c.stroke_circle(q, 4.5 * u, 0.8 * u, TEXT);
            }
            let nose = shape(p, h, &[(0.0, 6.0), (3.5, -2.0), (-3.5, -2.0)], u);
            c.fill_path(&nose, &Brush::Solid(TEXT));
        }
        VehicleType::Other => {
            let tri = shape(p, h, &[(0.0, 12.0), (6.0, -7.0), (-6.0, -7.0)], u);
            c.stroke_path(&tri, &Stroke::new(3.0 * u), &dark);
            c.fill_path(&tri, &Brush::Solid(fill));
            c.stroke_path(&tri, &Stroke::new(u), &rim);
        }
    }
}

/// The selected vehicle: a yellow ring; the controlled one: green corner brackets.
pub fn draw_marks(c: &mut dyn Canvas, p: Point, selected: bool, controlled: bool, u: f32) {
    if selected {
        c.stroke_circle(p, 17.0 * u, 4.0 * u, HALO);
        c.stroke_circle(p, 17.0 * u, 2.0 * u, SELECTED);
    }
    if controlled {
        let (r, l) = (21.0 * u, 7.0 * u);
        for (sx, sy) in [(-1.0f32, -1.0f32), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)] {
            let corner = Point::new(p.x + sx * r, p.y + sy * r);
            let pts = [
                Point::new(corner.x, corner.y - sy * l),
                corner,
                Point::new(corner.x - sx * l, corner.y),
            ];
            let path = Path::polyline(&pts, false);
            c.stroke_path(&path, &Stroke::new(4.5 * u), &Brush::Solid(HALO));
            c.stroke_path(&path, &Stroke::new(2.5 * u), &Brush::Solid(CONTROLLED));
        }
    }
}

/// A trail of past positions, fading towards the oldest.
pub fn draw_trail(c: &mut dyn Canvas, pts: &[Point], colour: Color, u: f32) {
    let n = pts.len();
    for (i, w) in pts.windows(2).enumerate() {
        let a = 0.15 + 0.55 * (i + 1) as f32 / n as f32;
        c.line(w[0], w[1], 2.0 * u, colour.with_alpha(a));
    }
}

/// A route in the vehicle's colour: legs dashed, the active leg (from the vehicle to the
/// next waypoint) solid and wide, waypoints as dots, the next one ringed and numbered.
pub fn draw_route(
    c: &mut dyn Canvas,
    pts: &[Point],
    vehicle: Point,
    next: Option<usize>,
    active: bool,
    colour: Color,
    u: f32,
) {
    let alpha = if active { 1.0 } else { 0.55 };
    let col = colour.with_alpha(alpha);
    if pts.len() >= 2 {
        let path = Path::polyline(pts, false);
        c.stroke_path(&path, &Stroke::new(3.5 * u), &Brush::Solid(HALO.with_alpha(0.6 * alpha)));
        c.stroke_path(
            &path,
            &Stroke::new(1.5 * u).dash(&[6.0 * u, 4.0 * u], 0.0),
            &Brush::Solid(col),
        );
    }
    let next = next.filter(|n| active && *n < pts.len());
    if let Some(n) = next {
        let leg = Path::polyline(&[vehicle, pts[n]], false);
        c.stroke_path(&leg, &Stroke::new(5.0 * u), &Brush::Solid(HALO.with_alpha(0.7)));
        c.stroke_path(&leg, &Stroke::new(3.0 * u), &Brush::Solid(colour));
    }
    for (i, p) in pts.iter().enumerate() {
        c.fill_circle(*p, 4.5 * u, HALO.with_alpha(alpha));
        c.fill_circle(*p, 3.0 * u, col);
        if Some(i) == next {
            c.stroke_circle(*p, 8.0 * u, 3.5 * u, HALO);
            c.stroke_circle(*p, 8.0 * u, 2.0 * u, colour);
        }
    }
}

/// Text with a dark halo all round, legible over land, water and tiles.
pub fn halo_text(c: &mut dyn Canvas, text: &str, at: Point, style: &TextStyle, u: f32) {
    let halo = TextStyle { color: HALO, ..style.clone() };
    let d = 1.2 * u;
    for (dx, dy) in [(-d, 0.0), (d, 0.0), (0.0, -d), (0.0, d), (-d, -d), (d, d), (-d, d), (d, -d)] {
        c.draw_text(text, Point::new(at.x + dx, at.y + dy), &halo);
    }
    c.draw_text(text, at, style);
}

/// Greedy label placement: each label takes the first of its candidate places (beside,
/// above or below its anchor, then further out) that overlaps no label or symbol already
/// placed and stays inside the window; one with no such place is left out.
pub struct Labels {
    taken: Vec<Rect>,
    bounds: Rect,
}

impl Labels {
    pub fn new(bounds: Rect) -> Labels {
        Labels { taken: Vec::new(), bounds }
    }

    /// Something labels must not cover (a symbol, the scale bar).
    pub fn block(&mut self, r: Rect) {
        self.taken.push(r);
    }

    /// A place for a `w`×`h` label around `anchor`, at least `gap` px from it, and
    /// whether it is one of the further places (then a leader line shows whose it is).
    pub fn place(&mut self, anchor: Point, gap: f32, w: f32, h: f32) -> Option<(Rect, bool)> {
        for ring in [1.0f32, 2.2] {
            let g = gap * ring;
            let candidates = [
                (anchor.x + g, anchor.y - h / 2.0),
                (anchor.x + g * 0.7, anchor.y - g * 0.7 - h),
                (anchor.x + g * 0.7, anchor.y + g * 0.7),
                (anchor.x - g - w, anchor.y - h / 2.0),
                (anchor.x - g * 0.7 - w, anchor.y - g * 0.7 - h),
                (anchor.x - g * 0.7 - w, anchor.y + g * 0.7),
                (anchor.x - w / 2.0, anchor.y - g - h),
                (anchor.x - w / 2.0, anchor.y + g),
            ];
            for (x, y) in candidates {
                let r = Rect::new(x, y, w, h);
                let inside = r.x >= self.bounds.x
                    && r.y >= self.bounds.y
                    && r.right() <= self.bounds.right()
                    && r.bottom() <= self.bounds.bottom();
                if inside && !self.taken.iter().any(|t| t.intersects(&r)) {
                    self.taken.push(r);
                    return Some((r, ring > 1.0));
                }
            }
        }
        None
    }
}

/// Draws `text` in `size` and `colour` in a place `labels` finds for it; returns whether
/// it found one.
pub fn label(
    c: &mut dyn Canvas,
    labels: &mut Labels,
    text: &str,
    anchor: Point,
    gap: f32,
    (size, colour): (f32, Color),
    u: f32,
) -> bool {
    let w = mocu_display::measure_text(text, size, false).width + 2.0 * u;
    let h = size * 1.25;
    let Some((r, far)) = labels.place(anchor, gap, w, h) else { return false };
    if far {
        // From the label's nearest point towards the anchor, stopping short of the symbol.
        let near = Point::new(anchor.x.clamp(r.x, r.right()), anchor.y.clamp(r.y, r.bottom()));
        let (dx, dy) = (anchor.x - near.x, anchor.y - near.y);
        let d = dx.hypot(dy);
        if d > gap * 0.6 {
            let k = (d - gap * 0.6) / d;
            let end = Point::new(near.x + dx * k, near.y + dy * k);
            c.line(near, end, 2.5 * u, HALO);
            c.line(near, end, u, colour.with_alpha(0.8));
        }
    }
    let style = TextStyle::new(size, colour).align(Align::Left).baseline(Baseline::Middle);
    halo_text(c, text, Point::new(r.x + u, r.y + h / 2.0), &style, u);
    true
}

/// A scale bar at the bottom left: a round length no longer than a quarter of the width,
/// in alternating segments; returns the area it covers.
pub fn draw_scale_bar(c: &mut dyn Canvas, view: &View, u: f32) -> Rect {
    let mpp = view.metres_per_px();
    let metres = nice_below(mpp * (view.w as f64 * 0.25).max(40.0 * u as f64));
    let len = (metres / mpp) as f32;
    let (x, y) = (10.0 * u, view.h - 14.0 * u);
    let text =
        if metres >= 1000.0 { format!("{} km", metres / 1000.0) } else { format!("{metres} m") };
    let style = TextStyle::new(12.0 * u, TEXT).align(Align::Left).baseline(Baseline::Bottom);
    let area = Rect::new(x - 4.0 * u, y - 24.0 * u, len + 8.0 * u, 32.0 * u);
    c.fill_rounded_rect(area, 3.0 * u, &Brush::Solid(HALO.with_alpha(0.6)));
    for i in 0..4 {
        let seg = Rect::new(x + len * i as f32 / 4.0, y, len / 4.0, 5.0 * u);
        c.fill_rect(seg, if i % 2 == 0 { TEXT } else { HALO });
    }
    c.stroke_rounded_rect(Rect::new(x, y, len, 5.0 * u), 0.0, &Stroke::new(u), TEXT);
    halo_text(c, &text, Point::new(x, y - 3.0 * u), &style, u);
    area
}

/// A north arrow at the top right (Web Mercator: north is always up); returns its area.
pub fn draw_north_arrow(c: &mut dyn Canvas, view: &View, u: f32) -> Rect {
    let p = Point::new(view.w - 22.0 * u, 34.0 * u);
    let area = Rect::new(p.x - 14.0 * u, p.y - 30.0 * u, 28.0 * u, 46.0 * u);
    c.fill_rounded_rect(area, 3.0 * u, &Brush::Solid(HALO.with_alpha(0.6)));
    let mut b = PathBuilder::new();
    b.move_to(Point::new(p.x, p.y - 14.0 * u))
        .line_to(Point::new(p.x + 7.0 * u, p.y + 10.0 * u))
        .line_to(Point::new(p.x, p.y + 5.0 * u))
        .close();
    c.fill_path(&b.finish(), &Brush::Solid(TEXT));
    let mut b = PathBuilder::new();
    b.move_to(Point::new(p.x, p.y - 14.0 * u))
        .line_to(Point::new(p.x - 7.0 * u, p.y + 10.0 * u))
        .line_to(Point::new(p.x, p.y + 5.0 * u))
        .close();
    let half = b.finish();
    c.fill_path(&half, &Brush::Solid(Color::rgb(0x5b, 0x67, 0x75)));
    c.stroke_path(&half, &Stroke::new(u), &Brush::Solid(TEXT));
    let style =
        TextStyle::new(12.0 * u, TEXT).align(Align::Center).baseline(Baseline::Bottom).bold();
    halo_text(c, "N", Point::new(p.x, p.y - 15.0 * u), &style, u);
    area
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_label_takes_the_next_free_place_and_none_overlaps_another() {
        let mut labels = Labels::new(Rect::new(0.0, 0.0, 400.0, 300.0));
        let (a, far) = labels.place(Point::new(100.0, 100.0), 10.0, 50.0, 15.0).unwrap();
        assert_eq!((a, far), (Rect::new(110.0, 92.5, 50.0, 15.0), false), "first: to the right");
        let (b, _) = labels.place(Point::new(100.0, 100.0), 10.0, 50.0, 15.0).unwrap();
        let (c, _) = labels.place(Point::new(102.0, 104.0), 10.0, 50.0, 15.0).unwrap();
        for (x, y) in [(a, b), (a, c), (b, c)] {
            assert!(!x.intersects(&y), "{x:?} overlaps {y:?}");
        }
    }

    #[test]
    fn a_label_stays_inside_the_window_or_is_left_out() {
        let mut labels = Labels::new(Rect::new(0.0, 0.0, 100.0, 100.0));
        let (r, _) = labels.place(Point::new(95.0, 50.0), 10.0, 40.0, 15.0).unwrap();
        assert!(r.right() <= 100.0, "placed to the left of an anchor near the right edge");
        labels.block(Rect::new(0.0, 0.0, 100.0, 100.0));
        assert_eq!(labels.place(Point::new(50.0, 50.0), 10.0, 40.0, 15.0), None);
    }

    #[test]
    fn with_the_near_places_taken_a_label_goes_further_out() {
        let mut labels = Labels::new(Rect::new(0.0, 0.0, 400.0, 300.0));
        labels.block(Rect::new(80.0, 80.0, 40.0, 40.0));
        let (r, far) = labels.place(Point::new(100.0, 100.0), 10.0, 20.0, 10.0).unwrap();
        assert!(far && !r.intersects(&Rect::new(80.0, 80.0, 40.0, 40.0)), "{r:?}");
    }
}
