//! The widget renderer: a module that claims every window of subtype `widgets` under
//! `root.display` and paints the widgets a layout published there, each from its
//! component's compiled body. It knows nothing of the layout that published them: it reads
//! the world model, like any other module.
//!
//! Every widget also shows, drawn generically around its component:
//! - control feedback (`feedback` property): pending (amber), accepted (green, briefly),
//!   refused / failed / timed out (red, with the reason beneath, for a few seconds);
//! - staleness: a widget whose `stale` property is true (the layout's compiled `stale`
//!   output: a vehicle it reads from lost its link; see `mocu-layout`'s `stale.rs`) and that
//!   shows data is veiled — everything it drew, read-outs outside its box included — and
//!   tagged STALE inside the veil (never over a neighbour); absent data is the component's
//!   own "no data" look, not stale. A value that merely did not change is never stale;
//! - hover and press, for enabled widgets with a `press` method (buttons).
//!
//! Native widgets: `VehicleList` (every vehicle under `root.vehicles`, optionally of one
//! `filter` type: name, type, link and fuel, live) and a `Video` placeholder.

use crate::component::Library;
use crate::draw::draw_shapes;
use mocu_dataserver::{
    CallOutcome, DataServer, Executor, Kind, Notification, Subject, SubscriptionId, Topic,
};
use mocu_display::{
    Align, Baseline, Brush, Canvas, Color, PaintArgs, Path, Point, Rect, Stroke, TextStyle,
    claim_window, invalidate, invalidate_rect,
};
use mocu_value::{Guid, PropName, Value};
use parking_lot::Mutex;
use std::collections::HashMap;
use std::sync::Arc;
use std::time::{Duration, Instant};

/// Settings of the renderer.
#[derive(Clone, Debug)]
pub struct RendererConfig {
    /// No longer used: staleness is the widget's `stale` property, which the layout
    /// computes from the link state of the vehicles it reads (docs/staleness.md). Kept so
    /// that existing configurations still build.
    pub stale_after: Duration,
    /// How long an accepted call's green outline shows.
    pub accepted_for: Duration,
    /// How long a refused or failed call's red outline and reason show.
    pub refused_for: Duration,
}

impl Default for RendererConfig {
    fn default() -> Self {
        RendererConfig {
            stale_after: Duration::from_secs(5),
            accepted_for: Duration::from_millis(1500),
            refused_for: Duration::from_secs(5),
        }
    }
}

/// The running module. Dropping it releases its windows and subscriptions.
pub struct WidgetRenderer {
    shared: Arc<Shared>,
}

struct Shared {
    ds: DataServer,
    lib: Mutex<Arc<Library>>,
    exec: Executor,
    config: RendererConfig,
    state: Mutex<State>,
    /// Alert layers to repaint when an alert comes, goes or is acknowledged, and the
    /// watches that tell (apart from `state`: ended with no lock held).
    alert_layers: Mutex<AlertFollow>,
}

/// The alert layers a renderer draws and the watches on `root.operator.alerts`.
#[derive(Default)]
struct AlertFollow {
    layers: Vec<(Guid, Guid)>,
    watches: Vec<mocu_dataserver::PathWatch>,
}

#[derive(Default)]
struct State {
    display_sub: Option<SubscriptionId>,
    windows: HashMap<Guid, SubscriptionId>,
    widgets: HashMap<Guid, WidgetState>,
    /// Vehicle lists to repaint when a vehicle changes, and the watches that tell.
    vehicle_lists: Vec<(Guid, Guid)>,
    vehicles_watch: Option<mocu_dataserver::PathWatch>,
    vehicle_subs: Vec<SubscriptionId>,
    closed: bool,
}

/// Room around a widget for its overlays (feedback outline, STALE tag, the reason beneath,
/// labels a component draws under itself).
const MARGIN: f32 = 16.0;
const BELOW: f32 = 22.0;

fn inflate(r: Rect) -> Rect {
    Rect::new(r.x - MARGIN, r.y - MARGIN, r.w + 2.0 * MARGIN, r.h + 2.0 * MARGIN + BELOW)
}

struct WidgetState {
    window: Guid,
    sub: SubscriptionId,
    bounds: Option<Rect>,
    feedback_at: Option<Instant>,
    hover: bool,
    pressed: bool,
}

const WIDGETS: &str = "widgets";

impl WidgetRenderer {
    /// Starts painting the `widgets` windows of `root.display` with `lib`'s components.
    pub fn start(
        ds: &DataServer,
        lib: Library,
        config: RendererConfig,
    ) -> Result<WidgetRenderer, String> {
        let display =
            mocu_display::ensure_display_object(ds, 1920, 1080).map_err(|e| e.to_string())?;
        let shared = Arc::new(Shared {
            ds: ds.clone(),
            lib: Mutex::new(Arc::new(lib)),
            exec: ds.serial_executor(),
            config,
            state: Mutex::default(),
            alert_layers: Mutex::default(),
        });
        let weak = Arc::downgrade(&shared);
        let sub = ds
            .subscribe_on(&shared.exec, Topic::children(display), move |n: &Notification| {
                if let Some(sh) = weak.upgrade() {
                    sh.on_window(n);
                }
            })
            .map_err(|e| e.to_string())?;
        shared.state.lock().display_sub = Some(sub);
        Ok(WidgetRenderer { shared })
    }
}

