//! Raster background: the tiles a window needs, asked of `root.map.tile(z, x, y)` (the
//! `map` module, mocu-mapdata) once each, decoded, kept, and drawn at the view's zoom;
//! a tile that has not come yet leaves the water colour showing.

use super::view::View;
use mocu_dataserver::{CallOutcome, DataServer, Guid, PropName, Value};
use mocu_display::{Canvas, Image, ImageFit, Rect};
use parking_lot::Mutex;
use std::collections::HashMap;
use std::sync::Arc;

type Key = (u32, u32, u32);

enum Tile {
    Asked,
    Missing,
    Ready(Arc<Image>),
}

/// Tiles kept between frames (at most `KEEP`; past that, those not on screen are dropped).
#[derive(Default)]
pub struct TileCache {
    tiles: Mutex<HashMap<Key, Tile>>,
}

const KEEP: usize = 512;

impl TileCache {
    /// Draws the tiles under `view`; asks for those not asked yet, and calls `arrived`
    /// when one comes. Returns whether the source has tiles at all.
    pub fn draw(
        self: &Arc<Self>,
        ds: &DataServer,
        c: &mut dyn Canvas,
        view: &View,
        arrived: impl Fn() + Clone + Send + 'static,
    ) -> bool {
        let Some(map) = ds.resolve(&["map"]) else { return false };
        let int = |k: &str| ds.try_get(map, PropName::new(k)).and_then(|v| v.as_i64());
        if ds
            .try_get(map, PropName::new("tiles"))
            .and_then(|v| v.as_str().map(str::to_owned))
            .is_none_or(|s| s.is_empty())
        {
            return false;
        }
        let (z0, z1) = (int("tiles_min_zoom").unwrap_or(0), int("tiles_max_zoom").unwrap_or(0));
        // The source's zoom nearest the view's; beyond its deepest level tiles are enlarged.
        let z = (view.zoom.round() as i64).clamp(z0.max(0), z1.clamp(0, 30)) as u32;
        let n = 1u32 << z;
        let tile_px = view.world_px() / n as f64;
        let tl = view.to_world(0.0, 0.0);
        let br = view.to_world(view.w, view.h);
        let (tx0, ty0) = ((tl.0 * n as f64).floor().max(0.0), (tl.1 * n as f64).floor().max(0.0));
        let (tx1, ty1) = (
            (br.0 * n as f64).floor().min(n as f64 - 1.0),
            (br.1 * n as f64).floor().min(n as f64 - 1.0),
        );
        if tx1 < tx0 || ty1 < ty0 || (tx1 - tx0 + 1.0) * (ty1 - ty0 + 1.0) > 400.0 {
            return true;
        }
        let mut visible = Vec::new();
        let mut tiles = self.tiles.lock();
        for ty in ty0 as u32..=ty1 as u32 {
            for tx in tx0 as u32..=tx1 as u32 {
                let key = (z, tx, ty);
                visible.push(key);
                match tiles.get(&key) {
                    Some(Tile::Ready(img)) => {
                        let p = view.world_to_screen(tx as f64 / n as f64, ty as f64 / n as f64);
                        // Whole pixels (and one more) so that neighbours leave no seam.
                        let (x, y) = (p.x.round(), p.y.round());
                        let s = tile_px as f32;
                        let dst = Rect::new(x, y, (p.x + s).round() - x, (p.y + s).round() - y);
                        c.draw_image(img, dst, ImageFit::Stretch, 1.0);
                    }
                    Some(Tile::Asked | Tile::Missing) => {}
                    None => {
                        tiles.insert(key, Tile::Asked);
                        self.ask(ds, map, key, arrived.clone());
                    }
                }
            }
        }
        if tiles.len() > KEEP {
            tiles.retain(|k, t| visible.contains(k) || matches!(t, Tile::Asked));
        }
        true
    }

    fn ask(
        self: &Arc<Self>,
        ds: &DataServer,
        map: Guid,
        key: Key,
        arrived: impl Fn() + Send + 'static,
    ) {
        let weak = Arc::downgrade(self);
        let args =
            vec![Value::Int(key.0 as i64), Value::Int(key.1 as i64), Value::Int(key.2 as i64)];
        ds.call(map, "tile", args, None, move |outcome| {
            let Some(cache) = weak.upgrade() else { return };
            let tile = match outcome {
                CallOutcome::Accepted(v) => match v.first() {
                    Some(Value::Bytes(b)) => {
                        Image::from_png(b).map_or(Tile::Missing, |i| Tile::Ready(Arc::new(i)))
                    }
                    _ => Tile::Missing,
                },
                _ => Tile::Missing,
            };
            let ready = matches!(tile, Tile::Ready(_));
            cache.tiles.lock().insert(key, tile);
            if ready {
                arrived();
            }
        });
    }
}
