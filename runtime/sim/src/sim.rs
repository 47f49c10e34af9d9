//! The simulator: its world, its publication in the DataServer, its methods and its module.

use crate::camera::{self, Lens, Pose};
use crate::manipulator::Manipulator;
use crate::rng::Rng;
use crate::vehicle::{Camera, Guidance, Vehicle, VehicleKind};
use mocu_dataserver::{
    Call, CallOutcome, DataServer, DsError, Guid, MethodSpec, ObjectInfo, ParamSpec, PropMeta,
    Value, ValueKind,
};
use mocu_host::world::{self, RouteFrame, boolean, float, float_in, int, string};
use mocu_host::{Module, ModuleContext, ModuleSpec, Registry};
use parking_lot::Mutex;
use std::collections::VecDeque;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

/// Settings of the simulator (the `[[modules]]` keys of kind `sim`).
#[derive(Clone, Debug, PartialEq)]
pub struct SimConfig {
    pub seed: u64,
    pub usv: usize,
    pub ugv: usize,
    pub uav: usize,
    /// Seconds between two vehicles appearing (discovery over time); the first appears at
    /// once.
    pub appear_every: f64,
    /// Simulation steps per second of real time (the module's tick).
    pub rate_hz: f64,
    pub camera_fps: f64,
    pub camera_width: u32,
    pub camera_height: u32,
    /// Latitude and longitude of the local origin (x = y = 0).
    pub origin: (f64, f64),
    /// Live data with nobody at the controls: the first vehicle of each type arms, starts
    /// and patrols its route on appearing; the others wait for the operator.
    pub autostart: bool,
    /// The vehicles by name, in the order they appear (the `vehicles` setting); each name
    /// starts with its type (`usv`, `ugv`, `uav`). Empty: `usv`, `ugv`, `uav` count them.
    pub names: Vec<String>,
}

impl Default for SimConfig {
    fn default() -> SimConfig {
        SimConfig {
            seed: 1,
            usv: 2,
            ugv: 1,
            uav: 1,
            appear_every: 0.5,
            rate_hz: 20.0,
            camera_fps: 10.0,
            camera_width: 640,
            camera_height: 480,
            origin: (32.7100, -117.2400),
            autostart: true,
            names: Vec::new(),
        }
    }
}

impl SimConfig {
    pub fn from_spec(spec: &ModuleSpec) -> Result<SimConfig, String> {
        let d = SimConfig::default();
        let count = |k: &str, def: usize| -> Result<usize, String> {
            let n = spec.i64_or(k, def as i64).map_err(|e| e.to_string())?;
            usize::try_from(n).map_err(|_| format!("module `{}`: `{k}` must be >= 0", spec.name))
        };
        let e = |r: Result<f64, mocu_host::SpecError>| r.map_err(|e| e.to_string());
        let cfg = SimConfig {
            seed: spec.i64_or("seed", d.seed as i64).map_err(|e| e.to_string())? as u64,
            usv: count("usv", d.usv)?,
            ugv: count("ugv", d.ugv)?,
            uav: count("uav", d.uav)?,
            appear_every: e(spec.f64_or("appear_every", d.appear_every))?,
            rate_hz: e(spec.f64_or("rate_hz", d.rate_hz))?,
            camera_fps: e(spec.f64_or("camera_fps", d.camera_fps))?,
            camera_width: count("camera_width", d.camera_width as usize)? as u32,
            camera_height: count("camera_height", d.camera_height as usize)? as u32,
            origin: (
                e(spec.f64_or("origin_lat", d.origin.0))?,
                e(spec.f64_or("origin_lon", d.origin.1))?,
            ),
            autostart: spec.bool_or("autostart", d.autostart).map_err(|e| e.to_string())?,
            names: names(spec)?,
        };
        if !(0.01..=1000.0).contains(&cfg.rate_hz) {
            return Err(format!("module `{}`: `rate_hz` must be in 0.01..=1000", spec.name));
        }
        if !(-90.0..=90.0).contains(&cfg.origin.0) || !(-180.0..=180.0).contains(&cfg.origin.1) {
            return Err(format!(
                "module `{}`: `origin_lat` must be in -90..=90 and `origin_lon` in -180..=180",
                spec.name
            ));
        }
        if !(1..=MAX_CAMERA.0).contains(&cfg.camera_width)
            || !(1..=MAX_CAMERA.1).contains(&cfg.camera_height)
        {
            return Err(format!(
                "module `{}`: camera size must be 1..={} x 1..={}",
                spec.name, MAX_CAMERA.0, MAX_CAMERA.1
            ));
        }
        Ok(cfg)
    }
}

