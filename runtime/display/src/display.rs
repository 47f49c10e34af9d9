//! The frame loop `mocu run` drives: a [`Display`] owns the window manager and a
//! compositor (tiny-skia on the CPU, or wgpu), draws frames, answers hit tests and writes
//! screenshots.

use crate::anim::{Animator, Clock};
use crate::color::Color;
use crate::compose::{CpuCompositor, LayerView};
use crate::geom::IRect;
use crate::wm::{FrameStats, Hit, WindowManager};
use mocu_dataserver::{DataServer, DsError, Guid, ObjectInfo, Value};
use std::path::Path;
use std::sync::Arc;
use std::time::{Duration, Instant};
use tiny_skia::Pixmap;

/// The dark background behind every layer.
pub const BACKGROUND: Color = Color::rgb(8, 10, 14);

/// A compositor: blends the layers into a frame.
pub trait Compositor {
    /// `tiny-skia` or `wgpu (<adapter>)`.
    fn name(&self) -> String;
    fn resize(&mut self, width: u32, height: u32);
    /// Recomposites `damage` from `layers` (bottom first).
    fn composite(&mut self, layers: &[LayerView<'_>], damage: IRect);
    /// The frame as premultiplied RGBA8.
    fn read_frame(&mut self) -> Pixmap;
    /// Shows the frame in an OS window, where the compositor has one.
    fn present(&mut self) -> bool {
        false
    }
    /// The OS window's new size (the display's own size does not change with it).
    fn resize_surface(&mut self, _width: u32, _height: u32) {}
}

impl Compositor for CpuCompositor {
    fn name(&self) -> String {
        "tiny-skia".into()
    }

    fn resize(&mut self, width: u32, height: u32) {
        CpuCompositor::resize(self, width, height)
    }

    fn composite(&mut self, layers: &[LayerView<'_>], damage: IRect) {
        CpuCompositor::composite(self, layers, damage)
    }

    fn read_frame(&mut self) -> Pixmap {
        self.frame().clone()
    }
}

/// Which compositor to use.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum BackendChoice {
    /// tiny-skia.
    Cpu,
    /// wgpu offscreen; fails when no adapter is found.
    Gpu,
    /// wgpu when an adapter is found, else tiny-skia (with a log line saying so).
    #[default]
    Auto,
}

/// Frames (and animation steps) a second unless a display is told otherwise.
pub const DEFAULT_RATE: f64 = 60.0;

/// How a display starts.
#[derive(Clone, Debug)]
pub struct DisplayOptions {
    pub width: u32,
    pub height: u32,
    pub backend: BackendChoice,
    pub background: Color,
    pub clock: Clock,
    /// Frames per second for `run_headless` and animation steps.
    pub rate: f64,
    /// Whether this display publishes the window manager's behaviours (`swap`, `animate`,
    /// `animate_eased` on `root.display`): yes by default; `mocu run` leaves them to its
    /// `window_manager` module ([`crate::WindowBehaviours`]).
    pub window_behaviours: bool,
}

impl DisplayOptions {
    pub fn new(width: u32, height: u32) -> DisplayOptions {
        DisplayOptions {
            width,
            height,
            backend: BackendChoice::Cpu,
            background: BACKGROUND,
            clock: Clock::Real,
            rate: DEFAULT_RATE,
            window_behaviours: true,
        }
    }

    pub fn backend(mut self, b: BackendChoice) -> DisplayOptions {
        self.backend = b;
        self
    }

    pub fn clock(mut self, c: Clock) -> DisplayOptions {
        self.clock = c;
        self
    }

    /// Leaves `swap`/`animate`/`animate_eased` to a `window_manager` module.
    pub fn without_window_behaviours(mut self) -> DisplayOptions {
        self.window_behaviours = false;
        self
    }
}

/// Why a display could not start or write.
#[derive(Debug)]
pub enum DisplayError {
    World(DsError),
    BadSize(u32, u32),
    NoAdapter(String),
    Io(String),
    Window(String),
}

impl std::fmt::Display for DisplayError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            DisplayError::World(e) => write!(f, "world model: {e}"),
            DisplayError::BadSize(w, h) => write!(f, "bad display size {w}x{h}"),
            DisplayError::NoAdapter(why) => write!(f, "no GPU adapter: {why}"),
            DisplayError::Io(why) => write!(f, "{why}"),
            DisplayError::Window(why) => write!(f, "window: {why}"),
        }
    }
}

impl std::error::Error for DisplayError {}

impl From<DsError> for DisplayError {
    fn from(e: DsError) -> Self {
        DisplayError::World(e)
    }
}

/// Totals since the display started (for tests and `root.display` statistics).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Counters {
    pub frames_drawn: u64,
    pub frames_skipped: u64,
    pub layers_repainted: u64,
    pub layers_partial: u64,
    pub paint_failures: u64,
}

