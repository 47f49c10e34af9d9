//! MAVLink's GCS operator-control protocol as the arbiter sees it, through the world model
//! only (docs/distribution.md, "Control arbitration"): a vehicle whose protocol module
//! publishes `gcs_in_control` speaks it; its `request_control(operator)` asks the vehicle for
//! control for this site (MAV_CMD_REQUEST_OPERATOR_CONTROL, answered by its COMMAND_ACK) and
//! `release_control()` gives it back; its `control` reads `gcs N` while another ground
//! station holds it. The arbiter knows nothing of MAVLink beyond these names.

use mocu_dataserver::{CallOutcome, DataServer, Guid, Value};

/// Whether the vehicle speaks the protocol (its module publishes who is in control).
pub(crate) fn speaks_protocol(ds: &DataServer, vehicle: Guid) -> bool {
    ds.try_get(vehicle, "gcs_in_control".into()).is_some()
}

/// Another ground station holding the vehicle (`gcs 200`), where it speaks the protocol.
pub(crate) fn foreign_holder(ds: &DataServer, vehicle: Guid) -> Option<String> {
    if !speaks_protocol(ds, vehicle) {
        return None;
    }
    match ds.try_get(vehicle, "control".into()) {
        Some(Value::Str(s)) if s.starts_with("gcs ") => Some(s.to_string()),
        _ => None,
    }
}

/// The reason a command is refused while another ground station holds the vehicle.
pub(crate) fn held_elsewhere(vehicle: &str, gcs: &str) -> String {
    format!("{vehicle} is controlled by {gcs}, another ground station: request control first")
}

/// Asks the vehicle for control for `operator`; `then` gets the vehicle's outcome.
pub(crate) fn request(
    ds: &DataServer,
    vehicle: Guid,
    operator: &str,
    then: impl FnOnce(CallOutcome) + Send + 'static,
) {
    ds.call(vehicle, "request_control", vec![Value::str(operator)], None, then);
}

/// Gives the vehicle's control back (the outcome is the vehicle's `control` afterwards).
pub(crate) fn release(ds: &DataServer, vehicle: Guid) {
    ds.call(vehicle, "release_control", vec![], None, |_| {});
}

/// The vehicle's refusal, said as the arbiter says its own.
pub(crate) fn refusal(vehicle: &str, outcome: CallOutcome) -> CallOutcome {
    let why = match outcome {
        CallOutcome::Refused(r) | CallOutcome::Failed(r) => r,
        CallOutcome::TimedOut => "it did not answer".into(),
        other => format!("{other:?}"),
    };
    CallOutcome::Refused(format!("{vehicle} refused control: {why}"))
}
