//! Code actions: the fixes the checker's help names. "did you mean `x`?" replaces the
//! misspelt name with `x`; "add `use \"FILE\"`" adds the `use` at the top of the file.

use crate::text::LineIndex;
use lsp_types::{
    CodeAction, CodeActionKind, CodeActionOrCommand, Diagnostic, Position, Range, TextEdit, Uri,
    WorkspaceEdit,
};
use std::collections::HashMap;

// lsp-types keys a WorkspaceEdit's changes by `Uri`.
#[allow(clippy::mutable_key_type)]
/// The fixes for `diagnostics` (as the server published them) in the document `text`.
pub fn code_actions(uri: &Uri, text: &str, diagnostics: &[Diagnostic]) -> Vec<CodeActionOrCommand> {
    let lines = LineIndex::new(text);
    let mut out = Vec::new();
    for d in diagnostics {
        let Some(help) = d.data.as_ref().and_then(|v| v.get("help")).and_then(|h| h.as_str())
        else {
            continue;
        };
        let (title, edit) = if let Some(best) = quoted_after(help, "did you mean `") {
            let (s, e) = (lines.offset(d.range.start), lines.offset(d.range.end));
            let Some((ws, we)) = misspelt_word(text, s, e, &d.message) else { continue };
            (format!("Change to `{best}`"), TextEdit { range: lines.range(ws, we), new_text: best })
        } else if let Some(file) = quoted_after(help, "add `use \"") {
            let file = file.trim_end_matches('"').to_string();
            let at = Range::new(Position::new(0, 0), Position::new(0, 0));
            (
                format!("Add `use \"{file}\"`"),
                TextEdit { range: at, new_text: format!("use \"{file}\"\n") },
            )
        } else {
            continue;
        };
        // "did you mean `Dial` (in stdlib/gauges.mocu: add `use …`)?" offers both.
        let extra = quoted_after(help, "add `use \"")
            .filter(|_| help.starts_with("did you mean"))
            .map(|f| {
                let f = f.trim_end_matches('"').to_string();
                TextEdit {
                    range: Range::new(Position::new(0, 0), Position::new(0, 0)),
                    new_text: format!("use \"{f}\"\n"),
                }
            });
        let mut edits = vec![edit];
        edits.extend(extra);
        out.push(CodeActionOrCommand::CodeAction(CodeAction {
            title,
            kind: Some(CodeActionKind::QUICKFIX),
            diagnostics: Some(vec![d.clone()]),
            edit: Some(WorkspaceEdit {
                changes: Some(HashMap::from([(uri.clone(), edits)])),
                ..WorkspaceEdit::default()
            }),
            is_preferred: Some(true),
            ..CodeAction::default()
        }));
    }
    out
}

/// The text between `prefix` and the next backtick.
fn quoted_after(s: &str, prefix: &str) -> Option<String> {
    let rest = &s[s.find(prefix)? + prefix.len()..];
    Some(rest[..rest.find('`')?].to_string())
}

/// The misspelt word in `text[s..e]`: the range itself when it is one word, else the word of
/// it that the message quotes (`unknown property \`sped\``), else its last word.
fn misspelt_word(text: &str, s: usize, e: usize, message: &str) -> Option<(usize, usize)> {
    let range = text.get(s..e)?;
    let is_word = |c: char| c.is_ascii_alphanumeric() || c == '_';
    let words: Vec<(usize, &str)> = range
        .split(|c: char| !is_word(c))
        .scan(0, |pos, w| {
            let at = *pos;
            *pos += w.len() + 1;
            Some((at, w))
        })
        .filter(|(_, w)| !w.is_empty())
        .collect();
    let quoted: Vec<&str> = message.split('`').skip(1).step_by(2).collect();
    let pick = words.iter().rev().find(|(_, w)| quoted.contains(w)).or(words.last())?;
    Some((s + pick.0, s + pick.0 + pick.1.len()))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_quoted_misspelt_segment_of_a_path_is_the_one_replaced() {
        let text = "let a = usv.nav.sped\n";
        let s = text.find("usv").unwrap();
        let (ws, we) = misspelt_word(text, s, s + 12, "`usv` has no property `sped`").unwrap();
        assert_eq!(&text[ws..we], "sped");
    }
}
