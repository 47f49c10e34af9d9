//! The object tree and properties: create, read, update, delete, ordering, metadata.
mod common;
use common::names;
use mocu_dataserver::*;

fn obj(ds: &DataServer, parent: Guid, name: &str) -> Guid {
    ds.create_object(parent, ObjectInfo::new(name, "thing")).unwrap()
}

#[test]
fn objects_get_unique_guids_and_keep_their_attributes() {
    let ds = DataServer::default();
    let v = ds.create_object(Guid::ROOT, ObjectInfo::new("vehicles", "folder")).unwrap();
    let u = ds.create_object(v, ObjectInfo::new("usv1", "usv").subtype("wamv")).unwrap();
    assert_ne!(u, v);
    assert_ne!(u, Guid::ROOT);
    let info = ds.info(u).unwrap();
    assert_eq!((&*info.name, &*info.kind, &*info.subtype), ("usv1", "usv", "wamv"));
    assert_eq!(ds.parent(u).unwrap(), Some(v));
    assert_eq!(ds.find_child(v, "usv1").unwrap(), Some(u));
    assert_eq!(ds.find_child(v, "usv9").unwrap(), None);
    assert_eq!(ds.resolve(&["vehicles", "usv1"]), Some(u));
}

#[test]
fn children_are_ordered_and_can_be_inserted_at_a_position() {
    let ds = DataServer::default();
    let r = obj(&ds, Guid::ROOT, "route");
    obj(&ds, r, "a");
    obj(&ds, r, "c");
    ds.create_object_at(r, 1, ObjectInfo::new("b", "waypoint")).unwrap();
    ds.create_object_at(r, 99, ObjectInfo::new("d", "waypoint")).unwrap();
    assert_eq!(names(&ds, r), ["a", "b", "c", "d"]);
}

#[test]
fn insert_between_puts_the_new_object_in_the_childs_place() {
    let ds = DataServer::default();
    let p = obj(&ds, Guid::ROOT, "p");
    let a = obj(&ds, p, "a");
    let b = obj(&ds, p, "b");
    let c = obj(&ds, p, "c");
    let x = ds.insert_between(p, b, ObjectInfo::new("x", "thing")).unwrap();
    assert_eq!(ds.children(p).unwrap(), [a, x, c]);
    assert_eq!(ds.children(x).unwrap(), [b]);
    assert_eq!(ds.parent(b).unwrap(), Some(x));
    let err = ds.insert_between(p, b, ObjectInfo::new("y", "thing")).unwrap_err();
    assert!(matches!(err, DsError::NotAChild { .. }), "{err}");
}

#[test]
fn delete_and_promote_keeps_the_position_and_deletes_the_rest() {
    let ds = DataServer::default();
    let p = obj(&ds, Guid::ROOT, "p");
    let a = obj(&ds, p, "a");
    let mid = obj(&ds, p, "mid");
    let z = obj(&ds, p, "z");
    let keep = obj(&ds, mid, "keep");
    let other = obj(&ds, mid, "other");
    let deep = obj(&ds, other, "deep");
    ds.delete_and_promote(mid, keep).unwrap();
    assert_eq!(ds.children(p).unwrap(), [a, keep, z]);
    assert_eq!(ds.parent(keep).unwrap(), Some(p));
    for gone in [mid, other, deep] {
        assert!(!ds.exists(gone));
    }
}

#[test]
fn deleting_a_parent_deletes_its_whole_subtree() {
    let ds = DataServer::default();
    let a = obj(&ds, Guid::ROOT, "a");
    let b = obj(&ds, a, "b");
    let c = obj(&ds, b, "c");
    ds.set(c, "x", Value::Int(1)).unwrap();
    let before = ds.object_count();
    ds.delete_object(a).unwrap();
    assert_eq!(ds.object_count(), before - 3);
    assert!(!ds.exists(b) && !ds.exists(c));
    assert!(matches!(ds.get(c, "x"), Err(DsError::NoSuchObject { .. })));
    assert_eq!(ds.delete_object(Guid::ROOT), Err(DsError::RootIsPermanent));
}

