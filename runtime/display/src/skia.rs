//! The tiny-skia (CPU) implementation of [`Canvas`].

use crate::canvas::{
    Baseline, Brush, Canvas, ImageFit, LineCap, LineJoin, Stroke, TextMetrics, TextStyle, fit_rect,
};
use crate::color::Color;
use crate::geom::{IRect, Point, Rect, Size, Transform};
use crate::image::Image;
use crate::path::Path;
use crate::text;
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
}

impl SkiaCanvas {
    /// A canvas over `pixmap`, whose pixel (0, 0) is window-local `origin`; `size` is the
    /// window's size. The damage is the pixmap's extent.
    pub fn new(pixmap: Pixmap, origin: (i32, i32), size: Size) -> SkiaCanvas {
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
        }
    }

    /// Gives the pixmap back.
    pub fn into_pixmap(self) -> Pixmap {
        self.pixmap
    }

    pub fn pixmap(&self) -> &Pixmap {
        &self.pixmap
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
    fn draw_with(&mut self, f: impl FnOnce(&mut Pixmap, Option<&Mask>)) {
        let clip = self.state.clip;
        if clip.is_empty() {
            return;
        }
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

    fn blit_text(&mut self, run: &text::ShapedRun, ox: i32, oy: i32, color: Color) {
        let clip = self.state.clip;
        let (pw, _) = (self.pixmap.width() as usize, self.pixmap.height() as usize);
        let data = self.pixmap.data_mut();
        let a = color.a as u32;
        let pre =
            [div255(color.r as u32 * a), div255(color.g as u32 * a), div255(color.b as u32 * a), a];
        text::with_engine(|e| {
            for g in &run.glyphs {
                let Some(img) = e.glyph(g.key) else { continue };
                let gx = ox + g.x + img.left;
                let gy = oy + g.y - img.top;
                let r = IRect::new(gx, gy, img.width as i32, img.height as i32).intersect(&clip);
                if r.is_empty() {
                    continue;
                }
                for y in r.y..r.bottom() {
                    let my = (y - gy) as usize;
                    let row = &mut data[(y as usize * pw + r.x as usize) * 4..][..r.w as usize * 4];
                    for (i, px) in row.chunks_exact_mut(4).enumerate() {
                        let mx = (r.x - gx) as usize + i;
                        if img.color {
                            let s = &img.data[(my * img.width as usize + mx) * 4..][..4];
                            // swash colour glyphs are straight RGBA.
                            let sa = div255(s[3] as u32 * a);
                            let src = [
                                div255(s[0] as u32 * sa),
                                div255(s[1] as u32 * sa),
                                div255(s[2] as u32 * sa),
                                sa,
                            ];
                            over(px, src);
                        } else {
                            let m = img.data[my * img.width as usize + mx] as u32;
                            if m == 0 {
                                continue;
                            }
                            let src = [
                                div255(pre[0] * m),
                                div255(pre[1] * m),
                                div255(pre[2] * m),
                                div255(pre[3] * m),
                            ];
                            over(px, src);
                        }
                    }
                }
            }
        });
    }
}

#[inline]
pub(crate) fn div255(x: u32) -> u32 {
    let t = x + 128;
    (t + (t >> 8)) >> 8
}

/// Source-over of one premultiplied pixel.
#[inline]
fn over(px: &mut [u8], src: [u32; 4]) {
    let inv = 255 - src[3];
    for c in 0..4 {
        px[c] = (src[c] + div255(px[c] as u32 * inv)).min(255) as u8;
    }
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
    fn size(&self) -> Size {
        self.size
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
        let d = self.device().map_rect(r);
        let x0 = d.x.round() as i32;
        let y0 = d.y.round() as i32;
        let c = IRect::new(x0, y0, d.right().round() as i32 - x0, d.bottom().round() as i32 - y0);
        self.state.clip = self.state.clip.intersect(&c);
    }

    fn clear(&mut self, color: Color) {
        let clip = self.state.clip;
        if clip.is_empty() {
            return;
        }
        let c = tiny_skia::Color::from_rgba8(color.r, color.g, color.b, color.a)
            .premultiply()
            .to_color_u8();
        let px = [c.red(), c.green(), c.blue(), c.alpha()];
        let w = self.pixmap.width() as usize;
        let data = self.pixmap.data_mut();
        for y in clip.y..clip.bottom() {
            let row = &mut data[(y as usize * w + clip.x as usize) * 4..][..clip.w as usize * 4];
            for p in row.chunks_exact_mut(4) {
                p.copy_from_slice(&px);
            }
        }
    }

    fn fill_path(&mut self, path: &Path, brush: &Brush) {
        let Some(p) = path.to_skia() else { return };
        if !self.visible(path_bounds(&p), 0.0) {
            return;
        }
        let Some(paint) = skia_paint(brush) else { return };
        let t = self.device().to_skia();
        self.draw_with(|pm, mask| pm.fill_path(&p, &paint, FillRule::Winding, t, mask));
    }

    fn stroke_path(&mut self, path: &Path, stroke: &Stroke, brush: &Brush) {
        let Some(p) = path.to_skia() else { return };
        if !self.visible(path_bounds(&p), stroke.width) {
            return;
        }
        let Some(paint) = skia_paint(brush) else { return };
        let t = self.device().to_skia();
        let s = skia_stroke(stroke);
        self.draw_with(|pm, mask| pm.stroke_path(&p, &paint, &s, t, mask));
    }

    fn draw_image(&mut self, image: &Image, dst: Rect, fit: ImageFit, opacity: f32) {
        let img = Size::new(image.width() as f32, image.height() as f32);
        let r = fit_rect(img, dst, fit);
        let shown = r.intersect(&dst);
        if shown.is_empty() || !self.visible(shown, 0.0) {
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
        self.draw_with(|pm, mask| pm.fill_rect(rect, &paint, t, mask));
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
            let o = dev.apply(Point::new(user_box.x, user_box.y));
            self.blit_text(&run, o.x.round() as i32, o.y.round() as i32, style.color);
        } else {
            // Rotated or skewed: rasterise the run upright, then draw it transformed.
            let (pw, ph) =
                ((m.width.ceil() as u32).max(1) + 2, (m.height.ceil() as u32).max(1) + 2);
            let Some(tmp) = Pixmap::new(pw, ph) else { return metrics };
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
            self.draw_with(|pm, mask| pm.fill_rect(rect, &paint, t, mask));
        }
        metrics
    }
}
