//! `POST /api/compare {"path","pou"?,"doc","against"}`: the chart on the canvas compared by
//! meaning (`sfc_diff`, docs/diff.md) with its file as saved on disk (`saved`) or as in git HEAD
//! (`head`: `git show HEAD:./NAME` in the file's directory), for *File → Compare with saved* and
//! *Compare with git HEAD*.
//!
//! Both sides are IEC text: the other side is the file's text (a PLCopen XML file imported to
//! text, as `sfc diff` reads it), and the canvas' side is that text with the document written
//! into it as a save would (`sfc_doc::splice_replacing`), so the file's other POUs, types and
//! globals are the same on both sides and only the POU on the canvas can differ. The answer
//! holds that POU's changes, each with the blocks of the current document it concerns (the page
//! colours them), the removed elements apart (they have no block), and the number of elements
//! only moved or resized.

use crate::api::{chart_path, read_existing, ApiError};
use crate::contract::{ChangeKind, CompareAgainst, CompareChange, CompareResult};
use crate::diag::{diag_json, problem_json};
use crate::AppState;
use axum::body::Bytes;
use axum::extract::rejection::BytesRejection;
use axum::extract::State;
use axum::http::StatusCode;
use axum::response::{IntoResponse, Response};
use axum::Json;
use serde::Deserialize;
use serde_json::{json, Value};
use sfc_diagnostics::Diagnostic;
use sfc_doc::EditorDoc;
use sfc_model::CheckOptions;
use std::path::Path;
use std::process::Command;

/// A file in git HEAD larger than this is not compared (the bound of files opened).
const MAX_FILE: usize = crate::MAX_BODY;

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct CompareRequest {
    /// The chart's file, as opened.
    path: String,
    /// The POU's name in the file, when the page renamed the chart since it was opened.
    #[serde(default)]
    pou: Option<String>,
    doc: EditorDoc,
    against: CompareAgainst,
}

/// A refusal with the diagnostics that locate it: `{"error", "diagnostics"}`.
struct Located {
    status: StatusCode,
    message: String,
    diagnostics: Vec<Value>,
}

enum Failure {
    Api(ApiError),
    Located(Located),
}

impl From<ApiError> for Failure {
    fn from(e: ApiError) -> Self {
        Failure::Api(e)
    }
}

impl IntoResponse for Failure {
    fn into_response(self) -> Response {
        match self {
            Failure::Api(e) => e.into_response(),
            Failure::Located(l) => {
                (l.status, Json(json!({ "error": l.message, "diagnostics": l.diagnostics }))).into_response()
            }
        }
    }
}

pub async fn compare(State(s): State<AppState>, body: Result<Bytes, BytesRejection>) -> Response {
    let req: CompareRequest = match body.map_err(|r| ApiError::new(r.status(), r.body_text())).and_then(|b| {
        serde_json::from_slice(&b).map_err(|e| ApiError::new(StatusCode::BAD_REQUEST, format!("bad request body: {e}")))
    }) {
        Ok(r) => r,
        Err(e) => return e.into_response(),
    };
    match tokio::task::spawn_blocking(move || compare_file(&s, req)).await {
        Ok(Ok(r)) => Json(r).into_response(),
        Ok(Err(f)) => f.into_response(),
        Err(_) => ApiError::new(StatusCode::INTERNAL_SERVER_ERROR, "internal error while comparing").into_response(),
    }
}

/// An IEC identifier, as a POU name must be.
fn is_identifier(s: &str) -> bool {
    let mut chars = s.chars();
    chars.next().is_some_and(|c| c.is_ascii_alphabetic() || c == '_')
        && chars.all(|c| c.is_ascii_alphanumeric() || c == '_')
}

/// Errors that mean the text could not be read as a chart file at all: lexical and syntax
/// errors, XML that is not well formed or not a project sfc reads.
fn unreadable(d: &Diagnostic) -> bool {
    d.is_error()
        && (d.code.starts_with("SFC00")
            || matches!(d.code, "SFC0101" | "SFC0102" | "SFC0103" | "SFC0701" | "SFC0702" | "SFC0731" | "SFC0740"))
}

