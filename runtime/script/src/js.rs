//! `#js:` — JavaScript on QuickJS-ng (rquickjs). The runtime has a memory limit and an
//! interrupt handler that stops a run past its operation budget; the context has no file,
//! network or module loader (QuickJS's `std`/`os` modules are not part of it). The API is
//! the global object `mocu` (`mocu.read(path)`).
//!
//! A script's text is compiled once as the body of a function, so an action's body runs
//! again on each event without being parsed again; callbacks the script hands to the API
//! are kept in a JavaScript map of the context (nothing JavaScript outlives the runtime).

use crate::api::{Api, CallbackId};
use crate::engine::{Engine, Instance, Limits};
use crate::error::{ApiError, ErrorKind, Location, ScriptError, Source};
use mocu_dataserver::{Guid, Value};
use rquickjs::context::EvalOptions;
use rquickjs::function::Opt;
use rquickjs::{Array, Context, Ctx, Exception, Function, Object, Runtime};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};

/// The JavaScript engine of the registry.
pub struct Js;

/// The file name QuickJS is given: positions in messages are found after it.
const FILE: &str = "<mocu-script>";
/// Where the callbacks live in the context.
const CALLBACKS: &str = "\u{0}mocu.callbacks";
/// QuickJS calls the interrupt handler about once per this many operations.
const OPS_PER_INTERRUPT: u64 = 10_000;

impl Engine for Js {
    fn prefix(&self) -> &'static str {
        "js"
    }

    fn extension(&self) -> &'static str {
        "js"
    }

    fn check(&self, source: &Source) -> Result<(), ScriptError> {
        let (rt, ctx) = bare(&Limits::default()).map_err(|e| setup(source, e))?;
        let r = ctx.with(|ctx| {
            compile(&ctx, source).map(|_| ()).map_err(|e| thrown(&ctx, source, e, false))
        });
        drop(ctx);
        drop(rt);
        r
    }

    fn load(
        &self,
        source: &Source,
        api: Api,
        limits: &Limits,
    ) -> Result<Box<dyn Instance>, ScriptError> {
        let (rt, ctx) = bare(limits).map_err(|e| setup(source, e))?;
        let budget = Arc::new(Budget::new(limits.operations));
        let b = budget.clone();
        rt.set_interrupt_handler(Some(Box::new(move || b.tick())));
        ctx.with(|ctx| {
            let store = rquickjs::Object::new(ctx.clone())?;
            ctx.globals().set(CALLBACKS, store)?;
            ctx.globals().set("mocu", api_object(&ctx, &api)?)?;
            Ok::<_, rquickjs::Error>(())
        })
        .map_err(|e| setup(source, e))?;
        ctx.with(|ctx| {
            let body = compile(&ctx, source).map_err(|e| thrown(&ctx, source, e, false))?;
            store(&ctx).and_then(|s| s.set(0u32, body)).map_err(|e| setup(source, e))
        })?;
        Ok(Box::new(JsInstance {
            ctx,
            rt,
            budget,
            source: source.clone(),
            memory_limit: limits.memory,
        }))
    }
}

/// The operation budget of one run, counted in interrupts.
struct Budget {
    ticks: AtomicU64,
    limit: u64,
    tripped: AtomicBool,
}

impl Budget {
    fn new(operations: u64) -> Budget {
        Budget {
            ticks: AtomicU64::new(0),
            limit: operations.div_ceil(OPS_PER_INTERRUPT).max(1),
            tripped: AtomicBool::new(false),
        }
    }

    /// Called by QuickJS; true stops the script.
    fn tick(&self) -> bool {
        let over = self.ticks.fetch_add(1, Ordering::Relaxed) + 1 > self.limit;
        if over {
            self.tripped.store(true, Ordering::Relaxed);
        }
        over
    }

    fn reset(&self) {
        self.ticks.store(0, Ordering::Relaxed);
        self.tripped.store(false, Ordering::Relaxed);
    }
}

