//! The video painter: claims every window of subtype `video` under `root.display`, shows
//! the camera its `source` property names (a dotted path text), scaled with its aspect
//! ratio kept — filling the window (cropped, centred) unless the window or its `Video`
//! widget asks for `fit "contain"` (letterboxed) — under a frame of its own (`chrome.rs`: a
//! border, the camera and vehicle, the fps and latency), and marks a stalled stream: its
//! last frame with `STALE` after [`WindowsConfig::stale_after`], then "no video from
//! <camera>" after [`WindowsConfig::no_video_after`] (or when there is no stream at all).
//! Ages are read on the DataServer's clock (a test's `ManualClock` moves them).
//!
//! A left press (a tap) on a video window raises the `press` event of the visible widgets
//! placed in it under the pointer (fig. 1: the small payload view swaps into the large
//! place).
//!
//! Each camera is joined once, however many windows show it (`Overflow::DropOldest`, a
//! queue of 2: the display never lags behind the camera); each frame is turned into an
//! [`Image`] once, off the frame thread, scaled there once to where each window showing it
//! shows it (the display then copies it, no resampling on its thread), and every window
//! showing it is invalidated.
//!
//! A network camera (`root.cameras.<name>`) whose `feeds` property names a camera path
//! (or is `auto`: the first vehicle's `cameras.drive`) stands in for that camera while it
//! is live (a frame in the last 1.5 s): windows whose source is the vehicle camera show the
//! network stream, and go back to the vehicle camera's own frames when it stops.

use crate::chrome::{self, Chrome};
use crate::frame::FrameMsg;
use crate::{normalize_path, now_us, resolve_path};
use mocu_dataserver::{
    Call, DataServer, Executor, Guid, Kind, MethodSpec, Notification, ObjectInfo, Overflow,
    ParamSpec, Subject, SubscriptionId, Topic, Value,
};
use mocu_display::{
    Canvas, Color, Image, ImageFit, PaintArgs, Rect, Size, claim_window, fit_rect, invalidate,
};
use mocu_value::PropName;
use parking_lot::Mutex;
use std::collections::{HashMap, VecDeque};
use std::sync::{Arc, Weak};
use std::time::{Duration, Instant};

/// Timing of the painter.
#[derive(Clone, Debug, PartialEq)]
pub struct WindowsConfig {
    /// No frame for this long: the last frame is shown marked `STALE`.
    pub stale_after: Duration,
    /// No frame for this long: `NO VIDEO`.
    pub no_video_after: Duration,
    /// How often sources are resolved again and staleness checked.
    pub tick: Duration,
    /// A network camera with no frame for this long no longer stands in for the camera
    /// it feeds.
    pub feed_live: Duration,
}

impl Default for WindowsConfig {
    fn default() -> WindowsConfig {
        WindowsConfig {
            stale_after: Duration::from_secs(1),
            no_video_after: Duration::from_secs(3),
            tick: Duration::from_millis(100),
            feed_live: Duration::from_millis(1500),
        }
    }
}

/// What a window showed at its last paint (for tests and the latency benchmark).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Shown {
    /// The camera's frame number, if a frame was drawn.
    pub frame: Option<i64>,
    /// When that frame's last packet arrived ([`crate::now_us`]), where known.
    pub arrival_us: Option<i64>,
    pub status: Status,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Status {
    Live,
    Stale,
    NoVideo,
}

/// The painter module. Dropping it unclaims its windows and leaves its cameras.
pub struct VideoWindows {
    shared: Arc<Shared>,
}

struct Shared {
    ds: DataServer,
    exec: Executor,
    cfg: WindowsConfig,
    /// `root.modules.video_windows`: holds one receiver object per joined camera.
    home: Guid,
    state: Mutex<State>,
}

#[derive(Default)]
struct State {
    subs: Vec<SubscriptionId>,
    windows: HashMap<Guid, Win>,
    cameras: HashMap<Guid, Cam>,
    stopped: bool,
}

struct Win {
    source: String,
    camera: Option<Guid>,
    status: Status,
    shown: Option<Shown>,
    fit: ImageFit,
    /// The camera's latest frame scaled once to where it lands in the window (its frame
    /// number, the image): painted pixel for pixel, no resampling on the display's thread.
    scaled: Option<(i64, Image)>,
}

