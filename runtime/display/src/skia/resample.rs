//! Axis-aligned image draws without tiny-skia's float pipeline: a bilinear resampler in
//! fixed point (8-bit weights) that writes premultiplied pixels straight into the
//! pixmap's rows. A full-window video frame (640×480 scaled to 1920×1080) is the case it
//! is made for: tiny-skia's `Pattern` shader costs ~20 ns a pixel there.
//!
//! It samples where tiny-skia's bilinear `Pattern` with `SpreadMode::Pad` does (pixel
//! centres, mapped back into the image, half a pixel off, edges clamped), so both agree
//! within the rounding of the weights. Every position is computed from window pixels,
//! never from the pixmap's: a damage repaint (a pixmap starting anywhere in the window)
//! writes the same bytes as a full repaint.
//!
//! Rows are resampled horizontally once per source row (two cached, reused by every
//! output row between them when magnifying), then interpolated vertically: the
//! per-pixel work of that second pass is straight-line 16-bit lane arithmetic that the
//! compiler vectorises.

use crate::geom::IRect;
use crate::pixel;

/// Where the image lands along one axis: image pixel `u` at window coordinate
/// `scale * u + offset`; only `lo..hi` (window coordinates) is painted.
#[derive(Clone, Copy, Debug)]
pub(super) struct Axis {
    pub scale: f64,
    pub offset: f64,
    pub lo: f64,
    pub hi: f64,
}

/// Per output column (or row): the two source indices, the weight of the second
/// (0..=256), and the coverage of the painted range over the pixel (0..=255).
struct Taps {
    i0: Vec<u32>,
    i1: Vec<u32>,
    w: Vec<u16>,
    cov: Vec<u8>,
}

impl Axis {
    /// The taps of window pixels `first..first + n` over a source of `len` pixels.
    fn taps(&self, first: i32, n: usize, len: u32) -> Taps {
        let last = len.saturating_sub(1) as i64;
        let mut t = Taps {
            i0: Vec::with_capacity(n),
            i1: Vec::with_capacity(n),
            w: Vec::with_capacity(n),
            cov: Vec::with_capacity(n),
        };
        for k in 0..n {
            let p = (first as i64 + k as i64) as f64;
            let u = (p + 0.5 - self.offset) / self.scale - 0.5;
            let f = u.floor();
            let (mut i, mut w) = (f as i64, ((u - f) * 256.0).round() as u16);
            if w == 256 {
                (i, w) = (i + 1, 0);
            }
            t.i0.push(i.clamp(0, last) as u32);
            t.i1.push((i + 1).clamp(0, last) as u32);
            t.w.push(w);
            let c = ((p + 1.0).min(self.hi) - p.max(self.lo)).clamp(0.0, 1.0);
            t.cov.push((c * 255.0).round() as u8);
        }
        t
    }
}

/// The source image: premultiplied pixels, `width` a row.
pub(super) struct Source<'a> {
    pub px: &'a [[u8; 4]],
    pub width: u32,
    pub height: u32,
}