/// The largest simulated camera picture (`camera_width`, `camera_height`).
pub const MAX_CAMERA: (u32, u32) = (1920, 1080);

/// The `vehicles` setting: names, each starting with its type, none twice.
fn names(spec: &ModuleSpec) -> Result<Vec<String>, String> {
    let Some(v) = spec.settings.get("vehicles") else { return Ok(Vec::new()) };
    let bad = || {
        format!(
            "module `{}`: `vehicles` must be a list of names, e.g. [\"usv1\", \"uav1\"]",
            spec.name
        )
    };
    let list = v.as_array().ok_or_else(bad)?;
    let mut out: Vec<String> = Vec::new();
    for n in list {
        let n = n.as_str().ok_or_else(bad)?;
        if kind_of(n).is_none() || !n.chars().all(|c| c.is_ascii_alphanumeric() || c == '_') {
            return Err(format!(
                "module `{}`: vehicle `{n}` must start with its type (usv, ugv or uav) and have only letters, digits and `_`",
                spec.name
            ));
        }
        if out.iter().any(|o| o == n) {
            return Err(format!("module `{}`: vehicle `{n}` is named twice", spec.name));
        }
        out.push(n.to_string());
    }
    if ["usv", "ugv", "uav"].iter().any(|k| spec.settings.contains_key(*k)) {
        return Err(format!(
            "module `{}`: give either `vehicles` or the counts `usv`, `ugv`, `uav`",
            spec.name
        ));
    }
    Ok(out)
}

/// The type of a vehicle named `usv…`, `ugv…` or `uav…`.
fn kind_of(name: &str) -> Option<VehicleKind> {
    [VehicleKind::Usv, VehicleKind::Ugv, VehicleKind::Uav]
        .into_iter()
        .find(|k| name.starts_with(k.type_name()))
}

struct World {
    cfg: SimConfig,
    rng: Rng,
    time: f64,
    pending: VecDeque<(f64, VehicleKind, String)>,
    vehicles: Vec<Vehicle>,
}

/// A handle on a running simulation. Cheap to clone.
#[derive(Clone)]
pub struct Sim {
    world: Arc<Mutex<World>>,
    ctx: ModuleContext,
    root: Guid,
}

impl Sim {
    /// Publishes `root.vehicles` (if absent); vehicles appear as [`Sim::step`] advances time.
    pub fn new(ctx: ModuleContext, cfg: SimConfig) -> Result<Sim, DsError> {
        let root = world::vehicles(&ctx.ds)?;
        let mut pending = VecDeque::new();
        let mut k = 0;
        for name in &cfg.names {
            if let Some(kind) = kind_of(name) {
                pending.push_back((k as f64 * cfg.appear_every, kind, name.clone()));
                k += 1;
            }
        }
        let n = if cfg.names.is_empty() { cfg.usv.max(cfg.ugv).max(cfg.uav) } else { 0 };
        for i in 0..n {
            for (kind, count) in [
                (VehicleKind::Usv, cfg.usv),
                (VehicleKind::Ugv, cfg.ugv),
                (VehicleKind::Uav, cfg.uav),
            ] {
                if i < count {
                    pending.push_back((
                        k as f64 * cfg.appear_every,
                        kind,
                        format!("{}{}", kind.type_name(), i + 1),
                    ));
                    k += 1;
                }
            }
        }
        let rng = Rng::new(cfg.seed);
        let world = World { cfg, rng, time: 0.0, pending, vehicles: Vec::new() };
        Ok(Sim { world: Arc::new(Mutex::new(world)), ctx, root })
    }

