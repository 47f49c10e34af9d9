//! Actions (`set`, `call`, `swap`, `show`, `hide`, `alert`) and their control feedback.
//!
//! Every call shows pending, then its outcome, on the control that issued it (`feedback`
//! and `feedback_reason` properties of the widget), in `root.operator.feedback`, and in
//! the event log. A refused write is feedback, never a crash. A `set` of a property another
//! process owns (an object publishing `write_at_owner`, a mirror of another site's vehicle)
//! is sent there instead of written here: it shows pending, then the owner's outcome, as a
//! call does; the new value appears when the owner's change is replicated back.

use crate::graph::{Builder, FnRef, Shared, State, eval_once, resolve};
use crate::lower::{Base, LowerError, Lowerer, Scope, value_ty};
use mocu_dataserver::{CallOutcome, DataServer, MethodSpec, ObjectInfo, ParamSpec, WRITE_AT_OWNER};
use mocu_jit as jit;
use mocu_language::program::{Action, Binding, SelectTarget, Shaping};
use mocu_value::{Guid, Value, ValueKind};
use std::sync::Arc;

#[derive(Clone, Debug)]
pub(crate) enum CompiledAction {
    Set {
        base: Base,
        objects: Vec<String>,
        property: String,
        func: FnRef,
    },
    /// `objects[i]`: argument `i` is a bare path that may name an object (passed as its GUID).
    Call {
        base: Base,
        objects: Vec<String>,
        method: String,
        func: FnRef,
        args: Vec<ArgObject>,
    },
    Swap {
        a: String,
        b: String,
        ms: f64,
    },
    Show(String),
    Hide(String),
    Alert {
        level: String,
        func: FnRef,
    },
    Mode(String),
    Select(Select),
    /// Acknowledge every alert (the runtime's own Escape / `select` bindings).
    Acknowledge,
    /// `#js: { … }`: see `scripts.rs`.
    Script(Arc<crate::scripts::ScriptAction>),
}

#[derive(Clone, Debug)]
pub(crate) enum Select {
    Next,
    Prev,
    Object { base: Base, objects: Vec<String> },
}

pub(crate) fn compile_actions(
    b: &mut Builder,
    actions: &[Action],
    screen: (f64, f64),
) -> Result<Vec<CompiledAction>, LowerError> {
    let mut out = Vec::new();
    for a in actions {
        out.push(match a {
            Action::Set { target, value, .. } => {
                let mut lw = Lowerer::new(Scope::Plain, screen);
                let (base, mut objects) = lw.path_names(target)?;
                let property = objects
                    .pop()
                    .ok_or_else(|| LowerError(format!("`set {target}` names no property")))?;
                let ty = value_ty(&value.expr.ty).unwrap_or(jit::Ty::Num);
                let e = lw.lower(&value.expr, ty)?;
                CompiledAction::Set { base, objects, property, func: b.add(lw, vec![e]) }
            }
            Action::Call { target, args, .. } => {
                let mut lw = Lowerer::new(Scope::Plain, screen);
                let (base, mut objects) = lw.path_names(target)?;
                let method = objects
                    .pop()
                    .ok_or_else(|| LowerError(format!("`call {target}` names no method")))?;
                let mut outs = Vec::new();
                let mut arg_objects = Vec::new();
                for a in args {
                    arg_objects.push(arg_object(&mut lw, &a.expr)?);
                    let ty = value_ty(&a.expr.ty).unwrap_or(jit::Ty::Num);
                    outs.push(match &arg_objects[arg_objects.len() - 1] {
                        // An object has no value to compute: its GUID is looked up at the call.
                        Some(_)
                            if matches!(
                                a.expr.ty.kind,
                                mocu_language::types::TypeKind::Object { .. }
                            ) =>
                        {
                            jit::Expr::Absent(jit::Ty::Num)
                        }
                        _ => lw.lower(&a.expr, ty)?,
                    });
                }
                let func = b.add(lw, outs);
                CompiledAction::Call { base, objects, method, func, args: arg_objects }
            }
            Action::Swap { a, b: w, duration_ms, .. } => {
                CompiledAction::Swap { a: a.clone(), b: w.clone(), ms: *duration_ms }
            }
            Action::Show { window, .. } => CompiledAction::Show(window.clone()),
            Action::Hide { window, .. } => CompiledAction::Hide(window.clone()),
            Action::Alert { level, message, .. } => {
                let mut lw = Lowerer::new(Scope::Plain, screen);
                let e = lw.lower(&message.expr, jit::Ty::Str)?;
                CompiledAction::Alert { level: level.clone(), func: b.add(lw, vec![e]) }
            }
            Action::Mode { mode, .. } => CompiledAction::Mode(mode.clone()),
            Action::Script { engine, body, origin, .. } => CompiledAction::Script(
                crate::scripts::ScriptAction::new(engine, body, origin.as_ref()),
            ),
            Action::Select { target, .. } => CompiledAction::Select(match target {
                SelectTarget::Next => Select::Next,
                SelectTarget::Prev => Select::Prev,
                SelectTarget::Object(p) => {
                    let (base, objects) = Lowerer::new(Scope::Plain, screen).path_names(p)?;
                    Select::Object { base, objects }
                }
            }),
        });
    }
    Ok(out)
}

