//! The tiny-skia (CPU) implementation of [`Canvas`].

use crate::canvas::{
    Baseline, Brush, Canvas, ImageFit, LineCap, LineJoin, Stroke, TextMetrics, TextStyle, fit_rect,
};
use crate::color::Color;
use crate::geom::{IRect, Point, Rect, Size, Transform};
use crate::image::Image;
use crate::path::Path;
use crate::pixel;
use crate::text;
use crate::tiles::Tiles;

mod analytic;
mod lazy;
mod masks;
mod pictures;
mod resample;
mod segments;
use tiny_skia::{FillRule, Mask, Paint, Pixmap};

#[derive(Clone, Copy, Debug)]
struct State {
    /// User coordinates to window-local coordinates.
    transform: Transform,
    /// The clip, in pixmap pixels.
    clip: IRect,
}

/// A canvas drawing into an owned tiny-skia pixmap that holds all or part of a window.
///
/// Window-local point `(x, y)` lands on pixmap pixel `(x - origin.x, y - origin.y)`: a
/// damage repaint draws into a small pixmap the size of the damaged rectangle, whose
/// bounds are the natural clip.
pub struct SkiaCanvas {
    pixmap: Pixmap,
    origin: (i32, i32),
    size: Size,
    damage: Rect,
    state: State,
    stack: Vec<State>,
    mask: Option<(IRect, Mask)>,
    /// What is owed to the pixmap before a drawing lands on it: the previous frame's tiles
    /// to clear, an opaque background's rows to fill (`lazy.rs`). Nothing is cleared
    /// where an opaque drawing covering the whole pixmap comes first (a chart's or a
    /// camera's background).
    pending: lazy::Pending,
    /// The tiles drawn on since the canvas began.
    tiles: Tiles,
    /// Every pixel is opaque: an opaque drawing covered the whole pixmap (source-over
    /// keeps it so).
    opaque: bool,
    /// A picture being recorded (this canvas then draws into its sprite).
    recording: Option<Box<pictures::Recording>>,
}

impl SkiaCanvas {
    /// A canvas over `pixmap`, whose pixel (0, 0) is window-local `origin`; `size` is the
    /// window's size. The damage is the pixmap's extent.
    pub fn new(pixmap: Pixmap, origin: (i32, i32), size: Size) -> SkiaCanvas {
        let tiles = Tiles::all(pixmap.width(), pixmap.height());
        SkiaCanvas::with_tiles(pixmap, tiles, origin, size)
    }

    /// A canvas over a transparent pixmap (nothing drawn on it yet).
    pub(crate) fn blank(pixmap: Pixmap, origin: (i32, i32), size: Size) -> SkiaCanvas {
        let tiles = Tiles::none(pixmap.width(), pixmap.height());
        SkiaCanvas::with_tiles(pixmap, tiles, origin, size)
    }

    /// As [`SkiaCanvas::reusing`], where only `tiles` of the pixmap were drawn on.
    pub(crate) fn reusing_drawn(
        pixmap: Pixmap,
        tiles: Tiles,
        origin: (i32, i32),
        size: Size,
    ) -> SkiaCanvas {
        let (w, h) = (pixmap.width(), pixmap.height());
        let stale = if tiles.size() == (w, h) { tiles } else { Tiles::all(w, h) };
        SkiaCanvas {
            pending: lazy::Pending::stale(stale),
            ..SkiaCanvas::with_tiles(pixmap, Tiles::none(w, h), origin, size)
        }
    }

    fn with_tiles(pixmap: Pixmap, tiles: Tiles, origin: (i32, i32), size: Size) -> SkiaCanvas {
        let full = IRect::new(0, 0, pixmap.width() as i32, pixmap.height() as i32);
        let damage = full.offset(origin.0, origin.1).to_rect().intersect(&Rect::from_size(size));
        SkiaCanvas {
            pixmap,
            origin,
            size,
            damage,
            state: State { transform: Transform::IDENTITY, clip: full },
            stack: Vec::new(),
            mask: None,
            pending: lazy::Pending::none(),
            tiles,
            opaque: false,
            recording: None,
        }
    }