/// `FILE:LINE:COLUMN: message` of a diagnostic as the page receives it.
fn located_line(d: &Value) -> String {
    format!(
        "{}:{}:{}: {}",
        d["file"].as_str().unwrap_or(""),
        d["line"].as_u64().unwrap_or(1),
        d["column"].as_u64().unwrap_or(1),
        d["message"].as_str().unwrap_or("")
    )
}

fn compare_file(s: &AppState, req: CompareRequest) -> Result<CompareResult, Failure> {
    let path = chart_path(s, &req.path)?;
    let doc = &req.doc;
    if !is_identifier(&doc.pou) {
        return Err(ApiError::new(
            StatusCode::BAD_REQUEST,
            format!("`{}` is not a valid POU name (an IEC identifier)", doc.pou),
        )
        .into());
    }
    refuse_unparsed(doc)?;
    let display = path.display().to_string();
    let (label, text) = match req.against {
        CompareAgainst::Saved => {
            let bytes = read_existing(&path)?.ok_or_else(|| {
                ApiError::new(StatusCode::NOT_FOUND, format!("`{display}` does not exist: it has not been saved"))
            })?;
            (display.clone(), sfc_syntax::encoding::decode(&bytes).text)
        }
        CompareAgainst::Head => (format!("{display}@HEAD"), at_head(&path)?),
    };
    let plain = CheckOptions { analysis: false, ..CheckOptions::default() };

    // The other side: the file's text (imported when it is PLCopen XML), which must read.
    let (file, old, diags) = sfc_driver::check_any(0, Path::new(&label), &text, &plain);
    let files = [file];
    let broken: Vec<Value> = diags.iter().filter(|d| unreadable(d)).map(|d| diag_json(d, &files, None, None)).collect();
    if let Some(first) = broken.first() {
        let against = match req.against {
            CompareAgainst::Saved => "the saved file",
            CompareAgainst::Head => "the file in git HEAD",
        };
        return Err(Failure::Located(Located {
            status: StatusCode::UNPROCESSABLE_ENTITY,
            message: format!("{against} does not parse, so it cannot be compared: {}", located_line(first)),
            diagnostics: broken,
        }));
    }
    let mut notes = Vec::new();
    let errors = diags.iter().filter(|d| d.is_error()).count();
    if errors > 0 {
        notes.push(format!(
            "`{label}` has {errors} error{}; it is compared as far as it could be read",
            if errors == 1 { "" } else { "s" }
        ));
    }

    // The canvas' side: that text with the document in place of its POU, as a save writes it.
    let replacing = req.pou.clone().filter(|p| is_identifier(p)).unwrap_or_else(|| doc.pou.clone());
    let renamed = !replacing.eq_ignore_ascii_case(&doc.pou);
    let base = &old.file.text;
    let in_file = sfc_doc::holds_pou(base, &replacing);
    let mut placed = doc.clone();
    // A renamed chart is compared under its old name, so its elements still match; the
    // rename is one change of its own.
    placed.pou = replacing.clone();
    let current = sfc_doc::splice_replacing(base, &placed, &replacing);
    let name = format!("{} (edited)", path.display());
    let new = sfc_analysis::check_source(0, &name, &current, &plain);
    let new_files = [new.file.clone()];
    let broken: Vec<Value> =
        new.diagnostics.iter().filter(|d| unreadable(d)).map(|d| diag_json(d, &new_files, None, None)).collect();
    if let Some(first) = broken.first() {
        return Err(Failure::Located(Located {
            status: StatusCode::UNPROCESSABLE_ENTITY,
            message: format!("the chart as edited does not parse, so it cannot be compared: {}", located_line(first)),
            diagnostics: broken,
        }));
    }

    let d = sfc_diff::diff(&old, &new);
    let ours = |pou: &str| pou.eq_ignore_ascii_case(&replacing);
    let mut changes = Vec::new();
    let mut removed = Vec::new();
    if renamed && in_file {
        changes.push(CompareChange {
            element: "pou".into(),
            name: replacing.clone(),
            kind: ChangeKind::Renamed,
            what: String::new(),
            old: Some(replacing.clone()),
            new: Some(doc.pou.clone()),
            element_ids: Vec::new(),
        });
    }
    for c in d.changes.iter().filter(|c| ours(&c.pou)) {
        let mut c = to_contract(c, doc);
        if c.element == "pou" && c.kind == ChangeKind::Added {
            // Not in the file yet: the chart as a whole is new there.
            c.name = doc.pou.clone();
        }
        if c.kind == ChangeKind::Removed {
            removed.push(c);
        } else {
            changes.push(c);
        }
    }
    let moved = if in_file { moved_blocks(base, &replacing, doc, &changes) } else { 0 };
    Ok(CompareResult {
        against: req.against,
        file: label,
        pou: doc.pou.clone(),
        equal: changes.is_empty() && removed.is_empty(),
        changes,
        removed,
        layout: moved,
        notes,
    })
}

