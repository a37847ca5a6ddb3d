//! `sfc lsp` with a real client: these tests start the binary and speak JSON-RPC to it over
//! its standard input and output (framing by `lsp-server`, messages typed by `lsp-types`), as
//! an editor does. Fixtures: `tests/lsp/*.st`.

use lsp_server::{Message, Notification, Request, RequestId, Response};
use lsp_types::notification::{self as note, Notification as _};
use lsp_types::request as req;
use lsp_types::*;
use std::io::BufReader;
use std::path::{Path, PathBuf};
use std::process::{Child, ChildStdin, Command, Stdio};
use std::sync::mpsc::{self, Receiver};
use std::time::{Duration, Instant};

const TIMEOUT: Duration = Duration::from_secs(60);

fn fixture(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/lsp").join(name)
}

fn uri(path: &Path) -> Uri {
    format!("file://{}", path.display()).replace(' ', "%20").parse().unwrap()
}

struct Client {
    child: Child,
    stdin: ChildStdin,
    rx: Receiver<Message>,
    next: i32,
    /// Every diagnostics notification, in arrival order.
    diagnostics: Vec<PublishDiagnosticsParams>,
    logs: Vec<String>,
}

impl Client {
    /// Starts `sfc lsp` and initialises it; `options` are the `initializationOptions`.
    fn start(root: Option<&Path>, options: serde_json::Value) -> Client {
        let mut child = Command::new(env!("CARGO_BIN_EXE_sfc"))
            .args(["lsp", "--stdio"])
            .stdin(Stdio::piped())
            .stdout(Stdio::piped())
            .stderr(Stdio::inherit())
            .spawn()
            .expect("start sfc lsp");
        let stdin = child.stdin.take().unwrap();
        let stdout = child.stdout.take().unwrap();
        let (tx, rx) = mpsc::channel();
        std::thread::spawn(move || {
            let mut r = BufReader::new(stdout);
            while let Ok(Some(m)) = Message::read(&mut r) {
                if tx.send(m).is_err() {
                    break;
                }
            }
        });
        let mut c = Client { child, stdin, rx, next: 0, diagnostics: Vec::new(), logs: Vec::new() };
        #[allow(deprecated)]
        let init = InitializeParams {
            workspace_folders: root.map(|r| vec![WorkspaceFolder { uri: uri(r), name: "ws".into() }]),
            initialization_options: Some(options),
            ..InitializeParams::default()
        };
        let result: InitializeResult = c.request::<req::Initialize>(init).unwrap();
        assert!(result.capabilities.rename_provider.is_some());
        c.notify::<note::Initialized>(InitializedParams {});
        c
    }

    fn send(&mut self, m: Message) {
        m.write(&mut self.stdin).expect("write to sfc lsp");
    }

    fn notify<N: note::Notification>(&mut self, params: N::Params) {
        self.send(Message::Notification(Notification::new(N::METHOD.to_string(), params)));
    }

    fn take(&mut self, deadline: Instant) -> Message {
        let left = deadline.saturating_duration_since(Instant::now());
        let m = self
            .rx
            .recv_timeout(left)
            .unwrap_or_else(|_| panic!("no message from sfc lsp in time; logs: {:?}", self.logs));
        if let Message::Notification(n) = &m {
            if n.method == note::PublishDiagnostics::METHOD {
                self.diagnostics.push(serde_json::from_value(n.params.clone()).unwrap());
            } else if n.method == note::LogMessage::METHOD {
                let p: LogMessageParams = serde_json::from_value(n.params.clone()).unwrap();
                self.logs.push(p.message);
            }
        }
        m
    }

    /// A request and its answer: `Err` holds the error message.
    fn request<R: req::Request>(&mut self, params: R::Params) -> Result<R::Result, String> {
        self.next += 1;
        let id = RequestId::from(self.next);
        self.send(Message::Request(Request::new(id.clone(), R::METHOD.to_string(), params)));
        let deadline = Instant::now() + TIMEOUT;
        loop {
            if let Message::Response(Response { id: got, response_result }) = self.take(deadline) {
                if got == id {
                    return match response_result {
                        Ok(v) => Ok(serde_json::from_value(v).expect("a well-formed result")),
                        Err(e) => Err(e.message),
                    };
                }
            }
        }
    }

    fn open(&mut self, path: &Path, text: &str) -> Uri {
        let u = uri(path);
        let language = match path.extension().and_then(|e| e.to_str()) {
            Some("xml") => "xml",
            Some("toml") => "toml",
            _ => "sfc",
        };
        self.notify::<note::DidOpenTextDocument>(DidOpenTextDocumentParams {
            text_document: TextDocumentItem::new(u.clone(), language.into(), 1, text.to_string()),
        });
        u
    }

    fn change(&mut self, u: &Uri, version: i32, range: Range, text: &str) {
        self.notify::<note::DidChangeTextDocument>(DidChangeTextDocumentParams {
            text_document: VersionedTextDocumentIdentifier::new(u.clone(), version),
            content_changes: vec![TextDocumentContentChangeEvent {
                range: Some(range),
                range_length: None,
                text: text.into(),
            }],
        });
    }

    /// Waits for diagnostics of `u` at `version` that satisfy `ok`.
    fn diagnostics_for(&mut self, u: &Uri, version: i32, ok: impl Fn(&[Diagnostic]) -> bool) -> Vec<Diagnostic> {
        let deadline = Instant::now() + TIMEOUT;
        loop {
            if let Some(p) = self.diagnostics.iter().rev().find(|p| p.uri == *u && p.version == Some(version)) {
                if ok(&p.diagnostics) {
                    return p.diagnostics.clone();
                }
            }
            self.take(deadline);
        }
    }

    fn pos(u: &Uri, line: u32, character: u32) -> TextDocumentPositionParams {
        TextDocumentPositionParams::new(TextDocumentIdentifier::new(u.clone()), Position::new(line, character))
    }

    fn stop(mut self) {
        let _ = self.request::<req::Shutdown>(());
        self.notify::<note::Exit>(());
        let deadline = Instant::now() + Duration::from_secs(20);
        loop {
            match self.child.try_wait() {
                Ok(Some(status)) => {
                    assert!(status.success(), "sfc lsp exited with {status}");
                    return;
                }
                _ if Instant::now() > deadline => {
                    let _ = self.child.kill();
                    panic!("sfc lsp did not exit after `exit`");
                }
                _ => std::thread::sleep(Duration::from_millis(20)),
            }
        }
    }
}

