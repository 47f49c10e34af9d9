//! A project's own map view: `plot_map` takes the place of the core `map_view` module (the
//! stock map painter). It claims every `map` window of `root.display` and draws the fleet as
//! a plot: a grid, and one dot per vehicle of `root.vehicles` at its `nav.x`/`nav.y`, the
//! view fitted to the fleet; it repaints when a vehicle moves. It sees only the display's
//! `Canvas` and the world model, as every painter does, and is registered beside the stock
//! kinds, as a project would in its own build of `mocu`, then chosen in the profile:
//!
//! ```toml
//! [modules.map_view]     # the role: the stock map view is not started
//! kind = "plot_map"
//! grid_m = 50            # its own settings
//! ```
//!
//! ```sh
//! cargo run --example own_map_view -- plot.png    # the simulator's fleet, plotted
//! ```

use mocu_dataserver::{
    Clock as _, Config, DataServer, Guid, Kind, ManualClock, Notification, ObjectInfo, PathWatch,
    Subject, SubscriptionId, Topic, Value,
};
use mocu_display::{BackendChoice, Canvas, Color, Display, DisplayOptions, PaintArgs, Point};
use mocu_host::{Module, ModuleContext, ModuleHost, ModuleSpec, Registry};
use mocu_language::modules::{ModuleKind, Setting, SettingType};
use std::sync::{Arc, Mutex};
use std::time::Duration;

const BACKGROUND: Color = Color::rgb(0x0c, 0x2a, 0x1e);
const GRID: Color = Color::rgb(0x1f, 0x4d, 0x3a);
const VEHICLE: Color = Color::rgb(0xff, 0xb0, 0x00);

/// The module: its setting, and what it holds while it runs.
struct PlotMap {
    grid_m: f64,
    state: Arc<Mutex<State>>,
}

#[derive(Default)]
struct State {
    ds: Option<DataServer>,
    /// The map windows it claimed.
    windows: Vec<Guid>,
    subs: Vec<SubscriptionId>,
    watches: Vec<PathWatch>,
    stopped: bool,
}

impl PlotMap {
    fn new(spec: &ModuleSpec) -> Result<PlotMap, String> {
        let grid_m = spec.f64_or("grid_m", 100.0).map_err(|e| e.to_string())?;
        if grid_m.is_nan() || grid_m < 1.0 {
            return Err(format!("`grid_m` must be at least 1 m, got {grid_m}"));
        }
        Ok(PlotMap { grid_m, state: Arc::default() })
    }
}

/// Every vehicle's position (metres east and north of the origin) and name.
fn positions(ds: &DataServer) -> Vec<(f64, f64)> {
    let Some(vehicles) = ds.resolve(&["vehicles"]) else { return Vec::new() };
    let num = |g: Guid, p: &str| ds.try_get(g, p.into()).and_then(|v| v.as_f64());
    ds.children(vehicles)
        .unwrap_or_default()
        .into_iter()
        .filter_map(|v| ds.find_child(v, "nav").ok().flatten())
        .filter_map(|nav| Some((num(nav, "x")?, num(nav, "y")?)))
        .collect()
}

/// Draws the plot: the view fits the fleet (at least 4 grid squares across), north up.
fn paint(ds: &DataServer, grid_m: f64, c: &mut dyn Canvas, a: &PaintArgs) {
    let (w, h) = (f64::from(a.size.w), f64::from(a.size.h));
    c.clear(BACKGROUND);
    let fleet = positions(ds);
    let (mut x0, mut x1, mut y0, mut y1) = (0.0f64, 0.0f64, 0.0f64, 0.0f64);
    for (x, y) in &fleet {
        (x0, x1, y0, y1) = (x0.min(*x), x1.max(*x), y0.min(*y), y1.max(*y));
    }
    let span = ((x1 - x0).max(y1 - y0) * 1.2).max(4.0 * grid_m);
    let scale = w.min(h) / span;
    let (cx, cy) = ((x0 + x1) / 2.0, (y0 + y1) / 2.0);
    let to_px = |x: f64, y: f64| {
        Point::new((w / 2.0 + (x - cx) * scale) as f32, (h / 2.0 - (y - cy) * scale) as f32)
    };
    let first = |lo: f64| (lo / grid_m).floor() * grid_m;
    let mut gx = first(cx - w / scale / 2.0);
    while gx <= cx + w / scale / 2.0 {
        c.line(to_px(gx, cy - h / scale), to_px(gx, cy + h / scale), 1.0, GRID);
        gx += grid_m;
    }
    let mut gy = first(cy - h / scale / 2.0);
    while gy <= cy + h / scale / 2.0 {
        c.line(to_px(cx - w / scale, gy), to_px(cx + w / scale, gy), 1.0, GRID);
        gy += grid_m;
    }
    for (x, y) in fleet {
        c.fill_circle(to_px(x, y), 5.0, VEHICLE);
    }
}

