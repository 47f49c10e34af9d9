//! Deferred clearing and background fills: a reused layer's old tiles are cleared, and an
//! opaque background that covers the whole layer (a chart's gradient, a `clear`) is
//! filled, row band by row band just before the first drawing that touches them. The
//! drawing then lands on rows that are in the cache, instead of on rows a memset of the
//! whole layer wrote out to memory a moment before (a chart's grid lines touch every row:
//! after a full-layer fill each of them missed the cache on every row).

use super::SkiaCanvas;
use crate::geom::IRect;
use crate::tiles::{TILE_H, TILE_W, Tiles};

/// What a canvas still owes its pixmap before the pixels under a drawing are right.
#[derive(Default)]
pub(super) struct Pending {
    /// Tiles that still hold the previous frame: cleared before anything draws on them.
    stale: Option<Tiles>,
    /// An opaque background: each pixmap row's colour, and whether it is filled yet.
    background: Option<Background>,
}

struct Background {
    rows: Vec<[u8; 4]>,
    filled: Vec<bool>,
    /// Rows not filled yet.
    left: usize,
}

impl Pending {
    /// Nothing owed: a fresh or fully prepared pixmap.
    pub fn none() -> Pending {
        Pending::default()
    }

    /// The pixmap holds a previous frame on `stale` tiles.
    pub fn stale(stale: Tiles) -> Pending {
        Pending { stale: Some(stale), background: None }
    }

    /// Every row `y` is to be `rows[y]` (opaque), whatever the pixmap holds now.
    pub fn background(rows: Vec<[u8; 4]>) -> Pending {
        let n = rows.len();
        Pending {
            stale: None,
            background: Some(Background { filled: vec![false; n], rows, left: n }),
        }
    }
}

impl SkiaCanvas {
    /// Makes the pixels of `area` (pixmap pixels) what the drawings so far left there:
    /// clears the stale tiles it touches (whole tiles) and fills the background rows it
    /// crosses (whole rows). Every drawing calls it on what it may touch, before touching.
    pub(super) fn prepare(&mut self, area: IRect) {
        let full = self.full();
        let area = area.intersect(&full);
        if area.is_empty() {
            return;
        }
        let w = self.pixmap.width() as usize;
        let (px, _) = self.pixmap.data_mut().as_chunks_mut::<4>();
        if let Some(bg) = &mut self.pending.background {
            for y in area.y..area.bottom() {
                let y = y as usize;
                if !bg.filled[y] {
                    px[y * w..][..w].fill(bg.rows[y]);
                    bg.filled[y] = true;
                    bg.left -= 1;
                }
            }
            if bg.left == 0 {
                self.pending.background = None;
            }
        }
        if let Some(st) = &mut self.pending.stale {
            if st.is_empty() {
                self.pending.stale = None;
                return;
            }
            // Whole tiles: a cleared tile is forgotten.
            let x0 = area.x / TILE_W * TILE_W;
            let x1 = (area.right() + TILE_W - 1) / TILE_W * TILE_W;
            let y0 = area.y / TILE_H * TILE_H;
            let y1 = ((area.bottom() + TILE_H - 1) / TILE_H * TILE_H).min(full.h);
            for ty in (y0..y1).step_by(TILE_H as usize) {
                let rows = ty as usize..(ty + TILE_H).min(full.h) as usize;
                st.row_runs(ty, x0, x1, |a, b| {
                    for y in rows.clone() {
                        px[y * w + a as usize..y * w + b as usize].fill([0; 4]);
                    }
                });
            }
            st.unmark(IRect::new(x0, y0, x1 - x0, y1 - y0));
        }
    }

    /// Settles everything owed (before the pixmap is handed out).
    pub(super) fn finish(&mut self) {
        self.prepare(self.full());
        self.pending = Pending::none();
    }

    /// An opaque background covers the whole pixmap: row `y` becomes `rows[y]`, filled
    /// when a drawing first needs it. Whatever the pixmap held is forgotten.
    pub(super) fn set_background(&mut self, rows: Vec<[u8; 4]>) {
        debug_assert_eq!(rows.len(), self.pixmap.height() as usize);
        self.pending = Pending::background(rows);
        self.opaque = true;
        self.tiles.mark_all();
    }
}
