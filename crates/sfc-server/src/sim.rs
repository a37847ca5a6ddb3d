//! The editor's built-in simulator (`docs/editor.md`, "Monitor mode"): `POST /api/sim/start`
//! runs the open chart in the soft-PLC of `sfc run` (simulator mode: no Modbus, inputs come from
//! the monitor's `set`/`force`) with its monitor protocol on a free loopback port and a fresh
//! token; `POST /api/sim/stop` ends it. The page then talks to the runtime over WebSocket like to
//! any other runtime. Stopping the server stops every simulation.

use crate::api::ApiError;
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
use sfc_doc::{EditorDoc, ElementKind};
use sfc_runtime::{RunOptions, Runtime};
use sfc_sim::{Profile, SimOptions, Simulation};
use std::collections::BTreeMap;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Mutex;

/// Most simulations running at once (each has a scan thread and two network threads).
pub const MAX_SIMULATIONS: usize = 4;
/// Scan periods a simulation accepts, µs: 1 ms … 1 s.
const PERIODS: std::ops::RangeInclusive<i64> = 1_000..=1_000_000;

/// The simulations of one editor session, by id.
#[derive(Default)]
pub struct Simulations {
    next: AtomicU64,
    running: Mutex<BTreeMap<u64, Runtime>>,
}

impl std::fmt::Debug for Simulations {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let ids: Vec<u64> = self.lock().keys().copied().collect();
        f.debug_struct("Simulations").field("running", &ids).finish()
    }
}

impl Simulations {
    fn lock(&self) -> std::sync::MutexGuard<'_, BTreeMap<u64, Runtime>> {
        self.running.lock().unwrap_or_else(|e| e.into_inner())
    }

    /// Stops every simulation and waits for them to end (the server is shutting down).
    pub fn stop_all(&self) {
        let all = std::mem::take(&mut *self.lock());
        for rt in all.values() {
            rt.stop();
        }
        // Dropping a runtime waits for its threads.
        drop(all);
    }
}

