//! The module kinds this binary knows: one list, which `tests/module_settings.rs` includes
//! too (so the settings the compiler checks profiles against are tried on these very kinds).

use mocu_host::Registry;

/// The module kinds this binary knows. A project replaces one by registering its own under
/// the same kind, or adds a kind and names it in a role (`[modules.map_view] kind = "…"`).
/// The widget renderer draws with `components` (the layouts' compiled components).
pub fn registry(components: mocu_widgets::Components) -> Registry {
    let mut r = Registry::new();
    mocu_sim::register(&mut r);
    mocu_mavlink::register(&mut r);
    mocu_video::register(&mut r);
    mocu_input::register(&mut r);
    mocu_distrib::register(&mut r);
    mocu_mapdata::register(&mut r);
    mocu_script::register(&mut r);
    mocu_host::register_process(&mut r);
    mocu_widgets::register(&mut r, components);
    r
}
