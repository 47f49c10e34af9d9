//! When to check: a burst of edits is checked once, after its last edit.
//!
//! An editor sends a `didChange` per keystroke, and a paste, a rename or a format as several at
//! once. Each edit of a document replaces the check it was waiting for and restarts its
//! document's quiet time ([`Timing::quiet`]); the check runs when the document has been quiet
//! that long, or when its oldest waiting edit has waited [`Timing::longest`] (a stream of edits
//! still gets diagnostics). Documents wait apart: an edit of one delays no other.
//!
//! The queue is told the time (`now`) and never reads a clock, so its tests move time by hand.

use std::time::{Duration, Instant};

/// How long edits wait to be checked.
#[derive(Clone, Copy, Debug)]
pub struct Timing {
    /// A document is checked once no edit of it came for this long.
    pub quiet: Duration,
    /// ... or once its oldest unchecked edit is this old.
    pub longest: Duration,
}

impl Default for Timing {
    /// Machine-made bursts (a paste, a rename, a format: edits a few microseconds apart) are
    /// caught whole; a typist's keystrokes, 50 ms or more apart, are each checked, and wait
    /// only the quiet time for it.
    fn default() -> Timing {
        Timing { quiet: Duration::from_millis(3), longest: Duration::from_millis(100) }
    }
}

/// The checks waiting, one per document (`J`: what a check needs).
#[derive(Debug)]
pub struct Queue<J> {
    timing: Timing,
    waiting: Vec<Waiting<J>>,
}

#[derive(Debug)]
struct Waiting<J> {
    path: String,
    job: J,
    /// When its oldest unchecked edit came.
    first: Instant,
    /// When its newest edit came.
    last: Instant,
}

impl<J> Waiting<J> {
    fn due(&self, t: &Timing) -> Instant {
        (self.last + t.quiet).min(self.first + t.longest)
    }
}

impl<J> Queue<J> {
    pub fn new(timing: Timing) -> Queue<J> {
        Queue { timing, waiting: Vec::new() }
    }

    /// An edit of `path` at `now`: `job` replaces the check waiting for it.
    pub fn push(&mut self, path: &str, job: J, now: Instant) {
        match self.waiting.iter_mut().find(|w| w.path == path) {
            Some(w) => {
                w.job = job;
                w.last = now;
            }
            None => self.waiting.push(Waiting { path: path.into(), job, first: now, last: now }),
        }
    }

    /// When the next check is due; `None` when none waits.
    pub fn due_at(&self) -> Option<Instant> {
        self.waiting.iter().map(|w| w.due(&self.timing)).min()
    }

    /// The check due first, when it is due at `now`.
    pub fn take_due(&mut self, now: Instant) -> Option<J> {
        let (i, _) = self
            .waiting
            .iter()
            .enumerate()
            .map(|(i, w)| (i, w.due(&self.timing)))
            .filter(|&(_, due)| due <= now)
            .min_by_key(|&(_, due)| due)?;
        Some(self.waiting.remove(i).job)
    }

    /// Any waiting check, due or not (the editor has gone: what is left is done at once).
    pub fn take_any(&mut self) -> Option<J> {
        (!self.waiting.is_empty()).then(|| self.waiting.remove(0).job)
    }

    /// Whether a check of `path` waits.
    pub fn has(&self, path: &str) -> bool {
        self.waiting.iter().any(|w| w.path == path)
    }

    /// Forgets the check waiting for `path` (its document was closed).
    pub fn remove(&mut self, path: &str) {
        self.waiting.retain(|w| w.path != path);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ms(n: u64) -> Duration {
        Duration::from_millis(n)
    }

    fn queue() -> (Queue<u32>, Instant) {
        (Queue::new(Timing { quiet: ms(10), longest: ms(100) }), Instant::now())
    }

    #[test]
    fn a_burst_of_edits_is_checked_once_at_its_last_edit_after_the_quiet_time() {
        let (mut q, t0) = queue();
        for (k, at) in [0, 2, 4, 6].into_iter().enumerate() {
            q.push("/a.mocu", k as u32, t0 + ms(at));
        }
        assert_eq!(q.due_at(), Some(t0 + ms(16)));
        assert_eq!(q.take_due(t0 + ms(15)), None);
        assert_eq!(q.take_due(t0 + ms(16)), Some(3));
        assert_eq!(q.take_due(t0 + ms(1000)), None, "checked once");
    }

    #[test]
    fn a_stream_of_edits_is_checked_when_its_oldest_edit_has_waited_the_longest() {
        let (mut q, t0) = queue();
        let mut checked = Vec::new();
        for at in (0..250).step_by(5) {
            let now = t0 + ms(at);
            checked.extend(q.take_due(now).map(|_| at));
            q.push("/a.mocu", at as u32, now);
        }
        assert_eq!(checked, vec![100, 200]);
    }

    #[test]
    fn documents_wait_apart_and_the_first_due_is_checked_first() {
        let (mut q, t0) = queue();
        q.push("/a.mocu", 1, t0);
        q.push("/b.mocu", 2, t0 + ms(3));
        q.push("/a.mocu", 3, t0 + ms(8));
        assert_eq!(q.take_due(t0 + ms(20)), Some(2));
        assert_eq!(q.take_due(t0 + ms(20)), Some(3));
        assert!(!q.has("/a.mocu") && q.due_at().is_none());
    }

    #[test]
    fn a_closed_documents_check_is_forgotten_and_the_rest_is_taken_at_once_when_asked() {
        let (mut q, t0) = queue();
        q.push("/a.mocu", 1, t0);
        q.push("/b.mocu", 2, t0);
        q.remove("/a.mocu");
        assert_eq!(q.take_any(), Some(2));
        assert_eq!(q.take_any(), None);
    }
}
