//! Telemetry into the world model. Each message is checked as a whole before any of it is
//! published: a position out of range, an altitude beyond ±100 km or a NaN attitude refuses
//! the message (nothing derived from it is published) and counts its reason. Home is
//! latched only from two agreeing plausible positions, never from the first one heard.

use crate::config::Reason;
use crate::lenient::{GpsRaw, Heartbeat};
use crate::link::Link;
use crate::modes;
use crate::vehicle::{GcsControl, Vehicle};
use mavlink::dialects::development::*;
use mocu_dataserver::Value;

/// Two consecutive positions closer than this (metres) may become home.
const HOME_AGREE_M: f64 = 100.0;
/// Altitudes beyond this (metres, either side) are not a vehicle's.
const MAX_ALT_M: f64 = 100_000.0;
/// Slack on the attitude ranges (radians).
const ANGLE_SLACK: f32 = 0.01;

impl Link {
    pub(crate) fn heartbeat(&self, v: &mut Vehicle, hb: &Heartbeat) {
        let ds = &self.inner.ctx.ds;
        let g = v.guid;
        v.last_heartbeat = ds.now();
        v.autopilot = hb.autopilot.known;
        if v.lost {
            v.lost = false;
            let _ = ds.set(g, "link_lost", Value::Bool(false));
            let _ = ds.set(g, "stale", Value::Bool(false));
        }
        let armed = hb.base_mode.contains(MavModeFlag::MAV_MODE_FLAG_SAFETY_ARMED);
        let _ = ds.set(g, "armed", Value::Bool(armed));
        let _ = ds.set(g, "engine", Value::Bool(armed));
        let mode = modes::mode_name(v.autopilot_or_generic(), v.family, hb.custom_mode);
        let _ = ds.set(g, "mode", Value::str(&mode));
        let _ = ds.set(g, "autopilot", Value::str(&hb.autopilot.name("MAV_AUTOPILOT_")));
        let _ = ds.set(g, "autopilot_raw", Value::Int(i64::from(hb.autopilot.raw)));
        let _ = ds.set(g, "system_status", Value::str(&hb.system_status.name("MAV_STATE_")));
        let _ = ds.set(g, "system_status_raw", Value::Int(i64::from(hb.system_status.raw)));
        let link = (v.rx_w / (v.rx_w + v.lost_w) * 100.0).round() / 100.0;
        let _ = ds.set(g, "link", Value::Float(link));
    }

    /// The GCS operator-control protocol (CONTROL_STATUS from the system manager): the GCS in
    /// control, shown as the vehicle's `control` — the operator this adapter asked for it
    /// when it is ours, `gcs N` when another ground station holds it, empty when none.
    pub(crate) fn control_status(&self, v: &mut Vehicle, c: &CONTROL_STATUS_DATA) {
        if !c.flags.contains(GcsControlStatusFlags::GCS_CONTROL_STATUS_FLAGS_SYSTEM_MANAGER) {
            return;
        }
        let ds = &self.inner.ctx.ds;
        let g = v.guid;
        let takeover_allowed =
            c.flags.contains(GcsControlStatusFlags::GCS_CONTROL_STATUS_FLAGS_TAKEOVER_ALLOWED);
        let first = v.gcs.is_none();
        v.gcs = Some(GcsControl { main: c.gcs_main, takeover_allowed });
        if first {
            self.inner.ctx.report(
                mocu_host::Level::Info,
                format!("mav{}: speaks the GCS operator-control protocol", v.sysid),
            );
        }
        let _ = ds.set(g, "gcs_in_control", Value::Int(i64::from(c.gcs_main)));
        let _ = ds.set(g, "gcs_takeover_allowed", Value::Bool(takeover_allowed));
        let ours = self.inner.cfg.system_id;
        let control = match c.gcs_main {
            0 => String::new(),
            m if m == ours && !v.requester.is_empty() => v.requester.clone(),
            m => format!("gcs {m}"),
        };
        if control != v.control {
            v.control = control;
            let _ = ds.set(g, "control", Value::str(&v.control));
        }
    }

    pub(crate) fn gps_raw(&self, v: &mut Vehicle, gps: &GpsRaw) {
        let ds = &self.inner.ctx.ds;
        let n = v.nav;
        v.gps_fix = Some(gps.fix.raw);
        let _ = ds.set(n, "gps_fix", Value::str(&gps.fix.name("GPS_FIX_TYPE_")));
        let _ = ds.set(n, "gps_fix_raw", Value::Int(i64::from(gps.fix.raw)));
        let _ = ds.set(n, "satellites", Value::Int(i64::from(gps.data.satellites_visible)));
        if gps.data.eph != u16::MAX {
            let _ = ds.set(n, "hdop", Value::Float(f64::from(gps.data.eph) / 100.0));
        }
    }

