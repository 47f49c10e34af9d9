//! The module kinds of this crate: `widgets` (the widget renderer), `map_view` (the map
//! painter) and `window_manager` (the window manager's behaviours: `swap`, `animate`). Each is a module like the others: started by the module host from the profile,
//! or by default when the profile leaves its role empty, and replaceable by a project's
//! own kind (docs/modules.md, "Core modules and replacing them").

use crate::{Library, MapModule, RendererConfig, WidgetRenderer};
use mocu_host::{Module, ModuleContext, ModuleSpec, Registry};
use parking_lot::Mutex;
use std::sync::{Arc, Weak};
use std::time::Duration;

/// The compiled components the widget renderer draws with: the seam between whoever loads
/// the layouts (`mocu run` compiles their components, and again on every hot reload) and
/// the `widgets` module. A renderer started from it draws with its current library and
/// swaps in each one given to [`Components::replace`].
#[derive(Clone, Default)]
pub struct Components {
    inner: Arc<Mutex<Inner>>,
}

#[derive(Default)]
struct Inner {
    /// None: no components (the native widgets only).
    library: Option<Arc<Library>>,
    renderers: Vec<Weak<WidgetRenderer>>,
}

impl Components {
    pub fn new(library: Library) -> Components {
        let inner = Inner { library: Some(Arc::new(library)), renderers: Vec::new() };
        Components { inner: Arc::new(Mutex::new(inner)) }
    }

    /// Swaps in newly compiled components: every running renderer started from here
    /// repaints with them, and one started later starts with them.
    pub fn replace(&self, library: Library) {
        let library = Arc::new(library);
        let live: Vec<Arc<WidgetRenderer>> = {
            let mut inner = self.inner.lock();
            inner.library = Some(library.clone());
            inner.renderers.retain(|r| r.strong_count() > 0);
            inner.renderers.iter().filter_map(Weak::upgrade).collect()
        };
        for r in live {
            r.replace_shared(library.clone());
        }
    }

    /// Starts a renderer drawing with the current components.
    fn start_renderer(
        &self,
        ctx: &ModuleContext,
        config: RendererConfig,
    ) -> Result<Arc<WidgetRenderer>, String> {
        let mut inner = self.inner.lock();
        let library = match &inner.library {
            Some(l) => l.clone(),
            None => Arc::new(Library::compile(&Default::default(), false)?),
        };
        let r = Arc::new(WidgetRenderer::start_shared(&ctx.ds, library, config)?);
        inner.renderers.push(Arc::downgrade(&r));
        Ok(r)
    }
}

/// The `widgets` module: the widget renderer, drawing the `widgets` windows of
/// `root.display` with the components of [`Components`].
struct Widgets {
    components: Components,
    config: RendererConfig,
    running: Option<Arc<WidgetRenderer>>,
}

fn millis(spec: &ModuleSpec, key: &str, default: Duration) -> Result<Duration, String> {
    let ms = spec.i64_or(key, default.as_millis() as i64).map_err(|e| e.to_string())?;
    if !(0..=600_000).contains(&ms) {
        return Err(format!("module `{}`: `{key}` must be 0 to 600000 ms, got {ms}", spec.name));
    }
    Ok(Duration::from_millis(ms as u64))
}

impl Module for Widgets {
    fn start(&mut self, ctx: &ModuleContext) -> Result<(), String> {
        self.running = Some(self.components.start_renderer(ctx, self.config.clone())?);
        Ok(())
    }

    fn stop(&mut self) {
        self.running = None;
    }
}

/// The `map_view` module: the map painter (`MapModule`), drawing the `map` windows.
#[derive(Default)]
struct MapView {
    running: Option<MapModule>,
}

impl Module for MapView {
    fn start(&mut self, ctx: &ModuleContext) -> Result<(), String> {
        self.running = Some(MapModule::start(&ctx.ds)?);
        Ok(())
    }

    fn stop(&mut self) {
        self.running = None;
    }
}

/// Registers the kinds `widgets` (settings `accepted_ms`, `refused_ms`: how long a call's
/// green or red outline shows), `map_view` and `window_manager` (setting `animate`). The renderer draws with `components`.
pub fn register(registry: &mut Registry, components: Components) {
    registry.register("widgets", move |spec| {
        let d = RendererConfig::default();
        let config = RendererConfig {
            accepted_for: millis(spec, "accepted_ms", d.accepted_for)?,
            refused_for: millis(spec, "refused_ms", d.refused_for)?,
            ..d
        };
        let components = components.clone();
        Ok(Box::new(Widgets { components, config, running: None }) as Box<dyn Module>)
    });
    registry.register("map_view", |_| Ok(Box::new(MapView::default()) as Box<dyn Module>));
    registry.register("window_manager", |spec| {
        let animate = spec.bool_or("animate", true).map_err(|e| e.to_string())?;
        Ok(Box::new(WindowManager { animate, running: None }) as Box<dyn Module>)
    });
}

/// The `window_manager` module: the window manager's behaviours on `root.display` (`swap`,
/// `animate`, `animate_eased`; setting `animate`, true: windows move over the duration
/// asked, false: at once). The frame loop that paints and composites the windows stays the
/// display's (`mocu_display::Display`, made `without_window_behaviours`).
struct WindowManager {
    animate: bool,
    running: Option<mocu_display::WindowBehaviours>,
}

impl Module for WindowManager {
    fn start(&mut self, ctx: &ModuleContext) -> Result<(), String> {
        let display = match ctx.ds.resolve(&["display"]) {
            Some(d) => d,
            // `mocu run` makes it at the screen's size first; alone, the default screen.
            None => mocu_display::ensure_display_object(&ctx.ds, 1920, 1080)
                .map_err(|e| e.to_string())?,
        };
        let rate = mocu_display::DEFAULT_RATE;
        let b = mocu_display::WindowBehaviours::publish(&ctx.ds, display, rate, self.animate)
            .map_err(|e| e.to_string())?;
        self.running = Some(b);
        Ok(())
    }

    fn stop(&mut self) {
        self.running = None;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use mocu_dataserver::DataServer;

    fn empty() -> Library {
        Library::compile(&Default::default(), false).unwrap()
    }

    #[test]
    fn replaced_components_reach_the_running_renderers_and_the_next_one() {
        let ds = DataServer::default();
        let ctx = ModuleContext::detached("widgets", ds.clone());
        let components = Components::new(empty());
        let first = components.start_renderer(&ctx, RendererConfig::default()).unwrap();
        let gone = components.start_renderer(&ctx, RendererConfig::default()).unwrap();
        drop(gone);
        components.replace(empty());
        let now = components.inner.lock().library.clone().unwrap();
        assert!(Arc::ptr_eq(&first.library(), &now), "the running renderer swapped");
        let next = components.start_renderer(&ctx, RendererConfig::default()).unwrap();
        assert!(Arc::ptr_eq(&next.library(), &now), "a later one starts with it");
        // A stopped renderer is forgotten, not kept alive.
        assert_eq!(components.inner.lock().renderers.len(), 2);
    }
}
