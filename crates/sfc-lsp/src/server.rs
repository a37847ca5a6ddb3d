//! The main loop: reads requests and notifications, answers requests from the documents'
//! indexes, hands checks to the workers and publishes their diagnostics when they are still
//! current.

use crate::check::{self, DiagnosticsProvider, Job, Outcome};
use crate::workspace::{path_of, DocKind, Document, View, Workspace};
use crate::{actions, complete, format, hover, navigate, symbols, text, tokens};
use crossbeam_channel::{select, Receiver, Sender};
use lsp_server::{Connection, ErrorCode, Message, Notification, Request, RequestId, Response};
use lsp_types::notification::{self as note, Notification as _};
use lsp_types::request::{self as req, Request as _};
use lsp_types::*;
use std::collections::HashMap;
use std::sync::Arc;
use std::time::Duration;

/// How the server behaves.
pub struct ServerOptions {
    /// Diagnostics producers, asked in order; the first that handles a document checks it.
    pub providers: Vec<Box<dyn DiagnosticsProvider>>,
    /// Quiet time after an edit before the document is checked (without the analysis).
    pub debounce: Duration,
    /// Quiet time after an edit before the full check with the analysis; `None`: only on save.
    pub idle: Option<Duration>,
}

impl Default for ServerOptions {
    fn default() -> Self {
        ServerOptions {
            providers: vec![Box::new(check::ChartDiagnostics)],
            debounce: Duration::from_millis(30),
            idle: Some(Duration::from_millis(1500)),
        }
    }
}

/// Serves on standard input and output until the client says `exit`.
pub fn run_stdio(options: ServerOptions) -> Result<(), String> {
    let (connection, io_threads) = Connection::stdio();
    serve(connection, options)?;
    io_threads.join().map_err(|e| format!("the connection failed: {e}"))
}

/// The settings a client may pass in `initializationOptions`.
#[derive(Debug, Default, serde::Deserialize)]
#[serde(rename_all = "camelCase", default)]
struct InitOptions {
    /// Milliseconds of quiet before a check after an edit.
    debounce_ms: Option<u64>,
    /// Milliseconds of quiet before the analysis; 0 turns the idle analysis off (on save only).
    analysis_idle_ms: Option<u64>,
}

fn capabilities() -> ServerCapabilities {
    ServerCapabilities {
        position_encoding: Some(PositionEncodingKind::UTF16),
        text_document_sync: Some(TextDocumentSyncCapability::Options(TextDocumentSyncOptions {
            open_close: Some(true),
            change: Some(TextDocumentSyncKind::INCREMENTAL),
            will_save: None,
            will_save_wait_until: None,
            save: Some(TextDocumentSyncSaveOptions::SaveOptions(SaveOptions { include_text: Some(false) })),
        })),
        hover_provider: Some(HoverProviderCapability::Simple(true)),
        completion_provider: Some(CompletionOptions {
            trigger_characters: Some(vec![".".into(), "(".into(), ",".into()]),
            ..CompletionOptions::default()
        }),
        definition_provider: Some(OneOf::Left(true)),
        references_provider: Some(OneOf::Left(true)),
        rename_provider: Some(OneOf::Right(RenameOptions {
            prepare_provider: Some(true),
            work_done_progress_options: Default::default(),
        })),
        document_symbol_provider: Some(OneOf::Left(true)),
        document_formatting_provider: Some(OneOf::Left(true)),
        document_range_formatting_provider: Some(OneOf::Left(true)),
        code_action_provider: Some(CodeActionProviderCapability::Options(CodeActionOptions {
            code_action_kinds: Some(vec![CodeActionKind::QUICKFIX, CodeActionKind::REFACTOR_REWRITE]),
            ..CodeActionOptions::default()
        })),
        semantic_tokens_provider: Some(SemanticTokensServerCapabilities::SemanticTokensOptions(
            SemanticTokensOptions {
                legend: tokens::legend(),
                range: None,
                full: Some(SemanticTokensFullOptions::Bool(true)),
                work_done_progress_options: Default::default(),
            },
        )),
        ..ServerCapabilities::default()
    }
}

