//! Analytic rasterisers for the shapes HUDs are made of — circles, rings, stroked arcs
//! and straight segments — under a translate + uniform scale: exact anti-aliased coverage
//! per pixel, fully covered runs blended at once. tiny-skia's supersampling rasteriser
//! costs several times more for these.

use super::SkiaCanvas;
use crate::canvas::{LineCap, Stroke};
use crate::color::Color;
use crate::geom::{IRect, Point, Rect};
use crate::pixel;

impl SkiaCanvas {
    /// Circles and rings under a translate + uniform scale, with analytic coverage:
    /// tiny-skia's supersampling rasteriser costs several times more for these, and
    /// gauges are made of them. `None` when the transform does not allow it.
    pub(super) fn ring(&mut self, c: Point, r_out: f32, r_in: f32, color: Color) -> Option<()> {
        let dev = self.device();
        if !(dev.is_axis_aligned() && dev.sx > 0.0 && (dev.sx - dev.sy).abs() < 1e-6) {
            return None;
        }
        let s = dev.sx;
        let c = dev.apply(c);
        let (ro, ri) = (r_out * s, (r_in * s).max(0.0));
        if ro <= 0.0 || color.a == 0 {
            return Some(());
        }
        let bbox = disc_bounds(c, ro);
        // Filled discs are mostly interior, blended as runs either way: only rings are
        // cached.
        let key = [1, c.x.to_bits(), c.y.to_bits(), ro.to_bits(), ri.to_bits()];
        let key = (ri > 0.0).then_some(&key[..]);
        self.shape(key, bbox, color, |t, area, solid| {
            let cov = |r: f32, d: f32| (r - d + 0.5).clamp(0.0, 1.0);
            let outer2 = (ro + 0.5) * (ro + 0.5);
            for y in area.y..area.bottom() {
                let dy = y as f32 + 0.5 - c.y;
                let dy2 = dy * dy;
                if dy2 >= outer2 {
                    continue;
                }
                let half = (outer2 - dy2).sqrt();
                let x0 = ((c.x - half).floor() as i32).max(area.x);
                let x1 = ((c.x + half).ceil() as i32).min(area.right());
                // Half-chords (in pixel-centre distance) of: full coverage by the outer
                // edge, the hollow inside the inner edge, and the inner edge's influence.
                let chord =
                    |r: f32| if r > 0.0 && r * r > dy2 { (r * r - dy2).sqrt() } else { -1.0 };
                let h_solid = chord(ro - 0.5);
                let h_hollow = if ri > 0.0 { chord(ri - 0.5) } else { -1.0 };
                let h_inner = if ri > 0.0 { chord(ri + 0.5) } else { -1.0 };
                // Runs known to be empty (the hollow) or fully covered (between the
                // edges); every other pixel gets its exact coverage.
                let mut runs = [(0, 0, false); 3];
                let mut n = 0;
                let mut add = |lo: f32, hi: f32, solid: bool| {
                    if lo <= hi {
                        let (a, b) = inside(c.x, lo, hi);
                        runs[n] = (a, b, solid);
                        n += 1;
                    }
                };
                if h_inner >= 0.0 {
                    add(-h_solid, -h_inner, true);
                    add(-h_hollow, h_hollow, false);
                    add(h_inner, h_solid, true);
                } else {
                    add(-h_solid, h_solid, true);
                }
                let (ox, clear) = (t.ox, t.clear(y, x0, x1));
                scan_row(t.row(y), ox, (x0, x1), &runs[..n], solid, clear, |xc| {
                    let dx = xc - c.x;
                    let d = (dx * dx + dy2).sqrt();
                    cov(ro, d) - if ri > 0.0 { cov(ri, d) } else { 0.0 }
                });
            }
        });
        Some(())
    }
}

impl SkiaCanvas {
    /// The uniform scale of the device transform when it is a translate + uniform
    /// positive scale (the analytic rasterisers' precondition).
    pub(super) fn uniform_scale(&self) -> Option<f32> {
        let dev = self.device();
        (dev.is_axis_aligned() && dev.sx > 0.0 && (dev.sx - dev.sy).abs() < 1e-6).then_some(dev.sx)
    }

