//! Pointer input on widget windows: hover and press of buttons, the context menu, alert
//! rows.

use super::native::{LIST_ROW, LIST_TOP, listed_vehicles};
use super::{Shared, enabled, widget_bounds};
use mocu_dataserver::CallOutcome;
use mocu_display::{Point, Rect};
use mocu_value::{Guid, PropName, Value};
use std::sync::Arc;

impl Shared {
    /// Pointer input routed by the window manager: hover and press of widgets with a
    /// `press` method.
    pub(super) fn publish_pointer(self: &Arc<Self>, window: Guid) {
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
            let scale = ds.try_get(w, PropName::new("scale")).and_then(|v| v.as_f64());
            let s = scale.unwrap_or(1.0) as f32;
            let row = ((p.y - b.y) / s - LIST_TOP) / LIST_ROW;
            let row = row.floor();
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
                let scale = self.ds.try_get(w, PropName::new("scale")).and_then(|v| v.as_f64());
                let s = crate::alerts::scale_of(scale);
                crate::alerts::press(&self.ds, Rect::new(0.0, 0.0, b.w, b.h), local, s)
            })
        })
    }

    /// The topmost pressable widget under a window-local point (a hidden widget has no
    /// events: fig. 1 shows one press target per place its window can be exchanged with).
    fn widget_at(&self, window: Guid, p: Point) -> Option<Guid> {
        let mut ws = self.ds.children(window).ok()?;
        ws.sort_by_key(|w| {
            self.ds.try_get(*w, PropName::new("order")).and_then(|v| v.as_i64()).unwrap_or(0)
        });
        ws.into_iter().rev().find(|w| {
            let has_press =
                self.ds.methods(*w).is_ok_and(|m| m.iter().any(|m| m.name.as_str() == "press"));
            let hidden = self.ds.try_get(*w, PropName::new("visible")) == Some(Value::Bool(false));
            has_press
                && !hidden
                && enabled(&self.ds, *w)
                && widget_bounds(&self.ds, *w).is_some_and(|b| b.contains(p))
        })
    }
}
