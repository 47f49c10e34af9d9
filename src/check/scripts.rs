//! The script modules of a profile being checked (`[modules.NAME] kind = "script"`): each
//! file is parsed by its engine, without running, and its syntax error reported as E0101 at
//! the script's own line and column (docs/scripting.md).

use mocu_language::passes::check_scripts::offset_of;
use mocu_language::{Diagnostics, SourceMap, Span, codes};
use mocu_script::{Registry, Source};
use std::path::Path;

/// Checks the script files a profile names; paths are relative to the profile's folder.
pub(crate) fn check(profile: &str, text: &str, sources: &mut SourceMap, diags: &mut Diagnostics) {
    let Ok(table) = toml::from_str::<toml::Table>(text) else { return };
    let Some(toml::Value::Table(modules)) = table.get("modules") else { return };
    let dir = Path::new(profile).parent().unwrap_or(Path::new(""));
    let engines = Registry::standard();
    for (name, settings) in modules {
        let kind = settings.get("kind").and_then(|k| k.as_str()).unwrap_or(name);
        let Some(file) = settings.get("file").and_then(|f| f.as_str()) else { continue };
        if kind != "script" {
            continue;
        }
        let path = crate::check::slashed(&dir.join(file));
        let Some(engine) = engines.for_file(&path) else {
            let at = setting_span(profile, text, file, sources);
            diags.error(
                codes::BAD_PROFILE,
                at,
                format!("module `{name}`: no script engine for `{file}` (known: .js, .rhai)"),
            );
            continue;
        };
        let Ok(script) = std::fs::read_to_string(&path) else {
            let at = setting_span(profile, text, file, sources);
            diags.error(
                codes::FILE_NOT_FOUND,
                at,
                format!("module `{name}`: cannot read `{path}`"),
            );
            continue;
        };
        if let Err(e) = engine.check(&Source::file(&path, &script)) {
            let start = offset_of(&script, e.at.line, e.at.col);
            let id = sources.add(path.clone(), script);
            let span = Span { file: id, start, end: start };
            diags.error(codes::SYNTAX, span, format!("{} script: {}", engine.prefix(), e.message));
        }
    }
}

/// Where the profile names the file (its `"file"` text), for errors about the setting.
fn setting_span(profile: &str, text: &str, file: &str, sources: &mut SourceMap) -> Span {
    let quoted = format!("\"{file}\"");
    let start = text.find(&quoted).unwrap_or(0) as u32;
    let end = start + if start == 0 { 0 } else { quoted.len() as u32 };
    let id = sources.add(profile.to_string(), text.to_string());
    Span { file: id, start, end }
}