    /// Blends premultiplied `pre` at coverage `k` (0..=1) onto pixel `i` of the pixmap.
    #[inline]
    pub(super) fn cover(px: &mut [[u8; 4]], i: usize, pre: [u8; 4], k: f32) {
        pixel::over_coverage(&mut px[i], pre, (k * 255.0 + 0.5) as u8);
    }

    /// A stroked circular arc with analytic coverage (butt or round caps): the band
    /// between two radii, cut by the two radial edges. Gauge scales are made of these;
    /// tiny-skia strokes them by flattening and supersampling, several times slower.
    pub(super) fn arc_band(
        &mut self,
        c: Point,
        radius: f32,
        start: f32,
        sweep: f32,
        stroke: &Stroke,
        color: Color,
    ) -> Option<()> {
        let s = self.uniform_scale()?;
        if stroke.dash.is_some() || stroke.cap == LineCap::Square {
            return None;
        }
        if color.a == 0 || sweep == 0.0 || stroke.width <= 0.0 {
            return Some(());
        }
        if sweep.abs() >= std::f32::consts::TAU - 1e-4 {
            return self.ring(c, radius + stroke.width / 2.0, radius - stroke.width / 2.0, color);
        }
        let (a0, sw) = if sweep < 0.0 { (start + sweep, -sweep) } else { (start, sweep) };
        let a1 = a0 + sw;
        let c = self.device().apply(c);
        let hw = stroke.width * s / 2.0;
        let rm = radius * s;
        let (ro, ri) = (rm + hw, (rm - hw).max(0.0));
        let round = stroke.cap == LineCap::Round;
        let (u0, u1) = ((a0.cos(), a0.sin()), (a1.cos(), a1.sin()));
        let caps = [(c.x + u0.0 * rm, c.y + u0.1 * rm), (c.x + u1.0 * rm, c.y + u1.1 * rm)];
        let bbox = disc_bounds(c, ro);
        let small = sw <= std::f32::consts::PI;
        let key = [
            2,
            c.x.to_bits(),
            c.y.to_bits(),
            rm.to_bits(),
            hw.to_bits(),
            a0.to_bits(),
            sw.to_bits(),
            round as u32,
        ];
        self.shape(Some(&key), bbox, color, |t, area, pre| {
            let cov = |r: f32, d: f32| (r - d + 0.5).clamp(0.0, 1.0);
            let outer2 = (ro + 0.5) * (ro + 0.5);
            for y in area.y..area.bottom() {
                let dy = y as f32 + 0.5 - c.y;
                let dy2 = dy * dy;
                if dy2 >= outer2 {
                    continue;
                }
                let half = (outer2 - dy2).sqrt();
                let x0 = ((c.x - half).floor() as i32).max(area.x);
                let x1 = ((c.x + half).ceil() as i32).min(area.right());
                let hollow = if ri > 0.5 && (ri - 0.5) * (ri - 0.5) > dy2 {
                    ((ri - 0.5) * (ri - 0.5) - dy2).sqrt()
                } else {
                    -1.0
                };
                // Where the band is wholly inside both radii (no square root needed).
                let chord =
                    |r: f32| if r > 0.0 && r * r > dy2 { (r * r - dy2).sqrt() } else { -1.0 };
                let h_solid = chord(ro - 0.5);
                let h_inner = if ri > 0.0 { chord(ri + 0.5) } else { -1.0 };
                // The caps this row passes near (a cap is a disc of radius hw about its centre).
                let near = caps.map(|(_, cy)| (dy + c.y - cy).abs() < hw + 0.5);
                let (ox, clear) = (t.ox, t.clear(y, x0, x1));
                let row = t.row(y);
                // The hollow is left alone; every other pixel gets its exact coverage.
                let mut runs = [(0, 0, false); 1];
                let n = if hollow > 0.0 {
                    let (a, b) = inside(c.x, -hollow, hollow);
                    runs[0] = (a, b, false);
                    1
                } else {
                    0
                };
                let band = |xc: f32| {
                    let dx = xc - c.x;
                    let adx = dx.abs();
                    let radial = if adx <= h_solid && adx >= h_inner {
                        1.0
                    } else {
                        let d = (dx * dx + dy2).sqrt();
                        cov(ro, d) - if ri > 0.0 { cov(ri, d) } else { 0.0 }
                    };
                    // Signed distances to the start and end edges (lines through the centre).
                    let e0 = (u0.0 * dy - u0.1 * dx + 0.5).clamp(0.0, 1.0);
                    let e1 = (dx * u1.1 - dy * u1.0 + 0.5).clamp(0.0, 1.0);
                    // At most half a turn the sector is the cone between both edges; more,
                    // it is everything but the cone of the rest of the turn.
                    let ang = if small { e0.min(e1) } else { e0.max(e1) };
                    if radial > 0.0 { radial * ang } else { 0.0 }
                };
                if round && (near[0] || near[1]) {
                    let reach = (hw + 0.5) * (hw + 0.5);
                    scan_row(row, ox, (x0, x1), &runs[..n], pre, clear, |xc| {
                        let mut k = band(xc);
                        for (i, (cx, cy)) in caps.into_iter().enumerate() {
                            let d2 = (xc - cx).powi(2) + (dy + c.y - cy).powi(2);
                            if near[i] && k < 1.0 && d2 < reach {
                                k = k.max(cov(hw, d2.sqrt()));
                            }
                        }
                        k
                    });
                } else {
                    scan_row(row, ox, (x0, x1), &runs[..n], pre, clear, band);
                }
            }
        });
        Some(())
    }
}

