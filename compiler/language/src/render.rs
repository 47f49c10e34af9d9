//! The three output forms of `mocu check`: human (rustc-like), JSON and SARIF 2.1.0.
//!
//! Human snippets put the carets under the right characters whatever the line holds: tabs are
//! shown as four spaces and wide characters (CJK, emoji) take two columns. A line longer than
//! [`MAX_SNIPPET`] columns is cut around the error. Colour is the caller's choice
//! ([`HumanOptions`]); the compiler does no I/O and does not look at the terminal.

use crate::diagnostics::{Diagnostic, Severity};
use crate::source::{SourceFile, SourceMap, Span};
use std::fmt::Write;
use unicode_width::UnicodeWidthChar;

/// The widest source text shown in a snippet, in terminal columns.
pub const MAX_SNIPPET: usize = 100;

/// Where each code is documented: `{DOCS_URI}#e0101`. Stable: the docs file on the main branch.
pub const DOCS_URI: &str = "https://github.com/mocu/mocu/blob/main/docs/diagnostics.md";

/// How to print the human form.
#[derive(Clone, Copy, Debug, Default)]
pub struct HumanOptions {
    /// ANSI colours (the CLI sets it on a terminal, unless `NO_COLOR` is set).
    pub colour: bool,
    /// Warnings were denied (`--deny warnings`): the summary says they fail the check.
    pub deny_warnings: bool,
}

struct Paint {
    on: bool,
}

impl Paint {
    fn wrap(&self, code: &str, text: &str) -> String {
        if self.on { format!("\x1b[{code}m{text}\x1b[0m") } else { text.to_string() }
    }
    fn severity(&self, s: Severity, text: &str) -> String {
        self.wrap(if s == Severity::Error { "1;31" } else { "1;33" }, text)
    }
    fn blue(&self, text: &str) -> String {
        self.wrap("1;34", text)
    }
    fn bold(&self, text: &str) -> String {
        self.wrap("1", text)
    }
}

/// Human output without colour (tests, the reload banner, logs).
pub fn human(sources: &SourceMap, diags: &[Diagnostic]) -> String {
    human_with(sources, diags, HumanOptions::default())
}

/// Human output: header, `-->` location, the source line, an underline, related places, then
/// `= help:`, and a summary line.
pub fn human_with(sources: &SourceMap, diags: &[Diagnostic], options: HumanOptions) -> String {
    let paint = Paint { on: options.colour };
    let mut out = String::new();
    for d in diags {
        let file = sources.get(d.span.file);
        let start = file.line_col(d.span.start as usize);
        let gutter = std::iter::once(start.line)
            .chain(
                d.related.iter().map(|(s, _)| sources.get(s.file).line_col(s.start as usize).line),
            )
            .max()
            .unwrap_or(1)
            .to_string()
            .len();
        let pad = " ".repeat(gutter);
        let header = format!("{}[{}]", d.severity.as_str(), d.code);
        let _ = writeln!(
            out,
            "{}{}",
            paint.severity(d.severity, &header),
            paint.bold(&format!(": {}", d.message))
        );
        let _ = writeln!(
            out,
            "{pad}{} {}:{}:{}",
            paint.blue("-->"),
            file.path,
            start.line,
            start.column
        );
        let mark = if d.severity == Severity::Error { '^' } else { '~' };
        let under = |s: &str| paint.severity(d.severity, s);
        snippet(&mut out, file, d.span, gutter, mark, d.label.as_deref(), &under, &paint);
        for (span, note) in &d.related {
            let rf = sources.get(span.file);
            let at = rf.line_col(span.start as usize);
            let _ =
                writeln!(out, "{pad}{} {}:{}:{}", paint.blue(":::"), rf.path, at.line, at.column);
            snippet(&mut out, rf, *span, gutter, '-', Some(note), &|s: &str| paint.blue(s), &paint);
        }
        if let Some(help) = &d.help {
            let _ = writeln!(out, "{pad} {} {help}", paint.bold("= help:"));
        }
        out.push('\n');
    }
    let errors = diags.iter().filter(|d| d.severity == Severity::Error).count();
    let warnings = diags.len() - errors;
    if errors + warnings > 0 {
        let denied = if options.deny_warnings && warnings > 0 {
            " (warnings denied by `--deny warnings`: they fail the check)"
        } else {
            ""
        };
        let _ = writeln!(out, "{errors} error(s), {warnings} warning(s){denied}");
    }
    out
}

