//! The DataServer distributed over Zenoh (docs/distribution.md): chosen subtrees of the
//! world model published on a key space and mirrored by other processes, method calls as
//! Zenoh queries with their full outcome, late joiners served a snapshot, and each site's
//! liveliness watched so that a site that disappears shows its objects stale.
//!
//! - `publish.rs`: the change feed → puts and deletes; snapshots from what was published.
//! - `mirror.rs`: other sites' samples → the local DataServer, through its API.
//! - `calls.rs`: calls served for other sites and forwarded to them.
//! - `writes.rs`: writes to another site's properties, forwarded to it and served there.
//! - `keys.rs`, `payload.rs`: the key space and the JSON payloads other tools read.
//! - `module.rs`: the `distrib` module of `mocu run` / `mocu serve`.
//!
//! Architecture invariant: the DataServer knows nothing of this crate; this crate reaches
//! the world model only through the DataServer's public API and change feed.

#![forbid(unsafe_code)]

pub mod arbiter;
mod calls;
pub mod control;
mod gcs;
pub mod keys;
mod mirror;
mod module;
pub mod payload;
mod publish;
pub mod security;
pub mod streams;
mod writes;

pub use mirror::MirrorStats;
pub use module::register;
pub use publish::PubStats;

use crossbeam_channel::{Sender, unbounded};
use mocu_dataserver::{DataServer, Guid};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};
use zenoh::Wait;
use zenoh::sample::{Locality, SampleKind};

/// Told what happens to the other sites (one line each: joined, gone), for the operator.
pub type Notify = Arc<dyn Fn(&str) + Send + Sync>;

/// How a process takes part.
#[derive(Clone, Debug)]
pub struct Config {
    /// This process's name on the key space (`mocu/<site>/…`); unique among the peers.
    pub site: String,
    /// The operator, sent with every call this process forwards.
    pub operator: String,
    /// Zenoh endpoints to listen on (`tcp/127.0.0.1:7447`).
    pub listen: Vec<String>,
    /// Zenoh endpoints to connect to.
    pub connect: Vec<String>,
    /// Object paths whose subtrees are published (`vehicles`, `root.vehicles`).
    pub share: Vec<String>,
    /// How long a forwarded call waits for its answer.
    pub call_timeout: Duration,
    /// How long a peer may stay silent before it is taken as gone (Zenoh's link lease).
    pub lease: Duration,
    /// Control arbitration of the shared `vehicles` (`arbiter.rs`); `None`: off.
    pub control: Option<arbiter::Settings>,
    /// Mutual TLS and access control (`security.rs`); the default: plain TCP, open.
    pub security: security::Security,
    /// Streams of the shared subtrees put on the key space (`streams.rs`); default: none.
    pub streams: streams::StreamChoice,
}

impl Default for Config {
    fn default() -> Config {
        Config {
            site: format!("ocu-{}", std::process::id()),
            operator: String::new(),
            listen: Vec::new(),
            connect: Vec::new(),
            share: Vec::new(),
            call_timeout: Duration::from_secs(10),
            lease: Duration::from_millis(2000),
            control: None,
            security: security::Security::default(),
            streams: streams::StreamChoice::default(),
        }
    }
}

/// An object path (`root.vehicles.usv1` or `vehicles.usv1`) as names from the root.
pub fn object_path(dotted: &str) -> Vec<String> {
    let mut segs: Vec<String> =
        dotted.split('.').filter(|s| !s.is_empty()).map(String::from).collect();
    if segs.first().map(String::as_str) == Some("root") {
        segs.remove(0);
    }
    segs
}

