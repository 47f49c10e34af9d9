//! The `video` module: one UDP port, one stream. It tells RTP/H.264, RTP/JPEG and raw
//! MJPEG apart by their payload, rebuilds encoded units, and publishes them on the
//! camera's `encoded` listener; by default it also attaches a decoder (see
//! [`crate::codec`]).
//!
//! Which stream a port hears, and how: see [`crate::stream`].

use crate::codec::{DecoderHandle, Meter, attach_decoder};
use crate::frame::EncodedUnit;
use crate::limits::{DEFAULT_LIMITS, Limits};
use crate::now_us;
use crate::stream::{SourceFilter, Stream, StreamConfig};
use mocu_dataserver::{DataServer, Guid, Value};
use mocu_host::world::ensure_path;
use mocu_host::{Level, Module, ModuleContext, ModuleSpec};
use std::net::{SocketAddr, UdpSocket};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::thread::JoinHandle;
use std::time::Duration;

/// Where video is heard when nothing says otherwise (QGroundControl's convention).
pub const DEFAULT_ADDRESS: &str = "0.0.0.0:5600";

/// The largest UDP payload: datagrams are read whole, never truncated.
pub const MAX_DATAGRAM: usize = 65_535;

/// Settings of the `video` module kind.
#[derive(Clone, Debug, PartialEq)]
pub struct ReceiverConfig {
    /// `address`: the UDP address to listen on (port 0: any free port, published as the
    /// camera's `port` property).
    pub address: SocketAddr,
    /// `camera`: the camera's name under `root.cameras` (default `udp<port>`).
    pub camera: Option<String>,
    /// `feeds`: the vehicle camera this stream stands for, as a path text
    /// (`root.vehicles.usv1.cameras.drive`), `auto` (the first vehicle's drive camera) or
    /// `none`. Windows showing that camera show this stream while it is live.
    pub feeds: String,
    /// `decode`: attach a decoder (default true); false leaves it to a `codec` module.
    pub decode: bool,
    /// `source`, `ssrc`, `silence_ms`, `reorder`, `reorder_ms`, `max_width`, `max_height`,
    /// `max_unit_kb`: which stream is chosen and how it is rebuilt (see [`crate::stream`]).
    pub stream: StreamConfig,
}

impl Default for ReceiverConfig {
    fn default() -> ReceiverConfig {
        ReceiverConfig {
            address: DEFAULT_ADDRESS.parse().expect("a valid address"),
            camera: None,
            feeds: "auto".into(),
            decode: true,
            stream: StreamConfig::default(),
        }
    }
}

impl ReceiverConfig {
    pub fn from_spec(spec: &ModuleSpec) -> Result<ReceiverConfig, String> {
        let e = |x: mocu_host::SpecError| x.to_string();
        let address = spec.socket_addr_or("address", DEFAULT_ADDRESS).map_err(e)?;
        let camera = spec.str_or("camera", "").map_err(e)?;
        let bad = |k: &str, want: &str| format!("module `{}`: `{k}` must be {want}", spec.name);
        let src = spec.str_or("source", "any").map_err(e)?;
        let source =
            SourceFilter::parse(&src).ok_or_else(|| bad("source", "`any`, HOST or HOST:PORT"))?;
        let ssrc = match spec.i64_or("ssrc", -1).map_err(e)? {
            -1 => None,
            v => Some(u32::try_from(v).map_err(|_| bad("ssrc", "0 to 4294967295"))?),
        };
        let ranged = |k: &str, d: i64, lo: i64, hi: i64| -> Result<i64, String> {
            let v = spec.i64_or(k, d).map_err(e)?;
            if (lo..=hi).contains(&v) { Ok(v) } else { Err(bad(k, &format!("{lo} to {hi}"))) }
        };
        let d = DEFAULT_LIMITS;
        let stream = StreamConfig {
            source,
            ssrc,
            silence: Duration::from_millis(ranged("silence_ms", 2000, 10, 600_000)? as u64),
            reorder: ranged("reorder", 8, 1, 1024)? as usize,
            reorder_delay: Duration::from_millis(ranged("reorder_ms", 100, 0, 5000)? as u64),
            limits: Limits {
                max_width: ranged("max_width", d.max_width as i64, 16, 16384)? as u32,
                max_height: ranged("max_height", d.max_height as i64, 16, 16384)? as u32,
                max_unit_bytes: ranged("max_unit_kb", (d.max_unit_bytes >> 10) as i64, 16, 1 << 20)?
                    as usize
                    * 1024,
            },
        };
        Ok(ReceiverConfig {
            address,
            camera: (!camera.is_empty()).then_some(camera),
            feeds: spec.str_or("feeds", "auto").map_err(e)?,
            decode: spec.bool_or("decode", true).map_err(e)?,
            stream,
        })
    }
}