impl WidgetRenderer {
    /// Swaps in newly compiled components (a reloaded layout) and repaints every window.
    pub fn replace_library(&self, lib: Library) {
        *self.shared.lib.lock() = Arc::new(lib);
        let windows: Vec<Guid> = self.shared.state.lock().windows.keys().copied().collect();
        for w in windows {
            let _ = invalidate(&self.shared.ds, w);
        }
    }
}

impl Drop for WidgetRenderer {
    /// Collects under the lock, then acts with it released: ending a watch or a
    /// subscription waits for its running callback, and the callbacks take `state`.
    fn drop(&mut self) {
        let alert_watches = std::mem::take(&mut self.shared.alert_layers.lock().watches);
        drop(alert_watches);
        let (subs, windows, watch) = {
            let mut st = self.shared.state.lock();
            st.closed = true;
            let mut v: Vec<SubscriptionId> = st.display_sub.take().into_iter().collect();
            let mut windows = Vec::new();
            for (g, s) in st.windows.drain() {
                windows.push(g);
                v.push(s);
            }
            v.extend(st.widgets.drain().map(|(_, w)| w.sub));
            v.append(&mut st.vehicle_subs);
            (v, windows, st.vehicles_watch.take())
        };
        for g in windows {
            let _ = self.shared.ds.unpublish_method(g, "paint");
            let _ = self.shared.ds.unpublish_method(g, "pointer");
        }
        drop(watch);
        for s in subs {
            self.shared.ds.unsubscribe(s);
        }
        // Whatever a callback that was running added meanwhile (none runs any more).
        let (late, late_watch) = {
            let mut st = self.shared.state.lock();
            let mut v: Vec<_> = st.windows.drain().map(|(_, s)| s).collect();
            v.extend(st.widgets.drain().map(|(_, w)| w.sub));
            v.append(&mut st.vehicle_subs);
            (v, st.vehicles_watch.take())
        };
        drop(late_watch);
        for s in late {
            self.shared.ds.unsubscribe(s);
        }
    }
}

impl Shared {
    fn on_window(self: &Arc<Self>, n: &Notification) {
        let Subject::Child { guid, .. } = &n.subject else { return };
        let g = *guid;
        let is_widgets = self.ds.info(g).is_ok_and(|i| &*i.subtype == WIDGETS);
        match n.kind {
            Kind::New if is_widgets => {
                if self.state.lock().windows.contains_key(&g) {
                    return;
                }
                let weak = Arc::downgrade(self);
                let painted =
                    claim_window(&self.ds, g, move |c: &mut dyn Canvas, a: &PaintArgs| {
                        if let Some(sh) = weak.upgrade() {
                            sh.paint(g, c, a);
                        }
                    });
                if painted.is_err() {
                    return; // another module drew it first
                }
                self.publish_pointer(g);
                let weak = Arc::downgrade(self);
                if let Ok(sub) =
                    self.ds.subscribe_on(&self.exec, Topic::children(g), move |n: &Notification| {
                        if let Some(sh) = weak.upgrade() {
                            sh.on_widget(g, n);
                        }
                    })
                {
                    self.state.lock().windows.insert(g, sub);
                }
            }
            Kind::Deleted => {
                let sub = self.state.lock().windows.remove(&g);
                if let Some(s) = sub {
                    self.ds.unsubscribe(s);
                }
            }
            _ => {}
        }
    }

    fn on_widget(self: &Arc<Self>, window: Guid, n: &Notification) {
        let Subject::Child { guid, .. } = &n.subject else { return };
        let w = *guid;
        match n.kind {
            Kind::New => {
                let weak = Arc::downgrade(self);
                let Ok(sub) = self.ds.subscribe_on(
                    &self.exec,
                    Topic::properties(w),
                    move |n: &Notification| {
                        if let Some(sh) = weak.upgrade() {
                            sh.on_widget_prop(window, w, n);
                        }
                    },
                ) else {
                    return;
                };
                self.state.lock().widgets.insert(
                    w,
                    WidgetState {
                        window,
                        sub,
                        bounds: None,
                        feedback_at: None,
                        hover: false,
                        pressed: false,
                    },
                );
                let _ = invalidate(&self.ds, window);
            }
            Kind::Deleted => {
                let old = self.state.lock().widgets.remove(&w);
                if let Some(ws) = old {
                    self.ds.unsubscribe(ws.sub);
                    self.damage(window, ws.bounds);
                }
            }
            Kind::Changed => {}
        }
    }

