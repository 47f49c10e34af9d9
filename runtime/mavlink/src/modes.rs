//! Flight-mode names: ArduPilot's custom modes by vehicle family; other autopilots show
//! `custom:<n>`.

use mavlink::dialects::development::{MavAutopilot, MavType};

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Family {
    Copter,
    Plane,
    Rover,
}

const COPTER: &[(&str, u32)] = &[
    ("STABILIZE", 0),
    ("ACRO", 1),
    ("ALT_HOLD", 2),
    ("AUTO", 3),
    ("GUIDED", 4),
    ("LOITER", 5),
    ("RTL", 6),
    ("CIRCLE", 7),
    ("LAND", 9),
    ("DRIFT", 11),
    ("SPORT", 13),
    ("POSHOLD", 16),
    ("BRAKE", 17),
    ("SMART_RTL", 21),
];
const PLANE: &[(&str, u32)] = &[
    ("MANUAL", 0),
    ("CIRCLE", 1),
    ("STABILIZE", 2),
    ("TRAINING", 3),
    ("ACRO", 4),
    ("FBWA", 5),
    ("FBWB", 6),
    ("CRUISE", 7),
    ("AUTOTUNE", 8),
    ("AUTO", 10),
    ("RTL", 11),
    ("LOITER", 12),
    ("TAKEOFF", 13),
    ("GUIDED", 15),
];
const ROVER: &[(&str, u32)] = &[
    ("MANUAL", 0),
    ("ACRO", 1),
    ("STEERING", 3),
    ("HOLD", 4),
    ("LOITER", 5),
    ("FOLLOW", 6),
    ("SIMPLE", 7),
    ("AUTO", 10),
    ("RTL", 11),
    ("SMART_RTL", 12),
    ("GUIDED", 15),
];

/// The world-model type, subtype and mode family of a MAV_TYPE; `None` for things that are
/// not vehicles (ground stations, gimbals, cameras…).
pub fn classify(t: MavType) -> Option<(&'static str, Family)> {
    use MavType::*;
    Some(match t {
        MAV_TYPE_QUADROTOR
        | MAV_TYPE_COAXIAL
        | MAV_TYPE_HELICOPTER
        | MAV_TYPE_HEXAROTOR
        | MAV_TYPE_OCTOROTOR
        | MAV_TYPE_TRICOPTER
        | MAV_TYPE_DODECAROTOR
        | MAV_TYPE_DECAROTOR
        | MAV_TYPE_GENERIC_MULTIROTOR => ("uav", Family::Copter),
        MAV_TYPE_FIXED_WING
        | MAV_TYPE_AIRSHIP
        | MAV_TYPE_FLAPPING_WING
        | MAV_TYPE_KITE
        | MAV_TYPE_PARAFOIL
        | MAV_TYPE_VTOL_TAILSITTER_DUOROTOR
        | MAV_TYPE_VTOL_TAILSITTER_QUADROTOR
        | MAV_TYPE_VTOL_TILTROTOR
        | MAV_TYPE_VTOL_FIXEDROTOR
        | MAV_TYPE_VTOL_TAILSITTER
        | MAV_TYPE_VTOL_TILTWING
        | MAV_TYPE_VTOL_GYRODYNE => ("uav", Family::Plane),
        MAV_TYPE_SURFACE_BOAT | MAV_TYPE_SUBMARINE => ("usv", Family::Rover),
        MAV_TYPE_GROUND_ROVER | MAV_TYPE_GROUND_QUADRUPED => ("ugv", Family::Rover),
        MAV_TYPE_GENERIC => ("uav", Family::Copter),
        _ => return None,
    })
}

/// `quadrotor` from `MAV_TYPE_QUADROTOR`.
pub fn subtype(t: MavType) -> String {
    format!("{t:?}").trim_start_matches("MAV_TYPE_").to_ascii_lowercase()
}

fn table(f: Family) -> &'static [(&'static str, u32)] {
    match f {
        Family::Copter => COPTER,
        Family::Plane => PLANE,
        Family::Rover => ROVER,
    }
}

pub fn mode_name(ap: MavAutopilot, f: Family, custom: u32) -> String {
    if ap == MavAutopilot::MAV_AUTOPILOT_ARDUPILOTMEGA
        && let Some((n, _)) = table(f).iter().find(|(_, c)| *c == custom)
    {
        return n.to_string();
    }
    format!("custom:{custom}")
}

/// The custom mode number for a name (case-insensitive), or `custom:N` / `N`.
pub fn mode_number(ap: MavAutopilot, f: Family, name: &str) -> Result<u32, String> {
    let n = name.trim();
    if let Ok(num) = n.strip_prefix("custom:").unwrap_or(n).parse::<u32>() {
        return Ok(num);
    }
    if ap == MavAutopilot::MAV_AUTOPILOT_ARDUPILOTMEGA
        && let Some((_, c)) = table(f).iter().find(|(m, _)| m.eq_ignore_ascii_case(n))
    {
        return Ok(*c);
    }
    let known: Vec<&str> = table(f).iter().map(|(m, _)| *m).collect();
    Err(format!("unknown mode `{n}` (known: {})", known.join(", ")))
}
