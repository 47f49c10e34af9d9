//! Properties: create, write, read, delete, and the type and range rules every write obeys.
//! A write checks and stores under the object's lock in one step, so no race (a delete
//! between a check and the store) can bypass the rules.

use crate::error::{DsError, ObjRef};
use crate::feed::Change;
use crate::meta::PropMeta;
use crate::notification::{Kind, Notification};
use crate::object::{ObjState, Prop};
use crate::server::{DataServer, obj_ref_of};
use crate::subscription::Sub;
use mocu_value::{Guid, PropName, Value, ValueKind};
use std::sync::Arc;
use std::time::Instant;

/// What a write does when the property is absent.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Absent {
    Create,
    Refuse,
}

impl DataServer {
    /// Creates a property with metadata; refused if the name is taken or the value does
    /// not fit the metadata.
    pub fn create_property(
        &self,
        guid: Guid,
        name: impl Into<PropName>,
        value: Value,
        meta: PropMeta,
    ) -> Result<(), DsError> {
        let name = name.into();
        let o = self.object(guid)?;
        let now = self.now();
        let mut os = o.state.write();
        if !os.alive {
            return Err(DsError::NoSuchObject { object: ObjRef::unnamed(guid) });
        }
        if os.props.get(name).is_some() {
            return Err(DsError::PropertyExists { object: obj_ref_of(guid, &os), property: name });
        }
        let value = validate(guid, &os, name, &meta, value)?;
        let meta = (meta != PropMeta::default()).then(|| Arc::new(meta));
        self.emit_at(now, || Change::PropertySet {
            object: guid,
            name,
            value: value.clone(),
            meta: meta.clone(),
            created: true,
        });
        add_prop(&mut os, name, value, meta, now);
        Ok(())
    }

    /// Writes a property, creating it (untyped) if absent. A write equal to the current
    /// value changes nothing and notifies nobody (it still counts as received: see
    /// [`DataServer::received_at`]).
    pub fn set(&self, guid: Guid, name: impl Into<PropName>, value: Value) -> Result<(), DsError> {
        self.write(guid, name.into(), value, Absent::Create)
    }

    /// Writes an existing property; refused if it does not exist (never creates one, even
    /// when a delete races the write).
    pub fn update(
        &self,
        guid: Guid,
        name: impl Into<PropName>,
        value: Value,
    ) -> Result<(), DsError> {
        self.write(guid, name.into(), value, Absent::Refuse)
    }

    fn write(
        &self,
        guid: Guid,
        name: PropName,
        value: Value,
        absent: Absent,
    ) -> Result<(), DsError> {
        let o = self.object(guid)?;
        let now = self.now();
        let mut guard = o.state.write();
        let os = &mut *guard;
        if !os.alive {
            return Err(DsError::NoSuchObject { object: ObjRef::unnamed(guid) });
        }
        let Some(p) = os.props.get_mut(name) else {
            if absent == Absent::Refuse {
                return Err(DsError::NoSuchProperty {
                    object: obj_ref_of(guid, os),
                    property: name,
                });
            }
            self.emit_at(now, || Change::PropertySet {
                object: guid,
                name,
                value: value.clone(),
                meta: None,
                created: true,
            });
            add_prop(os, name, value, None, now);
            return Ok(());
        };
        let value = match &p.meta {
            Some(meta) => check(meta, value).map_err(|e| e.at(guid, &os.info.name, name))?,
            None => value,
        };
        p.received = now;
        if unchanged(&p.value, &value) {
            return Ok(());
        }
        p.value = value.clone();
        // Metadata never changes after creation: a reader has it from `created`.
        self.emit_value(now, guid, name, &mut p.number, &value);
        notify_prop(&os.prop_subs, guid, Kind::Changed, name, Some(value));
        Ok(())
    }

    /// When the property last received a write on the server's clock — any write, one equal
    /// to the current value included (which notifies nobody) — or its creation. `None` when
    /// the object has no such property; an error when the object does not exist.
    pub fn received_at(
        &self,
        guid: Guid,
        name: impl Into<PropName>,
    ) -> Result<Option<Instant>, DsError> {
        let name = name.into();
        let o = self.object(guid)?;
        let os = o.state.read();
        Ok(os.props.get(name).map(|p| p.received))
    }

    /// Reads a property's current value.
    pub fn get(&self, guid: Guid, name: impl Into<PropName>) -> Result<Value, DsError> {
        let name = name.into();
        let o = self.object(guid)?;
        let os = o.state.read();
        match os.props.get(name) {
            Some(p) => Ok(p.value.clone()),
            None => Err(DsError::NoSuchProperty { object: obj_ref_of(guid, &os), property: name }),
        }
    }

    /// Reads a property, `None` when the object or the property is absent.
    pub fn try_get(&self, guid: Guid, name: PropName) -> Option<Value> {
        let objects = self.inner.objects.pin();
        let o = objects.get(&guid)?;
        let os = o.state.read();
        os.props.get(name).map(|p| p.value.clone())
    }

