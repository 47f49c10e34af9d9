//! How `mocu run` ends. SIGINT (Ctrl-C), SIGTERM and SIGHUP (the terminal or the SSH session
//! that ran it closed) ask the frame loop (headless or windowed) to stop; the run then writes `--screenshot`, `--dump` and `--log` before it
//! stops the modules. The shutdown a signal starts is bounded: if the process is still there
//! [`SIGNAL_BOUND`] after the first signal (outputs stuck, a module that will not stop, a machine
//! under load), it exits with 128 + the signal. A second signal ends the process at once,
//! from the signal handler itself (no thread, lock or busy worker can hold it up), and so
//! does a teardown that has not finished within [`GRACE`] (its outputs are already written).

use crossbeam_channel::{Receiver, Sender, bounded, never};
use mocu_display::WindowStop;
use signal_hook::consts::{SIGHUP, SIGINT, SIGTERM};
use signal_hook::iterator::Signals;
use std::io::Write;
use std::sync::Arc;
use std::sync::atomic::AtomicBool;
use std::time::Duration;

/// How long the modules get to stop after the outputs are written.
pub const GRACE: Duration = Duration::from_secs(10);

/// How long the whole shutdown a signal starts may take (the outputs, then the modules'
/// [`GRACE`]).
pub const SIGNAL_BOUND: Duration = Duration::from_secs(20);

/// A stop asked for by a signal.
pub struct Stop {
    /// Receives one message when a stop is asked for.
    pub requests: Receiver<()>,
    /// Ends a window's event loop.
    pub window: WindowStop,
}

/// The signals that stop a run, each handled the same way.
const STOP_SIGNALS: [i32; 3] = [SIGINT, SIGTERM, SIGHUP];

/// Starts listening for SIGINT, SIGTERM and SIGHUP. Where they cannot be caught, the run still
/// ends with `--frames` or by closing its window (and says so).
pub fn on_signals() -> Stop {
    let window = WindowStop::new();
    let (tx, rx) = bounded(1);
    match listen(tx, window.clone()) {
        Ok(()) => Stop { requests: rx, window },
        Err(e) => {
            eprintln!(
                "mocu: cannot catch SIGINT/SIGTERM/SIGHUP ({e}); Ctrl-C ends the run abruptly"
            );
            Stop { requests: never(), window }
        }
    }
}

fn listen(tx: Sender<()>, window: WindowStop) -> std::io::Result<()> {
    // In the handler, in this order: exit if a signal came before, then remember this one.
    let armed = Arc::new(AtomicBool::new(false));
    for sig in STOP_SIGNALS {
        signal_hook::flag::register_conditional_shutdown(sig, 128 + sig, armed.clone())?;
        signal_hook::flag::register(sig, armed.clone())?;
    }
    let mut signals = Signals::new(STOP_SIGNALS)?;
    std::thread::Builder::new().name("mocu-signals".into()).spawn(move || {
        if let Some(sig) = signals.forever().next() {
            let name = signal_name(sig);
            // After SIGHUP the terminal may be gone: a failed write must not end this thread.
            let _ = writeln!(
                std::io::stderr(),
                "mocu: {name}: stopping (send it again to exit at once)"
            );
            let _ = tx.try_send(());
            window.stop();
            // The shutdown is bounded from here, whatever it waits for.
            let (_never, wait) = bounded::<()>(0);
            let _ = wait.recv_timeout(SIGNAL_BOUND);
            let _ = writeln!(
                std::io::stderr(),
                "mocu: still stopping {} s after {name} (outputs or a module stuck); exiting",
                SIGNAL_BOUND.as_secs()
            );
            signal_hook::low_level::exit(128 + sig);
        }
    })?;
    Ok(())
}

fn signal_name(sig: i32) -> &'static str {
    match sig {
        SIGINT => "SIGINT",
        SIGHUP => "SIGHUP",
        _ => "SIGTERM",
    }
}

/// Ends the process with `code` if the returned guard is still alive after [`GRACE`]:
/// drop it when the teardown is done.
pub fn bounded_teardown(code: u8) -> Sender<()> {
    let (done, wait) = bounded::<()>(0);
    let _ = std::thread::Builder::new().name("mocu-teardown-guard".into()).spawn(move || {
        if wait.recv_timeout(GRACE) == Err(crossbeam_channel::RecvTimeoutError::Timeout) {
            eprintln!(
                "mocu: the modules did not stop within {} s (one is stuck); exiting anyway",
                GRACE.as_secs()
            );
            std::process::exit(code as i32);
        }
    });
    done
}
