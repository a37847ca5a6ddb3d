//! `POST /api/prove {"doc","path"}`: `sfc prove` on the open chart with the property file beside
//! its file (`<chart>.props.toml`, inside the roots). The answer is what the Error List shows:
//! one diagnostic per violated (SFC1002) or undecided (SFC1003) property, located in the
//! property file, each violation with the witness's inputs per scan so the page can replay it
//! in monitor mode; a property file with an error gives its SFC1001.

use crate::api::ApiError;
use crate::contract::{Diag, ProveResult, ProveSummary, Replay, Severity};
use crate::AppState;
use axum::body::Bytes;
use axum::extract::rejection::BytesRejection;
use axum::extract::State;
use axum::http::StatusCode;
use axum::response::{IntoResponse, Response};
use axum::Json;
use serde::Deserialize;
use serde_json::Value;
use sfc_doc::EditorDoc;
use sfc_prove::{Options, ProveError, Verdict};
use std::path::{Path, PathBuf};

/// Seconds a proof may take in the editor (all properties together).
const BUDGET_SECONDS: f64 = 20.0;

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct ProveRequest {
    doc: EditorDoc,
    /// The chart's file (as opened): its property file is beside it.
    path: String,
}

fn props_path(chart: &Path) -> PathBuf {
    let stem = chart.file_stem().map_or_else(|| "chart".into(), |s| s.to_string_lossy().into_owned());
    chart.with_file_name(format!("{stem}.props.toml"))
}

fn at(file: &str, line: u32, column: u32) -> (String, u32, u32) {
    (file.to_string(), line, column)
}

fn diag(code: &str, severity: Severity, message: String, element: Option<&str>, loc: (String, u32, u32)) -> Diag {
    Diag {
        code: code.to_string(),
        severity,
        message,
        title: sfc_diagnostics::explain(code).map_or_else(String::new, |i| i.title.to_string()),
        file: loc.0,
        line: loc.1,
        column: loc.2,
        end_line: loc.1,
        end_column: loc.2,
        element: element.map(str::to_string),
        element_ids: Vec::new(),
        notes: Vec::new(),
        witness: Value::Null,
        witness_ids: None,
        replay: None,
        pou: None,
    }
}

fn failed(props_name: &str, d: Diag) -> ProveResult {
    ProveResult { properties_file: props_name.to_string(), diagnostics: vec![d], summary: None }
}

pub async fn prove(State(s): State<AppState>, body: Result<Bytes, BytesRejection>) -> Response {
    let req: ProveRequest = match body.map_err(|r| ApiError::new(r.status(), r.body_text())).and_then(|b| {
        serde_json::from_slice(&b).map_err(|e| ApiError::new(StatusCode::BAD_REQUEST, format!("bad request body: {e}")))
    }) {
        Ok(r) => r,
        Err(e) => return e.into_response(),
    };
    let chart = match crate::confine(&s.0.roots, &s.0.open, &req.path) {
        Ok(p) => p,
        Err(e) => return ApiError::from(e).into_response(),
    };
    let props = props_path(&chart);
    let props_name = props.display().to_string();
    let text = match std::fs::read(&props) {
        Ok(b) => String::from_utf8_lossy(&b).into_owned(),
        Err(_) => {
            return ApiError::new(
                StatusCode::NOT_FOUND,
                format!("no property file: `{props_name}` does not exist (write the requirements there)"),
            )
            .into_response()
        }
    };
    let work = move || -> ProveResult {
        let file = match sfc_prove::props::parse(&props_name, &text) {
            Ok(f) => f,
            Err(e) => {
                let d = diag("SFC1001", Severity::Error, e.message.clone(), None, at(&props_name, e.line, e.column));
                return failed(&props_name, d);
            }
        };
        let written = sfc_doc::to_text(&req.doc);
        let name = chart.display().to_string();
        let opts = Options { seconds: BUDGET_SECONDS, pou: Some(req.doc.pou.clone()), ..Options::default() };
        let report = match sfc_prove::prove(&name, &written.text, &file, &opts) {
            Ok(r) => r,
            Err(ProveError::Props(e)) => {
                let d = diag("SFC1001", Severity::Error, e.message.clone(), None, at(&props_name, e.line, e.column));
                return failed(&props_name, d);
            }
            Err(ProveError::Unsupported(why)) => {
                let d = diag("SFC1001", Severity::Error, why, None, at(&props_name, 1, 1));
                return failed(&props_name, d);
            }
            Err(ProveError::Chart(b)) => {
                let (_, diags) = *b;
                let first = diags.first().map_or_else(String::new, |d| d.message.clone());
                let d = diag(
                    "SFC1001",
                    Severity::Error,
                    format!("the chart must be free of errors to be proved: {first}"),
                    None,
                    at(&props_name, 1, 1),
                );
                return failed(&props_name, d);
            }
        };
        let mut out = Vec::new();
        for p in &report.properties {
            let loc = at(&props_name, p.line.max(1), 1);
            match p.verdict {
                Verdict::Holds => {}
                Verdict::Violated => {
                    let mut d = diag(
                        "SFC1002",
                        Severity::Error,
                        format!("property `{}` is violated: {}", p.name, p.message),
                        Some(&p.name),
                        loc,
                    );
                    if let Some(w) = &p.witness {
                        d.notes = vec![format!("witness: {} ({} scans)", w.file, w.scans)];
                        d.replay = Some(Replay {
                            period: sfc_sim::format_time(report.period),
                            scans: w.inputs.clone(),
                            scenario: w.text.clone(),
                            file: w.file.clone(),
                        });
                    }
                    out.push(d);
                }
                Verdict::Unknown => out.push(diag(
                    "SFC1003",
                    Severity::Warning,
                    format!("property `{}` is not decided: {}", p.name, p.message),
                    Some(&p.name),
                    loc,
                )),
            }
        }
        let count = |v| u32::try_from(report.count(v)).unwrap_or(u32::MAX);
        ProveResult {
            properties_file: props_name,
            diagnostics: out,
            summary: Some(ProveSummary {
                holds: count(Verdict::Holds),
                violated: count(Verdict::Violated),
                unknown: count(Verdict::Unknown),
            }),
        }
    };
    match tokio::task::spawn_blocking(work).await {
        Ok(v) => Json(v).into_response(),
        Err(_) => ApiError::new(StatusCode::INTERNAL_SERVER_ERROR, "internal error while proving").into_response(),
    }
}
