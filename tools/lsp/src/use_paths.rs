//! Completion inside `use "…"`: the layout files and folders beside the document (a path is
//! relative to the file that `use`s it) and, under `stdlib/`, the standard library's files,
//! found where `mocu check` finds them.

use lsp_types::{CompletionItem, CompletionItemKind, CompletionTextEdit, TextEdit};
use mocu_language::source::{join, parent};
use mocu_language::{FsLoader, SourceLoader};
use std::path::Path;

/// What is typed of a `use` path when `before` (the document up to the cursor) ends inside
/// the string of a `use`: the path so far.
pub fn typed(before: &str) -> Option<&str> {
    let line = before.rsplit('\n').next().unwrap_or(before);
    let rest = line.trim_start().strip_prefix("use")?;
    let rest = rest.trim_start();
    if rest.len() == line.trim_start().len() - 3 {
        return None; // `user…`: no space after `use`.
    }
    let path = rest.strip_prefix('"')?;
    (!path.contains('"')).then_some(path)
}

/// The completions of the `use` path `typed` (the text just before the cursor at `cursor`, a
/// position in the document at `doc`): each item replaces the path's last segment.
pub fn complete(doc: &str, typed: &str, cursor: lsp_types::Position) -> Vec<CompletionItem> {
    let (folder, segment) = typed.rsplit_once('/').unwrap_or(("", typed));
    let replace = lsp_types::Range::new(
        lsp_types::Position::new(
            cursor.line,
            cursor.character - segment.chars().map(char::len_utf16).sum::<usize>() as u32,
        ),
        cursor,
    );
    let mut entries: Vec<(String, bool)> = Vec::new();
    if let Some(dir) = folder_on_disk(doc, folder) {
        entries.extend(
            list(&dir).into_iter().filter(|(name, is_dir)| *is_dir || join(&dir, name) != doc),
        );
    }
    if folder.is_empty() && !entries.iter().any(|(n, _)| n == "stdlib") {
        entries.push(("stdlib".into(), true));
    }
    entries.sort();
    entries.dedup();
    entries
        .into_iter()
        .map(|(name, is_dir)| {
            let text = if is_dir { format!("{name}/") } else { name.clone() };
            CompletionItem {
                label: text.clone(),
                kind: Some(if is_dir {
                    CompletionItemKind::FOLDER
                } else {
                    CompletionItemKind::FILE
                }),
                detail: Some(if is_dir { "folder".into() } else { "layout file".into() }),
                text_edit: Some(CompletionTextEdit::Edit(TextEdit {
                    range: replace,
                    new_text: text,
                })),
                ..CompletionItem::default()
            }
        })
        .collect()
}

/// The folder a typed `use` folder names, seen from the document at `doc`: beside it, or for
/// `stdlib/…` not found beside it, the standard library's folder the checker would read.
fn folder_on_disk(doc: &str, folder: &str) -> Option<String> {
    let local = join(parent(doc), folder);
    if Path::new(if local.is_empty() { "." } else { &local }).is_dir() {
        return Some(local);
    }
    let inside = folder.strip_prefix("stdlib")?;
    let inside = inside.strip_prefix('/').unwrap_or(inside);
    stdlib_folder(doc).map(|root| join(&root, inside)).filter(|d| Path::new(d).is_dir())
}

/// The standard library's folder for the document at `doc`: where `use "stdlib/gauges.mocu"`
/// resolves (every stdlib has it).
fn stdlib_folder(doc: &str) -> Option<String> {
    FsLoader.resolve(doc, "stdlib/gauges.mocu").map(|p| parent(&p).to_string())
}

/// A folder's layout files and sub-folders (hidden ones left out): (name, is a folder).
fn list(dir: &str) -> Vec<(String, bool)> {
    let Ok(rd) = std::fs::read_dir(if dir.is_empty() { "." } else { dir }) else {
        return Vec::new();
    };
    rd.filter_map(Result::ok)
        .filter_map(|e| {
            let name = e.file_name().to_string_lossy().into_owned();
            let is_dir = e.file_type().ok()?.is_dir();
            let wanted = !name.starts_with('.') && (is_dir || name.ends_with(".mocu"));
            wanted.then_some((name, is_dir))
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_typed_path_is_found_only_inside_the_string_of_a_use() {
        assert_eq!(typed("let a = 1\nuse \"stdlib/ga"), Some("stdlib/ga"));
        assert_eq!(typed("  use   \""), Some(""));
        assert_eq!(typed("use \"a.mocu\" as b"), None);
        assert_eq!(typed("let user = \"x"), None);
        assert_eq!(typed("user \"x"), None);
    }

    #[test]
    fn stdlib_files_are_offered_under_stdlib_each_replacing_the_last_segment() {
        let doc = format!("{}/layouts/none.mocu", env!("CARGO_MANIFEST_DIR"));
        let items = complete(&doc, "stdlib/ga", lsp_types::Position::new(3, 14));
        let labels: Vec<&str> = items.iter().map(|i| i.label.as_str()).collect();
        assert!(labels.contains(&"gauges.mocu"), "{labels:?}");
        let Some(CompletionTextEdit::Edit(e)) = &items[0].text_edit else { panic!("an edit") };
        assert_eq!((e.range.start.character, e.range.end.character), (12, 14));
    }

    #[test]
    fn the_documents_folder_is_listed_with_stdlib_and_without_the_document() {
        let dir = std::env::temp_dir().join(format!("mocu-lsp-use-{}", std::process::id()));
        std::fs::create_dir_all(dir.join("parts")).unwrap();
        for f in ["a.mocu", "b.mocu", "notes.txt"] {
            std::fs::write(dir.join(f), "").unwrap();
        }
        let doc = dir.join("a.mocu").to_string_lossy().replace('\\', "/");
        let items = complete(&doc, "", lsp_types::Position::new(0, 5));
        let labels: Vec<&str> = items.iter().map(|i| i.label.as_str()).collect();
        assert_eq!(labels, vec!["b.mocu", "parts/", "stdlib/"]);
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