    /// A canvas over a pixmap whose old content is to be discarded, as [`SkiaCanvas::new`]
    /// over a transparent pixmap: the clearing happens before the first drawing, or not
    /// at all when that drawing paints every pixel opaque.
    pub fn reusing(pixmap: Pixmap, origin: (i32, i32), size: Size) -> SkiaCanvas {
        let tiles = Tiles::all(pixmap.width(), pixmap.height());
        SkiaCanvas::reusing_drawn(pixmap, tiles, origin, size)
    }

    /// Gives the pixmap back.
    pub fn into_pixmap(self) -> Pixmap {
        self.into_parts().0
    }

    /// Gives the pixmap back with its drawn-on tiles and whether it is wholly opaque.
    pub(crate) fn into_parts(mut self) -> (Pixmap, Tiles, bool) {
        // A picture left recording (its painter panicked inside it): back to the canvas
        // it was recorded for.
        while let Some(rec) = self.recording.take() {
            self = rec.outer;
        }
        self.finish();
        (self.pixmap, self.tiles, self.opaque)
    }

    pub fn pixmap(&mut self) -> &Pixmap {
        self.finish();
        &self.pixmap
    }

    /// Records that pixels inside `r` (pixmap pixels) are drawn on.
    #[inline]
    fn touch(&mut self, r: IRect) {
        self.tiles.mark(r.intersect(&self.state.clip));
    }

    /// The pixmap pixels a drawing inside user-space `user`, grown by `pad` user units,
    /// may touch (all of the clip when the box is not finite).
    fn device_box(&self, user: Rect, pad: f32) -> IRect {
        match self.device_extent(user, pad) {
            Some(r) => r.intersect(&self.state.clip),
            None => self.state.clip,
        }
    }

    /// [`SkiaCanvas::device_box`] before the clip (`None` when the box is not finite).
    fn device_extent(&self, user: Rect, pad: f32) -> Option<IRect> {
        let d = self.device().map_rect(user.inset(-pad)).inset(-2.0);
        if !(d.x.is_finite() && d.y.is_finite() && d.w.is_finite() && d.h.is_finite()) {
            return None;
        }
        let big = 1.0e9;
        let d = Rect::new(d.x.max(-big), d.y.max(-big), d.w.min(2.0 * big), d.h.min(2.0 * big));
        Some(IRect::covering(d))
    }

    /// User coordinates to pixmap pixels.
    fn device(&self) -> Transform {
        self.state
            .transform
            .then(&Transform::translate(-self.origin.0 as f32, -self.origin.1 as f32))
    }

    fn full(&self) -> IRect {
        IRect::new(0, 0, self.pixmap.width() as i32, self.pixmap.height() as i32)
    }

    /// Runs a drawing operation with the clip mask (`None` when the clip is the whole
    /// pixmap); does nothing when the clip is empty.
    fn draw_with(&mut self, bounds: IRect, f: impl FnOnce(&mut Pixmap, Option<&Mask>)) {
        let clip = self.state.clip;
        if clip.is_empty() {
            return;
        }
        self.prepare(bounds.intersect(&clip));
        self.touch(bounds);
        if clip == self.full() {
            return f(&mut self.pixmap, None);
        }
        if self.mask.as_ref().is_none_or(|(r, _)| *r != clip) {
            let Some(mut m) = Mask::new(self.pixmap.width(), self.pixmap.height()) else { return };
            let Some(r) = tiny_skia::Rect::from_xywh(
                clip.x as f32,
                clip.y as f32,
                clip.w as f32,
                clip.h as f32,
            ) else {
                return;
            };
            let p = tiny_skia::PathBuilder::from_rect(r);
            m.fill_path(&p, FillRule::Winding, false, tiny_skia::Transform::identity());
            self.mask = Some((clip, m));
        }
        let mask = self.mask.as_ref().map(|(_, m)| m);
        f(&mut self.pixmap, mask)
    }

    /// Whether a user-space box (grown by `pad`) can touch the clip.
    fn visible(&self, user: Rect, pad: f32) -> bool {
        let d = self.device().map_rect(user).inset(-pad - 1.0);
        d.intersects(&self.state.clip.to_rect())
    }

