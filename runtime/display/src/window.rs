//! A real OS window (winit) showing a display: composited by wgpu on a hardware GPU
//! adapter, else by tiny-skia and shown by softbuffer (`present.rs`). What `mocu run` uses
//! where there is a display server.

use crate::display::{Compositor, Counters, Display, DisplayError, DisplayOptions, PointerEvent};
use crate::gpu::GpuCompositor;
use crate::present::{SoftPresenter, WindowPath, choose_path};
use mocu_dataserver::DataServer;
use mocu_dataserver::Value;
use parking_lot::Mutex;
use std::path::PathBuf;
use std::sync::Arc;
use std::time::{Duration, Instant};
use winit::application::ApplicationHandler;
use winit::event::{
    ElementState, MouseButton, MouseScrollDelta, StartCause, TouchPhase, WindowEvent,
};
use winit::event_loop::{ActiveEventLoop, ControlFlow, EventLoop, EventLoopProxy};
use winit::keyboard::{Key, NamedKey};
use winit::window::{Window, WindowId};

/// How [`run_window`] runs.
#[derive(Clone, Debug)]
pub struct WindowOptions {
    pub title: String,
    pub display: DisplayOptions,
    /// Stop after this many frame ticks at the display rate (`--frames N`); `None` runs
    /// until the window is closed, drawing only when something changes.
    pub frames: Option<u64>,
    /// Write the last frame here before returning (`--screenshot`), however the loop
    /// ends: frames done, window closed or [`WindowStop::stop`].
    pub screenshot: Option<PathBuf>,
    /// Ends the loop from another thread (a signal): `None` when only closing does.
    pub stop: Option<WindowStop>,
}

/// Ends a running [`run_window`] from any thread, as if the window were closed (the last
/// frame is still written to `screenshot`). Stopping before the loop starts ends it at
/// once.
#[derive(Clone, Default)]
pub struct WindowStop(Arc<Mutex<StopState>>);

#[derive(Default)]
struct StopState {
    requested: bool,
    proxy: Option<EventLoopProxy<Wake>>,
}

impl WindowStop {
    pub fn new() -> WindowStop {
        WindowStop::default()
    }

    pub fn stop(&self) {
        let mut st = self.0.lock();
        st.requested = true;
        if let Some(p) = &st.proxy {
            let _ = p.send_event(Wake::Stop);
        }
    }

    pub fn is_requested(&self) -> bool {
        self.0.lock().requested
    }

    fn attach(&self, proxy: EventLoopProxy<Wake>) {
        self.0.lock().proxy = Some(proxy);
    }
}

impl std::fmt::Debug for WindowStop {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "WindowStop {{ requested: {} }}", self.is_requested())
    }
}

/// Wakes the event loop: the world model changed what the display shows, or stop.
#[derive(Debug, Clone, Copy)]
enum Wake {
    Changed,
    Stop,
}

/// What runs once the display exists.
type Setup<'a> = Box<dyn FnOnce(&mut Display) + 'a>;

struct App<'a> {
    ds: DataServer,
    opts: WindowOptions,
    setup: Option<Setup<'a>>,
    proxy: EventLoopProxy<Wake>,
    window: Option<Arc<Window>>,
    display: Option<Display>,
    ticks: u64,
    next: Instant,
    result: Result<Counters, DisplayError>,
    cursor: (f32, f32),
    shown: Shown,
}

/// Frames actually shown in the window, for the line printed at the end.
#[derive(Default)]
struct Shown {
    frames: u64,
    first: Option<Instant>,
    last: Option<Instant>,
    drawing: Duration,
    compositing: Duration,
    showing: Duration,
}

impl Shown {
    fn add(&mut self, drawing: Duration, compositing: Duration, showing: Duration) {
        let now = Instant::now();
        self.frames += 1;
        self.first.get_or_insert(now);
        self.last = Some(now);
        self.drawing += drawing;
        self.compositing += compositing;
        self.showing += showing;
    }

    /// `300 frames shown in 5.0 s (60.0 a second), each 3.1 ms drawing (1.2 compositing) +
    /// 0.4 ms showing`.
    fn summary(&self) -> String {
        let n = self.frames.max(1) as f64;
        let span = match (self.first, self.last) {
            (Some(a), Some(b)) => (b - a).as_secs_f64(),
            _ => 0.0,
        };
        let rate = if span > 0.0 { (self.frames - 1) as f64 / span } else { 0.0 };
        format!(
            "{} frames shown in {span:.1} s ({rate:.1} a second), each {:.1} ms drawing ({:.1} compositing) + {:.1} ms showing",
            self.frames,
            self.drawing.as_secs_f64() * 1e3 / n,
            self.compositing.as_secs_f64() * 1e3 / n,
            self.showing.as_secs_f64() * 1e3 / n
        )
    }
}

