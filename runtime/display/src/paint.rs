//! The paint context: how a module reaches the canvas of the window it claimed.
//!
//! The window manager calls a window's `paint` method with `CallOptions::immediate()`, so
//! the handler runs on the frame thread, inside the call. Around that call the window
//! manager puts the window's canvas in a thread-local slot; [`with_canvas`] lends it to
//! the handler. Outside a paint call there is no canvas and `with_canvas` returns `None`.
//!
//! Conventions (the world-model side of this API):
//! - `paint(frame: int, w: float, h: float)` under the window object: draw the window's
//!   content in window-local pixels. The canvas starts transparent (or, for a damage
//!   repaint, transparent inside [`Canvas::damage`] and clipped to it).
//! - `revision` (int) on the window: bump it to say "my content changed" (whole window).
//! - `invalidate(x, y, w, h)` (published by the window manager under every window):
//!   only that window-local rectangle changed. Both only schedule a repaint; painting
//!   happens at the next frame.
//! - `pointer(kind: string, button: int, x: float, y: float)` (optional, published by the
//!   painter): pointer input routed to the window, window-local; kinds `enter`, `move`,
//!   `leave`, `down`, `up`; buttons 0 left, 1 right, 2 middle.
//! - `hit(x: float, y: float) -> [bool]` (optional, published by the painter): overrides
//!   the default hit test (the alpha of the layer's last rendered pixel).

use crate::canvas::Canvas;
use crate::geom::{Rect, Size};
use crate::skia::SkiaCanvas;
use mocu_dataserver::{
    CallOptions, CallOutcome, DataServer, DsError, Guid, MethodSpec, ParamSpec, Value, ValueKind,
};
use std::cell::RefCell;

thread_local! {
    static CANVAS: RefCell<Option<SkiaCanvas>> = const { RefCell::new(None) };
}

/// Lends the canvas of the window being painted to `f`. `None` outside a paint call (or
/// when called again from inside `f`).
pub fn with_canvas<R>(f: impl FnOnce(&mut dyn Canvas) -> R) -> Option<R> {
    CANVAS.with(|slot| {
        let mut slot = slot.try_borrow_mut().ok()?;
        let canvas = slot.as_mut()?;
        Some(f(canvas))
    })
}

pub(crate) fn install(canvas: SkiaCanvas) {
    CANVAS.with(|slot| *slot.borrow_mut() = Some(canvas));
}

pub(crate) fn take() -> Option<SkiaCanvas> {
    CANVAS.with(|slot| slot.borrow_mut().take())
}

/// What a paint call is told.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PaintArgs {
    /// The display's frame number.
    pub frame: u64,
    /// The window's size.
    pub size: Size,
}

impl PaintArgs {
    /// Parses the `paint` method's arguments `[frame, w, h]`.
    pub fn from_values(args: &[Value]) -> Option<PaintArgs> {
        match args {
            [f, w, h] => Some(PaintArgs {
                frame: f.as_i64()?.max(0) as u64,
                size: Size::new(w.as_f64()? as f32, h.as_f64()? as f32),
            }),
            _ => None,
        }
    }
}

/// The `paint` method's published signature.
pub fn paint_spec() -> MethodSpec {
    MethodSpec::new("paint")
        .param(ParamSpec::new("frame", ValueKind::Int))
        .param(ParamSpec::new("w", ValueKind::Float))
        .param(ParamSpec::new("h", ValueKind::Float))
        .defaults(CallOptions::immediate())
        .describe("Draws the window's content (called by the window manager on the frame thread)")
}

/// The `pointer` method's published signature (see the module docs): the window manager
/// calls it, painters that take pointer input publish it with this one spec.
pub fn pointer_spec() -> MethodSpec {
    MethodSpec::new("pointer")
        .param(ParamSpec::new("kind", ValueKind::String))
        .param(ParamSpec::new("button", ValueKind::Int))
        .param(ParamSpec::new("x", ValueKind::Float))
        .param(ParamSpec::new("y", ValueKind::Float))
        .ordered()
        .describe("Pointer input, window-local: kind (enter, move, leave, down, up), button (0 left, 1 right, 2 middle, -1 none), x, y")
}

