//! Disjoint straight segments stroked with analytic coverage under a translate + uniform
//! scale: ticks, crosses, grid lines. A chart's grid crosses every row of its layer, so
//! the axis-aligned case is worked out before the rows are scanned: which columns and rows
//! a segment covers wholly, the colour of each column of a narrow one (a vertical grid
//! line is two pixels a row, blended from colours made ready once), and only the ends of
//! a long one computed pixel by pixel.

use super::SkiaCanvas;
use crate::canvas::{LineCap, Stroke};
use crate::color::Color;
use crate::geom::{IRect, Point, Rect};
use crate::path::{Path, PathEl};
use crate::pixel::{self, Over};
use crate::tiles::TILE_H;

/// A segment in pixmap pixels, ready to scan: its start, unit direction and length, the
/// pixels it may touch, and for an axis-aligned one the coverage of each column.
struct Seg {
    a: Point,
    ux: f32,
    uy: f32,
    len: f32,
    bbox: IRect,
    axis: Option<Axis>,
}

/// An axis-aligned segment's coverage: a factor of the column times a factor of the row.
struct Axis {
    /// Each column's factor (from `bbox.x`).
    fx: Vec<f32>,
    /// The first run of columns whose factor is 1: `fx[ones.0..ones.1]`.
    ones: (usize, usize),
    /// The rows whose factor is 1 (`full.0..full.1`): there each column's coverage is its
    /// factor.
    full: (i32, i32),
    /// The columns' factors as coverage bytes, made when a wholly covered row needs them.
    kx: Option<Vec<u8>>,
    /// A narrow one (at most 8 covered columns, a vertical line): the pixmap column of
    /// its first covered column and each covered column's colour under its coverage.
    narrow: Option<(usize, Vec<Over>)>,
}

/// The index range `lo..hi` of `0..n` between the first and the last index where `p`
/// holds, scanning in from both ends (`(0, 0)` when it holds nowhere).
fn span(n: usize, p: impl Fn(usize) -> bool) -> (usize, usize) {
    match (0..n).find(|&i| p(i)) {
        Some(lo) => (lo, (lo..n).rev().find(|&i| p(i)).map_or(lo, |i| i + 1)),
        None => (0, 0),
    }
}

/// A coverage factor as a byte, as every blend here rounds it.
#[inline(always)]
fn byte(k: f32) -> u8 {
    (k * 255.0 + 0.5) as u8
}

impl SkiaCanvas {
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
                [PathEl::MoveTo(a), PathEl::LineTo(b)] => segs.push((*a, *b)),
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
        let w = self.pixmap.width() as usize;
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
            self.tiles.mark(bbox);
            // Axis-aligned (grid lines, ticks): the coverage is a factor of the column
            // times a factor of the row, and along the line whole runs share one.
            let axis = (stroke.cap != LineCap::Round && (ux == 0.0 || uy == 0.0)).then(|| {
                let col = |i: usize| {
                    let pxv = (bbox.x + i as i32) as f32 + 0.5 - a.x;
                    if uy == 0.0 { ka(pxv * ux, len) } else { kp((pxv * uy).abs()) }
                };
                let row = |y: i32| {
                    let py = y as f32 + 0.5 - a.y;
                    if uy == 0.0 { kp((py * ux).abs()) } else { ka(py * uy, len) }
                };
                let n = bbox.w as usize;
                let (fx, ones): (Vec<f32>, _) = if uy == 0.0 {
                    // Along a horizontal line the factor rises to 1, stays, and falls (the
                    // smaller of a rising and a falling clamp): only its ends are computed.
                    let ones = span(n, |i| col(i) == 1.0);
                    let fx = (0..n).map(|i| if i >= ones.0 && i < ones.1 { 1.0 } else { col(i) });
                    (fx.collect(), ones)
                } else {
                    let fx: Vec<f32> = (0..n).map(col).collect();
                    let lo = fx.iter().position(|k| *k == 1.0).unwrap_or(0);
                    let run = fx[lo..].iter().take_while(|k| **k == 1.0).count();
                    (fx, (lo, lo + run))
                };
                let full = span(bbox.h as usize, |i| row(bbox.y + i as i32) == 1.0);
                let full = (bbox.y + full.0 as i32, bbox.y + full.1 as i32);
                let (first, end) = span(n, |i| byte(fx[i]) != 0);
                let narrow = (end > first && end - first <= 8).then(|| {
                    let cols =
                        fx[first..end].iter().map(|k| Over::new(pixel::scale(pre, byte(*k))));
                    (bbox.x as usize + first, cols.collect())
                });
                Axis { fx, ones, full, kx: None, narrow }
            });
            prepared.push(Seg { a, ux, uy, len, bbox, axis });
        }
        let Some(top) = prepared.iter().map(|g| g.bbox.y).min() else { return Some(()) };
        let bottom = prepared.iter().map(|g| g.bbox.bottom()).max().unwrap_or(top);
        // Row by row over all the segments: a grid's vertical lines touch each row of the
        // pixmap once, in memory order, instead of a new page per pixel; a band of rows
        // made ready (cleared, its background filled) just before it is drawn on.
        let left = prepared.iter().map(|g| g.bbox.x).min().unwrap_or(0);
        let right = prepared.iter().map(|g| g.bbox.right()).max().unwrap_or(left);
        let mut band = top;
        while band < bottom {
            let end = ((band / TILE_H + 1) * TILE_H).min(bottom);
            self.prepare(IRect::new(left, band, right - left, end - band));
            let (px, _) = self.pixmap.data_mut().as_chunks_mut::<4>();
            for y in band..end {
                let row = &mut px[y as usize * w..][..w];
                for g in prepared.iter_mut() {
                    if y < g.bbox.y || y >= g.bbox.bottom() {
                        continue;
                    }
                    let (a, ux, uy, len) = (g.a, g.ux, g.uy, g.len);
                    let py = y as f32 + 0.5 - a.y;
                    if let Some(ax) = &mut g.axis {
                        let fy = if y >= ax.full.0 && y < ax.full.1 {
                            1.0
                        } else if uy == 0.0 {
                            kp((py * ux).abs())
                        } else {
                            ka(py * uy, len)
                        };
                        if fy <= 0.0 {
                            continue;
                        }
                        if fy == 1.0 {
                            if let Some((x0, cols)) = &ax.narrow {
                                // Wholly crossed, narrow: `over` of each column's colour
                                // under its coverage is `over_coverage` of the colour.
                                let dst = &mut row[*x0..*x0 + cols.len()];
                                dst.iter_mut().zip(cols).for_each(|(d, c)| c.over(d));
                                continue;
                            }
                            // Wholly crossed: each column's coverage as it is.
                            let kx = ax.kx.get_or_insert_with(|| {
                                ax.fx.iter().map(|k| byte(*k)).collect::<Vec<u8>>()
                            });
                            pixel::cover_row(&mut row[g.bbox.x as usize..][..kx.len()], pre, kx);
                            continue;
                        }
                        let fx = &ax.fx;
                        let row = &mut row[g.bbox.x as usize..][..fx.len()];
                        let run = pixel::scale(pre, byte(fy));
                        let mut i = 0;
                        while i < fx.len() {
                            if fx[i] == 1.0 {
                                let e = if i == ax.ones.0 {
                                    ax.ones.1
                                } else {
                                    i + fx[i..].iter().take_while(|k| **k == 1.0).count()
                                };
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
            band = end;
        }
        Some(())
    }
}
