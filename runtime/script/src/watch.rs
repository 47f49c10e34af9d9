//! A script module's file, followed with `notify`: the folder is watched (an editor that
//! saves by renaming a new file over the old one replaces the inode a file watch follows),
//! events for other files are ignored, and a burst of events (write, rename, chmod) reloads
//! once, when the file has been quiet for [`QUIET`] on the DataServer's clock.

use mocu_host::ModuleContext;
use notify::{RecursiveMode, Watcher as _};
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::atomic::{AtomicU64, Ordering};
use std::time::Duration;

/// How long the file must be quiet before it is reloaded.
pub const QUIET: Duration = Duration::from_millis(30);

/// Follows `file`; calls `reload` on the module's executor after each burst of changes.
/// The watch ends when the returned watcher is dropped.
pub fn follow(
    ctx: &ModuleContext,
    file: &str,
    reload: impl Fn() + Send + Sync + 'static,
) -> Result<notify::RecommendedWatcher, String> {
    let path = canonical(Path::new(file));
    let dir = path.parent().map(Path::to_path_buf).unwrap_or_default();
    let name = path.file_name().map(|n| n.to_os_string());
    let burst = Arc::new(AtomicU64::new(0));
    let reload = Arc::new(reload);
    let (ds, executor) = (ctx.ds.clone(), ctx.executor.clone());
    let mut watcher = notify::recommended_watcher(move |ev: notify::Result<notify::Event>| {
        let Ok(ev) = ev else { return };
        if !ev.paths.iter().any(|p| p.file_name().map(|n| n.to_os_string()) == name) {
            return;
        }
        let mine = burst.fetch_add(1, Ordering::AcqRel) + 1;
        let (burst, reload) = (burst.clone(), reload.clone());
        ds.run_after(QUIET, Some(&executor), move || {
            if burst.load(Ordering::Acquire) == mine {
                reload();
            }
        });
    })
    .map_err(|e| format!("cannot watch {file}: {e}"))?;
    watcher
        .watch(&dir, RecursiveMode::NonRecursive)
        .map_err(|e| format!("cannot watch {}: {e}", dir.display()))?;
    Ok(watcher)
}

fn canonical(p: &Path) -> PathBuf {
    p.canonicalize().unwrap_or_else(|_| p.to_path_buf())
}
