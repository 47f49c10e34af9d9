//! The chart under the vehicles: the overlays the `map` module publishes under
//! `root.map.features` (coastline, piers, breakwaters, buoys, zones, no-go areas), drawn
//! in a dusk chart palette. docs/map.md lists the kinds and how each is drawn.

use super::view::View;
use mocu_dataserver::{DataServer, Guid, PropName, Value};
use mocu_display::{Brush, Canvas, Color, Path, PathBuilder, Point, Stroke};

/// One overlay feature as the map reads it; `parts` are (longitude, latitude) lists.
pub struct ChartFeature {
    pub kind: String,
    pub name: String,
    pub shape: String,
    pub parts: Vec<Vec<(f64, f64)>>,
    pub colour: String,
    /// West, south, east, north bounds in degrees: what the view leaves out is not drawn.
    pub bounds: (f64, f64, f64, f64),
}

/// The features as last read, kept while `root.map.features` has the same children, each
/// read whole (a feature is published before its properties: one read without its parts
/// is read again).
#[derive(Default)]
pub struct FeatureCache {
    children: Vec<Guid>,
    complete: bool,
    features: std::sync::Arc<Vec<ChartFeature>>,
}

impl FeatureCache {
    pub fn get(&mut self, ds: &DataServer) -> std::sync::Arc<Vec<ChartFeature>> {
        let children =
            ds.resolve(&["map", "features"]).and_then(|f| ds.children(f).ok()).unwrap_or_default();
        if !(self.complete && children == self.children) {
            let features = features(ds);
            self.complete = features.len() == children.len();
            self.children = children;
            self.features = std::sync::Arc::new(features);
        }
        self.features.clone()
    }
}

/// Deep water where there are no tiles.
pub const WATER: Color = Color::rgb(0x0c, 0x22, 0x36);
pub const LAND: Color = Color::rgb(0x4a, 0x42, 0x33);
const SHORE: Color = Color::rgb(0xb9, 0xa7, 0x7c);
const PIER: Color = Color::rgb(0x70, 0x74, 0x7a);
const PIER_EDGE: Color = Color::rgb(0xa8, 0xae, 0xb4);
const ZONE: Color = Color::rgb(0x5e, 0xc8, 0xe5);
pub const NOGO: Color = Color::rgb(0xe0, 0x4f, 0xd8);

/// The features under `root.map.features`, in order.
pub fn features(ds: &DataServer) -> Vec<ChartFeature> {
    let Some(folder) = ds.resolve(&["map", "features"]) else { return Vec::new() };
    let text = |g: Guid, k: &str| match ds.try_get(g, PropName::new(k)) {
        Some(Value::Str(s)) => s.to_string(),
        _ => String::new(),
    };
    let mut out = Vec::new();
    for g in ds.children(folder).unwrap_or_default() {
        let parts: Vec<Vec<(f64, f64)>> = match ds.try_get(g, PropName::new("parts")) {
            Some(Value::List(ps)) => ps
                .iter()
                .map(|p| match p {
                    Value::List(xs) => xs
                        .chunks_exact(2)
                        .filter_map(|c| Some((c[0].as_f64()?, c[1].as_f64()?)))
                        .collect(),
                    _ => Vec::new(),
                })
                .collect(),
            _ => continue,
        };
        let mut bounds = (f64::MAX, f64::MAX, f64::MIN, f64::MIN);
        for (lon, lat) in parts.iter().flatten() {
            bounds =
                (bounds.0.min(*lon), bounds.1.min(*lat), bounds.2.max(*lon), bounds.3.max(*lat));
        }
        out.push(ChartFeature {
            bounds,
            kind: text(g, "kind"),
            name: text(g, "name"),
            shape: text(g, "shape"),
            parts,
            colour: text(g, "colour"),
        });
    }
    out
}

/// A part's positions on the screen.
fn screen(view: &View, part: &[(f64, f64)]) -> Vec<Point> {
    part.iter().map(|(lon, lat)| view.to_screen(*lat, *lon)).collect()
}

fn area(view: &View, f: &ChartFeature) -> Path {
    let mut b = PathBuilder::new();
    for part in &f.parts {
        let pts = screen(view, part);
        if let Some((first, rest)) = pts.split_first() {
            b.move_to(*first);
            for p in rest {
                b.line_to(*p);
            }
            b.close();
        }
    }
    b.finish()
}

fn lines(view: &View, f: &ChartFeature) -> Path {
    let mut b = PathBuilder::new();
    for part in &f.parts {
        let pts = screen(view, part);
        if let Some((first, rest)) = pts.split_first() {
            b.move_to(*first);
            for p in rest {
                b.line_to(*p);
            }
        }
    }
    b.finish()
}

/// A buoy's colour: the file's (`red`, `green`, `yellow`, `#rrggbb`), else yellow.
pub fn buoy_colour(name: &str) -> Color {
    match name {
        "red" => Color::rgb(0xef, 0x44, 0x44),
        "green" => Color::rgb(0x22, 0xc5, 0x5e),
        s if s.len() == 7 && s.starts_with('#') => {
            let v = u32::from_str_radix(&s[1..], 16).unwrap_or(0xfacc15);
            Color::rgb((v >> 16) as u8, (v >> 8) as u8, v as u8)
        }
        _ => Color::rgb(0xfa, 0xcc, 0x15),
    }
}