    /// A linear gradient over a pixel-aligned rectangle under an axis-aligned transform:
    /// tiny-skia's gradient pipeline costs ~10 ns a pixel, this a lookup table and a
    /// blend (a row copy when the gradient is vertical and opaque). Returns false when the
    /// case does not apply.
    fn fast_gradient_rect(
        &mut self,
        r: Rect,
        start: Point,
        end: Point,
        stops: &[(f32, Color)],
    ) -> bool {
        let dev = self.device();
        if !dev.is_axis_aligned() || stops.is_empty() {
            return false;
        }
        let d = dev.map_rect(r);
        let aligned = |v: f32| (v - v.round()).abs() < 1e-3;
        if !(aligned(d.x) && aligned(d.y) && aligned(d.right()) && aligned(d.bottom())) {
            return false;
        }
        let area = IRect::new(
            d.x.round() as i32,
            d.y.round() as i32,
            (d.right().round() - d.x.round()) as i32,
            (d.bottom().round() - d.y.round()) as i32,
        )
        .intersect(&self.state.clip);
        if area.is_empty() {
            return true;
        }
        let (p0, p1) = (dev.apply(start), dev.apply(end));
        let (vx, vy) = (p1.x - p0.x, p1.y - p0.y);
        let len2 = vx * vx + vy * vy;
        let lut = gradient_lut(stops);
        let opaque = lut.iter().all(|c| c[3] == 255);
        let t_at = |x: f32, y: f32| -> usize {
            if len2 <= f32::EPSILON {
                return 255;
            }
            let t = ((x - p0.x) * vx + (y - p0.y) * vy) / len2;
            (t.clamp(0.0, 1.0) * 255.0 + 0.5) as usize
        };
        if opaque && area == self.full() {
            if vx == 0.0 {
                // One colour a row: filled when a drawing first needs the row.
                let rows = (0..area.h).map(|y| lut[t_at(0.0, y as f32 + 0.5)]).collect();
                self.set_background(rows);
                return true;
            }
            self.pending = lazy::Pending::none(); // every pixel is overwritten
            self.opaque = true;
            self.tiles.mark_all();
        } else {
            self.prepare(area);
            self.touch(area);
        }
        let w = self.pixmap.width() as usize;
        let (px, _) = self.pixmap.data_mut().as_chunks_mut::<4>();
        // t along the row in 16.16 fixed point, stepping by a constant.
        let step = if len2 > f32::EPSILON { (vx / len2 * 255.0 * 65536.0) as i64 } else { 0 };
        for y in area.y..area.bottom() {
            let row = &mut px[y as usize * w + area.x as usize..][..area.w as usize];
            let fy = y as f32 + 0.5;
            if vx == 0.0 && opaque {
                row.fill(lut[t_at(0.0, fy)]);
                continue;
            }
            let t0 = if len2 > f32::EPSILON {
                ((area.x as f32 + 0.5 - p0.x) * vx + (fy - p0.y) * vy) / len2
            } else {
                1.0
            };
            let mut acc = (t0 as f64 * 255.0 * 65536.0) as i64 + 32768;
            for p in row.iter_mut() {
                let c = lut[(acc >> 16).clamp(0, 255) as usize];
                acc += step;
                if c[3] != 0 {
                    pixel::over(p, c);
                }
            }
        }
        true
    }

