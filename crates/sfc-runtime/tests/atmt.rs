//! The ATMT adapter: a transition table (or its chart) and a stream of `state condition_bits`
//! lines served as the monitor protocol. Fixture: `fixtures/press.st`, its table
//! `press.atmt`, the line stream `press.lines` and what a client must see, `press.expected.json`.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::indexing_slicing)] // test code: a panic is a failed test

mod common;

use common::{active, Client, TOKEN};
use serde_json::{json, Value};
use sfc_runtime::{AtmtModel, LineSource, RunOptions, Runtime};
use std::io::Write;
use std::path::PathBuf;

fn fixture(name: &str) -> String {
    let p = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures").join(name);
    std::fs::read_to_string(p).unwrap()
}

#[test]
fn the_chart_names_the_table() {
    let chart = AtmtModel::from_chart("press.st", &fixture("press.st"), None).unwrap();
    let table = AtmtModel::from_table(&fixture("press.atmt")).unwrap();
    let rules = |m: &AtmtModel| m.rules.iter().map(|r| (r.state, r.condition, r.next)).collect::<Vec<_>>();
    assert_eq!(rules(&chart), rules(&table));
    assert_eq!(table.steps, vec!["S0", "S1", "S2", "S3", "S4", "S5"]);
    assert_eq!(table.rules.iter().map(|r| r.name.as_str()).collect::<Vec<_>>(), vec!["R0", "R1", "R2", "R3"]);
    let err = AtmtModel::from_table("2[0 1 1][0 0]").unwrap_err();
    assert!(err.contains("not a transition table"), "{err}");
    let err =
        AtmtModel::from_chart("bad.st", "PROGRAM P\nINITIAL_STEP A: END_STEP\nEND_PROGRAM X\n", None).unwrap_err();
    assert!(err.contains("bad.st:"), "{err}");
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_line_stream_is_served_as_the_monitor_protocol() {
    let expected: Value = serde_json::from_str(&fixture("press.expected.json")).unwrap();
    let model = AtmtModel::from_chart("press.st", &fixture("press.st"), None).unwrap();
    let lines = std::net::TcpListener::bind("127.0.0.1:0").unwrap();
    let line_addr = lines.local_addr().unwrap();
    let rt = Runtime::start_atmt(
        model,
        LineSource::Listen(lines),
        RunOptions { monitor: Some("127.0.0.1:0".parse().unwrap()), token: Some(TOKEN.into()), ..Default::default() },
    )
    .unwrap();
    let mut c = Client::connect(rt.monitor_addr().unwrap(), Some(TOKEN)).await;
    let hello = c.until_type("hello").await;
    assert_eq!(hello["runtime"], "atmt");
    assert_eq!(hello["control"], false);
    let names = |k: &str| hello[k].as_array().unwrap().iter().map(|s| s["name"].clone()).collect::<Vec<_>>();
    assert_eq!(json!(names("steps")), expected["steps"]);
    assert_eq!(json!(names("transitions")), expected["transitions"]);
    assert_eq!(hello["transitions"][0], json!({"name": "TStart", "from": ["Idle"], "to": ["Down"]}));
    let r = c.cmd(json!({"cmd": "breakpoint", "op": "set", "kind": "step", "name": "Down"})).await;
    assert_eq!(r["ok"], true, "{r}");
    let r = c.cmd(json!({"cmd": "breakpoint", "op": "set", "kind": "transition", "name": "TTop"})).await;
    assert_eq!(r["result"].as_array().unwrap().len(), 2);
    // The block cannot be halted or forced from here.
    let r = c.cmd(json!({"cmd": "halt"})).await;
    assert_eq!(r["error"], "this runtime (atmt) observes only: it cannot halt");
    let r = c.cmd(json!({"cmd": "force", "name": "c1", "value": true})).await;
    assert_eq!(r["error"], "this runtime (atmt) cannot force variables");
    // Nor can it explain a step or time the steps: it sees only states and condition bits.
    let r = c.cmd(json!({"cmd": "explain", "step": "Down"})).await;
    assert_eq!(r["ok"], false, "{r}");
    assert!(r["error"].as_str().unwrap().contains("cannot explain `Down`"), "{r}");
    let r = c.cmd(json!({"cmd": "timing"})).await;
    assert_eq!(r["ok"], false, "{r}");
    assert!(r["error"].as_str().unwrap().contains("keeps no time analysis"), "{r}");

    let text = fixture("press.lines");
    std::thread::spawn(move || {
        let mut s = std::net::TcpStream::connect(line_addr).unwrap();
        s.write_all(text.as_bytes()).unwrap();
    })
    .join()
    .unwrap();
    let want_events = expected["events"].as_array().unwrap().clone();
    let mut events = Vec::new();
    while events.len() < want_events.len() {
        let mut e = c.until("event", |m| m["type"] == "event").await;
        e.as_object_mut().unwrap().remove("type");
        events.push(e);
    }
    assert_eq!(events, want_events);
    let h = c.cmd(json!({"cmd": "history"})).await;
    let states = h["states"].as_array().unwrap();
    let seen: Vec<String> = states.iter().map(|s| active(s)[0].clone()).collect();
    assert_eq!(json!(seen), expected["active"]);
    let fired: Vec<Value> = states.iter().map(|s| s["fired"].clone()).collect();
    assert_eq!(json!(fired), expected["fired"]);
    // Guards of the rules leaving the current state, from this line's bits.
    assert_eq!(states[3]["guards"], json!({"TBottom": true, "TAbort": false}));
    assert_eq!(states[3]["vars"], json!({"state": 5, "c0": false, "c1": false, "c2": true, "c7": false}));
    // Elapsed time restarts on a change of state.
    let elapsed: Vec<i64> = states.iter().map(|s| s["active"][0]["elapsedUs"].as_i64().unwrap()).collect();
    for entry in [0, 2, 4, 6, 7] {
        assert_eq!(elapsed[entry], 0, "{elapsed:?}");
    }
    assert!(elapsed[3] >= elapsed[2] && elapsed[1] >= elapsed[0], "{elapsed:?}");
    rt.stop();
    assert_eq!(rt.wait().error, None);
}