/// Who or what triggered actions.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct ActionCtx {
    pub(crate) instance_object: Option<Guid>,
    pub(crate) self_obj: Option<Guid>,
    pub(crate) input: Option<f64>,
    /// The widget that issued them (its feedback properties show the outcome).
    pub(crate) origin: Option<Guid>,
}

/// `root.operator.<name>`, created when first needed.
pub(crate) fn operator_child(sh: &Shared, name: &str, kind: &str) -> Option<Guid> {
    let op = crate::graph::ensure_object(&sh.ds, Guid::ROOT, "operator", "operator").ok()?;
    crate::graph::ensure_object(&sh.ds, op, name, kind).ok()
}

/// Whether `obj`'s properties are owned by another process: a write goes there.
fn owned_elsewhere(ds: &DataServer, obj: Guid) -> bool {
    ds.methods(obj).is_ok_and(|ms| ms.iter().any(|m| m.name.as_str() == WRITE_AT_OWNER))
}

/// Shows a call's (or a write sent to its owner's) outcome when it arrives, as
/// [`feedback`] and in the event log.
fn outcome_feedback(
    sh: &Arc<Shared>,
    origin: Option<Guid>,
    text: String,
) -> impl FnOnce(CallOutcome) + Send + 'static {
    let weak = Arc::downgrade(sh);
    move |outcome: CallOutcome| {
        let Some(sh) = weak.upgrade() else { return };
        let reason = match &outcome {
            CallOutcome::Refused(r) | CallOutcome::Failed(r) => r.clone(),
            CallOutcome::Accepted(_) => String::new(),
            other => other.to_string(),
        };
        feedback(&sh, origin, &text, outcome.label(), &reason);
        sh.sink.record(
            "feedback",
            &[
                ("target", Value::str(&text)),
                ("outcome", Value::str(outcome.label())),
                ("reason", Value::str(&reason)),
            ],
        );
    }
}

/// Shows a call's state on the issuing control and in `root.operator.feedback`; a call
/// that did not succeed is also an alert (`source` `command`), so the operator sees it
/// whatever the layout shows.
fn feedback(sh: &Arc<Shared>, origin: Option<Guid>, target: &str, state: &str, reason: &str) {
    if crate::alerts::is_failure(state) {
        let short = target.strip_prefix("root.").unwrap_or(target);
        let short = short.strip_prefix("vehicles.").unwrap_or(short);
        let what = state.replace('_', " ");
        let text = if reason.is_empty() {
            format!("{short}: {what}")
        } else {
            format!("{short}: {what} — {reason}")
        };
        crate::alerts::raise(sh, "warning", &text, "command");
    }
    let ds = &sh.ds;
    if let Some(w) = origin {
        let _ = ds.set(w, "feedback", Value::str(state));
        let _ = ds.set(w, "feedback_reason", Value::str(reason));
    }
    if let Some(f) = operator_child(sh, "feedback", "feedback") {
        let _ = ds.set(f, "target", Value::str(target));
        let _ = ds.set(f, "state", Value::str(state));
        let _ = ds.set(f, "reason", Value::str(reason));
        // Written last, and never twice the same: its change marks a complete record (the
        // toast list follows it), even when a call is answered at the instant it was made
        // (a clock that moves in steps: headless `--frames`, replay).
        let last = ds.try_get(f, "time".into()).and_then(|v| v.as_f64()).unwrap_or(0.0);
        let now = ds.wall_secs();
        let time = if now > last { now } else { last + 1e-6 };
        let _ = ds.set(f, "time", Value::Float(time));
    }
}

