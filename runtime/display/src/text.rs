//! Text: shaping with cosmic-text and glyph rasterising with swash, using the DejaVu Sans
//! fonts bundled in the binary (no system font is ever read), so that text renders to the
//! same pixels on every machine.
//!
//! One process-wide engine behind a mutex: the font system, the glyph cache and a cache
//! of shaped runs (a gauge redraws the same strings frame after frame).

use crate::canvas::TextMetrics;
use cosmic_text::{
    Attrs, Buffer, CacheKey, Family, FontSystem, Metrics, Shaping, SwashCache, SwashContent,
    Weight, fontdb,
};
use parking_lot::Mutex;
use std::collections::HashMap;
use std::sync::{Arc, OnceLock};

const SANS: &[u8] = include_bytes!("../assets/DejaVuSans.ttf");
const SANS_BOLD: &[u8] = include_bytes!("../assets/DejaVuSans-Bold.ttf");
/// The family name inside the bundled font files.
pub const FAMILY: &str = "DejaVu Sans";
/// Shaped runs kept before the cache is emptied.
const RUN_CACHE_MAX: usize = 8192;

#[derive(Clone, PartialEq, Eq, Hash)]
struct RunKey {
    text: Box<str>,
    size_bits: u32,
    bold: bool,
}

/// One glyph of a shaped run, placed relative to the run's top-left corner (integer
/// pixel origin).
#[derive(Clone, Copy, Debug)]
pub(crate) struct GlyphPlace {
    pub key: CacheKey,
    pub x: i32,
    pub y: i32,
}

/// A shaped run: its glyphs and metrics.
#[derive(Debug)]
pub(crate) struct ShapedRun {
    pub metrics: TextMetrics,
    pub glyphs: Vec<GlyphPlace>,
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
    runs: HashMap<RunKey, Arc<ShapedRun>>,
}

fn engine() -> &'static Mutex<TextEngine> {
    static ENGINE: OnceLock<Mutex<TextEngine>> = OnceLock::new();
    ENGINE.get_or_init(|| {
        let mut db = fontdb::Database::new();
        db.load_font_source(fontdb::Source::Binary(Arc::new(SANS)));
        db.load_font_source(fontdb::Source::Binary(Arc::new(SANS_BOLD)));
        let fonts = FontSystem::new_with_locale_and_db("en-US".into(), db);
        Mutex::new(TextEngine { fonts, glyphs: SwashCache::new(), runs: HashMap::new() })
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
        let size = if size.is_finite() { size.clamp(1.0, 1000.0) } else { 12.0 };
        let key = RunKey { text: text.into(), size_bits: size.to_bits(), bold };
        if let Some(r) = self.runs.get(&key) {
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
        let run = Arc::new(ShapedRun { metrics, glyphs });
        if self.runs.len() >= RUN_CACHE_MAX {
            self.runs.clear();
        }
        self.runs.insert(key, run.clone());
        run
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
