//! Analytic rasterisers for the shapes HUDs are made of — circles, rings, stroked arcs
//! and straight segments — under a translate + uniform scale: exact anti-aliased coverage
//! per pixel, fully covered runs blended at once. tiny-skia's supersampling rasteriser
//! costs several times more for these.

use super::SkiaCanvas;
use crate::canvas::{LineCap, Stroke};
use crate::color::Color;
use crate::geom::{IRect, Point, Rect};
use crate::path::Path;
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
        let Some(bbox) = self.disc_box(c, ro) else { return Some(()) };
        let solid = pixel::premultiply(color);
        self.ready();
        let w = self.pixmap.width() as usize;
        let (px, _) = self.pixmap.data_mut().as_chunks_mut::<4>();
        let cov = |r: f32, d: f32| (r - d + 0.5).clamp(0.0, 1.0);
        for y in bbox.y..bbox.bottom() {
            let dy = y as f32 + 0.5 - c.y;
            let dy2 = dy * dy;
            let outer2 = (ro + 0.5) * (ro + 0.5);
            if dy2 >= outer2 {
                continue;
            }
            let half = (outer2 - dy2).sqrt();
            let x0 = ((c.x - half).floor() as i32).max(bbox.x);
            let x1 = ((c.x + half).ceil() as i32).min(bbox.right());
            // Half-chords (in pixel-centre distance) of: full coverage by the outer edge,
            // the hollow inside the inner edge, and the inner edge's influence.
            let chord = |r: f32| if r > 0.0 && r * r > dy2 { (r * r - dy2).sqrt() } else { -1.0 };
            let h_solid = chord(ro - 0.5);
            let h_hollow = if ri > 0.0 { chord(ri - 0.5) } else { -1.0 };
            let h_inner = if ri > 0.0 { chord(ri + 0.5) } else { -1.0 };
            let row = &mut px[y as usize * w..][..w];
            let mut x = x0;
            while x < x1 {
                let dx = x as f32 + 0.5 - c.x;
                let adx = dx.abs();
                if adx < h_hollow {
                    // Skip to the first pixel past the hollow.
                    let next = (c.x + h_hollow - 0.5).floor() as i32 + 1;
                    x = next.max(x + 1);
                    continue;
                }
                let solid_at = |x: i32| {
                    let adx = (x as f32 + 0.5 - c.x).abs();
                    adx <= h_solid && adx >= h_inner
                };
                if solid_at(x) {
                    // A run of fully covered pixels at once.
                    // Its end: where the outer edge or the hole begins (estimated, then
                    // settled pixel by pixel).
                    let edge = if dx < 0.0 && h_inner >= 0.0 { -h_inner } else { h_solid };
                    let mut e = ((c.x + edge - 0.5).floor() as i32 + 1).clamp(x + 1, x1);
                    while e < x1 && solid_at(e) {
                        e += 1;
                    }
                    while e > x + 1 && !solid_at(e - 1) {
                        e -= 1;
                    }
                    pixel::blend_span(&mut row[x as usize..e as usize], solid);
                    x = e;
                    continue;
                }
                let k = {
                    let d = (dx * dx + dy2).sqrt();
                    let v = cov(ro, d) - if ri > 0.0 { cov(ri, d) } else { 0.0 };
                    (v * 255.0 + 0.5) as u32
                };
                pixel::over_coverage(&mut row[x as usize], solid, k.min(255) as u8);
                x += 1;
            }
        }
        Some(())
    }
}

impl SkiaCanvas {
    /// The uniform scale of the device transform when it is a translate + uniform
    /// positive scale (the analytic rasterisers' precondition).
    /// The pixels a disc of radius `ro` around `c` may touch (one pixel of anti-aliasing
    /// around it), within the clip; `None` when nothing of it is visible.
    fn disc_box(&self, c: Point, ro: f32) -> Option<IRect> {
        let r = Rect::new(c.x - ro - 1.0, c.y - ro - 1.0, 2.0 * ro + 2.0, 2.0 * ro + 2.0);
        let bbox = IRect::covering(r).intersect(&self.state.clip);
        (!bbox.is_empty()).then_some(bbox)
    }

    fn uniform_scale(&self) -> Option<f32> {
        let dev = self.device();
        (dev.is_axis_aligned() && dev.sx > 0.0 && (dev.sx - dev.sy).abs() < 1e-6).then_some(dev.sx)
    }

