//! `cargo bench -p sfc-lsp --bench ring`: how fast `sfc lsp` answers on the 10,000-step ring
//! (the chart of `sfc-model`'s check benchmark): diagnostics after an edit (from the change
//! notification to the published diagnostics of that version, debounce included), completion
//! after `S1.` and in a condition, hover, and the full check with the analysis after a save.
//! The server runs as `sfc lsp` does, on an in-memory connection instead of standard input and
//! output (the same messages, without the pipe). Under `cargo test` (no `--bench` argument) it
//! runs once on a 100-step ring as a smoke test. Figures are printed, never asserted.

// A benchmark, not input-facing code: a panic here is a failed run (as in a test).
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::indexing_slicing)]

/// The allocator of the `sfc` binary (`crates/sfc-cli/src/main.rs`), so the figures are those
/// of `sfc lsp`.
#[global_allocator]
static ALLOCATOR: mimalloc::MiMalloc = mimalloc::MiMalloc;

use lsp_server::{Connection, Message, Notification, Request, RequestId};
use lsp_types::notification::{self as note, Notification as _};
use lsp_types::request as req;
use lsp_types::*;
use std::fmt::Write;
use std::time::{Duration, Instant};

/// A ring of `n` steps with a selection branch every tenth step, an action with an ST body per
/// step, timers and integer arithmetic (as in `crates/sfc-model/benches/check.rs`).
fn chart(n: usize) -> String {
    let mut s = String::new();
    let _ = writeln!(s, "PROGRAM Big\n    VAR_INPUT\n        Go : BOOL;\n        Level : INT;\n    END_VAR\n    VAR\n        Count : DINT;\n        Timer : TON;\n        Out : BOOL;\n    END_VAR\n");
    for i in 0..n {
        let kw = if i == 0 { "INITIAL_STEP" } else { "STEP" };
        let _ = writeln!(s, "    {kw} S{i}:\n        A{i}(N);\n    END_STEP\n");
        let _ = writeln!(s, "    ACTION A{i}:\n        Count := Count + {i};\n        Timer(IN := TRUE, PT := T#1s);\n        Out := Timer.Q AND Level > {};\n    END_ACTION\n", i % 100);
        let next = (i + 1) % n;
        if i % 10 == 5 && i + 2 < n {
            let _ = writeln!(
                s,
                "    TRANSITION FROM S{i} TO S{}\n        := Go AND Level > {};\n    END_TRANSITION\n",
                i + 2,
                i % 50
            );
            let _ = writeln!(
                s,
                "    TRANSITION FROM S{i} TO S{next}\n        := NOT Go AND S{i}.T >= T#100ms;\n    END_TRANSITION\n"
            );
        } else {
            let _ = writeln!(
                s,
                "    TRANSITION FROM S{i} TO S{next}\n        := Go OR S{i}.T >= T#{}ms;\n    END_TRANSITION\n",
                10 + i % 90
            );
        }
    }
    s.push_str("END_PROGRAM\n");
    s
}

struct Client {
    conn: Connection,
    next: i32,
    /// Diagnostics that arrived while waiting for something else.
    seen: Vec<PublishDiagnosticsParams>,
}

