//! Keystroke-to-diagnostics latency of `mocu lsp` (issue 19 target: a keystroke in a
//! 10,000-line layout republishes diagnostics in ≤ 50 ms). The server runs in process on an
//! in-memory connection; the client opens the generated layout the check benchmark uses
//! (benches/common/layout_corpus.rs), then types: each edit is timed from `didChange` to the
//! `publishDiagnostics` of its version. A burst of edits sent at once is timed to the
//! diagnostics of its last version (the stale ones in between are dropped, not checked).
//!
//! `cargo run --release -p mocu-lsp --example latency [LINES]` (default 10000); figures:
//! docs/editors.md ("Latency").

#[path = "../../../benches/common/layout_corpus.rs"]
mod layout_corpus;

use lsp_server::{Connection, Message, Notification, Request, RequestId};
use lsp_types::notification::{
    DidChangeTextDocument, DidOpenTextDocument, Initialized, Notification as _, PublishDiagnostics,
};
use lsp_types::request::{Initialize, Request as _, Shutdown};
use lsp_types::*;
use std::time::{Duration, Instant};

fn main() {
    let lines: usize = std::env::args().nth(1).and_then(|a| a.parse().ok()).unwrap_or(10_000);
    let text = layout_corpus::generate(lines);
    let dir = std::env::temp_dir().join(format!("mocu-lsp-latency-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    let path = dir.join("big.mocu");
    std::fs::write(&path, &text).expect("write");
    let uri = mocu_lsp::text::path_to_uri(&path.to_string_lossy());

    let (server, client) = Connection::memory();
    let thread = std::thread::spawn(move || mocu_lsp::serve(server));
    let init = InitializeParams::default();
    send(
        &client,
        Message::Request(Request::new(RequestId::from(1), Initialize::METHOD.into(), init)),
    );
    let _ = client.receiver.recv();
    notify(&client, Initialized::METHOD, InitializedParams {});

    let started = Instant::now();
    notify(
        &client,
        DidOpenTextDocument::METHOD,
        DidOpenTextDocumentParams {
            text_document: TextDocumentItem::new(uri.clone(), "mocu".into(), 1, text.clone()),
        },
    );
    let found = wait(&client, &uri, 1);
    println!("{lines} lines: open → diagnostics {:?} ({found} diagnostics)", started.elapsed());

    // Typing: one character at a time on line 2 (`let kn = 1.94384`), each awaited.
    let mut times = Vec::new();
    for v in 2..=21 {
        let started = Instant::now();
        change(&client, &uri, v, 1, 15, if v % 2 == 0 { "5" } else { "" }, v % 2 == 1);
        wait(&client, &uri, v);
        times.push(started.elapsed());
    }
    times.sort();
    let ms = |d: Duration| d.as_secs_f64() * 1000.0;
    println!(
        "keystroke → diagnostics, {} edits: median {:.1} ms, p90 {:.1} ms, min {:.1} ms, max {:.1} ms",
        times.len(),
        ms(times[times.len() / 2]),
        ms(times[times.len() * 9 / 10]),
        ms(times[0]),
        ms(times[times.len() - 1])
    );

    // A burst of 10 keystrokes sent at once: only the newest is checked after the running one.
    let started = Instant::now();
    for v in 22..=31 {
        change(&client, &uri, v, 1, 15, if v % 2 == 0 { "5" } else { "" }, v % 2 == 1);
    }
    wait(&client, &uri, 31);
    println!("burst of 10 keystrokes → diagnostics of the last: {:.1} ms", ms(started.elapsed()));

    // The check alone (what `mocu check` pays), for comparison.
    let mut docs = mocu_lsp::overlay::Documents::default();
    let p = mocu_lsp::text::uri_to_path(&uri).expect("a file URI");
    docs.open.insert(p.clone(), mocu_lsp::overlay::Document { text: text.clone(), version: 1 });
    let (mut checks, mut freed) = (Vec::new(), Vec::new());
    for _ in 0..10 {
        let started = Instant::now();
        let (analysis, leftovers) = mocu_lsp::check::analyse(&p, 1, &docs.loader());
        drop(leftovers);
        checks.push(analysis.elapsed);
        freed.push(started.elapsed());
    }
    checks.sort();
    freed.sort();
    println!(
        "the check alone: median {:.1} ms, min {:.1} ms; with freeing its program: median {:.1} ms",
        ms(checks[5]),
        ms(checks[0]),
        ms(freed[5])
    );

    send(&client, Message::Request(Request::new(RequestId::from(2), Shutdown::METHOD.into(), ())));
    notify(&client, "exit", ());
    drop(client);
    let _ = thread.join();
    let _ = std::fs::remove_dir_all(&dir);
}

fn send(c: &Connection, m: Message) {
    c.sender.send(m).expect("server alive");
}

fn notify(c: &Connection, method: &str, params: impl serde::Serialize) {
    send(c, Message::Notification(Notification::new(method.into(), params)));
}

/// Inserts `insert` at (line, col), or deletes the character there when `delete`.
fn change(
    c: &Connection,
    uri: &Uri,
    version: i32,
    line: u32,
    col: u32,
    insert: &str,
    delete: bool,
) {
    let end = if delete { col + 1 } else { col };
    notify(
        c,
        DidChangeTextDocument::METHOD,
        DidChangeTextDocumentParams {
            text_document: VersionedTextDocumentIdentifier::new(uri.clone(), version),
            content_changes: vec![TextDocumentContentChangeEvent {
                range: Some(Range::new(Position::new(line, col), Position::new(line, end))),
                range_length: None,
                text: insert.to_string(),
            }],
        },
    );
}

/// Waits for the diagnostics of `uri` at `version`; returns how many there are.
fn wait(c: &Connection, uri: &Uri, version: i32) -> usize {
    for m in &c.receiver {
        if let Message::Notification(n) = m
            && n.method == PublishDiagnostics::METHOD
            && let Ok(p) = serde_json::from_value::<PublishDiagnosticsParams>(n.params)
            && p.uri == *uri
            && p.version == Some(version)
        {
            return p.diagnostics.len();
        }
    }
    panic!("the server stopped before publishing version {version}");
}
