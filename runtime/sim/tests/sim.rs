//! The simulator, stepped explicitly (no wall clock): determinism, discovery, kinematics,
//! refusals with reasons, route editing, camera frames.

use mocu_dataserver::{
    Call, CallOutcome, DataServer, Guid, MethodSpec, ObjectInfo, Overflow, ParamSpec, Value,
    ValueKind,
};
use mocu_host::ModuleContext;
use mocu_host::world::route_waypoints;
use mocu_sim::{Sim, SimConfig};
use std::sync::{Arc, Mutex};

fn sim(cfg: SimConfig) -> (DataServer, Sim) {
    let ds = DataServer::default();
    let ctx = ModuleContext::detached("sim", ds.clone());
    let sim = Sim::new(ctx, cfg).unwrap();
    (ds, sim)
}

fn quiet() -> SimConfig {
    SimConfig { autostart: false, appear_every: 0.0, ..SimConfig::default() }
}

fn run(sim: &Sim, seconds: f64) {
    for _ in 0..(seconds * 20.0).round() as usize {
        sim.step(0.05);
    }
}

fn num(ds: &DataServer, path: &[&str], prop: &str) -> f64 {
    let g = ds.resolve(path).unwrap_or_else(|| panic!("no {path:?}"));
    ds.get(g, prop).unwrap().as_f64().unwrap()
}

fn v(ds: &DataServer, name: &str) -> Guid {
    ds.resolve(&["vehicles", name]).unwrap()
}

fn call(ds: &DataServer, g: Guid, m: &str, args: Vec<Value>) -> CallOutcome {
    ds.call_wait(g, m, args, None)
}

#[test]
fn the_same_seed_gives_the_same_world() {
    let snap = |seed| {
        let (ds, s) = sim(SimConfig { seed, ..SimConfig::default() });
        run(&s, 30.0);
        ds.quiesce();
        ds.snapshot(ds.resolve(&["vehicles"]).unwrap()).unwrap()
    };
    let a = snap(42);
    assert_eq!(a, snap(42));
    assert_ne!(a, snap(43));
    assert_eq!(a.children.len(), 4);
}

#[test]
fn vehicles_appear_over_time() {
    let (_ds, s) = sim(SimConfig { appear_every: 1.0, ..quiet() });
    s.step(0.05);
    assert_eq!(s.vehicle_names(), ["usv1"]);
    run(&s, 1.0);
    assert_eq!(s.vehicle_names(), ["usv1", "ugv1"]);
    run(&s, 2.0);
    assert_eq!(s.vehicle_names(), ["usv1", "ugv1", "uav1", "usv2"]);
}

#[test]
fn the_world_model_follows_the_conventions() {
    let (ds, s) = sim(quiet());
    s.step(0.05);
    let usv = v(&ds, "usv1");
    let info = ds.info(usv).unwrap();
    assert_eq!((&*info.kind, &*info.subtype), ("usv", "boat"));
    let nav = ds.resolve(&["vehicles", "usv1", "nav"]).unwrap();
    for (p, units) in
        [("speed", "m/s"), ("heading", "deg"), ("x", "m"), ("lat", "deg"), ("goal_throttle", "%")]
    {
        assert_eq!(ds.meta(nav, p).unwrap().units.as_deref(), Some(units), "{p}");
    }
    // Goals are range-checked.
    assert!(ds.set(nav, "goal_throttle", Value::Float(150.0)).is_err());
    assert!(ds.set(nav, "goal_rudder", Value::Float(-31.0)).is_err());
    assert!(ds.resolve(&["vehicles", "uav1", "cameras", "payload"]).is_some());
    assert!(ds.resolve(&["vehicles", "ugv1", "cameras", "drive"]).is_some());
    assert!(ds.get(v(&ds, "ugv1"), "battery_v").unwrap().as_f64().unwrap() > 20.0);
}

