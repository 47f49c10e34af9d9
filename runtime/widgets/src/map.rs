//! The map module: claims windows of subtype `map` and draws a chart in Web Mercator
//! (`view.rs`): the raster tiles and GeoJSON overlays the `map` module (mocu-mapdata)
//! publishes under `root.map` (`tiles.rs`, `chart.rs`), and over them every vehicle under
//! `root.vehicles`, placed by latitude/longitude (or its local `x`, `y` from the origin in
//! `root.map`), with its type's symbol, heading, trail, routes and name (`symbols.rs`).
//! The Map widget's `follow` centres the view on a vehicle, its `zoom` sets the level.
//! docs/map.md.
//!
//! Pointer (routed by the window manager through transparent layers above): a left press
//! on a vehicle symbol selects it (`root.operator.selected`); elsewhere it raises the
//! `select` event of the `Map` widget placed in the window (fig. 1: the small map swaps
//! into the large place). A right press on a symbol opens the layout's context menu for
//! the vehicle's type. `symbols()` answers `[name, x, y, …]` in window pixels.
//!
//! Symbols, labels and lines grow with the layout's design scale (`root.display.scale`,
//! never below 1), like the widgets around the map, but not with the window: a larger map
//! window shows more ground.

mod chart;
mod edit;
mod symbols;
mod tiles;
pub mod view;

use mocu_dataserver::{
    CallOutcome, DataServer, DottedPath, Executor, Kind, MethodSpec, Notification, PathWatch,
    Subject, SubscriptionId, Topic,
};
use mocu_display::{
    Brush, Canvas, Coalesced, Color, PaintArgs, Point, Rect, Stroke, claim_window, invalidate,
};
use mocu_value::{Guid, PropName, Value};
use parking_lot::Mutex;
use std::collections::HashMap;
use std::sync::Arc;
use symbols::{Labels, VehicleType};
use tiles::TileCache;
use view::View;

pub struct MapModule {
    shared: Arc<Shared>,
}

struct Shared {
    ds: DataServer,
    exec: Executor,
    state: Mutex<State>,
    tiles: Arc<TileCache>,
    /// Itself, for the jobs it queues.
    me: std::sync::Weak<Shared>,
    /// The map windows' invalidation ([`Shared::repaint`]).
    repaint: Coalesced,
}

#[derive(Default)]
struct State {
    /// The module is stopping: callbacks still running add nothing.
    closed: bool,
    subs: Vec<SubscriptionId>,
    vehicles_watch: Option<PathWatch>,
    vehicles_sub: Option<SubscriptionId>,
    maps: Vec<Guid>,
    /// Where each map window last drew each vehicle (window-local px).
    symbols: HashMap<Guid, Vec<(Guid, String, Point)>>,
    /// What each map window showed last.
    views: HashMap<Guid, View>,
    /// Each vehicle's past positions (latitude, longitude), oldest first.
    trails: HashMap<Guid, Vec<(f64, f64)>>,
    per_vehicle: HashMap<Guid, Vec<PathWatch>>,
    /// `root.map.features`: the chart is drawn again when its features come or go.
    features_watch: Option<PathWatch>,
    features_sub: Option<SubscriptionId>,
    features: chart::FeatureCache,
    /// Where each window drew each route's waypoints, for editing.
    waypoints: HashMap<Guid, edit::Drawn>,
    /// The waypoint being dragged, and in which window.
    drag: Option<(Guid, Guid)>,
}