    fn on_widget_prop(self: &Arc<Self>, window: Guid, w: Guid, n: &Notification) {
        let Some(name) = n.property_name() else { return };
        let now = Instant::now();
        let bounds = widget_bounds(&self.ds, w);
        let old = {
            let mut st = self.state.lock();
            let Some(ws) = st.widgets.get_mut(&w) else { return };
            if name.as_str() == "feedback" {
                ws.feedback_at = Some(now);
            }
            std::mem::replace(&mut ws.bounds, bounds)
        };
        if name.as_str() == "component"
            && self.ds.try_get(w, PropName::new("component")).as_ref().and_then(Value::as_str)
                == Some("VehicleList")
        {
            self.watch_vehicles(window, w);
        }
        if name.as_str() == "component"
            && self.ds.try_get(w, PropName::new("component")).as_ref().and_then(Value::as_str)
                == Some(crate::alerts::COMPONENT)
        {
            self.watch_alerts(window, w);
        }
        // Repaint the old and the new place (a moved widget), with room for the overlays.
        self.damage(window, old);
        self.damage(window, bounds);
        if name.as_str() == "feedback" {
            let after =
                self.config.accepted_for.max(self.config.refused_for) + Duration::from_millis(20);
            let weak = Arc::downgrade(self);
            self.ds.run_after(after, Some(&self.exec), move || {
                if let Some(sh) = weak.upgrade() {
                    sh.damage(window, widget_bounds(&sh.ds, w));
                }
            });
        }
    }

    fn damage(&self, window: Guid, r: Option<Rect>) {
        let _ = match r {
            Some(r) => invalidate_rect(&self.ds, window, inflate(r)),
            None => invalidate(&self.ds, window),
        };
    }

    fn data_props(&self, component: &str) -> Vec<String> {
        match self.lib.lock().components.get(component) {
            Some(c) => c.data.clone(),
            None => Vec::new(),
        }
    }

    /// Repaints alert layer `w` whenever an alert is raised or acknowledged, and when a
    /// shown alert's time is up.
    fn watch_alerts(self: &Arc<Self>, window: Guid, w: Guid) {
        let start = {
            let mut al = self.alert_layers.lock();
            if al.layers.iter().any(|(_, x)| *x == w) {
                return;
            }
            al.layers.push((window, w));
            al.watches.is_empty()
        };
        if !start {
            return;
        }
        let mut watches = Vec::new();
        for prop in ["raised", "unacknowledged"] {
            let weak = Arc::downgrade(self);
            let path = mocu_dataserver::DottedPath::new(&["operator", "alerts"], prop);
            let watch = self.ds.watch_path(path, Some(&self.exec), move |_| {
                let Some(sh) = weak.upgrade() else { return };
                sh.repaint_alert_layers();
                let weak = Arc::downgrade(&sh);
                let after = crate::alerts::SHOW_FOR + Duration::from_millis(50);
                sh.ds.run_after(after, Some(&sh.exec), move || {
                    if let Some(sh) = weak.upgrade() {
                        sh.repaint_alert_layers();
                    }
                });
            });
            watches.extend(watch.ok());
        }
        self.alert_layers.lock().watches.extend(watches);
    }

    fn repaint_alert_layers(&self) {
        let layers = self.alert_layers.lock().layers.clone();
        for (window, w) in layers {
            self.damage(window, widget_bounds(&self.ds, w));
        }
    }

    /// Repaints vehicle list `w` whenever a vehicle appears, goes or changes.
    fn watch_vehicles(self: &Arc<Self>, window: Guid, w: Guid) {
        let start = {
            let mut st = self.state.lock();
            if st.vehicle_lists.iter().any(|(_, x)| *x == w) {
                return;
            }
            st.vehicle_lists.push((window, w));
            st.vehicles_watch.is_none()
        };
        if !start {
            return;
        }
        let weak = Arc::downgrade(self);
        let watch = self.ds.watch_object(Guid::ROOT, &["vehicles"], Some(&self.exec), move |e| {
            let Some(sh) = weak.upgrade() else { return };
            let old = std::mem::take(&mut sh.state.lock().vehicle_subs);
            for s in old {
                sh.ds.unsubscribe(s);
            }
            if e.kind != Kind::Deleted {
                sh.follow_vehicles(e.object);
            }
            sh.repaint_vehicle_lists();
        });
        self.state.lock().vehicles_watch = watch.ok();
    }

    fn follow_vehicles(self: &Arc<Self>, folder: Guid) {
        let weak = Arc::downgrade(self);
        let sub = self.ds.subscribe_on(&self.exec, Topic::children(folder), move |n| {
            let Some(sh) = weak.upgrade() else { return };
            if let (Kind::New, Subject::Child { guid, .. }) = (n.kind, &n.subject) {
                sh.follow_vehicle(*guid);
            }
            sh.repaint_vehicle_lists();
        });
        if let Ok(s) = sub {
            self.state.lock().vehicle_subs.push(s);
        }
        for v in self.ds.children(folder).unwrap_or_default() {
            self.follow_vehicle(v);
        }
    }

    fn follow_vehicle(self: &Arc<Self>, v: Guid) {
        let weak = Arc::downgrade(self);
        let sub = self.ds.subscribe_on(&self.exec, Topic::properties(v), move |n| {
            let Some(sh) = weak.upgrade() else { return };
            if matches!(
                n.property_name().as_ref().map(|p| p.as_str()),
                Some("fuel" | "link" | "link_lost" | "stale" | "armed")
            ) {
                sh.repaint_vehicle_lists();
            }
        });
        if let Ok(s) = sub {
            self.state.lock().vehicle_subs.push(s);
        }
    }