#[test]
fn properties_keep_creation_order_and_values_are_immutable_snapshots() {
    let ds = DataServer::default();
    let o = obj(&ds, Guid::ROOT, "o");
    for (i, n) in ["z", "a", "m"].iter().enumerate() {
        ds.set(o, *n, Value::Int(i as i64)).unwrap();
    }
    let names: Vec<String> = ds.properties(o).unwrap().iter().map(|(n, _)| n.to_string()).collect();
    assert_eq!(names, ["z", "a", "m"]);
    let list = Value::list([Value::str("wp1"), Value::set([Value::Int(2), Value::Int(1)])]);
    ds.set(o, "l", list.clone()).unwrap();
    let read = ds.get(o, "l").unwrap();
    assert_eq!(read, list);
    ds.set(o, "l", Value::Int(0)).unwrap();
    assert_eq!(read, list, "a value read earlier is not changed by a later write");
}

#[test]
fn many_properties_on_one_object_are_found_by_name() {
    let ds = DataServer::default();
    let o = obj(&ds, Guid::ROOT, "o");
    for i in 0..100 {
        ds.set(o, format!("p{i}").as_str(), Value::Int(i)).unwrap();
    }
    ds.delete_property(o, "p10").unwrap();
    for i in 0..100 {
        let got = ds.try_get(o, PropName::new(&format!("p{i}")));
        assert_eq!(got, (i != 10).then_some(Value::Int(i)));
    }
}

#[test]
fn typed_properties_refuse_wrong_types_and_out_of_range_writes() {
    let ds = DataServer::default();
    let o = obj(&ds, Guid::ROOT, "usv1");
    let meta = PropMeta::typed(ValueKind::Float).units("%").range(-100.0, 100.0);
    ds.create_property(o, "goal_throttle", Value::Float(0.0), meta.clone()).unwrap();
    assert_eq!(ds.meta(o, "goal_throttle").unwrap(), meta);
    let e = ds.set(o, "goal_throttle", Value::str("fast")).unwrap_err();
    assert!(matches!(e, DsError::TypeMismatch { .. }));
    let text = e.to_string();
    assert!(text.contains("goal_throttle") && text.contains("usv1"), "{text}");
    let e = ds.set(o, "goal_throttle", Value::Float(150.0)).unwrap_err();
    assert!(matches!(e, DsError::OutOfRange { .. }), "{e}");
    assert!(e.to_string().contains("-100"), "{e}");
    assert_eq!(ds.get(o, "goal_throttle").unwrap(), Value::Float(0.0), "nothing changed");
    ds.set(o, "goal_throttle", Value::Int(50)).unwrap();
    assert_eq!(ds.get(o, "goal_throttle").unwrap(), Value::Float(50.0), "ints widen to float");
    assert!(ds.set(o, "goal_throttle", Value::Float(f64::NAN)).is_err(), "NaN is not in range");
}

#[test]
fn update_requires_an_existing_property_but_set_creates_one() {
    let ds = DataServer::default();
    let o = obj(&ds, Guid::ROOT, "o");
    assert!(matches!(ds.update(o, "x", Value::Int(1)), Err(DsError::NoSuchProperty { .. })));
    ds.set(o, "x", Value::Int(1)).unwrap();
    ds.update(o, "x", Value::Int(2)).unwrap();
    assert_eq!(ds.get(o, "x").unwrap(), Value::Int(2));
    assert!(matches!(
        ds.create_property(o, "x", Value::Int(3), PropMeta::default()),
        Err(DsError::PropertyExists { .. })
    ));
}

#[test]
fn renaming_an_object_changes_what_find_child_sees() {
    let ds = DataServer::default();
    let o = obj(&ds, Guid::ROOT, "old");
    ds.set_info(o, ObjectInfo::new("new", "thing")).unwrap();
    assert_eq!(ds.find_child(Guid::ROOT, "new").unwrap(), Some(o));
    assert_eq!(ds.find_child(Guid::ROOT, "old").unwrap(), None);
}

#[test]
fn a_snapshot_prints_as_the_dump_json_contract() {
    let ds = DataServer::default();
    let v = obj(&ds, Guid::ROOT, "vehicles");
    let u = ds.create_object(v, ObjectInfo::new("usv1", "usv")).unwrap();
    ds.set(u, "speed", Value::Float(2.5)).unwrap();
    ds.set(u, "name", Value::str("USV \"one\"")).unwrap();
    let json = ds.snapshot(v).unwrap().to_json();
    assert!(json.contains("\"name\": \"usv1\""), "{json}");
    assert!(json.contains("\"type\": \"usv\""), "{json}");
    assert!(json.contains("\"speed\": 2.5"), "{json}");
    assert!(json.contains(r#""USV \"one\"""#), "{json}");
    assert!(json.contains("\"guid\": "), "{json}");
    assert!(json.contains("\"children\": ["), "{json}");
}