    /// An image draw under a scale-and-translate transform: [`resample`]'s fixed-point
    /// bilinear resampler instead of tiny-skia's float pattern pipeline. `r` is where the
    /// whole image lands, `shown` the part painted (user space). Returns false when the
    /// case does not apply (rotation, skew, a mirroring scale).
    fn fast_image(&mut self, image: &Image, r: Rect, shown: Rect, opacity: f32) -> bool {
        let t = self.state.transform;
        if !t.is_axis_aligned() || t.sx <= 0.0 || t.sy <= 0.0 || r.w <= 0.0 || r.h <= 0.0 {
            return false;
        }
        // Window coordinates (not the pixmap's): a damage repaint samples where a full
        // repaint does.
        let w = t.map_rect(shown);
        let area = IRect::covering(w)
            .offset(-self.origin.0, -self.origin.1)
            .intersect(&self.state.clip)
            .intersect(&self.full());
        if area.is_empty() {
            return true;
        }
        self.prepare(area);
        self.touch(area);
        let (iw, ih) = (image.width(), image.height());
        let ax = resample::Axis {
            scale: t.sx as f64 * r.w as f64 / iw as f64,
            offset: t.sx as f64 * r.x as f64 + t.tx as f64,
            lo: w.x as f64,
            hi: w.right() as f64,
        };
        let ay = resample::Axis {
            scale: t.sy as f64 * r.h as f64 / ih as f64,
            offset: t.sy as f64 * r.y as f64 + t.ty as f64,
            lo: w.y as f64,
            hi: w.bottom() as f64,
        };
        let (src, _) = image.pixmap.data().as_chunks::<4>();
        let src = resample::Source { px: src, width: iw, height: ih };
        let o = (opacity.clamp(0.0, 1.0) * 255.0).round() as u8;
        let pw = self.pixmap.width() as usize;
        let (dst, _) = self.pixmap.data_mut().as_chunks_mut::<4>();
        resample::draw(dst, pw, self.origin, area, &src, ax, ay, o);
        true
    }

    /// Draws a shaped run with its top-left corner at pixmap pixel `(ox, oy)`: the run's
    /// cached coverage mask blended in one pass (glyph by glyph only for colour glyphs).
    ///
    /// Any origin is accepted, far outside the pixmap included: every row and column
    /// touched is in the intersection of the image, the clip and the pixmap, and an
    /// empty intersection (an image wholly beside the clip but level with it) draws
    /// nothing.
    fn blit_text(&mut self, run: &text::ShapedRun, ox: i32, oy: i32, color: Color) {
        let clip = self.state.clip.intersect(&self.full());
        if clip.is_empty() {
            return;
        }
        let pw = self.pixmap.width() as usize;
        let pre = pixel::premultiply(color);
        if let Some(m) = text::with_engine(|e| e.mask(run)) {
            let (mx0, my0) = (ox.saturating_add(m.left), oy.saturating_add(m.top));
            let (mw, mh) =
                (m.width.min(i32::MAX as usize) as i32, m.height.min(i32::MAX as usize) as i32);
            let r = IRect::new(mx0, my0, mw, mh).intersect(&clip);
            if r.is_empty() || m.data.len() < m.width * m.height {
                return;
            }
            self.prepare(r);
            self.tiles.mark(r);
            let (px, _) = self.pixmap.data_mut().as_chunks_mut::<4>();
            let (cx, w) = ((r.x - mx0) as usize, r.w as usize);
            for y in r.y..r.bottom() {
                let mrow = &m.data[(y - my0) as usize * m.width + cx..][..w];
                let row = &mut px[y as usize * pw + r.x as usize..][..w];
                pixel::cover_row(row, pre, mrow);
            }
            return;
        }
        // Colour glyphs (rare): the whole clip made ready.
        self.prepare(clip);
        let (px, _) = self.pixmap.data_mut().as_chunks_mut::<4>();
        let tiles = &mut self.tiles;
        text::with_engine(|e| {
            for g in &run.glyphs {
                let Some(img) = e.glyph(g.key) else { continue };
                let (iw, ih) = (img.width as usize, img.height as usize);
                if img.data.len() < iw * ih * if img.color { 4 } else { 1 } {
                    continue;
                }
                let gx = ox.saturating_add(g.x).saturating_add(img.left);
                let gy = oy.saturating_add(g.y).saturating_sub(img.top);
                let (gw, gh) = (iw.min(i32::MAX as usize) as i32, ih.min(i32::MAX as usize) as i32);
                let r = IRect::new(gx, gy, gw, gh).intersect(&clip);
                if r.is_empty() {
                    continue;
                }
                tiles.mark(r);
                let cx = (r.x - gx) as usize;
                for y in r.y..r.bottom() {
                    let my = (y - gy) as usize;
                    let row = &mut px[y as usize * pw + r.x as usize..][..r.w as usize];
                    for (i, d) in row.iter_mut().enumerate() {
                        let mx = cx + i;
                        if img.color {
                            // swash colour glyphs are straight RGBA.
                            let s = &img.data[(my * iw + mx) * 4..][..4];
                            let a = pixel::div255(s[3] as u32 * color.a as u32) as u8;
                            pixel::over(d, pixel::premultiply(Color::rgba(s[0], s[1], s[2], a)));
                        } else {
                            let k = img.data[my * iw + mx];
                            pixel::over_coverage(d, pre, k);
                        }
                    }
                }
            }
        });
    }
}