impl MapModule {
    pub fn start(ds: &DataServer) -> Result<MapModule, String> {
        let display =
            mocu_display::ensure_display_object(ds, 1920, 1080).map_err(|e| e.to_string())?;
        let shared = Arc::new_cyclic(|me| Shared {
            ds: ds.clone(),
            exec: ds.serial_executor(),
            state: Mutex::default(),
            tiles: Arc::default(),
            me: me.clone(),
            repaint: Coalesced::default(),
        });
        let weak = Arc::downgrade(&shared);
        let sub = ds
            .subscribe_on(&shared.exec, Topic::children(display), move |n: &Notification| {
                if let (Some(sh), Subject::Child { guid, .. }) = (weak.upgrade(), &n.subject) {
                    sh.on_window(n.kind, *guid);
                }
            })
            .map_err(|e| e.to_string())?;
        let weak = Arc::downgrade(&shared);
        let watch = ds
            .watch_object(Guid::ROOT, &["vehicles"], Some(&shared.exec), move |e| {
                if let Some(sh) = weak.upgrade() {
                    sh.on_vehicles_folder((e.kind != Kind::Deleted).then_some(e.object));
                }
            })
            .map_err(|e| e.to_string())?;
        let weak = Arc::downgrade(&shared);
        let features = ds
            .watch_object(Guid::ROOT, &["map", "features"], Some(&shared.exec), move |e| {
                if let Some(sh) = weak.upgrade() {
                    sh.on_features_folder((e.kind != Kind::Deleted).then_some(e.object));
                }
            })
            .map_err(|e| e.to_string())?;
        {
            let mut st = shared.state.lock();
            st.subs.push(sub);
            st.vehicles_watch = Some(watch);
            st.features_watch = Some(features);
        }
        Ok(MapModule { shared })
    }
}

impl Drop for MapModule {
    /// Collects under the lock, then ends with it released: ending a watch or a
    /// subscription waits for its running callback, and the callbacks take `state`
    /// (dropping the watches under the lock deadlocked about one exit in 45).
    fn drop(&mut self) {
        let (watches, subs, maps) = {
            let mut st = self.shared.state.lock();
            st.closed = true;
            let mut watches: Vec<PathWatch> = st.vehicles_watch.take().into_iter().collect();
            watches.extend(st.features_watch.take());
            watches.extend(st.per_vehicle.drain().flat_map(|(_, w)| w));
            let mut subs = std::mem::take(&mut st.subs);
            subs.extend(st.vehicles_sub.take());
            subs.extend(st.features_sub.take());
            (watches, subs, std::mem::take(&mut st.maps))
        };
        drop(watches);
        for s in subs {
            self.shared.ds.unsubscribe(s);
        }
        // Whatever a callback that was running added meanwhile (none can run any more).
        let (late_watches, late_subs) = {
            let mut st = self.shared.state.lock();
            let subs: Vec<SubscriptionId> =
                st.vehicles_sub.take().into_iter().chain(st.features_sub.take()).collect();
            (std::mem::take(&mut st.per_vehicle), subs)
        };
        drop(late_watches);
        for s in late_subs {
            self.shared.ds.unsubscribe(s);
        }
        for m in maps {
            for name in ["paint", "pointer", "symbols", "waypoints"] {
                let _ = self.shared.ds.unpublish_method(m, name);
            }
        }
    }
}

impl Shared {
    fn on_window(self: &Arc<Self>, kind: Kind, g: Guid) {
        let is_map = self.ds.info(g).is_ok_and(|i| &*i.subtype == "map");
        match kind {
            Kind::New if is_map => {
                let weak = Arc::downgrade(self);
                let ok = claim_window(&self.ds, g, move |c: &mut dyn Canvas, a: &PaintArgs| {
                    if let Some(sh) = weak.upgrade() {
                        sh.paint(g, c, a);
                    }
                });
                if ok.is_ok() {
                    let mut st = self.state.lock();
                    if st.closed {
                        return;
                    }
                    st.maps.push(g);
                    drop(st);
                    self.publish_input(g);
                }
            }
            Kind::Deleted => {
                let mut st = self.state.lock();
                st.maps.retain(|m| *m != g);
                st.symbols.remove(&g);
                st.views.remove(&g);
                st.waypoints.remove(&g);
            }
            _ => {}
        }
    }

