//! `#rhai:` — Rhai, a Rust-native scripting language. Its operation, size and call-depth
//! limits are the engine's own; without the `files` grant no module resolver is set, so
//! `import` finds nothing. The API is the static module `mocu` (`mocu::read(path)`; a method
//! call is `mocu::call_method`, `call` being a Rhai keyword).

use crate::api::{Api, CallbackId};
use crate::engine::{Engine, Instance, Limits};
use crate::error::{ApiError, ErrorKind, ScriptError, Source};
use mocu_dataserver::{Guid, Value};
use parking_lot::Mutex;
use rhai::{AST, Array, Dynamic, EvalAltResult, FnPtr, Module, Position, Scope};
use std::collections::HashMap;
use std::sync::Arc;

/// The Rhai engine of the registry.
pub struct Rhai;

impl Engine for Rhai {
    fn prefix(&self) -> &'static str {
        "rhai"
    }

    fn extension(&self) -> &'static str {
        "rhai"
    }

    fn check(&self, source: &Source) -> Result<(), ScriptError> {
        let engine = rhai::Engine::new_raw();
        engine.compile(&*source.text).map(|_| ()).map_err(|e| syntax(source, &e))
    }

    fn load(
        &self,
        source: &Source,
        api: Api,
        limits: &Limits,
    ) -> Result<Box<dyn Instance>, ScriptError> {
        let callbacks = Callbacks::default();
        let mut engine = rhai::Engine::new();
        engine
            .set_max_operations(limits.operations.max(1))
            .set_max_call_levels(limits.call_depth)
            .set_max_string_size(limits.memory)
            .set_max_array_size(limits.memory / 16)
            .set_max_map_size(limits.memory / 64);
        if limits.files
            && let Some(dir) = std::path::Path::new(&*source.origin.file).parent()
        {
            engine.set_module_resolver(rhai::module_resolvers::FileModuleResolver::new_with_path(
                dir,
            ));
        } else {
            engine.set_module_resolver(rhai::module_resolvers::DummyModuleResolver::new());
        }
        engine.register_static_module("mocu", api_module(&api, &callbacks).into());
        let ast = engine.compile(&*source.text).map_err(|e| syntax(source, &e))?;
        Ok(Box::new(RhaiInstance { engine, ast, callbacks, source: source.clone() }))
    }
}

/// The function pointers a script handed to the API, by number.
#[derive(Clone, Default)]
struct Callbacks(Arc<Mutex<(CallbackId, HashMap<CallbackId, FnPtr>)>>);

impl Callbacks {
    fn add(&self, f: FnPtr) -> CallbackId {
        let mut g = self.0.lock();
        g.0 += 1;
        let id = g.0;
        g.1.insert(id, f);
        id
    }

    fn get(&self, id: CallbackId, once: bool) -> Option<FnPtr> {
        let mut g = self.0.lock();
        if once { g.1.remove(&id) } else { g.1.get(&id).cloned() }
    }
}

struct RhaiInstance {
    engine: rhai::Engine,
    ast: AST,
    callbacks: Callbacks,
    source: Source,
}

impl Instance for RhaiInstance {
    fn run(&mut self) -> Result<(), ScriptError> {
        self.run_with(&[])
    }

    fn run_with(&mut self, vars: &[(&str, Option<Value>)]) -> Result<(), ScriptError> {
        let mut scope = Scope::new();
        for (name, v) in vars {
            scope.push_constant(*name, v.as_ref().map_or(Dynamic::UNIT, to_dynamic));
        }
        self.engine.run_ast_with_scope(&mut scope, &self.ast).map_err(|e| runtime(&self.source, &e))
    }

    fn invoke(
        &mut self,
        callback: CallbackId,
        args: &[Option<Value>],
        once: bool,
    ) -> Result<(), ScriptError> {
        let Some(f) = self.callbacks.get(callback, once) else { return Ok(()) };
        let args: Vec<Dynamic> =
            args.iter().map(|v| v.as_ref().map_or(Dynamic::UNIT, to_dynamic)).collect();
        // A callback declared with fewer parameters than it is given gets the first ones.
        let arity = self
            .ast
            .iter_functions()
            .find(|d| d.name == f.fn_name())
            .map_or(args.len(), |d| d.params.len().saturating_sub(f.curry().len()));
        let args: Vec<Dynamic> = args.into_iter().take(arity).collect();
        f.call::<Dynamic>(&self.engine, &self.ast, args)
            .map(|_| ())
            .map_err(|e| runtime(&self.source, &e))
    }

    fn memory(&self) -> Option<usize> {
        None
    }
}