/// Draws `src` mapped by `x` and `y` (window coordinates) with `opacity` into `dst` (a
/// pixmap `dst_w` pixels wide whose pixel (0, 0) is window pixel `origin`), touching only
/// `area` (pixmap pixels, inside the pixmap). Edge pixels the painted range covers in
/// part are blended under their coverage.
#[allow(clippy::too_many_arguments)]
pub(super) fn draw(
    dst: &mut [[u8; 4]],
    dst_w: usize,
    origin: (i32, i32),
    area: IRect,
    src: &Source,
    x: Axis,
    y: Axis,
    opacity: u8,
) {
    let (sw, sh) = (src.width as usize, src.height as usize);
    if area.is_empty() || sw == 0 || sh == 0 || src.px.len() < sw * sh || opacity == 0 {
        return;
    }
    if let (Some(dx), Some(dy)) = (x.shift(), y.shift())
        && copy_shifted(dst, dst_w, origin, area, src, (dx, dy), opacity)
    {
        return;
    }
    let n = area.w as usize;
    let cols = x.taps(area.x + origin.0, n, src.width);
    let rows = y.taps(area.y + origin.1, area.h as usize, src.height);
    // The columns wholly covered: a contiguous run between at most one partial column
    // at each end.
    let full0 = cols.cov.iter().position(|&c| c == 255).unwrap_or(n);
    let full1 = cols.cov.iter().rposition(|&c| c == 255).map_or(full0, |i| i + 1);
    // Two horizontally resampled source rows, with the source row each holds.
    let mut h = [vec![[0u8; 4]; n], vec![[0u8; 4]; n]];
    let mut held = [usize::MAX; 2];
    let mut out = vec![[0u8; 4]; n];
    for (k, dy) in (area.y..area.bottom()).enumerate() {
        if rows.cov[k] == 0 {
            continue;
        }
        let (j0, j1, wy) = (rows.i0[k] as usize, rows.i1[k] as usize, rows.w[k]);
        let s0 = slot(&mut held, j0, j1);
        if held[s0] != j0 {
            horizontal(&mut h[s0], &src.px[j0 * sw..][..sw], &cols);
            held[s0] = j0;
        }
        let s1 = if j1 == j0 { s0 } else { slot(&mut held, j1, j0) };
        if held[s1] != j1 {
            horizontal(&mut h[s1], &src.px[j1 * sw..][..sw], &cols);
            held[s1] = j1;
        }
        vertical(&mut out, &h[s0], &h[s1], wy);
        let row = &mut dst[dy as usize * dst_w + area.x as usize..][..n];
        let o = pixel::div255(opacity as u32 * rows.cov[k] as u32) as u8;
        pixel::blend_row(&mut row[full0..full1], &out[full0..full1], o);
        for i in (0..full0).chain(full1..n) {
            let k = pixel::div255(o as u32 * cols.cov[i] as u32) as u8;
            pixel::over_coverage(&mut row[i], out[i], k);
        }
    }
}

impl Axis {
    /// `Some(offset)` when the image lands pixel for pixel (scale 1, whole-pixel offset
    /// and painted range): every window pixel is one source pixel, wholly covered.
    fn shift(&self) -> Option<i64> {
        let whole = |v: f64| v.fract() == 0.0 && v.abs() < 1e9;
        (self.scale == 1.0 && whole(self.offset) && whole(self.lo) && whole(self.hi))
            .then_some(self.offset as i64)
    }
}

/// The image placed pixel for pixel at window offset `shift`: its rows blended straight
/// into the destination (an opaque one is copied), no resampling. `false` (nothing drawn)
/// when `area` reaches beyond the image, which the general path pads.
fn copy_shifted(
    dst: &mut [[u8; 4]],
    dst_w: usize,
    origin: (i32, i32),
    area: IRect,
    src: &Source,
    shift: (i64, i64),
    opacity: u8,
) -> bool {
    let sx = (area.x + origin.0) as i64 - shift.0;
    let sy = (area.y + origin.1) as i64 - shift.1;
    let (n, rows) = (area.w as i64, area.h as i64);
    if sx < 0 || sy < 0 || sx + n > src.width as i64 || sy + rows > src.height as i64 {
        return false;
    }
    let sw = src.width as usize;
    for k in 0..rows as usize {
        let from = &src.px[(sy as usize + k) * sw + sx as usize..][..n as usize];
        let row = &mut dst[(area.y as usize + k) * dst_w + area.x as usize..][..n as usize];
        pixel::blend_row(row, from, opacity);
    }
    true
}

/// The cache slot for source row `want`: the one holding it, else one not holding
/// `keep` (the other row the output row needs).
fn slot(held: &mut [usize; 2], want: usize, keep: usize) -> usize {
    if held[0] == want {
        0
    } else if held[1] == want || held[0] == keep {
        1
    } else {
        0
    }
}

/// `a` and `b` weighted `256 - w` and `w` (`w` in 0..=255), rounded: 16-bit lanes
/// (`255 * 256 + 128` fits), which baseline x86-64 multiplies eight at a time (32-bit
/// lanes it emulates).
#[inline(always)]
fn lerp(a: u8, b: u8, w: u16) -> u8 {
    ((a as u16 * (256 - w) + b as u16 * w + 128) >> 8) as u8
}

/// One source row resampled at the columns' taps.
fn horizontal(h: &mut [[u8; 4]], src: &[[u8; 4]], cols: &Taps) {
    let taps = cols.i0.iter().zip(&cols.i1).zip(&cols.w);
    for (o, ((&i0, &i1), &w)) in h.iter_mut().zip(taps) {
        let (a, b) = (src[i0 as usize], src[i1 as usize]);
        *o = std::array::from_fn(|c| lerp(a[c], b[c], w));
    }
}

