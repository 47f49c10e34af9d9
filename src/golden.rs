//! Golden frames: a screenshot compared with an expected PNG (`mocu replay --expect`), and
//! an image of where they differ.

use tiny_skia::{IntSize, Pixmap};

/// How a frame compares with its golden.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Comparison {
    /// Pixels with a channel further than the tolerance from the golden's.
    pub differing: u64,
    /// The largest channel difference seen (0..=255).
    pub max_delta: u8,
    /// `(frame, golden)` sizes when they differ (then every pixel counts as differing).
    pub sizes: Option<((u32, u32), (u32, u32))>,
}

impl Comparison {
    pub fn matches(&self) -> bool {
        self.differing == 0 && self.sizes.is_none()
    }
}

/// Compares `frame` with `golden`: a pixel differs when one of its premultiplied RGBA
/// channels is more than `tolerance` away.
pub fn compare(frame: &Pixmap, golden: &Pixmap, tolerance: u8) -> Comparison {
    let (fw, fh, gw, gh) = (frame.width(), frame.height(), golden.width(), golden.height());
    if (fw, fh) != (gw, gh) {
        let n = u64::from(fw.max(gw)) * u64::from(fh.max(gh));
        return Comparison { differing: n, max_delta: 255, sizes: Some(((fw, fh), (gw, gh))) };
    }
    let mut c = Comparison { differing: 0, max_delta: 0, sizes: None };
    for (a, b) in frame.data().chunks_exact(4).zip(golden.data().chunks_exact(4)) {
        let d = a.iter().zip(b).map(|(x, y)| x.abs_diff(*y)).max().unwrap_or(0);
        c.max_delta = c.max_delta.max(d);
        if d > tolerance {
            c.differing += 1;
        }
    }
    c
}

/// Where `frame` differs from `golden`: differing pixels magenta, the others the golden's,
/// faded to grey (so the changed places stand out on the display they belong to). The size
/// is the larger of the two.
pub fn diff_image(frame: &Pixmap, golden: &Pixmap, tolerance: u8) -> Option<Pixmap> {
    let (w, h) = (frame.width().max(golden.width()), frame.height().max(golden.height()));
    let mut out = Vec::with_capacity(w as usize * h as usize * 4);
    let px = |p: &Pixmap, x: u32, y: u32| -> Option<[u8; 4]> {
        (x < p.width() && y < p.height()).then(|| {
            let i = (y as usize * p.width() as usize + x as usize) * 4;
            let d = &p.data()[i..i + 4];
            [d[0], d[1], d[2], d[3]]
        })
    };
    for y in 0..h {
        for x in 0..w {
            let (a, b) = (px(frame, x, y), px(golden, x, y));
            let same = matches!((a, b), (Some(a), Some(b))
                if a.iter().zip(&b).all(|(p, q)| p.abs_diff(*q) <= tolerance));
            if same {
                let g = b.unwrap_or([0; 4]);
                let grey = ((u16::from(g[0]) + u16::from(g[1]) + u16::from(g[2])) / 3) as u8;
                let faded = 128 + grey / 4;
                out.extend_from_slice(&[faded, faded, faded, 255]);
            } else {
                out.extend_from_slice(&[255, 0, 255, 255]);
            }
        }
    }
    Pixmap::from_vec(out, IntSize::from_wh(w, h)?)
}

/// The diff image's path: `shot.png` → `shot.diff.png`.
pub fn diff_path(beside: &std::path::Path) -> std::path::PathBuf {
    let stem = beside.file_stem().map_or_else(|| "frame".into(), |s| s.to_string_lossy());
    beside.with_file_name(format!("{stem}.diff.png"))
}

#[cfg(test)]
mod tests {
    use super::*;
    use tiny_skia::Color;

    fn filled(w: u32, h: u32, c: Color) -> Pixmap {
        let mut p = Pixmap::new(w, h).unwrap();
        p.fill(c);
        p
    }

    #[test]
    fn a_frame_matches_itself_and_a_golden_within_the_tolerance() {
        let a = filled(8, 4, Color::from_rgba8(10, 20, 30, 255));
        let b = filled(8, 4, Color::from_rgba8(12, 20, 30, 255));
        assert!(compare(&a, &a, 0).matches());
        assert!(compare(&a, &b, 2).matches());
        let c = compare(&a, &b, 1);
        assert_eq!((c.differing, c.max_delta), (32, 2));
    }

    #[test]
    fn the_diff_image_marks_exactly_the_changed_pixels() {
        let a = filled(4, 2, Color::WHITE);
        let mut b = a.clone();
        b.pixels_mut()[5] = tiny_skia::PremultipliedColorU8::from_rgba(0, 0, 0, 255).unwrap();
        assert_eq!(compare(&a, &b, 0).differing, 1);
        let d = diff_image(&a, &b, 0).unwrap();
        let magenta: Vec<usize> = d
            .pixels()
            .iter()
            .enumerate()
            .filter(|(_, p)| (p.red(), p.green(), p.blue()) == (255, 0, 255))
            .map(|(i, _)| i)
            .collect();
        assert_eq!(magenta, vec![5]);
    }

    #[test]
    fn frames_of_different_sizes_never_match() {
        let c = compare(&filled(4, 4, Color::BLACK), &filled(4, 5, Color::BLACK), 255);
        assert!(!c.matches());
        assert_eq!(c.sizes, Some(((4, 4), (4, 5))));
    }
}
