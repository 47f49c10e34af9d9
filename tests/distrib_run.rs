//! The distributed world model with real processes on loopback (docs/distribution.md):
//! `mocu serve` as the adapter, `mocu run` OCUs joining it, a Python peer written with
//! eclipse-zenoh alone, and an adapter killed and restarted. Each test picks free ports;
//! every wait is on something a process prints, bounded so that a hang fails.

mod cli_support;
use cli_support::sky_share;
use serde_json::Value as J;
use std::io::{BufRead, BufReader};
use std::net::TcpListener;
use std::process::{Child, Command, Output, Stdio};
use std::sync::{Arc, Condvar, Mutex};
use std::time::Duration;

/// Long enough for a loaded 2-core CI machine; a hang becomes a failure.
const PATIENCE: Duration = Duration::from_secs(90);

fn free_port() -> u16 {
    TcpListener::bind("127.0.0.1:0").unwrap().local_addr().unwrap().port()
}

fn endpoint(port: u16) -> String {
    format!("tcp/127.0.0.1:{port}")
}

type Lines = Arc<(Mutex<Vec<String>>, Condvar)>;

/// A `mocu` process whose stderr is read line by line.
struct Proc {
    child: Child,
    lines: Lines,
}

impl Proc {
    fn start(args: &[&str]) -> Proc {
        let mut child = Command::new(env!("CARGO_BIN_EXE_mocu"))
            .args(args)
            .current_dir(env!("CARGO_MANIFEST_DIR"))
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .expect("mocu starts");
        let lines: Lines = Arc::new((Mutex::new(Vec::new()), Condvar::new()));
        let err = child.stderr.take().unwrap();
        let l = lines.clone();
        std::thread::spawn(move || {
            for line in BufReader::new(err).lines().map_while(Result::ok) {
                l.0.lock().unwrap().push(line);
                l.1.notify_all();
            }
        });
        Proc { child, lines }
    }

    /// The adapter on `port`: the simulator's four vehicles, no MAVLink or video sockets.
    fn serve(port: u16) -> Proc {
        let ep = endpoint(port);
        Proc::start(&["serve", "--listen", &ep, "--mavlink", "off", "--video", "off"])
    }

    /// An adapter serving `profile` on `port`, no MAVLink or video sockets, with `extra`
    /// arguments.
    fn serve_profile(profile: &str, port: u16, extra: &[&str]) -> Proc {
        let ep = endpoint(port);
        let mut args =
            vec!["serve", profile, "--listen", &ep, "--mavlink", "off", "--video", "off"];
        args.extend_from_slice(extra);
        Proc::start(&args)
    }

    /// Waits until a line printed after the first `from` lines satisfies `pred`; returns
    /// how many lines there are then.
    fn wait_line(&self, from: usize, what: &str, pred: impl Fn(&str) -> bool) -> usize {
        let (lock, signal) = &*self.lines;
        let ok = |l: &Vec<String>| l.iter().skip(from).any(|x| pred(x));
        let lines = lock.lock().unwrap();
        let (lines, _) = signal.wait_timeout_while(lines, PATIENCE, |l| !ok(l)).unwrap();
        assert!(ok(&lines), "never printed {what}; printed:\n{}", lines.join("\n"));
        lines.len()
    }

    fn signal(&self, sig: &str) {
        let ok = Command::new("kill").args([sig, &self.child.id().to_string()]).status();
        assert!(ok.is_ok_and(|s| s.success()), "kill {sig}");
    }

    fn finish(mut self) -> (Output, Vec<String>) {
        let out = self.child.stdout.take().unwrap();
        let mut stdout = Vec::new();
        std::io::Read::read_to_end(&mut BufReader::new(out), &mut stdout).unwrap();
        let status = self.child.wait().unwrap();
        let lines = self.lines.0.lock().unwrap().clone();
        (Output { status, stdout, stderr: Vec::new() }, lines)
    }
}

