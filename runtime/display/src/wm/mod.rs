//! The window manager module (paper §5.1): reads the windows under `root.display`, orders
//! them (layer, then declaration order), asks each window's painter to repaint when its
//! window is dirty, and hands the layers, bottom first, to a compositor. It draws nothing
//! of its own.
//!
//! Architecture invariant: the window manager knows no painter. It finds windows by type
//! (`window`) in the world model and calls whatever `paint` method is published under
//! them; a window no module claims is an empty layer.

use crate::anim::Animator;
use crate::compose::LayerView;
use crate::geom::{IRect, Size};
use crate::paint;
use crate::skia::SkiaCanvas;
use crate::tiles::Tiles;
use mocu_dataserver::{
    CallOptions, CallOutcome, DataServer, DsError, Executor, Guid, Kind, MethodSpec, Notification,
    ParamSpec, Subject, SubscriptionId, Topic, Value, ValueKind,
};
use mocu_value::limits::MAX_SCREEN_SIDE;
use parking_lot::{Condvar, Mutex};
use std::collections::HashMap;
use std::sync::Arc;
use std::time::Duration;
use tiny_skia::Pixmap;

mod pointer;
mod props;
mod watch;

pub use pointer::Hit;
pub use props::WinProps;
use props::{Effect, apply_prop};
use watch::on_child;

/// The object type of a window.
pub const WINDOW_TYPE: &str = "window";
/// The property a failed painter's error is written to (ignored for dirtiness).
pub const PAINT_ERROR: &str = "paint_error";

struct WinEntry {
    props: WinProps,
    sub: Option<SubscriptionId>,
    repaint: bool,
    /// Window-local damage from `invalidate` calls.
    damage: IRect,
}

#[derive(Default)]
struct SharedState {
    windows: HashMap<Guid, WinEntry>,
    removed: Vec<Guid>,
    /// `width`/`height` of `root.display`, once published.
    size: (Option<f64>, Option<f64>),
    size_changed: bool,
    reindex: bool,
    /// Something changed since the last frame.
    pending: bool,
}

/// State shared between the subscription callbacks and the frame thread.
pub(crate) struct Shared {
    state: Mutex<SharedState>,
    wake: Condvar,
}

impl Shared {
    fn changed(&self, st: &mut SharedState) {
        st.pending = true;
        self.wake.notify_all();
    }
}

/// A layer: the last rendering of a window, owned by the frame thread.
struct Layer {
    pixmap: Option<Pixmap>,
    /// The pixmap's drawn-on tiles (the rest is transparent).
    tiles: Option<Tiles>,
    /// Every pixel of the pixmap is opaque.
    opaque: bool,
    /// Window-local coordinates of pixmap pixel (0, 0).
    origin: (i32, i32),
    painted_size: (i32, i32),
    painted_clip: bool,
    /// The window-local part of the window the pixmap holds (see [`layer_extent`]).
    painted_extent: IRect,
    /// Needs a full repaint before it can be shown.
    stale: bool,
    /// Window-local damage not yet repainted.
    damage: IRect,
    /// The painter failed: not composited until it paints successfully.
    failed: Option<String>,
    /// No painter claimed the window: nothing to composite.
    unclaimed: bool,
    /// Screen position of the window, last frame.
    pos: (i32, i32),
    /// Where the pixmap was composited last frame (empty: not shown).
    shown: IRect,
    opacity: f32,
    /// Pixmap region repainted since last composited.
    changed: Option<IRect>,
}

impl Layer {
    fn new() -> Layer {
        Layer {
            pixmap: None,
            tiles: None,
            opaque: false,
            origin: (0, 0),
            painted_size: (0, 0),
            painted_clip: true,
            painted_extent: IRect::default(),
            stale: true,
            damage: IRect::default(),
            failed: None,
            unclaimed: false,
            pos: (0, 0),
            shown: IRect::default(),
            opacity: 1.0,
            changed: None,
        }
    }
}

/// What one frame did.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct FrameStats {
    pub frame: u64,
    /// False when nothing had changed: no painting, no compositing.
    pub drawn: bool,
    /// Windows repainted whole, bottom first.
    pub repainted: Vec<Arc<str>>,
    /// Windows repainted in part (damage rectangles).
    pub partial: Vec<Arc<str>>,
    /// Windows whose painter failed (panicked, refused, failed), with why; their layers
    /// were skipped.
    pub failed: Vec<(Arc<str>, String)>,
    /// The screen rectangle recomposited.
    pub damage: IRect,
    /// Layers blended into the damage rectangle.
    pub composited: usize,
    pub paint_time: Duration,
    pub composite_time: Duration,
}

