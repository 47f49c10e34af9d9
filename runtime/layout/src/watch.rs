//! Watches: `when COND for HOLD then ACTIONS`. The hold time is a DataServer delayed call,
//! never polling; with nothing changing, a watch costs nothing.
//!
//! - Edge-triggered by default: the actions run once when the condition has held for the
//!   hold time; the watch is then *active* until the condition stops holding (or, with
//!   `clear when C`, until C holds: hysteresis), and only then can fire again.
//! - Level-triggered with `repeat every T`: while active, the actions run again every T.
//! - `snooze(ms)` on the watch's object (`root.operator.watches.<name>`) suppresses firing
//!   until the time is up; then, if the condition still holds, it fires.

use crate::actions::{ActionCtx, CompiledAction, compile_actions, operator_child, run_actions};
use crate::graph::{Builder, FnRef, Shared, State, Target};
use crate::lower::Scope;
use mocu_dataserver::{CallOutcome, MethodSpec, ObjectInfo, ParamSpec};
use mocu_jit as jit;
use mocu_value::{Guid, Value, ValueKind};
use std::sync::Arc;
use std::time::{Duration, Instant};

#[derive(Clone, Debug)]
pub(crate) struct CompiledWatch {
    name: String,
    func: FnRef,
    has_clear: bool,
    hold: Option<Duration>,
    repeat: Option<Duration>,
    actions: Vec<CompiledAction>,
}

pub(crate) fn compile_watch(
    b: &mut Builder,
    w: &mocu_language::program::Watch,
    screen: (f64, f64),
) -> Result<CompiledWatch, crate::graph::LoadError> {
    let err = |e: crate::lower::LowerError| {
        crate::graph::LoadError::Lower(format!("watch `{}`: {e}", w.name))
    };
    let mut lw = b.lowerer(Scope::Plain, screen);
    let mut outs = vec![lw.lower(&w.when.expr, jit::Ty::Bool).map_err(err)?];
    let clear = w.clear.as_ref();
    let has_clear = clear.is_some();
    if let Some(c) = clear {
        outs.push(lw.lower(&c.expr, jit::Ty::Bool).map_err(err)?);
    }
    let func = b.add(lw, outs);
    let ms = |x: Option<f64>| x.filter(|m| *m > 0.0).map(millis);
    Ok(CompiledWatch {
        name: w.name.clone(),
        func,
        has_clear,
        hold: ms(w.hold_ms),
        repeat: ms(w.repeat_ms),
        actions: compile_actions(b, &w.actions, screen).map_err(err)?,
    })
}

pub(crate) struct WatchRt {
    name: String,
    hold: Option<Duration>,
    repeat: Option<Duration>,
    has_clear: bool,
    actions: Vec<CompiledAction>,
    instance_object: Option<Guid>,
    cond: bool,
    holding: bool,
    active: bool,
    generation: u64,
    snoozed_until: Option<Instant>,
    fired: i64,
    cell: usize,
    alive: bool,
    pub(crate) object: Option<Guid>,
    pub(crate) alerts: Vec<Guid>,
}

pub(crate) fn publish_watch(
    sh: &Arc<Shared>,
    st: &mut State,
    w: CompiledWatch,
    instance: Option<usize>,
) -> usize {
    let idx = st.watches.len();
    let instance_object = instance.and_then(|i| st.instances[i].as_ref()).map(|i| i.object);
    let name = match instance_object.and_then(|o| sh.ds.info(o).ok()) {
        Some(info) => format!("{}@{}", w.name, info.name),
        None => w.name.clone(),
    };
    let object = operator_child(sh, "watches", "watches")
        .and_then(|p| sh.ds.create_object(p, ObjectInfo::new(&name, "watch")).ok());
    if let Some(o) = object {
        let _ = sh.ds.set(o, "state", Value::str("idle"));
        let _ = sh.ds.set(o, "fired", Value::Int(0));
        let weak = Arc::downgrade(sh);
        let _ = sh.ds.publish_method_fn(
            o,
            MethodSpec::new("snooze").param(ParamSpec::new("ms", ValueKind::Float)),
            move |args| {
                let Some(sh) = weak.upgrade() else {
                    return CallOutcome::Failed("unloaded".into());
                };
                snooze(&sh, idx, args[0].as_f64().unwrap_or(0.0));
                CallOutcome::Accepted(vec![])
            },
        );
    }
    let mut targets = vec![Target::WatchWhen(idx)];
    if w.has_clear {
        targets.push(Target::WatchClear(idx));
    }
    st.watches.push(WatchRt {
        name,
        hold: w.hold,
        repeat: w.repeat,
        has_clear: w.has_clear,
        actions: w.actions,
        instance_object,
        cond: false,
        holding: false,
        active: false,
        generation: 0,
        snoozed_until: None,
        fired: 0,
        cell: 0,
        alive: true,
        object,
        alerts: Vec::new(),
    });
    let cell = sh.add_cell(st, &w.func, targets, instance);
    st.watches[idx].cell = cell;
    idx
}

pub(crate) fn remove_watch(sh: &Arc<Shared>, st: &mut State, w: usize) {
    let rt = &mut st.watches[w];
    if !rt.alive {
        return;
    }
    rt.alive = false;
    rt.generation += 1;
    let cell = rt.cell;
    if let Some(o) = rt.object.take() {
        let _ = sh.ds.delete_object(o);
    }
    sh.remove_cell(st, cell);
}

fn set_state(sh: &Shared, rt: &WatchRt, state: &str) {
    if let Some(o) = rt.object {
        let _ = sh.ds.set(o, "state", Value::str(state));
    }
}

