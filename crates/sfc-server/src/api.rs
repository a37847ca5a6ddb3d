//! The calls of `docs/editor.md` ("HTTP API"). Each call parses its body itself (so every
//! refusal is `{"error": …}`), and does its work on a blocking thread: checking and building
//! are CPU work, and a failure there is answered with `500`, never a crashed server.

use crate::compile::{self, BuildTarget, CompileError, CompileOptions};
use crate::confine::Refusal;
use crate::diag::{chart_of, diag_json, pou_spans, problem_json, PouSpans};
use crate::disk::{content_hash, write_atomically};
use crate::{assets, AppState};
use axum::body::Bytes;
use axum::extract::rejection::BytesRejection;
use axum::extract::State;
use axum::http::{Method, StatusCode, Uri};
use axum::response::{IntoResponse, Response};
use axum::Json;
use serde::de::DeserializeOwned;
use serde::Deserialize;
use serde_json::{json, Value};
use sfc_diagnostics::{Diagnostic, SourceFile};
use sfc_doc::{ChartTarget, EditorDoc};
use sfc_model::{CheckOptions, Target};
use sfc_plcopen::Imported;
use std::path::{Path, PathBuf};

/// Chart files larger than this are not opened (the same bound as request bodies).
const MAX_FILE: u64 = crate::MAX_BODY as u64;
/// `files` lists at most this many files, and descends at most this deep.
const MAX_LISTED: usize = 10_000;
const MAX_DEPTH: usize = 32;

/// An error answer: `{"error": message}`, with `"conflict": true` for a save conflict.
#[derive(Debug)]
pub struct ApiError {
    status: StatusCode,
    body: Value,
}

impl ApiError {
    pub fn new(status: StatusCode, message: impl Into<String>) -> Self {
        ApiError { status, body: json!({ "error": message.into() }) }
    }

    /// The error with more fields (`conflict`, `diagnostics`).
    pub(crate) fn with(mut self, key: &str, value: Value) -> Self {
        if let Some(o) = self.body.as_object_mut() {
            o.insert(key.to_string(), value);
        }
        self
    }
}

impl IntoResponse for ApiError {
    fn into_response(self) -> Response {
        (self.status, Json(self.body)).into_response()
    }
}

impl From<Refusal> for ApiError {
    fn from(r: Refusal) -> Self {
        match r {
            Refusal::Malformed(m) => ApiError::new(StatusCode::BAD_REQUEST, m),
            Refusal::Outside(m) => ApiError::new(StatusCode::FORBIDDEN, m),
        }
    }
}

type Answer = Result<Value, ApiError>;

/// The body as JSON of the call's request type; `400` with serde's located message otherwise,
/// `413` when it is too large.
fn parse<T: DeserializeOwned>(body: Result<Bytes, BytesRejection>) -> Result<T, ApiError> {
    let bytes = body.map_err(|r| ApiError::new(r.status(), r.body_text()))?;
    serde_json::from_slice(&bytes).map_err(|e| ApiError::new(StatusCode::BAD_REQUEST, format!("bad request body: {e}")))
}

/// What a panic carried, for the `500` answer.
fn panic_message(payload: &(dyn std::any::Any + Send)) -> String {
    payload
        .downcast_ref::<&str>()
        .map(|s| s.to_string())
        .or_else(|| payload.downcast_ref::<String>().cloned())
        .unwrap_or_else(|| "unknown failure".to_string())
}

/// Runs a call's work on a blocking thread and answers with its JSON or its error.
async fn blocking(work: impl FnOnce() -> Answer + Send + 'static) -> Response {
    match tokio::task::spawn_blocking(work).await {
        Ok(Ok(v)) => Json(v).into_response(),
        Ok(Err(e)) => e.into_response(),
        Err(join) => {
            let why = if join.is_panic() { panic_message(&*join.into_panic()) } else { "cancelled".to_string() };
            ApiError::new(StatusCode::INTERNAL_SERVER_ERROR, format!("internal error: {why}")).into_response()
        }
    }
}

fn io_error(path: &Path, e: &std::io::Error) -> ApiError {
    ApiError::new(StatusCode::INTERNAL_SERVER_ERROR, format!("cannot access `{}`: {e}", path.display()))
}

