//! Premultiplied RGBA8 pixel arithmetic: the one copy of premultiplying, scaling by a
//! coverage or an opacity, and source-over blending that the canvas, the compositor, the
//! images and every other module use. Pixels are `[r, g, b, a]` bytes, premultiplied.
//!
//! The blends work on four 16-bit lanes of a `u64` (one multiply per pixel, not four);
//! every division by 255 rounds to nearest, so results are within one of the float
//! formula `dst = src + dst * (1 - src.a)`.

use crate::color::Color;
use multiversion::multiversion;

/// `x / 255`, rounded to nearest, for `x` in `0..=65535`.
#[inline(always)]
pub fn div255(x: u32) -> u32 {
    let t = x + 128;
    (t + (t >> 8)) >> 8
}

/// The premultiplied RGBA8 bytes of a straight-alpha colour.
#[inline]
pub fn premultiply(c: Color) -> [u8; 4] {
    let a = c.a as u32;
    let m = |v: u8| div255(v as u32 * a) as u8;
    [m(c.r), m(c.g), m(c.b), c.a]
}

/// Premultiplies straight-alpha RGBA8 bytes in place (`rgba.len()` a multiple of 4).
pub fn premultiply_in_place(rgba: &mut [u8]) {
    for px in rgba.chunks_exact_mut(4) {
        let a = px[3] as u32;
        if a != 255 {
            for c in &mut px[..3] {
                *c = div255(*c as u32 * a) as u8;
            }
        }
    }
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
fn scale_lanes(x: u64, m: u64) -> u64 {
    let t = x * m + 0x0080_0080_0080_0080;
    ((t + ((t >> 8) & LANES)) >> 8) & LANES
}

/// A premultiplied pixel times `k` (0..=255): a colour under partial coverage or opacity.
#[inline(always)]
pub fn scale(px: [u8; 4], k: u8) -> [u8; 4] {
    collapse(scale_lanes(expand(u32::from_le_bytes(px)), k as u64)).to_le_bytes()
}

/// Source-over of one premultiplied pixel onto another.
#[inline(always)]
pub fn over(dst: &mut [u8; 4], src: [u8; 4]) {
    let s = u32::from_le_bytes(src);
    let sa = (s >> 24) as u64;
    if sa == 255 {
        *dst = src;
        return;
    }
    let d = scale_lanes(expand(u32::from_le_bytes(*dst)), 255 - sa);
    *dst = collapse(expand(s) + d).to_le_bytes();
}

/// A colour made ready to be blended over many pixels one at a time (a grid line's
/// column, row after row): its lanes and inverse alpha worked out once. [`Over::over`]
/// writes exactly what [`over`] writes.
#[derive(Clone, Copy, Debug)]
pub struct Over {
    src: [u8; 4],
    lanes: u64,
    inv: u64,
}

impl Over {
    pub fn new(src: [u8; 4]) -> Over {
        Over { src, lanes: expand(u32::from_le_bytes(src)), inv: 255 - src[3] as u64 }
    }

    #[inline(always)]
    pub fn over(&self, dst: &mut [u8; 4]) {
        if self.inv == 0 {
            *dst = self.src;
            return;
        }
        let d = scale_lanes(expand(u32::from_le_bytes(*dst)), self.inv);
        *dst = collapse(self.lanes + d).to_le_bytes();
    }
}

/// Source-over of `src` under coverage `k` (0..=255): a glyph mask or an anti-aliased
/// edge pixel.
#[inline(always)]
pub fn over_coverage(dst: &mut [u8; 4], src: [u8; 4], k: u8) {
    match k {
        0 => {}
        255 => over(dst, src),
        _ => {
            let s = scale_lanes(expand(u32::from_le_bytes(src)), k as u64);
            let sa = s >> 48;
            let d = scale_lanes(expand(u32::from_le_bytes(*dst)), 255 - sa);
            *dst = collapse(s + d).to_le_bytes();
        }
    }
}

/// `a * b / 255`, rounded to nearest, in 16-bit arithmetic (`a`, `b` in `0..=255`): the
/// form the 8-pixel kernels below are written in, so that the compiler vectorises them.
#[inline(always)]
fn mul255(a: u16, b: u16) -> u16 {
    let t = a * b + 128;
    (t + (t >> 8)) >> 8
}

/// Source-over of one premultiplied colour onto a run of pixels (a shape's solid
/// interior): a fill when opaque. Compiled for AVX2 too (twice the 16-bit lanes), picked
/// at run time.
#[multiversion(targets("x86_64+avx2"))]
pub fn blend_span(dst: &mut [[u8; 4]], src: [u8; 4]) {
    if src[3] == 255 {
        dst.fill(src);
        return;
    }
    if src == [0; 4] {
        return;
    }
    let inv = 255 - src[3] as u16;
    let sv: [u16; 32] = std::array::from_fn(|i| src[i % 4] as u16);
    let mut d8 = dst.as_flattened_mut().chunks_exact_mut(32);
    for d in &mut d8 {
        for i in 0..32 {
            d[i] = (sv[i] + mul255(d[i] as u16, inv)) as u8;
        }
    }
    for (i, d) in d8.into_remainder().iter_mut().enumerate() {
        *d = (sv[i % 4] + mul255(*d as u16, inv)) as u8;
    }
}

/// Source-over of one premultiplied colour under per-pixel coverage (`mask[i]` for
/// `dst[i]`, 0..=255): a row of a glyph run or of a cached shape's mask. Compiled for
/// AVX2 too, picked at run time.
#[multiversion(targets("x86_64+avx2"))]
pub fn cover_row(dst: &mut [[u8; 4]], src: [u8; 4], mask: &[u8]) {
    let n = dst.len().min(mask.len());
    let (dst, mask) = (&mut dst[..n], &mask[..n]);
    let s = u32::from_le_bytes(src);
    let mut d8 = dst.chunks_exact_mut(8);
    let mut m8 = mask.chunks_exact(8);
    for (d, m) in (&mut d8).zip(&mut m8) {
        // The eight coverages as one word: none, or all full.
        let m8 = u64::from_le_bytes(m.try_into().expect("chunks of 8"));
        if m8 == 0 {
            continue;
        }
        if m8 == u64::MAX && src[3] == 255 {
            d.fill(src);
            continue;
        }
        // Two channels a multiply in 32-bit lanes (the 16-bit form's broadcasts of each
        // pixel's coverage and alpha cost more than its multiplies save under AVX2).
        for (d, k) in d.iter_mut().zip(m) {
            *d = over_pair(s, u32::from_le_bytes(*d), *k as u32).to_le_bytes();
        }
    }
    for (d, k) in d8.into_remainder().iter_mut().zip(m8.remainder()) {
        over_coverage(d, src, *k);
    }
}

/// `dst = src * opacity + dst * (1 - src.a * opacity)` over one row of premultiplied
/// pixels. Fast paths: transparent source pixels are skipped, opaque ones copied.
/// Compiled for AVX2 too (its 32-bit vector multiplies more than double the blend's
/// speed), picked at run time.
#[multiversion(targets("x86_64+avx2"))]
pub fn blend_row(dst: &mut [[u8; 4]], src: &[[u8; 4]], opacity: u8) {
    // Layers are mostly fully transparent (a HUD) or fully opaque (a chart, video): whole
    // runs of 8 pixels are skipped, or copied when the layer is opaque too, without
    // per-pixel arithmetic.
    let n = dst.len().min(src.len());
    let (dst, src) = (&mut dst[..n], &src[..n]);
    let o = opacity as u16;
    let mut d8 = dst.chunks_exact_mut(8);
    let mut s8 = src.chunks_exact(8);
    for (d, s) in (&mut d8).zip(&mut s8) {
        // Two pixels a word or'ed and and'ed, then their alpha bytes (four loads, not
        // eight: this test runs on every 8 pixels of a layer's drawn-on tiles).
        let (w, _) = s.as_flattened().as_chunks::<8>();
        let (mut any, mut all) = (0u64, u64::MAX);
        for p in w {
            let v = u64::from_le_bytes(*p);
            any |= v;
            all &= v;
        }
        if any & ALPHAS == 0 {
            continue;
        }
        if all & ALPHAS == ALPHAS && opacity == 255 {
            d.copy_from_slice(s);
            continue;
        }
        for (d, s) in d.iter_mut().zip(s) {
            *d = over_pair(u32::from_le_bytes(*s), u32::from_le_bytes(*d), o as u32).to_le_bytes();
        }
    }
    for (d, s) in d8.into_remainder().iter_mut().zip(s8.remainder()) {
        over_coverage(d, *s, opacity);
    }
}

/// The alpha bytes of two pixels in a little-endian word.
const ALPHAS: u64 = 0xFF00_0000_FF00_0000;

const PAIRS: u32 = 0x00FF_00FF;

/// Two 8-bit values in the 16-bit halves of `x` (as `PAIRS` masks them) times `m`
/// (0..=255), each divided by 255 with rounding: [`mul255`] on both at once.
#[inline(always)]
fn mul255_pair(x: u32, m: u32) -> u32 {
    let t = x * m + 0x0080_0080;
    ((t + ((t >> 8) & PAIRS)) >> 8) & PAIRS
}

/// `src * k` over `dst` (premultiplied RGBA8 as little-endian words): red and blue, then
/// green and alpha, two channels a multiply.
#[inline(always)]
fn over_pair(src: u32, dst: u32, k: u32) -> u32 {
    let (c_rb, c_ga) = (mul255_pair(src & PAIRS, k), mul255_pair((src >> 8) & PAIRS, k));
    let inv = 255 - (c_ga >> 16);
    let d_rb = mul255_pair(dst & PAIRS, inv);
    let d_ga = mul255_pair((dst >> 8) & PAIRS, inv);
    ((c_rb + d_rb) & PAIRS) | (((c_ga + d_ga) & PAIRS) << 8)
}

#[cfg(test)]
mod tests {
    use super::*;

    const SAMPLES: [[u8; 4]; 6] = [
        [0, 0, 0, 0],
        [255, 0, 0, 255],
        [10, 20, 30, 40],
        [128, 64, 0, 128],
        [1, 1, 1, 1],
        [200, 100, 50, 200],
    ];

    fn reference(d: [u8; 4], s: [u8; 4], o: u8) -> [u8; 4] {
        let o = o as f64 / 255.0;
        let sa = s[3] as f64 * o;
        std::array::from_fn(|i| (s[i] as f64 * o + d[i] as f64 * (1.0 - sa / 255.0)).round() as u8)
    }

    fn within_one(got: [u8; 4], want: [u8; 4], what: &str) {
        for i in 0..4 {
            assert!((got[i] as i32 - want[i] as i32).abs() <= 1, "{what}: {got:?} vs {want:?}");
        }
    }

    #[test]
    fn div255_rounds_to_nearest_over_the_whole_range() {
        for x in 0..=65535u32 {
            assert_eq!(div255(x), (x as f64 / 255.0).round() as u32, "x = {x}");
        }
    }

    #[test]
    fn two_channels_a_multiply_equal_one_channel_a_multiply_over_the_whole_range() {
        for x in 0..=255u32 {
            for m in 0..=255u32 {
                let one = mul255(x as u16, m as u16) as u32;
                assert_eq!(mul255_pair(x | (x << 16), m), one | (one << 16), "{x} * {m}");
            }
        }
    }

    #[test]
    fn over_of_the_colour_scaled_by_a_coverage_equals_over_coverage_for_every_coverage() {
        for d in SAMPLES {
            for s in SAMPLES {
                for k in 0..=255u8 {
                    let (mut got, mut want) = (d, d);
                    over(&mut got, scale(s, k));
                    over_coverage(&mut want, s, k);
                    assert_eq!(got, want, "d={d:?} s={s:?} k={k}");
                }
            }
        }
    }

    #[test]
    fn premultiplying_scales_the_colour_channels_by_alpha() {
        let cases = [
            (Color::rgba(255, 128, 0, 255), [255, 128, 0, 255]),
            (Color::rgba(255, 128, 0, 128), [128, 64, 0, 128]),
            (Color::rgba(200, 100, 50, 0), [0, 0, 0, 0]),
            (Color::rgba(10, 20, 30, 51), [2, 4, 6, 51]),
        ];
        for (c, want) in cases {
            assert_eq!(premultiply(c), want, "{c:?}");
            let mut bytes = [c.r, c.g, c.b, c.a];
            premultiply_in_place(&mut bytes);
            assert_eq!(bytes, want, "in place: {c:?}");
        }
    }

    #[test]
    fn every_blend_matches_the_float_formula_within_one() {
        for d in SAMPLES {
            for s in SAMPLES {
                for o in [0u8, 1, 77, 128, 200, 255] {
                    let want = reference(d, s, o);
                    let mut row = [d];
                    blend_row(&mut row, &[s], o);
                    within_one(row[0], want, &format!("blend_row d={d:?} s={s:?} o={o}"));
                    let mut px = d;
                    over_coverage(&mut px, s, o);
                    within_one(px, want, &format!("over_coverage d={d:?} s={s:?} k={o}"));
                    let mut px = d;
                    over(&mut px, scale(s, o));
                    within_one(px, want, &format!("over(scale) d={d:?} s={s:?} k={o}"));
                }
                let mut span = [d; 3];
                blend_span(&mut span, s);
                for px in span {
                    within_one(px, reference(d, s, 255), &format!("blend_span d={d:?} s={s:?}"));
                }
            }
        }
    }

    /// A row of 19 pixels (two 8-pixel runs and a remainder) of varied pixels.
    fn row(seed: usize) -> Vec<[u8; 4]> {
        (0..19).map(|i| SAMPLES[(i * 5 + seed) % SAMPLES.len()]).collect()
    }

    #[test]
    fn a_prepared_colour_blends_exactly_as_over_does() {
        for d in SAMPLES {
            for s in SAMPLES {
                for k in [0u8, 1, 77, 128, 254, 255] {
                    let s = scale(s, k);
                    let (mut got, mut want) = (d, d);
                    Over::new(s).over(&mut got);
                    over(&mut want, s);
                    assert_eq!(got, want, "d={d:?} s={s:?}");
                }
            }
        }
    }

    #[test]
    fn the_row_kernels_equal_blending_pixel_by_pixel() {
        let coverages: Vec<u8> = (0..19).map(|i| [0u8, 255, 17, 128, 254][i % 5]).collect();
        for seed in 0..SAMPLES.len() {
            let (d0, s) = (row(seed), row(seed + 1));
            for o in [0u8, 77, 200, 255] {
                let mut got = d0.clone();
                blend_row(&mut got, &s, o);
                let mut want = d0.clone();
                want.iter_mut().zip(&s).for_each(|(d, s)| over_coverage(d, *s, o));
                assert_eq!(got, want, "blend_row seed {seed} opacity {o}");
            }
            for colour in SAMPLES {
                let mut got = d0.clone();
                blend_span(&mut got, colour);
                let mut want = d0.clone();
                want.iter_mut().for_each(|d| over(d, colour));
                assert_eq!(got, want, "blend_span seed {seed} colour {colour:?}");
                let mut got = d0.clone();
                cover_row(&mut got, colour, &coverages);
                let mut want = d0.clone();
                want.iter_mut().zip(&coverages).for_each(|(d, k)| over_coverage(d, colour, *k));
                assert_eq!(got, want, "cover_row seed {seed} colour {colour:?}");
            }
        }
    }

    #[test]
    fn blend_row_takes_its_fast_paths_over_whole_runs() {
        let dst0 = [[9, 8, 7, 255]; 19];
        let mut dst = dst0;
        blend_row(&mut dst, &[[0; 4]; 19], 255);
        assert_eq!(dst, dst0, "transparent source leaves the row");
        blend_row(&mut dst, &[[1, 2, 3, 255]; 19], 255);
        assert_eq!(dst, [[1, 2, 3, 255]; 19], "opaque source replaces the row");
    }
}
