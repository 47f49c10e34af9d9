//! `mocu run`: the OCU itself. Starts the DataServer and the module host with the modules a
//! profile names (or the defaults: the simulator and MAVLink), runs frames at 60 Hz until
//! `--frames N` have passed or Ctrl-C, and prints `--dump PATH` as JSON on exit.
//!
//! Until the display lands, every run is headless: a compact summary of the vehicles goes
//! to stderr about once a second; stdout carries only the `--dump` JSON.

use mocu_dataserver::{DataServer, Guid, Value};
use mocu_host::{Events, HostEvent, Level, ModuleHost, ModuleSpec, Registry};
use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant, SystemTime, UNIX_EPOCH};

/// The display rate: one frame every 1/60 s.
const FRAME_RATE: f64 = 60.0;

#[derive(clap::Args)]
pub struct RunArgs {
    /// A layout (`.mocu`), a profile (`.toml`) or a built profile bundle.
    pub target: PathBuf,
    /// Run without a window (the only mode until the display module lands).
    #[arg(long)]
    pub headless: bool,
    /// Run N frames at the display rate, then exit.
    #[arg(long, value_name = "N")]
    pub frames: Option<u64>,
    /// Window size, e.g. 1280x720.
    #[arg(long, value_name = "WxH", value_parser = parse_size)]
    pub size: Option<(u32, u32)>,
    /// Write the last frame to this PNG file.
    #[arg(long, value_name = "FILE.png")]
    pub screenshot: Option<PathBuf>,
    /// Append the trial's event record (JSON lines) to this file.
    #[arg(long, value_name = "FILE.jsonl")]
    pub log: Option<PathBuf>,
    /// Print the world-model subtree at PATH (e.g. `root.vehicles`) as JSON on exit.
    #[arg(long, value_name = "PATH")]
    pub dump: Option<String>,
    /// UDP address MAVLink vehicles are heard on, or `off`.
    #[arg(long, value_name = "ADDR|off", default_value = mocu_mavlink::DEFAULT_ADDRESS)]
    pub mavlink: String,
    /// UDP address a video stream is heard on, or `off`.
    #[arg(long, value_name = "ADDR|off", default_value = "0.0.0.0:5600")]
    pub video: String,
    /// Leave the built-in simulator out.
    #[arg(long)]
    pub no_sim: bool,
    /// Do not watch the layout files for changes.
    #[arg(long)]
    pub no_watch: bool,
}

fn parse_size(s: &str) -> Result<(u32, u32), String> {
    let (w, h) = s.split_once(['x', 'X']).ok_or("expected WxH, e.g. 1280x720")?;
    let w: u32 = w.parse().map_err(|_| format!("bad width `{w}`"))?;
    let h: u32 = h.parse().map_err(|_| format!("bad height `{h}`"))?;
    if w == 0 || h == 0 || w > 16384 || h > 16384 {
        return Err("width and height must be 1..=16384".into());
    }
    Ok((w, h))
}

/// What TARGET is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TargetKind {
    Layout,
    Profile,
    Bundle,
}

/// A loaded TARGET. Layout compilation is wired in later; for now a profile contributes its
/// `[[modules]]` list.
pub struct Target {
    pub path: PathBuf,
    pub kind: TargetKind,
    /// The profile's `[[modules]]`, when it names any.
    pub modules: Option<Vec<ModuleSpec>>,
}

/// Loads TARGET: checks it exists, tells a layout from a profile from a bundle, and reads a
/// profile's module list. (Layouts and bundles are validated for existence only so far.)
pub fn load_target(path: &Path) -> Result<Target, String> {
    let meta = std::fs::metadata(path).map_err(|e| format!("{}: {e}", path.display()))?;
    let ext = path.extension().and_then(|e| e.to_str()).unwrap_or("");
    let kind = match ext {
        "toml" => TargetKind::Profile,
        "mocu" => TargetKind::Layout,
        _ if meta.is_dir() => TargetKind::Layout,
        _ => TargetKind::Bundle,
    };
    let modules = if kind == TargetKind::Profile {
        let text = std::fs::read_to_string(path).map_err(|e| format!("{}: {e}", path.display()))?;
        let table: toml::Table =
            text.parse().map_err(|e| format!("{}: not a TOML profile: {e}", path.display()))?;
        ModuleSpec::list_from_profile(&table).map_err(|e| format!("{}: {e}", path.display()))?
    } else {
        None
    };
    Ok(Target { path: path.to_path_buf(), kind, modules })
}