    /// Simulated seconds so far.
    pub fn time(&self) -> f64 {
        self.world.lock().time
    }

    /// Names of the vehicles that have appeared, in order.
    pub fn vehicle_names(&self) -> Vec<String> {
        self.world.lock().vehicles.iter().map(|v| v.name.clone()).collect()
    }

    /// A scenario hook: sets a vehicle's fuel (0..1) now.
    pub fn set_fuel(&self, name: &str, fuel: f64) {
        let mut w = self.world.lock();
        let origin = w.cfg.origin;
        if let Some(v) = w.vehicles.iter_mut().find(|v| v.name == name) {
            v.fuel = fuel.clamp(0.0, 1.0);
            if v.fuel == 0.0 {
                v.engine = false;
            }
            publish(&self.ctx.ds, v, origin);
        }
    }

    /// Advances the simulation by `dt` seconds: discovery, kinematics, publication, camera
    /// frames. Deterministic: the same seed and the same steps give the same world.
    pub fn step(&self, dt: f64) {
        let ds = &self.ctx.ds;
        let mut guard = self.world.lock();
        let w = &mut *guard;
        w.time += dt;
        while w.pending.front().is_some_and(|p| p.0 <= w.time + 1e-9) {
            let (_, kind, name) = w.pending.pop_front().expect("checked above");
            match self.spawn(w, kind, &name) {
                Ok(v) => w.vehicles.push(v),
                Err(e) => {
                    self.ctx.report(mocu_host::Level::Error, format!("cannot publish {name}: {e}"))
                }
            }
        }
        let origin = w.cfg.origin;
        let (cw, ch, fps) = (w.cfg.camera_width, w.cfg.camera_height, w.cfg.camera_fps);
        let time = w.time;
        for v in &mut w.vehicles {
            let goal = (
                ds.try_get(v.nav, "goal_throttle".into()).and_then(|x| x.as_f64()).unwrap_or(0.0),
                ds.try_get(v.nav, "goal_rudder".into()).and_then(|x| x.as_f64()).unwrap_or(0.0),
            );
            // A route edited in the world model (e.g. on the map) is flown as it is now.
            if let Guidance::Route { route, points, .. } = &mut v.guidance {
                let now: Vec<(f64, f64)> = world::route_waypoints(ds, *route)
                    .into_iter()
                    .filter_map(|wp| world::pair(ds, wp, "x", "y"))
                    .collect();
                if !now.is_empty() && now != *points {
                    *points = now;
                }
            }
            let noise = w.rng.unit();
            v.step(dt, goal, noise);
            if let Some(m) = &mut v.manipulator {
                m.step(dt);
                m.publish(ds);
            }
            publish(ds, v, origin);
            let pose =
                Pose { heading: v.heading, pitch: v.pitch, roll: v.roll, pan: 0.0, tilt: 0.0 };
            let head = Pose { pan: v.pan, tilt: v.tilt, ..pose };
            for c in &mut v.cameras {
                if fps > 0.0 && time + 1e-9 >= c.next_due {
                    c.next_due += 1.0 / fps;
                    c.frames += 1;
                    let _ = ds.set(c.listener, "frames", Value::Int(c.frames as i64));
                    if ds.receivers(c.listener).is_ok_and(|r| !r.is_empty()) {
                        let r = c
                            .renderer
                            .get_or_insert_with(|| camera::Renderer::new(cw, ch, c.lens, v.kind));
                        let px = r.render(if c.lens == Lens::Payload { head } else { pose });
                        let _ = ds.send(
                            c.listener,
                            vec![
                                Value::Bytes(px.into()),
                                Value::Int(cw as i64),
                                Value::Int(ch as i64),
                                Value::Int(c.frames as i64),
                            ],
                        );
                    }
                }
            }
        }
        let _ = ds.set(self.ctx.status, "time", Value::Float(w.time));
        let _ = ds.set(self.ctx.status, "vehicles", Value::Int(w.vehicles.len() as i64));
    }