/// Pointer input, in screen pixels (see [`Display::pointer`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PointerEvent {
    Move,
    /// Button 0 left, 1 right, 2 middle.
    Down(u8),
    Up(u8),
    /// The pointer left the OS window.
    Leave,
}

/// Finds `root.display`, or publishes it (type `display`) with `width` and `height`.
pub fn ensure_display_object(ds: &DataServer, width: u32, height: u32) -> Result<Guid, DsError> {
    if let Some(g) = ds.find_child(ds.root(), "display")? {
        return Ok(g);
    }
    let g = ds.create_object(ds.root(), ObjectInfo::new("display", "display"))?;
    ds.set(g, "width", Value::Int(width as i64))?;
    ds.set(g, "height", Value::Int(height as i64))?;
    ds.set(g, "frame", Value::Int(0))?;
    Ok(g)
}

/// A layered display: window manager plus compositor.
pub struct Display {
    ds: DataServer,
    wm: WindowManager,
    compositor: Box<dyn Compositor>,
    frame: u64,
    counters: Counters,
    clock: Clock,
    rate: f64,
    first: bool,
    touch: crate::touch::Touch,
}

impl Display {
    /// Starts a display over `root.display` (published if absent) with the compositor
    /// `options.backend` asks for.
    pub fn new(ds: &DataServer, options: DisplayOptions) -> Result<Display, DisplayError> {
        let (w, h) = (options.width, options.height);
        let compositor: Box<dyn Compositor> = match options.backend {
            BackendChoice::Cpu => Box::new(cpu(w, h, options.background)?),
            #[cfg(feature = "gpu")]
            BackendChoice::Gpu => {
                Box::new(crate::gpu::GpuCompositor::headless(w, h, options.background)?)
            }
            #[cfg(not(feature = "gpu"))]
            BackendChoice::Gpu => {
                return Err(DisplayError::NoAdapter("built without the `gpu` feature".into()));
            }
            BackendChoice::Auto => auto(w, h, options.background)?,
        };
        Display::with_compositor(ds, options, compositor)
    }

    /// Starts a display with a compositor made by the caller (the windowed presenter).
    pub fn with_compositor(
        ds: &DataServer,
        options: DisplayOptions,
        compositor: Box<dyn Compositor>,
    ) -> Result<Display, DisplayError> {
        let (w, h) = (options.width, options.height);
        if w == 0 || h == 0 {
            return Err(DisplayError::BadSize(w, h));
        }
        let display = ensure_display_object(ds, w, h)?;
        let interval = Duration::from_secs_f64(1.0 / options.rate.max(1.0));
        let animator = Animator::new(ds.clone(), options.clock.clone(), interval);
        let wm = WindowManager::new(ds, display, (w, h), animator, options.window_behaviours)?;
        Ok(Display {
            ds: ds.clone(),
            wm,
            compositor,
            frame: 0,
            counters: Counters::default(),
            clock: options.clock,
            rate: options.rate,
            first: true,
            touch: crate::touch::Touch::default(),
        })
    }

    /// Draws one frame: repaints the dirty windows, recomposites the damage. When nothing
    /// changed it does nothing at all and says so (`drawn: false`).
    pub fn frame(&mut self) -> FrameStats {
        let force = std::mem::take(&mut self.first);
        let Some(plan) = self.wm.plan(self.frame + 1, force) else {
            self.counters.frames_skipped += 1;
            return FrameStats { frame: self.frame, ..FrameStats::default() };
        };
        self.frame += 1;
        let mut stats = plan.stats;
        if let Some((w, h)) = plan.resized {
            self.compositor.resize(w, h);
        }
        if !stats.drawn {
            self.counters.frames_skipped += 1;
            return stats;
        }
        let t = Instant::now();
        let damage = stats.damage;
        {
            let views = self.wm.layer_views();
            stats.composited =
                views.iter().filter(|v| !v.screen_rect().intersect(&damage).is_empty()).count();
            self.compositor.composite(&views, damage);
        }
        self.wm.composited();
        stats.composite_time = t.elapsed();
        self.counters.frames_drawn += 1;
        self.counters.layers_repainted += stats.repainted.len() as u64;
        self.counters.layers_partial += stats.partial.len() as u64;
        self.counters.paint_failures += stats.failed.len() as u64;
        for (name, why) in &stats.failed {
            eprintln!(
                "mocu-display: window `{name}`: painter failed ({why}); its layer is skipped"
            );
        }
        let _ = self.ds.set(self.wm.display_object(), "frame", Value::Int(self.frame as i64));
        stats
    }

    /// Runs `frames` frames at the display rate in real time (headless `--frames N`).
    pub fn run_headless(&mut self, frames: u64) -> Counters {
        let period = Duration::from_secs_f64(1.0 / self.rate.max(1.0));
        let mut next = Instant::now();
        for _ in 0..frames {
            self.frame();
            next += period;
            let now = Instant::now();
            if next > now {
                std::thread::sleep(next - now);
            } else {
                next = now;
            }
        }
        self.counters
    }

