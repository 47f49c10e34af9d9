//! A replay in a window: the player on a thread of its own, moving trial time with the
//! system's clock (times the speed) while playing; keys (space, right, [ ], Home, End)
//! control it, and a timeline strip shows where it is. `None` when no window can open.

use super::ReplayArgs;
use super::timeline::{self, Control, Position};
use crossbeam_channel::RecvTimeoutError;
use mocu_display::{DisplayOptions, WindowOptions, WindowStop, run_window};
use mocu_replay::Player;
use std::sync::Arc;
use std::sync::Mutex;
use std::time::{Duration, Instant};

/// How far the right arrow steps (paused), in trial time.
const STEP: Duration = Duration::from_millis(100);
const PERIOD: Duration = Duration::from_micros(16_667);

pub fn run(player: &mut Player, args: &ReplayArgs, screen: (u32, u32)) -> Option<u8> {
    let (tx, rx) = crossbeam_channel::unbounded();
    let ds = player.ds().clone();
    timeline::keyboard(&ds, tx.clone());
    let position = Arc::new(Mutex::new(Position {
        length: (player.end_ns().saturating_sub(player.start_ns())) as f64 / 1e9,
        speed: args.speed,
        playing: true,
        ..Position::default()
    }));
    let strip = timeline::strip(&ds, screen, position.clone(), tx.clone());
    let begin = args.from.map_or(player.start_ns(), |f| player.at_secs(f));
    let stop_at = args.to.map_or(player.end_ns(), |t| player.at_secs(t));
    if let Err(e) = player.seek(begin) {
        eprintln!("mocu replay: {e}");
        return Some(2);
    }
    let stop = WindowStop::default();
    let opts = WindowOptions {
        title: format!("Mocu replay — {}", args.recording.display()),
        display: DisplayOptions::new(screen.0, screen.1).without_window_behaviours(),
        frames: args.frames,
        screenshot: args.screenshot.clone(),
        stop: Some(stop.clone()),
    };
    let (quit_tx, quit_rx) = crossbeam_channel::bounded::<()>(1);
    let result = std::thread::scope(|s| {
        let driver = s.spawn(|| {
            drive(player, &rx, &quit_rx, stop_at, &position, |p| {
                if let Some(g) = strip {
                    let _ = mocu_display::invalidate(p.ds(), g);
                }
            })
        });
        let r = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
            run_window(&ds, opts, |_| {})
        }));
        let _ = quit_tx.send(());
        let _ = driver.join();
        r
    });
    match result {
        Ok(Ok(c)) => {
            eprintln!("mocu: window closed after {} frames drawn", c.frames_drawn);
            if let Some(path) = &args.dump {
                match crate::run::dump(&ds, path) {
                    Ok(json) => println!("{json}"),
                    Err(e) => {
                        eprintln!("mocu replay: --dump {path}: {e}");
                        return Some(2);
                    }
                }
            }
            Some(0)
        }
        Ok(Err(e)) => {
            eprintln!("mocu: no window ({e}); replaying headless");
            None
        }
        Err(_) => {
            eprintln!("mocu: the window's graphics failed; replaying headless");
            None
        }
    }
}

/// Plays in real time until told to quit, following the controls.
fn drive(
    player: &mut Player,
    controls: &crossbeam_channel::Receiver<Control>,
    quit: &crossbeam_channel::Receiver<()>,
    stop_at: u64,
    position: &Mutex<Position>,
    shown: impl Fn(&Player),
) {
    let mut last = Instant::now();
    loop {
        if quit.try_recv().is_ok() {
            return;
        }
        let control = match controls.recv_timeout(PERIOD) {
            Ok(c) => Some(c),
            Err(RecvTimeoutError::Timeout) => None,
            Err(RecvTimeoutError::Disconnected) => return,
        };
        let now = Instant::now();
        let elapsed = now - last;
        last = now;
        let (mut playing, mut speed) = {
            let p = position.lock().unwrap_or_else(|e| e.into_inner());
            (p.playing, p.speed)
        };
        let result = match control {
            Some(Control::PlayPause) => {
                playing = !playing;
                Ok(())
            }
            Some(Control::Step) => {
                playing = false;
                player.step(STEP)
            }
            Some(Control::Slower) => {
                speed = (speed / 2.0).max(1.0 / 64.0);
                Ok(())
            }
            Some(Control::Faster) => {
                speed = (speed * 2.0).min(64.0);
                Ok(())
            }
            Some(Control::Start) => player.seek(player.start_ns()),
            Some(Control::End) => player.seek(stop_at),
            Some(Control::Seek(secs)) => player.seek(player.at_secs(secs).min(stop_at)),
            None if playing => {
                let d = (elapsed.as_nanos() as f64 * speed) as u64;
                player.advance_to(player.now_ns().saturating_add(d).min(stop_at))
            }
            None => Ok(()),
        };
        if let Err(e) = result {
            eprintln!("mocu replay: {e}");
            return;
        }
        if player.now_ns() >= stop_at {
            playing = false;
        }
        let p = Position {
            secs: player.trial_secs(),
            playing,
            speed,
            length: position.lock().unwrap_or_else(|e| e.into_inner()).length,
        };
        let changed = *position.lock().unwrap_or_else(|e| e.into_inner()) != p;
        *position.lock().unwrap_or_else(|e| e.into_inner()) = p;
        if changed {
            shown(player);
        }
    }
}
