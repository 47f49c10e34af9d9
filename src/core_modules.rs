//! The module kinds this binary knows, and its core modules: operator input and the
//! display's modules (the widget renderer, the map view, the video windows) are modules
//! like the others, each started by default when the profile leaves its role empty
//! (`mocu_host::fill_roles`), replaced by naming the role with another `kind`, or turned off
//! with `enabled = false` (docs/modules.md, "Core modules and replacing them"). The window
//! manager's behaviours (`swap`, `animate`, `animate_eased` on `root.display`) are the
//! `window_manager` module; its frame loop — paint calls, damage, compositing — stays the
//! display's (`mocu_display::Display`), which `mocu run` drives itself.

use mocu_host::{ModuleHost, ModuleSpec};

/// The display's modules, in the order they start (after every other module but process
/// modules): each claims its own windows of `root.display`.
pub const DISPLAY_ROLES: &[&str] = &["window_manager", "widgets", "map_view", "video_windows"];

/// Every core role of `mocu run`, in start order: operator input, then the display's.
pub const CORE_ROLES: &[&str] =
    &["input", "window_manager", "widgets", "map_view", "video_windows"];

pub use crate::registry::registry;

/// Whether a module fills one of `roles` (named after it, or of its kind).
pub fn in_role(spec: &ModuleSpec, roles: &[&str]) -> bool {
    roles.iter().any(|r| spec.name == *r || spec.kind == *r)
}

/// Fills `roles` (`mocu_host::fill_roles`: the defaults of those left empty, less the
/// modules turned off), then puts the core modules after the others (whose order stays),
/// in role order: input, then the display's, each finding the rest already running.
pub fn fill(specs: &mut Vec<ModuleSpec>, roles: &[&str]) {
    mocu_host::fill_roles(specs, roles);
    specs.sort_by_key(|s| CORE_ROLES.iter().position(|r| s.name == *r || s.kind == *r));
}

/// The compiled components of every layout of `bundle`, the seam the `widgets` module
/// draws with (replaced on hot reload: `reload_hook`).
pub fn components(
    bundle: &mocu_language::Bundle,
    jit: bool,
) -> Result<mocu_widgets::Components, String> {
    let program = crate::run::all_components(bundle);
    mocu_widgets::Library::compile(&program, jit).map(mocu_widgets::Components::new)
}

/// What the reloader calls with a reloaded program: its components compiled and swapped
/// into every widget renderer drawing with `components`.
pub fn reload_hook(
    components: mocu_widgets::Components,
    jit: bool,
) -> std::sync::Arc<dyn Fn(&mocu_language::Program) + Send + Sync> {
    std::sync::Arc::new(move |p: &mocu_language::Program| {
        match mocu_widgets::Library::compile(p, jit) {
            Ok(lib) => components.replace(lib),
            Err(e) => eprintln!("mocu: components: {e}"),
        }
    })
}

/// Starts the display's modules alone (a replay's: the world model comes from the
/// recording): the profile's choices for their roles, the defaults for the rest.
pub fn start_display(
    ds: &mocu_dataserver::DataServer,
    components: mocu_widgets::Components,
    profile: Option<Vec<ModuleSpec>>,
) -> Result<ModuleHost, String> {
    let mut specs: Vec<ModuleSpec> =
        profile.unwrap_or_default().into_iter().filter(|s| in_role(s, DISPLAY_ROLES)).collect();
    fill(&mut specs, DISPLAY_ROLES);
    let mut host = ModuleHost::new(ds.clone(), registry(components));
    let errors = host.start_all(&specs);
    if errors.is_empty() {
        Ok(host)
    } else {
        let why: Vec<String> = errors.iter().map(ToString::to_string).collect();
        Err(why.join("; "))
    }
}
