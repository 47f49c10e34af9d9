//! MAVLink ingest: messages decoded *and published* into the DataServer per second, against
//! the `mavlink` crate's decoding alone, on the same datagrams in the same run; and the
//! figures of a spoofed flood (10,713 system ids, as in issue #15): vehicles held, memory
//! grown and heartbeats sent back per second, with the old behaviour (no bound, every sender
//! answered) against the defaults.

#[path = "common/telemetry.rs"]
mod telemetry;

use criterion::{BatchSize, Criterion, Throughput, criterion_group, criterion_main};
use mavlink::MavHeader;
use mavlink::dialects::development::*;
use mocu_dataserver::DataServer;
use mocu_host::ModuleContext;
use mocu_mavlink::{Link, LinkConfig, decode_datagram, encode_v2};

/// A telemetry mix as a vehicle sends it: per second 1 HEARTBEAT + 1 SYS_STATUS and
/// 10 each of GLOBAL_POSITION_INT, ATTITUDE, VFR_HUD, GPS_RAW_INT; one datagram each.
fn datagrams(vehicles: u8) -> Vec<Vec<u8>> {
    let mut out = Vec::new();
    let mut seq = 0u8;
    for tick in 0..10u32 {
        for sys in 1..=vehicles {
            let mut push = |m: MavMessage| out.push(telemetry::datagram(sys, &mut seq, &m));
            if tick == 0 {
                push(telemetry::copter_heartbeat());
                push(MavMessage::SYS_STATUS(SYS_STATUS_DATA {
                    voltage_battery: 12600,
                    battery_remaining: 80,
                    ..SYS_STATUS_DATA::default()
                }));
            }
            let t = tick as i32;
            push(MavMessage::GLOBAL_POSITION_INT(GLOBAL_POSITION_INT_DATA {
                time_boot_ms: tick * 100,
                lat: 327_157_000 + t * 10,
                lon: -1_171_611_000 + t * 10,
                alt: 100_000,
                relative_alt: 10_000 + t,
                vx: 300,
                vy: 400,
                vz: 0,
                hdg: 9000 + tick as u16,
            }));
            push(MavMessage::ATTITUDE(ATTITUDE_DATA {
                time_boot_ms: tick * 100,
                roll: 0.01 * t as f32,
                pitch: 0.02,
                yaw: 1.5,
                rollspeed: 0.0,
                pitchspeed: 0.0,
                yawspeed: 0.0,
            }));
            push(MavMessage::VFR_HUD(VFR_HUD_DATA {
                airspeed: 5.0 + t as f32,
                groundspeed: 5.0,
                alt: 100.0,
                climb: 0.1,
                heading: 90,
                throttle: 40,
            }));
            push(MavMessage::GPS_RAW_INT(GPS_RAW_INT_DATA {
                fix_type: GpsFixType::GPS_FIX_TYPE_3D_FIX,
                satellites_visible: 10 + (tick % 3) as u8,
                ..GPS_RAW_INT_DATA::default()
            }));
        }
    }
    out
}

/// Resident memory in KiB (Linux), for the flood figures.
fn rss_kib() -> Option<u64> {
    let statm = std::fs::read_to_string("/proc/self/statm").ok()?;
    let pages: u64 = statm.split_whitespace().nth(1)?.parse().ok()?;
    Some(pages * 4)
}

/// One spoofed flood: a heartbeat from each of `ids` 32-bit system ids (three each, so they
/// would prove themselves), then one watchdog period with our heartbeats.
fn flood(label: &str, cfg: LinkConfig, ids: u32) {
    let ds = DataServer::default();
    let ours = std::sync::Arc::new(std::net::UdpSocket::bind("127.0.0.1:0").unwrap());
    // Replies go to a loopback port nobody listens on.
    let spoofed: std::net::SocketAddr = "127.0.0.1:9".parse().unwrap();
    let link = Link::new(ModuleContext::detached("mavlink", ds.clone()), cfg, Some(ours)).unwrap();
    let before = rss_kib();
    let t0 = std::time::Instant::now();
    for seq in 0..3u8 {
        for sys in 1000..1000 + ids {
            let h = MavHeader { system_id: sys, component_id: 1, sequence: seq };
            let hb = MavMessage::HEARTBEAT(HEARTBEAT_DATA {
                custom_mode: 0,
                mavtype: MavType::MAV_TYPE_QUADROTOR,
                autopilot: MavAutopilot::MAV_AUTOPILOT_ARDUPILOTMEGA,
                base_mode: MavModeFlag::empty(),
                system_status: MavState::MAV_STATE_ACTIVE,
                mavlink_version: 3,
            });
            link.ingest(&encode_v2(h, &hb), Some(spoofed));
        }
    }
    let secs = t0.elapsed().as_secs_f64();
    link.watchdog(true);
    ds.quiesce();
    let grown = match (before, rss_kib()) {
        (Some(a), Some(b)) => format!("{:.1} MiB", b.saturating_sub(a) as f64 / 1024.0),
        _ => "n/a".into(),
    };
    let sent = link.counters().sent.load(std::sync::atomic::Ordering::Relaxed);
    println!(
        "mavlink flood ({label}): {ids} spoofed ids x3 heartbeats in {secs:.2} s -> {} vehicles, memory +{grown}, {sent} heartbeats sent back per second",
        link.vehicles()
    );
}

fn bench(c: &mut Criterion) {
    // Issue #15's flood under `cargo bench`; a tenth of it in CI's quick test mode (a debug
    // build), where it only has to run.
    let ids = if std::env::args().any(|a| a == "--bench") { 10_713 } else { 1_000 };
    // The bounded defaults first (memory is measured as growth; freed memory is not returned).
    flood("defaults: max_vehicles 32, proof_heartbeats 3", LinkConfig::default(), ids);
    let unbounded = LinkConfig {
        max_vehicles: 65_535,
        proof_heartbeats: 1,
        max_send_rate: 100_000,
        ..LinkConfig::default()
    };
    flood("old behaviour: unbounded, every sender answered", unbounded, ids);
    let grams = datagrams(4);
    let n = grams.len() as u64;
    let mut group = c.benchmark_group("mavlink");
    group.throughput(Throughput::Elements(n));

    group.bench_function("crate_decode_only", |b| {
        b.iter(|| {
            let mut k = 0;
            for d in &grams {
                // Smallest read-ahead buffer (one max frame): no 16 KiB allocation per datagram.
                let mut r = mavlink::MavlinkReader::with_capacity(0, &d[..]);
                if r.read_any_message::<MavMessage>().is_ok() {
                    k += 1;
                }
            }
            assert_eq!(k, n);
        })
    });

    group.bench_function("mocu_decode_only", |b| {
        b.iter(|| {
            let mut k = 0u64;
            for d in &grams {
                k += decode_datagram(d, |_, m| {
                    std::hint::black_box(m);
                })
                .decoded;
            }
            assert_eq!(k, n);
        })
    });

    let ds = DataServer::default();
    let link =
        Link::new(ModuleContext::detached("mavlink", ds.clone()), LinkConfig::default(), None)
            .unwrap();
    for d in &grams {
        link.ingest(d, None); // discovery happens once, outside the measurement
    }
    group.bench_function("mocu_decode_and_publish", |b| {
        b.iter_batched(
            || (),
            |_| {
                for d in &grams {
                    link.ingest(d, None);
                }
            },
            BatchSize::SmallInput,
        )
    });
    group.finish();
    ds.quiesce();
}

criterion_group!(benches, bench);
criterion_main!(benches);