/// Runs actions now, on the calling thread; returns the alert objects it raised.
pub(crate) fn run_actions(
    sh: &Arc<Shared>,
    actions: &[CompiledAction],
    cx: ActionCtx,
) -> Vec<Guid> {
    let mut alerts = Vec::new();
    for a in actions {
        match a {
            CompiledAction::Set { base, objects, property, func } => {
                let value =
                    eval_once(sh, func, cx.instance_object, cx.self_obj, cx.input).remove(0);
                let text = format!("{}.{property}", target_text(sh, base, objects, cx));
                let mut at_owner = None;
                let outcome =
                    match (start(sh, base, cx).and_then(|s| resolve(&sh.ds, s, objects)), &value) {
                        (_, None) => Err("the value is absent (no data)".to_string()),
                        (None, _) => Err(format!(
                            "`{}` does not exist (yet)",
                            target_text(sh, base, objects, cx)
                        )),
                        (Some(obj), Some(_)) if owned_elsewhere(&sh.ds, obj) => {
                            at_owner = Some(obj);
                            Ok(())
                        }
                        (Some(obj), Some(v)) => {
                            sh.ds.set(obj, property.as_str(), v.clone()).map_err(|e| e.to_string())
                        }
                    };
                let v = value.unwrap_or(Value::str("absent"));
                sh.sink.record(
                    "action",
                    &[
                        ("kind", Value::str("set")),
                        ("target", Value::str(&text)),
                        ("value", v.clone()),
                    ],
                );
                if let Some(obj) = at_owner {
                    feedback(sh, cx.origin, &text, "pending", "");
                    let args = vec![Value::str(property), v];
                    sh.ds.call(
                        obj,
                        WRITE_AT_OWNER,
                        args,
                        None,
                        outcome_feedback(sh, cx.origin, text.clone()),
                    );
                }
                if let Err(why) = outcome {
                    feedback(sh, cx.origin, &text, "refused", &why);
                    sh.sink.record(
                        "feedback",
                        &[
                            ("target", Value::str(&text)),
                            ("outcome", Value::str("refused")),
                            ("reason", Value::str(&why)),
                        ],
                    );
                }
            }
            CompiledAction::Call { base, objects, method, func, args: arg_objects } => {
                let mut args = eval_once(sh, func, cx.instance_object, cx.self_obj, cx.input);
                for (a, o) in args.iter_mut().zip(arg_objects) {
                    if let Some((b, names)) = o
                        && let Some(g) = start(sh, b, cx).and_then(|s| resolve(&sh.ds, s, names))
                    {
                        *a = Some(Value::Guid(g));
                    }
                }
                let text = format!("{}.{method}", target_text(sh, base, objects, cx));
                sh.sink.record(
                    "action",
                    &[("kind", Value::str("call")), ("target", Value::str(&text))],
                );
                let obj = start(sh, base, cx).and_then(|s| resolve(&sh.ds, s, objects));
                let absent = args.iter().position(|a| a.is_none());
                let (Some(obj), None) = (obj, absent) else {
                    let why = match absent {
                        Some(i) => format!("argument {} is absent (no data)", i + 1),
                        None => {
                            format!("`{}` does not exist (yet)", target_text(sh, base, objects, cx))
                        }
                    };
                    feedback(sh, cx.origin, &text, "failed", &why);
                    sh.sink.record(
                        "feedback",
                        &[
                            ("target", Value::str(&text)),
                            ("outcome", Value::str("failed")),
                            ("reason", Value::str(&why)),
                        ],
                    );
                    continue;
                };
                let args = fit_args(&sh.ds, obj, method, args.into_iter().flatten().collect());
                sh.sink.record(
                    "call",
                    &[("target", Value::str(&text)), ("args", Value::list(args.clone()))],
                );
                feedback(sh, cx.origin, &text, "pending", "");
                sh.ds.call(obj, method.as_str(), args, None, outcome_feedback(sh, cx.origin, text));
            }
            CompiledAction::Swap { a, b, ms } => {
                sh.sink.record(
                    "action",
                    &[("kind", Value::str("swap")), ("a", Value::str(a)), ("b", Value::str(b))],
                );
                swap(sh, a, b, *ms);
            }
            CompiledAction::Show(w) | CompiledAction::Hide(w) => {
                let show = matches!(a, CompiledAction::Show(_));
                let g = sh.state.lock().windows.get(w).copied();
                if let Some(g) = g {
                    let _ = sh.ds.set(g, "visible", Value::Bool(show));
                }
                let kind = if show { "show" } else { "hide" };
                sh.sink.record("action", &[("kind", Value::str(kind)), ("window", Value::str(w))]);
            }
            CompiledAction::Mode(mode) => {
                if let Some(op) = operator(sh) {
                    let _ = sh.ds.set(op, "mode", Value::str(mode));
                }
                sh.sink
                    .record("action", &[("kind", Value::str("mode")), ("mode", Value::str(mode))]);
            }
            CompiledAction::Select(target) => select(sh, target, cx),
            CompiledAction::Acknowledge => crate::alerts::acknowledge(sh, cx),
            CompiledAction::Script(s) => s.run(sh, cx),
            CompiledAction::Alert { level, func } => {
                let text = eval_once(sh, func, cx.instance_object, cx.self_obj, cx.input)
                    .remove(0)
                    .unwrap_or(Value::str("(no data)"));
                if let Some(g) = raise_alert(sh, level, &text.to_string()) {
                    alerts.push(g);
                }
            }
        }
    }
    alerts
}

