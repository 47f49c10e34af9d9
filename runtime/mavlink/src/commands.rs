//! Commands: a method call becomes COMMAND_LONG / COMMAND_INT, resent on timeout (so is a
//! mission upload's opening message, `mission.rs`), and the vehicle's COMMAND_ACK becomes the
//! call's outcome. Nothing is sent to a system id that does not fit
//! a command's 8-bit target, nor to an address that has not proved to be the vehicle's.

use crate::lenient::CommandAck;
use crate::link::{After, Link};
use crate::vehicle::{Pending, Vehicle};
use mavlink::dialects::development::*;
use mocu_dataserver::{Call, CallOutcome};

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
        // The id of a whole upload that takes over from a partial write that timed out.
        let next = st.next_id;
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
                match self.upload_timed_out(v, next) {
                    Ok(msg) => {
                        st.next_id += 1;
                        drop(st);
                        self.send_to(addr, &msg);
                        self.arm_retry(sys, next);
                    }
                    Err(reply) => {
                        drop(st);
                        if let Some((r, o)) = reply {
                            r.reply(o);
                        }
                    }
                }
                return;
            }
            up.attempts += 1;
            // Until the vehicle asks for an item, the opening message again.
            let resend = (!up.requested).then(|| up.opening.clone());
            drop(st);
            if let Some(m) = resend {
                self.send_to(addr, &m);
            }
            self.arm_retry(sys, id);
        }
    }

    /// A COMMAND_ACK: the waiting call's outcome (a result newer than the dialect refuses it
    /// with its number).
    pub(crate) fn acknowledge(&self, v: &mut Vehicle, ack: &CommandAck, after: &mut After) {
        let Some(i) = v.commands.iter().position(|p| p.command == ack.command) else {
            return;
        };
        let outcome = match ack.result.known {
            // The vehicle's GCS in control asks before a takeover (MAVLink's operator-control
            // protocol): a refusal with the holder's name, not a failure.
            Some(MavResult::MAV_RESULT_FAILED)
                if ack.command == MavCmd::MAV_CMD_REQUEST_OPERATOR_CONTROL =>
            {
                let holder = v.gcs.map_or(0, |g| g.main);
                CallOutcome::Refused(format!(
                    "the vehicle is controlled by gcs {holder}, which must allow a takeover"
                ))
            }
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
}
