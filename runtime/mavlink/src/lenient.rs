//! Messages whose enum fields may be newer than our dialect. An autopilot newer than the
//! `common` dialect sends MAV_TYPE, MAV_AUTOPILOT or MAV_STATE values, or a GPS fix type,
//! that the typed parser rejects as a whole; here those fields keep their raw number and the
//! rest of the message is parsed as usual, so the vehicle still appears and shows
//! `unknown(42)` where a name would be.

use mavlink::dialects::development::{
    GPS_RAW_INT_DATA, GpsFixType, HEARTBEAT_DATA, MavAutopilot, MavCmd, MavMessage, MavModeFlag,
    MavResult, MavState, MavType,
};
use mavlink::error::ParserError;
use mavlink::{MavlinkVersion, Message};
use num_traits::FromPrimitive;
use std::fmt::Debug;

/// An enum field: its raw number, and its dialect name when the dialect knows it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Lenient<T> {
    pub raw: u8,
    pub known: Option<T>,
}

impl<T: FromPrimitive + Debug + Copy> Lenient<T> {
    pub fn from_raw(raw: u8) -> Lenient<T> {
        Lenient { raw, known: T::from_u8(raw) }
    }

    /// The dialect's name without `prefix` (`QUADROTOR` for `MAV_TYPE_QUADROTOR`), or
    /// `unknown(<raw>)`.
    pub fn name(&self, prefix: &str) -> String {
        match self.known {
            Some(k) => format!("{k:?}").trim_start_matches(prefix).to_string(),
            None => format!("unknown({})", self.raw),
        }
    }
}

/// HEARTBEAT with its enum fields kept as numbers.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Heartbeat {
    pub custom_mode: u32,
    pub mavtype: Lenient<MavType>,
    pub autopilot: Lenient<MavAutopilot>,
    pub base_mode: MavModeFlag,
    pub system_status: Lenient<MavState>,
}

/// GPS_RAW_INT with its fix type kept as a number (the other fields as the dialect has them).
#[derive(Clone, Debug, PartialEq)]
pub struct GpsRaw {
    pub fix: Lenient<GpsFixType>,
    pub data: GPS_RAW_INT_DATA,
}

/// COMMAND_ACK with its result kept as a number (a newer autopilot's result refuses the
/// command with its number rather than leaving it to time out).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CommandAck {
    pub command: MavCmd,
    pub result: Lenient<MavResult>,
}

/// A decoded message: the ones that carry the enums a newer autopilot extends, parsed
/// leniently, and every other message as the dialect types it.
/// (`MavMessage` is as large on its own; boxing it would allocate per message.)
#[allow(clippy::large_enum_variant)]
#[derive(Clone, Debug, PartialEq)]
pub enum Msg {
    Heartbeat(Heartbeat),
    GpsRaw(GpsRaw),
    CommandAck(CommandAck),
    Other(MavMessage),
}

const HEARTBEAT_ID: u32 = 0;
const GPS_RAW_INT_ID: u32 = 24;
const COMMAND_ACK_ID: u32 = 77;
/// Wire offsets (fields sorted by size, as MAVLink sends them).
const HB_TYPE: usize = 4;
const HB_AUTOPILOT: usize = 5;
const HB_STATUS: usize = 7;
const GPS_FIX: usize = 28;
const ACK_RESULT: usize = 2;

