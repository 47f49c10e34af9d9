//! Templates that flow (`for each … flow down rect … gap …`): the runtime places the
//! instances' windows one after another in the region, wraps, hides those that do not fit
//! and says "+N more" (docs/language.md, "Per-vehicle templates"), at every screen size and
//! as vehicles come and go.
mod common;
use common::program;
use mocu_dataserver::*;
use mocu_layout::*;
use mocu_value::Value;
use std::sync::Arc;
use std::time::Duration;

/// What an engineer might write: strips down the left edge, no visibility of their own.
const STRIPS: &str = r#"
use "stdlib/gauges.mocu"
design 1280 x 720
for each v in root.vehicles of type "usv" flow down rect 20 20 400 62% gap 8 {
  window strip { layer 30  rect 0 0 400 92 }
  in strip { speed: TextGauge { at 8 28 200 26  label "SPD"  value v.nav.speed } }
}
"#;

const SCREENS: [(f64, f64); 5] =
    [(800.0, 480.0), (1280.0, 720.0), (1920.0, 1080.0), (1920.0, 1200.0), (3840.0, 2160.0)];

fn load(text: &str, screen: (f64, f64)) -> (DataServer, Layout) {
    let ds = DataServer::default();
    let config = LayoutConfig {
        screen,
        tick: Duration::from_millis(1),
        alert_layer: false,
        ..LayoutConfig::default()
    };
    let layout = Layout::load(&ds, &program(text), config, Arc::new(NullSink)).unwrap();
    layout.settle();
    (ds, layout)
}

fn add(ds: &DataServer, name: &str, ty: &str) {
    let vs = match ds.resolve(&["vehicles"]) {
        Some(g) => g,
        None => ds.create_object(Guid::ROOT, ObjectInfo::new("vehicles", "folder")).unwrap(),
    };
    ds.create_object(vs, ObjectInfo::new(name, ty)).unwrap();
}

fn num(ds: &DataServer, g: Guid, k: &str) -> f64 {
    ds.get(g, k).ok().and_then(|v| v.as_f64()).unwrap_or(f64::NAN)
}

/// The shown windows under `root.display` whose names start with `prefix`: name and rect.
fn shown(ds: &DataServer, prefix: &str) -> Vec<(String, [f64; 4])> {
    let display = ds.resolve(&["display"]).unwrap();
    let mut out = Vec::new();
    for g in ds.children(display).unwrap() {
        let name = ds.info(g).unwrap().name.to_string();
        if name.starts_with(prefix) && ds.get(g, "visible").ok() == Some(Value::Bool(true)) {
            out.push((name, ["x", "y", "w", "h"].map(|k| num(ds, g, k))));
        }
    }
    out
}

fn overlap(a: [f64; 4], b: [f64; 4]) -> bool {
    a[0] < b[0] + b[2] && b[0] < a[0] + a[2] && a[1] < b[1] + b[3] && b[1] < a[1] + a[3]
}

fn inside(a: [f64; 4], r: [f64; 4]) -> bool {
    let e = 1e-6;
    a[0] >= r[0] - e
        && a[1] >= r[1] - e
        && a[0] + a[2] <= r[0] + r[2] + e
        && a[1] + a[3] <= r[1] + r[3] + e
}

/// The "+N more" window: N, and its rect when shown.
fn more(ds: &DataServer, name: &str) -> (i64, Option<[f64; 4]>) {
    let g = ds.resolve(&["display", name]).expect("the flow publishes its label window");
    let n = ds.get(g, "more").ok().and_then(|v| v.as_i64()).unwrap_or(-1);
    let shown = ds.get(g, "visible").ok() == Some(Value::Bool(true));
    (n, shown.then(|| ["x", "y", "w", "h"].map(|k| num(ds, g, k))))
}

/// No two shown strips overlap, all lie in the region, the label too, and every USV is
/// either shown or counted.
fn check(ds: &DataServer, region: [f64; 4], usvs: usize, what: &str) -> usize {
    let strips = shown(ds, "strip@");
    for (i, (a, ra)) in strips.iter().enumerate() {
        assert!(inside(*ra, region), "{what}: {a} {ra:?} leaves the region {region:?}");
        for (b, rb) in &strips[i + 1..] {
            assert!(!overlap(*ra, *rb), "{what}: {a} {ra:?} overlaps {b} {rb:?}");
        }
    }
    let (n, label) = more(ds, "strip+more");
    assert_eq!(strips.len() + n as usize, usvs, "{what}: shown + more = every USV");
    assert_eq!(label.is_some(), n > 0, "{what}: the label shows when some are hidden");
    if let Some(l) = label {
        assert!(inside(l, region), "{what}: the label {l:?} leaves the region");
        assert!(strips.iter().all(|(_, r)| !overlap(*r, l)), "{what}: the label covers a strip");
    }
    strips.len()
}

#[test]
fn eight_usvs_flow_down_the_region_without_overlap_and_the_rest_are_counted() {
    for (w, h) in SCREENS {
        let (ds, layout) = load(STRIPS, (w, h));
        let s = (w / 1280.0).min(h / 720.0);
        let region = [20.0 * s, 20.0 * s, 400.0 * s, 0.62 * h];
        add(&ds, "uav1", "uav"); // not a USV: no strip
        for n in 1..=8 {
            add(&ds, &format!("usv{n}"), "usv");
            layout.settle();
            check(&ds, region, n, &format!("{w}x{h}, {n} USVs"));
        }
        let fits = check(&ds, region, 8, &format!("{w}x{h}"));
        assert!(fits >= 3, "{w}x{h}: only {fits} strips shown");
        if (w, h) == (1280.0, 720.0) {
            // 446 px: four strips of 92 with gaps of 8, then the label; the first at the top.
            assert_eq!(fits, 4);
            assert_eq!(more(&ds, "strip+more").0, 4);
            let first = ds.resolve(&["display", "strip@usv1"]).unwrap();
            assert_eq!((num(&ds, first, "x"), num(&ds, first, "y")), (20.0, 20.0));
            let fourth = ds.resolve(&["display", "strip@usv4"]).unwrap();
            assert_eq!(num(&ds, fourth, "y"), 320.0);
        }
    }
}