fn path_string(p: &Path) -> String {
    p.to_string_lossy().into_owned()
}

/// `.st`, `.xml` or `.l5x` (the driver's rule).
fn is_chart_file(p: &Path) -> bool {
    sfc_driver::load::is_chart_file(p)
}

/// `path` from the page: one of the files named on the command line, or a chart file under a
/// directory named there; the page cannot touch other files.
pub(crate) fn chart_path(s: &AppState, raw: &str) -> Result<PathBuf, ApiError> {
    let path = crate::confine(&s.0.roots, &s.0.open, raw)?;
    if is_chart_file(&path) || s.0.open.contains(&path) {
        Ok(path)
    } else {
        Err(ApiError::new(StatusCode::FORBIDDEN, format!("`{raw}` is not a chart file (.st, .xml or .l5x)")))
    }
}

/// The chart file `raw` as the editor's simulations read it: its IEC text (a PLCopen XML file's
/// imported text), which holds the other POUs a chart uses, and the tool of the CODESYS family
/// that wrote it (a PLCopen XML export of CODESYS, TwinCAT or e!COCKPIT), which chooses the
/// profile ([`sfc_sim::file_profile`]). `None` for a file that no longer exists.
pub(crate) fn file_for_simulation(
    s: &AppState,
    raw: &str,
) -> Result<Option<(String, Option<sfc_plcopen::Vendor>)>, ApiError> {
    let path = chart_path(s, raw)?;
    let Some(bytes) = read_existing(&path)? else { return Ok(None) };
    let text = utf8(&path, bytes)?;
    if compile::is_xml(&path, &text) {
        let imported = sfc_plcopen::import(0, &path.display().to_string(), &text);
        Ok(Some((imported.text, imported.vendor)))
    } else {
        // A text converted from an export runs by its tool's rules too.
        let vendor = sfc_plcopen::text_vendor(&text);
        Ok(Some((text, vendor)))
    }
}

/// The file's bytes; `None` when it does not exist.
pub(crate) fn read_existing(path: &Path) -> Result<Option<Vec<u8>>, ApiError> {
    match std::fs::metadata(path) {
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(None),
        Err(e) => return Err(io_error(path, &e)),
        Ok(m) if m.is_dir() => {
            return Err(ApiError::new(StatusCode::BAD_REQUEST, format!("`{}` is a directory", path.display())))
        }
        Ok(m) if m.len() > MAX_FILE => {
            return Err(ApiError::new(
                StatusCode::PAYLOAD_TOO_LARGE,
                format!("`{}` is larger than {} MiB", path.display(), MAX_FILE >> 20),
            ))
        }
        Ok(_) => {}
    }
    match std::fs::read(path) {
        Ok(b) => Ok(Some(b)),
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => Ok(None),
        Err(e) => Err(io_error(path, &e)),
    }
}

/// A chart file's text: UTF-8 with or without a byte order mark, or Latin-1 / Windows-1252 (a
/// save writes it back the same way, see [`sfc_syntax::encoding`]).
fn utf8(_path: &Path, bytes: Vec<u8>) -> Result<String, ApiError> {
    Ok(sfc_syntax::encoding::decode(&bytes).text)
}

/// An IEC identifier (`Conveyor_2`), as a POU name must be.
fn is_identifier(s: &str) -> bool {
    let mut chars = s.chars();
    chars.next().is_some_and(|c| c.is_ascii_alphabetic() || c == '_')
        && chars.all(|c| c.is_ascii_alphanumeric() || c == '_')
}

fn check_pou_name(name: &str) -> Result<(), ApiError> {
    if is_identifier(name) {
        Ok(())
    } else {
        Err(ApiError::new(StatusCode::BAD_REQUEST, format!("`{name}` is not a valid POU name (an IEC identifier)")))
    }
}

fn model_target(t: ChartTarget) -> Target {
    match t {
        ChartTarget::Blank => Target::Blank,
        ChartTarget::Atmt => Target::Atmt,
        ChartTarget::Eatmt => Target::Eatmt,
    }
}

