//! A `set` of a property another process owns (its object publishes `write_at_owner`, as a
//! mirror of another site's vehicle does, docs/distribution.md "Forwarded writes") is sent to
//! the owner, not written here: the control shows pending, then the owner's outcome with its
//! reason, and the local value changes only when the owner's change arrives.
use mocu_dataserver::*;
use mocu_layout::*;
use parking_lot::Mutex;
use std::sync::Arc;
use std::time::Duration;

const LAYOUT: &str = r#"
let v = root.vehicles.usv1
watch go {
  when v.go
  then set v.goal_speed = 3
}
"#;

fn program(dir: &std::path::Path) -> mocu_language::Program {
    let path = dir.join("owned_elsewhere.mocu");
    std::fs::write(&path, LAYOUT).unwrap();
    match mocu_language::load_target(&path) {
        Ok((bundle, _)) => bundle.layouts.into_iter().next().unwrap().program,
        Err(e) => panic!("layout does not check:\n{e}"),
    }
}

fn feedback(ds: &DataServer) -> (Value, Value) {
    let fb = ds.resolve(&["operator", "feedback"]).expect("root.operator.feedback");
    (ds.get(fb, "state").unwrap(), ds.get(fb, "reason").unwrap())
}

#[test]
fn a_set_of_a_property_owned_elsewhere_shows_pending_then_the_owners_outcome() {
    for jit in [true, false] {
        let ds = DataServer::default();
        let vs = ds.create_object(Guid::ROOT, ObjectInfo::new("vehicles", "folder")).unwrap();
        let v = ds.create_object(vs, ObjectInfo::new("usv1", "usv")).unwrap();
        ds.set(v, "goal_speed", Value::Float(1.0)).unwrap();
        // The owner answers when the test says: its writes' arguments and responders wait here.
        type Waiting = Arc<Mutex<Vec<(Vec<Value>, Responder)>>>;
        let waiting: Waiting = Arc::default();
        let w = waiting.clone();
        let spec = MethodSpec::new(WRITE_AT_OWNER)
            .param(ParamSpec::new("name", ValueKind::String))
            .param(ParamSpec::any("value"));
        ds.publish_method(v, spec, move |c: Call| w.lock().push((c.args.to_vec(), c.responder)))
            .unwrap();
        let dir = tempfile::tempdir().unwrap();
        let config =
            LayoutConfig { tick: Duration::from_millis(1), jit, ..LayoutConfig::default() };
        let sink = Arc::new(MemorySink::default());
        let layout = Layout::load(&ds, &program(dir.path()), config, sink).unwrap();
        layout.settle();

        // Refused by the owner: the reason reaches the operator, the value never changes.
        ds.set(v, "go", Value::Bool(true)).unwrap();
        layout.settle();
        ds.quiesce();
        assert_eq!(feedback(&ds).0, Value::str("pending"), "jit {jit}");
        assert_eq!(ds.get(v, "goal_speed").unwrap(), Value::Float(1.0), "not written here");
        let (args, r) = waiting.lock().pop().expect("the write sent to its owner");
        assert_eq!(args, vec![Value::str("goal_speed"), Value::Float(3.0)]);
        r.reply(CallOutcome::Refused("usv1 is controlled by bob: request a takeover first".into()));
        ds.quiesce();
        assert_eq!(
            feedback(&ds),
            (
                Value::str("refused"),
                Value::str("usv1 is controlled by bob: request a takeover first")
            )
        );
        assert_eq!(ds.get(v, "goal_speed").unwrap(), Value::Float(1.0));

        // Accepted: the owner's change arrives (here, written as replication would).
        ds.set(v, "go", Value::Bool(false)).unwrap();
        layout.settle();
        ds.set(v, "go", Value::Bool(true)).unwrap();
        layout.settle();
        ds.quiesce();
        let (_, r) = waiting.lock().pop().expect("the second write sent to its owner");
        ds.set(v, "goal_speed", Value::Float(3.0)).unwrap();
        r.reply(CallOutcome::Accepted(vec![]));
        ds.quiesce();
        assert_eq!(feedback(&ds), (Value::str("accepted"), Value::str("")), "jit {jit}");
    }
}
