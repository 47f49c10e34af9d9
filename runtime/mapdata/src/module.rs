//! The `map` module: reads its settings, publishes `root.map` (the local frame's origin,
//! the tile source and its zoom range, the method `tile`) and `root.map.features`.

use crate::overlay;
use crate::tiles::TileSource;
use mocu_dataserver::{CallOutcome, Guid, MethodSpec, ParamSpec, Value, ValueKind};
use mocu_host::world::{create_props, ensure_path, float_in, int, string};
use mocu_host::{Level, Module, ModuleContext, ModuleSpec, Registry, SpecError};
use std::path::PathBuf;
use std::sync::Arc;

/// What a profile's `[modules.map]` table says (docs/map.md).
#[derive(Clone, Debug, PartialEq)]
pub struct MapDataConfig {
    /// GeoJSON files, drawn in this order (later ones on top).
    pub overlays: Vec<PathBuf>,
    /// An MBTiles file or a `z/x/y` folder of PNG tiles.
    pub tiles: Option<PathBuf>,
    /// Latitude and longitude of the local frame's origin (x = y = 0, metres east and
    /// north), for positions given only in the local frame, and where the map looks first.
    pub origin: (f64, f64),
}

impl Default for MapDataConfig {
    fn default() -> MapDataConfig {
        MapDataConfig { overlays: Vec::new(), tiles: None, origin: (32.71, -117.24) }
    }
}

impl MapDataConfig {
    pub fn from_spec(spec: &ModuleSpec) -> Result<MapDataConfig, SpecError> {
        let d = MapDataConfig::default();
        let overlays = match spec.settings.get("overlays") {
            None => Vec::new(),
            Some(toml::Value::Array(a)) if a.iter().all(|v| v.is_str()) => {
                a.iter().filter_map(|v| v.as_str()).map(PathBuf::from).collect()
            }
            Some(_) => {
                return Err(SpecError(format!(
                    "module `{}`: setting `overlays` must be a list of file names",
                    spec.name
                )));
            }
        };
        let tiles = spec.str_or("tiles", "")?;
        let origin =
            (spec.f64_or("origin_lat", d.origin.0)?, spec.f64_or("origin_lon", d.origin.1)?);
        if !(-85.0..=85.0).contains(&origin.0) || !(-180.0..=180.0).contains(&origin.1) {
            return Err(SpecError(format!(
                "module `{}`: origin_lat must be in [-85, 85] and origin_lon in [-180, 180]",
                spec.name
            )));
        }
        Ok(MapDataConfig {
            overlays,
            tiles: (!tiles.is_empty()).then(|| PathBuf::from(tiles)),
            origin,
        })
    }
}

pub struct MapDataModule {
    cfg: MapDataConfig,
    published: Option<(mocu_dataserver::DataServer, Guid)>,
}

impl MapDataModule {
    pub fn new(cfg: MapDataConfig) -> MapDataModule {
        MapDataModule { cfg, published: None }
    }
}

impl Module for MapDataModule {
    fn start(&mut self, ctx: &ModuleContext) -> Result<(), String> {
        let ds = &ctx.ds;
        let e = |e: mocu_dataserver::DsError| e.to_string();
        let map = ensure_path(ds, &["map"], "map").map_err(e)?;
        self.published = Some((ds.clone(), map));
        let source = match &self.cfg.tiles {
            None => None,
            Some(p) => match TileSource::open(p) {
                Ok(s) => Some(Arc::new(s)),
                Err(err) => {
                    ctx.report(Level::Error, format!("tiles: {err}"));
                    None
                }
            },
        };
        let (z0, z1) = source.as_ref().and_then(|s| s.zoom_range()).unwrap_or((0, 0));
        create_props(
            ds,
            map,
            vec![
                ("origin_lat", Value::Float(self.cfg.origin.0), float_in("deg", -90.0, 90.0)),
                ("origin_lon", Value::Float(self.cfg.origin.1), float_in("deg", -180.0, 180.0)),
                ("tiles", Value::str(source.as_ref().map_or("", |s| s.kind())), string()),
                ("tiles_min_zoom", Value::Int(z0 as i64), int("")),
                ("tiles_max_zoom", Value::Int(z1 as i64), int("")),
            ],
        )
        .map_err(e)?;
        let features = ensure_path(ds, &["map", "features"], "features").map_err(e)?;
        for path in &self.cfg.overlays {
            let name = path.file_stem().and_then(|s| s.to_str()).unwrap_or("overlay");
            let loaded = std::fs::read_to_string(path)
                .map_err(|err| err.to_string())
                .and_then(|text| overlay::parse(&text));
            match loaded {
                Ok(fs) => overlay::publish(ds, features, name, &fs).map_err(e)?,
                Err(err) => ctx.report(Level::Error, format!("overlay {}: {err}", path.display())),
            }
        }
        let spec = MethodSpec::new("tile")
            .param(ParamSpec::new("z", ValueKind::Int))
            .param(ParamSpec::new("x", ValueKind::Int))
            .param(ParamSpec::new("y", ValueKind::Int))
            .result(ParamSpec::new("image", ValueKind::Bytes))
            .describe("The encoded image of Web Mercator tile z/x/y (XYZ), refused when absent");
        ds.publish_method_on(&ctx.executor, map, spec, move |call| {
            let n = |i: usize| call.args.get(i).and_then(|v| v.as_i64()).unwrap_or(-1);
            let (z, x, y) = (n(0), n(1), n(2));
            let tile = source
                .as_ref()
                .filter(|_| z >= 0 && x >= 0 && y >= 0)
                .and_then(|s| s.tile(z as u32, x as u32, y as u32));
            call.responder.reply(match tile {
                Some(bytes) => CallOutcome::Accepted(vec![Value::Bytes(bytes.into())]),
                None => CallOutcome::Refused(format!("no tile {z}/{x}/{y}")),
            });
        })
        .map_err(e)?;
        Ok(())
    }

    fn stop(&mut self) {
        if let Some((ds, map)) = self.published.take() {
            let _ = ds.unpublish_method(map, "tile");
            let _ = ds.delete_object(map);
        }
    }
}

/// Registers the kind `map`.
pub fn register(registry: &mut Registry) {
    registry.register("map", |spec| {
        let cfg = MapDataConfig::from_spec(spec).map_err(|e| e.to_string())?;
        Ok(Box::new(MapDataModule::new(cfg)) as Box<dyn Module>)
    });
}
