//! The open documents, and the loader that serves their in-memory text over the file system:
//! what the editor shows is what is checked, saved or not.

use mocu_language::source::{join, normalize, parent};
use mocu_language::{FsLoader, SourceLoader};
use std::collections::HashMap;

/// One open document.
#[derive(Clone, Debug)]
pub struct Document {
    pub text: String,
    pub version: i32,
}

/// The editor's open documents, by path.
#[derive(Clone, Debug, Default)]
pub struct Documents {
    pub open: HashMap<String, Document>,
}

impl Documents {
    pub fn text(&self, path: &str) -> Option<&str> {
        self.open.get(path).map(|d| d.text.as_str())
    }
    /// A loader seeing these documents over the disk.
    pub fn loader(&self) -> OverlayLoader {
        OverlayLoader {
            texts: self.open.iter().map(|(p, d)| (p.clone(), d.text.clone())).collect(),
        }
    }
}

/// A [`SourceLoader`]: an open document's text wins over its file on disk, and a document that
/// was never saved resolves too; everything else comes from [`FsLoader`] (its stdlib search
/// included).
#[derive(Clone, Debug, Default)]
pub struct OverlayLoader {
    pub texts: HashMap<String, String>,
}

impl SourceLoader for OverlayLoader {
    fn resolve(&self, from: &str, spec: &str) -> Option<String> {
        let local = join(parent(from), spec);
        if self.texts.contains_key(&local) {
            return Some(local);
        }
        FsLoader.resolve(from, spec).map(|p| normalize(&p))
    }
    fn read(&self, path: &str) -> Result<String, String> {
        match self.texts.get(path) {
            Some(t) => Ok(t.clone()),
            None => FsLoader.read(path),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_open_document_wins_over_the_disk_and_resolves_unsaved() {
        let mut docs = Documents::default();
        docs.open
            .insert("/nowhere/a.mocu".into(), Document { text: "let a = 1\n".into(), version: 1 });
        let l = docs.loader();
        assert_eq!(l.resolve("/nowhere/b.mocu", "a.mocu").as_deref(), Some("/nowhere/a.mocu"));
        assert_eq!(l.read("/nowhere/a.mocu").as_deref(), Ok("let a = 1\n"));
        assert!(l.read("/nowhere/c.mocu").is_err());
    }
}