impl App<'_> {
    fn start(&mut self, el: &ActiveEventLoop) -> Result<(), DisplayError> {
        let d = &self.opts.display;
        let attrs = Window::default_attributes()
            .with_title(self.opts.title.clone())
            .with_inner_size(winit::dpi::PhysicalSize::new(d.width, d.height))
            .with_resizable(true);
        let window =
            Arc::new(el.create_window(attrs).map_err(|e| DisplayError::Window(e.to_string()))?);
        let choice = std::env::var("MOCU_COMPOSITOR").ok();
        let comp = open_compositor(el, &window, d, choice.as_deref())?;
        let mut display = Display::with_compositor(&self.ds, d.clone(), comp)?;
        if let Some(setup) = self.setup.take() {
            setup(&mut display);
        }
        // Idle: sleep until the world model changes, then wake the loop (no polling, no
        // timeout). The loop's end wakes it once more (`run_window`), and it ends.
        let waiter = display.change_waiter();
        let proxy = self.proxy.clone();
        let period = Duration::from_secs_f64(1.0 / d.rate.max(1.0));
        std::thread::Builder::new()
            .name("display-waker".into())
            .spawn(move || {
                loop {
                    if waiter.wait(Duration::MAX) {
                        if proxy.send_event(Wake::Changed).is_err() {
                            return;
                        }
                        // At most one frame per display period.
                        std::thread::sleep(period);
                    }
                }
            })
            .map_err(|e| DisplayError::Window(e.to_string()))?;
        self.window = Some(window.clone());
        self.display = Some(display);
        self.next = Instant::now();
        window.request_redraw();
        Ok(())
    }

    fn fail(&mut self, el: &ActiveEventLoop, e: DisplayError) {
        self.result = Err(e);
        el.exit();
    }

    /// Ends the loop with the last frame written to `screenshot`.
    fn finish(&mut self, el: &ActiveEventLoop) {
        let Some(display) = &mut self.display else {
            el.exit();
            return;
        };
        if let Some(path) = &self.opts.screenshot
            && let Err(e) = display.screenshot(path)
        {
            self.result = Err(e);
            el.exit();
            return;
        }
        self.result = Ok(display.counters());
        if self.shown.frames > 0 {
            eprintln!("mocu-display: {}", self.shown.summary());
        }
        el.exit();
    }

    fn draw(&mut self, el: &ActiveEventLoop) {
        let Some(display) = &mut self.display else { return };
        let t = Instant::now();
        let st = display.frame();
        if st.drawn {
            let drawn = t.elapsed();
            let t = Instant::now();
            if display.present() {
                self.shown.add(drawn, st.composite_time, t.elapsed());
            }
        }
        self.ticks += 1;
        if let Some(n) = self.opts.frames
            && self.ticks >= n
        {
            self.finish(el);
        }
    }
}