    fn spawn(&self, w: &mut World, kind: VehicleKind, name: &str) -> Result<Vehicle, DsError> {
        let ds = &self.ctx.ds;
        let ex = &self.ctx.executor;
        let (x, y) = (w.rng.range(-150.0, 150.0), w.rng.range(-150.0, 150.0));
        let heading = w.rng.range(0.0, 360.0);
        let fuel = w.rng.range(0.55, 1.0);
        let info = ObjectInfo::new(name, kind.type_name()).subtype(kind.subtype());
        let guid = ds.create_object(self.root, info)?;
        let nav = ds.create_object(guid, ObjectInfo::new("nav", "nav"))?;
        let cams = ds.create_object(guid, ObjectInfo::new("cameras", "cameras"))?;
        let mut cameras = Vec::new();
        // Every vehicle has a drive camera and a payload camera on a pan/tilt head.
        let (pan, tilt) = if kind == VehicleKind::Uav { (0.0, -30.0) } else { (30.0, -2.0) };
        for (cname, lens) in [("drive", Lens::Drive), ("payload", Lens::Payload)] {
            let l = ds.create_listener(cams, cname)?;
            let mut props = vec![
                ("width", Value::Int(w.cfg.camera_width as i64), int("px")),
                ("height", Value::Int(w.cfg.camera_height as i64), int("px")),
                ("fps", Value::Float(w.cfg.camera_fps), float("Hz")),
                ("frames", Value::Int(0), int("frames")),
                ("format", Value::str("rgb8"), string()),
                (
                    "fov",
                    Value::Float(lens.fov()),
                    float("deg").describe("horizontal field of view"),
                ),
            ];
            if lens == Lens::Payload {
                props.push(("pan", Value::Float(pan), float_in("deg", -180.0, 180.0)));
                props.push(("tilt", Value::Float(tilt), float_in("deg", -90.0, 30.0)));
            }
            world::create_props(ds, l, props)?;
            cameras.push(Camera { listener: l, lens, frames: 0, next_due: w.time, renderer: None });
        }
        let manipulator =
            if kind == VehicleKind::Ugv { Some(Manipulator::create(ds, guid)?) } else { None };
        let v = Vehicle {
            name: name.to_string(),
            kind,
            guid,
            nav,
            cameras,
            pan,
            tilt,
            manipulator,
            x,
            y,
            alt: 0.0,
            target_alt: 30.0,
            heading,
            speed: 0.0,
            roll: 0.0,
            pitch: 0.0,
            fuel,
            armed: false,
            engine: false,
            control: String::new(),
            guidance: Guidance::Manual,
            home: (x, y),
            link: 1.0,
        };
        let mut props = vec![
            ("name", Value::str(name), string()),
            (
                "fuel",
                Value::Float(fuel),
                float_in("fraction", 0.0, 1.0).describe("fuel or battery, 0..1"),
            ),
        ];
        if kind != VehicleKind::Usv {
            props.push(("battery_v", Value::Float(0.0), float("V")));
        }
        props.extend([
            ("armed", Value::Bool(false), boolean()),
            ("engine", Value::Bool(false), boolean()),
            ("link", Value::Float(1.0), float_in("fraction", 0.0, 1.0).describe("link quality")),
            ("link_lost", Value::Bool(false), boolean()),
            ("stale", Value::Bool(false), boolean()),
            ("mode", Value::str("manual"), string()),
            ("control", Value::str(""), string().describe("operator holding control")),
        ]);
        world::create_props(ds, guid, with_rate(props, w.cfg.rate_hz))?;
        world::create_props(
            ds,
            nav,
            with_rate(
                vec![
                    ("speed", Value::Float(0.0), float("m/s")),
                    ("heading", Value::Float(heading), float_in("deg", 0.0, 360.0)),
                    ("x", Value::Float(x), float("m")),
                    ("y", Value::Float(y), float("m")),
                    ("lat", Value::Float(0.0), float_in("deg", -90.0, 90.0)),
                    ("lon", Value::Float(0.0), float_in("deg", -180.0, 180.0)),
                    ("alt", Value::Float(0.0), float("m")),
                    ("roll", Value::Float(0.0), float("deg")),
                    ("pitch", Value::Float(0.0), float("deg")),
                    (
                        "goal_throttle",
                        Value::Float(0.0),
                        float_in("%", -100.0, 100.0).describe("operator goal"),
                    ),
                    (
                        "goal_rudder",
                        Value::Float(0.0),
                        float_in("deg", -30.0, 30.0).describe("operator goal"),
                    ),
                ],
                w.cfg.rate_hz,
            ),
        )?;
        publish(ds, &v, w.cfg.origin);
        let origin = w.cfg.origin;
        let frame = RouteFrame::Local(Some(Arc::new(move |x, y| to_global(origin, x, y))));
        let routes = world::publish_routes(ds, ex, guid, frame.clone())?;
        let r = 60.0;
        let square = [(x + r, y), (x + r, y + r), (x, y + r), (x, y)];
        let patrol = world::create_route(ds, ex, routes, "patrol", frame, &square)?;
        self.publish_methods(guid)?;
        self.publish_part_methods(&v)?;
        let mut v = v;
        let first_of_kind = !w.vehicles.iter().any(|o| o.kind == kind);
        if w.cfg.autostart && first_of_kind {
            v.armed = true;
            v.engine = true;
            v.guidance =
                Guidance::Route { route: patrol, points: square.to_vec(), next: 0, repeat: true };
            let _ = ds.set(guid, "route", Value::Guid(patrol));
            publish(ds, &v, w.cfg.origin);
        }
        Ok(v)
    }