struct JsInstance {
    // Dropped before the runtime.
    ctx: Context,
    rt: Runtime,
    budget: Arc<Budget>,
    source: Source,
    memory_limit: usize,
}

impl JsInstance {
    fn call(&self, key: CallbackId, args: &[Option<Value>], once: bool) -> Result<(), ScriptError> {
        self.budget.reset();
        let tripped = &self.budget.tripped;
        let r = self.ctx.with(|ctx| {
            let run = || -> rquickjs::Result<()> {
                let s = store(&ctx)?;
                let key = u32::try_from(key).unwrap_or(u32::MAX);
                let Some(f) = s.get::<_, Option<Function>>(key)? else { return Ok(()) };
                if once {
                    s.remove(key)?;
                }
                let mut a = rquickjs::function::Args::new(ctx.clone(), args.len());
                for v in args {
                    a.push_arg(to_js(&ctx, v.as_ref())?)?;
                }
                f.call_arg::<()>(a)
            };
            run().map_err(|e| thrown(&ctx, &self.source, e, tripped.load(Ordering::Relaxed)))
        });
        // Jobs the script queued (promise reactions) run under the same budget.
        while self.rt.is_job_pending() {
            if self.rt.execute_pending_job().is_err() {
                break;
            }
        }
        r.map_err(|mut e| {
            if e.kind == ErrorKind::Memory {
                e.message = format!("out of memory (limit {} KiB)", self.memory_limit >> 10);
            }
            e
        })
    }
}

impl Instance for JsInstance {
    fn run(&mut self) -> Result<(), ScriptError> {
        self.call(0, &[], false)
    }

    fn run_with(&mut self, vars: &[(&str, Option<Value>)]) -> Result<(), ScriptError> {
        self.ctx
            .with(|ctx| {
                for (name, v) in vars {
                    ctx.globals().set(*name, to_js(&ctx, v.as_ref())?)?;
                }
                Ok::<_, rquickjs::Error>(())
            })
            .map_err(|e| setup(&self.source, e))?;
        self.call(0, &[], false)
    }

    fn invoke(
        &mut self,
        callback: CallbackId,
        args: &[Option<Value>],
        once: bool,
    ) -> Result<(), ScriptError> {
        self.call(callback, args, once)
    }

    fn memory(&self) -> Option<usize> {
        usize::try_from(self.rt.memory_usage().memory_used_size).ok()
    }
}

fn bare(limits: &Limits) -> rquickjs::Result<(Runtime, Context)> {
    let rt = Runtime::new()?;
    rt.set_memory_limit(limits.memory);
    rt.set_max_stack_size(256 * 1024);
    let ctx = Context::full(&rt)?;
    Ok((rt, ctx))
}

/// The script's text as the body of a function. The wrapper's first line is its own, so
/// QuickJS's line L is the script's line L - 1.
fn compile<'js>(ctx: &Ctx<'js>, source: &Source) -> rquickjs::Result<Function<'js>> {
    let mut opts = EvalOptions::default();
    opts.filename = Some(FILE.to_string());
    opts.strict = false;
    ctx.eval_with_options(format!("(function () {{\n{}\n}})", source.text), opts)
}

fn store<'js>(ctx: &Ctx<'js>) -> rquickjs::Result<Object<'js>> {
    ctx.globals().get(CALLBACKS)
}

/// Keeps a callback in the context's map; its number for the API.
fn keep<'js>(ctx: &Ctx<'js>, f: Function<'js>) -> rquickjs::Result<CallbackId> {
    let s = store(ctx)?;
    let next: CallbackId = s.get::<_, Option<f64>>("next")?.unwrap_or(0.0) as CallbackId + 1;
    s.set("next", next as f64)?;
    s.set(u32::try_from(next).unwrap_or(u32::MAX), f)?;
    Ok(next)
}

