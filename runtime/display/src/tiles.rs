//! Which parts of a layer's pixmap have been drawn on since it was last cleared, in tiles
//! of [`TILE_W`] x [`TILE_H`] pixels. The canvas marks the tiles of every drawing's
//! bounds; a repaint clears only the marked tiles instead of the whole layer, and the
//! compositor reads only the marked tiles (the others are transparent). A HUD layer is
//! mostly empty: at 1920x1080 both save most of a memset and of a pass over the layer.
//!
//! Marking is conservative (a drawing's bounding box): a marked tile may be transparent,
//! an unmarked one never holds a drawn pixel.

use crate::geom::IRect;

/// Tile width in pixels (128 bytes of a row: two cache lines).
pub const TILE_W: i32 = 32;
/// Tile height in pixels.
pub const TILE_H: i32 = 8;

/// The drawn-on tiles of a `width` x `height` pixmap.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Tiles {
    width: i32,
    height: i32,
    cols: usize,
    /// One flag a tile, row-major.
    marked: Vec<bool>,
    /// How many tiles are marked.
    count: usize,
}

impl Tiles {
    /// No tile marked: a transparent pixmap.
    pub fn none(width: u32, height: u32) -> Tiles {
        let (w, h) = (width.min(i32::MAX as u32) as i32, height.min(i32::MAX as u32) as i32);
        let cols = (w + TILE_W - 1) / TILE_W;
        let rows = (h + TILE_H - 1) / TILE_H;
        Tiles {
            width: w,
            height: h,
            cols: cols as usize,
            marked: vec![false; cols as usize * rows as usize],
            count: 0,
        }
    }

    /// Every tile marked: a pixmap whose content is unknown.
    pub fn all(width: u32, height: u32) -> Tiles {
        let mut t = Tiles::none(width, height);
        t.mark_all();
        t
    }

    pub fn size(&self) -> (u32, u32) {
        (self.width as u32, self.height as u32)
    }

    pub fn bounds(&self) -> IRect {
        IRect::new(0, 0, self.width, self.height)
    }

    pub fn is_empty(&self) -> bool {
        self.count == 0
    }

    pub fn is_all(&self) -> bool {
        self.count == self.marked.len()
    }

    pub fn mark_all(&mut self) {
        self.marked.fill(true);
        self.count = self.marked.len();
    }

    /// Unmarks every tile (the pixmap was cleared).
    pub fn reset(&mut self) {
        self.marked.fill(false);
        self.count = 0;
    }

    /// Marks the tiles `r` (pixmap pixels) touches.
    pub fn mark(&mut self, r: IRect) {
        let r = r.intersect(&self.bounds());
        if r.is_empty() || self.is_all() {
            return;
        }
        let (c0, c1) = ((r.x / TILE_W) as usize, ((r.right() - 1) / TILE_W) as usize);
        for ty in r.y / TILE_H..=(r.bottom() - 1) / TILE_H {
            let row = &mut self.marked[ty as usize * self.cols..][c0..=c1];
            self.count += row.iter().filter(|m| !**m).count();
            row.fill(true);
        }
    }

    /// Unmarks the tiles `r` (pixmap pixels) touches (their pixels were cleared).
    pub fn unmark(&mut self, r: IRect) {
        let r = r.intersect(&self.bounds());
        if r.is_empty() || self.is_empty() {
            return;
        }
        let (c0, c1) = ((r.x / TILE_W) as usize, ((r.right() - 1) / TILE_W) as usize);
        for ty in r.y / TILE_H..=(r.bottom() - 1) / TILE_H {
            let row = &mut self.marked[ty as usize * self.cols..][c0..=c1];
            self.count -= row.iter().filter(|m| **m).count();
            row.fill(false);
        }
    }

    /// Whether any tile `r` touches is marked.
    pub fn touches(&self, r: IRect) -> bool {
        let r = r.intersect(&self.bounds());
        if r.is_empty() || self.is_empty() {
            return false;
        }
        if self.is_all() {
            return true;
        }
        let (c0, c1) = ((r.x / TILE_W) as usize, ((r.right() - 1) / TILE_W) as usize);
        (r.y / TILE_H..=(r.bottom() - 1) / TILE_H)
            .any(|ty| self.marked[ty as usize * self.cols..][c0..=c1].contains(&true))
    }

