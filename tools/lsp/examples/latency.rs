//! Keystroke-to-diagnostics latency of `mocu lsp` (issue 19 target: a keystroke in a
//! 10,000-line layout republishes diagnostics in ≤ 50 ms). The server runs in process on an
//! in-memory connection; the client opens the generated layout the check benchmark uses
//! (benches/common/layout_corpus.rs), then types in the middle of it: each keystroke makes or
//! mends an unknown name (`kn` ↔ `knx` in a widget), so each changes the diagnostics and is
//! published; it is timed from `didChange` to the `publishDiagnostics` of its version. A burst
//! of edits sent at once is timed to the diagnostics of its last version (the ones before it
//! are never checked).
//!
//! Wall time counts the machine's other load; beside it each keystroke's CPU time is given
//! (the server's threads, from /proc/self/task/*/schedstat on Linux): what the keystroke cost,
//! whatever else runs.
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

    // Typing in the middle of the file: `* kn` becomes `* knx` (an unknown name) and back.
    let line = text.lines().enumerate().skip(lines / 2).find(|(_, l)| l.contains("* kn"));
    let (line, col) =
        line.map(|(n, l)| (n as u32, (l.find("* kn").unwrap_or(0) + 4) as u32)).unwrap_or((1, 15));
    let type_at =
        |v: i32| change(&client, &uri, v, line, col, if v % 2 == 0 { "x" } else { "" }, v % 2 == 1);
    let mut times = Vec::new();
    let mut cpu = Vec::new();
    for v in 2..=41 {
        let (started, cpu0) = (Instant::now(), server_cpu());
        type_at(v);
        wait(&client, &uri, v);
        times.push(started.elapsed());
        cpu.push(server_cpu().saturating_sub(cpu0));
    }
    times.sort();
    cpu.sort();
    let ms = |d: Duration| d.as_secs_f64() * 1000.0;
    let at = |q: f64| ms(times[((times.len() as f64 * q) as usize).min(times.len() - 1)]);
    println!(
        "keystroke → diagnostics, {} keystrokes: median {:.1} ms, p95 {:.1} ms, min {:.1} ms, max {:.1} ms",
        times.len(),
        at(0.5),
        at(0.95),
        ms(times[0]),
        ms(times[times.len() - 1])
    );
    let cpu_at = |q: f64| ms(cpu[((cpu.len() as f64 * q) as usize).min(cpu.len() - 1)]);
    println!(
        "keystroke CPU time (the server's threads): median {:.1} ms, p95 {:.1} ms",
        cpu_at(0.5),
        cpu_at(0.95)
    );

    // A burst of 11 keystrokes sent at once: checked once, after the last.
    let started = Instant::now();
    for v in 42..=52 {
        type_at(v);
    }
    wait(&client, &uri, 52);
    println!("burst of 11 keystrokes → diagnostics of the last: {:.1} ms", ms(started.elapsed()));

    // The check alone, parsing every item (cold) and reusing the unchanged ones (warm).
    let mut docs = mocu_lsp::overlay::Documents::default();
    let p = mocu_lsp::text::uri_to_path(&uri).expect("a file URI");
    docs.open.insert(p.clone(), mocu_lsp::overlay::Document { text: text.clone(), version: 1 });
    let (mut cold, mut warm) = (Vec::new(), Vec::new());
    let mut cache = mocu_language::incremental::ItemCache::new();
    for k in 0..10 {
        let (a, leftovers) = mocu_lsp::check::analyse(&p, 1, &docs.loader(), &mut cache);
        drop(leftovers);
        if k > 0 {
            warm.push(a.elapsed);
        }
        let (a, _) = mocu_lsp::check::analyse(&p, 1, &docs.loader(), &mut Default::default());
        cold.push(a.elapsed);
    }
    cold.sort();
    warm.sort();
    println!(
        "the check alone: every item parsed: median {:.1} ms; unchanged items reused: median {:.1} ms",
        ms(cold[cold.len() / 2]),
        ms(warm[warm.len() / 2]),
    );

    send(&client, Message::Request(Request::new(RequestId::from(2), Shutdown::METHOD.into(), ())));
    notify(&client, "exit", ());
    drop(client);
    let _ = thread.join();
    let _ = std::fs::remove_dir_all(&dir);
}

/// CPU time used so far by the server's threads (all of this process's but the client's, which
/// only waits); zero where /proc has no per-thread figures.
fn server_cpu() -> Duration {
    let me = std::fs::read_to_string("/proc/thread-self/stat").ok();
    let my_tid = me.as_deref().and_then(|s| s.split_whitespace().next()).unwrap_or("");
    let Ok(tasks) = std::fs::read_dir("/proc/self/task") else { return Duration::ZERO };
    let mut ns = 0u64;
    for t in tasks.flatten() {
        if t.file_name().to_string_lossy() == my_tid {
            continue;
        }
        let stat = std::fs::read_to_string(t.path().join("schedstat")).unwrap_or_default();
        ns += stat.split_whitespace().next().and_then(|x| x.parse::<u64>().ok()).unwrap_or(0);
    }
    Duration::from_nanos(ns)
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
