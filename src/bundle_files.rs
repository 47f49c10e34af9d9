//! The files a profile's modules name, carried in a bundle: a script module's `file` and the
//! map's `overlays` (text). `mocu build` reads them beside the profile into the bundle;
//! `mocu run BUNDLE` writes them to a folder of its own and points the modules there, so a
//! bundle runs without the sources. The map's `tiles` (a binary MBTiles file or a folder) is
//! not carried: `mocu build` says so, and the path is used as written.

use mocu_host::ModuleSpec;
use std::path::{Path, PathBuf};

/// Each module setting that names a file to carry: (module name, the path as written).
fn named_files(profile: &mocu_language::profile::Profile) -> Vec<(String, String)> {
    let mut out = Vec::new();
    for (name, settings) in &profile.modules {
        let kind = settings.get("kind").and_then(|k| k.as_str()).unwrap_or(name);
        match kind {
            "script" => {
                if let Some(f) = settings.get("file").and_then(|f| f.as_str()) {
                    out.push((name.clone(), f.to_string()));
                }
            }
            "map" => {
                for f in settings.get("overlays").and_then(|o| o.as_array()).into_iter().flatten() {
                    if let Some(f) = f.as_str() {
                        out.push((name.clone(), f.to_string()));
                    }
                }
            }
            _ => {}
        }
    }
    out
}

/// Reads the files the profile at `profile_path` names into `bundle`. A file that cannot be
/// read is an error naming the module and the file (the check passed, so it is rare).
pub fn collect(profile_path: &Path, bundle: &mut mocu_language::Bundle) -> Result<(), String> {
    let Some(profile) = &bundle.profile else { return Ok(()) };
    let dir = profile_path.parent().unwrap_or(Path::new(""));
    for (module, file) in named_files(profile) {
        let text = std::fs::read_to_string(dir.join(&file))
            .map_err(|e| format!("module `{module}`: cannot read `{file}`: {e}"))?;
        bundle.files.insert(file, text);
    }
    if profile.modules.iter().any(|(name, s)| {
        s.get("kind").and_then(|k| k.as_str()).unwrap_or(name) == "map"
            && s.get("tiles").and_then(|t| t.as_str()).is_some_and(|t| !t.is_empty())
    }) {
        eprintln!(
            "note: the map's `tiles` is not carried in a bundle: `mocu run` looks for it where the profile says, beside the bundle"
        );
    }
    Ok(())
}

/// The folder a bundle's files were written to; removed when dropped (the run ends).
pub struct Carried(PathBuf);

impl Drop for Carried {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

/// Writes `bundle`'s files under a folder of this run's own and points `specs`' settings
/// that name them there.
pub fn extract(
    bundle: &mocu_language::Bundle,
    specs: &mut [ModuleSpec],
) -> Result<Option<Carried>, String> {
    if bundle.files.is_empty() {
        return Ok(None);
    }
    let root = std::env::temp_dir().join(format!("mocu-bundle-{}", std::process::id()));
    let carried = Carried(root.clone());
    for (file, text) in &bundle.files {
        // Inside the folder whatever the path says (`../x.js` included).
        let rel: PathBuf = Path::new(file)
            .components()
            .filter_map(|c| match c {
                std::path::Component::Normal(p) => Some(p),
                _ => None,
            })
            .collect();
        let to = root.join(&rel);
        if let Some(parent) = to.parent() {
            std::fs::create_dir_all(parent).map_err(|e| format!("{}: {e}", parent.display()))?;
        }
        std::fs::write(&to, text).map_err(|e| format!("{}: {e}", to.display()))?;
        let to = to.to_string_lossy().into_owned();
        for s in specs.iter_mut() {
            point(s, file, &to);
        }
    }
    Ok(Some(carried))
}

/// Replaces the setting naming `file` (a script's `file`, an entry of `overlays`) by `to`.
fn point(spec: &mut ModuleSpec, file: &str, to: &str) {
    let names = |v: &toml::Value| v.as_str() == Some(file);
    if let Some(v) = spec.settings.get_mut("file")
        && names(v)
    {
        *v = toml::Value::String(to.to_string());
    }
    if let Some(toml::Value::Array(a)) = spec.settings.get_mut("overlays") {
        for v in a.iter_mut().filter(|v| names(v)) {
            *v = toml::Value::String(to.to_string());
        }
    }
}
