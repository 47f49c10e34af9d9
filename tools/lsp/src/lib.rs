//! `mocu lsp`: the layout language's Language Server Protocol server, on stdin and stdout.
//!
//! Diagnostics are `mocu check`'s (same check, same project walk-up and schemas), run on a
//! worker thread over the open documents' text ([`check`]); the other requests are answered
//! on the main thread from a fresh parse of the document and the files it `use`s ([`index`]).
//! What works, and how to set an editor up: docs/editors.md.
#![forbid(unsafe_code)]

pub mod actions;
pub mod check;
pub mod completion;
pub mod hover;
pub mod index;
pub mod live;
pub mod overlay;
pub mod paths;
pub mod schedule;
pub mod script_completion;
pub mod symbols;
pub mod text;
pub mod use_paths;

use check::{Analyses, Job, Work};
use crossbeam_channel::Sender;
use index::Index;
use lsp_server::{Connection, ErrorCode, Message, Notification, Request, Response};
use lsp_types::notification::{
    DidChangeTextDocument, DidChangeWatchedFiles, DidCloseTextDocument, DidOpenTextDocument,
    DidSaveTextDocument, Notification as _,
};
use lsp_types::request::{
    CodeActionRequest, Completion, DocumentSymbolRequest, Formatting, GotoDefinition, HoverRequest,
    RangeFormatting, References, Rename, Request as _, SemanticTokensFullRequest,
};
use lsp_types::*;
use mocu_language::incremental::ItemCache;
use overlay::{Document, Documents};
use std::collections::HashMap;
use text::{LineIndex, path_to_uri, uri_to_path};

/// Serves the protocol on stdin/stdout until the client exits.
pub fn run_stdio(options: Options) -> Result<(), String> {
    let (connection, io) = Connection::stdio();
    serve_with(connection, options)?;
    io.join().map_err(|e| e.to_string())
}

/// What the server offers.
pub fn capabilities() -> ServerCapabilities {
    ServerCapabilities {
        text_document_sync: Some(TextDocumentSyncCapability::Options(TextDocumentSyncOptions {
            open_close: Some(true),
            change: Some(TextDocumentSyncKind::INCREMENTAL),
            save: Some(TextDocumentSyncSaveOptions::Supported(true)),
            ..TextDocumentSyncOptions::default()
        })),
        hover_provider: Some(HoverProviderCapability::Simple(true)),
        completion_provider: Some(CompletionOptions {
            trigger_characters: Some(vec![".".into(), "\"".into(), "/".into()]),
            ..CompletionOptions::default()
        }),
        definition_provider: Some(OneOf::Left(true)),
        references_provider: Some(OneOf::Left(true)),
        rename_provider: Some(OneOf::Left(true)),
        document_symbol_provider: Some(OneOf::Left(true)),
        code_action_provider: Some(CodeActionProviderCapability::Simple(true)),
        document_formatting_provider: Some(OneOf::Left(true)),
        document_range_formatting_provider: Some(OneOf::Left(true)),
        semantic_tokens_provider: Some(
            SemanticTokensOptions {
                legend: SemanticTokensLegend {
                    token_types: symbols::TOKEN_TYPES.to_vec(),
                    token_modifiers: Vec::new(),
                },
                full: Some(SemanticTokensFullOptions::Bool(true)),
                ..SemanticTokensOptions::default()
            }
            .into(),
        ),
        ..ServerCapabilities::default()
    }
}

/// Runs the server on a connection (stdio, or in memory for tests) until `exit`.
pub fn serve(connection: Connection) -> Result<(), String> {
    serve_with(connection, Options::default())
}

/// Makes the server's live world values from the client's `initialize` parameters (its
/// `initializationOptions`, its workspace folder), once the client has said them.
pub type LiveSource = Box<dyn FnOnce(Option<&serde_json::Value>) -> Box<dyn live::LiveTree>>;

/// How a server is set up.
pub struct Options {
    /// How long edits wait before they are checked.
    pub timing: schedule::Timing,
    /// Where live world values come from.
    pub live: LiveSource,
}

impl Default for Options {
    fn default() -> Options {
        Options {
            timing: schedule::Timing::default(),
            live: Box::new(|_| Box::new(live::NoLiveTree)),
        }
    }
}