struct Cam {
    receiver: Guid,
    assoc: Guid,
    latest: Option<Latest>,
    /// When the frames of the last second arrived (the DataServer's clock).
    arrivals: VecDeque<Instant>,
    latency_ms: Option<f64>,
}

impl Cam {
    /// Frames received in the second before `now`.
    fn fps(&self, now: Instant) -> f64 {
        self.arrivals.iter().filter(|t| now.saturating_duration_since(**t) < SECOND).count() as f64
    }
}

const SECOND: Duration = Duration::from_secs(1);

#[derive(Clone)]
struct Latest {
    image: Image,
    frame: i64,
    arrival_us: Option<i64>,
    received: Instant,
}

impl VideoWindows {
    pub fn start(ds: &DataServer) -> Result<VideoWindows, String> {
        VideoWindows::start_with(ds, WindowsConfig::default())
    }

    pub fn start_with(ds: &DataServer, cfg: WindowsConfig) -> Result<VideoWindows, String> {
        let display =
            mocu_display::ensure_display_object(ds, 1920, 1080).map_err(|e| e.to_string())?;
        let home = mocu_host::world::ensure_path(ds, &["modules", "video_windows"], "painter")
            .map_err(|e| e.to_string())?;
        let shared = Arc::new(Shared {
            ds: ds.clone(),
            exec: ds.serial_executor(),
            cfg,
            home,
            state: Mutex::default(),
        });
        let weak = Arc::downgrade(&shared);
        let sub = ds
            .subscribe_on(&shared.exec, Topic::children(display), move |n: &Notification| {
                if let (Some(sh), Subject::Child { guid, .. }) = (weak.upgrade(), &n.subject) {
                    sh.on_window(n.kind, *guid);
                }
            })
            .map_err(|e| e.to_string())?;
        shared.state.lock().subs.push(sub);
        Shared::schedule_tick(&Arc::downgrade(&shared));
        Ok(VideoWindows { shared })
    }

    /// What `window` showed at its last paint.
    pub fn shown(&self, window: Guid) -> Option<Shown> {
        self.shared.state.lock().windows.get(&window).and_then(|w| w.shown)
    }

    /// The camera `window` shows now, if any.
    pub fn camera_of(&self, window: Guid) -> Option<Guid> {
        self.shared.state.lock().windows.get(&window).and_then(|w| w.camera)
    }

    /// Resolves sources and checks staleness now (tests; normally on a timer).
    pub fn refresh(&self) {
        self.shared.tick();
    }
}

impl Drop for VideoWindows {
    fn drop(&mut self) {
        let (subs, windows, cams) = {
            let mut st = self.shared.state.lock();
            st.stopped = true;
            let w: Vec<Guid> = st.windows.drain().map(|(g, _)| g).collect();
            let c: Vec<Cam> = st.cameras.drain().map(|(_, c)| c).collect();
            (std::mem::take(&mut st.subs), w, c)
        };
        let ds = &self.shared.ds;
        for s in subs {
            ds.unsubscribe(s);
        }
        for w in windows {
            let _ = ds.unpublish_method(w, "paint");
        }
        for c in cams {
            let _ = ds.leave(c.assoc);
            let _ = ds.delete_object(c.receiver);
        }
    }
}

const BLACK: Color = Color::rgb(0, 0, 0);

impl Shared {
    fn schedule_tick(weak: &Weak<Shared>) {
        let Some(sh) = weak.upgrade() else { return };
        let w2 = weak.clone();
        sh.ds.run_after(sh.cfg.tick, Some(&sh.exec), move || {
            if let Some(sh) = w2.upgrade() {
                if sh.state.lock().stopped {
                    return;
                }
                sh.tick();
            }
            Shared::schedule_tick(&w2);
        });
    }

    fn on_window(self: &Arc<Self>, kind: Kind, g: Guid) {
        match kind {
            Kind::New if self.ds.info(g).is_ok_and(|i| &*i.subtype == "video") => {
                self.state.lock().windows.insert(
                    g,
                    Win {
                        source: String::new(),
                        camera: None,
                        status: Status::NoVideo,
                        shown: None,
                        fit: ImageFit::Cover,
                        scaled: None,
                    },
                );
                let weak = Arc::downgrade(self);
                let _ = claim_window(&self.ds, g, move |c: &mut dyn Canvas, a: &PaintArgs| {
                    if let Some(sh) = weak.upgrade() {
                        sh.paint(g, c, a);
                    }
                });
                chrome::publish_press(&self.ds, g);
                self.tick();
            }
            Kind::Deleted => {
                let had = self.state.lock().windows.remove(&g).is_some();
                if had {
                    self.tick();
                }
            }
            _ => {}
        }
    }