/// Parses one payload. HEARTBEAT and GPS_RAW_INT never fail on an enum value.
pub fn parse(version: MavlinkVersion, msgid: u32, payload: &[u8]) -> Result<Msg, ParserError> {
    // MAVLink 2 drops trailing zero bytes: a missing byte reads as 0.
    let byte = |i: usize| payload.get(i).copied().unwrap_or(0);
    match msgid {
        HEARTBEAT_ID => {
            let mut patched = payload.to_vec();
            let mavtype = Lenient::<MavType>::from_raw(byte(HB_TYPE));
            let autopilot = Lenient::<MavAutopilot>::from_raw(byte(HB_AUTOPILOT));
            let system_status = Lenient::<MavState>::from_raw(byte(HB_STATUS));
            for (at, known) in [
                (HB_TYPE, mavtype.known.is_some()),
                (HB_AUTOPILOT, autopilot.known.is_some()),
                (HB_STATUS, system_status.known.is_some()),
            ] {
                if !known {
                    patched[at] = 0;
                }
            }
            let hb: HEARTBEAT_DATA = match MavMessage::parse(version, msgid, &patched)? {
                MavMessage::HEARTBEAT(hb) => hb,
                _ => return Err(ParserError::UnknownMessage { id: msgid }),
            };
            Ok(Msg::Heartbeat(Heartbeat {
                custom_mode: hb.custom_mode,
                mavtype,
                autopilot,
                base_mode: hb.base_mode,
                system_status,
            }))
        }
        GPS_RAW_INT_ID => {
            let mut patched = payload.to_vec();
            let fix = Lenient::<GpsFixType>::from_raw(byte(GPS_FIX));
            if fix.known.is_none() {
                patched[GPS_FIX] = 0;
            }
            match MavMessage::parse(version, msgid, &patched)? {
                MavMessage::GPS_RAW_INT(data) => Ok(Msg::GpsRaw(GpsRaw { fix, data })),
                _ => Err(ParserError::UnknownMessage { id: msgid }),
            }
        }
        COMMAND_ACK_ID => {
            let mut patched = payload.to_vec();
            let result = Lenient::<MavResult>::from_raw(byte(ACK_RESULT));
            if result.known.is_none() {
                patched[ACK_RESULT] = 0;
            }
            match MavMessage::parse(version, msgid, &patched)? {
                MavMessage::COMMAND_ACK(ack) => {
                    Ok(Msg::CommandAck(CommandAck { command: ack.command, result }))
                }
                _ => Err(ParserError::UnknownMessage { id: msgid }),
            }
        }
        _ => MavMessage::parse(version, msgid, payload).map(Msg::Other),
    }
}

impl From<MavMessage> for Msg {
    /// The lenient form of a typed message (what a newer autopilot's would decode to when
    /// its values are known).
    fn from(m: MavMessage) -> Msg {
        match m {
            MavMessage::HEARTBEAT(hb) => Msg::Heartbeat(Heartbeat {
                custom_mode: hb.custom_mode,
                mavtype: Lenient { raw: hb.mavtype as u8, known: Some(hb.mavtype) },
                autopilot: Lenient { raw: hb.autopilot as u8, known: Some(hb.autopilot) },
                base_mode: hb.base_mode,
                system_status: Lenient {
                    raw: hb.system_status as u8,
                    known: Some(hb.system_status),
                },
            }),
            MavMessage::GPS_RAW_INT(data) => Msg::GpsRaw(GpsRaw {
                fix: Lenient { raw: data.fix_type as u8, known: Some(data.fix_type) },
                data,
            }),
            MavMessage::COMMAND_ACK(ack) => Msg::CommandAck(CommandAck {
                command: ack.command,
                result: Lenient { raw: ack.result as u8, known: Some(ack.result) },
            }),
            other => Msg::Other(other),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn heartbeat_payload(t: u8, ap: u8, status: u8) -> Vec<u8> {
        vec![4, 0, 0, 0, t, ap, 1, status, 3]
    }

    #[test]
    fn a_heartbeat_with_values_newer_than_the_dialect_keeps_them_as_numbers() {
        let Msg::Heartbeat(hb) =
            parse(MavlinkVersion::V2, 0, &heartbeat_payload(142, 99, 17)).unwrap()
        else {
            panic!("a heartbeat")
        };
        assert_eq!(hb.mavtype.name("MAV_TYPE_"), "unknown(142)");
        assert_eq!(hb.autopilot.name("MAV_AUTOPILOT_"), "unknown(99)");
        assert_eq!(hb.system_status.name("MAV_STATE_"), "unknown(17)");
        assert_eq!(hb.custom_mode, 4);
    }

    #[test]
    fn known_values_keep_their_dialect_names() {
        let Msg::Heartbeat(hb) = parse(MavlinkVersion::V2, 0, &heartbeat_payload(2, 3, 4)).unwrap()
        else {
            panic!("a heartbeat")
        };
        assert_eq!(hb.mavtype.known, Some(MavType::MAV_TYPE_QUADROTOR));
        assert_eq!(hb.mavtype.name("MAV_TYPE_"), "QUADROTOR");
        assert_eq!(hb.system_status.name("MAV_STATE_"), "ACTIVE");
    }

    #[test]
    fn a_gps_fix_type_of_9_is_kept_with_the_rest_of_the_message() {
        let mut p = vec![0u8; 30];
        p[8..12].copy_from_slice(&327_157_000i32.to_le_bytes());
        p[GPS_FIX] = 9;
        p[29] = 11;
        let Msg::GpsRaw(g) = parse(MavlinkVersion::V2, 24, &p).unwrap() else {
            panic!("GPS_RAW_INT")
        };
        assert_eq!(g.fix.name("GPS_FIX_TYPE_"), "unknown(9)");
        assert_eq!((g.data.lat, g.data.satellites_visible), (327_157_000, 11));
    }
}