    fn publish_methods(&self, guid: Guid) -> Result<(), DsError> {
        use ValueKind::{Bool, Float, Guid as G, String as S};
        let p = ParamSpec::new;
        self.method(guid, MethodSpec::new("arm").param(p("on", Bool)), |_, v, a| {
            let on = a[0].as_bool().unwrap_or(false);
            v.armed = on;
            if !on {
                v.engine = false;
            }
            CallOutcome::Accepted(vec![])
        })?;
        self.method(guid, MethodSpec::new("start_engine"), |_, v, _| {
            if v.engine {
                CallOutcome::Refused("engine already running".into())
            } else if v.fuel <= 0.0 {
                CallOutcome::Refused(format!("no fuel: {} cannot start its engine", v.name))
            } else if !v.armed {
                CallOutcome::Refused("not armed: arm before starting the engine".into())
            } else {
                v.engine = true;
                CallOutcome::Accepted(vec![])
            }
        })?;
        self.method(guid, MethodSpec::new("stop"), |sim, v, _| {
            v.guidance = Guidance::Manual;
            let _ = sim.ctx.ds.set(v.nav, "goal_throttle", Value::Float(0.0));
            let _ = sim.ctx.ds.set(v.nav, "goal_rudder", Value::Float(0.0));
            CallOutcome::Accepted(vec![])
        })?;
        self.method(guid, MethodSpec::new("set_mode").param(p("mode", S)), |_, v, a| {
            match a[0].as_str().unwrap_or("") {
                "manual" => v.guidance = Guidance::Manual,
                "hold" => v.guidance = Guidance::Hold,
                "rtl" => v.guidance = Guidance::Point { x: v.home.0, y: v.home.1, home: true },
                "route" if matches!(v.guidance, Guidance::Route { .. }) => {}
                "route" => return CallOutcome::Refused("no route assigned".into()),
                "guided" => {
                    return CallOutcome::Refused("guided mode starts with goto(x, y, alt)".into());
                }
                other => {
                    return CallOutcome::Refused(format!(
                        "unknown mode `{other}` (manual, hold, rtl, route, guided)"
                    ));
                }
            }
            CallOutcome::Accepted(vec![])
        })?;
        self.method(
            guid,
            MethodSpec::new("goto")
                .param(p("x", Float))
                .param(p("y", Float))
                .param(p("alt", Float)),
            |_, v, a| {
                let (x, y, alt) = (
                    a[0].as_f64().unwrap_or(0.0),
                    a[1].as_f64().unwrap_or(0.0),
                    a[2].as_f64().unwrap_or(0.0),
                );
                if !v.engine {
                    return CallOutcome::Refused("engine is off".into());
                }
                if v.kind == VehicleKind::Uav {
                    if !(5.0..=120.0).contains(&alt) {
                        return CallOutcome::Refused(format!(
                            "altitude {alt} m is outside 5..120 m"
                        ));
                    }
                    v.target_alt = alt;
                }
                v.guidance = Guidance::Point { x, y, home: false };
                CallOutcome::Accepted(vec![])
            },
        )?;
        self.method(guid, MethodSpec::new("return_home"), |_, v, _| {
            if !v.engine {
                return CallOutcome::Refused("engine is off".into());
            }
            v.guidance = Guidance::Point { x: v.home.0, y: v.home.1, home: true };
            CallOutcome::Accepted(vec![])
        })?;
        self.method(
            guid,
            MethodSpec::new("request_control").param(p("operator", S)),
            |_, v, a| {
                let op = a[0].as_str().unwrap_or("");
                if op.is_empty() {
                    CallOutcome::Refused("an operator name is needed".into())
                } else if !v.control.is_empty() && v.control != op {
                    CallOutcome::Refused(format!("control held by {}", v.control))
                } else {
                    v.control = op.to_string();
                    CallOutcome::Accepted(vec![])
                }
            },
        )?;
        self.method(
            guid,
            MethodSpec::new("release_control").param(p("operator", S)),
            |_, v, a| {
                let op = a[0].as_str().unwrap_or("");
                if v.control != op {
                    CallOutcome::Refused(format!("{op} does not hold control"))
                } else {
                    v.control.clear();
                    CallOutcome::Accepted(vec![])
                }
            },
        )?;
        self.method(guid, MethodSpec::new("assign_route").param(p("route", G)), |sim, v, a| {
            let ds = &sim.ctx.ds;
            let Some(route) = a[0].as_guid() else {
                return CallOutcome::Failed("not a GUID".into());
            };
            let Ok(info) = ds.info(route) else {
                return CallOutcome::Failed("no such route".into());
            };
            if &*info.kind != "route" {
                return CallOutcome::Failed(format!(
                    "`{}` is a {}, not a route",
                    info.name, info.kind
                ));
            }
            let points: Vec<(f64, f64)> = world::route_waypoints(ds, route)
                .into_iter()
                .filter_map(|wp| world::pair(ds, wp, "x", "y"))
                .collect();
            if points.is_empty() {
                return CallOutcome::Refused(format!("route `{}` has no waypoints", info.name));
            }
            v.guidance = Guidance::Route { route, points, next: 0, repeat: false };
            let _ = ds.set(v.guid, "route", Value::Guid(route));
            CallOutcome::Accepted(vec![])
        })?;
        Ok(())
    }