    /// Resolves each window's camera, joins and leaves cameras, publishes the shown
    /// statistics, and repaints windows whose status changed.
    fn tick(self: &Arc<Self>) {
        let ds = &self.ds;
        let wins: Vec<(Guid, String)> = {
            let st = self.state.lock();
            st.windows.keys().map(|g| (*g, text_prop(ds, *g, "source"))).collect()
        };
        let feeds = network_feeds(ds, self.cfg.feed_live);
        let mut choices = Vec::with_capacity(wins.len());
        for (g, source) in wins {
            choices.push((g, choose_camera(ds, &source, &feeds), source, chrome::fit_of(ds, g)));
        }
        let now = ds.now();
        let mut repaint = Vec::new();
        let mut st = self.state.lock();
        for (g, cam, source, fit) in choices {
            if let Some(cam) = cam
                && !st.cameras.contains_key(&cam)
                && let Some(c) = self.join(cam)
            {
                st.cameras.insert(cam, c);
            }
            let cam = cam.filter(|c| st.cameras.contains_key(c));
            let status = match cam.and_then(|c| st.cameras[&c].latest.as_ref()) {
                None => Status::NoVideo,
                Some(l) => self.status_of(now.saturating_duration_since(l.received)),
            };
            let Some(w) = st.windows.get_mut(&g) else { continue };
            if w.camera != cam || w.status != status || w.source != source || w.fit != fit {
                w.camera = cam;
                w.status = status;
                w.source = source;
                w.fit = fit;
                w.scaled = None;
                repaint.push(g);
            }
        }
        // Leave cameras no window shows any more.
        let used: Vec<Guid> = st.windows.values().filter_map(|w| w.camera).collect();
        let unused: Vec<Guid> = st.cameras.keys().filter(|c| !used.contains(c)).copied().collect();
        let mut left = Vec::new();
        for c in unused {
            if let Some(cam) = st.cameras.remove(&c) {
                left.push(cam);
            }
        }
        // Shown statistics, on the camera objects.
        let mut stats = Vec::new();
        for (g, cam) in st.cameras.iter_mut() {
            while cam.arrivals.front().is_some_and(|t| now.saturating_duration_since(*t) >= SECOND)
            {
                cam.arrivals.pop_front();
            }
            stats.push((*g, cam.fps(now), cam.latency_ms));
        }
        drop(st);
        for c in left {
            let _ = ds.leave(c.assoc);
            let _ = ds.delete_object(c.receiver);
        }
        for (g, fps, lat) in stats {
            let _ = ds.set(g, "shown_fps", Value::Float(fps));
            if let Some(l) = lat {
                let _ = ds.set(g, "shown_latency_ms", Value::Float((l * 10.0).round() / 10.0));
            }
        }
        for g in repaint {
            let _ = invalidate(ds, g);
        }
    }

    fn status_of(&self, age: Duration) -> Status {
        if age >= self.cfg.no_video_after {
            Status::NoVideo
        } else if age >= self.cfg.stale_after {
            Status::Stale
        } else {
            Status::Live
        }
    }

    /// Joins `camera` through a receiver object of our own.
    fn join(self: &Arc<Self>, camera: Guid) -> Option<Cam> {
        let ds = &self.ds;
        let name = format!("cam{}", camera.get());
        if let Ok(Some(old)) = ds.find_child(self.home, &name) {
            let _ = ds.delete_object(old);
        }
        let receiver =
            ds.create_object(self.home, ObjectInfo::new(&name, "video_receiver")).ok()?;
        // Cameras whose frames carry `arrival_us` say so with `arrival = true`.
        let timed = ds.try_get(camera, "arrival".into()) == Some(Value::Bool(true));
        let mut spec = MethodSpec::new(if timed { "frame_timed" } else { "frame" })
            .param(ParamSpec::any("pixels"))
            .param(ParamSpec::any("width"))
            .param(ParamSpec::any("height"))
            .param(ParamSpec::any("frame"))
            .describe("One decoded frame: pixels (RGB8/RGBA8), width, height, frame[, arrival_us]");
        if timed {
            spec = spec.param(ParamSpec::any("arrival_us"));
        }
        // Frames with or without their arrival time (a replay's decoder leaves it out: it
        // was taken on the recording process's clock), whatever the camera said before.
        let spec = spec.any_args();
        let method = spec.name.to_string();
        let weak = Arc::downgrade(self);
        let ok = ds.publish_method_on(&self.exec, receiver, spec, move |call: Call| {
            if let (Some(sh), Some(f)) = (weak.upgrade(), FrameMsg::from_values(&call.args)) {
                sh.on_frame(camera, f);
            }
            call.responder.accept(vec![]);
        });
        let assoc = ok.and_then(|_| ds.join(camera, receiver, &method, Overflow::DropOldest, 2));
        match assoc {
            Ok(assoc) => Some(Cam {
                receiver,
                assoc,
                latest: None,
                arrivals: VecDeque::new(),
                latency_ms: None,
            }),
            Err(_) => {
                let _ = ds.delete_object(receiver);
                None
            }
        }
    }

