//! The map at its design size (640×480), drawn by the CPU path: the simulator's harbour
//! (the shipped GeoJSON, through the `map` module), the simulator's vehicles by type with
//! their trails, routes and marks, the view that follows a vehicle at a zoom, and a raster
//! background from an MBTiles file this test draws itself, and a route edited on the map
//! (a waypoint dragged and one inserted; a waypoint's context menu).
//!
//! `UPDATE_GOLDEN=1 cargo test -p mocu-widgets --test map` rewrites tests/golden/map_*.png.

mod pixels;

use mocu_dataserver::{Config, DataServer, Guid, ManualClock, ObjectInfo, Value};
use mocu_display::{Clock, Display, DisplayOptions};
use mocu_host::{Module, ModuleContext};
use mocu_layout::{Layout, LayoutConfig, NullSink};
use mocu_mapdata::{MapDataConfig, MapDataModule};
use mocu_sim::{Sim, SimConfig};
use mocu_widgets::map::view;
use mocu_widgets::{Library, MapModule, RendererConfig, WidgetRenderer};
use pixels::check_golden;
use std::path::{Path, PathBuf};
use std::sync::Arc;

fn here(file: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join(file)
}

fn harbour() -> PathBuf {
    here("../../layouts/maps/harbour.geojson")
}

struct Rig {
    ds: DataServer,
    display: Display,
    layout: Layout,
    sim: Sim,
    _renderer: WidgetRenderer,
    _map: MapModule,
    _data: MapDataModule,
}

impl Rig {
    /// A map layout with the `map` module's data, and the simulator (seed 7, every
    /// vehicle started at once) run for `seconds`, a frame drawn every simulated second
    /// (the trails keep what the frames saw).
    fn new(layout: &str, data: MapDataConfig, seconds: usize) -> Rig {
        let (bundle, _) = mocu_language::load_target(&here(layout)).unwrap();
        let program = &bundle.layouts[0].program;
        let clock = ManualClock::new();
        let ds = DataServer::with_clock(Config { workers: 2 }, Arc::new(clock));
        let display =
            Display::new(&ds, DisplayOptions::new(640, 480).clock(Clock::manual())).unwrap();
        let mut data = MapDataModule::new(data);
        data.start(&ModuleContext::detached("map", ds.clone())).unwrap();
        let lib = Library::compile(program, true).unwrap();
        let renderer = WidgetRenderer::start(&ds, lib, RendererConfig::default()).unwrap();
        let map = MapModule::start(&ds).unwrap();
        let lc = LayoutConfig { screen: (640.0, 480.0), ..LayoutConfig::default() };
        let layout = Layout::load(&ds, program, lc, Arc::new(NullSink)).unwrap();
        let cfg = SimConfig {
            seed: 7,
            appear_every: 0.0,
            autostart: true,
            camera_width: 8,
            camera_height: 6,
            camera_fps: 1.0,
            ..SimConfig::default()
        };
        let sim = Sim::new(ModuleContext::detached("sim", ds.clone()), cfg).unwrap();
        let mut rig = Rig { ds, display, layout, sim, _renderer: renderer, _map: map, _data: data };
        for _ in 0..seconds {
            for _ in 0..20 {
                rig.sim.step(0.05);
            }
            rig.frame();
        }
        rig
    }

    fn frame(&mut self) -> tiny_skia::Pixmap {
        for _ in 0..3 {
            self.layout.settle();
            self.ds.quiesce();
            self.display.frame();
        }
        self.display.read_frame()
    }

    fn vehicle(&self, name: &str) -> Guid {
        self.ds.resolve(&["vehicles", name]).unwrap()
    }