    fn on_vehicles_folder(self: &Arc<Self>, folder: Option<Guid>) {
        let (old, watches) = {
            let mut st = self.state.lock();
            (st.vehicles_sub.take(), std::mem::take(&mut st.per_vehicle))
        };
        // Ended with the lock released (their callbacks take it).
        if let Some(s) = old {
            self.ds.unsubscribe(s);
        }
        drop(watches);
        if let Some(f) = folder {
            let weak = Arc::downgrade(self);
            let sub =
                self.ds.subscribe_on(&self.exec, Topic::children(f), move |n: &Notification| {
                    if let (Some(sh), Subject::Child { guid, .. }) = (weak.upgrade(), &n.subject) {
                        sh.on_vehicle(n.kind, *guid);
                    }
                });
            let mut st = self.state.lock();
            if st.closed {
                drop(st);
                if let Ok(s) = sub {
                    self.ds.unsubscribe(s);
                }
                return;
            }
            st.vehicles_sub = sub.ok();
        }
        self.repaint();
    }

    fn on_features_folder(self: &Arc<Self>, folder: Option<Guid>) {
        let old = self.state.lock().features_sub.take();
        if let Some(s) = old {
            self.ds.unsubscribe(s); // with the lock released: its callback takes it
        }
        if let Some(f) = folder {
            let weak = Arc::downgrade(self);
            let sub =
                self.ds.subscribe_on(&self.exec, Topic::children(f), move |_: &Notification| {
                    if let Some(sh) = weak.upgrade() {
                        sh.repaint();
                    }
                });
            let mut st = self.state.lock();
            if st.closed {
                drop(st);
                if let Ok(s) = sub {
                    self.ds.unsubscribe(s);
                }
                return;
            }
            st.features_sub = sub.ok();
        }
        self.repaint();
    }

    fn on_vehicle(self: &Arc<Self>, kind: Kind, v: Guid) {
        match kind {
            Kind::New => {
                let mut watches = Vec::new();
                for p in [
                    "nav.x",
                    "nav.y",
                    "nav.heading",
                    "nav.lat",
                    "nav.lon",
                    "control",
                    "route",
                    "route_next",
                    "stale",
                ] {
                    let weak = Arc::downgrade(self);
                    if let Ok(path) = DottedPath::parse(p)
                        && let Ok(w) =
                            self.ds.watch_path_from(v, path, Some(&self.exec), move |_| {
                                if let Some(sh) = weak.upgrade() {
                                    sh.repaint();
                                }
                            })
                    {
                        watches.push(w);
                    }
                }
                let mut st = self.state.lock();
                if st.closed {
                    drop(st);
                    drop(watches); // ended with the lock released
                    return;
                }
                let old = st.per_vehicle.insert(v, watches);
                drop(st);
                drop(old);
            }
            Kind::Deleted => {
                let old = self.state.lock().per_vehicle.remove(&v);
                drop(old); // ended with the lock released
            }
            Kind::Changed => {}
        }
        self.repaint();
    }

    /// Asks for the map windows to be drawn again: their `revision` moves once, in a job
    /// queued on the module's executor behind the changes that asked ([`Coalesced`]). A
    /// fleet at 100 Hz asks tens of thousands of times a second (each vehicle's position,
    /// heading, route…).
    fn repaint(&self) {
        let me = self.me.clone();
        self.repaint.ask(&self.exec, move || {
            let Some(sh) = me.upgrade() else { return };
            let maps = sh.state.lock().maps.clone();
            for m in maps {
                let _ = invalidate(&sh.ds, m);
            }
        });
    }

