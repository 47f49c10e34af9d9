//! Forwarded writes (docs/distribution.md, "Forwarded writes"): a write to a property of
//! another site's object is carried out by that site, never on the local mirror.
//!
//! Forwarding: each object the mirror creates publishes [`WRITE_AT_OWNER`]`(name, value)`; a
//! writer that finds it (the layout's `set`) calls it, and the call goes to the owning site
//! as a call query on `mocu/<site>/call/<path>/write_at_owner` (the calls' key space, so
//! `acl` grants cover goal writes as they cover commands). The local copy keeps the old value
//! until the owner's change comes back through replication.
//!
//! Serving: the owner screens the write with its arbiter exactly as a command (a non-holder
//! is refused, the holder named), then writes through the DataServer's checked write; a
//! type or range refusal is answered with the DataServer's reason.

use crate::arbiter::{Arbiter, Screen};
use crate::calls::CallJob;
use crate::control::Caller;
use crate::keys;
use crate::payload::CallRequest;
use crossbeam_channel::Sender;
use mocu_dataserver::{
    Call, CallOutcome, DataServer, Guid, MethodSpec, ParamSpec, Value, ValueKind, WRITE_AT_OWNER,
};

/// Publishes [`WRITE_AT_OWNER`] on `local`, the mirror of `path` of `site`: a call is
/// forwarded to the site and answered with its outcome.
pub(crate) fn proxy(
    ds: &DataServer,
    calls: &Sender<CallJob>,
    site: &str,
    path: &[String],
    local: Guid,
) {
    let spec = MethodSpec::new(WRITE_AT_OWNER)
        .param(ParamSpec::new("name", ValueKind::String))
        .param(ParamSpec::any("value"))
        .describe("writes the property at the site that owns this object");
    let key = keys::call(site, path, WRITE_AT_OWNER);
    let jobs = calls.clone();
    let _ = ds.publish_method(local, spec, move |call: Call| {
        let args = call.args.to_vec();
        if let Err(why) = forwardable(&args) {
            call.responder.reply(CallOutcome::Refused(why));
            return;
        }
        let _ = jobs.send(CallJob::Forward { key: key.clone(), args, responder: call.responder });
    });
}

/// Whether a write can cross to another site: a property name and a value without GUIDs
/// (a GUID here names a local object, which the owner does not know).
fn forwardable(args: &[Value]) -> Result<(), String> {
    fn has_guid(v: &Value) -> bool {
        match v {
            Value::Guid(_) => true,
            Value::List(xs) | Value::Set(xs) => xs.iter().any(has_guid),
            _ => false,
        }
    }
    match args {
        [Value::Str(_), v] if has_guid(v) => {
            Err("an object reference cannot be written to another site's object".into())
        }
        [Value::Str(_), _] => Ok(()),
        _ => Err(format!("{WRITE_AT_OWNER}(name, value) takes a property name and a value")),
    }
}

/// Carries out a forwarded write to the property of `object` (at `path`) for the caller
/// named in `req`: screened by the arbiter, then the DataServer's checked write.
pub(crate) fn serve(
    ds: &DataServer,
    arbiter: Option<&Arbiter>,
    object: Guid,
    path: &[String],
    req: CallRequest,
) -> CallOutcome {
    let mut args = req.args.into_iter();
    let (Some(Value::Str(name)), Some(value), None) = (args.next(), args.next(), args.next())
    else {
        return CallOutcome::Refused(format!(
            "{WRITE_AT_OWNER}(name, value) takes a property name and a value"
        ));
    };
    if let Some(a) = arbiter {
        let who =
            Caller::new(req.operator.as_deref().unwrap_or(""), req.site.as_deref().unwrap_or(""));
        match a.screen(path, WRITE_AT_OWNER, &who) {
            Screen::Pass => {}
            Screen::Refuse(reason) => return CallOutcome::Refused(reason),
            Screen::Arbitrate(vehicle) => {
                return CallOutcome::Refused(format!(
                    "{vehicle}.{} changes only through its methods (request, release, \
                     takeover, answer)",
                    crate::arbiter::OBJECT
                ));
            }
        }
    }
    match ds.set(object, &*name, value) {
        Ok(()) => CallOutcome::Accepted(Vec::new()),
        Err(e) => CallOutcome::Refused(e.to_string()),
    }
}
