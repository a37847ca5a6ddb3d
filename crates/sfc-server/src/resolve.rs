//! `POST /api/resolve {"path"?,"pou"?,"doc","element","side"}`: one merge conflict of the
//! chart on the canvas resolved by taking a side (the editor's *Merge conflicts* panel).
//!
//! `sfc merge` writes a conflicting element as ours and marks its POU with
//! `{attribute 'sfc.conflict' := 'KIND:NAME$N…their text…'}`, which the editor keeps among the
//! document's other attributes. Here the document is written as text (`sfc_doc::to_text`; put
//! into its file's text as a save would when `path` names an IEC text file, so the other POUs,
//! types and globals are there for the check), `sfc_diff::merge::resolve` takes the side (ours:
//! the mark removed; theirs: the element's text replaced by theirs as well), and the result is
//! opened again: the answer is that POU's chart and the diagnostics of the text, as
//! `POST /api/open` gives them. Nothing is written: the page holds the resolved chart as an
//! unsaved edit.

use crate::api::{chart_path, page_diagnostics, read_existing, ApiError};
use crate::contract::ConflictSide;
use crate::diag::problem_json;
use crate::AppState;
use axum::body::Bytes;
use axum::extract::rejection::BytesRejection;
use axum::extract::State;
use axum::http::StatusCode;
use axum::response::{IntoResponse, Response};
use axum::Json;
use serde::Deserialize;
use serde_json::{json, Value};
use sfc_doc::EditorDoc;

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct ResolveRequest {
    /// The chart's file, as opened (absent for a chart never saved).
    #[serde(default)]
    path: Option<String>,
    /// The POU's name in the file, when the page renamed the chart since it was opened.
    #[serde(default)]
    pou: Option<String>,
    doc: EditorDoc,
    /// The conflict's element as marked: `transition:TStart`, `step:Fill`, `action:Count`, …
    element: String,
    side: ConflictSide,
}

pub async fn resolve(State(s): State<AppState>, body: Result<Bytes, BytesRejection>) -> Response {
    let req: ResolveRequest = match body.map_err(|r| ApiError::new(r.status(), r.body_text())).and_then(|b| {
        serde_json::from_slice(&b).map_err(|e| ApiError::new(StatusCode::BAD_REQUEST, format!("bad request body: {e}")))
    }) {
        Ok(r) => r,
        Err(e) => return e.into_response(),
    };
    match tokio::task::spawn_blocking(move || resolve_conflict(&s, req)).await {
        Ok(Ok(v)) => Json(v).into_response(),
        Ok(Err(e)) => e.into_response(),
        Err(_) => ApiError::new(StatusCode::INTERNAL_SERVER_ERROR, "internal error while resolving the conflict")
            .into_response(),
    }
}

/// An IEC identifier, as a POU name must be.
fn is_identifier(s: &str) -> bool {
    let mut chars = s.chars();
    chars.next().is_some_and(|c| c.is_ascii_alphabetic() || c == '_')
        && chars.all(|c| c.is_ascii_alphanumeric() || c == '_')
}

fn unprocessable(message: String) -> ApiError {
    ApiError::new(StatusCode::UNPROCESSABLE_ENTITY, message)
}

/// The conflicts the document's POU is marked with: (element as `kind:Name`, their text), as
/// `sfc_diff::merge::conflicts_of` reads them from the text.
fn conflicts(doc: &EditorDoc) -> Vec<(String, String)> {
    doc.attributes
        .iter()
        .filter(|a| a.name.eq_ignore_ascii_case(sfc_diff::merge::CONFLICT))
        .map(|a| {
            let v = sfc_syntax::attr_value::unescape(a.value.as_deref().unwrap_or(""));
            let (element, theirs) = v.split_once('\n').unwrap_or((v.as_str(), ""));
            (element.trim().to_string(), theirs.to_string())
        })
        .collect()
}

