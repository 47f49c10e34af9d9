//! A headless replay: frames on the CPU compositor, each one display period of trial time
//! (times `--speed`) after the last, as fast as they can be drawn (a replay is not paced by
//! the system's clock). Ends with `--screenshot`, `--expect` and `--dump`.

use super::ReplayArgs;
use mocu_display::Display;
use mocu_replay::Player;
use std::time::Duration;

/// Trial time played before `--at` when no `--from` is given: timers and ticks of the
/// layout (holds, ageing, animations) settle as they would have live.
const LEAD_IN: Duration = Duration::from_secs(2);

pub fn run(player: &mut Player, args: &ReplayArgs, screen: (u32, u32)) -> u8 {
    let mut display = match crate::frames::cpu_display(player.ds(), screen) {
        Ok(d) => d,
        Err(e) => {
            eprintln!("mocu replay: cannot start the display: {e}");
            return 2;
        }
    };
    let period = Duration::from_secs_f64(1.0 / mocu_display::DEFAULT_RATE);
    let frame_ns = (period.as_nanos() as f64 * args.speed).round().max(1.0) as u64;
    let (start, end) = (player.start_ns(), player.end_ns());
    let stop = args.to.map_or(end, |t| player.at_secs(t));
    let (begin, last, frames) = match args.at {
        Some(at) => {
            let t = player.at_secs(at);
            let lead = LEAD_IN.as_nanos() as u64;
            let begin =
                args.from.map_or(t.saturating_sub(lead).max(start), |f| player.at_secs(f).min(t));
            (begin, t, u64::MAX)
        }
        None => {
            (args.from.map_or(start, |f| player.at_secs(f)), stop, args.frames.unwrap_or(u64::MAX))
        }
    };
    let sought = std::time::Instant::now();
    if let Err(e) = player.seek(begin) {
        eprintln!("mocu replay: {e}");
        return 2;
    }
    eprintln!(
        "mocu: at {:.3} s (seek: {:.1} ms)",
        player.trial_secs(),
        sought.elapsed().as_secs_f64() * 1e3
    );
    let mut n = 0;
    while n < frames && player.now_ns() < last {
        let next = player.now_ns().saturating_add(frame_ns).min(last);
        if let Err(e) = player.advance_to(next) {
            eprintln!("mocu replay: {e}");
            return 2;
        }
        display.tick_animations();
        display.frame();
        n += 1;
    }
    player.ds().quiesce();
    display.frame();
    eprintln!("mocu: replayed to {:.3} s, {n} frames", player.trial_secs());
    finish(player, args, &mut display)
}

/// `--screenshot`, `--expect` (exit 1 with a diff image when the frame changed), `--dump`.
pub fn finish(player: &Player, args: &ReplayArgs, display: &mut Display) -> u8 {
    let mut code = 0;
    let frame = display.read_frame();
    if let Some(p) = &args.screenshot
        && let Err(e) = frame.save_png(p)
    {
        eprintln!("mocu replay: --screenshot {}: {e}", p.display());
        return 2;
    }
    if let Some(golden_path) = &args.expect {
        let golden = match tiny_skia::Pixmap::load_png(golden_path) {
            Ok(g) => g,
            Err(e) => {
                eprintln!("mocu replay: --expect {}: {e}", golden_path.display());
                return 2;
            }
        };
        let c = crate::golden::compare(&frame, &golden, args.tolerance);
        if !c.matches() {
            let beside = args.screenshot.as_deref().unwrap_or(golden_path);
            let diff = crate::golden::diff_path(beside);
            let wrote = crate::golden::diff_image(&frame, &golden, args.tolerance)
                .is_some_and(|d| d.save_png(&diff).is_ok());
            let sizes = c.sizes.map_or(String::new(), |((fw, fh), (gw, gh))| {
                format!(" (the frame is {fw}x{fh}, the golden {gw}x{gh})")
            });
            eprintln!(
                "mocu replay: the frame at {:.3} s differs from {}: {} pixels beyond tolerance {} (largest difference {}){sizes}{}",
                player.trial_secs(),
                golden_path.display(),
                c.differing,
                args.tolerance,
                c.max_delta,
                if wrote { format!("; see {}", diff.display()) } else { String::new() }
            );
            code = 1;
        } else {
            eprintln!("mocu: the frame matches {}", golden_path.display());
        }
    }
    if let Some(path) = &args.dump {
        match crate::run::dump(player.ds(), path) {
            Ok(json) => println!("{json}"),
            Err(e) => {
                eprintln!("mocu replay: --dump {path}: {e}");
                return 2;
            }
        }
    }
    code
}
