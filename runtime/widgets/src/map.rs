//! The map module: claims windows of subtype `map` and draws every vehicle under
//! `root.vehicles` (a symbol pointing along its heading, its name) and its routes with
//! their waypoints, in local metres, scaled to fit. No tiles.
//!
//! Pointer (routed by the window manager through transparent layers above): a left press
//! on a vehicle symbol selects it (`root.operator.selected`); elsewhere it raises the
//! `select` event of the `Map` widget placed in the window (fig. 1: the small map swaps
//! into the large place). A right press on a symbol opens the layout's context menu for
//! the vehicle's type. `symbols()` answers `[name, x, y, …]` in window pixels.
//!
//! Symbols, labels and lines grow with the layout's design scale (`root.display.scale`,
//! never below 1), like the widgets around the map.

use mocu_dataserver::{
    CallOutcome, DataServer, DottedPath, Executor, Kind, MethodSpec, Notification, PathWatch,
    Subject, SubscriptionId, Topic,
};
use mocu_display::{
    Align, Baseline, Brush, Canvas, Color, PaintArgs, Path, Point, Rect, Stroke, TextStyle,
    claim_window, invalidate,
};
use mocu_value::{Guid, PropName, Value};
use parking_lot::Mutex;
use std::collections::HashMap;
use std::sync::Arc;

pub struct MapModule {
    shared: Arc<Shared>,
}

struct Shared {
    ds: DataServer,
    exec: Executor,
    state: Mutex<State>,
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
    per_vehicle: HashMap<Guid, Vec<PathWatch>>,
}