    fn repaint_vehicle_lists(&self) {
        let lists = self.state.lock().vehicle_lists.clone();
        for (window, w) in lists {
            self.damage(window, widget_bounds(&self.ds, w));
        }
    }

    /// Pointer input routed by the window manager: hover and press of widgets with a
    /// `press` method.
    fn publish_pointer(self: &Arc<Self>, window: Guid) {
        let weak = Arc::downgrade(self);
        let spec = mocu_display::pointer_spec();
        let _ = self.ds.publish_method_fn(window, spec, move |args| {
            let Some(sh) = weak.upgrade() else {
                return CallOutcome::Failed("renderer stopped".into());
            };
            let kind = args[0].as_str().unwrap_or("");
            let button = args[1].as_i64().unwrap_or(-1);
            let p = Point::new(
                args[2].as_f64().unwrap_or(0.0) as f32,
                args[3].as_f64().unwrap_or(0.0) as f32,
            );
            sh.pointer(window, kind, button, p);
            CallOutcome::Accepted(vec![])
        });
    }

    fn pointer(self: &Arc<Self>, window: Guid, kind: &str, button: i64, p: Point) {
        if self.ds.info(window).is_ok_and(|i| &*i.name == crate::menu::WINDOW) {
            self.menu_pointer(window, kind, button, p);
            return;
        }
        if (kind, button) == ("down", 1) {
            self.context_menu(window, p);
            return;
        }
        if (kind, button) == ("down", 0) && self.alert_press(window, p) {
            return;
        }
        let under = self.widget_at(window, p);
        let mut changed = Vec::new();
        let press_target = {
            let mut st = self.state.lock();
            let mut target = None;
            for (g, ws) in st.widgets.iter_mut().filter(|(_, ws)| ws.window == window) {
                let inside = Some(*g) == under && kind != "leave";
                if ws.hover != inside {
                    ws.hover = inside;
                    changed.push(ws.bounds);
                }
                match (kind, button) {
                    ("down", 0) if inside => {
                        ws.pressed = true;
                        changed.push(ws.bounds);
                    }
                    ("up", 0) if ws.pressed => {
                        ws.pressed = false;
                        changed.push(ws.bounds);
                        if inside {
                            target = Some(*g);
                        }
                    }
                    _ => {}
                }
            }
            target
        };
        for b in changed {
            self.damage(window, b);
        }
        if let Some(g) = press_target
            && enabled(&self.ds, g)
        {
            self.ds.call(g, "press", vec![], None, |_| {});
        }
    }

    /// Pointer input on the open context menu: hover a row, press to choose, leave to close.
    fn menu_pointer(&self, window: Guid, kind: &str, button: i64, p: Point) {
        let Some(&m) = self.ds.children(window).ok().and_then(|c| c.first().copied()).as_ref()
        else {
            return;
        };
        let items = self.ds.try_get(m, PropName::new("items")).and_then(|v| v.as_i64());
        let row = crate::menu::row_at(p.y, items.unwrap_or(0).max(0) as usize);
        match (kind, button) {
            ("leave", _) => crate::menu::close(&self.ds),
            ("down", 0) => {
                if let Some(i) = row {
                    crate::menu::choose(&self.ds, m, i);
                }
            }
            _ => {
                let r = Value::Int(row.map_or(-1, |r| r as i64));
                if self.ds.try_get(m, PropName::new("hover_row")) != Some(r.clone()) {
                    let _ = self.ds.set(m, "hover_row", r);
                }
            }
        }
    }

    /// A right-click on a widget bound to an object that has a context menu: a vehicle
    /// list's row, or any widget with a property naming an object (`root.vehicles.usv1`).
    fn context_menu(&self, window: Guid, p: Point) {
        let ds = &self.ds;
        let Ok(mut ws) = ds.children(window) else { return };
        ws.sort_by_key(|w| {
            ds.try_get(*w, PropName::new("order")).and_then(|v| v.as_i64()).unwrap_or(0)
        });
        let Some(w) =
            ws.into_iter().rev().find(|w| widget_bounds(ds, *w).is_some_and(|b| b.contains(p)))
        else {
            return;
        };
        let b = widget_bounds(ds, w).unwrap_or_default();
        let component = ds.try_get(w, PropName::new("component"));
        let object = if component.as_ref().and_then(Value::as_str) == Some("VehicleList") {
            let filter = ds.try_get(w, PropName::new("filter"));
            let filter = filter.as_ref().and_then(Value::as_str).filter(|f| !f.is_empty());
            let row = ((p.y - b.y - LIST_TOP) / LIST_ROW).floor();
            (row >= 0.0)
                .then(|| listed_vehicles(ds, filter).get(row as usize).map(|v| v.0))
                .flatten()
        } else {
            ds.properties(w).ok().and_then(|props| {
                props.into_iter().find_map(|(_, v)| {
                    let path = v.as_str()?.strip_prefix("root.")?.to_string();
                    let segs: Vec<&str> = path.split('.').collect();
                    let g = ds.resolve(&segs)?;
                    let kind = ds.info(g).ok()?.kind;
                    ds.resolve(&["display", "menus", &kind]).map(|_| g)
                })
            })
        };
        let Some(object) = object else { return };
        let n = |k: &str| {
            ds.try_get(window, PropName::new(k)).and_then(|v| v.as_f64()).unwrap_or(0.0) as f32
        };
        crate::menu::open(ds, object, Point::new(n("x") + p.x, n("y") + p.y));
    }

