//! Video (paper §3.1 criterion 5, §3.2 streams): cameras are **listener objects** in the
//! world model, and video flows through them like any other stream.
//!
//! ```text
//! UDP ──► receiver (module `video`) ──► root.cameras.<name>.encoded   (listener: encoded units)
//!                                              │ join (DropOldest)
//!                                              ▼
//!                                      codec (JPEG: zune-jpeg, H.264: openh264)
//!                                              │ send
//!                                              ▼
//!                                      root.cameras.<name>            (listener: decoded frames)
//!                                              │ join (DropOldest, 2)          ▲ the simulator's
//!                                              ▼                               │ cameras send here
//!                                      video painter ──► windows of subtype `video`, any number
//! ```
//!
//! Conventions (see `docs/video.md`):
//! - A **camera** is a listener object whose messages are decoded frames:
//!   `[pixels: bytes, width: int, height: int, frame: int]`, optionally followed by
//!   `arrival_us: int` (when the frame's last packet arrived, on [`now_us`]'s clock).
//!   `pixels` is RGB8 or RGBA8 rows (told apart by length); a camera whose messages carry
//!   `arrival_us` has the property `arrival = true`. The simulator's cameras
//!   (`root.vehicles.<v>.cameras.drive`) are cameras as they are.
//! - A network camera also has a child listener `encoded` carrying
//!   `[data: bytes, codec: string ("h264" | "jpeg"), unit: int, arrival_us: int]`:
//!   one H.264 access unit (Annex B) or one complete JPEG file per message.
//! - Statistics are properties of the camera object: `width`, `height`, `frames`, `fps`,
//!   `sent`, `dropped`, `decode_errors`, `refused`, `ignored`, `restarts`, …,
//!   `latency_ms` (arrival → decoded), `codec`, and from the painter `shown_fps`,
//!   `shown_latency_ms` (arrival → painted). They add up: `sent = frames + dropped +
//!   decode_errors` (`docs/video.md` lists every counter).
//! - Frames are bounded per camera ([`Limits`]): the size a frame declares is checked
//!   before it is decoded.
//!
//! Architecture invariant: the receiver, the codecs and the painter talk only through the
//! DataServer (listener objects and properties); none holds a handle on another.

#![forbid(unsafe_code)]

mod chrome;
mod clock;
pub mod codec;
mod frame;
pub mod h264;
mod h264dec;
pub mod jitter;
pub mod limits;
pub mod mjpeg;
pub mod receiver;
pub mod rtp;
pub mod rtp_jpeg;
pub mod stream;
pub mod window;

pub use clock::now_us;
pub use codec::{
    Codec, CodecModule, DecodeError, DecodedFrame, Decoder, attach_decoder, attach_replay_decoder,
};
pub use frame::{EncodedUnit, FrameMsg};
pub use limits::{DEFAULT_LIMITS, Limits};
pub use receiver::{DEFAULT_ADDRESS, MAX_DATAGRAM, ReceiverConfig, VideoReceiver};
pub use stream::{SourceFilter, Stream, StreamConfig, StreamStats};
pub use window::{VideoWindows, WindowsConfig};

use mocu_host::{Module, Registry};
use std::time::Duration;

/// Registers the module kinds `video` (the UDP receiver, with its decoder), `codec` (a
/// decoder on its own, for a camera whose receiver has `decode = false`) and
/// `video_windows` (the painter of the `video` windows, `window::VideoWindows`).
pub fn register(registry: &mut Registry) {
    registry.register("video_windows", |spec| {
        Ok(Box::new(WindowsModule::from_spec(spec)?) as Box<dyn Module>)
    });
    registry.register("video", |spec| {
        Ok(Box::new(VideoReceiver::new(ReceiverConfig::from_spec(spec)?)) as Box<dyn Module>)
    });
    registry
        .register("codec", |spec| Ok(Box::new(CodecModule::from_spec(spec)?) as Box<dyn Module>));
}

/// The `video_windows` module: [`VideoWindows`] started by the module host. Settings
/// `stale_ms` and `no_video_ms` (a window's `STALE` mark and `NO VIDEO`).
pub struct WindowsModule {
    cfg: WindowsConfig,
    running: Option<VideoWindows>,
}

impl WindowsModule {
    pub fn from_spec(spec: &mocu_host::ModuleSpec) -> Result<WindowsModule, String> {
        let d = WindowsConfig::default();
        let ms = |key: &str, default: Duration| -> Result<Duration, String> {
            let v = spec.i64_or(key, default.as_millis() as i64).map_err(|e| e.to_string())?;
            if !(1..=600_000).contains(&v) {
                return Err(format!(
                    "module `{}`: `{key}` must be 1 to 600000 ms, got {v}",
                    spec.name
                ));
            }
            Ok(Duration::from_millis(v as u64))
        };
        let cfg = WindowsConfig {
            stale_after: ms("stale_ms", d.stale_after)?,
            no_video_after: ms("no_video_ms", d.no_video_after)?,
            ..d
        };
        Ok(WindowsModule { cfg, running: None })
    }
}

impl Module for WindowsModule {
    fn start(&mut self, ctx: &mocu_host::ModuleContext) -> Result<(), String> {
        self.running = Some(VideoWindows::start_with(&ctx.ds, self.cfg.clone())?);
        Ok(())
    }

    fn stop(&mut self) {
        self.running = None;
    }
}

/// The object at a dotted path text (`root.cameras.udp5600`, `vehicles.usv1.cameras.drive`;
/// the leading `root.` is optional).
pub fn resolve_path(ds: &mocu_dataserver::DataServer, text: &str) -> Option<mocu_value::Guid> {
    let segs = path_segments(text);
    if segs.is_empty() {
        return None;
    }
    ds.resolve(&segs)
}

/// A dotted path's object names without the leading `root`.
pub fn path_segments(text: &str) -> Vec<&str> {
    let mut segs: Vec<&str> = text.trim().split('.').filter(|s| !s.is_empty()).collect();
    if segs.first() == Some(&"root") {
        segs.remove(0);
    }
    segs
}

/// A path text in its full form, `root.` first.
pub fn normalize_path(text: &str) -> String {
    let segs = path_segments(text);
    if segs.is_empty() { "root".into() } else { format!("root.{}", segs.join(".")) }
}
