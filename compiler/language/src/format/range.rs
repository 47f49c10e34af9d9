//! Formatting part of a file (an editor's "format selection"): the items a range touches.
//!
//! The whole file is formatted ([`super::format_source`], with its checks) and cut into items
//! by the parser's cut ([`crate::parser::split_items`]), as is the text: formatting changes
//! nothing but the space between tokens, so the `k`-th item of one is the `k`-th item of the
//! other. Each touched item that the formatting changes is one edit: its text replaced by its
//! formatted text. What lies between items (blank lines, comments above an item) is left.

use super::{FormatError, format_source};
use crate::diagnostics::Diagnostics;
use crate::parser::{ChunkKind, split_items};
use crate::source::FileId;
use std::ops::Range;

/// The edits (a byte range of `text` and its new text, in order) that format the items of
/// `text` (the layout file `file`) that `range` touches; an empty range touches the item it is
/// in or at the edge of. Syntax errors go to `diags` and give [`FormatError::Syntax`].
pub fn format_range(
    file: FileId,
    text: &str,
    range: Range<usize>,
    diags: &mut Diagnostics,
) -> Result<Vec<(Range<usize>, String)>, FormatError> {
    let formatted = format_source(file, text, diags)?;
    if formatted == text {
        return Ok(Vec::new());
    }
    let (old, new) = (split_items(text), split_items(&formatted));
    let items = |cs: &[crate::parser::Chunk]| cs.iter().all(|c| c.kind == ChunkKind::Item);
    if old.len() != new.len() || !items(&old) || !items(&new) {
        return Err(FormatError::WouldChangeMeaning(
            "the formatted file is not cut into the same items".into(),
        ));
    }
    let touches = |c: &crate::parser::Chunk| c.start <= range.end && range.start <= c.end;
    Ok(old
        .iter()
        .zip(&new)
        .filter(|(o, _)| touches(o))
        .map(|(o, n)| (o.start..o.end, &formatted[n.start..n.end]))
        .filter(|(o, n)| text[o.clone()] != **n)
        .map(|(o, n)| (o, n.to_string()))
        .collect())
}