/// The pixels a disc of radius `ro` around `c` may touch (one pixel of anti-aliasing
/// around it).
fn disc_bounds(c: Point, ro: f32) -> IRect {
    IRect::covering(Rect::new(c.x - ro - 1.0, c.y - ro - 1.0, 2.0 * ro + 2.0, 2.0 * ro + 2.0))
}

/// The pixel columns whose centres lie between `lo` and `hi` from `cx`, less one pixel at
/// each end (so that rounding never puts a pixel in that is out): `(start, end)`.
fn inside(cx: f32, lo: f32, hi: f32) -> (i32, i32) {
    ((cx + lo - 0.5).ceil() as i32 + 1, (cx + hi - 0.5).floor() as i32)
}

/// Blends `pre` over columns `x0..x1` of `row` (`row[0]` is device column `ox`): inside the sorted,
/// disjoint `runs` `(start, end, solid)` at once (fully covered: a copy where the row is
/// `clear`, i.e. transparent; or left alone), elsewhere under the coverage `k` of each
/// pixel (its argument the pixel centre's x), computed 64 pixels at a time so that the
/// loop vectorises, then blended as one masked row.
#[inline(always)]
fn scan_row(
    row: &mut [[u8; 4]],
    ox: i32,
    (x0, x1): (i32, i32),
    runs: &[(i32, i32, bool)],
    pre: [u8; 4],
    clear: bool,
    k: impl Fn(f32) -> f32,
) {
    if x1 <= x0 {
        return; // nothing of the row is covered (a ring cut by the layer's edge)
    }
    let mut x = x0;
    for &(a, b, solid) in runs {
        let a = a.clamp(x, x1);
        let b = b.clamp(a, x1);
        cover_span(row, ox, x, a, pre, &k);
        let run = &mut row[(a - ox) as usize..(b - ox) as usize];
        match (solid, clear) {
            (true, true) => run.fill(pre),
            (true, false) => pixel::blend_span(run, pre),
            _ => {}
        }
        x = x.max(b);
    }
    cover_span(row, ox, x, x1, pre, &k);
}

/// [`scan_row`] with no runs: every pixel of `row[x0..x1]` under its coverage.
#[inline(always)]
fn cover_span(
    row: &mut [[u8; 4]],
    ox: i32,
    x0: i32,
    x1: i32,
    pre: [u8; 4],
    k: &impl Fn(f32) -> f32,
) {
    let mut buf = [0u8; 64];
    let mut x = x0;
    while x < x1 {
        let n = ((x1 - x) as usize).min(buf.len());
        for (i, m) in buf[..n].iter_mut().enumerate() {
            *m = (k((x + i as i32) as f32 + 0.5) * 255.0 + 0.5) as u8;
        }
        let at = (x - ox) as usize;
        pixel::cover_row(&mut row[at..at + n], pre, &buf[..n]);
        x += n as i32;
    }
}
