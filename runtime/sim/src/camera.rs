//! A synthetic camera: small RGB frames that move with the vehicle (horizon with pitch,
//! colour bars that slide with heading, a frame counter in the top row).

/// Renders one `w`×`h` RGB8 frame.
pub(crate) fn render(
    w: u32,
    h: u32,
    heading: f64,
    pitch: f64,
    frame: u64,
    tint: [u8; 3],
) -> Vec<u8> {
    let (w, h) = (w as usize, h as usize);
    let mut px = vec![0u8; w * h * 3];
    let horizon = (h as f64 / 2.0 + pitch * h as f64 / 60.0).clamp(0.0, h as f64) as usize;
    let shift = (heading / 360.0 * w as f64) as usize;
    for y in 0..h {
        for x in 0..w {
            let i = (y * w + x) * 3;
            let rgb = if y == 0 {
                // Frame counter, one bit per pixel, for tests and for spotting freezes.
                let bit = x < 64 && (frame >> (x % 64)) & 1 == 1;
                if bit { [255, 255, 255] } else { [0, 0, 0] }
            } else if y < horizon {
                [90, 140, (200u16 + (y * 40 / h.max(1)) as u16).min(255) as u8]
            } else {
                let bar = ((x + shift) * 8 / w.max(1)) % 8;
                let v = 60 + (bar as u8) * 20;
                [v / 2 + tint[0] / 2, v / 2 + tint[1] / 2, v / 2 + tint[2] / 2]
            };
            px[i..i + 3].copy_from_slice(&rgb);
        }
    }
    px
}