/// The 0-based position of the `n`-th (0-based) occurrence of `needle` in `text`, plus `delta`
/// characters (ASCII fixtures).
fn at(text: &str, needle: &str, n: usize, delta: u32) -> Position {
    let offset = text.match_indices(needle).nth(n).unwrap_or_else(|| panic!("`{needle}` #{n} not in the text")).0;
    let line = text[..offset].matches('\n').count() as u32;
    let col = (offset - text[..offset].rfind('\n').map_or(0, |i| i + 1)) as u32;
    Position::new(line, col + delta)
}

fn no_idle() -> serde_json::Value {
    serde_json::json!({ "analysisIdleMs": 0 })
}

fn apply(text: &str, edits: &[TextEdit]) -> String {
    let mut sorted = edits.to_vec();
    sorted.sort_by_key(|e| std::cmp::Reverse((e.range.start.line, e.range.start.character)));
    let mut t = text.to_string();
    for e in sorted {
        let off = |p: Position| {
            let start: usize = t.split_inclusive('\n').take(p.line as usize).map(str::len).sum();
            start + p.character as usize
        };
        let (s, en) = (off(e.range.start), off(e.range.end));
        t.replace_range(s..en, &e.new_text);
    }
    t
}

/// Settings the server cannot read are said in the editor's log, not dropped silently; the
/// server goes on with its defaults.
#[test]
fn unreadable_initialization_options_are_reported() {
    let mut c = Client::start(None, serde_json::json!({"debounceMs": "soon"}));
    let text = std::fs::read_to_string(fixture("tank.st")).unwrap();
    let u = c.open(&fixture("tank.st"), &text);
    c.diagnostics_for(&u, 1, |d| d.is_empty());
    assert!(c.logs.iter().any(|l| l.contains("initializationOptions ignored")), "{:?}", c.logs);
    c.stop();
}

#[test]
fn open_with_errors_then_edit_then_fix() {
    let text = std::fs::read_to_string(fixture("tank.st")).unwrap().replace("Level > 80", "Levle > 80");
    let mut c = Client::start(None, no_idle());
    let u = c.open(&fixture("tank.st"), &text);
    let diags = c.diagnostics_for(&u, 1, |d| !d.is_empty());
    assert_eq!(diags.len(), 1, "{diags:#?}");
    let d = &diags[0];
    assert_eq!(d.code, Some(NumberOrString::String("SFC0301".into())));
    assert_eq!(d.severity, Some(DiagnosticSeverity::ERROR));
    assert_eq!(d.range, Range::new(at(&text, "Levle", 0, 0), at(&text, "Levle", 0, 5)));
    assert!(
        d.message.contains("undeclared variable `Levle`") && d.message.contains("did you mean `Level`?"),
        "{}",
        d.message
    );
    assert_eq!(d.code_description.as_ref().unwrap().href.as_str(), "sfc-explain:SFC0301");
    let explained: String = serde_json::from_value(
        serde_json::to_value(c.request::<Explain>(serde_json::json!({"code": "SFC0301"})).unwrap()).unwrap(),
    )
    .unwrap();
    assert!(explained.starts_with("# SFC0301 (error): undeclared variable"), "{explained}");

    // The quick fix of the "did you mean" note.
    let actions = c
        .request::<req::CodeActionRequest>(CodeActionParams {
            text_document: TextDocumentIdentifier::new(u.clone()),
            range: d.range,
            context: CodeActionContext { diagnostics: diags.clone(), only: None, trigger_kind: None },
            work_done_progress_params: Default::default(),
            partial_result_params: Default::default(),
        })
        .unwrap()
        .unwrap();
    let titles: Vec<String> = actions
        .iter()
        .map(|a| match a {
            CodeActionOrCommand::CodeAction(a) => a.title.clone(),
            CodeActionOrCommand::Command(c) => c.title.clone(),
        })
        .collect();
    assert!(titles.contains(&"Replace `Levle` with `Level`".to_string()), "{titles:?}");
    assert!(titles.contains(&"Declare `Levle : INT` in VAR".to_string()), "{titles:?}");
    let CodeActionOrCommand::CodeAction(fix) = &actions[0] else { panic!() };
    let edits = &fix.edit.as_ref().unwrap().changes.as_ref().unwrap()[&u];
    let fixed = apply(&text, edits);
    assert_eq!(fixed, std::fs::read_to_string(fixture("tank.st")).unwrap());

    // An edit (a new error), then the fix as an incremental change: diagnostics follow.
    let p = at(&text, "Start;", 0, 0);
    c.change(&u, 2, Range::new(p, Position::new(p.line, p.character + 5)), "Stat");
    let d2 = c.diagnostics_for(&u, 2, |d| d.len() == 2);
    assert!(d2.iter().any(|d| d.message.contains("undeclared variable `Stat`")), "{d2:#?}");
    c.change(&u, 3, Range::new(p, Position::new(p.line, p.character + 4)), "Start");
    let l = at(&text, "Levle", 0, 0);
    c.change(&u, 4, Range::new(l, Position::new(l.line, l.character + 5)), "Level");
    let d4 = c.diagnostics_for(&u, 4, |_| true);
    assert!(d4.is_empty(), "{d4:#?}");
    c.stop();
}

enum Explain {}
impl req::Request for Explain {
    type Params = serde_json::Value;
    type Result = serde_json::Value;
    const METHOD: &'static str = "sfc/explain";
}

