//! The built-in simulator of monitor mode: `POST /api/sim/start` and `/api/sim/stop` through
//! the in-process router, and the runtime it starts, over a real WebSocket.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::indexing_slicing)] // test code: a panic is a failed test

mod common;

use common::{post, send, state, Call};
use futures_util::StreamExt;
use serde_json::{json, Value};
use std::path::{Path, PathBuf};
use std::time::Duration;
use tokio_tungstenite::tungstenite::Message;

fn carwash_dir() -> PathBuf {
    std::fs::canonicalize(Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples/carwash")).unwrap()
}

/// The car wash chart as the page has it after `open`.
async fn carwash_doc(s: &sfc_server::AppState) -> Value {
    let path = carwash_dir().join("carwash.st");
    let a = post(s, "/api/open", &json!({ "path": path.to_str().unwrap() })).await;
    assert_eq!(a.status, 200, "{}", a.text);
    a.body["charts"][0].clone()
}

type Ws = tokio_tungstenite::WebSocketStream<tokio_tungstenite::MaybeTlsStream<tokio::net::TcpStream>>;

/// The next JSON message, `None` when the connection ends (or after 10 s).
async fn next(ws: &mut Ws) -> Option<Value> {
    loop {
        match tokio::time::timeout(Duration::from_secs(10), ws.next()).await.ok()?? {
            Ok(Message::Text(t)) => return Some(serde_json::from_str(&t).unwrap()),
            Ok(Message::Close(_)) | Err(_) => return None,
            Ok(_) => continue,
        }
    }
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn start_serves_the_chart_and_stop_ends_it() {
    let dir = carwash_dir();
    let s = state(&[dir.as_path()], None);
    let doc = carwash_doc(&s).await;
    let a = post(&s, "/api/sim/start", &json!({ "doc": doc, "period": "T#20ms", "halted": true })).await;
    assert_eq!(a.status, 200, "{}", a.text);
    let url = a.body["url"].as_str().unwrap().to_string();
    assert!(url.starts_with("ws://127.0.0.1:") && url.contains("/?token="), "{url}");
    assert_eq!(a.body["period"], "T#20ms");
    let id = a.body["id"].as_u64().unwrap();
    // Each step and transition of the runtime is named with its block.
    let idle = a.body["elements"]["Idle"].as_array().expect("Idle has a block").clone();
    let blocks = doc["elements"].as_array().unwrap();
    let kind = |id: &Value| blocks.iter().find(|e| e["id"] == *id).map(|e| e["kind"].clone()).unwrap();
    assert_eq!(idle.len(), 1);
    assert_eq!(kind(&idle[0]), "step");
    assert_eq!(kind(&a.body["elements"]["TStart"][0]), "transition");

    let (mut ws, _) = tokio_tungstenite::connect_async(&url).await.expect("the monitor accepts the URL");
    let hello = next(&mut ws).await.unwrap();
    assert_eq!((hello["type"].clone(), hello["pou"].clone()), (json!("hello"), json!("CarWash")));
    assert_eq!(hello["authorized"], true, "the URL carries the run's token");
    assert_eq!(hello["halted"], true);
    assert_eq!(hello["period"], "T#20ms");
    use futures_util::SinkExt;
    // Halted: nothing has scanned yet; one scan runs the initial step.
    ws.send(Message::Text(json!({"id": 1, "cmd": "step"}).to_string().into())).await.unwrap();
    let snap = loop {
        let m = next(&mut ws).await.unwrap();
        if m["type"] == "snapshot" || m["type"] == "delta" {
            break m;
        }
    };
    assert_eq!(snap["scan"], 0);
    assert_eq!(snap["active"][0]["step"], "Idle");
    ws.send(Message::Text(json!({"id": 2, "cmd": "explain", "step": "Idle"}).to_string().into())).await.unwrap();
    let r = loop {
        let m = next(&mut ws).await.unwrap();
        if m["re"] == 2 {
            break m;
        }
    };
    assert_eq!(r["ok"], true, "{r}");
    assert_eq!(r["result"]["transitions"][0]["transition"], "TStart");

    let a = post(&s, "/api/sim/stop", &json!({ "id": id })).await;
    assert_eq!((a.status.as_u16(), a.body.clone()), (200, json!({ "stopped": id })));
    // The monitor goes away with the run.
    while next(&mut ws).await.is_some() {}
    let a = post(&s, "/api/sim/stop", &json!({ "id": id })).await;
    assert_eq!((a.status.as_u16(), a.body["error"].clone()), (404, json!(format!("no simulation {id}"))));
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn refusals() {
    let dir = carwash_dir();
    let s = state(&[dir.as_path()], None);
    let doc = carwash_doc(&s).await;
    // The token and Host checks of every call.
    let host = common::own_host();
    let body = Some(serde_json::to_vec(&json!({ "doc": doc })).unwrap());
    let a = send(&s, Call { method: "POST", uri: "/api/sim/start", host: Some(&host), token: None, body }).await;
    assert_eq!(a.status, 403);
    let body = Some(serde_json::to_vec(&json!({ "doc": doc })).unwrap());
    let a = send(
        &s,
        Call { method: "POST", uri: "/api/sim/start", host: Some("evil.example:80"), token: Some(s.token()), body },
    )
    .await;
    assert_eq!(a.status, 403);
    // Bad periods and bodies.
    let a = post(&s, "/api/sim/start", &json!({ "doc": doc, "period": "10ms" })).await;
    assert_eq!(
        (a.status.as_u16(), a.body["error"].clone()),
        (400, json!("period `10ms` is not a TIME literal (such as T#10ms)"))
    );
    let a = post(&s, "/api/sim/start", &json!({ "doc": doc, "period": "T#5s" })).await;
    assert_eq!(
        (a.status.as_u16(), a.body["error"].clone()),
        (400, json!("period `T#5s` is out of range: from T#1ms to T#1s"))
    );
    let a = post(&s, "/api/sim/start", &json!({ "doc": doc, "speed": 2 })).await;
    assert_eq!(a.status, 400);
    assert!(a.body["error"].as_str().unwrap().contains("unknown field `speed`"), "{}", a.text);
    let a = post(&s, "/api/sim/stop", &json!({ "id": "x" })).await;
    assert_eq!(a.status, 400);
    // A chart with an error: 422 with the diagnostics, located on its block.
    let mut broken = doc.clone();
    let t = broken["elements"].as_array_mut().unwrap().iter_mut().find(|e| e["name"] == "TStart").unwrap();
    t["condition"] = json!("StartButon AND CarPresent");
    let tid = t["id"].clone();
    let a = post(&s, "/api/sim/start", &json!({ "doc": broken })).await;
    assert_eq!(a.status, 422, "{}", a.text);
    assert_eq!(a.body["error"], "the chart `CarWash` has errors");
    let d = a.body["diagnostics"].as_array().unwrap();
    assert!(
        d.iter().any(|d| d["severity"] == "error"
            && d["message"].as_str().unwrap().contains("StartButon")
            && d["elementIds"].as_array().unwrap().contains(&tid)),
        "{}",
        a.text
    );
    // At most four at once; stopping one makes room.
    let mut ids = Vec::new();
    for _ in 0..4 {
        let a = post(&s, "/api/sim/start", &json!({ "doc": doc, "halted": true })).await;
        assert_eq!(a.status, 200, "{}", a.text);
        ids.push(a.body["id"].as_u64().unwrap());
    }
    let a = post(&s, "/api/sim/start", &json!({ "doc": doc })).await;
    assert_eq!(
        (a.status.as_u16(), a.body["error"].clone()),
        (429, json!("4 simulations are running already: stop one first"))
    );
    assert_eq!(post(&s, "/api/sim/stop", &json!({ "id": ids[0] })).await.status, 200);
    let a = post(&s, "/api/sim/start", &json!({ "doc": doc })).await;
    assert_eq!(a.status, 200, "{}", a.text);
    assert!(!ids.contains(&a.body["id"].as_u64().unwrap()), "ids are not reused");
}

/// A simulation whose scan runs away stops at the scan budget: the monitor shows FAULT with the
/// step, the action and the line of the loop, and a stop ends the simulation (its thread is
/// not left spinning).
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_runaway_simulation_faults_at_its_loop_and_stops() {
    let dir = std::fs::canonicalize(Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures")).unwrap();
    let s = state(&[dir.as_path()], None);
    let a = post(&s, "/api/open", &json!({ "path": dir.join("runaway.st").to_str().unwrap() })).await;
    assert_eq!(a.status, 200, "{}", a.text);
    let doc = a.body["charts"][0].clone();
    let a = post(&s, "/api/sim/start", &json!({ "doc": doc, "period": "T#20ms" })).await;
    assert_eq!(a.status, 200, "{}", a.text);
    let url = a.body["url"].as_str().unwrap().to_string();
    let id = a.body["id"].as_u64().unwrap();
    let (mut ws, _) = tokio_tungstenite::connect_async(&url).await.expect("the monitor accepts the URL");
    let started = std::time::Instant::now();
    let state_msg = loop {
        let m = next(&mut ws).await.expect("a FAULT state before the monitor closes");
        if m["type"] == "state" && m["state"] == "FAULT" {
            break m;
        }
        if m["type"] == "hello" && m["state"] == "FAULT" {
            // The budget ran out before the client connected: the hello says so.
            break json!({"fault": m["fault"].clone()});
        }
    };
    println!("the runaway scan was stopped {:?} after the start", started.elapsed());
    let f = &state_msg["fault"];
    assert_eq!(
        (f["kind"].as_str(), f["step"].as_str(), f["action"].as_str()),
        (Some("error"), Some("Spin"), Some("Loop")),
        "{f}"
    );
    assert!(f["message"].as_str().unwrap().starts_with("runaway scan"), "{f}");
    // Written by the editor, the chart's FOR j is on some line of the generated text: the fault
    // names a line and a column.
    assert!(f["line"].as_u64().is_some() && f["column"].as_u64().is_some(), "{f}");
    let a = post(&s, "/api/sim/stop", &json!({ "id": id })).await;
    assert_eq!(a.status.as_u16(), 200, "{}", a.text);
    while next(&mut ws).await.is_some() {}
}

/// A chart opened from a TwinCAT export runs with profile codesys, and the answer says why; a
/// chart of an IEC text file (or without a file) with iec. The runtime's `hello` names it too.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn the_profile_comes_from_the_file() {
    let dir = std::fs::canonicalize(Path::new(env!("CARGO_MANIFEST_DIR")).join("../sfc-cli/tests/profile")).unwrap();
    let twincat = dir.join("final_scan.twincat.xml");
    let s = state(&[dir.as_path()], None);
    let a = post(&s, "/api/open", &json!({ "path": twincat.to_str().unwrap() })).await;
    assert_eq!(a.status, 200, "{}", a.text);
    let doc = a.body["charts"][0].clone();
    let a = post(&s, "/api/sim/start", &json!({ "doc": doc, "halted": true, "path": twincat.to_str().unwrap() })).await;
    assert_eq!(a.status, 200, "{}", a.text);
    assert_eq!(
        a.body["profile"],
        json!({"name": "codesys", "source": "vendor", "vendor": "TwinCAT", "file": "final_scan.twincat.xml"})
    );
    let (mut ws, _) = tokio_tungstenite::connect_async(a.body["url"].as_str().unwrap()).await.unwrap();
    assert_eq!(next(&mut ws).await.unwrap()["profile"], "codesys");
    let id = a.body["id"].clone();
    assert_eq!(post(&s, "/api/sim/stop", &json!({ "id": id })).await.status, 200);
    // The same chart without its file (a new tab): iec.
    let a = post(&s, "/api/sim/start", &json!({ "doc": doc, "halted": true })).await;
    assert_eq!(a.status, 200, "{}", a.text);
    assert_eq!(a.body["profile"], json!({"name": "iec", "source": "default"}));
    let id = a.body["id"].clone();
    assert_eq!(post(&s, "/api/sim/stop", &json!({ "id": id })).await.status, 200);
    // A file the editor may not read is refused, as opening it would be.
    let a = post(&s, "/api/sim/start", &json!({ "doc": doc, "path": "/etc/passwd" })).await;
    assert_eq!(a.status, 403, "{}", a.text);
}

/// A chart that instantiates function blocks of its file (crates/sfc-cli/tests/nested: Main runs
/// the lift, whose action charts run the gripper's) is simulated in its file when the page names
/// it; alone, its document does not know those blocks (422).
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_chart_runs_with_the_blocks_of_its_file() {
    let dir = std::fs::canonicalize(Path::new(env!("CARGO_MANIFEST_DIR")).join("../sfc-cli/tests/nested")).unwrap();
    let file = dir.join("machine.st");
    let s = state(&[dir.as_path()], None);
    let a = post(&s, "/api/open", &json!({ "path": file.to_str().unwrap() })).await;
    assert_eq!(a.status, 200, "{}", a.text);
    let main = a.body["charts"].as_array().unwrap().iter().find(|c| c["pou"] == "Main").cloned().unwrap();
    let a = post(&s, "/api/sim/start", &json!({ "doc": main, "halted": true })).await;
    assert_eq!(a.status, 422, "{}", a.text);
    let a = post(&s, "/api/sim/start", &json!({ "doc": main, "halted": true, "path": file.to_str().unwrap() })).await;
    assert_eq!(a.status, 200, "{}", a.text);
    assert_eq!(a.body["profile"]["name"], "iec");
    let (mut ws, _) = tokio_tungstenite::connect_async(a.body["url"].as_str().unwrap()).await.unwrap();
    let hello = next(&mut ws).await.unwrap();
    let steps: Vec<&str> = hello["steps"].as_array().unwrap().iter().map(|s| s["name"].as_str().unwrap()).collect();
    assert!(steps.contains(&"Lift.Grip.ACT_Grip.Holding"), "{steps:?}");
    let id = a.body["id"].clone();
    assert_eq!(post(&s, "/api/sim/stop", &json!({ "id": id })).await.status, 200);
}