/// 256 premultiplied colours along the gradient (stops interpolated unpremultiplied).
fn gradient_lut(stops: &[(f32, Color)]) -> [[u8; 4]; 256] {
    std::array::from_fn(|i| {
        let t = i as f32 / 255.0;
        let c = match stops.iter().position(|(o, _)| *o >= t) {
            None => stops[stops.len() - 1].1,
            Some(0) => stops[0].1,
            Some(k) => {
                let (o0, c0) = stops[k - 1];
                let (o1, c1) = stops[k];
                let f = if o1 > o0 { (t - o0) / (o1 - o0) } else { 1.0 };
                let m = |a: u8, b: u8| (a as f32 + (b as f32 - a as f32) * f).round() as u8;
                Color::rgba(m(c0.r, c1.r), m(c0.g, c1.g), m(c0.b, c1.b), m(c0.a, c1.a))
            }
        };
        pixel::premultiply(c)
    })
}

fn skia_paint(brush: &Brush) -> Option<Paint<'static>> {
    let mut paint = Paint { anti_alias: true, ..Paint::default() };
    match brush {
        Brush::Solid(c) => paint.set_color(c.to_skia()),
        Brush::Linear { start, end, stops } => {
            let stops =
                stops.iter().map(|(o, c)| tiny_skia::GradientStop::new(*o, c.to_skia())).collect();
            paint.shader = tiny_skia::LinearGradient::new(
                tiny_skia::Point::from_xy(start.x, start.y),
                tiny_skia::Point::from_xy(end.x, end.y),
                stops,
                tiny_skia::SpreadMode::Pad,
                tiny_skia::Transform::identity(),
            )?;
        }
    }
    Some(paint)
}

fn skia_stroke(s: &Stroke) -> tiny_skia::Stroke {
    tiny_skia::Stroke {
        width: s.width,
        line_cap: match s.cap {
            LineCap::Butt => tiny_skia::LineCap::Butt,
            LineCap::Round => tiny_skia::LineCap::Round,
            LineCap::Square => tiny_skia::LineCap::Square,
        },
        line_join: match s.join {
            LineJoin::Miter => tiny_skia::LineJoin::Miter,
            LineJoin::Round => tiny_skia::LineJoin::Round,
            LineJoin::Bevel => tiny_skia::LineJoin::Bevel,
        },
        dash: s.dash.as_ref().and_then(|(p, o)| tiny_skia::StrokeDash::new(p.clone(), *o)),
        ..tiny_skia::Stroke::default()
    }
}

fn path_bounds(p: &tiny_skia::Path) -> Rect {
    let b = p.bounds();
    Rect::new(b.x(), b.y(), b.width(), b.height())
}

impl Canvas for SkiaCanvas {
    fn fill_circle(&mut self, c: Point, radius: f32, color: Color) {
        if self.ring(c, radius, 0.0, color).is_none() {
            self.fill_path(&Path::circle(c, radius), &Brush::Solid(color));
        }
    }

    fn stroke_circle(&mut self, c: Point, radius: f32, width: f32, color: Color) {
        let h = width / 2.0;
        if self.ring(c, radius + h, (radius - h).max(0.0), color).is_none() {
            self.stroke_path(&Path::circle(c, radius), &Stroke::new(width), &Brush::Solid(color));
        }
    }

    fn stroke_arc(
        &mut self,
        c: Point,
        radius: f32,
        start: f32,
        sweep: f32,
        stroke: &Stroke,
        color: Color,
    ) {
        if self.arc_band(c, radius, start, sweep, stroke, color).is_none() {
            self.stroke_path(&Path::arc(c, radius, start, sweep), stroke, &Brush::Solid(color));
        }
    }

    fn size(&self) -> Size {
        self.size
    }

    fn draw_picture(&mut self, key: u64, bounds: Rect) -> bool {
        self.draw_cached_picture(key, bounds)
    }