#[test]
fn analysis_on_save_with_witness_related_information_and_fixes() {
    let text = std::fs::read_to_string(fixture("choice.st")).unwrap();
    let mut c = Client::start(None, no_idle());
    let u = c.open(&fixture("choice.st"), &text);
    // Without the analysis: only the structural warning.
    let quick = c.diagnostics_for(&u, 1, |d| !d.is_empty());
    assert!(quick.iter().all(|d| d.code != Some(NumberOrString::String("SFC0505".into()))), "{quick:#?}");
    c.notify::<note::DidSaveTextDocument>(DidSaveTextDocumentParams {
        text_document: TextDocumentIdentifier::new(u.clone()),
        text: None,
    });
    let full = c.diagnostics_for(&u, 1, |d| d.iter().any(|d| d.code == Some(NumberOrString::String("SFC0505".into()))));
    let nonex = full.iter().find(|d| d.code == Some(NumberOrString::String("SFC0505".into()))).unwrap();
    assert_eq!(nonex.severity, Some(DiagnosticSeverity::WARNING));
    assert!(nonex.message.contains("witness: Big = TRUE, Heavy = TRUE"), "{}", nonex.message);
    let related = nonex.related_information.as_ref().unwrap();
    assert_eq!(related[0].message, "`ToBig` is also true");
    assert_eq!(related[0].location.range.start, at(&text, "TRANSITION ToBig", 0, 0));

    let ask = |c: &mut Client, range: Range, diags: Vec<Diagnostic>| {
        c.request::<req::CodeActionRequest>(CodeActionParams {
            text_document: TextDocumentIdentifier::new(u.clone()),
            range,
            context: CodeActionContext { diagnostics: diags, only: None, trigger_kind: None },
            work_done_progress_params: Default::default(),
            partial_result_params: Default::default(),
        })
        .unwrap()
        .unwrap()
        .into_iter()
        .filter_map(|a| match a {
            CodeActionOrCommand::CodeAction(a) => Some(a),
            _ => None,
        })
        .collect::<Vec<_>>()
    };
    let prio = ask(&mut c, nonex.range, vec![nonex.clone()]);
    let prio = prio.iter().find(|a| a.title.starts_with("Add PRIORITY")).expect("an Add PRIORITY action");
    let after = apply(&text, &prio.edit.as_ref().unwrap().changes.as_ref().unwrap()[&u]);
    assert!(after.contains("TRANSITION ToBig (PRIORITY := 1) FROM Sort TO Left"), "{after}");
    assert!(after.contains("TRANSITION ToHeavy (PRIORITY := 2) FROM Sort TO Right"), "{after}");
    assert!(after.contains("TRANSITION (PRIORITY := 3) FROM Sort TO Done"), "{after}");
    // The fixed chart checks clean of SFC0505 (explicit priorities give a note).
    let dir = scratch("prio");
    std::fs::write(dir.join("choice.st"), &after).unwrap();
    let out = Command::new(env!("CARGO_BIN_EXE_sfc"))
        .args(["check", "--format", "json"])
        .arg(dir.join("choice.st"))
        .output()
        .unwrap();
    let found: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert!(found.as_array().unwrap().iter().all(|d| d["code"] != "SFC0505" || d["severity"] == "note"), "{found:#}");

    let final_step = full.iter().find(|d| d.code == Some(NumberOrString::String("SFC0213".into()))).unwrap();
    let acts = ask(&mut c, final_step.range, vec![final_step.clone()]);
    let mark = acts.iter().find(|a| a.title == "Mark step `Done` as final (sfc.final)").expect("mark final");
    let after = apply(&text, &mark.edit.as_ref().unwrap().changes.as_ref().unwrap()[&u]);
    assert!(after.contains("    {attribute 'sfc.final' := 'true'}\n    STEP Done:"), "{after}");
    c.stop();
}

