//! Route editing on the map, as changes of the world-model route (docs/map.md, "Editing
//! routes"): a left press on a route's leg inserts a waypoint there (the route's
//! `insert_waypoint`), a left press on a waypoint drags it (its own `x`/`y` or `lat`/`lon`
//! follow the pointer: that waypoint alone changes), a right press on a waypoint opens a
//! context menu whose item deletes it (the route's `delete_waypoint`). The menu is
//! `root.display.menus.waypoint`, published by the map when a layout has none.

use super::Shared;
use mocu_dataserver::{CallOutcome, DataServer, MethodSpec, ObjectInfo, ParamSpec};
use mocu_display::Point;
use mocu_value::{Guid, PropName, Value, ValueKind};
use std::sync::Arc;

/// Where a window drew each route's waypoints: (route, [(waypoint, window px)]).
pub(super) type Drawn = Vec<(Guid, Vec<(Guid, Point)>)>;

/// The waypoints of a route in order: a chain, each the child of the one before (so that
/// waypoints are inserted between and deleted with their successor promoted).
pub(super) fn route_waypoints(ds: &DataServer, route: Guid) -> Vec<Guid> {
    let mut out = Vec::new();
    let mut level = ds.children(route).unwrap_or_default();
    while let Some(&first) = level.first() {
        out.extend(level.iter().copied());
        level = ds.children(first).unwrap_or_default();
        if out.len() > 10_000 {
            break;
        }
    }
    out
}

/// The route a waypoint belongs to (its nearest ancestor of kind `route`).
fn route_of(ds: &DataServer, mut g: Guid) -> Option<Guid> {
    for _ in 0..10_001 {
        g = ds.parent(g).ok().flatten()?;
        if ds.info(g).is_ok_and(|i| &*i.kind == "route") {
            return Some(g);
        }
    }
    None
}