#[test]
fn kinematics_follow_the_goals() {
    let (ds, s) = sim(quiet());
    s.step(0.05);
    let usv = v(&ds, "usv1");
    let nav = ds.resolve(&["vehicles", "usv1", "nav"]).unwrap();
    ds.set(nav, "goal_throttle", Value::Float(50.0)).unwrap();
    // Engine off: the goal does nothing.
    run(&s, 5.0);
    assert_eq!(num(&ds, &["vehicles", "usv1", "nav"], "speed"), 0.0);
    assert!(call(&ds, usv, "arm", vec![Value::Bool(true)]).is_accepted());
    assert!(call(&ds, usv, "start_engine", vec![]).is_accepted());
    let fuel0 = num(&ds, &["vehicles", "usv1"], "fuel");
    let h0 = num(&ds, &["vehicles", "usv1", "nav"], "heading");
    run(&s, 20.0);
    let speed = num(&ds, &["vehicles", "usv1", "nav"], "speed");
    assert!((speed - 4.0).abs() < 0.05, "50% of 8 m/s, got {speed}");
    assert_eq!(num(&ds, &["vehicles", "usv1", "nav"], "heading"), h0, "no rudder, no turn");
    assert!(num(&ds, &["vehicles", "usv1"], "fuel") < fuel0);
    ds.set(nav, "goal_rudder", Value::Float(15.0)).unwrap();
    run(&s, 2.0);
    let turned = (num(&ds, &["vehicles", "usv1", "nav"], "heading") - h0).rem_euclid(360.0);
    assert!(turned > 10.0 && turned < 30.0, "half rudder turns right ~10°/s: {turned}");
    // Stop zeroes the goals and the vehicle slows down.
    assert!(call(&ds, usv, "stop", vec![]).is_accepted());
    assert_eq!(ds.get(nav, "goal_throttle").unwrap(), Value::Float(0.0));
    run(&s, 15.0);
    assert!(num(&ds, &["vehicles", "usv1", "nav"], "speed") < 0.1);
}

#[test]
fn refusals_carry_reasons() {
    let (ds, s) = sim(quiet());
    s.step(0.05);
    let usv = v(&ds, "usv1");
    assert_eq!(
        call(&ds, usv, "start_engine", vec![]),
        CallOutcome::Refused("not armed: arm before starting the engine".into())
    );
    assert!(call(&ds, usv, "arm", vec![Value::Bool(true)]).is_accepted());
    s.set_fuel("usv1", 0.0);
    assert_eq!(
        call(&ds, usv, "start_engine", vec![]),
        CallOutcome::Refused("no fuel: usv1 cannot start its engine".into())
    );
    let op = |n: &str| vec![Value::str(n)];
    assert!(call(&ds, usv, "request_control", op("alice")).is_accepted());
    assert_eq!(ds.get(usv, "control").unwrap(), Value::str("alice"));
    assert_eq!(
        call(&ds, usv, "request_control", op("bob")),
        CallOutcome::Refused("control held by alice".into())
    );
    let routes = ds.resolve(&["vehicles", "usv1", "routes"]).unwrap();
    let empty = match call(&ds, routes, "create_route", op("empty")) {
        CallOutcome::Accepted(r) => r[0].clone(),
        other => panic!("{other:?}"),
    };
    assert_eq!(
        call(&ds, usv, "assign_route", vec![empty]),
        CallOutcome::Refused("route `empty` has no waypoints".into())
    );
    assert!(matches!(call(&ds, usv, "set_mode", op("warp")), CallOutcome::Refused(_)));
    assert_eq!(
        call(&ds, usv, "goto", vec![Value::Float(1.0), Value::Float(2.0), Value::Float(0.0)]),
        CallOutcome::Refused("engine is off".into())
    );
}

