//! Every engine sees the same DataServer API with the same rules, and is sandboxed the same
//! way: each case is written once per engine and run against a real DataServer.

mod common;

use common::World;
use mocu_dataserver::Value;
use mocu_script::{ErrorKind, Limits, Registry, Script, Source};
use std::time::Duration;

/// One behaviour, written in each language.
struct Case {
    js: &'static str,
    rhai: &'static str,
}

impl Case {
    fn each(&self) -> [(&'static str, &'static str); 2] {
        [("js", self.js), ("rhai", self.rhai)]
    }
}

/// A number as written by a script: JavaScript has one number type, and writes a whole
/// number as an int (a float property takes it as a float).
fn number(v: Option<Value>) -> Option<f64> {
    match v? {
        Value::Int(i) => Some(i as f64),
        Value::Float(f) => Some(f),
        other => panic!("not a number: {other:?}"),
    }
}

/// Runs a case's script to completion in a fresh world; returns the world and the script
/// (its subscriptions last as long as it does).
fn run(engine: &str, text: &str) -> (World, Script) {
    let w = World::with_a_vehicle();
    let s = w.load(engine, text, &Limits::default()).unwrap_or_else(|e| panic!("{engine}: {e}"));
    s.run_here().unwrap_or_else(|e| panic!("{engine}: {e}"));
    w.ds.quiesce();
    assert!(w.errors.lock().is_empty(), "{engine}: {:?}", w.errors.lock());
    (w, s)
}

#[test]
fn a_script_reads_a_property_and_writes_another() {
    let case = Case {
        js: r#"mocu.write("out.double", mocu.read("vehicles.usv1.speed") * 2);"#,
        rhai: r#"mocu::write("out.double", mocu::read("vehicles.usv1.speed") * 2.0);"#,
    };
    for (engine, text) in case.each() {
        let (w, _s) = run(engine, text);
        assert_eq!(number(w.out("double")), Some(4.0), "{engine}");
    }
}

#[test]
fn a_path_that_is_not_there_reads_as_absent() {
    let case = Case {
        js: r#"mocu.write("out.absent", mocu.read("vehicles.usv9.speed") === undefined);"#,
        rhai: r#"mocu::write("out.absent", mocu::read("vehicles.usv9.speed") == ());"#,
    };
    for (engine, text) in case.each() {
        assert_eq!(run(engine, text).0.out("absent"), Some(Value::Bool(true)), "{engine}");
    }
}

#[test]
fn a_subscription_sees_the_value_now_and_each_change() {
    let case = Case {
        js: r#"let n = 0; mocu.subscribe("vehicles.usv1.speed", function (v) {
                 n += 1; mocu.write("out.seen", v); mocu.write("out.count", n); });"#,
        rhai: r#"let n = [0]; mocu::subscribe("vehicles.usv1.speed", |v| {
                 n[0] += 1; mocu::write("out.seen", v); mocu::write("out.count", n[0]); });"#,
    };
    for (engine, text) in case.each() {
        let (w, _s) = run(engine, text);
        assert_eq!(number(w.out("seen")), Some(2.0), "{engine}");
        w.ds.set(w.usv, "speed", Value::Float(3.5)).unwrap();
        assert_eq!(number(w.out("seen")), Some(3.5), "{engine}");
        assert_eq!(w.out("count"), Some(Value::Int(2)), "{engine}");
    }
}

#[test]
fn a_call_answers_its_callback_with_the_outcome_and_results() {
    let case = Case {
        js: r#"mocu.call("vehicles.usv1.arm", [true], function (status, results) {
                 mocu.write("out.status", status); mocu.write("out.armed", results[0]); });"#,
        rhai: r#"mocu::call_method("vehicles.usv1.arm", [true], |status, results| {
                 mocu::write("out.status", status); mocu::write("out.armed", results[0]); });"#,
    };
    for (engine, text) in case.each() {
        let (w, _s) = run(engine, text);
        assert_eq!(w.out("status"), Some(Value::str("accepted")), "{engine}");
        assert_eq!(w.out("armed"), Some(Value::Bool(true)), "{engine}");
    }
}

#[test]
fn a_call_with_bad_arguments_is_answered_failed_as_for_a_native_module() {
    let case = Case {
        js: r#"mocu.call("vehicles.usv1.arm", ["yes"], function (status, why) {
                 mocu.write("out.status", status); });"#,
        rhai: r#"mocu::call_method("vehicles.usv1.arm", ["yes"], |status, why| {
                 mocu::write("out.status", status); });"#,
    };
    for (engine, text) in case.each() {
        assert_eq!(run(engine, text).0.out("status"), Some(Value::str("failed")), "{engine}");
    }
}

