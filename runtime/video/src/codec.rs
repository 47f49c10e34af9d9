//! Decoders: JPEG with zune-jpeg, H.264 with openh264 (Cisco's decoder, built from the
//! sources the `openh264` crate bundles — no download, no system library).
//!
//! A decoder joins a camera's `encoded` listener (dropping the oldest unit when it falls
//! behind) and sends RGBA8 frames on the camera listener itself. [`attach_decoder`] does it
//! for one camera; the `codec` module kind does it for a camera named in a profile.

use crate::frame::{EncodedUnit, FrameMsg};
use crate::limits::Limits;
use crate::{now_us, resolve_path};
use mocu_dataserver::{
    Call, DataServer, DsError, Executor, Guid, MethodSpec, ObjectInfo, Overflow, ParamSpec, Value,
    ValueKind,
};
use mocu_host::{Module, ModuleContext, ModuleSpec};
use parking_lot::Mutex;
use std::sync::Arc;
use std::time::{Duration, Instant};

/// The codecs a receiver can hand on.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Codec {
    Jpeg,
    H264,
}

impl Codec {
    pub fn name(self) -> &'static str {
        match self {
            Codec::Jpeg => "jpeg",
            Codec::H264 => "h264",
        }
    }

    pub fn parse(s: &str) -> Option<Codec> {
        match s {
            "jpeg" | "mjpeg" => Some(Codec::Jpeg),
            "h264" => Some(Codec::H264),
            _ => None,
        }
    }
}

/// One decoded picture: RGBA8 rows.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct DecodedFrame {
    pub rgba: Vec<u8>,
    pub width: u32,
    pub height: u32,
}

impl DecodedFrame {
    /// The pixel at (x, y) as RGB.
    pub fn rgb_at(&self, x: u32, y: u32) -> [u8; 3] {
        let i = (y as usize * self.width as usize + x as usize) * 4;
        [self.rgba[i], self.rgba[i + 1], self.rgba[i + 2]]
    }
}

/// Why a unit gave no picture.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum DecodeError {
    /// The declared size is over the camera's limits: not decoded.
    Refused { width: u32, height: u32 },
    /// The decoder failed (corrupt or truncated data).
    Failed(String),
}

impl std::fmt::Display for DecodeError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            DecodeError::Refused { width, height } => {
                write!(f, "{width}x{height} is over the camera's size limit")
            }
            DecodeError::Failed(e) => f.write_str(e),
        }
    }
}

/// A decoder for one stream (it keeps the H.264 decoder's reference pictures).
#[derive(Default)]
pub struct Decoder {
    h264: crate::h264dec::H264Decoder,
}

impl Decoder {
    pub fn new() -> Decoder {
        Decoder::default()
    }

    /// Times the H.264 decoder was rebuilt after a decode error (see `h264dec.rs`).
    pub fn recoveries(&self) -> u64 {
        self.h264.recoveries
    }

    /// H.264 pictures that openh264's error concealment completed (lost slices or
    /// references); they are among the frames decoded.
    pub fn concealed(&self) -> u64 {
        self.h264.concealed
    }

    /// Decodes one unit within the default limits (see [`Decoder::decode_limited`]).
    pub fn decode(&mut self, codec: Codec, data: &[u8]) -> Result<Option<DecodedFrame>, String> {
        self.decode_limited(codec, data, &Limits::default()).map_err(|e| e.to_string())
    }

    /// Decodes one unit: a JPEG file, or an H.264 access unit (Annex B). The size the unit
    /// declares is checked against `limits` first. `Ok(None)` when the unit gave no
    /// picture (parameter sets only).
    pub fn decode_limited(
        &mut self,
        codec: Codec,
        data: &[u8],
        limits: &Limits,
    ) -> Result<Option<DecodedFrame>, DecodeError> {
        if data.len() > limits.max_unit_bytes {
            return Err(DecodeError::Failed(format!("a unit of {} bytes", data.len())));
        }
        match codec {
            Codec::Jpeg => decode_jpeg_limited(data, limits).map(Some),
            Codec::H264 => self.h264.decode(data, limits),
        }
    }
}