/// Distance from `p` to the segment `a`–`b`.
fn to_segment(p: Point, a: Point, b: Point) -> f32 {
    let (dx, dy) = (b.x - a.x, b.y - a.y);
    let len2 = dx * dx + dy * dy;
    let t = if len2 > 0.0 {
        (((p.x - a.x) * dx + (p.y - a.y) * dy) / len2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    (p.x - a.x - t * dx).hypot(p.y - a.y - t * dy)
}

impl Shared {
    /// The editing part of a pointer event in window `g`; whether it took the event.
    /// A press on a vehicle is never an edit (it selects the vehicle or opens its menu).
    pub(super) fn edit(self: &Arc<Self>, g: Guid, kind: &str, button: i64, p: Point) -> bool {
        if kind == "down" && self.vehicle_at(g, p).is_some() {
            return false;
        }
        match (kind, button) {
            ("down", 0) => {
                if let Some(wp) = self.waypoint_at(g, p) {
                    self.state.lock().drag = Some((g, wp));
                    true
                } else if let Some((route, index)) = self.leg_at(g, p) {
                    self.insert(g, route, index, p);
                    true
                } else {
                    false
                }
            }
            ("down", 1) => match self.waypoint_at(g, p) {
                Some(wp) => {
                    self.open_menu(g, wp, p);
                    true
                }
                None => false,
            },
            ("move", _) => {
                let drag = self.state.lock().drag;
                match drag {
                    Some((w, wp)) if w == g => {
                        self.move_to(g, wp, p);
                        true
                    }
                    _ => false,
                }
            }
            ("up" | "leave", _) => self.state.lock().drag.take().is_some(),
            _ => false,
        }
    }

    /// The waypoint drawn within reach of `p`.
    fn waypoint_at(&self, g: Guid, p: Point) -> Option<Guid> {
        let reach = 9.0 * self.ui_scale();
        let st = self.state.lock();
        st.waypoints
            .get(&g)?
            .iter()
            .flat_map(|(_, wps)| wps.iter())
            .map(|(w, q)| (*w, (q.x - p.x).hypot(q.y - p.y)))
            .filter(|(_, d)| *d <= reach)
            .min_by(|a, b| a.1.total_cmp(&b.1))
            .map(|(w, _)| w)
    }

    /// The route leg within reach of `p`: the route and the index a waypoint put there
    /// takes.
    fn leg_at(&self, g: Guid, p: Point) -> Option<(Guid, usize)> {
        let reach = 5.0 * self.ui_scale();
        let st = self.state.lock();
        let mut best: Option<(Guid, usize, f32)> = None;
        for (route, wps) in st.waypoints.get(&g)? {
            for (i, pair) in wps.windows(2).enumerate() {
                let d = to_segment(p, pair[0].1, pair[1].1);
                if d <= reach && best.is_none_or(|b| d < b.2) {
                    best = Some((*route, i + 1, d));
                }
            }
        }
        best.map(|(r, i, _)| (r, i))
    }

    /// Latitude/longitude and local x/y (from `root.map`'s origin) under window point `p`.
    fn ground(&self, g: Guid, p: Point) -> Option<((f64, f64), (f64, f64))> {
        let view = *self.state.lock().views.get(&g)?;
        let (lat, lon) = view.to_lat_lon(p);
        let o = self.origin();
        let x = (lon - o.1) * 111_320.0 * o.0.to_radians().cos();
        let y = (lat - o.0) * 111_320.0;
        Some(((lat, lon), (x, y)))
    }

    fn insert(self: &Arc<Self>, g: Guid, route: Guid, index: usize, p: Point) {
        let Some(((lat, lon), (x, y))) = self.ground(g, p) else { return };
        let local = matches!(self.ds.try_get(route, PropName::new("frame")), Some(Value::Str(f)) if &*f == "local");
        let (a, b) = if local { (x, y) } else { (lat, lon) };
        let args = vec![Value::Int(index as i64), Value::Float(a), Value::Float(b)];
        let weak = Arc::downgrade(self);
        self.ds.call(route, "insert_waypoint", args, None, move |_| {
            if let Some(sh) = weak.upgrade() {
                sh.repaint();
            }
        });
    }

    /// Moves one waypoint: only its own position properties change.
    fn move_to(&self, g: Guid, wp: Guid, p: Point) {
        let Some(((lat, lon), (x, y))) = self.ground(g, p) else { return };
        let has = |k: &str| self.ds.try_get(wp, PropName::new(k)).is_some();
        if has("x") && has("y") {
            let _ = self.ds.set(wp, "x", Value::Float(x));
            let _ = self.ds.set(wp, "y", Value::Float(y));
        }
        if has("lat") && has("lon") {
            let _ = self.ds.set(wp, "lat", Value::Float(lat));
            let _ = self.ds.set(wp, "lon", Value::Float(lon));
        }
        self.repaint();
    }

    fn open_menu(self: &Arc<Self>, g: Guid, wp: Guid, p: Point) {
        let ds = &self.ds;
        if ds.resolve(&["display", "menus", "waypoint"]).is_none() && publish_menu(self).is_none() {
            return;
        }
        let n = |k: &str| {
            ds.try_get(g, PropName::new(k)).and_then(|x| x.as_f64()).unwrap_or(0.0) as f32
        };
        crate::menu::open(ds, wp, Point::new(n("x") + p.x, n("y") + p.y));
    }
}

/// `root.display.menus.waypoint`: one item, "Delete waypoint N", that deletes it from its
/// route (the same protocol as a layout's menus: `open(object)`, `choose(index, object)`).
fn publish_menu(sh: &Arc<Shared>) -> Option<Guid> {
    let ds = &sh.ds;
    let weak = Arc::downgrade(sh);
    let display = ds.resolve(&["display"])?;
    let folder = match ds.resolve(&["display", "menus"]) {
        Some(f) => f,
        None => ds.create_object(display, ObjectInfo::new("menus", "menus")).ok()?,
    };
    let menu = ds.create_object(folder, ObjectInfo::new("waypoint", "menu")).ok()?;
    let _ = ds.set(menu, "items", Value::Int(1));
    let at = |ds: &DataServer, path: &str| -> Option<(Guid, usize)> {
        let parts: Vec<&str> = path.strip_prefix("root.").unwrap_or(path).split('.').collect();
        let wp = ds.resolve(&parts)?;
        let route = route_of(ds, wp)?;
        let index = route_waypoints(ds, route).iter().position(|w| *w == wp)?;
        Some((route, index))
    };
    let d = ds.clone();
    let open = MethodSpec::new("open").param(ParamSpec::new("object", ValueKind::String));
    let _ = ds.publish_method_fn(menu, open, move |args| {
        match at(&d, args[0].as_str().unwrap_or("")) {
            Some((_, i)) => CallOutcome::Accepted(vec![
                Value::str(&format!("Delete waypoint {}", i + 1)),
                Value::Bool(true),
            ]),
            None => CallOutcome::Refused("no such waypoint".into()),
        }
    });
    let d = ds.clone();
    let choose = MethodSpec::new("choose")
        .param(ParamSpec::new("index", ValueKind::Int))
        .param(ParamSpec::new("object", ValueKind::String));
    let _ = ds.publish_method_fn(menu, choose, move |args| {
        match (args[0].as_i64(), at(&d, args[1].as_str().unwrap_or(""))) {
            (Some(0), Some((route, i))) => {
                let weak = weak.clone();
                d.call(route, "delete_waypoint", vec![Value::Int(i as i64)], None, move |_| {
                    if let Some(sh) = weak.upgrade() {
                        sh.repaint();
                    }
                });
                CallOutcome::Accepted(vec![])
            }
            _ => CallOutcome::Refused("no such item or waypoint".into()),
        }
    });
    Some(menu)
}
