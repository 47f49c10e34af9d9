//! The input module as `mocu run` starts it: gilrs with no gamepad, a scripted pad
//! replayed in real time, the window's keyboard through a method, the default selection.

mod common;
use common::program;
use mocu_dataserver::{DataServer, Guid, PropName, Topic, Value};
use mocu_host::{Module, ModuleContext};
use mocu_input::{GilrsSource, InputConfig, InputModule, ScriptedSource};
use mocu_layout::{Layout, LayoutConfig, MemorySink};
use mocu_sim::{Sim, SimConfig};
use std::sync::Arc;
use std::time::Duration;

/// Waits until `f` holds, checking it again at each change of `object`'s properties (the
/// event it waits for); the 20 s bound only turns a hang into a failure.
fn eventually(ds: &DataServer, object: Guid, what: &str, mut f: impl FnMut() -> bool) {
    let (tx, rx) = std::sync::mpsc::channel();
    let sub = ds
        .subscribe(Topic::properties(object), move |_| {
            let _ = tx.send(());
        })
        .unwrap();
    while !f() {
        if rx.recv_timeout(Duration::from_secs(20)).is_err() {
            ds.unsubscribe(sub);
            panic!("never: {what}");
        }
    }
    ds.unsubscribe(sub);
}

#[test]
fn gilrs_starts_cleanly_with_no_gamepad() {
    let p = GilrsSource::probe().expect("gilrs opens with no gamepad and no udev devices");
    assert_eq!(p.pads, vec![], "this machine has no gamepad (and no /dev/uinput)");
    // And as part of the module: it starts, runs, stops.
    let ds = DataServer::default();
    let mut m = InputModule::new(InputConfig::default());
    m.start(&ModuleContext::detached("input", ds.clone())).unwrap();
    // Stopping joins the gilrs thread, which opens gilrs first (the probe above found no pad).
    m.stop();
    ds.quiesce();
    assert!(ds.resolve(&["operator", "inputs", "gamepad1"]).is_none());
}

#[test]
fn a_scripted_gamepad_and_the_keyboard_drive_a_simulated_vehicle() {
    let ds = DataServer::default();
    let sim = Sim::new(
        ModuleContext::detached("sim", ds.clone()),
        SimConfig { usv: 1, ugv: 0, uav: 0, autostart: false, ..SimConfig::default() },
    )
    .unwrap();
    sim.step(0.1);
    let script = ScriptedSource::parse(
        "0 pad connect gamepad \"Scripted Pad\"\n\
         20 pad axis left_y 0.5\n\
         40 pad axis left_y 0.75\n\
         60 pad press south\n\
         80 pad release south\n",
    )
    .unwrap();
    let cfg = InputConfig { gilrs: false, ..InputConfig::default() };
    let mut m = InputModule::new(cfg).with_source(Box::new(script));
    m.start(&ModuleContext::detached("input", ds.clone())).unwrap();
    let usv = ds.resolve(&["vehicles", "usv1"]).unwrap();
    let op = ds.resolve(&["operator"]).unwrap();
    eventually(&ds, op, "the first vehicle is selected", || {
        ds.try_get(op, PropName::new("selected")) == Some(Value::Guid(usv))
    });
    let sink = Arc::new(MemorySink::default());
    let text = r#"
      bind gamepad {
        axis left_y scale 100 -> set selected.nav.goal_throttle = axis
        button south -> call selected.arm(true)
      }
      bind keyboard { key space -> call selected.stop() }
    "#;
    let layout = Layout::load(&ds, &program(text), LayoutConfig::default(), sink.clone()).unwrap();
    // The script starts when the bindings appear.
    let nav = ds.resolve(&["vehicles", "usv1", "nav"]).unwrap();
    eventually(&ds, nav, "the stick drives the goal", || {
        ds.try_get(nav, PropName::new("goal_throttle")) == Some(Value::Float(75.0))
    });
    eventually(&ds, usv, "south armed the vehicle", || {
        ds.try_get(usv, PropName::new("armed")) == Some(Value::Bool(true))
    });
    let pad = ds.resolve(&["operator", "inputs", "gamepad1"]).unwrap();
    assert_eq!(ds.get(pad, "name").unwrap(), Value::str("Scripted Pad"));
    // The window hands keys to `root.operator.inputs.keyboard.key(name, pressed)`.
    let kb = ds.resolve(&["operator", "inputs", "keyboard"]).unwrap();
    assert!(
        ds.call_wait(kb, "key", vec![Value::str("space"), Value::Bool(true)], None).is_accepted()
    );
    ds.quiesce();
    eventually(&ds, nav, "space stopped the vehicle (its goals back to 0)", || {
        ds.try_get(nav, PropName::new("goal_throttle")) == Some(Value::Float(0.0))
    });
    let calls = format!("{:?}", sink.of("call"));
    assert!(calls.contains("usv1.arm") && calls.contains("usv1.stop"), "{calls}");
    m.stop();
    drop(layout);
}