    /// The payload head's `point_payload(pan, tilt)` and, on a UGV, its manipulator's
    /// `move_joints(shoulder, elbow, wrist)`, `grip(close)` and `stow()`.
    fn publish_part_methods(&self, v: &Vehicle) -> Result<(), DsError> {
        use ValueKind::{Bool, Float};
        let p = ParamSpec::new;
        let spec = MethodSpec::new("point_payload").param(p("pan", Float)).param(p("tilt", Float));
        self.method(v.guid, spec, |sim, v, a| {
            let (pan, tilt) =
                (a[0].as_f64().unwrap_or(f64::NAN), a[1].as_f64().unwrap_or(f64::NAN));
            if !(-180.0..=180.0).contains(&pan) || !(-90.0..=30.0).contains(&tilt) {
                return CallOutcome::Refused(format!(
                    "pan {pan}° tilt {tilt}°: the head turns -180..180° and tilts -90..30°"
                ));
            }
            (v.pan, v.tilt) = (pan, tilt);
            if let Some(c) = v.cameras.iter().find(|c| c.lens == Lens::Payload) {
                let _ = sim.ctx.ds.set(c.listener, "pan", Value::Float(pan));
                let _ = sim.ctx.ds.set(c.listener, "tilt", Value::Float(tilt));
            }
            CallOutcome::Accepted(vec![])
        })?;
        let Some(m) = v.manipulator.as_ref().map(|m| m.object) else { return Ok(()) };
        let part = |v: &mut Vehicle, f: &dyn Fn(&mut Manipulator) -> CallOutcome| match &mut v
            .manipulator
        {
            Some(m) => f(m),
            None => CallOutcome::NoSuchObject,
        };
        let mut spec = MethodSpec::new("move_joints");
        for (name, _, _) in crate::manipulator::JOINTS {
            spec = spec.param(p(name, Float));
        }
        self.method_on(m, v.guid, spec, move |_, v, a| part(v, &|m| m.move_joints(a)))?;
        self.method_on(
            m,
            v.guid,
            MethodSpec::new("grip").param(p("close", Bool)),
            move |_, v, a| {
                let close = a[0].as_bool().unwrap_or(false);
                part(v, &|m| m.grip(close))
            },
        )?;
        self.method_on(m, v.guid, MethodSpec::new("stow"), move |_, v, _| part(v, &|m| m.stow()))
    }

