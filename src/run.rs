//! `mocu run`: the OCU itself. Checks the target (a layout, a profile or a bundle), starts
//! the DataServer, the module host with the modules the profile names (or the defaults: the
//! simulator, MAVLink and video) and the core modules it leaves out (input, the widget
//! renderer, the map view, the video windows: `crate::core_modules`), then the layout, then runs frames — in a window where there is a display, headless
//! otherwise — until `--frames N` have passed at 60 Hz, the window is closed, or SIGINT
//! (Ctrl-C) or SIGTERM. A frame is drawn only when something changed: an idle run sleeps.
//! On exit it writes `--screenshot`, prints `--dump PATH` as JSON (the display and the
//! layout still live), then stops every module within a bounded time (`crate::stop`).
//! Headless runs print a compact summary of the vehicles to stderr, at most once a second
//! and only when it changed; stdout carries only the `--dump` JSON.

use crate::frames::Pace;
use mocu_dataserver::{DataServer, Guid, Value};
use mocu_display::{DisplayOptions, WindowOptions, run_window};
use mocu_host::{Events, HostEvent, Level, ModuleHost, ModuleSpec};
use mocu_layout::{EventSink, JsonlLog, LayoutConfig, NullSink};
use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::sync::Arc;
use std::time::{Duration, Instant};

#[derive(clap::Args)]
pub struct RunArgs {
    /// A layout (`.mocu`), a profile (`.toml`) or a built profile bundle.
    pub target: PathBuf,
    /// Run without a window even where there is a display.
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
    /// Record the whole trial (world model, calls, events, video as received) to this MCAP
    /// file (docs/recording.md).
    #[arg(long, value_name = "FILE.mcap")]
    pub record: Option<PathBuf>,
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
    /// Which of a profile's layouts to show (its file name or stem); the first by default.
    #[arg(long, value_name = "NAME")]
    pub layout: Option<String>,
    /// Evaluate layout expressions with the reference interpreter instead of the JIT.
    #[arg(long)]
    pub interpret: bool,
    /// Replay this input script as a virtual gamepad (docs/input.md), for tests and trials.
    #[arg(long, value_name = "FILE")]
    pub input_script: Option<PathBuf>,
    /// Share the world model over Zenoh (docs/distribution.md).
    #[command(flatten)]
    pub net: crate::serve::NetArgs,
}

pub(crate) fn parse_size(s: &str) -> Result<(u32, u32), String> {
    let (w, h) = s.split_once(['x', 'X']).ok_or("expected WxH, e.g. 1280x720")?;
    let w: u32 = w.parse().map_err(|_| format!("bad width `{w}`"))?;
    let h: u32 = h.parse().map_err(|_| format!("bad height `{h}`"))?;
    if w == 0 || h == 0 || w > 16384 || h > 16384 {
        return Err("width and height must be 1..=16384".into());
    }
    Ok((w, h))
}

/// A checked TARGET: the bundle (layouts, schema, profile) and the modules to start.
pub struct Target {
    pub bundle: mocu_language::Bundle,
    /// The profile's modules, when it names any.
    pub modules: Option<Vec<ModuleSpec>>,
    /// A bundle's carried files, written out for its modules while the target lives.
    _carried: Option<crate::bundle_files::Carried>,
}

/// Why TARGET could not be run.
pub enum TargetError {
    /// Unreadable, or not a layout, profile or bundle: exit 2.
    Io(String),
    /// The sources have errors (already rendered): exit 1.
    Diagnostics(String),
}

