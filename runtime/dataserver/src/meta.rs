use mocu_value::ValueKind;
use std::sync::Arc;

/// What a property's publisher says about it. All fields are optional: an untyped property
/// with no metadata accepts any value.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct PropMeta {
    /// When set, writes of another kind are refused (an int is accepted by a float
    /// property and stored as a float).
    pub kind: Option<ValueKind>,
    /// Units of the value, e.g. `m/s`, `deg`, `%`.
    pub units: Option<Arc<str>>,
    /// How a display should show it, e.g. `percent`, `lat`, `hex`.
    pub representation: Option<Arc<str>>,
    /// A human description.
    pub description: Option<Arc<str>>,
    /// Inclusive numeric limits; writes outside are refused.
    pub range: Option<(f64, f64)>,
    /// How often the publisher writes it, changed or not (Hz). A display takes a value
    /// that has received no write for three periods as stale, unless the schema gives the
    /// property a `stale_after` (docs/display.md, "Stale data").
    pub rate_hz: Option<f64>,
}

impl PropMeta {
    pub fn typed(kind: ValueKind) -> PropMeta {
        PropMeta { kind: Some(kind), ..PropMeta::default() }
    }

    pub fn units(mut self, units: &str) -> PropMeta {
        self.units = Some(units.into());
        self
    }

    pub fn range(mut self, min: f64, max: f64) -> PropMeta {
        self.range = Some((min, max));
        self
    }

    pub fn describe(mut self, text: &str) -> PropMeta {
        self.description = Some(text.into());
        self
    }

    /// The publisher writes the value `hz` times a second (see [`PropMeta::rate_hz`]).
    pub fn rate(mut self, hz: f64) -> PropMeta {
        self.rate_hz = (hz.is_finite() && hz > 0.0).then_some(hz);
        self
    }

    pub fn representation(mut self, how: &str) -> PropMeta {
        self.representation = Some(how.into());
        self
    }
}

/// The descriptive attributes of an object: no meaning to the DataServer.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ObjectInfo {
    pub name: Arc<str>,
    pub kind: Arc<str>,
    pub subtype: Arc<str>,
}

impl ObjectInfo {
    pub fn new(name: &str, kind: &str) -> ObjectInfo {
        ObjectInfo { name: name.into(), kind: kind.into(), subtype: "".into() }
    }

    pub fn subtype(mut self, subtype: &str) -> ObjectInfo {
        self.subtype = subtype.into();
        self
    }
}
