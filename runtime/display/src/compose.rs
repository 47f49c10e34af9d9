//! CPU compositing: blends layer pixmaps bottom-up, with opacity, into the frame, only
//! inside the frame's damage rectangle.

use crate::color::Color;
use crate::geom::IRect;
use mocu_dataserver::Guid;
use tiny_skia::Pixmap;

/// One layer as the compositor sees it.
pub struct LayerView<'a> {
    /// The window the layer belongs to (a stable id for GPU textures).
    pub window: Guid,
    pub pixmap: &'a Pixmap,
    /// Where the pixmap's pixel (0, 0) lands on the screen.
    pub x: i32,
    pub y: i32,
    pub opacity: f32,
    /// The part of the pixmap repainted since the layer was last composited (pixmap
    /// pixels), or `None` when unchanged.
    pub changed: Option<IRect>,
}

impl LayerView<'_> {
    pub fn screen_rect(&self) -> IRect {
        IRect::new(self.x, self.y, self.pixmap.width() as i32, self.pixmap.height() as i32)
    }
}

/// The premultiplied RGBA8 bytes of an opaque colour.
pub(crate) fn premul(c: Color) -> [u8; 4] {
    let a = c.a as u32;
    let m = |v: u8| crate::skia::div255(v as u32 * a) as u8;
    [m(c.r), m(c.g), m(c.b), c.a]
}

const LANES: u64 = 0x00FF_00FF_00FF_00FF;

/// Spreads RGBA8 into four 16-bit lanes (r, b, g, a order inside the u64).
#[inline(always)]
fn expand(p: u32) -> u64 {
    let p = p as u64;
    (p | (p << 24)) & LANES
}

#[inline(always)]
fn collapse(x: u64) -> u32 {
    ((x & 0x00FF_00FF) | ((x >> 24) & 0xFF00_FF00)) as u32
}

/// Each lane times `m` (0..=255), divided by 255 with rounding.
#[inline(always)]
fn scale(x: u64, m: u64) -> u64 {
    let t = x * m + 0x0080_0080_0080_0080;
    ((t + ((t >> 8) & LANES)) >> 8) & LANES
}

/// `dst = src * opacity + dst * (1 - src.a * opacity)` over one row of premultiplied
/// pixels. Fast paths: transparent source pixels are skipped, opaque ones copied.
pub(crate) fn blend_row(dst: &mut [[u8; 4]], src: &[[u8; 4]], opacity: u8) {
    // Layers are mostly fully transparent (a HUD) or fully opaque (a chart, video): whole
    // runs of 8 pixels are skipped, or copied when the layer is opaque too, without
    // per-pixel arithmetic.
    let n = dst.len().min(src.len());
    let (dst, src) = (&mut dst[..n], &src[..n]);
    let mut d8 = dst.chunks_exact_mut(8);
    let mut s8 = src.chunks_exact(8);
    for (d, s) in (&mut d8).zip(&mut s8) {
        let (mut any, mut all) = (0u8, 255u8);
        for p in s {
            any |= p[3];
            all &= p[3];
        }
        if any == 0 {
            continue;
        }
        if all == 255 && opacity == 255 {
            d.copy_from_slice(s);
            continue;
        }
        blend_pixels(d, s, opacity);
    }
    blend_pixels(d8.into_remainder(), s8.remainder(), opacity);
}

/// Source-over pixel by pixel, with a layer opacity.
fn blend_pixels(dst: &mut [[u8; 4]], src: &[[u8; 4]], opacity: u8) {
    let o = opacity as u64;
    for (d, s) in dst.iter_mut().zip(src) {
        let sp = u32::from_le_bytes(*s);
        if sp == 0 {
            continue;
        }
        let sx = if opacity == 255 { expand(sp) } else { scale(expand(sp), o) };
        let sa = (sx >> 48) & 0xFF;
        if sa == 255 {
            *d = collapse(sx).to_le_bytes();
            continue;
        }
        if sx == 0 {
            continue;
        }
        let dx = scale(expand(u32::from_le_bytes(*d)), 255 - sa);
        *d = collapse(sx + dx).to_le_bytes();
    }
}

