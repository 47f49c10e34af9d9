//! World-model conventions shared by vehicle modules (simulator, MAVLink, …), so that every
//! vehicle looks the same to layouts: `root.vehicles.<name>` with `nav`, `cameras` and
//! `routes` children, numeric properties with units, and routes as waypoint chains.
//!
//! # Routes
//! A route object's waypoints form a *chain* (paper §4.1): the route's waypoint child is the
//! first waypoint, that waypoint's waypoint child is the second, and so on. Inserting is
//! `insert_between(parent, wp)`; deleting is `delete_and_promote(wp, next)`, so an edit
//! touches only its neighbours and subscribers see only that delta. [`route_waypoints`]
//! walks the chain in order.

use mocu_dataserver::{
    Call, DataServer, DsError, Executor, Guid, MethodSpec, ObjectInfo, ParamSpec, PropMeta, Value,
    ValueKind,
};
use parking_lot::Mutex;
use std::sync::Arc;

/// Serialises find-or-create so two modules starting together make one `root.vehicles`.
static SHAPE: Mutex<()> = Mutex::new(());

/// Finds or creates the object at `root.<path…>`; intermediate objects get their segment as
/// type, the last one `kind`.
pub fn ensure_path(ds: &DataServer, path: &[&str], kind: &str) -> Result<Guid, DsError> {
    let _g = SHAPE.lock();
    let mut at = ds.root();
    for (i, seg) in path.iter().enumerate() {
        at = match ds.find_child(at, seg)? {
            Some(g) => g,
            None => {
                let k = if i + 1 == path.len() { kind } else { seg };
                ds.create_object(at, ObjectInfo::new(seg, k))?
            }
        };
    }
    Ok(at)
}

/// `root.vehicles`, created on first use.
pub fn vehicles(ds: &DataServer) -> Result<Guid, DsError> {
    ensure_path(ds, &["vehicles"], "vehicles")
}

/// Metadata helpers: every numeric property carries units.
pub fn float(units: &str) -> PropMeta {
    PropMeta::typed(ValueKind::Float).units(units)
}

pub fn float_in(units: &str, min: f64, max: f64) -> PropMeta {
    float(units).range(min, max)
}

pub fn int(units: &str) -> PropMeta {
    PropMeta::typed(ValueKind::Int).units(units)
}

pub fn boolean() -> PropMeta {
    PropMeta::typed(ValueKind::Bool)
}

pub fn string() -> PropMeta {
    PropMeta::typed(ValueKind::String)
}

/// Creates properties in order (an existing one keeps its metadata and gets the value).
pub fn create_props(
    ds: &DataServer,
    guid: Guid,
    props: Vec<(&str, Value, PropMeta)>,
) -> Result<(), DsError> {
    for (name, value, meta) in props {
        match ds.create_property(guid, name, value.clone(), meta) {
            Err(DsError::PropertyExists { .. }) => ds.set(guid, name, value)?,
            other => other?,
        }
    }
    Ok(())
}

/// The waypoints of a route, in order (walks the chain).
pub fn route_waypoints(ds: &DataServer, route: Guid) -> Vec<Guid> {
    let mut out = Vec::new();
    let mut at = route;
    while let Some(next) = first_waypoint_child(ds, at) {
        out.push(next);
        at = next;
    }
    out
}

fn first_waypoint_child(ds: &DataServer, guid: Guid) -> Option<Guid> {
    ds.children(guid).ok()?.into_iter().find(|c| ds.info(*c).is_ok_and(|i| &*i.kind == "waypoint"))
}

/// Reads two numeric properties of an object.
pub fn pair(ds: &DataServer, guid: Guid, a: &str, b: &str) -> Option<(f64, f64)> {
    let x = ds.try_get(guid, a.into())?.as_f64()?;
    let y = ds.try_get(guid, b.into())?.as_f64()?;
    Some((x, y))
}

/// Converts local metres to latitude/longitude (for waypoints of a local route).
pub type ToGlobal = Arc<dyn Fn(f64, f64) -> (f64, f64) + Send + Sync>;

/// How a route's waypoints are placed.
#[derive(Clone)]
pub enum RouteFrame {
    /// `x`, `y` in metres (east, north) from the vehicle's origin; with a converter the
    /// waypoints also get `lat`, `lon`.
    Local(Option<ToGlobal>),
    /// `lat`, `lon` in degrees.
    Global,
}

impl RouteFrame {
    fn name(&self) -> &'static str {
        match self {
            RouteFrame::Local(_) => "local",
            RouteFrame::Global => "global",
        }
    }
}

/// Publishes `<vehicle>.routes` with the method `create_route(name: string) -> guid`.
pub fn publish_routes(
    ds: &DataServer,
    executor: &Executor,
    vehicle: Guid,
    frame: RouteFrame,
) -> Result<Guid, DsError> {
    let routes = ds.create_object(vehicle, ObjectInfo::new("routes", "routes"))?;
    let d = ds.clone();
    let ex = executor.clone();
    ds.publish_method_on(
        executor,
        routes,
        MethodSpec::new("create_route")
            .param(ParamSpec::new("name", ValueKind::String))
            .result(ParamSpec::new("route", ValueKind::Guid))
            .describe("Creates an empty route under this vehicle"),
        move |call: Call| {
            let name = call.args[0].as_str().unwrap_or("route").to_string();
            if name.is_empty() {
                call.responder.refuse("a route needs a name");
                return;
            }
            match create_route(&d, &ex, routes, &name, frame.clone(), &[]) {
                Ok(g) => call.responder.accept(vec![Value::Guid(g)]),
                Err(e) => call.responder.fail(e.to_string()),
            };
        },
    )?;
    Ok(routes)
}

