//! The MAVLink module against a real peer written by others: a vehicle played by pymavlink
//! (tests/peers/mav_vehicle.py) on loopback. CI installs pymavlink; without python3 and
//! pymavlink this test fails and says so.

use mocu_dataserver::{CallOutcome, DataServer, Guid, Topic, Value};
use mocu_host::{ModuleHost, ModuleSpec, Registry};
use std::io::{BufRead, BufReader, Write};
use std::process::{Child, Command, Stdio};
use std::sync::{Arc, Condvar, Mutex};
use std::time::Duration;

struct Peer {
    child: Child,
    /// What the peer printed, and a signal at each new line.
    lines: Arc<(Mutex<Vec<String>>, Condvar)>,
}

impl Peer {
    fn start(port: u16, sysid: u8, extra: &[&str]) -> Peer {
        let script = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/peers/mav_vehicle.py");
        let check = Command::new("python3").args(["-c", "import pymavlink"]).output();
        match check {
            Ok(o) if o.status.success() => {}
            _ => panic!(
                "this test needs python3 with pymavlink: `python3 -m pip install pymavlink==2.4.50` \
                 (CI installs it in .ci/run)"
            ),
        }
        let mut child = Command::new("python3")
            .arg(script)
            .args(["--port", &port.to_string(), "--sysid", &sysid.to_string()])
            .args(extra)
            .stdin(Stdio::piped())
            .stdout(Stdio::piped())
            .stderr(Stdio::inherit())
            .spawn()
            .expect("starting the pymavlink vehicle");
        let lines = Arc::new((Mutex::new(Vec::new()), Condvar::new()));
        let out = child.stdout.take().expect("piped stdout");
        let l = lines.clone();
        std::thread::spawn(move || {
            for line in BufReader::new(out).lines().map_while(Result::ok) {
                l.0.lock().unwrap().push(line);
                l.1.notify_all();
            }
        });
        Peer { child, lines }
    }

    fn tell(&mut self, line: &str) {
        let stdin = self.child.stdin.as_mut().expect("piped stdin");
        writeln!(stdin, "{line}").expect("writing to the peer");
        stdin.flush().unwrap();
    }

    /// The lines starting with `prefix` once there are `n` of them (the peer prints what it
    /// received on its own time: an acknowledged upload may still be on its way to us).
    fn said_n(&self, prefix: &str, n: usize) -> Vec<String> {
        let (lock, signal) = &*self.lines;
        let count = |l: &Vec<String>| l.iter().filter(|l| l.starts_with(prefix)).count();
        let lines = lock.lock().unwrap();
        let (lines, _) =
            signal.wait_timeout_while(lines, Duration::from_secs(30), |l| count(l) < n).unwrap();
        lines.iter().filter(|l| l.starts_with(prefix)).cloned().collect()
    }
}

