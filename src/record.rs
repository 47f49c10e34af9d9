//! `--record TRIAL.mcap` and `--log FILE.jsonl`: the trial's record. The recorder
//! (`mocu-record`) takes the DataServer's change feed itself; this hands it the events that
//! do not pass through the DataServer (the layout's and the modules' `--log` events), and
//! stamps every `--log` line on the DataServer's clock, when the event happened.

use mocu_dataserver::{DataServer, Value};
use mocu_layout::EventSink;
use mocu_record::{Header, Recorder};
use std::path::Path;
use std::sync::Arc;
use std::time::{Duration, SystemTime, UNIX_EPOCH};

/// Starts recording `ds` to `path` (before any module starts).
pub fn start(
    ds: &DataServer,
    path: &Path,
    target: &crate::run::Target,
    layout: &str,
    manual_clock: bool,
) -> Result<Arc<Recorder>, String> {
    let name = target.bundle.layouts.first().map(|l| l.path.clone()).unwrap_or_default();
    start_with(ds, path, &name, Some(&target.bundle), layout, manual_clock)
}

/// Ends the recording (`--record FILE`) and says on stderr what it holds, or why it
/// failed (`command`: `mocu run`, `mocu serve`).
pub fn finish(recorder: &Recorder, file: &Path, command: &str) {
    match recorder.finish() {
        Ok(t) => {
            let mb = |b: u64| b as f64 / 1e6;
            let on_disk = std::fs::metadata(file).map_or(0, |m| m.len());
            eprintln!(
                "mocu: recorded {} messages to {} ({:.1} MB, {:.1} MB before compression)",
                t.messages,
                file.display(),
                mb(on_disk),
                mb(t.bytes)
            );
        }
        Err(e) => eprintln!("{command}: --record: {e}"),
    }
}

/// [`start`] for what may have no layout: `mocu serve`'s adapter records its world model
/// with the profile's bundle when it has one (a replay shows it through its first layout,
/// or through `--layout`), with none otherwise.
pub fn start_with(
    ds: &DataServer,
    path: &Path,
    target: &str,
    bundle: Option<&mocu_language::Bundle>,
    layout: &str,
    manual_clock: bool,
) -> Result<Arc<Recorder>, String> {
    let header = Header {
        command: std::env::args().collect::<Vec<_>>().join(" "),
        target: target.to_string(),
        layout: layout.to_string(),
        clock: if manual_clock { "manual" } else { "system" }.into(),
        bundle: bundle.map(mocu_language::bundle::write),
    };
    Recorder::start(ds, path, header).map(Arc::new)
}

/// Where the trial's events go: the `--log` lines and the recording, each event once,
/// stamped on the DataServer's clock (a module's event carries the time it happened as its
/// `time` field; anything else is stamped when recorded, which is when it happened).
pub struct TrialSink {
    pub ds: DataServer,
    pub log: Option<Arc<dyn EventSink>>,
    pub recorder: Option<Arc<Recorder>>,
}

impl EventSink for TrialSink {
    fn record(&self, event: &str, fields: &[(&str, Value)]) {
        let stamped = fields.iter().find(|(k, _)| *k == "time").and_then(|(_, v)| v.as_f64());
        let time = stamped.unwrap_or_else(|| self.ds.wall_secs());
        if let Some(log) = &self.log {
            if stamped.is_some() {
                log.record(event, fields);
            } else {
                let mut f = Vec::with_capacity(fields.len() + 1);
                f.push(("time", Value::Float((time * 1000.0).round() / 1000.0)));
                f.extend(fields.iter().cloned());
                log.record(event, &f);
            }
        }
        if let Some(r) = &self.recorder {
            let source = match fields.iter().find(|(k, _)| *k == "module") {
                Some((_, Value::Str(m))) => m.to_string(),
                _ => "layout".to_string(),
            };
            let rest: Vec<(&str, Value)> =
                fields.iter().filter(|(k, _)| *k != "time" && *k != "module").cloned().collect();
            r.event_at(at(time), &source, event, &rest);
        }
    }
}

/// A module's trial event (`HostEvent::Record`) into `sink`, named by its module.
pub fn module_event(sink: &dyn EventSink, module: &str, event: &str, fields: &[(String, Value)]) {
    let mut f: Vec<(&str, Value)> = vec![("module", Value::str(module))];
    f.extend(fields.iter().map(|(k, v)| (k.as_str(), v.clone())));
    sink.record(event, &f);
}

fn at(secs: f64) -> SystemTime {
    UNIX_EPOCH + Duration::try_from_secs_f64(secs).unwrap_or_default()
}