    /// A frame from `camera`: made into an image once, then every window showing the
    /// camera is repainted.
    fn on_frame(&self, camera: Guid, f: FrameMsg) {
        let image = if f.channels() == 4 {
            Image::from_rgba8(f.width, f.height, f.pixels.to_vec())
        } else {
            Image::from_rgb8(f.width, f.height, &f.pixels)
        };
        let Some(image) = image else { return };
        let frame = f.frame;
        let showing: Vec<Guid> = {
            let st = self.state.lock();
            st.windows.iter().filter(|(_, w)| w.camera == Some(camera)).map(|(g, _)| *g).collect()
        };
        // Scaled here, once per window size, rather than resampled in each paint.
        let scaled: Vec<(Guid, Option<Image>)> =
            showing.iter().map(|g| (*g, self.scale_for(*g, &image))).collect();
        let received = self.ds.now();
        let latest = Latest { image, frame, arrival_us: f.arrival_us, received };
        let windows: Vec<Guid> = {
            let mut st = self.state.lock();
            let Some(cam) = st.cameras.get_mut(&camera) else { return };
            cam.latest = Some(latest);
            cam.arrivals.push_back(received);
            if cam.arrivals.len() > 240 {
                cam.arrivals.pop_front();
            }
            let mut ws = Vec::new();
            for (g, w) in st.windows.iter_mut() {
                if w.camera == Some(camera) {
                    w.status = Status::Live;
                    let img = scaled.iter().find(|(x, _)| x == g).and_then(|(_, i)| i.clone());
                    w.scaled = img.map(|i| (frame, i));
                    ws.push(*g);
                }
            }
            ws
        };
        for w in windows {
            let _ = invalidate(&self.ds, w);
        }
    }

    /// `image` scaled to the rectangle it is shown in within window `g` (centred, whole or
    /// cropped: [`picture_at`]) when that rectangle has whole-pixel sides and corner.
    fn scale_for(&self, g: Guid, image: &Image) -> Option<Image> {
        let n = |k: &str| self.ds.try_get(g, PropName::new(k)).and_then(|v| v.as_f64());
        let (w, h) = (n("w")? as f32, n("h")? as f32);
        let fit = self.state.lock().windows.get(&g).map_or(ImageFit::Cover, |w| w.fit);
        let r = picture_at(image, Rect::new(0.0, 0.0, w, h), fit)?;
        image.scaled(r.w as u32, r.h as u32)
    }

