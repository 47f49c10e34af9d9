//! The type system: number (with an optional unit), bool, string, colour, duration, range,
//! object, each possibly absent (`T?`), plus `dynamic` for paths whose type is unknown.
//!
//! Rules (docs/language.md, "Types"):
//! - A path is always possibly absent; without a schema its type is `dynamic?`, which is
//!   accepted wherever a value is expected (its use is checked at run time).
//! - `+`, `-` and comparisons need equal units when both sides carry one; a unitless side
//!   takes the other's unit. `*` and `/` give a unitless number (`speed * 1.94384` is
//!   unitless), except duration `*`/`/` number, which stays a duration.
//! - Absence propagates through operators; `a ?? b` removes it when `b` is never absent.

use serde::{Deserialize, Serialize};
use std::fmt;

/// A unit (`kn`, `px`) or an object type name (`usv`): interned, so that a [`Type`] is a few
/// bytes, copied for free, and typing a literal allocates nothing. Written as its text.
pub type Name = mocu_value::PropName;

/// `px`, `%` and `deg`, the units of literals, interned once.
pub fn literal_unit(u: &'static str) -> Name {
    use std::sync::LazyLock;
    static PX: LazyLock<Name> = LazyLock::new(|| Name::new("px"));
    static PERCENT: LazyLock<Name> = LazyLock::new(|| Name::new("%"));
    static DEG: LazyLock<Name> = LazyLock::new(|| Name::new("deg"));
    match u {
        "px" => *PX,
        "%" => *PERCENT,
        "deg" => *DEG,
        other => Name::new(other),
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "lowercase", tag = "kind")]
pub enum TypeKind {
    Number {
        #[serde(skip_serializing_if = "Option::is_none", default)]
        unit: Option<Name>,
    },
    Bool,
    String,
    Colour,
    Duration,
    Range {
        #[serde(skip_serializing_if = "Option::is_none", default)]
        unit: Option<Name>,
    },
    /// An object of the world model; its schema type when known.
    Object {
        #[serde(skip_serializing_if = "Option::is_none", default)]
        object_type: Option<Name>,
    },
    /// A path whose type is only known at run time (no schema).
    Dynamic,
    /// An action-only value (a method call result).
    Void,
    /// A type error already reported; accepted everywhere to avoid cascades.
    Error,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub struct Type {
    #[serde(flatten)]
    pub kind: TypeKind,
    /// May be absent at run time (`T?`).
    #[serde(skip_serializing_if = "std::ops::Not::not", default)]
    pub absent: bool,
}

impl Type {
    pub const fn new(kind: TypeKind) -> Type {
        Type { kind, absent: false }
    }
    pub fn number() -> Type {
        Type::new(TypeKind::Number { unit: None })
    }
    pub fn number_in(unit: Option<Name>) -> Type {
        Type::new(TypeKind::Number { unit })
    }
    pub const BOOL: Type = Type::new(TypeKind::Bool);
    pub const STRING: Type = Type::new(TypeKind::String);
    pub const COLOUR: Type = Type::new(TypeKind::Colour);
    pub const DURATION: Type = Type::new(TypeKind::Duration);
    pub const DYNAMIC: Type = Type { kind: TypeKind::Dynamic, absent: true };
    pub const ERROR: Type = Type::new(TypeKind::Error);
    pub const VOID: Type = Type::new(TypeKind::Void);

    pub fn maybe_absent(mut self, absent: bool) -> Type {
        self.absent |= absent;
        self
    }
    pub fn present(mut self) -> Type {
        self.absent = false;
        self
    }
    pub fn is_numeric(&self) -> bool {
        matches!(self.kind, TypeKind::Number { .. } | TypeKind::Dynamic | TypeKind::Error)
    }
    pub fn is_bool(&self) -> bool {
        matches!(self.kind, TypeKind::Bool | TypeKind::Dynamic | TypeKind::Error)
    }
    pub fn is_lenient(&self) -> bool {
        matches!(self.kind, TypeKind::Dynamic | TypeKind::Error)
    }
    pub fn unit(&self) -> Option<&str> {
        match &self.kind {
            TypeKind::Number { unit } | TypeKind::Range { unit } => unit.map(Name::as_str),
            _ => None,
        }
    }
    /// Whether a value of type `self` may be used where `want` is expected.
    pub fn fits(&self, want: &Type) -> bool {
        if self.is_lenient() || want.is_lenient() {
            return true;
        }
        match (&self.kind, &want.kind) {
            (TypeKind::Number { .. }, TypeKind::Number { .. }) => true,
            (TypeKind::Range { .. }, TypeKind::Range { .. }) => true,
            (TypeKind::Object { object_type: a }, TypeKind::Object { object_type: b }) => {
                a.is_none() || b.is_none() || a == b
            }
            (a, b) => std::mem::discriminant(a) == std::mem::discriminant(b),
        }
    }
    /// Parses a parameter type name: number, bool, string, colour, duration, range,
    /// object.
    pub fn parse_name(name: &str) -> Option<Type> {
        Some(Type::new(match name {
            "number" => TypeKind::Number { unit: None },
            "bool" => TypeKind::Bool,
            "string" => TypeKind::String,
            "colour" => TypeKind::Colour,
            "duration" => TypeKind::Duration,
            "range" => TypeKind::Range { unit: None },
            "object" => TypeKind::Object { object_type: None },
            _ => return None,
        }))
    }
}

impl fmt::Display for Type {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match &self.kind {
            TypeKind::Number { unit: Some(u) } => write!(f, "number ({u})")?,
            TypeKind::Number { unit: None } => f.write_str("number")?,
            TypeKind::Bool => f.write_str("bool")?,
            TypeKind::String => f.write_str("string")?,
            TypeKind::Colour => f.write_str("colour")?,
            TypeKind::Duration => f.write_str("duration")?,
            TypeKind::Range { .. } => f.write_str("range")?,
            TypeKind::Object { object_type: Some(t) } => write!(f, "object of type \"{t}\"")?,
            TypeKind::Object { object_type: None } => f.write_str("object")?,
            TypeKind::Dynamic => f.write_str("dynamic")?,
            TypeKind::Void => f.write_str("nothing")?,
            TypeKind::Error => f.write_str("{error}")?,
        }
        if self.absent && !matches!(self.kind, TypeKind::Dynamic) {
            f.write_str("?")
        } else {
            Ok(())
        }
    }
}
