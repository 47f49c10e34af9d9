//! The H.264 decoder of one stream: openh264 with error concealment, the size check before
//! decoding, and a recovery from decode errors.
//!
//! openh264 runs with error concealment on (`ERROR_CON_SLICE_MV_COPY_CROSS_IDR_FREEZE_RES_CHANGE`,
//! through the vendored crate's setter, `vendor/openh264/PATCHED.md`): a unit that lost
//! slices or packets (the receiver hands such units on, see [`crate::rtp`]) gives a picture
//! completed from the previous one, counted in `concealed`. An access unit delimiter is
//! appended to each unit so that openh264 outputs a picture whose last slice is missing.
//! An error openh264 did not conceal (it would then refuse every unit until the next IDR)
//! still triggers the recovery: the decoder keeps the units it decoded since the last IDR
//! (bounded), and after such an error it starts a fresh openh264 and decodes them again
//! (without converting pictures): the bad unit is then like a lost one, and decoding goes
//! on from the last good reference (the SPS allows frame_num gaps, see [`crate::h264`]).

use crate::codec::{DecodeError, DecodedFrame};
use crate::limits::Limits;
use openh264::formats::YUVSource;

/// Units kept since the last IDR, at most (beyond, an error freezes until the next IDR).
pub const KEEP_UNITS: usize = 300;
/// Bytes kept since the last IDR, at most.
pub const KEEP_BYTES: usize = 64 << 20;

#[derive(Default)]
pub struct H264Decoder {
    dec: Option<openh264::decoder::Decoder>,
    /// The last SPS declared a size over the limits: units are refused until one within
    /// them comes (openh264 never saw that SPS).
    refusing: bool,
    /// Units decoded since the last IDR (as given to openh264), and whether they can be
    /// replayed (none lost to an error, within the bounds).
    since_key: Vec<Vec<u8>>,
    kept_bytes: usize,
    replayable: bool,
    /// Times the decoder was rebuilt from the kept units.
    pub recoveries: u64,
    /// Pictures returned that openh264 concealed in part (lost slices or references).
    pub concealed: u64,
}

/// An access unit delimiter (NAL unit type 9, any primary picture type).
const END_OF_UNIT: [u8; 6] = [0, 0, 0, 1, 0x09, 0xf0];

/// openh264's `dsDataErrorConcealed` decoding state bit.
const fn openh264_sys_concealed() -> i32 {
    0x20
}

fn is_idr(annexb: &[u8]) -> bool {
    crate::rtp::annexb_nals(annexb).iter().any(|n| n.first().is_some_and(|h| h & 0x1f == 5))
}

/// openh264 with error concealment on (the vendored crate's setter, `vendor/openh264`): a
/// picture with lost or undecodable slices, or a missing reference, is completed from the
/// previous picture (slices copied along their neighbours' motion vectors) instead of
/// refused; a change of resolution freezes the last picture until the next IDR.
fn fresh() -> Result<openh264::decoder::Decoder, DecodeError> {
    use openh264::decoder::{
        Decoder, DecoderConfig, ERROR_CON_SLICE_MV_COPY_CROSS_IDR_FREEZE_RES_CHANGE as CONCEAL,
    };
    let config = DecoderConfig::new().error_concealment(CONCEAL);
    Decoder::with_api_config(openh264::OpenH264API::from_source(), config)
        .map_err(|e| DecodeError::Failed(e.to_string()))
}

impl H264Decoder {
    /// Decodes one access unit (Annex B) within `limits`.
    pub fn decode(
        &mut self,
        data: &[u8],
        limits: &Limits,
    ) -> Result<Option<DecodedFrame>, DecodeError> {
        if let Some((width, height)) = crate::h264::unit_size(data) {
            self.refusing = !limits.allows(width, height);
            if self.refusing {
                return Err(DecodeError::Refused { width, height });
            }
        } else if self.refusing {
            return Err(DecodeError::Refused { width: 0, height: 0 });
        }
        let mut unit = crate::h264::allow_frame_num_gaps(data).into_owned();
        // An access unit delimiter after the unit tells openh264 the picture is complete:
        // otherwise it waits for the next unit's first slice, and a picture whose last
        // slice was lost is concealed but never output (a decode error, no picture).
        unit.extend_from_slice(&END_OF_UNIT);
        if self.dec.is_none() {
            self.dec = Some(fresh()?);
        }
        let d = self.dec.as_mut().expect("made above");
        let mut concealing = false;
        let result = match d.decode(&unit) {
            Ok(Some(yuv)) => {
                let (w, h) = yuv.dimensions();
                if limits.allows(w as u32, h as u32) {
                    let mut rgba = vec![0u8; w * h * 4];
                    yuv.write_rgba8(&mut rgba);
                    self.concealed += d.concealed() as u64;
                    Ok(Some(DecodedFrame { rgba, width: w as u32, height: h as u32 }))
                } else {
                    Err(DecodeError::Refused { width: w as u32, height: h as u32 })
                }
            }
            Ok(None) => Ok(None),
            Err(e) => {
                // openh264 concealed what it could (the state has dsDataErrorConcealed)
                // but gave no picture: it goes on decoding, no recovery is needed.
                concealing = e.native_code() & i64::from(openh264_sys_concealed()) != 0;
                Err(DecodeError::Failed(e.to_string()))
            }
        };
        let idr = is_idr(&unit);
        match &result {
            Ok(_) => self.keep(unit, idr),
            Err(DecodeError::Failed(_)) if idr => {
                self.since_key.clear();
                self.replayable = false;
            }
            Err(DecodeError::Failed(_)) if concealing => {}
            Err(DecodeError::Failed(_)) => self.recover(),
            Err(DecodeError::Refused { .. }) => {}
        }
        result
    }

    fn keep(&mut self, unit: Vec<u8>, idr: bool) {
        if idr {
            self.since_key.clear();
            self.kept_bytes = 0;
            self.replayable = true;
        }
        if !self.replayable {
            return;
        }
        self.kept_bytes += unit.len();
        self.since_key.push(unit);
        if self.since_key.len() > KEEP_UNITS || self.kept_bytes > KEEP_BYTES {
            self.since_key = Vec::new();
            self.replayable = false;
        }
    }

    /// A fresh openh264 fed the units kept since the last IDR; without them (none kept, or
    /// they fail again), openh264 stays as it is and waits for the next IDR.
    fn recover(&mut self) {
        if !self.replayable || self.since_key.is_empty() {
            return;
        }
        let Ok(mut d) = fresh() else { return };
        let ok = self.since_key.iter().all(|u| d.decode(u).is_ok());
        if ok {
            self.dec = Some(d);
            self.recoveries += 1;
        } else {
            self.since_key.clear();
            self.replayable = false;
        }
    }
}
