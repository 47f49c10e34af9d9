//! What the MAVLink benches send: a copter's heartbeat, and a message as one MAVLink 2
//! datagram (`benches/mavlink.rs`, `benches/record_trial.rs`).

use mavlink::MavHeader;
use mavlink::dialects::development::*;

/// An ArduPilot copter's heartbeat, armed in a custom mode.
pub fn copter_heartbeat() -> MavMessage {
    MavMessage::HEARTBEAT(HEARTBEAT_DATA {
        custom_mode: 4,
        mavtype: MavType::MAV_TYPE_QUADROTOR,
        autopilot: MavAutopilot::MAV_AUTOPILOT_ARDUPILOTMEGA,
        base_mode: MavModeFlag::MAV_MODE_FLAG_CUSTOM_MODE_ENABLED,
        system_status: MavState::MAV_STATE_ACTIVE,
        mavlink_version: 3,
    })
}

/// `m` from system `sys`, component 1, as the datagram numbered `seq` (which moves on).
pub fn datagram(sys: u8, seq: &mut u8, m: &MavMessage) -> Vec<u8> {
    *seq = seq.wrapping_add(1);
    let h = MavHeader { system_id: u32::from(sys), component_id: 1, sequence: *seq };
    mocu_mavlink::encode_v2(h, m)
}
