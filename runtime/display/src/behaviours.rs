//! The window manager's behaviours: `swap(a, b, ms)`, `animate(window, x, y, w, h, ms)` and
//! `animate_eased(window, x, y, w, h, ms, easing)` on `root.display`, what layouts (`swap a b
//! 300ms`) and modules call to move windows. They write the windows' rectangles (through an
//! [`Animator`]), which the frame loop's window manager then composites like any change.
//!
//! A display publishes them itself by default; `mocu run` leaves them to its
//! `window_manager` module (docs/modules.md), which publishes them with this type, so that a
//! profile can set them (`animate = false`: every move at once) or replace them with a
//! project's own window policy.

use crate::anim::{Animator, Clock, Easing};
use crate::wm::WINDOW_TYPE;
use mocu_dataserver::{
    CallOptions, CallOutcome, DataServer, DsError, Guid, MethodSpec, ParamSpec, Value, ValueKind,
};
use std::sync::Arc;
use std::time::Duration;

/// The behaviours' methods, published while this lives.
pub struct WindowBehaviours {
    ds: DataServer,
    display: Guid,
}

const METHODS: [&str; 3] = ["swap", "animate", "animate_eased"];

fn arg_f(v: &Value) -> f64 {
    v.as_f64().unwrap_or(0.0)
}

impl WindowBehaviours {
    /// Publishes them on `display` (the `root.display` object), animating on the
    /// DataServer's clock at `rate` steps a second; with `animate` false every move and
    /// swap happens at once.
    pub fn publish(
        ds: &DataServer,
        display: Guid,
        rate: f64,
        animate: bool,
    ) -> Result<WindowBehaviours, DsError> {
        let interval = Duration::from_secs_f64(1.0 / rate.max(1.0));
        Self::publish_with(ds, display, Animator::new(ds.clone(), Clock::Real, interval), animate)
    }

    pub(crate) fn publish_with(
        ds: &DataServer,
        display: Guid,
        animator: Arc<Animator>,
        animate: bool,
    ) -> Result<WindowBehaviours, DsError> {
        let me = WindowBehaviours { ds: ds.clone(), display };
        let find = {
            let ds = ds.clone();
            move |name: &str| -> Option<Guid> {
                let g = ds.find_child(display, name).ok()??;
                (ds.info(g).ok()?.kind.as_ref() == WINDOW_TYPE).then_some(g)
            }
        };
        let an = animator.clone();
        let f2 = find.clone();
        ds.publish_method_fn(
            display,
            MethodSpec::new("swap")
                .param(ParamSpec::new("a", ValueKind::String))
                .param(ParamSpec::new("b", ValueKind::String))
                .param(ParamSpec::new("ms", ValueKind::Int))
                .defaults(CallOptions::immediate())
                .describe("Exchanges two windows' rectangles, animated with ease-in-out"),
            move |a| {
                let (Some(x), Some(y)) = (a[0].as_str().and_then(&f2), a[1].as_str().and_then(&f2))
                else {
                    return CallOutcome::Refused("no such window".into());
                };
                let ms = if animate { a[2].as_i64().unwrap_or(0).max(0) as u64 } else { 0 };
                an.swap(x, y, Duration::from_millis(ms), Easing::EaseInOut);
                CallOutcome::Accepted(vec![])
            },
        )?;
        let rect_params = |spec: MethodSpec| {
            spec.param(ParamSpec::new("window", ValueKind::String))
                .param(ParamSpec::new("x", ValueKind::Float))
                .param(ParamSpec::new("y", ValueKind::Float))
                .param(ParamSpec::new("w", ValueKind::Float))
                .param(ParamSpec::new("h", ValueKind::Float))
                .param(ParamSpec::new("ms", ValueKind::Int))
                .defaults(CallOptions::immediate())
        };
        for eased in [false, true] {
            let an = animator.clone();
            let f3 = find.clone();
            let mut spec =
                rect_params(MethodSpec::new(if eased { "animate_eased" } else { "animate" }));
            if eased {
                spec = spec.param(ParamSpec::new("easing", ValueKind::String));
            }
            ds.publish_method_fn(
                display,
                spec.describe("Moves/resizes a window, animated"),
                move |a| {
                    let Some(w) = a[0].as_str().and_then(&f3) else {
                        return CallOutcome::Refused("no such window".into());
                    };
                    let easing = if eased {
                        match a[6].as_str().and_then(Easing::parse) {
                            Some(e) => e,
                            None => return CallOutcome::Refused("unknown easing".into()),
                        }
                    } else {
                        Easing::EaseInOut
                    };
                    let to = [arg_f(&a[1]), arg_f(&a[2]), arg_f(&a[3]), arg_f(&a[4])];
                    let ms = if animate { a[5].as_i64().unwrap_or(0).max(0) as u64 } else { 0 };
                    an.start(w, to, Duration::from_millis(ms), easing);
                    CallOutcome::Accepted(vec![])
                },
            )?;
        }
        Ok(me)
    }
}

impl Drop for WindowBehaviours {
    fn drop(&mut self) {
        for m in METHODS {
            let _ = self.ds.unpublish_method(self.display, m);
        }
    }
}
