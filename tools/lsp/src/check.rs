//! Diagnostics as you type: the same check as `mocu check` (`check_path`: the project found
//! by walking up to the nearest `project.toml`, its schemas, the `use`d files), run on a worker
//! thread over the open documents' text, published per file.
//!
//! A keystroke costs the check of what changed, not of the file: the worker parses through
//! an [`ItemCache`] (the trees of the items and `use`d files that did not change are reused),
//! a burst of edits is checked once, after its last edit ([`crate::schedule`]), a result whose
//! document changed while it was computed is dropped, and a file's diagnostics are published
//! only when they differ from what the editor shows.

use crate::overlay::OverlayLoader;
use crate::schedule::{Queue, Timing};
use crate::text::{LineIndex, path_to_uri};
use crossbeam_channel::{Receiver, RecvTimeoutError, Sender};
use lsp_server::{Message, Notification};
use lsp_types::notification::{Notification as _, PublishDiagnostics};
use lsp_types::{
    DiagnosticRelatedInformation, DiagnosticSeverity, Location, NumberOrString,
    PublishDiagnosticsParams,
};
use mocu_language::incremental::ItemCache;
use mocu_language::{Diagnostics, FileId, FileKind, Schema, Severity, SourceMap};
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
    _program: Option<mocu_language::Program>,
    _bundle: Option<mocu_language::Bundle>,
    _sources: SourceMap,
}

/// Checks `path` (its text from `loader`) as `mocu check PATH` does; a layout's files are
/// parsed through `cache`.
pub fn analyse(
    path: &str,
    version: i32,
    loader: &OverlayLoader,
    cache: &mut ItemCache,
) -> (Analysis, Leftovers) {
    let started = Instant::now();
    let mut sources = SourceMap::new();
    let mut diags = Diagnostics::new();
    let mut out = Analysis { version, ..Analysis::default() };
    let mut left = Leftovers { _program: None, _bundle: None, _sources: SourceMap::new() };
    let Ok(text) = mocu_language::SourceLoader::read(loader, path) else {
        return (out, left);
    };
    if mocu_language::file_kind(path, &text) == FileKind::Layout {
        // `check_layout`, its parse through the cache.
        let project = mocu_language::project_of(path, None, loader, &mut sources, &mut diags);
        let default = mocu_language::project::Project::default();
        let p = project.as_ref().unwrap_or(&default);
        out.schema = p.schema.clone();
        let program = cache.compile_layout(
            path,
            text,
            loader,
            &p.schema,
            &p.config,
            &mut sources,
            &mut diags,
        );
        for l in &program.lets.0 {
            let file = sources.get(l.value.span.file);
            out.let_types.insert((file.path.clone(), l.value.span.start), l.value.ty.to_string());
        }
        left._program = Some(program);
    } else {
        left._bundle = mocu_language::check_path(path, text, loader, &mut sources, &mut diags);
    }
    diags.sort();
    for (_, f) in sources.files() {
        out.by_file.entry(f.path.clone()).or_default();
    }
    out.by_file.entry(path.to_string()).or_default();
    // One line index per file, not per diagnostic: a finding in a 10,000-line file would
    // otherwise cost a scan of the file.
    let mut lines: HashMap<FileId, LineIndex> = HashMap::new();
    for d in diags.iter() {
        let file = sources.get(d.span.file);
        let lsp = to_lsp(d, &sources, &mut lines);
        out.by_file.entry(file.path.clone()).or_default().push(lsp);
    }
    drop(lines);
    out.elapsed = started.elapsed();
    left._sources = sources;
    (out, left)
}

/// One diagnostic as LSP shows it: the message, then its label and help as `mocu check`
/// prints them; the help also goes in `data` for the code actions.
fn to_lsp<'s>(
    d: &mocu_language::Diagnostic,
    sources: &'s SourceMap,
    lines: &mut HashMap<FileId, LineIndex<'s>>,
) -> lsp_types::Diagnostic {
    let mut range_of = |span: mocu_language::Span| {
        lines
            .entry(span.file)
            .or_insert_with(|| LineIndex::new(&sources.get(span.file).text))
            .range(span.start as usize, span.end as usize)
    };
    let range = range_of(d.span);
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
                location: Location { uri: path_to_uri(&f.path), range: range_of(*span) },
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
    /// The document was just opened: its diagnostics are published even if unchanged.
    pub opened: bool,
}

/// What the worker is asked.
pub enum Work {
    Check(Job),
    /// The document was closed: its diagnostics are cleared, its waiting check forgotten.
    Close(String),
}

/// The latest analysis of each document, shared by the worker and the request handlers.
pub type Analyses = Arc<Mutex<HashMap<String, Arc<Analysis>>>>;