    fn publish_input(self: &Arc<Self>, g: Guid) {
        let weak = Arc::downgrade(self);
        let spec = mocu_display::pointer_spec();
        let _ = self.ds.publish_method_fn(g, spec, move |args| {
            let Some(sh) = weak.upgrade() else {
                return CallOutcome::Failed("map stopped".into());
            };
            let p = Point::new(
                args[2].as_f64().unwrap_or(0.0) as f32,
                args[3].as_f64().unwrap_or(0.0) as f32,
            );
            let (kind, button) = (args[0].as_str().unwrap_or(""), args[1].as_i64().unwrap_or(-1));
            if !sh.edit(g, kind, button, p) && kind == "down" {
                sh.press(g, button, p);
            }
            CallOutcome::Accepted(vec![])
        });
        let weak = Arc::downgrade(self);
        let spec = MethodSpec::new("waypoints")
            .describe("Where the map drew each route's waypoints: [route path, index, x, y, …]");
        let _ = self.ds.publish_method_fn(g, spec, move |_| {
            let Some(sh) = weak.upgrade() else {
                return CallOutcome::Failed("map stopped".into());
            };
            let drawn = sh.state.lock().waypoints.get(&g).cloned().unwrap_or_default();
            let mut out = Vec::new();
            for (route, wps) in drawn {
                let path = sh.ds.path_text(route);
                for (i, (_, p)) in wps.iter().enumerate() {
                    out.extend([
                        Value::str(&path),
                        Value::Int(i as i64),
                        Value::Float(p.x as f64),
                        Value::Float(p.y as f64),
                    ]);
                }
            }
            CallOutcome::Accepted(out)
        });
        let weak = Arc::downgrade(self);
        let _ = self.ds.publish_method_fn(g, MethodSpec::new("symbols"), move |_| {
            let Some(sh) = weak.upgrade() else {
                return CallOutcome::Failed("map stopped".into());
            };
            let st = sh.state.lock();
            let mut out = Vec::new();
            for (_, name, p) in st.symbols.get(&g).into_iter().flatten() {
                out.push(Value::str(name));
                out.push(Value::Float(p.x as f64));
                out.push(Value::Float(p.y as f64));
            }
            CallOutcome::Accepted(out)
        });
    }

    /// The vehicle whose symbol is within reach of a window-local point.
    fn vehicle_at(&self, g: Guid, p: Point) -> Option<Guid> {
        let reach = (16.0 * self.ui_scale()).powi(2);
        let st = self.state.lock();
        st.symbols
            .get(&g)?
            .iter()
            .map(|(v, _, s)| (*v, (s.x - p.x).powi(2) + (s.y - p.y).powi(2)))
            .filter(|(_, d2)| *d2 <= reach)
            .min_by(|a, b| a.1.total_cmp(&b.1))
            .map(|(v, _)| v)
    }

    fn press(&self, g: Guid, button: i64, p: Point) {
        let ds = &self.ds;
        let vehicle = self.vehicle_at(g, p);
        match (button, vehicle) {
            (1, Some(v)) => {
                let n = |k: &str| {
                    ds.try_get(g, PropName::new(k)).and_then(|x| x.as_f64()).unwrap_or(0.0) as f32
                };
                crate::menu::open(ds, v, Point::new(n("x") + p.x, n("y") + p.y));
            }
            (0, Some(v)) => {
                if let Ok(Some(op)) = ds.find_child(Guid::ROOT, "operator").map(|o| {
                    o.or_else(|| {
                        ds.create_object(
                            Guid::ROOT,
                            mocu_dataserver::ObjectInfo::new("operator", "operator"),
                        )
                        .ok()
                    })
                }) {
                    let _ = ds.set(op, "selected", Value::Guid(v));
                    if let Ok(i) = ds.info(v) {
                        let _ = ds.set(op, "selected_name", Value::str(&i.name));
                    }
                }
                self.repaint();
            }
            (0, None) => {
                for w in ds.children(g).unwrap_or_default() {
                    // A hidden widget has no events (fig. 1 shows one per place to swap with).
                    let hidden =
                        ds.try_get(w, PropName::new("visible")) == Some(Value::Bool(false));
                    if !hidden
                        && ds
                            .methods(w)
                            .is_ok_and(|m| m.iter().any(|m| m.name.as_str() == "select"))
                    {
                        ds.call(w, "select", vec![], None, |_| {});
                    }
                }
            }
            _ => {}
        }
    }

