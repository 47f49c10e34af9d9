//! Process modules (`kind = "process"`): the supervisor restarts a command that keeps
//! exiting, after a back-off that doubles up to its cap on the DataServer's clock, and the
//! OCU goes on. Real child processes; the clock is a ManualClock the test advances.

use mocu_dataserver::{Config, DataServer, ManualClock, Topic, Value};
use mocu_host::{Module, ModuleContext, ModuleSpec, ProcessModule};
use std::sync::Arc;
use std::time::Duration;

/// Waits until `cond` holds, looking again at each change of the module's status object (a
/// child process's exit is real, not on the test's clock); a status that stops changing for
/// a minute fails the test instead of hanging it.
fn wait_for(ds: &DataServer, ctx: &ModuleContext, what: &str, mut cond: impl FnMut() -> bool) {
    let (tx, rx) = crossbeam_channel::unbounded();
    let sub = ds
        .subscribe(Topic::properties(ctx.status), move |_| {
            let _ = tx.send(());
        })
        .unwrap();
    while !cond() {
        if rx.recv_timeout(Duration::from_secs(60)).is_err() {
            panic!("never happened: {what}");
        }
    }
    ds.unsubscribe(sub);
}

fn status(ds: &DataServer, ctx: &ModuleContext, key: &str) -> Option<Value> {
    ds.try_get(ctx.status, key.into())
}

fn int(ds: &DataServer, ctx: &ModuleContext, key: &str) -> i64 {
    status(ds, ctx, key).and_then(|v| v.as_i64()).unwrap_or(-1)
}

fn text(ds: &DataServer, ctx: &ModuleContext, key: &str) -> String {
    status(ds, ctx, key).and_then(|v| v.as_str().map(str::to_string)).unwrap_or_default()
}

#[test]
fn a_crashing_command_is_restarted_with_a_doubling_back_off_and_the_ocu_goes_on() {
    let clock = ManualClock::new();
    let ds = DataServer::with_clock(Config::default(), Arc::new(clock.clone()));
    let ctx = ModuleContext::detached("crasher", ds.clone());
    let spec = ModuleSpec::new("process")
        .named("crasher")
        .with("command", toml::Value::Array(vec!["sh".into(), "-c".into(), "exit 3".into()]))
        .with("restart_backoff_ms", 100)
        .with("max_backoff_ms", 400);
    let mut m = ProcessModule::from_spec(&spec).unwrap();
    m.start(&ctx).unwrap();

    // Each exit is seen, then the next start waits for the back-off on the clock.
    for (restarts, backoff) in [(0, 100), (1, 200), (2, 400), (3, 400)] {
        wait_for(&ds, &ctx, "the child's exit", || {
            text(&ds, &ctx, "state") == "down"
                && int(&ds, &ctx, "restarts") == restarts
                && int(&ds, &ctx, "next_start_in_ms") == backoff
        });
        assert_eq!(text(&ds, &ctx, "last_exit"), "exit 3");
        assert_eq!(int(&ds, &ctx, "next_start_in_ms"), backoff);
        clock.advance(Duration::from_millis(backoff as u64 - 1));
        ds.quiesce();
        assert_eq!(int(&ds, &ctx, "restarts"), restarts, "restarted before its back-off");
        clock.advance(Duration::from_millis(1));
        wait_for(&ds, &ctx, "the restart", || int(&ds, &ctx, "restarts") == restarts + 1);
    }

    // The OCU is untouched: its DataServer still works, and stop ends the supervision.
    let g = ds.create_object(ds.root(), mocu_dataserver::ObjectInfo::new("x", "x")).unwrap();
    ds.set(g, "alive", Value::Bool(true)).unwrap();
    m.stop();
    assert_eq!(text(&ds, &ctx, "state"), "stopped");
    clock.advance(Duration::from_secs(10));
    ds.quiesce();
    assert_eq!(text(&ds, &ctx, "state"), "stopped", "no restart after stop");
}

#[test]
fn a_command_that_cannot_start_is_retried_and_reported() {
    let clock = ManualClock::new();
    let ds = DataServer::with_clock(Config::default(), Arc::new(clock.clone()));
    let ctx = ModuleContext::detached("missing", ds.clone());
    let spec = ModuleSpec::new("process")
        .with("command", toml::Value::Array(vec!["/nonexistent/mocu-module".into()]));
    let mut m = ProcessModule::from_spec(&spec).unwrap();
    m.start(&ctx).unwrap();
    assert_eq!(text(&ds, &ctx, "state"), "failed_to_start");
    assert!(text(&ds, &ctx, "last_exit").starts_with("cannot start"));
    assert_eq!(int(&ds, &ctx, "next_start_in_ms"), 500);
    clock.advance(Duration::from_millis(500));
    // The second failure doubles the wait (the status's properties are written one by one).
    wait_for(&ds, &ctx, "the second try, a doubled wait", || {
        int(&ds, &ctx, "restarts") == 1 && int(&ds, &ctx, "next_start_in_ms") == 1000
    });
    m.stop();
}

#[test]
fn settings_are_checked() {
    let bad = [
        (ModuleSpec::new("process"), "needs `command`"),
        (ModuleSpec::new("process").with("command", toml::Value::Array(vec![])), "needs"),
        (
            ModuleSpec::new("process")
                .with("command", toml::Value::Array(vec!["pythno3".into(), "x.py".into()])),
            "no program `pythno3` on PATH",
        ),
        (
            ModuleSpec::new("process")
                .with("command", toml::Value::Array(vec!["true".into()]))
                .with("restart_backoff_ms", 0),
            "`restart_backoff_ms` must be",
        ),
        (
            ModuleSpec::new("process")
                .with("command", toml::Value::Array(vec!["true".into()]))
                .with("restart_backoff_ms", 1000)
                .with("max_backoff_ms", 10),
            "at least",
        ),
    ];
    for (spec, want) in bad {
        let e = ProcessModule::from_spec(&spec).err().expect("refused");
        assert!(e.contains(want), "{e}");
    }
}
