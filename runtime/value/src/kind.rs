use std::fmt;

/// The type of a property value, used by typed properties and schemas.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum ValueKind {
    Int,
    Float,
    Bool,
    String,
    Guid,
    List,
    Set,
    Bytes,
}

impl ValueKind {
    pub fn name(self) -> &'static str {
        match self {
            ValueKind::Int => "int",
            ValueKind::Float => "float",
            ValueKind::Bool => "bool",
            ValueKind::String => "string",
            ValueKind::Guid => "guid",
            ValueKind::List => "list",
            ValueKind::Set => "set",
            ValueKind::Bytes => "bytes",
        }
    }

    pub fn parse(s: &str) -> Option<ValueKind> {
        Some(match s {
            "int" | "integer" => ValueKind::Int,
            "float" | "number" => ValueKind::Float,
            "bool" | "boolean" => ValueKind::Bool,
            "string" => ValueKind::String,
            "guid" => ValueKind::Guid,
            "list" => ValueKind::List,
            "set" => ValueKind::Set,
            "bytes" => ValueKind::Bytes,
            _ => return None,
        })
    }

    pub fn is_numeric(self) -> bool {
        matches!(self, ValueKind::Int | ValueKind::Float)
    }
}

impl fmt::Display for ValueKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}
