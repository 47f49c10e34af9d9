//! Raster tiles a trial site has offline, addressed as Web Mercator `z/x/y` (the XYZ
//! scheme: `y` counts down from the north): an MBTiles file (SQLite; its rows are TMS,
//! `y` counting up, and are flipped here) or a folder `z/x/y.png`.

use parking_lot::Mutex;
use std::path::{Path, PathBuf};

/// Where tiles come from.
pub enum TileSource {
    MbTiles { conn: Mutex<rusqlite::Connection>, path: PathBuf },
    Folder(PathBuf),
}

impl TileSource {
    /// A folder is read as `z/x/y.png`; a file is opened read-only as MBTiles.
    pub fn open(path: &Path) -> Result<TileSource, String> {
        if path.is_dir() {
            return Ok(TileSource::Folder(path.to_path_buf()));
        }
        if !path.is_file() {
            return Err(format!("{}: no such file or folder", path.display()));
        }
        let flags =
            rusqlite::OpenFlags::SQLITE_OPEN_READ_ONLY | rusqlite::OpenFlags::SQLITE_OPEN_NO_MUTEX;
        let conn = rusqlite::Connection::open_with_flags(path, flags)
            .map_err(|e| format!("{}: {e}", path.display()))?;
        conn.query_row("SELECT count(*) FROM tiles LIMIT 1", [], |r| r.get::<_, i64>(0))
            .map_err(|e| format!("{}: not an MBTiles file ({e})", path.display()))?;
        Ok(TileSource::MbTiles { conn: Mutex::new(conn), path: path.to_path_buf() })
    }

    /// `mbtiles` or `folder`.
    pub fn kind(&self) -> &'static str {
        match self {
            TileSource::MbTiles { .. } => "mbtiles",
            TileSource::Folder(_) => "folder",
        }
    }

    pub fn path(&self) -> &Path {
        match self {
            TileSource::MbTiles { path, .. } => path,
            TileSource::Folder(p) => p,
        }
    }

    /// The encoded image of tile `z/x/y` (XYZ), if the source has it.
    pub fn tile(&self, z: u32, x: u32, y: u32) -> Option<Vec<u8>> {
        if z > 30 || x >= 1 << z || y >= 1 << z {
            return None;
        }
        match self {
            TileSource::MbTiles { conn, .. } => {
                let row = (1u32 << z) - 1 - y;
                conn.lock()
                    .query_row(
                        "SELECT tile_data FROM tiles \
                         WHERE zoom_level = ?1 AND tile_column = ?2 AND tile_row = ?3",
                        [z, x, row],
                        |r| r.get::<_, Vec<u8>>(0),
                    )
                    .ok()
            }
            TileSource::Folder(dir) => {
                std::fs::read(dir.join(z.to_string()).join(x.to_string()).join(format!("{y}.png")))
                    .ok()
            }
        }
    }

    /// The zoom levels the source holds, lowest and highest (`None` when it holds none).
    pub fn zoom_range(&self) -> Option<(u32, u32)> {
        match self {
            TileSource::MbTiles { conn, .. } => conn
                .lock()
                .query_row("SELECT min(zoom_level), max(zoom_level) FROM tiles", [], |r| {
                    Ok((r.get::<_, Option<u32>>(0)?, r.get::<_, Option<u32>>(1)?))
                })
                .ok()
                .and_then(|(a, b)| Some((a?, b?))),
            TileSource::Folder(dir) => {
                let zooms: Vec<u32> = std::fs::read_dir(dir)
                    .ok()?
                    .filter_map(|e| e.ok()?.file_name().to_str()?.parse::<u32>().ok())
                    .filter(|z| *z <= 30)
                    .collect();
                Some((*zooms.iter().min()?, *zooms.iter().max()?))
            }
        }
    }
}

/// One tile to store: its XYZ address and its encoded image.
pub type TileData = ((u32, u32, u32), Vec<u8>);

/// Writes an MBTiles file (1.3: `metadata` and `tiles` tables, TMS rows) holding `tiles`
/// as PNGs: how tests and tools make a site's tile file of their own.
pub fn write_mbtiles(path: &Path, name: &str, tiles: &[TileData]) -> Result<(), String> {
    let e = |e: rusqlite::Error| format!("{}: {e}", path.display());
    let mut db = rusqlite::Connection::open(path).map_err(e)?;
    let tx = db.transaction().map_err(e)?;
    tx.execute_batch(
        "CREATE TABLE metadata (name TEXT, value TEXT);
         CREATE TABLE tiles (zoom_level INTEGER, tile_column INTEGER, tile_row INTEGER,
                             tile_data BLOB);
         CREATE UNIQUE INDEX tile_index ON tiles (zoom_level, tile_column, tile_row);",
    )
    .map_err(e)?;
    tx.execute(
        "INSERT INTO metadata VALUES ('name', ?1), ('format', 'png'), ('type', 'baselayer')",
        [name],
    )
    .map_err(e)?;
    for ((z, x, y), data) in tiles {
        if *z > 30 || *x >= 1 << z || *y >= 1 << z {
            return Err(format!("no tile {z}/{x}/{y} in Web Mercator"));
        }
        let row = (1u32 << z) - 1 - y;
        tx.execute("INSERT INTO tiles VALUES (?1, ?2, ?3, ?4)", rusqlite::params![z, x, row, data])
            .map_err(e)?;
    }
    tx.commit().map_err(e)
}
