//! Diagnostics: who produces them for which kind of file ([`DiagnosticsProvider`]), how they
//! become LSP diagnostics, and the worker threads that check documents in the background so the
//! reader of the connection never waits for a check.
//!
//! Two workers: the *check* worker runs `sfc check` without the analysis shortly after each
//! edit (debounced); the *analysis* worker runs the full `sfc check`, analysis included, when
//! the document is saved or has been idle for a while. Results carry the document version they
//! were computed for; the server drops those of an older version.

use crate::text::LineIndex;
use crate::workspace::Analysis;
use crossbeam_channel::{Receiver, RecvTimeoutError, Sender};
use lsp_types::{CodeDescription, DiagnosticRelatedInformation, DiagnosticSeverity, Location, NumberOrString, Uri};
use sfc_diagnostics::{Diagnostic, Severity, SourceFile, Witness};
use sfc_model::CheckOptions;
use sfc_syntax::ast::SourceUnit;
use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::{Duration, Instant};

/// A producer of diagnostics for one kind of file. The server asks each provider in turn
/// whether it handles a document; the first that does checks it. The chart provider handles
/// IEC text and PLCopen XML; another kind of file (a property file of `sfc prove`, say) plugs in
/// its own provider with [`crate::ServerOptions::providers`].
pub trait DiagnosticsProvider: Send + Sync {
    /// Whether this provider checks the document at `path` (editor language id `language`).
    fn handles(&self, path: &Path, language: &str, text: &str) -> bool;
    /// The diagnostics of `text`, located in `file` (whose text is what the user edits).
    /// `analysis` asks for the slow checks too (on save or after idle).
    fn check(&self, path: &Path, text: &str, analysis: bool) -> (SourceFile, Vec<Diagnostic>);
    /// The quick check (no analysis) of IEC text already parsed (`parsed` is
    /// `sfc_syntax::parse(0, text)`, its tree shared with the index worker), so one parse serves
    /// the check and the index; `None` when this provider does not check from a syntax tree
    /// (then [`Self::check`] is called).
    fn check_parsed(
        &self,
        _path: &Path,
        _text: &str,
        _parsed: (Arc<SourceUnit>, Vec<Diagnostic>),
    ) -> Option<(SourceFile, Vec<Diagnostic>)> {
        None
    }
    /// Whether [`Self::check_parsed`] checks IEC text from a syntax tree.
    fn checks_parsed(&self) -> bool {
        false
    }
}

/// `sfc check` for IEC text and PLCopen XML (through the driver, as the CLI does).
pub struct ChartDiagnostics;

impl DiagnosticsProvider for ChartDiagnostics {
    fn handles(&self, path: &Path, language: &str, text: &str) -> bool {
        let ext = path.extension().and_then(|e| e.to_str()).unwrap_or("").to_ascii_lowercase();
        if sfc_driver::is_xml(path, text) || language == "xml" {
            // Only PLCopen XML: an editor sends every XML file it opens (a `pom.xml` is no chart).
            let head: String = text.chars().take(4096).collect::<String>().to_ascii_lowercase();
            return head.contains("plcopen");
        }
        matches!(language, "sfc" | "iec-st" | "st") || matches!(ext.as_str(), "st" | "")
    }

    fn check(&self, path: &Path, text: &str, analysis: bool) -> (SourceFile, Vec<Diagnostic>) {
        let opts = CheckOptions { analysis, ..CheckOptions::default() };
        let kind = sfc_driver::FileKind::of(path, text);
        let (file, checked, diags) = sfc_driver::check_text(0, &path.display().to_string(), text, kind, &opts);
        // The diagnostics go out without waiting for the tree and model to be freed.
        crate::dispose::later(checked);
        (file, diags)
    }

    fn check_parsed(
        &self,
        path: &Path,
        text: &str,
        parsed: (Arc<SourceUnit>, Vec<Diagnostic>),
    ) -> Option<(SourceFile, Vec<Diagnostic>)> {
        let opts = CheckOptions { analysis: false, ..CheckOptions::default() };
        let (file, checked, diags) = sfc_driver::check_parsed_text(0, &path.display().to_string(), text, parsed, &opts);
        crate::dispose::later(checked);
        Some((file, diags))
    }