/// Creates a route object under `routes` with the given waypoints (in the route's frame),
/// and its editing methods `insert_waypoint(index, a, b)` and `delete_waypoint(index)`.
pub fn create_route(
    ds: &DataServer,
    executor: &Executor,
    routes: Guid,
    name: &str,
    frame: RouteFrame,
    points: &[(f64, f64)],
) -> Result<Guid, DsError> {
    let route = ds.create_object(routes, ObjectInfo::new(name, "route"))?;
    create_props(
        ds,
        route,
        vec![
            ("name", Value::str(name), string()),
            ("frame", Value::str(frame.name()), string()),
            ("count", Value::Int(0), int("")),
            ("alt", Value::Float(20.0), float("m")),
        ],
    )?;
    for (i, &(a, b)) in points.iter().enumerate() {
        insert_waypoint(ds, route, &frame, i, a, b)?;
    }
    let (d, f) = (ds.clone(), frame.clone());
    ds.publish_method_on(
        executor,
        route,
        MethodSpec::new("insert_waypoint")
            .param(ParamSpec::new("index", ValueKind::Int))
            .param(ParamSpec::new("a", ValueKind::Float))
            .param(ParamSpec::new("b", ValueKind::Float))
            .result(ParamSpec::new("waypoint", ValueKind::Guid))
            .describe("Inserts a waypoint at index (x, y in m, or lat, lon in deg)"),
        move |call: Call| {
            let index = call.args[0].as_i64().unwrap_or(-1);
            let (a, b) =
                (call.args[1].as_f64().unwrap_or(0.0), call.args[2].as_f64().unwrap_or(0.0));
            let count = route_waypoints(&d, route).len();
            if index < 0 || index as usize > count {
                call.responder.refuse(format!("index {index} is outside 0..={count}"));
                return;
            }
            match insert_waypoint(&d, route, &f, index as usize, a, b) {
                Ok(g) => call.responder.accept(vec![Value::Guid(g)]),
                Err(e) => call.responder.fail(e.to_string()),
            };
        },
    )?;
    let d = ds.clone();
    ds.publish_method_on(
        executor,
        route,
        MethodSpec::new("delete_waypoint")
            .param(ParamSpec::new("index", ValueKind::Int))
            .describe("Deletes the waypoint at index; the next one takes its place"),
        move |call: Call| {
            let index = call.args[0].as_i64().unwrap_or(-1);
            let count = route_waypoints(&d, route).len();
            if index < 0 || index as usize >= count {
                call.responder.refuse(format!("no waypoint {index} (the route has {count})"));
                return;
            }
            match delete_waypoint(&d, route, index as usize) {
                Ok(()) => call.responder.accept(vec![]),
                Err(e) => call.responder.fail(e.to_string()),
            };
        },
    )?;
    Ok(route)
}

/// Inserts a waypoint at `index` of the chain (`index == count` appends).
pub fn insert_waypoint(
    ds: &DataServer,
    route: Guid,
    frame: &RouteFrame,
    index: usize,
    a: f64,
    b: f64,
) -> Result<Guid, DsError> {
    let wps = route_waypoints(ds, route);
    let info = ObjectInfo::new("waypoint", "waypoint");
    let wp = match wps.get(index) {
        Some(&at) => {
            let parent = ds.parent(at)?.unwrap_or(route);
            ds.insert_between(parent, at, info)?
        }
        None => ds.create_object(wps.last().copied().unwrap_or(route), info)?,
    };
    let alt = ds.try_get(route, "alt".into()).and_then(|v| v.as_f64()).unwrap_or(20.0);
    let mut props = Vec::new();
    match frame {
        RouteFrame::Local(to_global) => {
            props.push(("x", Value::Float(a), float("m")));
            props.push(("y", Value::Float(b), float("m")));
            if let Some(f) = to_global {
                let (lat, lon) = f(a, b);
                props.push(("lat", Value::Float(lat), float_in("deg", -90.0, 90.0)));
                props.push(("lon", Value::Float(lon), float_in("deg", -180.0, 180.0)));
            }
        }
        RouteFrame::Global => {
            props.push(("lat", Value::Float(a), float_in("deg", -90.0, 90.0)));
            props.push(("lon", Value::Float(b), float_in("deg", -180.0, 180.0)));
        }
    }
    props.push(("alt", Value::Float(alt), float("m")));
    create_props(ds, wp, props)?;
    ds.set(route, "count", Value::Int(wps.len() as i64 + 1))?;
    Ok(wp)
}

/// Deletes the waypoint at `index`, promoting the next one into its place.
pub fn delete_waypoint(ds: &DataServer, route: Guid, index: usize) -> Result<(), DsError> {
    let wps = route_waypoints(ds, route);
    let Some(&wp) = wps.get(index) else { return Ok(()) };
    match wps.get(index + 1) {
        Some(&next) => ds.delete_and_promote(wp, next)?,
        None => ds.delete_object(wp)?,
    }
    ds.set(route, "count", Value::Int(wps.len() as i64 - 1))
}
