//! The figure for the size limit: peak memory and time of one 9 KB JPEG whose frame header
//! claims 16384×16384, decoded as before the limit (zune-jpeg with its own defaults, whose
//! only bound is 16384) and as now (`decode_jpeg_limited`, default limits). Each mode runs
//! in its own process, so that its peak resident size is its own:
//!
//! ```sh
//! cargo run --release -p mocu-video --example frame_bomb -- before
//! cargo run --release -p mocu-video --example frame_bomb -- after
//! ```
//! (ffmpeg makes the 64×64 JPEG whose header is then rewritten.)

use mocu_video::Limits;
use mocu_video::codec::decode_jpeg_limited;
use std::process::Command;
use std::time::Instant;

fn bomb() -> Vec<u8> {
    let out = Command::new("ffmpeg")
        .args(["-nostdin", "-loglevel", "error", "-f", "lavfi", "-i", "testsrc=size=64x64"])
        .args(["-frames:v", "1", "-f", "mjpeg", "pipe:1"])
        .output()
        .expect("ffmpeg");
    let mut j = out.stdout;
    let sof = j.windows(2).position(|m| m == [0xff, 0xc0]).expect("a baseline JPEG");
    j[sof + 5..sof + 9].copy_from_slice(&[0x40, 0, 0x40, 0]); // 16384 rows, 16384 columns
    let pad = (9 * 1024usize).saturating_sub(j.len() + 4);
    let mut com = vec![0xff, 0xfe];
    com.extend_from_slice(&((pad + 2) as u16).to_be_bytes());
    com.extend(std::iter::repeat_n(b'x', pad));
    j.splice(2..2, com);
    j
}

/// VmHWM (peak resident set) in MiB, from /proc/self/status.
fn peak_rss_mib() -> f64 {
    let s = std::fs::read_to_string("/proc/self/status").unwrap_or_default();
    s.lines()
        .find(|l| l.starts_with("VmHWM:"))
        .and_then(|l| l.split_whitespace().nth(1))
        .and_then(|kb| kb.parse::<f64>().ok())
        .map_or(0.0, |kb| kb / 1024.0)
}

fn main() {
    let mode = std::env::args().nth(1).unwrap_or_else(|| "after".into());
    let data = bomb();
    let base = peak_rss_mib();
    let t = Instant::now();
    let result = match mode.as_str() {
        "before" => {
            use zune_jpeg::zune_core::bytestream::ZCursor;
            use zune_jpeg::zune_core::colorspace::ColorSpace;
            use zune_jpeg::zune_core::options::DecoderOptions;
            let opts = DecoderOptions::default().jpeg_set_out_colorspace(ColorSpace::RGBA);
            let mut d = zune_jpeg::JpegDecoder::new_with_options(ZCursor::new(&data), opts);
            d.decode().map(|p| format!("decoded {} bytes", p.len())).map_err(|e| e.to_string())
        }
        _ => decode_jpeg_limited(&data, &Limits::default())
            .map(|f| format!("decoded {}x{}", f.width, f.height))
            .map_err(|e| e.to_string()),
    };
    let ms = t.elapsed().as_secs_f64() * 1000.0;
    println!(
        "{mode}: {} bytes in, {:?}; {ms:.3} ms; peak RSS {:.1} MiB (before decoding {base:.1} MiB)",
        data.len(),
        result,
        peak_rss_mib()
    );
}
