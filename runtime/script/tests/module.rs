//! Script modules: `[modules.NAME] kind = "script"`, started by the module host, reloaded
//! by their `reload()` method (what `mocu run` calls when the file is saved).

mod common;

use common::World;
use mocu_dataserver::Value;
use mocu_host::{HostEvent, ModuleHost, ModuleSpec, Registry};
use std::path::Path;

fn host(w: &World) -> ModuleHost {
    let mut r = Registry::new();
    mocu_script::register(&mut r);
    ModuleHost::new(w.ds.clone(), r)
}

fn spec(file: &Path) -> ModuleSpec {
    ModuleSpec::new("script").named("ops").with("file", file.display().to_string())
}

fn status(w: &World, name: &str) -> Option<Value> {
    w.ds.quiesce();
    let m = w.ds.resolve(&["modules", "ops"])?;
    w.ds.get(m, name).ok()
}

#[test]
fn a_script_module_runs_its_file_on_its_executor_and_follows_the_world() {
    for (ext, text) in [
        (
            "js",
            r#"mocu.subscribe("vehicles.usv1.speed", function (v) { mocu.write("out.seen", v); });"#,
        ),
        ("rhai", r#"mocu::subscribe("vehicles.usv1.speed", |v| mocu::write("out.seen", v));"#),
    ] {
        let dir = tempfile::tempdir().unwrap();
        let file = dir.path().join(format!("ops.{ext}"));
        std::fs::write(&file, text).unwrap();
        let w = World::with_a_vehicle();
        let mut h = host(&w);
        h.start(&spec(&file)).unwrap();
        w.ds.set(w.usv, "speed", Value::Float(5.5)).unwrap();
        assert_eq!(w.out("seen"), Some(Value::Float(5.5)), "{ext}");
        assert_eq!(status(&w, "engine"), Some(Value::str(ext)));
        assert_eq!(status(&w, "generation"), Some(Value::Int(1)));
    }
}

#[test]
fn a_module_whose_file_has_a_syntax_error_does_not_start_and_says_where() {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("ops.js");
    std::fs::write(&file, "let a = 1;\nlet b = a +;\n").unwrap();
    let w = World::with_a_vehicle();
    let mut h = host(&w);
    let e = h.start(&spec(&file)).expect_err("a syntax error");
    let want = format!("{}:2:12: script syntax error", file.display());
    assert!(e.to_string().contains(&want), "{e}");
}

#[test]
fn a_reload_replaces_the_script_and_a_broken_file_keeps_the_running_one() {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("ops.rhai");
    std::fs::write(
        &file,
        r#"mocu::subscribe("vehicles.usv1.speed", |v| mocu::write("out.a", v));"#,
    )
    .unwrap();
    let w = World::with_a_vehicle();
    let mut h = host(&w);
    h.start(&spec(&file)).unwrap();
    let module = w.ds.resolve(&["modules", "ops"]).unwrap();
    // The first script's initial value is delivered on its executor: wait for it, so the
    // reload below stops a script that has run (a reload before it would drop it unseen).
    assert_eq!(w.out("a"), Some(Value::Float(2.0)), "the first script saw the initial value");

    std::fs::write(
        &file,
        r#"mocu::subscribe("vehicles.usv1.speed", |v| mocu::write("out.b", v));"#,
    )
    .unwrap();
    assert!(w.ds.call_wait(module, "reload", vec![], None).is_accepted());
    w.ds.set(w.usv, "speed", Value::Float(7.0)).unwrap();
    assert_eq!(w.out("b"), Some(Value::Float(7.0)), "the new script runs");
    assert_eq!(w.out("a"), Some(Value::Float(2.0)), "the old one stopped before the change");
    assert_eq!(status(&w, "generation"), Some(Value::Int(2)));

    std::fs::write(&file, "mocu::subscribe(\n  \"x\" |v| )").unwrap();
    let refused = w.ds.call_wait(module, "reload", vec![], None);
    assert_eq!(refused.label(), "refused");
    let Some(Value::Str(error)) = status(&w, "error") else { panic!("no error shown") };
    assert!(error.starts_with(&format!("{}:2:", file.display())), "{error}");
    w.ds.set(w.usv, "speed", Value::Float(8.0)).unwrap();
    assert_eq!(w.out("b"), Some(Value::Float(8.0)), "the running script is kept");
    assert_eq!(status(&w, "generation"), Some(Value::Int(2)));
}

#[test]
fn an_error_while_running_is_reported_to_the_host_with_file_line_and_column() {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("ops.js");
    std::fs::write(&file, "let a = 1;\nmocu.write(\"vehicles.usv1.speed\", \"fast\");\n").unwrap();
    let w = World::with_a_vehicle();
    let mut h = host(&w);
    let events = h.events();
    h.start(&spec(&file)).unwrap();
    w.ds.quiesce();
    let events: Vec<HostEvent> = events.try_iter().collect();
    let messages: Vec<&String> = events
        .iter()
        .filter_map(|e| match e {
            HostEvent::Message { text, .. } => Some(text),
            _ => None,
        })
        .collect();
    let recorded = events.iter().find_map(|e| match e {
        HostEvent::Record { event, fields, .. } if event == "script_error" => Some(fields),
        _ => None,
    });
    let field = |name: &str| recorded?.iter().find(|(k, _)| k == name).map(|(_, v)| v.clone());
    // The refused call: `write` of `mocu.write(…)`, line 2, column 6.
    assert_eq!((field("line"), field("col")), (Some(Value::Int(2)), Some(Value::Int(6))));
    let want = format!("{}:2:", file.display());
    assert!(messages.iter().any(|m| m.starts_with(&want) && m.contains("speed")), "{messages:?}");
    let Some(Value::Str(error)) = status(&w, "error") else { panic!("no error shown") };
    assert!(error.starts_with(&want), "{error}");
}

#[test]
fn saving_the_file_reloads_the_module_and_a_broken_save_keeps_the_running_script() {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("ops.js");
    std::fs::write(&file, r#"mocu.write("out.version", 1);"#).unwrap();
    // The reload waits for the file to be quiet on the server's clock: the system clock here.
    let w = World::on_the_system_clock();
    let mut h = host(&w);
    let events = h.events();
    h.start(&spec(&file)).unwrap();
    let module = w.ds.resolve(&["modules", "ops"]).unwrap();
    let (tx, rx) = crossbeam_channel::unbounded();
    let _sub = w.ds.subscribe(mocu_dataserver::Topic::properties(module), move |n| {
        let _ = tx.send((n.property_name().map(|p| p.to_string()), n.value().cloned()));
    });
    let wait_for = |prop: &str, want: Value| {
        loop {
            match rx.recv_timeout(std::time::Duration::from_secs(60)) {
                Ok((Some(p), Some(v))) if p == prop && v == want => return,
                Ok(_) => {}
                Err(_) => panic!("{prop} never became {want:?}"),
            }
        }
    };
    std::fs::write(&file, r#"mocu.write("out.version", 2);"#).unwrap();
    wait_for("generation", Value::Int(2));
    assert_eq!(w.out("version"), Some(Value::Int(2)));

    std::fs::write(&file, "mocu.write(\"out.version\",\n 3 +);").unwrap();
    let want = format!("{}:2:", file.display());
    loop {
        match rx.recv_timeout(std::time::Duration::from_secs(60)) {
            Ok((Some(p), Some(Value::Str(e)))) if p == "error" && e.starts_with(&want) => break,
            Ok(_) => {}
            Err(_) => panic!("the broken save was not reported"),
        }
    }
    assert_eq!(status(&w, "generation"), Some(Value::Int(2)), "the running script is kept");
    let reported = events
        .try_iter()
        .any(|e| matches!(e, HostEvent::Message { text, .. } if text.starts_with(&want)));
    assert!(reported, "the host was told");
}
