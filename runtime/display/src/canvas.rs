//! The drawing interface every module paints through. Backend-neutral: nothing here names
//! tiny-skia or wgpu, so a painter written against [`Canvas`] draws on both.

use crate::color::Color;
use crate::geom::{Point, Rect, Size, Transform};
use crate::image::Image;
use crate::path::Path;

/// What fills a shape.
#[derive(Clone, Debug, PartialEq)]
pub enum Brush {
    Solid(Color),
    /// A linear gradient from `start` to `end`; `stops` are (offset 0..=1, colour), in
    /// order. Outside the segment the end colours extend.
    Linear {
        start: Point,
        end: Point,
        stops: Vec<(f32, Color)>,
    },
}

impl From<Color> for Brush {
    fn from(c: Color) -> Brush {
        Brush::Solid(c)
    }
}

#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum LineCap {
    #[default]
    Butt,
    Round,
    Square,
}

#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum LineJoin {
    #[default]
    Miter,
    Round,
    Bevel,
}

/// How a path is stroked.
#[derive(Clone, Debug, PartialEq)]
pub struct Stroke {
    pub width: f32,
    pub cap: LineCap,
    pub join: LineJoin,
    /// Dash pattern (on, off, on, off… lengths; an even count) and its start offset.
    pub dash: Option<(Vec<f32>, f32)>,
}

impl Stroke {
    pub fn new(width: f32) -> Stroke {
        Stroke { width, cap: LineCap::Butt, join: LineJoin::Miter, dash: None }
    }

    pub fn cap(mut self, cap: LineCap) -> Stroke {
        self.cap = cap;
        self
    }

    pub fn join(mut self, join: LineJoin) -> Stroke {
        self.join = join;
        self
    }

    pub fn dash(mut self, pattern: &[f32], offset: f32) -> Stroke {
        self.dash = Some((pattern.to_vec(), offset));
        self
    }
}

/// Horizontal placement of a text run relative to its anchor point.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum Align {
    #[default]
    Left,
    Center,
    Right,
}

/// Vertical placement of a text run relative to its anchor point.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum Baseline {
    /// The anchor is the top of the line box.
    #[default]
    Top,
    /// The anchor is the middle of the line box.
    Middle,
    /// The anchor is on the alphabetic baseline.
    Alphabetic,
    /// The anchor is the bottom of the line box.
    Bottom,
}

/// How a text run looks.
#[derive(Clone, Debug, PartialEq)]
pub struct TextStyle {
    /// Font size in pixels.
    pub size: f32,
    pub color: Color,
    pub align: Align,
    pub baseline: Baseline,
    pub bold: bool,
}

impl TextStyle {
    pub fn new(size: f32, color: Color) -> TextStyle {
        TextStyle { size, color, align: Align::Left, baseline: Baseline::Top, bold: false }
    }

    pub fn align(mut self, align: Align) -> TextStyle {
        self.align = align;
        self
    }

    pub fn baseline(mut self, baseline: Baseline) -> TextStyle {
        self.baseline = baseline;
        self
    }

    pub fn bold(mut self) -> TextStyle {
        self.bold = true;
        self
    }
}

/// The measured extent of a text run (one line; newlines are drawn as spaces).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct TextMetrics {
    pub width: f32,
    /// Height of the line box.
    pub height: f32,
    /// Distance from the top of the line box to the alphabetic baseline.
    pub baseline: f32,
}

/// How an image fills its destination rectangle.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum ImageFit {
    /// Scaled to fit inside, aspect ratio kept, centred (letterboxed). Video uses this.
    #[default]
    Contain,
    /// Scaled to cover, aspect ratio kept, centred, cropped.
    Cover,
    /// Scaled to the rectangle exactly.
    Stretch,
}

/// A drawing surface in window-local pixels (origin at the window's top-left corner).
///
/// Every module paints through this trait, inside its window's `paint` method, reached
/// with [`crate::with_canvas`]. The state (transform, clip) is a stack: [`Canvas::save`]
/// pushes, [`Canvas::restore`] pops; a paint call starts with an identity transform, no
/// clip beyond the window, and a transparent (cleared) area to draw on.
pub trait Canvas {
    /// The window's size.
    fn size(&self) -> Size;

    /// The part of the window being repainted, window-local. Drawing outside it has no
    /// effect; a painter may skip what lies wholly outside (see `invalidate_rect`).
    fn damage(&self) -> Rect;

    fn save(&mut self);
    fn restore(&mut self);

    /// Applies `t` before the current transform (to coordinates given from now on).
    fn transform(&mut self, t: Transform);
    /// The current transform (window-local to window pixels).
    fn current_transform(&self) -> Transform;

    /// Narrows the clip to `r` (in current coordinates). Under a rotation the clip is the
    /// bounding box of the rotated rectangle.
    fn clip_rect(&mut self, r: Rect);

    /// Sets every pixel inside the clip to `color` (no blending).
    fn clear(&mut self, color: Color);

    fn fill_path(&mut self, path: &Path, brush: &Brush);
    fn stroke_path(&mut self, path: &Path, stroke: &Stroke, brush: &Brush);