#[test]
fn routes_are_chains_edited_by_insert_between_and_delete_and_promote() {
    let (ds, s) = sim(quiet());
    s.step(0.05);
    let patrol = ds.resolve(&["vehicles", "usv1", "routes", "patrol"]).unwrap();
    let xs = |ds: &DataServer| -> Vec<(f64, f64)> {
        route_waypoints(ds, patrol)
            .iter()
            .map(|w| mocu_host::world::pair(ds, *w, "x", "y").unwrap())
            .collect()
    };
    let before = xs(&ds);
    assert_eq!(before.len(), 4);
    // The chain: the second waypoint is the child of the first.
    let wps = route_waypoints(&ds, patrol);
    assert_eq!(ds.parent(wps[1]).unwrap(), Some(wps[0]));
    let args = vec![Value::Int(1), Value::Float(7.0), Value::Float(8.0)];
    assert!(call(&ds, patrol, "insert_waypoint", args).is_accepted());
    let after = xs(&ds);
    assert_eq!(after.len(), 5);
    assert_eq!(after[1], (7.0, 8.0));
    assert_eq!((after[0], &after[2..]), (before[0], &before[1..]));
    assert_eq!(ds.get(patrol, "count").unwrap(), Value::Int(5));
    assert!(ds.get(route_waypoints(&ds, patrol)[1], "lat").is_ok(), "local routes get lat/lon too");
    // Delete the first: the second is promoted into its place under the route.
    assert!(call(&ds, patrol, "delete_waypoint", vec![Value::Int(0)]).is_accepted());
    assert_eq!(xs(&ds), after[1..]);
    assert_eq!(ds.parent(route_waypoints(&ds, patrol)[0]).unwrap(), Some(patrol));
    // Delete the last.
    assert!(call(&ds, patrol, "delete_waypoint", vec![Value::Int(3)]).is_accepted());
    assert_eq!(xs(&ds), after[1..4]);
    assert!(matches!(
        call(&ds, patrol, "delete_waypoint", vec![Value::Int(9)]),
        CallOutcome::Refused(_)
    ));
}

#[test]
fn an_assigned_route_is_followed_to_its_end() {
    let (ds, s) = sim(quiet());
    s.step(0.05);
    let usv = v(&ds, "usv1");
    let patrol = ds.resolve(&["vehicles", "usv1", "routes", "patrol"]).unwrap();
    assert!(call(&ds, usv, "arm", vec![Value::Bool(true)]).is_accepted());
    assert!(call(&ds, usv, "start_engine", vec![]).is_accepted());
    assert!(call(&ds, usv, "assign_route", vec![Value::Guid(patrol)]).is_accepted());
    assert_eq!(ds.get(usv, "mode").unwrap(), Value::str("route"));
    run(&s, 240.0);
    assert_eq!(ds.get(usv, "mode").unwrap(), Value::str("hold"));
    let last = *route_waypoints(&ds, patrol).last().unwrap();
    let (wx, wy) = mocu_host::world::pair(&ds, last, "x", "y").unwrap();
    let (x, y) =
        (num(&ds, &["vehicles", "usv1", "nav"], "x"), num(&ds, &["vehicles", "usv1", "nav"], "y"));
    assert!(((x - wx).powi(2) + (y - wy).powi(2)).sqrt() < 15.0, "ended near the last waypoint");
}

#[test]
fn camera_frames_flow_through_the_listener() {
    let (ds, s) = sim(quiet());
    s.step(0.05);
    let cam = ds.resolve(&["vehicles", "usv1", "cameras", "drive"]).unwrap();
    let display = ds.create_object(ds.root(), ObjectInfo::new("display", "window")).unwrap();
    type Frames = Arc<Mutex<Vec<(usize, i64, i64, i64)>>>;
    let got: Frames = Arc::default();
    let g = got.clone();
    ds.publish_method(
        display,
        MethodSpec::new("frame")
            .param(ParamSpec::new("rgb", ValueKind::Bytes))
            .param(ParamSpec::new("width", ValueKind::Int))
            .param(ParamSpec::new("height", ValueKind::Int))
            .param(ParamSpec::new("n", ValueKind::Int)),
        move |c: Call| {
            let Value::Bytes(px) = &c.args[0] else { panic!("bytes") };
            let a = |i: usize| c.args[i].as_i64().unwrap();
            g.lock().unwrap().push((px.len(), a(1), a(2), a(3)));
            c.responder.accept(vec![]);
        },
    )
    .unwrap();
    // Room for every frame of the second: the test checks that none is lost, whatever the
    // scheduling (DropOldest only drops when the queue is full).
    ds.join(cam, display, "frame", Overflow::DropOldest, 64).unwrap();
    run(&s, 1.0);
    ds.quiesce();
    let frames = got.lock().unwrap().clone();
    assert!(frames.len() >= 9 && frames.len() <= 11, "10 fps for 1 s: {}", frames.len());
    assert_eq!(frames[0].0, 640 * 480 * 3, "640x480 RGB by default");
    assert_eq!((frames[0].1, frames[0].2), (640, 480));
    assert!(frames.windows(2).all(|w| w[1].3 == w[0].3 + 1), "in order, none lost");
    assert_eq!(ds.get(cam, "frames").unwrap(), Value::Int(*frames.last().map(|f| &f.3).unwrap()));
}