#[test]
fn a_write_the_dataserver_refuses_is_an_exception_the_script_can_catch() {
    let case = Case {
        js: r#"try { mocu.write("vehicles.usv1.speed", "fast"); } catch (e) {
                 mocu.write("out.caught", String(e.message)); }"#,
        rhai: r#"try { mocu::write("vehicles.usv1.speed", "fast"); } catch (e) {
                 mocu::write("out.caught", `${e}`); }"#,
    };
    for (engine, text) in case.each() {
        let caught = run(engine, text).0.out("caught");
        let Some(Value::Str(s)) = caught else { panic!("{engine}: {caught:?}") };
        assert!(s.contains("vehicles.usv1.speed"), "{engine}: {s}");
    }
}

#[test]
fn a_script_creates_objects_and_writes_under_them() {
    let case = Case {
        js: r#"let p = mocu.create("out", "made", "thing"); mocu.write(p + ".x", 1);"#,
        rhai: r#"let p = mocu::create("out", "made", "thing"); mocu::write(p + ".x", 1);"#,
    };
    for (engine, text) in case.each() {
        let (w, _s) = run(engine, text);
        let made = w.ds.resolve(&["out", "made"]).expect(engine);
        assert_eq!(w.ds.get(made, "x").ok(), Some(Value::Int(1)), "{engine}");
    }
}

#[test]
fn a_delayed_call_runs_when_the_clock_reaches_it_and_not_before() {
    let case = Case {
        js: r#"mocu.after(500, function () { mocu.write("out.late", true); });"#,
        rhai: r#"mocu::after(500, || mocu::write("out.late", true));"#,
    };
    for (engine, text) in case.each() {
        let (w, _s) = run(engine, text);
        let t0 = w.ds.now();
        w.ds.advance_settled(&w.clock, t0 + Duration::from_millis(499));
        assert_eq!(w.out("late"), None, "{engine}");
        w.ds.advance_settled(&w.clock, t0 + Duration::from_millis(500));
        assert_eq!(w.out("late"), Some(Value::Bool(true)), "{engine}");
    }
}

#[test]
fn a_delay_past_what_a_duration_holds_never_fires_and_a_nan_or_negative_one_is_now() {
    let case = Case {
        js: r#"mocu.after(1e30, function () { mocu.write("out.never", true); });
               mocu.after(Infinity, function () { mocu.write("out.never", true); });
               mocu.after(NaN, function () { mocu.write("out.nan", true); });
               mocu.after(-5, function () { mocu.write("out.neg", true); });"#,
        rhai: r#"mocu::after(1e30, || mocu::write("out.never", true));
                 mocu::after(-5.0, || mocu::write("out.neg", true));"#,
    };
    for (engine, text) in case.each() {
        let (w, _s) = run(engine, text);
        let t0 = w.ds.now();
        w.ds.advance_settled(&w.clock, t0 + Duration::from_secs(3600 * 24 * 365));
        assert_eq!(w.out("never"), None, "{engine}");
        assert_eq!(w.out("neg"), Some(Value::Bool(true)), "{engine}");
        assert!(w.errors.lock().is_empty(), "{engine}: {:?}", w.errors.lock());
    }
}

/// Where a runaway is reported: Rhai knows the statement (the loop, on the script's second
/// line: line 8 of layout.mocu); QuickJS knows the function it was in, here the script's own
/// body, which starts at 7:20.
const RUNAWAY_LINE: [(&str, u32); 2] = [("js", 7), ("rhai", 8)];

#[test]
fn a_runaway_script_is_stopped_and_reported_at_its_place_in_the_file() {
    let case =
        Case { js: "let i = 0;\nwhile (true) { i += 1; }", rhai: "let i = 0;\nloop { i += 1; }" };
    for ((engine, text), (_, line)) in case.each().into_iter().zip(RUNAWAY_LINE) {
        let w = World::with_a_vehicle();
        let limits = Limits { operations: 50_000, ..Limits::default() };
        let s = w.load(engine, text, &limits).unwrap();
        let e = s.run_here().expect_err(engine);
        assert_eq!(e.kind, ErrorKind::Runaway, "{engine}: {e}");
        assert_eq!((&*e.at.file, e.at.line), ("layout.mocu", line), "{engine}: {e}");
        assert!(s.is_stopped(), "{engine}");
        assert!(e.to_string().starts_with(&format!("layout.mocu:{line}:")), "{engine}: {e}");
    }
}