/// A call argument that is a bare path to an object, or to something only the world
/// knows (`dynamic`): the object it names, if it names one when the call runs.
pub(crate) type ArgObject = Option<(Base, Vec<String>)>;

fn arg_object(lw: &mut Lowerer, e: &mocu_language::program::Expr) -> Result<ArgObject, LowerError> {
    use mocu_language::types::TypeKind;
    match (&e.node, &e.ty.kind) {
        (mocu_language::program::Node::Path(p), TypeKind::Object { .. } | TypeKind::Dynamic) => {
            Ok(Some(lw.path_names(p)?))
        }
        _ => Ok(None),
    }
}

/// The arguments as the method's parameters take them: the language's numbers are floats,
/// so a whole number goes to an `int` parameter as an int (anything else is left for the
/// DataServer to refuse with its reason).
fn fit_args(
    ds: &mocu_dataserver::DataServer,
    obj: Guid,
    method: &str,
    mut args: Vec<Value>,
) -> Vec<Value> {
    let Ok(specs) = ds.methods(obj) else { return args };
    let Some(spec) = specs.iter().find(|m| m.name.as_str() == method) else { return args };
    for (a, p) in args.iter_mut().zip(spec.params.iter()) {
        if let (Some(ValueKind::Int), Value::Float(f)) = (p.kind, &*a)
            && f.fract() == 0.0
            && f.abs() < 9.0e15
        {
            *a = Value::Int(*f as i64);
        }
    }
    args
}

fn start(sh: &Shared, base: &Base, cx: ActionCtx) -> Option<Guid> {
    match base {
        Base::Root => Some(Guid::ROOT),
        Base::Var(_) => cx.instance_object,
        Base::SelfObject => cx.self_obj,
        Base::Selected => selected_object(&sh.ds),
    }
}

fn operator(sh: &Shared) -> Option<Guid> {
    crate::graph::ensure_object(&sh.ds, Guid::ROOT, "operator", "operator").ok()
}

/// The object whose GUID is in `root.operator.selected`, if it still exists.
pub(crate) fn selected_object(ds: &mocu_dataserver::DataServer) -> Option<Guid> {
    let op = ds.find_child(Guid::ROOT, "operator").ok()??;
    let g = ds.try_get(op, "selected".into())?.as_guid()?;
    ds.exists(g).then_some(g)
}

/// `select next|prev|path`: writes `root.operator.selected` (a GUID) and
/// `root.operator.selected_name`. Next and previous step through `root.vehicles` in order,
/// wrapping around; with nothing selected, next is the first and previous the last.
fn select(sh: &Arc<Shared>, target: &Select, cx: ActionCtx) {
    let ds = &sh.ds;
    let current = selected_object(ds);
    let chosen = match target {
        Select::Object { base, objects } => {
            start(sh, base, cx).and_then(|s| resolve(ds, s, objects))
        }
        step => {
            let list =
                ds.resolve(&["vehicles"]).and_then(|v| ds.children(v).ok()).unwrap_or_default();
            let n = list.len();
            let at = current.and_then(|c| list.iter().position(|g| *g == c));
            let i = match (step, at) {
                (_, _) if n == 0 => None,
                (Select::Next, Some(i)) => Some((i + 1) % n),
                (Select::Next, None) => Some(0),
                (_, Some(i)) => Some((i + n - 1) % n),
                (_, None) => Some(n - 1),
            };
            i.map(|i| list[i])
        }
    };
    let text = chosen.map(|g| ds.path_text(g));
    sh.sink.record(
        "action",
        &[
            ("kind", Value::str("select")),
            ("target", Value::str(text.as_deref().unwrap_or("nothing"))),
        ],
    );
    let (Some(g), Some(op)) = (chosen, operator(sh)) else {
        let why = "there is nothing to select".to_string();
        feedback(sh, cx.origin, "select", "refused", &why);
        sh.sink.record(
            "feedback",
            &[
                ("target", Value::str("select")),
                ("outcome", Value::str("refused")),
                ("reason", Value::str(&why)),
            ],
        );
        return;
    };
    let name = ds.info(g).map(|i| i.name.to_string()).unwrap_or_default();
    let _ = ds.set(op, "selected", Value::Guid(g));
    let _ = ds.set(op, "selected_name", Value::str(&name));
}

