//! A seeded fuzz of the MAVLink framing, run in CI: valid frames (MAVLink 1 and 2, 32-bit
//! system ids, signed), mutated many ways (bits, bytes, insertions, cuts, splices, and
//! payload changes with the CRC made good again so they reach the parser and the checks),
//! fed to a link. Nothing panics, every datagram is accounted for, the vehicles stay
//! bounded with plausible values, and no mutated frame passes a signed link.

use mavlink::dialects::development::*;
use mavlink::{MavHeader, Message};
use mocu_dataserver::{Config, DataServer, ManualClock, Value};
use mocu_host::ModuleContext;
use mocu_mavlink::{DecodeCounts, Key, Link, LinkConfig, Signing, decode_checked, encode_v2};
use std::sync::Arc;

const SEED: u64 = 0x5eed_3a7f_1c0d_e015;
const ITERATIONS: usize = 20_000;
const MAX_VEHICLES: usize = 16;

/// xorshift64*: the same sequence on every run.
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        self.0.wrapping_mul(0x2545_f491_4f6c_dd1d)
    }
    fn below(&mut self, n: usize) -> usize {
        (self.next() % n.max(1) as u64) as usize
    }
}

fn corpus() -> Vec<Vec<u8>> {
    let msgs = [
        MavMessage::HEARTBEAT(HEARTBEAT_DATA {
            custom_mode: 4,
            mavtype: MavType::MAV_TYPE_QUADROTOR,
            autopilot: MavAutopilot::MAV_AUTOPILOT_ARDUPILOTMEGA,
            base_mode: MavModeFlag::MAV_MODE_FLAG_SAFETY_ARMED,
            system_status: MavState::MAV_STATE_ACTIVE,
            mavlink_version: 3,
        }),
        MavMessage::GLOBAL_POSITION_INT(GLOBAL_POSITION_INT_DATA {
            lat: 327_157_000,
            lon: -1_171_611_000,
            alt: 100_000,
            relative_alt: 10_000,
            vx: 300,
            hdg: 9000,
            ..Default::default()
        }),
        MavMessage::ATTITUDE(ATTITUDE_DATA {
            roll: 0.1,
            pitch: -0.2,
            yaw: 1.5,
            ..Default::default()
        }),
        MavMessage::GPS_RAW_INT(GPS_RAW_INT_DATA {
            fix_type: GpsFixType::GPS_FIX_TYPE_3D_FIX,
            satellites_visible: 11,
            ..Default::default()
        }),
        MavMessage::VFR_HUD(VFR_HUD_DATA { airspeed: 5.0, throttle: 40, ..Default::default() }),
        MavMessage::SYS_STATUS(SYS_STATUS_DATA {
            voltage_battery: 12_600,
            battery_remaining: 80,
            ..Default::default()
        }),
        MavMessage::COMMAND_ACK(COMMAND_ACK_DATA {
            command: MavCmd::MAV_CMD_COMPONENT_ARM_DISARM,
            result: MavResult::MAV_RESULT_ACCEPTED,
        }),
    ];
    let mut out = Vec::new();
    for (i, m) in msgs.iter().enumerate() {
        for sysid in [1u32, 7, 300] {
            let h = MavHeader { system_id: sysid, component_id: 1, sequence: i as u8 };
            out.push(encode_v2(h, m));
        }
        let mut v1 = Vec::new();
        let h = MavHeader { system_id: 2, component_id: 1, sequence: i as u8 };
        let _ = mavlink::write_v1_msg(&mut v1, h, m);
        out.push(v1);
    }
    out
}

/// Makes the CRC of a MAVLink 2 frame good again (so a changed payload reaches the parser).
fn fix_crc(f: &mut [u8]) {
    if f.len() < 12 || f[0] != 0xFD {
        return;
    }
    let hlen = if f[2] & 0x02 != 0 { 12 } else { 9 };
    let end = 1 + hlen + usize::from(f[1]);
    if f.len() < end + 2 {
        return;
    }
    let id = u32::from_le_bytes([f[hlen - 2], f[hlen - 1], f[hlen], 0]);
    let crc = mavlink::calculate_crc(&f[1..end], MavMessage::extra_crc(id));
    f[end..end + 2].copy_from_slice(&crc.to_le_bytes());
}

