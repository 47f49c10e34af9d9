//! The methods a MAVLink vehicle publishes in the world model (`arm`, `set_mode`, `goto`,
//! `return_home`, `land`, `upload_route`, `request_control`, `release_control`); each becomes a command or the
//! mission protocol (`commands.rs`).

use crate::link::Link;
use crate::modes;
use mavlink::dialects::development::{MavCmd, MavModeFlag};
use mocu_dataserver::{Call, CallOutcome, DsError, Guid, MethodSpec, ParamSpec, Value, ValueKind};

impl Link {
    pub(crate) fn publish_methods(&self, guid: Guid) -> Result<(), DsError> {
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
                        .map(|v| modes::mode_number(v.autopilot_or_generic(), v.family, &mode))
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
            MethodSpec::new("request_control")
                .param(p("operator", S))
                .describe("Take control for an operator: asked of the vehicle where it speaks the GCS operator-control protocol"),
            move |c: Call| {
                let op = c.args[0].as_str().unwrap_or("").to_string();
                me.operator_control(c, Some(op));
            },
        )?;
        let me = self.clone();
        ds.publish_method_on(
            ex,
            guid,
            MethodSpec::new("release_control")
                .describe("Give control back (to the vehicle, where it speaks the GCS operator-control protocol)"),
            move |c: Call| me.operator_control(c, None),
        )?;
        Ok(())
    }
}

impl Link {
    /// `request_control(operator)` (`Some`) or `release_control()` (`None`): asked of the
    /// vehicle where it speaks MAVLink's GCS operator-control protocol
    /// (MAV_CMD_REQUEST_OPERATOR_CONTROL for this adapter's system id, takeovers by others
    /// asked of it), kept by this module otherwise.
    fn operator_control(&self, c: Call, op: Option<String>) {
        let mut st = self.inner.state.lock();
        let Some(sys) = st.by_guid.get(&c.object).copied() else {
            drop(st);
            c.responder.reply(CallOutcome::NoSuchObject);
            return;
        };
        let v = st.vehicles.get_mut(&sys).expect("by_guid and vehicles agree");
        if op.as_deref() == Some("") {
            drop(st);
            c.responder.refuse("an operator name is needed");
            return;
        }
        if v.gcs.is_some() {
            let (label, action) = match op {
                Some(op) => {
                    v.requester = op;
                    ("request_control", 1.0)
                }
                None => ("release_control", 0.0),
            };
            drop(st);
            let ours = f32::from(self.inner.cfg.system_id);
            let cmd = MavCmd::MAV_CMD_REQUEST_OPERATOR_CONTROL;
            self.command(c, label, cmd, [action, 0.0, 10.0, ours, 0.0, 0.0, 0.0]);
            return;
        }
        let outcome = match op {
            Some(op) if !v.control.is_empty() && v.control != op => {
                CallOutcome::Refused(format!("control held by {}", v.control))
            }
            Some(op) => {
                let _ = self.inner.ctx.ds.set(v.guid, "control", Value::str(&op));
                v.control = op;
                CallOutcome::Accepted(vec![])
            }
            None => {
                v.control.clear();
                let _ = self.inner.ctx.ds.set(v.guid, "control", Value::str(""));
                CallOutcome::Accepted(vec![])
            }
        };
        drop(st);
        c.responder.reply(outcome);
    }
}