/// The receiver module.
pub struct VideoReceiver {
    cfg: ReceiverConfig,
    stop: Arc<AtomicBool>,
    thread: Option<JoinHandle<()>>,
    decoder: Option<DecoderHandle>,
}

impl VideoReceiver {
    pub fn new(cfg: ReceiverConfig) -> VideoReceiver {
        VideoReceiver { cfg, stop: Arc::default(), thread: None, decoder: None }
    }
}

impl Module for VideoReceiver {
    fn start(&mut self, ctx: &ModuleContext) -> Result<(), String> {
        let sock = UdpSocket::bind(self.cfg.address)
            .map_err(|e| format!("cannot listen on {}: {e}", self.cfg.address))?;
        // Short enough that a packet waiting in the reorder buffer is let go in time.
        let wake = self
            .cfg
            .stream
            .reorder_delay
            .clamp(Duration::from_millis(10), Duration::from_millis(100));
        sock.set_read_timeout(Some(wake)).map_err(|e| e.to_string())?;
        let local = sock.local_addr().map_err(|e| e.to_string())?;
        let name = self.cfg.camera.clone().unwrap_or_else(|| format!("udp{}", local.port()));
        let ds = &ctx.ds;
        let (camera, encoded) =
            publish_camera(ds, &name, local, &self.cfg.feeds).map_err(|e| e.to_string())?;
        self.cfg.stream.limits.publish(ds, camera);
        if self.cfg.decode {
            self.decoder = Some(
                attach_decoder(ds, &ds.serial_executor(), camera, encoded)
                    .map_err(|e| e.to_string())?,
            );
        }
        let _ = ds.set(ctx.status, "camera", Value::str(&format!("root.cameras.{name}")));
        let _ = ds.set(ctx.status, "address", Value::str(&local.to_string()));
        ctx.report(Level::Info, format!("video on udp://{local} → root.cameras.{name}"));
        let stop = self.stop.clone();
        let ds = ds.clone();
        let stream = Stream::with_config(self.cfg.stream);
        self.thread = Some(
            ctx.spawn_thread("udp", move || receive(ds, sock, stream, camera, encoded, stop))
                .map_err(|e| e.to_string())?,
        );
        Ok(())
    }

    fn stop(&mut self) {
        self.stop.store(true, Ordering::SeqCst);
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
        self.decoder = None;
    }
}

/// `root.cameras.<name>` (a listener: decoded frames) and its `encoded` child listener.
pub fn publish_camera(
    ds: &DataServer,
    name: &str,
    local: SocketAddr,
    feeds: &str,
) -> Result<(Guid, Guid), mocu_dataserver::DsError> {
    let cameras = ensure_path(ds, &["cameras"], "cameras")?;
    if let Some(old) = ds.find_child(cameras, name)? {
        ds.delete_object(old)?;
    }
    let camera = ds.create_listener(cameras, name)?;
    let encoded = ds.create_listener(camera, "encoded")?;
    let feeds = match feeds {
        "" | "none" | "auto" => feeds.to_string(),
        p => crate::normalize_path(p),
    };
    for (k, v) in [
        ("source", Value::str("network")),
        ("address", Value::str(&local.to_string())),
        ("port", Value::Int(local.port() as i64)),
        ("feeds", Value::str(&feeds)),
        ("transport", Value::str("")),
        ("codec", Value::str("")),
        ("format", Value::str("rgba8")),
        ("arrival", Value::Bool(true)),
        ("width", Value::Int(0)),
        ("height", Value::Int(0)),
        ("frames", Value::Int(0)),
        ("fps", Value::Float(0.0)),
        ("dropped", Value::Int(0)),
        ("dropped_network", Value::Int(0)),
        ("latency_ms", Value::Float(0.0)),
        ("packets", Value::Int(0)),
        ("bytes", Value::Int(0)),
        ("units", Value::Int(0)),
        ("last_frame_us", Value::Int(0)),
        ("sent", Value::Int(0)),
        ("oversize", Value::Int(0)),
        ("lost_packets", Value::Int(0)),
        ("reordered", Value::Int(0)),
        ("late_packets", Value::Int(0)),
        ("restarts", Value::Int(0)),
        ("ignored", Value::Int(0)),
        ("decode_errors", Value::Int(0)),
        ("recoveries", Value::Int(0)),
        ("concealed", Value::Int(0)),
        ("damaged", Value::Int(0)),
        ("refused", Value::Int(0)),
        ("dropped_queue", Value::Int(0)),
        ("no_picture", Value::Int(0)),
    ] {
        ds.set(camera, k, v)?;
    }
    Ok((camera, encoded))
}

