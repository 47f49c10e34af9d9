//! Following the target's files with `notify`. Folders are watched, not files: an editor that
//! saves by writing a new file and renaming it over the old one (vim, VS Code), or that
//! deletes and recreates it, replaces the inode a file watch would follow. Events are
//! filtered by the files the target depends on, and a burst of them (write, rename, chmod)
//! is coalesced per file: the reload runs once those files have been quiet for a short while,
//! whatever other files of their folders do (`debounce.rs`).

use crate::debounce::Debounce;
use crate::reloader::Inner;
use crossbeam_channel::{Receiver, RecvTimeoutError};
use notify::{RecursiveMode, Watcher as _};
use std::collections::BTreeSet;
use std::path::PathBuf;
use std::sync::{Arc, Weak};
use std::time::{Duration, Instant};

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

fn run(weak: Weak<Inner>, rx: Receiver<notify::Result<notify::Event>>) {
    let mut debounce = Debounce::new(QUIET);
    loop {
        let got = match debounce.deadline() {
            None => rx.recv().map_err(|_| RecvTimeoutError::Disconnected),
            Some(due) => rx.recv_deadline(due),
        };
        match got {
            Ok(Ok(ev)) if !matches!(ev.kind, notify::EventKind::Access(_)) => {
                let Some(inner) = weak.upgrade() else { return };
                let files: Vec<PathBuf> =
                    inner.state.lock().files.iter().map(|f| canonical(f)).collect();
                let now = Instant::now();
                for p in ev.paths.iter().map(|p| canonical(p)) {
                    debounce.event(&p, files.contains(&p), now);
                }
            }
            Ok(_) | Err(RecvTimeoutError::Timeout) => {}
            // The watcher was dropped: the reloader is gone.
            Err(RecvTimeoutError::Disconnected) => return,
        }
        if !debounce.take_due(Instant::now()) {
            continue;
        }
        let Some(inner) = weak.upgrade() else { return };
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
