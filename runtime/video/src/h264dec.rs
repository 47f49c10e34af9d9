//! The H.264 decoder of one stream: openh264, with the size check before decoding and a
//! recovery from decode errors.
//!
//! openh264 as the `openh264` crate builds it runs without error concealment: after one
//! unit it cannot decode (corrupt, or truncated on the way), it refuses every unit until
//! the next IDR — a second or more of frozen picture, and for ever on a link that damages
//! some packet of every key frame. So the decoder keeps the units it decoded since the last
//! IDR (bounded), and after an error it starts a fresh openh264 and decodes them again
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
}

fn is_idr(annexb: &[u8]) -> bool {
    crate::rtp::annexb_nals(annexb).iter().any(|n| n.first().is_some_and(|h| h & 0x1f == 5))
}

fn fresh() -> Result<openh264::decoder::Decoder, DecodeError> {
    openh264::decoder::Decoder::new().map_err(|e| DecodeError::Failed(e.to_string()))
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
        let unit = crate::h264::allow_frame_num_gaps(data).into_owned();
        if self.dec.is_none() {
            self.dec = Some(fresh()?);
        }
        let d = self.dec.as_mut().expect("made above");
        let result = match d.decode(&unit) {
            Ok(Some(yuv)) => {
                let (w, h) = yuv.dimensions();
                if limits.allows(w as u32, h as u32) {
                    let mut rgba = vec![0u8; w * h * 4];
                    yuv.write_rgba8(&mut rgba);
                    Ok(Some(DecodedFrame { rgba, width: w as u32, height: h as u32 }))
                } else {
                    Err(DecodeError::Refused { width: w as u32, height: h as u32 })
                }
            }
            Ok(None) => Ok(None),
            Err(e) => Err(DecodeError::Failed(e.to_string())),
        };
        let idr = is_idr(&unit);
        match &result {
            Ok(_) => self.keep(unit, idr),
            Err(DecodeError::Failed(_)) if idr => {
                self.since_key.clear();
                self.replayable = false;
            }
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
