//! The file-system edge: the only module that reads files or the environment. The CLI and
//! `mocu run` use it; the compiler core sees only the [`SourceLoader`] trait.

use crate::source::{SourceLoader, join, normalize, parent};
use std::path::Path;

/// Reads files from disk. `use "stdlib/…"` that is not found beside the using file is looked
/// up, in order, under `$MOCU_STDLIB` (the stdlib folder itself), in a `stdlib/` folder in the
/// using file's folder or any folder above it, and in the stdlib of the source tree mocu was
/// built from.
#[derive(Debug, Default, Clone)]
pub struct FsLoader;

impl FsLoader {
    fn exists(p: &str) -> bool {
        Path::new(if p.is_empty() { "." } else { p }).is_file()
    }
}

/// The stdlib folder baked in at build time.
pub const BUILTIN_STDLIB: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../../stdlib");

impl SourceLoader for FsLoader {
    fn resolve(&self, from: &str, spec: &str) -> Option<String> {
        let local = join(parent(from), spec);
        if Self::exists(&local) {
            return Some(local);
        }
        let rest = spec.strip_prefix("stdlib/")?;
        if let Ok(root) = std::env::var("MOCU_STDLIB") {
            let p = join(&root, rest);
            if Self::exists(&p) {
                return Some(p);
            }
        }
        let mut dir = parent(from).to_string();
        loop {
            let p = join(&dir, spec);
            if Self::exists(&p) {
                return Some(p);
            }
            if dir.is_empty() || dir == "/" {
                break;
            }
            dir = parent(&dir).to_string();
        }
        let p = normalize(&format!("{BUILTIN_STDLIB}/{rest}"));
        Self::exists(&p).then_some(p)
    }

    /// Bytes in: text that is not UTF-8 is refused with the line and column of the first bad
    /// byte.
    fn read(&self, path: &str) -> Result<String, String> {
        let bytes = std::fs::read(path).map_err(|e| e.to_string())?;
        String::from_utf8(bytes).map_err(|e| {
            crate::lexer::describe_bad_utf8(e.as_bytes())
                .unwrap_or_else(|| "not UTF-8 text".to_string())
        })
    }
}

/// The bytes of a file `mocu run` was given (a built bundle, a profile or a layout).
pub fn read_bytes(path: &Path) -> std::io::Result<Vec<u8>> {
    std::fs::read(path)
}