/// Diagnostics of IEC `text` (file 0) for the page: moved to the XML when the text was
/// imported from it (after the import's own diagnostics), each with the blocks of the chart it
/// concerns among `charts`.
pub(crate) fn page_diagnostics(
    name: &str,
    text: &str,
    import: Option<&Imported>,
    in_text: &[Diagnostic],
    charts: &[EditorDoc],
) -> Vec<Value> {
    page_diagnostics_in(&pou_spans(text), name, text, import, in_text, charts)
}

/// [`page_diagnostics`] with the POUs of `text` already found. Each diagnostic names the POU
/// it lies in (`pou`): its chart's name when it concerns one of `charts`, the POU holding its
/// span otherwise; none outside every POU (a TYPE), nor for the import's own, unless the file
/// holds just one chart.
pub(crate) fn page_diagnostics_in(
    pous: &PouSpans,
    name: &str,
    text: &str,
    import: Option<&Imported>,
    in_text: &[Diagnostic],
    charts: &[EditorDoc],
) -> Vec<Value> {
    let mut items: Vec<(Diagnostic, Option<&EditorDoc>, Option<String>)> = Vec::new();
    if let Some(imp) = import {
        items.extend(imp.diagnostics.iter().map(|d| {
            let doc = chart_of(charts, pous, None);
            (d.clone(), doc, doc.map(|c| c.pou.clone()))
        }));
    }
    for d in in_text {
        let span = (d.span.file == 0).then_some(d.span);
        let doc = chart_of(charts, pous, span);
        let pou = match (doc, span.and_then(|s| pous.pou_at(s))) {
            (Some(c), Some(_)) => Some(c.pou.clone()),
            (_, Some(p)) => Some(p.to_string()),
            (Some(c), None) if span.is_none() => Some(c.pou.clone()),
            _ => None,
        };
        // A syntax error inside a step, transition or action concerns that element.
        let inside = (d.element.is_none() && d.span.file == 0).then(|| pous.element_at(d.span)).flatten();
        let mut d = match import {
            Some(imp) => sfc_plcopen::relocate(d, &imp.map, 0),
            None => d.clone(),
        };
        if let Some(name) = inside {
            d.element = Some(name.to_string());
        }
        items.push((d, doc, pou));
    }
    items.sort_by(|(a, _, _), (b, _, _)| {
        (a.span.file, a.span.start, a.span.end, a.code).cmp(&(b.span.file, b.span.start, b.span.end, b.code))
    });
    items.dedup_by(|a, b| a.0 == b.0);
    let files = [match import {
        Some(imp) => imp.xml.clone(),
        None => SourceFile::new(name, text),
    }];
    items.iter().map(|(d, doc, pou)| diag_json(d, &files, *doc, pou.as_deref())).collect()
}

/// The check of a document: its problems, then the check of its text with `opts`.
fn check_document(doc: &EditorDoc, opts: &CheckOptions) -> (Vec<Value>, bool, sfc_model::Checked) {
    let written = sfc_doc::to_text(doc);
    let name = format!("{}.st", doc.pou);
    let mut out: Vec<Value> = written.problems.iter().map(|p| problem_json(p, doc, &name, &written.text)).collect();
    let mut errors = written.problems.iter().any(|p| p.severity == sfc_diagnostics::Severity::Error);
    let checked = sfc_analysis::check_source(0, &name, &written.text, opts);
    errors |= checked.has_errors();
    out.extend(page_diagnostics(&name, &written.text, None, &checked.diagnostics, std::slice::from_ref(doc)));
    (out, errors, checked)
}

// ---- calls ----

pub async fn session(State(s): State<AppState>) -> Json<Value> {
    let paths = |v: &[PathBuf]| v.iter().map(|p| path_string(p)).collect::<Vec<_>>();
    let mut v = json!({
        "mode": if s.0.host.is_some() { "host" } else { "mdi" },
        "version": env!("CARGO_PKG_VERSION"),
        "roots": paths(&s.0.roots),
        "open": paths(&s.0.open),
    });
    if let Some(h) = &s.0.host {
        put(
            &mut v,
            "host",
            json!({
                "fb": h.fb.name(),
                "nstep": h.nstep,
                "ntr": h.ntr,
                "file": path_string(&h.file),
                "result": path_string(&h.result),
            }),
        );
    }
    Json(v)
}

