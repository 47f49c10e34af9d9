//! The MAVLink link against crafted frames, on a clock the test controls: values newer than
//! the dialect are kept, implausible messages are refused whole (one counter per reason),
//! a flood of system ids is bounded, silent vehicles are forgotten, only proved addresses
//! are answered, commands never truncate a system id, and a link with a key accepts only
//! frames signed with it. (runtime/mavlink/tests/crafted_peers.rs sends the same from pymavlink.)

use mavlink::dialects::development::*;
use mavlink::{MavHeader, Message};
use mocu_dataserver::{CallOutcome, Config, DataServer, Guid, ManualClock, Value};
use mocu_host::ModuleContext;
use mocu_mavlink::{Key, Link, LinkConfig, Reason, Signing, encode_v2};
use std::net::{SocketAddr, UdpSocket};
use std::sync::Arc;
use std::time::Duration;

/// A MAVLink 2 frame from component 1 of `sysid` (32-bit ids with the crate's SYSID32 flag).
fn frame(sysid: u32, seq: u8, msgid: u32, payload: &[u8], iflags: u8) -> Vec<u8> {
    let mut f = vec![0xFD, payload.len() as u8, iflags, 0, seq];
    if sysid > 255 {
        f[2] |= 0x02;
        f.extend(sysid.to_le_bytes());
    } else {
        f.push(sysid as u8);
    }
    f.push(1);
    f.extend(&msgid.to_le_bytes()[..3]);
    f.extend(payload);
    let crc = mavlink::calculate_crc(&f[1..], MavMessage::extra_crc(msgid));
    f.extend(crc.to_le_bytes());
    f
}

/// The wire payload of a typed message.
fn payload(msg: &MavMessage) -> Vec<u8> {
    let e = encode_v2(MavHeader::default(), msg);
    e[10..10 + usize::from(e[1])].to_vec()
}

fn msg(sysid: u32, seq: u8, m: &MavMessage) -> Vec<u8> {
    frame(sysid, seq, m.message_id(), &payload(m), 0)
}

fn heartbeat_payload(mavtype: u8, autopilot: u8, status: u8) -> Vec<u8> {
    vec![0, 0, 0, 0, mavtype, autopilot, 0, status, 3]
}

fn quad(sysid: u32, seq: u8) -> Vec<u8> {
    frame(sysid, seq, 0, &heartbeat_payload(2, 3, 4), 0)
}

fn position(lat: f64, lon: f64, alt_m: f64) -> MavMessage {
    MavMessage::GLOBAL_POSITION_INT(GLOBAL_POSITION_INT_DATA {
        lat: (lat * 1e7) as i32,
        lon: (lon * 1e7) as i32,
        relative_alt: (alt_m * 1000.0) as i32,
        alt: (alt_m * 1000.0) as i32,
        hdg: u16::MAX,
        ..Default::default()
    })
}

struct World {
    clock: ManualClock,
    ds: DataServer,
    link: Link,
}

fn world(cfg: LinkConfig, socket: Option<Arc<UdpSocket>>) -> World {
    let clock = ManualClock::new();
    let ds = DataServer::with_clock(Config::default(), Arc::new(clock.clone()));
    let link = Link::new(ModuleContext::detached("mavlink", ds.clone()), cfg, socket).unwrap();
    World { clock, ds, link }
}

impl World {
    fn get(&self, path: &[&str], prop: &str) -> Value {
        let g = self.ds.resolve(path).unwrap_or_else(|| panic!("{path:?}"));
        self.ds.get(g, prop).unwrap()
    }
    fn f(&self, path: &[&str], prop: &str) -> f64 {
        self.get(path, prop).as_f64().unwrap()
    }
    fn status(&self, prop: &str) -> i64 {
        self.link.watchdog(false);
        let s = self.ds.resolve(&["modules", "mavlink"]).unwrap();
        self.ds.get(s, prop).unwrap().as_i64().unwrap()
    }
    fn vehicle(&self, name: &str) -> Guid {
        self.ds.resolve(&["vehicles", name]).unwrap_or_else(|| panic!("{name} is not there"))
    }
}