    /// usv1 selected by the operator, ugv1 under their control.
    fn select_and_control(&mut self) {
        let op = self.ds.create_object(Guid::ROOT, ObjectInfo::new("operator", "operator"));
        let op = op.unwrap_or_else(|_| self.ds.resolve(&["operator"]).unwrap());
        self.ds.set(op, "selected", Value::Guid(self.vehicle("usv1"))).unwrap();
        let ugv = self.vehicle("ugv1");
        let out = self.ds.call_wait(ugv, "request_control", vec![Value::str("op1")], None);
        assert!(out.is_accepted(), "{out:?}");
        self.sim.step(0.05);
    }

    /// Where the map drew each vehicle: (name, window px).
    fn symbols(&self) -> Vec<(String, f32, f32)> {
        let win = self.ds.resolve(&["display", "chart"]).unwrap();
        let out = self.ds.call_wait(win, "symbols", vec![], None);
        let mocu_dataserver::CallOutcome::Accepted(v) = out else { panic!("{out:?}") };
        v.chunks(3)
            .map(|c| {
                (
                    c[0].as_str().unwrap().to_string(),
                    c[1].as_f64().unwrap() as f32,
                    c[2].as_f64().unwrap() as f32,
                )
            })
            .collect()
    }
}

fn with_harbour() -> MapDataConfig {
    MapDataConfig { overlays: vec![harbour()], ..MapDataConfig::default() }
}

#[test]
fn the_harbour_with_every_vehicle_type_trails_routes_and_the_selected_and_controlled_marks() {
    let mut rig = Rig::new("tests/map.mocu", with_harbour(), 30);
    rig.select_and_control();
    let f = rig.frame();
    check_golden("map_harbour", &f);
    // Every vehicle is on the map, inside the window.
    let symbols = rig.symbols();
    assert_eq!(symbols.len(), 4, "{symbols:?}");
    for (name, x, y) in &symbols {
        assert!((0.0..640.0).contains(x) && (0.0..480.0).contains(y), "{name} at {x},{y}");
    }
}

#[test]
fn follow_centres_the_view_on_the_vehicle_and_zoom_sets_the_web_mercator_level() {
    let mut rig = Rig::new("tests/map_follow.mocu", with_harbour(), 20);
    let f = rig.frame();
    check_golden("map_follow_zoom17", &f);
    let symbols = rig.symbols();
    let (_, x, y) = symbols.iter().find(|s| s.0 == "usv1").unwrap();
    assert!((x - 320.0).abs() < 1.0 && (y - 240.0).abs() < 1.0, "usv1 at {x},{y}");
    // Zoom 17 at 32.71° N: about 1.0 m a pixel, so two vehicles 100 m apart are about
    // 100 px apart on the screen.
    let lat_lon = |name: &str| {
        let nav = rig.ds.resolve(&["vehicles", name, "nav"]).unwrap();
        let get = |k: &str| rig.ds.try_get(nav, k.into()).and_then(|v| v.as_f64()).unwrap();
        (get("lat"), get("lon"))
    };
    let (a, b) = (lat_lon("usv1"), lat_lon("usv2"));
    let metres = ((a.0 - b.0) * 111_320.0).hypot((a.1 - b.1) * 111_320.0 * a.0.to_radians().cos());
    let (_, bx, by) = symbols.iter().find(|s| s.0 == "usv2").unwrap();
    let px = (bx - x).hypot(by - y) as f64;
    let per_px = 156_543.034 * 32.71f64.to_radians().cos() / 2f64.powi(17);
    assert!((px * per_px - metres).abs() < 2.0, "{px} px for {metres} m");
}

