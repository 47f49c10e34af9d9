//! When a burst of file events becomes a reload: per file the layout depends on. Each such
//! file's last event is remembered; the reload is due once every one of them has been quiet
//! for `quiet`. Events of other files in a watched folder (a log being written beside the
//! layout, a build's output) are ignored, so they can never hold a reload back. Time is an
//! input: the watcher passes `Instant::now()`, tests pass the instants they choose.

use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

#[derive(Debug)]
pub(crate) struct Debounce {
    quiet: Duration,
    /// The files the layout depends on that changed, with their last event.
    pending: HashMap<PathBuf, Instant>,
}

impl Debounce {
    pub fn new(quiet: Duration) -> Debounce {
        Debounce { quiet, pending: HashMap::new() }
    }

    /// An event on `path` at `now`; `depends` says whether the layout depends on that file.
    pub fn event(&mut self, path: &Path, depends: bool, now: Instant) {
        if depends {
            self.pending.insert(path.to_path_buf(), now);
        }
    }

    /// When the reload is due, if a file the layout depends on changed.
    pub fn deadline(&self) -> Option<Instant> {
        self.pending.values().max().map(|t| *t + self.quiet)
    }

    /// True (once) when the reload is due at `now`.
    pub fn take_due(&mut self, now: Instant) -> bool {
        match self.deadline() {
            Some(d) if d <= now => {
                self.pending.clear();
                true
            }
            _ => false,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const QUIET: Duration = Duration::from_millis(30);

    fn ms(t0: Instant, n: u64) -> Instant {
        t0 + Duration::from_millis(n)
    }

    #[test]
    fn a_reload_is_due_once_the_layouts_file_has_been_quiet() {
        let t0 = Instant::now();
        let mut d = Debounce::new(QUIET);
        assert_eq!(d.deadline(), None);
        d.event(Path::new("/p/a.mocu"), true, t0);
        d.event(Path::new("/p/a.mocu"), true, ms(t0, 10));
        assert!(!d.take_due(ms(t0, 39)), "an editor's burst is still going on");
        assert!(d.take_due(ms(t0, 40)));
        assert!(!d.take_due(ms(t0, 41)), "once per burst");
    }

    #[test]
    fn writes_to_unrelated_files_in_the_folder_never_delay_a_reload() {
        let t0 = Instant::now();
        let mut d = Debounce::new(QUIET);
        d.event(Path::new("/p/a.mocu"), true, t0);
        // A log beside the layout, written every 5 ms for a minute.
        for i in 1..12_000 {
            d.event(Path::new("/p/trial.jsonl"), false, ms(t0, i * 5));
        }
        assert_eq!(d.deadline(), Some(ms(t0, 30)));
        assert!(d.take_due(ms(t0, 30)));
    }

    #[test]
    fn each_file_the_layout_depends_on_must_be_quiet() {
        let t0 = Instant::now();
        let mut d = Debounce::new(QUIET);
        d.event(Path::new("/p/a.mocu"), true, t0);
        d.event(Path::new("/p/lib.mocu"), true, ms(t0, 20));
        assert!(!d.take_due(ms(t0, 35)), "lib.mocu changed 15 ms ago");
        assert_eq!(d.deadline(), Some(ms(t0, 50)));
        assert!(d.take_due(ms(t0, 50)));
    }
}