pub(crate) struct Planned {
    pub stats: FrameStats,
    pub resized: Option<(u32, u32)>,
}

/// The window manager of one display.
pub struct WindowManager {
    ds: DataServer,
    display: Guid,
    shared: Arc<Shared>,
    subs: Arc<Mutex<Vec<SubscriptionId>>>,
    layers: HashMap<Guid, Layer>,
    props: HashMap<Guid, WinProps>,
    index: HashMap<Guid, usize>,
    /// Windows bottom first, as last composited.
    stacking: Vec<Guid>,
    size: (u32, u32),
    animator: Arc<Animator>,
    /// `swap`, `animate`, `animate_eased` on `root.display`, when this display publishes
    /// them (`DisplayOptions::window_behaviours`; else the `window_manager` module does).
    _behaviours: Option<crate::behaviours::WindowBehaviours>,
    hover: Option<Guid>,
    capture: Option<(Guid, i64)>,
}

fn arg_f(v: &Value) -> f64 {
    v.as_f64().unwrap_or(0.0)
}

impl WindowManager {
    /// Starts managing the windows under `display` (an existing `display` object).
    pub(crate) fn new(
        ds: &DataServer,
        display: Guid,
        size: (u32, u32),
        animator: Arc<Animator>,
        behaviours: bool,
    ) -> Result<WindowManager, DsError> {
        let shared = Arc::new(Shared { state: Mutex::default(), wake: Condvar::new() });
        let exec = ds.serial_executor();
        let subs: Arc<Mutex<Vec<SubscriptionId>>> = Arc::default();
        {
            let sh = shared.clone();
            let sub = ds.subscribe_on(&exec, Topic::properties(display), move |n| {
                let Some(name) = n.property_name() else { return };
                let v = n.value().and_then(Value::as_f64);
                let mut st = sh.state.lock();
                match name.as_str() {
                    "width" => st.size.0 = v,
                    "height" => st.size.1 = v,
                    _ => return,
                }
                st.size_changed = true;
                sh.changed(&mut st);
            })?;
            subs.lock().push(sub);
        }
        {
            let sh = shared.clone();
            let ds2 = ds.clone();
            let ex2 = exec.clone();
            let subs2 = subs.clone();
            let sub = ds.subscribe_on(&exec, Topic::children(display), move |n| {
                on_child(&ds2, &ex2, &sh, &subs2, n);
            })?;
            subs.lock().push(sub);
        }
        let behaviours = if behaviours {
            Some(crate::behaviours::WindowBehaviours::publish_with(
                ds,
                display,
                animator.clone(),
                true,
            )?)
        } else {
            None
        };
        Ok(WindowManager {
            _behaviours: behaviours,
            ds: ds.clone(),
            display,
            shared,
            subs,
            layers: HashMap::new(),
            props: HashMap::new(),
            index: HashMap::new(),
            stacking: Vec::new(),
            size,
            animator,
            hover: None,
            capture: None,
        })
    }

    pub fn display_object(&self) -> Guid {
        self.display
    }

    pub fn animator(&self) -> &Arc<Animator> {
        &self.animator
    }

    /// Waits until something changes or `timeout` passes; returns whether something
    /// changed. A display with nothing changing sleeps here (no CPU).
    pub fn wait_for_change(&self, timeout: Duration) -> bool {
        let mut st = self.shared.state.lock();
        if !st.pending {
            self.shared.wake.wait_for(&mut st, timeout);
        }
        st.pending
    }

    /// Marks everything for repainting (after a backend change).
    pub fn invalidate_all(&mut self) {
        for l in self.layers.values_mut() {
            l.stale = true;
        }
        let mut st = self.shared.state.lock();
        self.shared.changed(&mut st);
    }

