//! The module host: order, failure isolation, panic isolation, specs from profiles.

use mocu_dataserver::{DataServer, Value};
use mocu_host::{HostEvent, Module, ModuleContext, ModuleHost, ModuleSpec, Registry, StartError};
use std::sync::{Arc, Mutex};
use std::time::Duration;

struct Probe {
    log: Arc<Mutex<Vec<String>>>,
    behaviour: &'static str,
}

impl Module for Probe {
    fn start(&mut self, ctx: &ModuleContext) -> Result<(), String> {
        self.log.lock().unwrap().push(format!("start {}", ctx.name));
        match self.behaviour {
            "fail" => Err("no such serial port /dev/ttyX".into()),
            "panic" => panic!("bug in start"),
            "thread-panic" => {
                ctx.spawn_thread("worker", || panic!("bug in a reader thread")).unwrap();
                Ok(())
            }
            _ => {
                ctx.ds.set(ctx.status, "hello", Value::Int(1)).unwrap();
                Ok(())
            }
        }
    }

    fn stop(&mut self) {
        self.log.lock().unwrap().push(format!("stop {}", self.behaviour));
    }
}

fn host(log: &Arc<Mutex<Vec<String>>>) -> ModuleHost {
    let mut reg = Registry::new();
    for b in ["ok", "fail", "panic", "thread-panic"] {
        let l = log.clone();
        reg.register(b, move |_| {
            Ok(Box::new(Probe { log: l.clone(), behaviour: b }) as Box<dyn Module>)
        });
    }
    reg.register("bad-factory", |spec| Err(format!("bad settings for {}", spec.name)));
    ModuleHost::new(DataServer::default(), reg)
}

fn state(h: &ModuleHost, name: &str) -> Value {
    let ds = h.dataserver();
    ds.get(ds.resolve(&["modules", name]).unwrap(), "state").unwrap()
}

#[test]
fn a_failing_module_is_reported_and_the_others_run() {
    let log = Arc::default();
    let mut h = host(&log);
    let specs = [
        ModuleSpec::new("ok").named("first"),
        ModuleSpec::new("fail"),
        ModuleSpec::new("bad-factory"),
        ModuleSpec::new("nonesuch"),
        ModuleSpec::new("ok").named("last"),
    ];
    let errors = h.start_all(&specs);
    assert_eq!(errors.len(), 3);
    assert!(
        matches!(&errors[0], StartError::Failed { reason, .. } if reason.contains("/dev/ttyX"))
    );
    assert!(matches!(&errors[2], StartError::UnknownKind { kind, .. } if kind == "nonesuch"));
    assert_eq!(h.running(), ["first", "last"]);
    assert_eq!(state(&h, "first"), Value::str("running"));
    assert_eq!(state(&h, "fail"), Value::str("failed"));
    let events: Vec<HostEvent> = h.events().try_iter().collect();
    assert!(
        events.iter().any(|e| matches!(e, HostEvent::Failed { module, .. } if module == "fail"))
    );
    assert!(
        events.iter().any(|e| matches!(e, HostEvent::Started { module, .. } if module == "last"))
    );
    h.stop_all();
    assert_eq!(
        *log.lock().unwrap(),
        ["start first", "start fail", "stop fail", "start last", "stop ok", "stop ok"]
    );
    assert_eq!(state(&h, "last"), Value::str("stopped"));
}

#[test]
fn an_unknown_kind_names_the_module_and_the_kinds_known() {
    let log = Arc::default();
    let mut h = host(&log);
    let err = h.start(&ModuleSpec::new("my_map").named("map_view")).unwrap_err();
    assert_eq!(
        err.to_string(),
        "module `map_view`: no module kind `my_map` is registered (the kinds are: \
         bad-factory, fail, ok, panic, thread-panic)"
    );
    assert!(h.running().is_empty());
}

#[test]
fn a_panicking_module_is_isolated() {
    let log = Arc::default();
    let mut h = host(&log);
    let errors = h.start_all(&[
        ModuleSpec::new("panic"),
        ModuleSpec::new("thread-panic"),
        ModuleSpec::new("ok"),
    ]);
    assert!(
        matches!(&errors[..], [StartError::Panicked { message, .. }] if message == "bug in start")
    );
    assert_eq!(h.running(), ["thread-panic", "ok"]);
    assert_eq!(state(&h, "panic"), Value::str("panicked"));
    // The reader thread's panic is caught and reported (the event comes after the module
    // is marked); the wait is on the event, the deadline only guards against a hang.
    let events = h.events();
    let reported = loop {
        match events.recv_timeout(Duration::from_secs(30)) {
            Ok(HostEvent::Panicked { module, message }) if module == "thread-panic" => {
                break message;
            }
            Ok(_) => continue,
            Err(e) => panic!("the reader thread's panic was never reported: {e}"),
        }
    };
    assert_eq!(reported, "bug in a reader thread");
    assert_eq!(state(&h, "thread-panic"), Value::str("panicked"));
    assert_eq!(state(&h, "ok"), Value::str("running"));
}

#[test]
fn duplicate_names_are_refused() {
    let log = Arc::default();
    let mut h = host(&log);
    h.start(&ModuleSpec::new("ok")).unwrap();
    assert!(matches!(h.start(&ModuleSpec::new("ok")), Err(StartError::DuplicateName { .. })));
}

#[test]
fn a_profile_names_modules_in_order_with_settings() {
    let profile: toml::Table = r#"
        [[modules]]
        name = "sim"
        seed = 7
        usv = 3

        [[modules]]
        name = "boats"
        kind = "mavlink"
        address = "127.0.0.1:14551"
    "#
    .parse()
    .unwrap();
    let specs = ModuleSpec::list_from_profile(&profile).unwrap().unwrap();
    assert_eq!(specs.len(), 2);
    assert_eq!((specs[0].name.as_str(), specs[0].kind.as_str()), ("sim", "sim"));
    assert_eq!(specs[0].i64_or("seed", 1), Ok(7));
    assert_eq!((specs[1].name.as_str(), specs[1].kind.as_str()), ("boats", "mavlink"));
    assert_eq!(specs[1].str_or("address", "x").unwrap(), "127.0.0.1:14551");
    assert!(specs[1].settings.get("kind").is_none());
    assert!(specs[0].f64_or("usv", 0.0).is_ok());
    assert!(specs[1].i64_or("address", 0).unwrap_err().to_string().contains("must be an integer"));
    let none: toml::Table = "title = 'x'".parse().unwrap();
    assert_eq!(ModuleSpec::list_from_profile(&none).unwrap(), None);
    let bad: toml::Table = "[[modules]]\nkind = 'sim'".parse().unwrap();
    assert!(ModuleSpec::list_from_profile(&bad).is_err());
}
