//! Root paths no object can match (E0401), checked by `check_types` segment by segment.
//! Two cases, both only with a project (a schema, or the vehicles its modules publish):
//! - the first segment after `root` is not where any object lives (the schema's instances,
//!   and what the runtime publishes: `display`, `operator`, `modules`, `cameras`) but is a
//!   near miss of one: `root.vehicle.usv1` (did you mean `vehicles`?);
//! - the profile says which vehicles exist (its modules: the simulator's `vehicles` list or
//!   counts, `mav*` with MAVLink) and `root.vehicles.usv9` is none of them.
//!
//! Anything else under `root` may be published at run time by a module and is accepted.

use crate::codes;
use crate::diagnostics::{Diagnostics, did_you_mean};
use crate::schema::Schema;
use crate::source::Span;

/// Objects under `root` that the runtime itself publishes (not described by schemas).
pub const RUNTIME_ROOTS: &[&str] = &["vehicles", "display", "operator", "modules", "cameras"];

/// Checks the segment just added to a `root` path (called by `check_types` for the first
/// two segments, where each segment's span is known).
pub fn check_root_member(
    schema: &Schema,
    segments: &[String],
    span: Span,
    diags: &mut Diagnostics,
) {
    if schema.is_empty() && schema.vehicles.is_none() {
        return;
    }
    match segments {
        [first] => {
            let mut roots: Vec<&str> = RUNTIME_ROOTS.to_vec();
            for inst in &schema.instances {
                if let Some(f) = inst.path.split('.').find(|s| *s != "root")
                    && !f.contains('*')
                    && !roots.contains(&f)
                {
                    roots.push(f);
                }
            }
            if roots.contains(&first.as_str()) {
                return;
            }
            if let Some(best) = did_you_mean(first, roots.iter().copied()) {
                diags
                    .error(
                        codes::UNKNOWN_PROPERTY,
                        span,
                        format!("no object lives at `root.{first}`"),
                    )
                    .label(format!("`{first}` is not under `root`"))
                    .help(format!("did you mean `{best}`?"));
            }
        }
        [first, name] if first == "vehicles" => {
            let Some(list) = &schema.vehicles else { return };
            if list.iter().any(|pat| glob(pat, name)) {
                return;
            }
            let d = diags
                .error(
                    codes::UNKNOWN_PROPERTY,
                    span,
                    format!("the profile's modules publish no vehicle `{name}`"),
                )
                .label(format!("no vehicle `{name}`"));
            let listed = list.iter().map(|v| format!("`{v}`")).collect::<Vec<_>>().join(", ");
            match did_you_mean(name, list.iter().map(String::as_str)) {
                Some(best) => d.help(format!("did you mean `{best}`? the vehicles are {listed}")),
                None => d.help(format!("the vehicles are {listed} (the profile's [modules.*])")),
            };
        }
        _ => {}
    }
}

fn glob(pattern: &str, s: &str) -> bool {
    match pattern.split_once('*') {
        None => pattern == s,
        Some((pre, post)) => {
            s.len() >= pre.len() + post.len() && s.starts_with(pre) && s.ends_with(post)
        }
    }
}