/// How many blocks of `doc` have another place or size than in the chart the other side's
/// text opens as (`sfc_doc::open`, as the page opened it): steps and transitions by name (a
/// renamed step by its old name), other blocks by id. Counted on the drawing rather than on
/// the diff's layout attributes, which a chart written without positions gains for every
/// block at its first save.
fn moved_blocks(base: &str, pou: &str, doc: &EditorDoc, changes: &[CompareChange]) -> u32 {
    let opened = sfc_doc::open(0, "compared", base);
    let Some(before) = opened.charts.iter().find(|c| c.pou.eq_ignore_ascii_case(pou)) else { return 0 };
    let old_name = |kind: &str, name: &str| -> String {
        changes
            .iter()
            .find(|c| {
                c.kind == ChangeKind::Renamed
                    && c.element == kind
                    && c.new.as_deref().is_some_and(|n| n.eq_ignore_ascii_case(name))
            })
            .map_or_else(|| name.to_string(), |c| c.name.clone())
    };
    let named = |k: Option<sfc_doc::ElementKind>| match k {
        Some(sfc_doc::ElementKind::Step) => Some("step"),
        Some(sfc_doc::ElementKind::Transition) => Some("transition"),
        _ => None,
    };
    let mut n = 0u32;
    for e in &doc.elements {
        let was = match named(e.kind).filter(|_| !e.name.is_empty()) {
            Some(kind) => {
                let name = old_name(kind, &e.name);
                before.elements.iter().find(|b| b.kind == e.kind && b.name.eq_ignore_ascii_case(&name))
            }
            None => before.elements.iter().find(|b| b.kind == e.kind && b.id == e.id),
        };
        let apart = |a: f64, b: f64| (a - b).abs() > 0.5;
        if was.is_some_and(|b| apart(b.x, e.x) || apart(b.y, e.y) || apart(b.w, e.w) || apart(b.h, e.h)) {
            n = n.saturating_add(1);
        }
    }
    n
}

/// A change of the diff with the blocks of `doc` it concerns: a step or transition by its name
/// in the document (the new name of a renamed one), an action by the action blocks naming it.
fn to_contract(c: &sfc_diff::Change, doc: &EditorDoc) -> CompareChange {
    let kind = match c.kind {
        sfc_diff::Kind::Added => ChangeKind::Added,
        sfc_diff::Kind::Removed => ChangeKind::Removed,
        sfc_diff::Kind::Renamed => ChangeKind::Renamed,
        sfc_diff::Kind::Changed => ChangeKind::Changed,
    };
    let element_ids = match (kind, c.element) {
        (ChangeKind::Removed, _) => Vec::new(),
        (ChangeKind::Renamed, "step" | "transition") => sfc_doc::element_ids(doc, c.new.as_deref().unwrap_or(&c.name)),
        (_, "step" | "transition") => sfc_doc::element_ids(doc, &c.name),
        (_, "action") => doc
            .elements
            .iter()
            .filter(|e| e.kind == Some(sfc_doc::ElementKind::ActionBlock))
            .filter(|e| e.associations.iter().any(|a| a.action.eq_ignore_ascii_case(&c.name)))
            .map(|e| e.id.clone())
            .collect(),
        _ => Vec::new(),
    };
    CompareChange {
        element: c.element.to_string(),
        name: c.name.clone(),
        kind,
        what: c.what.clone(),
        old: c.old.clone(),
        new: c.new.clone(),
        element_ids,
    }
}