/// Decodes a JPEG file to RGBA8 with zune-jpeg, within the default limits.
pub fn decode_jpeg(data: &[u8]) -> Result<DecodedFrame, String> {
    decode_jpeg_limited(data, &Limits::default()).map_err(|e| e.to_string())
}

/// Decodes a JPEG file to RGBA8 with zune-jpeg: the size its frame header declares is
/// checked first, and the decoder is strict (corrupt entropy-coded data is an error, not a
/// picture of garbage).
pub fn decode_jpeg_limited(data: &[u8], limits: &Limits) -> Result<DecodedFrame, DecodeError> {
    use zune_jpeg::zune_core::bytestream::ZCursor;
    use zune_jpeg::zune_core::colorspace::ColorSpace;
    use zune_jpeg::zune_core::options::DecoderOptions;
    let failed = |e: String| DecodeError::Failed(e);
    let (width, height) = crate::limits::jpeg_size(data).ok_or(failed("no frame header".into()))?;
    if !limits.allows(width, height) {
        return Err(DecodeError::Refused { width, height });
    }
    let opts = DecoderOptions::default()
        .jpeg_set_out_colorspace(ColorSpace::RGBA)
        .set_strict_mode(true)
        .set_max_width(limits.max_width as usize)
        .set_max_height(limits.max_height as usize);
    let mut d = zune_jpeg::JpegDecoder::new_with_options(ZCursor::new(data), opts);
    let rgba = d.decode().map_err(|e| failed(e.to_string()))?;
    let (w, h) = d.dimensions().ok_or(failed("no dimensions".into()))?;
    if rgba.len() != w * h * 4 {
        return Err(failed(format!("decoded {} bytes for {w}x{h}", rgba.len())));
    }
    Ok(DecodedFrame { rgba, width: w as u32, height: h as u32 })
}

/// How many encoded units may wait for the decoder before the oldest is dropped.
/// Small: a decoder that falls behind should skip ahead, not build up latency (at 30 fps
/// four units are 133 ms).
pub const ENCODED_QUEUE: usize = 4;

/// Whether an H.264 access unit (Annex B) holds an IDR slice or a sequence parameter set.
pub fn is_key_unit(annexb: &[u8]) -> bool {
    crate::rtp::annexb_nals(annexb)
        .iter()
        .any(|n| n.first().is_some_and(|h| matches!(h & 0x1f, 5 | 7)))
}

/// A decoder attached to one camera; detaches when dropped.
pub struct DecoderHandle {
    ds: DataServer,
    object: Guid,
    assoc: Guid,
}

impl Drop for DecoderHandle {
    fn drop(&mut self) {
        let _ = self.ds.leave(self.assoc);
        let _ = self.ds.delete_object(self.object);
    }
}

struct DecodeState {
    decoder: Decoder,
    frames: i64,
    errors: i64,
    size: (u32, u32),
    codec: Option<Codec>,
    meter: Meter,
    last_latency_ms: f64,
    last_frame_us: i64,
    last_unit: Option<i64>,
    limits: Limits,
    /// Units dropped from the queue before the decoder (gaps in unit numbers).
    dropped_queue: i64,
    /// Units refused for their declared size.
    refused: i64,
    /// Units that gave no picture (parameter sets only, or the decoder waiting for a key
    /// frame).
    no_picture: i64,
    /// Decoding a replay: pictures only; the camera's statistics are the recording's.
    replayed: bool,
}

/// Frames per second over windows of about 250 ms, and when to publish statistics.
#[derive(Debug)]
pub(crate) struct Meter {
    since: Instant,
    count: u32,
    pub(crate) fps: f64,
}

impl Default for Meter {
    fn default() -> Meter {
        Meter { since: Instant::now(), count: 0, fps: 0.0 }
    }
}

impl Meter {
    pub(crate) const PERIOD: Duration = Duration::from_millis(250);

    /// Counts one event; true when a period ended (publish now).
    pub(crate) fn tick(&mut self, events: u32) -> bool {
        self.count += events;
        let dt = self.since.elapsed();
        if dt >= Self::PERIOD {
            self.fps = self.count as f64 / dt.as_secs_f64();
            self.count = 0;
            self.since = Instant::now();
            true
        } else {
            false
        }
    }
}