    /// Publishes a vehicle method whose handler runs on the simulator's executor with the
    /// world locked, then republishes the vehicle. (The call and its outcome are recorded
    /// once, by whoever made the call: the layout's `--log` record, the `--record` feed.)
    fn method(
        &self,
        guid: Guid,
        spec: MethodSpec,
        f: impl Fn(&Sim, &mut Vehicle, &[Value]) -> CallOutcome + Send + Sync + 'static,
    ) -> Result<(), DsError> {
        self.method_on(guid, guid, spec, f)
    }

    /// [`Sim::method`] on `object`, a part of `vehicle` (its manipulator).
    fn method_on(
        &self,
        object: Guid,
        vehicle: Guid,
        spec: MethodSpec,
        f: impl Fn(&Sim, &mut Vehicle, &[Value]) -> CallOutcome + Send + Sync + 'static,
    ) -> Result<(), DsError> {
        let sim = self.clone();
        self.ctx.ds.publish_method_on(&self.ctx.executor, object, spec, move |call: Call| {
            let mut w = sim.world.lock();
            let origin = w.cfg.origin;
            let Some(v) = w.vehicles.iter_mut().find(|v| v.guid == vehicle) else {
                call.responder.reply(CallOutcome::NoSuchObject);
                return;
            };
            let outcome = f(&sim, v, &call.args);
            publish(&sim.ctx.ds, v, origin);
            if let Some(m) = &v.manipulator {
                m.publish(&sim.ctx.ds);
            }
            drop(w);
            call.responder.reply(outcome);
        })
    }
}

/// Properties [`publish`] writes every step, changed or not: their metadata says so
/// (`PropMeta::rate_hz`), so that a display takes them as stale after three missed steps.
const TELEMETRY: &[&str] = &[
    "fuel",
    "battery_v",
    "armed",
    "engine",
    "link",
    "mode",
    "control",
    "speed",
    "heading",
    "x",
    "y",
    "lat",
    "lon",
    "alt",
    "roll",
    "pitch",
];

fn with_rate(
    mut props: Vec<(&str, Value, PropMeta)>,
    rate_hz: f64,
) -> Vec<(&str, Value, PropMeta)> {
    for (name, _, meta) in &mut props {
        if TELEMETRY.contains(name) {
            *meta = std::mem::take(meta).rate(rate_hz);
        }
    }
    props
}

fn to_global(origin: (f64, f64), x: f64, y: f64) -> (f64, f64) {
    let lat = origin.0 + y / 111_320.0;
    let lon = origin.1 + x / (111_320.0 * origin.0.to_radians().cos());
    (lat, lon)
}