    /// A press on an alert layer of `window`: acknowledges what it hit.
    fn alert_press(&self, window: Guid, p: Point) -> bool {
        let layers = self.alert_layers.lock().layers.clone();
        layers.into_iter().filter(|(win, _)| *win == window).any(|(_, w)| {
            widget_bounds(&self.ds, w).is_some_and(|b| {
                let local = Point::new(p.x - b.x, p.y - b.y);
                crate::alerts::press(&self.ds, Rect::new(0.0, 0.0, b.w, b.h), local)
            })
        })
    }

    /// The topmost pressable widget under a window-local point.
    fn widget_at(&self, window: Guid, p: Point) -> Option<Guid> {
        let mut ws = self.ds.children(window).ok()?;
        ws.sort_by_key(|w| {
            self.ds.try_get(*w, PropName::new("order")).and_then(|v| v.as_i64()).unwrap_or(0)
        });
        ws.into_iter().rev().find(|w| {
            let has_press =
                self.ds.methods(*w).is_ok_and(|m| m.iter().any(|m| m.name.as_str() == "press"));
            has_press
                && enabled(&self.ds, *w)
                && widget_bounds(&self.ds, *w).is_some_and(|b| b.contains(p))
        })
    }

    fn paint(&self, window: Guid, c: &mut dyn Canvas, _a: &PaintArgs) {
        let Ok(mut widgets) = self.ds.children(window) else { return };
        widgets.sort_by_key(|w| {
            self.ds.try_get(*w, PropName::new("order")).and_then(|v| v.as_i64()).unwrap_or(0)
        });
        let damage = c.damage();
        for w in widgets {
            let props: HashMap<String, Value> = match self.ds.properties(w) {
                Ok(p) => p.into_iter().map(|(n, v)| (n.as_str().to_string(), v)).collect(),
                Err(_) => continue,
            };
            if props.get("visible").and_then(Value::as_bool) == Some(false) {
                continue;
            }
            let num = |k: &str| props.get(k).and_then(Value::as_f64).map(|x| x as f32);
            let (Some(x), Some(y)) = (num("x"), num("y")) else { continue };
            let bounds = match (num("w"), num("h")) {
                (Some(ww), Some(hh)) => Some(Rect::new(x, y, ww, hh)),
                _ => None,
            };
            if let Some(b) = bounds
                && !inflate(b).intersects(&damage)
            {
                continue;
            }
            let component = props.get("component").and_then(Value::as_str).unwrap_or("");
            c.save();
            c.translate(x, y);
            let lib = self.lib.lock().clone();
            let mut drawn = bounds.map(|b| Rect::new(0.0, 0.0, b.w, b.h));
            if let Some(comp) = lib.components.get(component) {
                let prop = |name: &str| props.get(name).cloned();
                let outs = lib.evaluate(comp, &prop);
                draw_shapes(c, &comp.shapes, &outs);
                if let (Some(d), Some(e)) = (drawn, crate::draw::extent(&comp.shapes, &outs)) {
                    drawn = Some(union(d, e));
                }
            } else {
                draw_native(c, &self.ds, component, &props, bounds);
            }
            let data = self.data_props(component);
            self.overlays(c, w, &props, &data, bounds, drawn);
            c.restore();
        }
    }

