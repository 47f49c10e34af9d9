//! The two message shapes that travel through camera listeners.

use mocu_value::Value;
use std::sync::Arc;

/// One encoded unit on a camera's `encoded` listener.
#[derive(Clone, Debug, PartialEq)]
pub struct EncodedUnit {
    /// An H.264 access unit in Annex B form, or one complete JPEG file.
    pub data: Arc<[u8]>,
    /// `"h264"` or `"jpeg"`.
    pub codec: Arc<str>,
    /// Counts units from 1 (gaps: units dropped before the listener).
    pub unit: i64,
    /// When its last packet arrived ([`crate::now_us`]).
    pub arrival_us: i64,
}

impl EncodedUnit {
    pub fn to_values(&self) -> Vec<Value> {
        vec![
            Value::Bytes(self.data.clone()),
            Value::Str(self.codec.clone()),
            Value::Int(self.unit),
            Value::Int(self.arrival_us),
        ]
    }

    pub fn from_values(args: &[Value]) -> Option<EncodedUnit> {
        match args {
            [Value::Bytes(d), Value::Str(c), u, t, ..] => Some(EncodedUnit {
                data: d.clone(),
                codec: c.clone(),
                unit: u.as_i64()?,
                arrival_us: t.as_i64()?,
            }),
            _ => None,
        }
    }
}

/// One decoded frame on a camera listener: `[pixels, width, height, frame, arrival_us?]`.
#[derive(Clone, Debug, PartialEq)]
pub struct FrameMsg {
    /// RGB8 or RGBA8 rows, told apart by length.
    pub pixels: Arc<[u8]>,
    pub width: u32,
    pub height: u32,
    pub frame: i64,
    /// When the frame's last packet arrived, where known (the simulator does not say).
    pub arrival_us: Option<i64>,
}

impl FrameMsg {
    pub fn to_values(&self) -> Vec<Value> {
        let mut v = vec![
            Value::Bytes(self.pixels.clone()),
            Value::Int(self.width as i64),
            Value::Int(self.height as i64),
            Value::Int(self.frame),
        ];
        if let Some(t) = self.arrival_us {
            v.push(Value::Int(t));
        }
        v
    }

    pub fn from_values(args: &[Value]) -> Option<FrameMsg> {
        let (px, w, h, n) = match args {
            [Value::Bytes(px), w, h, n, ..] => (px, w.as_i64()?, h.as_i64()?, n.as_i64()?),
            _ => return None,
        };
        let (w, h) = (u32::try_from(w).ok()?, u32::try_from(h).ok()?);
        let area = w as usize * h as usize;
        if area == 0 || (px.len() != area * 3 && px.len() != area * 4) {
            return None;
        }
        Some(FrameMsg {
            pixels: px.clone(),
            width: w,
            height: h,
            frame: n,
            arrival_us: args.get(4).and_then(|v| v.as_i64()),
        })
    }

    /// Bytes per pixel: 3 (RGB8) or 4 (RGBA8).
    pub fn channels(&self) -> usize {
        self.pixels.len() / (self.width as usize * self.height as usize)
    }
}
