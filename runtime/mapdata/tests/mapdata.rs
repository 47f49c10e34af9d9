//! The `map` module: overlays named in its settings appear under `root.map.features`, and
//! tiles of an MBTiles file or a `z/x/y` folder come from `root.map.tile(z, x, y)`.
//! The tiles are small PNGs these tests draw themselves.

use mocu_dataserver::{CallOutcome, DataServer, Guid, PropName, Value};
use mocu_host::{HostEvent, ModuleHost, ModuleSpec, Registry};
use mocu_mapdata::Shape;
use std::path::PathBuf;

fn harbour() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../layouts/maps/harbour.geojson")
}

fn host(spec: ModuleSpec) -> (DataServer, ModuleHost) {
    let mut reg = Registry::new();
    mocu_mapdata::register(&mut reg);
    let ds = DataServer::default();
    let mut host = ModuleHost::new(ds.clone(), reg);
    host.start(&spec).expect("the map module starts");
    (ds, host)
}

fn text(ds: &DataServer, g: Guid, k: &str) -> String {
    ds.try_get(g, PropName::new(k)).and_then(|v| v.as_str().map(str::to_owned)).unwrap_or_default()
}

/// A 256×256 PNG of one colour.
fn png(rgb: [u8; 3]) -> Vec<u8> {
    let mut p = tiny_skia::Pixmap::new(256, 256).unwrap();
    p.fill(tiny_skia::Color::from_rgba8(rgb[0], rgb[1], rgb[2], 255));
    p.encode_png().unwrap()
}

fn tile(ds: &DataServer, z: i64, x: i64, y: i64) -> CallOutcome {
    let map = ds.resolve(&["map"]).unwrap();
    ds.call_wait(map, "tile", vec![Value::Int(z), Value::Int(x), Value::Int(y)], None)
}

#[test]
fn the_shipped_harbour_has_coastline_piers_a_breakwater_buoys_zones_and_no_go_areas() {
    let fs = mocu_mapdata::overlay::parse(&std::fs::read_to_string(harbour()).unwrap()).unwrap();
    let count = |k: &str| fs.iter().filter(|f| f.kind == k).count();
    assert_eq!(count("coastline"), 2);
    assert_eq!(count("pier"), 4);
    assert_eq!(count("breakwater"), 1);
    assert_eq!(count("buoy"), 9);
    assert_eq!(count("zone"), 2);
    assert_eq!(count("nogo"), 2);
    let buoy = fs.iter().find(|f| f.name == "R2").unwrap();
    assert_eq!((buoy.shape, buoy.colour.as_str()), (Shape::Point, "red"));
    // Around the simulator's default origin (32.71 N, 117.24 W), within a few kilometres.
    for f in &fs {
        for (lon, lat) in f.parts.iter().flatten() {
            assert!((lat - 32.71).abs() < 0.02 && (lon + 117.24).abs() < 0.02, "{f:?}");
        }
    }
}

#[test]
fn overlays_named_in_the_settings_are_objects_under_root_map_features() {
    let spec = ModuleSpec::new("map")
        .with("overlays", toml::Value::Array(vec![harbour().to_string_lossy().into_owned().into()]))
        .with("origin_lat", 10.5)
        .with("origin_lon", 20);
    let (ds, _host) = host(spec);
    let map = ds.resolve(&["map"]).unwrap();
    assert_eq!(ds.try_get(map, PropName::new("origin_lat")), Some(Value::Float(10.5)));
    assert_eq!(ds.try_get(map, PropName::new("origin_lon")), Some(Value::Float(20.0)));
    assert_eq!(text(&ds, map, "tiles"), "");
    let pier = ds.resolve(&["map", "features", "pier2"]).expect("root.map.features.pier2");
    assert_eq!(text(&ds, pier, "name"), "Pier 2");
    assert_eq!(text(&ds, pier, "shape"), "polygon");
    assert_eq!(text(&ds, pier, "source"), "harbour");
    let Some(Value::List(parts)) = ds.try_get(pier, PropName::new("parts")) else {
        panic!("parts is a list")
    };
    let Value::List(ring) = &parts[0] else { panic!("a part is a list") };
    // A closed rectangle: five positions, ten numbers, first = last.
    assert_eq!(ring.len(), 10);
    assert_eq!((&ring[0], &ring[1]), (&ring[8], &ring[9]));
    let features = ds.resolve(&["map", "features"]).unwrap();
    assert_eq!(ds.children(features).unwrap().len(), 20);
}