/// The answer (`contract::ResolveResult`): the POU's chart as resolved and the diagnostics.
fn resolve_conflict(s: &AppState, req: ResolveRequest) -> Result<Value, ApiError> {
    let doc = &req.doc;
    if !is_identifier(&doc.pou) {
        return Err(ApiError::new(
            StatusCode::BAD_REQUEST,
            format!("`{}` is not a valid POU name (an IEC identifier)", doc.pou),
        ));
    }
    let element = req.element.trim();
    if element.is_empty() {
        return Err(ApiError::new(StatusCode::BAD_REQUEST, "no element named: give the conflict's `kind:Name`"));
    }
    let marked = conflicts(doc);
    if !marked.iter().any(|(e, _)| e.eq_ignore_ascii_case(element)) {
        let known: Vec<&str> = marked.iter().map(|(e, _)| e.as_str()).collect();
        let listed = if known.is_empty() { "none".to_string() } else { known.join(", ") };
        return Err(ApiError::new(
            StatusCode::NOT_FOUND,
            format!("`{}` has no merge conflict on `{element}` (its conflicts: {listed})", doc.pou),
        ));
    }
    refuse_unparsed(doc)?;

    // The text the conflict is resolved in: the file's with the document in place of its POU
    // (as a save writes it), or the document's own text.
    let own = || (format!("{}.st", doc.pou), sfc_doc::to_text(doc).text);
    let (name, text) = match req.path.as_deref() {
        Some(raw) => {
            let path = chart_path(s, raw)?;
            let file = read_existing(&path)?.map(|b| sfc_syntax::encoding::decode(&b).text);
            match file {
                Some(t) if !sfc_driver::compile::is_xml(&path, &t) => {
                    let replacing = req.pou.clone().filter(|p| is_identifier(p)).unwrap_or_else(|| doc.pou.clone());
                    let renamed = !replacing.eq_ignore_ascii_case(&doc.pou);
                    if renamed && sfc_doc::holds_pou(&t, &doc.pou) {
                        // Saving would refuse it too: two POUs of that name.
                        own()
                    } else {
                        (path.display().to_string(), sfc_doc::splice_replacing(&t, doc, &replacing))
                    }
                }
                // PLCopen XML, or not saved yet: the POU's text alone.
                _ => own(),
            }
        }
        None => own(),
    };
    let theirs = req.side == ConflictSide::Theirs;
    let resolved = sfc_diff::merge::resolve(&text, &doc.pou, element, theirs)
        .map_err(|why| unprocessable(format!("the conflict on `{element}` cannot be resolved: {why}")))?;
    let opened = sfc_doc::open(0, &name, &resolved);
    let Some(chart) = opened.charts.iter().find(|c| c.pou.eq_ignore_ascii_case(&doc.pou)).cloned() else {
        let first = opened.diagnostics.iter().find(|d| d.is_error()).map(|d| {
            let at = opened.file.line_col(d.span.start);
            format!(": {name}:{}:{}: {}", at.line, at.column, d.message)
        });
        return Err(unprocessable(format!(
            "taking {} on `{element}` leaves no chart `{}`{}",
            if theirs { "theirs" } else { "ours" },
            doc.pou,
            first.unwrap_or_default()
        )));
    };
    let diagnostics = page_diagnostics(&name, &resolved, None, &opened.diagnostics, &opened.charts);
    Ok(json!({ "doc": chart, "diagnostics": diagnostics }))
}

/// A document with text the user typed that does not parse (a condition, a body, a name) is
/// not resolved: its text would not say what the canvas shows, and the resolved chart would
/// lose what was typed.
fn refuse_unparsed(doc: &EditorDoc) -> Result<(), ApiError> {
    let (written, lost) = crate::api::unparsed(doc);
    let Some(first) = lost.first() else { return Ok(()) };
    let name = format!("{}.st", doc.pou);
    let block = doc.elements.iter().find(|e| e.id == first.element).filter(|e| !e.name.is_empty());
    let what = match block {
        Some(e) => format!("`{}`: {}", e.name, first.message),
        None => first.message.clone(),
    };
    let d: Vec<Value> = lost.iter().map(|p| problem_json(p, doc, &name, &written.text)).collect();
    Err(unprocessable(format!("the conflict cannot be resolved while {what} (fix it first)"))
        .with("diagnostics", json!(d)))
}
