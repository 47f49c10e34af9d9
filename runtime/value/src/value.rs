use crate::{Guid, ValueKind};
use std::cmp::Ordering;
use std::fmt;
use std::sync::Arc;

/// An immutable property value. Cloning is cheap: scalars are copied, strings, lists and
/// sets share one reference-counted allocation.
///
/// # Guarantees
/// A `Set` is sorted by [`Value::total_cmp`] and holds no duplicates (build it with
/// [`Value::set`]). Values compare with a total order (floats by `f64::total_cmp`), so
/// `NaN == NaN` here: a property that stays NaN is not "changed".
#[derive(Clone)]
pub enum Value {
    Int(i64),
    Float(f64),
    Bool(bool),
    Str(Arc<str>),
    Guid(Guid),
    List(Arc<[Value]>),
    Set(Arc<[Value]>),
    /// Opaque bytes (encoded video, raw payloads): shared, never copied on clone.
    Bytes(Arc<[u8]>),
}

impl Value {
    pub fn kind(&self) -> ValueKind {
        match self {
            Value::Int(_) => ValueKind::Int,
            Value::Float(_) => ValueKind::Float,
            Value::Bool(_) => ValueKind::Bool,
            Value::Str(_) => ValueKind::String,
            Value::Guid(_) => ValueKind::Guid,
            Value::List(_) => ValueKind::List,
            Value::Set(_) => ValueKind::Set,
            Value::Bytes(_) => ValueKind::Bytes,
        }
    }

    pub fn str(s: &str) -> Value {
        Value::Str(Arc::from(s))
    }

    pub fn list(items: impl IntoIterator<Item = Value>) -> Value {
        Value::List(items.into_iter().collect())
    }

    /// A set: sorted, duplicates removed.
    pub fn set(items: impl IntoIterator<Item = Value>) -> Value {
        let mut v: Vec<Value> = items.into_iter().collect();
        v.sort_by(Value::total_cmp);
        v.dedup_by(|a, b| a.total_cmp(b) == Ordering::Equal);
        Value::Set(v.into())
    }

    /// The value as a number, if it is one (ints widen to f64).
    pub fn as_f64(&self) -> Option<f64> {
        match *self {
            Value::Int(i) => Some(i as f64),
            Value::Float(f) => Some(f),
            _ => None,
        }
    }

    pub fn as_i64(&self) -> Option<i64> {
        match *self {
            Value::Int(i) => Some(i),
            _ => None,
        }
    }

    pub fn as_bool(&self) -> Option<bool> {
        match *self {
            Value::Bool(b) => Some(b),
            _ => None,
        }
    }

    pub fn as_str(&self) -> Option<&str> {
        match self {
            Value::Str(s) => Some(s),
            _ => None,
        }
    }

    pub fn as_guid(&self) -> Option<Guid> {
        match *self {
            Value::Guid(g) => Some(g),
            _ => None,
        }
    }

    pub fn as_slice(&self) -> Option<&[Value]> {
        match self {
            Value::List(l) | Value::Set(l) => Some(l),
            _ => None,
        }
    }

    fn rank(&self) -> u8 {
        match self {
            Value::Int(_) => 0,
            Value::Float(_) => 1,
            Value::Bool(_) => 2,
            Value::Str(_) => 3,
            Value::Guid(_) => 4,
            Value::List(_) => 5,
            Value::Set(_) => 6,
            Value::Bytes(_) => 7,
        }
    }

    /// A total order over all values: by kind first, then by content.
    pub fn total_cmp(&self, other: &Value) -> Ordering {
        match (self, other) {
            (Value::Int(a), Value::Int(b)) => a.cmp(b),
            (Value::Float(a), Value::Float(b)) => a.total_cmp(b),
            (Value::Bool(a), Value::Bool(b)) => a.cmp(b),
            (Value::Str(a), Value::Str(b)) => a.cmp(b),
            (Value::Guid(a), Value::Guid(b)) => a.cmp(b),
            (Value::List(a), Value::List(b)) | (Value::Set(a), Value::Set(b)) => {
                for (x, y) in a.iter().zip(b.iter()) {
                    match x.total_cmp(y) {
                        Ordering::Equal => continue,
                        o => return o,
                    }
                }
                a.len().cmp(&b.len())
            }
            (Value::Bytes(a), Value::Bytes(b)) => a.cmp(b),
            _ => self.rank().cmp(&other.rank()),
        }
    }

    /// Writes the value as JSON text (used by `--dump` and the event log).
    pub fn to_json(&self) -> serde_json_free::Json<'_> {
        serde_json_free::Json(self)
    }
}

/// A tiny JSON writer so this crate needs no serde_json (keeps it dependency-light).
pub mod serde_json_free {
    use super::Value;
    use std::fmt;

