//! The operator's clock: `root.operator.clock` (type `clock`) with `utc`, the UTC time of
//! day as `14:03:07`, and `time`, whole seconds since the Unix epoch, read from the
//! DataServer's clock (`DataServer::wall_time`: a test's manual clock fixes it).
//!
//! It runs only while the running program reads `root.operator.clock` (a layout that
//! shows no clock costs nothing): one delayed call on the server's clock at each whole
//! second, re-armed from inside (no thread, no polling). It stops at the first second
//! after the layout is unloaded or reloaded without a clock.

use crate::graph::Shared;
use mocu_dataserver::DataServer;
use mocu_language::program::{Path, PathBase, Program, Widget};
use mocu_value::Value;
use parking_lot::Mutex;
use std::sync::{Arc, Weak};
use std::time::{Duration, UNIX_EPOCH};

/// The clock's object under `root.operator`.
pub(crate) const OBJECT: &str = "clock";

/// A running clock: the layout it runs for, and whether that layout still reads it.
struct Ticker {
    owner: Weak<Shared>,
    wanted: bool,
}

/// Every running clock (one per layout that reads it).
static TICKERS: Mutex<Vec<Ticker>> = Mutex::new(Vec::new());

/// After a program was loaded: runs the clock while it reads `root.operator.clock`.
pub(crate) fn follow(sh: &Arc<Shared>, program: &Program) {
    let wanted = reads_clock(program);
    let mut tickers = TICKERS.lock();
    let me = Arc::downgrade(sh);
    if let Some(t) = tickers.iter_mut().find(|t| t.owner.ptr_eq(&me)) {
        t.wanted = wanted;
        return;
    }
    if !wanted {
        return;
    }
    tickers.push(Ticker { owner: me.clone(), wanted });
    drop(tickers);
    tick(me);
}

/// Writes the time, then waits on the server's clock for the next whole second.
fn tick(me: Weak<Shared>) {
    let ds = {
        let mut tickers = TICKERS.lock();
        let live = me.upgrade();
        let wanted = tickers.iter().any(|t| t.owner.ptr_eq(&me) && t.wanted);
        let (Some(sh), true) = (live, wanted) else {
            tickers.retain(|t| !t.owner.ptr_eq(&me));
            return;
        };
        sh.ds.clone()
    };
    let next = write(&ds);
    ds.run_after(next, None, move || tick(me));
}

/// Writes `utc` and `time`; returns how long until the next whole second.
fn write(ds: &DataServer) -> Duration {
    let since = ds.wall_time().duration_since(UNIX_EPOCH).unwrap_or_default();
    let secs = since.as_secs();
    if let Some(g) = operator_clock(ds) {
        let _ = ds.set(g, "time", Value::Float(secs as f64));
        let _ = ds.set(g, "utc", Value::str(&time_of_day(secs)));
    }
    Duration::from_secs(1) - Duration::from_nanos(since.subsec_nanos() as u64)
}

fn operator_clock(ds: &DataServer) -> Option<mocu_value::Guid> {
    let op =
        crate::graph::ensure_object(ds, mocu_value::Guid::ROOT, "operator", "operator").ok()?;
    crate::graph::ensure_object(ds, op, OBJECT, "clock").ok()
}

/// `hh:mm:ss` of a time in seconds since the Unix epoch, in UTC.
pub(crate) fn time_of_day(secs: u64) -> String {
    let s = secs % 86_400;
    format!("{:02}:{:02}:{:02}", s / 3600, s / 60 % 60, s % 60)
}

/// Whether any widget of the program (or of its templates) reads `root.operator.clock`.
fn reads_clock(program: &Program) -> bool {
    let is_clock = |p: &Path| {
        p.base == PathBase::Root
            && p.segments.first().is_some_and(|s| s == "operator")
            && p.segments.get(1).is_some_and(|s| s == OBJECT)
    };
    let widget = |w: &Widget| {
        let bound = w.args.iter().map(|a| &a.value).chain(&w.at).chain(&w.visible);
        bound.flat_map(|b| &b.paths).any(is_clock)
    };
    program.widgets.iter().chain(program.templates.iter().flat_map(|t| &t.widgets)).any(widget)
}

#[cfg(test)]
mod tests {
    #[test]
    fn the_time_of_day_is_utc_hours_minutes_and_seconds() {
        assert_eq!(super::time_of_day(0), "00:00:00");
        assert_eq!(super::time_of_day(86_400 * 19_000 + 14 * 3600 + 3 * 60 + 7), "14:03:07");
        assert_eq!(super::time_of_day(86_399), "23:59:59");
    }
}
