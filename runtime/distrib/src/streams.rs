//! Shared streams (docs/distribution.md, "Streams"): the messages of chosen listeners in
//! the shared subtrees (a camera's frames) put on `mocu/<site>/stream/<path>`, at most
//! `stream_rate_hz` a second each, and sent again on the mirror's listener at the same path.
//!
//! A chosen listener gets a tap: a receiver of this site's (under the status object, or the
//! root) whose method takes any message and puts it on the key space. Being a receiver is
//! what makes a source produce: the simulator renders a camera only while someone listens,
//! so an adapter without a display renders exactly the cameras it shares. The tap's queue
//! drops the oldest frame when the network is slower than the camera, never blocks it.

use crate::keys;
use crate::payload;
use crate::publish::PubStats;
use mocu_dataserver::{
    Call, CallOutcome, DataServer, Guid, MethodSpec, ObjectInfo, Overflow, ParamSpec,
};
use parking_lot::Mutex;
use std::collections::HashMap;
use std::sync::Arc;
use std::sync::atomic::Ordering;
use std::time::{Duration, Instant};
use zenoh::Wait;

/// The object type of a tap (the publisher never shares one).
pub const TAP_TYPE: &str = "stream_tap";

/// A tap's receiver queue: a frame or two in flight, the oldest dropped.
const QUEUE: usize = 2;

/// Which listeners are shared, and how often.
#[derive(Clone, Debug, PartialEq)]
pub struct StreamChoice {
    /// Listener paths from the root; `*` stands for any one name (`vehicles.*.cameras.drive`).
    pub patterns: Vec<Vec<String>>,
    /// The most messages a second put on the key space per listener.
    pub rate_hz: f64,
}

impl Default for StreamChoice {
    fn default() -> StreamChoice {
        StreamChoice { patterns: Vec::new(), rate_hz: 5.0 }
    }
}

impl StreamChoice {
    pub fn new(patterns: &[String], rate_hz: f64) -> StreamChoice {
        StreamChoice { patterns: patterns.iter().map(|p| crate::object_path(p)).collect(), rate_hz }
    }

    /// Whether the listener at `path` is shared.
    pub fn matches(&self, path: &[String]) -> bool {
        self.patterns.iter().any(|p| {
            p.len() == path.len()
                && p.iter().zip(path).all(|(want, got)| want == "*" || want == got)
        })
    }
}

/// When the next message may go: at most one per `gap`, on the DataServer's clock.
struct Pace {
    gap: Duration,
    next: Option<Instant>,
}

impl Pace {
    /// Whether a message at `now` goes (a millisecond early counts as on time: a 30 Hz
    /// camera shared at 5 Hz sends every sixth frame, not every seventh).
    fn admit(&mut self, now: Instant) -> bool {
        let slack = Duration::from_millis(1);
        match self.next {
            Some(next) if now + slack < next => false,
            Some(next) => {
                let after = next + self.gap;
                self.next = Some(if now > after { now + self.gap } else { after });
                true
            }
            None => {
                self.next = Some(now + self.gap);
                true
            }
        }
    }
}

pub(crate) struct Taps {
    ds: DataServer,
    session: zenoh::Session,
    site: String,
    choice: StreamChoice,
    home: Option<Guid>,
    stats: Arc<PubStats>,
    /// Listener → its tap object.
    taps: HashMap<Guid, Guid>,
}

impl Taps {
    pub fn new(
        ds: DataServer,
        session: zenoh::Session,
        site: String,
        choice: StreamChoice,
        home: Option<Guid>,
        stats: Arc<PubStats>,
    ) -> Taps {
        Taps { ds, session, site, choice, home, stats, taps: HashMap::new() }
    }

    pub fn wanted(&self, path: &[String]) -> bool {
        self.choice.rate_hz > 0.0 && self.choice.matches(path)
    }

    /// Taps the listener `listener` at `path` (once).
    pub fn tap(&mut self, listener: Guid, path: &[String]) {
        if self.taps.contains_key(&listener) {
            return;
        }
        match self.open(listener, path) {
            Ok(tap) => {
                self.taps.insert(listener, tap);
            }
            Err(e) => eprintln!("distrib: cannot share the stream {}: {e}", path.join(".")),
        }
    }

    fn open(&self, listener: Guid, path: &[String]) -> Result<Guid, String> {
        let home = self.home.unwrap_or_else(|| self.ds.root());
        let name = format!("stream_tap {}", path.join("."));
        let tap = self.ds.create_object(home, ObjectInfo::new(&name, TAP_TYPE));
        let tap = tap.map_err(|e| e.to_string())?;
        let key = keys::stream(&self.site, path);
        let (ds, session, stats) = (self.ds.clone(), self.session.clone(), self.stats.clone());
        let gap = Duration::from_secs_f64(1.0 / self.choice.rate_hz);
        let pace = Mutex::new(Pace { gap, next: None });
        let spec = MethodSpec::new("message")
            .param(ParamSpec::any("message"))
            .any_args()
            .describe("Puts a stream message on the key space (paced)");
        let published = self.ds.publish_method(tap, spec, move |call: Call| {
            if pace.lock().admit(ds.now()) {
                if session.put(key.as_str(), payload::stream(&call.args)).wait().is_ok() {
                    stats.stream_puts.fetch_add(1, Ordering::Relaxed);
                }
            } else {
                stats.stream_paced.fetch_add(1, Ordering::Relaxed);
            }
            call.responder.reply(CallOutcome::Accepted(vec![]));
        });
        let joined = published
            .and_then(|_| self.ds.join(listener, tap, "message", Overflow::DropOldest, QUEUE));
        if let Err(e) = joined {
            let _ = self.ds.delete_object(tap);
            return Err(e.to_string());
        }
        Ok(tap)
    }

    /// Closes the tap of a listener that left the shared subtrees.
    pub fn untap(&mut self, listener: Guid) {
        if let Some(tap) = self.taps.remove(&listener) {
            let _ = self.ds.delete_object(tap);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn p(s: &str) -> Vec<String> {
        crate::object_path(s)
    }

    #[test]
    fn a_pattern_chooses_listeners_by_path_with_a_star_for_any_one_name() {
        let c = StreamChoice::new(
            &["vehicles.*.cameras.drive".into(), "root.cameras.mast".into()],
            5.0,
        );
        assert!(c.matches(&p("vehicles.usv1.cameras.drive")));
        assert!(c.matches(&p("cameras.mast")));
        assert!(!c.matches(&p("vehicles.usv1.cameras.payload")));
        assert!(!c.matches(&p("vehicles.usv1.cameras.drive.encoded")));
        assert!(!c.matches(&p("vehicles.cameras.drive")));
    }

    #[test]
    fn a_thirty_hertz_camera_paced_at_five_sends_every_sixth_frame() {
        let t0 = Instant::now();
        let mut pace = Pace { gap: Duration::from_secs_f64(0.2), next: None };
        let sent: Vec<u32> = (0..60)
            .filter(|i| pace.admit(t0 + Duration::from_secs_f64(*i as f64 / 30.0)))
            .collect();
        assert_eq!(sent, (0..60).step_by(6).collect::<Vec<_>>());
        // A source that stalls and comes back is not sent a burst to catch up.
        let later = t0 + Duration::from_secs(10);
        assert!(pace.admit(later));
        assert!(!pace.admit(later + Duration::from_millis(100)));
        assert!(pace.admit(later + Duration::from_millis(200)));
    }
}
