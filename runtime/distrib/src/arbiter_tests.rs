//! The arbiter over a real DataServer on a clock the test moves: the world model it
//! publishes, the calls it screens, the answers it gives late, its timers.

use super::*;
use crossbeam_channel::{Receiver, unbounded};
use mocu_dataserver::{Clock, Config, ManualClock};

const ASK: Duration = Duration::from_secs(8);
const RELEASE: Duration = Duration::from_secs(5);

struct World {
    ds: DataServer,
    clock: ManualClock,
    arbiter: Arbiter,
}

fn world() -> World {
    let clock = ManualClock::new();
    let ds = DataServer::with_clock(Config::default(), Arc::new(clock.clone()));
    let vs = ds.create_object(ds.root(), ObjectInfo::new("vehicles", "vehicles")).unwrap();
    let settings = Settings {
        vehicles: HashMap::from([("usv2".to_string(), Takeover::Ask)]),
        open_when_free: false,
        release_after: RELEASE,
        ask_timeout: ASK,
        ..Settings::default()
    };
    let arbiter = Arbiter::start(&ds, settings, Caller::new("", "adapter")).unwrap();
    for name in ["usv1", "usv2"] {
        ds.create_object(vs, ObjectInfo::new(name, "usv")).unwrap();
    }
    ds.quiesce();
    World { ds, clock, arbiter }
}

fn alice() -> Caller {
    Caller::new("alice", "alice")
}
fn bob() -> Caller {
    Caller::new("bob", "bob")
}

impl World {
    /// Calls a method of `vehicle`'s arbitration object as `who`; the outcome arrives on
    /// the receiver (at once, or when the holder answers).
    fn call(
        &self,
        vehicle: &str,
        method: &str,
        args: &[Value],
        who: Caller,
    ) -> Receiver<CallOutcome> {
        let (tx, rx) = unbounded();
        self.arbiter.arbitrate(
            vehicle,
            method,
            args,
            who,
            None,
            Box::new(move |o| {
                let _ = tx.send(o);
            }),
        );
        rx
    }

    fn now(&self, vehicle: &str, method: &str, who: Caller) -> CallOutcome {
        self.call(vehicle, method, &[], who).try_recv().expect("answered at once")
    }

    fn prop(&self, vehicle: &str, name: &str) -> Value {
        self.ds.quiesce();
        let o = self.ds.resolve(&["vehicles", vehicle, OBJECT]).expect("the arbitration object");
        self.ds.get(o, name).unwrap()
    }

    fn screen(&self, path: &str, method: &str, who: &Caller) -> Result<(), String> {
        let path: Vec<String> = path.split('.').map(String::from).collect();
        match self.arbiter.screen(&path, method, who) {
            Screen::Pass => Ok(()),
            Screen::Refuse(r) => Err(r),
            Screen::Arbitrate(v) => Err(format!("arbitrated: {v}")),
        }
    }

    fn advance(&self, d: Duration) {
        self.ds.advance_settled(&self.clock, self.clock.now() + d);
    }
}

fn ok() -> CallOutcome {
    CallOutcome::Accepted(Vec::new())
}

#[test]
fn every_vehicle_gets_an_arbitration_object_with_its_policy_and_methods() {
    let w = world();
    assert_eq!(w.prop("usv1", "holder"), Value::str(""));
    assert_eq!(w.prop("usv1", "policy"), Value::str("allowed"));
    assert_eq!(w.prop("usv2", "policy"), Value::str("ask"));
    assert_eq!(w.prop("usv2", "holder_connected"), Value::Bool(false));
    let o = w.ds.resolve(&["vehicles", "usv1", OBJECT]).unwrap();
    let names: Vec<String> =
        w.ds.methods(o).unwrap().iter().map(|m| m.name.as_str().to_string()).collect();
    assert_eq!(names, ["answer", "release", "request", "takeover"]);
    // A vehicle that comes later gets one too.
    let vs = w.ds.resolve(&["vehicles"]).unwrap();
    w.ds.create_object(vs, ObjectInfo::new("uav1", "uav")).unwrap();
    assert_eq!(w.prop("uav1", "policy"), Value::str("allowed"));
}

#[test]
fn a_non_holders_commands_are_refused_with_the_holder_named_and_the_holders_pass() {
    let w = world();
    assert_eq!(
        w.screen("vehicles.usv1.nav", "set_goal", &bob()),
        Err("nobody controls usv1: request control first".into()),
        "free = closed"
    );
    assert_eq!(w.now("usv1", "request", alice()), ok());
    assert_eq!(w.prop("usv1", "holder"), Value::str("alice"));
    assert_eq!(w.prop("usv1", "holder_connected"), Value::Bool(true));
    assert_eq!(w.screen("vehicles.usv1", "start_engine", &alice()), Ok(()));
    assert_eq!(
        w.screen("vehicles.usv1", "start_engine", &bob()),
        Err("usv1 is controlled by alice: request a takeover first".into())
    );
    assert_eq!(
        w.screen("vehicles.usv1.manipulator", "grip", &bob()),
        Err("usv1 is controlled by alice: request a takeover first".into()),
        "a vehicle's parts are the vehicle's"
    );
    assert_eq!(w.screen("map.tiles", "tile", &bob()), Ok(()), "not a vehicle");
    assert_eq!(
        w.screen("vehicles.usv1.arbitration", "takeover", &bob()),
        Err("arbitrated: usv1".into())
    );
    assert!(
        w.screen("vehicles.usv1", "request_control", &alice())
            .unwrap_err()
            .contains("usv1.arbitration.request()"),
        "the vehicle's own control methods are not a way around the arbiter"
    );
    assert_eq!(
        w.now("usv1", "request", bob()),
        CallOutcome::Refused("usv1 is controlled by alice: request a takeover instead".into())
    );
}