#[test]
fn a_vehicle_going_away_moves_the_others_up_and_the_count_follows() {
    let (ds, layout) = load(STRIPS, (1280.0, 720.0));
    let region = [20.0, 20.0, 400.0, 0.62 * 720.0];
    for n in 1..=8 {
        add(&ds, &format!("usv{n}"), "usv");
    }
    layout.settle();
    assert_eq!(check(&ds, region, 8, "8 USVs"), 4);
    let y = |name: &str| num(&ds, ds.resolve(&["display", name]).unwrap(), "y");
    assert_eq!(y("strip@usv2"), 120.0);
    let hidden = ds.resolve(&["display", "strip@usv5"]).unwrap();
    assert_eq!(ds.get(hidden, "visible").unwrap(), Value::Bool(false));

    ds.delete_object(ds.resolve(&["vehicles", "usv1"]).unwrap()).unwrap();
    layout.settle();
    assert_eq!(check(&ds, region, 7, "usv1 gone"), 4);
    assert_eq!(y("strip@usv2"), 20.0, "the second moves up to the top");
    assert_eq!(y("strip@usv5"), 320.0, "the fifth is shown now, fourth in the column");
    assert_eq!(more(&ds, "strip+more").0, 3);

    for n in 2..=4 {
        ds.delete_object(ds.resolve(&["vehicles", &format!("usv{n}")]).unwrap()).unwrap();
    }
    layout.settle();
    assert_eq!(check(&ds, region, 4, "four left"), 4);
    assert_eq!(more(&ds, "strip+more"), (0, None), "all fit: no label");
    assert_eq!(y("strip@usv5"), 20.0);
}

/// Tiles along the bottom edge, wrapping to the next row; a tile hidden by its own
/// `visible` takes no room.
const TILES: &str = r#"
design 1280 x 720
for each v in root.vehicles flow right rect 0 8 100% 230 anchor bottom gap 10 {
  window tile { layer 5  rect 0 0 300 100  visible !(v.parked ?? false) }
}
"#;

#[test]
fn a_row_wraps_to_the_next_and_a_hidden_instance_takes_no_room() {
    let (ds, layout) = load(TILES, (1280.0, 720.0));
    for n in 1..=10 {
        add(&ds, &format!("v{n}"), "usv");
    }
    layout.settle();
    // 1280 wide: four tiles of 300 with gaps of 10 per row (1230), two rows in 230 px.
    let region = [0.0, 720.0 - 8.0 - 230.0, 1280.0, 230.0];
    let tiles = shown(&ds, "tile@");
    let x = |name: &str| {
        let g = ds.resolve(&["display", name]).unwrap();
        (num(&ds, g, "x"), num(&ds, g, "y"))
    };
    assert_eq!(x("tile@v1"), (0.0, region[1]));
    assert_eq!(x("tile@v5"), (0.0, region[1] + 110.0), "the fifth starts the second row");
    // Two rows of four, the label after the seventh: seven shown, three counted.
    assert_eq!(tiles.len(), 7);
    let (n, label) = more(&ds, "tile+more");
    assert_eq!(n, 3);
    assert!(inside(label.unwrap(), region));

    let v2 = ds.resolve(&["vehicles", "v2"]).unwrap();
    ds.set(v2, "parked", Value::Bool(true)).unwrap();
    layout.settle();
    assert_eq!(x("tile@v3"), (310.0, region[1]), "the third takes the parked one's place");
    let hidden = ds.resolve(&["display", "tile@v2"]).unwrap();
    assert_eq!(ds.get(hidden, "visible").unwrap(), Value::Bool(false));
    assert_eq!(more(&ds, "tile+more").0, 2, "the parked one is not counted");
}

#[test]
fn a_reloaded_flow_is_placed_anew_and_an_unloaded_one_leaves_nothing() {
    let (ds, layout) = load(STRIPS, (1280.0, 720.0));
    for n in 1..=8 {
        add(&ds, &format!("usv{n}"), "usv");
    }
    layout.settle();
    assert_eq!(more(&ds, "strip+more").0, 4);
    // About half the height: two strips and the label (2 × 100 + 24 ≤ 230).
    let half = STRIPS.replace("62% gap 8", "32% gap 8");
    layout.reload(&program(&half)).unwrap();
    layout.settle();
    assert_eq!(check(&ds, [20.0, 20.0, 400.0, 0.32 * 720.0], 8, "reloaded"), 2);
    let display = ds.resolve(&["display"]).unwrap();
    let labels = |ds: &DataServer| {
        let names = ds.children(display).unwrap().into_iter().map(|g| ds.info(g).unwrap().name);
        names.filter(|n| n.ends_with("+more")).count()
    };
    assert_eq!(labels(&ds), 1, "one label window");
    layout.unload();
    assert_eq!(labels(&ds), 0);
    assert!(ds.children(display).unwrap().is_empty(), "nothing of the layout left");
}