/// [`serve`] with `options`.
pub fn serve_with(connection: Connection, options: Options) -> Result<(), String> {
    let Options { timing, live } = options;
    let caps = serde_json::to_value(capabilities()).map_err(|e| e.to_string())?;
    let init = connection.initialize(caps).map_err(|e| e.to_string())?;
    let live = live(Some(&init));
    let (jobs, rx) = crossbeam_channel::unbounded();
    let analyses = Analyses::default();
    let worker = check::spawn_worker(rx, connection.sender.clone(), analyses.clone(), timing)
        .map_err(|e| e.to_string())?;
    let mut server = Server {
        docs: Documents::default(),
        generation: 0,
        indexes: HashMap::new(),
        cache: ItemCache::new(),
        live,
        jobs,
        analyses,
    };
    for msg in &connection.receiver {
        match msg {
            Message::Request(req) => {
                if connection.handle_shutdown(&req).map_err(|e| e.to_string())? {
                    break;
                }
                let resp = server.request(req);
                let _ = connection.sender.send(Message::Response(resp));
            }
            Message::Notification(n) => server.notification(n),
            Message::Response(_) => {}
        }
    }
    drop(server);
    let _ = worker.join();
    Ok(())
}

struct Server {
    docs: Documents,
    /// Bumped by every change of the open documents: an index built at the same generation
    /// is still right.
    generation: u64,
    /// The last index built for each document, with its generation.
    indexes: HashMap<String, (u64, std::rc::Rc<Index>)>,
    /// The trees of the indexes' files, for the next index.
    cache: ItemCache,
    /// A running OCU's world model, for hover and completion.
    live: Box<dyn live::LiveTree>,
    jobs: Sender<Work>,
    analyses: Analyses,
}

impl Server {
    fn notification(&mut self, n: Notification) {
        self.generation += 1;
        match n.method.as_str() {
            DidOpenTextDocument::METHOD => {
                let Ok(p) = serde_json::from_value::<DidOpenTextDocumentParams>(n.params) else {
                    return;
                };
                let Some(path) = uri_to_path(&p.text_document.uri) else { return };
                self.docs.open.insert(
                    path.clone(),
                    Document { text: p.text_document.text, version: p.text_document.version },
                );
                self.send_check(&path, true);
                self.changed(&path);
            }
            DidChangeTextDocument::METHOD => {
                let Ok(p) = serde_json::from_value::<DidChangeTextDocumentParams>(n.params) else {
                    return;
                };
                let Some(path) = uri_to_path(&p.text_document.uri) else { return };
                let Some(doc) = self.docs.open.get_mut(&path) else { return };
                for c in p.content_changes {
                    apply_change(&mut doc.text, c);
                }
                doc.version = p.text_document.version;
                self.changed(&path);
            }
            DidSaveTextDocument::METHOD | DidChangeWatchedFiles::METHOD => {
                let open: Vec<String> = self.docs.open.keys().cloned().collect();
                for p in open {
                    self.check(&p);
                }
            }
            DidCloseTextDocument::METHOD => {
                let Ok(p) = serde_json::from_value::<DidCloseTextDocumentParams>(n.params) else {
                    return;
                };
                let Some(path) = uri_to_path(&p.text_document.uri) else { return };
                self.docs.open.remove(&path);
                self.indexes.remove(&path);
                let _ = self.jobs.send(Work::Close(path.clone()));
                // Documents that use it now read it from the disk.
                self.changed(&path);
            }
            _ => {}
        }
    }

    /// Rechecks `path` and every open document whose last check read it.
    fn changed(&self, path: &str) {
        let readers: Vec<String> = match self.analyses.lock() {
            Ok(a) => a
                .iter()
                .filter(|(root, an)| root.as_str() != path && an.by_file.contains_key(path))
                .map(|(root, _)| root.clone())
                .collect(),
            Err(_) => Vec::new(),
        };
        if self.docs.open.contains_key(path) {
            self.check(path);
        }
        for r in readers {
            if self.docs.open.contains_key(&r) {
                self.check(&r);
            }
        }
    }

    fn check(&self, path: &str) {
        self.send_check(path, false);
    }

    fn send_check(&self, path: &str, opened: bool) {
        let version = self.docs.open.get(path).map_or(0, |d| d.version);
        let loader = self.docs.loader();
        let job = Job { path: path.to_string(), version, loader, opened };
        let _ = self.jobs.send(Work::Check(job));
    }

