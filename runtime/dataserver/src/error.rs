use mocu_value::{Guid, PropName, ValueKind};
use std::fmt;
use std::sync::Arc;

/// An object as named in an error: its GUID and, where it was known, its name.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ObjRef {
    pub guid: Guid,
    pub name: Option<Arc<str>>,
}

impl ObjRef {
    pub fn unnamed(guid: Guid) -> ObjRef {
        ObjRef { guid, name: None }
    }
}

impl fmt::Display for ObjRef {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match &self.name {
            Some(n) => write!(f, "object `{n}` ({})", self.guid),
            None => write!(f, "object {}", self.guid),
        }
    }
}

/// Why the DataServer refused an operation. Every refused operation changes nothing.
#[derive(Clone, Debug, PartialEq)]
pub enum DsError {
    /// The object does not exist (never did, or was deleted).
    NoSuchObject { object: ObjRef },
    /// The object exists but has no property of that name.
    NoSuchProperty { object: ObjRef, property: PropName },
    /// A write of the wrong type to a typed property.
    TypeMismatch { object: ObjRef, property: PropName, expected: ValueKind, got: ValueKind },
    /// A numeric write outside the property's declared range.
    OutOfRange { object: ObjRef, property: PropName, value: f64, min: f64, max: f64 },
    /// `create_property` of a name the object already has.
    PropertyExists { object: ObjRef, property: PropName },
    /// `publish_method` of a name the object already has.
    MethodExists { object: ObjRef, method: PropName },
    /// The object is not a child of the given parent.
    NotAChild { parent: ObjRef, child: ObjRef },
    /// The root object cannot be deleted, renamed or moved.
    RootIsPermanent,
    /// The object is not a stream listener.
    NotAListener { object: ObjRef },
    /// A dotted path that does not parse (`root.a.b.prop`).
    BadPath { path: String, reason: &'static str },
}

impl fmt::Display for DsError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            DsError::NoSuchObject { object } => write!(f, "{object} does not exist"),
            DsError::NoSuchProperty { object, property } => {
                write!(f, "{object} has no property `{property}`")
            }
            DsError::TypeMismatch { object, property, expected, got } => write!(
                f,
                "refused write to `{property}` of {object}: it holds {expected} values, not {got}"
            ),
            DsError::OutOfRange { object, property, value, min, max } => write!(
                f,
                "refused write to `{property}` of {object}: {value} is outside its range {min} ..= {max}"
            ),
            DsError::PropertyExists { object, property } => {
                write!(f, "{object} already has a property `{property}`")
            }
            DsError::MethodExists { object, method } => {
                write!(f, "{object} already has a method `{method}`")
            }
            DsError::NotAChild { parent, child } => write!(f, "{child} is not a child of {parent}"),
            DsError::RootIsPermanent => {
                write!(f, "the root object cannot be deleted, renamed or moved")
            }
            DsError::NotAListener { object } => write!(f, "{object} is not a stream listener"),
            DsError::BadPath { path, reason } => write!(f, "bad path `{path}`: {reason}"),
        }
    }
}

impl std::error::Error for DsError {}
