//! One vehicle heard on a link: what we keep of it, how it appears in the world model (its
//! object, properties and methods), how its address proves itself, and how it is forgotten.

use crate::lenient::{Heartbeat, Lenient};
use crate::link::Link;
use crate::mission::{Mission, Upload};
use crate::modes::{self, Family};
use mavlink::MavHeader;
use mavlink::dialects::development::{MavAutopilot, MavCmd, MavMessage, MavType};
use mocu_dataserver::{DsError, Guid, ObjectInfo, Responder, Value};
use mocu_host::world::{self, RouteFrame, boolean, float, float_in, int, string};
use std::net::SocketAddr;
use std::time::Instant;

/// The heartbeat rate the MAVLink spec asks of every system (Hz).
const HEARTBEAT_HZ: f64 = 1.0;
/// The rates (Hz) declared on the telemetry each message writes (`PropMeta::rate_hz`): the
/// least the autopilots' default streams send — ArduPilot's `SRn_*` stream rates and PX4's
/// telemetry profiles send GLOBAL_POSITION_INT, ATTITUDE and VFR_HUD at 2 Hz or more on
/// every link, SYS_STATUS and GPS_RAW_INT at 1 Hz or more. A display takes a value as stale
/// after three periods without a write (docs/display.md): one a vehicle stopped sending.
pub(crate) const POSITION_HZ: f64 = 2.0;
pub(crate) const ATTITUDE_HZ: f64 = 2.0;
pub(crate) const VFR_HUD_HZ: f64 = 2.0;
pub(crate) const SYS_STATUS_HZ: f64 = 1.0;
pub(crate) const GPS_RAW_HZ: f64 = 1.0;

pub(crate) struct Pending {
    pub id: u64,
    pub command: MavCmd,
    pub msg: MavMessage,
    pub attempts: u32,
    pub responder: Responder,
}

/// What the vehicle's CONTROL_STATUS says (docs/distribution.md, "Control arbitration").
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct GcsControl {
    pub main: u8,
    pub takeover_allowed: bool,
}

/// An address being proved: heartbeats seen from it, in sequence.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Candidate {
    pub addr: SocketAddr,
    pub heartbeats: u32,
    pub last_seq: u8,
}

pub(crate) struct Vehicle {
    pub sysid: u32,
    pub compid: u8,
    pub guid: Guid,
    pub nav: Guid,
    /// The address we answer: set only once it has proved itself (`prove`).
    pub addr: Option<SocketAddr>,
    pub candidate: Option<Candidate>,
    pub family: Family,
    pub autopilot: Option<MavAutopilot>,
    pub last_heartbeat: Instant,
    pub lost: bool,
    pub last_seq: Option<u8>,
    pub rx_w: f64,
    pub lost_w: f64,
    /// Home, latched from two agreeing plausible positions (`telemetry.rs`).
    pub home: Option<(f64, f64)>,
    pub home_candidate: Option<(f64, f64)>,
    /// The last GPS fix type heard (raw), if any.
    pub gps_fix: Option<u8>,
    pub control: String,
    /// The GCS operator-control protocol, once the vehicle streams CONTROL_STATUS: the
    /// system id of the GCS in control (0: none) and whether a takeover is granted at once.
    pub gcs: Option<GcsControl>,
    /// The operator this adapter asked the vehicle's control for.
    pub requester: String,
    pub commands: Vec<Pending>,
    pub upload: Option<Upload>,
    /// The route the vehicle holds, kept in step by deltas (`mission.rs`).
    pub mission: Option<Mission>,
}

impl Vehicle {
    /// The autopilot for mode names (an unknown one names modes `custom:N`).
    pub fn autopilot_or_generic(&self) -> MavAutopilot {
        self.autopilot.unwrap_or(MavAutopilot::MAV_AUTOPILOT_GENERIC)
    }

    /// Counts a heartbeat from `from` towards proving that address; a sequence that does
    /// not move forward (by less than half the sequence space) starts the count again.
    /// Returns true when the address just became the one we answer.
    pub fn prove(&mut self, from: SocketAddr, seq: u8, needed: u32) -> bool {
        let next = match self.candidate {
            Some(c) if c.addr == from => {
                let step = seq.wrapping_sub(c.last_seq);
                let heartbeats = if (1..128).contains(&step) { c.heartbeats + 1 } else { 1 };
                Candidate { addr: from, heartbeats, last_seq: seq }
            }
            _ => Candidate { addr: from, heartbeats: 1, last_seq: seq },
        };
        self.candidate = Some(next);
        if next.heartbeats >= needed && self.addr != Some(from) {
            self.addr = Some(from);
            return true;
        }
        false
    }
}

/// The world-model kind and mode family of a MAV_TYPE: `None` for things that are not
/// vehicles (ground stations, gimbals…); a type newer than the dialect is a `vehicle`.
pub(crate) fn classify(t: Lenient<MavType>) -> Option<(&'static str, Family, String)> {
    match t.known {
        Some(k) => modes::classify(k).map(|(kind, f)| (kind, f, modes::subtype(k))),
        None => Some(("vehicle", Family::Copter, t.name("MAV_TYPE_"))),
    }
}

