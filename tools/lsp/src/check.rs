//! Diagnostics as you type: the same check as `mocu check` (`check_path`: the project found
//! by walking up to the nearest `project.toml`, its schemas, the `use`d files), run on a worker
//! thread over the open documents' text, published per file.
//!
//! Stale work is dropped, not queued: the worker takes the newest request for each document
//! when it is free, so a burst of keystrokes costs one check after the check that was
//! running, and a result whose document changed while it was computed is not published.

use crate::overlay::OverlayLoader;
use crate::text::{LineIndex, path_to_uri};
use crossbeam_channel::{Receiver, Sender};
use lsp_server::{Message, Notification};
use lsp_types::notification::{Notification as _, PublishDiagnostics};
use lsp_types::{
    DiagnosticRelatedInformation, DiagnosticSeverity, Location, NumberOrString,
    PublishDiagnosticsParams,
};
use mocu_language::{Diagnostics, FileKind, Schema, Severity, SourceMap};
use std::collections::{BTreeMap, BTreeSet, HashMap};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

/// What one check of a document found.
#[derive(Debug, Default)]
pub struct Analysis {
    /// The document's version the check read.
    pub version: i32,
    /// Diagnostics by file path, for every file the check read (empty: nothing to show).
    pub by_file: BTreeMap<String, Vec<lsp_types::Diagnostic>>,
    /// The checked type of each top-level `let`, by (path, byte offset of its value).
    pub let_types: HashMap<(String, u32), String>,
    /// The schema of the document's project (empty when it has none).
    pub schema: Schema,
    /// How long the check took.
    pub elapsed: Duration,
}

/// What a check leaves behind: its program and sources, handed to the caller to drop after
/// publishing (freeing the program of a 10,000-line layout takes a while).
pub struct Leftovers {
    _bundle: Option<mocu_language::Bundle>,
    _sources: SourceMap,
}

/// Checks `path` (its text from `loader`) as `mocu check PATH` does.
pub fn analyse(path: &str, version: i32, loader: &OverlayLoader) -> (Analysis, Leftovers) {
    let started = Instant::now();
    let mut sources = SourceMap::new();
    let mut diags = Diagnostics::new();
    let mut out = Analysis { version, ..Analysis::default() };
    let Ok(text) = mocu_language::SourceLoader::read(loader, path) else {
        return (out, Leftovers { _bundle: None, _sources: sources });
    };
    let bundle = if mocu_language::file_kind(path, &text) == FileKind::Layout {
        let project = mocu_language::project_of(path, None, loader, &mut sources, &mut diags);
        if let Some(p) = &project {
            out.schema = p.schema.clone();
        }
        Some(mocu_language::check_layout(
            path,
            text,
            loader,
            project.as_ref(),
            &mut sources,
            &mut diags,
        ))
    } else {
        mocu_language::check_path(path, text, loader, &mut sources, &mut diags)
    };
    diags.sort();
    for (_, f) in sources.files() {
        out.by_file.entry(f.path.clone()).or_default();
    }
    out.by_file.entry(path.to_string()).or_default();
    for d in diags.iter() {
        let file = sources.get(d.span.file);
        let lsp = to_lsp(d, &sources);
        out.by_file.entry(file.path.clone()).or_default().push(lsp);
    }
    for layout in bundle.iter().flat_map(|b| &b.layouts) {
        for l in &layout.program.lets.0 {
            let file = sources.get(l.value.span.file);
            out.let_types.insert((file.path.clone(), l.value.span.start), l.value.ty.to_string());
        }
    }
    out.elapsed = started.elapsed();
    (out, Leftovers { _bundle: bundle, _sources: sources })
}

/// One diagnostic as LSP shows it: the message, then its label and help as `mocu check`
/// prints them; the help also goes in `data` for the code actions.
fn to_lsp(d: &mocu_language::Diagnostic, sources: &SourceMap) -> lsp_types::Diagnostic {
    let file = sources.get(d.span.file);
    let range = LineIndex::new(&file.text).range(d.span.start as usize, d.span.end as usize);
    let mut message = d.message.clone();
    if let Some(label) = &d.label {
        message.push_str(&format!(" ({label})"));
    }
    if let Some(help) = &d.help {
        message.push_str(&format!("\nhelp: {help}"));
    }
    let related = d
        .related
        .iter()
        .map(|(span, note)| {
            let f = sources.get(span.file);
            DiagnosticRelatedInformation {
                location: Location {
                    uri: path_to_uri(&f.path),
                    range: LineIndex::new(&f.text).range(span.start as usize, span.end as usize),
                },
                message: note.clone(),
            }
        })
        .collect::<Vec<_>>();
    lsp_types::Diagnostic {
        range,
        severity: Some(match d.severity {
            Severity::Error => DiagnosticSeverity::ERROR,
            Severity::Warning => DiagnosticSeverity::WARNING,
        }),
        code: Some(NumberOrString::String(d.code.to_string())),
        source: Some("mocu".into()),
        message,
        related_information: (!related.is_empty()).then_some(related),
        data: d.help.as_ref().map(|h| serde_json::json!({ "help": h })),
        ..lsp_types::Diagnostic::default()
    }
}

