//! The one way the display allocates a pixmap or a per-pixel buffer: checked against
//! [`MAX_PIXMAP_PX`] (shared with `mocu check` through mocu-value), so that an absurd size
//! from a layout is refused — drawn as nothing — instead of aborting the OCU.

use mocu_value::limits::MAX_PIXMAP_PX;
use tiny_skia::Pixmap;

/// Whether a `w` × `h` buffer is within what the display allocates (no zero side).
pub(crate) fn fits(w: u64, h: u64) -> bool {
    w > 0 && h > 0 && w.saturating_mul(h) <= MAX_PIXMAP_PX
}

/// A transparent `w` × `h` pixmap, or `None` for a zero side or one beyond the limit.
pub(crate) fn pixmap(w: u32, h: u32) -> Option<Pixmap> {
    if fits(w as u64, h as u64) { Pixmap::new(w, h) } else { None }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_pixmap_beyond_the_limit_is_refused_not_allocated() {
        assert!(pixmap(100_000_000, 100_000_000).is_none());
        assert!(pixmap(u32::MAX, 2).is_none());
        assert!(pixmap(0, 10).is_none());
        assert_eq!(pixmap(800, 480).map(|p| (p.width(), p.height())), Some((800, 480)));
    }

    /// Every `Pixmap::new` of the display's code (its tests aside) is the one above.
    #[test]
    fn no_pixmap_is_allocated_unchecked() {
        fn walk(dir: &std::path::Path, found: &mut Vec<String>) {
            for e in std::fs::read_dir(dir).unwrap() {
                let p = e.unwrap().path();
                if p.is_dir() {
                    walk(&p, found);
                } else if p.extension().is_some_and(|x| x == "rs") && !p.ends_with("alloc.rs") {
                    let text = std::fs::read_to_string(&p).unwrap();
                    let code = text.split("#[cfg(test)]").next().unwrap_or("");
                    for (i, line) in code.lines().enumerate() {
                        if line.contains("Pixmap::new(") {
                            found.push(format!("{}:{}", p.display(), i + 1));
                        }
                    }
                }
            }
        }
        let mut found = Vec::new();
        walk(&std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("src"), &mut found);
        assert_eq!(found, Vec::<String>::new(), "use crate::alloc::pixmap");
    }
}