impl Drop for Proc {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

const VEHICLES: [&str; 4] = ["usv1", "usv2", "ugv1", "uav1"];

/// Waits for the adapter to have all the simulator's vehicles.
fn wait_vehicles(adapter: &Proc) {
    adapter.wait_line(0, "the four vehicles", |l| {
        l.contains("vehicles: ") && VEHICLES.iter().all(|v| l.contains(v))
    });
}

/// A headless OCU on `layout` with no vehicles or sockets of its own, joined to the adapter.
fn joined_run(layout: &str, port: u16) -> Vec<String> {
    let ep = endpoint(port);
    let args = ["run", layout, "--no-sim", "--mavlink", "off", "--video", "off"];
    let rest = ["--headless", "--no-watch", "--connect", &ep];
    args.iter().chain(&rest).map(|s| s.to_string()).collect()
}

/// An OCU on fig3 against the adapter, headless for `frames` frames, dumping root.vehicles.
fn ocu_args(port: u16, operator: &str, frames: Option<&str>) -> Vec<String> {
    let mut a = joined_run("layouts/fig3-multi-usv.mocu", port);
    a.extend(["--operator", operator, "--dump", "root.vehicles"].map(String::from));
    if let Some(n) = frames {
        a.extend(["--frames".to_string(), n.to_string()]);
    }
    a
}

fn ocu(port: u16, operator: &str) -> Proc {
    let args = ocu_args(port, operator, Some("30"));
    Proc::start(&args.iter().map(String::as_str).collect::<Vec<_>>())
}

/// The dump's vehicles by name.
fn vehicles(out: &Output, lines: &[String]) -> Vec<(String, J)> {
    assert!(out.status.success(), "the OCU failed:\n{}", lines.join("\n"));
    let dump: J = serde_json::from_slice(&out.stdout).expect("--dump is JSON");
    dump["children"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| (v["name"].as_str().unwrap().to_string(), v.clone()))
        .collect()
}

fn names(vs: &[(String, J)]) -> Vec<String> {
    let mut n: Vec<String> = vs.iter().map(|(n, _)| n.clone()).collect();
    n.sort();
    n
}

fn child<'a>(v: &'a J, name: &str) -> &'a J {
    v["children"].as_array().unwrap().iter().find(|c| c["name"] == name).unwrap()
}

#[test]
fn an_adapter_and_two_ocus_show_the_same_vehicles() {
    let port = free_port();
    let adapter = Proc::serve(port);
    wait_vehicles(&adapter);
    let (alice, bob) = (ocu(port, "alice"), ocu(port, "bob"));
    let (a_out, a_lines) = alice.finish();
    let (b_out, b_lines) = bob.finish();
    let (a, b) = (vehicles(&a_out, &a_lines), vehicles(&b_out, &b_lines));
    let mut want: Vec<String> = VEHICLES.iter().map(|s| s.to_string()).collect();
    want.sort();
    assert_eq!(names(&a), want, "alice's vehicles");
    assert_eq!(names(&b), want, "bob's vehicles");
    for (name, v) in a.iter().chain(&b) {
        let nav = child(v, "nav");
        assert!(nav["properties"]["speed"].is_number(), "{name}.nav.speed mirrored: {nav}");
        assert!(v["methods"].as_array().unwrap().iter().any(|m| m == "arm"), "{name}.arm mirrored");
    }
    // The first of each kind patrols on its own at the adapter: armed on both screens.
    for vs in [&a, &b] {
        let usv1 = &vs.iter().find(|(n, _)| n == "usv1").unwrap().1;
        assert_eq!(usv1["properties"]["armed"], J::Bool(true));
    }
    assert!(a_lines.iter().any(|l| l.contains("site `adapter` joined")), "{}", a_lines.join("\n"));
}

