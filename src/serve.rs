//! `mocu serve [PROFILE]`: the headless adapter. The world model and the vehicle and video
//! modules (the profile's, or the simulator, MAVLink and video), no display and no layout,
//! sharing `root.vehicles` over Zenoh (docs/distribution.md) until SIGINT or SIGTERM.
//! Also the `--listen`, `--connect` and `--operator` flags `mocu run` shares.

use mocu_dataserver::{DataServer, Guid, Value};
use mocu_host::{ModuleHost, ModuleSpec};
use std::path::PathBuf;
use std::process::ExitCode;
use std::time::{Duration, Instant};

/// Where a process meets the others (docs/distribution.md). With none of them (and no
/// `[modules.distrib]` in the profile), `mocu run` opens no network session at all.
#[derive(clap::Args, Clone, Debug, Default)]
pub struct NetArgs {
    /// Zenoh endpoint to listen on for other OCUs and adapters, e.g. tcp/127.0.0.1:7447
    /// (repeatable).
    #[arg(long, value_name = "ENDPOINT")]
    pub listen: Vec<String>,
    /// Zenoh endpoint of an adapter or OCU to connect to (repeatable).
    #[arg(long, value_name = "ENDPOINT")]
    pub connect: Vec<String>,
    /// The operator's name: this process's site on the key space, sent with its calls.
    #[arg(long, value_name = "NAME")]
    pub operator: Option<String>,
}

/// The endpoint `mocu serve` listens on when told neither `--listen` nor `--connect`.
pub const DEFAULT_LISTEN: &str = "tcp/127.0.0.1:7447";

/// Adds the flags to the profile's `distrib` module, or adds one for them. `serve`: the
/// adapter's defaults (site `adapter`, sharing `vehicles`, listening on [`DEFAULT_LISTEN`]).
pub fn add_distrib(specs: &mut Vec<ModuleSpec>, net: &NetArgs, serve: bool) {
    let flagged = !net.listen.is_empty() || !net.connect.is_empty() || net.operator.is_some();
    let at = match specs.iter().position(|s| s.kind == "distrib") {
        Some(i) => i,
        None if flagged || serve => {
            specs.insert(0, ModuleSpec::new("distrib"));
            0
        }
        None => return,
    };
    let s = &mut specs[at];
    let mut append = |key: &str, more: &[String]| {
        let mut list: Vec<toml::Value> = match s.settings.remove(key) {
            Some(toml::Value::Array(a)) => a,
            Some(v) => vec![v],
            None => Vec::new(),
        };
        list.extend(more.iter().map(|e| toml::Value::String(e.clone())));
        s.settings.insert(key.into(), toml::Value::Array(list));
    };
    append("listen", &net.listen);
    append("connect", &net.connect);
    if let Some(op) = &net.operator {
        s.settings.insert("operator".into(), op.clone().into());
    }
    if serve {
        let empty = |t: &toml::Table, k: &str| {
            t.get(k).and_then(|v| v.as_array()).is_none_or(|a| a.is_empty())
        };
        if empty(&s.settings, "listen") && empty(&s.settings, "connect") {
            s.settings.insert("listen".into(), toml::Value::Array(vec![DEFAULT_LISTEN.into()]));
        }
        if empty(&s.settings, "share") {
            s.settings.insert("share".into(), toml::Value::Array(vec!["vehicles".into()]));
        }
        if !s.settings.contains_key("site") && !s.settings.contains_key("operator") {
            s.settings.insert("site".into(), "adapter".into());
        }
    }
}

#[derive(clap::Args)]
pub struct ServeArgs {
    /// A profile (`.toml`) naming the modules (and `[modules.distrib]`); without one, the
    /// simulator, MAVLink and video.
    pub profile: Option<PathBuf>,
    #[command(flatten)]
    pub net: NetArgs,
    /// UDP address MAVLink vehicles are heard on, or `off`.
    #[arg(long, value_name = "ADDR|off", default_value = mocu_mavlink::DEFAULT_ADDRESS)]
    pub mavlink: String,
    /// UDP address a video stream is heard on, or `off`.
    #[arg(long, value_name = "ADDR|off", default_value = "0.0.0.0:5600")]
    pub video: String,
    /// Leave the built-in simulator out.
    #[arg(long)]
    pub no_sim: bool,
    /// Record the adapter's world model (telemetry, calls and their outcomes, the modules'
    /// events, camera frames) to an MCAP file (docs/recording.md); `mocu replay` shows it.
    #[arg(long, value_name = "TRIAL.mcap")]
    pub record: Option<PathBuf>,
}