    fn checks_parsed(&self) -> bool {
        true
    }
}

/// The URI that explains a code (`sfc check --explain CODE`): the VS Code extension opens it
/// as a read-only document; other clients can ask the server with `sfc/explain`.
pub fn explain_uri(code: &str) -> Option<Uri> {
    format!("sfc-explain:{code}").parse().ok()
}

/// The data a diagnostic carries for code actions.
#[derive(Debug, Clone, Default, serde::Serialize, serde::Deserialize, PartialEq)]
pub struct DiagnosticData {
    /// The chart element it concerns.
    #[serde(skip_serializing_if = "Option::is_none", default)]
    pub element: Option<String>,
    /// The names a "did you mean" note suggests.
    #[serde(skip_serializing_if = "Vec::is_empty", default)]
    pub suggestions: Vec<String>,
}

/// An sfc diagnostic as the protocol has it: code with its explanation link, secondary labels
/// as related information, notes and the witness in the message.
pub fn to_lsp(d: &Diagnostic, file: &SourceFile, lines: &LineIndex, uri: &Uri) -> lsp_types::Diagnostic {
    let range = |s: sfc_diagnostics::Span| lines.range(&file.text, s.start, s.end);
    let mut message = d.message.clone();
    match &d.witness {
        Some(Witness::Firing(seq)) if seq.is_empty() => message.push_str("\nwitness: in the initial situation"),
        Some(Witness::Firing(seq)) => {
            message.push_str("\nwitness: fire ");
            message.push_str(&seq.join(", "));
        }
        Some(Witness::Valuation(vals)) => {
            let v: Vec<String> = vals.iter().map(|(n, v)| format!("{n} = {}", json_value(v))).collect();
            message.push_str("\nwitness: ");
            message.push_str(&v.join(", "));
        }
        None => {}
    }
    let mut suggestions = Vec::new();
    for n in &d.notes {
        message.push_str("\nnote: ");
        message.push_str(n);
        if let Some(s) = n.strip_prefix("did you mean `").and_then(|r| r.strip_suffix("`?")) {
            suggestions.push(s.to_string());
        }
    }
    let related: Vec<DiagnosticRelatedInformation> = d
        .labels
        .iter()
        .map(|l| DiagnosticRelatedInformation {
            location: Location::new(uri.clone(), range(l.span)),
            message: l.message.clone(),
        })
        .collect();
    let data = DiagnosticData { element: d.element.clone(), suggestions };
    lsp_types::Diagnostic {
        range: range(d.span),
        severity: Some(match d.severity {
            Severity::Error => DiagnosticSeverity::ERROR,
            Severity::Warning => DiagnosticSeverity::WARNING,
            Severity::Note => DiagnosticSeverity::INFORMATION,
        }),
        code: Some(NumberOrString::String(d.code.to_string())),
        code_description: explain_uri(d.code).map(|href| CodeDescription { href }),
        source: Some("sfc".to_string()),
        message,
        related_information: (!related.is_empty()).then_some(related),
        tags: None,
        data: serde_json::to_value(data).ok(),
    }
}

fn json_value(v: &serde_json::Value) -> String {
    match v {
        serde_json::Value::Bool(true) => "TRUE".into(),
        serde_json::Value::Bool(false) => "FALSE".into(),
        serde_json::Value::String(s) => s.clone(),
        other => other.to_string(),
    }
}

