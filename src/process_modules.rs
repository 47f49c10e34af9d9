//! `mocu run` with process modules (`kind = "process"`, docs/modules.md): such a module joins
//! the world model over Zenoh, so the OCU must share it there. When a profile names one, the
//! distribution module is added if missing, shares `vehicles` if it shares nothing, and
//! listens on a free loopback port if it listens nowhere (the module added here arbitrates no
//! control: only the OCU's own modules join it); each process module is handed the
//! first listening endpoint (`connect`, passed on as `MOCU_CONNECT`) and starts after every
//! other module.

use mocu_host::ModuleSpec;

/// Wires the process modules of `specs` to the OCU's Zenoh endpoint (see the module doc).
pub fn connect(specs: &mut Vec<ModuleSpec>) {
    if !specs.iter().any(|s| s.kind == "process") {
        return;
    }
    // Processes last: what they join is up by then.
    let (procs, mut rest): (Vec<_>, Vec<_>) = specs.drain(..).partition(|s| s.kind == "process");
    if !rest.iter().any(|s| s.kind == "distrib") {
        // Only the OCU's own modules join it: no control arbitration between them and it.
        rest.insert(0, ModuleSpec::new("distrib").with("control", false));
    }
    let distrib = rest.iter_mut().find(|s| s.kind == "distrib").expect("inserted above");
    let list = |s: &ModuleSpec, key: &str| -> Vec<String> {
        match s.settings.get(key) {
            Some(toml::Value::Array(a)) => {
                a.iter().filter_map(|v| v.as_str().map(str::to_string)).collect()
            }
            _ => Vec::new(),
        }
    };
    let mut listen = list(distrib, "listen");
    if listen.is_empty() {
        match free_loopback_port() {
            Ok(port) => listen.push(format!("tcp/127.0.0.1:{port}")),
            Err(e) => eprintln!("mocu: no free loopback port for the process modules: {e}"),
        }
        let v = listen.iter().map(|e| toml::Value::String(e.clone())).collect();
        distrib.settings.insert("listen".into(), toml::Value::Array(v));
    }
    if list(distrib, "share").is_empty() {
        distrib.settings.insert("share".into(), toml::Value::Array(vec!["vehicles".into()]));
    }
    let endpoint = listen.first().map(|e| reachable(e)).unwrap_or_default();
    specs.extend(rest);
    for mut p in procs {
        if !p.settings.contains_key("connect") && !endpoint.is_empty() {
            p.settings.insert("connect".into(), endpoint.clone().into());
        }
        specs.push(p);
    }
}

/// A port nobody listens on now (the distribution module binds it a moment later).
fn free_loopback_port() -> std::io::Result<u16> {
    Ok(std::net::TcpListener::bind("127.0.0.1:0")?.local_addr()?.port())
}

/// A listening endpoint as a local child connects to it: a wildcard address becomes loopback.
pub(crate) fn reachable(endpoint: &str) -> String {
    endpoint.replace("/0.0.0.0:", "/127.0.0.1:").replace("/[::]:", "/[::1]:")
}

#[cfg(test)]
mod tests {
    use super::*;

    fn process() -> ModuleSpec {
        ModuleSpec::new("process")
            .named("fence")
            .with("command", toml::Value::Array(vec!["true".into()]))
    }

    #[test]
    fn a_process_module_gets_a_listening_ocu_and_its_endpoint() {
        let mut specs = vec![process(), ModuleSpec::new("sim")];
        connect(&mut specs);
        let kinds: Vec<&str> = specs.iter().map(|s| s.kind.as_str()).collect();
        assert_eq!(kinds, ["distrib", "sim", "process"]);
        let listen = specs[0].settings["listen"].as_array().unwrap()[0].as_str().unwrap();
        assert!(listen.starts_with("tcp/127.0.0.1:"), "{listen}");
        assert_eq!(specs[2].settings["connect"].as_str(), Some(listen));
        assert_eq!(specs[0].settings["share"].as_array().unwrap()[0].as_str(), Some("vehicles"));
        assert_eq!(specs[0].settings["control"].as_bool(), Some(false));
    }

    #[test]
    fn a_listening_ocu_keeps_its_endpoint_and_a_wildcard_is_reached_on_loopback() {
        let distrib = ModuleSpec::new("distrib")
            .with("listen", toml::Value::Array(vec!["tcp/0.0.0.0:7447".into()]))
            .with("share", toml::Value::Array(vec!["boats".into()]));
        let mut specs = vec![distrib, process()];
        connect(&mut specs);
        assert_eq!(specs[1].settings["connect"].as_str(), Some("tcp/127.0.0.1:7447"));
        assert_eq!(specs[0].settings["share"].as_array().unwrap()[0].as_str(), Some("boats"));
    }

    #[test]
    fn without_process_modules_nothing_changes() {
        let mut specs = vec![ModuleSpec::new("sim")];
        connect(&mut specs);
        assert_eq!(specs.len(), 1);
        assert!(specs[0].settings.is_empty());
    }
}