    /// The marked parts of pixel row `y` between columns `x0` and `x1`, as runs
    /// `(start, end)` of whole marked tiles clipped to `x0..x1`, left to right.
    pub fn row_runs(&self, y: i32, x0: i32, x1: i32, mut f: impl FnMut(i32, i32)) {
        let (x0, x1) = (x0.max(0), x1.min(self.width));
        if y < 0 || y >= self.height || x0 >= x1 || self.is_empty() {
            return;
        }
        if self.is_all() {
            return f(x0, x1);
        }
        let row = &self.marked[(y / TILE_H) as usize * self.cols..][..self.cols];
        let (c0, c1) = ((x0 / TILE_W) as usize, ((x1 - 1) / TILE_W) as usize);
        let mut c = c0;
        while c <= c1 {
            if !row[c] {
                c += 1;
                continue;
            }
            let start = c;
            while c <= c1 && row[c] {
                c += 1;
            }
            f((start as i32 * TILE_W).max(x0), (c as i32 * TILE_W).min(x1));
        }
    }

    /// The marked tiles as rectangles, one a run of marked tiles in a tile row.
    pub fn rects(&self) -> Vec<IRect> {
        let mut out = Vec::new();
        if self.is_empty() {
            return out;
        }
        if self.is_all() {
            out.push(self.bounds());
            return out;
        }
        for ty in 0..self.marked.len() / self.cols.max(1) {
            let y = ty as i32 * TILE_H;
            let h = TILE_H.min(self.height - y);
            self.row_runs(y, 0, self.width, |a, b| out.push(IRect::new(a, y, b - a, h)));
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn marking_a_rectangle_marks_the_tiles_it_touches_and_no_other() {
        let mut t = Tiles::none(100, 40);
        assert!(t.is_empty());
        t.mark(IRect::new(31, 7, 2, 2));
        assert!(t.touches(IRect::new(0, 0, 1, 1)));
        assert!(t.touches(IRect::new(63, 15, 1, 1)));
        assert!(!t.touches(IRect::new(64, 0, 30, 40)));
        assert!(!t.touches(IRect::new(0, 16, 100, 24)));
        assert_eq!(
            t.rects(),
            vec![IRect::new(0, 0, 64, 8), IRect::new(0, 8, 64, 8)],
            "two tile rows of two tiles"
        );
    }

    #[test]
    fn row_runs_are_clipped_to_the_asked_columns_and_the_pixmap() {
        let mut t = Tiles::none(100, 16);
        t.mark(IRect::new(0, 0, 40, 1));
        t.mark(IRect::new(96, 0, 50, 1));
        let mut runs = Vec::new();
        t.row_runs(3, 10, 200, |a, b| runs.push((a, b)));
        assert_eq!(runs, vec![(10, 64), (96, 100)]);
        runs.clear();
        t.row_runs(8, 0, 100, |a, b| runs.push((a, b)));
        assert!(runs.is_empty(), "the second tile row is clean: {runs:?}");
    }

    #[test]
    fn unmarking_forgets_the_tiles_touched_and_keeps_the_others() {
        let mut t = Tiles::all(100, 40);
        t.unmark(IRect::new(40, 9, 1, 1));
        assert!(!t.is_all() && !t.touches(IRect::new(32, 8, 32, 8)));
        assert!(t.touches(IRect::new(0, 8, 32, 8)) && t.touches(IRect::new(32, 0, 32, 8)));
        t.unmark(IRect::new(0, 0, 100, 40));
        assert!(t.is_empty());
    }

    #[test]
    fn marks_outside_the_pixmap_are_ignored_and_reset_forgets_everything() {
        let mut t = Tiles::none(50, 50);
        t.mark(IRect::new(-100, -100, 50, 50));
        t.mark(IRect::new(60, 0, 10, 10));
        assert!(t.is_empty());
        t.mark_all();
        assert!(t.is_all() && t.touches(IRect::new(49, 49, 1, 1)));
        t.reset();
        assert!(t.is_empty() && !t.is_all());
    }
}
