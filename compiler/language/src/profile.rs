//! Project profiles (TOML): a project's layouts, schemas, modules with their settings, and
//! input mappings. See docs/language.md, "Profiles".
//!
//! ```toml
//! [profile]
//! name = "usv-trials"
//! screen = [1920, 1080]          # for the "outside its window" warning; default 1920×1080
//! layouts = ["usv.mocu"]         # relative to this file
//! schemas = ["schemas/vehicles.toml"]
//!
//! [modules.sim]                  # any table: handed to the module as its settings
//! vehicles = ["usv1", "usv2"]
//!
//! [inputs.gamepad]               # logical input name -> device input name
//! south = "button_a"
//! ```

use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ProfileFile {
    pub profile: ProfileSection,
    #[serde(default)]
    pub modules: BTreeMap<String, toml::Table>,
    #[serde(default)]
    pub inputs: BTreeMap<String, BTreeMap<String, String>>,
}

#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ProfileSection {
    #[serde(default)]
    pub name: String,
    #[serde(default)]
    pub description: String,
    #[serde(default)]
    pub screen: Option<[f64; 2]>,
    pub layouts: Vec<String>,
    #[serde(default)]
    pub schemas: Vec<String>,
}

/// The profile as stored in a bundle: module settings as JSON values.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Profile {
    pub name: String,
    pub description: String,
    pub screen: [f64; 2],
    pub modules: BTreeMap<String, serde_json::Value>,
    pub inputs: BTreeMap<String, BTreeMap<String, String>>,
}

/// Whether a TOML text has the shape of a profile (a `[profile]` table with `layouts`).
pub fn looks_like_profile(text: &str) -> bool {
    toml::from_str::<toml::Table>(text).is_ok_and(|t| {
        t.get("profile").and_then(|p| p.as_table()).is_some_and(|p| p.contains_key("layouts"))
    })
}

/// Whether a TOML text has the shape of a schema (`[types.…]` or `[[instances]]`).
pub fn looks_like_schema(text: &str) -> bool {
    toml::from_str::<toml::Table>(text)
        .is_ok_and(|t| t.contains_key("types") || t.contains_key("instances"))
}

impl ProfileFile {
    pub fn to_profile(&self) -> Profile {
        Profile {
            name: self.profile.name.clone(),
            description: self.profile.description.clone(),
            screen: self.profile.screen.unwrap_or([1920.0, 1080.0]),
            modules: self
                .modules
                .iter()
                .map(|(k, v)| {
                    (k.clone(), serde_json::to_value(v).unwrap_or(serde_json::Value::Null))
                })
                .collect(),
            inputs: self.inputs.clone(),
        }
    }
}