/// The module kinds this binary knows. A project replaces one by registering its own.
pub fn registry() -> Registry {
    let mut r = Registry::new();
    mocu_sim::register(&mut r);
    mocu_mavlink::register(&mut r);
    r
}

/// The modules to start: the profile's (minus those the flags turn off), or the defaults.
pub fn module_specs(target: &Target, args: &RunArgs) -> Vec<ModuleSpec> {
    let mavlink_off = args.mavlink.eq_ignore_ascii_case("off");
    let mut specs = target
        .modules
        .clone()
        .unwrap_or_else(|| vec![ModuleSpec::new("sim"), ModuleSpec::new("mavlink")]);
    specs.retain(|s| !(args.no_sim && s.kind == "sim" || mavlink_off && s.kind == "mavlink"));
    for s in specs.iter_mut().filter(|s| s.kind == "mavlink") {
        if !s.settings.contains_key("address") {
            s.settings.insert("address".into(), args.mavlink.clone().into());
        }
    }
    specs
}

static INTERRUPTED: AtomicBool = AtomicBool::new(false);

#[cfg(unix)]
#[allow(unsafe_code)]
fn catch_ctrl_c() {
    unsafe extern "C" {
        fn signal(signum: i32, handler: extern "C" fn(i32)) -> usize;
    }
    extern "C" fn on_sigint(_: i32) {
        INTERRUPTED.store(true, Ordering::SeqCst);
    }
    // SAFETY: `on_sigint` only stores to an atomic, which is async-signal-safe.
    unsafe {
        signal(2, on_sigint);
        signal(15, on_sigint);
    }
}

#[cfg(not(unix))]
fn catch_ctrl_c() {}

pub fn main(args: RunArgs) -> ExitCode {
    let target = match load_target(&args.target) {
        Ok(t) => t,
        Err(e) => {
            eprintln!("mocu run: {e}");
            return ExitCode::from(2);
        }
    };
    let mut log = match &args.log {
        None => None,
        Some(p) => match std::fs::OpenOptions::new().create(true).append(true).open(p) {
            Ok(f) => Some(std::io::BufWriter::new(f)),
            Err(e) => {
                eprintln!("mocu run: --log {}: {e}", p.display());
                return ExitCode::from(2);
            }
        },
    };
    if args.screenshot.is_some() || args.size.is_some() {
        eprintln!(
            "mocu run: no display module yet: running headless (--size/--screenshot ignored)"
        );
    }
    catch_ctrl_c();
    eprintln!("mocu: running {:?} {} (headless)", target.kind, target.path.display());

    let ds = DataServer::default();
    let mut host = ModuleHost::new(ds.clone(), registry());
    let events = host.events();
    let specs = module_specs(&target, &args);
    host.start_all(&specs);

    let period = Duration::from_secs_f64(1.0 / FRAME_RATE);
    let t0 = Instant::now();
    let mut frame: u64 = 0;
    loop {
        drain_events(&events, &mut log);
        if args.frames.is_some_and(|n| frame >= n) || INTERRUPTED.load(Ordering::SeqCst) {
            break;
        }
        frame += 1;
        if frame.is_multiple_of(FRAME_RATE as u64) {
            eprintln!("{}", summary(&ds, t0.elapsed()));
        }
        let due = t0 + period.mul_f64(frame as f64);
        std::thread::sleep(due.saturating_duration_since(Instant::now()));
    }

    host.stop_all();
    ds.quiesce();
    drain_events(&events, &mut log);
    if let Some(l) = log.as_mut()
        && let Err(e) = l.flush()
    {
        eprintln!("mocu run: --log: {e}");
        return ExitCode::from(2);
    }
    if let Some(path) = &args.dump {
        match dump(&ds, path) {
            Ok(json) => println!("{json}"),
            Err(e) => {
                eprintln!("mocu run: --dump {path}: {e}");
                return ExitCode::from(2);
            }
        }
    }
    ExitCode::SUCCESS
}

