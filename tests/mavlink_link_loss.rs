//! Link loss on a clock the test controls: no heartbeat for `link_timeout` marks the
//! vehicle lost and its data stale, not a moment before; the next heartbeat recovers it.
//! (tests/mavlink_peer.rs checks the same against a real pymavlink peer, in real time.)

use mavlink::MavHeader;
use mavlink::dialects::development::*;
use mocu_dataserver::{Config, DataServer, ManualClock, Value};
use mocu_host::ModuleContext;
use mocu_mavlink::{Link, LinkConfig, encode_v2};
use std::sync::Arc;
use std::time::Duration;

fn heartbeat(sequence: u8) -> Vec<u8> {
    let h = MavHeader { system_id: 7, component_id: 1, sequence };
    encode_v2(
        h,
        &MavMessage::HEARTBEAT(HEARTBEAT_DATA {
            custom_mode: 0,
            mavtype: MavType::MAV_TYPE_QUADROTOR,
            autopilot: MavAutopilot::MAV_AUTOPILOT_ARDUPILOTMEGA,
            base_mode: MavModeFlag::MAV_MODE_FLAG_CUSTOM_MODE_ENABLED,
            system_status: MavState::MAV_STATE_ACTIVE,
            mavlink_version: 3,
        }),
    )
}

#[test]
fn a_vehicle_is_lost_exactly_after_the_link_timeout_without_a_heartbeat_and_recovers_with_the_next()
{
    let clock = ManualClock::new();
    let ds = DataServer::with_clock(Config::default(), Arc::new(clock.clone()));
    let cfg = LinkConfig { link_timeout: Duration::from_secs(3), ..LinkConfig::default() };
    let link = Link::new(ModuleContext::detached("mavlink", ds.clone()), cfg, None).unwrap();
    link.ingest(&heartbeat(0), None);
    let v = ds.resolve(&["vehicles", "mav7"]).expect("discovered by its heartbeat");
    let lost = || ds.get(v, "link_lost").unwrap();
    let stale = || ds.get(v, "stale").unwrap();
    assert_eq!((lost(), stale()), (Value::Bool(false), Value::Bool(false)));

    // Heartbeats keep it: silence is counted from the last one.
    clock.advance(Duration::from_secs(2));
    link.ingest(&heartbeat(1), None);
    clock.advance(Duration::from_secs(2));
    link.watchdog(false);
    assert_eq!(lost(), Value::Bool(false), "2 s after the last heartbeat");

    clock.advance(Duration::from_millis(999));
    link.watchdog(false);
    assert_eq!(lost(), Value::Bool(false), "2.999 s: not yet");

    clock.advance(Duration::from_millis(2));
    link.watchdog(false);
    assert_eq!((lost(), stale()), (Value::Bool(true), Value::Bool(true)), "3.001 s: lost");
    assert_eq!(ds.get(v, "link").unwrap(), Value::Float(0.0));

    link.ingest(&heartbeat(2), None);
    assert_eq!((lost(), stale()), (Value::Bool(false), Value::Bool(false)), "recovered");
    link.watchdog(false);
    assert_eq!(lost(), Value::Bool(false), "the new heartbeat restarts the count");
}