    /// Feedback, staleness, hover and press, drawn in widget-local coordinates.
    fn overlays(
        &self,
        c: &mut dyn Canvas,
        w: Guid,
        props: &HashMap<String, Value>,
        data: &[String],
        bounds: Option<Rect>,
        drawn: Option<Rect>,
    ) {
        let Some(b) = bounds else { return };
        // Round widgets (dials, compasses, horizons) get round overlays.
        let radius = if (b.w - b.h).abs() < 1.0 && b.w >= 48.0 { b.w / 2.0 } else { 4.0 };
        let r = Rect::new(-2.0, -2.0, b.w + 4.0, b.h + 4.0);
        let (hover, pressed, feedback_at) = {
            let st = self.state.lock();
            match st.widgets.get(&w) {
                Some(ws) => (ws.hover, ws.pressed, ws.feedback_at),
                None => (false, false, None),
            }
        };
        if pressed {
            c.fill_rounded_rect(
                Rect::new(0.0, 0.0, b.w, b.h),
                4.0,
                &Brush::Solid(Color::rgba(0, 0, 0, 90)),
            );
        } else if hover {
            c.fill_rounded_rect(
                Rect::new(0.0, 0.0, b.w, b.h),
                4.0,
                &Brush::Solid(Color::rgba(255, 255, 255, 28)),
            );
        }
        if data.iter().any(|d| props.contains_key(d))
            && (props.get("stale").and_then(Value::as_bool) == Some(true)
                || props.get("aged").and_then(Value::as_bool) == Some(true))
        {
            stale_veil(c, b, drawn.unwrap_or(Rect::new(0.0, 0.0, b.w, b.h)), radius);
        }
        let state = props.get("feedback").and_then(Value::as_str).unwrap_or("");
        let age = feedback_at.map_or(Duration::MAX, |t| t.elapsed());
        let (col, show_reason) = match state {
            "pending" => (Some(Color::rgb(0xf5, 0x9e, 0x0b)), false),
            "accepted" if age < self.config.accepted_for => {
                (Some(Color::rgb(0x22, 0xc5, 0x5e)), false)
            }
            "refused" | "failed" | "timed_out" | "no_such_method" | "no_such_object"
                if age < self.config.refused_for =>
            {
                (Some(Color::rgb(0xef, 0x44, 0x44)), true)
            }
            _ => (None, false),
        };
        if let Some(col) = col {
            let mut stroke = Stroke::new(2.0);
            if state == "pending" {
                stroke = stroke.dash(&[5.0, 3.0], 0.0);
            }
            let rr = if radius > 4.0 { radius + 2.0 } else { 5.0 };
            c.stroke_path(&Path::rounded_rect(r, rr), &stroke, &Brush::Solid(col));
            if show_reason {
                let reason = props.get("feedback_reason").and_then(Value::as_str).unwrap_or(state);
                let mut label = format!("{}: {reason}", state.replace('_', " ").to_uppercase());
                // Cut to the room there is (the widget and its margins), with an ellipsis.
                let room = b.w + MARGIN;
                let width = |t: &str| mocu_display::measure_text(t, 12.0, false).width;
                if width(&label) > room {
                    let mut chars: Vec<char> = label.chars().collect();
                    while chars.len() > 4
                        && width(&format!("{}…", chars.iter().collect::<String>())) > room
                    {
                        chars.pop();
                    }
                    label = format!("{}…", chars.iter().collect::<String>().trim_end());
                }
                let style = TextStyle::new(12.0, col).baseline(Baseline::Top);
                c.draw_text(&label, Point::new(0.0, b.h + 5.0), &style);
            }
        }
    }
}

/// The smallest rectangle holding both.
fn union(a: Rect, b: Rect) -> Rect {
    let (x0, y0) = (a.x.min(b.x), a.y.min(b.y));
    let (x1, y1) = ((a.x + a.w).max(b.x + b.w), (a.y + a.h).max(b.y + b.h));
    Rect::new(x0, y0, x1 - x0, y1 - y0)
}

/// The stale veil over everything a widget drew (`drawn`, widget-local; a round widget
/// that drew nothing outside its box gets a round veil) and the STALE tag in its middle,
/// inside the veil: it never covers a neighbour.
fn stale_veil(c: &mut dyn Canvas, b: Rect, drawn: Rect, radius: f32) {
    let veil = Color::rgba(8, 10, 14, 170);
    let inside = drawn.x >= -0.5
        && drawn.y >= -0.5
        && drawn.x + drawn.w <= b.w + 0.5
        && drawn.y + drawn.h <= b.h + 0.5;
    let area = if inside { Rect::new(0.0, 0.0, b.w, b.h) } else { drawn };
    let r = if inside { radius } else { 4.0 };
    c.fill_rounded_rect(
        Rect::new(area.x - 1.0, area.y - 1.0, area.w + 2.0, area.h + 2.0),
        r,
        &Brush::Solid(veil),
    );
    // Where it hides the least: a short, wide widget's label (left), else high in the middle
    // (the value read-outs sit low or right).
    let size = if area.h >= 16.0 { 12.0 } else { (area.h - 2.0).max(8.0) };
    let tw = mocu_display::measure_text("STALE", size, true).width;
    let mid = if area.h < 48.0 && area.w >= tw + 12.0 {
        Point::new(area.x + 6.0 + tw / 2.0, area.y + area.h / 2.0)
    } else {
        Point::new(area.x + area.w / 2.0, area.y + (area.h * 0.25).max(size))
    };
    if tw + 8.0 <= area.w {
        c.fill_rounded_rect(
            Rect::new(mid.x - tw / 2.0 - 4.0, mid.y - size * 0.75, tw + 8.0, size * 1.5),
            3.0,
            &Brush::Solid(Color::rgba(0, 0, 0, 200)),
        );
    }
    let style = TextStyle::new(size, Color::rgb(0xf5, 0x9e, 0x0b))
        .align(Align::Center)
        .baseline(Baseline::Middle)
        .bold();
    c.draw_text("STALE", mid, &style);
}

fn enabled(ds: &DataServer, w: Guid) -> bool {
    ds.try_get(w, PropName::new("enabled")).and_then(|v| v.as_bool()) != Some(false)
}

