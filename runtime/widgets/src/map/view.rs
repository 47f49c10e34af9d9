//! Web Mercator (EPSG:3857) placement: what part of the world a map window shows, and
//! where a latitude/longitude falls in it. World coordinates are in [0, 1) on both axes
//! (x east from 180° W, y south from 85.05° N); zoom `z` makes the world `256 · 2^z` px.

use mocu_display::Point;

/// Latitudes beyond this have no Web Mercator place (the projection's square).
pub const MAX_LAT: f64 = 85.051_128_78;
/// Metres per pixel at zoom 0 on the equator (WGS 84's equator / 256).
const M_PER_PX_Z0: f64 = 156_543.033_928;

/// A latitude/longitude in degrees → world coordinates in [0, 1).
pub fn world(lat: f64, lon: f64) -> (f64, f64) {
    let phi = lat.clamp(-MAX_LAT, MAX_LAT).to_radians();
    let x = (lon + 180.0) / 360.0;
    let y = (1.0 - (phi.tan() + 1.0 / phi.cos()).ln() / std::f64::consts::PI) / 2.0;
    (x, y)
}

/// World coordinates → latitude/longitude in degrees.
pub fn lat_lon(x: f64, y: f64) -> (f64, f64) {
    let n = std::f64::consts::PI * (1.0 - 2.0 * y);
    (n.sinh().atan().to_degrees(), x * 360.0 - 180.0)
}

/// A position in the local frame (metres east and north of `origin`) → latitude and
/// longitude, on the same flat-earth step the simulator uses for its own frame.
pub fn local_to_lat_lon(origin: (f64, f64), x: f64, y: f64) -> (f64, f64) {
    let lat = origin.0 + y / 111_320.0;
    let lon = origin.1 + x / (111_320.0 * origin.0.to_radians().cos());
    (lat, lon)
}

/// What a window shows: its centre in world coordinates, its zoom and its size in px.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct View {
    pub centre: (f64, f64),
    pub zoom: f64,
    pub w: f32,
    pub h: f32,
}

impl View {
    /// Pixels across the whole world at this zoom.
    pub fn world_px(&self) -> f64 {
        256.0 * self.zoom.exp2()
    }

    pub fn to_screen(&self, lat: f64, lon: f64) -> Point {
        let (x, y) = world(lat, lon);
        self.world_to_screen(x, y)
    }

    pub fn world_to_screen(&self, x: f64, y: f64) -> Point {
        let s = self.world_px();
        Point::new(
            (self.w as f64 / 2.0 + (x - self.centre.0) * s) as f32,
            (self.h as f64 / 2.0 + (y - self.centre.1) * s) as f32,
        )
    }

    /// A window-local pixel → world coordinates.
    pub fn to_world(&self, px: f32, py: f32) -> (f64, f64) {
        let s = self.world_px();
        (
            self.centre.0 + (px as f64 - self.w as f64 / 2.0) / s,
            self.centre.1 + (py as f64 - self.h as f64 / 2.0) / s,
        )
    }

    pub fn to_lat_lon(&self, p: Point) -> (f64, f64) {
        let (x, y) = self.to_world(p.x, p.y);
        lat_lon(x, y)
    }

    /// Ground metres per pixel at the centre's latitude.
    pub fn metres_per_px(&self) -> f64 {
        let lat = lat_lon(self.centre.0, self.centre.1).0;
        M_PER_PX_Z0 * lat.to_radians().cos() / self.zoom.exp2()
    }

    /// The view centred on `centre` that shows every point (world coordinates) with a
    /// margin, and at least `min_span_m` metres across its shorter side; zoom in [1, 22].
    pub fn fit(
        points: &[(f64, f64)],
        centre: Option<(f64, f64)>,
        w: f32,
        h: f32,
        min_span_m: f64,
    ) -> View {
        let c = centre.unwrap_or_else(|| {
            let (mut x0, mut y0, mut x1, mut y1) = (f64::MAX, f64::MAX, f64::MIN, f64::MIN);
            for (x, y) in points {
                (x0, y0, x1, y1) = (x0.min(*x), y0.min(*y), x1.max(*x), y1.max(*y));
            }
            ((x0 + x1) / 2.0, (y0 + y1) / 2.0)
        });
        // Half-extent needed around the centre on each axis, in world units.
        let (mut hx, mut hy) = (0.0f64, 0.0f64);
        for (x, y) in points {
            hx = hx.max((x - c.0).abs());
            hy = hy.max((y - c.1).abs());
        }
        let lat = lat_lon(c.0, c.1).0;
        // World units per metre at this latitude.
        let wpm = 1.0 / (M_PER_PX_Z0 * 256.0 * lat.to_radians().cos());
        let min_half = min_span_m / 2.0 * wpm;
        let (w, h) = (w.max(1.0) as f64, h.max(1.0) as f64);
        // Room for symbols and labels around the outermost points.
        let margin = 0.8;
        let sx = (w * margin / 2.0) / hx.max(min_half * w / w.min(h));
        let sy = (h * margin / 2.0) / hy.max(min_half * h / w.min(h));
        let zoom = (sx.min(sy) / 256.0).log2().clamp(1.0, 22.0);
        View { centre: c, zoom, w: w as f32, h: h as f32 }
    }
}

/// A "nice" length (1, 2 or 5 times a power of ten) no longer than `x`.
pub fn nice_below(x: f64) -> f64 {
    if x.is_nan() || x <= 0.0 {
        return 1.0;
    }
    let p = 10f64.powf(x.log10().floor());
    for m in [5.0, 2.0, 1.0] {
        if m * p <= x {
            return m * p;
        }
    }
    p
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn web_mercator_round_trips_and_puts_greenwich_on_the_equator_at_the_centre() {
        assert_eq!(world(0.0, 0.0), (0.5, 0.5));
        let (x, y) = world(32.71, -117.24);
        let (lat, lon) = lat_lon(x, y);
        assert!((lat - 32.71).abs() < 1e-9 && (lon + 117.24).abs() < 1e-9);
        // North is up: a higher latitude has a smaller y.
        assert!(world(33.0, 0.0).1 < world(32.0, 0.0).1);
    }

    #[test]
    fn a_fitted_view_shows_every_point_and_keeps_the_minimum_span() {
        let pts = [world(32.70, -117.25), world(32.72, -117.23)];
        let v = View::fit(&pts, None, 400.0, 300.0, 100.0);
        for (x, y) in pts {
            let p = v.world_to_screen(x, y);
            assert!(p.x >= 0.0 && p.x <= 400.0 && p.y >= 0.0 && p.y <= 300.0, "{p:?}");
        }
        let one = [world(32.71, -117.24)];
        let v = View::fit(&one, None, 400.0, 300.0, 500.0);
        let across = v.metres_per_px() * 300.0;
        assert!((across - 500.0 / 0.8).abs() < 1.0, "{across}");
    }

    #[test]
    fn the_local_frame_is_anchored_at_its_origin() {
        let (lat, lon) = local_to_lat_lon((32.71, -117.24), 0.0, 0.0);
        assert_eq!((lat, lon), (32.71, -117.24));
        let (lat, _) = local_to_lat_lon((32.71, -117.24), 0.0, 111_320.0);
        assert!((lat - 33.71).abs() < 1e-9);
    }

    #[test]
    fn nice_lengths_are_one_two_or_five_times_a_power_of_ten() {
        assert_eq!(nice_below(180.0), 100.0);
        assert_eq!(nice_below(250.0), 200.0);
        assert_eq!(nice_below(999.0), 500.0);
        assert_eq!(nice_below(5.0), 5.0);
    }
}