/// The `mocu` object: the DataServer API.
fn api_object<'js>(ctx: &Ctx<'js>, api: &Api) -> rquickjs::Result<Object<'js>> {
    let m = Object::new(ctx.clone())?;
    let a = api.clone();
    m.set(
        "read",
        Function::new(ctx.clone(), move |ctx: Ctx<'js>, path: String| {
            let v = a.read(&path).map_err(|e| throw(&ctx, &e))?;
            to_js(&ctx, v.as_ref())
        })?,
    )?;
    let a = api.clone();
    m.set(
        "write",
        Function::new(ctx.clone(), move |ctx: Ctx<'js>, path: String, v: rquickjs::Value<'js>| {
            let v = from_js(&v)
                .map_err(|e| Exception::throw_type(&ctx, &format!("write `{path}`: {e}")))?;
            a.write(&path, v).map_err(|e| throw(&ctx, &e))
        })?,
    )?;
    let a = api.clone();
    m.set(
        "subscribe",
        Function::new(ctx.clone(), move |ctx: Ctx<'js>, path: String, f: Function<'js>| {
            let id = keep(&ctx, f)?;
            a.subscribe(&path, id).map_err(|e| throw(&ctx, &e))
        })?,
    )?;
    let a = api.clone();
    m.set(
        "call",
        Function::new(
            ctx.clone(),
            move |ctx: Ctx<'js>, path: String, args: Opt<Array<'js>>, f: Opt<Function<'js>>| {
                let mut values = Vec::new();
                if let Some(list) = args.0 {
                    for v in list.iter::<rquickjs::Value>() {
                        values.push(from_js(&v?).map_err(|e| Exception::throw_type(&ctx, &e))?);
                    }
                }
                let id = f.0.map(|f| keep(&ctx, f)).transpose()?;
                a.call(&path, values, id).map_err(|e| throw(&ctx, &e))
            },
        )?,
    )?;
    let a = api.clone();
    m.set(
        "create",
        Function::new(
            ctx.clone(),
            move |ctx: Ctx<'js>, parent: String, name: String, kind: String| {
                a.create(&parent, &name, &kind).map_err(|e| throw(&ctx, &e))
            },
        )?,
    )?;
    let a = api.clone();
    m.set(
        "after",
        Function::new(ctx.clone(), move |ctx: Ctx<'js>, ms: f64, f: Function<'js>| {
            let id = keep(&ctx, f)?;
            a.after(ms, id).map_err(|e| throw(&ctx, &e))
        })?,
    )?;
    Ok(m)
}

fn throw(ctx: &Ctx<'_>, e: &ApiError) -> rquickjs::Error {
    Exception::throw_message(ctx, &e.to_string())
}

/// A world-model value in JavaScript: numbers, booleans, strings, arrays (bytes as an array
/// of numbers); a GUID as `{ guid: N }`; absent as `undefined`.
fn to_js<'js>(ctx: &Ctx<'js>, v: Option<&Value>) -> rquickjs::Result<rquickjs::Value<'js>> {
    use rquickjs::IntoJs;
    let Some(v) = v else { return Ok(rquickjs::Value::new_undefined(ctx.clone())) };
    match v {
        Value::Int(i) => match i32::try_from(*i) {
            Ok(i) => Ok(rquickjs::Value::new_int(ctx.clone(), i)),
            Err(_) => Ok(rquickjs::Value::new_float(ctx.clone(), *i as f64)),
        },
        Value::Float(f) => Ok(rquickjs::Value::new_float(ctx.clone(), *f)),
        Value::Bool(b) => Ok(rquickjs::Value::new_bool(ctx.clone(), *b)),
        Value::Str(s) => (**s).into_js(ctx),
        Value::Guid(g) => {
            let o = Object::new(ctx.clone())?;
            o.set("guid", g.get() as f64)?;
            Ok(o.into_value())
        }
        Value::List(l) | Value::Set(l) => {
            let a = Array::new(ctx.clone())?;
            for (i, x) in l.iter().enumerate() {
                a.set(i, to_js(ctx, Some(x))?)?;
            }
            Ok(a.into_value())
        }
        Value::Bytes(b) => b.to_vec().into_js(ctx),
    }
}