/// A document to check.
#[derive(Debug, Clone)]
pub struct Job {
    pub uri: Uri,
    pub version: i32,
    pub path: PathBuf,
    pub language: String,
    pub text: Arc<String>,
    /// Include the analysis (the slow part of `sfc check`).
    pub analysis: bool,
    /// Wait this long without a newer job for the same document before checking.
    pub delay: Duration,
    /// A quick check of IEC text that also gives this version's index: the check worker parses
    /// once and shares the tree with the index worker (which would otherwise parse the same
    /// text again, on the other core, at the same moment).
    pub index: bool,
    /// For the index worker: the tree of `text`, parsed by the check worker and shared with
    /// it. The index worker copies it for itself at once (the copy costs about a third of a
    /// parse) while the check worker type-checks the shared tree; lowering then takes the tree
    /// over, so the copy is off the path to the diagnostics.
    pub parsed: Option<Arc<SourceUnit>>,
}

/// The diagnostics of one version of a document.
#[derive(Debug, Clone)]
pub struct Outcome {
    pub uri: Uri,
    pub version: i32,
    pub analysis: bool,
    pub diagnostics: Vec<lsp_types::Diagnostic>,
    /// How long the check took.
    pub elapsed: Duration,
    /// The check failed inside (a bug): its message, for the log.
    pub failure: Option<String>,
    /// From the index worker (no diagnostics): the parse and index of this version, None when
    /// it failed inside (`failure` says why).
    pub from_index: bool,
    pub indexed: Option<Arc<Analysis>>,
}

/// Starts a worker thread: it takes jobs from `jobs`, keeps only the newest per document, waits
/// for each job's delay, checks and sends the outcome to `out`. It ends when `jobs` closes.
/// `index` takes the index jobs of the jobs marked [`Job::index`].
pub fn spawn_worker(
    name: &str,
    jobs: Receiver<Job>,
    out: Sender<Outcome>,
    providers: Arc<Vec<Box<dyn DiagnosticsProvider>>>,
    index: Option<Sender<Job>>,
) -> std::io::Result<std::thread::JoinHandle<()>> {
    spawn(name, jobs, out, providers, index, run)
}

/// Starts the index worker: as [`spawn_worker`], but it parses and indexes each job's text
/// (what completion, hover and navigation read) instead of checking it, so that requests find
/// the analysis made when they come.
pub fn spawn_index_worker(
    name: &str,
    jobs: Receiver<Job>,
    out: Sender<Outcome>,
) -> std::io::Result<std::thread::JoinHandle<()>> {
    spawn(name, jobs, out, Arc::new(Vec::new()), None, index)
}

type Runner = fn(Job, &[Box<dyn DiagnosticsProvider>], Option<&Sender<Job>>) -> Outcome;

fn spawn(
    name: &str,
    jobs: Receiver<Job>,
    out: Sender<Outcome>,
    providers: Arc<Vec<Box<dyn DiagnosticsProvider>>>,
    index: Option<Sender<Job>>,
    runner: Runner,
) -> std::io::Result<std::thread::JoinHandle<()>> {
    std::thread::Builder::new()
        .name(name.to_string())
        // Parsing and checking recurse along the (depth-capped) tree, as in the CLI.
        .stack_size(64 << 20)
        .spawn(move || worker(jobs, out, providers, index, runner))
}

/// The parse and index of one job's text (a panic inside becomes a failure for the log).
fn index(mut job: Job, _: &[Box<dyn DiagnosticsProvider>], _: Option<&Sender<Job>>) -> Outcome {
    let start = Instant::now();
    let parsed = job.parsed.take();
    let made = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
        Arc::new(match parsed {
            // The check worker takes the shared tree over once its type check is done: copy it
            // and let go of it first.
            Some(unit) => Analysis::from_parsed(job.text.clone(), Arc::unwrap_or_clone(unit)),
            None => Analysis::new(job.text.clone()),
        })
    }));
    let (indexed, failure) = match made {
        Ok(a) => (Some(a), None),
        Err(_) => (None, Some(format!("indexing `{}` failed inside sfc", job.path.display()))),
    };
    Outcome {
        uri: job.uri.clone(),
        version: job.version,
        analysis: false,
        diagnostics: Vec::new(),
        elapsed: start.elapsed(),
        failure,
        from_index: true,
        indexed,
    }
}