/// Loads and checks TARGET. A profile's modules (`[modules.NAME]` tables, each handed to
/// its module as settings; `kind` defaults to NAME) start in the order of their `order`
/// setting, then the core order sim, mavlink, video, then by name.
pub fn load_target(path: &Path) -> Result<Target, TargetError> {
    let (bundle, warnings) = match mocu_language::load_target(path) {
        Ok(x) => x,
        Err(mocu_language::LoadError::Diagnostics { rendered, .. }) => {
            return Err(TargetError::Diagnostics(rendered));
        }
        Err(e) => return Err(TargetError::Io(e.to_string())),
    };
    if !warnings.trim().is_empty() {
        eprint!("{warnings}");
    }
    let mut carried = None;
    let modules = match profile_specs(&bundle).map_err(TargetError::Io)? {
        Some(mut specs) => {
            // A bundle's modules find their files where it writes them (absolute paths,
            // which the joins below keep).
            carried = crate::bundle_files::extract(&bundle, &mut specs).map_err(TargetError::Io)?;
            // The files the modules name, as paths from the working folder (docs/map.md,
            // docs/scripting.md).
            let dir = profile_dir(path);
            for s in &mut specs {
                crate::bundle_files::resolve_from(s, &dir);
            }
            Some(specs)
        }
        None => None,
    };
    Ok(Target { bundle, modules, _carried: carried })
}

/// A bundle's profile's modules in start order: their `order` setting, then the core order
/// sim, mavlink, video, then by name. None when the profile names no module.
pub(crate) fn profile_specs(
    bundle: &mocu_language::Bundle,
) -> Result<Option<Vec<ModuleSpec>>, String> {
    let Some(p) = bundle.profile.as_ref().filter(|p| !p.modules.is_empty()) else {
        return Ok(None);
    };
    let mut specs = Vec::new();
    for (name, settings) in &p.modules {
        let mut table: toml::Table = serde_json::from_value(settings.clone())
            .map_err(|e| format!("module `{name}`: {e}"))?;
        table.insert("name".into(), toml::Value::String(name.clone()));
        specs.push(ModuleSpec::from_table(&table).map_err(|e| e.to_string())?);
    }
    let rank = |s: &ModuleSpec| {
        let order = s.settings.get("order").and_then(|v| v.as_integer()).unwrap_or(i64::MAX);
        let core = ["sim", "mavlink", "video"].iter().position(|k| *k == s.kind).unwrap_or(9);
        (order, core, s.name.clone())
    };
    specs.sort_by_key(rank);
    Ok(Some(specs))
}

/// The folder a profile's file settings (the map's `overlays` and `tiles`, a script module's
/// `file`) are relative
/// to: the profile's own, a layout's project's, or a bundle's.
fn profile_dir(target: &Path) -> PathBuf {
    if target.extension().is_some_and(|e| e == "mocu")
        && let Some(p) =
            mocu_language::project::discover(&target.to_string_lossy(), &mocu_language::FsLoader)
    {
        return Path::new(&p).parent().map(Path::to_path_buf).unwrap_or_default();
    }
    target.parent().map(Path::to_path_buf).unwrap_or_default()
}

/// The modules to start: the profile's (minus those the flags turn off), or the defaults;
/// then the core modules whose role the profile leaves empty, less those it turns off
/// (`enabled = false`).
pub fn module_specs(target: &Target, args: &RunArgs) -> Vec<ModuleSpec> {
    let mavlink_off = args.mavlink.eq_ignore_ascii_case("off");
    let video_off = args.video.eq_ignore_ascii_case("off");
    let mut specs = target.modules.clone().unwrap_or_else(|| {
        vec![ModuleSpec::new("sim"), ModuleSpec::new("mavlink"), ModuleSpec::new("video")]
    });
    specs.retain(|s| {
        !(args.no_sim && s.kind == "sim"
            || mavlink_off && s.kind == "mavlink"
            || video_off && s.kind == "video")
    });
    for s in specs.iter_mut().filter(|s| s.kind == "mavlink") {
        if !s.settings.contains_key("address") {
            s.settings.insert("address".into(), args.mavlink.clone().into());
        }
    }
    for s in specs.iter_mut().filter(|s| s.kind == "video") {
        if !s.settings.contains_key("address") {
            s.settings.insert("address".into(), args.video.clone().into());
        }
    }
    // Operator input and the display's modules always run unless the profile turns them
    // off; a profile configures them (`[modules.input]`) or puts another kind in their role.
    crate::core_modules::fill(&mut specs, crate::core_modules::CORE_ROLES);
    if let Some(script) = &args.input_script {
        for s in specs.iter_mut().filter(|s| s.kind == "input") {
            s.settings.insert("script".into(), script.display().to_string().into());
        }
    }
    crate::serve::add_distrib(&mut specs, &args.net, false);
    crate::process_modules::connect(&mut specs);
    specs
}