/// The CPU compositor: owns the frame.
/// Source-over of one premultiplied colour onto a run of pixels (a shape's solid
/// interior): a fill when opaque, else the lane arithmetic of [`blend_row`].
pub(crate) fn blend_span(dst: &mut [[u8; 4]], src: [u8; 4]) {
    if src[3] == 255 {
        dst.fill(src);
        return;
    }
    if src == [0; 4] {
        return;
    }
    let sx = expand(u32::from_le_bytes(src));
    let inv = 255 - src[3] as u64;
    for d in dst {
        let dx = scale(expand(u32::from_le_bytes(*d)), inv);
        *d = collapse(sx + dx).to_le_bytes();
    }
}

pub struct CpuCompositor {
    frame: Pixmap,
    background: [u8; 4],
}

impl CpuCompositor {
    pub fn new(width: u32, height: u32, background: Color) -> Option<CpuCompositor> {
        Some(CpuCompositor { frame: Pixmap::new(width, height)?, background: premul(background) })
    }

    pub fn frame(&self) -> &Pixmap {
        &self.frame
    }

    pub fn resize(&mut self, width: u32, height: u32) {
        if let Some(p) = Pixmap::new(width, height) {
            self.frame = p;
        }
    }

    pub fn bounds(&self) -> IRect {
        IRect::new(0, 0, self.frame.width() as i32, self.frame.height() as i32)
    }

    /// Recomposites `damage` (screen pixels) from `layers`, bottom first.
    pub fn composite(&mut self, layers: &[LayerView<'_>], damage: IRect) {
        let damage = damage.intersect(&self.bounds());
        if damage.is_empty() {
            return;
        }
        let fw = self.frame.width() as usize;
        let (dst_px, _) = self.frame.data_mut().as_chunks_mut::<4>();
        for y in damage.y..damage.bottom() {
            let row = &mut dst_px[y as usize * fw + damage.x as usize..][..damage.w as usize];
            row.fill(self.background);
        }
        for l in layers {
            let op = (l.opacity.clamp(0.0, 1.0) * 255.0).round() as u8;
            if op == 0 {
                continue;
            }
            let r = l.screen_rect().intersect(&damage);
            if r.is_empty() {
                continue;
            }
            let lw = l.pixmap.width() as usize;
            let (src_px, _) = l.pixmap.data().as_chunks::<4>();
            for y in r.y..r.bottom() {
                let sy = (y - l.y) as usize;
                let sx = (r.x - l.x) as usize;
                let src = &src_px[sy * lw + sx..][..r.w as usize];
                let dst = &mut dst_px[y as usize * fw + r.x as usize..][..r.w as usize];
                blend_row(dst, src, op);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn reference(d: [u8; 4], s: [u8; 4], o: u8) -> [u8; 4] {
        let o = o as f64 / 255.0;
        let sa = s[3] as f64 * o;
        std::array::from_fn(|i| (s[i] as f64 * o + d[i] as f64 * (1.0 - sa / 255.0)).round() as u8)
    }

    #[test]
    fn blending_matches_the_float_formula_within_one() {
        let samples =
            [[0, 0, 0, 0], [255, 0, 0, 255], [10, 20, 30, 40], [128, 64, 0, 128], [1, 1, 1, 1]];
        for d in samples {
            for s in samples {
                for o in [0u8, 1, 77, 128, 200, 255] {
                    let mut out = [d];
                    blend_row(&mut out, &[s], o);
                    let want = reference(d, s, o);
                    for i in 0..4 {
                        assert!(
                            (out[0][i] as i32 - want[i] as i32).abs() <= 1,
                            "d={d:?} s={s:?} o={o}: {:?} vs {want:?}",
                            out[0]
                        );
                    }
                }
            }
        }
    }
}

/// Source-over of one premultiplied colour onto one pixel (lane arithmetic).
#[inline(always)]
pub(crate) fn over_px(dst: &mut [u8; 4], src: [u8; 4]) {
    let s = u32::from_le_bytes(src);
    let sa = (s >> 24) as u64;
    if sa == 255 {
        *dst = src;
        return;
    }
    let d = scale(expand(u32::from_le_bytes(*dst)), 255 - sa);
    *dst = collapse(expand(s) + d).to_le_bytes();
}