fn mutate(rng: &mut Rng, corpus: &[Vec<u8>]) -> Vec<u8> {
    let mut f = corpus[rng.below(corpus.len())].clone();
    for _ in 0..1 + rng.below(3) {
        let n = f.len();
        match rng.below(8) {
            0 => f[rng.below(n)] ^= 1 << rng.below(8),
            1 => f[rng.below(n)] = rng.next() as u8,
            2 => {
                let at = rng.below(n + 1);
                let extra: Vec<u8> = (0..1 + rng.below(8)).map(|_| rng.next() as u8).collect();
                f.splice(at..at, extra);
            }
            3 => f.truncate(rng.below(n)),
            4 => {
                let at = rng.below(n);
                f.drain(at..(at + 1 + rng.below(4)).min(n));
            }
            5 => f.extend(corpus[rng.below(corpus.len())].iter()),
            6 => {
                // A payload byte changed, the CRC made good: the parser and the checks see it.
                if n > 12 {
                    let at = 10 + rng.below(n - 12);
                    f[at] = rng.next() as u8;
                    fix_crc(&mut f);
                }
            }
            _ => {
                // Header fields: length, flags, ids.
                f[rng.below(n.min(10))] = rng.next() as u8;
                if rng.below(2) == 0 {
                    fix_crc(&mut f);
                }
            }
        }
        if f.is_empty() {
            f.push(0xFD);
        }
    }
    f
}

fn accounted(c: &DecodeCounts) -> u64 {
    c.decoded
        + c.malformed
        + c.unknown
        + c.incompatible
        + c.unsigned
        + c.bad_signature
        + c.old_timestamp
}

#[test]
fn mutated_mavlink_frames_never_panic_are_all_accounted_for_and_keep_the_world_plausible() {
    let clock = ManualClock::new();
    let ds = DataServer::with_clock(Config::default(), Arc::new(clock.clone()));
    let cfg = LinkConfig { max_vehicles: MAX_VEHICLES, ..LinkConfig::default() };
    let link = Link::new(ModuleContext::detached("mavlink", ds.clone()), cfg, None).unwrap();
    let corpus = corpus();
    for f in &corpus {
        let c = decode_checked(f, None, |_, _| {});
        assert_eq!(c.decoded, 1, "the corpus is valid: {f:?}");
    }
    let mut rng = Rng(SEED);
    for i in 0..ITERATIONS {
        let f = mutate(&mut rng, &corpus);
        let c = decode_checked(&f, None, |_, _| {});
        assert!(accounted(&c) >= 1, "iteration {i}: {f:?} was not accounted for");
        assert!(c.decoded <= f.iter().filter(|b| **b == 0xFD || **b == 0xFE).count() as u64);
        link.ingest(&f, None);
        if i % 1000 == 0 {
            link.watchdog(false);
        }
    }
    link.watchdog(false);
    assert!(link.vehicles() <= MAX_VEHICLES);
    let vehicles = ds.resolve(&["vehicles"]).unwrap();
    for v in ds.children(vehicles).unwrap() {
        let nav = ds
            .children(v)
            .unwrap()
            .into_iter()
            .find(|c| ds.info(*c).is_ok_and(|i| &*i.name == "nav"));
        let nav = nav.expect("every vehicle has nav");
        let f = |p: &str| ds.get(nav, p).unwrap().as_f64().unwrap();
        assert!((-90.0..=90.0).contains(&f("lat")) && (-180.0..=180.0).contains(&f("lon")));
        for p in ["roll", "pitch", "yaw", "x", "y", "alt"] {
            assert!(f(p).is_finite(), "{p} = {}", f(p));
        }
        assert!(f("alt").abs() <= 100_000.0);
    }
    assert_eq!(
        ds.get(ds.resolve(&["modules", "mavlink"]).unwrap(), "datagrams").unwrap(),
        Value::Int(ITERATIONS as i64)
    );
}

#[test]
fn no_mutation_of_a_signed_frame_passes_a_link_with_the_key() {
    let key = Key::parse("fuzz key").unwrap();
    let mut sender = Signing::new(key.clone(), 3);
    let corpus: Vec<Vec<u8>> = corpus()
        .into_iter()
        .filter(|f| f[0] == 0xFD)
        .enumerate()
        .map(|(i, mut f)| {
            let id = u32::from_le_bytes([f[7], f[8], f[9], 0]);
            let id =
                if f[2] & 0x02 != 0 { u32::from_le_bytes([f[10], f[11], f[12], 0]) } else { id };
            sender.sign(&mut f, MavMessage::extra_crc(id), 1_000 + i as u64);
            f
        })
        .collect();
    let mut receiver = Signing::new(key, 0);
    for f in &corpus {
        assert_eq!(decode_checked(f, Some(&mut receiver), |_, _| {}).decoded, 1);
    }
    // Every frame was seen once: a copy is a replay, a change breaks the signature.
    let mut rng = Rng(SEED ^ 1);
    for i in 0..ITERATIONS / 2 {
        let f = mutate(&mut rng, &corpus);
        let c = decode_checked(&f, Some(&mut receiver), |_, _| {});
        assert_eq!(c.decoded, 0, "iteration {i}: a mutated signed frame passed: {f:?}");
    }
}