/// Serves a connection (after `initialize`) until `exit`.
pub fn serve(connection: Connection, mut options: ServerOptions) -> Result<(), String> {
    let caps = serde_json::to_value(capabilities()).map_err(|e| e.to_string())?;
    let init = connection.initialize(caps).map_err(|e| format!("initialisation failed: {e}"))?;
    let params: InitializeParams =
        serde_json::from_value(init).map_err(|e| format!("bad initialize parameters: {e}"))?;
    let init_options = match params.initialization_options.clone().map(serde_json::from_value::<InitOptions>) {
        Some(Ok(o)) => Some(o),
        Some(Err(e)) => {
            // Nothing silent: the editor's log says which settings were not taken.
            let note = LogMessageParams {
                typ: MessageType::WARNING,
                message: format!("sfc lsp: initializationOptions ignored, the defaults are used: {e}"),
            };
            let _ = connection.sender.send(lsp_server::Message::Notification(lsp_server::Notification::new(
                "window/logMessage".into(),
                note,
            )));
            None
        }
        None => None,
    };
    if let Some(o) = init_options {
        if let Some(ms) = o.debounce_ms {
            options.debounce = Duration::from_millis(ms);
        }
        match o.analysis_idle_ms {
            Some(0) => options.idle = None,
            Some(ms) => options.idle = Some(Duration::from_millis(ms)),
            None => {}
        }
    }
    let mut roots: Vec<std::path::PathBuf> =
        params.workspace_folders.iter().flatten().map(|f| path_of(&f.uri)).collect();
    #[allow(deprecated)]
    if roots.is_empty() {
        roots.extend(params.root_uri.as_ref().map(path_of));
    }
    let providers = Arc::new(std::mem::take(&mut options.providers));
    let (check_tx, check_rx) = crossbeam_channel::unbounded();
    let (analysis_tx, analysis_rx) = crossbeam_channel::unbounded();
    let (index_tx, index_rx) = crossbeam_channel::unbounded();
    let (out_tx, out_rx) = crossbeam_channel::unbounded();
    let workers = [
        check::spawn_worker("sfc-lsp-check", check_rx, out_tx.clone(), providers.clone(), Some(index_tx.clone())),
        check::spawn_worker("sfc-lsp-analysis", analysis_rx, out_tx.clone(), providers, None),
        check::spawn_index_worker("sfc-lsp-index", index_rx, out_tx),
    ];
    let mut server = Server {
        conn: &connection,
        ws: Workspace::new(roots),
        check_tx,
        analysis_tx,
        index_tx,
        indexing: HashMap::new(),
        outcomes: out_rx.clone(),
        published: HashMap::new(),
        options,
    };
    let result = server.run(&out_rx);
    drop(server);
    for w in workers.into_iter().flatten() {
        let _ = w.join();
    }
    result
}

struct Server<'c> {
    conn: &'c Connection,
    ws: Workspace,
    check_tx: Sender<Job>,
    analysis_tx: Sender<Job>,
    /// Parses and indexes each new version in the background (requests then find it made).
    index_tx: Sender<Job>,
    /// URI → the version the index worker was last asked to parse (until it answers).
    indexing: HashMap<String, i32>,
    /// The workers' outcomes (also read while a request waits for the index worker).
    outcomes: Receiver<Outcome>,
    /// URI → (version, with analysis) of the diagnostics last published.
    published: HashMap<String, (i32, bool)>,
    options: ServerOptions,
}

type Handled = Result<serde_json::Value, (ErrorCode, String)>;

fn params<P: serde::de::DeserializeOwned>(v: serde_json::Value) -> Result<P, (ErrorCode, String)> {
    serde_json::from_value(v).map_err(|e| (ErrorCode::InvalidParams, e.to_string()))
}

fn to_json<T: serde::Serialize>(v: T) -> Handled {
    serde_json::to_value(v).map_err(|e| (ErrorCode::InternalError, e.to_string()))
}

fn failed(msg: impl Into<String>) -> (ErrorCode, String) {
    (ErrorCode::RequestFailed, msg.into())
}