impl Drop for Simulations {
    fn drop(&mut self) {
        self.stop_all();
    }
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct StartRequest {
    doc: EditorDoc,
    /// Scan period, a TIME literal (default `T#10ms`).
    period: Option<String>,
    /// Start halted: nothing scans until the monitor sends `continue` or `step`.
    #[serde(default)]
    halted: bool,
    /// The file the chart was opened from: a CODESYS, TwinCAT or e!COCKPIT export runs with the
    /// `codesys` profile, as `sfc sim` runs it.
    #[serde(default)]
    path: Option<String>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct StopRequest {
    id: u64,
}

fn parse<T: serde::de::DeserializeOwned>(body: Result<Bytes, BytesRejection>) -> Result<T, ApiError> {
    let bytes = body.map_err(|r| ApiError::new(r.status(), r.body_text()))?;
    serde_json::from_slice(&bytes).map_err(|e| ApiError::new(StatusCode::BAD_REQUEST, format!("bad request body: {e}")))
}

/// Why a simulation does not start.
enum Refused {
    /// A bad request, the limit, or a failure to start: `{"error"}` with its status.
    Api(ApiError),
    /// `422 {"error","diagnostics"}`: the chart cannot be simulated.
    Chart(String, Vec<Value>),
}

impl IntoResponse for Refused {
    fn into_response(self) -> Response {
        match self {
            Refused::Api(e) => e.into_response(),
            Refused::Chart(message, diagnostics) => {
                (StatusCode::UNPROCESSABLE_ENTITY, Json(json!({"error": message, "diagnostics": diagnostics})))
                    .into_response()
            }
        }
    }
}

fn refuse(status: StatusCode, message: impl Into<String>) -> Refused {
    Refused::Api(ApiError::new(status, message))
}

fn too_many() -> Refused {
    refuse(StatusCode::TOO_MANY_REQUESTS, format!("{MAX_SIMULATIONS} simulations are running already: stop one first"))
}

/// The blocks of each step and transition of the simulation, by the names the runtime uses, so
/// the page can frame them (an unnamed transition is `T<n>` in the text, and in the runtime).
fn element_map(doc: &EditorDoc, sim: &Simulation) -> Value {
    let (steps, transitions) = sim.outline();
    let kind_of = |id: &str| doc.elements.iter().find(|e| e.id == id).and_then(|e| e.kind);
    let mut map = serde_json::Map::new();
    let names = steps
        .iter()
        .map(|s| (&s.0, ElementKind::Step))
        .chain(transitions.iter().map(|t| (&t.0, ElementKind::Transition)));
    for (name, kind) in names {
        let ids: Vec<String> =
            sfc_doc::element_ids(doc, name).into_iter().filter(|id| kind_of(id) == Some(kind)).collect();
        if !ids.is_empty() {
            map.insert(name.clone(), json!(ids));
        }
    }
    Value::Object(map)
}

/// The profile of a simulation of the chart opened from `path` (whose `vendor` wrote it) and
/// why, as the answer's `profile`:
/// `{"name":"codesys","source":"vendor","vendor":"TwinCAT","file":"lift.xml"}` for an export of a
/// tool of the CODESYS family, `{"name":"iec","source":"default"}` otherwise.
fn profile_of(path: Option<&str>, vendor: Option<sfc_plcopen::Vendor>) -> (Profile, Value) {
    let (profile, source) = sfc_sim::file_profile(vendor);
    let answer = match source {
        sfc_sim::ProfileSource::Vendor(v) => {
            let file = path.map(|p| std::path::Path::new(p).file_name().map_or(p.into(), |f| f.to_string_lossy()));
            json!({"name": profile.name(), "source": "vendor", "vendor": v.name(), "file": file})
        }
        _ => json!({"name": profile.name(), "source": "default"}),
    };
    (profile, answer)
}

/// Builds and starts the simulation of `req.doc`; `Err` is the answer to send instead.
fn start_simulation(state: &AppState, req: StartRequest, port: u16) -> Result<Value, Refused> {
    let sims = &state.0.sims;
    let period = match &req.period {
        None => 10_000,
        Some(p) => match sfc_sim::parse_time(p) {
            Some(us) if PERIODS.contains(&us) => us,
            Some(_) => {
                return Err(refuse(
                    StatusCode::BAD_REQUEST,
                    format!("period `{p}` is out of range: from T#1ms to T#1s"),
                ))
            }
            None => {
                return Err(refuse(
                    StatusCode::BAD_REQUEST,
                    format!("period `{p}` is not a TIME literal (such as T#10ms)"),
                ))
            }
        },
    };
    {
        let mut running = sims.lock();
        // A simulation that ended on its own (a runtime error) no longer counts.
        let ended: Vec<u64> = running.iter().filter(|(_, rt)| rt.is_finished()).map(|(&id, _)| id).collect();
        for id in ended {
            running.remove(&id);
        }
        if running.len() >= MAX_SIMULATIONS {
            return Err(too_many());
        }
    }
    let doc = req.doc;
    let written = sfc_doc::to_text(&doc);
    let name = format!("{}.st", doc.pou);
    let mut diagnostics: Vec<Value> =
        written.problems.iter().map(|p| problem_json(p, &doc, &name, &written.text)).collect();
    let problems = written.problems.iter().any(|p| p.severity == sfc_diagnostics::Severity::Error);
    // The file the chart was opened from: its other POUs (the function blocks the chart
    // instantiates, its globals) and its vendor, which chooses the profile.
    let file = match req.path.as_deref() {
        Some(p) => crate::api::file_for_simulation(state, p).map_err(Refused::Api)?,
        None => None,
    };
    let (profile, profile_answer) = profile_of(req.path.as_deref(), file.as_ref().and_then(|f| f.1));
    let opts = SimOptions { period, profile };
    // The chart in its file (the document spliced in place of its POU), else on its own, whose
    // errors are the ones shown.
    let in_file = file.as_ref().filter(|_| !problems).and_then(|(text, _)| {
        let spliced = sfc_doc::splice(text, &doc);
        Simulation::from_source(&name, &spliced, Some(&doc.pou), opts).ok()
    });
    let sim = match in_file.map_or_else(|| Simulation::from_source(&name, &written.text, Some(&doc.pou), opts), Ok) {
        Ok(sim) if !problems => sim,
        Ok(_) => return Err(Refused::Chart(format!("the chart `{}` has errors", doc.pou), diagnostics)),
        Err((file, diags)) => {
            let files = [file];
            diagnostics.extend(diags.iter().map(|d| diag_json(d, &files, Some(&doc), Some(&doc.pou))));
            return Err(Refused::Chart(format!("the chart `{}` has errors", doc.pou), diagnostics));
        }
    };
    let elements = element_map(&doc, &sim);
    let opts = RunOptions {
        monitor: Some(std::net::SocketAddr::from(([127, 0, 0, 1], 0))),
        // Only the editor's own page (and clients that are not browsers) may connect.
        monitor_access: sfc_runtime::MonitorAccess {
            origins: Some(vec![format!("http://127.0.0.1:{port}"), format!("http://localhost:{port}")]),
            hosts: Vec::new(),
        },
        // A runaway scan or a runtime error shows as FAULT in the monitor until stopped or reset.
        wait_in_fault: true,
        halted: req.halted,
        ..Default::default()
    };
    let rt = Runtime::start(sim, opts).map_err(|e| refuse(StatusCode::INTERNAL_SERVER_ERROR, e))?;
    let addr =
        rt.monitor_addr().ok_or_else(|| refuse(StatusCode::INTERNAL_SERVER_ERROR, "the monitor has no address"))?;
    let url = format!("ws://{addr}/?token={}", rt.token());
    let id = sims.next.fetch_add(1, Ordering::Relaxed) + 1;
    let mut running = sims.lock();
    if running.len() >= MAX_SIMULATIONS {
        // Another start won the last place while this one was being built.
        drop(running);
        rt.stop();
        drop(rt);
        return Err(too_many());
    }
    running.insert(id, rt);
    Ok(json!({
        "id": id,
        "url": url,
        "period": sfc_sim::format_time(period),
        "elements": elements,
        "profile": profile_answer,
    }))
}

/// `POST /api/sim/start {"doc","period"?,"halted"?,"path"?}` → `{"id","url","period","elements","profile"}`.
pub async fn start(State(s): State<AppState>, body: Result<Bytes, BytesRejection>) -> Response {
    let req: StartRequest = match parse(body) {
        Ok(r) => r,
        Err(e) => return e.into_response(),
    };
    let state = s.clone();
    let port = state.port();
    match tokio::task::spawn_blocking(move || start_simulation(&state, req, port)).await {
        Ok(Ok(v)) => Json(v).into_response(),
        Ok(Err(r)) => r.into_response(),
        Err(_) => {
            refuse(StatusCode::INTERNAL_SERVER_ERROR, "internal error: the simulation failed to start").into_response()
        }
    }
}

/// `POST /api/sim/stop {"id"}` → `{"stopped":id}`; `404` for an unknown id.
pub async fn stop(State(s): State<AppState>, body: Result<Bytes, BytesRejection>) -> Response {
    let req: StopRequest = match parse(body) {
        Ok(r) => r,
        Err(e) => return e.into_response(),
    };
    let Some(rt) = s.0.sims.lock().remove(&req.id) else {
        return refuse(StatusCode::NOT_FOUND, format!("no simulation {}", req.id)).into_response();
    };
    rt.stop();
    // Dropping waits for the scan and network threads: not on a worker of the server.
    let _ = tokio::task::spawn_blocking(move || drop(rt)).await;
    Json(json!({"stopped": req.id})).into_response()
}