pub fn main(args: ServeArgs) -> ExitCode {
    let mut bundle = None;
    let profile_specs = match &args.profile {
        None => None,
        Some(p) => match crate::run::load_target(p) {
            Ok(t) => {
                bundle = Some(t.bundle);
                t.modules
            }
            Err(crate::run::TargetError::Io(e)) => {
                eprintln!("mocu serve: {e}");
                return ExitCode::from(2);
            }
            Err(crate::run::TargetError::Diagnostics(rendered)) => {
                eprint!("{rendered}");
                eprintln!("mocu serve: {} has errors; nothing to serve", p.display());
                return ExitCode::from(1);
            }
        },
    };
    let mut specs = profile_specs.unwrap_or_else(|| {
        vec![ModuleSpec::new("sim"), ModuleSpec::new("mavlink"), ModuleSpec::new("video")]
    });
    let off = |a: &str| a.eq_ignore_ascii_case("off");
    // No operator at the adapter: no input, no display, no map.
    specs.retain(|s| {
        !(args.no_sim && s.kind == "sim"
            || off(&args.mavlink) && s.kind == "mavlink"
            || off(&args.video) && s.kind == "video"
            || crate::core_modules::in_role(s, crate::core_modules::CORE_ROLES)
            || s.kind == "map")
    });
    mocu_host::fill_roles(&mut specs, &[]);
    for s in specs.iter_mut() {
        let addr = match s.kind.as_str() {
            "mavlink" => &args.mavlink,
            "video" => &args.video,
            _ => continue,
        };
        if !s.settings.contains_key("address") {
            s.settings.insert("address".into(), addr.clone().into());
        }
    }
    add_distrib(&mut specs, &args.net, true);

    let stop = crate::stop::on_signals();
    let ds = DataServer::default();
    // `--record`: from the first change on, before any module starts.
    let recorder = match &args.record {
        None => None,
        Some(p) => {
            let target = args.profile.as_ref().map(|p| p.display().to_string()).unwrap_or_default();
            let layout = bundle.as_ref().and_then(|b| b.layouts.first()).map(|l| l.path.clone());
            let layout = layout.unwrap_or_default();
            match crate::record::start_with(&ds, p, &target, bundle.as_ref(), &layout, false) {
                Ok(r) => Some(r),
                Err(e) => {
                    eprintln!("mocu serve: --record {}: {e}", p.display());
                    return ExitCode::from(2);
                }
            }
        }
    };
    let sink = crate::record::TrialSink { ds: ds.clone(), log: None, recorder: recorder.clone() };
    let mut host = ModuleHost::new(ds.clone(), crate::core_modules::registry(Default::default()));
    let events = host.events();
    host.start_all(&specs);
    eprintln!("mocu: serving (headless adapter)");
    // Reports as they come, and the vehicles at most once a second when they changed.
    let t0 = Instant::now();
    let mut said = String::new();
    loop {
        crossbeam_channel::select! {
            recv(stop.requests) -> _ => break,
            recv(events) -> e => match e {
                Ok(e) => report(e, &sink),
                Err(_) => break,
            },
            default(Duration::from_secs(1)) => {}
        }
        let line = summary(&ds);
        if line != said {
            eprintln!("[{:6.1}s] {line}", t0.elapsed().as_secs_f64());
            said = line;
        }
    }
    let guard = crate::stop::bounded_teardown(0);
    host.stop_all();
    ds.quiesce();
    for e in events.try_iter() {
        report(e, &sink);
    }
    if let (Some(r), Some(file)) = (&recorder, &args.record) {
        crate::record::finish(r, file, "mocu serve");
    }
    drop(guard);
    ExitCode::SUCCESS
}

/// Prints one host report on stderr; a module's trial event goes to the recording.
fn report(e: mocu_host::HostEvent, sink: &crate::record::TrialSink) {
    use mocu_host::HostEvent;
    match e {
        HostEvent::Record { module, event, fields } => {
            crate::record::module_event(sink, &module, &event, &fields)
        }
        HostEvent::Started { module, kind } => eprintln!("mocu: module {module} ({kind}) started"),
        HostEvent::Failed { reason, .. } => eprintln!("mocu: {reason} (the rest keeps running)"),
        HostEvent::Panicked { module, message } => {
            eprintln!("mocu: module {module} panicked and was isolated: {message}")
        }
        HostEvent::Message { module, text, .. } => eprintln!("mocu: {module}: {text}"),
        HostEvent::Stopped { .. } => {}
    }
}

/// The vehicles by name, who holds each, and whether their links are up.
fn summary(ds: &DataServer) -> String {
    let Some(vs) = ds.resolve(&["vehicles"]) else { return "no vehicles".into() };
    let names: Vec<String> = ds
        .children(vs)
        .unwrap_or_default()
        .into_iter()
        .filter_map(|v: Guid| {
            let info = ds.info(v).ok()?;
            let lost = ds.try_get(v, "link_lost".into()) == Some(Value::Bool(true));
            // Who holds it, when control is arbitrated here (docs/distribution.md).
            let holder = ds
                .find_child(v, mocu_distrib::arbiter::OBJECT)
                .ok()
                .flatten()
                .and_then(|a| ds.try_get(a, "holder".into()))
                .and_then(|h| h.as_str().filter(|h| !h.is_empty()).map(|h| format!(" ({h})")))
                .unwrap_or_default();
            Some(format!("{}{holder}{}", info.name, if lost { " LINK LOST" } else { "" }))
        })
        .collect();
    format!("vehicles: {}", names.join(", "))
}
