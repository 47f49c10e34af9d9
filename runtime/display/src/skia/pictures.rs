//! Pictures: parts of a drawing that look the same frame after frame (a dial's face, its
//! ticks and track) rasterised once into a premultiplied sprite and then blitted, a copy
//! where the layer is still transparent. A HUD repaint then costs a copy of each face
//! instead of filling, stroking and blending its shapes again.
//!
//! A picture is keyed by the caller's key (which names what it draws relative to its
//! bounds), the bounds' size, the device scale and the bounds' sub-pixel phase: a cached
//! picture holds exactly the pixels drawing it there would give, shifted by whole pixels.
//! Source-over is associative, so blitting the picture equals drawing its shapes one by
//! one onto a transparent area, and comes within a rounding step of it elsewhere.

use super::SkiaCanvas;
use crate::geom::{IRect, Rect};
use crate::pixel;
use crate::tiles::Tiles;
use parking_lot::Mutex;
use std::collections::HashMap;
use std::sync::{Arc, OnceLock};

/// Pictures kept (bytes, all together) before the cache is emptied.
const CACHE_BYTES: usize = 32 << 20;
/// The largest picture cached (pixels); a larger one is drawn directly.
const PICTURE_MAX: i64 = 1024 * 1024;

/// A rasterised picture: premultiplied pixels and each row's non-transparent columns.
struct Sprite {
    w: usize,
    h: usize,
    px: Vec<[u8; 4]>,
    /// Each row's first and end non-transparent column (`0..0` when empty).
    rows: Vec<(u32, u32)>,
}

type Key = [u32; 7];

/// The sprites, and their bytes all together.
type Cache = (HashMap<Key, Arc<Sprite>>, usize);

fn cache() -> &'static Mutex<Cache> {
    static CACHE: OnceLock<Mutex<Cache>> = OnceLock::new();
    CACHE.get_or_init(Mutex::default)
}

/// A picture being recorded: the canvas drawing before it began, and where it goes.
pub(super) struct Recording {
    pub outer: SkiaCanvas,
    key: Key,
    at: IRect,
}

impl SkiaCanvas {
    /// Where a picture of user-space `bounds` lands on the pixmap, and its cache key;
    /// `None` when the transform is not a translate + uniform scale or the picture is too
    /// large to cache.
    fn picture_place(&self, key: u64, bounds: Rect) -> Option<(IRect, Key)> {
        let dev = self.device();
        if !(dev.is_axis_aligned() && dev.sx > 0.0 && (dev.sx - dev.sy).abs() < 1e-6) {
            return None;
        }
        let d = dev.map_rect(bounds);
        let at = IRect::covering(d);
        if at.is_empty() || at.area() > PICTURE_MAX || !(d.x.is_finite() && d.y.is_finite()) {
            return None;
        }
        let phase = |v: f32| (v - v.floor()).to_bits();
        let k = [
            key as u32,
            (key >> 32) as u32,
            dev.sx.to_bits(),
            bounds.w.to_bits(),
            bounds.h.to_bits(),
            phase(d.x),
            phase(d.y),
        ];
        Some((at, k))
    }

    /// Draws the cached picture `key` of `bounds`, if there is one: true when drawn.
    pub(super) fn draw_cached_picture(&mut self, key: u64, bounds: Rect) -> bool {
        let Some((at, k)) = self.picture_place(key, bounds) else { return false };
        let found = cache().lock().0.get(&k).cloned();
        match found {
            Some(s) if (s.w, s.h) == (at.w as usize, at.h as usize) => {
                self.blit_sprite(&s, at);
                true
            }
            _ => false,
        }
    }

    /// Starts recording picture `key` of `bounds`: drawings go to a transparent sprite
    /// until [`SkiaCanvas::end_recording`]. False (nothing recorded) when it cannot be
    /// cached.
    pub(super) fn begin_recording(&mut self, key: u64, bounds: Rect) -> bool {
        let Some((at, k)) = self.picture_place(key, bounds) else { return false };
        let Some(pm) = crate::alloc::pixmap(at.w as u32, at.h as u32) else { return false };
        let origin = (self.origin.0 + at.x, self.origin.1 + at.y);
        let mut sprite = SkiaCanvas::blank(pm, origin, self.size);
        sprite.state.transform = self.state.transform;
        let outer = std::mem::replace(self, sprite);
        self.recording = Some(Box::new(Recording { outer, key: k, at }));
        true
    }

    /// Ends the recording [`SkiaCanvas::begin_recording`] began: caches the sprite and
    /// draws it on the canvas it was recorded for.
    pub(super) fn end_recording(&mut self) {
        let Some(rec) = self.recording.take() else { return };
        let Recording { outer, key, at } = *rec;
        let sprite = std::mem::replace(self, outer);
        let (pm, _, _) = sprite.into_parts();
        let (px, _) = pm.data().as_chunks::<4>();
        let (w, h) = (at.w as usize, at.h as usize);
        let rows = px
            .chunks_exact(w)
            .map(|r| match r.iter().position(|p| p[3] != 0) {
                Some(a) => {
                    (a as u32, (w - r.iter().rev().position(|p| p[3] != 0).unwrap_or(0)) as u32)
                }
                None => (0, 0),
            })
            .collect();
        let s = Arc::new(Sprite { w, h, px: px.to_vec(), rows });
        {
            let mut c = cache().lock();
            let bytes = w * h * 4;
            if c.1 + bytes > CACHE_BYTES {
                c.0.clear();
                c.1 = 0;
            }
            c.1 += bytes;
            c.0.insert(key, s.clone());
        }
        self.blit_sprite(&s, at);
    }

    /// Source-over of `s` with its pixel (0, 0) at pixmap pixel `(at.x, at.y)`, inside the
    /// clip: a copy of each row where the pixmap is still transparent.
    fn blit_sprite(&mut self, s: &Sprite, at: IRect) {
        let area = at.intersect(&self.state.clip).intersect(&self.full());
        if area.is_empty() {
            return;
        }
        self.prepare(area);
        let w = self.pixmap.width() as usize;
        let (c0, c1) = ((area.x - at.x) as u32, (area.right() - at.x) as u32);
        let (px, _) = self.pixmap.data_mut().as_chunks_mut::<4>();
        for y in area.y..area.bottom() {
            let sy = (y - at.y) as usize;
            let (first, end) = s.rows[sy];
            let (a, b) = (first.max(c0) as usize, end.min(c1) as usize);
            if a >= b {
                continue;
            }
            let src = &s.px[sy * s.w + a..sy * s.w + b];
            let x = at.x + a as i32;
            let dst = &mut px[y as usize * w + x as usize..][..b - a];
            if clear(&self.tiles, x, y, (b - a) as i32) {
                dst.copy_from_slice(src);
            } else {
                pixel::blend_row(dst, src, 255);
            }
        }
        self.tiles.mark(area);
    }
}

/// Whether `n` pixels of row `y` from column `x` lie on undrawn (transparent) tiles.
fn clear(t: &Tiles, x: i32, y: i32, n: i32) -> bool {
    !t.touches(IRect::new(x, y, n, 1))
}
