//! Following the target's files with `notify`. Folders are watched, not files: an editor that
//! saves by writing a new file and renaming it over the old one (vim, VS Code), or that
//! deletes and recreates it, replaces the inode a file watch would follow. Events are
//! filtered by the files the target depends on, and a burst of them (write, rename, chmod)
//! is coalesced: the reload runs once the files have been quiet for a short while.

use crate::reloader::Inner;
use crossbeam_channel::{Receiver, RecvTimeoutError};
use notify::{RecursiveMode, Watcher as _};
use std::collections::BTreeSet;
use std::path::PathBuf;
use std::sync::{Arc, Weak};
use std::time::Duration;

/// How long the files must be quiet before reloading.
const QUIET: Duration = Duration::from_millis(30);

pub(crate) struct Watcher {
    watcher: notify::RecommendedWatcher,
    dirs: BTreeSet<PathBuf>,
}

fn canonical(p: &std::path::Path) -> PathBuf {
    p.canonicalize().unwrap_or_else(|_| {
        // A file being replaced may not exist this instant: canonicalise its folder.
        match (p.parent().and_then(|d| d.canonicalize().ok()), p.file_name()) {
            (Some(d), Some(f)) => d.join(f),
            _ => p.to_path_buf(),
        }
    })
}

pub(crate) fn start(inner: &Arc<Inner>) -> Result<(), String> {
    let (tx, rx) = crossbeam_channel::unbounded::<notify::Result<notify::Event>>();
    let watcher =
        notify::recommended_watcher(tx).map_err(|e| format!("cannot watch files: {e}"))?;
    let mut w = Watcher { watcher, dirs: BTreeSet::new() };
    sync_dirs(inner, &mut w)?;
    inner.state.lock().watcher = Some(w);
    let weak = Arc::downgrade(inner);
    std::thread::Builder::new()
        .name("mocu-hot-reload".into())
        .stack_size(mocu_language::COMPILER_STACK)
        .spawn(move || run(weak, rx))
        .map_err(|e| e.to_string())?;
    Ok(())
}

/// Watches the folder of every file the target depends on (and no others).
fn sync_dirs(inner: &Inner, w: &mut Watcher) -> Result<(), String> {
    let files = inner.state.lock().files.clone();
    let want: BTreeSet<PathBuf> =
        files.iter().filter_map(|f| canonical(f).parent().map(|p| p.to_path_buf())).collect();
    for d in want.difference(&w.dirs.clone()) {
        w.watcher
            .watch(d, RecursiveMode::NonRecursive)
            .map_err(|e| format!("cannot watch {}: {e}", d.display()))?;
        w.dirs.insert(d.clone());
    }
    for d in w.dirs.clone().difference(&want) {
        let _ = w.watcher.unwatch(d);
        w.dirs.remove(d);
    }
    Ok(())
}

fn touches_target(inner: &Inner, ev: &notify::Event) -> bool {
    if matches!(ev.kind, notify::EventKind::Access(_)) {
        return false;
    }
    let files: Vec<PathBuf> = inner.state.lock().files.iter().map(|f| canonical(f)).collect();
    ev.paths.iter().any(|p| files.contains(&canonical(p)))
}

fn run(weak: Weak<Inner>, rx: Receiver<notify::Result<notify::Event>>) {
    loop {
        // Wait for the first relevant event…
        let ev = match rx.recv() {
            Ok(ev) => ev,
            Err(_) => return, // the watcher was dropped: the reloader is gone
        };
        let Some(inner) = weak.upgrade() else { return };
        if !ev.is_ok_and(|e| touches_target(&inner, &e)) {
            continue;
        }
        // …then until the burst is over.
        loop {
            match rx.recv_timeout(QUIET) {
                Ok(_) => continue,
                Err(RecvTimeoutError::Timeout) => break,
                Err(RecvTimeoutError::Disconnected) => return,
            }
        }
        inner.reload();
        // A reload may add or drop files (a new `use`): follow them.
        let mut st = inner.state.lock();
        if let Some(mut w) = st.watcher.take() {
            drop(st);
            let _ = sync_dirs(&inner, &mut w);
            inner.state.lock().watcher = Some(w);
        }
    }
}