    /// Blends premultiplied `pre` at coverage `k` (0..=1) onto pixel `i` of the pixmap.
    #[inline]
    fn cover(px: &mut [[u8; 4]], i: usize, pre: [u8; 4], k: f32) {
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
        let Some(bbox) = self.disc_box(c, ro) else { return Some(()) };
        let pre = pixel::premultiply(color);
        self.ready();
        let w = self.pixmap.width() as usize;
        let (px, _) = self.pixmap.data_mut().as_chunks_mut::<4>();
        let cov = |r: f32, d: f32| (r - d + 0.5).clamp(0.0, 1.0);
        let small = sw <= std::f32::consts::PI;
        let outer2 = (ro + 0.5) * (ro + 0.5);
        for y in bbox.y..bbox.bottom() {
            let dy = y as f32 + 0.5 - c.y;
            let dy2 = dy * dy;
            if dy2 >= outer2 {
                continue;
            }
            let half = (outer2 - dy2).sqrt();
            let x0 = ((c.x - half).floor() as i32).max(bbox.x);
            let x1 = ((c.x + half).ceil() as i32).min(bbox.right());
            let hollow = if ri > 0.5 && (ri - 0.5) * (ri - 0.5) > dy2 {
                ((ri - 0.5) * (ri - 0.5) - dy2).sqrt()
            } else {
                -1.0
            };
            // Where the band is wholly inside both radii (no square root needed).
            let chord = |r: f32| if r > 0.0 && r * r > dy2 { (r * r - dy2).sqrt() } else { -1.0 };
            let h_solid = chord(ro - 0.5);
            let h_inner = if ri > 0.0 { chord(ri + 0.5) } else { -1.0 };
            // The caps this row passes near (a cap is a disc of radius hw about its centre).
            let near = caps.map(|(_, cy)| (dy + c.y - cy).abs() < hw + 0.5);
            let row = &mut px[y as usize * w..][..w];
            // Fully covered pixels are blended as runs.
            let mut run: Option<i32> = None;
            let flush = |row: &mut [[u8; 4]], run: &mut Option<i32>, end: i32| {
                if let Some(r0) = run.take() {
                    pixel::blend_span(&mut row[r0 as usize..end as usize], pre);
                }
            };
            let mut x = x0;
            while x < x1 {
                let dx = x as f32 + 0.5 - c.x;
                let adx = dx.abs();
                if adx < hollow {
                    flush(row, &mut run, x);
                    x = ((c.x + hollow - 0.5).floor() as i32 + 1).max(x + 1);
                    continue;
                }
                let radial = if adx <= h_solid && adx >= h_inner {
                    1.0
                } else {
                    let d = (dx * dx + dy2).sqrt();
                    cov(ro, d) - if ri > 0.0 { cov(ri, d) } else { 0.0 }
                };
                let mut k = 0.0f32;
                if radial > 0.0 {
                    // Signed distances to the start and end edges (lines through the centre).
                    let e0 = (u0.0 * dy - u0.1 * dx + 0.5).clamp(0.0, 1.0);
                    let e1 = (dx * u1.1 - dy * u1.0 + 0.5).clamp(0.0, 1.0);
                    // At most half a turn the sector is the cone between both edges;
                    // more, it is everything but the cone of the rest of the turn.
                    let ang = if small { e0.min(e1) } else { e0.max(e1) };
                    k = radial * ang;
                }
                if round && k < 1.0 && (near[0] || near[1]) {
                    let reach = (hw + 0.5) * (hw + 0.5);
                    for (i, (cx, cy)) in caps.into_iter().enumerate() {
                        if !near[i] {
                            continue;
                        }
                        let d2 = (x as f32 + 0.5 - cx).powi(2) + (dy + c.y - cy).powi(2);
                        if d2 < reach {
                            k = k.max(cov(hw, d2.sqrt()));
                        }
                    }
                }
                if k >= 1.0 {
                    run.get_or_insert(x);
                } else {
                    flush(row, &mut run, x);
                    if k > 0.0 {
                        Self::cover(row, x as usize, pre, k);
                    }
                }
                x += 1;
            }
            flush(row, &mut run, x1);
        }
        Some(())
    }