pub fn main(args: RunArgs) -> ExitCode {
    let target = match load_target(&args.target) {
        Ok(t) => t,
        Err(TargetError::Io(e)) => {
            eprintln!("mocu run: {e}");
            return ExitCode::from(2);
        }
        Err(TargetError::Diagnostics(rendered)) => {
            eprint!("{rendered}");
            eprintln!("mocu run: {} has errors; nothing to run", args.target.display());
            return ExitCode::from(1);
        }
    };
    let sink: Arc<dyn EventSink> = match &args.log {
        None => Arc::new(NullSink),
        Some(p) => match JsonlLog::append(p) {
            Ok(l) => Arc::new(l),
            Err(e) => {
                eprintln!("mocu run: --log {}: {e}", p.display());
                return ExitCode::from(2);
            }
        },
    };
    let Some(chosen) = mocu_hotreload::choose(&target.bundle, args.layout.as_deref()) else {
        let names: Vec<&str> = target.bundle.layouts.iter().map(|l| l.path.as_str()).collect();
        eprintln!(
            "mocu run: no layout `{}` in the profile (it has: {})",
            args.layout.as_deref().unwrap_or(""),
            names.join(", ")
        );
        return ExitCode::from(2);
    };
    let stop = crate::stop::on_signals();
    let screen = args.size.unwrap_or_else(|| match &target.bundle.profile {
        Some(p) => (p.screen[0].max(1.0) as u32, p.screen[1].max(1.0) as u32),
        None => (1920, 1080),
    });
    let windowed = !args.headless && std::env::var_os("DISPLAY").is_some_and(|d| !d.is_empty());

    // `--frames N` headless: the frames clock the run, so that it is deterministic.
    let stepped = (!windowed && args.frames.is_some()).then(crate::frames::Stepped::new);
    let ds = stepped.as_ref().map_or_else(DataServer::default, |s| s.ds.clone());
    // `--record`: from the first change on, before any module starts.
    let layout_name = target.bundle.layouts[chosen].path.clone();
    let manual = !windowed && args.frames.is_some();
    let recorder = match &args.record {
        None => None,
        Some(p) => match crate::record::start(&ds, p, &target, &layout_name, manual) {
            Ok(r) => Some(r),
            Err(e) => {
                eprintln!("mocu run: --record {}: {e}", p.display());
                return ExitCode::from(2);
            }
        },
    };
    let log = args.log.is_some().then(|| sink.clone());
    let sink: Arc<dyn EventSink> =
        Arc::new(crate::record::TrialSink { ds: ds.clone(), log, recorder: recorder.clone() });
    // The modules (the display's last: each finds the others through root.display, of the
    // screen's size), then the layout.
    let jit = !args.interpret;
    let components = match crate::core_modules::components(&target.bundle, jit) {
        Ok(c) => c,
        Err(e) => {
            eprintln!("mocu run: {e}");
            return ExitCode::from(1);
        }
    };
    let _ = mocu_display::ensure_display_object(&ds, screen.0, screen.1);
    let mut host = ModuleHost::new(ds.clone(), crate::core_modules::registry(components.clone()));
    let events = host.events();
    let specs = module_specs(&target, &args);
    let required_failed = required_failures(&specs, &host.start_all(&specs));
    // The layout runs under the reloader: a saved edit swaps in between two frames, its
    // components into the widget renderer.
    let hook = Some(crate::core_modules::reload_hook(components, jit));
    let options = mocu_hotreload::ReloaderOptions {
        config: LayoutConfig {
            screen: (screen.0 as f64, screen.1 as f64),
            jit,
            name: target.bundle.layouts[chosen].path.clone(),
            stale_after: LayoutConfig::stale_after_from(&target.bundle.schema),
            ..LayoutConfig::default()
        },
        layout: args.layout.clone(),
        on_components: hook,
    };
    let layout = match mocu_hotreload::Reloader::start(
        &ds,
        &args.target,
        &target.bundle,
        options,
        sink.clone(),
    ) {
        Ok(l) => l,
        Err(e) => {
            eprintln!("mocu run: {e}");
            return ExitCode::from(1);
        }
    };
    if args.no_watch
        || mocu_language::bundle::is_bundle(&std::fs::read(&args.target).unwrap_or_default())
    {
        // Fielded use, or a built bundle (no sources): nothing to watch.
    } else if let Err(e) = layout.watch() {
        eprintln!("mocu: {e}; hot reload is off");
    }
    eprintln!(
        "mocu: running {} ({})",
        target.bundle.layouts[chosen].path,
        if windowed { "window" } else { "headless" }
    );

    let mut code: u8 = 0;
    let mut ran_window = false;
    if windowed {
        let opts = WindowOptions {
            title: format!("Mocu — {}", target.bundle.layouts[chosen].path),
            display: DisplayOptions::new(screen.0, screen.1).without_window_behaviours(),
            frames: args.frames,
            screenshot: args.screenshot.clone(),
            stop: Some(stop.window.clone()),
        };
        let ev = events.clone();
        let s2 = sink.clone();
        // A graphics stack can fail in ways wgpu reports by panicking (a surface the
        // adapter cannot present to, seen with lavapipe under Xvfb): the operator gets the
        // CPU path, not a crash.
        let attempt = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
            run_window(&ds, opts, move |_d| drain_events(&ev, &s2))
        }));
        match attempt {
            Ok(Ok(c)) => {
                ran_window = true;
                eprintln!("mocu: window closed after {} frames drawn", c.frames_drawn);
            }
            Ok(Err(e)) => eprintln!(
                "mocu: no window ({e}); falling back to headless frames on the CPU (tiny-skia)"
            ),
            Err(_) => eprintln!(
                "mocu: the window's graphics failed (try WGPU_BACKEND=gl); falling back to headless frames on the CPU (tiny-skia)"
            ),
        }
    }
    if !ran_window {
        code = run_headless(&ds, &args, screen, &events, &sink, &stop, stepped.as_ref());
    }
    if code == 0 && !required_failed.is_empty() {
        eprintln!(
            "mocu run: exit 1: {} did not start (mark a module `optional = true` in the profile to run without it)",
            required_failed.join(", ")
        );
        code = 1;
    }

    // The outputs first, with the display and the layout still live (`--dump
    // root.display` shows the display as it was), then the teardown, bounded.
    ds.quiesce();
    drain_events(&events, &sink);
    if let Some(path) = &args.dump {
        match dump(&ds, path) {
            Ok(json) => println!("{json}"),
            Err(e) => {
                eprintln!("mocu run: --dump {path}: {e}");
                code = 2;
            }
        }
    }
    let _ = std::io::stdout().flush();
    let guard = crate::stop::bounded_teardown(code);
    drop(layout);
    host.stop_all();
    ds.quiesce();
    drain_events(&events, &sink);
    if let (Some(r), Some(file)) = (&recorder, &args.record) {
        crate::record::finish(r, file, "mocu run");
    }
    drop(guard);
    ExitCode::from(code)
}

