//! The MAVLink link: telemetry into the world model, methods into commands, acknowledgements
//! into call outcomes, the mission upload protocol, and the link-loss watchdog.

use crate::decode::{decode_datagram, encode_v2};
use crate::modes::{self, Family};
use mavlink::MavHeader;
use mavlink::dialects::common::*;
use mocu_dataserver::{
    Call, CallOutcome, DsError, Guid, MethodSpec, ObjectInfo, ParamSpec, Responder, Value,
    ValueKind,
};
use mocu_host::ModuleContext;
use mocu_host::world::{self, RouteFrame, boolean, float, float_in, int, string};
use parking_lot::Mutex;
use std::collections::HashMap;
use std::net::{SocketAddr, UdpSocket};
use std::sync::Arc;
use std::sync::atomic::{AtomicU8, AtomicU64, Ordering};
use std::time::{Duration, Instant};

/// Timing of the protocol.
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
}

impl Default for LinkConfig {
    fn default() -> LinkConfig {
        LinkConfig {
            command_timeout: Duration::from_millis(1000),
            attempts: 3,
            link_timeout: Duration::from_secs(3),
            system_id: 255,
            component_id: 190,
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
}

struct Pending {
    id: u64,
    command: MavCmd,
    msg: MavMessage,
    attempts: u32,
    responder: Responder,
    label: &'static str,
}

struct Upload {
    id: u64,
    items: Vec<MISSION_ITEM_INT_DATA>,
    attempts: u32,
    requested: bool,
    responder: Responder,
}

struct Vehicle {
    sysid: u32,
    compid: u8,
    guid: Guid,
    nav: Guid,
    addr: Option<SocketAddr>,
    family: Family,
    autopilot: MavAutopilot,
    last_heartbeat: Instant,
    lost: bool,
    last_seq: Option<u8>,
    rx_w: f64,
    lost_w: f64,
    home: Option<(f64, f64)>,
    control: String,
    commands: Vec<Pending>,
    upload: Option<Upload>,
}

struct State {
    vehicles: HashMap<u32, Vehicle>,
    by_guid: HashMap<Guid, u32>,
    next_id: u64,
}

/// One MAVLink link (a UDP socket, or none for tests and benchmarks) publishing the
/// vehicles it hears under `root.vehicles`. Cheap to clone.
#[derive(Clone)]
pub struct Link {
    inner: Arc<Inner>,
}

struct Inner {
    ctx: ModuleContext,
    cfg: LinkConfig,
    root: Guid,
    socket: Option<Arc<UdpSocket>>,
    state: Mutex<State>,
    counters: Counters,
    seq: AtomicU8,
}

type Replies = Vec<(Responder, CallOutcome)>;

fn fire(replies: Replies) {
    for (r, o) in replies {
        r.reply(o);
    }
}

impl Link {
    pub fn new(
        ctx: ModuleContext,
        cfg: LinkConfig,
        socket: Option<Arc<UdpSocket>>,
    ) -> Result<Link, DsError> {
        let root = world::vehicles(&ctx.ds)?;
        let state = State { vehicles: HashMap::new(), by_guid: HashMap::new(), next_id: 1 };
        Ok(Link {
            inner: Arc::new(Inner {
                ctx,
                cfg,
                root,
                socket,
                state: Mutex::new(state),
                counters: Counters::default(),
                seq: AtomicU8::new(0),
            }),
        })
    }

    pub fn counters(&self) -> &Counters {
        &self.inner.counters
    }

    /// Decodes one datagram and publishes what it says. `from` is where replies go.
    pub fn ingest(&self, datagram: &[u8], from: Option<SocketAddr>) {
        let c = &self.inner.counters;
        c.datagrams.fetch_add(1, Ordering::Relaxed);
        let mut replies = Vec::new();
        let counts = {
            let mut st = self.inner.state.lock();
            decode_datagram(datagram, |h, m| self.handle(&mut st, h, m, from, &mut replies))
        };
        c.decoded.fetch_add(counts.decoded, Ordering::Relaxed);
        c.malformed.fetch_add(counts.malformed, Ordering::Relaxed);
        c.unknown.fetch_add(counts.unknown, Ordering::Relaxed);
        fire(replies);
    }

    fn handle(
        &self,
        st: &mut State,
        h: MavHeader,
        msg: MavMessage,
        from: Option<SocketAddr>,
        replies: &mut Replies,
    ) {
        let ds = &self.inner.ctx.ds;
        if let MavMessage::HEARTBEAT(hb) = &msg
            && !st.vehicles.contains_key(&h.system_id)
        {
            let Some((kind, family)) = modes::classify(hb.mavtype) else { return };
            match self.discover(h, hb, kind, family) {
                Ok(v) => {
                    st.by_guid.insert(v.guid, v.sysid);
                    st.vehicles.insert(h.system_id, v);
                }
                Err(e) => {
                    self.inner
                        .ctx
                        .report(mocu_host::Level::Error, format!("mav{}: {e}", h.system_id));
                    return;
                }
            }
        }
        let Some(v) = st.vehicles.get_mut(&h.system_id) else { return };
        if from.is_some() {
            v.addr = from;
        }
        // Link quality from sequence gaps, smoothed.
        if h.component_id == v.compid {
            let lost = v.last_seq.map_or(0, |s| h.sequence.wrapping_sub(s.wrapping_add(1)));
            v.last_seq = Some(h.sequence);
            v.rx_w = v.rx_w * 0.98 + 1.0;
            v.lost_w = v.lost_w * 0.98 + f64::from(lost);
        }
        let (g, n) = (v.guid, v.nav);
        match msg {
            MavMessage::HEARTBEAT(hb) => {
                v.last_heartbeat = ds.now();
                v.autopilot = hb.autopilot;
                if v.lost {
                    v.lost = false;
                    let _ = ds.set(g, "link_lost", Value::Bool(false));
                    let _ = ds.set(g, "stale", Value::Bool(false));
                }
                let armed = hb.base_mode.contains(MavModeFlag::MAV_MODE_FLAG_SAFETY_ARMED);
                let _ = ds.set(g, "armed", Value::Bool(armed));
                let _ = ds.set(g, "engine", Value::Bool(armed));
                let _ = ds.set(
                    g,
                    "mode",
                    Value::str(&modes::mode_name(hb.autopilot, v.family, hb.custom_mode)),
                );
                let status = format!("{:?}", hb.system_status);
                let _ =
                    ds.set(g, "system_status", Value::str(status.trim_start_matches("MAV_STATE_")));
                let link = (v.rx_w / (v.rx_w + v.lost_w) * 100.0).round() / 100.0;
                let _ = ds.set(g, "link", Value::Float(link));
            }
            MavMessage::GLOBAL_POSITION_INT(p) => {
                let (lat, lon) = (f64::from(p.lat) / 1e7, f64::from(p.lon) / 1e7);
                let home = *v.home.get_or_insert((lat, lon));
                let (x, y) = local(home, lat, lon);
                let _ = ds.set(n, "lat", Value::Float(lat));
                let _ = ds.set(n, "lon", Value::Float(lon));
                let _ = ds.set(n, "x", Value::Float(x));
                let _ = ds.set(n, "y", Value::Float(y));
                let _ = ds.set(n, "alt", Value::Float(f64::from(p.relative_alt) / 1000.0));
                let _ = ds.set(n, "alt_msl", Value::Float(f64::from(p.alt) / 1000.0));
                let (vx, vy) = (f64::from(p.vx) / 100.0, f64::from(p.vy) / 100.0);
                let _ = ds.set(n, "speed", Value::Float((vx * vx + vy * vy).sqrt()));
                let _ = ds.set(n, "climb", Value::Float(-f64::from(p.vz) / 100.0));
                if p.hdg != u16::MAX {
                    let _ = ds.set(n, "heading", Value::Float((f64::from(p.hdg) / 100.0) % 360.0));
                }
            }
            MavMessage::ATTITUDE(a) => {
                let _ = ds.set(n, "roll", Value::Float(f64::from(a.roll).to_degrees()));
                let _ = ds.set(n, "pitch", Value::Float(f64::from(a.pitch).to_degrees()));
                let _ =
                    ds.set(n, "yaw", Value::Float(f64::from(a.yaw).to_degrees().rem_euclid(360.0)));
            }
            MavMessage::VFR_HUD(hud) => {
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
                    let _ = ds.set(
                        g,
                        "fuel",
                        Value::Float(f64::from(s.battery_remaining.min(100)) / 100.0),
                    );
                }
                let _ = ds.set(g, "drop_rate", Value::Float(f64::from(s.drop_rate_comm) / 100.0));
            }
            MavMessage::GPS_RAW_INT(gps) => {
                let fix = format!("{:?}", gps.fix_type);
                let _ = ds.set(n, "gps_fix", Value::str(fix.trim_start_matches("GPS_FIX_TYPE_")));
                let _ = ds.set(n, "satellites", Value::Int(i64::from(gps.satellites_visible)));
                if gps.eph != u16::MAX {
                    let _ = ds.set(n, "hdop", Value::Float(f64::from(gps.eph) / 100.0));
                }
            }
            MavMessage::COMMAND_ACK(ack) => {
                let Some(i) = v.commands.iter().position(|p| p.command == ack.command) else {
                    return;
                };
                let outcome = match ack.result {
                    MavResult::MAV_RESULT_ACCEPTED => CallOutcome::Accepted(vec![]),
                    MavResult::MAV_RESULT_IN_PROGRESS => {
                        v.commands[i].attempts = 0;
                        return;
                    }
                    MavResult::MAV_RESULT_FAILED | MavResult::MAV_RESULT_CANCELLED => {
                        CallOutcome::Failed(format!("{:?}", ack.result))
                    }
                    other => CallOutcome::Refused(format!("{other:?}")),
                };
                let p = v.commands.remove(i);
                self.record_feedback(g, p.label, &outcome);
                replies.push((p.responder, outcome));
            }
            // Legacy peers still send MISSION_REQUEST; the answer is MISSION_ITEM_INT either way.
            #[allow(deprecated)]
            MavMessage::MISSION_REQUEST_INT(MISSION_REQUEST_INT_DATA { seq, .. })
            | MavMessage::MISSION_REQUEST(MISSION_REQUEST_DATA { seq, .. }) => {
                let Some(up) = v.upload.as_mut() else { return };
                let Some(item) = up.items.get(usize::from(seq)) else { return };
                up.requested = true;
                up.attempts = 0;
                let msg = MavMessage::MISSION_ITEM_INT(item.clone());
                let (sysid, addr) = (v.sysid, v.addr);
                self.send_to(sysid, addr, &msg);
            }
            MavMessage::MISSION_ACK(ack) => {
                let Some(up) = v.upload.take() else { return };
                let outcome = match ack.mavtype {
                    MavMissionResult::MAV_MISSION_ACCEPTED => {
                        CallOutcome::Accepted(vec![Value::Int(up.items.len() as i64)])
                    }
                    MavMissionResult::MAV_MISSION_ERROR
                    | MavMissionResult::MAV_MISSION_OPERATION_CANCELLED => {
                        CallOutcome::Failed(format!("{:?}", ack.mavtype))
                    }
                    other => CallOutcome::Refused(format!("{other:?}")),
                };
                self.record_feedback(g, "upload_route", &outcome);
                replies.push((up.responder, outcome));
            }
            _ => {}
        }
    }

    fn discover(
        &self,
        h: MavHeader,
        hb: &HEARTBEAT_DATA,
        kind: &str,
        family: Family,
    ) -> Result<Vehicle, DsError> {
        let ds = &self.inner.ctx.ds;
        let ex = &self.inner.ctx.executor;
        let name = format!("mav{}", h.system_id);
        let info = ObjectInfo::new(&name, kind).subtype(&modes::subtype(hb.mavtype));
        let guid = ds.create_object(self.inner.root, info)?;
        world::create_props(
            ds,
            guid,
            vec![
                ("name", Value::str(&name), string()),
                ("sysid", Value::Int(i64::from(h.system_id)), int("")),
                (
                    "autopilot",
                    Value::str(format!("{:?}", hb.autopilot).trim_start_matches("MAV_AUTOPILOT_")),
                    string(),
                ),
                (
                    "fuel",
                    Value::Float(0.0),
                    float_in("fraction", 0.0, 1.0).describe("battery remaining, 0..1"),
                ),
                ("battery_v", Value::Float(0.0), float("V")),
                ("armed", Value::Bool(false), boolean()),
                ("engine", Value::Bool(false), boolean()),
                (
                    "link",
                    Value::Float(1.0),
                    float_in("fraction", 0.0, 1.0).describe("link quality"),
                ),
                ("link_lost", Value::Bool(false), boolean()),
                ("stale", Value::Bool(false), boolean()),
                ("mode", Value::str(""), string()),
                ("system_status", Value::str(""), string()),
                ("control", Value::str(""), string()),
                ("drop_rate", Value::Float(0.0), float_in("fraction", 0.0, 1.0)),
            ],
        )?;
        let nav = ds.create_object(guid, ObjectInfo::new("nav", "nav"))?;
        world::create_props(
            ds,
            nav,
            vec![
                ("speed", Value::Float(0.0), float("m/s")),
                ("heading", Value::Float(0.0), float_in("deg", 0.0, 360.0)),
                ("x", Value::Float(0.0), float("m")),
                ("y", Value::Float(0.0), float("m")),
                ("lat", Value::Float(0.0), float_in("deg", -90.0, 90.0)),
                ("lon", Value::Float(0.0), float_in("deg", -180.0, 180.0)),
                ("alt", Value::Float(0.0), float("m").describe("above home")),
                ("alt_msl", Value::Float(0.0), float("m")),
                ("roll", Value::Float(0.0), float("deg")),
                ("pitch", Value::Float(0.0), float("deg")),
                ("yaw", Value::Float(0.0), float("deg")),
                ("climb", Value::Float(0.0), float("m/s")),
                ("airspeed", Value::Float(0.0), float("m/s")),
                ("groundspeed", Value::Float(0.0), float("m/s")),
                ("throttle", Value::Float(0.0), float("%")),
                ("gps_fix", Value::str(""), string()),
                ("satellites", Value::Int(0), int("")),
                ("hdop", Value::Float(0.0), float("")),
            ],
        )?;
        ds.create_object(guid, ObjectInfo::new("cameras", "cameras"))?;
        world::publish_routes(ds, ex, guid, RouteFrame::Global)?;
        self.publish_methods(guid)?;
        self.inner.ctx.report(
            mocu_host::Level::Info,
            format!("discovered {name} ({kind}, {})", modes::subtype(hb.mavtype)),
        );
        Ok(Vehicle {
            sysid: h.system_id,
            compid: h.component_id,
            guid,
            nav,
            addr: None,
            family,
            autopilot: hb.autopilot,
            last_heartbeat: ds.now(),
            lost: false,
            last_seq: None,
            rx_w: 0.0,
            lost_w: 0.0,
            home: None,
            control: String::new(),
            commands: Vec::new(),
            upload: None,
        })
    }

    fn publish_methods(&self, guid: Guid) -> Result<(), DsError> {
        use ValueKind::{Bool, Float, Guid as G, String as S};
        let p = ParamSpec::new;
        let ds = &self.inner.ctx.ds;
        let ex = &self.inner.ctx.executor;
        let me = self.clone();
        ds.publish_method_on(
            ex,
            guid,
            MethodSpec::new("arm").param(p("on", Bool)),
            move |c: Call| {
                let on = c.args[0].as_bool().unwrap_or(false);
                me.command(
                    c,
                    "arm",
                    MavCmd::MAV_CMD_COMPONENT_ARM_DISARM,
                    [if on { 1.0 } else { 0.0 }, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
                );
            },
        )?;
        let me = self.clone();
        ds.publish_method_on(
            ex,
            guid,
            MethodSpec::new("set_mode").param(p("mode", S)),
            move |c: Call| {
                let mode = c.args[0].as_str().unwrap_or("").to_string();
                let number = {
                    let st = me.inner.state.lock();
                    st.by_guid
                        .get(&c.object)
                        .and_then(|s| st.vehicles.get(s))
                        .map(|v| modes::mode_number(v.autopilot, v.family, &mode))
                };
                match number {
                    None => {
                        c.responder.reply(CallOutcome::NoSuchObject);
                    }
                    Some(Err(why)) => {
                        c.responder.refuse(why);
                    }
                    Some(Ok(n)) => {
                        let flag = MavModeFlag::MAV_MODE_FLAG_CUSTOM_MODE_ENABLED.bits() as f32;
                        me.command(
                            c,
                            "set_mode",
                            MavCmd::MAV_CMD_DO_SET_MODE,
                            [flag, n as f32, 0.0, 0.0, 0.0, 0.0, 0.0],
                        );
                    }
                }
            },
        )?;
        let me = self.clone();
        ds.publish_method_on(
            ex,
            guid,
            MethodSpec::new("goto")
                .param(p("lat", Float))
                .param(p("lon", Float))
                .param(p("alt", Float)),
            move |c: Call| {
                let (lat, lon, alt) = (
                    c.args[0].as_f64().unwrap_or(0.0),
                    c.args[1].as_f64().unwrap_or(0.0),
                    c.args[2].as_f64().unwrap_or(0.0),
                );
                if !(-90.0..=90.0).contains(&lat) || !(-180.0..=180.0).contains(&lon) {
                    c.responder.fail(format!("({lat}, {lon}) is not a position"));
                    return;
                }
                me.command_int(c, "goto", lat, lon, alt);
            },
        )?;
        let me = self.clone();
        ds.publish_method_on(ex, guid, MethodSpec::new("return_home"), move |c: Call| {
            me.command(c, "return_home", MavCmd::MAV_CMD_NAV_RETURN_TO_LAUNCH, [0.0; 7]);
        })?;
        let me = self.clone();
        ds.publish_method_on(ex, guid, MethodSpec::new("land"), move |c: Call| {
            me.command(c, "land", MavCmd::MAV_CMD_NAV_LAND, [0.0; 7]);
        })?;
        let me = self.clone();
        ds.publish_method_on(
            ex,
            guid,
            MethodSpec::new("upload_route").param(p("route", G)),
            move |c: Call| {
                me.upload(c);
            },
        )?;
        let me = self.clone();
        ds.publish_method_on(
            ex,
            guid,
            MethodSpec::new("request_control").param(p("operator", S)),
            move |c: Call| {
                let op = c.args[0].as_str().unwrap_or("").to_string();
                let mut st = me.inner.state.lock();
                let Some(sys) = st.by_guid.get(&c.object).copied() else {
                    drop(st);
                    c.responder.reply(CallOutcome::NoSuchObject);
                    return;
                };
                let v = st.vehicles.get_mut(&sys).expect("by_guid and vehicles agree");
                let outcome = if op.is_empty() {
                    CallOutcome::Refused("an operator name is needed".into())
                } else if !v.control.is_empty() && v.control != op {
                    CallOutcome::Refused(format!("control held by {}", v.control))
                } else {
                    v.control = op.clone();
                    let _ = me.inner.ctx.ds.set(v.guid, "control", Value::str(&op));
                    CallOutcome::Accepted(vec![])
                };
                drop(st);
                c.responder.reply(outcome);
            },
        )?;
        Ok(())
    }

    fn record_feedback(&self, g: Guid, method: &str, outcome: &CallOutcome) {
        let name = self.inner.ctx.ds.info(g).map(|i| i.name.to_string()).unwrap_or_default();
        let reason = match outcome {
            CallOutcome::Refused(r) | CallOutcome::Failed(r) => r.clone(),
            _ => String::new(),
        };
        self.inner.ctx.record(
            "feedback",
            vec![
                ("object", Value::str(&name)),
                ("method", Value::str(method)),
                ("outcome", Value::str(outcome.label())),
                ("reason", Value::str(&reason)),
            ],
        );
    }

    fn record_call(&self, g: Guid, method: &str, args: &[Value]) {
        let name = self.inner.ctx.ds.info(g).map(|i| i.name.to_string()).unwrap_or_default();
        self.inner.ctx.record(
            "call",
            vec![
                ("object", Value::str(&name)),
                ("method", Value::str(method)),
                ("args", Value::list(args.iter().cloned())),
            ],
        );
    }

    fn command(&self, c: Call, label: &'static str, command: MavCmd, p: [f32; 7]) {
        self.start_command(c, label, command, |sysid, compid| {
            MavMessage::COMMAND_LONG(COMMAND_LONG_DATA {
                param1: p[0],
                param2: p[1],
                param3: p[2],
                param4: p[3],
                param5: p[4],
                param6: p[5],
                param7: p[6],
                command,
                target_system: sysid,
                target_component: compid,
                confirmation: 0,
            })
        });
    }

    fn command_int(&self, c: Call, label: &'static str, lat: f64, lon: f64, alt: f64) {
        let command = MavCmd::MAV_CMD_DO_REPOSITION;
        self.start_command(c, label, command, |sysid, compid| {
            MavMessage::COMMAND_INT(COMMAND_INT_DATA {
                param1: -1.0,
                param2: 1.0,
                param3: 0.0,
                param4: f32::NAN,
                x: (lat * 1e7).round() as i32,
                y: (lon * 1e7).round() as i32,
                z: alt as f32,
                command,
                target_system: sysid,
                target_component: compid,
                frame: MavFrame::MAV_FRAME_GLOBAL_RELATIVE_ALT,
                current: 0,
                autocontinue: 0,
            })
        });
    }

    /// Sends a command and waits (asynchronously) for its COMMAND_ACK, resending on timeout.
    fn start_command(
        &self,
        c: Call,
        label: &'static str,
        command: MavCmd,
        make: impl FnOnce(u8, u8) -> MavMessage,
    ) {
        self.record_call(c.object, label, &c.args);
        let mut st = self.inner.state.lock();
        let Some(sys) = st.by_guid.get(&c.object).copied() else {
            drop(st);
            c.responder.reply(CallOutcome::NoSuchObject);
            return;
        };
        let id = st.next_id;
        st.next_id += 1;
        let v = st.vehicles.get_mut(&sys).expect("by_guid and vehicles agree");
        if v.lost {
            drop(st);
            let o = CallOutcome::Failed("link lost: no heartbeat from the vehicle".into());
            self.record_feedback(c.object, label, &o);
            c.responder.reply(o);
            return;
        }
        if v.commands.iter().any(|p| p.command == command) {
            drop(st);
            let o = CallOutcome::Refused(format!(
                "a {label} command is already waiting for its acknowledgement"
            ));
            self.record_feedback(c.object, label, &o);
            c.responder.reply(o);
            return;
        }
        let msg = make(v.sysid as u8, v.compid);
        let (sysid, addr) = (v.sysid, v.addr);
        v.commands.push(Pending {
            id,
            command,
            msg: msg.clone(),
            attempts: 1,
            responder: c.responder,
            label,
        });
        drop(st);
        self.send_to(sysid, addr, &msg);
        self.arm_retry(sys, id);
    }

    fn arm_retry(&self, sys: u32, id: u64) {
        let me = self.clone();
        let ctx = &self.inner.ctx;
        ctx.ds.run_after(self.inner.cfg.command_timeout, Some(&ctx.executor), move || {
            me.retry(sys, id)
        });
    }

    fn retry(&self, sys: u32, id: u64) {
        let mut st = self.inner.state.lock();
        let Some(v) = st.vehicles.get_mut(&sys) else { return };
        let (sysid, addr, guid) = (v.sysid, v.addr, v.guid);
        if let Some(i) = v.commands.iter().position(|p| p.id == id) {
            if v.commands[i].attempts >= self.inner.cfg.attempts {
                let p = v.commands.remove(i);
                drop(st);
                self.record_feedback(guid, p.label, &CallOutcome::TimedOut);
                p.responder.reply(CallOutcome::TimedOut);
                return;
            }
            v.commands[i].attempts += 1;
            let msg = v.commands[i].msg.clone();
            drop(st);
            self.send_to(sysid, addr, &msg);
            self.arm_retry(sys, id);
            return;
        }
        if let Some(up) = v.upload.as_mut().filter(|u| u.id == id) {
            if up.attempts >= self.inner.cfg.attempts {
                let up = v.upload.take().expect("checked above");
                drop(st);
                self.record_feedback(guid, "upload_route", &CallOutcome::TimedOut);
                up.responder.reply(CallOutcome::TimedOut);
                return;
            }
            up.attempts += 1;
            let resend = (!up.requested).then(|| count_msg(sysid as u8, v.compid, up.items.len()));
            drop(st);
            if let Some(m) = resend {
                self.send_to(sysid, addr, &m);
            }
            self.arm_retry(sys, id);
        }
    }

    /// Route upload with the mission protocol: MISSION_COUNT, then one MISSION_ITEM_INT per
    /// MISSION_REQUEST(_INT), until MISSION_ACK.
    fn upload(&self, c: Call) {
        self.record_call(c.object, "upload_route", &c.args);
        let ds = &self.inner.ctx.ds;
        let refuse = |c: Call, o: CallOutcome| {
            self.record_feedback(c.object, "upload_route", &o);
            c.responder.reply(o);
        };
        let Some(route) = c.args[0].as_guid() else {
            return refuse(c, CallOutcome::Failed("not a GUID".into()));
        };
        match ds.info(route) {
            Ok(i) if &*i.kind == "route" => {}
            Ok(i) => {
                return refuse(
                    c,
                    CallOutcome::Failed(format!("`{}` is a {}, not a route", i.name, i.kind)),
                );
            }
            Err(_) => return refuse(c, CallOutcome::Failed("no such route".into())),
        }
        let wps = world::route_waypoints(ds, route);
        if wps.is_empty() {
            return refuse(c, CallOutcome::Refused("the route has no waypoints".into()));
        }
        let mut st = self.inner.state.lock();
        let Some(sys) = st.by_guid.get(&c.object).copied() else {
            drop(st);
            return refuse(c, CallOutcome::NoSuchObject);
        };
        let id = st.next_id;
        st.next_id += 1;
        let v = st.vehicles.get_mut(&sys).expect("by_guid and vehicles agree");
        if v.lost {
            drop(st);
            return refuse(
                c,
                CallOutcome::Failed("link lost: no heartbeat from the vehicle".into()),
            );
        }
        if v.upload.is_some() {
            drop(st);
            return refuse(c, CallOutcome::Refused("a route upload is already in progress".into()));
        }
        let mut items = Vec::with_capacity(wps.len());
        for (i, wp) in wps.iter().enumerate() {
            let Some((lat, lon)) = world::pair(ds, *wp, "lat", "lon") else {
                drop(st);
                return refuse(c, CallOutcome::Failed(format!("waypoint {i} has no lat/lon")));
            };
            let alt = ds.try_get(*wp, "alt".into()).and_then(|a| a.as_f64()).unwrap_or(20.0);
            items.push(MISSION_ITEM_INT_DATA {
                param1: 0.0,
                param2: 2.0,
                param3: 0.0,
                param4: f32::NAN,
                x: (lat * 1e7).round() as i32,
                y: (lon * 1e7).round() as i32,
                z: alt as f32,
                seq: i as u16,
                command: MavCmd::MAV_CMD_NAV_WAYPOINT,
                target_system: v.sysid as u8,
                target_component: v.compid,
                frame: MavFrame::MAV_FRAME_GLOBAL_RELATIVE_ALT,
                current: 0,
                autocontinue: 1,
            });
        }
        let msg = count_msg(v.sysid as u8, v.compid, items.len());
        let (sysid, addr) = (v.sysid, v.addr);
        v.upload =
            Some(Upload { id, items, attempts: 1, requested: false, responder: c.responder });
        drop(st);
        self.send_to(sysid, addr, &msg);
        self.arm_retry(sys, id);
    }

    fn send_to(&self, sysid: u32, addr: Option<SocketAddr>, msg: &MavMessage) {
        let (Some(sock), Some(addr)) = (&self.inner.socket, addr) else { return };
        let header = MavHeader {
            system_id: u32::from(self.inner.cfg.system_id),
            component_id: self.inner.cfg.component_id,
            sequence: self.inner.seq.fetch_add(1, Ordering::Relaxed),
        };
        let bytes = encode_v2(header, msg);
        if sock.send_to(&bytes, addr).is_ok() {
            self.inner.counters.sent.fetch_add(1, Ordering::Relaxed);
        }
        let _ = sysid;
    }

    /// Marks links lost after `link_timeout` without a heartbeat, sends our own heartbeat,
    /// and publishes the counters. Called periodically by the module.
    pub fn watchdog(&self, send_heartbeat: bool) {
        let ds = &self.inner.ctx.ds;
        let mut st = self.inner.state.lock();
        let mut targets = Vec::new();
        for v in st.vehicles.values_mut() {
            // On the DataServer's clock: a test advances it instead of waiting.
            let silent = ds.now().saturating_duration_since(v.last_heartbeat);
            if !v.lost && silent > self.inner.cfg.link_timeout {
                v.lost = true;
                let _ = ds.set(v.guid, "link_lost", Value::Bool(true));
                let _ = ds.set(v.guid, "stale", Value::Bool(true));
                let _ = ds.set(v.guid, "link", Value::Float(0.0));
                self.inner
                    .ctx
                    .report(mocu_host::Level::Warning, format!("mav{}: link lost", v.sysid));
            }
            targets.push((v.sysid, v.addr));
        }
        let n = st.vehicles.len();
        drop(st);
        if send_heartbeat {
            let hb = MavMessage::HEARTBEAT(HEARTBEAT_DATA {
                custom_mode: 0,
                mavtype: MavType::MAV_TYPE_GCS,
                autopilot: MavAutopilot::MAV_AUTOPILOT_INVALID,
                base_mode: MavModeFlag::empty(),
                system_status: MavState::MAV_STATE_ACTIVE,
                mavlink_version: 3,
            });
            for (sysid, addr) in targets {
                self.send_to(sysid, addr, &hb);
            }
        }
        let c = &self.inner.counters;
        let s = self.inner.ctx.status;
        let _ = ds.set(s, "vehicles", Value::Int(n as i64));
        let _ = ds.set(s, "datagrams", Value::Int(c.datagrams.load(Ordering::Relaxed) as i64));
        let _ = ds.set(s, "decoded", Value::Int(c.decoded.load(Ordering::Relaxed) as i64));
        let _ = ds.set(s, "malformed", Value::Int(c.malformed.load(Ordering::Relaxed) as i64));
        let _ = ds.set(s, "unknown", Value::Int(c.unknown.load(Ordering::Relaxed) as i64));
        let _ = ds.set(s, "sent", Value::Int(c.sent.load(Ordering::Relaxed) as i64));
    }
}

fn count_msg(sysid: u8, compid: u8, n: usize) -> MavMessage {
    MavMessage::MISSION_COUNT(MISSION_COUNT_DATA {
        count: n as u16,
        target_system: sysid,
        target_component: compid,
    })
}

/// Metres east and north of `home`.
fn local(home: (f64, f64), lat: f64, lon: f64) -> (f64, f64) {
    let y = (lat - home.0) * 111_320.0;
    let x = (lon - home.1) * 111_320.0 * home.0.to_radians().cos();
    (x, y)
}