impl Server<'_> {
    fn run(&mut self, outcomes: &Receiver<Outcome>) -> Result<(), String> {
        loop {
            select! {
                recv(self.conn.receiver) -> msg => {
                    let Ok(msg) = msg else { return Ok(()) };
                    match msg {
                        Message::Request(r) => {
                            if self.conn.handle_shutdown(&r).map_err(|e| e.to_string())? {
                                return Ok(());
                            }
                            self.request(r);
                        }
                        Message::Notification(n) => {
                            if n.method == note::Exit::METHOD {
                                return Ok(());
                            }
                            self.notification(n);
                        }
                        Message::Response(_) => {}
                    }
                }
                recv(outcomes) -> o => {
                    if let Ok(o) = o {
                        self.publish(o);
                    }
                }
            }
        }
    }

    fn send(&self, msg: Message) {
        let _ = self.conn.sender.send(msg);
    }

    fn log(&self, typ: MessageType, message: String) {
        self.send(Message::Notification(Notification::new(
            note::LogMessage::METHOD.to_string(),
            LogMessageParams { typ, message },
        )));
    }

    fn publish(&mut self, o: Outcome) {
        if let Some(f) = &o.failure {
            self.log(MessageType::ERROR, f.clone());
        }
        if o.from_index {
            if self.indexing.get(o.uri.as_str()) == Some(&o.version) {
                self.indexing.remove(o.uri.as_str());
            }
            if let (Some(a), Some(doc)) = (o.indexed, self.ws.open.get_mut(o.uri.as_str())) {
                doc.offer(o.version, a);
            }
            return;
        }
        let Some(doc) = self.ws.open.get(o.uri.as_str()) else { return };
        if doc.version != o.version {
            return; // stale: a newer version is on its way
        }
        let key = o.uri.as_str().to_string();
        if !o.analysis && self.published.get(&key) == Some(&(o.version, true)) {
            return; // the full check of this version is already shown
        }
        self.published.insert(key, (o.version, o.analysis));
        self.send(Message::Notification(Notification::new(
            note::PublishDiagnostics::METHOD.to_string(),
            PublishDiagnosticsParams { uri: o.uri, diagnostics: o.diagnostics, version: Some(o.version) },
        )));
    }

    /// Sends the document's jobs to the workers; true when the index worker gets one (from the
    /// quick check, which parses once for both, or directly).
    fn schedule(&self, doc: &Document, quick: Option<Duration>, analysis: Option<Duration>) -> bool {
        let wants_index = doc.kind == DocKind::Iec && !doc.analysed();
        let job = |analysis: bool, delay: Duration, index: bool| Job {
            uri: doc.uri.clone(),
            version: doc.version,
            path: doc.path.clone(),
            language: doc.language.clone(),
            text: doc.text.clone(),
            analysis,
            delay,
            index,
            parsed: None,
        };
        if let Some(d) = analysis {
            let _ = self.analysis_tx.send(job(true, d, false));
        }
        match quick {
            Some(d) => self.check_tx.send(job(false, d, wants_index)).is_ok() && wants_index,
            None => wants_index && self.index_tx.send(job(false, Duration::ZERO, false)).is_ok(),
        }
    }

    fn notification(&mut self, n: Notification) {
        match n.method.as_str() {
            note::DidOpenTextDocument::METHOD => {
                let Ok(p) = serde_json::from_value::<DidOpenTextDocumentParams>(n.params) else { return };
                let d = p.text_document;
                let doc = Document::new(d.uri.clone(), d.language_id, d.version, d.text);
                if self.schedule(&doc, Some(Duration::ZERO), self.options.idle) {
                    self.indexing.insert(d.uri.as_str().to_string(), d.version);
                }
                self.ws.open.insert(d.uri.as_str().to_string(), doc);
            }
            note::DidChangeTextDocument::METHOD => {
                let Ok(p) = serde_json::from_value::<DidChangeTextDocumentParams>(n.params) else { return };
                let Some(doc) = self.ws.open.get_mut(p.text_document.uri.as_str()) else { return };
                let mut t = doc.text.as_str().to_string();
                let edits = text::apply_changes(&mut t, p.content_changes);
                doc.set_text_edited(p.text_document.version, t, edits);
                let (debounce, idle) = (self.options.debounce, self.options.idle);
                if let Some(doc) = self.ws.open.get(p.text_document.uri.as_str()) {
                    if self.schedule(doc, Some(debounce), idle) {
                        self.indexing.insert(p.text_document.uri.as_str().to_string(), p.text_document.version);
                    }
                }
            }
            note::DidSaveTextDocument::METHOD => {
                let Ok(p) = serde_json::from_value::<DidSaveTextDocumentParams>(n.params) else { return };
                if let Some(doc) = self.ws.open.get(p.text_document.uri.as_str()) {
                    if self.schedule(doc, None, Some(Duration::ZERO)) {
                        self.indexing.insert(p.text_document.uri.as_str().to_string(), doc.version);
                    }
                }
            }
            note::DidCloseTextDocument::METHOD => {
                let Ok(p) = serde_json::from_value::<DidCloseTextDocumentParams>(n.params) else { return };
                let uri = p.text_document.uri;
                self.ws.open.remove(uri.as_str());
                self.published.remove(uri.as_str());
                self.indexing.remove(uri.as_str());
                self.send(Message::Notification(Notification::new(
                    note::PublishDiagnostics::METHOD.to_string(),
                    PublishDiagnosticsParams { uri, diagnostics: Vec::new(), version: None },
                )));
            }
            _ => {}
        }
    }

    fn request(&mut self, r: Request) {
        let id = r.id.clone();
        let result = self.handle(r);
        let response = match result {
            Ok(v) => Response { id, response_result: Ok(v) },
            Err((code, message)) => Response::new_err(id, code as i32, message),
        };
        self.send(Message::Response(response));
    }

    fn analysis_of(&mut self, uri: &Uri) -> Result<Arc<crate::workspace::Analysis>, (ErrorCode, String)> {
        if let Some(doc) = self.ws.doc(uri) {
            if doc.kind != DocKind::Iec {
                return Err(failed("only IEC text has this feature (PLCopen XML: diagnostics only)"));
            }
        }
        self.await_index(uri);
        self.ws.analysis(uri).ok_or_else(|| failed(format!("`{}` is not an open or readable IEC text", uri.as_str())))
    }

    /// When the index worker is parsing the current version of an open document, waits for it
    /// (publishing what the other workers send meanwhile) rather than parsing it a second time;
    /// bounded, then the request parses it itself.
    fn await_index(&mut self, uri: &Uri) {
        let key = uri.as_str();
        let deadline = std::time::Instant::now() + INDEX_WAIT;
        loop {
            let Some(doc) = self.ws.open.get(key) else { return };
            if doc.analysed() || self.indexing.get(key) != Some(&doc.version) {
                return;
            }
            let Some(left) = deadline.checked_duration_since(std::time::Instant::now()) else { return };
            match self.outcomes.recv_timeout(left) {
                Ok(o) => self.publish(o),
                Err(_) => return,
            }
        }
    }

    fn handle(&mut self, r: Request) -> Handled {
        let _: &RequestId = &r.id;
        match r.method.as_str() {
            req::HoverRequest::METHOD => {
                let p: HoverParams = params(r.params)?;
                let uri = p.text_document_position_params.text_document.uri;
                let a = self.analysis_of(&uri)?;
                let offset = a.offset(p.text_document_position_params.position);
                to_json(hover::hover(&mut self.ws, &uri, &a, offset))
            }
            req::Completion::METHOD => {
                let p: CompletionParams = params(r.params)?;
                let uri = p.text_document_position.text_document.uri;
                // While typing in a long chart, the last analysis with the edits since answers
                // at once (parsing again takes a while); else the current one.
                let view = match self.ws.open.get(uri.as_str()).and_then(|d| d.quick_view()) {
                    Some(v) => v,
                    None => {
                        let a = self.analysis_of(&uri)?;
                        View { text: a.text.clone(), lines: Arc::new(a.lines.clone()), analysis: a, edits: Vec::new() }
                    }
                };
                let offset = view.offset(p.text_document_position.position);
                let mut items = complete::complete_view(&view, offset);
                // A long chart has thousands of names: send those that match what is typed.
                let mut incomplete = false;
                if items.len() > MAX_ITEMS {
                    let prefix = typed_prefix(&view.text, offset).to_ascii_uppercase();
                    items.retain(|i| i.label.to_ascii_uppercase().starts_with(&prefix));
                    if items.len() > MAX_ITEMS {
                        items.truncate(MAX_ITEMS);
                        incomplete = true;
                    }
                }
                to_json(CompletionResponse::List(CompletionList { is_incomplete: incomplete, items }))
            }
            req::GotoDefinition::METHOD => {
                let p: GotoDefinitionParams = params(r.params)?;
                let uri = p.text_document_position_params.text_document.uri;
                let a = self.analysis_of(&uri)?;
                let offset = a.offset(p.text_document_position_params.position);
                let Some((identity, _)) = navigate::identity_at(&mut self.ws, &uri, &a, offset) else {
                    return to_json(());
                };
                let locs: Vec<Location> = navigate::declarations(&mut self.ws, &uri, &a, &identity)
                    .iter()
                    .filter_map(|f| Some(navigate::location(&f.uri, &f.analysis, f.symbol()?.name_span)))
                    .collect();
                to_json(GotoDefinitionResponse::Array(locs))
            }
            req::References::METHOD => {
                let p: ReferenceParams = params(r.params)?;
                let uri = p.text_document_position.text_document.uri;
                let a = self.analysis_of(&uri)?;
                let offset = a.offset(p.text_document_position.position);
                let Some((identity, _)) = navigate::identity_at(&mut self.ws, &uri, &a, offset) else {
                    return to_json(());
                };
                let locs: Vec<Location> = navigate::references(&mut self.ws, &uri, &a, &identity)
                    .into_iter()
                    .filter(|(_, _, _, decl)| p.context.include_declaration || !decl)
                    .map(|(u, fa, span, _)| navigate::location(&u, &fa, span))
                    .collect();
                to_json(locs)
            }
            req::PrepareRenameRequest::METHOD => {
                let p: TextDocumentPositionParams = params(r.params)?;
                let a = self.analysis_of(&p.text_document.uri)?;
                let offset = a.offset(p.position);
                let range = navigate::prepare_rename(&mut self.ws, &p.text_document.uri, &a, offset).map_err(failed)?;
                to_json(PrepareRenameResponse::Range(range))
            }
            req::Rename::METHOD => {
                let p: RenameParams = params(r.params)?;
                let uri = p.text_document_position.text_document.uri;
                let a = self.analysis_of(&uri)?;
                let offset = a.offset(p.text_document_position.position);
                let (identity, _) =
                    navigate::identity_at(&mut self.ws, &uri, &a, offset).ok_or_else(|| failed("no name here"))?;
                navigate::prepare_rename(&mut self.ws, &uri, &a, offset).map_err(failed)?;
                let edit = navigate::rename(&mut self.ws, &uri, &a, &identity, &p.new_name).map_err(failed)?;
                to_json(edit)
            }
            req::DocumentSymbolRequest::METHOD => {
                let p: DocumentSymbolParams = params(r.params)?;
                let a = self.analysis_of(&p.text_document.uri)?;
                to_json(DocumentSymbolResponse::Nested(symbols::document_symbols(&a)))
            }
            req::Formatting::METHOD => {
                let p: DocumentFormattingParams = params(r.params)?;
                self.format(&p.text_document.uri, None)
            }
            req::RangeFormatting::METHOD => {
                let p: DocumentRangeFormattingParams = params(r.params)?;
                let lines = (p.range.start.line, p.range.end.line);
                self.format(&p.text_document.uri, Some(lines))
            }
            req::CodeActionRequest::METHOD => {
                let p: CodeActionParams = params(r.params)?;
                let a = self.analysis_of(&p.text_document.uri)?;
                to_json(actions::code_actions(&p.text_document.uri, &a, p.range, &p.context.diagnostics))
            }
            req::SemanticTokensFullRequest::METHOD => {
                let p: SemanticTokensParams = params(r.params)?;
                let a = self.analysis_of(&p.text_document.uri)?;
                to_json(SemanticTokensResult::Tokens(SemanticTokens {
                    result_id: None,
                    data: tokens::semantic_tokens(&a),
                }))
            }
            "sfc/explain" => {
                #[derive(serde::Deserialize)]
                struct P {
                    code: String,
                }
                let p: P = params(r.params)?;
                let code = p.code.trim_start_matches("sfc-explain:").to_ascii_uppercase();
                let info =
                    sfc_diagnostics::explain(&code).ok_or_else(|| failed(format!("no diagnostic code `{code}`")))?;
                to_json(format!(
                    "# {} ({}): {}\n\n{}\n",
                    info.code,
                    info.severity.as_str(),
                    info.title,
                    info.explanation
                ))
            }
            other => Err((ErrorCode::MethodNotFound, format!("sfc lsp does not implement `{other}`"))),
        }
    }

    fn format(&mut self, uri: &Uri, lines: Option<(u32, u32)>) -> Handled {
        let (name, text) = match self.ws.doc(uri) {
            Some(d) => (d.path.display().to_string(), d.text.clone()),
            None => return Err(failed("the document is not open")),
        };
        let edits = format::format(&name, &text, lines).map_err(failed)?;
        to_json(edits)
    }
}

/// At most this many completion items are sent at once.
/// A request waits at most this long for the index worker before parsing the text itself.
const INDEX_WAIT: Duration = Duration::from_secs(10);

const MAX_ITEMS: usize = 500;

/// The part of an identifier before `offset`.
fn typed_prefix(text: &str, offset: u32) -> &str {
    let before = text.get(..offset as usize).unwrap_or("");
    let start = before.rfind(|c: char| !(c.is_ascii_alphanumeric() || c == '_')).map_or(0, |i| i + 1);
    before.get(start..).unwrap_or("")
}
