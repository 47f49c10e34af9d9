//! The MAVLink link: datagrams in (decoded, checked, dispatched to the vehicle they come
//! from), datagrams out (signed when the link has a key, rate-limited, only to addresses that
//! proved to be a vehicle's), and the watchdog (link loss, forgetting silent vehicles, our
//! heartbeat, the counters). Telemetry: `telemetry.rs`; methods and commands: `methods.rs`,
//! `commands.rs`; the vehicles themselves: `vehicle.rs`.

use crate::config::{Counters, LinkConfig, Reason};
use crate::decode::{DecodeCounts, decode_checked, encode_v2, encode_v2_signed};
use crate::lenient::Msg;
use crate::signing::Signing;
use crate::vehicle::{self, Vehicle};
use mavlink::MavHeader;
use mavlink::dialects::development::*;
use mocu_dataserver::{CallOutcome, DsError, Guid, Responder, Value};
use mocu_host::ModuleContext;
use mocu_host::world;
use parking_lot::Mutex;
use std::collections::HashMap;
use std::net::{SocketAddr, UdpSocket};
use std::sync::Arc;
use std::sync::atomic::{AtomicU8, Ordering};
use std::time::{Duration, Instant};

pub(crate) struct State {
    pub vehicles: HashMap<u32, Vehicle>,
    pub by_guid: HashMap<Guid, u32>,
    pub next_id: u64,
}

/// One MAVLink link (a UDP socket, or none for tests and benchmarks) publishing the
/// vehicles it hears under `root.vehicles`. Cheap to clone.
#[derive(Clone)]
pub struct Link {
    pub(crate) inner: Arc<Inner>,
}

pub(crate) struct Inner {
    pub ctx: ModuleContext,
    pub cfg: LinkConfig,
    pub root: Guid,
    socket: Option<Arc<UdpSocket>>,
    pub state: Mutex<State>,
    /// Taken after `state` when both are held (ingest), alone when sending.
    signing: Mutex<Option<Signing>>,
    /// The send rate window: its start and the datagrams sent in it.
    window: Mutex<(Instant, u32)>,
    counters: Counters,
    seq: AtomicU8,
}

/// What handling a datagram leaves to do once the link's locks are released.
#[derive(Default)]
pub(crate) struct After {
    pub replies: Vec<(Responder, CallOutcome)>,
    pub sends: Vec<(Option<SocketAddr>, MavMessage)>,
    /// Retries to arm: (system id, upload id).
    pub timers: Vec<(u32, u64)>,
}

impl Link {
    pub fn new(
        ctx: ModuleContext,
        cfg: LinkConfig,
        socket: Option<Arc<UdpSocket>>,
    ) -> Result<Link, DsError> {
        let root = world::vehicles(&ctx.ds)?;
        let state = State { vehicles: HashMap::new(), by_guid: HashMap::new(), next_id: 1 };
        let signing = cfg.signing_key.clone().map(|k| Signing::new(k, cfg.signing_link_id));
        let now = ctx.ds.now();
        Ok(Link {
            inner: Arc::new(Inner {
                ctx,
                cfg,
                root,
                socket,
                state: Mutex::new(state),
                signing: Mutex::new(signing),
                window: Mutex::new((now, 0)),
                counters: Counters::default(),
                seq: AtomicU8::new(0),
            }),
        })
    }

    pub fn counters(&self) -> &Counters {
        &self.inner.counters
    }

    /// How many vehicles the link holds now.
    pub fn vehicles(&self) -> usize {
        self.inner.state.lock().vehicles.len()
    }

