//! Coverage masks of analytic shapes, kept between frames: a HUD draws the same rings and
//! arcs at the same places frame after frame, and blending a cached mask is several times
//! cheaper than working out each edge pixel's coverage again.
//!
//! A mask is keyed by everything its coverage depends on, device coordinates included, so
//! a cached shape draws exactly the pixels the rasteriser would: the rasteriser draws the
//! mask once (opaque black onto transparent pixels leaves the coverage in the alpha), and
//! blending `colour x coverage` over the pixmap is the arithmetic the rasteriser's own
//! blends do.

use super::SkiaCanvas;
use crate::color::Color;
use crate::geom::IRect;
use crate::pixel;
use crate::tiles::Tiles;
use parking_lot::Mutex;
use std::collections::{HashMap, HashSet};
use std::sync::{Arc, OnceLock};

/// Masks kept (bytes, all masks together) before the cache is emptied.
const CACHE_BYTES: usize = 16 << 20;
/// The largest shape cached (pixels of its bounding box); larger ones draw directly.
const MASK_MAX: i64 = 512 * 512;

/// Where a rasteriser draws: pixels `w` wide whose (0, 0) is device pixel `(ox, oy)`.
pub(super) struct Target<'a> {
    px: &'a mut [[u8; 4]],
    w: usize,
    pub ox: i32,
    oy: i32,
    /// The pixmap's drawn-on tiles, when the target is the pixmap: elsewhere it is
    /// transparent.
    drawn: Option<&'a Tiles>,
}

impl Target<'_> {
    /// Whether device pixels `x0..x1` of row `y` are known to be transparent (source-over
    /// there is a copy).
    #[inline]
    pub fn clear(&self, y: i32, x0: i32, x1: i32) -> bool {
        self.drawn.is_some_and(|t| !t.touches(IRect::new(x0, y, x1 - x0, 1)))
    }

    /// Device row `y`, indexed by `x - ox`.
    #[inline]
    pub fn row(&mut self, y: i32) -> &mut [[u8; 4]] {
        &mut self.px[(y - self.oy) as usize * self.w..][..self.w]
    }
}

struct Mask {
    bbox: IRect,
    data: Vec<u8>,
    /// Each row's covered columns, `first..end` (mask columns; empty rows `0..0`).
    rows: Vec<(u32, u32)>,
}

#[derive(Default)]
struct Cache {
    masks: HashMap<Box<[u32]>, Arc<Mask>>,
    bytes: usize,
    /// Hashes of the keys drawn once and not cached: a shape is cached the second time it
    /// is drawn, so a shape that moves every frame (a needle, a value's arc) is drawn
    /// directly instead of paying for a mask it never reuses.
    seen: HashSet<u64>,
}

/// Keys remembered as seen once, at most (then forgotten all together).
const SEEN_MAX: usize = 8192;

/// Whether the shape `key` is to be drawn through its mask: it is cached, or was drawn
/// once before. The first time, it is remembered and drawn directly.
fn admit(key: &[u32]) -> bool {
    let mut c = cache().lock();
    if c.masks.contains_key(key) {
        return true;
    }
    let h = seen_hash(key);
    if c.seen.contains(&h) {
        return true;
    }
    if c.seen.len() >= SEEN_MAX {
        c.seen.clear();
    }
    c.seen.insert(h);
    false
}

fn seen_hash(key: &[u32]) -> u64 {
    use std::hash::{BuildHasher, BuildHasherDefault};
    BuildHasherDefault::<std::collections::hash_map::DefaultHasher>::default().hash_one(key)
}

fn cache() -> &'static Mutex<Cache> {
    static CACHE: OnceLock<Mutex<Cache>> = OnceLock::new();
    CACHE.get_or_init(Mutex::default)
}

