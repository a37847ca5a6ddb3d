//! In-process calls of the editor's router (tower `oneshot`), with the Host and token headers
//! a browser page would send.

#![allow(dead_code)]
// each test file uses a part
// Test helpers, like the tests themselves, may panic: a panic is a failed test (clippy.toml
// allows it in `#[test]` functions only, not in the helpers they share).
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::indexing_slicing)]

use axum::body::Body;
use axum::http::{Request, StatusCode};
use http_body_util::BodyExt;
use serde_json::Value;
use sfc_server::{app, AppState, EditOptions, HostMode};
use std::path::{Path, PathBuf};
use tower::ServiceExt;

/// The port the in-process server pretends to listen on (the `Host` header must name it).
pub const PORT: u16 = 47123;

pub fn fixtures() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures")
}

/// A fresh, empty, canonical scratch directory.
pub fn scratch(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("sfc-server-test-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    std::fs::canonicalize(&d).unwrap()
}

/// A scratch directory holding copies of the fixtures named.
pub fn scratch_with(name: &str, files: &[&str]) -> PathBuf {
    let d = scratch(name);
    for f in files {
        std::fs::copy(fixtures().join(f), d.join(f)).unwrap();
    }
    d
}

pub fn state(files: &[&Path], host: Option<HostMode>) -> AppState {
    let opts = EditOptions { files: files.iter().map(|p| p.to_path_buf()).collect(), port: Some(PORT), host };
    AppState::new(&opts, PORT).expect("the session starts")
}

/// An answer: status, headers we look at, and the body (JSON when it parses, else a string).
pub struct Answer {
    pub status: StatusCode,
    pub content_type: String,
    pub cache_control: String,
    pub body: Value,
    pub text: String,
}

pub struct Call<'a> {
    pub method: &'a str,
    pub uri: &'a str,
    pub host: Option<&'a str>,
    pub token: Option<&'a str>,
    pub body: Option<Vec<u8>>,
}

pub async fn send(state: &AppState, call: Call<'_>) -> Answer {
    let mut req = Request::builder().method(call.method).uri(call.uri);
    if let Some(h) = call.host {
        req = req.header("host", h);
    }
    if let Some(t) = call.token {
        req = req.header("x-sfc-token", t);
    }
    let body = match call.body {
        Some(b) => {
            req = req.header("content-type", "application/json");
            Body::from(b)
        }
        None => Body::empty(),
    };
    let resp = app(state.clone()).oneshot(req.body(body).unwrap()).await.expect("the router answers");
    let status = resp.status();
    let header = |name: &str| resp.headers().get(name).and_then(|v| v.to_str().ok()).unwrap_or("").to_string();
    let content_type = header("content-type");
    let cache_control = header("cache-control");
    let bytes = resp.into_body().collect().await.unwrap().to_bytes();
    let text = String::from_utf8_lossy(&bytes).into_owned();
    let body = serde_json::from_slice(&bytes).unwrap_or(Value::Null);
    Answer { status, content_type, cache_control, body, text }
}

pub fn own_host() -> String {
    format!("127.0.0.1:{PORT}")
}

/// A GET of `uri` as the page sends it.
pub async fn get(state: &AppState, uri: &str) -> Answer {
    let host = own_host();
    send(state, Call { method: "GET", uri, host: Some(&host), token: Some(state.token()), body: None }).await
}

/// A POST of JSON to `uri` as the page sends it.
pub async fn post(state: &AppState, uri: &str, body: &Value) -> Answer {
    let host = own_host();
    let body = Some(serde_json::to_vec(body).unwrap());
    send(state, Call { method: "POST", uri, host: Some(&host), token: Some(state.token()), body }).await
}

/// A POST of raw bytes.
pub async fn post_raw(state: &AppState, uri: &str, body: Vec<u8>) -> Answer {
    let host = own_host();
    send(state, Call { method: "POST", uri, host: Some(&host), token: Some(state.token()), body: Some(body) }).await
}

pub fn path_str(p: &Path) -> String {
    p.to_str().unwrap().to_string()
}

/// Names of the entries of a directory, sorted.
pub fn entries(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> =
        std::fs::read_dir(dir).unwrap().map(|e| e.unwrap().file_name().to_string_lossy().into_owned()).collect();
    v.sort();
    v
}

/// A document that deserialises (the calls that refuse before converting it need no more).
pub fn small_doc(pou: &str) -> Value {
    serde_json::json!({
        "pou": pou, "pouKind": "program", "target": "blank", "declarations": "",
        "actions": [], "elements": [], "connections": []
    })
}

/// The status of a GET of `uri` with two `Host` headers, `first` then `second`.
pub async fn status_with_two_hosts(state: &AppState, uri: &str, first: &str, second: &str) -> StatusCode {
    let req = Request::builder()
        .method("GET")
        .uri(uri)
        .header("host", first)
        .header("host", second)
        .header("x-sfc-token", state.token())
        .body(Body::empty())
        .unwrap();
    app(state.clone()).oneshot(req).await.expect("the router answers").status()
}