impl Client {
    fn request<R: req::Request>(&mut self, params: R::Params) -> (R::Result, Duration) {
        self.next += 1;
        let id = RequestId::from(self.next);
        let start = Instant::now();
        self.conn.sender.send(Message::Request(Request::new(id.clone(), R::METHOD.into(), params))).unwrap();
        loop {
            match self.conn.receiver.recv_timeout(Duration::from_secs(600)).expect("an answer") {
                Message::Response(r) if r.id == id => {
                    let took = start.elapsed();
                    let v = r.response_result.expect("no error");
                    return (serde_json::from_value(v).unwrap(), took);
                }
                Message::Notification(n) if n.method == note::PublishDiagnostics::METHOD => {
                    self.seen.push(serde_json::from_value(n.params).unwrap());
                }
                _ => {}
            }
        }
    }
    fn notify<N: note::Notification>(&self, params: N::Params) {
        self.conn.sender.send(Message::Notification(Notification::new(N::METHOD.into(), params))).unwrap();
    }
    /// Waits for diagnostics of `version` (with `count` entries, when given); a bounded wait that
    /// says what arrived instead of hanging.
    fn diagnostics(&mut self, version: i32, count: Option<usize>) -> Vec<Diagnostic> {
        let fits =
            |p: &PublishDiagnosticsParams| p.version == Some(version) && count.is_none_or(|c| p.diagnostics.len() == c);
        if let Some(i) = self.seen.iter().position(fits) {
            let p = self.seen.remove(i);
            self.seen.clear();
            return p.diagnostics;
        }
        self.seen.clear();
        let deadline = Instant::now() + Duration::from_secs(300);
        let mut last = None;
        loop {
            let left = deadline.saturating_duration_since(Instant::now());
            let Ok(m) = self.conn.receiver.recv_timeout(left) else {
                panic!("no diagnostics of version {version} with {count:?} entries; the last were {last:#?}");
            };
            if let Message::Notification(n) = m {
                if n.method == note::PublishDiagnostics::METHOD {
                    let p: PublishDiagnosticsParams = serde_json::from_value(n.params).unwrap();
                    if fits(&p) {
                        return p.diagnostics;
                    }
                    last = Some((p.version, p.diagnostics));
                }
            }
        }
    }
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(|a, b| a.total_cmp(b));
    v[v.len() / 2]
}

fn ms(d: Duration) -> f64 {
    d.as_secs_f64() * 1e3
}

