use std::fmt;
use std::num::NonZeroU64;

/// A runtime-unique 64-bit object identifier (the paper's "GUID": unique for the life of
/// one DataServer, not globally).
///
/// # Guarantees
/// Never zero, so `Option<Guid>` is eight bytes. `Guid::ROOT` is the root object's id.
#[derive(
    Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash, serde::Serialize, serde::Deserialize,
)]
#[serde(transparent)]
pub struct Guid(NonZeroU64);

impl Guid {
    /// The root object, ancestor of every other object.
    pub const ROOT: Guid = Guid(NonZeroU64::MIN);

    /// A GUID from its raw number; `None` for zero.
    pub fn new(raw: u64) -> Option<Guid> {
        NonZeroU64::new(raw).map(Guid)
    }

    pub fn get(self) -> u64 {
        self.0.get()
    }
}

impl fmt::Debug for Guid {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "#{}", self.0)
    }
}

impl fmt::Display for Guid {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "#{}", self.0)
    }
}