fn target_text(sh: &Shared, base: &Base, objects: &[String], cx: ActionCtx) -> String {
    let head = match (start(sh, base, cx), base) {
        (Some(g), _) => sh.ds.path_text(g),
        (None, Base::Selected) => "selected (nothing selected)".into(),
        (None, _) => "self".into(),
    };
    if objects.is_empty() { head } else { format!("{head}.{}", objects.join(".")) }
}

/// Exchanges two windows' places: animated by the window manager's `swap` method when one
/// is published on `root.display`, else at once.
fn swap(sh: &Arc<Shared>, a: &str, b: &str, ms: f64) {
    let (display, ga, gb) = {
        let st = sh.state.lock();
        (st.display, st.windows.get(a).copied(), st.windows.get(b).copied())
    };
    let args = vec![Value::str(a), Value::str(b), Value::Int(ms as i64)];
    let out =
        sh.ds.call_wait(display, "swap", args, Some(mocu_dataserver::CallOptions::immediate()));
    if out != CallOutcome::NoSuchMethod {
        return;
    }
    let (Some(ga), Some(gb)) = (ga, gb) else { return };
    for p in ["x", "y", "w", "h"] {
        let (va, vb) = (sh.ds.try_get(ga, p.into()), sh.ds.try_get(gb, p.into()));
        if let (Some(va), Some(vb)) = (va, vb) {
            let _ = sh.ds.set(ga, p, vb);
            let _ = sh.ds.set(gb, p, va);
        }
    }
}

/// Raises a layout's `alert` (see [`crate::alerts`]).
pub(crate) fn raise_alert(sh: &Arc<Shared>, level: &str, text: &str) -> Option<Guid> {
    crate::alerts::raise(sh, level, text, "layout")
}

/// Publishes each widget event (`press`, …) as a method of the widget object: whoever
/// handles the mouse calls `widget.press()`, knowing nothing of the layout.
pub(crate) fn publish_handlers(
    sh: &Arc<Shared>,
    widget: Guid,
    handlers: &[(String, Vec<CompiledAction>)],
    instance_object: Option<Guid>,
) {
    for (event, acts) in handlers {
        let weak = Arc::downgrade(sh);
        let acts = acts.clone();
        let _ = sh.ds.publish_method_fn(widget, MethodSpec::new(event), move |_| {
            let Some(sh) = weak.upgrade() else {
                return CallOutcome::Failed("the layout was unloaded".into());
            };
            let cx = ActionCtx { instance_object, origin: Some(widget), ..ActionCtx::default() };
            run_actions(&sh, &acts, cx);
            CallOutcome::Accepted(vec![])
        });
    }
}

/// What the input module needs to know of one binding: which input, which event, shaping,
/// mode and shift layer (a program [`Binding`] without its actions).
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
pub(crate) struct BindingSpec {
    device: String,
    kind: String,
    input: String,
    event: String,
    hold_ms: f64,
    mode: Option<String>,
    shift: bool,
    shift_input: Option<String>,
    shaping: Shaping,
}

/// The key a compiled binding is kept under: its [`BindingSpec`] as JSON text (the State
/// keeps `(String, actions)` pairs).
pub(crate) fn binding_key(b: &Binding) -> String {
    let spec = BindingSpec {
        device: b.device.clone(),
        kind: b.kind.clone(),
        input: b.input.clone(),
        event: b.event.clone(),
        hold_ms: b.hold_ms,
        mode: b.mode.clone(),
        shift: b.shift,
        shift_input: b.shift_input.clone(),
        shaping: b.shaping.clone(),
    };
    serde_json::to_string(&spec).unwrap_or_default()
}