    /// Decodes one datagram and publishes what it says. `from` is where it came from (replies
    /// go there once it has proved to be the vehicle's address).
    pub fn ingest(&self, datagram: &[u8], from: Option<SocketAddr>) {
        let c = &self.inner.counters;
        c.datagrams.fetch_add(1, Ordering::Relaxed);
        let mut after = After::default();
        let counts = {
            let mut st = self.inner.state.lock();
            let mut signing = self.inner.signing.lock();
            decode_checked(datagram, signing.as_mut(), |h, m| {
                self.handle(&mut st, h, m, from, &mut after)
            })
        };
        self.count(&counts);
        for (r, o) in after.replies {
            r.reply(o);
        }
        for (addr, msg) in after.sends {
            self.send_to(addr, &msg);
        }
        for (sys, id) in after.timers {
            self.arm_retry(sys, id);
        }
    }

    fn count(&self, counts: &DecodeCounts) {
        let c = &self.inner.counters;
        c.decoded.fetch_add(counts.decoded, Ordering::Relaxed);
        c.malformed.fetch_add(counts.malformed, Ordering::Relaxed);
        c.unknown.fetch_add(counts.unknown, Ordering::Relaxed);
        c.refuse(Reason::Incompatible, counts.incompatible);
        c.refuse(Reason::Unsigned, counts.unsigned);
        c.refuse(Reason::BadSignature, counts.bad_signature);
        c.refuse(Reason::OldTimestamp, counts.old_timestamp);
    }

    fn handle(
        &self,
        st: &mut State,
        h: MavHeader,
        msg: Msg,
        from: Option<SocketAddr>,
        after: &mut After,
    ) {
        let cfg = &self.inner.cfg;
        if let Msg::Heartbeat(hb) = &msg
            && !st.vehicles.contains_key(&h.system_id)
        {
            let Some((kind, family, subtype)) = vehicle::classify(hb.mavtype) else { return };
            if st.vehicles.len() >= cfg.max_vehicles {
                self.inner.counters.refuse(Reason::VehicleLimit, 1);
                return;
            }
            match self.discover(h, hb, kind, family, &subtype) {
                Ok(v) => {
                    st.by_guid.insert(v.guid, v.sysid);
                    st.vehicles.insert(h.system_id, v);
                }
                Err(e) => {
                    self.inner
                        .ctx
                        .report(mocu_host::Level::Error, format!("mav{}: {e}", h.system_id));
                    return;
                }
            }
        }
        let State { vehicles, next_id, .. } = st;
        let Some(v) = vehicles.get_mut(&h.system_id) else { return };
        // Link quality from sequence gaps, smoothed.
        if h.component_id == v.compid {
            let lost = v.last_seq.map_or(0, |s| h.sequence.wrapping_sub(s.wrapping_add(1)));
            v.last_seq = Some(h.sequence);
            v.rx_w = v.rx_w * 0.98 + 1.0;
            v.lost_w = v.lost_w * 0.98 + f64::from(lost);
        }
        match msg {
            Msg::Heartbeat(hb) => {
                self.heartbeat(v, &hb);
                if let Some(from) = from
                    && h.component_id == v.compid
                    && v.prove(from, h.sequence, cfg.proof_heartbeats)
                {
                    let _ = self.inner.ctx.ds.set(v.guid, "verified", Value::Bool(true));
                }
            }
            Msg::GpsRaw(gps) => self.gps_raw(v, &gps),
            Msg::CommandAck(ack) => self.acknowledge(v, &ack, after),
            Msg::Other(m) => {
                if let Err(r) = self.telemetry(v, &m) {
                    self.inner.counters.refuse(r, 1);
                }
                self.answer(v, &m, next_id, after);
            }
        }
    }

    /// Sends `msg` to `addr` (an address that proved itself; `None` sends nothing), signed
    /// when the link has a key, within `max_send_rate`.
    pub(crate) fn send_to(&self, addr: Option<SocketAddr>, msg: &MavMessage) {
        let (Some(sock), Some(addr)) = (&self.inner.socket, addr) else { return };
        if !self.take_send_slot() {
            self.inner.counters.send_dropped.fetch_add(1, Ordering::Relaxed);
            return;
        }
        let header = MavHeader {
            system_id: u32::from(self.inner.cfg.system_id),
            component_id: self.inner.cfg.component_id,
            sequence: self.inner.seq.fetch_add(1, Ordering::Relaxed),
        };
        let bytes = match self.inner.signing.lock().as_mut() {
            Some(s) => {
                let now = crate::signing::timestamp(self.inner.ctx.ds.wall_time());
                encode_v2_signed(header, msg, s, now)
            }
            None => encode_v2(header, msg),
        };
        if sock.send_to(&bytes, addr).is_ok() {
            self.inner.counters.sent.fetch_add(1, Ordering::Relaxed);
        }
    }