/// A document with text the user typed that does not parse (a condition, a body, the
/// declarations, a name) is not compared: its text would not say what the canvas shows.
fn refuse_unparsed(doc: &EditorDoc) -> Result<(), Failure> {
    let (written, lost) = crate::api::unparsed(doc);
    let Some(first) = lost.first() else { return Ok(()) };
    let name = format!("{}.st", doc.pou);
    let block = doc.elements.iter().find(|e| e.id == first.element).filter(|e| !e.name.is_empty());
    let what = match block {
        Some(e) => format!("`{}`: {}", e.name, first.message),
        None => first.message.clone(),
    };
    Err(Failure::Located(Located {
        status: StatusCode::UNPROCESSABLE_ENTITY,
        message: format!("the chart cannot be compared while {what} (fix it first)"),
        diagnostics: lost.iter().map(|p| problem_json(p, doc, &name, &written.text)).collect(),
    }))
}

/// The file's text in git HEAD: `git show HEAD:./NAME` in its directory. A file outside a git
/// repository, a repository without commits, and a file HEAD does not hold are refused with a
/// message saying which.
fn at_head(path: &Path) -> Result<String, ApiError> {
    let shown = path.display();
    let dir = path.parent().filter(|d| !d.as_os_str().is_empty()).unwrap_or(Path::new("."));
    let name = path.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
    let out = Command::new("git")
        .current_dir(dir)
        // The blob as stored: no text conversion (`sfc git setup` configures one for charts).
        .args(["show", "--no-textconv", &format!("HEAD:./{name}")])
        .env("GIT_TERMINAL_PROMPT", "0")
        .stdin(std::process::Stdio::null())
        .output()
        .map_err(|e| ApiError::new(StatusCode::INTERNAL_SERVER_ERROR, format!("cannot run git: {e}")))?;
    if !out.status.success() {
        let why = String::from_utf8_lossy(&out.stderr).trim().to_string();
        let lower = why.to_ascii_lowercase();
        let (status, message) = if lower.contains("not a git repository") {
            (
                StatusCode::UNPROCESSABLE_ENTITY,
                format!("`{shown}` is not under git: its folder is not in a git repository"),
            )
        } else if lower.contains("invalid object name 'head'") || lower.contains("ambiguous argument 'head'") {
            (StatusCode::NOT_FOUND, format!("`{shown}` is not in git HEAD: its repository has no commit yet"))
        } else if lower.contains("exists on disk, but not in")
            || lower.contains("does not exist in")
            || lower.contains("is outside repository")
        {
            (StatusCode::NOT_FOUND, format!("`{shown}` is not in git HEAD: it has never been committed"))
        } else {
            (StatusCode::UNPROCESSABLE_ENTITY, format!("git cannot give `{shown}` at HEAD: {why}"))
        };
        return Err(ApiError::new(status, message));
    }
    if out.stdout.len() > MAX_FILE {
        return Err(ApiError::new(
            StatusCode::PAYLOAD_TOO_LARGE,
            format!("`{shown}` in git HEAD is larger than {} MiB", MAX_FILE >> 20),
        ));
    }
    Ok(sfc_syntax::encoding::decode(&out.stdout).text)
}

#[cfg(test)]
mod tests {
    use super::*;
    use sfc_diagnostics::SourceFile;

    #[test]
    fn unreadable_codes() {
        let d = |code: &'static str| Diagnostic::error(code, sfc_diagnostics::Span::new(0, 0, 0), "x");
        assert!(unreadable(&d("SFC0101")));
        assert!(unreadable(&d("SFC0701")));
        assert!(!unreadable(&d("SFC0301")));
    }

    #[test]
    fn source_file_is_used() {
        // `located_line` reads what `diag_json` writes.
        let f = SourceFile::new("a.st", "PROGRAM P\nEND_PROGRAM x");
        let d = Diagnostic::error("SFC0101", sfc_diagnostics::Span::new(0, 22, 23), "unexpected `x`");
        let v = diag_json(&d, &[f], None, None);
        assert_eq!(located_line(&v), "a.st:2:13: unexpected `x`");
    }
}
