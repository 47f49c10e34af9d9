//! Method calls from a layout reach the method as its parameters take them: a whole number
//! goes to an `int` parameter as an int, and a path to an object as the object's GUID.
use mocu_dataserver::*;
use mocu_layout::*;
use std::sync::{Arc, Mutex};
use std::time::Duration;

const LAYOUT: &str = r#"
let v = root.vehicles.usv1
watch go {
  when v.go
  then call v.routes.survey.insert_waypoint(1, 2.5, 3)
       call v.upload_route(v.routes.survey)
       call v.routes.survey.insert_waypoint(v.index, 0, 0)
}
"#;

fn program(dir: &std::path::Path, text: &str) -> mocu_language::Program {
    let path = dir.join("calls.mocu");
    std::fs::write(&path, text).unwrap();
    match mocu_language::load_target(&path) {
        Ok((bundle, _)) => bundle.layouts.into_iter().next().unwrap().program,
        Err(e) => panic!("layout does not check:\n{e}"),
    }
}

#[test]
fn a_layout_passes_whole_numbers_to_int_parameters_and_objects_as_their_guid() {
    for jit in [true, false] {
        let ds = DataServer::default();
        let vs = ds.create_object(Guid::ROOT, ObjectInfo::new("vehicles", "folder")).unwrap();
        let v = ds.create_object(vs, ObjectInfo::new("usv1", "usv")).unwrap();
        let routes = ds.create_object(v, ObjectInfo::new("routes", "routes")).unwrap();
        let survey = ds.create_object(routes, ObjectInfo::new("survey", "route")).unwrap();
        ds.set(v, "index", Value::Float(4.0)).unwrap();
        type Calls = Arc<Mutex<Vec<(String, Vec<Value>)>>>;
        let seen: Calls = Arc::default();
        let record = |name: &'static str| {
            let seen = seen.clone();
            move |call: Call| {
                seen.lock().unwrap().push((name.to_string(), call.args.to_vec()));
                call.responder.reply(CallOutcome::Accepted(vec![]));
            }
        };
        // As the vehicle's module does, on its serial executor: calls queued on the pool may
        // run in any order (docs/dataserver.md); the order asserted is the layout's.
        let exec = ds.serial_executor();
        let insert = MethodSpec::new("insert_waypoint")
            .param(ParamSpec::new("index", ValueKind::Int))
            .param(ParamSpec::new("a", ValueKind::Float))
            .param(ParamSpec::new("b", ValueKind::Float));
        ds.publish_method_on(&exec, survey, insert, record("insert")).unwrap();
        let upload =
            MethodSpec::new("upload_route").param(ParamSpec::new("route", ValueKind::Guid));
        ds.publish_method_on(&exec, v, upload, record("upload")).unwrap();
        let dir = tempfile::tempdir().unwrap();
        let config =
            LayoutConfig { tick: Duration::from_millis(1), jit, ..LayoutConfig::default() };
        let sink = Arc::new(MemorySink::default());
        let layout = Layout::load(&ds, &program(dir.path(), LAYOUT), config, sink.clone()).unwrap();
        layout.settle();
        ds.set(v, "go", Value::Bool(true)).unwrap();
        layout.settle();
        ds.quiesce();
        let got = seen.lock().unwrap().clone();
        let want = vec![
            ("insert".to_string(), vec![Value::Int(1), Value::Float(2.5), Value::Float(3.0)]),
            ("upload".to_string(), vec![Value::Guid(survey)]),
            ("insert".to_string(), vec![Value::Int(4), Value::Float(0.0), Value::Float(0.0)]),
        ];
        assert_eq!(got, want, "jit {jit}; feedback: {:?}", sink.of("feedback"));
    }
}