impl SkiaCanvas {
    /// Draws a shape in `color`: `draw` rasterises it (drawing a premultiplied colour onto
    /// a target, inside an area of device pixels), `bbox` is every pixel it may touch.
    /// With a `key` (naming the shape exactly) the shape is drawn through its cached
    /// coverage mask (from the second time it is drawn); without one, or when it is
    /// large, straight onto the pixmap.
    pub(super) fn shape(
        &mut self,
        key: Option<&[u32]>,
        bbox: IRect,
        color: Color,
        draw: impl FnOnce(&mut Target<'_>, IRect, [u8; 4]),
    ) {
        if bbox.intersect(&self.state.clip).is_empty() || color.a == 0 {
            return;
        }
        // Drawn directly the first time: the analytic rasterisers blend their coverage
        // with the arithmetic a mask's blend uses, so both give the same pixels.
        let key = key.filter(|k| bbox.area() <= MASK_MAX && admit(k));
        self.through_mask(key, true, bbox, color, draw)
    }

    /// [`SkiaCanvas::shape`] once the key is admitted: through the mask of `key` (kept in
    /// the cache when `keep`), or directly when there is no key.
    fn through_mask(
        &mut self,
        key: Option<&[u32]>,
        keep: bool,
        bbox: IRect,
        color: Color,
        draw: impl FnOnce(&mut Target<'_>, IRect, [u8; 4]),
    ) {
        let area = bbox.intersect(&self.state.clip);
        if area.is_empty() || color.a == 0 {
            return;
        }
        let pre = pixel::premultiply(color);
        self.prepare(area);
        let w = self.pixmap.width() as usize;
        let (px, _) = self.pixmap.data_mut().as_chunks_mut::<4>();
        let Some(key) = key.filter(|_| bbox.area() <= MASK_MAX) else {
            draw(&mut Target { px, w, ox: 0, oy: 0, drawn: Some(&self.tiles) }, area, pre);
            self.tiles.mark(area);
            return;
        };
        self.tiles.mark(area);
        let found = cache().lock().masks.get(key).cloned();
        let mask = match found {
            Some(m) if m.bbox == bbox => m,
            _ if !keep => Arc::new(rasterise(bbox, draw)),
            _ => {
                let m = Arc::new(rasterise(bbox, draw));
                let mut c = cache().lock();
                if c.bytes + m.data.len() > CACHE_BYTES {
                    c.masks.clear();
                    c.bytes = 0;
                }
                c.bytes += m.data.len();
                c.masks.insert(key.into(), m.clone());
                m
            }
        };
        let mw = bbox.w as usize;
        let (c0, c1) = ((area.x - bbox.x) as u32, (area.right() - bbox.x) as u32);
        for y in area.y..area.bottom() {
            let my = (y - bbox.y) as usize;
            let (first, end) = mask.rows[my];
            let (a, b) = (first.max(c0) as usize, end.min(c1) as usize);
            if a >= b {
                continue;
            }
            let m = &mask.data[my * mw + a..my * mw + b];
            let x = (bbox.x + a as i32) as usize; // inside the area, so on the pixmap
            pixel::cover_row(&mut px[y as usize * w + x..][..b - a], pre, m);
        }
    }
}

/// Path elements (points) cached at most: longer paths are drawn directly.
const PATH_MAX: usize = 64;

impl SkiaCanvas {
    /// Fills (`stroke` None) or strokes a small path in a solid colour through its cached
    /// coverage mask: tiny-skia rasterises it once, opaque black onto a transparent
    /// pixmap the size of `bbox` (the pixmap pixels it may touch), under the same
    /// transform shifted by whole pixels, and the mask's alpha is the coverage. Keyed by
    /// the path's points, the transform and the stroke, so a needle or an outline that
    /// did not move is blended, not rasterised again. False when not applicable (a long
    /// path, a large one).
    pub(super) fn cached_path(
        &mut self,
        path: &crate::path::Path,
        sk: &tiny_skia::Path,
        stroke: Option<&tiny_skia::Stroke>,
        color: Color,
        bbox: IRect,
    ) -> bool {
        use crate::path::PathEl;
        let els = path.elements();
        if els.len() > PATH_MAX || bbox.area() > MASK_MAX || bbox.is_empty() {
            return false;
        }
        let dev = self.device();
        let mut key: Vec<u32> = Vec::with_capacity(16 + els.len() * 3);
        key.push(3);
        key.extend([dev.sx, dev.ky, dev.kx, dev.sy, dev.tx, dev.ty].map(f32::to_bits));
        key.extend([bbox.x, bbox.y, bbox.w, bbox.h].map(|v| v as u32));
        match stroke {
            None => key.push(0),
            Some(s) => {
                key.extend([1, s.width.to_bits(), s.miter_limit.to_bits()]);
                key.extend([s.line_cap as u32, s.line_join as u32]);
                if let Some(d) = &s.dash {
                    // The dash pattern as the stroke was built from it.
                    key.push(2);
                    key.extend(format!("{d:?}").bytes().map(u32::from));
                }
            }
        }
        for el in els {
            let pts: &[crate::geom::Point] = match el {
                PathEl::MoveTo(p) => {
                    key.push(10);
                    std::slice::from_ref(p)
                }
                PathEl::LineTo(p) => {
                    key.push(11);
                    std::slice::from_ref(p)
                }
                PathEl::QuadTo(a, b) => {
                    key.push(12);
                    key.extend([a.x, a.y].map(f32::to_bits));
                    std::slice::from_ref(b)
                }
                PathEl::CubicTo(a, b, c) => {
                    key.push(13);
                    key.extend([a.x, a.y, b.x, b.y].map(f32::to_bits));
                    std::slice::from_ref(c)
                }
                PathEl::Close => {
                    key.push(14);
                    &[]
                }
            };
            for p in pts {
                key.extend([p.x.to_bits(), p.y.to_bits()]);
            }
        }
        if color.a == 0 {
            return true;
        }
        // Always through a mask (the same pixels cached or not); kept from the second time.
        let keep = admit(&key);
        let paint = tiny_skia::Paint { anti_alias: true, ..tiny_skia::Paint::default() };
        // Through a mask: never drawn directly by this black-ink closure.
        self.through_mask(Some(&key), keep, bbox, color, |t, _, _| {
            let (w, h) = (t.w, t.px.len() / t.w.max(1));
            let Some(mut pm) =
                tiny_skia::PixmapMut::from_bytes(t.px.as_flattened_mut(), w as u32, h as u32)
            else {
                return;
            };
            let shift = crate::geom::Transform::translate(-t.ox as f32, -t.oy as f32);
            let tt = dev.then(&shift).to_skia();
            match stroke {
                None => pm.fill_path(sk, &paint, tiny_skia::FillRule::Winding, tt, None),
                Some(s) => pm.stroke_path(sk, &paint, s, tt, None),
            }
        });
        true
    }
}

/// The coverage of the shape `draw` rasterises inside `bbox`.
fn rasterise(bbox: IRect, draw: impl FnOnce(&mut Target<'_>, IRect, [u8; 4])) -> Mask {
    let (w, h) = (bbox.w as usize, bbox.h as usize);
    let mut px = vec![[0u8; 4]; w * h];
    let mut t = Target { px: &mut px, w, ox: bbox.x, oy: bbox.y, drawn: None };
    draw(&mut t, bbox, [0, 0, 0, 255]);
    let data: Vec<u8> = px.iter().map(|p| p[3]).collect();
    let rows = data
        .chunks_exact(w.max(1))
        .map(|r| match r.iter().position(|&k| k != 0) {
            Some(a) => (a as u32, (w - r.iter().rev().position(|&k| k != 0).unwrap_or(0)) as u32),
            None => (0, 0),
        })
        .collect();
    Mask { bbox, data, rows }
}
