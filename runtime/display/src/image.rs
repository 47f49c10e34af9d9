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

    pub fn width(&self) -> u32 {
        self.pixmap.width()
    }

    pub fn height(&self) -> u32 {
        self.pixmap.height()
    }
}
