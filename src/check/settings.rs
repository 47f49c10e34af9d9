//! The modules of a profile being checked: each `[modules.NAME]` table is handed to its
//! module kind's own factory, as `mocu run` hands it before starting the module, so a
//! setting the module refuses (a range, a format, a missing file) is an error of `mocu
//! check` with the module's own words (E0210 at the table), not a module that fails to start
//! in front of the operator. Nothing is started: no socket, thread or process.

use mocu_host::{ModuleSpec, StartError};
use mocu_language::{Diagnostics, SourceMap, Span, codes};
use std::path::Path;

/// Checks the modules the profile at `profile` names (file settings relative to its folder,
/// as `mocu run` resolves them).
pub(crate) fn check(profile: &str, text: &str, sources: &mut SourceMap, diags: &mut Diagnostics) {
    let Ok(table) = toml::from_str::<toml::Table>(text) else { return };
    let Some(toml::Value::Table(modules)) = table.get("modules") else { return };
    // A malformed module table is the profile pass's error already.
    let mut specs: Vec<ModuleSpec> = modules
        .iter()
        .filter_map(|(name, settings)| {
            let mut t = settings.as_table()?.clone();
            t.insert("name".into(), toml::Value::String(name.clone()));
            ModuleSpec::from_table(&t).ok()
        })
        .collect();
    let dir = Path::new(profile).parent().unwrap_or(Path::new(""));
    let registry = crate::registry::registry(mocu_widgets::Components::default());
    for spec in &mut specs {
        if spec.settings.get("enabled").and_then(toml::Value::as_bool) == Some(false) {
            continue;
        }
        crate::bundle_files::resolve_from(spec, dir);
        let why = match registry.make(spec) {
            Ok(_) => continue,
            // The profile pass names unknown kinds itself (with the known ones).
            Err(StartError::UnknownKind { .. }) => continue,
            Err(StartError::Failed { reason, .. }) => reason,
            Err(StartError::Panicked { message, .. }) => {
                format!("its settings crash it: {message}")
            }
            Err(e) => e.to_string(),
        };
        let at = table_span(profile, text, &spec.name, sources);
        let why =
            why.strip_prefix(&format!("module `{}`: ", spec.name)).unwrap_or(&why).to_string();
        diags.error(
            codes::BAD_PROFILE,
            at,
            format!("module `{}` would not start: {why}", spec.name),
        );
    }
}

/// The `[modules.NAME]` header of the profile, for errors about that module.
fn table_span(profile: &str, text: &str, name: &str, sources: &mut SourceMap) -> Span {
    let headers = [format!("[modules.{name}]"), format!("[modules.\"{name}\"]")];
    let found = headers.iter().find_map(|h| text.find(h.as_str()).map(|at| (at, h.len())));
    let (start, len) = found.unwrap_or((0, 0));
    let id = sources.add(profile.to_string(), text.to_string());
    Span { file: id, start: start as u32, end: (start + len) as u32 }
}