#[test]
fn a_vehicle_newer_than_the_dialect_appears_with_its_raw_values() {
    let w = world(LinkConfig::default(), None);
    w.link.ingest(&frame(9, 0, 0, &heartbeat_payload(142, 99, 17), 0), None);
    let v = w.vehicle("mav9");
    let info = w.ds.info(v).unwrap();
    assert_eq!((&*info.kind, &*info.subtype), ("vehicle", "unknown(142)"));
    let at = ["vehicles", "mav9"];
    assert_eq!(w.get(&at, "mav_type"), Value::str("unknown(142)"));
    assert_eq!(w.get(&at, "mav_type_raw"), Value::Int(142));
    assert_eq!(w.get(&at, "autopilot"), Value::str("unknown(99)"));
    assert_eq!(w.get(&at, "autopilot_raw"), Value::Int(99));
    assert_eq!(w.get(&at, "system_status"), Value::str("unknown(17)"));
    assert_eq!(w.get(&at, "system_status_raw"), Value::Int(17));
    assert_eq!(w.get(&at, "mode"), Value::str("custom:0"));

    // GPS_RAW_INT with fix type 9: kept, with the rest of the message.
    let mut gps = payload(&MavMessage::GPS_RAW_INT(GPS_RAW_INT_DATA {
        satellites_visible: 14,
        eph: 90,
        ..Default::default()
    }));
    gps.resize(30, 0);
    gps[28] = 9;
    w.link.ingest(&frame(9, 1, 24, &gps, 0), None);
    let nav = ["vehicles", "mav9", "nav"];
    assert_eq!(w.get(&nav, "gps_fix"), Value::str("unknown(9)"));
    assert_eq!(w.get(&nav, "gps_fix_raw"), Value::Int(9));
    assert_eq!(w.get(&nav, "satellites"), Value::Int(14));
    assert_eq!(w.status("malformed"), 0);
}

#[test]
fn an_out_of_range_position_is_refused_whole_and_counted() {
    let w = world(LinkConfig::default(), None);
    w.link.ingest(&quad(3, 0), None);
    let nav = ["vehicles", "mav3", "nav"];
    w.link.ingest(&msg(3, 1, &position(32.7, -117.1, 10.0)), None);
    w.link.ingest(&msg(3, 2, &position(32.7, -117.1, 10.0)), None);
    let before: Vec<f64> = ["lat", "lon", "x", "y", "alt"].iter().map(|p| w.f(&nav, p)).collect();
    // lat 95°, lon 200°, (0, 0) and 500 km up: nothing of them is published.
    w.link.ingest(&msg(3, 3, &position(95.0, -117.1, 12.0)), None);
    w.link.ingest(&msg(3, 4, &position(32.7, 200.0, 12.0)), None);
    w.link.ingest(&msg(3, 5, &position(0.0, 0.0, 12.0)), None);
    w.link.ingest(&msg(3, 6, &position(32.7, -117.1, 500_000.0)), None);
    let after: Vec<f64> = ["lat", "lon", "x", "y", "alt"].iter().map(|p| w.f(&nav, p)).collect();
    assert_eq!(before, after);
    assert_eq!(w.status(Reason::Position.property()), 2);
    assert_eq!(w.status(Reason::NullPosition.property()), 1);
    assert_eq!(w.status(Reason::Altitude.property()), 1);
}

#[test]
fn an_absurd_first_position_is_not_latched_as_home() {
    let w = world(LinkConfig::default(), None);
    w.link.ingest(&quad(4, 0), None);
    let nav = ["vehicles", "mav4", "nav"];
    // A glitch far away, then the vehicle where it is.
    w.link.ingest(&msg(4, 1, &position(-10.0, 60.0, 0.0)), None);
    assert_eq!((w.f(&nav, "x"), w.f(&nav, "y")), (0.0, 0.0), "no home yet: no x/y");
    w.link.ingest(&msg(4, 2, &position(32.7157, -117.1611, 0.0)), None);
    w.link.ingest(&msg(4, 3, &position(32.7157, -117.1611, 0.0)), None);
    w.link.ingest(&msg(4, 4, &position(32.7167, -117.1611, 0.0)), None);
    let (x, y) = (w.f(&nav, "x"), w.f(&nav, "y"));
    assert!(x.abs() < 1.0 && (y - 111.3).abs() < 1.0, "x/y from a plausible home: {x}, {y}");
}