    /// Waits until something changes (or `timeout`): how an idle display sleeps.
    pub fn wait_for_change(&self, timeout: Duration) -> bool {
        self.wm.wait_for_change(timeout)
    }

    /// A handle that waits for changes from another thread (to wake an event loop).
    pub fn change_waiter(&self) -> ChangeWaiter {
        ChangeWaiter { shared: self.wm.shared_handle() }
    }

    pub fn counters(&self) -> Counters {
        self.counters
    }

    pub fn frame_number(&self) -> u64 {
        self.frame
    }

    pub fn size(&self) -> (u32, u32) {
        self.wm.size()
    }

    pub fn backend_name(&self) -> String {
        self.compositor.name()
    }

    pub fn window_manager(&self) -> &WindowManager {
        &self.wm
    }

    /// The `root.display` object.
    pub fn display_object(&self) -> Guid {
        self.wm.display_object()
    }

    /// Steps the animations to the clock's time (for a manual clock; the real clock's
    /// timers do this by themselves).
    pub fn tick_animations(&self) -> bool {
        self.wm.animator().tick()
    }

    pub fn clock(&self) -> &Clock {
        &self.clock
    }

    pub fn animator(&self) -> &Arc<Animator> {
        self.wm.animator()
    }

    /// The topmost non-transparent window at a screen point (§5.1: transparent parts of a
    /// layer pass the pointer to the layer below).
    pub fn hit_test(&self, x: f32, y: f32) -> Option<Hit> {
        self.wm.hit_test(x, y)
    }

    /// Routes pointer input to the window under it (or holding the capture).
    pub fn pointer(&mut self, x: f32, y: f32, ev: PointerEvent) -> Option<Hit> {
        self.wm.pointer(x, y, ev)
    }

    /// Routes touch input as pointer input (`touch.rs`: a tap is a left click, a drag a left
    /// drag, a long press a right click), on the display's clock. Returns the pointer input
    /// it made, for the same mouse bindings as the mouse's.
    pub fn touch(
        &mut self,
        id: u64,
        phase: crate::touch::TouchPhase,
        x: f32,
        y: f32,
    ) -> Vec<crate::touch::PointerInput> {
        let now = self.clock.now();
        let made = self.touch.event(id, phase, x, y, now);
        for &(x, y, ev) in &made {
            self.wm.pointer(x, y, ev);
        }
        made
    }

    /// A finger held still past its time becomes a long press (a right click); call at
    /// [`Display::touch_deadline`].
    pub fn touch_tick(&mut self) -> Vec<crate::touch::PointerInput> {
        let made = self.touch.tick(self.clock.now());
        for &(x, y, ev) in &made {
            self.wm.pointer(x, y, ev);
        }
        made
    }

    /// When a finger held still becomes a long press, if one is down.
    pub fn touch_deadline(&self) -> Option<Instant> {
        self.touch.deadline()
    }

    /// Marks every layer for a full repaint at the next frame (a backend change, a
    /// benchmark's full frame).
    pub fn invalidate_all(&mut self) {
        self.wm.invalidate_all();
    }

    /// Shows the last frame in the OS window (windowed compositors only).
    pub fn present(&mut self) -> bool {
        self.compositor.present()
    }

    #[cfg(feature = "gpu")]
    pub(crate) fn compositor_mut(&mut self) -> &mut dyn Compositor {
        &mut *self.compositor
    }

    /// The last frame, premultiplied RGBA8.
    pub fn read_frame(&mut self) -> Pixmap {
        self.compositor.read_frame()
    }

    /// Writes the last frame as a PNG.
    pub fn screenshot(&mut self, path: &Path) -> Result<(), DisplayError> {
        let frame = self.read_frame();
        frame
            .save_png(path)
            .map_err(|e| DisplayError::Io(format!("writing {}: {e}", path.display())))
    }
}

/// Waits for the world model to change what a display shows.
#[derive(Clone)]
pub struct ChangeWaiter {
    shared: Arc<crate::wm::Shared>,
}

impl ChangeWaiter {
    pub fn wait(&self, timeout: Duration) -> bool {
        crate::wm::wait_pending(&self.shared, timeout)
    }
}

fn cpu(w: u32, h: u32, bg: Color) -> Result<CpuCompositor, DisplayError> {
    CpuCompositor::new(w, h, bg).ok_or(DisplayError::BadSize(w, h))
}

fn auto(w: u32, h: u32, bg: Color) -> Result<Box<dyn Compositor>, DisplayError> {
    #[cfg(feature = "gpu")]
    match crate::gpu::GpuCompositor::headless(w, h, bg) {
        Ok(g) => return Ok(Box::new(g)),
        Err(e) => eprintln!("mocu-display: {e}; falling back to the CPU compositor (tiny-skia)"),
    }
    Ok(Box::new(cpu(w, h, bg)?))
}