    /// The index of the document at `path` over the open documents as they are now.
    fn index(&mut self, path: &str) -> std::rc::Rc<Index> {
        if let Some((g, ix)) = self.indexes.get(path)
            && *g == self.generation
        {
            return ix.clone();
        }
        // The last index of this document gives its trees to the next (when no answer holds it).
        if let Some((_, old)) = self.indexes.remove(path)
            && let Ok(old) = std::rc::Rc::try_unwrap(old)
        {
            self.cache.recycle(old.modules, &old.sources);
        }
        let ix = std::rc::Rc::new(Index::build(path, &self.docs.loader(), &mut self.cache));
        self.indexes.insert(path.to_string(), (self.generation, ix.clone()));
        ix
    }

    fn analysis(&self, path: &str) -> Option<std::sync::Arc<check::Analysis>> {
        self.analyses.lock().ok()?.get(path).cloned()
    }

    fn request(&mut self, req: Request) -> Response {
        let id = req.id.clone();
        let method = req.method.clone();
        // A bug in one answer fails that request, not the editor's session.
        let answer = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| self.answer(req)));
        match answer {
            Ok(Ok(v)) => Response::new_ok(id, v),
            Ok(Err((code, message))) => Response::new_err(id, code as i32, message),
            Err(_) => Response::new_err(
                id,
                ErrorCode::InternalError as i32,
                format!("mocu lsp failed answering {method} (a bug: please report it)"),
            ),
        }
    }

    // lsp-types keys a WorkspaceEdit's changes by `Uri` (its interior cache never changes
    // its hash).
    #[allow(clippy::mutable_key_type)]
    fn answer(&mut self, req: Request) -> Result<serde_json::Value, (ErrorCode, String)> {
        let bad = |e: serde_json::Error| (ErrorCode::InvalidParams, e.to_string());
        let json = |v: &dyn erased::Json| v.to_json();
        match req.method.as_str() {
            HoverRequest::METHOD => {
                let p: HoverParams = serde_json::from_value(req.params).map_err(bad)?;
                let Some((path, ix, off)) = self.locate(&p.text_document_position_params) else {
                    return Ok(serde_json::Value::Null);
                };
                let analysis = self.analysis(&path);
                let h = hover::hover(&ix, analysis.as_deref(), self.live.as_ref(), &path, off).map(
                    |value| Hover {
                        contents: HoverContents::Markup(MarkupContent {
                            kind: MarkupKind::Markdown,
                            value,
                        }),
                        range: None,
                    },
                );
                Ok(json(&h))
            }
            Completion::METHOD => {
                let p: CompletionParams = serde_json::from_value(req.params).map_err(bad)?;
                let Some((path, ix, off)) = self.locate(&p.text_document_position) else {
                    return Ok(serde_json::Value::Null);
                };
                let analysis = self.analysis(&path);
                let items =
                    completion::complete(&ix, analysis.as_deref(), self.live.as_ref(), &path, off);
                Ok(json(&CompletionResponse::Array(items)))
            }
            GotoDefinition::METHOD => {
                let p: GotoDefinitionParams = serde_json::from_value(req.params).map_err(bad)?;
                let Some((path, ix, off)) = self.locate(&p.text_document_position_params) else {
                    return Ok(serde_json::Value::Null);
                };
                let def = ix.at(&path, off).and_then(|o| ix.defs.get(&o.def));
                let loc = def.map(|d| location(&ix, &d.path, d.start, d.end));
                Ok(json(&loc.map(GotoDefinitionResponse::Scalar)))
            }
            References::METHOD => {
                let p: ReferenceParams = serde_json::from_value(req.params).map_err(bad)?;
                let Some((path, ix, off)) = self.locate(&p.text_document_position) else {
                    return Ok(serde_json::Value::Null);
                };
                let Some(o) = ix.at(&path, off) else { return Ok(serde_json::Value::Null) };
                let uses = self.uses_everywhere(&ix, &o.def.clone());
                let locs: Vec<Location> = uses
                    .into_iter()
                    .filter(|(_, _, _, is_def)| p.context.include_declaration || !is_def)
                    .map(|(p, s, e, _)| location_in(&self.docs, &p, s, e))
                    .collect();
                Ok(json(&locs))
            }
            Rename::METHOD => {
                let p: RenameParams = serde_json::from_value(req.params).map_err(bad)?;
                if !is_name(&p.new_name) {
                    return Err((
                        ErrorCode::InvalidParams,
                        format!(
                            "`{}` is not a name (a letter or `_`, then letters, digits, `_`; not a keyword)",
                            p.new_name
                        ),
                    ));
                }
                let Some((path, ix, off)) = self.locate(&p.text_document_position) else {
                    return Ok(serde_json::Value::Null);
                };
                let Some(o) = ix.at(&path, off) else {
                    return Err((ErrorCode::InvalidParams, "nothing to rename here".into()));
                };
                let kind = ix.defs.get(&o.def).map(|d| d.kind);
                if matches!(kind, Some(index::Kind::Component | index::Kind::Param))
                    && o.def.0.contains("/stdlib/")
                {
                    return Err((
                        ErrorCode::InvalidParams,
                        "the standard library's names cannot be renamed".into(),
                    ));
                }
                let mut changes: HashMap<Uri, Vec<TextEdit>> = HashMap::new();
                for (p2, s, e, _) in self.uses_everywhere(&ix, &o.def.clone()) {
                    let range = location_in(&self.docs, &p2, s, e).range;
                    changes
                        .entry(path_to_uri(&p2))
                        .or_default()
                        .push(TextEdit { range, new_text: p.new_name.clone() });
                }
                Ok(json(&WorkspaceEdit { changes: Some(changes), ..WorkspaceEdit::default() }))
            }
            DocumentSymbolRequest::METHOD => {
                let p: DocumentSymbolParams = serde_json::from_value(req.params).map_err(bad)?;
                let Some(path) = uri_to_path(&p.text_document.uri) else {
                    return Ok(serde_json::Value::Null);
                };
                let ix = self.index(&path);
                Ok(json(&DocumentSymbolResponse::Nested(symbols::document_symbols(&ix, &path))))
            }
            SemanticTokensFullRequest::METHOD => {
                let p: SemanticTokensParams = serde_json::from_value(req.params).map_err(bad)?;
                let Some(path) = uri_to_path(&p.text_document.uri) else {
                    return Ok(serde_json::Value::Null);
                };
                let ix = self.index(&path);
                let data = symbols::semantic_tokens(&ix, &path);
                Ok(json(&SemanticTokensResult::Tokens(SemanticTokens { result_id: None, data })))
            }
            CodeActionRequest::METHOD => {
                let p: CodeActionParams = serde_json::from_value(req.params).map_err(bad)?;
                let Some(path) = uri_to_path(&p.text_document.uri) else {
                    return Ok(serde_json::Value::Null);
                };
                let text = self.docs.loader().texts.get(&path).cloned().unwrap_or_default();
                let list =
                    actions::code_actions(&p.text_document.uri, &text, &p.context.diagnostics);
                Ok(json(&list))
            }
            Formatting::METHOD => {
                let p: DocumentFormattingParams =
                    serde_json::from_value(req.params).map_err(bad)?;
                let Some(path) = uri_to_path(&p.text_document.uri) else {
                    return Ok(serde_json::Value::Null);
                };
                let Some(text) = self.docs.text(&path) else { return Ok(serde_json::Value::Null) };
                Ok(json(&format(text)?))
            }
            RangeFormatting::METHOD => {
                let p: DocumentRangeFormattingParams =
                    serde_json::from_value(req.params).map_err(bad)?;
                let Some(path) = uri_to_path(&p.text_document.uri) else {
                    return Ok(serde_json::Value::Null);
                };
                let Some(text) = self.docs.text(&path) else { return Ok(serde_json::Value::Null) };
                Ok(json(&format_range(text, p.range)?))
            }
            _ => Err((ErrorCode::MethodNotFound, format!("unknown request {}", req.method))),
        }
    }

    /// The document's path, its index and the byte offset of a position.
    fn locate(
        &mut self,
        at: &TextDocumentPositionParams,
    ) -> Option<(String, std::rc::Rc<Index>, usize)> {
        let path = uri_to_path(&at.text_document.uri)?;
        let ix = self.index(&path);
        let off = LineIndex::new(ix.text(&path)).offset(at.position);
        Some((path, ix, off))
    }

    /// Every occurrence of a definition: in `ix`, and in every open document's files (a file
    /// used by several layouts is renamed in all of them): (path, start, end, is the definition).
    fn uses_everywhere(
        &mut self,
        ix: &Index,
        def: &index::DefKey,
    ) -> Vec<(String, u32, u32, bool)> {
        let mut out: Vec<(String, u32, u32, bool)> =
            ix.uses_of(def).iter().map(|o| (o.path.clone(), o.start, o.end, o.is_def)).collect();
        let roots: Vec<String> = self.docs.open.keys().cloned().collect();
        for root in roots {
            if ix.modules.first().is_some_and(|m| m.path == root) {
                continue;
            }
            let other = self.index(&root);
            out.extend(
                other.uses_of(def).iter().map(|o| (o.path.clone(), o.start, o.end, o.is_def)),
            );
        }
        out.sort_by(|a, b| (!a.3, &a.0, a.1).cmp(&(!b.3, &b.0, b.1)));
        out.dedup_by(|a, b| a.0 == b.0 && a.1 == b.1);
        out
    }
}