#[test]
fn a_takeover_the_holder_is_asked_for_is_answered_when_the_holder_answers() {
    let w = world();
    w.now("usv2", "request", alice());
    let bobs = w.call("usv2", "takeover", &[], bob());
    assert!(bobs.try_recv().is_err(), "bob waits for alice's answer");
    assert_eq!(w.prop("usv2", "requested_by"), Value::str("bob"));
    let alices = w.call("usv2", "answer", &[Value::Bool(false)], alice());
    assert_eq!(alices.try_recv().unwrap(), ok());
    assert_eq!(
        bobs.try_recv().unwrap(),
        CallOutcome::Refused("alice denied the takeover of usv2".into())
    );
    assert_eq!(
        (w.prop("usv2", "holder"), w.prop("usv2", "requested_by")),
        (Value::str("alice"), Value::str(""))
    );
    let bobs = w.call("usv2", "takeover", &[], bob());
    w.call("usv2", "answer", &[Value::Bool(true)], alice());
    assert_eq!(bobs.try_recv().unwrap(), ok());
    assert_eq!(w.prop("usv2", "holder"), Value::str("bob"));
    assert_eq!(
        w.call("usv2", "answer", &[Value::Int(1)], bob()).try_recv().unwrap(),
        CallOutcome::Refused("answer(accept) takes true or false".into())
    );
}

#[test]
fn an_unanswered_takeover_is_refused_when_the_ask_timeout_passes() {
    let w = world();
    w.now("usv2", "request", alice());
    let bobs = w.call("usv2", "takeover", &[], bob());
    w.advance(ASK - Duration::from_millis(1));
    assert!(bobs.try_recv().is_err(), "still asking");
    w.advance(Duration::from_millis(1));
    assert_eq!(
        bobs.try_recv().unwrap(),
        CallOutcome::Refused("alice did not answer the takeover of usv2 within 8 s".into())
    );
    assert_eq!(w.prop("usv2", "requested_by"), Value::str(""));
}

#[test]
fn a_holder_whose_site_disappears_loses_control_after_the_release_timeout_unless_it_returns() {
    let w = world();
    w.now("usv1", "request", alice());
    w.arbiter.site("alice", false);
    assert_eq!(w.prop("usv1", "holder_connected"), Value::Bool(false));
    w.advance(RELEASE / 2);
    w.arbiter.site("alice", true);
    w.advance(RELEASE);
    assert_eq!(w.prop("usv1", "holder"), Value::str("alice"), "back in time");
    assert_eq!(w.prop("usv1", "holder_connected"), Value::Bool(true));
    w.arbiter.site("alice", false);
    w.advance(RELEASE - Duration::from_millis(1));
    assert_eq!(w.prop("usv1", "holder"), Value::str("alice"));
    w.advance(Duration::from_millis(1));
    assert_eq!(w.prop("usv1", "holder"), Value::str(""), "released");
    assert_eq!(w.now("usv1", "request", bob()), ok());
}

#[test]
fn a_release_hands_control_to_the_operator_waiting_for_the_holders_answer() {
    let w = world();
    w.now("usv2", "request", alice());
    let bobs = w.call("usv2", "takeover", &[], bob());
    assert_eq!(w.now("usv2", "release", alice()), ok());
    assert_eq!(bobs.try_recv().unwrap(), ok());
    assert_eq!(w.prop("usv2", "holder"), Value::str("bob"));
}

#[test]
fn the_sites_own_calls_come_from_its_operator() {
    let w = world();
    let o = w.ds.resolve(&["vehicles", "usv1", OBJECT]).unwrap();
    let out = w.ds.call_wait(o, "request", vec![], None);
    assert!(matches!(&out, CallOutcome::Refused(r) if r.contains("--operator NAME")), "{out:?}");
}

/// A vehicle whose protocol module says another ground station holds it (MAVLink's
/// operator-control protocol: `gcs_in_control`, `control` = `gcs 200`): every OCU sees that
/// holder, and every operator's command is refused with it named, holder here or not.
#[test]
fn a_vehicle_held_by_another_ground_station_shows_it_and_refuses_every_operators_commands() {
    let w = world();
    let v = w.ds.resolve(&["vehicles", "usv1"]).unwrap();
    assert_eq!(w.now("usv1", "request", alice()), ok());
    w.ds.set(v, "gcs_in_control", Value::Int(200)).unwrap();
    w.ds.set(v, "control", Value::str("gcs 200")).unwrap();
    w.ds.quiesce();
    assert_eq!(w.prop("usv1", "holder"), Value::str("gcs 200"));
    for who in [alice(), bob()] {
        let refused = w.screen("vehicles.usv1", "start_engine", &who).unwrap_err();
        assert!(refused.contains("gcs 200, another ground station"), "{refused}");
    }
    // Without the protocol a `control` that reads the same is only the module's own word.
    let v2 = w.ds.resolve(&["vehicles", "usv2"]).unwrap();
    assert_eq!(w.now("usv2", "request", alice()), ok());
    w.ds.set(v2, "control", Value::str("gcs 7")).unwrap();
    w.ds.quiesce();
    assert_eq!(w.screen("vehicles.usv2", "start_engine", &alice()), Ok(()));
}