pub async fn codes() -> Json<Value> {
    let list: Vec<Value> = sfc_diagnostics::CODES
        .iter()
        .map(|c| json!({ "code": c.code, "severity": c.severity.as_str(), "title": c.title }))
        .collect();
    Json(Value::Array(list))
}

pub async fn files(State(s): State<AppState>) -> Response {
    blocking(move || Ok(json!({ "files": list_files(&s.0.roots, &s.0.open) }))).await
}

/// The files named on the command line that exist, and every `.st` and `.xml` under the roots,
/// sorted, without `target/`, `node_modules/`, hidden files and hidden directories. Linked
/// directories are not entered (they may lead out of the roots or in circles); a linked file
/// is listed when its target is under a root.
fn list_files(roots: &[PathBuf], named: &[PathBuf]) -> Vec<Value> {
    let mut found: std::collections::BTreeSet<PathBuf> = named.iter().filter(|p| p.is_file()).cloned().collect();
    let mut stack: Vec<(PathBuf, usize)> = roots.iter().map(|r| (r.clone(), 0)).collect();
    while let Some((dir, depth)) = stack.pop() {
        let Ok(entries) = std::fs::read_dir(&dir) else { continue };
        for entry in entries.flatten() {
            let name = entry.file_name();
            let Some(name) = name.to_str() else { continue };
            let Ok(kind) = entry.file_type() else { continue };
            let path = entry.path();
            if kind.is_dir() {
                if depth < MAX_DEPTH && !name.starts_with('.') && name != "target" && name != "node_modules" {
                    stack.push((path, depth + 1));
                }
            } else if is_chart_file(&path)
                && !name.starts_with('.')
                && (kind.is_file()
                    || std::fs::canonicalize(&path)
                        .is_ok_and(|t| t.is_file() && roots.iter().any(|r| t.starts_with(r))))
            {
                found.insert(path);
                if found.len() >= MAX_LISTED {
                    stack.clear();
                    break;
                }
            }
        }
    }
    found
        .into_iter()
        .map(|p| {
            let xml = p.extension().is_some_and(|e| e.eq_ignore_ascii_case("xml") || e.eq_ignore_ascii_case("l5x"));
            json!({ "path": path_string(&p), "format": if xml { "xml" } else { "st" } })
        })
        .collect()
}

#[derive(Deserialize)]
struct OpenRequest {
    path: String,
}

pub async fn open(State(s): State<AppState>, body: Result<Bytes, BytesRejection>) -> Response {
    let req: OpenRequest = match parse(body) {
        Ok(r) => r,
        Err(e) => return e.into_response(),
    };
    // The first named file's answer, when the server made it ahead (see `prepare_first`):
    // waited for if still being made, and used only if the file still has the bytes it was
    // made from.
    let prepared = {
        let mut slot = s.0.prepared.lock().await;
        if slot.as_ref().is_some_and(|p| p.raw == req.path) {
            slot.take()
        } else {
            None
        }
    };
    blocking(move || open_file(&s, &req.path, prepared)).await
}

/// The answer to `POST /api/open` for a chart file, made before the page asked for it.
#[derive(Debug)]
pub(crate) struct Prepared {
    /// The path as the session lists it (what the page sends).
    raw: String,
    bytes: Vec<u8>,
    answer: Value,
}

/// Opens the first file named on the command line the way `POST /api/open` will, so reading,
/// checking and laying it out overlap with the browser loading the app. `None` when it cannot
/// be opened: the request then reports why, as it would have.
pub(crate) fn prepare_first(s: &AppState) -> Option<Prepared> {
    let raw = path_string(s.0.open.first()?);
    let path = chart_path(s, &raw).ok()?;
    let bytes = read_existing(&path).ok()??;
    let answer = open_bytes(&path, bytes.clone()).ok()?;
    Some(Prepared { raw, bytes, answer })
}

fn open_file(s: &AppState, raw: &str, prepared: Option<Prepared>) -> Answer {
    let path = chart_path(s, raw)?;
    let bytes = read_existing(&path)?
        .ok_or_else(|| ApiError::new(StatusCode::NOT_FOUND, format!("`{}` does not exist", path.display())))?;
    match prepared {
        Some(p) if p.bytes == bytes => Ok(p.answer),
        _ => open_bytes(&path, bytes),
    }
}

