//! The files a profile's modules name, carried in a bundle: a script module's `file` and the
//! map's `overlays` (text). `mocu build` reads them beside the profile into the bundle;
//! `mocu run BUNDLE` writes them to a folder of its own and points the modules there, so a
//! bundle runs without the sources. The map's `tiles` (a binary MBTiles file or a folder) is
//! not carried: `mocu build` says so, and the path is used as written.

use mocu_host::ModuleSpec;
use std::path::{Path, PathBuf};

/// Every setting of `spec` that names a file, with whether a bundle carries it (text files):
/// a script module's `file` and the map's `overlays` (carried), the map's `tiles` (not).
/// The one list of them: `mocu run` resolves these against the profile's folder too.
pub fn for_each_file(spec: &mut ModuleSpec, mut f: impl FnMut(&mut String, bool)) {
    match spec.kind.as_str() {
        "script" => {
            if let Some(toml::Value::String(s)) = spec.settings.get_mut("file") {
                f(s, true);
            }
        }
        "map" => {
            if let Some(toml::Value::Array(a)) = spec.settings.get_mut("overlays") {
                for v in a.iter_mut() {
                    if let toml::Value::String(s) = v {
                        f(s, true);
                    }
                }
            }
            if let Some(toml::Value::String(s)) = spec.settings.get_mut("tiles") {
                f(s, false);
            }
        }
        _ => {}
    }
}

/// Makes the files `spec` names (a script's `file`, the map's `overlays` and `tiles`) paths
/// from `dir`, as `mocu run` and `mocu check` both read them; absolute paths stay.
pub fn resolve_from(spec: &mut ModuleSpec, dir: &std::path::Path) {
    for_each_file(spec, |f, _| {
        if !f.is_empty() {
            *f = dir.join(&*f).to_string_lossy().into_owned();
        }
    });
}

/// Reads the files the profile at `profile_path` names into `bundle`. A file that cannot be
/// read is an error naming the module and the file (the check passed, so it is rare).
pub fn collect(profile_path: &Path, bundle: &mut mocu_language::Bundle) -> Result<(), String> {
    let Some(mut specs) = crate::run::profile_specs(bundle)? else { return Ok(()) };
    let dir = profile_path.parent().unwrap_or(Path::new(""));
    let (mut named, mut tiles) = (Vec::new(), false);
    for s in &mut specs {
        let module = s.name.clone();
        for_each_file(s, |file, carried| match carried {
            true => named.push((module.clone(), file.clone())),
            false => tiles |= !file.is_empty(),
        });
    }
    for (module, file) in named {
        let text = std::fs::read_to_string(dir.join(&file))
            .map_err(|e| format!("module `{module}`: cannot read `{file}`: {e}"))?;
        bundle.files.insert(file, text);
    }
    if tiles {
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

/// Replaces the carried setting naming `file` (a script's `file`, an entry of `overlays`)
/// by `to`.
fn point(spec: &mut ModuleSpec, file: &str, to: &str) {
    for_each_file(spec, |s, carried| {
        if carried && s == file {
            *s = to.to_string();
        }
    });
}