impl MapModule {
    pub fn start(ds: &DataServer) -> Result<MapModule, String> {
        let display =
            mocu_display::ensure_display_object(ds, 1920, 1080).map_err(|e| e.to_string())?;
        let shared = Arc::new(Shared {
            ds: ds.clone(),
            exec: ds.serial_executor(),
            state: Mutex::default(),
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
        {
            let mut st = shared.state.lock();
            st.subs.push(sub);
            st.vehicles_watch = Some(watch);
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
            watches.extend(st.per_vehicle.drain().flat_map(|(_, w)| w));
            let mut subs = std::mem::take(&mut st.subs);
            subs.extend(st.vehicles_sub.take());
            (watches, subs, std::mem::take(&mut st.maps))
        };
        drop(watches);
        for s in subs {
            self.shared.ds.unsubscribe(s);
        }
        // Whatever a callback that was running added meanwhile (none can run any more).
        let (late_watches, late_sub) = {
            let mut st = self.shared.state.lock();
            (std::mem::take(&mut st.per_vehicle), st.vehicles_sub.take())
        };
        drop(late_watches);
        if let Some(s) = late_sub {
            self.shared.ds.unsubscribe(s);
        }
        for m in maps {
            for name in ["paint", "pointer", "symbols"] {
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

    fn on_vehicle(self: &Arc<Self>, kind: Kind, v: Guid) {
        match kind {
            Kind::New => {
                let mut watches = Vec::new();
                for p in ["nav.x", "nav.y", "nav.heading", "nav.lat", "nav.lon"] {
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

    fn repaint(&self) {
        let maps = self.state.lock().maps.clone();
        for m in maps {
            let _ = invalidate(&self.ds, m);
        }
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
            if args[0].as_str() == Some("down") {
                sh.press(g, args[1].as_i64().unwrap_or(-1), p);
            }
            CallOutcome::Accepted(vec![])
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
                    if ds.methods(w).is_ok_and(|m| m.iter().any(|m| m.name.as_str() == "select")) {
                        ds.call(w, "select", vec![], None, |_| {});
                    }
                }
            }
            _ => {}
        }
    }

    fn paint(&self, g: Guid, c: &mut dyn Canvas, _a: &PaintArgs) {
        let size = c.size();
        let u = self.ui_scale();
        let bg = Color::rgba(0x0e, 0x17, 0x22, 0xf0);
        let grid = Color::rgba(0x38, 0xbd, 0xf8, 0x22);
        let frame = Color::rgb(0x3a, 0x4a, 0x5a);
        c.fill_rounded_rect(Rect::new(0.0, 0.0, size.w, size.h), 6.0 * u, &Brush::Solid(bg));
        // Vehicles and route points in local metres.
        let vehicles = self.vehicles();
        let mut pts: Vec<(f64, f64)> = vehicles.iter().map(|v| v.pos).collect();
        for v in &vehicles {
            for r in &v.routes {
                pts.extend(r.iter().copied());
            }
        }
        let (mut x0, mut y0, mut x1, mut y1) = (f64::MAX, f64::MAX, f64::MIN, f64::MIN);
        for (x, y) in &pts {
            x0 = x0.min(*x);
            y0 = y0.min(*y);
            x1 = x1.max(*x);
            y1 = y1.max(*y);
        }
        if pts.is_empty() {
            (x0, y0, x1, y1) = (-100.0, -100.0, 100.0, 100.0);
        }
        let span = ((x1 - x0).max(y1 - y0)).max(100.0) * 1.3;
        let (cx, cy) = ((x0 + x1) / 2.0, (y0 + y1) / 2.0);
        let scale = (size.w.min(size.h) as f64 - 20.0 * u as f64).max(10.0) / span;
        let to_screen = |x: f64, y: f64| {
            Point::new(
                (size.w as f64 / 2.0 + (x - cx) * scale) as f32,
                (size.h as f64 / 2.0 - (y - cy) * scale) as f32,
            )
        };
        // A grid every "nice" distance.
        let step = nice_step(span / 6.0);
        let gx0 = ((cx - span) / step).floor() * step;
        let mut gx = gx0;
        while gx < cx + span {
            let a = to_screen(gx, cy - span);
            let b = to_screen(gx, cy + span);
            c.line(Point::new(a.x, 0.0), Point::new(b.x, size.h), u, grid);
            let a = to_screen(cx - span, gx - gx0 + ((cy - span) / step).floor() * step);
            c.line(Point::new(0.0, a.y), Point::new(size.w, a.y), u, grid);
            gx += step;
        }
        let dim = Color::rgb(0x8f, 0xa3, 0xb5);
        let scale_text = format!("grid {} m", step);
        c.draw_text(
            &scale_text,
            Point::new(8.0 * u, size.h - 8.0 * u),
            &TextStyle::new(12.0 * u, dim).baseline(Baseline::Bottom),
        );
        for v in &vehicles {
            for route in &v.routes {
                let pts: Vec<Point> = route.iter().map(|(x, y)| to_screen(*x, *y)).collect();
                if pts.len() >= 2 {
                    c.stroke_path(
                        &Path::polyline(&pts, false),
                        &Stroke::new(1.5 * u).dash(&[6.0 * u, 4.0 * u], 0.0),
                        &Brush::Solid(Color::rgb(0xf5, 0x9e, 0x0b)),
                    );
                }
                for p in pts {
                    c.fill_circle(p, 3.5 * u, Color::rgb(0xf5, 0x9e, 0x0b));
                }
            }
        }
        let selected = self
            .ds
            .find_child(Guid::ROOT, "operator")
            .ok()
            .flatten()
            .and_then(|op| self.ds.try_get(op, PropName::new("selected")))
            .and_then(|v| v.as_guid());
        let mut symbols = Vec::new();
        // Labels already placed: a label that would overlap one moves down a line.
        let mut labels: Vec<Rect> = Vec::new();
        for v in &vehicles {
            let p = to_screen(v.pos.0, v.pos.1);
            symbols.push((v.guid, v.name.clone(), p));
            if selected == Some(v.guid) {
                c.stroke_circle(p, 16.0 * u, 1.5 * u, Color::rgb(0xfa, 0xcc, 0x15));
            }
            let h = (v.heading as f32).to_radians();
            // Heading 0 = north (up), clockwise.
            let dir = |a: f32, r: f32| Point::new(p.x + (h + a).sin() * r, p.y - (h + a).cos() * r);
            let tri =
                Path::polyline(&[dir(0.0, 12.0 * u), dir(2.5, 8.0 * u), dir(-2.5, 8.0 * u)], true);
            let col =
                if v.stale { Color::rgb(0x5b, 0x64, 0x70) } else { Color::rgb(0x38, 0xbd, 0xf8) };
            c.fill_path(&tri, &Brush::Solid(col));
            let white = Brush::Solid(Color::rgb(0xe8, 0xf0, 0xf8));
            c.stroke_path(&tri, &Stroke::new(u), &white);
            let style = TextStyle::new(12.0 * u, Color::rgb(0xe8, 0xf0, 0xf8))
                .align(Align::Left)
                .baseline(Baseline::Middle);
            let tw = mocu_display::measure_text(&v.name, 12.0 * u, false).width;
            let line = 15.0 * u;
            let mut at = Rect::new(p.x + 14.0 * u, p.y - line / 2.0, tw, line);
            for _ in 0..labels.len() {
                match labels.iter().find(|l| l.intersects(&at)) {
                    Some(l) => at.y = l.y + l.h,
                    None => break,
                }
            }
            labels.push(at);
            c.draw_text(&v.name, Point::new(at.x, at.y + line / 2.0), &style);
        }
        self.state.lock().symbols.insert(g, symbols);
        c.stroke_rounded_rect(
            Rect::new(0.5, 0.5, size.w - 1.0, size.h - 1.0),
            6.0 * u,
            &Stroke::new(1.0),
            frame,
        );
    }

    /// The scale symbols, labels and lines draw at: the layout's design scale
    /// (`root.display.scale`, docs/language.md "Screen sizes"), never below 1.
    fn ui_scale(&self) -> f32 {
        let display = self.ds.resolve(&["display"]);
        let s = display.and_then(|d| self.ds.try_get(d, PropName::new("scale")));
        s.and_then(|v| v.as_f64()).filter(|s| s.is_finite()).map_or(1.0, |s| s.max(1.0)) as f32
    }

    fn vehicles(&self) -> Vec<MapVehicle> {
        let Some(folder) = self.ds.resolve(&["vehicles"]) else { return Vec::new() };
        let mut out = Vec::new();
        let mut origin: Option<(f64, f64)> = None;
        for v in self.ds.children(folder).unwrap_or_default() {
            let Some(nav) = self.ds.find_child(v, "nav").ok().flatten() else { continue };
            let get =
                |o: Guid, k: &str| self.ds.try_get(o, PropName::new(k)).and_then(|x| x.as_f64());
            let pos = match (get(nav, "x"), get(nav, "y"), get(nav, "lat"), get(nav, "lon")) {
                (Some(x), Some(y), _, _) => (x, y),
                (_, _, Some(lat), Some(lon)) => {
                    let o = *origin.get_or_insert((lat, lon));
                    ((lon - o.1) * 111_320.0 * o.0.to_radians().cos(), (lat - o.0) * 110_540.0)
                }
                _ => continue,
            };
            let name = self.ds.info(v).map(|i| i.name.to_string()).unwrap_or_default();
            let stale = self.ds.try_get(v, PropName::new("stale")) == Some(Value::Bool(true));
            let mut routes = Vec::new();
            if let Some(rs) = self.ds.find_child(v, "routes").ok().flatten() {
                for r in self.ds.children(rs).unwrap_or_default() {
                    // Waypoints form a chain (each the child of the one before, so they can
                    // be edited by insert-between and delete-and-promote); siblings are
                    // taken in order too.
                    let mut wps = Vec::new();
                    let mut level = self.ds.children(r).unwrap_or_default();
                    while let Some(&first) = level.first() {
                        for w in &level {
                            if let (Some(x), Some(y)) = (get(*w, "x"), get(*w, "y")) {
                                wps.push((x, y));
                            }
                        }
                        level = self.ds.children(first).unwrap_or_default();
                        if wps.len() > 10_000 {
                            break;
                        }
                    }
                    routes.push(wps);
                }
            }
            out.push(MapVehicle {
                guid: v,
                name,
                pos,
                heading: get(nav, "heading").unwrap_or(0.0),
                stale,
                routes,
            });
        }
        out
    }
}

struct MapVehicle {
    guid: Guid,
    name: String,
    pos: (f64, f64),
    heading: f64,
    stale: bool,
    routes: Vec<Vec<(f64, f64)>>,
}

fn nice_step(x: f64) -> f64 {
    let p = 10f64.powf(x.max(1.0).log10().floor());
    for m in [1.0, 2.0, 5.0, 10.0] {
        if m * p >= x {
            return m * p;
        }
    }
    10.0 * p
}