/// Joins `encoded` (a listener of [`EncodedUnit`]s) with a decoder that sends RGBA8
/// [`FrameMsg`]s on `camera` and keeps the camera's statistics (`width`, `height`,
/// `frames`, `fps`, `dropped`, `latency_ms`, `codec`, `decode_errors`, `last_frame_us`).
/// The decoder runs on `executor`.
pub fn attach_decoder(
    ds: &DataServer,
    executor: &Executor,
    camera: Guid,
    encoded: Guid,
) -> Result<DecoderHandle, DsError> {
    attach(ds, executor, camera, encoded, false)
}

/// [`attach_decoder`] for a replay (`mocu replay`): the recorded units decoded into pictures
/// on `camera`, nothing else written (the camera's statistics are replayed as recorded, and
/// nothing here reads the system's clock: the same recording gives the same pictures).
pub fn attach_replay_decoder(
    ds: &DataServer,
    executor: &Executor,
    camera: Guid,
    encoded: Guid,
) -> Result<DecoderHandle, DsError> {
    attach(ds, executor, camera, encoded, true)
}

fn attach(
    ds: &DataServer,
    executor: &Executor,
    camera: Guid,
    encoded: Guid,
    replayed: bool,
) -> Result<DecoderHandle, DsError> {
    if let Some(old) = ds.find_child(camera, "decoder")? {
        ds.delete_object(old)?;
    }
    let object = ds.create_object(camera, ObjectInfo::new("decoder", "codec"))?;
    let state = Arc::new(Mutex::new(DecodeState {
        decoder: Decoder::new(),
        frames: 0,
        errors: 0,
        size: (0, 0),
        codec: None,
        meter: Meter::default(),
        last_latency_ms: 0.0,
        last_frame_us: 0,
        last_unit: None,
        limits: Limits::of(ds, camera),
        dropped_queue: 0,
        refused: 0,
        no_picture: 0,
        replayed,
    }));
    let spec = MethodSpec::new("unit")
        .param(ParamSpec::new("data", ValueKind::Bytes))
        .param(ParamSpec::new("codec", ValueKind::String))
        .param(ParamSpec::new("unit", ValueKind::Int))
        .param(ParamSpec::new("arrival_us", ValueKind::Int))
        .describe("Decodes one encoded unit and sends the picture on the camera");
    let ds2 = ds.clone();
    ds.publish_method_on(executor, object, spec, move |call: Call| {
        if let Some(u) = EncodedUnit::from_values(&call.args) {
            on_unit(&ds2, camera, &state, &u);
        }
        call.responder.accept(vec![]);
    })?;
    let assoc = ds.join(encoded, object, "unit", Overflow::DropOldest, ENCODED_QUEUE)?;
    Ok(DecoderHandle { ds: ds.clone(), object, assoc })
}