/// Starts the checking worker: it publishes on `out` and records each analysis in `store`.
/// It ends when `work` is closed.
pub fn spawn_worker(
    work: Receiver<Work>,
    out: Sender<Message>,
    store: Analyses,
    timing: Timing,
) -> std::io::Result<std::thread::JoinHandle<()>> {
    std::thread::Builder::new()
        .name("mocu-lsp-check".into())
        .stack_size(mocu_language::COMPILER_STACK)
        .spawn(move || Worker::new(out, store, timing).run(&work))
}

/// Starts the thread that frees what checks leave behind (a 10,000-line layout's program
/// takes tens of milliseconds to free: the next check need not wait for it). It ends when
/// `left` is closed.
fn spawn_freer() -> Option<Sender<Leftovers>> {
    let (tx, rx) = crossbeam_channel::unbounded::<Leftovers>();
    std::thread::Builder::new()
        .name("mocu-lsp-free".into())
        .spawn(move || rx.iter().for_each(drop))
        .ok()?;
    Some(tx)
}

/// The checking thread's state.
struct Worker {
    out: Sender<Message>,
    store: Analyses,
    queue: Queue<Job>,
    cache: ItemCache,
    /// The files each document's last published check read.
    read_by: HashMap<String, BTreeSet<String>>,
    /// What the editor shows for each file: the last list published.
    shown: HashMap<String, Vec<lsp_types::Diagnostic>>,
    /// Documents opened and not yet published.
    opened: BTreeSet<String>,
    /// Where leftovers go to be freed (`None`: freed here).
    freer: Option<Sender<Leftovers>>,
}

impl Worker {
    fn new(out: Sender<Message>, store: Analyses, timing: Timing) -> Worker {
        Worker {
            out,
            store,
            queue: Queue::new(timing),
            cache: ItemCache::new(),
            read_by: HashMap::new(),
            shown: HashMap::new(),
            opened: BTreeSet::new(),
            freer: spawn_freer(),
        }
    }

    fn run(mut self, work: &Receiver<Work>) {
        loop {
            if let Some(job) = self.queue.take_due(Instant::now()) {
                self.check(job, work);
                continue;
            }
            let next = match self.queue.due_at() {
                None => work.recv().map_err(|_| RecvTimeoutError::Disconnected),
                Some(at) => work.recv_deadline(at),
            };
            match next {
                Ok(w) => self.take(w),
                Err(RecvTimeoutError::Timeout) => {}
                Err(RecvTimeoutError::Disconnected) => {
                    while let Some(job) = self.queue.take_any() {
                        self.check(job, work);
                    }
                    return;
                }
            }
        }
    }

    fn take(&mut self, w: Work) {
        match w {
            Work::Check(job) => {
                if job.opened {
                    self.opened.insert(job.path.clone());
                }
                let path = job.path.clone();
                self.queue.push(&path, job, Instant::now());
            }
            Work::Close(path) => {
                self.queue.remove(&path);
                self.opened.remove(&path);
                self.read_by.remove(&path);
                if let Ok(mut s) = self.store.lock() {
                    s.remove(&path);
                }
                self.publish(&path, Vec::new(), None, true);
            }
        }
    }