fn widget_bounds(ds: &DataServer, w: Guid) -> Option<Rect> {
    let n = |k: &str| ds.try_get(w, PropName::new(k)).and_then(|v| v.as_f64()).map(|x| x as f32);
    Some(Rect::new(n("x")?, n("y")?, n("w")?, n("h")?))
}

/// Widgets drawn by Rust: the vehicle list, a video placeholder (the video module claims
/// video windows); unknown components draw a labelled frame, never nothing.
fn draw_native(
    c: &mut dyn Canvas,
    ds: &DataServer,
    component: &str,
    props: &HashMap<String, Value>,
    bounds: Option<Rect>,
) {
    let b = bounds.unwrap_or(Rect::new(0.0, 0.0, 160.0, 40.0));
    if component == "ContextMenu" {
        context_menu(c, props, b);
        return;
    }
    if component == crate::alerts::COMPONENT {
        crate::alerts::draw(c, ds, Rect::new(0.0, 0.0, b.w, b.h));
        return;
    }
    c.fill_rounded_rect(Rect::new(0.0, 0.0, b.w, b.h), 4.0, &Brush::Solid(theme::PANEL));
    c.stroke_rounded_rect(
        Rect::new(0.5, 0.5, b.w - 1.0, b.h - 1.0),
        4.0,
        &Stroke::new(1.0),
        theme::FRAME,
    );
    if component == "VehicleList" {
        let filter = props.get("filter").and_then(Value::as_str).filter(|f| !f.is_empty());
        vehicle_list(c, ds, filter, b);
        return;
    }
    let label = match component {
        "Video" => {
            format!("NO VIDEO  {}", props.get("source").map(|v| v.to_string()).unwrap_or_default())
        }
        other => other.to_string(),
    };
    let style = TextStyle::new(12.0, theme::DIM).align(Align::Center).baseline(Baseline::Middle);
    c.draw_text(&label, Point::new(b.w / 2.0, b.h / 2.0), &style);
}

/// The stdlib theme's colours, for what Rust draws (stdlib/theme.mocu).
mod theme {
    use mocu_display::Color;
    pub const PANEL: Color = Color::rgba(0x10, 0x18, 0x20, 0xe0);
    pub const TRACK: Color = Color::rgb(0x26, 0x32, 0x3e);
    pub const FRAME: Color = Color::rgb(0x3a, 0x4a, 0x5a);
    pub const ACCENT: Color = Color::rgb(0x38, 0xbd, 0xf8);
    pub const TEXT: Color = Color::rgb(0xe8, 0xf0, 0xf8);
    pub const DIM: Color = Color::rgb(0x8f, 0xa3, 0xb5);
    pub const GOOD: Color = Color::rgb(0x22, 0xc5, 0x5e);
    pub const CAUTION: Color = Color::rgb(0xf5, 0x9e, 0x0b);
    pub const ALARM: Color = Color::rgb(0xef, 0x44, 0x44);
    pub const NODATA: Color = Color::rgb(0x5b, 0x64, 0x70);
}

/// Where a vehicle list's rows start, and their height.
const LIST_TOP: f32 = 28.0;
const LIST_ROW: f32 = 26.0;

/// The vehicles a list shows, in order.
fn listed_vehicles(
    ds: &DataServer,
    filter: Option<&str>,
) -> Vec<(Guid, mocu_dataserver::ObjectInfo)> {
    ds.resolve(&["vehicles"])
        .and_then(|f| ds.children(f).ok())
        .unwrap_or_default()
        .into_iter()
        .filter_map(|v| ds.info(v).ok().map(|i| (v, i)))
        .filter(|(_, i)| filter.is_none_or(|f| &*i.kind == f))
        .collect()
}

/// The context menu: a title and one row per item, the hovered row lit.
fn context_menu(c: &mut dyn Canvas, props: &HashMap<String, Value>, b: Rect) {
    let s = |k: &str| props.get(k).and_then(Value::as_str).unwrap_or("").to_string();
    c.fill_rounded_rect(
        Rect::new(0.0, 0.0, b.w, b.h),
        5.0,
        &Brush::Solid(Color::rgba(0x0d, 0x14, 0x1b, 0xf2)),
    );
    c.stroke_rounded_rect(
        Rect::new(0.75, 0.75, b.w - 1.5, b.h - 1.5),
        5.0,
        &Stroke::new(1.5),
        theme::ACCENT,
    );
    let head = TextStyle::new(11.0, theme::DIM).baseline(Baseline::Middle).bold();
    c.draw_text(&s("title"), Point::new(10.0, crate::menu::TITLE / 2.0), &head);
    c.line(
        Point::new(6.0, crate::menu::TITLE - 1.0),
        Point::new(b.w - 6.0, crate::menu::TITLE - 1.0),
        1.0,
        theme::FRAME,
    );
    let n = props.get("items").and_then(Value::as_i64).unwrap_or(0).max(0) as usize;
    let hover = props.get("hover_row").and_then(Value::as_i64).unwrap_or(-1);
    for i in 0..n {
        let y = crate::menu::TITLE + i as f32 * crate::menu::ROW;
        let enabled = props.get(&format!("enabled{i}")) == Some(&Value::Bool(true));
        if hover == i as i64 && enabled {
            c.fill_rounded_rect(
                Rect::new(3.0, y + 1.0, b.w - 6.0, crate::menu::ROW - 2.0),
                3.0,
                &Brush::Solid(Color::rgba(0x38, 0xbd, 0xf8, 0x40)),
            );
        }
        let label = props.get(&format!("item{i}")).map(|v| v.to_string()).unwrap_or_default();
        let st = TextStyle::new(14.0, if enabled { theme::TEXT } else { theme::NODATA })
            .baseline(Baseline::Middle);
        c.draw_text(&label, Point::new(14.0, y + crate::menu::ROW / 2.0), &st);
    }
}