/// The key of a plain (unshaped, every-mode) button or key binding the runtime adds itself.
pub(crate) fn button_key(device: &str, kind: &str, input: &str, event: &str) -> String {
    let spec = BindingSpec {
        device: device.into(),
        kind: kind.into(),
        input: input.into(),
        event: event.into(),
        hold_ms: 0.0,
        mode: None,
        shift: false,
        shift_input: None,
        shaping: Shaping::default(),
    };
    serde_json::to_string(&spec).unwrap_or_default()
}

/// Publishes the layout's input bindings as objects `root.display.bindings.b1…bN` (type
/// `binding`): `device`, `kind`, `input`, `event`, `hold_ms`, `mode`, `shift`,
/// `shift_input`, `deadzone`, `expo`, `scale`, `invert`, `rate`, `action` (what it does, in
/// a few words: `legend.rs`), then a method
/// `fire(value)` that runs the actions with `axis`/`delta` bound to the value, then
/// `ready = true`. When all are there, `revision` of `root.display.bindings` goes up: the
/// input module (or any other) rescans. The first mode declared becomes
/// `root.operator.mode` when none is set.
pub(crate) fn publish_bindings(sh: &Arc<Shared>, st: &mut State) {
    if st.bindings.is_empty() {
        return;
    }
    let Ok(obj) = crate::graph::ensure_object(&sh.ds, st.display, "bindings", "bindings") else {
        return;
    };
    let ds = &sh.ds;
    let mut first_mode = None;
    for (i, (key, acts)) in st.bindings.iter().enumerate() {
        let Ok(spec) = serde_json::from_str::<BindingSpec>(key) else { continue };
        let Ok(b) = ds.create_object(obj, ObjectInfo::new(&format!("b{}", i + 1), "binding"))
        else {
            continue;
        };
        let text = |v: &str| Value::str(v);
        let _ = ds.set(b, "device", text(&spec.device));
        let _ = ds.set(b, "kind", text(&spec.kind));
        let _ = ds.set(b, "input", text(&spec.input));
        let _ = ds.set(b, "event", text(&spec.event));
        let _ = ds.set(b, "hold_ms", Value::Float(spec.hold_ms));
        let _ = ds.set(b, "mode", text(spec.mode.as_deref().unwrap_or("")));
        let _ = ds.set(b, "shift", Value::Bool(spec.shift));
        let _ = ds.set(b, "shift_input", text(spec.shift_input.as_deref().unwrap_or("")));
        let _ = ds.set(b, "deadzone", Value::Float(spec.shaping.deadzone));
        let _ = ds.set(b, "expo", Value::Float(spec.shaping.expo));
        let _ = ds.set(b, "scale", Value::Float(spec.shaping.scale));
        let _ = ds.set(b, "invert", Value::Bool(spec.shaping.invert));
        let _ = ds.set(b, "rate", Value::Float(spec.shaping.rate));
        let _ = ds.set(b, "action", text(&crate::legend::describe(acts)));
        if first_mode.is_none() {
            first_mode = spec.mode.clone();
        }
        let weak = Arc::downgrade(sh);
        let acts = acts.clone();
        let fire = MethodSpec::new("fire").param(ParamSpec::new("value", ValueKind::Float));
        let _ = ds.publish_method_fn(b, fire, move |args| {
            let Some(sh) = weak.upgrade() else {
                return CallOutcome::Failed("the layout was unloaded".into());
            };
            let cx = ActionCtx { input: args[0].as_f64(), origin: Some(b), ..ActionCtx::default() };
            run_actions(&sh, &acts, cx);
            CallOutcome::Accepted(vec![])
        });
        let _ = ds.set(b, "ready", Value::Bool(true));
    }
    if let (Some(m), Some(op)) = (first_mode, operator(sh))
        && ds.try_get(op, "mode".into()).is_none()
    {
        let _ = ds.set(op, "mode", Value::str(&m));
    }
    let rev = ds.try_get(obj, "revision".into()).and_then(|v| v.as_f64()).unwrap_or(0.0);
    let _ = ds.set(obj, "revision", Value::Float(rev + 1.0));
    st.owned_push(obj);
}

impl State {
    pub(crate) fn owned_push(&mut self, g: Guid) {
        self.owned_objects().push(g);
    }
}