    fn paint(&self, window: Guid, c: &mut dyn Canvas, _a: &PaintArgs) {
        let size = c.size();
        let full = Rect::new(0.0, 0.0, size.w, size.h);
        let now = self.ds.now();
        let (latest, status, source, scaled, fit, stats) = {
            let mut st = self.state.lock();
            let Some(w) = st.windows.get(&window) else { return };
            let (cam, source, fit) = (w.camera, w.source.clone(), w.fit);
            let latest = cam.and_then(|g| st.cameras.get(&g)).and_then(|c| c.latest.clone());
            let status = match &latest {
                None => Status::NoVideo,
                Some(l) => self.status_of(now.saturating_duration_since(l.received)),
            };
            let shown = Shown {
                frame: latest.as_ref().filter(|_| status != Status::NoVideo).map(|l| l.frame),
                arrival_us: latest.as_ref().and_then(|l| l.arrival_us),
                status,
            };
            let first_paint = st
                .windows
                .get(&window)
                .and_then(|w| w.shown)
                .is_none_or(|s| s.frame != shown.frame);
            if let Some(w) = st.windows.get_mut(&window) {
                w.shown = Some(shown);
                w.status = status;
            }
            if first_paint
                && status == Status::Live
                && let Some(cam) = cam.and_then(|g| st.cameras.get_mut(&g))
                && let Some(t) = shown.arrival_us
            {
                cam.latency_ms = Some((now_us() - t) as f64 / 1000.0);
            }
            let stats = cam.and_then(|g| st.cameras.get(&g)).map(|c| (c.fps(now), c.latency_ms));
            let scaled = st.windows.get(&window).and_then(|w| w.scaled.clone());
            (latest, status, source, scaled, fit, stats)
        };
        c.fill_rect(full, BLACK);
        if let (Some(l), true) = (&latest, status != Status::NoVideo) {
            // The frame scaled when it arrived, when it is this frame at this size.
            let at = picture_at(&l.image, full, fit);
            let ready = scaled.filter(|(f, img)| {
                *f == l.frame
                    && at.is_some_and(|r| (r.w, r.h) == (img.width() as f32, img.height() as f32))
            });
            c.save();
            c.clip_rect(full);
            match (ready, at) {
                (Some((_, img)), Some(r)) => c.draw_image(&img, r, ImageFit::Stretch, 1.0),
                _ => c.draw_image(&l.image, full, fit, 1.0),
            }
            c.restore();
        }
        let chrome = Chrome::of(&source);
        let live = status != Status::NoVideo;
        chrome.draw(c, full, if live { stats } else { None });
        match status {
            Status::Live => {}
            Status::Stale => chrome::badge(c, full, "STALE", Color::rgb(0xf5, 0x9e, 0x0b)),
            Status::NoVideo => chrome.no_video(c, full),
        }
    }
}

/// Where `image` is shown in `full` (centred, aspect kept: whole with `Contain`, cropped
/// with `Cover`), when that rectangle lies on whole pixels — where a copy scaled to its size
/// is drawn pixel for pixel.
fn picture_at(image: &Image, full: Rect, fit: ImageFit) -> Option<Rect> {
    let size = Size::new(image.width() as f32, image.height() as f32);
    let r = fit_rect(size, full, fit);
    let whole = |v: f32| v.fract() == 0.0;
    (r.w >= 1.0 && r.h >= 1.0 && [r.x, r.y, r.w, r.h].into_iter().all(whole)).then_some(r)
}

pub(crate) fn text_prop(ds: &DataServer, g: Guid, name: &str) -> String {
    match ds.try_get(g, PropName::new(name)) {
        Some(Value::Str(s)) => s.to_string(),
        _ => String::new(),
    }
}

/// Live network cameras under `root.cameras` and the camera path each feeds.
fn network_feeds(ds: &DataServer, live: Duration) -> Vec<(Guid, String)> {
    let Some(folder) = ds.resolve(&["cameras"]) else { return Vec::new() };
    let now = now_us();
    let mut out = Vec::new();
    for cam in ds.children(folder).unwrap_or_default() {
        let feeds = text_prop(ds, cam, "feeds");
        if feeds.is_empty() || feeds == "none" {
            continue;
        }
        let last = ds.try_get(cam, "last_frame_us".into()).and_then(|v| v.as_i64()).unwrap_or(0);
        if last > 0 && now - last < live.as_micros() as i64 {
            out.push((cam, feeds));
        }
    }
    out
}

/// The first vehicle's drive camera (what `feeds = "auto"` stands for).
fn auto_camera(ds: &DataServer) -> Option<Guid> {
    let vehicles = ds.resolve(&["vehicles"])?;
    ds.children(vehicles).ok()?.into_iter().find_map(|v| {
        let cams = ds.find_child(v, "cameras").ok().flatten()?;
        ds.find_child(cams, "drive").ok().flatten()
    })
}

/// The camera a window with `source` shows: a live network camera that feeds it, else the
/// camera at `source` itself (if it is a listener).
fn choose_camera(ds: &DataServer, source: &str, feeds: &[(Guid, String)]) -> Option<Guid> {
    if source.trim().is_empty() {
        return None;
    }
    let target = resolve_path(ds, source);
    let full = normalize_path(source);
    for (cam, f) in feeds {
        let hit =
            if f == "auto" { target.is_some() && target == auto_camera(ds) } else { *f == full };
        if hit {
            return Some(*cam);
        }
    }
    target.filter(|g| ds.receivers(*g).is_ok())
}
