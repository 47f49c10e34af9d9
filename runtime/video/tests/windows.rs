//! The video painter against a camera of our own (a listener sent RGB frames by the test), on
//! a headless CPU display and the DataServer's manual clock: the picture fills its window
//! with its aspect ratio kept unless the window asks for a letterbox, a frame of its own
//! around it, staleness on the run's clock, and a press on the window raising the `press`
//! event of the visible widget under it.

use mocu_dataserver::{Config, DataServer, Guid, ManualClock, MethodSpec, ObjectInfo, Value};
use mocu_display::{BackendChoice, Display, DisplayOptions, Rect};
use mocu_video::window::Status;
use mocu_video::{VideoWindows, WindowsConfig};
use std::sync::Arc;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::Duration;

struct Rig {
    ds: DataServer,
    clock: ManualClock,
    display: Display,
    camera: Guid,
    root: Guid,
    windows: VideoWindows,
}

impl Rig {
    /// A 800×400 screen and a camera `root.vehicles.usv1.cameras.drive` (an object with a
    /// listener of frames).
    fn new() -> Rig {
        let clock = ManualClock::new();
        let ds = DataServer::with_clock(Config { workers: 2 }, Arc::new(clock.clone()));
        let root = mocu_display::ensure_display_object(&ds, 800, 400).unwrap();
        let vehicles =
            ds.create_object(ds.root(), ObjectInfo::new("vehicles", "vehicles")).unwrap();
        let usv = ds.create_object(vehicles, ObjectInfo::new("usv1", "usv")).unwrap();
        let cams = ds.create_object(usv, ObjectInfo::new("cameras", "cameras")).unwrap();
        let camera = ds.create_listener(cams, "drive").unwrap();
        let windows = VideoWindows::start_with(&ds, WindowsConfig::default()).unwrap();
        let opts = DisplayOptions::new(800, 400).backend(BackendChoice::Cpu);
        let display = Display::new(&ds, opts).unwrap();
        Rig { ds, clock, display, camera, root, windows }
    }

    fn window(&self, name: &str, r: Rect, source: &str) -> Guid {
        let w = mocu_display::publish_window(&self.ds, self.root, name, "video", 0, r).unwrap();
        self.ds.set(w, "source", Value::str(source)).unwrap();
        w
    }

    /// Sends a 4:3 frame, all one colour, then lets it reach the windows.
    fn send(&mut self, n: i64, rgb: [u8; 3]) {
        self.settle();
        let px: Vec<u8> = rgb.iter().copied().cycle().take(64 * 48 * 3).collect();
        let args = vec![Value::Bytes(px.into()), Value::Int(64), Value::Int(48), Value::Int(n)];
        self.ds.send(self.camera, args).unwrap();
        self.settle();
    }

    fn settle(&mut self) {
        self.windows.refresh();
        self.ds.quiesce();
        self.display.frame();
    }

    fn advance(&mut self, d: Duration) {
        self.clock.advance(d);
        self.settle();
    }

    fn pixel(&mut self, x: u32, y: u32) -> [u8; 3] {
        let f = self.display.read_frame();
        let i = ((y * f.width() + x) * 4) as usize;
        [f.data()[i], f.data()[i + 1], f.data()[i + 2]]
    }
}

const RED: [u8; 3] = [200, 30, 30];

#[test]
fn a_picture_fills_its_window_with_its_aspect_kept_unless_a_letterbox_is_asked() {
    let mut rig = Rig::new();
    // Two 2:1 windows: the 4:3 picture is cropped top and bottom in the first, letterboxed
    // (black bars left and right) in the second.
    let fill =
        rig.window("fill", Rect::new(0.0, 0.0, 400.0, 200.0), "root.vehicles.usv1.cameras.drive");
    let boxed =
        rig.window("boxed", Rect::new(400.0, 200.0, 400.0, 200.0), "vehicles.usv1.cameras.drive");
    rig.ds.set(boxed, "fit", Value::str("contain")).unwrap();
    rig.send(1, RED);
    assert_eq!(rig.windows.shown(fill).map(|s| s.status), Some(Status::Live));
    // Left edge, mid-height (clear of the title and of the border).
    assert_eq!(rig.pixel(10, 100), RED, "the picture reaches the window's sides");
    assert_eq!(rig.pixel(200, 190), RED, "and its bottom");
    assert_eq!(rig.pixel(410, 300), [0, 0, 0], "letterboxed: a black bar on the left");
    assert_eq!(rig.pixel(600, 300), RED, "the picture in the middle");
}

#[test]
fn staleness_is_read_on_the_runs_clock() {
    let mut rig = Rig::new();
    let w = rig.window("v", Rect::new(0.0, 0.0, 400.0, 300.0), "root.vehicles.usv1.cameras.drive");
    rig.settle();
    assert_eq!(rig.windows.shown(w).map(|s| s.status), Some(Status::NoVideo), "no frame yet");
    rig.send(1, RED);
    assert_eq!(rig.windows.shown(w).map(|s| s.status), Some(Status::Live));
    rig.advance(Duration::from_millis(1100));
    assert_eq!(rig.windows.shown(w).map(|s| s.status), Some(Status::Stale));
    rig.advance(Duration::from_secs(2));
    assert_eq!(rig.windows.shown(w).map(|s| s.status), Some(Status::NoVideo));
    // The frame rate counts the frames of the last second of the run's clock.
    for n in 2..12 {
        rig.send(n, RED);
        rig.advance(Duration::from_millis(100));
    }
    let fps = rig.ds.get(rig.camera, "shown_fps").unwrap().as_f64().unwrap();
    assert!((9.0..=10.0).contains(&fps), "{fps}");
}

#[test]
fn a_press_on_a_video_window_raises_the_press_of_the_visible_widget_under_it() {
    let mut rig = Rig::new();
    let w = rig.window("v", Rect::new(0.0, 0.0, 400.0, 300.0), "root.vehicles.usv1.cameras.drive");
    let pressed: Vec<Arc<AtomicUsize>> = (0..2).map(|_| Arc::default()).collect();
    for (i, visible) in [true, false].into_iter().enumerate() {
        let g = rig.ds.create_object(w, ObjectInfo::new(&format!("w{i}"), "widget")).unwrap();
        rig.ds.set(g, "component", Value::str("Video")).unwrap();
        rig.ds.set(g, "visible", Value::Bool(visible)).unwrap();
        for (k, v) in [("x", 0.0), ("y", 0.0), ("w", 200.0), ("h", 150.0)] {
            rig.ds.set(g, k, Value::Float(v)).unwrap();
        }
        let count = pressed[i].clone();
        rig.ds
            .publish_method_fn(g, MethodSpec::new("press"), move |_| {
                count.fetch_add(1, Ordering::SeqCst);
                mocu_dataserver::CallOutcome::Accepted(vec![])
            })
            .unwrap();
    }
    rig.settle();
    rig.display.pointer(300.0, 250.0, mocu_display::PointerEvent::Down(0));
    rig.ds.quiesce();
    assert_eq!(pressed[0].load(Ordering::SeqCst), 0, "outside the widget");
    rig.display.pointer(50.0, 50.0, mocu_display::PointerEvent::Down(0));
    rig.display.pointer(50.0, 50.0, mocu_display::PointerEvent::Up(0));
    rig.ds.quiesce();
    assert_eq!(pressed[0].load(Ordering::SeqCst), 1, "the visible widget");
    assert_eq!(pressed[1].load(Ordering::SeqCst), 0, "never the hidden one");
}
