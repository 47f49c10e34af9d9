//! A link's settings (the profile's `[modules.NAME]` table of kind `mavlink`) and its
//! counters, published on `root.modules.<name>`.

use crate::signing::Key;
use mocu_dataserver::{DataServer, Guid, Value};
use mocu_host::ModuleSpec;
use std::sync::atomic::{AtomicU64, Ordering};
use std::time::Duration;

/// Timing of the protocol, and the bounds a link keeps against hostile senders.
#[derive(Clone, Debug, PartialEq)]
pub struct LinkConfig {
    /// Wait this long for a COMMAND_ACK (or the next mission request) before resending.
    pub command_timeout: Duration,
    /// Sends per command before it times out.
    pub attempts: u32,
    /// No heartbeat for this long: link lost, data stale.
    pub link_timeout: Duration,
    /// Our own system and component ids (a ground station: 255, 190).
    pub system_id: u8,
    pub component_id: u8,
    /// At most this many vehicles per link; heartbeats of further system ids are refused.
    pub max_vehicles: usize,
    /// A vehicle silent this long (no heartbeat, on the server's clock) is forgotten: its
    /// object goes from the world model and its place is free.
    pub forget_after: Duration,
    /// Heartbeats (in sequence, from one address) before we send anything to that address.
    pub proof_heartbeats: u32,
    /// Datagrams we send per second at most (heartbeats, commands, mission items).
    pub max_send_rate: u32,
    /// With a key: only frames signed with it are accepted, and what we send is signed.
    pub signing_key: Option<Key>,
    /// The link id we sign with.
    pub signing_link_id: u8,
}

impl Default for LinkConfig {
    fn default() -> LinkConfig {
        LinkConfig {
            command_timeout: Duration::from_millis(1000),
            attempts: 3,
            link_timeout: Duration::from_secs(3),
            system_id: 255,
            component_id: 190,
            max_vehicles: 32,
            forget_after: Duration::from_secs(60),
            proof_heartbeats: 3,
            max_send_rate: 200,
            signing_key: None,
            signing_link_id: 0,
        }
    }
}

impl LinkConfig {
    /// Reads the settings of `spec` (compiler/language/src/modules.rs declares them).
    pub fn from_spec(spec: &ModuleSpec) -> Result<LinkConfig, String> {
        let i = |key: &str, default: i64| spec.i64_or(key, default).map_err(|e| e.to_string());
        let d = LinkConfig::default();
        let ms = |v: i64| Duration::from_millis(v.max(1) as u64);
        let key = spec.str_or("signing_key", "").map_err(|e| e.to_string())?;
        let signing_key = match key.trim() {
            "" => None,
            k => Some(Key::parse(k).map_err(|e| format!("signing_key: {e}"))?),
        };
        Ok(LinkConfig {
            command_timeout: ms(i("command_timeout_ms", d.command_timeout.as_millis() as i64)?),
            attempts: i("attempts", d.attempts as i64)?.clamp(1, 100) as u32,
            link_timeout: ms(i("link_timeout_ms", d.link_timeout.as_millis() as i64)?),
            max_vehicles: i("max_vehicles", d.max_vehicles as i64)?.clamp(1, 65_535) as usize,
            forget_after: ms(i("forget_after_ms", d.forget_after.as_millis() as i64)?),
            proof_heartbeats: i("proof_heartbeats", d.proof_heartbeats as i64)?.clamp(1, 100)
                as u32,
            max_send_rate: i("max_send_rate", d.max_send_rate as i64)?.clamp(1, 100_000) as u32,
            signing_key,
            signing_link_id: i("signing_link_id", 0)?.clamp(0, 255) as u8,
            ..d
        })
    }
}

/// Why a message (or a frame, or a vehicle) was refused: one counter each, published as
/// `refused_<name>` on the module's status object.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Reason {
    /// Latitude outside ±90° or longitude outside ±180°.
    Position,
    /// Exactly (0°, 0°): what autopilots send before a fix.
    NullPosition,
    /// An altitude beyond ±100 km.
    Altitude,
    /// A NaN, infinite or out-of-range attitude angle.
    Attitude,
    /// A NaN or infinite value elsewhere (VFR_HUD).
    NonFinite,
    /// A new system id when the link already has `max_vehicles`.
    VehicleLimit,
    /// Unknown incompatibility flags.
    Incompatible,
    /// No signature on a link with a key.
    Unsigned,
    /// A signature that does not match the key.
    BadSignature,
    /// A signature timestamp that does not move forward.
    OldTimestamp,
}

impl Reason {
    pub const ALL: [Reason; 10] = [
        Reason::Position,
        Reason::NullPosition,
        Reason::Altitude,
        Reason::Attitude,
        Reason::NonFinite,
        Reason::VehicleLimit,
        Reason::Incompatible,
        Reason::Unsigned,
        Reason::BadSignature,
        Reason::OldTimestamp,
    ];

    /// The status property: `refused_position`, …
    pub fn property(self) -> &'static str {
        match self {
            Reason::Position => "refused_position",
            Reason::NullPosition => "refused_null_position",
            Reason::Altitude => "refused_altitude",
            Reason::Attitude => "refused_attitude",
            Reason::NonFinite => "refused_non_finite",
            Reason::VehicleLimit => "refused_vehicle_limit",
            Reason::Incompatible => "refused_incompatible",
            Reason::Unsigned => "refused_unsigned",
            Reason::BadSignature => "refused_bad_signature",
            Reason::OldTimestamp => "refused_old_timestamp",
        }
    }
}

/// Counters, also published on `root.modules.<name>`.
#[derive(Default)]
pub struct Counters {
    pub datagrams: AtomicU64,
    pub decoded: AtomicU64,
    pub malformed: AtomicU64,
    pub unknown: AtomicU64,
    pub sent: AtomicU64,
    /// Sends dropped by `max_send_rate`.
    pub send_dropped: AtomicU64,
    /// Vehicles forgotten after `forget_after` of silence.
    pub forgotten: AtomicU64,
    refused: [AtomicU64; Reason::ALL.len()],
}

impl Counters {
    pub fn refuse(&self, r: Reason, n: u64) {
        if n > 0 {
            self.refused[r as usize].fetch_add(n, Ordering::Relaxed);
        }
    }

    pub fn refused(&self, r: Reason) -> u64 {
        self.refused[r as usize].load(Ordering::Relaxed)
    }

    pub(crate) fn publish(&self, ds: &DataServer, status: Guid, vehicles: usize) {
        let int = |a: &AtomicU64| Value::Int(a.load(Ordering::Relaxed) as i64);
        let _ = ds.set(status, "vehicles", Value::Int(vehicles as i64));
        for (name, c) in [
            ("datagrams", &self.datagrams),
            ("decoded", &self.decoded),
            ("malformed", &self.malformed),
            ("unknown", &self.unknown),
            ("sent", &self.sent),
            ("send_dropped", &self.send_dropped),
            ("forgotten", &self.forgotten),
        ] {
            let _ = ds.set(status, name, int(c));
        }
        for r in Reason::ALL {
            let _ = ds.set(status, r.property(), Value::Int(self.refused(r) as i64));
        }
    }
}
