//! The three output forms of `mocu check`: human (rustc-like), JSON and SARIF 2.1.0.

use crate::diagnostics::{Diagnostic, Severity};
use crate::source::SourceMap;
use std::fmt::Write;

/// Human output: header, `-->` location, the source line, an underline, then `= help:`.
pub fn human(sources: &SourceMap, diags: &[Diagnostic]) -> String {
    let mut out = String::new();
    for d in diags {
        let file = sources.get(d.span.file);
        let start = file.line_col(d.span.start as usize);
        let end = file.line_col(d.span.end as usize);
        let line = file.line_text(start.line);
        let gutter = start.line.to_string().len();
        let pad = " ".repeat(gutter);
        let _ = writeln!(out, "{}[{}]: {}", d.severity.as_str(), d.code, d.message);
        let _ = writeln!(out, "{pad}--> {}:{}:{}", file.path, start.line, start.column);
        let _ = writeln!(out, "{pad} |");
        let shown: String = line.replace('\t', " ");
        let _ = writeln!(out, "{} | {}", start.line, shown);
        let width = if end.line == start.line {
            end.column.saturating_sub(start.column).max(1)
        } else {
            (line.chars().count() + 1).saturating_sub(start.column).max(1)
        };
        let mark = if d.severity == Severity::Error { "^" } else { "~" };
        let label = d.label.as_deref().map(|l| format!(" {l}")).unwrap_or_default();
        let _ = writeln!(
            out,
            "{pad} | {}{}{}",
            " ".repeat(start.column - 1),
            mark.repeat(width),
            label
        );
        if let Some(help) = &d.help {
            let _ = writeln!(out, "{pad} = help: {help}");
        }
        out.push('\n');
    }
    let errors = diags.iter().filter(|d| d.severity == Severity::Error).count();
    let warnings = diags.len() - errors;
    if errors + warnings > 0 {
        let _ = writeln!(out, "{errors} error(s), {warnings} warning(s)");
    }
    out
}

/// One JSON array of `{"file","line","column","end_line","end_column","severity","code","message"}`
/// objects, with `"help"` when known.
pub fn json(sources: &SourceMap, diags: &[Diagnostic]) -> String {
    let located: Vec<_> = diags.iter().map(|d| d.locate(sources)).collect();
    serde_json::to_string_pretty(&located).unwrap_or_else(|_| "[]".to_string())
}

/// SARIF 2.1.0: one run, the tool's rules (every code that occurs) and one result per finding.
pub fn sarif(sources: &SourceMap, diags: &[Diagnostic]) -> String {
    let mut codes: Vec<&str> = diags.iter().map(|d| d.code).collect();
    codes.sort_unstable();
    codes.dedup();
    let rules: Vec<_> = codes
        .iter()
        .map(|c| {
            serde_json::json!({
                "id": c,
                "shortDescription": { "text": crate::codes::describe(c) },
                "helpUri": format!("docs/diagnostics.md#{}", c.to_lowercase()),
            })
        })
        .collect();
    let results: Vec<_> = diags
        .iter()
        .map(|d| {
            let l = d.locate(sources);
            let mut text = l.message.clone();
            if let Some(h) = &l.help {
                text.push_str(" (help: ");
                text.push_str(h);
                text.push(')');
            }
            serde_json::json!({
                "ruleId": l.code,
                "level": match l.severity { Severity::Error => "error", Severity::Warning => "warning" },
                "message": { "text": text },
                "locations": [{
                    "physicalLocation": {
                        "artifactLocation": { "uri": l.file },
                        "region": {
                            "startLine": l.line, "startColumn": l.column,
                            "endLine": l.end_line, "endColumn": l.end_column,
                        }
                    }
                }]
            })
        })
        .collect();
    let doc = serde_json::json!({
        "version": "2.1.0",
        "$schema": "https://json.schemastore.org/sarif-2.1.0.json",
        "runs": [{
            "tool": { "driver": {
                "name": "mocu",
                "version": env!("CARGO_PKG_VERSION"),
                "informationUri": "https://github.com/mocu/mocu",
                "rules": rules,
            }},
            "results": results,
        }]
    });
    serde_json::to_string_pretty(&doc).unwrap_or_else(|_| "{}".to_string())
}