/// `mocu fmt`'s edit of a document: the whole text replaced, or nothing when it is already
/// formatted or has syntax errors (which its diagnostics show).
fn format(text: &str) -> Result<Vec<TextEdit>, (ErrorCode, String)> {
    let mut diags = mocu_language::Diagnostics::new();
    match mocu_language::format::format_source(mocu_language::FileId(0), text, &mut diags) {
        Ok(out) if out == text => Ok(Vec::new()),
        Ok(out) => {
            let end = LineIndex::new(text).position(text.len());
            Ok(vec![TextEdit { range: Range::new(Position::new(0, 0), end), new_text: out }])
        }
        Err(mocu_language::format::FormatError::Syntax) => Ok(Vec::new()),
        Err(e) => Err((ErrorCode::RequestFailed, e.to_string())),
    }
}

/// `mocu fmt`'s edits of the items `range` touches (an editor's "format selection"); nothing
/// for a file with syntax errors.
fn format_range(text: &str, range: Range) -> Result<Vec<TextEdit>, (ErrorCode, String)> {
    let lines = LineIndex::new(text);
    let bytes = lines.offset(range.start)..lines.offset(range.end);
    let mut diags = mocu_language::Diagnostics::new();
    match mocu_language::format::range::format_range(
        mocu_language::FileId(0),
        text,
        bytes,
        &mut diags,
    ) {
        Ok(edits) => Ok(edits
            .into_iter()
            .map(|(r, new_text)| TextEdit { range: lines.range(r.start, r.end), new_text })
            .collect()),
        Err(mocu_language::format::FormatError::Syntax) => Ok(Vec::new()),
        Err(e) => Err((ErrorCode::RequestFailed, e.to_string())),
    }
}