    pub struct Json<'a>(pub &'a Value);

    impl fmt::Display for Json<'_> {
        fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
            match self.0 {
                Value::Int(i) => write!(f, "{i}"),
                Value::Float(x) if x.is_finite() => write!(f, "{x:?}"),
                Value::Float(_) => f.write_str("null"),
                Value::Bool(b) => write!(f, "{b}"),
                Value::Str(s) => write_json_str(f, s),
                Value::Guid(g) => write!(f, "{}", g.get()),
                Value::List(l) | Value::Set(l) => {
                    f.write_str("[")?;
                    for (i, v) in l.iter().enumerate() {
                        if i > 0 {
                            f.write_str(",")?;
                        }
                        write!(f, "{}", Json(v))?;
                    }
                    f.write_str("]")
                }
                Value::Bytes(b) => write!(f, "{{\"bytes\":{}}}", b.len()),
            }
        }
    }

    pub fn write_json_str(f: &mut fmt::Formatter<'_>, s: &str) -> fmt::Result {
        f.write_str("\"")?;
        for c in s.chars() {
            match c {
                '"' => f.write_str("\\\"")?,
                '\\' => f.write_str("\\\\")?,
                '\n' => f.write_str("\\n")?,
                '\r' => f.write_str("\\r")?,
                '\t' => f.write_str("\\t")?,
                c if (c as u32) < 0x20 => write!(f, "\\u{:04x}", c as u32)?,
                c => write!(f, "{c}")?,
            }
        }
        f.write_str("\"")
    }
}

impl PartialEq for Value {
    fn eq(&self, other: &Value) -> bool {
        self.total_cmp(other) == Ordering::Equal
    }
}
impl Eq for Value {}
impl PartialOrd for Value {
    fn partial_cmp(&self, other: &Value) -> Option<Ordering> {
        Some(self.cmp(other))
    }
}
impl Ord for Value {
    fn cmp(&self, other: &Value) -> Ordering {
        self.total_cmp(other)
    }
}

impl fmt::Debug for Value {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Value::Int(i) => write!(f, "{i}"),
            Value::Float(x) => write!(f, "{x:?}"),
            Value::Bool(b) => write!(f, "{b}"),
            Value::Str(s) => write!(f, "{s:?}"),
            Value::Guid(g) => write!(f, "{g:?}"),
            Value::List(l) => f.debug_list().entries(l.iter()).finish(),
            Value::Set(l) => f.debug_set().entries(l.iter()).finish(),
            Value::Bytes(b) => write!(f, "<{} bytes>", b.len()),
        }
    }
}

impl fmt::Display for Value {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Value::Str(s) => f.write_str(s),
            other => write!(f, "{other:?}"),
        }
    }
}

impl From<i64> for Value {
    fn from(v: i64) -> Self {
        Value::Int(v)
    }
}
impl From<f64> for Value {
    fn from(v: f64) -> Self {
        Value::Float(v)
    }
}
impl From<bool> for Value {
    fn from(v: bool) -> Self {
        Value::Bool(v)
    }
}
impl From<&str> for Value {
    fn from(v: &str) -> Self {
        Value::str(v)
    }
}
impl From<String> for Value {
    fn from(v: String) -> Self {
        Value::Str(v.into())
    }
}
impl From<Guid> for Value {
    fn from(v: Guid) -> Self {
        Value::Guid(v)
    }
}

impl serde::Serialize for Value {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        use serde::ser::SerializeSeq;
        match self {
            Value::Int(i) => s.serialize_i64(*i),
            Value::Float(x) => s.serialize_f64(*x),
            Value::Bool(b) => s.serialize_bool(*b),
            Value::Str(v) => s.serialize_str(v),
            Value::Guid(g) => s.serialize_u64(g.get()),
            Value::List(l) | Value::Set(l) => {
                let mut seq = s.serialize_seq(Some(l.len()))?;
                for v in l.iter() {
                    seq.serialize_element(v)?;
                }
                seq.end()
            }
            Value::Bytes(b) => s.serialize_bytes(b),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sets_are_sorted_and_deduplicated() {
        let s = Value::set([Value::Int(3), Value::Int(1), Value::Int(3)]);
        assert_eq!(s.as_slice().unwrap(), &[Value::Int(1), Value::Int(3)]);
    }

    #[test]
    fn nan_equals_itself_so_an_unchanged_nan_is_not_a_change() {
        assert_eq!(Value::Float(f64::NAN), Value::Float(f64::NAN));
        assert_ne!(Value::Float(0.0), Value::Int(0));
    }

    #[test]
    fn clones_share_the_allocation() {
        let l = Value::list([Value::str("a"), Value::list([Value::Int(1)])]);
        let c = l.clone();
        match (&l, &c) {
            (Value::List(a), Value::List(b)) => assert!(Arc::ptr_eq(a, b)),
            _ => unreachable!(),
        }
    }

    #[test]
    fn json_text_escapes_strings() {
        let v = Value::list([Value::str("a\"b\n"), Value::Float(1.5), Value::Bool(true)]);
        assert_eq!(v.to_json().to_string(), r#"["a\"b\n",1.5,true]"#);
    }

    #[test]
    fn interned_names_compare_by_string() {
        assert_eq!(crate::PropName::new("speed"), crate::PropName::new("speed"));
        assert_eq!(crate::PropName::new("speed").as_str(), "speed");
        assert!(crate::PropName::existing("never-interned-xyz").is_none());
    }
}