#[test]
fn a_nan_or_infinite_attitude_is_refused_and_the_last_good_one_stays() {
    let w = world(LinkConfig::default(), None);
    w.link.ingest(&quad(5, 0), None);
    let att = |roll: f32, pitch: f32, yaw: f32| {
        MavMessage::ATTITUDE(ATTITUDE_DATA { roll, pitch, yaw, ..Default::default() })
    };
    w.link.ingest(&msg(5, 1, &att(0.1, 0.2, 0.3)), None);
    for (i, bad) in [att(f32::NAN, 0.0, 0.0), att(0.0, f32::INFINITY, 0.0), att(0.0, 0.0, 99.0)]
        .iter()
        .enumerate()
    {
        w.link.ingest(&msg(5, 2 + i as u8, bad), None);
    }
    let nav = ["vehicles", "mav5", "nav"];
    assert!((w.f(&nav, "roll") - 0.1f64.to_degrees()).abs() < 1e-3);
    assert!((w.f(&nav, "pitch") - 0.2f64.to_degrees()).abs() < 1e-3);
    assert_eq!(w.status(Reason::Attitude.property()), 3);
}

#[test]
fn a_flood_of_system_ids_is_bounded_and_silent_vehicles_are_forgotten() {
    let cfg = LinkConfig {
        max_vehicles: 8,
        forget_after: Duration::from_secs(30),
        ..LinkConfig::default()
    };
    let w = world(cfg, None);
    for sysid in 1..=10_000u32 {
        w.link.ingest(&quad(sysid, 0), None);
    }
    assert_eq!(w.link.vehicles(), 8);
    assert_eq!(w.ds.children(w.ds.resolve(&["vehicles"]).unwrap()).unwrap().len(), 8);
    assert_eq!(w.status("vehicles"), 8);
    assert_eq!(w.status(Reason::VehicleLimit.property()), 10_000 - 8);

    // Vehicle 1 keeps talking; the others fall silent and are forgotten, not before.
    w.clock.advance(Duration::from_secs(20));
    w.link.ingest(&quad(1, 1), None);
    w.clock.advance(Duration::from_secs(10));
    w.link.watchdog(false);
    assert_eq!(w.link.vehicles(), 8, "30 s of silence: not yet");
    w.clock.advance(Duration::from_millis(1));
    w.link.watchdog(false);
    assert_eq!(w.link.vehicles(), 1);
    assert!(w.ds.resolve(&["vehicles", "mav2"]).is_none(), "its object is gone");
    assert_eq!(w.status("forgotten"), 7);
    // Their places are free again.
    w.link.ingest(&quad(20_000, 0), None);
    w.vehicle("mav20000");
}

fn peer() -> (UdpSocket, SocketAddr) {
    let s = UdpSocket::bind("127.0.0.1:0").unwrap();
    s.set_read_timeout(Some(Duration::from_secs(30))).unwrap();
    let a = s.local_addr().unwrap();
    (s, a)
}

#[test]
fn only_an_address_that_proved_itself_with_heartbeats_in_sequence_is_answered() {
    let ours = Arc::new(UdpSocket::bind("127.0.0.1:0").unwrap());
    let w = world(LinkConfig { proof_heartbeats: 3, ..LinkConfig::default() }, Some(ours));
    let (vehicle, at) = peer();
    let (_spoofer, spoofed) = peer();
    let sent = || w.link.counters().sent.load(std::sync::atomic::Ordering::Relaxed);

    // A spoofed flood: one heartbeat each from many system ids.
    for sysid in 100..120 {
        w.link.ingest(&quad(sysid, 0), Some(spoofed));
    }
    // A replayed sequence number does not count twice.
    w.link.ingest(&quad(7, 0), Some(at));
    w.link.ingest(&quad(7, 0), Some(at));
    w.link.ingest(&quad(7, 1), Some(at));
    w.link.watchdog(true);
    assert_eq!(sent(), 0, "nothing to unproved addresses");
    assert_eq!(w.get(&["vehicles", "mav7"], "verified"), Value::Bool(false));
    match w.ds.call_wait(w.vehicle("mav7"), "arm", vec![Value::Bool(true)], None) {
        CallOutcome::Refused(why) => assert!(why.contains("not proved"), "{why}"),
        other => panic!("a command to an unproved vehicle: {other:?}"),
    }

    w.link.ingest(&quad(7, 2), Some(at));
    assert_eq!(w.get(&["vehicles", "mav7"], "verified"), Value::Bool(true));
    w.link.watchdog(true);
    assert_eq!(sent(), 1, "one heartbeat, to the proved vehicle only");
    let mut buf = [0u8; 512];
    let (n, _) = vehicle.recv_from(&mut buf).unwrap();
    let mut got = Vec::new();
    mocu_mavlink::decode_datagram(&buf[..n], |h, m| got.push((h.system_id, m)));
    assert!(matches!(got[..], [(255, mocu_mavlink::Msg::Heartbeat(_))]), "{got:?}");
}

