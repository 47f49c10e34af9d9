//! Dotted paths follow system discovery: objects appear, vanish, are renamed or replaced.
use mocu_dataserver::*;
use std::sync::{Arc, Mutex};

type Log = Arc<Mutex<Vec<(Kind, Option<Value>)>>>;

fn watch(ds: &DataServer, path: &str) -> (PathWatch, Log) {
    let log = Arc::new(Mutex::new(Vec::new()));
    let l = log.clone();
    let w = ds
        .watch_path(DottedPath::parse(path).unwrap(), None, move |e: &PathEvent| {
            l.lock().unwrap().push((e.kind, e.value.clone()))
        })
        .unwrap();
    (w, log)
}

fn take(ds: &DataServer, log: &Log) -> Vec<(Kind, Option<Value>)> {
    ds.quiesce();
    std::mem::take(&mut *log.lock().unwrap())
}

#[test]
fn a_path_becomes_reachable_level_by_level_as_objects_appear() {
    let ds = DataServer::default();
    let (w, log) = watch(&ds, "root.vehicles.usv1.nav.speed");
    assert!(take(&ds, &log).is_empty(), "only root exists: absent");
    let v = ds.create_object(Guid::ROOT, ObjectInfo::new("vehicles", "folder")).unwrap();
    let u = ds.create_object(v, ObjectInfo::new("usv1", "usv")).unwrap();
    let nav = ds.create_object(u, ObjectInfo::new("nav", "nav")).unwrap();
    assert!(take(&ds, &log).is_empty());
    ds.set(nav, "speed", Value::Float(1.5)).unwrap();
    assert_eq!(take(&ds, &log), [(Kind::New, Some(Value::Float(1.5)))]);
    ds.set(nav, "speed", Value::Float(2.0)).unwrap();
    assert_eq!(take(&ds, &log), [(Kind::Changed, Some(Value::Float(2.0)))]);
    assert_eq!(w.bound_object(), Some(nav));
}

#[test]
fn a_path_that_exists_already_is_reported_new_at_once() {
    let ds = DataServer::default();
    let u = ds.create_object(Guid::ROOT, ObjectInfo::new("usv1", "usv")).unwrap();
    ds.set(u, "fuel", Value::Float(0.5)).unwrap();
    let (_w, log) = watch(&ds, "usv1.fuel");
    assert_eq!(take(&ds, &log), [(Kind::New, Some(Value::Float(0.5)))]);
}

#[test]
fn a_vanishing_object_makes_the_property_deleted_and_a_replacement_rebinds() {
    let ds = DataServer::default();
    let v = ds.create_object(Guid::ROOT, ObjectInfo::new("vehicles", "folder")).unwrap();
    let u = ds.create_object(v, ObjectInfo::new("usv1", "usv")).unwrap();
    ds.set(u, "fuel", Value::Float(0.5)).unwrap();
    let (_w, log) = watch(&ds, "root.vehicles.usv1.fuel");
    assert_eq!(take(&ds, &log), [(Kind::New, Some(Value::Float(0.5)))]);
    ds.delete_object(u).unwrap();
    assert_eq!(take(&ds, &log), [(Kind::Deleted, None)]);
    let u2 = ds.create_object(v, ObjectInfo::new("usv1", "usv")).unwrap();
    ds.set(u2, "fuel", Value::Float(0.9)).unwrap();
    assert_eq!(take(&ds, &log), [(Kind::New, Some(Value::Float(0.9)))]);
}

#[test]
fn renames_along_the_path_unbind_and_rebind() {
    let ds = DataServer::default();
    let u = ds.create_object(Guid::ROOT, ObjectInfo::new("usv1", "usv")).unwrap();
    ds.set(u, "fuel", Value::Float(0.5)).unwrap();
    let other = ds.create_object(Guid::ROOT, ObjectInfo::new("spare", "usv")).unwrap();
    ds.set(other, "fuel", Value::Float(0.7)).unwrap();
    let (_w, log) = watch(&ds, "usv1.fuel");
    assert_eq!(take(&ds, &log), [(Kind::New, Some(Value::Float(0.5)))]);
    ds.set_info(u, ObjectInfo::new("old", "usv")).unwrap();
    assert_eq!(take(&ds, &log), [(Kind::Deleted, None)]);
    ds.set_info(other, ObjectInfo::new("usv1", "usv")).unwrap();
    assert_eq!(take(&ds, &log), [(Kind::New, Some(Value::Float(0.7)))]);
}