/// The chart of a file's bytes, laid out, with its diagnostics and content hash.
fn open_bytes(path: &Path, bytes: Vec<u8>) -> Answer {
    let hash = content_hash(&bytes);
    let text = utf8(path, bytes)?;
    let name = path.display().to_string();
    let xml = compile::is_xml(path, &text);
    let (charts, diagnostics, pous) = if xml {
        let imported = sfc_plcopen::import(0, &name, &text);
        let opened = sfc_doc::open(0, &format!("{name} (imported)"), &imported.text);
        let pous = pou_spans(&imported.text);
        let d = page_diagnostics_in(&pous, &name, &imported.text, Some(&imported), &opened.diagnostics, &opened.charts);
        (opened.charts, d, pous.tree)
    } else {
        let opened = sfc_doc::open(0, &name, &text);
        let pous = pou_spans(&text);
        let d = page_diagnostics_in(&pous, &name, &text, None, &opened.diagnostics, &opened.charts);
        (opened.charts, d, pous.tree)
    };
    Ok(json!({
        "path": path_string(path),
        "format": if xml { "xml" } else { "st" },
        "charts": charts,
        "diagnostics": diagnostics,
        "hash": hash,
        "pous": pous,
    }))
}

#[derive(Deserialize, Clone, Copy, PartialEq, Eq)]
#[serde(rename_all = "lowercase")]
enum FileFormat {
    St,
    Xml,
}

#[derive(Deserialize)]
struct SaveRequest {
    path: String,
    format: FileFormat,
    doc: EditorDoc,
    #[serde(default)]
    hash: Option<String>,
    #[serde(default)]
    overwrite: bool,
    /// The POU's name as opened, when the page renamed it: that POU is the one replaced.
    #[serde(default)]
    pou: Option<String>,
}

pub async fn save(State(s): State<AppState>, body: Result<Bytes, BytesRejection>) -> Response {
    let req: SaveRequest = match parse(body) {
        Ok(r) => r,
        Err(e) => return e.into_response(),
    };
    // The guard moves into the work, so a page that goes away mid-save does not let another
    // save start on the same file before this one has finished.
    let guard = s.0.save_lock.clone().lock_owned().await;
    blocking(move || {
        let _guard = guard;
        save_file(&s, req)
    })
    .await
}