/// A location in a file the index read.
fn location(ix: &Index, path: &str, start: u32, end: u32) -> Location {
    let lines = LineIndex::new(ix.text(path));
    Location { uri: path_to_uri(path), range: lines.range(start as usize, end as usize) }
}

/// A location in any file: an open document's text, else the file on disk.
fn location_in(docs: &Documents, path: &str, start: u32, end: u32) -> Location {
    let text = mocu_language::SourceLoader::read(&docs.loader(), path).unwrap_or_default();
    let lines = LineIndex::new(&text);
    Location { uri: path_to_uri(path), range: lines.range(start as usize, end as usize) }
}

/// Whether `s` is a name the language accepts for a `let`, window or component.
fn is_name(s: &str) -> bool {
    let mut chars = s.chars();
    chars.next().is_some_and(|c| c.is_ascii_alphabetic() || c == '_')
        && chars.all(|c| c.is_ascii_alphanumeric() || c == '_')
        && !completion::KEYWORDS.contains(&s)
}

/// Applies one change (a range, or the whole text) to a document.
fn apply_change(text: &mut String, c: TextDocumentContentChangeEvent) {
    match c.range {
        Some(r) => {
            let lines = LineIndex::new(text);
            let (s, e) = (lines.offset(r.start), lines.offset(r.end));
            text.replace_range(s..e.max(s), &c.text);
        }
        None => *text = c.text,
    }
}

mod erased {
    /// A response value, serialised.
    pub trait Json {
        fn to_json(&self) -> serde_json::Value;
    }
    impl<T: serde::Serialize> Json for T {
        fn to_json(&self) -> serde_json::Value {
            serde_json::to_value(self).unwrap_or(serde_json::Value::Null)
        }
    }
}