impl Drop for Peer {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

/// Waits until `f` gives a value, checking it again at each change of `topics` (what the
/// peer's packets publish); the 30 s bound only turns a hang into a failure.
fn wait_for<T>(
    ds: &DataServer,
    topics: &[Topic],
    what: &str,
    mut f: impl FnMut() -> Option<T>,
) -> T {
    let (tx, rx) = std::sync::mpsc::channel();
    let subs: Vec<_> = topics
        .iter()
        .map(|t| {
            let tx = tx.clone();
            ds.subscribe(t.clone(), move |_| {
                let _ = tx.send(());
            })
            .unwrap()
        })
        .collect();
    let found = loop {
        if let Some(v) = f() {
            break Some(v);
        }
        if rx.recv_timeout(Duration::from_secs(30)).is_err() {
            break None;
        }
    };
    for s in subs {
        ds.unsubscribe(s);
    }
    found.unwrap_or_else(|| panic!("never: {what}"))
}

fn num(ds: &DataServer, g: Guid, p: &str) -> Option<f64> {
    ds.try_get(g, p.into()).and_then(|v| v.as_f64())
}

fn call(ds: &DataServer, g: Guid, m: &str, args: Vec<Value>) -> CallOutcome {
    ds.call_wait(g, m, args, None)
}

/// The MAVLink module on a loopback port, and a pymavlink vehicle of system id `sysid` sending
/// to it.
fn connect(sysid: u8) -> (DataServer, ModuleHost, Peer) {
    connect_with(sysid, &[])
}

/// [`connect`], the peer started with `extra` arguments.
fn connect_with(sysid: u8, extra: &[&str]) -> (DataServer, ModuleHost, Peer) {
    let ds = DataServer::default();
    let mut reg = Registry::new();
    mocu_mavlink::register(&mut reg);
    let mut host = ModuleHost::new(ds.clone(), reg);
    let spec = ModuleSpec::new("mavlink")
        .with("address", "127.0.0.1:0")
        .with("command_timeout_ms", 500)
        .with("link_timeout_ms", 3000);
    host.start(&spec).expect("the MAVLink module starts");
    let status = ds.resolve(&["modules", "mavlink"]).unwrap();
    let addr = ds.get(status, "address").unwrap();
    let port: u16 = addr.as_str().unwrap().rsplit(':').next().unwrap().parse().unwrap();
    let peer = Peer::start(port, sysid, extra);
    (ds, host, peer)
}

#[test]
fn a_pymavlink_vehicle_is_discovered_monitored_and_commanded() {
    let (ds, mut host, mut peer) = connect(7);
    let status = ds.resolve(&["modules", "mavlink"]).unwrap();

    // Discovery by HEARTBEAT.
    let vehicles = ds.resolve(&["vehicles"]).unwrap();
    let v = wait_for(&ds, &[Topic::children(vehicles)], "mav7 to be discovered", || {
        ds.resolve(&["vehicles", "mav7"])
    });
    let info = ds.info(v).unwrap();
    assert_eq!((&*info.kind, &*info.subtype), ("uav", "quadrotor"));
    // Its `nav` is made just after it: waited for as the vehicle was.
    let nav = wait_for(&ds, &[Topic::children(v)], "mav7's nav", || {
        ds.resolve(&["vehicles", "mav7", "nav"])
    });

    // Telemetry with units.
    wait_for(&ds, &[Topic::properties(nav), Topic::properties(v)], "telemetry", || {
        (num(&ds, nav, "satellites")? == 11.0 && num(&ds, v, "battery_v")? > 0.0).then_some(())
    });
    assert!((num(&ds, nav, "lat").unwrap() - 32.7157).abs() < 1e-6);
    assert!((num(&ds, nav, "lon").unwrap() + 117.1611).abs() < 1e-6);
    assert!((num(&ds, nav, "alt").unwrap() - 12.345).abs() < 1e-9);
    assert!((num(&ds, nav, "speed").unwrap() - 5.0).abs() < 1e-9);
    assert!((num(&ds, nav, "heading").unwrap() - 90.0).abs() < 1e-9);
    assert!((num(&ds, nav, "roll").unwrap() - 0.1f32.to_degrees() as f64).abs() < 1e-3);
    assert!((num(&ds, nav, "throttle").unwrap() - 42.0).abs() < 1e-9);
    assert!((num(&ds, v, "battery_v").unwrap() - 12.6).abs() < 1e-9);
    assert!((num(&ds, v, "fuel").unwrap() - 0.87).abs() < 1e-9);
    assert_eq!(ds.get(nav, "gps_fix").unwrap(), Value::str("3D_FIX"));
    assert_eq!(ds.meta(nav, "speed").unwrap().units.as_deref(), Some("m/s"));
    assert_eq!(ds.meta(nav, "alt").unwrap().units.as_deref(), Some("m"));
    assert_eq!(ds.get(v, "mode").unwrap(), Value::str("STABILIZE"));
    assert_eq!(ds.get(v, "armed").unwrap(), Value::Bool(false));
    // Every telemetry value declares a rate (a display ages it after three periods without
    // a write), none above what this peer streams (mav_vehicle.py: SYS_STATUS 1 Hz, the
    // rest 10 Hz): its fresh telemetry is never taken as stale.
    for (g, p, peer_hz) in [
        (nav, "speed", 10.0),
        (nav, "heading", 10.0),
        (nav, "roll", 10.0),
        (nav, "throttle", 10.0),
        (nav, "satellites", 10.0),
        (v, "fuel", 1.0),
        (v, "battery_v", 1.0),
    ] {
        let hz = ds.meta(g, p).unwrap().rate_hz.unwrap_or_else(|| panic!("{p} declares a rate"));
        assert!(hz <= peer_hz, "{p}: declared {hz} Hz, the peer sends {peer_hz} Hz");
    }

    // Commands go only to an address that proved itself with heartbeats in sequence.
    wait_for(&ds, &[Topic::properties(v)], "the vehicle's address verified", || {
        (ds.get(v, "verified").ok()? == Value::Bool(true)).then_some(())
    });
    // Arm: accepted, and the next heartbeat shows it.
    assert_eq!(call(&ds, v, "arm", vec![Value::Bool(true)]), CallOutcome::Accepted(vec![]));
    wait_for(&ds, &[Topic::properties(v)], "armed in the heartbeat", || {
        (ds.get(v, "armed").ok()? == Value::Bool(true)).then_some(())
    });
    // Set mode by name.
    assert!(call(&ds, v, "set_mode", vec![Value::str("guided")]).is_accepted());
    wait_for(&ds, &[Topic::properties(v)], "GUIDED in the heartbeat", || {
        (ds.get(v, "mode").ok()? == Value::str("GUIDED")).then_some(())
    });
    match call(&ds, v, "set_mode", vec![Value::str("WARP")]) {
        CallOutcome::Refused(why) => assert!(why.contains("unknown mode `WARP`"), "{why}"),
        other => panic!("expected a refusal, got {other:?}"),
    }
    // Go to a position (COMMAND_INT) and return home.
    let goto = vec![Value::Float(32.72), Value::Float(-117.16), Value::Float(30.0)];
    assert!(call(&ds, v, "goto", goto).is_accepted());
    assert!(call(&ds, v, "return_home", vec![]).is_accepted());
    // A refused command shows the vehicle's reason.
    assert_eq!(call(&ds, v, "land", vec![]), CallOutcome::Refused("MAV_RESULT_DENIED".into()));

    // Mission upload: a route of three waypoints.
    let routes = ds.resolve(&["vehicles", "mav7", "routes"]).unwrap();
    let route = match call(&ds, routes, "create_route", vec![Value::str("survey")]) {
        CallOutcome::Accepted(r) => r[0].as_guid().unwrap(),
        other => panic!("create_route: {other:?}"),
    };
    match call(&ds, v, "upload_route", vec![Value::Guid(route)]) {
        CallOutcome::Refused(why) => assert!(why.contains("no waypoints"), "{why}"),
        other => panic!("uploading an empty route: {other:?}"),
    }
    for (i, (lat, lon)) in
        [(32.716, -117.161), (32.717, -117.162), (32.718, -117.160)].iter().enumerate()
    {
        let args = vec![Value::Int(i as i64), Value::Float(*lat), Value::Float(*lon)];
        assert!(call(&ds, route, "insert_waypoint", args).is_accepted());
    }
    assert_eq!(
        call(&ds, v, "upload_route", vec![Value::Guid(route)]),
        CallOutcome::Accepted(vec![Value::Int(3)])
    );
    let items = peer.said_n("mission_item", 3);
    assert_eq!(items.len(), 3, "{items:?}");
    assert!(items[1].starts_with("mission_item 1 32.717"), "{items:?}");

    // Malformed and unknown packets were counted, not fatal.
    wait_for(&ds, &[Topic::properties(status)], "counters", || {
        (num(&ds, status, "malformed")? >= 1.0 && num(&ds, status, "unknown")? >= 1.0).then_some(())
    });

    // Link loss without a heartbeat, recovery when they return (the 3 s timeout itself is
    // checked on a clock the test controls: tests/mavlink_link_loss.rs).
    assert_eq!(ds.get(v, "link_lost").unwrap(), Value::Bool(false));
    peer.tell("silence 5");
    wait_for(&ds, &[Topic::properties(v)], "link lost", || {
        (ds.get(v, "link_lost").ok()? == Value::Bool(true)).then_some(())
    });
    assert_eq!(ds.get(v, "stale").unwrap(), Value::Bool(true));
    match call(&ds, v, "arm", vec![Value::Bool(false)]) {
        CallOutcome::Failed(why) => assert!(why.contains("link lost"), "{why}"),
        other => panic!("a command while the link is lost: {other:?}"),
    }
    wait_for(&ds, &[Topic::properties(v)], "link recovered", || {
        (ds.get(v, "link_lost").ok()? == Value::Bool(false)).then_some(())
    });
    assert_eq!(ds.get(v, "stale").unwrap(), Value::Bool(false));
    peer.tell("quit");
    host.stop_all();
}

/// A waypoint's latitude moved as the map moves it (a change of that waypoint only).
fn move_lat(ds: &DataServer, route: Guid, index: usize, lat: f64) {
    let wp = mocu_host::world::route_waypoints(ds, route)[index];
    ds.set(wp, "lat", Value::Float(lat)).unwrap();
}

/// The peer's `partial_item` lines as (seq, lat).
fn partial_items(peer: &Peer, n: usize) -> Vec<(u16, f64)> {
    peer.said_n("partial_item ", n)
        .iter()
        .map(|l| {
            let w: Vec<&str> = l.split_whitespace().collect();
            (w[1].parse().unwrap(), w[2].parse().unwrap())
        })
        .collect()
}

#[test]
fn an_uploaded_route_edited_in_the_world_model_sends_only_the_changed_waypoints() {
    let (ds, mut host, mut peer) = connect(8);
    let vehicles = ds.resolve(&["vehicles"]).unwrap();
    let v = wait_for(&ds, &[Topic::children(vehicles)], "mav8 to be discovered", || {
        ds.resolve(&["vehicles", "mav8"])
    });
    wait_for(&ds, &[Topic::properties(v)], "the vehicle's address verified", || {
        (ds.get(v, "verified").ok()? == Value::Bool(true)).then_some(())
    });
    let routes = ds.resolve(&["vehicles", "mav8", "routes"]).unwrap();
    let route = match call(&ds, routes, "create_route", vec![Value::str("survey")]) {
        CallOutcome::Accepted(r) => r[0].as_guid().unwrap(),
        other => panic!("create_route: {other:?}"),
    };
    for i in 0..4 {
        let at =
            vec![Value::Int(i), Value::Float(32.716 + 0.001 * i as f64), Value::Float(-117.16)];
        assert!(call(&ds, route, "insert_waypoint", at).is_accepted());
    }
    let uploaded = call(&ds, v, "upload_route", vec![Value::Guid(route)]);
    assert_eq!(uploaded, CallOutcome::Accepted(vec![Value::Int(4)]));
    assert_eq!(peer.said_n("mission_item ", 4).len(), 4);
    assert_eq!(ds.get(v, "route").unwrap(), Value::Guid(route));
    let synced = || {
        wait_for(&ds, &[Topic::properties(v)], "the route synced", || {
            (ds.get(v, "route_synced").ok()? == Value::Bool(true)).then_some(())
        })
    };
    synced();

    // One waypoint moved: a partial write of that item alone.
    move_lat(&ds, route, 2, 32.7251);
    assert_eq!(peer.said_n("partial ", 1), ["partial 2 2"]);
    assert_eq!(partial_items(&peer, 1), [(2, 32.7251)]);
    synced();
    // Two waypoints apart: one partial write each, never the unchanged ones between them.
    move_lat(&ds, route, 0, 32.7102);
    move_lat(&ds, route, 3, 32.7303);
    assert_eq!(peer.said_n("partial ", 3), ["partial 2 2", "partial 0 0", "partial 3 3"]);
    assert_eq!(partial_items(&peer, 3), [(2, 32.7251), (0, 32.7102), (3, 32.7303)]);
    synced();
    // A waypoint inserted changes the count: the protocol has no insert, the whole route goes.
    let at = vec![Value::Int(1), Value::Float(32.7111), Value::Float(-117.161)];
    assert!(call(&ds, route, "insert_waypoint", at).is_accepted());
    assert_eq!(peer.said_n("mission ", 2), ["mission 4", "mission 5"]);
    assert_eq!(peer.said_n("mission_item ", 9).len(), 9);
    synced();

    // A vehicle that refuses partial writes gets the whole route, and from then on only that.
    peer.tell("refuse_partial");
    peer.said_n("refusing partial writes", 1);
    move_lat(&ds, route, 4, 32.7404);
    assert_eq!(peer.said_n("partial_refused ", 1), ["partial_refused 4 4"]);
    assert_eq!(peer.said_n("mission ", 3), ["mission 4", "mission 5", "mission 5"]);
    let items = peer.said_n("mission_item ", 14);
    assert!(items[13].starts_with("mission_item 4 32.7404"), "{items:?}");
    synced();
    move_lat(&ds, route, 1, 32.7122);
    assert_eq!(peer.said_n("mission ", 4).len(), 4);
    let items = peer.said_n("mission_item ", 19);
    assert!(items[15].starts_with("mission_item 1 32.7122"), "{items:?}");
    synced();
    // Everything the vehicle was sent, counted once the last upload is done.
    assert_eq!(peer.said_n("partial ", 0).len(), 3);
    assert_eq!(peer.said_n("partial_item ", 0).len(), 3);
    assert_eq!(peer.said_n("partial_refused ", 0).len(), 1);
    peer.tell("quit");
    host.stop_all();
}

/// MAVLink's GCS operator-control protocol (development dialect) through the adapter's
/// arbiter: a vehicle held by another ground station (GCS 200, takeover not allowed) shows
/// that holder and refuses our request with the reason; once GCS 200 lets go, an operator's
/// request asks the vehicle (MAV_CMD_REQUEST_OPERATOR_CONTROL), which grants this adapter's
/// system id; releasing the last holder gives the vehicle's control back.
#[test]
fn a_vehicle_speaking_the_operator_control_protocol_is_arbitrated_through_it() {
    use mocu_distrib::arbiter::{Arbiter, Settings};
    use mocu_distrib::control::Caller;
    let (ds, mut host, mut peer) = connect_with(9, &["--gcs-control", "200"]);
    let arbiter =
        Arbiter::start(&ds, Settings::default(), Caller::new("alice", "adapter")).unwrap();
    let vehicles = ds.resolve(&["vehicles"]).unwrap();
    let v = wait_for(&ds, &[Topic::Children { object: vehicles }], "the vehicle", || {
        ds.children(vehicles).ok()?.first().copied()
    });
    let s = |g: Guid, p: &str| ds.try_get(g, p.into()).and_then(|v| v.as_str().map(String::from));
    wait_for(&ds, &[Topic::properties(v)], "CONTROL_STATUS heard, the address proved", || {
        let proved = ds.try_get(v, "verified".into()) == Some(Value::Bool(true));
        (s(v, "control")? == "gcs 200" && proved).then_some(())
    });
    let arb = wait_for(&ds, &[Topic::Children { object: v }], "the arbitration object", || {
        ds.find_child(v, "arbitration").ok().flatten()
    });
    wait_for(&ds, &[Topic::properties(arb)], "gcs 200 shown as the holder", || {
        (s(arb, "holder")? == "gcs 200").then_some(())
    });

    // Held elsewhere, takeover not allowed: the vehicle refuses, and says who holds it.
    let out = call(&ds, arb, "request", vec![]);
    let CallOutcome::Refused(why) = &out else { panic!("{out:?}") };
    assert!(why.contains("gcs 200"), "{why}");
    assert_eq!(arbiter.holder(&ds.info(v).unwrap().name), Some(String::new()));

    // GCS 200 lets go; alice's request is the vehicle's to grant, to this adapter (255).
    peer.tell("gcs_release");
    wait_for(&ds, &[Topic::properties(v)], "the vehicle free", || {
        (s(v, "control")?.is_empty()).then_some(())
    });
    assert_eq!(call(&ds, arb, "request", vec![]), CallOutcome::Accepted(vec![]));
    assert!(peer.said_n("control 255", 1).len() == 1, "the vehicle granted 255");
    wait_for(&ds, &[Topic::properties(v)], "alice in control", || {
        (s(v, "control")? == "alice").then_some(())
    });
    assert_eq!(s(arb, "holder").as_deref(), Some("alice"));

    // The last holder releases: the vehicle's control is given back.
    assert_eq!(call(&ds, arb, "release", vec![]), CallOutcome::Accepted(vec![]));
    assert_eq!(peer.said_n("control 0", 2).len(), 2, "released by gcs 200, then by us");
    wait_for(&ds, &[Topic::properties(v)], "the vehicle free again", || {
        (s(v, "control")?.is_empty()).then_some(())
    });
    arbiter.stop();
    host.stop_all();
}