    fn take_send_slot(&self) -> bool {
        let now = self.inner.ctx.ds.now();
        let mut w = self.inner.window.lock();
        if now.saturating_duration_since(w.0) >= Duration::from_secs(1) {
            *w = (now, 0);
        }
        if w.1 >= self.inner.cfg.max_send_rate {
            return false;
        }
        w.1 += 1;
        true
    }

    /// Marks links lost after `link_timeout` without a heartbeat, forgets vehicles silent
    /// for `forget_after`, sends our own heartbeat to the proved addresses, and publishes the
    /// counters. Called periodically by the module.
    pub fn watchdog(&self, send_heartbeat: bool) {
        let ds = &self.inner.ctx.ds;
        let cfg = &self.inner.cfg;
        // On the DataServer's clock: a test advances it instead of waiting.
        let now = ds.now();
        let mut st = self.inner.state.lock();
        let mut targets = Vec::new();
        let mut silent_ones = Vec::new();
        for v in st.vehicles.values_mut() {
            let silent = now.saturating_duration_since(v.last_heartbeat);
            if silent > cfg.forget_after {
                silent_ones.push(v.sysid);
                continue;
            }
            if !v.lost && silent > cfg.link_timeout {
                v.lost = true;
                let _ = ds.set(v.guid, "link_lost", Value::Bool(true));
                let _ = ds.set(v.guid, "stale", Value::Bool(true));
                let _ = ds.set(v.guid, "link", Value::Float(0.0));
                self.inner
                    .ctx
                    .report(mocu_host::Level::Warning, format!("mav{}: link lost", v.sysid));
            }
            targets.push(v.addr);
        }
        let mut forgotten = Vec::new();
        for s in silent_ones {
            if let Some(v) = st.vehicles.remove(&s) {
                st.by_guid.remove(&v.guid);
                forgotten.push(v);
            }
        }
        let n = st.vehicles.len();
        drop(st);
        for v in forgotten {
            self.forget(v);
        }
        if send_heartbeat {
            let hb = MavMessage::HEARTBEAT(HEARTBEAT_DATA {
                custom_mode: 0,
                mavtype: MavType::MAV_TYPE_GCS,
                autopilot: MavAutopilot::MAV_AUTOPILOT_INVALID,
                base_mode: MavModeFlag::empty(),
                system_status: MavState::MAV_STATE_ACTIVE,
                mavlink_version: 3,
            });
            for addr in targets {
                self.send_to(addr, &hb);
            }
        }
        self.sync_routes();
        self.inner.counters.publish(ds, self.inner.ctx.status, n);
    }

    /// Removes a vehicle silent for `forget_after` from the world model; its waiting calls
    /// fail.
    fn forget(&self, v: Vehicle) {
        let why = || CallOutcome::Failed("the vehicle was forgotten after a long silence".into());
        for p in v.commands {
            p.responder.reply(why());
        }
        if let Some(r) = v.upload.and_then(|up| up.responder) {
            r.reply(why());
        }
        let _ = self.inner.ctx.ds.delete_object(v.guid);
        self.inner.counters.forgotten.fetch_add(1, Ordering::Relaxed);
        self.inner.ctx.report(
            mocu_host::Level::Warning,
            format!("mav{}: forgotten after {} s without a heartbeat", v.sysid, {
                self.inner.cfg.forget_after.as_secs()
            }),
        );
    }
}