    /// Draws `image` into `dst` according to `fit`, with bilinear filtering.
    fn draw_image(&mut self, image: &Image, dst: Rect, fit: ImageFit, opacity: f32);

    /// Draws one line of text anchored at `at`; returns its metrics.
    fn draw_text(&mut self, text: &str, at: Point, style: &TextStyle) -> TextMetrics;

    /// Measures a text run without drawing it.
    fn measure_text(&mut self, text: &str, style: &TextStyle) -> TextMetrics {
        crate::text::measure(text, style.size, style.bold)
    }

    /// Draws the picture `key` of `bounds` (current coordinates) this canvas cached, if it
    /// holds one for the current scale and sub-pixel position: true when drawn. See
    /// [`picture`].
    fn draw_picture(&mut self, _key: u64, _bounds: Rect) -> bool {
        false
    }

    /// Starts recording the picture `key` of `bounds`: drawings until
    /// [`Canvas::end_picture`] make the picture. False when this canvas does not cache
    /// pictures (they are then drawn directly).
    fn begin_picture(&mut self, _key: u64, _bounds: Rect) -> bool {
        false
    }

    /// Ends the recording [`Canvas::begin_picture`] began: keeps the picture and draws it.
    fn end_picture(&mut self) {}

    // ----- conveniences (provided) -----------------------------------------------

    fn translate(&mut self, dx: f32, dy: f32) {
        self.transform(Transform::translate(dx, dy));
    }

    fn scale(&mut self, sx: f32, sy: f32) {
        self.transform(Transform::scale(sx, sy));
    }

    /// Rotates by `radians` (clockwise on screen) about the current origin.
    fn rotate(&mut self, radians: f32) {
        self.transform(Transform::rotate(radians));
    }

    fn fill_rect(&mut self, r: Rect, color: Color) {
        self.fill_path(&Path::rect(r), &Brush::Solid(color));
    }

    fn fill_rounded_rect(&mut self, r: Rect, radius: f32, brush: &Brush) {
        self.fill_path(&Path::rounded_rect(r, radius), brush);
    }

    fn stroke_rounded_rect(&mut self, r: Rect, radius: f32, stroke: &Stroke, color: Color) {
        self.stroke_path(&Path::rounded_rect(r, radius), stroke, &Brush::Solid(color));
    }

    fn fill_circle(&mut self, c: Point, radius: f32, color: Color) {
        self.fill_path(&Path::circle(c, radius), &Brush::Solid(color));
    }

    /// Strokes a circle (a ring `width` wide centred on `radius`).
    fn stroke_circle(&mut self, c: Point, radius: f32, width: f32, color: Color) {
        self.stroke_path(&Path::circle(c, radius), &Stroke::new(width), &Brush::Solid(color));
    }

    fn line(&mut self, a: Point, b: Point, width: f32, color: Color) {
        self.stroke_path(&Path::line(a, b), &Stroke::new(width), &Brush::Solid(color));
    }

    /// Strokes an arc (angles in radians, 0 = +x, positive clockwise on screen).
    fn stroke_arc(
        &mut self,
        c: Point,
        radius: f32,
        start: f32,
        sweep: f32,
        stroke: &Stroke,
        color: Color,
    ) {
        self.stroke_path(&Path::arc(c, radius, start, sweep), stroke, &Brush::Solid(color));
    }
}

/// Draws what `draw` draws through a picture cached by the canvas (a dial's face, ticks
/// and track): the first time it is drawn into a sprite kept under `key`, then the sprite
/// is blitted — a copy where nothing was drawn yet — instead of drawing again.
///
/// `key` names everything the drawing depends on *relative to `bounds`*: the same key with
/// `bounds` moved must draw the same thing moved (the cache adds the bounds' size, the
/// scale and the sub-pixel position). Nothing may be drawn outside `bounds`. Canvases that
/// do not cache, and transforms other than translate + uniform scale, draw directly.
pub fn picture(c: &mut dyn Canvas, key: u64, bounds: Rect, draw: impl FnOnce(&mut dyn Canvas)) {
    if c.draw_picture(key, bounds) {
        return;
    }
    let recording = c.begin_picture(key, bounds);
    draw(c);
    if recording {
        c.end_picture();
    }
}

/// A picture key from anything hashable (a tag and the parameters the drawing depends on).
pub fn picture_key(what: impl std::hash::Hash) -> u64 {
    use std::hash::{BuildHasher, BuildHasherDefault};
    BuildHasherDefault::<std::collections::hash_map::DefaultHasher>::default().hash_one(what)
}

/// The destination rectangle of an image of `img` pixels drawn into `dst` with `fit`.
pub fn fit_rect(img: Size, dst: Rect, fit: ImageFit) -> Rect {
    if img.w <= 0.0 || img.h <= 0.0 {
        return Rect::new(dst.x, dst.y, 0.0, 0.0);
    }
    let (sx, sy) = (dst.w / img.w, dst.h / img.h);
    let s = match fit {
        ImageFit::Stretch => return dst,
        ImageFit::Contain => sx.min(sy),
        ImageFit::Cover => sx.max(sy),
    };
    let (w, h) = (img.w * s, img.h * s);
    Rect::new(dst.x + (dst.w - w) / 2.0, dst.y + (dst.h - h) / 2.0, w, h)
}
