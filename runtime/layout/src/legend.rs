//! What a binding does, in a few words, for the legend of the bindings in use (fig. 3: the
//! gamepad's buttons and sticks and what each does): "usv1 throttle", "usv1 start engine",
//! "swap video ⇄ forward". Published with each binding as its `action` property
//! (`actions::publish_bindings`); the `BindingLegend` native widget shows them.

use crate::actions::{CompiledAction, Select};
use mocu_lower::Base;

/// The actions of one binding, described in order.
pub(crate) fn describe(acts: &[CompiledAction]) -> String {
    acts.iter().map(describe_one).collect::<Vec<_>>().join(", ")
}

fn describe_one(a: &CompiledAction) -> String {
    match a {
        CompiledAction::Set { base, objects, property, .. } => {
            let what = property.strip_prefix("goal_").unwrap_or(property).replace('_', " ");
            format!("{} {what}", object(base, objects))
        }
        CompiledAction::Call { base, objects, method, .. } => {
            format!("{} {}", object(base, objects), method.replace('_', " "))
        }
        CompiledAction::Swap { a, b, .. } => format!("swap {a} ⇄ {b}"),
        CompiledAction::Show(w) => format!("show {w}"),
        CompiledAction::Hide(w) => format!("hide {w}"),
        CompiledAction::Alert { level, .. } => format!("{level} alert"),
        CompiledAction::Mode(m) => format!("mode {m}"),
        CompiledAction::Select(Select::Next) => "select next".into(),
        CompiledAction::Select(Select::Prev) => "select previous".into(),
        CompiledAction::Select(Select::Object { base, objects }) => {
            format!("select {}", object(base, objects))
        }
        CompiledAction::Acknowledge => "acknowledge alerts".into(),
        CompiledAction::Script(s) => s.describe(),
    }
}

/// The object an action acts on, by the name an operator knows: the vehicle for a path
/// under `root.vehicles` (`usv1` for `root.vehicles.usv1.nav`), else its last name.
fn object(base: &Base, objects: &[String]) -> String {
    let start = match base {
        Base::Root => None,
        Base::Var(v) => Some(v.clone()),
        Base::SelfObject => Some("self".into()),
        Base::Selected => Some("selected".into()),
    };
    if let Some(s) = start {
        return s;
    }
    match objects.iter().position(|o| o == "vehicles") {
        Some(i) if i + 1 < objects.len() => objects[i + 1].clone(),
        _ => objects.last().cloned().unwrap_or_else(|| "root".into()),
    }
}
