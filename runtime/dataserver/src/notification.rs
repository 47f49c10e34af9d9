use mocu_value::{Guid, PropName, Value};
use std::sync::Arc;

/// The nature of an update.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Kind {
    New,
    Changed,
    Deleted,
}

/// What a notification is about.
#[derive(Clone, Debug, PartialEq)]
pub enum Subject {
    /// A property of the subscribed object. `value` is `None` only for `Deleted`.
    Property { name: PropName, value: Option<Value> },
    /// A child of the subscribed object: added (`New`, with its position), renamed or
    /// retyped (`Changed`), deleted or moved away (`Deleted`).
    Child { guid: Guid, name: Arc<str>, kind: Arc<str>, index: usize },
    /// The subscribed object itself was deleted. Always the last notification a
    /// subscription receives.
    Object,
}

/// One update delivered to one subscription.
#[derive(Clone, Debug, PartialEq)]
pub struct Notification {
    /// The subscribed object.
    pub object: Guid,
    pub kind: Kind,
    pub subject: Subject,
}

impl Notification {
    pub fn property_name(&self) -> Option<PropName> {
        match &self.subject {
            Subject::Property { name, .. } => Some(*name),
            _ => None,
        }
    }

    pub fn value(&self) -> Option<&Value> {
        match &self.subject {
            Subject::Property { value, .. } => value.as_ref(),
            _ => None,
        }
    }

    /// The key under which later changes may coalesce with this one.
    pub(crate) fn coalesce_key(&self) -> Option<CoalesceKey> {
        match (&self.kind, &self.subject) {
            (Kind::New | Kind::Changed, Subject::Property { name, .. }) => {
                Some(CoalesceKey::Property(*name))
            }
            (Kind::New | Kind::Changed, Subject::Child { guid, .. }) => {
                Some(CoalesceKey::Child(*guid))
            }
            _ => None,
        }
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub(crate) enum CoalesceKey {
    Property(PropName),
    Child(Guid),
}
