//! Vector overlays from GeoJSON (RFC 7946): coastline, land, piers, buoys, zones and
//! no-go areas, each a [`Feature`] with a kind, a name and its coordinates in degrees.
//!
//! A feature's kind and name come from its `properties` (`kind`, `name`, optional
//! `colour`); docs/map.md lists the kinds the map draws. Multi-geometries keep their parts;
//! a polygon's parts are its rings (exterior first, holes after), each closed.

use mocu_dataserver::{DataServer, DsError, Guid, ObjectInfo, PropMeta, Value, ValueKind};
use mocu_host::world::{create_props, string};

/// The shape of a feature's geometry.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Shape {
    Point,
    Line,
    Polygon,
}

impl Shape {
    pub fn name(self) -> &'static str {
        match self {
            Shape::Point => "point",
            Shape::Line => "line",
            Shape::Polygon => "polygon",
        }
    }
}

/// One overlay feature: `parts` are lists of (longitude, latitude) in degrees.
#[derive(Clone, Debug, PartialEq)]
pub struct Feature {
    pub kind: String,
    pub name: String,
    pub shape: Shape,
    pub parts: Vec<Vec<(f64, f64)>>,
    /// A colour the file asks for (`red`, `green`, `yellow`, or `#rrggbb`), else empty.
    pub colour: String,
}

/// Parses a GeoJSON text (a FeatureCollection, one Feature or a bare Geometry) into
/// features. A feature without geometry is skipped; a GeometryCollection is refused.
pub fn parse(text: &str) -> Result<Vec<Feature>, String> {
    let gj: geojson::GeoJson = text.parse().map_err(|e: geojson::Error| e.to_string())?;
    let features = match gj {
        geojson::GeoJson::FeatureCollection(fc) => fc.features,
        geojson::GeoJson::Feature(f) => vec![f],
        geojson::GeoJson::Geometry(g) => {
            vec![geojson::Feature { geometry: Some(g), ..geojson::Feature::default() }]
        }
    };
    let mut out = Vec::with_capacity(features.len());
    for (i, f) in features.iter().enumerate() {
        let Some(g) = &f.geometry else { continue };
        let prop = |k: &str| {
            f.properties
                .as_ref()
                .and_then(|p| p.get(k))
                .and_then(|v| v.as_str())
                .unwrap_or("")
                .to_string()
        };
        let (shape, parts) = geometry(&g.value).map_err(|e| format!("feature {}: {e}", i + 1))?;
        let kind = match prop("kind") {
            k if k.is_empty() => "feature".to_string(),
            k => k.to_ascii_lowercase(),
        };
        out.push(Feature { kind, name: prop("name"), shape, parts, colour: prop("colour") });
    }
    Ok(out)
}

type Parts = Vec<Vec<(f64, f64)>>;

fn geometry(v: &geojson::Value) -> Result<(Shape, Parts), String> {
    use geojson::Value as G;
    let pos = |p: &Vec<f64>| -> Result<(f64, f64), String> {
        match p.as_slice() {
            [lon, lat, ..] if lon.is_finite() && lat.is_finite() && lat.abs() <= 90.0 => {
                Ok((*lon, *lat))
            }
            _ => Err(format!("bad position {p:?} (want [longitude, latitude])")),
        }
    };
    let line = |l: &Vec<Vec<f64>>| l.iter().map(pos).collect::<Result<Vec<_>, _>>();
    Ok(match v {
        G::Point(p) => (Shape::Point, vec![vec![pos(p)?]]),
        G::MultiPoint(ps) => {
            (Shape::Point, ps.iter().map(|p| pos(p).map(|x| vec![x])).collect::<Result<_, _>>()?)
        }
        G::LineString(l) => (Shape::Line, vec![line(l)?]),
        G::MultiLineString(ls) => (Shape::Line, ls.iter().map(line).collect::<Result<_, _>>()?),
        G::Polygon(rings) => (Shape::Polygon, rings.iter().map(line).collect::<Result<_, _>>()?),
        G::MultiPolygon(polys) => {
            (Shape::Polygon, polys.iter().flatten().map(line).collect::<Result<_, _>>()?)
        }
        G::GeometryCollection(_) => {
            return Err("a GeometryCollection: give each geometry its own feature".into());
        }
    })
}

/// Publishes features as children of `folder`: each an object of kind `feature` named
/// after its kind and number (`buoy3`), with `kind`, `name`, `shape`, `source` (the
/// overlay it came from), `colour` and `parts` (a list of flat `[lon, lat, lon, lat, …]`
/// lists).
pub fn publish(
    ds: &DataServer,
    folder: Guid,
    source: &str,
    features: &[Feature],
) -> Result<(), DsError> {
    let existing = ds.children(folder)?;
    let mut counts = std::collections::HashMap::<String, usize>::new();
    for g in existing {
        if let Ok(i) = ds.info(g) {
            let base = i.name.trim_end_matches(|c: char| c.is_ascii_digit()).to_string();
            *counts.entry(base).or_default() += 1;
        }
    }
    for f in features {
        let base: String =
            f.kind.chars().map(|c| if c.is_ascii_alphanumeric() { c } else { '_' }).collect();
        let n = counts.entry(base.clone()).or_default();
        *n += 1;
        let obj = ds.create_object(folder, ObjectInfo::new(&format!("{base}{n}"), "feature"))?;
        let parts: Vec<Value> = f
            .parts
            .iter()
            .map(|p| Value::list(p.iter().flat_map(|(x, y)| [Value::Float(*x), Value::Float(*y)])))
            .collect();
        create_props(
            ds,
            obj,
            vec![
                ("kind", Value::str(&f.kind), string()),
                ("name", Value::str(&f.name), string()),
                ("shape", Value::str(f.shape.name()), string()),
                ("source", Value::str(source), string()),
                ("colour", Value::str(&f.colour), string()),
                ("parts", Value::list(parts), PropMeta::typed(ValueKind::List)),
            ],
        )?;
    }
    Ok(())
}