/// Two resampled rows interpolated with weight `w` (0..=255) on the second.
fn vertical(out: &mut [[u8; 4]], h0: &[[u8; 4]], h1: &[[u8; 4]], w: u16) {
    if w == 0 {
        out.copy_from_slice(h0);
        return;
    }
    let (h0, h1) = (h0.as_flattened(), h1.as_flattened());
    for ((o, a), b) in out.as_flattened_mut().iter_mut().zip(h0).zip(h1) {
        *o = lerp(*a, *b, w);
    }
}

#[cfg(test)]
mod tests {
    use crate::canvas::{Canvas, ImageFit, fit_rect};
    use crate::geom::{Rect, Size, Transform};
    use crate::image::Image;
    use crate::skia::SkiaCanvas;
    use tiny_skia::Pixmap;

    const BACK: [u8; 4] = [40, 20, 10, 100];

    /// A `w`×`h` image of varied colours and alphas (a transparent pixel among them).
    fn image(w: u32, h: u32) -> Image {
        let mut v = Vec::new();
        for i in 0..w * h {
            let a = [255u32, 255, 180, 0, 90][(i % 5) as usize];
            v.extend([(i * 37 % 256) as u8, (i * 91 % 256) as u8, (i * 53 % 256) as u8, a as u8]);
        }
        Image::from_rgba8(w, h, v).expect("sizes match")
    }

    fn pixmap(w: u32, h: u32) -> Pixmap {
        let mut p = Pixmap::new(w, h).expect("non-empty");
        p.pixels_mut().iter_mut().for_each(|px| {
            *px = tiny_skia::PremultipliedColorU8::from_rgba(BACK[0], BACK[1], BACK[2], BACK[3])
                .expect("premultiplied")
        });
        p
    }

    struct Case {
        what: &'static str,
        img: (u32, u32),
        dst: Rect,
        fit: ImageFit,
        transform: Transform,
        clip: Option<Rect>,
        opacity: f32,
    }

    fn paint(c: &Case, img: &Image, pm: Pixmap, origin: (i32, i32), size: Size) -> Pixmap {
        let mut cv = SkiaCanvas::new(pm, origin, size);
        cv.transform(c.transform);
        if let Some(r) = c.clip {
            cv.clip_rect(r);
        }
        cv.draw_image(img, c.dst, c.fit, c.opacity);
        cv.into_pixmap()
    }

    /// tiny-skia's bilinear `Pattern` over the shown rectangle: the path the fast path
    /// replaces. The clip is pixel-aligned in these cases: outside it, the background.
    fn reference(c: &Case, img: &Image, w: u32, h: u32) -> Pixmap {
        let mut pm = pixmap(w, h);
        let isz = Size::new(img.width() as f32, img.height() as f32);
        let r = fit_rect(isz, c.dst, c.fit);
        let shown = r.intersect(&c.dst);
        let paint = tiny_skia::Paint {
            shader: tiny_skia::Pattern::new(
                img.pixmap.as_ref().as_ref(),
                tiny_skia::SpreadMode::Pad,
                tiny_skia::FilterQuality::Bilinear,
                c.opacity,
                tiny_skia::Transform::from_row(r.w / isz.w, 0.0, 0.0, r.h / isz.h, r.x, r.y),
            ),
            anti_alias: true,
            ..tiny_skia::Paint::default()
        };
        let rect = tiny_skia::Rect::from_xywh(shown.x, shown.y, shown.w, shown.h).expect("rect");
        pm.fill_rect(rect, &paint, c.transform.to_skia(), None);
        if let Some(clip) = c.clip {
            let d = c.transform.map_rect(clip);
            for y in 0..h {
                for x in 0..w {
                    let (fx, fy) = (x as f32 + 0.5, y as f32 + 0.5);
                    if !d.contains(crate::geom::Point::new(fx, fy)) {
                        let i = (y * w + x) as usize * 4;
                        pm.data_mut()[i..i + 4].copy_from_slice(&BACK);
                    }
                }
            }
        }
        pm
    }

