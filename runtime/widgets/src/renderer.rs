//! The widget renderer: a module that claims every window of subtype `widgets` under
//! `root.display` and paints the widgets a layout published there, each from its
//! component's compiled body. It knows nothing of the layout that published them: it reads
//! the world model, like any other module.
//!
//! Every widget also shows, drawn generically around its component:
//! - control feedback (`feedback` property): pending (amber), accepted (green, briefly),
//!   refused / failed / timed out (red, with the reason beneath, for a few seconds);
//! - staleness: a widget whose `value` has not changed for `stale_after` is veiled and
//!   tagged STALE (a single delayed call per widget re-checks; idle displays stay idle);
//! - hover and press, for widgets with a `press` method (buttons).

use crate::component::Library;
use crate::draw::draw_shapes;
use mocu_dataserver::{
    CallOutcome, DataServer, Executor, Kind, MethodSpec, Notification, ParamSpec, Subject,
    SubscriptionId, Topic, ValueKind,
};
use mocu_display::{
    Align, Baseline, Brush, Canvas, Color, PaintArgs, Path, Point, Rect, Stroke, TextStyle,
    claim_window, invalidate, invalidate_rect,
};
use mocu_value::{Guid, PropName, Value};
use parking_lot::Mutex;
use std::collections::HashMap;
use std::sync::{Arc, Weak};
use std::time::{Duration, Instant};

/// Settings of the renderer.
#[derive(Clone, Debug)]
pub struct RendererConfig {
    /// A `value` unchanged for this long is shown stale.
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
}

#[derive(Default)]
struct State {
    display_sub: Option<SubscriptionId>,
    windows: HashMap<Guid, SubscriptionId>,
    widgets: HashMap<Guid, WidgetState>,
    closed: bool,
}

struct WidgetState {
    window: Guid,
    sub: SubscriptionId,
    bounds: Option<Rect>,
    value_at: Option<Instant>,
    feedback_at: Option<Instant>,
    stale_timer: bool,
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
    fn drop(&mut self) {
        let subs: Vec<SubscriptionId> = {
            let mut st = self.shared.state.lock();
            st.closed = true;
            let mut v: Vec<_> = st.display_sub.take().into_iter().collect();
            v.extend(st.windows.drain().map(|(g, s)| {
                let _ = self.shared.ds.unpublish_method(g, "paint");
                let _ = self.shared.ds.unpublish_method(g, "pointer");
                s
            }));
            v.extend(st.widgets.drain().map(|(_, w)| w.sub));
            v
        };
        for s in subs {
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
                        value_at: None,
                        feedback_at: None,
                        stale_timer: false,
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
            match name.as_str() {
                "value" => ws.value_at = Some(now),
                "feedback" => ws.feedback_at = Some(now),
                _ => {}
            }
            std::mem::replace(&mut ws.bounds, bounds)
        };
        // Repaint the old and the new place (a moved widget), with room for the overlays.
        self.damage(window, old);
        self.damage(window, bounds);
        match name.as_str() {
            "value" => self.arm_stale_timer(w, self.config.stale_after),
            "feedback" => {
                let after = self.config.accepted_for.max(self.config.refused_for)
                    + Duration::from_millis(20);
                let weak = Arc::downgrade(self);
                self.ds.run_after(after, Some(&self.exec), move || {
                    if let Some(sh) = weak.upgrade() {
                        sh.damage(window, widget_bounds(&sh.ds, w));
                    }
                });
            }
            _ => {}
        }
    }

    /// One delayed call per widget: when it fires, the widget is either stale now (repaint)
    /// or was updated meanwhile (re-arm for the rest of the time).
    fn arm_stale_timer(self: &Arc<Self>, w: Guid, after: Duration) {
        {
            let mut st = self.state.lock();
            let Some(ws) = st.widgets.get_mut(&w) else { return };
            if ws.stale_timer {
                return;
            }
            ws.stale_timer = true;
        }
        let weak: Weak<Shared> = Arc::downgrade(self);
        self.ds.run_after(after + Duration::from_millis(5), Some(&self.exec), move || {
            let Some(sh) = weak.upgrade() else { return };
            let (window, since) = {
                let mut st = sh.state.lock();
                let Some(ws) = st.widgets.get_mut(&w) else { return };
                ws.stale_timer = false;
                (ws.window, ws.value_at.map(|t| t.elapsed()))
            };
            match since {
                Some(e) if e >= sh.config.stale_after => {
                    sh.damage(window, widget_bounds(&sh.ds, w))
                }
                Some(e) => sh.arm_stale_timer(w, sh.config.stale_after - e),
                None => {}
            }
        });
    }

    fn damage(&self, window: Guid, r: Option<Rect>) {
        let _ = match r {
            Some(r) => invalidate_rect(
                &self.ds,
                window,
                Rect::new(r.x - 4.0, r.y - 4.0, r.w + 8.0, r.h + 26.0),
            ),
            None => invalidate(&self.ds, window),
        };
    }

