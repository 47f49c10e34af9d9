//! What the `mocu check`/`mocu build` end-to-end tests share: running the built binary from
//! the repository root, and a fresh scratch folder per test.
#![allow(dead_code)]

use std::path::PathBuf;
use std::process::{Command, Output};

/// Runs the built `mocu` with `args` in the repository root and waits for it.
pub fn mocu(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_mocu"))
        .args(args)
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output()
        .expect("mocu runs")
}

/// An empty folder of its own for one test of one suite (`suite`, `name`): emptied first.
pub fn scratch_dir(suite: &str, name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("mocu-{suite}-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("temp dir");
    dir
}

/// The share of pixels of `png` in `x0..x1` × `y0..y1` that are sky blue (the simulator's
/// camera sky: bright, blue well above red; the map's sea is dark).
pub fn sky_share(png: &std::path::Path, (x0, x1): (u32, u32), (y0, y1): (u32, u32)) -> f64 {
    let p = tiny_skia::Pixmap::load_png(png).expect("a PNG");
    let mut sky = 0;
    for y in y0..y1 {
        for x in x0..x1 {
            let c = p.pixel(x, y).expect("inside").demultiply();
            let blue = u16::from(c.blue());
            sky += usize::from(blue > 140 && blue > u16::from(c.red()) + 40);
        }
    }
    sky as f64 / f64::from((x1 - x0) * (y1 - y0))
}

/// The peer's report on a recording (see its docstring).
pub fn read_recording(file: &std::path::Path, properties: &[&str]) -> serde_json::Value {
    let mut cmd = Command::new("python3");
    cmd.arg("tests/peers/read_recording.py").arg(file);
    for p in properties {
        cmd.args(["--property", p]);
    }
    let out = cmd.output().expect("python3 runs");
    assert!(
        out.status.success(),
        "the reader failed (is the Python `mcap` package installed? .ci/run pins it): {}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).unwrap()
}

pub fn count(r: &serde_json::Value, topic: &str) -> u64 {
    r["channels"][topic]["count"].as_u64().unwrap_or(0)
}
