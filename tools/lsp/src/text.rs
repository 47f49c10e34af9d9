//! Positions and addresses: LSP positions (line, UTF-16 column) ↔ byte offsets, and `file:`
//! URIs ↔ the `/`-separated paths the compiler's loaders use.

use lsp_types::{Position, Range, Uri};
use std::str::FromStr;

/// Where each line of a text starts, to turn byte offsets into LSP positions and back.
pub struct LineIndex<'a> {
    text: &'a str,
    starts: Vec<usize>,
}

impl<'a> LineIndex<'a> {
    pub fn new(text: &'a str) -> LineIndex<'a> {
        let mut starts = vec![0];
        starts.extend(text.match_indices('\n').map(|(i, _)| i + 1));
        LineIndex { text, starts }
    }

    /// The position of byte `offset` (clamped to the text and to a character boundary);
    /// columns count UTF-16 code units, as LSP's default encoding does.
    pub fn position(&self, offset: usize) -> Position {
        let mut offset = offset.min(self.text.len());
        while !self.text.is_char_boundary(offset) {
            offset -= 1;
        }
        let line = self.starts.partition_point(|&s| s <= offset) - 1;
        let col: usize = self.text[self.starts[line]..offset].chars().map(char::len_utf16).sum();
        Position::new(line as u32, col as u32)
    }

    pub fn range(&self, start: usize, end: usize) -> Range {
        Range::new(self.position(start), self.position(end))
    }

    /// The byte offset of a position; a column past the line's end is its end.
    pub fn offset(&self, pos: Position) -> usize {
        let Some(&start) = self.starts.get(pos.line as usize) else { return self.text.len() };
        let end = self.starts.get(pos.line as usize + 1).map_or(self.text.len(), |&e| e - 1);
        let mut units = 0;
        for (i, c) in self.text[start..end].char_indices() {
            if units >= pos.character as usize {
                return start + i;
            }
            units += c.len_utf16();
        }
        end
    }
}

/// The path of a `file:` URI (percent-decoded); `None` for other schemes.
pub fn uri_to_path(uri: &Uri) -> Option<String> {
    let rest = uri.as_str().strip_prefix("file://")?;
    // `file://host/path`: only the local host (empty or `localhost`) is a path here.
    let rest = rest.strip_prefix("localhost").unwrap_or(rest);
    let bytes = rest.as_bytes();
    let mut out = Vec::with_capacity(bytes.len());
    let mut i = 0;
    while i < bytes.len() {
        let hex = |b: u8| (b as char).to_digit(16);
        if bytes[i] == b'%'
            && let (Some(h), Some(l)) =
                (bytes.get(i + 1).and_then(|&b| hex(b)), bytes.get(i + 2).and_then(|&b| hex(b)))
        {
            out.push((h * 16 + l) as u8);
            i += 3;
        } else {
            out.push(bytes[i]);
            i += 1;
        }
    }
    let path = String::from_utf8(out).ok()?;
    // Windows drive paths come as `/C:/…`.
    let windows_drive = path.len() > 2 && path.as_bytes()[2] == b':';
    Some(if windows_drive { path[1..].to_string() } else { path })
}

/// The `file:` URI of a path (made absolute against the working folder when relative).
pub fn path_to_uri(path: &str) -> Uri {
    let absolute = if path.starts_with('/') || path.get(1..2) == Some(":") {
        path.to_string()
    } else {
        let cwd = std::env::current_dir().map(|d| d.to_string_lossy().replace('\\', "/"));
        mocu_language::source::join(&cwd.unwrap_or_default(), path)
    };
    let mut s = String::from("file://");
    if !absolute.starts_with('/') {
        s.push('/');
    }
    for b in absolute.bytes() {
        if b.is_ascii_alphanumeric() || b"/-._~:".contains(&b) {
            s.push(b as char);
        } else {
            s.push_str(&format!("%{b:02X}"));
        }
    }
    Uri::from_str(&s).unwrap_or_else(|_| Uri::from_str("file:///").expect("a valid URI"))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn positions_count_utf16_units_and_round_trip() {
        let text = "let a = 1\nlet é😀 = \"x\"\n";
        let ix = LineIndex::new(text);
        let x = text.find('x').unwrap();
        assert_eq!(ix.position(x), Position::new(1, 11));
        assert_eq!(ix.offset(Position::new(1, 11)), x);
        assert_eq!(ix.offset(Position::new(0, 99)), 9);
        assert_eq!(ix.offset(Position::new(9, 0)), text.len());
    }

    #[test]
    fn file_uris_and_paths_convert_both_ways() {
        let uri = path_to_uri("/tmp/my layouts/usv.mocu");
        assert_eq!(uri.as_str(), "file:///tmp/my%20layouts/usv.mocu");
        assert_eq!(uri_to_path(&uri).as_deref(), Some("/tmp/my layouts/usv.mocu"));
        let other = Uri::from_str("untitled:Untitled-1").unwrap();
        assert_eq!(uri_to_path(&other), None);
    }
}