fn worker(
    jobs: Receiver<Job>,
    out: Sender<Outcome>,
    providers: Arc<Vec<Box<dyn DiagnosticsProvider>>>,
    index: Option<Sender<Job>>,
    runner: Runner,
) {
    // Pending jobs by URI with the time each becomes due.
    let mut pending: HashMap<String, (Instant, Job)> = HashMap::new();
    loop {
        let next_due = pending.values().map(|(due, _)| *due).min();
        let received = match next_due {
            None => jobs.recv().map_err(|_| RecvTimeoutError::Disconnected),
            Some(due) => jobs.recv_timeout(due.saturating_duration_since(Instant::now())),
        };
        match received {
            Ok(job) => {
                let due = Instant::now() + job.delay;
                pending.insert(job.uri.as_str().to_string(), (due, job));
                continue;
            }
            Err(RecvTimeoutError::Disconnected) => return,
            Err(RecvTimeoutError::Timeout) => {}
        }
        let now = Instant::now();
        let due: Vec<String> = pending.iter().filter(|(_, (d, _))| *d <= now).map(|(k, _)| k.clone()).collect();
        for key in due {
            let Some((_, job)) = pending.remove(&key) else { continue };
            if out.send(runner(job, &providers, index.as_ref())).is_err() {
                return;
            }
        }
    }
}

/// Checks one job (a panic inside a check becomes a failure, the worker goes on). A job marked
/// [`Job::index`] also goes to `index`, with the tree of its text when the provider checks
/// from one (parsed here once for both).
pub fn run(job: Job, providers: &[Box<dyn DiagnosticsProvider>], index: Option<&Sender<Job>>) -> Outcome {
    let start = Instant::now();
    let mut outcome = Outcome {
        uri: job.uri.clone(),
        version: job.version,
        analysis: job.analysis,
        diagnostics: Vec::new(),
        elapsed: Duration::ZERO,
        failure: None,
        from_index: false,
        indexed: None,
    };
    let provider = providers.iter().find(|p| p.handles(&job.path, &job.language, &job.text));
    let index = index.filter(|_| job.index);
    let from_tree = !job.analysis && index.is_some() && provider.is_some_and(|p| p.checks_parsed());
    let Some(provider) = provider else {
        if let Some(index) = index {
            let _ = index.send(Job { delay: Duration::ZERO, index: false, ..job.clone() });
        }
        return outcome;
    };
    let checked = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
        if from_tree {
            // One parse for both: the index worker gets the tree (it copies it for itself
            // while this thread type-checks) and builds the index while this thread checks.
            let (unit, parse_diags) = sfc_syntax::parse(0, &job.text);
            let unit = Arc::new(unit);
            if let Some(index) = index {
                let _ =
                    index.send(Job { delay: Duration::ZERO, index: false, parsed: Some(unit.clone()), ..job.clone() });
            }
            let parsed = (unit, parse_diags);
            if let Some(found) = provider.check_parsed(&job.path, &job.text, parsed) {
                return found;
            }
        } else if let Some(index) = index {
            let _ = index.send(Job { delay: Duration::ZERO, index: false, ..job.clone() });
        }
        provider.check(&job.path, &job.text, job.analysis)
    }));
    match checked {
        Ok((file, diags)) => {
            let lines = LineIndex::new(&file.text);
            outcome.diagnostics = diags.iter().map(|d| to_lsp(d, &file, &lines, &job.uri)).collect();
        }
        Err(e) => {
            if from_tree {
                // The tree may not have reached the index worker: it parses for itself (a
                // second index job of one version only replaces the first).
                if let Some(index) = index {
                    let _ = index.send(Job { delay: Duration::ZERO, index: false, ..job.clone() });
                }
            }
            let msg = e
                .downcast_ref::<String>()
                .cloned()
                .or_else(|| e.downcast_ref::<&str>().map(|s| s.to_string()))
                .unwrap_or_else(|| "unknown panic".into());
            outcome.failure = Some(format!("checking `{}` failed inside sfc: {msg}", job.path.display()));
        }
    }
    outcome.elapsed = start.elapsed();
    outcome
}
