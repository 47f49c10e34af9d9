//! The operations the properties run, and their proptest strategies.

use mocu_dataserver::{ObjectInfo, PropMeta, Value, ValueKind};
use proptest::prelude::*;

pub(crate) const PROP_NAMES: [&str; 4] = ["a", "b", "c", "d"];
const OBJ_NAMES: [&str; 3] = ["x", "y", "z"];
const OBJ_KINDS: [&str; 2] = ["robot", "sensor"];

/// One operation. Objects, children and subscriptions are chosen by selector bytes that are
/// resolved against the model's state when the operation runs (mostly live objects, now and
/// then a deleted or never-created one).
#[derive(Clone, Debug)]
pub(crate) enum Op {
    Create {
        parent: u8,
        info: ObjectInfo,
    },
    CreateAt {
        parent: u8,
        index: usize,
        info: ObjectInfo,
    },
    InsertBetween {
        parent: u8,
        child: u8,
        info: ObjectInfo,
    },
    Delete {
        obj: u8,
    },
    DeleteAndPromote {
        obj: u8,
        keep: u8,
    },
    SetInfo {
        obj: u8,
        info: ObjectInfo,
    },
    Set {
        obj: u8,
        prop: usize,
        value: Value,
    },
    CreateProperty {
        obj: u8,
        prop: usize,
        value: Value,
        meta: PropMeta,
    },
    Update {
        obj: u8,
        prop: usize,
        value: Value,
    },
    DeleteProperty {
        obj: u8,
        prop: usize,
    },
    SubscribeProperties {
        obj: u8,
        names: Option<Vec<usize>>,
        on: Option<usize>,
    },
    SubscribeChildren {
        obj: u8,
        on: Option<usize>,
    },
    Unsubscribe {
        sub: u8,
    },
    /// Holds every callback back at its next notification, so changes pile up (only in the
    /// variant without quiesce).
    Hold,
    Release,
}

fn info() -> impl Strategy<Value = ObjectInfo> {
    (0..OBJ_NAMES.len(), 0..OBJ_KINDS.len(), any::<bool>()).prop_map(|(n, k, sub)| {
        let i = ObjectInfo::new(OBJ_NAMES[n], OBJ_KINDS[k]);
        if sub { i.subtype("mk2") } else { i }
    })
}

fn value() -> impl Strategy<Value = Value> {
    prop_oneof![
        3 => (-3i64..=3).prop_map(Value::Int),
        2 => prop_oneof![
            Just(0.0),
            Just(-0.0),
            Just(1.5),
            Just(-2.5),
            Just(3.0),
            Just(f64::NAN),
            Just(f64::INFINITY),
        ]
        .prop_map(Value::Float),
        1 => any::<bool>().prop_map(Value::Bool),
        1 => prop_oneof![Just("up"), Just("down")].prop_map(Value::str),
    ]
}

fn meta() -> impl Strategy<Value = PropMeta> {
    let kind = prop::option::of(prop_oneof![
        Just(ValueKind::Int),
        Just(ValueKind::Float),
        Just(ValueKind::Bool),
        Just(ValueKind::String),
    ]);
    let range = prop::option::of(prop_oneof![Just((-2.0, 2.0)), Just((0.0, 3.0))]);
    (kind, range, any::<bool>()).prop_map(|(kind, range, units)| {
        let m = PropMeta { kind, range, ..PropMeta::default() };
        if units { m.units("m/s") } else { m }
    })
}

pub(crate) fn op() -> impl Strategy<Value = Op> {
    let prop = 0..PROP_NAMES.len();
    let on = prop::option::of(0..2usize);
    prop_oneof![
        5 => (any::<u8>(), info()).prop_map(|(parent, info)| Op::Create { parent, info }),
        2 => (any::<u8>(), 0..4usize, info())
            .prop_map(|(parent, index, info)| Op::CreateAt { parent, index, info }),
        2 => (any::<u8>(), any::<u8>(), info())
            .prop_map(|(parent, child, info)| Op::InsertBetween { parent, child, info }),
        2 => any::<u8>().prop_map(|obj| Op::Delete { obj }),
        2 => (any::<u8>(), any::<u8>()).prop_map(|(obj, keep)| Op::DeleteAndPromote { obj, keep }),
        3 => (any::<u8>(), info()).prop_map(|(obj, info)| Op::SetInfo { obj, info }),
        8 => (any::<u8>(), prop.clone(), value())
            .prop_map(|(obj, prop, value)| Op::Set { obj, prop, value }),
        3 => (any::<u8>(), prop.clone(), value(), meta())
            .prop_map(|(obj, prop, value, meta)| Op::CreateProperty { obj, prop, value, meta }),
        4 => (any::<u8>(), prop.clone(), value())
            .prop_map(|(obj, prop, value)| Op::Update { obj, prop, value }),
        2 => (any::<u8>(), prop.clone()).prop_map(|(obj, prop)| Op::DeleteProperty { obj, prop }),
        3 => (any::<u8>(), prop::option::of(prop::collection::vec(prop, 1..3)), on.clone())
            .prop_map(|(obj, names, on)| Op::SubscribeProperties { obj, names, on }),
        3 => (any::<u8>(), on).prop_map(|(obj, on)| Op::SubscribeChildren { obj, on }),
        1 => any::<u8>().prop_map(|sub| Op::Unsubscribe { sub }),
    ]
}

pub(crate) fn op_or_hold() -> impl Strategy<Value = Op> {
    prop_oneof![12 => op(), 2 => Just(Op::Hold), 1 => Just(Op::Release)]
}
