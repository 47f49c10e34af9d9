//! What a replay shows the recording through: the display's modules (widget renderer, map,
//! video windows) and one layout, on the replay's DataServer. No module host: the world
//! model comes from the recording.

use mocu_dataserver::DataServer;
use mocu_language::Bundle;
use mocu_layout::{Layout, LayoutConfig, NullSink};
use std::sync::Arc;

/// The display's modules and the layout, alive while it is.
pub struct Stage {
    _layout: Layout,
    _renderer: Option<mocu_widgets::WidgetRenderer>,
    _map: Option<mocu_widgets::MapModule>,
    _video: Option<mocu_video::VideoWindows>,
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
    let library = mocu_widgets::Library::compile(&crate::run::all_components(bundle), jit)
        .map_err(|e| e.to_string())?;
    let _ = mocu_display::ensure_display_object(ds, screen.0, screen.1);
    let renderer =
        mocu_widgets::WidgetRenderer::start(ds, library, mocu_widgets::RendererConfig::default())
            .map_err(|e| format!("cannot start the widget renderer: {e}"))?;
    let map =
        mocu_widgets::MapModule::start(ds).map_err(|e| format!("cannot start the map: {e}"))?;
    let video = mocu_video::VideoWindows::start(ds).ok();
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
    Ok(Stage { _layout: layout, _renderer: Some(renderer), _map: Some(map), _video: video })
}