impl Link {
    /// Publishes a newly heard vehicle under `root.vehicles`.
    pub(crate) fn discover(
        &self,
        h: MavHeader,
        hb: &Heartbeat,
        kind: &str,
        family: Family,
        subtype: &str,
    ) -> Result<Vehicle, DsError> {
        let ds = &self.inner.ctx.ds;
        let ex = &self.inner.ctx.executor;
        let name = format!("mav{}", h.system_id);
        let info = ObjectInfo::new(&name, kind).subtype(subtype);
        let guid = ds.create_object(self.inner.root, info)?;
        let raw = |r: u8| Value::Int(i64::from(r));
        world::create_props(
            ds,
            guid,
            vec![
                ("name", Value::str(&name), string()),
                ("sysid", Value::Int(i64::from(h.system_id)), int("")),
                ("autopilot", Value::str(&hb.autopilot.name("MAV_AUTOPILOT_")), string()),
                ("autopilot_raw", raw(hb.autopilot.raw), int("").describe("MAV_AUTOPILOT")),
                ("mav_type", Value::str(subtype), string()),
                ("mav_type_raw", raw(hb.mavtype.raw), int("").describe("MAV_TYPE")),
                (
                    "fuel",
                    Value::Float(0.0),
                    float_in("fraction", 0.0, 1.0)
                        .describe("battery remaining, 0..1")
                        .rate(SYS_STATUS_HZ),
                ),
                ("battery_v", Value::Float(0.0), float("V").rate(SYS_STATUS_HZ)),
                // Written at each heartbeat (1 Hz by the MAVLink spec): a display takes them as
                // stale after three missed ones (`PropMeta::rate_hz`, docs/display.md).
                ("armed", Value::Bool(false), boolean().rate(HEARTBEAT_HZ)),
                ("engine", Value::Bool(false), boolean().rate(HEARTBEAT_HZ)),
                (
                    "link",
                    Value::Float(1.0),
                    float_in("fraction", 0.0, 1.0).describe("link quality").rate(HEARTBEAT_HZ),
                ),
                ("link_lost", Value::Bool(false), boolean()),
                ("stale", Value::Bool(false), boolean()),
                (
                    "verified",
                    Value::Bool(false),
                    boolean()
                        .describe("its address proved itself: commands and heartbeats go to it"),
                ),
                ("mode", Value::str(""), string().rate(HEARTBEAT_HZ)),
                ("system_status", Value::str(""), string().rate(HEARTBEAT_HZ)),
                ("system_status_raw", raw(hb.system_status.raw), int("").describe("MAV_STATE")),
                ("control", Value::str(""), string()),
                (
                    "drop_rate",
                    Value::Float(0.0),
                    float_in("fraction", 0.0, 1.0).rate(SYS_STATUS_HZ),
                ),
            ],
        )?;
        let nav = ds.create_object(guid, ObjectInfo::new("nav", "nav"))?;
        world::create_props(
            ds,
            nav,
            vec![
                ("speed", Value::Float(0.0), float("m/s").rate(POSITION_HZ)),
                ("heading", Value::Float(0.0), float_in("deg", 0.0, 360.0).rate(POSITION_HZ)),
                ("x", Value::Float(0.0), float("m").rate(POSITION_HZ)),
                ("y", Value::Float(0.0), float("m").rate(POSITION_HZ)),
                ("lat", Value::Float(0.0), float_in("deg", -90.0, 90.0).rate(POSITION_HZ)),
                ("lon", Value::Float(0.0), float_in("deg", -180.0, 180.0).rate(POSITION_HZ)),
                ("alt", Value::Float(0.0), float("m").describe("above home").rate(POSITION_HZ)),
                ("alt_msl", Value::Float(0.0), float("m").rate(POSITION_HZ)),
                ("roll", Value::Float(0.0), float("deg").rate(ATTITUDE_HZ)),
                ("pitch", Value::Float(0.0), float("deg").rate(ATTITUDE_HZ)),
                ("yaw", Value::Float(0.0), float("deg").rate(ATTITUDE_HZ)),
                // Written by GLOBAL_POSITION_INT and VFR_HUD alike.
                ("climb", Value::Float(0.0), float("m/s").rate(POSITION_HZ)),
                ("airspeed", Value::Float(0.0), float("m/s").rate(VFR_HUD_HZ)),
                ("groundspeed", Value::Float(0.0), float("m/s").rate(VFR_HUD_HZ)),
                ("throttle", Value::Float(0.0), float("%").rate(VFR_HUD_HZ)),
                ("gps_fix", Value::str(""), string().rate(GPS_RAW_HZ)),
                ("gps_fix_raw", Value::Int(0), int("").describe("GPS_FIX_TYPE").rate(GPS_RAW_HZ)),
                ("satellites", Value::Int(0), int("").rate(GPS_RAW_HZ)),
                ("hdop", Value::Float(0.0), float("").rate(GPS_RAW_HZ)),
            ],
        )?;
        ds.create_object(guid, ObjectInfo::new("cameras", "cameras"))?;
        world::publish_routes(ds, ex, guid, RouteFrame::Global)?;
        self.publish_methods(guid)?;
        self.inner
            .ctx
            .report(mocu_host::Level::Info, format!("discovered {name} ({kind}, {subtype})"));
        Ok(Vehicle {
            sysid: h.system_id,
            compid: h.component_id,
            guid,
            nav,
            addr: None,
            candidate: None,
            family,
            autopilot: hb.autopilot.known,
            last_heartbeat: ds.now(),
            lost: false,
            last_seq: None,
            rx_w: 0.0,
            lost_w: 0.0,
            home: None,
            home_candidate: None,
            gps_fix: None,
            control: String::new(),
            gcs: None,
            requester: String::new(),
            commands: Vec::new(),
            upload: None,
            mission: None,
        })
    }
}