fn save_file(s: &AppState, req: SaveRequest) -> Answer {
    let path = chart_path(s, &req.path)?;
    check_pou_name(&req.doc.pou)?;
    let current = read_existing(&path)?;
    if !req.overwrite {
        let why = match (&current, &req.hash) {
            (Some(bytes), Some(h)) if content_hash(bytes) != *h => Some("changed on disk since it was opened"),
            (Some(_), None) => Some("exists already"),
            (None, Some(_)) => Some("was deleted since it was opened"),
            _ => None,
        };
        if let Some(why) = why {
            return Err(ApiError::new(StatusCode::CONFLICT, format!("`{}` {why}", path.display()))
                .with("conflict", json!(true)));
        }
    }
    // The file keeps its encoding, byte order mark and line endings.
    let written_as = current.as_deref().map(sfc_syntax::encoding::decode).unwrap_or_default();
    let current = current.map(|b| utf8(&path, b)).transpose()?;
    let name = path.display().to_string();
    if !path.parent().is_some_and(Path::is_dir) {
        return Err(ApiError::new(StatusCode::NOT_FOUND, format!("the directory of `{name}` does not exist")));
    }
    refuse_unparsed(&req.doc)?;
    let plain = CheckOptions { analysis: false, ..CheckOptions::default() };
    // The POU replaced in the file: the one opened, which the page may have renamed since.
    let replacing = req.pou.clone().unwrap_or_else(|| req.doc.pou.clone());
    let renamed = !replacing.eq_ignore_ascii_case(&req.doc.pou);
    let bytes = match req.format {
        FileFormat::St => {
            let text = current.as_deref().unwrap_or("");
            refuse_rename_onto(&name, text, renamed, &req.doc.pou)?;
            sfc_doc::splice_replacing(text, &req.doc, &replacing)
        }
        FileFormat::Xml => {
            // Only what changed in this POU is written (`patch_pou`: places, sizes, an inline
            // ST condition, a step's name in place; else the POU's element replaced): every
            // other byte of the file (the other POUs as their tool drew them, headers,
            // instances, vendor data, element ids) stays as it was.
            let pou_text = sfc_doc::to_text(&req.doc).text;
            let mut unchanged = None;
            if let Some(xml) = &current {
                let others = sfc_plcopen::import(0, &name, xml);
                refuse_rename_onto(&name, &others.text, renamed, &req.doc.pou)?;
                // The chart as the file opens, saved without an edit: the file stays byte for
                // byte (also one the file holds without a layout, which the editor draws).
                let opened = sfc_doc::open(0, &format!("{name} (imported)"), &others.text);
                let same = |c: &EditorDoc| c.pou == req.doc.pou && sfc_doc::to_text(c).text == pou_text;
                if !renamed && opened.charts.iter().any(same) {
                    unchanged = Some(xml.clone());
                }
            }
            let checked = sfc_analysis::check_source(0, &format!("{name} (as text)"), &pou_text, &plain);
            let base = current.clone().unwrap_or_else(|| sfc_plcopen::export(&checked).unwrap_or_default());
            let patched = match unchanged {
                Some(xml) => Ok((xml, sfc_plcopen::Patched::Unchanged)),
                None => sfc_plcopen::patch_pou(&base, &replacing, &checked),
            };
            match patched {
                Ok((xml, _)) => xml,
                Err(sfc_plcopen::SpliceError::Diagnostics(errors)) => {
                    let d =
                        page_diagnostics(&checked.file.name, &pou_text, None, &errors, std::slice::from_ref(&req.doc));
                    return Err(ApiError::new(
                        StatusCode::UNPROCESSABLE_ENTITY,
                        "the chart cannot be written as PLCopen XML; nothing was written",
                    )
                    .with("diagnostics", json!(d)));
                }
                Err(sfc_plcopen::SpliceError::NotAProject(why)) => {
                    return Err(ApiError::new(
                        StatusCode::UNPROCESSABLE_ENTITY,
                        format!("`{name}`: {why}; nothing was written"),
                    ));
                }
            }
        }
    };
    let (raw, lost) = sfc_syntax::encoding::encode(&bytes, &written_as);
    if lost > 0 {
        return Err(ApiError::new(
            StatusCode::UNPROCESSABLE_ENTITY,
            format!("`{name}` is Latin-1 / Windows-1252, which cannot hold {lost} character(s) of the chart; nothing was written"),
        ));
    }
    write_atomically(&path, &raw).map_err(|e| io_error(&path, &e))?;
    // What the page shows after saving: the document's problems, then the check of the file as
    // written (located in it), without the analysis (`check` runs that on request).
    let problems = sfc_doc::to_text(&req.doc).problems;
    let at = if req.format == FileFormat::St { bytes.as_str() } else { "" };
    let mut diagnostics: Vec<Value> = problems.iter().map(|p| problem_json(p, &req.doc, &name, at)).collect();
    let charts = std::slice::from_ref(&req.doc);
    if req.format == FileFormat::Xml {
        let imported = sfc_plcopen::import(0, &name, &bytes);
        let checked = sfc_analysis::check_source(0, &format!("{name} (imported)"), &imported.text, &plain);
        diagnostics.extend(page_diagnostics(&name, &imported.text, Some(&imported), &checked.diagnostics, charts));
    } else {
        let checked = sfc_analysis::check_source(0, &name, &bytes, &plain);
        diagnostics.extend(page_diagnostics(&name, &bytes, None, &checked.diagnostics, charts));
    }
    Ok(json!({ "path": path_string(&path), "hash": content_hash(&raw), "diagnostics": diagnostics }))
}

