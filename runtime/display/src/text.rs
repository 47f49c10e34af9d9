//! Text: shaping with cosmic-text and glyph rasterising with swash, using the DejaVu Sans
//! fonts bundled in the binary (no system font is ever read), so that text renders to the
//! same pixels on every machine.
//!
//! One process-wide engine behind a mutex: the font system, the glyph cache and a cache
//! of shaped runs (a gauge redraws the same strings frame after frame). Each shaped run
//! keeps the coverage mask of all its glyphs, rasterised the first time it is drawn, so a
//! run drawn again is one masked blend, with no shaping, no glyph lookup and no
//! rasterising. Runs are placed at whole pixels, so one mask serves every position.

use crate::canvas::TextMetrics;
use cosmic_text::{
    Attrs, Buffer, CacheKey, Family, FontSystem, Metrics, Shaping, SwashCache, SwashContent,
    Weight, fontdb,
};
use mocu_value::limits::MAX_FONT_PX;
use parking_lot::Mutex;
use std::collections::HashMap;
use std::sync::{Arc, OnceLock};

/// Size (as bits) and boldness: the outer key of the run cache (the text is the inner key,
/// so a lookup borrows the caller's `&str` and allocates nothing).
type StyleKey = (u32, bool);

const SANS: &[u8] = include_bytes!("../assets/DejaVuSans.ttf");
const SANS_BOLD: &[u8] = include_bytes!("../assets/DejaVuSans-Bold.ttf");
/// The family name inside the bundled font files.
pub const FAMILY: &str = "DejaVu Sans";
/// Shaped runs kept before the cache is emptied.
const RUN_CACHE_MAX: usize = 8192;

/// One glyph of a shaped run, placed relative to the run's top-left corner (integer
/// pixel origin).
#[derive(Clone, Copy, Debug)]
pub(crate) struct GlyphPlace {
    pub key: CacheKey,
    pub x: i32,
    pub y: i32,
}

/// A shaped run: its glyphs and metrics, and its coverage mask once drawn.
#[derive(Debug)]
pub(crate) struct ShapedRun {
    pub metrics: TextMetrics,
    pub glyphs: Vec<GlyphPlace>,
    /// `None` inside when a glyph is a colour glyph (drawn glyph by glyph).
    mask: OnceLock<Option<Arc<RunMask>>>,
}

/// The coverage of every glyph of a run in one 8-bit mask; `(left, top)` is its top-left
/// pixel relative to the run's origin. Overlapping glyphs add up as coverage does
/// (`a + b - a·b`), which is what drawing them one over the other in one colour gives.
#[derive(Debug)]
pub(crate) struct RunMask {
    pub left: i32,
    pub top: i32,
    pub width: usize,
    pub height: usize,
    pub data: Vec<u8>,
}

/// A rasterised glyph: an 8-bit coverage mask (or premultiplied RGBA for colour glyphs).
pub(crate) struct GlyphImage<'a> {
    pub left: i32,
    pub top: i32,
    pub width: u32,
    pub height: u32,
    pub color: bool,
    pub data: &'a [u8],
}

pub(crate) struct TextEngine {
    fonts: FontSystem,
    glyphs: SwashCache,
    runs: HashMap<StyleKey, HashMap<Box<str>, Arc<ShapedRun>>>,
    /// Runs in `runs`, all styles together.
    run_count: usize,
}

fn engine() -> &'static Mutex<TextEngine> {
    static ENGINE: OnceLock<Mutex<TextEngine>> = OnceLock::new();
    ENGINE.get_or_init(|| {
        let mut db = fontdb::Database::new();
        db.load_font_source(fontdb::Source::Binary(Arc::new(SANS)));
        db.load_font_source(fontdb::Source::Binary(Arc::new(SANS_BOLD)));
        let fonts = FontSystem::new_with_locale_and_db("en-US".into(), db);
        Mutex::new(TextEngine {
            fonts,
            glyphs: SwashCache::new(),
            runs: HashMap::new(),
            run_count: 0,
        })
    })
}

/// Runs `f` with the text engine locked.
pub(crate) fn with_engine<R>(f: impl FnOnce(&mut TextEngine) -> R) -> R {
    f(&mut engine().lock())
}

/// Measures a run of text (one or more lines).
pub fn measure(text: &str, size: f32, bold: bool) -> TextMetrics {
    with_engine(|e| e.shape(text, size, bold).metrics)
}