/// One row per vehicle: a link-state dot, the name, its type, link and fuel as small bars.
fn vehicle_list(c: &mut dyn Canvas, ds: &DataServer, filter: Option<&str>, b: Rect) {
    let head = TextStyle::new(12.0, theme::DIM).baseline(Baseline::Middle).bold();
    c.draw_text("VEHICLES", Point::new(10.0, 13.0), &head);
    c.line(Point::new(6.0, 25.0), Point::new(b.w - 6.0, 25.0), 1.0, theme::FRAME);
    let vehicles = listed_vehicles(ds, filter);
    if vehicles.is_empty() {
        let st = TextStyle::new(12.0, theme::NODATA).baseline(Baseline::Middle);
        c.draw_text("— no vehicles —", Point::new(10.0, 40.0), &st);
        return;
    }
    let row_h = LIST_ROW;
    // Two labelled bars after the name and type, within the list's width.
    // A narrow list leaves the type out.
    let first = if b.w < 320.0 { 86.0 } else { 130.0 };
    let bar_w = ((b.w - first - 2.0 * 42.0 - 8.0) / 2.0).clamp(16.0, 90.0);
    // The rows that fit; with more vehicles than that, the last row says how many are left.
    let fit = (((b.h - LIST_TOP) / row_h).floor().max(0.0)) as usize;
    let shown = if vehicles.len() > fit { fit.saturating_sub(1) } else { vehicles.len() };
    if shown < vehicles.len() && fit > 0 {
        let y = LIST_TOP + shown as f32 * row_h + row_h / 2.0;
        let st = TextStyle::new(12.0, theme::TEXT).baseline(Baseline::Middle).bold();
        c.draw_text(&format!("+{} more", vehicles.len() - shown), Point::new(26.0, y), &st);
    }
    for (i, (v, info)) in vehicles.iter().take(shown).enumerate() {
        let y = LIST_TOP + i as f32 * row_h + row_h / 2.0;
        let num = |k: &str| ds.try_get(*v, PropName::new(k)).and_then(|x| x.as_f64());
        let flag = |k: &str| ds.try_get(*v, PropName::new(k)) == Some(Value::Bool(true));
        let lost = flag("link_lost") || flag("stale");
        let link = num("link");
        let fuel = num("fuel");
        let dot = if lost {
            theme::ALARM
        } else if link.is_some_and(|l| l < 0.3) {
            theme::CAUTION
        } else if link.is_some() {
            theme::GOOD
        } else {
            theme::NODATA
        };
        c.fill_circle(Point::new(14.0, y), 4.5, dot);
        let name = TextStyle::new(13.0, if lost { theme::DIM } else { theme::TEXT })
            .baseline(Baseline::Middle)
            .bold();
        c.draw_text(&info.name, Point::new(26.0, y), &name);
        let kind = TextStyle::new(12.0, theme::DIM).baseline(Baseline::Middle);
        if first > 86.0 {
            c.draw_text(&info.kind.to_uppercase(), Point::new(86.0, y), &kind);
        }
        let mut x = first;
        for (label, value, warn, alarm) in [("LNK", link, 0.3, 0.1), ("FUEL", fuel, 0.2, 0.1)] {
            let small = TextStyle::new(11.0, theme::DIM).baseline(Baseline::Middle);
            c.draw_text(label, Point::new(x, y), &small);
            let bx = x + 32.0;
            let track = Rect::new(bx, y - 4.0, bar_w, 8.0);
            c.fill_rounded_rect(track, 2.0, &Brush::Solid(theme::TRACK));
            match value {
                Some(f) => {
                    let col = if f < alarm {
                        theme::ALARM
                    } else if f < warn {
                        theme::CAUTION
                    } else {
                        theme::GOOD
                    };
                    let fw = (bar_w * f.clamp(0.0, 1.0) as f32).max(0.0);
                    if fw > 0.5 {
                        c.fill_rounded_rect(
                            Rect::new(bx, y - 4.0, fw, 8.0),
                            2.0,
                            &Brush::Solid(col),
                        );
                    }
                }
                None => c.stroke_rounded_rect(track, 2.0, &Stroke::new(1.0), theme::NODATA),
            }
            x = bx + bar_w + 10.0;
        }
    }
}
