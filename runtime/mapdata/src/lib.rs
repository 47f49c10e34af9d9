//! The map's data as a module (kind `map`): the GeoJSON overlays a profile names, published
//! in the world model under `root.map.features`, and the raster tiles of an MBTiles file or
//! a `z/x/y` folder, served by the method `root.map.tile(z, x, y) -> bytes`. The map window
//! (`mocu-widgets`) draws both; it never opens a file itself. docs/map.md.
//!
//! Architecture invariant: like every module, this one talks to the others only through
//! the DataServer.

#![forbid(unsafe_code)]

mod module;
pub mod overlay;
pub mod tiles;

pub use module::{MapDataConfig, MapDataModule, register};
pub use overlay::{Feature, Shape};
pub use tiles::TileSource;