fn on_unit(ds: &DataServer, camera: Guid, state: &Mutex<DecodeState>, u: &EncodedUnit) {
    let mut st = state.lock();
    let Some(codec) = Codec::parse(&u.codec) else {
        st.errors += 1;
        return;
    };
    if st.codec != Some(codec) {
        st.codec = Some(codec);
        st.decoder = Decoder::new();
        let _ = ds.set(camera, "codec", Value::str(codec.name()));
    }
    // A gap in unit numbers: units were dropped from the queue before the decoder (it fell
    // behind). Decoding goes on: the SPS allows frame_num gaps (see `crate::h264`).
    if let Some(l) = st.last_unit {
        st.dropped_queue += (u.unit - l - 1).max(0);
    }
    st.last_unit = Some(u.unit);
    let limits = st.limits;
    let mut shown = 0;
    match st.decoder.decode_limited(codec, &u.data, &limits) {
        Ok(Some(f)) => {
            st.frames += 1;
            shown = 1;
            let (w, h) = (f.width, f.height);
            let msg = FrameMsg {
                pixels: f.rgba.into(),
                width: w,
                height: h,
                frame: st.frames,
                // A replay's frames arrived in another process, on another clock: their
                // latency is not this one's to show.
                arrival_us: (!st.replayed).then_some(u.arrival_us),
            };
            let _ = ds.send(camera, msg.to_values());
            if st.replayed {
                return;
            }
            let now = now_us();
            st.last_latency_ms = (now - u.arrival_us) as f64 / 1000.0;
            st.last_frame_us = now;
            if st.size != (w, h) {
                st.size = (w, h);
                let _ = ds.set(camera, "width", Value::Int(w as i64));
                let _ = ds.set(camera, "height", Value::Int(h as i64));
            }
        }
        Ok(None) => st.no_picture += 1,
        // The last good frame stays on screen: nothing is sent.
        Err(DecodeError::Refused { .. }) => st.refused += 1,
        Err(DecodeError::Failed(_)) => st.errors += 1,
    }
    if st.replayed {
        return;
    }
    // Counters on every unit (they add up: see docs/video.md; the receiver sums `dropped`),
    // rates once a period.
    for (k, v) in [
        ("frames", Value::Int(st.frames)),
        ("dropped_queue", Value::Int(st.dropped_queue)),
        ("refused", Value::Int(st.refused)),
        ("no_picture", Value::Int(st.no_picture)),
        ("decode_errors", Value::Int(st.errors)),
        ("recoveries", Value::Int(st.decoder.recoveries() as i64)),
        ("concealed", Value::Int(st.decoder.concealed() as i64)),
    ] {
        let _ = ds.set(camera, k, v);
    }
    let first = st.frames == 1 && shown == 1;
    if st.meter.tick(shown) || first {
        for (k, v) in [
            ("fps", Value::Float((st.meter.fps * 10.0).round() / 10.0)),
            ("latency_ms", Value::Float((st.last_latency_ms * 10.0).round() / 10.0)),
            ("last_frame_us", Value::Int(st.last_frame_us)),
        ] {
            let _ = ds.set(camera, k, v);
        }
    }
}

/// The `codec` module kind: a decoder for the camera at `source` (a dotted path text such
/// as `root.cameras.front`), whose receiver publishes `encoded` but does not decode.
pub struct CodecModule {
    source: String,
    handle: Arc<Mutex<Option<DecoderHandle>>>,
    stopped: Arc<std::sync::atomic::AtomicBool>,
}

impl CodecModule {
    pub fn from_spec(spec: &ModuleSpec) -> Result<CodecModule, String> {
        let source = spec.str_or("source", "").map_err(|e| e.to_string())?;
        if source.is_empty() {
            return Err(format!("module `{}`: `source` (a camera path) is required", spec.name));
        }
        Ok(CodecModule { source, handle: Arc::default(), stopped: Arc::default() })
    }
}

impl Module for CodecModule {
    fn start(&mut self, ctx: &ModuleContext) -> Result<(), String> {
        try_attach(ctx.clone(), self.source.clone(), self.handle.clone(), self.stopped.clone());
        Ok(())
    }

    fn stop(&mut self) {
        self.stopped.store(true, std::sync::atomic::Ordering::SeqCst);
        self.handle.lock().take();
    }
}

/// Attaches when the camera and its `encoded` listener exist; until then, looks again
/// twice a second.
fn try_attach(
    ctx: ModuleContext,
    source: String,
    handle: Arc<Mutex<Option<DecoderHandle>>>,
    stopped: Arc<std::sync::atomic::AtomicBool>,
) {
    if stopped.load(std::sync::atomic::Ordering::SeqCst) {
        return;
    }
    let ds = &ctx.ds;
    let cam = resolve_path(ds, &source);
    let enc = cam.and_then(|c| ds.find_child(c, "encoded").ok().flatten());
    if let (Some(c), Some(e)) = (cam, enc)
        && let Ok(h) = attach_decoder(ds, &ctx.executor, c, e)
    {
        *handle.lock() = Some(h);
        let _ = ds.set(ctx.status, "camera", Value::str(&source));
        return;
    }
    let ctx2 = ctx.clone();
    ctx.ds.run_after(Duration::from_millis(500), Some(&ctx.executor), move || {
        try_attach(ctx2, source, handle, stopped)
    });
}