#[test]
fn a_broken_overlay_is_reported_and_the_others_still_load() {
    let dir = tempfile::tempdir().unwrap();
    let bad = dir.path().join("bad.geojson");
    std::fs::write(
        &bad,
        r#"{"type": "Feature", "geometry": {"type": "Point", "coordinates": [10, 100]}}"#,
    )
    .unwrap();
    let list = vec![
        bad.to_string_lossy().into_owned().into(),
        dir.path().join("missing.geojson").to_string_lossy().into_owned().into(),
        harbour().to_string_lossy().into_owned().into(),
    ];
    let spec = ModuleSpec::new("map").with("overlays", toml::Value::Array(list));
    let (ds, host) = host(spec);
    let messages: Vec<String> = host
        .events()
        .try_iter()
        .filter_map(|e| match e {
            HostEvent::Message { text, .. } => Some(text),
            _ => None,
        })
        .collect();
    assert!(
        messages.iter().any(|m| m.contains("bad.geojson") && m.contains("bad position")),
        "{messages:?}"
    );
    assert!(messages.iter().any(|m| m.contains("missing.geojson")), "{messages:?}");
    let features = ds.resolve(&["map", "features"]).unwrap();
    assert_eq!(ds.children(features).unwrap().len(), 20);
}

#[test]
fn a_geometry_collection_is_refused_with_the_fix() {
    let text = r#"{"type": "Feature", "properties": {"kind": "zone"},
        "geometry": {"type": "GeometryCollection", "geometries": []}}"#;
    let err = mocu_mapdata::overlay::parse(text).unwrap_err();
    assert!(err.contains("give each geometry its own feature"), "{err}");
}

#[test]
fn an_mbtiles_file_serves_tiles_by_z_x_y_with_its_rows_flipped() {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("site.mbtiles");
    let (north, south) = (png([10, 40, 70]), png([200, 180, 120]));
    // Zoom 1: y = 0 is the northern half of the world.
    let tiles =
        [((1, 0, 0), north.clone()), ((1, 0, 1), south.clone()), ((3, 2, 5), png([1, 2, 3]))];
    mocu_mapdata::tiles::write_mbtiles(&file, "test", &tiles).unwrap();
    let spec = ModuleSpec::new("map").with("tiles", file.to_string_lossy().into_owned());
    let (ds, _host) = host(spec);
    let map = ds.resolve(&["map"]).unwrap();
    assert_eq!(text(&ds, map, "tiles"), "mbtiles");
    assert_eq!(ds.try_get(map, PropName::new("tiles_min_zoom")), Some(Value::Int(1)));
    assert_eq!(ds.try_get(map, PropName::new("tiles_max_zoom")), Some(Value::Int(3)));
    assert_eq!(tile(&ds, 1, 0, 0), CallOutcome::Accepted(vec![Value::Bytes(north.into())]));
    assert_eq!(tile(&ds, 1, 0, 1), CallOutcome::Accepted(vec![Value::Bytes(south.into())]));
    assert!(matches!(tile(&ds, 1, 1, 0), CallOutcome::Refused(r) if r == "no tile 1/1/0"));
    assert!(matches!(tile(&ds, 1, 2, 0), CallOutcome::Refused(_)), "x beyond the world");
    assert!(matches!(tile(&ds, -1, 0, 0), CallOutcome::Refused(_)));
}

#[test]
fn a_folder_of_png_tiles_serves_z_x_y() {
    let dir = tempfile::tempdir().unwrap();
    let t = png([0, 90, 140]);
    std::fs::create_dir_all(dir.path().join("16/2915")).unwrap();
    std::fs::write(dir.path().join("16/2915/6609.png"), &t).unwrap();
    let spec = ModuleSpec::new("map").with("tiles", dir.path().to_string_lossy().into_owned());
    let (ds, _host) = host(spec);
    let map = ds.resolve(&["map"]).unwrap();
    assert_eq!(text(&ds, map, "tiles"), "folder");
    assert_eq!(ds.try_get(map, PropName::new("tiles_max_zoom")), Some(Value::Int(16)));
    assert_eq!(tile(&ds, 16, 2915, 6609), CallOutcome::Accepted(vec![Value::Bytes(t.into())]));
    assert!(matches!(tile(&ds, 16, 2915, 6610), CallOutcome::Refused(_)));
}

#[test]
fn a_file_that_is_not_mbtiles_is_reported_and_the_map_has_no_tiles() {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("notes.txt");
    std::fs::write(&file, "not a database").unwrap();
    let spec = ModuleSpec::new("map").with("tiles", file.to_string_lossy().into_owned());
    let (ds, host) = host(spec);
    let reported = host
        .events()
        .try_iter()
        .any(|e| matches!(e, HostEvent::Message { text, .. } if text.contains("notes.txt")));
    assert!(reported);
    let map = ds.resolve(&["map"]).unwrap();
    assert_eq!(text(&ds, map, "tiles"), "");
    assert!(matches!(tile(&ds, 0, 0, 0), CallOutcome::Refused(_)));
}

#[test]
fn stopping_the_module_removes_root_map() {
    let spec = ModuleSpec::new("map").with(
        "overlays",
        toml::Value::Array(vec![harbour().to_string_lossy().into_owned().into()]),
    );
    let (ds, mut host) = host(spec);
    assert!(ds.resolve(&["map", "features"]).is_some());
    host.stop_all();
    assert!(ds.resolve(&["map"]).is_none());
}
