//! The settings the compiler checks profiles against (mocu_language::modules) are the ones
//! `mocu run`'s modules accept: the same kinds, and every declared key, set to a value of its
//! declared type, starts its module.

use mocu_dataserver::DataServer;
use mocu_host::{ModuleHost, ModuleSpec, Registry};
use mocu_language::modules::{self, SettingType};

/// The binary's own list of module kinds.
#[path = "../src/registry.rs"]
mod registry;

fn registry() -> Registry {
    registry::registry(mocu_widgets::Components::default())
}

/// A valid value of each declared setting (ranges and formats the modules check).
fn sample(kind: &str, key: &str, ty: SettingType) -> toml::Value {
    match (kind, key) {
        (_, "address") => "127.0.0.1:0".into(),
        ("sim", "rate_hz") | ("input", "rate_hz") => 20.0.into(),
        ("input", "double_ms") => 300.0.into(),
        ("sim", "camera_width") | ("sim", "camera_height") => 16.into(),
        ("sim", "vehicles") => toml::Value::Array(vec!["usv1".into(), "uav_a".into()]),
        ("codec", "source") => "root.cameras.test".into(),
        ("video", "feeds") => "auto".into(),
        ("input", "gilrs") => false.into(),
        ("input", "script") | ("video", "camera") | ("map", "tiles") => "".into(),
        ("script", "file") => script_file().into(),
        ("script", "memory_kb") => 1024.into(),
        ("process", "command") => toml::Value::Array(vec!["true".into()]),
        ("video", "source") => "127.0.0.1".into(),
        ("distrib", "takeover") => "ask".into(),
        ("distrib", "free") => "closed".into(),
        ("video", "silence_ms") | ("video", "max_width" | "max_height" | "max_unit_kb") => {
            640.into()
        }
        ("distrib", "tls_ca" | "tls_cert" | "tls_key") => "".into(),
        // The host takes `enabled = false` modules out before they start (`fill_roles`).
        (_, "enabled") => true.into(),
        (_, "kind") => kind.into(),
        _ => match ty {
            SettingType::Int => 1.into(),
            SettingType::Number => 1.5.into(),
            SettingType::Bool => true.into(),
            SettingType::String => "x".into(),
            SettingType::Names => toml::Value::Array(vec![]),
        },
    }
}

/// A script module's file: one that runs (a script module does not start without its file).
fn script_file() -> String {
    let path = std::env::temp_dir().join(format!("mocu-module-settings-{}.js", std::process::id()));
    std::fs::write(&path, "mocu.read(\"modules.t_script.kind\");").expect("temp dir writable");
    path.display().to_string()
}

#[test]
fn the_compiler_knows_exactly_the_module_kinds_mocu_run_registers() {
    let r = registry();
    let mut run: Vec<&str> = r.kinds().collect();
    let mut declared: Vec<&str> = modules::MODULES.iter().map(|m| m.kind).collect();
    run.sort();
    declared.sort();
    assert_eq!(run, declared);
}

#[test]
fn every_declared_setting_is_accepted_by_its_module() {
    for m in modules::MODULES {
        // The simulator takes `vehicles` or the counts, not both: one spec with each.
        let groups: Vec<Vec<&str>> = if m.kind == "sim" {
            vec![vec!["usv", "ugv", "uav"], vec!["vehicles"]]
        } else {
            vec![vec![]]
        };
        for skip in groups {
            let mut spec = ModuleSpec::new(m.kind).named(&format!("t_{}", m.kind));
            for s in m.settings.iter().chain(modules::COMMON) {
                if !skip.contains(&s.name) {
                    spec = spec.with(s.name, sample(m.kind, s.name, s.ty));
                }
            }
            let mut host = ModuleHost::new(DataServer::default(), registry());
            let started = host.start(&spec);
            host.stop_all();
            assert!(started.is_ok(), "{}: {:?} with {:?}", m.kind, started, spec.settings);
        }
    }
}
