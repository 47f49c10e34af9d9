//! CPU compositing: blends layer pixmaps bottom-up, with opacity, into the frame, only
//! inside the frame's damage rectangle.

use crate::color::Color;
use crate::geom::IRect;
use crate::pixel::{blend_row, premultiply};
use crate::tiles::Tiles;
use mocu_dataserver::Guid;
use tiny_skia::Pixmap;

/// One layer as the compositor sees it.
pub struct LayerView<'a> {
    /// The window the layer belongs to (a stable id for GPU textures).
    pub window: Guid,
    pub pixmap: &'a Pixmap,
    /// The pixmap's drawn-on tiles, where known: the rest is transparent.
    pub tiles: Option<&'a Tiles>,
    /// Every pixel of the pixmap is opaque.
    pub opaque: bool,
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

/// The CPU compositor: owns the frame.
pub struct CpuCompositor {
    frame: Pixmap,
    background: [u8; 4],
}

impl CpuCompositor {
    pub fn new(width: u32, height: u32, background: Color) -> Option<CpuCompositor> {
        Some(CpuCompositor {
            frame: crate::alloc::pixmap(width, height)?,
            background: premultiply(background),
        })
    }

    pub fn frame(&self) -> &Pixmap {
        &self.frame
    }

    pub fn resize(&mut self, width: u32, height: u32) {
        if let Some(p) = crate::alloc::pixmap(width, height) {
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
        // The layers' parts inside the damage, with their opacity.
        let parts: Vec<(IRect, &LayerView<'_>, u8)> = layers
            .iter()
            .filter_map(|l| {
                let op = (l.opacity.clamp(0.0, 1.0) * 255.0).round() as u8;
                let r = l.screen_rect().intersect(&damage);
                let blank = l.tiles.is_some_and(|t| !t.touches(r.offset(-l.x, -l.y)));
                (op > 0 && !r.is_empty() && !blank).then_some((r, l, op))
            })
            .collect();
        // Row by row, every layer: the frame's row stays in the cache while the layers
        // are blended into it, so the frame is written to memory once. An opaque layer
        // across the whole row hides the background and the layers below: the row starts
        // as a copy of it.
        for y in damage.y..damage.bottom() {
            let row = &mut dst_px[y as usize * fw..][..fw];
            let in_row = |(r, _, _): &&(IRect, &LayerView<'_>, u8)| y >= r.y && y < r.bottom();
            let base = parts.iter().rposition(|(r, l, op)| {
                *op == 255
                    && l.opaque
                    && r.x == damage.x
                    && r.w == damage.w
                    && in_row(&&(*r, *l, *op))
            });
            let above = match base {
                Some(i) => {
                    let (r, l, _) = &parts[i];
                    let lw = l.pixmap.width() as usize;
                    let (src_px, _) = l.pixmap.data().as_chunks::<4>();
                    let (sy, sx) = ((y - l.y) as usize, (r.x - l.x) as usize);
                    row[r.x as usize..r.right() as usize]
                        .copy_from_slice(&src_px[sy * lw + sx..][..r.w as usize]);
                    &parts[i + 1..]
                }
                None => {
                    row[damage.x as usize..damage.right() as usize].fill(self.background);
                    &parts[..]
                }
            };
            for part in above.iter().filter(in_row) {
                let (r, l, op) = part;
                let lw = l.pixmap.width() as usize;
                let (src_px, _) = l.pixmap.data().as_chunks::<4>();
                let sy = (y - l.y) as usize;
                let src_row = &src_px[sy * lw..][..lw];
                let mut blend = |x0: i32, x1: i32| {
                    let (a, b) = ((x0 - l.x) as usize, (x1 - l.x) as usize);
                    blend_row(&mut row[x0 as usize..x1 as usize], &src_row[a..b], *op);
                };
                match l.tiles {
                    // Only the drawn-on tiles: the rest of the layer is transparent.
                    Some(t) => t.row_runs(y - l.y, r.x - l.x, r.right() - l.x, |a, b| {
                        blend(a + l.x, b + l.x)
                    }),
                    None => blend(r.x, r.right()),
                }
            }
        }
    }
}
