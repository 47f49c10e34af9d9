//! `mocu replay TRIAL.mcap`: a recorded trial (docs/recording.md) driven into a fresh
//! DataServer and shown through the recorded layout or another one (`--layout`), in a
//! window with keyboard controls and a timeline, or headless (`--frames`, `--at`,
//! `--screenshot`, `--expect`, `--dump`). The replay moves the DataServer's clock itself
//! (`mocu_replay::Player`), so the same recording and layout give the same frames at the
//! same trial times, run after run.

mod headless;
mod stage;
mod timeline;
mod window;

use mocu_language::Bundle;
use mocu_replay::Player;
use std::path::PathBuf;
use std::process::ExitCode;

#[derive(clap::Args)]
pub struct ReplayArgs {
    /// The recording (`mocu run --record TRIAL.mcap`).
    pub recording: PathBuf,
    /// Show it through this layout, profile or bundle instead of the recorded one.
    #[arg(long, value_name = "FILE")]
    pub layout: Option<PathBuf>,
    /// Trial seconds per second of replay (window), or per second of frames (headless).
    #[arg(long, value_name = "X", default_value_t = 1.0)]
    pub speed: f64,
    /// Start at this trial time (`12.5s`, `1500ms`, `2m`; seconds when bare).
    #[arg(long, value_name = "T", value_parser = parse_time)]
    pub from: Option<f64>,
    /// Stop at this trial time.
    #[arg(long, value_name = "T", value_parser = parse_time)]
    pub to: Option<f64>,
    /// Show the display as it was at this trial time, then exit (headless).
    #[arg(long, value_name = "T", value_parser = parse_time)]
    pub at: Option<f64>,
    /// Run without a window even where there is a display.
    #[arg(long)]
    pub headless: bool,
    /// Play N frames at the display rate (1/60 s of trial time each, times `--speed`).
    #[arg(long, value_name = "N")]
    pub frames: Option<u64>,
    /// Screen size, e.g. 1280x720 (default: the recorded display's, else the profile's).
    #[arg(long, value_name = "WxH", value_parser = crate::run::parse_size)]
    pub size: Option<(u32, u32)>,
    /// Write the last frame to this PNG file.
    #[arg(long, value_name = "FILE.png")]
    pub screenshot: Option<PathBuf>,
    /// Compare the last frame with this PNG: exit 1 and write FILE.diff.png beside the
    /// screenshot (or the golden) when they differ.
    #[arg(long, value_name = "GOLDEN.png")]
    pub expect: Option<PathBuf>,
    /// Channel difference (0-255) a pixel may have and still match `--expect`.
    #[arg(long, value_name = "N", default_value_t = 0)]
    pub tolerance: u8,
    /// Print the world-model subtree at PATH as JSON on exit.
    #[arg(long, value_name = "PATH")]
    pub dump: Option<String>,
    /// Evaluate layout expressions with the reference interpreter instead of the JIT.
    #[arg(long)]
    pub interpret: bool,
}

/// A trial time: `12.5s`, `1500ms`, `2m`, or bare seconds.
pub fn parse_time(s: &str) -> Result<f64, String> {
    let s = s.trim();
    let (num, scale) = if let Some(n) = s.strip_suffix("ms") {
        (n, 0.001)
    } else if let Some(n) = s.strip_suffix('s') {
        (n, 1.0)
    } else if let Some(n) = s.strip_suffix('m') {
        (n, 60.0)
    } else if let Some(n) = s.strip_suffix('h') {
        (n, 3600.0)
    } else {
        (s, 1.0)
    };
    match num.trim().parse::<f64>() {
        Ok(v) if v.is_finite() && v >= 0.0 => Ok(v * scale),
        _ => Err(format!("`{s}` is not a trial time (e.g. 12.5s, 1500ms, 2m)")),
    }
}

/// The layout to show: `--layout`'s, else the bundle recorded with the trial.
fn bundle(args: &ReplayArgs, player: &Player) -> Result<(Bundle, usize), (u8, String)> {
    let (bundle, name) = match &args.layout {
        Some(path) => match crate::run::load_target(path) {
            Ok(t) => (t.bundle, None),
            Err(crate::run::TargetError::Io(e)) => return Err((2, e)),
            Err(crate::run::TargetError::Diagnostics(r)) => {
                return Err((1, format!("{r}{} has errors", path.display())));
            }
        },
        None => {
            let bytes = player.recording().bundle().ok_or((
                2,
                "the recording has no layout attached (bundle.mocub); give one with --layout"
                    .to_string(),
            ))?;
            let b = mocu_language::bundle::read(bytes).map_err(|e| (2, e.to_string()))?;
            let name = player.recording().meta().get("layout").map(str::to_string);
            (b, name)
        }
    };
    let chosen = mocu_hotreload::choose(&bundle, name.as_deref())
        .or_else(|| mocu_hotreload::choose(&bundle, None))
        .ok_or((2, "the bundle has no layout".to_string()))?;
    Ok((bundle, chosen))
}

pub fn main(args: ReplayArgs) -> ExitCode {
    if !(args.speed.is_finite() && args.speed > 0.0) {
        eprintln!("mocu replay: --speed must be a positive number");
        return ExitCode::from(2);
    }
    let mut player = match Player::open(&args.recording) {
        Ok(p) => p,
        Err(e) => {
            eprintln!("mocu replay: {e}");
            return ExitCode::from(2);
        }
    };
    // Network cameras' units are decoded as they play (their windows show what the
    // operator saw), on the replay server's executor, so a frame is decoded by the time the
    // replay has settled.
    let exec = player.ds().serial_executor();
    let mut decoders = Vec::new();
    player.set_decoder(Box::new(
        move |ds, camera, encoded| match mocu_video::attach_replay_decoder(
            ds, &exec, camera, encoded,
        ) {
            Ok(h) => decoders.push(h),
            Err(e) => eprintln!("mocu replay: no decoder for a camera: {e}"),
        },
    ));
    if !player.recording().indexed() {
        eprintln!(
            "mocu replay: {} has no index (the recorder was killed?): read up to its last complete chunk",
            args.recording.display()
        );
    }
    let (bundle, chosen) = match bundle(&args, &player) {
        Ok(x) => x,
        Err((code, e)) => {
            eprintln!("mocu replay: {e}");
            return ExitCode::from(code);
        }
    };
    let recorded = player.recorded_screen();
    let screen = args.size.or(recorded).unwrap_or_else(|| match &bundle.profile {
        Some(p) => (p.screen[0].max(1.0) as u32, p.screen[1].max(1.0) as u32),
        None => (1920, 1080),
    });
    let stage = match stage::start(player.ds(), &bundle, chosen, screen, !args.interpret) {
        Ok(s) => s,
        Err(e) => {
            eprintln!("mocu replay: {e}");
            return ExitCode::from(1);
        }
    };
    eprintln!(
        "mocu: replaying {} ({:.1} s) through {}",
        args.recording.display(),
        (player.end_ns().saturating_sub(player.start_ns())) as f64 / 1e9,
        bundle.layouts[chosen].path
    );
    let windowed = !args.headless
        && args.at.is_none()
        && args.expect.is_none()
        && std::env::var_os("DISPLAY").is_some_and(|d| !d.is_empty());
    let code = if windowed {
        window::run(&mut player, &args, screen)
            .unwrap_or_else(|| headless::run(&mut player, &args, screen))
    } else {
        headless::run(&mut player, &args, screen)
    };
    drop(stage);
    ExitCode::from(code)
}
