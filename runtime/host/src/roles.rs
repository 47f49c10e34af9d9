//! Core modules by role: the pieces every OCU runs (operator input, the widget renderer,
//! the map view, the video windows) are modules like the others, started by default and
//! replaceable from the profile.

use crate::spec::ModuleSpec;

/// Fills the roles a profile leaves empty with their default modules, and leaves out the
/// modules it turns off.
///
/// A role (a name such as `map_view`) is filled by a module *named* after it or *of its
/// kind*: `[modules.map_view] kind = "my_map"` puts a project's own kind in the role;
/// `[modules.chart] kind = "map_view"` is the default kind under another name. A role that
/// nothing fills gets its default module, `ModuleSpec::new(role)`, appended, in the order of
/// `roles`. A module whose `enabled` setting is `false` is not started: a role it fills stays
/// empty, which turns that core module off (`[modules.map_view] enabled = false`).
/// `enabled` is taken out of every module's settings (it is the host's, not the module's).
pub fn fill_roles(specs: &mut Vec<ModuleSpec>, roles: &[&str]) {
    for role in roles {
        if !specs.iter().any(|s| s.name == *role || s.kind == *role) {
            specs.push(ModuleSpec::new(role));
        }
    }
    specs.retain(|s| s.settings.get("enabled") != Some(&toml::Value::Boolean(false)));
    for s in specs.iter_mut() {
        s.settings.remove("enabled");
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn names(specs: &[ModuleSpec]) -> Vec<(String, String)> {
        specs.iter().map(|s| (s.name.clone(), s.kind.clone())).collect()
    }

    const ROLES: &[&str] = &["input", "widgets", "map_view"];

    #[test]
    fn empty_roles_get_their_default_modules_in_order() {
        let mut specs = vec![ModuleSpec::new("sim")];
        fill_roles(&mut specs, ROLES);
        let want =
            [("sim", "sim"), ("input", "input"), ("widgets", "widgets"), ("map_view", "map_view")];
        assert_eq!(names(&specs), want.map(|(a, b)| (a.to_string(), b.to_string())));
    }

    #[test]
    fn a_module_named_after_a_role_or_of_its_kind_fills_it() {
        let mut specs = vec![
            ModuleSpec::new("my_map").named("map_view"),
            ModuleSpec::new("widgets").named("hud"),
            ModuleSpec::new("my_input").named("input"),
        ];
        fill_roles(&mut specs, ROLES);
        let want = [("map_view", "my_map"), ("hud", "widgets"), ("input", "my_input")];
        assert_eq!(names(&specs), want.map(|(a, b)| (a.to_string(), b.to_string())));
    }

    #[test]
    fn enabled_false_turns_a_module_off_and_its_role_stays_empty() {
        let mut specs = vec![
            ModuleSpec::new("map_view").with("enabled", false),
            ModuleSpec::new("sim").with("enabled", true),
        ];
        fill_roles(&mut specs, ROLES);
        let want = [("sim", "sim"), ("input", "input"), ("widgets", "widgets")];
        assert_eq!(names(&specs), want.map(|(a, b)| (a.to_string(), b.to_string())));
        assert!(specs.iter().all(|s| !s.settings.contains_key("enabled")));
    }
}