    fn check(&mut self, job: Job, work: &Receiver<Work>) {
        // A checker bug on one text must not end the diagnostics of the session (the cache
        // is rebuilt: a panic may have left it half-way).
        let checked = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
            analyse(&job.path, job.version, &job.loader, &mut self.cache)
        }));
        let Ok((analysis, leftovers)) = checked else {
            self.cache = ItemCache::new();
            return;
        };
        // A newer edit of this document arrived while checking: this result is stale.
        while let Ok(w) = work.try_recv() {
            self.take(w);
        }
        if self.queue.has(&job.path) || !self.opened_or_checked(&job.path) {
            return;
        }
        let files: BTreeSet<String> = analysis.by_file.keys().cloned().collect();
        let gone: Vec<String> = self
            .read_by
            .get(&job.path)
            .map(|old| old.difference(&files).cloned().collect())
            .unwrap_or_default();
        for f in gone {
            self.publish(&f, Vec::new(), None, false);
        }
        let opened = self.opened.remove(&job.path);
        for (f, list) in &analysis.by_file {
            let own = *f == job.path;
            self.publish(f, list.clone(), own.then_some(job.version), own && opened);
        }
        self.read_by.insert(job.path.clone(), files);
        if let Some(freer) = &self.freer {
            let _ = freer.send(leftovers);
        }
        if let Ok(mut s) = self.store.lock() {
            s.insert(job.path, Arc::new(analysis));
        }
    }

    /// Whether `path` is still open: opened and not closed since, or checked before.
    fn opened_or_checked(&self, path: &str) -> bool {
        self.opened.contains(path) || self.read_by.contains_key(path)
    }

    /// Publishes a file's diagnostics, unless the editor shows them already (and `always` is
    /// not set).
    fn publish(
        &mut self,
        path: &str,
        diagnostics: Vec<lsp_types::Diagnostic>,
        version: Option<i32>,
        always: bool,
    ) {
        let unchanged = self.shown.get(path).map_or(diagnostics.is_empty(), |s| *s == diagnostics);
        if unchanged && !always {
            return;
        }
        self.shown.insert(path.to_string(), diagnostics.clone());
        let params = PublishDiagnosticsParams { uri: path_to_uri(path), diagnostics, version };
        let _ = self.out.send(Message::Notification(Notification::new(
            PublishDiagnostics::METHOD.to_string(),
            params,
        )));
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const A: &str = "/virtual/a.mocu";

    fn job(version: i32, text: &str) -> Job {
        let mut loader = OverlayLoader::default();
        loader.texts.insert(A.into(), text.into());
        Job { path: A.into(), version, loader, opened: version == 1 }
    }

    /// What was published for the document: (version, how many diagnostics), in order.
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

    fn worker() -> (Worker, Receiver<Message>) {
        let (out, published_rx) = crossbeam_channel::unbounded();
        (Worker::new(out, Analyses::default(), Timing::default()), published_rx)
    }

    /// The worker takes `w` and does at once what it asks.
    fn step(worker: &mut Worker, w: Work) {
        let (_keep, none) = crossbeam_channel::unbounded();
        worker.take(w);
        while let Some(job) = worker.queue.take_any() {
            worker.check(job, &none);
        }
    }

    #[test]
    fn queued_edits_are_checked_once_at_their_newest_version() {
        let (jobs, rx) = crossbeam_channel::unbounded();
        let (w, published_rx) = worker();
        let store = w.store.clone();
        for (v, text) in [(1, "let a = \n"), (2, "let a = b\n"), (3, "let a = 1\n")] {
            jobs.send(Work::Check(job(v, text))).unwrap();
        }
        drop(jobs);
        w.run(&rx);
        assert_eq!(published(&published_rx), vec![(Some(3), 0)]);
        assert_eq!(store.lock().unwrap()[A].version, 3);
    }

    #[test]
    fn diagnostics_are_published_on_open_and_then_only_when_they_change() {
        let (mut w, rx) = worker();
        step(&mut w, Work::Check(job(1, "let a = 1\nlet b = a + c\n")));
        step(&mut w, Work::Check(job(2, "let a = 1\nlet b = a + c\n// same\n")));
        step(&mut w, Work::Check(job(3, "let a = 1\nlet b = a + 1\n// fixed\n")));
        step(&mut w, Work::Check(job(4, "let a = 1\nlet b = a + 2\n// fixed\n")));
        step(&mut w, Work::Check(job(5, "let a = 1\n\nlet b = a + c\n")));
        assert_eq!(published(&rx), vec![(Some(1), 1), (Some(3), 0), (Some(5), 1)]);
    }

    #[test]
    fn an_opened_document_is_published_even_without_diagnostics_and_closing_clears_it() {
        let (mut w, rx) = worker();
        step(&mut w, Work::Check(job(1, "let a = 1\n")));
        step(&mut w, Work::Check(job(2, "let a = c\n")));
        step(&mut w, Work::Close(A.into()));
        assert!(w.store.lock().unwrap().get(A).is_none());
        step(&mut w, Work::Check(job(1, "let a = c\n")));
        assert_eq!(published(&rx), vec![(Some(1), 0), (Some(2), 1), (None, 0), (Some(1), 1)]);
    }

    #[test]
    fn a_check_of_a_closed_document_is_not_published() {
        let (jobs, rx) = crossbeam_channel::unbounded();
        let (mut w, published_rx) = worker();
        w.take(Work::Check(job(1, "let a = c\n")));
        let running = w.queue.take_any().unwrap();
        jobs.send(Work::Close(A.into())).unwrap();
        w.check(running, &rx);
        assert_eq!(published(&published_rx), vec![(None, 0)]);
    }

    #[test]
    fn a_diagnostic_carries_mocu_checks_code_range_and_message() {
        let mut cache = ItemCache::new();
        let text = "let a = 1\nlet b = a + c\n";
        let (a, _) = analyse(A, 1, &job(1, text).loader, &mut cache);
        let d = &a.by_file[A][0];
        assert_eq!(d.code, Some(NumberOrString::String("E0204".into())));
        assert_eq!((d.range.start.line, d.range.start.character), (1, 12));
        assert!(d.message.starts_with("unknown name `c`"), "{}", d.message);
    }
}
