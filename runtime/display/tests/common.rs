//! Shared helpers: a world with a display, golden-image comparison.
#![allow(dead_code)]

use mocu_dataserver::{Config, DataServer, Guid};
use mocu_display::*;
use std::path::PathBuf;

/// Golden-image tolerance: every channel of every pixel within `CHANNEL_TOL` of the
/// reference, except at most `OUTLIER_FRACTION` of the pixels (anti-aliased edges whose
/// coverage can differ by a step between CPUs with and without FMA/SIMD paths).
pub const CHANNEL_TOL: u8 = 3;
pub const OUTLIER_FRACTION: f64 = 0.001;

pub fn world(w: u32, h: u32) -> (DataServer, Display) {
    let ds = DataServer::new(Config { workers: 2 });
    let d = Display::new(&ds, DisplayOptions::new(w, h).clock(Clock::manual())).unwrap();
    (ds, d)
}

pub fn window(ds: &DataServer, d: &Display, name: &str, sub: &str, layer: i64, r: Rect) -> Guid {
    publish_window(ds, d.display_object(), name, sub, layer, r).unwrap()
}

/// Waits for the world model's notifications, then draws a frame.
pub fn frame(ds: &DataServer, d: &mut Display) -> FrameStats {
    ds.quiesce();
    d.frame()
}

fn golden_path(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/golden").join(format!("{name}.png"))
}

/// Compares a frame with `tests/golden/<name>.png`; `UPDATE_GOLDEN=1` rewrites it. On a
/// mismatch the actual image is written next to the target dir for inspection.
pub fn check_golden(name: &str, frame: &tiny_skia::Pixmap) {
    let path = golden_path(name);
    if std::env::var_os("UPDATE_GOLDEN").is_some() {
        frame.save_png(&path).unwrap();
        eprintln!("golden: wrote {}", path.display());
        return;
    }
    let want = tiny_skia::Pixmap::load_png(&path).unwrap_or_else(|e| {
        panic!("golden {} missing ({e}); run with UPDATE_GOLDEN=1 to create it", path.display())
    });
    let actual_dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("golden-actual");
    std::fs::create_dir_all(&actual_dir).unwrap();
    let actual = actual_dir.join(format!("{name}.png"));
    assert_eq!((want.width(), want.height()), (frame.width(), frame.height()), "size of {name}");
    let (mut outliers, mut worst) = (0usize, 0u8);
    for (a, b) in frame.data().chunks_exact(4).zip(want.data().chunks_exact(4)) {
        let d = a.iter().zip(b).map(|(x, y)| x.abs_diff(*y)).max().unwrap();
        worst = worst.max(d);
        if d > CHANNEL_TOL {
            outliers += 1;
        }
    }
    let px = (frame.width() * frame.height()) as f64;
    if outliers as f64 > px * OUTLIER_FRACTION {
        frame.save_png(&actual).unwrap();
        panic!(
            "{name}: {outliers} pixels differ by more than {CHANNEL_TOL} (worst {worst}); actual image in {}",
            actual.display()
        );
    }
}

/// The straight-alpha RGBA of a frame pixel.
pub fn pixel(frame: &tiny_skia::Pixmap, x: u32, y: u32) -> [u8; 4] {
    let c = frame.pixel(x, y).unwrap().demultiply();
    [c.red(), c.green(), c.blue(), c.alpha()]
}