/// The `mocu` module: the DataServer API.
fn api_module(api: &Api, callbacks: &Callbacks) -> Module {
    let mut m = Module::new();
    let a = api.clone();
    m.set_native_fn("read", move |path: &str| {
        Ok(a.read(path).map_err(thrown)?.as_ref().map_or(Dynamic::UNIT, to_dynamic))
    });
    let a = api.clone();
    m.set_native_fn("write", move |path: &str, v: Dynamic| {
        let v = from_dynamic(&v).map_err(|e| thrown_text(format!("write `{path}`: {e}")))?;
        a.write(path, v).map_err(thrown)
    });
    let (a, c) = (api.clone(), callbacks.clone());
    m.set_native_fn("subscribe", move |path: &str, f: FnPtr| {
        a.subscribe(path, c.add(f)).map_err(thrown)
    });
    let (a, c) = (api.clone(), callbacks.clone());
    m.set_native_fn("call_method", move |path: &str, args: Array, f: FnPtr| {
        a.call(path, values(&args)?, Some(c.add(f))).map_err(thrown)
    });
    let a = api.clone();
    m.set_native_fn("call_method", move |path: &str, args: Array| {
        a.call(path, values(&args)?, None).map_err(thrown)
    });
    let a = api.clone();
    m.set_native_fn("create", move |parent: &str, name: &str, kind: &str| {
        a.create(parent, name, kind).map_err(thrown)
    });
    let (a, c) = (api.clone(), callbacks.clone());
    m.set_native_fn("after", move |ms: rhai::INT, f: FnPtr| {
        a.after(ms as f64, c.add(f)).map_err(thrown)
    });
    let (a, c) = (api.clone(), callbacks.clone());
    m.set_native_fn("after", move |ms: rhai::FLOAT, f: FnPtr| {
        a.after(ms, c.add(f)).map_err(thrown)
    });
    m
}

fn values(args: &Array) -> Result<Vec<Value>, Box<EvalAltResult>> {
    args.iter().map(|d| from_dynamic(d).map_err(thrown_text)).collect()
}

fn thrown(e: ApiError) -> Box<EvalAltResult> {
    thrown_text(e.to_string())
}

fn thrown_text(text: String) -> Box<EvalAltResult> {
    EvalAltResult::ErrorRuntime(text.into(), Position::NONE).into()
}

/// A world-model value as a Rhai value: numbers, booleans, strings, arrays, blobs; a GUID
/// as an opaque value that can be written back.
pub(crate) fn to_dynamic(v: &Value) -> Dynamic {
    match v {
        Value::Int(i) => Dynamic::from_int(*i),
        Value::Float(f) => Dynamic::from_float(*f),
        Value::Bool(b) => Dynamic::from_bool(*b),
        Value::Str(s) => Dynamic::from(s.to_string()),
        Value::Guid(g) => Dynamic::from(*g),
        Value::List(l) | Value::Set(l) => Dynamic::from_array(l.iter().map(to_dynamic).collect()),
        Value::Bytes(b) => Dynamic::from_blob(b.to_vec()),
    }
}

pub(crate) fn from_dynamic(d: &Dynamic) -> Result<Value, String> {
    if let Ok(i) = d.as_int() {
        Ok(Value::Int(i))
    } else if let Ok(f) = d.as_float() {
        Ok(Value::Float(f))
    } else if let Ok(b) = d.as_bool() {
        Ok(Value::Bool(b))
    } else if d.is_string() {
        Ok(Value::str(&d.clone().into_string().unwrap_or_default()))
    } else if d.is_array() {
        let a = d.clone().into_array().unwrap_or_default();
        Ok(Value::List(a.iter().map(from_dynamic).collect::<Result<Vec<_>, _>>()?.into()))
    } else if d.is_blob() {
        Ok(Value::Bytes(d.clone().into_blob().unwrap_or_default().into()))
    } else if let Some(g) = d.clone().try_cast::<Guid>() {
        Ok(Value::Guid(g))
    } else {
        Err(format!("a {} is not a world-model value", d.type_name()))
    }
}

fn syntax(source: &Source, e: &rhai::ParseError) -> ScriptError {
    ScriptError {
        kind: ErrorKind::Syntax,
        at: at(source, e.position()),
        message: e.err_type().to_string(),
    }
}

/// The innermost error (a closure's own, not the call that reached it) at its place.
fn runtime(source: &Source, e: &EvalAltResult) -> ScriptError {
    let mut e = e;
    while let EvalAltResult::ErrorInFunctionCall(_, _, inner, _)
    | EvalAltResult::ErrorInModule(_, inner, _) = e
    {
        e = inner;
    }
    let kind = match e {
        EvalAltResult::ErrorTooManyOperations(_) => ErrorKind::Runaway,
        EvalAltResult::ErrorDataTooLarge(..) => ErrorKind::Memory,
        _ => ErrorKind::Runtime,
    };
    let message = match e {
        EvalAltResult::ErrorRuntime(v, _) => v.to_string(),
        other => other.to_string(),
    };
    ScriptError { kind, at: at(source, e.position()), message }
}

fn at(source: &Source, p: Position) -> crate::error::Location {
    let line = p.line().unwrap_or(0) as u32;
    let col = p.position().unwrap_or(1) as u32;
    source.locate(line, col)
}
