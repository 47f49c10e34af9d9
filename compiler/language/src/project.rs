//! A project: its profile (`project.toml`), the schemas it names and the settings it gives
//! the compiler. [`discover`] finds a layout's profile by walking up from the layout's folder
//! to the nearest `project.toml` that is a profile; [`load`] reads and checks one: its TOML,
//! its schemas (E0201, E0405) and its module settings against [`crate::modules`] (E0210).

use crate::diagnostics::Diagnostics;
use crate::profile::{self, ProfileFile};
use crate::schema::Schema;
use crate::source::{SourceLoader, SourceMap, Span, join, parent};
use crate::{Config, codes, load_schema, modules};

/// The file name a layout's profile is found by.
pub const PROFILE_NAME: &str = "project.toml";

/// A loaded profile.
#[derive(Clone, Debug, Default)]
pub struct Project {
    /// The profile's path.
    pub path: String,
    /// The profile, when it parsed.
    pub file: Option<ProfileFile>,
    /// Its schemas, merged, with the vehicles its modules publish.
    pub schema: Schema,
    /// What its layouts are checked with (the screen).
    pub config: Config,
}

/// The nearest `project.toml` that is a profile, from the folder of `layout` upwards.
pub fn discover(layout: &str, loader: &dyn SourceLoader) -> Option<String> {
    let mut dir = parent(layout).to_string();
    for _ in 0..64 {
        let candidate = join(&dir, PROFILE_NAME);
        if let Some(p) = loader.resolve(&candidate, PROFILE_NAME)
            && loader.read(&p).is_ok_and(|t| profile::looks_like_profile(&t))
        {
            return Some(p);
        }
        if dir == "/" {
            break;
        }
        // Relative paths walk on above the working folder with `..`.
        dir = if dir.is_empty() || dir == "." {
            "..".to_string()
        } else if dir == ".." || dir.ends_with("/..") {
            format!("{dir}/..")
        } else {
            parent(&dir).to_string()
        };
        if dir.matches("..").count() > 32 {
            break;
        }
    }
    None
}

/// The files a project's checks read: the profile and the schemas it names (those found).
/// What a reloader watches besides the layout and its `use`s.
pub fn files(profile: &str, loader: &dyn SourceLoader) -> Vec<String> {
    let mut out = vec![profile.to_string()];
    if let Ok(Ok(parsed)) = loader.read(profile).map(|t| toml::from_str::<ProfileFile>(&t)) {
        out.extend(parsed.profile.schemas.iter().filter_map(|s| loader.resolve(profile, s)));
    }
    out
}

/// Reads and checks the profile at `path` (text already read); problems are reported.
pub fn load(
    path: &str,
    text: &str,
    loader: &dyn SourceLoader,
    sources: &mut SourceMap,
    diags: &mut Diagnostics,
) -> Project {
    let file =
        sources.find(path).unwrap_or_else(|| sources.add(path.to_string(), text.to_string()));
    let mut project = Project { path: path.to_string(), ..Project::default() };
    let parsed: ProfileFile = match toml::from_str(text) {
        Ok(p) => p,
        Err(e) => {
            let r = e.span().unwrap_or(0..0);
            diags
                .error(codes::BAD_PROFILE, Span::new(file, r.start, r.end), format!("invalid profile: {}", e.message().trim()))
                .help("a profile has a [profile] table with `layouts`, and optional `schemas`, [modules.*] and [inputs.*] (docs/language.md, \"Profiles\")");
            return project;
        }
    };
    let span_of = |needle: &str| {
        let at = text.find(&format!("\"{needle}\"")).unwrap_or(0);
        Span::new(file, at, at + needle.len() + 2)
    };
    for s in &parsed.profile.schemas {
        match loader.resolve(path, s) {
            Some(p) => {
                if let Some(sch) = load_schema(&p, loader, sources, diags, Some(span_of(s))) {
                    project.schema.merge(sch);
                }
            }
            None => {
                diags
                    .error(
                        codes::FILE_NOT_FOUND,
                        span_of(s),
                        format!("cannot find the schema `{s}`"),
                    )
                    .help("paths in a profile are relative to the profile");
            }
        }
    }
    check_modules(&parsed, text, file, diags);
    let screen = parsed.profile.screen.unwrap_or([1920.0, 1080.0]);
    project.config = Config { screen: (screen[0], screen[1]) };
    project.schema.vehicles = vehicles(&parsed);
    project.file = Some(parsed);
    project
}