    /// Publishes one telemetry message, or refuses all of it.
    pub(crate) fn telemetry(&self, v: &mut Vehicle, msg: &MavMessage) -> Result<(), Reason> {
        let ds = &self.inner.ctx.ds;
        let (g, n) = (v.guid, v.nav);
        match msg {
            MavMessage::GLOBAL_POSITION_INT(p) => self.position(v, p)?,
            MavMessage::CONTROL_STATUS(c) => self.control_status(v, c),
            MavMessage::ATTITUDE(a) => {
                let pi = std::f32::consts::PI + ANGLE_SLACK;
                let ok = a.roll.abs() <= pi
                    && a.pitch.abs() <= pi / 2.0 + ANGLE_SLACK
                    && a.yaw.abs() <= 2.0 * pi;
                if !ok {
                    // NaN fails every comparison above.
                    return Err(Reason::Attitude);
                }
                let _ = ds.set(n, "roll", Value::Float(f64::from(a.roll).to_degrees()));
                let _ = ds.set(n, "pitch", Value::Float(f64::from(a.pitch).to_degrees()));
                let yaw = f64::from(a.yaw).to_degrees().rem_euclid(360.0);
                let _ = ds.set(n, "yaw", Value::Float(yaw));
            }
            MavMessage::VFR_HUD(hud) => {
                if ![hud.airspeed, hud.groundspeed, hud.climb, hud.alt]
                    .iter()
                    .all(|f| f.is_finite())
                {
                    return Err(Reason::NonFinite);
                }
                let _ = ds.set(n, "airspeed", Value::Float(f64::from(hud.airspeed)));
                let _ = ds.set(n, "groundspeed", Value::Float(f64::from(hud.groundspeed)));
                let _ = ds.set(n, "throttle", Value::Float(f64::from(hud.throttle)));
                let _ = ds.set(n, "climb", Value::Float(f64::from(hud.climb)));
            }
            MavMessage::SYS_STATUS(s) => {
                if s.voltage_battery != u16::MAX {
                    let _ =
                        ds.set(g, "battery_v", Value::Float(f64::from(s.voltage_battery) / 1000.0));
                }
                if s.battery_remaining >= 0 {
                    let fuel = f64::from(s.battery_remaining.min(100)) / 100.0;
                    let _ = ds.set(g, "fuel", Value::Float(fuel));
                }
                let _ = ds.set(g, "drop_rate", Value::Float(f64::from(s.drop_rate_comm) / 100.0));
            }
            _ => {}
        }
        Ok(())
    }

    fn position(&self, v: &mut Vehicle, p: &GLOBAL_POSITION_INT_DATA) -> Result<(), Reason> {
        let (lat, lon) = (f64::from(p.lat) / 1e7, f64::from(p.lon) / 1e7);
        if !(-90.0..=90.0).contains(&lat) || !(-180.0..=180.0).contains(&lon) {
            return Err(Reason::Position);
        }
        if p.lat == 0 && p.lon == 0 {
            return Err(Reason::NullPosition);
        }
        let (alt, msl) = (f64::from(p.relative_alt) / 1000.0, f64::from(p.alt) / 1000.0);
        if alt.abs() > MAX_ALT_M || msl.abs() > MAX_ALT_M {
            return Err(Reason::Altitude);
        }
        let ds = &self.inner.ctx.ds;
        let n = v.nav;
        // Home: two consecutive agreeing positions, with a fix when GPS_RAW_INT tells.
        let fixed = v.gps_fix.is_none_or(|f| f >= GpsFixType::GPS_FIX_TYPE_2D_FIX as u8);
        if v.home.is_none() && fixed {
            match v.home_candidate {
                Some(c) if distance(c, (lat, lon)) < HOME_AGREE_M => v.home = Some(c),
                _ => v.home_candidate = Some((lat, lon)),
            }
        }
        let _ = ds.set(n, "lat", Value::Float(lat));
        let _ = ds.set(n, "lon", Value::Float(lon));
        if let Some(home) = v.home {
            let (x, y) = local(home, lat, lon);
            let _ = ds.set(n, "x", Value::Float(x));
            let _ = ds.set(n, "y", Value::Float(y));
        }
        let _ = ds.set(n, "alt", Value::Float(alt));
        let _ = ds.set(n, "alt_msl", Value::Float(msl));
        let (vx, vy) = (f64::from(p.vx) / 100.0, f64::from(p.vy) / 100.0);
        let _ = ds.set(n, "speed", Value::Float((vx * vx + vy * vy).sqrt()));
        let _ = ds.set(n, "climb", Value::Float(-f64::from(p.vz) / 100.0));
        if p.hdg != u16::MAX {
            let _ = ds.set(n, "heading", Value::Float((f64::from(p.hdg) / 100.0) % 360.0));
        }
        Ok(())
    }
}

/// Metres east and north of `home`.
pub(crate) fn local(home: (f64, f64), lat: f64, lon: f64) -> (f64, f64) {
    let y = (lat - home.0) * 111_320.0;
    let x = (lon - home.1) * 111_320.0 * home.0.to_radians().cos();
    (x, y)
}

fn distance(a: (f64, f64), b: (f64, f64)) -> f64 {
    let (x, y) = local(a, b.0, b.1);
    x.hypot(y)
}