/// A request to check one document.
pub struct Job {
    pub path: String,
    pub version: i32,
    pub loader: OverlayLoader,
}

/// The latest analysis of each document, shared by the worker and the request handlers.
pub type Analyses = Arc<Mutex<HashMap<String, Arc<Analysis>>>>;

/// Starts the checking worker: it publishes on `out` and records each analysis in `store`.
/// It ends when `jobs` is closed.
pub fn spawn_worker(
    jobs: Receiver<Job>,
    out: Sender<Message>,
    store: Analyses,
) -> std::io::Result<std::thread::JoinHandle<()>> {
    std::thread::Builder::new()
        .name("mocu-lsp-check".into())
        .stack_size(mocu_language::COMPILER_STACK)
        .spawn(move || worker(&jobs, &out, &store))
}

fn worker(jobs: &Receiver<Job>, out: &Sender<Message>, store: &Analyses) {
    // What each document's last published check showed, to clear files it no longer reads.
    let mut shown: HashMap<String, BTreeSet<String>> = HashMap::new();
    let mut pending: Vec<Job> = Vec::new();
    loop {
        if pending.is_empty() {
            match jobs.recv() {
                Ok(j) => pending.push(j),
                Err(_) => return,
            }
        }
        take_newest(jobs, &mut pending);
        let job = pending.remove(0);
        // A checker bug on one text must not end the diagnostics of the session.
        let checked = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
            analyse(&job.path, job.version, &job.loader)
        }));
        let Ok((analysis, leftovers)) = checked else { continue };
        // A newer edit of this document arrived while checking: this result is stale.
        take_newest(jobs, &mut pending);
        if pending.iter().any(|j| j.path == job.path) {
            continue;
        }
        let files: BTreeSet<String> = analysis.by_file.keys().cloned().collect();
        let gone: Vec<String> = shown
            .get(&job.path)
            .map(|old| old.difference(&files).cloned().collect())
            .unwrap_or_default();
        for f in gone {
            publish(out, &f, Vec::new(), None);
        }
        for (f, list) in &analysis.by_file {
            let version = (*f == job.path).then_some(job.version);
            publish(out, f, list.clone(), version);
        }
        shown.insert(job.path.clone(), files);
        drop(leftovers);
        if let Ok(mut s) = store.lock() {
            s.insert(job.path, Arc::new(analysis));
        }
    }
}

/// Adds every queued job to `pending`, keeping only the newest per document.
fn take_newest(jobs: &Receiver<Job>, pending: &mut Vec<Job>) {
    while let Ok(j) = jobs.try_recv() {
        pending.retain(|p| p.path != j.path);
        pending.push(j);
    }
}

fn publish(
    out: &Sender<Message>,
    path: &str,
    diagnostics: Vec<lsp_types::Diagnostic>,
    version: Option<i32>,
) {
    let params = PublishDiagnosticsParams { uri: path_to_uri(path), diagnostics, version };
    let _ = out.send(Message::Notification(Notification::new(
        PublishDiagnostics::METHOD.to_string(),
        params,
    )));
}

#[cfg(test)]
mod tests {
    use super::*;

    fn job(version: i32, text: &str) -> Job {
        let mut loader = OverlayLoader::default();
        loader.texts.insert("/virtual/a.mocu".into(), text.into());
        Job { path: "/virtual/a.mocu".into(), version, loader }
    }

    /// The versions published for the document, in order.
    fn published(rx: &Receiver<Message>) -> Vec<(Option<i32>, usize)> {
        rx.try_iter()
            .filter_map(|m| match m {
                Message::Notification(n) => {
                    serde_json::from_value::<PublishDiagnosticsParams>(n.params).ok()
                }
                _ => None,
            })
            .filter(|p| p.uri.as_str() == "file:///virtual/a.mocu")
            .map(|p| (p.version, p.diagnostics.len()))
            .collect()
    }

    #[test]
    fn queued_edits_are_checked_once_at_their_newest_version() {
        let (jobs, rx) = crossbeam_channel::unbounded();
        let (out, published_rx) = crossbeam_channel::unbounded();
        let store = Analyses::default();
        jobs.send(job(1, "let a = \n")).unwrap();
        jobs.send(job(2, "let a = b\n")).unwrap();
        jobs.send(job(3, "let a = 1\n")).unwrap();
        drop(jobs);
        worker(&rx, &out, &store);
        assert_eq!(published(&published_rx), vec![(Some(3), 0)]);
        assert_eq!(store.lock().unwrap()["/virtual/a.mocu"].version, 3);
    }

    #[test]
    fn a_diagnostic_carries_mocu_checks_code_range_and_message() {
        let (a, _) = analyse("/virtual/a.mocu", 1, &job(1, "let a = 1\nlet b = a + c\n").loader);
        let d = &a.by_file["/virtual/a.mocu"][0];
        assert_eq!(d.code, Some(NumberOrString::String("E0204".into())));
        assert_eq!((d.range.start.line, d.range.start.character), (1, 12));
        assert!(d.message.starts_with("unknown name `c`"), "{}", d.message);
    }
}