/// Prints the host's reports on stderr and writes trial records to the log.
fn drain_events(events: &Events, log: &mut Option<impl Write>) {
    for e in events.try_iter() {
        match e {
            HostEvent::Started { module, kind } => {
                eprintln!("mocu: module {module} ({kind}) started")
            }
            HostEvent::Failed { reason, .. } => {
                eprintln!("mocu: {reason} (the rest keeps running)")
            }
            HostEvent::Panicked { module, message } => {
                eprintln!("mocu: module {module} panicked and was isolated: {message}")
            }
            HostEvent::Stopped { .. } => {}
            HostEvent::Message { module, level, text } => {
                let l = match level {
                    Level::Info => "",
                    Level::Warning => "warning: ",
                    Level::Error => "error: ",
                };
                eprintln!("mocu: {module}: {l}{text}");
            }
            HostEvent::Record { module, event, fields } => {
                if let Some(w) = log.as_mut() {
                    let _ = writeln!(w, "{}", record_json(&module, &event, &fields));
                }
            }
        }
    }
}

/// One `--log` line: `{"time": <unix seconds>, "event": …, "module": …, fields…}`.
fn record_json(module: &str, event: &str, fields: &[(String, Value)]) -> String {
    let time = SystemTime::now().duration_since(UNIX_EPOCH).map_or(0.0, |d| d.as_secs_f64());
    let q = |s: &str| Value::str(s).to_json().to_string();
    let mut out =
        format!("{{\"time\": {time:.3}, \"event\": {}, \"module\": {}", q(event), q(module));
    for (k, v) in fields {
        out.push_str(&format!(", {}: {}", q(k), v.to_json()));
    }
    out.push('}');
    out
}

/// One line: every vehicle with its speed, heading and fuel.
fn summary(ds: &DataServer, t: Duration) -> String {
    let mut parts = Vec::new();
    if let Some(vs) = ds.resolve(&["vehicles"]) {
        for v in ds.children(vs).unwrap_or_default() {
            let Ok(info) = ds.info(v) else { continue };
            let nav = ds.find_child(v, "nav").ok().flatten();
            let n = |g: Option<Guid>, p: &str| {
                g.and_then(|g| ds.try_get(g, p.into())).and_then(|x| x.as_f64())
            };
            let lost = ds.try_get(v, "link_lost".into()) == Some(Value::Bool(true));
            parts.push(format!(
                "{} {:.1}m/s {:03.0}° fuel {:.2}{}",
                info.name,
                n(nav, "speed").unwrap_or(f64::NAN),
                n(nav, "heading").unwrap_or(f64::NAN),
                n(Some(v), "fuel").unwrap_or(f64::NAN),
                if lost { " LINK LOST" } else { "" }
            ));
        }
    }
    if parts.is_empty() {
        parts.push("no vehicles".into());
    }
    format!("[{:6.1}s] {}", t.as_secs_f64(), parts.join(" | "))
}

/// The subtree at a dotted object path (`root.vehicles`, `root`) as JSON.
fn dump(ds: &DataServer, path: &str) -> Result<String, String> {
    let mut segs: Vec<&str> = path.split('.').filter(|s| !s.is_empty()).collect();
    if segs.first() == Some(&"root") {
        segs.remove(0);
    }
    let guid = ds.resolve(&segs).ok_or_else(|| format!("no object at `{path}`"))?;
    ds.snapshot(guid).map(|s| s.to_json()).map_err(|e| e.to_string())
}
