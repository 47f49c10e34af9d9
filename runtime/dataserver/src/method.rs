//! Methods on objects: the paper's answer to control feedback (§3.2). A call is Accepted,
//! Refused with the module's reason, Failed, TimedOut, or finds no such object or method.

use crate::call::Call;
use crate::error::{DsError, ObjRef};
use crate::executor::{Executor, Target};
use crate::server::{DataServer, obj_ref_of};
use mocu_value::{Guid, PropName, Value, ValueKind};
use std::fmt;
use std::sync::Arc;
use std::time::Duration;

/// The method an object publishes when its properties are owned by another process (a
/// mirror of another site's object, docs/distribution.md "Forwarded writes"):
/// `write_at_owner(name, value)` writes there, and a writer that finds it calls it instead
/// of writing the local copy. The outcome is the owner's checked write (accepted, or refused
/// with its reason); the value comes back through replication.
pub const WRITE_AT_OWNER: &str = "write_at_owner";

/// One parameter (or result) of a method.
#[derive(Clone, Debug, PartialEq)]
pub struct ParamSpec {
    pub name: Arc<str>,
    /// `None`: any value.
    pub kind: Option<ValueKind>,
    pub units: Option<Arc<str>>,
}

impl ParamSpec {
    pub fn new(name: &str, kind: ValueKind) -> ParamSpec {
        ParamSpec { name: name.into(), kind: Some(kind), units: None }
    }

    pub fn any(name: &str) -> ParamSpec {
        ParamSpec { name: name.into(), kind: None, units: None }
    }
}

/// Where and when a call runs.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CallMode {
    /// On the caller's thread, now (for thread-sensitive work such as painting).
    Immediate,
    /// On a DataServer worker (or the method owner's serial executor), after `delay`.
    Queued,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct CallOptions {
    pub mode: CallMode,
    /// Run the call this long from now (implies `Queued`).
    pub delay: Duration,
    /// Give up waiting for an answer after this long: the outcome is `TimedOut`.
    pub timeout: Option<Duration>,
}

impl Default for CallOptions {
    fn default() -> Self {
        CallOptions { mode: CallMode::Queued, delay: Duration::ZERO, timeout: None }
    }
}

impl CallOptions {
    pub fn immediate() -> CallOptions {
        CallOptions { mode: CallMode::Immediate, ..CallOptions::default() }
    }

    pub fn queued() -> CallOptions {
        CallOptions::default()
    }

    pub fn delayed(delay: Duration) -> CallOptions {
        CallOptions { delay, ..CallOptions::default() }
    }

    pub fn timeout(mut self, t: Duration) -> CallOptions {
        self.timeout = Some(t);
        self
    }
}

/// What a method publishes about itself.
#[derive(Clone, Debug, PartialEq)]
pub struct MethodSpec {
    pub name: PropName,
    pub params: Vec<ParamSpec>,
    pub results: Vec<ParamSpec>,
    pub defaults: CallOptions,
    pub description: Option<Arc<str>>,
    /// Queued calls run one at a time in the order they were made, even when the handler is
    /// published without a serial executor of its own (the DataServer gives it one): for
    /// event streams such as pointer and key input, where a press overtaken by its release
    /// would be a different gesture.
    pub ordered: bool,
    /// The method takes any arguments, unchecked (`params` only describes them): a stream
    /// tap that forwards whatever its listener sends, whatever the sender's message is.
    pub any_args: bool,
}

impl MethodSpec {
    pub fn new(name: &str) -> MethodSpec {
        MethodSpec {
            name: PropName::new(name),
            params: Vec::new(),
            results: Vec::new(),
            defaults: CallOptions::default(),
            description: None,
            ordered: false,
            any_args: false,
        }
    }

    pub fn param(mut self, p: ParamSpec) -> MethodSpec {
        self.params.push(p);
        self
    }

    pub fn result(mut self, p: ParamSpec) -> MethodSpec {
        self.results.push(p);
        self
    }

    pub fn defaults(mut self, o: CallOptions) -> MethodSpec {
        self.defaults = o;
        self
    }

    /// Calls to this method run in the order they were made (see [`MethodSpec::ordered`]).
    pub fn ordered(mut self) -> MethodSpec {
        self.ordered = true;
        self
    }

    /// Calls to this method pass any arguments through unchecked (see [`MethodSpec::any_args`]).
    pub fn any_args(mut self) -> MethodSpec {
        self.any_args = true;
        self
    }

    pub fn describe(mut self, d: &str) -> MethodSpec {
        self.description = Some(d.into());
        self
    }
}

/// The outcome of a method call.
#[derive(Clone, Debug, PartialEq)]
pub enum CallOutcome {
    Accepted(Vec<Value>),
    /// The module declined, with its reason ("engine already running").
    Refused(String),
    /// The call could not be carried out (bad arguments, a lost link, a panic).
    Failed(String),
    NoSuchMethod,
    NoSuchObject,
    /// No answer within the call's timeout.
    TimedOut,
}

impl CallOutcome {
    pub fn is_accepted(&self) -> bool {
        matches!(self, CallOutcome::Accepted(_))
    }

    /// A stable one-word name (`accepted`, `refused`, …) for logs and displays.
    pub fn label(&self) -> &'static str {
        match self {
            CallOutcome::Accepted(_) => "accepted",
            CallOutcome::Refused(_) => "refused",
            CallOutcome::Failed(_) => "failed",
            CallOutcome::NoSuchMethod => "no_such_method",
            CallOutcome::NoSuchObject => "no_such_object",
            CallOutcome::TimedOut => "timed_out",
        }
    }
}