    /// Pointer input routed by the window manager: hover and press of widgets with a
    /// `press` method.
    fn publish_pointer(self: &Arc<Self>, window: Guid) {
        let weak = Arc::downgrade(self);
        let spec = MethodSpec::new("pointer")
            .param(ParamSpec::new("kind", ValueKind::String))
            .param(ParamSpec::new("button", ValueKind::Int))
            .param(ParamSpec::new("x", ValueKind::Float))
            .param(ParamSpec::new("y", ValueKind::Float));
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

    /// The topmost pressable widget under a window-local point.
    fn widget_at(&self, window: Guid, p: Point) -> Option<Guid> {
        let mut ws = self.ds.children(window).ok()?;
        ws.sort_by_key(|w| {
            self.ds.try_get(*w, PropName::new("order")).and_then(|v| v.as_i64()).unwrap_or(0)
        });
        ws.into_iter().rev().find(|w| {
            let has_press =
                self.ds.methods(*w).is_ok_and(|m| m.iter().any(|m| m.name.as_str() == "press"));
            has_press && widget_bounds(&self.ds, *w).is_some_and(|b| b.contains(p))
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
                && !Rect::new(b.x - 4.0, b.y - 4.0, b.w + 8.0, b.h + 26.0).intersects(&damage)
            {
                continue;
            }
            let component = props.get("component").and_then(Value::as_str).unwrap_or("");
            c.save();
            c.translate(x, y);
            let lib = self.lib.lock().clone();
            if let Some(comp) = lib.components.get(component) {
                let prop = |name: &str| props.get(name).cloned();
                let outs = lib.evaluate(comp, &prop);
                draw_shapes(c, &comp.shapes, &outs);
            } else {
                draw_native(c, component, &props, bounds);
            }
            self.overlays(c, w, &props, bounds);
            c.restore();
        }
    }

    /// Feedback, staleness, hover and press, drawn in widget-local coordinates.
    fn overlays(
        &self,
        c: &mut dyn Canvas,
        w: Guid,
        props: &HashMap<String, Value>,
        bounds: Option<Rect>,
    ) {
        let Some(b) = bounds else { return };
        let r = Rect::new(-2.0, -2.0, b.w + 4.0, b.h + 4.0);
        let (hover, pressed, value_at, feedback_at) = {
            let st = self.state.lock();
            match st.widgets.get(&w) {
                Some(ws) => (ws.hover, ws.pressed, ws.value_at, ws.feedback_at),
                None => (false, false, None, None),
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
        if props.contains_key("value")
            && value_at.is_some_and(|t| t.elapsed() >= self.config.stale_after)
        {
            c.fill_rounded_rect(
                Rect::new(0.0, 0.0, b.w, b.h),
                4.0,
                &Brush::Solid(Color::rgba(11, 15, 20, 150)),
            );
            tag(c, "STALE", Point::new(b.w - 4.0, 4.0), Color::rgb(0xf5, 0x9e, 0x0b), Align::Right);
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
            c.stroke_path(&Path::rounded_rect(r, 5.0), &stroke, &Brush::Solid(col));
            if show_reason {
                let reason = props.get("feedback_reason").and_then(Value::as_str).unwrap_or(state);
                let label = format!("{}: {reason}", state.replace('_', " ").to_uppercase());
                let style = TextStyle::new(11.0, col).baseline(Baseline::Top);
                c.draw_text(&label, Point::new(0.0, b.h + 5.0), &style);
            }
        }
    }
}

fn tag(c: &mut dyn Canvas, text: &str, at: Point, col: Color, align: Align) {
    let style = TextStyle::new(10.0, col).align(align).baseline(Baseline::Top).bold();
    c.draw_text(text, at, &style);
}

fn enabled(ds: &DataServer, w: Guid) -> bool {
    ds.try_get(w, PropName::new("enabled")).and_then(|v| v.as_bool()) != Some(false)
}

fn widget_bounds(ds: &DataServer, w: Guid) -> Option<Rect> {
    let n = |k: &str| ds.try_get(w, PropName::new(k)).and_then(|v| v.as_f64()).map(|x| x as f32);
    Some(Rect::new(n("x")?, n("y")?, n("w")?, n("h")?))
}

/// Widgets drawn by Rust: a video placeholder (the video module claims video windows) and
/// the vehicle list; unknown components draw a labelled frame, never nothing.
fn draw_native(
    c: &mut dyn Canvas,
    component: &str,
    props: &HashMap<String, Value>,
    bounds: Option<Rect>,
) {
    let b = bounds.unwrap_or(Rect::new(0.0, 0.0, 160.0, 40.0));
    let panel = Color::rgba(0x14, 0x1c, 0x24, 0xe6);
    let frame = Color::rgb(0x3a, 0x4a, 0x5a);
    c.fill_rounded_rect(Rect::new(0.0, 0.0, b.w, b.h), 4.0, &Brush::Solid(panel));
    c.stroke_rounded_rect(Rect::new(0.0, 0.0, b.w, b.h), 4.0, &Stroke::new(1.0), frame);
    let dim = Color::rgb(0x8f, 0xa3, 0xb5);
    let label = match component {
        "Video" => {
            format!("NO VIDEO  {}", props.get("source").map(|v| v.to_string()).unwrap_or_default())
        }
        other => other.to_string(),
    };
    let style = TextStyle::new(12.0, dim).align(Align::Center).baseline(Baseline::Middle);
    c.draw_text(&label, Point::new(b.w / 2.0, b.h / 2.0), &style);
}