/// The Zenoh configuration of a site: a peer that listens and connects where it is told
/// and nowhere else (no multicast scouting, no gossip), with a short lease so that a
/// silent peer is found gone within [`Config::lease`] and reconnected within a second.
pub fn zenoh_config(c: &Config) -> Result<zenoh::Config, String> {
    let list = |eps: &[String]| serde_json::to_string(eps).unwrap_or_else(|_| "[]".into());
    let mut z = zenoh::Config::default();
    let lease = c.lease.as_millis().max(100);
    for (k, v) in [
        ("mode", "\"peer\"".to_string()),
        ("listen/endpoints", list(&c.listen)),
        ("connect/endpoints", list(&c.connect)),
        ("scouting/multicast/enabled", "false".into()),
        ("scouting/gossip/enabled", "false".into()),
        ("transport/link/tx/lease", lease.to_string()),
        ("transport/link/tx/keep_alive", "4".into()),
        ("connect/retry", "{period_init_ms: 200, period_max_ms: 1000}".into()),
    ] {
        z.insert_json5(k, &v).map_err(|e| format!("zenoh configuration `{k}`: {e}"))?;
    }
    let endpoints: Vec<String> = c.listen.iter().chain(&c.connect).cloned().collect();
    let secured = security::zenoh_entries(&c.site, &c.security, &endpoints);
    for (k, v) in secured.map_err(|e| e.to_string())? {
        z.insert_json5(k, &v).map_err(|e| format!("zenoh configuration `{k}`: {e}"))?;
    }
    Ok(z)
}

/// A running site: drop or [`Distrib::stop`] to leave.
pub struct Distrib {
    session: zenoh::Session,
    stop: Arc<AtomicBool>,
    feed_waker: mocu_dataserver::FeedWaker,
    inbound: Sender<mirror::Inbound>,
    calls: Sender<calls::CallJob>,
    threads: Vec<JoinHandle<()>>,
    joined: Arc<mirror::Joined>,
    pub publish_stats: Arc<PubStats>,
    pub mirror_stats: Arc<MirrorStats>,
    /// Control arbitration, where this site arbitrates its vehicles.
    pub arbiter: Option<arbiter::Arbiter>,
    _token: zenoh::liveliness::LivelinessToken,
}

impl Distrib {
    /// Opens the Zenoh session and starts publishing, mirroring and serving calls.
    /// `status`: an object to show the peers under (`peers.<site>.alive`).
    pub fn start(
        ds: &DataServer,
        config: &Config,
        status: Option<Guid>,
    ) -> Result<Distrib, String> {
        Distrib::start_notifying(ds, config, status, None)
    }

