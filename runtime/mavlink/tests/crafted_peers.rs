//! The MAVLink module against crafted senders written with pymavlink
//! (tests/peers/mav_sender.py) on loopback: a vehicle newer than our dialect, frames signed
//! with the right key, the wrong key, none, or with unknown incompatibility flags, and a
//! spoofed flood of system ids. CI installs pymavlink (.ci/run); without it these fail and
//! say so.

use mocu_dataserver::{DataServer, Guid, Topic, Value};
use mocu_host::{ModuleHost, ModuleSpec, Registry};
use std::process::Command;
use std::time::Duration;

struct Ocu {
    ds: DataServer,
    host: ModuleHost,
    status: Guid,
    port: u16,
}

fn start(spec: ModuleSpec) -> Ocu {
    let ds = DataServer::default();
    let mut reg = Registry::new();
    mocu_mavlink::register(&mut reg);
    let mut host = ModuleHost::new(ds.clone(), reg);
    host.start(&spec.with("address", "127.0.0.1:0")).expect("the MAVLink module starts");
    let status = ds.resolve(&["modules", "mavlink"]).unwrap();
    let addr = ds.get(status, "address").unwrap();
    let port = addr.as_str().unwrap().rsplit(':').next().unwrap().parse().unwrap();
    Ocu { ds, host, status, port }
}

/// Runs the sender to its end (bounded by `timeout`); returns what it printed.
fn send(ocu: &Ocu, args: &[&str]) -> String {
    let script = concat!(env!("CARGO_MANIFEST_DIR"), "/../../tests/peers/mav_sender.py");
    let check = Command::new("python3").args(["-c", "import pymavlink"]).output();
    assert!(
        check.is_ok_and(|o| o.status.success()),
        "this test needs python3 with pymavlink: `python3 -m pip install pymavlink==2.4.50` \
         (CI installs it in .ci/run)"
    );
    let out = Command::new("timeout")
        .args(["-k", "5", "60", "python3", script, "--port", &ocu.port.to_string()])
        .args(args)
        .output()
        .expect("running the pymavlink sender");
    let stdout = String::from_utf8_lossy(&out.stdout).to_string();
    assert!(out.status.success(), "{args:?}: {stdout}\n{}", String::from_utf8_lossy(&out.stderr));
    stdout
}

impl Ocu {
    fn counter(&self, name: &str) -> i64 {
        self.ds.try_get(self.status, name.into()).and_then(|v| v.as_i64()).unwrap_or(-1)
    }

    /// Waits until the published counters satisfy `f`, checking at each change (the 30 s bound
    /// only turns a hang into a failure).
    fn wait(&self, what: &str, f: impl Fn(&Ocu) -> bool) {
        let (tx, rx) = std::sync::mpsc::channel();
        let sub = self
            .ds
            .subscribe(Topic::properties(self.status), move |_| {
                let _ = tx.send(());
            })
            .unwrap();
        let mut ok = f(self);
        while !ok && rx.recv_timeout(Duration::from_secs(30)).is_ok() {
            ok = f(self);
        }
        self.ds.unsubscribe(sub);
        assert!(ok, "never: {what}");
    }
}

impl Drop for Ocu {
    fn drop(&mut self) {
        self.host.stop_all();
    }
}

#[test]
fn a_vehicle_newer_than_our_dialect_sent_by_pymavlink_appears_with_its_raw_values() {
    let ocu = start(ModuleSpec::new("mavlink"));
    assert_eq!(send(&ocu, &["--mode", "newer", "--sysid", "11"]).trim(), "sent");
    ocu.wait("its GPS_RAW_INT decoded", |o| o.counter("decoded") >= 5);
    let v = ocu.ds.resolve(&["vehicles", "mav11"]).expect("the newer vehicle appears");
    let nav = ocu.ds.resolve(&["vehicles", "mav11", "nav"]).unwrap();
    assert_eq!(ocu.ds.get(v, "mav_type").unwrap(), Value::str("unknown(142)"));
    assert_eq!(ocu.ds.get(v, "autopilot_raw").unwrap(), Value::Int(99));
    assert_eq!(ocu.ds.get(v, "system_status").unwrap(), Value::str("unknown(17)"));
    assert_eq!(ocu.ds.get(nav, "gps_fix").unwrap(), Value::str("unknown(9)"));
    assert_eq!(ocu.ds.get(nav, "satellites").unwrap(), Value::Int(14));
    assert_eq!(ocu.counter("malformed"), 0);
}

#[test]
fn with_a_key_pymavlinks_signed_frames_are_accepted_and_ours_verify_there() {
    let spec =
        ModuleSpec::new("mavlink").with("signing_key", "trial key").with("proof_heartbeats", 2);
    let ocu = start(spec);
    let out = send(&ocu, &["--mode", "signed", "--key", "trial key", "--sysid", "12"]);
    let verified: u64 =
        out.trim().strip_prefix("verified ").and_then(|n| n.parse().ok()).unwrap_or(0);
    assert!(verified >= 1, "pymavlink verified our signed heartbeat: {out}");
    let v = ocu.ds.resolve(&["vehicles", "mav12"]).expect("the signed vehicle appears");
    assert_eq!(ocu.ds.get(v, "verified").unwrap(), Value::Bool(true));
    assert_eq!(ocu.counter("refused_bad_signature"), 0);
}

#[test]
fn with_a_key_wrongly_signed_unsigned_and_unknown_flag_frames_from_pymavlink_are_refused() {
    let ocu = start(ModuleSpec::new("mavlink").with("signing_key", "trial key"));
    let wrong = send(&ocu, &["--mode", "wrongkey", "--key", "guess", "--sysid", "13"]);
    let unsigned = send(&ocu, &["--mode", "unsigned", "--sysid", "14"]);
    let incompat = send(&ocu, &["--mode", "incompat", "--sysid", "15"]);
    ocu.wait("every refusal counted", |o| {
        o.counter("refused_bad_signature") == 5
            && o.counter("refused_unsigned") == 5
            && o.counter("refused_incompatible") == 5
    });
    assert_eq!(ocu.counter("vehicles"), 0);
    assert!(ocu.ds.resolve(&["vehicles", "mav13"]).is_none());
    for out in [wrong, unsigned, incompat] {
        assert_eq!(out.trim(), "replies 0", "nothing goes back to a refused sender");
    }
}

#[test]
fn a_spoofed_flood_of_system_ids_from_pymavlink_is_bounded_and_never_answered() {
    let ocu = start(ModuleSpec::new("mavlink").with("max_vehicles", 8));
    let out = send(&ocu, &["--mode", "flood", "--count", "255", "--listen", "2"]);
    ocu.wait("the flood counted", |o| o.counter("refused_vehicle_limit") == 255 - 8);
    assert_eq!(ocu.counter("vehicles"), 8);
    let vehicles = ocu.ds.resolve(&["vehicles"]).unwrap();
    assert_eq!(ocu.ds.children(vehicles).unwrap().len(), 8);
    assert_eq!(out.trim(), "replies 0", "no heartbeat goes to an address that proved nothing");
    assert_eq!(ocu.counter("sent"), 0);
}