/// Writes a vehicle's state to the DataServer (equal values notify nobody).
fn publish(ds: &DataServer, v: &Vehicle, origin: (f64, f64)) {
    let (lat, lon) = to_global(origin, v.x, v.y);
    let g = v.guid;
    let _ = ds.set(g, "fuel", Value::Float(v.fuel));
    if v.kind == VehicleKind::Ugv {
        let _ = ds.set(g, "battery_v", Value::Float(21.0 + 4.2 * v.fuel));
    } else if v.kind == VehicleKind::Uav {
        let _ = ds.set(g, "battery_v", Value::Float(13.2 + 3.6 * v.fuel));
    }
    let _ = ds.set(g, "armed", Value::Bool(v.armed));
    let _ = ds.set(g, "engine", Value::Bool(v.engine));
    let _ = ds.set(g, "link", Value::Float(v.link));
    let _ = ds.set(g, "link_lost", Value::Bool(v.link < 0.05));
    let _ = ds.set(g, "stale", Value::Bool(v.link < 0.05));
    let _ = ds.set(g, "mode", Value::str(v.mode()));
    let _ = ds.set(g, "control", Value::str(&v.control));
    let n = v.nav;
    let _ = ds.set(n, "speed", Value::Float(v.speed));
    let _ = ds.set(n, "heading", Value::Float(v.heading));
    let _ = ds.set(n, "x", Value::Float(v.x));
    let _ = ds.set(n, "y", Value::Float(v.y));
    let _ = ds.set(n, "lat", Value::Float(lat));
    let _ = ds.set(n, "lon", Value::Float(lon));
    let _ = ds.set(n, "alt", Value::Float(v.alt));
    let _ = ds.set(n, "roll", Value::Float(v.roll));
    let _ = ds.set(n, "pitch", Value::Float(v.pitch));
    if let Guidance::Route { next, .. } = &v.guidance {
        let _ = ds.set(g, "route_next", Value::Int(*next as i64));
    }
}

/// The simulator as a module: ticks [`Sim::step`] at `rate_hz` of the DataServer's clock
/// on its serial executor, with a fixed `dt`, catching up if a tick was late.
pub struct SimModule {
    cfg: SimConfig,
    sim: Option<Sim>,
    running: Arc<AtomicBool>,
}

impl SimModule {
    pub fn new(cfg: SimConfig) -> SimModule {
        SimModule { cfg, sim: None, running: Arc::new(AtomicBool::new(false)) }
    }

    /// The running simulation (after `start`).
    pub fn sim(&self) -> Option<&Sim> {
        self.sim.as_ref()
    }
}

impl Module for SimModule {
    fn start(&mut self, ctx: &ModuleContext) -> Result<(), String> {
        let sim = Sim::new(ctx.clone(), self.cfg.clone()).map_err(|e| e.to_string())?;
        self.running.store(true, Ordering::SeqCst);
        let period = Duration::from_secs_f64(1.0 / self.cfg.rate_hz);
        tick(sim.clone(), self.running.clone(), ctx.ds.now(), 0, period);
        self.sim = Some(sim);
        Ok(())
    }

    fn stop(&mut self) {
        self.running.store(false, Ordering::SeqCst);
    }
}

/// Step `n + 1` falls due at `t0 + (n + 1) * period` on the DataServer's clock, and each
/// step advances the world by `period` whenever it runs: the world follows the run's clock
/// in fixed steps, never the system's (a late tick catches up, it does not stretch `dt`).
fn tick(sim: Sim, running: Arc<AtomicBool>, t0: Instant, n: u64, period: Duration) {
    let due = t0 + period.mul_f64((n + 1) as f64);
    let ds = sim.ctx.ds.clone();
    let delay = due.saturating_duration_since(ds.now());
    let ex = sim.ctx.executor.clone();
    ds.run_after(delay, Some(&ex), move || {
        if !running.load(Ordering::SeqCst) {
            return;
        }
        let ok = sim.ctx.guard(|| sim.step(period.as_secs_f64()));
        if ok {
            tick(sim, running, t0, n + 1, period);
        }
    });
}

/// Registers the kind `sim`.
pub fn register(registry: &mut Registry) {
    registry.register("sim", |spec| {
        let cfg = SimConfig::from_spec(spec)?;
        Ok(Box::new(SimModule::new(cfg)) as Box<dyn Module>)
    });
}
