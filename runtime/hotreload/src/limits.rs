//! A layout saved during a trial must never take the OCU down. Checking it is bounded: a
//! source over `max_source_bytes` is not read into the checker, a check that runs past
//! `check_time` (or panics) is refused like a layout with errors, and the last good layout
//! stays. (The checker bounds what a layout expands to itself: E0106.) A check that ran out
//! of time goes on on its own thread until it ends, holding only its own data; nothing waits
//! for it. One check runs at a time: the next waits for it (within its own time limit) rather
//! than piling up another.

use crossbeam_channel::{Receiver, Sender};
use mocu_language::{Bundle, Diagnostics, FsLoader, SourceMap};
use std::time::Duration;

/// Bounds on one reload's check.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ReloadLimits {
    /// The longest a check may take.
    pub check_time: Duration,
    /// The largest layout or profile file checked.
    pub max_source_bytes: u64,
}

impl Default for ReloadLimits {
    fn default() -> ReloadLimits {
        ReloadLimits { check_time: Duration::from_secs(10), max_source_bytes: 8 << 20 }
    }
}

/// What a check gave: its sources, its diagnostics and (without errors) the bundle.
pub(crate) type Checked = (SourceMap, Diagnostics, Option<Bundle>);

/// Reads and checks `target` within `limits`; `Err` says why it was refused.
/// The right to run a check: one token, taken by a check and given back when it ends.
pub(crate) type Token = (Sender<()>, Receiver<()>);

pub(crate) fn token() -> Token {
    let (tx, rx) = crossbeam_channel::bounded(1);
    let _ = tx.send(());
    (tx, rx)
}

pub(crate) fn check_bounded(
    target: &std::path::Path,
    limits: ReloadLimits,
    token: &Token,
) -> Result<Checked, String> {
    let size = std::fs::metadata(target)
        .map_err(|e| format!("cannot read {}: {e}", target.display()))?
        .len();
    if size > limits.max_source_bytes {
        return Err(format!(
            "{} is {size} bytes, over the {} bytes a layout may have",
            target.display(),
            limits.max_source_bytes
        ));
    }
    let text = std::fs::read_to_string(target)
        .map_err(|e| format!("cannot read {}: {e}", target.display()))?;
    let path = target.to_string_lossy().replace('\\', "/");
    if token.1.recv_timeout(limits.check_time).is_err() {
        return Err("the check of an earlier save is still running (it ran out of time)".into());
    }
    let give_back = token.0.clone();
    let (tx, rx) = crossbeam_channel::bounded(1);
    std::thread::Builder::new()
        .name("mocu-check".into())
        .stack_size(mocu_language::COMPILER_STACK)
        .spawn(move || {
            let checked = std::panic::catch_unwind(move || {
                let mut sources = SourceMap::new();
                let mut diags = Diagnostics::new();
                let bundle =
                    mocu_language::check_path(&path, text, &FsLoader, &mut sources, &mut diags);
                (sources, diags, bundle)
            });
            let _ = give_back.send(());
            let _ = tx.send(checked);
        })
        .map_err(|e| {
            let _ = token.0.send(());
            format!("cannot start the check: {e}")
        })?;
    match rx.recv_timeout(limits.check_time) {
        Ok(Ok(checked)) => Ok(checked),
        Ok(Err(_)) => Err("the checker failed on this layout (a bug: please report it)".into()),
        Err(_) => Err(format!(
            "checking took longer than {:.1} s, the most a reload may take",
            limits.check_time.as_secs_f64()
        )),
    }
}