#[test]
fn the_vehicles_setting_names_the_vehicles_in_the_order_they_appear() {
    let list = toml::Value::Array(["uav_north", "usv7", "usv2"].map(toml::Value::from).to_vec());
    let spec = mocu_host::ModuleSpec::new("sim").with("vehicles", list).with("autostart", true);
    let cfg = SimConfig::from_spec(&spec).unwrap();
    let (ds, s) = sim(SimConfig { appear_every: 1.0, ..cfg });
    run(&s, 2.5);
    assert_eq!(s.vehicle_names(), ["uav_north", "usv7", "usv2"]);
    let kind = |n: &str| ds.info(v(&ds, n)).unwrap().kind.to_string();
    assert_eq!((kind("uav_north"), kind("usv7")), ("uav".to_string(), "usv".to_string()));
    // Autostart: the first of each type arms; the second waits for the operator.
    let armed = |n: &str| ds.get(v(&ds, n), "armed").unwrap() == Value::Bool(true);
    assert!(armed("usv7") && armed("uav_north") && !armed("usv2"));
}

#[test]
fn the_vehicles_setting_refuses_untyped_names_duplicates_and_counts_beside_it() {
    let names = |v: &[&str]| toml::Value::Array(v.iter().map(|s| toml::Value::from(*s)).collect());
    for (spec, why) in [
        (
            mocu_host::ModuleSpec::new("sim").with("vehicles", names(&["boat1"])),
            "start with its type",
        ),
        (
            mocu_host::ModuleSpec::new("sim").with("vehicles", names(&["usv1", "usv1"])),
            "named twice",
        ),
        (
            mocu_host::ModuleSpec::new("sim").with("vehicles", names(&["usv1"])).with("usv", 2),
            "either",
        ),
        (mocu_host::ModuleSpec::new("sim").with("vehicles", "usv1"), "list of names"),
    ] {
        let e = SimConfig::from_spec(&spec).unwrap_err();
        assert!(e.contains(why), "{e}");
    }
}

/// What the simulator writes every step declares its rate (`PropMeta::rate_hz`), so that
/// a display ages it after three missed steps; what the operator sets does not.
#[test]
fn telemetry_declares_the_step_rate_and_operator_goals_do_not() {
    let (ds, sim) = sim(SimConfig { rate_hz: 10.0, ..quiet() });
    run(&sim, 0.1);
    let usv = v(&ds, "usv1");
    let nav = ds.resolve(&["vehicles", "usv1", "nav"]).unwrap();
    for (g, p) in [(usv, "fuel"), (usv, "link"), (usv, "mode"), (nav, "speed"), (nav, "heading")] {
        assert_eq!(ds.meta(g, p).unwrap().rate_hz, Some(10.0), "{p}");
    }
    assert_eq!(ds.meta(nav, "goal_throttle").unwrap().rate_hz, None);
    assert_eq!(ds.meta(usv, "name").unwrap().rate_hz, None);
}

/// The camera size is a module setting; past 1920x1080 it is refused with the limits.
#[test]
fn the_camera_size_is_a_setting_within_limits() {
    let spec =
        mocu_host::ModuleSpec::new("sim").with("camera_width", 320).with("camera_height", 240);
    let cfg = SimConfig::from_spec(&spec).unwrap();
    assert_eq!((cfg.camera_width, cfg.camera_height), (320, 240));
    let (ds, s) = sim(SimConfig { camera_width: 320, camera_height: 240, ..quiet() });
    s.step(0.05);
    let cam = ds.resolve(&["vehicles", "usv1", "cameras", "payload"]).unwrap();
    assert_eq!(ds.get(cam, "width").unwrap(), Value::Int(320));
    let big = mocu_host::ModuleSpec::new("sim").with("camera_width", 4000);
    assert!(SimConfig::from_spec(&big).unwrap_err().contains("1..=1920"));
}

