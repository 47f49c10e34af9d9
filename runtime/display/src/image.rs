//! Images a painter can draw: decoded pixels, premultiplied once when made.

use std::sync::Arc;

/// An immutable RGBA image. Cloning shares the pixels.
#[derive(Clone)]
pub struct Image {
    pub(crate) pixmap: Arc<tiny_skia::Pixmap>,
}

impl std::fmt::Debug for Image {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "Image({}x{})", self.width(), self.height())
    }
}

impl Image {
    /// From straight-alpha RGBA8 rows (`width * 4` bytes each). `None` when the sizes do
    /// not match or a side is zero.
    pub fn from_rgba8(width: u32, height: u32, mut rgba: Vec<u8>) -> Option<Image> {
        if rgba.len() != width as usize * height as usize * 4 {
            return None;
        }
        crate::pixel::premultiply_in_place(&mut rgba);
        let pixmap =
            tiny_skia::Pixmap::from_vec(rgba, tiny_skia::IntSize::from_wh(width, height)?)?;
        Some(Image { pixmap: Arc::new(pixmap) })
    }

    /// From RGB8 rows (opaque), the usual shape of a decoded video frame.
    pub fn from_rgb8(width: u32, height: u32, rgb: &[u8]) -> Option<Image> {
        if rgb.len() != width as usize * height as usize * 3 {
            return None;
        }
        let mut v = Vec::with_capacity(rgb.len() / 3 * 4);
        for px in rgb.chunks_exact(3) {
            v.extend_from_slice(&[px[0], px[1], px[2], 255]);
        }
        Image::from_rgba8(width, height, v)
    }

    /// Decodes a PNG file's bytes.
    pub fn from_png(bytes: &[u8]) -> Result<Image, String> {
        tiny_skia::Pixmap::decode_png(bytes)
            .map(|p| Image { pixmap: Arc::new(p) })
            .map_err(|e| e.to_string())
    }

    /// This image resampled to `width`×`height` as a draw at that size samples it
    /// (bilinear), drawn once: a video frame scaled to its window when it arrives, off
    /// the display's thread, is then drawn pixel for pixel (`skia/resample.rs` copies
    /// it). The image itself when the size is its own; `None` for a zero side.
    pub fn scaled(&self, width: u32, height: u32) -> Option<Image> {
        if (width, height) == (self.width(), self.height()) {
            return Some(self.clone());
        }
        let (w, h) = (width as f32, height as f32);
        let pixmap = crate::alloc::pixmap(width, height)?;
        let mut c = crate::SkiaCanvas::new(pixmap, (0, 0), crate::Size::new(w, h));
        crate::Canvas::draw_image(
            &mut c,
            self,
            crate::Rect::new(0.0, 0.0, w, h),
            crate::ImageFit::Stretch,
            1.0,
        );
        Some(Image { pixmap: Arc::new(c.into_pixmap()) })
    }

    pub fn width(&self) -> u32 {
        self.pixmap.width()
    }

    pub fn height(&self) -> u32 {
        self.pixmap.height()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{Canvas, ImageFit, Rect, Size, SkiaCanvas};

    /// Scaling once and drawing the result pixel for pixel shows what drawing the image at
    /// that size shows.
    #[test]
    fn a_scaled_image_drawn_one_to_one_matches_the_image_drawn_scaled() {
        let mut v = Vec::new();
        for i in 0..64u32 * 48 {
            v.extend([(i * 37 % 256) as u8, (i * 91 % 256) as u8, (i * 53 % 256) as u8, 255]);
        }
        let img = Image::from_rgba8(64, 48, v).unwrap();
        let (w, h) = (200u32, 120u32);
        let draw = |img: &Image, dst: Rect| {
            let pm = tiny_skia::Pixmap::new(w, h).unwrap();
            let mut c = SkiaCanvas::new(pm, (0, 0), Size::new(w as f32, h as f32));
            c.draw_image(img, dst, ImageFit::Stretch, 1.0);
            c.into_pixmap()
        };
        let at = Rect::new(20.0, 6.0, 160.0, 108.0);
        let direct = draw(&img, at);
        let once = draw(&img.scaled(160, 108).unwrap(), at);
        assert!(direct.data() == once.data(), "the same pixels");
        assert_eq!(img.scaled(64, 48).unwrap().width(), 64);
        assert!(img.scaled(0, 10).is_none());
    }
}
