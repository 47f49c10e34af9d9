//! How large a camera's frames may be. A frame's size is read from what it declares (the
//! JPEG frame header, the H.264 sequence parameter set, the RTP/JPEG header) **before** it
//! is decoded; a frame over the limits is refused and counted, never decoded (a 9 KB JPEG
//! that claims 16384×16384 would otherwise cost 1 GB of pixels and seconds of decoding).

use mocu_dataserver::{DataServer, Guid, Value};

/// The limits of one camera (module settings `max_width`, `max_height`, `max_unit_kb` of
/// the `video` kind, published as the camera's properties of the same names).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Limits {
    /// Widest and tallest frame decoded, in pixels.
    pub max_width: u32,
    pub max_height: u32,
    /// Largest encoded unit (one JPEG file, one H.264 access unit), in bytes: what the
    /// reassembly of one frame may hold.
    pub max_unit_bytes: usize,
}

/// 4096×4096 (a 64 MB RGBA frame) and 32 MB encoded units.
pub const DEFAULT_LIMITS: Limits =
    Limits { max_width: 4096, max_height: 4096, max_unit_bytes: 32 << 20 };

impl Default for Limits {
    fn default() -> Limits {
        DEFAULT_LIMITS
    }
}

impl Limits {
    /// Whether a declared size is within the limits (a zero side is not a picture).
    pub fn allows(&self, width: u32, height: u32) -> bool {
        width > 0 && height > 0 && width <= self.max_width && height <= self.max_height
    }

    /// The most memory one camera's pictures take: the reassembly buffer, plus the decoded
    /// RGBA frame in the decoder, in the camera's message and in the painter's queue of 2.
    pub fn memory_bound(&self) -> usize {
        self.max_unit_bytes + 4 * (self.max_width as usize * self.max_height as usize * 4)
    }

    /// Publishes the limits as properties of `camera`.
    pub fn publish(&self, ds: &DataServer, camera: Guid) {
        let _ = ds.set(camera, "max_width", Value::Int(self.max_width as i64));
        let _ = ds.set(camera, "max_height", Value::Int(self.max_height as i64));
        let _ = ds.set(camera, "max_unit_kb", Value::Int((self.max_unit_bytes >> 10) as i64));
    }

    /// The limits `camera` publishes (the defaults for what it does not).
    pub fn of(ds: &DataServer, camera: Guid) -> Limits {
        let get = |k: &str, d: i64| {
            ds.try_get(camera, k.into()).and_then(|v| v.as_i64()).filter(|&v| v > 0).unwrap_or(d)
        };
        let d = DEFAULT_LIMITS;
        Limits {
            max_width: get("max_width", d.max_width as i64).min(u32::MAX as i64) as u32,
            max_height: get("max_height", d.max_height as i64).min(u32::MAX as i64) as u32,
            max_unit_bytes: (get("max_unit_kb", (d.max_unit_bytes >> 10) as i64) as usize)
                .saturating_mul(1024),
        }
    }
}

/// The size a JPEG file declares in its first frame header (SOF0–SOF15 but DHT, JPG, DAC),
/// found by walking the marker segments before the scan.
pub fn jpeg_size(data: &[u8]) -> Option<(u32, u32)> {
    if !data.starts_with(&[0xff, 0xd8]) {
        return None;
    }
    let mut i = 2;
    loop {
        while data.get(i)? == &0xff && data.get(i + 1)? == &0xff {
            i += 1;
        }
        if data[i] != 0xff {
            return None;
        }
        let m = *data.get(i + 1)?;
        if m == 0xd8 || m == 0x01 || (0xd0..=0xd7).contains(&m) {
            i += 2;
            continue;
        }
        if m == 0xda || m == 0xd9 {
            return None; // a scan or the end before any frame header
        }
        let len = u16::from_be_bytes([*data.get(i + 2)?, *data.get(i + 3)?]) as usize;
        if (0xc0..=0xcf).contains(&m) && !matches!(m, 0xc4 | 0xc8 | 0xcc) {
            let b = data.get(i + 4..i + 9)?;
            let (h, w) = (u16::from_be_bytes([b[1], b[2]]), u16::from_be_bytes([b[3], b[4]]));
            return Some((w as u32, h as u32));
        }
        if len < 2 {
            return None;
        }
        i += 2 + len;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn jpeg_header(w: u16, h: u16) -> Vec<u8> {
        let mut v = vec![0xff, 0xd8, 0xff, 0xe0, 0, 4, 0, 0, 0xff, 0xc0, 0, 11, 8];
        v.extend_from_slice(&h.to_be_bytes());
        v.extend_from_slice(&w.to_be_bytes());
        v.extend_from_slice(&[1, 1, 0x11, 0]);
        v
    }

    #[test]
    fn a_jpeg_declares_its_size_in_its_frame_header() {
        assert_eq!(jpeg_size(&jpeg_header(640, 480)), Some((640, 480)));
        assert_eq!(jpeg_size(&jpeg_header(16384, 16384)), Some((16384, 16384)));
        assert_eq!(jpeg_size(&[0xff, 0xd8, 0xff, 0xda, 0, 2]), None);
        assert_eq!(jpeg_size(&[1, 2, 3]), None);
        assert_eq!(jpeg_size(&jpeg_header(640, 480)[..12]), None, "cut");
    }

    #[test]
    fn the_default_limits_allow_4k_and_refuse_16k() {
        let l = Limits::default();
        assert!(l.allows(4096, 2160) && l.allows(4096, 4096));
        assert!(!l.allows(16384, 16384) && !l.allows(4097, 10) && !l.allows(0, 10));
        assert_eq!(l.memory_bound(), (32 << 20) + 4 * 64 * (1 << 20));
    }
}