impl State {
    /// Repaints every claimed window at the next frame.
    fn invalidate(&self) {
        if let Some(ds) = &self.ds {
            for w in &self.windows {
                let _ = mocu_display::invalidate(ds, *w);
            }
        }
    }
}

impl Module for PlotMap {
    fn start(&mut self, ctx: &ModuleContext) -> Result<(), String> {
        let ds = ctx.ds.clone();
        self.state.lock().unwrap().ds = Some(ds.clone());
        let display = ds.resolve(&["display"]).ok_or("no root.display to draw on")?;
        // Claims each map window, now and as the layout publishes them.
        let (state, grid_m, ds2) = (self.state.clone(), self.grid_m, ds.clone());
        let on_window = move |n: &Notification| {
            let Subject::Child { guid, .. } = &n.subject else { return };
            let is_map = ds2.info(*guid).is_ok_and(|i| &*i.subtype == "map");
            if n.kind != Kind::New || !is_map || state.lock().unwrap().stopped {
                return;
            }
            let ds3 = ds2.clone();
            let painter = move |c: &mut dyn Canvas, a: &PaintArgs| paint(&ds3, grid_m, c, a);
            if mocu_display::claim_window(&ds2, *guid, painter).is_ok() {
                state.lock().unwrap().windows.push(*guid);
            }
        };
        let sub = ds.subscribe_on(&ctx.executor, Topic::children(display), on_window);
        self.state.lock().unwrap().subs.push(sub.map_err(|e| e.to_string())?);
        // Repaints when a vehicle moves: root.vehicles, then each vehicle's `nav`, then its
        // `x` and `y`, all followed as they appear, on this module's executor.
        let (state, exec, ds2) = (self.state.clone(), ctx.executor.clone(), ds.clone());
        let on_folder = move |e: &mocu_dataserver::PathEvent| {
            if e.kind != Kind::New {
                return;
            }
            let (state2, exec2, ds3) = (state.clone(), exec.clone(), ds2.clone());
            let on_vehicle = move |n: &Notification| {
                let Subject::Child { guid, .. } = &n.subject else { return };
                if n.kind != Kind::New {
                    return;
                }
                let (state3, exec3, ds4) = (state2.clone(), exec2.clone(), ds3.clone());
                let on_nav = move |e: &mocu_dataserver::PathEvent| {
                    if e.kind != Kind::New {
                        return;
                    }
                    let state4 = state3.clone();
                    let moved = move |_: &Notification| state4.lock().unwrap().invalidate();
                    let topic = Topic::property_names(e.object, &["x", "y"]);
                    if let Ok(s) = ds4.subscribe_on(&exec3, topic, moved) {
                        state3.lock().unwrap().subs.push(s);
                    }
                };
                if let Ok(w) = ds3.watch_object(*guid, &["nav"], Some(&exec2), on_nav) {
                    state2.lock().unwrap().watches.push(w);
                }
            };
            if let Ok(s) = ds2.subscribe_on(&exec, Topic::children(e.object), on_vehicle) {
                state.lock().unwrap().subs.push(s);
            }
        };
        let watch = ds.watch_object(ds.root(), &["vehicles"], Some(&ctx.executor), on_folder);
        self.state.lock().unwrap().watches.push(watch.map_err(|e| e.to_string())?);
        Ok(())
    }

    /// Ends the watches and subscriptions with the lock released (ending one waits for its
    /// running callback, which may take the lock).
    fn stop(&mut self) {
        let (watches, subs, ds) = {
            let mut st = self.state.lock().unwrap();
            st.stopped = true;
            (std::mem::take(&mut st.watches), std::mem::take(&mut st.subs), st.ds.clone())
        };
        drop(watches);
        if let Some(ds) = ds {
            for s in subs {
                ds.unsubscribe(s);
            }
        }
    }
}