/// Every vehicle has a payload camera on a head of its own: `point_payload` turns it
/// (published as the camera's `pan` and `tilt`) and refuses what the head cannot reach.
#[test]
fn the_payload_head_is_pointed_by_its_method() {
    let (ds, s) = sim(quiet());
    run(&s, 2.0);
    for name in ["usv1", "ugv1", "uav1"] {
        assert!(ds.resolve(&["vehicles", name, "cameras", "payload"]).is_some(), "{name}");
    }
    let usv = v(&ds, "usv1");
    let cam = ds.resolve(&["vehicles", "usv1", "cameras", "payload"]).unwrap();
    let out = call(&ds, usv, "point_payload", vec![Value::Float(-45.0), Value::Float(-10.0)]);
    assert!(out.is_accepted(), "{out:?}");
    assert_eq!(ds.get(cam, "pan").unwrap(), Value::Float(-45.0));
    assert_eq!(ds.get(cam, "tilt").unwrap(), Value::Float(-10.0));
    let out = call(&ds, usv, "point_payload", vec![Value::Float(0.0), Value::Float(60.0)]);
    assert!(matches!(&out, CallOutcome::Refused(r) if r.contains("tilts -90..30")), "{out:?}");
}

/// The UGV's manipulator: joints and gripper published, moved by its methods at a limited
/// rate (so `moving` shows while they travel), goals outside a joint's range refused.
#[test]
fn the_ugv_manipulator_moves_its_joints_and_gripper_toward_their_goals() {
    let (ds, s) = sim(quiet());
    run(&s, 2.0);
    assert!(ds.resolve(&["vehicles", "usv1", "manipulator"]).is_none(), "only UGVs have one");
    let m = ds.resolve(&["vehicles", "ugv1", "manipulator"]).unwrap();
    let get = |p: &str| ds.get(m, p).unwrap();
    assert_eq!(get("shoulder"), Value::Float(35.0));
    assert_eq!(get("gripper_state"), Value::str("open"));
    let out = call(
        &ds,
        m,
        "move_joints",
        vec![Value::Float(65.0), Value::Float(70.0), Value::Float(0.0)],
    );
    assert!(out.is_accepted(), "{out:?}");
    let out = call(&ds, m, "grip", vec![Value::Bool(true)]);
    assert!(out.is_accepted(), "{out:?}");
    s.step(0.5);
    ds.quiesce();
    assert_eq!(get("shoulder"), Value::Float(50.0), "30 deg/s for 0.5 s");
    assert_eq!(get("moving"), Value::Bool(true));
    assert_eq!(get("gripper_state"), Value::str("moving"));
    run(&s, 2.0);
    ds.quiesce();
    assert_eq!((get("shoulder"), get("wrist")), (Value::Float(65.0), Value::Float(0.0)));
    assert_eq!((get("moving"), get("gripper_state")), (Value::Bool(false), Value::str("closed")));
    let out =
        call(&ds, m, "move_joints", vec![Value::Float(95.0), Value::Float(0.0), Value::Float(0.0)]);
    assert!(matches!(&out, CallOutcome::Refused(r) if r.contains("shoulder 95")), "{out:?}");
    assert!(call(&ds, m, "stow", vec![]).is_accepted());
    run(&s, 5.0);
    ds.quiesce();
    assert_eq!(get("elbow"), Value::Float(0.0));
}

/// A route edited in the world model while the vehicle flies it (a waypoint moved on the
/// map) is flown as edited: the vehicle heads for the waypoint's new place.
#[test]
fn a_waypoint_moved_while_the_route_is_flown_is_flown_to_where_it_is_now() {
    let cfg = SimConfig { usv: 1, ugv: 0, uav: 0, appear_every: 0.0, ..SimConfig::default() };
    let (ds, sim) = sim(cfg);
    run(&sim, 0.1);
    let usv = v(&ds, "usv1");
    let route = ds.resolve(&["vehicles", "usv1", "routes", "patrol"]).unwrap();
    let wps = route_waypoints(&ds, route);
    let next = ds.get(usv, "route_next").unwrap().as_i64().unwrap() as usize;
    let far = (num(&ds, &["vehicles", "usv1", "nav"], "x") + 400.0, 0.0);
    ds.set(wps[next], "x", Value::Float(far.0)).unwrap();
    ds.set(wps[next], "y", Value::Float(far.1)).unwrap();
    run(&sim, 60.0);
    let (x, y) =
        (num(&ds, &["vehicles", "usv1", "nav"], "x"), num(&ds, &["vehicles", "usv1", "nav"], "y"));
    assert!((x - far.0).hypot(y - far.1) < 100.0, "usv1 at {x}, {y}, the waypoint at {far:?}");
}