fn from_js(v: &rquickjs::Value<'_>) -> Result<Value, String> {
    if let Some(i) = v.as_int() {
        Ok(Value::Int(i64::from(i)))
    } else if let Some(f) = v.as_float() {
        Ok(Value::Float(f))
    } else if let Some(b) = v.as_bool() {
        Ok(Value::Bool(b))
    } else if let Some(s) = v.as_string() {
        Ok(Value::str(&s.to_string().map_err(|e| e.to_string())?))
    } else if let Some(a) = v.as_array() {
        let items = a
            .iter::<rquickjs::Value>()
            .map(|x| x.map_err(|e| e.to_string()).and_then(|x| from_js(&x)))
            .collect::<Result<Vec<_>, _>>()?;
        Ok(Value::List(items.into()))
    } else if let Some(g) = v
        .as_object()
        .and_then(|o| o.get::<_, Option<f64>>("guid").ok().flatten())
        .and_then(|n| Guid::new(n as u64))
    {
        Ok(Value::Guid(g))
    } else {
        Err(format!("a {} is not a world-model value", v.type_name()))
    }
}

fn setup(source: &Source, e: rquickjs::Error) -> ScriptError {
    ScriptError { kind: ErrorKind::Runtime, at: source.locate(0, 0), message: e.to_string() }
}

/// The pending exception as a script error at the script's file:line:col.
fn thrown(ctx: &Ctx<'_>, source: &Source, e: rquickjs::Error, tripped: bool) -> ScriptError {
    if !matches!(e, rquickjs::Error::Exception) {
        return setup(source, e);
    }
    let caught = ctx.catch();
    let exception = caught.as_exception();
    let name = exception.and_then(|x| x.get::<_, Option<String>>("name").ok().flatten());
    let message = exception
        .and_then(Exception::message)
        .or_else(|| caught.as_string().and_then(|s| s.to_string().ok()))
        .unwrap_or_else(|| "an exception that is not an Error".to_string());
    let stack = exception.and_then(Exception::stack).unwrap_or_default();
    let position = position_in(&stack)
        .or_else(|| {
            let o = exception?;
            let line = o.get::<_, Option<u32>>("lineNumber").ok().flatten()?;
            let col = o.get::<_, Option<u32>>("columnNumber").ok().flatten()?;
            Some((line, col))
        })
        .unwrap_or((1, 1));
    let kind = if tripped {
        ErrorKind::Runaway
    } else if message.contains("out of memory") || caught.is_null() {
        // QuickJS throws `null` when it cannot even allocate the error: its out-of-memory
        // signal (a script's own `throw null` is taken as the same).
        ErrorKind::Memory
    } else if name.as_deref() == Some("SyntaxError") {
        ErrorKind::Syntax
    } else {
        ErrorKind::Runtime
    };
    // Line 1 is the wrapper's own: QuickJS names it for an interrupted loop (it knows the
    // function, not the statement), so the script's start is the best place to give.
    let at: Location = match position {
        (0 | 1, _) => source.locate(0, 0),
        (line, col) => source.locate(line - 1, col),
    };
    ScriptError { kind, at, message }
}

/// The first `<mocu-script>:LINE:COL` of a QuickJS stack.
fn position_in(stack: &str) -> Option<(u32, u32)> {
    let rest = &stack[stack.find(FILE)? + FILE.len()..];
    let mut parts = rest.strip_prefix(':')?.splitn(3, |c: char| !c.is_ascii_digit());
    let line = parts.next()?.parse().ok()?;
    let col = parts.next()?.parse().ok()?;
    Some((line, col))
}
