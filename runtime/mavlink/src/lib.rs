//! The MAVLink 2 protocol module (paper §2, §4.3): vehicles heard over UDP are discovered by
//! HEARTBEAT and published as `root.vehicles.mav<sysid>`; their telemetry becomes properties
//! with units; methods (`arm`, `set_mode`, `goto`, `return_home`, `land`, `upload_route`)
//! become COMMAND_LONG/COMMAND_INT or the mission protocol, and the vehicle's COMMAND_ACK /
//! MISSION_ACK becomes the call's outcome (Accepted, Refused with the result's name, Failed,
//! or TimedOut after retries). An uploaded route edited in the world model is sent as
//! deltas: partial mission writes of the changed waypoints (`mission.rs`). Three seconds
//! without a heartbeat mark the link lost and the data stale until heartbeats return.
//! Malformed and unknown packets are counted, never fatal; enum values newer than the
//! dialect are kept as `unknown(N)`; implausible values refuse their message with a counter
//! per reason. A link holds at most `max_vehicles`, forgets the silent ones, answers only
//! addresses that proved to be a vehicle's, and with a `signing_key` accepts only frames
//! signed with it and signs what it sends (docs/mavlink.md).
//!
//! One blocking reader thread per socket (I/O at the module's edge); everything else runs
//! on the module's serial executor. No async runtime.

#![forbid(unsafe_code)]

mod commands;
mod config;
mod decode;
mod lenient;
mod link;
mod methods;
mod mission;
mod modes;
mod signing;
mod telemetry;
mod vehicle;

pub use config::{Counters, LinkConfig, Reason};
pub use decode::{DecodeCounts, decode_checked, decode_datagram, encode_v2, encode_v2_signed};
pub use lenient::{CommandAck, GpsRaw, Heartbeat, Lenient, Msg};
pub use link::Link;
pub use signing::{Key, Signing};

use mocu_host::{Module, ModuleContext, ModuleSpec, Registry};
use std::net::UdpSocket;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Duration;

/// The default address, as QGroundControl listens.
pub const DEFAULT_ADDRESS: &str = "0.0.0.0:14550";

/// The MAVLink module: binds `address`, reads datagrams on its own thread, runs a watchdog
/// every 250 ms on its executor.
pub struct MavlinkModule {
    address: String,
    cfg: LinkConfig,
    running: Arc<AtomicBool>,
    reader: Option<std::thread::JoinHandle<()>>,
    link: Option<Link>,
}

impl MavlinkModule {
    pub fn new(address: &str, cfg: LinkConfig) -> MavlinkModule {
        MavlinkModule {
            address: address.to_string(),
            cfg,
            running: Arc::new(AtomicBool::new(false)),
            reader: None,
            link: None,
        }
    }

    /// Settings: `address` (default 0.0.0.0:14550) and those of [`LinkConfig::from_spec`]
    /// (docs/mavlink.md).
    pub fn from_spec(spec: &ModuleSpec) -> Result<MavlinkModule, String> {
        let cfg = LinkConfig::from_spec(spec)?;
        let address = spec.socket_addr_or("address", DEFAULT_ADDRESS).map_err(|e| e.to_string())?;
        Ok(MavlinkModule::new(&address.to_string(), cfg))
    }

    pub fn link(&self) -> Option<&Link> {
        self.link.as_ref()
    }
}

impl Module for MavlinkModule {
    fn start(&mut self, ctx: &ModuleContext) -> Result<(), String> {
        let socket = UdpSocket::bind(&self.address)
            .map_err(|e| format!("cannot listen for MAVLink on {}: {e}", self.address))?;
        socket.set_read_timeout(Some(Duration::from_millis(200))).map_err(|e| e.to_string())?;
        let local = socket.local_addr().map_err(|e| e.to_string())?;
        let socket = Arc::new(socket);
        let link = Link::new(ctx.clone(), self.cfg.clone(), Some(socket.clone()))
            .map_err(|e| e.to_string())?;
        let _ = ctx.ds.set(ctx.status, "address", mocu_dataserver::Value::str(&local.to_string()));
        self.running.store(true, Ordering::SeqCst);
        let (running, l) = (self.running.clone(), link.clone());
        self.reader = Some(
            ctx.spawn_thread("udp", move || {
                // The largest UDP payload: a datagram is never cut short.
                let mut buf = vec![0u8; 65_536];
                while running.load(Ordering::SeqCst) {
                    match socket.recv_from(&mut buf) {
                        Ok((n, from)) => l.ingest(&buf[..n], Some(from)),
                        Err(e)
                            if matches!(
                                e.kind(),
                                std::io::ErrorKind::WouldBlock | std::io::ErrorKind::TimedOut
                            ) => {}
                        // ICMP port-unreachable from a peer that went away, and the like.
                        Err(_) => std::thread::sleep(Duration::from_millis(10)),
                    }
                }
            })
            .map_err(|e| e.to_string())?,
        );
        watchdog(ctx.clone(), link.clone(), self.running.clone(), 0);
        self.link = Some(link);
        Ok(())
    }

    fn stop(&mut self) {
        self.running.store(false, Ordering::SeqCst);
        if let Some(r) = self.reader.take() {
            let _ = r.join();
        }
    }
}

fn watchdog(ctx: ModuleContext, link: Link, running: Arc<AtomicBool>, n: u64) {
    let ex = ctx.executor.clone();
    let ds = ctx.ds.clone();
    ds.run_after(Duration::from_millis(250), Some(&ex), move || {
        if !running.load(Ordering::SeqCst) {
            return;
        }
        if ctx.guard(|| link.watchdog(n.is_multiple_of(4))) {
            watchdog(ctx, link, running, n + 1);
        }
    });
}

/// Registers the kind `mavlink`.
pub fn register(registry: &mut Registry) {
    registry.register("mavlink", |spec| {
        Ok(Box::new(MavlinkModule::from_spec(spec)?) as Box<dyn Module>)
    });
}
