//! What a replay shows the recording through: the display's modules (widget renderer, map
//! view, video windows, as the profile chooses them) and one layout, on the replay's
//! DataServer. Only those modules: the world model comes from the recording.

use mocu_dataserver::DataServer;
use mocu_language::Bundle;
use mocu_layout::{Layout, LayoutConfig, NullSink};
use std::sync::Arc;

/// The display's modules and the layout, alive while it is.
pub struct Stage {
    _layout: Layout,
    /// The display's modules (`crate::core_modules::DISPLAY_ROLES`), as the profile
    /// chooses them; stopped after the layout.
    _modules: mocu_host::ModuleHost,
}

/// Starts the display's modules and layout `chosen` of `bundle` on `ds`, on a screen of
/// `screen` pixels.
pub fn start(
    ds: &DataServer,
    bundle: &Bundle,
    chosen: usize,
    screen: (u32, u32),
    jit: bool,
) -> Result<Stage, String> {
    let components = crate::core_modules::components(bundle, jit)?;
    let _ = mocu_display::ensure_display_object(ds, screen.0, screen.1);
    let profile = crate::run::profile_specs(bundle)?;
    let modules = crate::core_modules::start_display(ds, components, profile)?;
    let config = LayoutConfig {
        screen: (f64::from(screen.0), f64::from(screen.1)),
        jit,
        name: bundle.layouts[chosen].path.clone(),
        // A replay's ageing comes from the recorded `stale` and `link_lost` flags: the
        // recording keeps changes, not repeated equal writes (docs/recording.md).
        alerts_to_terminal: false,
        ..LayoutConfig::default()
    };
    let layout = Layout::load(ds, &bundle.layouts[chosen].program, config, Arc::new(NullSink))
        .map_err(|e| e.to_string())?;
    Ok(Stage { _layout: layout, _modules: modules })
}