    /// Disjoint straight segments (each subpath one `move`+`line`), stroked with analytic
    /// coverage: ticks, needles' lines, crosses, grid lines. `None` when the path or the
    /// transform is not of that kind.
    pub(super) fn segments(&mut self, path: &Path, stroke: &Stroke, color: Color) -> Option<()> {
        let s = self.uniform_scale()?;
        if stroke.dash.is_some() {
            return None;
        }
        let els = path.elements();
        if els.is_empty() || !els.len().is_multiple_of(2) || els.len() > 512 {
            return None;
        }
        let mut segs = Vec::with_capacity(els.len() / 2);
        for pair in els.chunks_exact(2) {
            match pair {
                [crate::path::PathEl::MoveTo(a), crate::path::PathEl::LineTo(b)] => {
                    segs.push((*a, *b))
                }
                _ => return None,
            }
        }
        if color.a == 0 || stroke.width <= 0.0 {
            return Some(());
        }
        let dev = self.device();
        let hw = stroke.width * s / 2.0;
        let pre = pixel::premultiply(color);
        let clip = self.state.clip;
        self.ready();
        let w = self.pixmap.width() as usize;
        let (px, _) = self.pixmap.data_mut().as_chunks_mut::<4>();
        // Caps extend the segment: square by hw, round (as capsules) by hw.
        let ext = match stroke.cap {
            LineCap::Butt => 0.0,
            LineCap::Square | LineCap::Round => hw,
        };
        let pad = hw + 1.0;
        let thin = (2.0 * hw).min(1.0);
        let ka = |along: f32, len: f32| {
            (along + ext + 0.5).clamp(0.0, 1.0).min((len + ext - along + 0.5).clamp(0.0, 1.0))
        };
        let kp = |across: f32| (hw + 0.5 - across).clamp(0.0, thin);
        let mut prepared: Vec<Seg> = Vec::with_capacity(segs.len());
        for (a, b) in segs {
            let (a, b) = (dev.apply(a), dev.apply(b));
            let (vx, vy) = (b.x - a.x, b.y - a.y);
            let len = (vx * vx + vy * vy).sqrt();
            if len < 1e-4 {
                continue;
            }
            let (ux, uy) = (vx / len, vy / len);
            let bbox = IRect::covering(Rect::new(
                a.x.min(b.x) - pad - ext,
                a.y.min(b.y) - pad - ext,
                vx.abs() + 2.0 * (pad + ext),
                vy.abs() + 2.0 * (pad + ext),
            ))
            .intersect(&clip);
            if bbox.is_empty() {
                continue;
            }
            // Axis-aligned (grid lines, ticks): the coverage is a factor of the column
            // times a factor of the row, and along the line whole runs share one.
            let fx = (stroke.cap != LineCap::Round && (ux == 0.0 || uy == 0.0)).then(|| {
                (bbox.x..bbox.right())
                    .map(|x| {
                        let pxv = x as f32 + 0.5 - a.x;
                        if uy == 0.0 { ka(pxv * ux, len) } else { kp((pxv * uy).abs()) }
                    })
                    .collect()
            });
            prepared.push(Seg { a, ux, uy, len, bbox, fx });
        }
        let Some(top) = prepared.iter().map(|g| g.bbox.y).min() else { return Some(()) };
        let bottom = prepared.iter().map(|g| g.bbox.bottom()).max().unwrap_or(top);
        // Row by row over all the segments: a grid's vertical lines touch each row of the
        // pixmap once, in memory order, instead of a new page per pixel.
        for y in top..bottom {
            let row = &mut px[y as usize * w..][..w];
            for g in &prepared {
                if y < g.bbox.y || y >= g.bbox.bottom() {
                    continue;
                }
                let (a, ux, uy, len) = (g.a, g.ux, g.uy, g.len);
                let py = y as f32 + 0.5 - a.y;
                if let Some(fx) = &g.fx {
                    let fy = if uy == 0.0 { kp((py * ux).abs()) } else { ka(py * uy, len) };
                    if fy <= 0.0 {
                        continue;
                    }
                    let row = &mut row[g.bbox.x as usize..][..fx.len()];
                    let run = pixel::scale(pre, (fy * 255.0 + 0.5) as u8);
                    let mut i = 0;
                    while i < fx.len() {
                        if fx[i] == 1.0 {
                            let e = i + fx[i..].iter().take_while(|k| **k == 1.0).count();
                            pixel::blend_span(&mut row[i..e], run);
                            i = e;
                            continue;
                        }
                        let k = fx[i] * fy;
                        if k > 0.0 {
                            SkiaCanvas::cover(row, i, pre, k);
                        }
                        i += 1;
                    }
                    continue;
                }
                // The columns near the line on this row.
                let (xa, xb) = if uy.abs() > 1e-3 {
                    let xc = a.x + py * ux / uy;
                    let span = (pad + ext) / uy.abs();
                    ((xc - span).floor() as i32, (xc + span).ceil() as i32)
                } else {
                    (g.bbox.x, g.bbox.right())
                };
                for x in xa.max(g.bbox.x)..xb.min(g.bbox.right()) {
                    let pxv = x as f32 + 0.5 - a.x;
                    let along = pxv * ux + py * uy;
                    let across = (pxv * uy - py * ux).abs();
                    let k = match stroke.cap {
                        LineCap::Round => {
                            let t = along.clamp(0.0, len);
                            let d = ((pxv - ux * t).powi(2) + (py - uy * t).powi(2)).sqrt();
                            (hw + 0.5 - d).clamp(0.0, thin)
                        }
                        _ => ka(along, len) * kp(across),
                    };
                    if k > 0.0 {
                        SkiaCanvas::cover(row, x as usize, pre, k);
                    }
                }
            }
        }
        Some(())
    }
}

/// A segment in pixmap pixels, ready to scan: its start, unit direction and length, the
/// pixels it may touch, and for an axis-aligned one the coverage factor of each column.
struct Seg {
    a: Point,
    ux: f32,
    uy: f32,
    len: f32,
    bbox: IRect,
    fx: Option<Vec<f32>>,
}