/// Each `[modules.NAME]` table against its kind's declared settings.
fn check_modules(parsed: &ProfileFile, text: &str, file: crate::FileId, diags: &mut Diagnostics) {
    for (name, table) in &parsed.modules {
        let header = section_span(text, name);
        let kind_name = table.get("kind").and_then(|k| k.as_str()).unwrap_or(name);
        let Some(kind) = modules::kind(kind_name) else {
            let at = key_span(text, name, "kind").unwrap_or(header);
            diags
                .error(
                    codes::BAD_PROFILE,
                    Span::new(file, at.0, at.1),
                    format!("`mocu run` has no module kind `{kind_name}`"),
                )
                .label("unknown module kind")
                .help(format!(
                    "{}the kinds are {}; a table's kind is its name unless `kind = \"…\"` says otherwise",
                    crate::diagnostics::did_you_mean(kind_name, modules::kinds().into_iter())
                        .map(|b| format!("did you mean `{b}`? "))
                        .unwrap_or_default(),
                    names(modules::kinds().into_iter())
                ));
            continue;
        };
        for (key, value) in table {
            let at = key_span(text, name, key).unwrap_or(header);
            let span = Span::new(file, at.0, at.1);
            match kind.setting(key) {
                None => {
                    let accepted = kind.settings.iter().chain(modules::COMMON).map(|s| s.name);
                    let best = crate::diagnostics::did_you_mean(key, accepted.clone());
                    diags
                        .error(
                            codes::BAD_PROFILE,
                            span,
                            format!("the {} module has no setting `{key}`", kind.kind),
                        )
                        .label("unknown setting")
                        .help(format!(
                            "{}it accepts {}",
                            best.map(|b| format!("did you mean `{b}`? ")).unwrap_or_default(),
                            names(accepted)
                        ));
                }
                Some(setting) if !setting.ty.accepts(value) => {
                    diags
                        .error(
                            codes::BAD_PROFILE,
                            span,
                            format!(
                                "setting `{key}` of the {} module must be {}, not {}",
                                kind.kind,
                                setting.ty.describe(),
                                value.type_str()
                            ),
                        )
                        .help(setting.description);
                }
                Some(setting) if setting.name == "vehicles" => {
                    check_vehicle_names(value, span, diags);
                }
                Some(_) => {}
            }
        }
        if kind.kind == "sim"
            && table.contains_key("vehicles")
            && let Some(k) = ["usv", "ugv", "uav"].iter().find(|k| table.contains_key(**k))
        {
            let at = key_span(text, name, k).unwrap_or(header);
            diags
                .error(
                    codes::BAD_PROFILE,
                    Span::new(file, at.0, at.1),
                    format!("`{k}` counts vehicles, but `vehicles` already names them"),
                )
                .help("give either `vehicles = [...]` or the counts `usv`, `ugv`, `uav`");
        }
    }
}

fn check_vehicle_names(value: &toml::Value, span: Span, diags: &mut Diagnostics) {
    let Some(list) = value.as_array() else { return };
    let mut seen = std::collections::HashSet::new();
    for n in list.iter().filter_map(|v| v.as_str()) {
        let typed = ["usv", "ugv", "uav"].iter().any(|k| n.starts_with(k));
        let ident = !n.is_empty() && n.chars().all(|c| c.is_ascii_alphanumeric() || c == '_');
        if !typed || !ident {
            diags
                .error(codes::BAD_PROFILE, span, format!("the simulator cannot make a vehicle `{n}`"))
                .help("a name starts with its type, usv, ugv or uav, and has only letters, digits and `_`: \"usv1\", \"uav_north\"");
        } else if !seen.insert(n) {
            diags.error(codes::BAD_PROFILE, span, format!("the vehicle `{n}` is named twice"));
        }
    }
}

/// The vehicles the profile's modules publish, when it names its modules.
pub fn vehicles(parsed: &ProfileFile) -> Option<Vec<String>> {
    if parsed.modules.is_empty() {
        return None;
    }
    let mut out = Vec::new();
    for (name, table) in &parsed.modules {
        let kind = table.get("kind").and_then(|k| k.as_str()).unwrap_or(name);
        match kind {
            "sim" => match table.get("vehicles").and_then(|v| v.as_array()) {
                Some(list) => {
                    out.extend(list.iter().filter_map(|v| v.as_str().map(str::to_string)))
                }
                None => {
                    for (k, d) in [("usv", 2), ("ugv", 1), ("uav", 1)] {
                        let n = table.get(k).and_then(|v| v.as_integer()).unwrap_or(d);
                        out.extend((1..=n.clamp(0, 1000)).map(|i| format!("{k}{i}")));
                    }
                }
            },
            "mavlink" => out.push("mav*".to_string()),
            _ => {}
        }
    }
    Some(out)
}

fn names<'a>(it: impl Iterator<Item = &'a str>) -> String {
    it.map(|n| format!("`{n}`")).collect::<Vec<_>>().join(", ")
}

/// The byte range of the `[modules.NAME]` header.
fn section_span(text: &str, name: &str) -> (usize, usize) {
    let header = format!("[modules.{name}]");
    text.find(&header).map_or((0, 0), |at| (at, at + header.len()))
}

/// The byte range of `key` in the `[modules.NAME]` table.
fn key_span(text: &str, name: &str, key: &str) -> Option<(usize, usize)> {
    let (_, start) = section_span(text, name);
    let mut offset = start;
    for line in text[start..].split_inclusive('\n') {
        let t = line.trim_start();
        if t.starts_with('[') && offset != start {
            break;
        }
        let lead = line.len() - t.len();
        if let Some(rest) = t.strip_prefix(key)
            && rest.trim_start().starts_with('=')
        {
            return Some((offset + lead, offset + lead + key.len()));
        }
        offset += line.len();
    }
    None
}
