//! What a profile says about one module: `[[modules]]` tables.

use std::fmt;

/// One module as a profile names it:
///
/// ```toml
/// [[modules]]
/// name = "sim"          # instance name: root.modules.sim
/// kind = "sim"          # registry key; defaults to the name
/// seed = 7              # everything else is the module's settings
/// vehicles = { usv = 2, ugv = 1, uav = 1 }
/// ```
#[derive(Clone, Debug, PartialEq)]
pub struct ModuleSpec {
    pub name: String,
    pub kind: String,
    pub settings: toml::Table,
}

/// A setting of the wrong type, or a malformed `[[modules]]` entry.
#[derive(Clone, Debug, PartialEq)]
pub struct SpecError(pub String);

impl fmt::Display for SpecError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for SpecError {}

impl ModuleSpec {
    /// A spec with no settings; `kind` doubles as the instance name.
    pub fn new(kind: &str) -> ModuleSpec {
        ModuleSpec { name: kind.to_string(), kind: kind.to_string(), settings: toml::Table::new() }
    }

    pub fn named(mut self, name: &str) -> ModuleSpec {
        self.name = name.to_string();
        self
    }

    pub fn with(mut self, key: &str, value: impl Into<toml::Value>) -> ModuleSpec {
        self.settings.insert(key.to_string(), value.into());
        self
    }

    /// One `[[modules]]` table: `name` (required), `kind` (defaults to the name); every
    /// other key is a setting.
    pub fn from_table(table: &toml::Table) -> Result<ModuleSpec, SpecError> {
        let name = match table.get("name") {
            Some(toml::Value::String(s)) if !s.is_empty() => s.clone(),
            Some(_) => return Err(SpecError("module `name` must be a non-empty string".into())),
            None => return Err(SpecError("a [[modules]] entry needs a `name`".into())),
        };
        let kind = match table.get("kind") {
            Some(toml::Value::String(s)) => s.clone(),
            Some(_) => return Err(SpecError(format!("module `{name}`: `kind` must be a string"))),
            None => name.clone(),
        };
        let settings = table
            .iter()
            .filter(|(k, _)| *k != "name" && *k != "kind")
            .map(|(k, v)| (k.clone(), v.clone()))
            .collect();
        Ok(ModuleSpec { name, kind, settings })
    }

    /// Every `[[modules]]` entry of a profile, in order. A profile without `modules` gives
    /// `Ok(None)` (the caller picks the defaults).
    pub fn list_from_profile(profile: &toml::Table) -> Result<Option<Vec<ModuleSpec>>, SpecError> {
        match profile.get("modules") {
            None => Ok(None),
            Some(toml::Value::Array(items)) => items
                .iter()
                .map(|v| match v {
                    toml::Value::Table(t) => ModuleSpec::from_table(t),
                    _ => {
                        Err(SpecError("`modules` must be an array of tables ([[modules]])".into()))
                    }
                })
                .collect::<Result<Vec<_>, _>>()
                .map(Some),
            Some(_) => Err(SpecError("`modules` must be an array of tables ([[modules]])".into())),
        }
    }

    // ----- typed settings ------------------------------------------------------------

    fn wrong(&self, key: &str, want: &str, got: &toml::Value) -> SpecError {
        SpecError(format!(
            "module `{}`: setting `{key}` must be {want}, not {}",
            self.name,
            got.type_str()
        ))
    }

    pub fn f64_or(&self, key: &str, default: f64) -> Result<f64, SpecError> {
        match self.settings.get(key) {
            None => Ok(default),
            Some(toml::Value::Float(f)) => Ok(*f),
            Some(toml::Value::Integer(i)) => Ok(*i as f64),
            Some(v) => Err(self.wrong(key, "a number", v)),
        }
    }

    pub fn i64_or(&self, key: &str, default: i64) -> Result<i64, SpecError> {
        match self.settings.get(key) {
            None => Ok(default),
            Some(toml::Value::Integer(i)) => Ok(*i),
            Some(v) => Err(self.wrong(key, "an integer", v)),
        }
    }

    pub fn bool_or(&self, key: &str, default: bool) -> Result<bool, SpecError> {
        match self.settings.get(key) {
            None => Ok(default),
            Some(toml::Value::Boolean(b)) => Ok(*b),
            Some(v) => Err(self.wrong(key, "a boolean", v)),
        }
    }

    pub fn str_or(&self, key: &str, default: &str) -> Result<String, SpecError> {
        match self.settings.get(key) {
            None => Ok(default.to_string()),
            Some(toml::Value::String(s)) => Ok(s.clone()),
            Some(v) => Err(self.wrong(key, "a string", v)),
        }
    }

    /// A UDP/TCP socket address setting, `IP:PORT` (`0.0.0.0:14550`, `[::1]:5600`): refused
    /// here, where `mocu check` sees it, rather than when the module binds it.
    pub fn socket_addr_or(
        &self,
        key: &str,
        default: &str,
    ) -> Result<std::net::SocketAddr, SpecError> {
        let text = self.str_or(key, default)?;
        text.parse().map_err(|_| {
            SpecError(format!(
                "module `{}`: `{key}` `{text}` is not IP:PORT (e.g. 0.0.0.0:14550)",
                self.name
            ))
        })
    }

    pub fn table(&self, key: &str) -> Result<Option<&toml::Table>, SpecError> {
        match self.settings.get(key) {
            None => Ok(None),
            Some(toml::Value::Table(t)) => Ok(Some(t)),
            Some(v) => Err(self.wrong(key, "a table", v)),
        }
    }
}