impl ApplicationHandler<Wake> for App<'_> {
    fn resumed(&mut self, el: &ActiveEventLoop) {
        if self.window.is_none()
            && let Err(e) = self.start(el)
        {
            self.fail(el, e);
        }
    }

    fn new_events(&mut self, el: &ActiveEventLoop, cause: StartCause) {
        if self.opts.stop.as_ref().is_some_and(WindowStop::is_requested) {
            self.finish(el);
            return;
        }
        if self.opts.frames.is_some() && matches!(cause, StartCause::ResumeTimeReached { .. }) {
            self.draw(el);
        }
        if self.opts.frames.is_some() {
            let period = Duration::from_secs_f64(1.0 / self.opts.display.rate.max(1.0));
            let now = Instant::now();
            while self.next <= now {
                self.next += period;
            }
            el.set_control_flow(ControlFlow::WaitUntil(self.next));
        } else {
            el.set_control_flow(ControlFlow::Wait);
        }
        // A finger held still becomes a long press at its deadline: wake for it.
        if let Some(display) = &mut self.display {
            forward_pointer(&self.ds, &display.touch_tick());
            if let Some(due) = display.touch_deadline() {
                let due = match el.control_flow() {
                    ControlFlow::WaitUntil(t) => t.min(due),
                    _ => due,
                };
                el.set_control_flow(ControlFlow::WaitUntil(due));
            }
        }
    }

    fn user_event(&mut self, el: &ActiveEventLoop, wake: Wake) {
        match wake {
            Wake::Stop => self.finish(el),
            Wake::Changed if self.opts.frames.is_none() => self.draw(el),
            Wake::Changed => {}
        }
    }

    fn window_event(&mut self, el: &ActiveEventLoop, _: WindowId, event: WindowEvent) {
        let Some(display) = &mut self.display else { return };
        match event {
            WindowEvent::CloseRequested => self.finish(el),
            WindowEvent::Resized(s) => {
                display.compositor_mut().resize_surface(s.width, s.height);
                display.present();
            }
            WindowEvent::RedrawRequested => {
                // Exposed or first shown: show the last frame again.
                if display.frame_number() == 0 {
                    self.draw(el);
                } else {
                    display.present();
                }
            }
            WindowEvent::CursorMoved { position, .. } => {
                self.cursor = (position.x as f32, position.y as f32);
                display.pointer(self.cursor.0, self.cursor.1, PointerEvent::Move);
            }
            WindowEvent::CursorLeft { .. } => {
                display.pointer(self.cursor.0, self.cursor.1, PointerEvent::Leave);
            }
            WindowEvent::KeyboardInput { event, .. } => {
                if let Some(name) = key_name(&event.logical_key) {
                    let down = event.state == ElementState::Pressed;
                    forward_input(&self.ds, "keyboard", "key", name, Value::Bool(down));
                }
            }
            WindowEvent::MouseWheel { delta, .. } => {
                let (x, y) = match delta {
                    MouseScrollDelta::LineDelta(x, y) => (x as f64, y as f64),
                    MouseScrollDelta::PixelDelta(p) => (p.x / 40.0, p.y / 40.0),
                };
                for (axis, d) in [("vertical", y), ("horizontal", x)] {
                    if d != 0.0 {
                        forward_input(&self.ds, "mouse", "wheel", axis.into(), Value::Float(d));
                    }
                }
            }
            WindowEvent::MouseInput { state, button, .. } => {
                let b = match button {
                    MouseButton::Left => 0,
                    MouseButton::Right => 1,
                    MouseButton::Middle => 2,
                    _ => return,
                };
                let name = ["left", "right", "middle"][b as usize];
                let down = state == ElementState::Pressed;
                forward_input(&self.ds, "mouse", "button", name.into(), Value::Bool(down));
                let ev = match state {
                    ElementState::Pressed => PointerEvent::Down(b),
                    ElementState::Released => PointerEvent::Up(b),
                };
                display.pointer(self.cursor.0, self.cursor.1, ev);
            }
            // One finger is the mouse (`touch.rs`): the same routing, the same bindings.
            WindowEvent::Touch(t) => {
                let phase = match t.phase {
                    TouchPhase::Started => crate::touch::TouchPhase::Started,
                    TouchPhase::Moved => crate::touch::TouchPhase::Moved,
                    TouchPhase::Ended => crate::touch::TouchPhase::Ended,
                    TouchPhase::Cancelled => crate::touch::TouchPhase::Cancelled,
                };
                let (x, y) = (t.location.x as f32, t.location.y as f32);
                forward_pointer(&self.ds, &display.touch(t.id, phase, x, y));
                if let Some(due) = display.touch_deadline() {
                    el.set_control_flow(ControlFlow::WaitUntil(due));
                }
            }
            _ => {}
        }
    }
}