/// The modules that failed to start and are not marked `optional = true`: the run goes on
/// (the operator sees what is there), and exits 1 at its end.
fn required_failures(specs: &[ModuleSpec], errors: &[mocu_host::StartError]) -> Vec<String> {
    errors
        .iter()
        .map(mocu_host::StartError::module)
        .filter(|m| {
            let optional = specs
                .iter()
                .find(|s| s.name == *m)
                .and_then(|s| s.settings.get("optional"))
                .and_then(toml::Value::as_bool);
            optional != Some(true)
        })
        .map(|m| format!("module `{m}`"))
        .collect()
}

/// Every component of every layout of the bundle, once (the first definition wins).
pub(crate) fn all_components(bundle: &mocu_language::Bundle) -> mocu_language::Program {
    let mut p = mocu_language::Program::default();
    for l in &bundle.layouts {
        for c in &l.program.components {
            if !p.components.iter().any(|x| x.name == c.name) {
                p.components.push(c.clone());
            }
        }
    }
    p
}

/// Frames on the CPU compositor, drawn only when something changed (`crate::frames`):
/// `--frames N` ticks N times at the display rate, otherwise until SIGINT or SIGTERM.
/// Ends with the last frame drawn and written to `--screenshot`.
fn run_headless(
    ds: &DataServer,
    args: &RunArgs,
    screen: (u32, u32),
    events: &Events,
    sink: &Arc<dyn EventSink>,
    stop: &crate::stop::Stop,
    stepped: Option<&crate::frames::Stepped>,
) -> u8 {
    let mut display = match crate::frames::cpu_display(ds, screen) {
        Ok(d) => d,
        Err(e) => {
            eprintln!("mocu run: cannot start the display: {e}");
            return 2;
        }
    };
    let pace = args.frames.map_or(Pace::UntilStopped, Pace::Frames);
    let t0 = Instant::now();
    // A summary of the vehicles at most once a second, when a frame is drawn and it
    // says something new: an idle run prints nothing.
    let mut said = (t0, String::new());
    let inputs = crate::frames::Inputs { stop: &stop.requests, events, stepped };
    let c = crate::frames::run(
        &mut display,
        pace,
        inputs,
        |e| report(e, sink),
        |st| {
            if st.drawn && said.0.elapsed() >= Duration::from_secs(1) {
                let line = summary(ds);
                if line != said.1 {
                    eprintln!("[{:6.1}s] {line}", t0.elapsed().as_secs_f64());
                }
                said = (Instant::now(), line);
            }
        },
    );
    // Whatever changed during the last frame period is on the last frame.
    ds.quiesce();
    display.frame();
    if let Some(p) = &args.screenshot
        && let Err(e) = display.screenshot(p)
    {
        eprintln!("mocu run: --screenshot {}: {e}", p.display());
        return 2;
    }
    eprintln!("mocu: {} frames, {} drawn, {} wake-ups", c.ticks, c.drawn, c.wakeups);
    0
}

/// Prints the host's reports on stderr and writes trial records to the log.
fn drain_events(events: &Events, sink: &Arc<dyn EventSink>) {
    for e in events.try_iter() {
        report(e, sink);
    }
}

/// Prints one host report on stderr, or writes it to the log.
fn report(e: HostEvent, sink: &Arc<dyn EventSink>) {
    {
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
                crate::record::module_event(sink.as_ref(), &module, &event, &fields)
            }
        }
    }
}

/// One line: every vehicle with its speed, heading and fuel.
fn summary(ds: &DataServer) -> String {
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
    parts.join(" | ")
}

/// The subtree at a dotted object path (`root.vehicles`, `root`) as JSON.
pub(crate) fn dump(ds: &DataServer, path: &str) -> Result<String, String> {
    let mut segs: Vec<&str> = path.split('.').filter(|s| !s.is_empty()).collect();
    if segs.first() == Some(&"root") {
        segs.remove(0);
    }
    let guid = ds.resolve(&segs).ok_or_else(|| format!("no object at `{path}`"))?;
    ds.snapshot(guid).map(|s| s.to_json()).map_err(|e| e.to_string())
}