    fn paint(self: &Arc<Self>, g: Guid, c: &mut dyn Canvas, _a: &PaintArgs) {
        let size = c.size();
        let u = self.ui_scale();
        let whole = Rect::new(0.0, 0.0, size.w, size.h);
        c.fill_rounded_rect(whole, 6.0 * u, &Brush::Solid(chart::WATER));
        let origin = self.origin();
        let vehicles = self.vehicles(origin);
        let features = self.state.lock().features.get(&self.ds);
        let view = self.view(g, size.w, size.h, u, &vehicles, &features, origin);
        self.state.lock().views.insert(g, view);
        c.save();
        c.clip_rect(whole);
        let weak = Arc::downgrade(self);
        self.tiles.draw(&self.ds, c, &view, move || {
            if let Some(sh) = weak.upgrade() {
                sh.repaint();
            }
        });
        chart::draw(c, &view, &features, u);
        let selected = self
            .ds
            .resolve(&["operator"])
            .and_then(|op| self.ds.try_get(op, PropName::new("selected")))
            .and_then(|v| v.as_guid());
        // Trails: a point each time a vehicle has moved a few metres since the last.
        let trails: Vec<Vec<Point>> = {
            let mut st = self.state.lock();
            st.trails.retain(|k, _| vehicles.iter().any(|v| v.guid == *k));
            vehicles
                .iter()
                .map(|v| {
                    let t = st.trails.entry(v.guid).or_default();
                    let moved = t.last().is_none_or(|l| metres(*l, v.pos) >= TRAIL_STEP_M);
                    if moved {
                        t.push(v.pos);
                        if t.len() > TRAIL_POINTS {
                            t.remove(0);
                        }
                    }
                    t.iter().map(|(lat, lon)| view.to_screen(*lat, *lon)).collect()
                })
                .collect()
        };
        let at: Vec<Point> = vehicles.iter().map(|v| view.to_screen(v.pos.0, v.pos.1)).collect();
        for (v, trail) in vehicles.iter().zip(&trails) {
            symbols::draw_trail(c, trail, v.colour, u);
        }
        let mut drawn: edit::Drawn = Vec::new();
        for (v, p) in vehicles.iter().zip(&at) {
            for r in &v.routes {
                let pts: Vec<Point> =
                    r.points.iter().map(|(la, lo)| view.to_screen(*la, *lo)).collect();
                symbols::draw_route(c, &pts, *p, r.next, r.active, v.colour, u);
                drawn.push((r.guid, r.waypoints.iter().copied().zip(pts).collect()));
            }
        }
        self.state.lock().waypoints.insert(g, drawn);
        let mut labels = Labels::new(whole.inset(2.0 * u));
        labels.block(symbols::draw_scale_bar(c, &view, u));
        labels.block(symbols::draw_north_arrow(c, &view, u));
        for p in &at {
            labels.block(Rect::new(p.x - 16.0 * u, p.y - 16.0 * u, 32.0 * u, 32.0 * u));
        }
        for (v, p) in vehicles.iter().zip(&at) {
            let fill = if v.stale { symbols::STALE } else { v.colour };
            symbols::draw_vehicle(c, v.kind, *p, v.heading, fill, u);
            symbols::draw_marks(c, *p, selected == Some(v.guid), v.controlled, u);
        }
        // Names: the selected and controlled vehicles' first, then the others', then the
        // chart's (buoys, zones), each where it overlaps nothing placed before it.
        let mut order: Vec<usize> = (0..vehicles.len()).collect();
        order.sort_by_key(|&i| !(selected == Some(vehicles[i].guid) || vehicles[i].controlled));
        for i in order {
            let v = &vehicles[i];
            let colour = if v.stale { symbols::STALE } else { symbols::TEXT };
            symbols::label(c, &mut labels, &v.name, at[i], 18.0 * u, (13.0 * u, colour), u);
        }
        for f in features.iter() {
            if let Some(p) = chart::label_anchor(&view, f) {
                let colour = match f.kind.as_str() {
                    "nogo" => chart::NOGO,
                    "buoy" => chart::buoy_colour(&f.colour),
                    _ => Color::rgb(0x9f, 0xd8, 0xea),
                };
                let gap = if f.kind == "buoy" { 8.0 * u } else { 0.0 };
                symbols::label(c, &mut labels, &f.name, p, gap, (12.0 * u, colour), u);
            }
        }
        c.restore();
        let placed = vehicles.iter().zip(&at).map(|(v, p)| (v.guid, v.name.clone(), *p)).collect();
        self.state.lock().symbols.insert(g, placed);
        c.stroke_rounded_rect(
            Rect::new(0.5, 0.5, size.w - 1.0, size.h - 1.0),
            6.0 * u,
            &Stroke::new(1.0),
            Color::rgb(0x3a, 0x4a, 0x5a),
        );
    }