/// What the checker knows of `plot_map` (`mocu check` of this project's build): a profile
/// naming it is checked against these settings, as the stock kinds' are.
const PLOT_MAP: ModuleKind = ModuleKind {
    kind: "plot_map",
    description: "The project's map view: the fleet as a plot",
    settings: &[Setting::new("grid_m", SettingType::Number, "100", "Grid spacing, in metres")],
};

/// The stock kinds of the display (`widgets`, `map_view`, `video_windows`), the simulator,
/// and this project's `plot_map`, declared to the checker too.
fn registry() -> Registry {
    let mut r = Registry::new();
    mocu_sim::register(&mut r);
    mocu_video::register(&mut r);
    mocu_widgets::register(&mut r, mocu_widgets::Components::default());
    r.register("plot_map", |spec| Ok(Box::new(PlotMap::new(spec)?) as Box<dyn Module>));
    mocu_language::modules::declare(PLOT_MAP);
    r
}

/// The display's roles, filled by the profile or by their stock kinds.
const DISPLAY_ROLES: &[&str] = &["widgets", "map_view", "video_windows"];

/// The project's profile: the simulator, and its own map view in the `map_view` role.
const PROFILE: &str = r#"
[modules.sim]
vehicles = ["usv1", "usv2"]
seed = 7
appear_every = 0.0

[modules.map_view]
kind = "plot_map"
grid_m = 50
"#;

/// The modules a profile's `[modules.NAME]` tables name, with the display's roles filled.
fn specs(profile: &str) -> Vec<ModuleSpec> {
    let table: toml::Table = profile.parse().expect("the profile is TOML");
    let mut specs = Vec::new();
    if let Some(toml::Value::Table(modules)) = table.get("modules") {
        for (name, settings) in modules {
            let mut t = settings.as_table().cloned().unwrap_or_default();
            t.insert("name".into(), name.clone().into());
            specs.push(ModuleSpec::from_table(&t).expect("a module table"));
        }
    }
    mocu_host::fill_roles(&mut specs, DISPLAY_ROLES);
    // The display's modules last, in role order (`mocu run` does the same).
    specs.sort_by_key(|s| DISPLAY_ROLES.iter().position(|r| s.name == *r || s.kind == *r));
    specs
}

/// An OCU on a clock the caller moves: the profile's modules and a 320x200 display with one
/// map window, as a layout would publish it.
struct Ocu {
    ds: DataServer,
    clock: ManualClock,
    host: ModuleHost,
    display: Display,
}

impl Ocu {
    fn start(profile: &str) -> Ocu {
        let clock = ManualClock::new();
        let ds = DataServer::with_clock(Config { workers: 2 }, Arc::new(clock.clone()));
        let root_display = mocu_display::ensure_display_object(&ds, 320, 200).unwrap();
        let mut host = ModuleHost::new(ds.clone(), registry());
        let errors = host.start_all(&specs(profile));
        assert!(errors.is_empty(), "{errors:?}");
        let opts = DisplayOptions::new(320, 200).backend(BackendChoice::Cpu);
        let display = Display::new(&ds, opts.clock(mocu_display::Clock::manual())).unwrap();
        let info = ObjectInfo::new("chart", mocu_display::WINDOW_TYPE).subtype("map");
        let chart = ds.create_object(root_display, info).unwrap();
        ds.set(chart, "layer", Value::Int(1)).unwrap();
        Ocu { ds, clock, host, display }
    }

    /// Runs `seconds` of simulated time, then draws.
    fn run(&mut self, seconds: u64) -> tiny_skia::Pixmap {
        self.ds.advance_settled(&self.clock, self.clock.now() + Duration::from_secs(seconds));
        for _ in 0..3 {
            self.ds.quiesce();
            self.display.frame();
        }
        self.display.read_frame()
    }

    /// The running modules: (name, kind), in start order.
    fn modules(&self) -> Vec<(String, String)> {
        let kind = |n: &str| {
            let g = self.ds.resolve(&["modules", n]).unwrap();
            self.ds.try_get(g, "kind".into()).and_then(|v| v.as_str().map(str::to_string))
        };
        self.host.running().into_iter().map(|n| (kind(&n).unwrap_or_default(), n)).collect()
    }
}