    fn cases() -> Vec<Case> {
        let id = Transform::IDENTITY;
        let case = |what, img, dst, fit, transform, clip, opacity| Case {
            what,
            img,
            dst,
            fit,
            transform,
            clip,
            opacity,
        };
        vec![
            case(
                "magnified 8x",
                (8, 6),
                Rect::new(0.0, 0.0, 64.0, 48.0),
                ImageFit::Stretch,
                id,
                None,
                1.0,
            ),
            case(
                "magnified 22.5x, contained",
                (4, 3),
                Rect::new(0.0, 0.0, 96.0, 60.0),
                ImageFit::Contain,
                id,
                None,
                1.0,
            ),
            case(
                "stretched unevenly",
                (7, 5),
                Rect::new(3.0, 2.0, 50.0, 33.0),
                ImageFit::Stretch,
                id,
                None,
                1.0,
            ),
            case(
                "shrunk",
                (40, 30),
                Rect::new(5.0, 4.0, 23.0, 17.0),
                ImageFit::Stretch,
                id,
                None,
                1.0,
            ),
            case(
                "cropped by cover",
                (7, 5),
                Rect::new(2.0, 3.0, 60.0, 20.0),
                ImageFit::Cover,
                id,
                None,
                1.0,
            ),
            case(
                "half opacity",
                (7, 5),
                Rect::new(1.0, 1.0, 40.0, 30.0),
                ImageFit::Stretch,
                id,
                None,
                0.5,
            ),
            case(
                "pixel-aligned clip",
                (7, 5),
                Rect::new(0.0, 0.0, 64.0, 48.0),
                ImageFit::Stretch,
                id,
                Some(Rect::new(10.0, 7.0, 31.0, 20.0)),
                0.8,
            ),
            case(
                "scaled and moved",
                (6, 4),
                Rect::new(1.0, 2.0, 20.0, 14.0),
                ImageFit::Stretch,
                Transform::scale(2.0, 1.5).then(&Transform::translate(5.0, 3.0)),
                None,
                1.0,
            ),
            case(
                "one to one",
                (20, 10),
                Rect::new(4.0, 5.0, 20.0, 10.0),
                ImageFit::Stretch,
                id,
                None,
                1.0,
            ),
            case(
                "one to one at half opacity, clipped",
                (20, 10),
                Rect::new(4.0, 5.0, 20.0, 10.0),
                ImageFit::Stretch,
                id,
                Some(Rect::new(6.0, 6.0, 12.0, 6.0)),
                0.5,
            ),
            case(
                "fractional edges",
                (7, 5),
                Rect::new(2.3, 1.6, 40.4, 30.7),
                ImageFit::Stretch,
                id,
                None,
                1.0,
            ),
        ]
    }

    #[test]
    fn the_fast_path_matches_tiny_skias_bilinear_pattern() {
        let (w, h) = (70, 52);
        for c in cases() {
            let img = image(c.img.0, c.img.1);
            let got = paint(&c, &img, pixmap(w, h), (0, 0), Size::new(w as f32, h as f32));
            let want = reference(&c, &img, w, h);
            let mut worst = (0, 0, 0);
            for (i, (a, b)) in got.data().iter().zip(want.data()).enumerate() {
                let d = (*a as i32 - *b as i32).abs();
                if d > worst.0 {
                    worst = (d, (i / 4) as u32 % w, (i / 4) as u32 / w);
                }
            }
            assert!(
                worst.0 <= 2,
                "{}: channel off by {} at {:?}",
                c.what,
                worst.0,
                (worst.1, worst.2)
            );
        }
    }

    #[test]
    fn a_damage_repaint_writes_what_a_full_repaint_writes_there() {
        let (w, h) = (70, 52);
        let size = Size::new(w as f32, h as f32);
        for c in cases() {
            let img = image(c.img.0, c.img.1);
            let full = paint(&c, &img, pixmap(w, h), (0, 0), size);
            for (dx, dy, dw, dh) in
                [(0, 0, 9, 7), (13, 11, 17, 5), (33, 20, 37, 32), (1, 47, 69, 5)]
            {
                let part = paint(&c, &img, pixmap(dw, dh), (dx as i32, dy as i32), size);
                for y in 0..dh {
                    let got = &part.data()[(y * dw * 4) as usize..][..(dw * 4) as usize];
                    let want =
                        &full.data()[(((dy + y) * w + dx) * 4) as usize..][..(dw * 4) as usize];
                    assert_eq!(got, want, "{}: damage {:?}, row {y}", c.what, (dx, dy, dw, dh));
                }
            }
        }
    }
}