    /// What window `g` shows: centred on the `follow` vehicle of its Map widget (or on
    /// everything), at the widget's `zoom` (a Web Mercator level, times the design scale)
    /// or else at the zoom that fits every vehicle and route (or the chart, when there are
    /// none) with at least 300 m across.
    #[allow(clippy::too_many_arguments)]
    fn view(
        &self,
        g: Guid,
        w: f32,
        h: f32,
        u: f32,
        vehicles: &[MapVehicle],
        features: &[chart::ChartFeature],
        origin: (f64, f64),
    ) -> View {
        let (follow, zoom) = self.widget_params(g);
        let mut pts: Vec<(f64, f64)> = Vec::new();
        for v in vehicles {
            pts.push(view::world(v.pos.0, v.pos.1));
            for r in &v.routes {
                pts.extend(r.points.iter().map(|(la, lo)| view::world(*la, *lo)));
            }
        }
        if pts.is_empty() {
            for f in features.iter().filter(|f| f.kind != "coastline" && f.kind != "land") {
                pts.extend(f.parts.iter().flatten().map(|(lo, la)| view::world(*la, *lo)));
            }
        }
        if pts.is_empty() {
            pts.push(view::world(origin.0, origin.1));
        }
        let centre = follow
            .and_then(|f| vehicles.iter().find(|v| v.guid == f))
            .map(|v| view::world(v.pos.0, v.pos.1));
        let fitted = View::fit(&pts, centre, w, h, 300.0);
        match zoom {
            Some(z) => View { zoom: (z + (u as f64).log2()).clamp(1.0, 22.0), ..fitted },
            None => fitted,
        }
    }

    /// The `follow` and `zoom` of the Map widget placed in window `g` (the first shown one),
    /// if given.
    fn widget_params(&self, g: Guid) -> (Option<Guid>, Option<f64>) {
        let ds = &self.ds;
        let widgets = ds.children(g).unwrap_or_default();
        let maps: Vec<Guid> = widgets
            .into_iter()
            .filter(|w| ds.info(*w).is_ok_and(|i| &*i.subtype == "Map"))
            .collect();
        // The shown one, where a window holds several (fig. 1: one per place to swap with).
        let shown =
            |w: &&Guid| ds.try_get(**w, PropName::new("visible")) != Some(Value::Bool(false));
        let Some(w) = maps.iter().find(shown).or(maps.first()) else {
            return (None, None);
        };
        // An object argument is published as its path (`root.vehicles.usv1`).
        let follow = match ds.try_get(*w, PropName::new("follow")) {
            Some(Value::Guid(v)) => Some(v),
            Some(Value::Str(path)) => {
                let parts: Vec<&str> =
                    path.strip_prefix("root.").unwrap_or(&path).split('.').collect();
                ds.resolve(&parts)
            }
            _ => None,
        };
        let zoom = ds
            .try_get(*w, PropName::new("zoom"))
            .and_then(|z| z.as_f64())
            .filter(|z| z.is_finite());
        (follow, zoom)
    }

    /// The local frame's origin: `root.map`'s, else the simulator's default.
    fn origin(&self) -> (f64, f64) {
        let map = self.ds.resolve(&["map"]);
        let get = |k: &str| {
            map.and_then(|m| self.ds.try_get(m, PropName::new(k))).and_then(|v| v.as_f64())
        };
        (get("origin_lat").unwrap_or(32.71), get("origin_lon").unwrap_or(-117.24))
    }

    /// The scale symbols, labels and lines draw at: the layout's design scale
    /// (`root.display.scale`, docs/language.md "Screen sizes"), never below 1.
    fn ui_scale(&self) -> f32 {
        let display = self.ds.resolve(&["display"]);
        let s = display.and_then(|d| self.ds.try_get(d, PropName::new("scale")));
        s.and_then(|v| v.as_f64()).filter(|s| s.is_finite()).map_or(1.0, |s| s.max(1.0)) as f32
    }