    /// Takes the changes since the last frame, calls the painters of dirty windows and
    /// works out the damage. Returns `None` when nothing changed.
    pub(crate) fn plan(&mut self, frame: u64, force: bool) -> Option<Planned> {
        let t0 = std::time::Instant::now();
        let mut stats = FrameStats { frame, ..FrameStats::default() };
        let (snaps, removed, resized, reindex) = {
            let mut st = self.shared.state.lock();
            if !st.pending && !force {
                return None;
            }
            st.pending = false;
            let snaps: Vec<(Guid, WinProps, bool, IRect)> = st
                .windows
                .iter_mut()
                .map(|(g, e)| {
                    (
                        *g,
                        e.props.clone(),
                        std::mem::take(&mut e.repaint),
                        std::mem::take(&mut e.damage),
                    )
                })
                .collect();
            let removed = std::mem::take(&mut st.removed);
            let resized = if std::mem::take(&mut st.size_changed) {
                let w = screen_side(st.size.0.unwrap_or(self.size.0 as f64));
                let h = screen_side(st.size.1.unwrap_or(self.size.1 as f64));
                ((w, h) != self.size).then_some((w, h))
            } else {
                None
            };
            (snaps, removed, resized, std::mem::take(&mut st.reindex))
        };
        let mut damage = IRect::default();
        if let Some(sz) = resized {
            self.size = sz;
            damage = self.bounds();
            for l in self.layers.values_mut() {
                if !l.painted_clip {
                    l.stale = true;
                }
            }
        }
        if force {
            damage = self.bounds();
        }
        for g in removed {
            if let Some(l) = self.layers.remove(&g) {
                damage = damage.union(&l.shown);
            }
            self.props.remove(&g);
        }
        if reindex || self.index.len() != snaps.len() {
            let kids = self.ds.children(self.display).unwrap_or_default();
            self.index = kids.into_iter().enumerate().map(|(i, g)| (g, i)).collect();
        }
        let mut snaps = snaps;
        snaps.sort_by_key(|(g, p, _, _)| {
            (p.layer, p.order, self.index.get(g).copied().unwrap_or(usize::MAX), *g)
        });
        let stacking: Vec<Guid> = snaps.iter().map(|s| s.0).collect();
        if stacking != self.stacking {
            // Windows whose place in the stack changed are recomposited.
            let old: HashMap<Guid, usize> =
                self.stacking.iter().enumerate().map(|(i, g)| (*g, i)).collect();
            for (i, g) in stacking.iter().enumerate() {
                if old.get(g) != Some(&i)
                    && let Some(l) = self.layers.get(g)
                {
                    damage = damage.union(&l.shown);
                }
            }
        }
        self.stacking = stacking;
        for (g, props, repaint, dmg) in snaps {
            let r = props.rect(self.size);
            let extent = layer_extent(props.clip, r, self.size);
            let layer = self.layers.entry(g).or_insert_with(Layer::new);
            if repaint
                || layer.painted_size != (r.w, r.h)
                || layer.painted_clip != props.clip
                || (!props.clip && resized.is_some())
                || (props.clip && layer.painted_extent != extent)
            {
                layer.stale = true;
            }
            layer.damage = layer.damage.union(&dmg);
            let visible =
                props.visible && props.opacity > 0.0 && r.w > 0 && r.h > 0 && !extent.is_empty();
            if visible {
                if layer.stale {
                    self.paint(g, &props, r, frame, None, &mut stats);
                } else if !layer.damage.is_empty() {
                    let d = layer.damage;
                    self.paint(g, &props, r, frame, Some(d), &mut stats);
                }
            }
            let layer = self.layers.get_mut(&g).expect("inserted above");
            layer.pos = (r.x, r.y);
            let shown = match &layer.pixmap {
                Some(pm)
                    if visible && layer.failed.is_none() && !layer.unclaimed && !layer.stale =>
                {
                    IRect::new(
                        r.x + layer.origin.0,
                        r.y + layer.origin.1,
                        pm.width() as i32,
                        pm.height() as i32,
                    )
                }
                _ => IRect::default(),
            };
            let opacity = props.opacity as f32;
            if shown != layer.shown || (opacity != layer.opacity && !shown.is_empty()) {
                damage = damage.union(&layer.shown).union(&shown);
            }
            if let Some(c) = layer.changed
                && !shown.is_empty()
            {
                damage = damage.union(&c.offset(shown.x, shown.y));
            }
            layer.shown = shown;
            layer.opacity = opacity;
            self.props.insert(g, props);
        }
        stats.damage = damage.intersect(&self.bounds());
        stats.drawn = !stats.damage.is_empty()
            || !stats.repainted.is_empty()
            || !stats.partial.is_empty()
            || !stats.failed.is_empty();
        stats.paint_time = t0.elapsed();
        Some(Planned { stats, resized })
    }