/// Claims `window`: publishes its `paint` method running `painter` with the canvas, then
/// bumps its `revision` so that the next frame paints it.
pub fn claim_window(
    ds: &DataServer,
    window: Guid,
    painter: impl Fn(&mut dyn Canvas, &PaintArgs) + Send + Sync + 'static,
) -> Result<(), DsError> {
    ds.publish_method_fn(window, paint_spec(), move |args| {
        let Some(pa) = PaintArgs::from_values(args) else {
            return CallOutcome::Failed("paint takes (frame, w, h)".into());
        };
        match with_canvas(|c| painter(c, &pa)) {
            Some(()) => CallOutcome::Accepted(vec![]),
            None => CallOutcome::Failed("paint called outside a frame".into()),
        }
    })?;
    invalidate(ds, window)
}

/// Says the whole content of `window` changed: bumps its `revision`.
pub fn invalidate(ds: &DataServer, window: Guid) -> Result<(), DsError> {
    let rev = ds.get(window, "revision").ok().and_then(|v| v.as_i64()).unwrap_or(0);
    ds.set(window, "revision", Value::Int(rev.wrapping_add(1)))
}

/// A job that any number of asks run once: [`Coalesced::ask`] queues it on an executor
/// unless it is queued already, and every ask made before it runs is answered by that run.
/// For a module that invalidates its windows on world-model changes: a fleet at 100 Hz
/// changes tens of thousands of properties a second, and a window needs its `revision`
/// moved once before the next frame, not once per change.
#[derive(Clone, Default)]
pub struct Coalesced {
    queued: std::sync::Arc<std::sync::atomic::AtomicBool>,
}

impl Coalesced {
    /// Queues `job` on `exec`, unless a job asked for earlier has not started yet.
    pub fn ask(&self, exec: &mocu_dataserver::Executor, job: impl FnOnce() + Send + 'static) {
        use std::sync::atomic::Ordering;
        if self.queued.swap(true, Ordering::AcqRel) {
            return;
        }
        let queued = self.queued.clone();
        exec.spawn(move || {
            // Cleared before the job: an ask made while it runs queues the next one.
            queued.store(false, Ordering::Release);
            job();
        });
    }
}

/// Says only `r` (window-local) of `window` changed. Falls back to [`invalidate`] when no
/// window manager serves the window.
pub fn invalidate_rect(ds: &DataServer, window: Guid, r: Rect) -> Result<(), DsError> {
    let args = [r.x, r.y, r.w, r.h].map(|v| Value::Float(v as f64)).to_vec();
    let slot = std::sync::Arc::new(parking_lot::Mutex::new(None));
    let s2 = slot.clone();
    ds.call(window, "invalidate", args, Some(CallOptions::immediate()), move |o| {
        *s2.lock() = Some(o)
    });
    let outcome = slot.lock().take();
    match outcome {
        Some(CallOutcome::Accepted(_)) => Ok(()),
        _ => invalidate(ds, window),
    }
}

#[cfg(test)]
mod tests {
    use super::Coalesced;
    use mocu_dataserver::DataServer;
    use std::sync::Arc;
    use std::sync::atomic::{AtomicUsize, Ordering};

    #[test]
    fn asks_made_before_the_job_runs_run_it_once_and_a_later_ask_runs_it_again() {
        let ds = DataServer::default();
        let exec = ds.serial_executor();
        let runs = Arc::new(AtomicUsize::new(0));
        let once = Coalesced::default();
        // The executor held until the asks are made.
        let (release, held) = std::sync::mpsc::sync_channel::<()>(0);
        exec.spawn(move || {
            let _ = held.recv();
        });
        for _ in 0..1000 {
            let runs = runs.clone();
            once.ask(&exec, move || {
                runs.fetch_add(1, Ordering::SeqCst);
            });
        }
        release.send(()).unwrap();
        ds.quiesce();
        assert_eq!(runs.load(Ordering::SeqCst), 1);
        let r = runs.clone();
        once.ask(&exec, move || {
            r.fetch_add(1, Ordering::SeqCst);
        });
        ds.quiesce();
        assert_eq!(runs.load(Ordering::SeqCst), 2);
    }
}