#[test]
fn a_runaway_callback_stops_the_script_and_its_subscriptions_end() {
    let case = Case {
        js: r#"mocu.subscribe("vehicles.usv1.speed", function (v) {
                 mocu.write("out.seen", v); if (v > 3) { while (true) {} } });"#,
        rhai: r#"mocu::subscribe("vehicles.usv1.speed", |v| {
                 mocu::write("out.seen", v); if v > 3.0 { loop {} } });"#,
    };
    for (engine, text) in case.each() {
        let w = World::with_a_vehicle();
        let limits = Limits { operations: 50_000, ..Limits::default() };
        let s = w.load(engine, text, &limits).unwrap();
        s.run_here().unwrap();
        w.ds.set(w.usv, "speed", Value::Float(4.0)).unwrap();
        assert_eq!(number(w.out("seen")), Some(4.0), "{engine}");
        let reported: Vec<_> =
            w.errors.lock().iter().map(|e| (e.kind, e.at.file.to_string())).collect();
        assert_eq!(reported, vec![(ErrorKind::Runaway, "layout.mocu".to_string())], "{engine}");
        assert!(s.is_stopped(), "{engine}");
        w.ds.set(w.usv, "speed", Value::Float(1.0)).unwrap();
        assert_eq!(number(w.out("seen")), Some(4.0), "{engine}: stopped, it sees nothing more");
    }
}

#[test]
fn a_script_over_its_memory_limit_is_stopped() {
    let case = Case {
        js: r#"let a = []; while (true) { a.push("0123456789abcdef" + a.length); }"#,
        rhai: r#"let s = "0123456789abcdef"; loop { s += s; }"#,
    };
    for (engine, text) in case.each() {
        let w = World::with_a_vehicle();
        let limits = Limits { operations: u64::MAX / 2, memory: 1 << 20, ..Limits::default() };
        let s = w.load(engine, text, &limits).unwrap();
        let e = s.run_here().expect_err(engine);
        assert_eq!(e.kind, ErrorKind::Memory, "{engine}: {e}");
        assert!(s.is_stopped(), "{engine}");
    }
}

#[test]
fn a_runtime_error_names_the_file_line_and_column_of_the_script() {
    let case = Case { js: "let a = 1;\n  null.x;", rhai: "let a = 1;\n  a.nothing();" };
    for (engine, text) in case.each() {
        let w = World::with_a_vehicle();
        let s = w.load(engine, text, &Limits::default()).unwrap();
        let e = s.run_here().expect_err(engine);
        assert_eq!(e.kind, ErrorKind::Runtime, "{engine}: {e}");
        assert_eq!((&*e.at.file, e.at.line), ("layout.mocu", 8), "{engine}: {e}");
        assert!(!s.is_stopped(), "{engine}: an error does not stop the script");
    }
}

#[test]
fn a_syntax_error_is_found_without_running_at_its_line_and_column() {
    // `;` where an expression must be: the script's line 2, column 11.
    let case = Case { js: "let a = 1;\nlet b = a +;", rhai: "let a = 1;\nlet b = a +;" };
    let engines = Registry::standard();
    for (engine, text) in case.each() {
        let source = Source::embedded("layout.mocu", 7, 20, text);
        let e = engines.get(engine).unwrap().check(&source).expect_err(engine);
        assert_eq!(e.kind, ErrorKind::Syntax, "{engine}: {e}");
        assert_eq!((e.at.line, e.at.col), (8, 12), "{engine}: {e}");
    }
}

#[test]
fn a_script_has_no_file_or_module_access_unless_granted() {
    let case = Case {
        js: r#"mocu.write("out.io", typeof require + typeof std + typeof os + typeof fetch);"#,
        rhai: r#"try { import "secret" as s; mocu::write("out.io", "imported"); }
                 catch (e) { mocu::write("out.io", "refused"); }"#,
    };
    let want = [("js", "undefinedundefinedundefinedundefined"), ("rhai", "refused")];
    for ((engine, text), (_, io)) in case.each().into_iter().zip(want) {
        assert_eq!(run(engine, text).0.out("io"), Some(Value::str(io)), "{engine}");
    }
}

#[test]
fn the_registry_finds_engines_by_prefix_and_by_file_extension() {
    let r = Registry::standard();
    assert_eq!(r.get("js").map(|e| e.prefix()), Some("js"));
    assert_eq!(r.get("rhai").map(|e| e.prefix()), Some("rhai"));
    assert!(r.get("lua").is_none());
    assert_eq!(r.for_file("scripts/a.js").map(|e| e.prefix()), Some("js"));
    assert_eq!(r.for_file("b.rhai").map(|e| e.prefix()), Some("rhai"));
    assert!(r.for_file("c.py").is_none());
}
