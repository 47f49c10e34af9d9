use lasso::{Spur, ThreadedRodeo};
use std::fmt;
use std::sync::OnceLock;

/// An interned property (or method) name: a `u32` key, so comparing and hashing names on the
/// hot path costs no string work.
///
/// # Guarantees
/// Two `PropName`s are equal exactly when their strings are equal. Interned strings live for
/// the whole process (names are few and come from schemas and layouts).
#[derive(Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct PropName(Spur);

fn interner() -> &'static ThreadedRodeo {
    static INTERNER: OnceLock<ThreadedRodeo> = OnceLock::new();
    INTERNER.get_or_init(ThreadedRodeo::new)
}

impl PropName {
    pub fn new(name: &str) -> PropName {
        PropName(interner().get_or_intern(name))
    }

    /// The name if it was ever interned; never interns (cheap lookups for unknown names).
    pub fn existing(name: &str) -> Option<PropName> {
        interner().get(name).map(PropName)
    }

    pub fn as_str(self) -> &'static str {
        // The interner is a process-wide static and never frees, so its strings are 'static.
        interner().resolve(&self.0)
    }
}

impl From<&str> for PropName {
    fn from(s: &str) -> Self {
        PropName::new(s)
    }
}

impl fmt::Debug for PropName {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{:?}", self.as_str())
    }
}

impl fmt::Display for PropName {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.as_str())
    }
}

impl serde::Serialize for PropName {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.serialize_str(self.as_str())
    }
}

impl<'de> serde::Deserialize<'de> for PropName {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let s = <std::borrow::Cow<'de, str>>::deserialize(d)?;
        Ok(PropName::new(&s))
    }
}