/// A harbour chart drawn into tiles in the paper-chart palette (water, land, piers), the
/// way a site's offline tiles look.
fn harbour_tile(z: u32, x: u32, y: u32, features: &[mocu_mapdata::Feature]) -> Vec<u8> {
    let mut p = tiny_skia::Pixmap::new(256, 256).unwrap();
    p.fill(tiny_skia::Color::from_rgba8(0xa9, 0xcf, 0xe0, 255));
    let n = f64::from(1u32 << z);
    let to_px = |lon: f64, lat: f64| {
        let (wx, wy) = view::world(lat, lon);
        (((wx * n) - x as f64) * 256.0, ((wy * n) - y as f64) * 256.0)
    };
    let paint = |rgb: [u8; 3]| {
        let mut paint = tiny_skia::Paint::default();
        paint.set_color_rgba8(rgb[0], rgb[1], rgb[2], 255);
        paint.anti_alias = true;
        paint
    };
    for f in features {
        let colour = match f.kind.as_str() {
            "coastline" => [0xf1, 0xec, 0xdf],
            "pier" => [0xb4, 0xb0, 0xa8],
            "breakwater" => [0x9c, 0x98, 0x90],
            _ => continue,
        };
        let mut b = tiny_skia::PathBuilder::new();
        for part in &f.parts {
            for (i, (lon, lat)) in part.iter().enumerate() {
                let (px, py) = to_px(*lon, *lat);
                if i == 0 {
                    b.move_to(px as f32, py as f32);
                } else {
                    b.line_to(px as f32, py as f32);
                }
            }
            if f.shape == mocu_mapdata::Shape::Polygon {
                b.close();
            }
        }
        let Some(path) = b.finish() else { continue };
        if f.shape == mocu_mapdata::Shape::Polygon {
            p.fill_path(
                &path,
                &paint(colour),
                tiny_skia::FillRule::Winding,
                Default::default(),
                None,
            );
            let stroke = tiny_skia::Stroke { width: 1.0, ..Default::default() };
            p.stroke_path(&path, &paint([0x8a, 0x80, 0x6a]), &stroke, Default::default(), None);
        } else {
            let width = (6.0 * (z as f32 - 16.0).exp2()).max(2.0);
            let stroke = tiny_skia::Stroke { width, ..Default::default() };
            p.stroke_path(&path, &paint(colour), &stroke, Default::default(), None);
        }
    }
    p.encode_png().unwrap()
}

fn harbour_mbtiles(file: &Path) {
    let text = std::fs::read_to_string(harbour()).unwrap();
    let features = mocu_mapdata::overlay::parse(&text).unwrap();
    let mut tiles = Vec::new();
    for z in 15..=17u32 {
        let n = f64::from(1u32 << z);
        let (x0, y0) = view::world(32.722, -117.252);
        let (x1, y1) = view::world(32.698, -117.228);
        for ty in (y0 * n) as u32..=(y1 * n) as u32 {
            for tx in (x0 * n) as u32..=(x1 * n) as u32 {
                tiles.push(((z, tx, ty), harbour_tile(z, tx, ty, &features)));
            }
        }
    }
    mocu_mapdata::tiles::write_mbtiles(file, "harbour", &tiles).unwrap();
}

#[test]
fn a_raster_background_from_an_mbtiles_file_under_the_vehicles() {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("harbour.mbtiles");
    harbour_mbtiles(&file);
    let data = MapDataConfig { tiles: Some(file), ..MapDataConfig::default() };
    let mut rig = Rig::new("tests/map.mocu", data, 30);
    let f = rig.frame();
    check_golden("map_tiles", &f);
    // The tiles are there: the paper chart's land colour shows, which the map's own
    // palette never uses.
    let land = f.pixels().iter().filter(|p| (p.red(), p.green(), p.blue()) == (0xf1, 0xec, 0xdf));
    assert!(land.count() > 1000);
}