    pub fn meta(&self, guid: Guid, name: impl Into<PropName>) -> Result<PropMeta, DsError> {
        let name = name.into();
        let o = self.object(guid)?;
        let os = o.state.read();
        match os.props.get(name) {
            Some(p) => Ok(p.meta.as_deref().cloned().unwrap_or_default()),
            None => Err(DsError::NoSuchProperty { object: obj_ref_of(guid, &os), property: name }),
        }
    }

    /// The object's properties with their values, in creation order.
    pub fn properties(&self, guid: Guid) -> Result<Vec<(PropName, Value)>, DsError> {
        let o = self.object(guid)?;
        let os = o.state.read();
        Ok(os.props.iter().map(|p| (p.name, p.value.clone())).collect())
    }

    pub fn delete_property(&self, guid: Guid, name: impl Into<PropName>) -> Result<(), DsError> {
        let name = name.into();
        let o = self.object(guid)?;
        let mut os = o.state.write();
        if os.props.remove(name).is_none() {
            return Err(DsError::NoSuchProperty { object: obj_ref_of(guid, &os), property: name });
        }
        self.emit(|| Change::PropertyDeleted { object: guid, name });
        notify_prop(&os.prop_subs, guid, Kind::Deleted, name, None);
        Ok(())
    }
}

/// Whether writing `new` over `old` is no change: equal by the values' total order, where
/// additionally any NaN equals any other NaN (whatever its payload or sign), also inside
/// lists and sets. In a set every NaN is the same element: sets are compared with their
/// NaNs made one (which moves them where the total order sorts it, and merges them).
pub(crate) fn unchanged(old: &Value, new: &Value) -> bool {
    match (old, new) {
        (Value::Float(a), Value::Float(b)) => {
            (a.is_nan() && b.is_nan()) || a.to_bits() == b.to_bits()
        }
        (Value::List(a), Value::List(b)) => {
            a.len() == b.len() && a.iter().zip(b.iter()).all(|(x, y)| unchanged(x, y))
        }
        (Value::Set(_), Value::Set(_)) => {
            let (Value::Set(a), Value::Set(b)) = (one_nan(old), one_nan(new)) else {
                unreachable!("one_nan keeps a set a set")
            };
            a.len() == b.len() && a.iter().zip(b.iter()).all(|(x, y)| unchanged(x, y))
        }
        _ => old == new,
    }
}

/// `v` with every NaN in it (nested ones included) made the same NaN, sets re-sorted and
/// merged accordingly.
fn one_nan(v: &Value) -> Value {
    match v {
        Value::Float(x) if x.is_nan() => Value::Float(f64::NAN),
        Value::List(l) => Value::list(l.iter().map(one_nan)),
        Value::Set(s) => Value::set(s.iter().map(one_nan)),
        _ => v.clone(),
    }
}

fn add_prop(
    os: &mut ObjState,
    name: PropName,
    value: Value,
    meta: Option<Arc<PropMeta>>,
    now: Instant,
) {
    os.props.insert(Prop { name, value: value.clone(), meta, received: now, number: 0 });
    notify_prop(&os.prop_subs, os.self_guid, Kind::New, name, Some(value));
}

pub(crate) fn notify_prop(
    subs: &[Arc<Sub>],
    guid: Guid,
    kind: Kind,
    name: PropName,
    value: Option<Value>,
) {
    for s in subs.iter().filter(|s| s.wants(name)) {
        s.enqueue(Notification {
            object: guid,
            kind,
            subject: crate::notification::Subject::Property { name, value: value.clone() },
        });
    }
}

/// A refusal by the metadata, before it is given the object's and property's names.
enum Refusal {
    Type { expected: ValueKind, got: ValueKind },
    Range { value: f64, min: f64, max: f64 },
}

impl Refusal {
    fn at(self, guid: Guid, object: &Arc<str>, property: PropName) -> DsError {
        let object = ObjRef { guid, name: Some(object.clone()) };
        match self {
            Refusal::Type { expected, got } => {
                DsError::TypeMismatch { object, property, expected, got }
            }
            Refusal::Range { value, min, max } => {
                DsError::OutOfRange { object, property, value, min, max }
            }
        }
    }
}

/// Checks a value against metadata; returns the value to store (an int becomes a float for
/// a float property).
fn check(meta: &PropMeta, value: Value) -> Result<Value, Refusal> {
    let value = match (meta.kind, value) {
        (None, v) => v,
        (Some(ValueKind::Float), Value::Int(i)) => Value::Float(i as f64),
        (Some(k), v) if v.kind() == k => v,
        (Some(k), v) => return Err(Refusal::Type { expected: k, got: v.kind() }),
    };
    if let (Some((min, max)), Some(x)) = (meta.range, value.as_f64())
        && !(min <= x && x <= max)
    {
        return Err(Refusal::Range { value: x, min, max });
    }
    Ok(value)
}

fn validate(
    guid: Guid,
    os: &ObjState,
    name: PropName,
    meta: &PropMeta,
    value: Value,
) -> Result<Value, DsError> {
    check(meta, value).map_err(|e| e.at(guid, &os.info.name, name))
}
