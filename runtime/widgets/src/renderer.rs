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
use mocu_dataserver::{DataServer, Executor, Kind, Notification, Subject, SubscriptionId, Topic};
use mocu_display::{Canvas, PaintArgs, Rect, claim_window, invalidate, invalidate_rect};
use mocu_value::{Guid, PropName, Value};
use parking_lot::Mutex;
use std::collections::HashMap;
use std::sync::Arc;
use std::time::{Duration, Instant};

mod native;
mod paint;
mod pointer;

pub use native::draw_native;

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
        WidgetRenderer::start_shared(ds, Arc::new(lib), config)
    }

    /// [`WidgetRenderer::start`] with a library others draw with too (`crate::Components`).
    pub(crate) fn start_shared(
        ds: &DataServer,
        lib: Arc<Library>,
        config: RendererConfig,
    ) -> Result<WidgetRenderer, String> {
        let display =
            mocu_display::ensure_display_object(ds, 1920, 1080).map_err(|e| e.to_string())?;
        let shared = Arc::new(Shared {
            ds: ds.clone(),
            lib: Mutex::new(lib),
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
        self.replace_shared(Arc::new(lib));
    }

    /// The library it draws with now.
    #[cfg(test)]
    pub(crate) fn library(&self) -> Arc<Library> {
        self.shared.lib.lock().clone()
    }

    pub(crate) fn replace_shared(&self, lib: Arc<Library>) {
        *self.shared.lib.lock() = lib;
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
        let now = self.ds.now();
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
}

/// The smallest rectangle holding both.
fn union(a: Rect, b: Rect) -> Rect {
    let (x0, y0) = (a.x.min(b.x), a.y.min(b.y));
    let (x1, y1) = ((a.x + a.w).max(b.x + b.w), (a.y + a.h).max(b.y + b.h));
    Rect::new(x0, y0, x1 - x0, y1 - y0)
}

fn enabled(ds: &DataServer, w: Guid) -> bool {
    ds.try_get(w, PropName::new("enabled")).and_then(|v| v.as_bool()) != Some(false)
}

fn widget_bounds(ds: &DataServer, w: Guid) -> Option<Rect> {
    let n = |k: &str| ds.try_get(w, PropName::new(k)).and_then(|v| v.as_f64()).map(|x| x as f32);
    Some(Rect::new(n("x")?, n("y")?, n("w")?, n("h")?))
}