fn receive(
    ds: DataServer,
    sock: UdpSocket,
    mut stream: Stream,
    camera: Guid,
    encoded: Guid,
    stop: Arc<AtomicBool>,
) {
    let mut buf = vec![0u8; MAX_DATAGRAM];
    let (mut packets, mut bytes, mut units) = (0i64, 0i64, 0i64);
    let mut meter = Meter::default();
    let mut transport = "";
    let mut source = None;
    let mut published = None;
    while !stop.load(Ordering::Relaxed) {
        let got = sock.recv_from(&mut buf);
        let arrival_us = now_us();
        let now = ds.clock().now();
        let mut n_units = 0;
        let mut send = |codec: crate::Codec, u: crate::rtp::Unit| {
            n_units += 1;
            let unit = EncodedUnit {
                data: u.data.into(),
                codec: codec.name().into(),
                unit: units + n_units,
                arrival_us,
            };
            let _ = ds.send(encoded, unit.to_values());
        };
        match got {
            Ok((n, from)) => {
                packets += 1;
                bytes += n as i64;
                stream.datagram(from, &buf[..n], now, &mut send);
            }
            Err(_) => stream.tick(now, &mut send),
        }
        units += n_units;
        if source != stream.sender() && stream.sender().is_some() {
            source = stream.sender();
            let from = source.map(|s| s.to_string()).unwrap_or_default();
            let _ = ds.set(camera, "sender", Value::str(&from));
        }
        let st = stream.stats();
        // Counters are published whenever they changed, and every period: `dropped` sums
        // the receiver's drops and the decoder's (its one writer is this thread).
        if published != Some(st) || meter.tick(0) {
            let get = |k: &str| ds.try_get(camera, k.into()).and_then(|v| v.as_i64()).unwrap_or(0);
            let decoder = get("dropped_queue") + get("refused") + get("no_picture");
            let _ = ds.set(camera, "dropped", Value::Int(st.dropped as i64 + decoder));
            published = Some(st);
            if stream.transport() != transport {
                transport = stream.transport();
                let _ = ds.set(camera, "transport", Value::str(transport));
            }
            for (k, v) in [
                ("packets", packets),
                ("bytes", bytes),
                ("units", units),
                ("sent", st.sent as i64),
                ("dropped_network", st.dropped as i64),
                ("oversize", st.oversize as i64),
                ("damaged", st.damaged as i64),
                ("lost_packets", st.lost_packets as i64),
                ("reordered", st.reorder.reordered as i64),
                ("late_packets", st.reorder.late as i64),
                ("restarts", st.reorder.restarts as i64),
                ("ignored", st.ignored as i64),
            ] {
                let _ = ds.set(camera, k, Value::Int(v));
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn spec() -> ModuleSpec {
        ModuleSpec::new("video").named("v")
    }

    #[test]
    fn stream_choice_and_limits_come_from_the_module_settings() {
        let s = spec()
            .with("source", "10.0.0.5:5600")
            .with("ssrc", 77)
            .with("silence_ms", 500)
            .with("reorder", 4)
            .with("max_width", 1920)
            .with("max_height", 1080)
            .with("max_unit_kb", 1024);
        let s = ReceiverConfig::from_spec(&s).unwrap().stream;
        assert_eq!(s.source, SourceFilter::Addr("10.0.0.5:5600".parse().unwrap()));
        assert_eq!((s.ssrc, s.silence, s.reorder), (Some(77), Duration::from_millis(500), 4));
        assert_eq!(s.limits, Limits { max_width: 1920, max_height: 1080, max_unit_bytes: 1 << 20 });
        assert_eq!(ReceiverConfig::from_spec(&spec()).unwrap().stream, StreamConfig::default());
    }

    #[test]
    fn bad_stream_settings_are_refused_with_their_name() {
        for (k, s) in [
            ("source", spec().with("source", "somewhere")),
            ("ssrc", spec().with("ssrc", -5)),
            ("max_width", spec().with("max_width", 100_000)),
            ("silence_ms", spec().with("silence_ms", 0)),
        ] {
            let e = ReceiverConfig::from_spec(&s).unwrap_err();
            assert!(e.contains(k), "{e}");
        }
    }
}