impl TextEngine {
    pub(crate) fn shape(&mut self, text: &str, size: f32, bold: bool) -> Arc<ShapedRun> {
        let size = if size.is_finite() { size.clamp(1.0, MAX_FONT_PX as f32) } else { 12.0 };
        let key = (size.to_bits(), bold);
        if let Some(r) = self.runs.get(&key).and_then(|m| m.get(text)) {
            return r.clone();
        }
        let line_height = (size * 1.2).ceil();
        let mut buffer = Buffer::new(&mut self.fonts, Metrics::new(size, line_height));
        buffer.set_size(None, None);
        let weight = if bold { Weight::BOLD } else { Weight::NORMAL };
        let attrs = Attrs::new().family(Family::Name(FAMILY)).weight(weight);
        buffer.set_text(text, &attrs, Shaping::Advanced, None);
        buffer.shape_until_scroll(&mut self.fonts, false);
        let mut glyphs = Vec::new();
        let mut width: f32 = 0.0;
        let mut lines = 0;
        let mut baseline = None;
        for run in buffer.layout_runs() {
            lines += 1;
            width = width.max(run.line_w);
            baseline.get_or_insert(run.line_y);
            for g in run.glyphs {
                let p = g.physical((0.0, run.line_y), 1.0);
                glyphs.push(GlyphPlace { key: p.cache_key, x: p.x, y: p.y });
            }
        }
        let metrics = TextMetrics {
            width,
            height: line_height * lines.max(1) as f32,
            baseline: baseline.unwrap_or(size),
        };
        let run = Arc::new(ShapedRun { metrics, glyphs, mask: OnceLock::new() });
        if self.run_count >= RUN_CACHE_MAX {
            self.runs.clear();
            self.run_count = 0;
        }
        self.runs.entry(key).or_default().insert(text.into(), run.clone());
        self.run_count += 1;
        run
    }

    /// The run's coverage mask, rasterised on first use; `None` when a glyph is a colour
    /// glyph or the run draws nothing.
    pub(crate) fn mask(&mut self, run: &ShapedRun) -> Option<Arc<RunMask>> {
        run.mask.get_or_init(|| self.rasterise(&run.glyphs)).clone()
    }

    fn rasterise(&mut self, glyphs: &[GlyphPlace]) -> Option<Arc<RunMask>> {
        let (mut x0, mut y0, mut x1, mut y1) = (i32::MAX, i32::MAX, i32::MIN, i32::MIN);
        for g in glyphs {
            let img = self.glyph(g.key)?;
            if img.color {
                return None;
            }
            if img.width == 0 || img.height == 0 {
                continue;
            }
            let (gx, gy) = (g.x + img.left, g.y - img.top);
            x0 = x0.min(gx);
            y0 = y0.min(gy);
            x1 = x1.max(gx + img.width as i32);
            y1 = y1.max(gy + img.height as i32);
        }
        if x0 >= x1 || y0 >= y1 {
            return None;
        }
        let (width, height) = ((x1 - x0) as usize, (y1 - y0) as usize);
        if !crate::alloc::fits(width as u64, height as u64) {
            return None;
        }
        let mut data = vec![0u8; width * height];
        for g in glyphs {
            let Some(img) = self.glyph(g.key) else { continue };
            let (gw, gx, gy) = (img.width as usize, g.x + img.left - x0, g.y - img.top - y0);
            for (my, src) in img.data.chunks_exact(gw.max(1)).take(img.height as usize).enumerate()
            {
                let row = &mut data[(gy as usize + my) * width + gx as usize..][..gw];
                for (d, &k) in row.iter_mut().zip(src) {
                    let a = *d as u32;
                    *d = (a + crate::pixel::div255(k as u32 * (255 - a))) as u8;
                }
            }
        }
        Some(Arc::new(RunMask { left: x0, top: y0, width, height, data }))
    }

    /// The rasterised image of a glyph (cached).
    pub(crate) fn glyph(&mut self, key: CacheKey) -> Option<GlyphImage<'_>> {
        let img = self.glyphs.get_image(&mut self.fonts, key).as_ref()?;
        let color = match img.content {
            SwashContent::Mask => false,
            SwashContent::Color => true,
            SwashContent::SubpixelMask => return None,
        };
        Some(GlyphImage {
            left: img.placement.left,
            top: img.placement.top,
            width: img.placement.width,
            height: img.placement.height,
            color,
            data: &img.data,
        })
    }
}

#[cfg(test)]
mod tests {
    #[test]
    fn the_bundled_font_shapes_text() {
        let m = super::measure("HDG 270°", 20.0, false);
        assert!(m.width > 60.0 && m.width < 120.0, "{m:?}");
        assert_eq!(m.height, 24.0);
        let b = super::measure("HDG 270°", 20.0, true);
        assert!(b.width > m.width, "bold is wider: {b:?} vs {m:?}");
        assert_eq!(super::measure("", 20.0, false).width, 0.0);
    }
}