    /// The layers to composite, bottom first, with what changed in each.
    pub(crate) fn layer_views(&mut self) -> Vec<LayerView<'_>> {
        let mut out = Vec::with_capacity(self.stacking.len());
        for g in &self.stacking {
            let Some(l) = self.layers.get(g) else { continue };
            if l.shown.is_empty() {
                continue;
            }
            let Some(pm) = &l.pixmap else { continue };
            out.push(LayerView {
                window: *g,
                pixmap: pm,
                tiles: l.tiles.as_ref(),
                opaque: l.opaque,
                x: l.shown.x,
                y: l.shown.y,
                opacity: l.opacity,
                changed: l.changed,
            });
        }
        out
    }

    /// Forgets the per-layer "changed" regions once a compositor has used them.
    pub(crate) fn composited(&mut self) {
        for l in self.layers.values_mut() {
            l.changed = None;
        }
    }

    pub fn bounds(&self) -> IRect {
        IRect::new(0, 0, self.size.0 as i32, self.size.1 as i32)
    }

    pub fn size(&self) -> (u32, u32) {
        self.size
    }

    /// The size of the pixmap a window's layer holds (what its rendering costs), if any.
    pub fn layer_size(&self, window: Guid) -> Option<(u32, u32)> {
        let pm = self.layers.get(&window)?.pixmap.as_ref()?;
        Some((pm.width(), pm.height()))
    }

    /// Calls the window's painter over the whole window (`region` None) or a damaged part.
    fn paint(
        &mut self,
        g: Guid,
        props: &WinProps,
        r: IRect,
        frame: u64,
        region: Option<IRect>,
        stats: &mut FrameStats,
    ) {
        let size = self.size;
        let layer = self.layers.get_mut(&g).expect("the caller made the layer");
        let wsize = Size::new(r.w as f32, r.h as f32);
        let mut scratch_at = IRect::default();
        let canvas = match region {
            None => {
                let extent = layer_extent(props.clip, r, size);
                let (pw, ph, origin) = (extent.w as u32, extent.h as u32, (extent.x, extent.y));
                let tiles = layer.tiles.take();
                layer.origin = origin;
                layer.painted_extent = extent;
                match layer.pixmap.take() {
                    // Cleared by the canvas before its first drawing (only where the last
                    // frame drew), or not at all when that drawing covers the layer
                    // opaquely.
                    Some(pm) if pm.width() == pw && pm.height() == ph => match tiles {
                        Some(t) => SkiaCanvas::reusing_drawn(pm, t, origin, wsize),
                        None => SkiaCanvas::reusing(pm, origin, wsize),
                    },
                    _ => match crate::alloc::pixmap(pw, ph) {
                        Some(pm) => SkiaCanvas::blank(pm, origin, wsize),
                        None => return,
                    },
                }
            }
            Some(d) => {
                let Some(pm) = &layer.pixmap else { return };
                let extent = IRect::new(
                    layer.origin.0,
                    layer.origin.1,
                    pm.width() as i32,
                    pm.height() as i32,
                );
                let d = d.intersect(&extent);
                if d.is_empty() {
                    layer.damage = IRect::default();
                    return;
                }
                let Some(scratch) = crate::alloc::pixmap(d.w as u32, d.h as u32) else { return };
                scratch_at = d;
                SkiaCanvas::blank(scratch, (d.x, d.y), wsize)
            }
        };
        paint::install(canvas);
        let outcome = Arc::new(Mutex::new(None));
        let o2 = outcome.clone();
        let args =
            vec![Value::Int(frame as i64), Value::Float(r.w as f64), Value::Float(r.h as f64)];
        self.ds.call(g, "paint", args, Some(CallOptions::immediate()), move |o| {
            *o2.lock() = Some(o);
        });
        let canvas = paint::take();
        let outcome = outcome.lock().take();
        let layer = self.layers.get_mut(&g).expect("still there");
        let Some(canvas) = canvas else { return };
        let (drawn, drawn_tiles, drawn_opaque) = canvas.into_parts();
        let was_failed = layer.failed.take().is_some();
        layer.unclaimed = false;
        match outcome {
            Some(CallOutcome::Accepted(_)) | None => {}
            Some(CallOutcome::NoSuchMethod) => layer.unclaimed = true,
            Some(CallOutcome::NoSuchObject) => layer.unclaimed = true,
            Some(other) => {
                let why = other.to_string();
                stats.failed.push((props.name.clone(), why.clone()));
                let _ = self.ds.set(g, PAINT_ERROR, Value::str(&why));
                layer.failed = Some(why);
            }
        }
        if was_failed && layer.failed.is_none() {
            let _ = self.ds.set(g, PAINT_ERROR, Value::str(""));
        }
        match region {
            None => {
                layer.changed = Some(IRect::new(0, 0, drawn.width() as i32, drawn.height() as i32));
                layer.pixmap = Some(drawn);
                layer.tiles = Some(drawn_tiles);
                layer.opaque = drawn_opaque;
                layer.painted_size = (r.w, r.h);
                layer.painted_clip = props.clip;
                layer.stale = false;
                layer.damage = IRect::default();
                stats.repainted.push(props.name.clone());
            }
            Some(_) => {
                let Some(pm) = layer.pixmap.as_mut() else { return };
                // The scratch pixmap replaces its rectangle of the layer.
                let at = scratch_at.offset(-layer.origin.0, -layer.origin.1);
                copy_into(pm, &drawn, at.x, at.y);
                // The scratch replaced its rectangle: drawn on (unless transparent), and
                // opaque only if the scratch is.
                if !drawn_tiles.is_empty()
                    && let Some(t) = layer.tiles.as_mut()
                {
                    t.mark(at);
                }
                layer.opaque &= drawn_opaque;
                layer.changed = Some(layer.changed.unwrap_or_default().union(&at));
                layer.damage = IRect::default();
                stats.partial.push(props.name.clone());
            }
        }
    }
}