    /// [`Distrib::start`], telling `notify` when other sites join or go.
    pub fn start_notifying(
        ds: &DataServer,
        config: &Config,
        status: Option<Guid>,
        notify: Option<Notify>,
    ) -> Result<Distrib, String> {
        let session =
            zenoh::open(zenoh_config(config)?).wait().map_err(|e| format!("zenoh: {e}"))?;
        let share: Vec<Vec<String>> = config.share.iter().map(|s| object_path(s)).collect();
        let site = config.site.clone();
        let stop = Arc::new(AtomicBool::new(false));
        let publish_stats = Arc::new(PubStats::default());
        let mirror_stats = Arc::new(MirrorStats::default());
        let joined = Arc::new(mirror::Joined::default());
        let mut threads = Vec::new();
        let spawn = |name: &str, f: Box<dyn FnOnce() + Send>| {
            std::thread::Builder::new()
                .name(format!("distrib-{name}"))
                .spawn(f)
                .map_err(|e| e.to_string())
        };
        let zerr = |e: zenoh::Error| format!("zenoh: {e}");

        // Control arbitration of the vehicles shared here (docs/distribution.md).
        let arbiter = match &config.control {
            Some(settings) if share.iter().any(|s| s.first().is_some_and(|f| f == "vehicles")) => {
                let me = control::Caller::new(&config.operator, &site);
                let a = arbiter::Arbiter::start(ds, settings.clone(), me)?;
                a.watch_sites(&session)?;
                Some(a)
            }
            _ => None,
        };

        // Calls: served here, forwarded from mirrored methods.
        let (calls_tx, calls_rx) = unbounded();
        let c = calls::Calls {
            ds: ds.clone(),
            session: session.clone(),
            me: site.clone(),
            operator: config.operator.clone(),
            share: share.clone(),
            timeout: config.call_timeout,
            tx: calls_tx.clone(),
            arbiter: arbiter.clone(),
        };
        threads.push(spawn("calls", Box::new(move || c.run(calls_rx)))?);
        let tx = calls_tx.clone();
        session
            .declare_queryable(format!("mocu/{}/call/**", keys::chunk(&site)))
            .callback(move |q| {
                let _ = tx.send(calls::CallJob::Serve(q));
            })
            .background()
            .wait()
            .map_err(zerr)?;

        // Publishing, and the snapshots it answers.
        let feed = ds.change_feed();
        let feed_waker = feed.waker();
        let (q_tx, q_rx) = unbounded();
        for what in ["obj", "prop"] {
            let (tx, w) = (q_tx.clone(), feed_waker.clone());
            session
                .declare_queryable(keys::state_of(Some(&site), what))
                .callback(move |q| {
                    let _ = tx.send(q);
                    w.wake();
                })
                .background()
                .wait()
                .map_err(zerr)?;
        }
        let taps = streams::Taps::new(
            ds.clone(),
            session.clone(),
            site.clone(),
            config.streams.clone(),
            status,
            publish_stats.clone(),
        );
        let p = publish::Publisher::new(
            ds.clone(),
            session.clone(),
            site.clone(),
            share,
            publish_stats.clone(),
            taps,
        );
        let st = stop.clone();
        threads.push(spawn("publish", Box::new(move || p.run(feed, q_rx, st)))?);

        // Mirroring other sites: their samples, their liveliness (history: the sites
        // already there count as appearing now).
        let (in_tx, in_rx) = unbounded();
        let mut m = mirror::Mirror::new(
            ds.clone(),
            session.clone(),
            site.clone(),
            in_tx.clone(),
            calls_tx.clone(),
            mirror_stats.clone(),
            joined.clone(),
            status,
        );
        m.notify = notify;
        threads.push(spawn("mirror", Box::new(move || m.run(in_rx)))?);
        for what in ["obj", "prop", "stream"] {
            let tx = in_tx.clone();
            session
                .declare_subscriber(keys::state_of(None, what))
                .allowed_origin(Locality::Remote)
                .callback(move |s| {
                    let _ = tx.send(mirror::Inbound::Sample {
                        key: s.key_expr().as_str().to_string(),
                        put: s.kind() == SampleKind::Put,
                        bytes: s.payload().to_bytes().into_owned(),
                    });
                })
                .background()
                .wait()
                .map_err(zerr)?;
        }
        let tx = in_tx.clone();
        session
            .liveliness()
            .declare_subscriber("mocu/*/alive")
            .history(true)
            .callback(move |s| {
                if let Some(keys::Key::Alive { site }) = keys::parse(s.key_expr().as_str()) {
                    let _ =
                        tx.send(mirror::Inbound::Alive { site, up: s.kind() == SampleKind::Put });
                }
            })
            .background()
            .wait()
            .map_err(zerr)?;
        let token = session.liveliness().declare_token(keys::alive(&site)).wait().map_err(zerr)?;
        Ok(Distrib {
            session,
            stop,
            feed_waker,
            inbound: in_tx,
            calls: calls_tx,
            threads,
            joined,
            publish_stats,
            mirror_stats,
            arbiter,
            _token: token,
        })
    }

    /// Waits until `n` snapshots of other sites have been mirrored, or `timeout` passes;
    /// returns whether they were.
    pub fn wait_snapshots(&self, n: u64, timeout: Duration) -> bool {
        let deadline = Instant::now() + timeout;
        let mut c = self.joined.count.lock();
        while *c < n {
            if self.joined.cv.wait_until(&mut c, deadline).timed_out() {
                return *c >= n;
            }
        }
        true
    }

    /// Snapshots of other sites mirrored so far.
    pub fn snapshots(&self) -> u64 {
        *self.joined.count.lock()
    }

    /// This process's Zenoh session (benchmarks, tools).
    pub fn session(&self) -> &zenoh::Session {
        &self.session
    }

    /// Leaves: the liveliness token goes (peers see this site gone), threads end.
    pub fn stop(mut self) {
        self.shutdown();
    }

    fn shutdown(&mut self) {
        if self.stop.swap(true, Ordering::Relaxed) {
            return;
        }
        let _ = self.session.close().wait();
        if let Some(a) = &self.arbiter {
            a.stop();
        }
        self.feed_waker.wake();
        let _ = self.inbound.send(mirror::Inbound::Stop);
        let _ = self.calls.send(calls::CallJob::Stop);
        for t in self.threads.drain(..) {
            let _ = t.join();
        }
    }
}

impl Drop for Distrib {
    fn drop(&mut self) {
        self.shutdown();
    }
}