fn main() {
    let full = std::env::args().any(|a| a == "--bench");
    let n = if full { 10_000 } else { 100 };
    let runs = if full { 9 } else { 2 };
    let text = chart(n);
    let (server, client) = Connection::memory();
    let options = sfc_lsp::ServerOptions { idle: None, ..sfc_lsp::ServerOptions::default() };
    let debounce = options.debounce;
    let thread =
        std::thread::Builder::new().stack_size(64 << 20).spawn(move || sfc_lsp::serve(server, options)).unwrap();
    let mut c = Client { conn: client, next: 0, seen: Vec::new() };
    #[allow(deprecated)]
    let _ = c.request::<req::Initialize>(InitializeParams::default());
    c.notify::<note::Initialized>(InitializedParams {});
    let uri: Uri = "file:///bench/ring.st".parse().unwrap();
    let start = Instant::now();
    c.notify::<note::DidOpenTextDocument>(DidOpenTextDocumentParams {
        text_document: TextDocumentItem::new(uri.clone(), "sfc".into(), 1, text.clone()),
    });
    // The ring's own findings (warnings the chart may have) are the baseline of the edits.
    let base = c.diagnostics(1, None).len();
    let open = start.elapsed();

    // Edits: break and mend the condition of the last transition (`Go` ↔ `Gox`).
    let line = text[..text.rfind(":= Go OR").unwrap()].matches('\n').count() as u32;
    let col = text.lines().nth(line as usize).unwrap().find("Go OR").unwrap() as u32 + 2;
    let mut edit_times = Vec::new();
    for v in 2..2 + runs as i32 * 2 {
        let broken = v % 2 == 0;
        let range = if broken {
            Range::new(Position::new(line, col), Position::new(line, col))
        } else {
            Range::new(Position::new(line, col), Position::new(line, col + 1))
        };
        let t = Instant::now();
        c.notify::<note::DidChangeTextDocument>(DidChangeTextDocumentParams {
            text_document: VersionedTextDocumentIdentifier::new(uri.clone(), v),
            content_changes: vec![TextDocumentContentChangeEvent {
                range: Some(range),
                range_length: None,
                text: if broken { "x".into() } else { String::new() },
            }],
        });
        c.diagnostics(v, Some(base + usize::from(broken)));
        edit_times.push(ms(t.elapsed()));
    }
    let version = 1 + runs as i32 * 2;

    // Completion after `S1.` (typed into a condition: the edit is sent, then the request, as an
    // editor does) and completion of a name in a condition.
    let cond_line = text[..text.find(":= Go OR S1.T").unwrap()].matches('\n').count() as u32;
    let cond_col = text.lines().nth(cond_line as usize).unwrap().find("S1.T").unwrap() as u32 + 3;
    let mut member_times = Vec::new();
    let mut name_times = Vec::new();
    let mut hover_times = Vec::new();
    let mut v = version;
    for _ in 0..runs {
        // Touch the document so the request meets a new version (the worst case: it is parsed
        // and indexed again for the request).
        v += 1;
        c.notify::<note::DidChangeTextDocument>(DidChangeTextDocumentParams {
            text_document: VersionedTextDocumentIdentifier::new(uri.clone(), v),
            content_changes: vec![TextDocumentContentChangeEvent {
                range: Some(Range::new(Position::new(0, 0), Position::new(0, 0))),
                range_length: None,
                text: String::new(),
            }],
        });
        let pos = TextDocumentPositionParams::new(
            TextDocumentIdentifier::new(uri.clone()),
            Position::new(cond_line, cond_col),
        );
        let (items, took) = c.request::<req::Completion>(CompletionParams {
            text_document_position: pos.clone(),
            work_done_progress_params: Default::default(),
            partial_result_params: Default::default(),
            context: None,
        });
        let labels = match items.unwrap() {
            CompletionResponse::List(l) => l.items.into_iter().map(|i| i.label).collect::<Vec<_>>(),
            CompletionResponse::Array(a) => a.into_iter().map(|i| i.label).collect(),
        };
        assert_eq!(labels, ["X", "T"]);
        member_times.push(ms(took));
        let name_pos = TextDocumentPositionParams::new(
            TextDocumentIdentifier::new(uri.clone()),
            Position::new(cond_line, cond_col - 2),
        );
        let (_, took) = c.request::<req::Completion>(CompletionParams {
            text_document_position: name_pos.clone(),
            work_done_progress_params: Default::default(),
            partial_result_params: Default::default(),
            context: None,
        });
        name_times.push(ms(took));
        let (h, took) = c.request::<req::HoverRequest>(HoverParams {
            text_document_position_params: name_pos,
            work_done_progress_params: Default::default(),
        });
        assert!(h.is_some());
        hover_times.push(ms(took));
    }

    // The full check with the analysis, as after a save (once the quick check is in).
    c.diagnostics(v, Some(base));
    let t = Instant::now();
    c.notify::<note::DidSaveTextDocument>(DidSaveTextDocumentParams {
        text_document: TextDocumentIdentifier::new(uri.clone()),
        text: None,
    });
    // The next diagnostics of the same version are the analysis's.
    let analysed = c.diagnostics(v, None).len();
    let analysis = t.elapsed();

    let _ = c.request::<req::Shutdown>(());
    c.notify::<note::Exit>(());
    thread.join().unwrap().unwrap();
    println!(
        "sfc lsp on a ring of {n} steps ({} lines, {} KiB; {base} diagnostics without the analysis, {analysed} with it):",
        text.lines().count(),
        text.len() / 1024
    );
    println!("  open → first diagnostics:                 {:8.1} ms", ms(open));
    println!("  edit → diagnostics of that version:       {:8.1} ms (median of {}; {} ms debounce included; target < 300 ms)", median(edit_times.clone()), edit_times.len(), debounce.as_millis());
    println!(
        "  completion after `S1.` (after an edit):   {:8.1} ms (median of {runs}; target < 50 ms)",
        median(member_times)
    );
    println!("  completion of a name in a condition:      {:8.1} ms (median of {runs})", median(name_times));
    println!("  hover (document unchanged):               {:8.1} ms (median of {runs})", median(hover_times));
    println!("  save → diagnostics with the analysis:     {:8.1} ms", ms(analysis));
}