/// A document with text the user typed that does not parse (a condition, an action body, the
/// declarations, a name) is not saved: the file would hold something else than what was typed
/// (`FALSE` for a condition, an empty body). The answer names each piece (`422`, with the
/// problems as `diagnostics`); nothing is written, and the page keeps the typed text.
fn refuse_unparsed(doc: &EditorDoc) -> Result<(), ApiError> {
    let (written, lost) = unparsed(doc);
    if lost.is_empty() {
        return Ok(());
    }
    let name = format!("{}.st", doc.pou);
    let what: Vec<String> = lost
        .iter()
        .map(|p| {
            let block = doc.elements.iter().find(|e| e.id == p.element);
            match block {
                Some(e) if !e.name.is_empty() && p.code == "SFC0217" => format!("the condition of `{}`", e.name),
                _ => p.message.clone(),
            }
        })
        .collect();
    let d: Vec<Value> = lost.iter().map(|p| problem_json(p, doc, &name, &written.text)).collect();
    // Where the first problem is (file:line:col), as the Error list shows it.
    let at = d
        .first()
        .map(|f| {
            format!(
                " at {}:{}:{}",
                f["file"].as_str().unwrap_or(""),
                f["line"].as_u64().unwrap_or(1),
                f["column"].as_u64().unwrap_or(1)
            )
        })
        .unwrap_or_default();
    Err(ApiError::new(
        StatusCode::UNPROCESSABLE_ENTITY,
        format!(
            "not saved: {} does not parse{at}; fix it first (the file would otherwise hold something else than what \
             you typed). Nothing was written.",
            what.join(", ")
        ),
    )
    .with("diagnostics", json!(d)))
}

/// The document as text, and the problems of text the user typed that does not parse (its
/// text would hold something else: `FALSE` for a condition, an empty body). SFC0217 is a
/// transition without a condition: lost text only when one was typed.
pub(crate) fn unparsed(doc: &EditorDoc) -> (sfc_doc::Written, Vec<sfc_doc::Problem>) {
    let written = sfc_doc::to_text(doc);
    let typed = |id: &str| {
        doc.elements
            .iter()
            .find(|e| e.id == id)
            .and_then(|e| e.condition.as_deref())
            .is_some_and(|c| !c.trim().is_empty())
    };
    let lost = written
        .problems
        .iter()
        .filter(|p| p.code == "SFC0101" || (p.code == "SFC0217" && typed(&p.element)))
        .cloned()
        .collect();
    (written, lost)
}

/// A renamed POU may not take the name of another POU of its file: saving would leave two.
fn refuse_rename_onto(file: &str, text: &str, renamed: bool, pou: &str) -> Result<(), ApiError> {
    if renamed && sfc_doc::holds_pou(text, pou) {
        return Err(ApiError::new(
            StatusCode::UNPROCESSABLE_ENTITY,
            format!("`{file}` already holds a POU named `{pou}`; rename the chart to another name"),
        ));
    }
    Ok(())
}

#[derive(Deserialize)]
struct CheckRequest {
    doc: EditorDoc,
    #[serde(default)]
    analysis: bool,
}

pub async fn check(State(s): State<AppState>, body: Result<Bytes, BytesRejection>) -> Response {
    let req: CheckRequest = match parse(body) {
        Ok(r) => r,
        Err(e) => return e.into_response(),
    };
    blocking(move || {
        // In host mode the host's block decides the rules and limits.
        let opts = match &s.0.host {
            Some(h) => CheckOptions {
                target: Some(h.fb.target()),
                nstep: Some(h.nstep),
                ntr: Some(h.ntr),
                analysis: req.analysis,
                ..CheckOptions::default()
            },
            None => CheckOptions {
                target: Some(model_target(req.doc.target)),
                analysis: req.analysis,
                ..Default::default()
            },
        };
        let (diagnostics, _, _) = check_document(&req.doc, &opts);
        Ok(json!({ "diagnostics": diagnostics }))
    })
    .await
}

#[derive(Deserialize)]
struct BuildRequest {
    doc: EditorDoc,
    target: String,
    #[serde(default)]
    nstep: Option<u32>,
    #[serde(default)]
    ntr: Option<u32>,
}

pub async fn build(State(s): State<AppState>, body: Result<Bytes, BytesRejection>) -> Response {
    let req: BuildRequest = match parse(body) {
        Ok(r) => r,
        Err(e) => return e.into_response(),
    };
    blocking(move || build_document(&s, req)).await
}

