//! Commands and the mission protocol: a method call becomes COMMAND_LONG / COMMAND_INT (or
//! MISSION_COUNT and the items asked for), resent on timeout, and the vehicle's COMMAND_ACK /
//! MISSION_ACK becomes the call's outcome. Nothing is sent to a system id that does not fit
//! a command's 8-bit target, nor to an address that has not proved to be the vehicle's.

use crate::lenient::CommandAck;
use crate::link::{After, Link};
use crate::vehicle::{Pending, Upload, Vehicle};
use mavlink::dialects::common::*;
use mocu_dataserver::{Call, CallOutcome, Value};
use mocu_host::world;

/// Why nothing may be sent to `v`, if so.
/// The 8-bit target system of `v`, or why nothing may be sent to it.
pub(crate) fn can_send(v: &Vehicle) -> Result<u8, String> {
    let Ok(target) = u8::try_from(v.sysid) else {
        return Err(format!(
            "system id {} does not fit a MAVLink command's target (0 to 255)",
            v.sysid
        ));
    };
    if v.addr.is_none() {
        return Err("the vehicle has not proved its address yet (too few heartbeats)".into());
    }
    Ok(target)
}

impl Link {
    pub(crate) fn command(&self, c: Call, label: &'static str, command: MavCmd, p: [f32; 7]) {
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

    pub(crate) fn command_int(&self, c: Call, label: &'static str, lat: f64, lon: f64, alt: f64) {
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
    pub(crate) fn start_command(
        &self,
        c: Call,
        label: &'static str,
        command: MavCmd,
        make: impl FnOnce(u8, u8) -> MavMessage,
    ) {
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
            c.responder.reply(o);
            return;
        }
        if v.commands.iter().any(|p| p.command == command) {
            drop(st);
            let o = CallOutcome::Refused(format!(
                "a {label} command is already waiting for its acknowledgement"
            ));
            c.responder.reply(o);
            return;
        }
        let target = match can_send(v) {
            Ok(t) => t,
            Err(why) => {
                drop(st);
                let o = CallOutcome::Refused(why);
                c.responder.reply(o);
                return;
            }
        };
        let msg = make(target, v.compid);
        let addr = v.addr;
        v.commands.push(Pending {
            id,
            command,
            msg: msg.clone(),
            attempts: 1,
            responder: c.responder,
        });
        drop(st);
        self.send_to(addr, &msg);
        self.arm_retry(sys, id);
    }

    pub(crate) fn arm_retry(&self, sys: u32, id: u64) {
        let me = self.clone();
        let ctx = &self.inner.ctx;
        ctx.ds.run_after(self.inner.cfg.command_timeout, Some(&ctx.executor), move || {
            me.retry(sys, id)
        });
    }

    pub(crate) fn retry(&self, sys: u32, id: u64) {
        let mut st = self.inner.state.lock();
        let Some(v) = st.vehicles.get_mut(&sys) else { return };
        let addr = v.addr;
        if let Some(i) = v.commands.iter().position(|p| p.id == id) {
            if v.commands[i].attempts >= self.inner.cfg.attempts {
                let p = v.commands.remove(i);
                drop(st);
                p.responder.reply(CallOutcome::TimedOut);
                return;
            }
            v.commands[i].attempts += 1;
            let msg = v.commands[i].msg.clone();
            drop(st);
            self.send_to(addr, &msg);
            self.arm_retry(sys, id);
            return;
        }
        if let Some(up) = v.upload.as_mut().filter(|u| u.id == id) {
            if up.attempts >= self.inner.cfg.attempts {
                let up = v.upload.take().expect("checked above");
                drop(st);
                up.responder.reply(CallOutcome::TimedOut);
                return;
            }
            up.attempts += 1;
            // The items carry the target checked when the upload started.
            let resend = (!up.requested)
                .then(|| {
                    up.items.first().map(|i| count_msg(i.target_system, v.compid, up.items.len()))
                })
                .flatten();
            drop(st);
            if let Some(m) = resend {
                self.send_to(addr, &m);
            }
            self.arm_retry(sys, id);
        }
    }

    /// Route upload with the mission protocol: MISSION_COUNT, then one MISSION_ITEM_INT per
    /// MISSION_REQUEST(_INT), until MISSION_ACK.
    pub(crate) fn upload(&self, c: Call) {
        let ds = &self.inner.ctx.ds;
        let refuse = |c: Call, o: CallOutcome| {
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
        let target = match can_send(v) {
            Ok(t) => t,
            Err(why) => {
                drop(st);
                return refuse(c, CallOutcome::Refused(why));
            }
        };
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
                target_system: target,
                target_component: v.compid,
                frame: MavFrame::MAV_FRAME_GLOBAL_RELATIVE_ALT,
                current: 0,
                autocontinue: 1,
            });
        }
        let msg = count_msg(target, v.compid, items.len());
        let addr = v.addr;
        v.upload =
            Some(Upload { id, items, attempts: 1, requested: false, responder: c.responder });
        drop(st);
        self.send_to(addr, &msg);
        self.arm_retry(sys, id);
    }

    /// A COMMAND_ACK: the waiting call's outcome (a result newer than the dialect refuses it
    /// with its number).
    pub(crate) fn acknowledge(&self, v: &mut Vehicle, ack: &CommandAck, after: &mut After) {
        let Some(i) = v.commands.iter().position(|p| p.command == ack.command) else {
            return;
        };
        let outcome = match ack.result.known {
            Some(MavResult::MAV_RESULT_ACCEPTED) => CallOutcome::Accepted(vec![]),
            Some(MavResult::MAV_RESULT_IN_PROGRESS) => {
                v.commands[i].attempts = 0;
                return;
            }
            Some(r @ (MavResult::MAV_RESULT_FAILED | MavResult::MAV_RESULT_CANCELLED)) => {
                CallOutcome::Failed(format!("{r:?}"))
            }
            Some(other) => CallOutcome::Refused(format!("{other:?}")),
            None => CallOutcome::Refused(format!("MAV_RESULT {}", ack.result.name(""))),
        };
        let p = v.commands.remove(i);
        after.replies.push((p.responder, outcome));
    }

    /// The mission protocol's answers.
    pub(crate) fn answer(&self, v: &mut Vehicle, msg: &MavMessage, after: &mut After) {
        match msg {
            // Legacy peers still send MISSION_REQUEST; the answer is MISSION_ITEM_INT either way.
            #[allow(deprecated)]
            MavMessage::MISSION_REQUEST_INT(MISSION_REQUEST_INT_DATA { seq, .. })
            | MavMessage::MISSION_REQUEST(MISSION_REQUEST_DATA { seq, .. }) => {
                let Some(up) = v.upload.as_mut() else { return };
                let Some(item) = up.items.get(usize::from(*seq)) else { return };
                up.requested = true;
                up.attempts = 0;
                after.sends.push((v.addr, MavMessage::MISSION_ITEM_INT(item.clone())));
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
                after.replies.push((up.responder, outcome));
            }
            _ => {}
        }
    }
}

pub(crate) fn count_msg(sysid: u8, compid: u8, n: usize) -> MavMessage {
    MavMessage::MISSION_COUNT(MISSION_COUNT_DATA {
        count: n as u16,
        target_system: sysid,
        target_component: compid,
    })
}