    /// Every vehicle with a position: its latitude/longitude where it reports one (MAVLink,
    /// the simulator), else its local `x`, `y` from `origin`.
    fn vehicles(&self, origin: (f64, f64)) -> Vec<MapVehicle> {
        let Some(folder) = self.ds.resolve(&["vehicles"]) else { return Vec::new() };
        let get = |o: Guid, k: &str| self.ds.try_get(o, PropName::new(k)).and_then(|x| x.as_f64());
        let place = |o: Guid| match (get(o, "lat"), get(o, "lon"), get(o, "x"), get(o, "y")) {
            (Some(lat), Some(lon), _, _) if lat != 0.0 || lon != 0.0 => Some((lat, lon)),
            (_, _, Some(x), Some(y)) => Some(view::local_to_lat_lon(origin, x, y)),
            _ => None,
        };
        let mut out = Vec::new();
        for (index, v) in self.ds.children(folder).unwrap_or_default().into_iter().enumerate() {
            let Some(nav) = self.ds.find_child(v, "nav").ok().flatten() else { continue };
            let Some(pos) = place(nav) else { continue };
            let info = self.ds.info(v).ok();
            let active = match self.ds.try_get(v, PropName::new("route")) {
                Some(Value::Guid(r)) => Some(r),
                _ => None,
            };
            let next = self.ds.try_get(v, PropName::new("route_next")).and_then(|n| n.as_i64());
            let mut routes = Vec::new();
            if let Some(rs) = self.ds.find_child(v, "routes").ok().flatten() {
                for r in self.ds.children(rs).unwrap_or_default() {
                    // Waypoints form a chain (each the child of the one before, so they can
                    // be edited by insert-between and delete-and-promote); siblings are
                    // taken in order too.
                    let (waypoints, points): (Vec<Guid>, Vec<(f64, f64)>) =
                        edit::route_waypoints(&self.ds, r)
                            .into_iter()
                            .filter_map(|w| Some((w, place(w)?)))
                            .unzip();
                    let is_active = active == Some(r);
                    routes.push(MapRoute {
                        guid: r,
                        waypoints,
                        points,
                        active: is_active,
                        next: next.filter(|_| is_active).and_then(|n| usize::try_from(n).ok()),
                    });
                }
            }
            out.push(MapVehicle {
                guid: v,
                name: info.as_ref().map(|i| i.name.to_string()).unwrap_or_default(),
                kind: VehicleType::of(info.as_ref().map_or("", |i| &*i.kind)),
                colour: symbols::vehicle_colour(index),
                pos,
                heading: get(nav, "heading").unwrap_or(0.0),
                stale: self.ds.try_get(v, PropName::new("stale")) == Some(Value::Bool(true)),
                controlled: matches!(self.ds.try_get(v, PropName::new("control")), Some(Value::Str(s)) if !s.is_empty()),
                routes,
            });
        }
        out
    }
}

struct MapVehicle {
    guid: Guid,
    name: String,
    kind: VehicleType,
    colour: Color,
    /// Latitude, longitude.
    pos: (f64, f64),
    heading: f64,
    stale: bool,
    /// An operator holds its control (`control` is not empty).
    controlled: bool,
    routes: Vec<MapRoute>,
}

struct MapRoute {
    guid: Guid,
    /// Its waypoints (those with a position), in order.
    waypoints: Vec<Guid>,
    /// Latitude, longitude of each waypoint, in order.
    points: Vec<(f64, f64)>,
    /// The vehicle's `route` is this one.
    active: bool,
    /// The waypoint the vehicle heads for (`route_next`), on the active route.
    next: Option<usize>,
}

/// Trails keep a point every few metres, the last few hundred.
const TRAIL_STEP_M: f64 = 3.0;
const TRAIL_POINTS: usize = 300;

/// Metres between two latitude/longitude pairs (flat earth: trail spacing only).
fn metres(a: (f64, f64), b: (f64, f64)) -> f64 {
    let dy = (a.0 - b.0) * 111_320.0;
    let dx = (a.1 - b.1) * 111_320.0 * a.0.to_radians().cos();
    (dx * dx + dy * dy).sqrt()
}