/// One source line with the underline of `span` (its part on that line).
#[allow(clippy::too_many_arguments)]
fn snippet(
    out: &mut String,
    file: &SourceFile,
    span: Span,
    gutter: usize,
    mark: char,
    label: Option<&str>,
    colour: &dyn Fn(&str) -> String,
    paint: &Paint,
) {
    let start = file.line_col(span.start as usize);
    let end = file.line_col(span.end as usize);
    let line = file.line_text(start.line);
    let pad = " ".repeat(gutter);
    let bar = paint.blue("|");
    let chars: Vec<char> = line.chars().collect();
    let first = (start.column - 1).min(chars.len());
    let last = if end.line == start.line { (end.column - 1).min(chars.len()) } else { chars.len() };
    let last = last.max(first);
    // The window of the line shown: all of it, or a cut around the error.
    let (from, to) = window(&chars, first, last);
    let mut shown = String::new();
    let mut lead = 0usize;
    let mut width = 0usize;
    if from > 0 {
        shown.push('…');
        lead += 1;
    }
    for (k, &c) in chars.iter().enumerate().take(to).skip(from) {
        let (text, w) = display(c);
        shown.push_str(&text);
        if k < first {
            lead += w;
        } else if k < last {
            width += w;
        }
    }
    if to < chars.len() {
        shown.push('…');
    }
    let _ = writeln!(out, "{pad} {bar}");
    let _ = writeln!(out, "{} {bar} {shown}", paint.blue(&format!("{:>gutter$}", start.line)));
    let marks: String = std::iter::repeat_n(mark, width.max(1)).collect();
    let label = label.map(|l| format!(" {l}")).unwrap_or_default();
    let _ = writeln!(out, "{pad} {bar} {}{}", " ".repeat(lead), colour(&format!("{marks}{label}")));
}

/// How a character is shown and how many columns it takes: tabs as four spaces, control
/// characters as `�`, wide characters as two.
fn display(c: char) -> (String, usize) {
    match c {
        '\t' => ("    ".to_string(), 4),
        c if c.is_control() => ("\u{FFFD}".to_string(), 1),
        c => (c.to_string(), c.width().unwrap_or(0)),
    }
}

/// The character range of a line to show: the whole line when it fits in [`MAX_SNIPPET`]
/// columns, else a window that holds the start of the error.
fn window(chars: &[char], first: usize, last: usize) -> (usize, usize) {
    let widths: Vec<usize> = chars.iter().map(|&c| display(c).1).collect();
    let total: usize = widths.iter().sum();
    if total <= MAX_SNIPPET {
        return (0, chars.len());
    }
    // Up to a third of the room before the error, the rest for it and after it.
    let mut from = first;
    let mut used = 0;
    while from > 0 && used + widths[from - 1] <= MAX_SNIPPET / 3 {
        from -= 1;
        used += widths[from];
    }
    let mut to = first;
    while to < chars.len() && used + widths[to] <= MAX_SNIPPET {
        used += widths[to];
        to += 1;
    }
    let _ = last;
    (from, to.max((first + 1).min(chars.len())))
}

/// One JSON array of `{"file","line","column","end_line","end_column","severity","code","message"}`
/// objects, with `"help"` when known.
pub fn json(sources: &SourceMap, diags: &[Diagnostic]) -> String {
    let located: Vec<_> = diags.iter().map(|d| d.locate(sources)).collect();
    serde_json::to_string_pretty(&located).unwrap_or_else(|_| "[]".to_string())
}

/// What SARIF needs beyond the diagnostics: where relative paths are from, and the files the
/// tool could not read (reported in `invocations`, the run then marked unsuccessful).
#[derive(Clone, Debug, Default)]
pub struct SarifOptions {
    /// The absolute folder relative paths are resolved against (the working directory).
    pub base: Option<String>,
    /// Failures that are not findings: unreadable files, bad arguments.
    pub failures: Vec<String>,
}