#[test]
fn a_command_to_a_system_id_over_255_is_refused_not_truncated() {
    let ours = Arc::new(UdpSocket::bind("127.0.0.1:0").unwrap());
    let w = world(LinkConfig { proof_heartbeats: 1, ..LinkConfig::default() }, Some(ours));
    let (listener, at) = peer();
    w.link.ingest(&quad(256, 0), Some(at));
    let v = w.vehicle("mav256");
    assert_eq!(w.get(&["vehicles", "mav256"], "sysid"), Value::Int(256));
    match w.ds.call_wait(v, "arm", vec![Value::Bool(true)], None) {
        CallOutcome::Refused(why) => assert!(why.contains("256 does not fit"), "{why}"),
        other => panic!("{other:?}"),
    }
    assert_eq!(w.link.counters().sent.load(std::sync::atomic::Ordering::Relaxed), 0);
    drop(listener);
}

fn signed(sysid: u32, seq: u8, key: &str, timestamp: u64) -> Vec<u8> {
    let mut f = quad(sysid, seq);
    Signing::new(Key::parse(key).unwrap(), 1).sign(&mut f, MavMessage::extra_crc(0), timestamp);
    f
}

#[test]
fn a_link_with_a_key_accepts_only_frames_signed_with_it_and_moving_forward() {
    let key = "correct horse battery staple";
    let cfg = LinkConfig { signing_key: Some(Key::parse(key).unwrap()), ..LinkConfig::default() };
    let w = world(cfg, None);
    w.link.ingest(&quad(1, 0), None);
    w.link.ingest(&signed(2, 0, "wrong key", 1_000), None);
    let mut garbage = signed(3, 0, key, 1_000);
    let n = garbage.len();
    garbage[n - 1] ^= 0x55;
    w.link.ingest(&garbage, None);
    let unknown_flag = frame(4, 0, 0, &heartbeat_payload(2, 3, 4), 0x04);
    w.link.ingest(&unknown_flag, None);
    assert_eq!(w.link.vehicles(), 0);
    assert_eq!(w.status(Reason::Unsigned.property()), 1);
    assert_eq!(w.status(Reason::BadSignature.property()), 2);
    assert_eq!(w.status(Reason::Incompatible.property()), 1);

    let good = signed(5, 0, key, 1_000);
    w.link.ingest(&good, None);
    w.vehicle("mav5");
    w.link.ingest(&good, None);
    w.link.ingest(&signed(5, 1, key, 999), None);
    assert_eq!(w.status(Reason::OldTimestamp.property()), 2, "a replay and a step back");
    w.link.ingest(&signed(5, 2, key, 1_001), None);
    assert_eq!(w.status("decoded"), 2);
}

#[test]
fn unknown_incompatibility_flags_are_refused_even_without_a_key() {
    let w = world(LinkConfig::default(), None);
    w.link.ingest(&frame(4, 0, 0, &heartbeat_payload(2, 3, 4), 0x80), None);
    assert_eq!(w.link.vehicles(), 0);
    assert_eq!(w.status(Reason::Incompatible.property()), 1);
}