fn python_peer(port: u16, args: &[&str]) -> J {
    let check = Command::new("python3").args(["-c", "import zenoh"]).output();
    assert!(
        check.is_ok_and(|o| o.status.success()),
        "this test needs python3 with eclipse-zenoh: `python3 -m pip install eclipse-zenoh==1.10.2` \
         (CI installs it in .ci/run)"
    );
    let script = concat!(env!("CARGO_MANIFEST_DIR"), "/examples/zenoh_peer.py");
    let out = Command::new("python3")
        .arg(script)
        .arg(endpoint(port))
        .args(args)
        .output()
        .expect("python3 runs");
    assert!(
        out.status.success(),
        "the Python peer failed:\n{}\n{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).expect("the peer prints JSON")
}

#[test]
fn a_python_peer_reads_a_vehicle_and_calls_its_methods_with_their_outcomes() {
    let port = free_port();
    let adapter = Proc::serve(port);
    wait_vehicles(&adapter);
    // usv1 patrols on its own: its engine runs, so starting it is refused, with the reason.
    let r = python_peer(port, &["usv1", "start_engine"]);
    assert_eq!(r["site"], "adapter");
    assert!(r["properties"]["nav/speed"].is_number(), "{r}");
    assert_eq!(r["units"]["nav/speed"], "m/s", "{r}");
    assert_eq!(r["outcome"]["outcome"], "refused", "{r}");
    assert_eq!(r["outcome"]["reason"], "engine already running", "{r}");
    // A bool parameter given an int fails at the adapter; disarming is accepted.
    let r = python_peer(port, &["usv1", "arm", "3"]);
    assert_eq!(r["outcome"]["outcome"], "failed", "{r}");
    let r = python_peer(port, &["usv1", "arm", "false"]);
    assert_eq!(r["outcome"]["outcome"], "accepted", "{r}");
    let r = python_peer(port, &["usv1", "no_such_thing"]);
    assert_eq!(r["outcome"]["outcome"], "no_such_method", "{r}");
}

#[test]
fn a_late_joiner_starts_from_the_state_others_left() {
    let port = free_port();
    let adapter = Proc::serve(port);
    wait_vehicles(&adapter);
    let r = python_peer(port, &["usv1", "arm", "false"]);
    assert_eq!(r["outcome"]["outcome"], "accepted", "{r}");
    let (out, lines) = ocu(port, "carol").finish();
    let vs = vehicles(&out, &lines);
    let usv1 = &vs.iter().find(|(n, _)| n == "usv1").unwrap().1;
    assert_eq!(usv1["properties"]["armed"], J::Bool(false), "disarmed before carol joined");
    assert_eq!(usv1["properties"]["engine"], J::Bool(false));
}

#[test]
fn a_killed_adapter_shows_stale_on_the_ocu_and_its_return_brings_no_duplicates() {
    let port = free_port();
    let adapter = Proc::serve(port);
    wait_vehicles(&adapter);
    let args = ocu_args(port, "dave", None);
    let ocu = Proc::start(&args.iter().map(String::as_str).collect::<Vec<_>>());
    let n = ocu.wait_line(0, "the adapter joining", |l| l.contains("site `adapter` joined"));
    drop(adapter); // SIGKILL: no goodbye, the link just closes
    // Detected by liveliness (the link closed); each vehicle's stale flag raised.
    let stale = format!("site `adapter` is gone: {} of its objects shown stale", VEHICLES.len());
    let n = ocu.wait_line(n, "the adapter gone", |l| l.contains(&stale));
    let adapter = Proc::serve(port);
    let n = ocu.wait_line(n, "the adapter back", |l| l.contains("site `adapter` joined"));
    wait_vehicles(&adapter);
    // The restarted adapter's vehicles, appearing one by one, reach the OCU.
    ocu.wait_line(n, "four vehicles on the OCU", |l| {
        l.contains("m/s") && VEHICLES.iter().all(|v| l.contains(v))
    });
    ocu.signal("-TERM");
    let (out, lines) = ocu.finish();
    let vs = vehicles(&out, &lines);
    let mut want: Vec<String> = VEHICLES.iter().map(|s| s.to_string()).collect();
    want.sort();
    assert_eq!(names(&vs), want, "each vehicle once");
    for (name, v) in &vs {
        assert_eq!(v["properties"]["stale"], J::Bool(false), "{name} fresh again");
    }
    drop(adapter);
}

/// An OCU on tests/distrib/control.mocu against the adapter, playing `script`, until it is
/// told to stop; it dumps `root.vehicles` when it does.
fn control_ocu(port: u16, operator: &str, script: &str) -> Proc {
    let mut a = ocu_args(port, operator, None);
    a[1] = "tests/distrib/control.mocu".into();
    a.extend(["--input-script".into(), script.into()]);
    Proc::start(&a.iter().map(String::as_str).collect::<Vec<_>>())
}

#[test]
fn a_non_holders_command_is_refused_takeovers_follow_each_vehicles_policy_and_a_killed_holder_is_released()
 {
    let port = free_port();
    let adapter = Proc::serve_profile("tests/distrib/adapter.toml", port, &[]);
    adapter.wait_line(0, "usv1 and usv2", |l| l.contains("vehicles: usv1, usv2"));
    // alice requests both vehicles; the adapter says who holds them.
    let alice = control_ocu(port, "alice", "tests/distrib/alice.script");
    let n = adapter.wait_line(0, "alice holding both", |l| {
        l.contains("usv1 (alice)") && l.contains("usv2 (alice)")
    });
    // bob's command is refused with the reason, on his screen (the alert on stderr).
    let bob = control_ocu(port, "bob", "tests/distrib/bob.script");
    let refused =
        "usv1.start_engine: refused — usv1 is controlled by alice: request a takeover first";
    let b = bob.wait_line(0, "bob's command refused", |l| l.contains(refused));
    // usv2's takeover is denied by the adapter's profile; usv1's is allowed.
    let denied =
        "usv2.arbitration.takeover: refused — takeover of usv2 is denied: alice controls it";
    bob.wait_line(b, "bob's takeover of usv2 denied", |l| l.contains(denied));
    let n = adapter.wait_line(n, "bob holding usv1", |l| {
        l.contains("usv1 (bob)") && l.contains("usv2 (alice)")
    });
    // alice's OCU is killed: usv2 is released once release_after_ms has passed.
    drop(alice);
    adapter
        .wait_line(n, "usv2 released", |l| l.contains("usv1 (bob), usv2") && !l.contains("alice"));
    // bob's world model says the same.
    bob.signal("-TERM");
    let (out, lines) = bob.finish();
    let vs = vehicles(&out, &lines);
    let holder = |name: &str| {
        let v = &vs.iter().find(|(n, _)| n == name).unwrap().1;
        child(v, "arbitration")["properties"]["holder"].clone()
    };
    assert_eq!((holder("usv1"), holder("usv2")), (J::from("bob"), J::from("")));
    drop(adapter);
}

/// The pid in the supervisor's `started `…` (pid N)` line.
fn child_pid(line: &str) -> String {
    let at = line.rfind("(pid ").expect("a pid") + 5;
    line[at..].trim_end_matches(')').to_string()
}

#[test]
fn a_python_process_module_stops_a_vehicle_leaving_its_zone_and_is_restarted_after_a_crash() {
    let check = Command::new("python3").args(["-c", "import zenoh"]).output();
    assert!(check.is_ok_and(|o| o.status.success()), "needs python3 with eclipse-zenoh 1.10.2");
    let ocu = Proc::start(&[
        "run",
        "tests/distrib/geofence.toml",
        "--headless",
        "--no-watch",
        "--mavlink",
        "off",
        "--video",
        "off",
        "--frames",
        "36000",
        "--dump",
        "root",
    ]);
    // The module joins the OCU, sees usv1 patrol out of its 5 m leash, alerts and stops it.
    let n = ocu.wait_line(0, "the module joining", |l| l.contains("site `geofence` joined"));
    let n = ocu.wait_line(n, "the alert", |l| l.contains("geofence: ALERT usv1 left its zone"));
    let n = ocu.wait_line(n, "stop() accepted", |l| {
        l.contains("geofence: usv1.stop()") && l.contains("\"accepted\"")
    });
    // A crash: the OCU shows the module's object stale and restarts it.
    let started = {
        let lines = ocu.lines.0.lock().unwrap();
        lines.iter().find(|l| l.contains("started `python3")).cloned().expect("started line")
    };
    let killed = Command::new("kill").args(["-KILL", &child_pid(&started)]).status();
    assert!(killed.is_ok_and(|s| s.success()));
    // Two watchers of one event (the supervisor, the distribution layer): either may print first.
    let exit =
        ocu.wait_line(n, "the exit", |l| l.contains("exited (signal 9); restarting in 200 ms"));
    let stale = "site `geofence` is gone: 1 of its objects shown stale";
    ocu.wait_line(n, "its object stale", |l| l.contains(stale));
    let n = ocu.wait_line(exit, "the restart", |l| l.contains("restarted `python3"));
    ocu.wait_line(n, "the module back", |l| l.contains("site `geofence` joined"));
    ocu.signal("-TERM");
    let (out, lines) = ocu.finish();
    assert!(out.status.success(), "the OCU failed:\n{}", lines.join("\n"));
    let root: J = serde_json::from_slice(&out.stdout).expect("--dump is JSON");
    let fence = child(&root, "geofence");
    assert_eq!(fence["properties"]["stale"], J::Bool(false), "fresh again: {fence}");
    let status = child(child(&root, "modules"), "geofence");
    assert_eq!(status["properties"]["restarts"], 1, "{status}");
    assert_eq!(status["properties"]["state"], "running", "{status}");
    let nav = child(child(child(&root, "vehicles"), "usv1"), "nav");
    assert_eq!(nav["properties"]["goal_throttle"], 0.0, "usv1 stopped: {nav}");
}

#[test]
fn an_ocu_shows_the_camera_an_adapter_shares_in_its_video_window() {
    let port = free_port();
    let adapter = Proc::serve_profile("tests/distrib/streams.toml", port, &[]);
    adapter.wait_line(0, "usv1", |l| l.contains("vehicles: ") && l.contains("usv1"));
    let dir = tempfile::tempdir().unwrap();
    let shot = dir.path().join("ocu.png");
    // layouts/usv.mocu shows usv1's drive camera full screen: the adapter's simulator renders
    // it (someone listens: the share), the OCU has no simulator of its own.
    let mut args = joined_run("layouts/usv.mocu", port);
    args.extend(["--frames", "300", "--size", "640x400", "--screenshot"].map(String::from));
    args.push(shot.to_str().unwrap().to_string());
    let ocu = Proc::start(&args.iter().map(String::as_str).collect::<Vec<_>>());
    let (out, lines) = ocu.finish();
    assert!(out.status.success(), "the OCU failed:\n{}", lines.join("\n"));
    // The upper right of the screen, clear of the HUD and above the horizon whatever the
    // boat's heading when the run ends (the adapter's simulator runs on the wall clock).
    let sky = sky_share(&shot, (490, 630), (50, 120));
    assert!(
        sky > 0.9,
        "the camera's sky in the video window: {sky:.2} of the pixels; the OCU said:\n{}",
        lines.join("\n")
    );
    drop(adapter);
}

/// `mocu serve --record`: the adapter's trial on the record (its telemetry, its shared camera's
/// frames), read back by the independent reader and shown again by `mocu replay` through the
/// profile's layout.
#[test]
fn an_adapter_records_its_world_model_and_replay_shows_it() {
    let port = free_port();
    let dir = tempfile::tempdir().unwrap();
    let trial = dir.path().join("adapter.mcap");
    let record = ["--record", trial.to_str().unwrap()];
    let adapter = Proc::serve_profile("tests/distrib/streams.toml", port, &record);
    // The summary is looked at once a second: by its line naming both USVs, the simulator
    // has run for a second at least.
    adapter.wait_line(0, "usv1 and usv2", |l| l.contains("vehicles: usv1, usv2"));
    adapter.signal("-TERM");
    let (out, lines) = adapter.finish();
    assert!(out.status.success(), "the adapter failed:\n{}", lines.join("\n"));
    assert!(lines.iter().any(|l| l.contains("mocu: recorded")), "{}", lines.join("\n"));
    let r = cli_support::read_recording(&trial, &["root.vehicles.usv1.nav.x"]);
    assert_eq!(r["summary"], J::Bool(true), "a finished recording: {r}");
    assert!(r["values"].as_u64().unwrap_or(0) > 0, "telemetry on /world/values: {r}");
    let xs = r["properties"]["root.vehicles.usv1.nav.x"].as_array().map_or(0, Vec::len);
    assert!(xs > 2, "usv1's x as it moved: {xs} values");
    let frames = &r["frames"]["/camera/root.vehicles.usv1.cameras.drive"];
    assert!(frames["count"].as_u64().unwrap_or(0) > 0, "the shared camera's frames: {r}");
    // The profile's layout came with it: a replay needs no --layout.
    let shot = dir.path().join("replay.png");
    let o = Command::new(env!("CARGO_BIN_EXE_mocu"))
        .args(["replay", trial.to_str().unwrap(), "--at", "0.5s", "--screenshot"])
        .arg(&shot)
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .env_remove("DISPLAY")
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(shot.exists());
}