    fn begin_picture(&mut self, key: u64, bounds: Rect) -> bool {
        self.begin_recording(key, bounds)
    }

    fn end_picture(&mut self) {
        self.end_recording()
    }

    fn damage(&self) -> Rect {
        self.damage
    }

    fn save(&mut self) {
        self.stack.push(self.state);
    }

    fn restore(&mut self) {
        if let Some(s) = self.stack.pop() {
            self.state = s;
        }
    }

    fn transform(&mut self, t: Transform) {
        self.state.transform = self.state.transform.pre(&t);
    }

    fn current_transform(&self) -> Transform {
        self.state.transform
    }

    fn clip_rect(&mut self, r: Rect) {
        // Rounded in window pixels, then moved to the pixmap's: a damage repaint (whose
        // pixmap starts anywhere) clips where a full repaint does.
        let d = self.state.transform.map_rect(r);
        let x0 = d.x.round() as i32;
        let y0 = d.y.round() as i32;
        let c = IRect::new(x0, y0, d.right().round() as i32 - x0, d.bottom().round() as i32 - y0)
            .offset(-self.origin.0, -self.origin.1);
        self.state.clip = self.state.clip.intersect(&c);
    }

    fn clear(&mut self, color: Color) {
        let clip = self.state.clip;
        if clip.is_empty() {
            return;
        }
        let px = pixel::premultiply(color);
        if clip == self.full() {
            if color.a == 255 {
                // Filled row by row when drawings first need the rows.
                self.set_background(vec![px; clip.h as usize]);
                return;
            }
            self.pending = lazy::Pending::none(); // every pixel is overwritten
            self.opaque = false;
        } else {
            self.prepare(clip);
            self.opaque &= color.a == 255;
        }
        self.touch(clip);
        let w = self.pixmap.width() as usize;
        let (data, _) = self.pixmap.data_mut().as_chunks_mut::<4>();
        for y in clip.y..clip.bottom() {
            data[y as usize * w + clip.x as usize..][..clip.w as usize].fill(px);
        }
    }

    fn fill_path(&mut self, path: &Path, brush: &Brush) {
        if let Brush::Linear { start, end, stops } = brush
            && let Some(r) = path.as_rect()
            && self.fast_gradient_rect(r, *start, *end, stops)
        {
            return;
        }
        let Some(p) = path.to_skia() else { return };
        if !self.visible(path_bounds(&p), 0.0) {
            return;
        }
        if let Brush::Solid(color) = brush
            && let Some(e) = self.device_extent(path_bounds(&p), 0.0)
            && self.cached_path(path, &p, None, *color, e)
        {
            return;
        }
        let b = self.device_box(path_bounds(&p), 0.0);
        let Some(paint) = skia_paint(brush) else { return };
        let t = self.device().to_skia();
        self.draw_with(b, |pm, mask| pm.fill_path(&p, &paint, FillRule::Winding, t, mask));
    }

    fn stroke_path(&mut self, path: &Path, stroke: &Stroke, brush: &Brush) {
        if let Brush::Solid(color) = brush
            && self.segments(path, stroke, *color).is_some()
        {
            return;
        }
        let Some(p) = path.to_skia() else { return };
        if !self.visible(path_bounds(&p), stroke.width) {
            return;
        }
        let s = skia_stroke(stroke);
        // Miter joins reach miter_limit * width / 2 from the path.
        let pad = stroke.width * s.miter_limit.max(1.0);
        if let Brush::Solid(color) = brush
            && let Some(e) = self.device_extent(path_bounds(&p), pad)
            && self.cached_path(path, &p, Some(&s), *color, e)
        {
            return;
        }
        let b = self.device_box(path_bounds(&p), pad);
        let Some(paint) = skia_paint(brush) else { return };
        let t = self.device().to_skia();
        self.draw_with(b, |pm, mask| pm.stroke_path(&p, &paint, &s, t, mask));
    }

