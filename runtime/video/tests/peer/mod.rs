//! Real video peers for tests: ffmpeg (Debian package `ffmpeg`) streaming its `testsrc`
//! pattern to a loopback port. Every process is bounded (`-t`, and `timeout -s INT -k 2`)
//! and stopped when its guard drops.
#![allow(dead_code)]

pub mod receiver;
pub mod relay;

use std::process::{Child, Command, Stdio};

/// What a missing peer says: the test fails (it does not skip) and names the package.
pub fn require_ffmpeg() {
    let ok = Command::new("ffmpeg")
        .arg("-version")
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .status()
        .is_ok_and(|s| s.success());
    assert!(ok, "ffmpeg is missing: install the Debian package with `apt-get install ffmpeg`");
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Kind {
    RtpH264,
    RtpJpeg,
    RawMjpeg,
}

/// An ffmpeg sender; killed (SIGTERM through `timeout`) when dropped.
pub struct Ffmpeg {
    child: Child,
    ended: bool,
}

impl Ffmpeg {
    /// Streams testsrc at `w`×`h`, 30 fps, for at most `secs` seconds to 127.0.0.1:`port`.
    pub fn stream(kind: Kind, w: u32, h: u32, port: u16, secs: u32) -> Ffmpeg {
        Ffmpeg::stream_with(kind, w, h, port, secs, &[], "")
    }

    /// As [`Ffmpeg::stream`], with more output options (`-ssrc 7 -seq 100`, …) and URL
    /// options (`localport=5000`).
    pub fn stream_with(
        kind: Kind,
        w: u32,
        h: u32,
        port: u16,
        secs: u32,
        extra: &[&str],
        query: &str,
    ) -> Ffmpeg {
        Ffmpeg::stream_source(
            &format!("testsrc=size={w}x{h}:rate=30"),
            kind,
            port,
            secs,
            extra,
            query,
        )
    }

    /// As [`Ffmpeg::stream_with`], from any lavfi source (`testsrc2=size=640x480:rate=30`
    /// moves everywhere: a realistic 8 packets a frame where testsrc needs 1.3).
    pub fn stream_source(
        src: &str,
        kind: Kind,
        port: u16,
        secs: u32,
        extra: &[&str],
        query: &str,
    ) -> Ffmpeg {
        require_ffmpeg();
        let src = src.to_string();
        let mut args: Vec<String> = vec![
            "-s".into(),
            "INT".into(),
            "-k".into(),
            "2".into(),
            (secs + 2).to_string(),
            "ffmpeg".into(),
            "-nostdin".into(),
            "-loglevel".into(),
            "error".into(),
            "-re".into(),
            "-f".into(),
            "lavfi".into(),
            "-t".into(),
            secs.to_string(),
            "-i".into(),
            src,
        ];
        let codec: &[&str] = match kind {
            Kind::RtpH264 => &[
                "-c:v",
                "libx264",
                "-preset",
                "ultrafast",
                "-tune",
                "zerolatency",
                "-g",
                "30",
                "-pix_fmt",
                "yuv420p",
                "-f",
                "rtp",
            ],
            Kind::RtpJpeg => {
                &["-c:v", "mjpeg", "-huffman", "0", "-pix_fmt", "yuvj420p", "-f", "rtp"]
            }
            Kind::RawMjpeg => {
                &["-c:v", "mjpeg", "-pix_fmt", "yuvj420p", "-q:v", "4", "-f", "mjpeg"]
            }
        };
        args.extend(codec.iter().map(|s| s.to_string()));
        args.extend(extra.iter().map(|s| s.to_string()));
        args.push(match kind {
            Kind::RawMjpeg => format!("udp://127.0.0.1:{port}?pkt_size=1316"),
            _ if query.is_empty() => format!("rtp://127.0.0.1:{port}"),
            _ => format!("rtp://127.0.0.1:{port}?{query}"),
        });
        let child = Command::new("timeout")
            .args(&args)
            .stdin(Stdio::null())
            .stdout(Stdio::null())
            .spawn()
            .expect("cannot start `timeout ffmpeg …` (coreutils, ffmpeg)");
        Ffmpeg { child, ended: false }
    }
}

impl Ffmpeg {
    /// Waits for ffmpeg to end (bounded: `timeout` ends it `secs` + 2 s after its start,
    /// and kills it 2 s later).
    pub fn wait(mut self) {
        let _ = self.child.wait();
        self.ended = true;
    }
}

impl Drop for Ffmpeg {
    fn drop(&mut self) {
        if self.ended {
            return;
        }
        // `timeout` passes the TERM on to ffmpeg and, with `-k 2`, kills it 2 s later if it
        // is still running: waiting for the exit is bounded.
        let _ = Command::new("kill").args(["-TERM", &self.child.id().to_string()]).status();
        let _ = self.child.wait();
    }
}

/// testsrc's colour bars at points that neither the moving gradient nor the counter
/// touch, as fractions of the picture, with the colour expected there.
pub const BARS: &[((f32, f32), [u8; 3], &str)] = &[
    ((40.0 / 640.0, 100.0 / 480.0), [0, 0, 0], "black"),
    ((120.0 / 640.0, 100.0 / 480.0), [0, 255, 255], "cyan"),
    ((200.0 / 640.0, 100.0 / 480.0), [255, 0, 255], "magenta"),
    ((280.0 / 640.0, 100.0 / 480.0), [0, 0, 255], "blue"),
    ((360.0 / 640.0, 100.0 / 480.0), [255, 255, 0], "yellow"),
    ((440.0 / 640.0, 100.0 / 480.0), [0, 255, 0], "green"),
    ((520.0 / 640.0, 100.0 / 480.0), [255, 0, 0], "red"),
    ((600.0 / 640.0, 100.0 / 480.0), [255, 255, 255], "white"),
    ((120.0 / 640.0, 450.0 / 480.0), [255, 0, 0], "red (bottom)"),
];

/// Per-channel tolerance: lossy codecs, limited-range YUV and chroma subsampling.
pub const TOLERANCE: i32 = 48;

/// Checks every bar of `BARS` with `pixel(fx, fy) -> rgb`; returns the mismatches.
pub fn check_bars(pixel: impl Fn(f32, f32) -> [u8; 3]) -> Vec<String> {
    check_bars_at(BARS, pixel)
}

/// Checks the given points of the test picture (as in `BARS`); returns the mismatches.
pub fn check_bars_at(
    bars: &[((f32, f32), [u8; 3], &str)],
    pixel: impl Fn(f32, f32) -> [u8; 3],
) -> Vec<String> {
    let mut bad = Vec::new();
    for ((fx, fy), want, name) in bars {
        let got = pixel(*fx, *fy);
        if got.iter().zip(want).any(|(g, w)| (*g as i32 - *w as i32).abs() > TOLERANCE) {
            bad.push(format!("{name} at ({fx:.3}, {fy:.3}): got {got:?}, want {want:?}"));
        }
    }
    bad
}
