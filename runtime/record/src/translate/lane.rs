//! The change feed's numeric lane (`DataServer::change_feed_numeric`): almost every change of
//! a busy trial, a changed number of a known property, comes as a 32-byte entry naming the
//! property by the server's number for it. Runs of them go into the `/world/values` batch
//! after one look-up each (the server's number → the recording's `id`) and one store into the
//! mirror: no value to clone or drop, no stamp to convert, no hash, and the checks (keyframe
//! due, batch full) once per run.

use super::{SNAPSHOT_CHANGES, SNAPSHOT_NS, Translator};
use crate::values;
use mocu_dataserver::{Change, ChangeFeed, Guid, NumKind, Numeric, PropName, Stamped};
use std::time::{Duration, UNIX_EPOCH};

/// The server's number of a property not resolved yet.
const UNKNOWN: u32 = u32::MAX;
/// A property whose changes are translated one by one (`lat`, `lon`, `alt`: they also make
/// a location fix).
const SLOW: u32 = u32::MAX - 1;

impl Translator {
    /// Both lanes as taken at once from the feed, in the order of their numbers.
    pub fn take(
        &mut self,
        changes: &[Stamped],
        numeric: &[Numeric],
        feed: &ChangeFeed,
    ) -> Result<(), String> {
        let mut rest = numeric;
        for c in changes {
            let before = rest.partition_point(|n| n.seq < c.seq);
            self.numeric(&rest[..before], feed)?;
            rest = &rest[before..];
            self.change(c)?;
        }
        self.numeric(rest, feed)?;
        for (listener, muted) in self.mute.drain(..) {
            feed.mute(listener, muted);
        }
        self.due_fixes(self.last_time)
    }

    fn numeric(&mut self, entries: &[Numeric], feed: &ChangeFeed) -> Result<(), String> {
        let mut rest = entries;
        while let Some(first) = rest.first() {
            let n = self.run(rest);
            if n > 0 {
                rest = &rest[n..];
                continue;
            }
            // A keyframe or a batch is due first, or the property is met for the first time
            // (or is translated one by one).
            let id = self.lane.get(first.id as usize).copied().unwrap_or(UNKNOWN);
            self.numeric_slow(first, if id == SLOW { UNKNOWN } else { id }, feed)?;
            rest = &rest[1..];
        }
        Ok(())
    }

    /// The rule: the longest run at the start of `entries` that goes into the open batch as
    /// it is (known properties, no keyframe or new batch due on the way), in three tight
    /// passes. Returns its length (0: the first entry needs [`Translator::numeric_slow`]).
    fn run(&mut self, entries: &[Numeric]) -> usize {
        if self.since_snapshot == 0 {
            return 0; // right after a keyframe: the next entry decides when the next one is
        }
        let room = (SNAPSHOT_CHANGES.saturating_sub(self.since_snapshot) as usize)
            .min(values::MAX_ENTRIES - self.batch.len());
        let entries = &entries[..entries.len().min(room)];
        let lane = &self.lane;
        let known = |n: &Numeric| match lane.get(n.id as usize) {
            Some(&id) if id < SLOW => n.kind != NumKind::Int || values::exact(n.bits as i64),
            _ => false,
        };
        let run = &entries[..entries.iter().position(|n| !known(n)).unwrap_or(entries.len())];
        // Stamps never go back along the numbers: the entries in time go first.
        let (first_seq, first_ns) = match self.batch.is_empty() {
            true => run.first().map_or((0, 0), |n| (n.seq, n.ns)),
            false => self.batch.first(),
        };
        let snapshot_time = self.snapshot_time;
        let in_time = |n: &Numeric| {
            n.ns.saturating_sub(snapshot_time) < SNAPSHOT_NS
                && n.seq.wrapping_sub(first_seq) <= u64::from(u32::MAX)
                && n.ns.wrapping_sub(first_ns) <= u64::from(u32::MAX)
        };
        let run = &run[..run.partition_point(in_time)];
        let Some(last) = run.last() else { return 0 };
        for n in run {
            self.world.set_number(self.lane[n.id as usize], n.kind, n.bits);
        }
        self.batch.extend(run, &self.lane);
        self.last_seq = last.seq;
        self.last_time = self.last_time.max(last.ns);
        self.since_snapshot += run.len() as u64;
        run.len()
    }

    /// An entry as the change it stands for (a keyframe or a new batch first when due);
    /// a property met for the first time is then known by the server's number.
    fn numeric_slow(&mut self, n: &Numeric, id: u32, feed: &ChangeFeed) -> Result<(), String> {
        let Some((object, name)) = self.named(n.id, feed) else { return Ok(()) };
        let change =
            Change::PropertySet { object, name, value: n.value(), meta: None, created: false };
        let wall = UNIX_EPOCH + Duration::from_nanos(n.ns);
        self.change(&Stamped { seq: n.seq, wall, change })?;
        if id != UNKNOWN {
            return Ok(());
        }
        let id = match self.place_names.contains(&name) {
            true => SLOW,
            false => self.world.id(object, name).unwrap_or(UNKNOWN),
        };
        let i = n.id as usize;
        if self.lane.len() <= i {
            self.lane.resize(i + 1, UNKNOWN);
        }
        self.lane[i] = id;
        Ok(())
    }

    /// The object and name of the property the feed numbered `number`: asked of the feed
    /// (under its lock, which the writers take) only the first time; numbers are never
    /// reused.
    fn named(&mut self, number: u32, feed: &ChangeFeed) -> Option<(Guid, PropName)> {
        let i = number as usize;
        if let Some(Some(known)) = self.numbered.get(i) {
            return Some(*known);
        }
        let named = feed.numbered(number)?;
        if self.numbered.len() <= i {
            self.numbered.resize(i + 1, None);
        }
        self.numbered[i] = Some(named);
        Some(named)
    }
}