/// SARIF 2.1.0 with default options (paths as given, no failures).
pub fn sarif(sources: &SourceMap, diags: &[Diagnostic]) -> String {
    sarif_with(sources, diags, &SarifOptions::default())
}

/// SARIF 2.1.0: one run, the tool's rules (every code that occurs, each with an absolute
/// `helpUri`), one result per finding with a `file://` URI, columns counted in Unicode code
/// points, and one invocation saying whether the tool ran to the end.
pub fn sarif_with(sources: &SourceMap, diags: &[Diagnostic], options: &SarifOptions) -> String {
    let mut codes: Vec<&str> = diags.iter().map(|d| d.code).collect();
    codes.sort_unstable();
    codes.dedup();
    let rules: Vec<_> = codes
        .iter()
        .map(|c| {
            serde_json::json!({
                "id": c,
                "shortDescription": { "text": crate::codes::describe(c) },
                "helpUri": format!("{DOCS_URI}#{}", c.to_lowercase()),
            })
        })
        .collect();
    let location = |span: Span| {
        let file = sources.get(span.file);
        let s = file.line_col(span.start as usize);
        let e = file.line_col(span.end as usize);
        serde_json::json!({
            "physicalLocation": {
                "artifactLocation": { "uri": file_uri(&file.path, options.base.as_deref()) },
                "region": {
                    "startLine": s.line, "startColumn": s.column,
                    "endLine": e.line, "endColumn": e.column,
                }
            }
        })
    };
    let results: Vec<_> = diags
        .iter()
        .map(|d| {
            let mut text = d.message.clone();
            if let Some(h) = &d.help {
                text.push_str(" (help: ");
                text.push_str(h);
                text.push(')');
            }
            let index = codes.iter().position(|c| *c == d.code).unwrap_or(0);
            let mut r = serde_json::json!({
                "ruleId": d.code,
                "ruleIndex": index,
                "level": match d.severity { Severity::Error => "error", Severity::Warning => "warning" },
                "message": { "text": text },
                "locations": [location(d.span)],
            });
            if !d.related.is_empty() {
                r["relatedLocations"] = d
                    .related
                    .iter()
                    .enumerate()
                    .map(|(i, (span, note))| {
                        let mut l = location(*span);
                        l["id"] = serde_json::json!(i);
                        l["message"] = serde_json::json!({ "text": note });
                        l
                    })
                    .collect();
            }
            r
        })
        .collect();
    let notifications: Vec<_> = options
        .failures
        .iter()
        .map(|f| serde_json::json!({ "level": "error", "message": { "text": f } }))
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
            "invocations": [{
                "executionSuccessful": options.failures.is_empty(),
                "toolExecutionNotifications": notifications,
            }],
            "columnKind": "unicodeCodePoints",
            "results": results,
        }]
    });
    serde_json::to_string_pretty(&doc).unwrap_or_else(|_| "{}".to_string())
}

/// An absolute, percent-encoded `file://` URI for a path (relative ones joined to `base`;
/// without a base, a relative one stays a percent-encoded relative reference).
pub fn file_uri(path: &str, base: Option<&str>) -> String {
    let path = path.replace('\\', "/");
    let absolute = match base {
        Some(b) if !path.starts_with('/') && !is_drive(&path) => {
            crate::source::join(&b.replace('\\', "/"), &path)
        }
        _ => path,
    };
    let rooted = absolute.starts_with('/') || is_drive(&absolute);
    let mut out = String::from(if rooted { "file://" } else { "" });
    if is_drive(&absolute) {
        out.push('/');
    }
    for b in absolute.bytes() {
        if b.is_ascii_alphanumeric() || b"-._~/".contains(&b) || (b == b':' && is_drive(&absolute))
        {
            out.push(b as char);
        } else {
            let _ = write!(out, "%{b:02X}");
        }
    }
    out
}

/// `C:/…`: a Windows drive path.
fn is_drive(p: &str) -> bool {
    let b = p.as_bytes();
    b.len() >= 2 && b[0].is_ascii_alphabetic() && b[1] == b':'
}