#[test]
fn what_a_link_with_a_key_sends_is_signed_with_it() {
    let key = "00112233445566778899aabbccddeeff00112233445566778899aabbccddeeff";
    let ours = Arc::new(UdpSocket::bind("127.0.0.1:0").unwrap());
    let cfg = LinkConfig {
        signing_key: Some(Key::parse(key).unwrap()),
        proof_heartbeats: 1,
        ..LinkConfig::default()
    };
    let w = world(cfg, Some(ours));
    let (vehicle, at) = peer();
    w.link.ingest(&signed(7, 0, key, 5), Some(at));
    w.link.watchdog(true);
    let mut buf = [0u8; 512];
    let (n, _) = vehicle.recv_from(&mut buf).unwrap();
    assert_eq!(buf[2] & 0x01, 0x01, "the SIGNED flag");
    let mut theirs = Signing::new(Key::parse(key).unwrap(), 0);
    let mut got = 0;
    let counts = mocu_mavlink::decode_checked(&buf[..n], Some(&mut theirs), |_, _| got += 1);
    assert_eq!((got, counts.bad_signature, counts.unsigned), (1, 0, 0));
    let mut wrong = Signing::new(Key::parse("another").unwrap(), 0);
    let counts = mocu_mavlink::decode_checked(&buf[..n], Some(&mut wrong), |_, _| {});
    assert_eq!(counts.bad_signature, 1);
}

#[test]
fn a_command_acknowledged_with_a_result_newer_than_the_dialect_is_refused_with_its_number() {
    let ours = Arc::new(UdpSocket::bind("127.0.0.1:0").unwrap());
    let w = world(LinkConfig { proof_heartbeats: 1, ..LinkConfig::default() }, Some(ours));
    let (vehicle, at) = peer();
    w.link.ingest(&quad(8, 0), Some(at));
    let v = w.vehicle("mav8");
    let ds = w.ds.clone();
    let call = std::thread::spawn(move || ds.call_wait(v, "arm", vec![Value::Bool(true)], None));
    // The command reaches the vehicle…
    let mut buf = [0u8; 512];
    let (n, _) = vehicle.recv_from(&mut buf).unwrap();
    let mut got = Vec::new();
    mocu_mavlink::decode_datagram(&buf[..n], |_, m| got.push(m));
    assert!(matches!(got[..], [mocu_mavlink::Msg::Other(MavMessage::COMMAND_LONG(_))]), "{got:?}");
    // …which answers with a result our dialect does not know.
    let mut ack = payload(&MavMessage::COMMAND_ACK(COMMAND_ACK_DATA {
        command: MavCmd::MAV_CMD_COMPONENT_ARM_DISARM,
        result: MavResult::MAV_RESULT_ACCEPTED,
    }));
    ack.resize(3, 0);
    ack[2] = 99;
    w.link.ingest(&frame(8, 1, 77, &ack, 0), None);
    assert_eq!(call.join().unwrap(), CallOutcome::Refused("MAV_RESULT unknown(99)".into()));
    assert_eq!(w.status("malformed"), 0);
}

/// What each heartbeat writes declares the heartbeat's rate (1 Hz), so that a display takes
/// it as stale after three missed heartbeats; the telemetry each message writes declares
/// the least rate autopilots stream that message at (position, attitude, VFR_HUD 2 Hz;
/// SYS_STATUS and GPS_RAW_INT 1 Hz): a stream that stops goes stale while the link lives.
#[test]
fn heartbeat_properties_declare_one_hertz_and_telemetry_the_rate_of_its_message() {
    let w = world(LinkConfig::default(), None);
    w.link.ingest(&quad(7, 0), None);
    let v = w.vehicle("mav7");
    for p in ["armed", "engine", "mode", "system_status", "link"] {
        assert_eq!(w.ds.meta(v, p).unwrap().rate_hz, Some(1.0), "{p}");
    }
    for p in ["fuel", "battery_v", "drop_rate"] {
        assert_eq!(w.ds.meta(v, p).unwrap().rate_hz, Some(1.0), "SYS_STATUS: {p}");
    }
    let nav = w.ds.resolve(&["vehicles", "mav7", "nav"]).unwrap();
    let rates = [
        (["speed", "heading", "lat", "lon", "x", "y", "alt", "alt_msl", "climb"].as_slice(), 2.0),
        (&["roll", "pitch", "yaw"], 2.0),
        (&["airspeed", "groundspeed", "throttle"], 2.0),
        (&["gps_fix", "gps_fix_raw", "satellites", "hdop"], 1.0),
    ];
    for (props, hz) in rates {
        for p in props {
            assert_eq!(w.ds.meta(nav, *p).unwrap().rate_hz, Some(hz), "nav.{p}");
        }
    }
    // Not telemetry: what the vehicle is and what we made of its link.
    for p in ["name", "sysid", "link_lost", "stale", "verified", "control"] {
        assert_eq!(w.ds.meta(v, p).unwrap().rate_hz, None, "{p}");
    }
}