impl Drop for WindowManager {
    fn drop(&mut self) {
        // Taken out first, then ended with the lock released: `unsubscribe` waits for a
        // running callback, and `on_child` takes this lock (holding it here deadlocked).
        // A callback still running may add a window's subscription meanwhile: once the
        // children subscription has ended none runs, so the next round takes the last.
        loop {
            let subs = std::mem::take(&mut *self.subs.lock());
            if subs.is_empty() {
                break;
            }
            for s in subs {
                self.ds.unsubscribe(s);
            }
        }
        let windows: Vec<Guid> = self.shared.state.lock().windows.keys().copied().collect();
        for g in windows {
            let _ = self.ds.unpublish_method(g, "invalidate");
        }
    }
}

/// A screen side as published on `root.display`, within what the display allocates (at
/// least 1 px, at most [`MAX_SCREEN_SIDE`]).
fn screen_side(v: f64) -> u32 {
    if v.is_nan() { 1 } else { v.round().clamp(1.0, MAX_SCREEN_SIDE as f64) as u32 }
}

/// The window-local rectangle a window's layer holds: a clipped window only the part of it
/// on the screen (a window far larger than the screen costs no more than the screen), an
/// unclipped one the whole screen.
fn layer_extent(clip: bool, r: IRect, screen: (u32, u32)) -> IRect {
    let screen = IRect::new(0, 0, screen.0 as i32, screen.1 as i32);
    if clip {
        let on_screen = r.intersect(&screen);
        if on_screen.is_empty() { IRect::default() } else { on_screen.offset(-r.x, -r.y) }
    } else {
        screen.offset(-r.x, -r.y)
    }
}

/// Copies `src` over `dst` at (x, y), replacing pixels (no blending).
fn copy_into(dst: &mut Pixmap, src: &Pixmap, x: i32, y: i32) {
    let r = IRect::new(x, y, src.width() as i32, src.height() as i32).intersect(&IRect::new(
        0,
        0,
        dst.width() as i32,
        dst.height() as i32,
    ));
    if r.is_empty() {
        return;
    }
    let dw = dst.width() as usize * 4;
    let sw = src.width() as usize * 4;
    let s = src.data();
    let d = dst.data_mut();
    for row in r.y..r.bottom() {
        let sy = (row - y) as usize;
        let sx = (r.x - x) as usize * 4;
        let n = r.w as usize * 4;
        d[row as usize * dw + r.x as usize * 4..][..n].copy_from_slice(&s[sy * sw + sx..][..n]);
    }
}

impl WindowManager {
    pub(crate) fn shared_handle(&self) -> Arc<Shared> {
        self.shared.clone()
    }
}

pub(crate) fn wait_pending(sh: &Shared, timeout: Duration) -> bool {
    let mut st = sh.state.lock();
    if !st.pending {
        sh.wake.wait_for(&mut st, timeout);
    }
    st.pending
}