fn main() {
    let out = std::env::args().nth(1).unwrap_or_else(|| "plot_map.png".into());
    let mut ocu = Ocu::start(PROFILE);
    ocu.run(5);
    for (kind, name) in ocu.modules() {
        println!("module {name} ({kind})");
    }
    match ocu.display.screenshot(std::path::Path::new(&out)) {
        Ok(()) => println!("the map window, drawn by plot_map: {out}"),
        Err(e) => eprintln!("own_map_view: {e}"),
    }
    ocu.host.stop_all();
}

#[cfg(test)]
mod tests {
    use super::*;

    fn is(p: &tiny_skia::Pixmap, x: u32, y: u32, c: Color) -> bool {
        let px = p.pixel(x, y).unwrap().demultiply();
        let want = [c.r, c.g, c.b];
        [px.red(), px.green(), px.blue()].iter().zip(want).all(|(a, b)| a.abs_diff(b) <= 2)
    }

    fn count(p: &tiny_skia::Pixmap, c: Color) -> usize {
        (0..p.height())
            .flat_map(|y| (0..p.width()).map(move |x| (x, y)))
            .filter(|(x, y)| is(p, *x, *y, c))
            .count()
    }

    #[test]
    fn the_profile_s_own_map_view_paints_the_map_window_and_the_stock_one_is_not_started() {
        let mut ocu = Ocu::start(PROFILE);
        let frame = ocu.run(3);
        let running = ocu.modules();
        let kinds: Vec<&str> = running.iter().map(|(k, _)| k.as_str()).collect();
        assert_eq!(kinds, ["sim", "widgets", "plot_map", "video_windows"], "{running:?}");
        assert!(running.contains(&("plot_map".into(), "map_view".into())));
        // Its plot fills the window: its background, and a dot for each of the two vehicles.
        assert!(is(&frame, 2, 2, BACKGROUND));
        let dots = count(&frame, VEHICLE);
        assert!(dots > 100, "two vehicle dots: {dots} px");
        // It follows the fleet: the vehicles move, the plot is drawn again.
        let later = ocu.run(20);
        assert_ne!(later.data(), frame.data(), "the plot did not follow the vehicles");
        ocu.host.stop_all();

        // Without the profile's choice, the stock map view paints the same window.
        let stock = PROFILE.replace("kind = \"plot_map\"\ngrid_m = 50\n", "");
        let mut ocu = Ocu::start(&stock);
        let frame = ocu.run(3);
        assert!(ocu.modules().contains(&("map_view".into(), "map_view".into())));
        assert!(!is(&frame, 2, 2, BACKGROUND));
        ocu.host.stop_all();
    }

    /// `PROFILE` with `modules` instead of its modules, and a layout, as files.
    fn project(dir: &std::path::Path, profile: &str) -> std::path::PathBuf {
        std::fs::write(dir.join("chart.mocu"), "window chart {\n    type \"map\"\n}\n").unwrap();
        let text = format!("[profile]\nname = \"plot\"\nlayouts = [\"chart.mocu\"]\n{profile}");
        std::fs::write(dir.join("project.toml"), text).unwrap();
        dir.join("project.toml")
    }

    #[test]
    fn the_checker_knows_the_declared_kind_and_refuses_a_typo_in_its_settings() {
        let _ = registry();
        let dir = tempfile::tempdir().unwrap();
        let loaded = mocu_language::load_target(&project(dir.path(), PROFILE));
        assert!(loaded.is_ok(), "the profile checks clean");
        let typo = PROFILE.replace("grid_m", "grid_n");
        match mocu_language::load_target(&project(dir.path(), &typo)) {
            Err(mocu_language::LoadError::Diagnostics { rendered, .. }) => {
                assert!(rendered.contains("the plot_map module has no setting `grid_n`"));
                assert!(rendered.contains("did you mean `grid_m`?"), "{rendered}");
            }
            _ => panic!("a typo in plot_map's settings was not refused"),
        }
    }

    #[test]
    fn a_bad_setting_is_refused_with_the_reason() {
        let spec = ModuleSpec::new("plot_map").named("map_view").with("grid_m", 0.5);
        let mut host = ModuleHost::new(DataServer::default(), registry());
        let err = host.start(&spec).unwrap_err().to_string();
        assert!(err.contains("`grid_m` must be at least 1 m"), "{err}");
    }
}
