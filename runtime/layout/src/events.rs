//! The trial's event record: every operator action, method call and its outcome, alert
//! raised and cleared, layout load and reload, and diagnostic (`mocu run --log`).

use mocu_value::Value;
use parking_lot::Mutex;
use std::io::Write;
use std::time::{SystemTime, UNIX_EPOCH};

/// Where events go. Implementations must be cheap: events are recorded on the layout's
/// executor.
pub trait EventSink: Send + Sync {
    fn record(&self, event: &str, fields: &[(&str, Value)]);
}

/// Discards events.
pub struct NullSink;

impl EventSink for NullSink {
    fn record(&self, _event: &str, _fields: &[(&str, Value)]) {}
}

/// Keeps events in memory (tests, and the on-screen toast list).
#[derive(Default)]
pub struct MemorySink {
    pub events: Mutex<Vec<Event>>,
}

/// A recorded event: its kind and its fields.
pub type Event = (String, Vec<(String, Value)>);

impl EventSink for MemorySink {
    fn record(&self, event: &str, fields: &[(&str, Value)]) {
        let f = fields.iter().map(|(k, v)| (k.to_string(), v.clone())).collect();
        self.events.lock().push((event.to_string(), f));
    }
}

impl MemorySink {
    /// The events of one kind, each as its fields.
    pub fn of(&self, event: &str) -> Vec<Vec<(String, Value)>> {
        self.events.lock().iter().filter(|(e, _)| e == event).map(|(_, f)| f.clone()).collect()
    }
}

/// Appends one JSON object per line: `{"time": <unix seconds>, "event": "...", ...}`.
pub struct JsonlLog {
    out: Mutex<Box<dyn Write + Send>>,
}

impl JsonlLog {
    pub fn new(out: Box<dyn Write + Send>) -> JsonlLog {
        JsonlLog { out: Mutex::new(out) }
    }

    /// Opens (appends to) a log file.
    pub fn append(path: &std::path::Path) -> std::io::Result<JsonlLog> {
        let f = std::fs::OpenOptions::new().create(true).append(true).open(path)?;
        Ok(JsonlLog::new(Box::new(std::io::LineWriter::new(f))))
    }
}

/// One event as a JSON line (no newline).
pub fn json_line(event: &str, fields: &[(&str, Value)]) -> String {
    let time = SystemTime::now().duration_since(UNIX_EPOCH).map_or(0.0, |d| d.as_secs_f64());
    let mut obj = serde_json::Map::new();
    obj.insert("time".into(), serde_json::json!((time * 1000.0).round() / 1000.0));
    obj.insert("event".into(), serde_json::Value::String(event.into()));
    for (k, v) in fields {
        obj.insert((*k).into(), serde_json::to_value(v).unwrap_or(serde_json::Value::Null));
    }
    serde_json::Value::Object(obj).to_string()
}

impl EventSink for JsonlLog {
    fn record(&self, event: &str, fields: &[(&str, Value)]) {
        let line = json_line(event, fields);
        let mut out = self.out.lock();
        let _ = writeln!(out, "{line}");
    }
}

/// Sends every event to several sinks.
pub struct Tee(pub Vec<std::sync::Arc<dyn EventSink>>);

impl EventSink for Tee {
    fn record(&self, event: &str, fields: &[(&str, Value)]) {
        for s in &self.0 {
            s.record(event, fields);
        }
    }
}
