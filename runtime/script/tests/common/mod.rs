//! A DataServer on a manual clock with one vehicle (`vehicles.usv1`: `speed`, method `arm`)
//! and an `out` object the scripts write their findings to.

#![allow(dead_code)]

use mocu_dataserver::{
    CallOutcome, Config, DataServer, Guid, ManualClock, MethodSpec, ObjectInfo, ParamSpec,
    PropMeta, Value, ValueKind,
};
use mocu_script::{Limits, Registry, Reporter, Script, ScriptError, Source};
use parking_lot::Mutex;
use std::sync::Arc;

pub struct World {
    pub ds: DataServer,
    pub clock: ManualClock,
    pub usv: Guid,
    pub out: Guid,
    pub errors: Arc<Mutex<Vec<ScriptError>>>,
}

impl World {
    pub fn with_a_vehicle() -> World {
        let clock = ManualClock::new();
        World::on(DataServer::with_clock(Config::default(), Arc::new(clock.clone())), clock)
    }

    /// The same world on the system clock (the clock given is not the server's).
    pub fn on_the_system_clock() -> World {
        World::on(DataServer::default(), ManualClock::new())
    }

    fn on(ds: DataServer, clock: ManualClock) -> World {
        let vehicles = ds.create_object(Guid::ROOT, ObjectInfo::new("vehicles", "folder")).unwrap();
        let usv = ds.create_object(vehicles, ObjectInfo::new("usv1", "usv")).unwrap();
        ds.create_property(usv, "speed", Value::Float(2.0), PropMeta::typed(ValueKind::Float))
            .unwrap();
        let spec = MethodSpec::new("arm").param(ParamSpec::new("on", ValueKind::Bool));
        ds.publish_method_fn(usv, spec, |args| CallOutcome::Accepted(args.to_vec())).unwrap();
        let out = ds.create_object(Guid::ROOT, ObjectInfo::new("out", "folder")).unwrap();
        World { ds, clock, usv, out, errors: Arc::default() }
    }

    pub fn reporter(&self) -> Reporter {
        let errors = self.errors.clone();
        Arc::new(move |e: &ScriptError| errors.lock().push(e.clone()))
    }

    /// Loads a script of `engine` whose text starts at line 7, column 20 of `layout.mocu`.
    pub fn load(&self, engine: &str, text: &str, limits: &Limits) -> Result<Script, ScriptError> {
        let engines = Registry::standard();
        let e = engines.get(engine).expect("a standard engine");
        let source = Source::embedded("layout.mocu", 7, 20, text);
        Script::load(
            &*e,
            &source,
            self.ds.clone(),
            self.ds.serial_executor(),
            limits,
            self.reporter(),
        )
    }

    pub fn out(&self, name: &str) -> Option<Value> {
        self.ds.quiesce();
        self.ds.get(self.out, name).ok()
    }
}