/// The `when` condition's new value.
pub(crate) fn on_when(sh: &Arc<Shared>, st: &mut State, w: usize, v: Option<bool>) {
    let rt = &mut st.watches[w];
    if !rt.alive {
        return;
    }
    rt.cond = v == Some(true);
    if rt.active {
        if !rt.has_clear && !rt.cond {
            clear(sh, st, w);
        }
        return;
    }
    match (rt.cond, rt.holding) {
        (true, false) => match rt.hold {
            Some(hold) => {
                rt.holding = true;
                rt.generation += 1;
                set_state(sh, rt, "holding");
                let generation = rt.generation;
                schedule(sh, w, generation, hold);
            }
            None => fire(sh, st, w),
        },
        (false, true) => {
            rt.holding = false;
            rt.generation += 1; // the pending hold timer now does nothing
            set_state(sh, rt, "idle");
        }
        _ => {}
    }
}

/// The `clear when` condition's new value.
pub(crate) fn on_clear(sh: &Arc<Shared>, st: &mut State, w: usize, v: Option<bool>) {
    if st.watches[w].alive && st.watches[w].active && v == Some(true) {
        clear(sh, st, w);
    }
}

fn schedule(sh: &Arc<Shared>, w: usize, generation: u64, after: Duration) {
    let weak = Arc::downgrade(sh);
    sh.ds.run_after(after, Some(&sh.exec), move || {
        let Some(sh) = weak.upgrade() else { return };
        let mut st = sh.state.lock();
        if st.closed || st.watches[w].generation != generation || !st.watches[w].alive {
            return;
        }
        let rt = &mut st.watches[w];
        if rt.active {
            // A repeat of a level-triggered watch.
            fire(&sh, &mut st, w);
        } else if rt.cond {
            rt.holding = false;
            fire(&sh, &mut st, w);
        }
    });
}

fn fire(sh: &Arc<Shared>, st: &mut State, w: usize) {
    let rt = &mut st.watches[w];
    if let Some(until) = rt.snoozed_until {
        let now = sh.ds.now();
        if until > now {
            set_state(sh, rt, "snoozed");
            rt.generation += 1;
            let generation = rt.generation;
            rt.holding = true;
            schedule(sh, w, generation, until - now);
            return;
        }
        rt.snoozed_until = None;
    }
    rt.active = true;
    rt.fired += 1;
    set_state(sh, rt, "active");
    if let Some(o) = rt.object {
        let _ = sh.ds.set(o, "fired", Value::Int(rt.fired));
    }
    sh.sink.record("watch", &[("name", Value::str(&rt.name)), ("state", Value::str("fired"))]);
    if let Some(every) = rt.repeat {
        rt.generation += 1;
        schedule(sh, w, rt.generation, every);
    }
    // Actions read the world and may call methods: run them after this evaluation, outside
    // the layout's lock.
    let acts = rt.actions.clone();
    let cx = ActionCtx { instance_object: rt.instance_object, ..ActionCtx::default() };
    let weak = Arc::downgrade(sh);
    sh.exec.spawn(move || {
        let Some(sh) = weak.upgrade() else { return };
        let alerts = run_actions(&sh, &acts, cx);
        let mut st = sh.state.lock();
        if let Some(rt) = st.watches.get_mut(w) {
            rt.alerts.extend(alerts);
        }
    });
}

fn clear(sh: &Arc<Shared>, st: &mut State, w: usize) {
    let rt = &mut st.watches[w];
    rt.active = false;
    rt.holding = false;
    rt.generation += 1;
    set_state(sh, rt, "idle");
    for a in &rt.alerts {
        if sh.ds.try_get(*a, "active".into()) == Some(Value::Bool(true)) {
            let _ = sh.ds.set(*a, "active", Value::Bool(false));
            let text = sh.ds.try_get(*a, "text".into()).unwrap_or(Value::str(""));
            sh.sink.record("alert_cleared", &[("watch", Value::str(&rt.name)), ("text", text)]);
        }
    }
    sh.sink.record("watch", &[("name", Value::str(&rt.name)), ("state", Value::str("cleared"))]);
    // With `clear when`, a condition that still holds may fire again later.
    if rt.cond && rt.has_clear {
        on_when(sh, st, w, Some(true));
    }
}

fn snooze(sh: &Arc<Shared>, w: usize, ms: f64) {
    let mut st = sh.state.lock();
    let Some(rt) = st.watches.get_mut(w) else { return };
    let d = millis(ms);
    let now = sh.ds.now();
    rt.snoozed_until = Some(now.checked_add(d).or_else(|| now.checked_add(FOREVER)).unwrap_or(now));
    if rt.active && rt.repeat.is_some() {
        rt.generation += 1; // stops repeating until the snooze is over
        let generation = rt.generation;
        schedule(sh, w, generation, d);
    }
    set_state(sh, rt, "snoozed");
    sh.sink.record("watch", &[("name", Value::str(&rt.name)), ("state", Value::str("snoozed"))]);
}

/// How long "for ever" is when a snooze does not fit the clock (`snooze(inf)`).
const FOREVER: Duration = Duration::from_secs(100 * 365 * 24 * 3600);

/// Milliseconds as a duration, saturating: negative or NaN is zero, too large (infinity
/// included) is `Duration::MAX` (the DataServer clamps such delays).
fn millis(ms: f64) -> Duration {
    if ms.is_nan() || ms <= 0.0 {
        return Duration::ZERO;
    }
    Duration::try_from_secs_f64(ms / 1000.0).unwrap_or(Duration::MAX)
}