/// The compositor for a window: wgpu on a hardware adapter; tiny-skia shown by
/// softbuffer where wgpu finds none or only a software rasteriser (no GL then), or where
/// `MOCU_COMPOSITOR=cpu` (`choice`) asks for it, when wgpu is not even started. Says which
/// on stderr.
fn open_compositor(
    el: &ActiveEventLoop,
    window: &Arc<Window>,
    d: &DisplayOptions,
    choice: Option<&str>,
) -> Result<Box<dyn Compositor>, DisplayError> {
    let size = window.inner_size();
    let wants_cpu = choice.is_some_and(|c| c.eq_ignore_ascii_case("cpu"));
    let mut found: Option<(wgpu::Adapter, wgpu::Surface<'static>)> = None;
    let mut info = None;
    if !wants_cpu {
        let instance = wgpu::Instance::new(
            wgpu::InstanceDescriptor::new_with_display_handle(Box::new(el.owned_display_handle()))
                .with_env(),
        );
        let surface = instance
            .create_surface(window.clone())
            .map_err(|e| DisplayError::Window(e.to_string()))?;
        match pollster::block_on(instance.request_adapter(&wgpu::RequestAdapterOptions {
            power_preference: wgpu::PowerPreference::HighPerformance,
            force_fallback_adapter: false,
            apply_limit_buckets: false,
            compatible_surface: Some(&surface),
        })) {
            Ok(adapter) => {
                info = Some(adapter.get_info());
                found = Some((adapter, surface));
            }
            Err(e) => log::info!("no GPU adapter for the window: {e}"),
        }
    }
    let path = choose_path(info.as_ref(), choice);
    let why = path.reason(info.as_ref(), choice);
    if path == WindowPath::Cpu {
        // The wgpu surface and adapter are gone before softbuffer takes the window.
        drop(found.take());
    }
    let comp: Box<dyn Compositor> = match (path, found) {
        (WindowPath::Gpu, Some((adapter, surface))) => Box::new(GpuCompositor::for_window(
            &adapter,
            surface,
            d.width,
            d.height,
            size.width,
            size.height,
            d.background,
        )?),
        _ => {
            let cpu = crate::compose::CpuCompositor::new(d.width, d.height, d.background)
                .ok_or(DisplayError::BadSize(d.width, d.height))?;
            Box::new(SoftPresenter::new(cpu, window.clone())?)
        }
    };
    let what = match path {
        WindowPath::Gpu => "layers composited on the GPU",
        WindowPath::Cpu => "layers composited on the CPU, no GPU in the way",
    };
    log::info!("window {}x{} on {} ({what}: {why})", d.width, d.height, comp.name());
    eprintln!("mocu-display: window {}x{} on {} ({what}: {why})", d.width, d.height, comp.name());
    Ok(comp)
}

/// Hands a key, mouse button or wheel to the input module through
/// `root.operator.inputs.<device>.<method>(name, value)`; nothing happens without one.
/// The mouse buttons of pointer input made from touch, to the `bind mouse` bindings (as a
/// mouse's buttons go).
fn forward_pointer(ds: &DataServer, made: &[crate::touch::PointerInput]) {
    for (_, _, ev) in made {
        let (b, down) = match ev {
            PointerEvent::Down(b) => (*b, true),
            PointerEvent::Up(b) => (*b, false),
            _ => continue,
        };
        let name = ["left", "right", "middle"].get(b as usize).copied().unwrap_or("left");
        forward_input(ds, "mouse", "button", name.into(), Value::Bool(down));
    }
}

fn forward_input(ds: &DataServer, device: &str, method: &str, name: String, value: Value) {
    if let Some(g) = ds.resolve(&["operator", "inputs", device]) {
        ds.call(g, method, vec![Value::str(&name), value], None, |_| {});
    }
}

/// The layout language's name of a key (`a`, `7`, `space`, `up`, `f1`).
fn key_name(k: &Key) -> Option<String> {
    Some(match k {
        Key::Character(c) => c.to_lowercase(),
        Key::Named(n) => match n {
            NamedKey::Space => "space",
            NamedKey::Enter => "enter",
            NamedKey::Escape => "escape",
            NamedKey::Tab => "tab",
            NamedKey::Backspace => "backspace",
            NamedKey::Delete => "delete",
            NamedKey::Insert => "insert",
            NamedKey::Home => "home",
            NamedKey::End => "end",
            NamedKey::PageUp => "page_up",
            NamedKey::PageDown => "page_down",
            NamedKey::ArrowUp => "up",
            NamedKey::ArrowDown => "down",
            NamedKey::ArrowLeft => "left",
            NamedKey::ArrowRight => "right",
            NamedKey::Shift => "shift",
            NamedKey::Control => "ctrl",
            NamedKey::Alt => "alt",
            NamedKey::F1 => "f1",
            NamedKey::F2 => "f2",
            NamedKey::F3 => "f3",
            NamedKey::F4 => "f4",
            NamedKey::F5 => "f5",
            NamedKey::F6 => "f6",
            NamedKey::F7 => "f7",
            NamedKey::F8 => "f8",
            NamedKey::F9 => "f9",
            NamedKey::F10 => "f10",
            NamedKey::F11 => "f11",
            NamedKey::F12 => "f12",
            _ => return None,
        }
        .to_string(),
        _ => return None,
    })
}

/// Opens an OS window and runs the display in it until closed (or for `frames` ticks).
/// `setup` runs once the display exists (publish windows, claim them...).
///
/// Errors: `Window` when there is no display server (no `DISPLAY`) or neither wgpu nor
/// softbuffer can show in the window; without a GPU adapter the window still opens (CPU
/// path). `mocu run` falls back to the headless CPU path on an error.
pub fn run_window<'a>(
    ds: &DataServer,
    opts: WindowOptions,
    setup: impl FnOnce(&mut Display) + 'a,
) -> Result<Counters, DisplayError> {
    let el = EventLoop::<Wake>::with_user_event()
        .build()
        .map_err(|e| DisplayError::Window(e.to_string()))?;
    let proxy = el.create_proxy();
    if let Some(stop) = &opts.stop {
        stop.attach(el.create_proxy());
    }
    let mut app = App {
        ds: ds.clone(),
        opts,
        setup: Some(Box::new(setup)),
        proxy,
        window: None,
        display: None,
        ticks: 0,
        next: Instant::now(),
        result: Err(DisplayError::Window("the event loop ended before the window opened".into())),
        cursor: (0.0, 0.0),
        shown: Shown::default(),
    };
    let ran = el.run_app(&mut app).map_err(|e| DisplayError::Window(e.to_string()));
    // The waker thread sleeps until a change: this one finds the loop gone, and it ends.
    if let Some(d) = &mut app.display {
        d.invalidate_all();
    }
    ran?;
    app.result
}