    fn draw_image(&mut self, image: &Image, dst: Rect, fit: ImageFit, opacity: f32) {
        let img = Size::new(image.width() as f32, image.height() as f32);
        let r = fit_rect(img, dst, fit);
        let shown = r.intersect(&dst);
        if shown.is_empty() || !self.visible(shown, 0.0) {
            return;
        }
        if self.fast_image(image, r, shown, opacity) {
            return;
        }
        let pattern_t =
            tiny_skia::Transform::from_row(r.w / img.w, 0.0, 0.0, r.h / img.h, r.x, r.y);
        let paint = Paint {
            shader: tiny_skia::Pattern::new(
                image.pixmap.as_ref().as_ref(),
                tiny_skia::SpreadMode::Pad,
                tiny_skia::FilterQuality::Bilinear,
                opacity.clamp(0.0, 1.0),
                pattern_t,
            ),
            anti_alias: true,
            ..Paint::default()
        };
        let Some(rect) = tiny_skia::Rect::from_xywh(shown.x, shown.y, shown.w, shown.h) else {
            return;
        };
        let t = self.device().to_skia();
        let b = self.device_box(shown, 0.0);
        self.draw_with(b, |pm, mask| pm.fill_rect(rect, &paint, t, mask));
    }

    fn draw_text(&mut self, txt: &str, at: Point, style: &TextStyle) -> TextMetrics {
        let dev = self.device();
        let uniform = dev.is_axis_aligned() && dev.sx > 0.0 && (dev.sx - dev.sy).abs() < 1e-6;
        let scale = if uniform { dev.sx } else { 1.0 };
        let run = text::with_engine(|e| e.shape(txt, style.size * scale, style.bold));
        let m = run.metrics;
        // Metrics in user units.
        let (w, h, base) = (m.width / scale, m.height / scale, m.baseline / scale);
        let dx = match style.align {
            crate::canvas::Align::Left => 0.0,
            crate::canvas::Align::Center => -w / 2.0,
            crate::canvas::Align::Right => -w,
        };
        let dy = match style.baseline {
            Baseline::Top => 0.0,
            Baseline::Middle => -h / 2.0,
            Baseline::Alphabetic => -base,
            Baseline::Bottom => -h,
        };
        let user_box = Rect::new(at.x + dx, at.y + dy, w, h);
        let metrics = TextMetrics { width: w, height: h, baseline: base };
        if run.glyphs.is_empty() || !self.visible(user_box, 2.0) {
            return metrics;
        }
        if uniform {
            // Snapped to whole window pixels before moving to the pixmap's: rounding a
            // half pixel after the move went the other way in a damage repaint whose
            // pixmap starts below the text's top, shifting the text by one pixel there.
            let o = self.state.transform.apply(Point::new(user_box.x, user_box.y));
            let (ox, oy) = (
                (o.x.round() as i32).saturating_sub(self.origin.0),
                (o.y.round() as i32).saturating_sub(self.origin.1),
            );
            self.blit_text(&run, ox, oy, style.color);
        } else {
            // Rotated or skewed: rasterise the run upright, then draw it transformed.
            let (pw, ph) =
                ((m.width.ceil() as u32).max(1) + 2, (m.height.ceil() as u32).max(1) + 2);
            let Some(tmp) = crate::alloc::pixmap(pw, ph) else { return metrics };
            let mut sub = SkiaCanvas::new(tmp, (0, 0), Size::new(pw as f32, ph as f32));
            sub.blit_text(&run, 1, 1, style.color);
            let tmp = sub.into_pixmap();
            let paint = Paint {
                shader: tiny_skia::Pattern::new(
                    tmp.as_ref(),
                    tiny_skia::SpreadMode::Pad,
                    tiny_skia::FilterQuality::Bilinear,
                    1.0,
                    tiny_skia::Transform::from_translate(user_box.x - 1.0, user_box.y - 1.0),
                ),
                anti_alias: true,
                ..Paint::default()
            };
            let Some(rect) = tiny_skia::Rect::from_xywh(
                user_box.x - 1.0,
                user_box.y - 1.0,
                pw as f32,
                ph as f32,
            ) else {
                return metrics;
            };
            let t = dev.to_skia();
            let b = self.device_box(
                Rect::new(user_box.x - 1.0, user_box.y - 1.0, pw as f32, ph as f32),
                0.0,
            );
            self.draw_with(b, |pm, mask| pm.fill_rect(rect, &paint, t, mask));
        }
        metrics
    }
}