/// Whether any of a feature can be on the screen (with room for strokes and marks).
fn on_screen(view: &View, f: &ChartFeature) -> bool {
    let (w, s, e, n) = f.bounds;
    let (a, b) = (view.to_screen(n, w), view.to_screen(s, e));
    let m = 20.0;
    a.x <= view.w + m && b.x >= -m && a.y <= view.h + m && b.y >= -m
}

/// Draws the features in chart order: areas under lines, lines under marks; those wholly
/// outside the view are left out.
pub fn draw(c: &mut dyn Canvas, view: &View, features: &[ChartFeature], u: f32) {
    let visible: Vec<&ChartFeature> = features.iter().filter(|f| on_screen(view, f)).collect();
    let features = &visible[..];
    let dash = [6.0 * u, 4.0 * u];
    // Zones and no-go areas: a tint under everything.
    for f in features.iter().filter(|f| f.shape == "polygon") {
        match f.kind.as_str() {
            "zone" => c.fill_path(&area(view, f), &Brush::Solid(ZONE.with_alpha(0.11))),
            "nogo" => c.fill_path(&area(view, f), &Brush::Solid(NOGO.with_alpha(0.19))),
            _ => {}
        }
    }
    // Land and its shoreline.
    for f in features.iter().filter(|f| matches!(f.kind.as_str(), "coastline" | "land")) {
        if f.shape == "polygon" {
            let p = area(view, f);
            c.fill_path(&p, &Brush::Solid(LAND));
            c.stroke_path(&p, &Stroke::new(1.5 * u), &Brush::Solid(SHORE));
        } else if f.shape == "line" {
            c.stroke_path(&lines(view, f), &Stroke::new(1.5 * u), &Brush::Solid(SHORE));
        }
    }
    // Piers, quays and breakwaters.
    for f in features.iter().filter(|f| matches!(f.kind.as_str(), "pier" | "breakwater")) {
        if f.shape == "polygon" {
            let p = area(view, f);
            c.fill_path(&p, &Brush::Solid(PIER));
            c.stroke_path(&p, &Stroke::new(u), &Brush::Solid(PIER_EDGE));
        } else if f.shape == "line" {
            let p = lines(view, f);
            c.stroke_path(&p, &Stroke::new(5.0 * u), &Brush::Solid(PIER_EDGE));
            c.stroke_path(&p, &Stroke::new(3.0 * u), &Brush::Solid(PIER));
        }
    }
    // Outlines of zones (dashed) and no-go areas (dashed, heavier).
    for f in features.iter().filter(|f| f.shape == "polygon") {
        let (colour, width) = match f.kind.as_str() {
            "zone" => (ZONE, 1.5 * u),
            "nogo" => (NOGO, 2.0 * u),
            _ => continue,
        };
        c.stroke_path(&area(view, f), &Stroke::new(width).dash(&dash, 0.0), &Brush::Solid(colour));
    }
    // Anything else the file holds: thin grey lines and dots.
    let other = Color::rgb(0x9a, 0xa4, 0xae);
    for f in features.iter().filter(|f| !is_known(&f.kind)) {
        match f.shape.as_str() {
            "polygon" => c.stroke_path(&area(view, f), &Stroke::new(u), &Brush::Solid(other)),
            "line" => c.stroke_path(&lines(view, f), &Stroke::new(u), &Brush::Solid(other)),
            _ => {
                for p in f.parts.iter().flat_map(|p| screen(view, p)) {
                    c.fill_circle(p, 3.0 * u, other);
                }
            }
        }
    }
    // Buoys: a coloured mark with a dark rim and a light ring.
    for f in features.iter().filter(|f| f.kind == "buoy") {
        for p in f.parts.iter().flat_map(|p| screen(view, p)) {
            c.fill_circle(p, 5.5 * u, Color::rgb(0x0b, 0x12, 0x1a));
            c.fill_circle(p, 4.0 * u, buoy_colour(&f.colour));
            c.stroke_circle(p, 7.0 * u, u, Color::rgb(0xe8, 0xf0, 0xf8).with_alpha(0.7));
        }
    }
}

fn is_known(kind: &str) -> bool {
    matches!(kind, "coastline" | "land" | "pier" | "breakwater" | "zone" | "nogo" | "buoy")
}

/// Where a feature's name goes: a buoy's beside the mark, an area's at its middle; land
/// and lines carry no name on the map.
pub fn label_anchor(view: &View, f: &ChartFeature) -> Option<Point> {
    if f.name.is_empty() {
        return None;
    }
    match (f.kind.as_str(), f.shape.as_str()) {
        ("buoy", _) => {
            f.parts.first().and_then(|p| p.first()).map(|(lon, lat)| view.to_screen(*lat, *lon))
        }
        ("zone" | "nogo", "polygon") => {
            let ring = f.parts.first()?;
            let n = ring.len().saturating_sub(1).max(1) as f64;
            let (sx, sy) =
                ring.iter().take(n as usize).fold((0.0, 0.0), |a, p| (a.0 + p.0, a.1 + p.1));
            Some(view.to_screen(sy / n, sx / n))
        }
        _ => None,
    }
}
