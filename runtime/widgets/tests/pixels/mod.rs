//! Golden-image comparison for the widget tests (see tests/golden.rs for the rules):
//! every channel of every pixel within `CHANNEL_TOL` of the reference, except at most
//! `OUTLIER_FRACTION` of the pixels. `UPDATE_GOLDEN=1` rewrites the references.

use std::path::PathBuf;

const CHANNEL_TOL: u8 = 3;
const OUTLIER_FRACTION: f64 = 0.001;

pub fn check_golden(name: &str, frame: &tiny_skia::Pixmap) {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join(format!("tests/golden/{name}.png"));
    if std::env::var_os("UPDATE_GOLDEN").is_some() {
        frame.save_png(&path).unwrap();
        eprintln!("golden: wrote {}", path.display());
        return;
    }
    let want = tiny_skia::Pixmap::load_png(&path).unwrap_or_else(|e| {
        panic!("golden {} missing ({e}); run with UPDATE_GOLDEN=1 to create it", path.display())
    });
    assert_eq!((want.width(), want.height()), (frame.width(), frame.height()), "size of {name}");
    let (mut outliers, mut worst) = (0usize, 0u8);
    for (a, b) in frame.data().chunks_exact(4).zip(want.data().chunks_exact(4)) {
        let d = a.iter().zip(b).map(|(x, y)| x.abs_diff(*y)).max().unwrap_or(0);
        worst = worst.max(d);
        if d > CHANNEL_TOL {
            outliers += 1;
        }
    }
    let px = (frame.width() * frame.height()) as f64;
    if outliers as f64 > px * OUTLIER_FRACTION {
        let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("golden-actual");
        std::fs::create_dir_all(&dir).unwrap();
        let actual = dir.join(format!("{name}.png"));
        frame.save_png(&actual).unwrap();
        panic!(
            "{name}: {outliers} pixels differ by more than {CHANNEL_TOL} (worst {worst}); actual image in {}",
            actual.display()
        );
    }
}