fn scratch(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("sfc-lsp-test-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

#[test]
fn formatting_full_and_range() {
    let text = "PROGRAM P\nVAR_INPUT a:BOOL; END_VAR\n\n    INITIAL_STEP S1 :   END_STEP\n\n    STEP S2:END_STEP\n\n    TRANSITION FROM S1 TO S2 := a; END_TRANSITION\n    TRANSITION FROM S2 TO S1 := NOT a; END_TRANSITION\nEND_PROGRAM\n";
    let mut c = Client::start(None, no_idle());
    let path = fixture("unformatted.st");
    let u = c.open(&path, text);
    let opts = FormattingOptions { tab_size: 4, insert_spaces: true, ..FormattingOptions::default() };
    let edits = c
        .request::<req::Formatting>(DocumentFormattingParams {
            text_document: TextDocumentIdentifier::new(u.clone()),
            options: opts.clone(),
            work_done_progress_params: Default::default(),
        })
        .unwrap()
        .unwrap();
    let formatted = apply(text, &edits);
    let cli = Command::new(env!("CARGO_BIN_EXE_sfc"))
        .args(["fmt", "-"])
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .spawn()
        .and_then(|mut ch| {
            use std::io::Write;
            ch.stdin.take().unwrap().write_all(text.as_bytes())?;
            ch.wait_with_output()
        })
        .unwrap();
    assert_eq!(formatted, String::from_utf8(cli.stdout).unwrap(), "formatting equals `sfc fmt`");
    // Range: only the line of S2 (line 5); the initial step keeps its spacing.
    let edits = c
        .request::<req::RangeFormatting>(DocumentRangeFormattingParams {
            text_document: TextDocumentIdentifier::new(u.clone()),
            range: Range::new(Position::new(5, 0), Position::new(5, 20)),
            options: opts.clone(),
            work_done_progress_params: Default::default(),
        })
        .unwrap()
        .unwrap();
    let partly = apply(text, &edits);
    assert!(partly.contains("    STEP S2: END_STEP\n"), "{partly}");
    assert!(partly.contains("INITIAL_STEP S1 :   END_STEP"), "{partly}");
    // A syntax error: the request fails and says why.
    c.change(&u, 2, Range::new(Position::new(0, 0), Position::new(0, 7)), "PROGRAMM");
    let err = c
        .request::<req::Formatting>(DocumentFormattingParams {
            text_document: TextDocumentIdentifier::new(u.clone()),
            options: opts,
            work_done_progress_params: Default::default(),
        })
        .unwrap_err();
    assert!(err.starts_with("not formatted: the file has"), "{err}");
    c.stop();
}

fn locations(mut l: Vec<Location>) -> Vec<(u32, u32)> {
    l.sort_by_key(|l| (l.range.start.line, l.range.start.character));
    l.iter().map(|l| (l.range.start.line, l.range.start.character)).collect()
}

#[test]
fn definition_references_and_rename_of_a_step() {
    let text = std::fs::read_to_string(fixture("tank.st")).unwrap();
    let mut c = Client::start(None, no_idle());
    let u = c.open(&fixture("tank.st"), &text);
    // `Fill` is used in `Fill.X` (a condition) and in FROM/TO of two transitions.
    let use_in_code = at(&text, "Fill.X", 0, 1);
    let def = c
        .request::<req::GotoDefinition>(GotoDefinitionParams {
            text_document_position_params: Client::pos(&u, use_in_code.line, use_in_code.character),
            work_done_progress_params: Default::default(),
            partial_result_params: Default::default(),
        })
        .unwrap()
        .unwrap();
    let GotoDefinitionResponse::Array(def) = def else { panic!("{def:?}") };
    let decl = at(&text, "STEP Fill", 0, 5);
    assert_eq!(locations(def), [(decl.line, decl.character)]);
    let link = at(&text, "FROM Fill", 0, 5);
    let def = c
        .request::<req::GotoDefinition>(GotoDefinitionParams {
            text_document_position_params: Client::pos(&u, link.line, link.character + 2),
            work_done_progress_params: Default::default(),
            partial_result_params: Default::default(),
        })
        .unwrap()
        .unwrap();
    let GotoDefinitionResponse::Array(def) = def else { panic!() };
    assert_eq!(locations(def), [(decl.line, decl.character)]);

    let refs = c
        .request::<req::References>(ReferenceParams {
            text_document_position: Client::pos(&u, decl.line, decl.character),
            context: ReferenceContext { include_declaration: true },
            work_done_progress_params: Default::default(),
            partial_result_params: Default::default(),
        })
        .unwrap()
        .unwrap();
    let expect: Vec<(u32, u32)> = [at(&text, "TO Fill", 0, 3), decl, link, at(&text, "Fill.X", 0, 0)]
        .iter()
        .map(|p| (p.line, p.character))
        .collect();
    assert_eq!(locations(refs), expect);

    // Rename: every use, case-insensitively; a clash with another name of the POU is refused.
    let ws = c
        .request::<req::Rename>(RenameParams {
            text_document_position: Client::pos(&u, use_in_code.line, use_in_code.character),
            new_name: "Filling".into(),
            work_done_progress_params: Default::default(),
        })
        .unwrap()
        .unwrap();
    let renamed = apply(&text, &ws.changes.as_ref().unwrap()[&u]);
    assert!(
        renamed.contains("STEP Filling:")
            && renamed.contains("FROM Idle TO Filling")
            && renamed.contains("FROM Filling TO Heat")
            && renamed.contains("Filling.X = FALSE"),
        "{renamed}"
    );
    assert!(!renamed.contains("Fill:") && !renamed.contains("Fill.X"));
    let clash = c
        .request::<req::Rename>(RenameParams {
            text_document_position: Client::pos(&u, decl.line, decl.character),
            new_name: "VALVE".into(),
            work_done_progress_params: Default::default(),
        })
        .unwrap_err();
    assert!(clash.contains("`Valve` is already a variable of `Tank`") && clash.contains("one namespace"), "{clash}");
    let keyword = c
        .request::<req::Rename>(RenameParams {
            text_document_position: Client::pos(&u, decl.line, decl.character),
            new_name: "END_STEP".into(),
            work_done_progress_params: Default::default(),
        })
        .unwrap_err();
    assert!(keyword.contains("keyword"), "{keyword}");
    c.stop();
}

fn hover_text(c: &mut Client, u: &Uri, p: Position) -> String {
    let h = c
        .request::<req::HoverRequest>(HoverParams {
            text_document_position_params: Client::pos(u, p.line, p.character),
            work_done_progress_params: Default::default(),
        })
        .unwrap()
        .unwrap_or_else(|| panic!("no hover at {p:?}"));
    match h.contents {
        HoverContents::Markup(m) => m.value,
        other => panic!("{other:?}"),
    }
}

#[test]
fn hover_on_variables_steps_transitions_and_qualifiers() {
    let text = std::fs::read_to_string(fixture("tank.st")).unwrap();
    let mut c = Client::start(None, no_idle());
    let u = c.open(&fixture("tank.st"), &text);
    let level = hover_text(&mut c, &u, at(&text, "Level > 80", 0, 2));
    assert!(level.contains("Level AT %IW2 : INT := 0") && level.contains("section `VAR_INPUT`"), "{level}");
    let heat = hover_text(&mut c, &u, at(&text, "STEP Heat", 0, 6));
    assert!(heat.contains("**step Heat**"), "{heat}");
    assert!(heat.contains("`Heater(S)`, `Watch(L, T#30s)`"), "{heat}");
    assert!(heat.contains("incoming: `Full` from Fill"), "{heat}");
    assert!(heat.contains("outgoing: `Warm` to Drain when `Hot OR Heat.T > T#1m`"), "{heat}");
    let idle = hover_text(&mut c, &u, at(&text, "FROM Idle", 0, 6));
    assert!(idle.contains("initial step Idle"), "{idle}");
    let go = hover_text(&mut c, &u, at(&text, "TRANSITION Go", 0, 12));
    assert!(go.contains("FROM Idle TO Fill") && go.contains("no PRIORITY"), "{go}");
    let q = hover_text(&mut c, &u, at(&text, "Heater(S)", 0, 7));
    assert!(q.contains("qualifier S") && q.contains("until an R"), "{q}");
    let l = hover_text(&mut c, &u, at(&text, "Watch(L", 0, 6));
    assert!(l.contains("time limited"), "{l}");
    let open = hover_text(&mut c, &u, at(&text, "Open.Q", 0, 1));
    assert!(open.contains("**action Open**") && open.contains("`Fill` (N), `Drain` (P1)"), "{open}");
    c.stop();
}

fn labels(c: &mut Client, u: &Uri, p: Position) -> Vec<String> {
    let r = c
        .request::<req::Completion>(CompletionParams {
            text_document_position: Client::pos(u, p.line, p.character),
            work_done_progress_params: Default::default(),
            partial_result_params: Default::default(),
            context: None,
        })
        .unwrap()
        .unwrap();
    let items = match r {
        CompletionResponse::Array(a) => a,
        CompletionResponse::List(l) => l.items,
    };
    items.into_iter().map(|i| i.label).collect()
}

#[test]
fn completion_knows_the_context() {
    let text = std::fs::read_to_string(fixture("tank.st")).unwrap();
    let mut c = Client::start(None, no_idle());
    let u = c.open(&fixture("tank.st"), &text);
    // Type `Fill.` into the condition of `Go`: after `S1.` come the step's flags.
    let p = at(&text, "Start;", 0, 0);
    c.change(&u, 2, Range::new(p, p), "Fill.");
    assert_eq!(labels(&mut c, &u, Position::new(p.line, p.character + 5)), ["X", "T"]);
    let text2 = text.replacen("        := Start;", "        := Fill.Start;", 1);
    let p = at(&text2, "Open.Q", 0, 5);
    assert_eq!(labels(&mut c, &u, p), ["Q", "A"]);
    // Qualifiers inside an association, steps after FROM/TO, actions in a step.
    let q = at(&text2, "Open(N)", 0, 5);
    let quals = labels(&mut c, &u, q);
    assert_eq!(quals, ["N", "R", "S", "L", "D", "P", "SD", "DS", "SL", "P1", "P0"]);
    let f = at(&text2, "FROM Fill", 0, 5);
    let steps = labels(&mut c, &u, f);
    assert_eq!(steps, ["Idle", "Fill", "Heat", "Drain"]);
    let a = at(&text2, "Open(N)", 0, 0);
    let acts = labels(&mut c, &u, a);
    assert!(
        acts.contains(&"Open".to_string())
            && acts.contains(&"Watch".to_string())
            && acts.contains(&"Heater".to_string()),
        "{acts:?}"
    );
    assert!(!acts.contains(&"Level".to_string()), "an INT is no action: {acts:?}");
    // Between elements: snippets for the blocks.
    let between = at(&text2, "    STEP Fill", 0, 0);
    let snippets = labels(&mut c, &u, between);
    for s in ["STEP", "INITIAL_STEP", "TRANSITION", "ACTION"] {
        assert!(snippets.contains(&s.to_string()), "{s} in {snippets:?}");
    }
    // In code: variables, steps and actions, keywords.
    let code = at(&text2, "Hot OR", 0, 0);
    let names = labels(&mut c, &u, code);
    for n in ["Level", "Valve", "Heat", "Open", "AND", "SFCInit"] {
        assert!(names.contains(&n.to_string()), "{n} in {names:?}");
    }
    c.stop();
}

/// While typing in a long chart, completion answers from the last analysis with the edits made
/// since (the index worker parses the new text in the background): the same answers, at the
/// shifted places.
#[test]
fn completion_while_typing_follows_the_edits_since_the_last_analysis() {
    let text = std::fs::read_to_string(fixture("tank.st")).unwrap();
    let mut c = Client::start(None, no_idle());
    let u = c.open(&fixture("tank.st"), &text);
    // Analysed once (a hover needs it), then two lines inserted above everything.
    let _ = hover_text(&mut c, &u, at(&text, "Level", 0, 1));
    let head = "(* a comment\n   over two lines *)\n";
    c.change(&u, 2, Range::new(Position::new(0, 0), Position::new(0, 0)), head);
    let text2 = format!("{head}{text}");
    let p = at(&text2, "Start;", 0, 0);
    c.change(&u, 3, Range::new(p, p), "Fill.");
    assert_eq!(labels(&mut c, &u, Position::new(p.line, p.character + 5)), ["X", "T"]);
    let text3 = text2.replacen("Start;", "Fill.Start;", 1);
    assert_eq!(labels(&mut c, &u, at(&text3, "FROM Fill", 0, 5)), ["Idle", "Fill", "Heat", "Drain"]);
    let q = at(&text3, "Open(N)", 0, 5);
    assert_eq!(labels(&mut c, &u, q)[0], "N");
    c.stop();
}

#[test]
fn outline_and_semantic_tokens() {
    let text = std::fs::read_to_string(fixture("tank.st")).unwrap();
    let mut c = Client::start(None, no_idle());
    let u = c.open(&fixture("tank.st"), &text);
    let syms = c
        .request::<req::DocumentSymbolRequest>(DocumentSymbolParams {
            text_document: TextDocumentIdentifier::new(u.clone()),
            work_done_progress_params: Default::default(),
            partial_result_params: Default::default(),
        })
        .unwrap()
        .unwrap();
    let DocumentSymbolResponse::Nested(syms) = syms else { panic!() };
    assert_eq!(syms.len(), 1);
    let tank = &syms[0];
    assert_eq!((tank.name.as_str(), tank.detail.as_deref()), ("Tank", Some("PROGRAM")));
    let kids: Vec<String> = tank.children.as_ref().unwrap().iter().map(|s| s.name.clone()).collect();
    assert_eq!(
        kids,
        ["Start", "Level", "Hot", "Valve", "Heater", "Drained", "Idle", "Fill", "Heat", "Drain", "Open", "Watch"]
    );
    let fill = &tank.children.as_ref().unwrap()[7];
    assert_eq!(fill.detail.as_deref(), Some("step — Open(N)"));
    let out = fill.children.as_ref().unwrap();
    assert_eq!((out[0].name.as_str(), out[0].detail.as_deref()), ("Full", Some("Fill → Heat")));

    let tokens = c
        .request::<req::SemanticTokensFullRequest>(SemanticTokensParams {
            text_document: TextDocumentIdentifier::new(u.clone()),
            work_done_progress_params: Default::default(),
            partial_result_params: Default::default(),
        })
        .unwrap()
        .unwrap();
    let SemanticTokensResult::Tokens(tokens) = tokens else { panic!() };
    // Decode to (line, column, length, type) and look up two names: a step and a variable.
    let (mut line, mut col) = (0, 0);
    let mut decoded = Vec::new();
    for t in &tokens.data {
        if t.delta_line > 0 {
            col = 0;
        }
        line += t.delta_line;
        col += t.delta_start;
        decoded.push((line, col, t.length, t.token_type));
    }
    let ty = |p: Position| decoded.iter().find(|d| d.0 == p.line && d.1 == p.character).map(|d| d.3);
    let step = ty(at(&text, "Heat.T", 0, 0)).unwrap();
    let var = ty(at(&text, "Hot OR", 0, 0)).unwrap();
    let action = ty(at(&text, "Open.Q", 0, 0)).unwrap();
    let transition = ty(at(&text, "TRANSITION Warm", 0, 11)).unwrap();
    let legend = ["step", "action", "transition", "variable", "parameter"];
    assert_eq!(
        [step, action, transition, var].map(|t| legend.get(t as usize).copied().unwrap_or("?")),
        ["step", "action", "transition", "parameter"]
    );
    c.stop();
}

/// Methods, properties and interfaces are in the outline (under their POU, at file level).
#[test]
fn outline_holds_methods_properties_and_interfaces() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../tests/fixtures/invalid/objects_kept_as_written.st");
    let text = std::fs::read_to_string(&path).unwrap();
    let mut c = Client::start(None, no_idle());
    let u = c.open(&path, &text);
    let syms = c
        .request::<req::DocumentSymbolRequest>(DocumentSymbolParams {
            text_document: TextDocumentIdentifier::new(u.clone()),
            work_done_progress_params: Default::default(),
            partial_result_params: Default::default(),
        })
        .unwrap()
        .unwrap();
    let DocumentSymbolResponse::Nested(syms) = syms else { panic!() };
    let names: Vec<(&str, Option<&str>)> = syms.iter().map(|s| (s.name.as_str(), s.detail.as_deref())).collect();
    assert!(names.contains(&("I_Cylinder", Some("interface"))), "{names:?}");
    let cyl = syms.iter().find(|s| s.name == "FB_Cylinder").expect("FB_Cylinder");
    let kids: Vec<(&str, Option<&str>)> =
        cyl.children.as_ref().unwrap().iter().map(|s| (s.name.as_str(), s.detail.as_deref())).collect();
    assert!(kids.contains(&("Extend", Some("method"))), "{kids:?}");
    assert!(kids.contains(&("Position", Some("property"))), "{kids:?}");
    c.stop();
}

#[test]
fn a_hundred_rapid_edits_leave_no_stale_result() {
    let text = std::fs::read_to_string(fixture("tank.st")).unwrap();
    let mut c = Client::start(None, serde_json::json!({ "debounceMs": 5, "analysisIdleMs": 20 }));
    let u = c.open(&fixture("tank.st"), &text);
    c.diagnostics_for(&u, 1, |_| true);
    // Type and delete a character after `Start` in a condition: even versions have an
    // undeclared name (`StartX`), odd versions are clean. 100 edits without waiting.
    let p = at(&text, "Start;", 0, 5);
    for v in 2..=101 {
        if v % 2 == 0 {
            c.change(&u, v, Range::new(p, p), "X");
        } else {
            c.change(&u, v, Range::new(p, Position::new(p.line, p.character + 1)), "");
        }
    }
    // Version 101 deleted the last X: clean.
    let last = c.diagnostics_for(&u, 101, |_| true);
    assert!(last.is_empty(), "{last:#?}");
    // The server still answers, and nothing stale arrives after the final version.
    let h = hover_text(&mut c, &u, at(&text, "STEP Heat", 0, 6));
    assert!(h.contains("step Heat"));
    std::thread::sleep(Duration::from_millis(300));
    let _ = c.request::<req::DocumentSymbolRequest>(DocumentSymbolParams {
        text_document: TextDocumentIdentifier::new(u.clone()),
        work_done_progress_params: Default::default(),
        partial_result_params: Default::default(),
    });
    let versions: Vec<i32> = c.diagnostics.iter().filter(|p| p.uri == u).filter_map(|p| p.version).collect();
    assert!(versions.windows(2).all(|w| w[0] <= w[1]), "versions went back: {versions:?}");
    assert_eq!(versions.last(), Some(&101), "{versions:?}");
    for p in c.diagnostics.iter().filter(|p| p.uri == u) {
        let even = p.version.unwrap() % 2 == 0;
        let has_error = p.diagnostics.iter().any(|d| d.message.contains("StartX"));
        assert_eq!(even, has_error, "version {:?}: {:#?}", p.version, p.diagnostics);
    }
    eprintln!("100 edits: {} diagnostics notifications for {} versions", versions.len(), 101);
    c.stop();
}

#[test]
fn plcopen_xml_diagnostics_at_xml_positions() {
    let dir = scratch("xml");
    let st = dir.join("tank.st");
    std::fs::write(&st, std::fs::read_to_string(fixture("tank.st")).unwrap()).unwrap();
    let xml = dir.join("tank.xml");
    let out = Command::new(env!("CARGO_BIN_EXE_sfc"))
        .args(["build", "--target", "plcopen", "-o"])
        .arg(&xml)
        .arg(&st)
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let text = std::fs::read_to_string(&xml).unwrap().replacen("Level &gt; 80", "Levle &gt; 80", 1).replacen(
        "Level > 80",
        "Levle > 80",
        1,
    );
    assert!(text.contains("Levle"), "the export holds the condition");
    std::fs::write(&xml, &text).unwrap();
    let cli = Command::new(env!("CARGO_BIN_EXE_sfc")).args(["check", "--format", "json"]).arg(&xml).output().unwrap();
    let cli: serde_json::Value = serde_json::from_slice(&cli.stdout).unwrap();
    let mut c = Client::start(Some(&dir), no_idle());
    let u = c.open(&xml, &text);
    let diags = c.diagnostics_for(&u, 1, |d| !d.is_empty());
    let d = diags.iter().find(|d| d.message.contains("undeclared variable `Levle`")).expect("the XML's error");
    let first = &cli[0];
    assert_eq!(d.range.start.line + 1, first["line"].as_u64().unwrap() as u32, "the same line as `sfc check`");
    assert_eq!(d.range.start.character + 1, first["column"].as_u64().unwrap() as u32);
    let line = text.lines().nth(d.range.start.line as usize).unwrap();
    assert!(line.contains("Levle"), "{line}");
    c.stop();
}

#[test]
fn references_and_rename_across_workspace_files() {
    let dir = scratch("workspace");
    std::fs::write(dir.join("globals.st"), "VAR_GLOBAL\n    EmergencyStop AT %IX0.0 : BOOL;\nEND_VAR\n").unwrap();
    let main = "PROGRAM Line\n    VAR_EXTERNAL\n        EmergencyStop : BOOL;\n    END_VAR\n    INITIAL_STEP Run:\n    END_STEP\n    TRANSITION FROM Run TO Halt\n        := EmergencyStop;\n    END_TRANSITION\n    STEP Halt:\n    END_STEP\n    TRANSITION FROM Halt TO Run\n        := NOT EmergencyStop;\n    END_TRANSITION\nEND_PROGRAM\n";
    std::fs::write(dir.join("line.st"), main).unwrap();
    let mut c = Client::start(Some(&dir), no_idle());
    let u = c.open(&dir.join("line.st"), main);
    let p = at(main, "EmergencyStop;", 1, 3);
    let refs = c
        .request::<req::References>(ReferenceParams {
            text_document_position: Client::pos(&u, p.line, p.character),
            context: ReferenceContext { include_declaration: true },
            work_done_progress_params: Default::default(),
            partial_result_params: Default::default(),
        })
        .unwrap()
        .unwrap();
    let files: std::collections::BTreeSet<String> =
        refs.iter().map(|l| l.uri.as_str().rsplit('/').next().unwrap().to_string()).collect();
    assert_eq!(files.into_iter().collect::<Vec<_>>(), ["globals.st", "line.st"]);
    assert_eq!(refs.len(), 4, "{refs:#?}");
    let def = c
        .request::<req::GotoDefinition>(GotoDefinitionParams {
            text_document_position_params: Client::pos(&u, p.line, p.character),
            work_done_progress_params: Default::default(),
            partial_result_params: Default::default(),
        })
        .unwrap()
        .unwrap();
    let GotoDefinitionResponse::Array(def) = def else { panic!() };
    assert!(def[0].uri.as_str().ends_with("/globals.st") && def[0].range.start == Position::new(1, 4), "{def:?}");
    let hover = hover_text(&mut c, &u, p);
    assert!(hover.contains("EmergencyStop AT %IX0.0 : BOOL") && hover.contains("globals.st"), "{hover}");
    let edit = c
        .request::<req::Rename>(RenameParams {
            text_document_position: Client::pos(&u, p.line, p.character),
            new_name: "EStop".into(),
            work_done_progress_params: Default::default(),
        })
        .unwrap()
        .unwrap();
    let changes = edit.changes.unwrap();
    assert_eq!(changes.len(), 2);
    let g = changes.iter().find(|(k, _)| k.as_str().ends_with("/globals.st")).unwrap().1;
    assert_eq!(
        apply(&std::fs::read_to_string(dir.join("globals.st")).unwrap(), g),
        "VAR_GLOBAL\n    EStop AT %IX0.0 : BOOL;\nEND_VAR\n"
    );
    let clash = c
        .request::<req::Rename>(RenameParams {
            text_document_position: Client::pos(&u, p.line, p.character),
            new_name: "run".into(),
            work_done_progress_params: Default::default(),
        })
        .unwrap_err();
    assert!(clash.contains("`Run` is already a step"), "{clash}");
    c.stop();
}

#[test]
fn property_file_diagnostics_while_typing_and_the_proof_on_save() {
    let dir = scratch("props");
    let prover = Path::new(env!("CARGO_MANIFEST_DIR")).join("../sfc-prove/tests/fixtures");
    std::fs::copy(prover.join("carwash.st"), dir.join("carwash.st")).unwrap();
    let good = std::fs::read_to_string(prover.join("carwash.props.toml")).unwrap();
    std::fs::write(dir.join("carwash.props.toml"), &good).unwrap();
    let mut c = Client::start(Some(&dir), no_idle());
    // A name the chart does not declare: SFC1001 at its line, while typing.
    let bad_path = dir.join("carwash.props.toml");
    let bad = "[[property]]\nname = \"x\"\nnever = \"Travel AND Nonsense\"\n";
    let u = c.open(&bad_path, bad);
    let code = |d: &Diagnostic| d.code.clone();
    let found = c.diagnostics_for(&u, 1, |d| !d.is_empty());
    assert_eq!(code(&found[0]), Some(NumberOrString::String("SFC1001".into())), "{found:#?}");
    assert_eq!(found[0].range.start.line, 2, "{found:#?}");
    assert!(found[0].message.contains("Nonsense"), "{}", found[0].message);
    // The real requirements, then saved: the proof finds the violated one at its [[property]].
    let end = Position::new(3, 0);
    c.change(&u, 2, Range::new(Position::new(0, 0), end), &good);
    let typed = c.diagnostics_for(&u, 2, |_| true);
    assert!(typed.is_empty(), "no errors while typing valid requirements: {typed:#?}");
    c.notify::<note::DidSaveTextDocument>(DidSaveTextDocumentParams {
        text_document: TextDocumentIdentifier::new(u.clone()),
        text: None,
    });
    let proved = c.diagnostics_for(&u, 2, |d| !d.is_empty());
    assert_eq!(proved.len(), 1, "{proved:#?}");
    assert_eq!(code(&proved[0]), Some(NumberOrString::String("SFC1002".into())));
    assert!(proved[0].message.contains("no travel without a car"), "{}", proved[0].message);
    let line = good.lines().position(|l| l.contains("no travel without a car")).unwrap() as u32;
    assert!(proved[0].range.start.line + 1 >= line && proved[0].range.start.line <= line, "{proved:#?}");
    c.stop();
}

/// `sfc check -` on `text`: whether it has no error.
fn checks(text: &str) -> bool {
    let out = Command::new(env!("CARGO_BIN_EXE_sfc"))
        .args(["check", "-"])
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .and_then(|mut ch| {
            use std::io::Write;
            ch.stdin.take().unwrap().write_all(text.as_bytes())?;
            ch.wait_with_output()
        })
        .unwrap();
    out.status.success()
}

/// A function block with a method, a property and an action in one file, used in another:
/// definition goes to the member (and a method's variable to the method's declaration), rename
/// changes both files, and the outline holds the members.
#[test]
fn methods_properties_and_actions_across_files() {
    let dir = scratch("methods");
    let motor = "FUNCTION_BLOCK Motor\n  VAR_INPUT speed : INT; END_VAR\n  VAR_OUTPUT on : BOOL; END_VAR\n  VAR count : INT; tmp : INT; END_VAR\n  METHOD Start : BOOL\n    VAR_INPUT s : INT; END_VAR\n    VAR tmp : INT; END_VAR\n    tmp := s + speed; count := count + 1; on := TRUE; Start := TRUE;\n  END_METHOD\n  PROPERTY Running : BOOL\n    GET Running := on; END_GET\n    SET on := Running; END_SET\n  END_PROPERTY\n  count := 0; tmp := 1;\n  ACTION Reset:\n    count := 0; Start(s := 1); THIS^.Start(s := 2);\n  END_ACTION\nEND_FUNCTION_BLOCK\n";
    let main = "PROGRAM Main\n  VAR m : Motor; ok : BOOL; END_VAR\n  ok := m.Start(s := 5);\n  IF m.Running THEN m.Reset(); END_IF\n  m.Running := FALSE;\nEND_PROGRAM\n";
    assert!(checks(&format!("{motor}{main}")), "the fixture is valid");
    std::fs::write(dir.join("motor.st"), motor).unwrap();
    std::fs::write(dir.join("main.st"), main).unwrap();
    let mut c = Client::start(Some(&dir), no_idle());
    let mu = c.open(&dir.join("motor.st"), motor);
    let pu = c.open(&dir.join("main.st"), main);
    let definition = |c: &mut Client, u: &Uri, p: Position| {
        let def = c
            .request::<req::GotoDefinition>(GotoDefinitionParams {
                text_document_position_params: Client::pos(u, p.line, p.character),
                work_done_progress_params: Default::default(),
                partial_result_params: Default::default(),
            })
            .unwrap()
            .unwrap();
        let GotoDefinitionResponse::Array(def) = def else { panic!("{def:?}") };
        def.iter().map(|l| (l.uri.as_str().rsplit('/').next().unwrap().to_string(), l.range.start)).collect::<Vec<_>>()
    };
    let in_motor = |needle: &str, n: usize| vec![("motor.st".to_string(), at(motor, needle, n, 0))];
    assert_eq!(definition(&mut c, &pu, at(main, "m.Start", 0, 3)), in_motor("Start : BOOL", 0));
    assert_eq!(definition(&mut c, &pu, at(main, "m.Running :=", 0, 3)), in_motor("Running : BOOL", 0));
    assert_eq!(definition(&mut c, &pu, at(main, "m.Reset", 0, 3)), in_motor("Reset:", 0));
    assert_eq!(definition(&mut c, &mu, at(motor, "Start(s := 1)", 0, 1)), in_motor("Start : BOOL", 0));
    // The method's `tmp`, not the block's; the block's `count` from the method.
    assert_eq!(definition(&mut c, &mu, at(motor, "tmp := s", 0, 1)), in_motor("tmp : INT; END_VAR\n    tmp", 0));
    assert_eq!(definition(&mut c, &mu, at(motor, "count + 1", 0, 1)), in_motor("count : INT", 0));

    let rename = |c: &mut Client, u: &Uri, p: Position, new_name: &str| {
        let edit = c
            .request::<req::Rename>(RenameParams {
                text_document_position: Client::pos(u, p.line, p.character),
                new_name: new_name.into(),
                work_done_progress_params: Default::default(),
            })
            .unwrap()
            .unwrap();
        let changes = edit.changes.unwrap();
        let file = |u: &Uri, text: &str| changes.get(u).map_or(text.to_string(), |e| apply(text, e));
        (file(&mu, motor), file(&pu, main))
    };
    // A method, from a call on an instance in the other file.
    let (m2, p2) = rename(&mut c, &pu, at(main, "m.Start", 0, 2), "Launch");
    assert_eq!(
        (m2.as_str(), p2.as_str()),
        (motor.replace("Start", "Launch").as_str(), main.replace("Start", "Launch").as_str())
    );
    assert!(checks(&format!("{m2}{p2}")));
    // A property, from its SET: its uses read and written, its GET and SET.
    let (m2, p2) = rename(&mut c, &mu, at(motor, "on := Running", 0, 8), "Active");
    assert_eq!(
        (m2.as_str(), p2.as_str()),
        (motor.replace("Running", "Active").as_str(), main.replace("Running", "Active").as_str())
    );
    assert!(checks(&format!("{m2}{p2}")));
    // The method's parameter: also the formal parameters of its calls.
    let (m2, p2) = rename(&mut c, &mu, at(motor, "s : INT", 0, 0), "setpoint");
    assert_eq!(
        m2,
        motor
            .replace("s : INT", "setpoint : INT")
            .replace("s + speed", "setpoint + speed")
            .replace("(s :=", "(setpoint :=")
    );
    assert_eq!(p2, main.replace("(s :=", "(setpoint :="));
    assert!(checks(&format!("{m2}{p2}")));
    // The method's variable: only in the method.
    let (m2, p2) = rename(&mut c, &mu, at(motor, "tmp := s", 0, 0), "sum");
    assert_eq!(m2, motor.replace("VAR tmp", "VAR sum").replace("tmp := s", "sum := s"));
    assert_eq!(p2, main);
    assert!(checks(&format!("{m2}{p2}")));

    let syms = c
        .request::<req::DocumentSymbolRequest>(DocumentSymbolParams {
            text_document: TextDocumentIdentifier::new(mu.clone()),
            work_done_progress_params: Default::default(),
            partial_result_params: Default::default(),
        })
        .unwrap()
        .unwrap();
    let DocumentSymbolResponse::Nested(syms) = syms else { panic!() };
    let kids = syms[0].children.as_ref().unwrap();
    let names: Vec<(&str, Option<&str>)> = kids.iter().map(|s| (s.name.as_str(), s.detail.as_deref())).collect();
    assert!(
        names.ends_with(&[("Reset", Some("action")), ("Start", Some("method")), ("Running", Some("property"))]),
        "{names:?}"
    );
    let start = kids.iter().find(|s| s.name == "Start").unwrap();
    let vars: Vec<&str> = start.children.as_ref().unwrap().iter().map(|s| s.name.as_str()).collect();
    assert_eq!(vars, ["s", "tmp"]);
    c.stop();
}