/// A vehicle that reports only its local `x`, `y` is placed from `root.map`'s origin: at
/// the same place as one that reports the origin's latitude and longitude.
#[test]
fn a_vehicle_in_the_local_frame_is_anchored_at_the_configured_origin() {
    let data = MapDataConfig { origin: (32.7105, -117.2395), ..with_harbour() };
    let mut rig = Rig::new("tests/map.mocu", data, 1);
    let vehicles = rig.ds.resolve(&["vehicles"]).unwrap();
    let add = |name: &str, props: &[(&str, f64)]| {
        let v = rig.ds.create_object(vehicles, ObjectInfo::new(name, "usv")).unwrap();
        let nav = rig.ds.create_object(v, ObjectInfo::new("nav", "nav")).unwrap();
        for (k, x) in props {
            rig.ds.set(nav, *k, Value::Float(*x)).unwrap();
        }
    };
    add("local", &[("x", 0.0), ("y", 0.0), ("heading", 90.0)]);
    add("global", &[("lat", 32.7105), ("lon", -117.2395), ("heading", 0.0)]);
    rig.frame();
    let symbols = rig.symbols();
    let at = |n: &str| symbols.iter().find(|s| s.0 == n).map(|s| (s.1, s.2)).unwrap();
    let (a, b) = (at("local"), at("global"));
    assert!((a.0 - b.0).abs() < 0.5 && (a.1 - b.1).abs() < 0.5, "{a:?} vs {b:?}");
}

impl Rig {
    /// Where the map drew route `path`'s waypoints, in order.
    fn drawn(&self, path: &str) -> Vec<(f32, f32)> {
        let win = self.ds.resolve(&["display", "chart"]).unwrap();
        let out = self.ds.call_wait(win, "waypoints", vec![], None);
        let mocu_dataserver::CallOutcome::Accepted(v) = out else { panic!("{out:?}") };
        v.chunks(4)
            .filter(|c| c[0].as_str() == Some(path))
            .map(|c| (c[2].as_f64().unwrap() as f32, c[3].as_f64().unwrap() as f32))
            .collect()
    }

    fn pointer(&mut self, kind: &str, button: i64, (x, y): (f32, f32)) {
        let win = self.ds.resolve(&["display", "chart"]).unwrap();
        let args = vec![
            Value::str(kind),
            Value::Int(button),
            Value::Float(x as f64),
            Value::Float(y as f64),
        ];
        assert!(self.ds.call_wait(win, "pointer", args, None).is_accepted());
        self.frame();
    }

    /// The route's waypoints as (x, y) in metres, in order.
    fn route(&self, route: Guid) -> Vec<(f64, f64)> {
        let mut out = Vec::new();
        let mut level = self.ds.children(route).unwrap();
        while let Some(&first) = level.first() {
            for w in &level {
                let get = |k: &str| self.ds.try_get(*w, k.into()).and_then(|v| v.as_f64()).unwrap();
                out.push((get("x"), get("y")));
            }
            level = self.ds.children(first).unwrap();
        }
        out
    }
}