#[test]
fn the_end_property_itself_can_come_and_go() {
    let ds = DataServer::default();
    let u = ds.create_object(Guid::ROOT, ObjectInfo::new("usv1", "usv")).unwrap();
    let (_w, log) = watch(&ds, "usv1.armed");
    ds.set(u, "armed", Value::Bool(true)).unwrap();
    ds.quiesce();
    ds.delete_property(u, "armed").unwrap();
    ds.quiesce();
    ds.set(u, "armed", Value::Bool(false)).unwrap();
    assert_eq!(
        take(&ds, &log),
        [
            (Kind::New, Some(Value::Bool(true))),
            (Kind::Deleted, None),
            (Kind::New, Some(Value::Bool(false)))
        ]
    );
}

#[test]
fn an_object_inserted_between_breaks_the_path_until_it_matches_again() {
    let ds = DataServer::default();
    let r = ds.create_object(Guid::ROOT, ObjectInfo::new("route", "route")).unwrap();
    let wp = ds.create_object(r, ObjectInfo::new("wp", "waypoint")).unwrap();
    ds.set(wp, "x", Value::Int(1)).unwrap();
    let (_w, log) = watch(&ds, "route.wp.x");
    assert_eq!(take(&ds, &log), [(Kind::New, Some(Value::Int(1)))]);
    let mid = ds.insert_between(r, wp, ObjectInfo::new("mid", "waypoint")).unwrap();
    assert_eq!(take(&ds, &log), [(Kind::Deleted, None)]);
    ds.delete_and_promote(mid, wp).unwrap();
    assert_eq!(take(&ds, &log), [(Kind::New, Some(Value::Int(1)))]);
}

#[test]
fn cancelling_a_watch_removes_every_subscription_it_made() {
    let ds = DataServer::default();
    let a = ds.create_object(Guid::ROOT, ObjectInfo::new("a", "t")).unwrap();
    ds.create_object(a, ObjectInfo::new("b", "t")).unwrap();
    for _ in 0..100 {
        let (w, _log) = watch(&ds, "a.b.c");
        ds.quiesce();
        assert_eq!(ds.subscription_count(), 3);
        w.cancel();
    }
    assert_eq!(ds.subscription_count(), 0);
}

#[test]
fn a_path_can_start_at_any_object() {
    let ds = DataServer::default();
    let v = ds.create_object(Guid::ROOT, ObjectInfo::new("vehicles", "folder")).unwrap();
    let u = ds.create_object(v, ObjectInfo::new("usv1", "usv")).unwrap();
    let nav = ds.create_object(u, ObjectInfo::new("nav", "nav")).unwrap();
    ds.set(nav, "speed", Value::Float(3.0)).unwrap();
    let log = Arc::new(Mutex::new(Vec::new()));
    let l = log.clone();
    let _w = ds
        .watch_path_from(u, DottedPath::parse("nav.speed").unwrap(), None, move |e: &PathEvent| {
            l.lock().unwrap().push((e.kind, e.value.clone()))
        })
        .unwrap();
    assert_eq!(take(&ds, &log), [(Kind::New, Some(Value::Float(3.0)))]);
}

#[test]
fn an_object_watch_reports_the_object_as_it_comes_and_goes() {
    let ds = DataServer::default();
    let log = Arc::new(Mutex::new(Vec::new()));
    let l = log.clone();
    let _w = ds
        .watch_object(Guid::ROOT, &["vehicles", "usv1"], None, move |e: &PathEvent| {
            l.lock().unwrap().push((e.kind, e.object))
        })
        .unwrap();
    let v = ds.create_object(Guid::ROOT, ObjectInfo::new("vehicles", "folder")).unwrap();
    let u = ds.create_object(v, ObjectInfo::new("usv1", "usv")).unwrap();
    ds.quiesce();
    ds.delete_object(u).unwrap();
    ds.quiesce();
    let u2 = ds.create_object(v, ObjectInfo::new("usv1", "usv")).unwrap();
    ds.quiesce();
    assert_eq!(*log.lock().unwrap(), [(Kind::New, u), (Kind::Deleted, u), (Kind::New, u2)]);
}