fn build_document(s: &AppState, req: BuildRequest) -> Answer {
    let asked = BuildTarget::from_name(&req.target).ok_or_else(|| {
        let names: Vec<&str> = BuildTarget::ALL.iter().map(|t| t.name()).collect();
        ApiError::new(StatusCode::BAD_REQUEST, format!("unknown target `{}` (one of {})", req.target, names.join(", ")))
    })?;
    check_pou_name(&req.doc.pou)?;
    // Host mode: a table is built for the host's block and limits, and written for the host.
    let host = s.0.host.as_ref().filter(|_| asked.table_target().is_some());
    let (target, nstep, ntr) = match host {
        Some(h) => (h.fb.build_target(), Some(h.nstep), Some(h.ntr)),
        None => (asked, req.nstep, req.ntr),
    };
    let (mut diagnostics, errors, checked) = check_document(&req.doc, &compile::validation_options(target, nstep, ntr));
    if errors {
        return Ok(json!({ "ok": false, "diagnostics": diagnostics }));
    }
    let opts = CompileOptions { pou: Some(&req.doc.pou), flatten: false, nstep, ntr, ..Default::default() };
    let charts = std::slice::from_ref(&req.doc);
    let built = match compile::compile(&checked, target, &opts) {
        Ok(b) => b,
        Err(CompileError::Chart(m)) => return Err(ApiError::new(StatusCode::UNPROCESSABLE_ENTITY, m)),
        Err(CompileError::Diagnostics(ds)) => {
            diagnostics.extend(page_diagnostics(&checked.file.name, &checked.file.text, None, &ds, charts));
            return Ok(json!({ "ok": false, "diagnostics": diagnostics }));
        }
    };
    diagnostics.extend(page_diagnostics(&checked.file.name, &checked.file.text, None, &built.notes, charts));
    let mut answer = json!({ "ok": true, "diagnostics": diagnostics, "output": built.text });
    if target.table_target().is_some() {
        let table = compile::parse_table(&built.text).ok_or_else(|| {
            ApiError::new(StatusCode::INTERNAL_SERVER_ERROR, format!("the table `{}` cannot be read back", built.text))
        })?;
        put(&mut answer, "table", json!(table));
    }
    if let Some(h) = host {
        write_atomically(&h.result, built.text.as_bytes()).map_err(|e| io_error(&h.result, &e))?;
        put(&mut answer, "resultWritten", json!(path_string(&h.result)));
    }
    Ok(answer)
}

#[derive(Deserialize)]
struct DocRequest {
    doc: EditorDoc,
}

pub async fn layout(body: Result<Bytes, BytesRejection>) -> Response {
    let req: DocRequest = match parse(body) {
        Ok(r) => r,
        Err(e) => return e.into_response(),
    };
    blocking(move || Ok(json!({ "doc": sfc_doc::auto_layout(&req.doc) }))).await
}

#[derive(Deserialize)]
struct NewRequest {
    name: String,
    target: ChartTarget,
}

pub async fn new_chart(body: Result<Bytes, BytesRejection>) -> Response {
    let req: NewRequest = match parse(body) {
        Ok(r) => r,
        Err(e) => return e.into_response(),
    };
    if let Err(e) = check_pou_name(&req.name) {
        return e.into_response();
    }
    blocking(move || Ok(json!({ "doc": sfc_doc::blank(&req.name, req.target) }))).await
}

pub async fn not_found(uri: Uri) -> ApiError {
    ApiError::new(StatusCode::NOT_FOUND, format!("no API call `{}`", uri.path()))
}

pub async fn method_not_allowed(method: Method, uri: Uri) -> ApiError {
    ApiError::new(StatusCode::METHOD_NOT_ALLOWED, format!("`{}` does not take {method}", uri.path()))
}

/// Everything outside `/api/`: the web app's files, read-only.
pub async fn static_file(method: Method, uri: Uri) -> Response {
    if method == Method::GET || method == Method::HEAD {
        assets::serve(uri).await
    } else {
        (StatusCode::METHOD_NOT_ALLOWED, "the web app's files are read-only\n").into_response()
    }
}

/// Sets `key` of a JSON object (the answers built here are objects; anything else is left as it
/// is rather than panicking).
fn put(v: &mut Value, key: &str, value: Value) {
    if let Some(o) = v.as_object_mut() {
        o.insert(key.to_string(), value);
    }
}