/// Editing on the map changes the world-model route: a press on a leg inserts a waypoint
/// there, a drag moves one waypoint (and nothing else), the waypoint's context menu
/// deletes it.
#[test]
fn a_route_is_edited_on_the_map_by_inserting_dragging_and_deleting_waypoints() {
    let mut rig = Rig::new("tests/map.mocu", with_harbour(), 2);
    let path = "root.vehicles.usv2.routes.patrol";
    let route = rig.ds.resolve(&["vehicles", "usv2", "routes", "patrol"]).unwrap();
    let before = rig.route(route);
    let at = rig.drawn(path);
    assert_eq!((before.len(), at.len()), (4, 4));
    // Drag waypoint 2 thirty pixels east: only it moves, about 30 px worth of metres.
    rig.pointer("down", 0, at[1]);
    rig.pointer("move", -1, (at[1].0 + 15.0, at[1].1));
    rig.pointer("move", -1, (at[1].0 + 30.0, at[1].1));
    rig.pointer("up", 0, (at[1].0 + 30.0, at[1].1));
    let moved = rig.route(route);
    let (dx, dy) = (moved[1].0 - before[1].0, moved[1].1 - before[1].1);
    assert!(dx > 5.0 && dy.abs() < 1.0, "moved by {dx}, {dy}");
    assert_eq!((moved[0], moved[2], moved[3]), (before[0], before[2], before[3]));
    // A press in the middle of the first leg puts a waypoint there, second in the route.
    let at = rig.drawn(path);
    let mid = ((at[0].0 + at[1].0) / 2.0, (at[0].1 + at[1].1) / 2.0);
    rig.pointer("down", 0, mid);
    rig.pointer("up", 0, mid);
    let inserted = rig.route(route);
    assert_eq!(inserted.len(), 5);
    let want = ((moved[0].0 + moved[1].0) / 2.0, (moved[0].1 + moved[1].1) / 2.0);
    let near = (inserted[1].0 - want.0).abs() < 2.0 && (inserted[1].1 - want.1).abs() < 2.0;
    assert!(near, "{inserted:?} want {want:?}");
    // What the operator sees: usv2's patrol with waypoint 2 moved east and a new waypoint
    // on the first leg, in the route's colour.
    check_golden("map_route_edited", &rig.frame());
    // A right press on it opens its menu; "Delete waypoint 2" removes it.
    let at = rig.drawn(path);
    rig.pointer("down", 1, at[1]);
    let menu = rig.ds.resolve(&["display", "context_menu", "menu"]).expect("a context menu");
    assert_eq!(rig.ds.try_get(menu, "item0".into()), Some(Value::str("Delete waypoint 2")));
    check_golden("map_waypoint_menu", &rig.frame());
    mocu_widgets::menu::choose(&rig.ds, menu, 0);
    rig.frame();
    assert_eq!(rig.route(route), moved);
    assert!(rig.ds.resolve(&["display", "context_menu"]).is_none(), "the menu closed");
}

/// The route deltas of the simulator: a waypoint dragged on the map is a change of that one
/// waypoint's position in the world model, nothing else of the route (no object created,
/// moved or deleted, no other waypoint written), as the DataServer's change feed — what a
/// recorder or a remote OCU sees — shows. (The simulator flies it as it is now:
/// runtime/sim/tests/sim.rs, `a_waypoint_moved_while_the_route_is_flown_is_flown_to_where_it_is_now`.)
#[test]
fn a_waypoint_dragged_on_the_map_changes_only_that_waypoint_in_the_world_model() {
    use mocu_dataserver::Change;
    let mut rig = Rig::new("tests/map.mocu", with_harbour(), 2);
    let path = "root.vehicles.usv2.routes.patrol";
    let route = rig.ds.resolve(&["vehicles", "usv2", "routes", "patrol"]).unwrap();
    let wps = mocu_host::world::route_waypoints(&rig.ds, route);
    let ours: Vec<Guid> = std::iter::once(route).chain(wps.iter().copied()).collect();
    let at = rig.drawn(path);
    let feed = rig.ds.change_feed();
    rig.pointer("down", 0, at[2]);
    rig.pointer("move", -1, (at[2].0 + 12.0, at[2].1 - 6.0));
    rig.pointer("move", -1, (at[2].0 + 24.0, at[2].1 - 12.0));
    rig.pointer("up", 0, (at[2].0 + 24.0, at[2].1 - 12.0));
    let mut written = std::collections::BTreeSet::new();
    for c in feed.take() {
        match c.change {
            Change::PropertySet { object, name, .. } | Change::PropertyDeleted { object, name }
                if ours.contains(&object) =>
            {
                assert_eq!(object, wps[2], "only the dragged waypoint is written, not {name}");
                written.insert(name.to_string());
            }
            Change::Created { object, parent, .. } if ours.contains(&parent) => {
                panic!("an object {object:?} created in the route")
            }
            Change::Moved { object, .. } | Change::Deleted { object } if ours.contains(&object) => {
                panic!("the route's shape changed: {:?}", c.change)
            }
            _ => {}
        }
    }
    let want = ["lat", "lon", "x", "y"].map(String::from);
    assert_eq!(written, want.into_iter().collect(), "its position, and only that");
}