impl fmt::Display for CallOutcome {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            CallOutcome::Accepted(r) if r.is_empty() => f.write_str("accepted"),
            CallOutcome::Accepted(r) => write!(f, "accepted: {r:?}"),
            CallOutcome::Refused(why) => write!(f, "refused: {why}"),
            CallOutcome::Failed(why) => write!(f, "failed: {why}"),
            CallOutcome::NoSuchMethod => f.write_str("no such method"),
            CallOutcome::NoSuchObject => f.write_str("no such object"),
            CallOutcome::TimedOut => f.write_str("timed out"),
        }
    }
}

pub(crate) type Handler = Arc<dyn Fn(Call) + Send + Sync + 'static>;

pub(crate) struct Method {
    pub(crate) spec: MethodSpec,
    pub(crate) handler: Handler,
    executor: Option<Executor>,
}

impl Method {
    /// Where queued calls of this method run.
    pub(crate) fn target(&self, pool: &Arc<crate::executor::Pool>) -> Target {
        match &self.executor {
            Some(ex) => Target::Serial(ex.clone()),
            None => Target::Pool(pool.clone()),
        }
    }
}

impl DataServer {
    /// Publishes a method under an object. The handler answers through `call.responder`
    /// (now, or later from another thread: a protocol module answers when the vehicle
    /// acknowledges).
    pub fn publish_method(
        &self,
        guid: Guid,
        spec: MethodSpec,
        handler: impl Fn(Call) + Send + Sync + 'static,
    ) -> Result<(), DsError> {
        self.publish_method_with(guid, spec, None, Arc::new(handler))
    }

    /// Like `publish_method`, but queued calls run on the module's serial executor.
    pub fn publish_method_on(
        &self,
        executor: &Executor,
        guid: Guid,
        spec: MethodSpec,
        handler: impl Fn(Call) + Send + Sync + 'static,
    ) -> Result<(), DsError> {
        self.publish_method_with(guid, spec, Some(executor.clone()), Arc::new(handler))
    }

    /// Publishes a method whose handler answers at once with an outcome.
    pub fn publish_method_fn(
        &self,
        guid: Guid,
        spec: MethodSpec,
        handler: impl Fn(&[Value]) -> CallOutcome + Send + Sync + 'static,
    ) -> Result<(), DsError> {
        self.publish_method(guid, spec, move |call: Call| {
            let outcome = handler(&call.args);
            call.responder.reply(outcome);
        })
    }

    fn publish_method_with(
        &self,
        guid: Guid,
        spec: MethodSpec,
        executor: Option<Executor>,
        handler: Handler,
    ) -> Result<(), DsError> {
        let o = self.object(guid)?;
        let mut os = o.state.write();
        if !os.alive {
            return Err(DsError::NoSuchObject { object: ObjRef::unnamed(guid) });
        }
        if os.methods.contains_key(&spec.name) {
            return Err(DsError::MethodExists { object: obj_ref_of(guid, &os), method: spec.name });
        }
        // An ordered method gets a serial executor of its own, the same one each time it is
        // published again under that name: calls still queued for the earlier publication
        // keep their place, before the calls made since.
        let executor = match executor {
            None if spec.ordered => Some(
                os.ordered_executors
                    .entry(spec.name)
                    .or_insert_with(|| self.serial_executor())
                    .clone(),
            ),
            e => e,
        };
        os.methods.insert(spec.name, Arc::new(Method { spec, handler, executor }));
        Ok(())
    }

    pub fn unpublish_method(&self, guid: Guid, name: impl Into<PropName>) -> Result<(), DsError> {
        let o = self.object(guid)?;
        let removed = o.state.write().methods.remove(&name.into());
        // The handler is the module's: it is dropped once the object's lock is released,
        // so its `Drop` may use the DataServer (docs/dataserver.md "Dropping module state").
        drop(removed);
        Ok(())
    }

    /// The methods of an object, sorted by name.
    pub fn methods(&self, guid: Guid) -> Result<Vec<MethodSpec>, DsError> {
        let o = self.object(guid)?;
        let mut v: Vec<MethodSpec> =
            o.state.read().methods.values().map(|m| m.spec.clone()).collect();
        v.sort_by(|a, b| a.name.as_str().cmp(b.name.as_str()));
        Ok(v)
    }
}

pub(crate) fn check_args(spec: &MethodSpec, args: Vec<Value>) -> Result<Arc<[Value]>, String> {
    if spec.any_args {
        return Ok(args.into());
    }
    if args.len() != spec.params.len() {
        let names: Vec<&str> = spec.params.iter().map(|p| &*p.name).collect();
        return Err(format!(
            "`{}` takes {} argument(s) ({}), got {}",
            spec.name,
            spec.params.len(),
            names.join(", "),
            args.len()
        ));
    }
    let mut out = Vec::with_capacity(args.len());
    for (p, a) in spec.params.iter().zip(args) {
        let a = match (p.kind, a) {
            (None, a) => a,
            (Some(ValueKind::Float), Value::Int(i)) => Value::Float(i as f64),
            (Some(k), a) if a.kind() == k => a,
            (Some(k), a) => {
                return Err(format!(
                    "argument `{}` of `{}` must be {k}, got {}",
                    p.name,
                    spec.name,
                    a.kind()
                ));
            }
        };
        out.push(a);
    }
    Ok(out.into())
}
