//! The monitor protocol against the car wash running in `sfc run` (docs/monitor.md).
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::indexing_slicing)] // test code: a panic is a failed test

mod common;

use common::{active, carwash, Client, TOKEN};
use serde_json::json;
use sfc_runtime::{Limits, RunOptions, Runtime};
use sfc_sim::{SimOptions, Simulation};

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn hello_then_snapshot_describe_the_chart() {
    let rt = carwash(10_000, false);
    let mut c = Client::connect(rt.monitor_addr().unwrap(), None).await;
    let hello = c.next(5.0).await.unwrap();
    assert_eq!(hello["type"], "hello");
    assert_eq!(hello["protocol"], "sfc-monitor");
    assert_eq!(hello["version"], 1);
    assert_eq!(hello["pou"], "CarWash");
    assert_eq!(hello["period"], "T#10ms");
    assert_eq!(hello["authorized"], false);
    assert!(hello["steps"].as_array().unwrap().contains(&json!({"name": "Idle", "initial": true})));
    assert!(hello["transitions"]
        .as_array()
        .unwrap()
        .contains(&json!({"name": "TStart", "from": ["Idle"], "to": ["Spraying"]})));
    let vars = hello["variables"].as_array().unwrap();
    assert!(vars.contains(&json!({"name": "StartButton", "type": "BOOL", "location": "%IX0.0"})), "{vars:?}");
    assert!(vars.contains(&json!({"name": "Washes", "type": "UDINT"})), "{vars:?}");
    let snap = c.until_type("snapshot").await;
    assert_eq!(active(&snap), vec!["Idle"]);
    assert_eq!(snap["guards"]["TStart"], false);
    assert_eq!(snap["guards"]["TGoHome"], false);
    assert_eq!(snap["vars"]["MaxTravelTime"], "T#1m");
    // Deltas follow, with the elapsed time of Idle growing.
    let d1 = c.until_type("delta").await;
    let d2 = c.until("a later delta", |m| m["type"] == "delta" && m["scan"].as_u64() > d1["scan"].as_u64()).await;
    assert!(d2["active"][0]["elapsedUs"].as_i64() > d1["active"][0]["elapsedUs"].as_i64());
    drop(c);
    rt.stop();
    assert_eq!(rt.wait().error, None);
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn breakpoints_halt_step_and_continue() {
    let rt = carwash(10_000, false);
    let mut c = Client::connect(rt.monitor_addr().unwrap(), Some(TOKEN)).await;
    assert_eq!(c.until_type("hello").await["authorized"], true);
    let r = c.cmd(json!({"cmd": "breakpoint", "op": "set", "kind": "step", "name": "Spraying"})).await;
    assert_eq!(r["ok"], true, "{r}");
    assert_eq!(r["result"], json!([{"kind": "step", "name": "Spraying", "enabled": true}]));
    let r = c.cmd(json!({"cmd": "breakpoint", "op": "set", "kind": "transition", "name": "TCarAtBrush"})).await;
    assert_eq!(r["result"].as_array().unwrap().len(), 2);
    let r = c.cmd(json!({"cmd": "breakpoint", "op": "set", "kind": "step", "name": "Nowhere"})).await;
    assert_eq!((r["ok"].clone(), r["error"].clone()), (json!(false), json!("no step `Nowhere`")));
    for (n, v) in [("CarPresent", true), ("AtHome", true), ("StartButton", true)] {
        let r = c.cmd(json!({"cmd": "set", "name": n, "value": v})).await;
        assert_eq!(r["ok"], true, "{r}");
    }
    let hit = c.until("breakpoint event", |m| m["type"] == "event" && m["kind"] == "breakpoint").await;
    assert_eq!(hit["step"], "Spraying");
    let halted = c.until_type("halted").await;
    assert_eq!(halted["reason"], "breakpoint");
    // Halted: the scan number stands still.
    let h1 = c.cmd(json!({"cmd": "history", "count": 1})).await;
    tokio::time::sleep(std::time::Duration::from_millis(200)).await;
    let h2 = c.cmd(json!({"cmd": "history", "count": 1})).await;
    let scan = h1["states"][0]["scan"].as_u64().unwrap();
    assert_eq!(h2["states"][0]["scan"].as_u64(), Some(scan));
    assert_eq!(active(&h1["states"][0]), vec!["Spraying"]);
    // One scan at a time.
    let r = c.cmd(json!({"cmd": "step"})).await;
    assert_eq!(r["result"]["scan"].as_u64(), Some(scan + 1), "{r} {h1} {h2} {:?}", c.seen);
    let h3 = c.cmd(json!({"cmd": "history", "count": 1})).await;
    assert_eq!(h3["states"][0]["scan"].as_u64(), Some(scan + 1));
    // The transition breakpoint: it fires during a single step, and the step reports it.
    c.cmd(json!({"cmd": "set", "name": "CarAtBrush", "value": true})).await;
    c.cmd(json!({"cmd": "step"})).await;
    let hit = c.until("transition breakpoint", |m| m["type"] == "event" && m["kind"] == "breakpoint").await;
    assert_eq!(hit["transition"], "TCarAtBrush");
    let r = c.cmd(json!({"cmd": "continue"})).await;
    assert_eq!(r["ok"], true);
    c.until_type("resumed").await;
    let d = c.until("scanning again", |m| m["type"] == "delta" && m["scan"].as_u64() > Some(scan + 2)).await;
    assert_eq!(active(&d), vec!["Brushing"]);
    // step is refused while running; disable, enable, delete, deleteAll.
    let r = c.cmd(json!({"cmd": "step"})).await;
    assert_eq!(r["ok"], false);
    let r = c.cmd(json!({"cmd": "breakpoint", "op": "disable", "kind": "step", "name": "Spraying"})).await;
    assert!(r["result"].as_array().unwrap().contains(&json!({"kind": "step", "name": "Spraying", "enabled": false})));
    let r = c.cmd(json!({"cmd": "breakpoint", "op": "delete", "kind": "transition", "name": "TCarAtBrush"})).await;
    assert_eq!(r["result"].as_array().unwrap().len(), 1);
    let r = c.cmd(json!({"cmd": "breakpoint", "op": "deleteAll"})).await;
    assert_eq!(r["result"], json!([]));
    rt.stop();
    assert_eq!(rt.wait().error, None);
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn forcing_needs_the_token() {
    let rt = carwash(10_000, false);
    let addr = rt.monitor_addr().unwrap();
    let mut anon = Client::connect(addr, None).await;
    anon.until_type("hello").await;
    let r = anon.cmd(json!({"cmd": "force", "name": "Washes", "value": 7})).await;
    assert_eq!((r["ok"].clone(), r["error"].clone()), (json!(false), json!("`force` needs the run's token")));
    let r = anon.cmd(json!({"cmd": "set", "name": "StartButton", "value": true})).await;
    assert_eq!(r["error"], "`set` needs the run's token");
    let r = anon.cmd(json!({"cmd": "force", "name": "Washes", "value": 7, "token": "guess"})).await;
    assert_eq!(r["error"], "wrong token");
    // After a wrong token the client waits 100 ms before it may try another, right or wrong.
    let r = anon.cmd(json!({"cmd": "force", "name": "Washes", "value": 7, "token": TOKEN})).await;
    assert!(r["error"].as_str().unwrap().starts_with("too many wrong tokens from 127.0.0.1: try again in"), "{r}");
    tokio::time::sleep(std::time::Duration::from_millis(150)).await;
    // The token in a command authorises the connection from then on.
    let r = anon.cmd(json!({"cmd": "force", "name": "Washes", "value": 7, "token": TOKEN})).await;
    assert_eq!(r["ok"], true, "{r}");
    let r = anon.cmd(json!({"cmd": "force", "name": "Washes", "value": -1})).await;
    assert_eq!(r["ok"], false);
    assert!(r["error"].as_str().unwrap().contains("out of range"), "{r}");
    let r = anon.cmd(json!({"cmd": "force", "name": "Nothing", "value": 1})).await;
    assert_eq!(r["error"], "no variable `Nothing`");
    // The change comes in a delta, or in the connection's first snapshot when the scan applied
    // the force before the session sent it (a loaded machine).
    let d = anon
        .until("forced value", |m| {
            (m["type"] == "delta" || m["type"] == "snapshot") && m["forced"] == json!(["Washes"])
        })
        .await;
    assert!(d.get("forced").is_some());
    let h = anon.cmd(json!({"cmd": "history", "count": 1})).await;
    assert_eq!(h["states"][0]["vars"]["Washes"], 7);
    let r = anon.cmd(json!({"cmd": "unforce", "name": "Washes"})).await;
    assert_eq!(r["ok"], true);
    anon.until("unforced", |m| m["type"] == "delta" && m["forced"] == json!([])).await;
    rt.stop();
    rt.wait();
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn history_holds_the_last_100_states_and_pause_keeps_buffering() {
    let rt = carwash(2_000, false);
    let mut c = Client::connect(rt.monitor_addr().unwrap(), None).await;
    c.until_type("snapshot").await;
    let r = c.cmd(json!({"cmd": "pause"})).await;
    assert_eq!(r["result"]["paused"], true);
    let h1 = c.cmd(json!({"cmd": "history", "count": 1})).await;
    // While paused nothing but replies arrives.
    let t0 = tokio::time::Instant::now();
    while t0.elapsed() < std::time::Duration::from_millis(400) {
        if let Some(m) = c.next(0.05).await {
            panic!("paused, yet received {m}");
        }
    }
    let h = c.cmd(json!({"cmd": "history"})).await;
    let states = h["states"].as_array().unwrap();
    assert_eq!(states.len(), 100, "400 ms at 2 ms fill the history");
    let scans: Vec<u64> = states.iter().map(|s| s["scan"].as_u64().unwrap()).collect();
    assert!(scans.windows(2).all(|w| w[0] < w[1]), "{scans:?}");
    assert!(scans[0] > h1["states"][0]["scan"].as_u64().unwrap(), "the runtime kept buffering while paused");
    assert!(states[0]["vars"].get("StartButton").is_some());
    let r = c.cmd(json!({"cmd": "resume"})).await;
    assert_eq!(r["ok"], true);
    let snap = c.until_type("snapshot").await;
    assert!(snap["scan"].as_u64() >= Some(*scans.last().unwrap()));
    let bad = c.cmd(json!({"cmd": "history", "count": "all"})).await;
    assert_eq!(bad["ok"], false);
    rt.stop();
    rt.wait();
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_halted_start_waits_for_continue() {
    let rt = carwash(10_000, true);
    let mut anon = Client::connect(rt.monitor_addr().unwrap(), None).await;
    assert_eq!(anon.until_type("hello").await["halted"], true);
    for cmd in ["step", "continue", "halt"] {
        let r = anon.cmd(json!({"cmd": cmd})).await;
        assert_eq!(r["error"], format!("`{cmd}` needs the run's token"));
    }
    let r = anon.cmd(json!({"cmd": "breakpoint", "op": "set", "name": "Idle"})).await;
    assert_eq!(r["error"], "`breakpoint` needs the run's token");
    let mut c = Client::connect(rt.monitor_addr().unwrap(), Some(TOKEN)).await;
    assert_eq!(c.until_type("hello").await["authorized"], true);
    let r = c.cmd(json!({"cmd": "step"})).await;
    assert_eq!(r["result"]["scan"], 0);
    let s = c.until("scan 0", |m| (m["type"] == "snapshot" || m["type"] == "delta") && m["scan"] == 0).await;
    assert_eq!(active(&s), vec!["Idle"]);
    c.cmd(json!({"cmd": "continue"})).await;
    c.until_type("resumed").await;
    c.until("scanning", |m| m["type"] == "delta" && m["scan"].as_u64() > Some(3)).await;
    rt.stop();
    rt.wait();
}

/// `explain` and `timing` are for watchers too; the expected analysis of the halted car wash
/// is `fixtures/carwash_idle.explain.json` (Idle with a car present at home, before Start).
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn explain_and_timing_answer_watchers() {
    let rt = carwash(10_000, true);
    let addr = rt.monitor_addr().unwrap();
    let mut ctl = Client::connect(addr, Some(TOKEN)).await;
    ctl.until_type("hello").await;
    let mut watcher = Client::connect(addr, None).await;
    assert_eq!(watcher.until_type("hello").await["authorized"], false);
    for (n, v) in [("CarPresent", true), ("AtHome", true)] {
        assert_eq!(ctl.cmd(json!({"cmd": "set", "name": n, "value": v})).await["ok"], true);
    }
    for _ in 0..3 {
        assert_eq!(ctl.cmd(json!({"cmd": "step"})).await["ok"], true);
    }
    let r = watcher.cmd(json!({"cmd": "explain", "step": "idle"})).await;
    assert_eq!(r["ok"], true, "{r}");
    let mut got = r["result"].clone();
    assert_eq!(got["scan"], 2);
    assert_eq!(got["elapsedUs"], 20_000);
    got.as_object_mut().unwrap().remove("scan");
    let path = common::root().join("crates/sfc-runtime/tests/fixtures/carwash_idle.explain.json");
    let want: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&path).unwrap()).unwrap();
    assert_eq!(got, want, "{}", serde_json::to_string_pretty(&got).unwrap());
    // A step that is not active is not stuck; an unknown one is a bad command.
    let r = watcher.cmd(json!({"cmd": "explain", "step": "Brushing"})).await;
    assert_eq!(r["error"], "step `Brushing` is not active: only an active step can be stuck");
    let r = watcher.cmd(json!({"cmd": "explain", "step": "Nowhere"})).await;
    assert_eq!(r["error"], "no step `Nowhere`");
    let r = watcher.cmd(json!({"cmd": "explain"})).await;
    assert_eq!(r["error"], "`explain` needs `step`");

    // Start, then the time analysis: Idle was active for 3 scans once, Spraying is active now.
    ctl.cmd(json!({"cmd": "set", "name": "StartButton", "value": true})).await;
    ctl.cmd(json!({"cmd": "step"})).await;
    ctl.cmd(json!({"cmd": "step"})).await;
    let r = watcher.cmd(json!({"cmd": "timing"})).await;
    assert_eq!(r["ok"], true, "{r}");
    let steps = r["result"]["steps"].as_array().unwrap();
    let of = |n: &str| steps.iter().find(|s| s["step"] == n).unwrap_or_else(|| panic!("no {n} in {r}")).clone();
    assert_eq!(of("Idle")["activations"], 1, "{r}");
    assert_eq!(of("Idle")["maxUs"], 30_000, "{r}");
    assert_eq!(of("Idle")["max"], "T#30ms", "{r}");
    assert_eq!(of("Spraying")["activations"], 1, "{r}");
    assert_eq!(of("Spraying")["meanUs"], 10_000, "{r}");
    assert_eq!(of("Brushing")["activations"], 0, "{r}");
    assert_eq!(of("Brushing")["min"], serde_json::Value::Null, "{r}");
    rt.stop();
    assert_eq!(rt.wait().error, None);
}

/// A top chart whose two tokens move every scan (one through a simultaneous divergence), and a
/// function block's chart that is called only while `A` is active and waits on its own step
/// time: the runtime publishes most states as changes (fired transitions), and the monitor's
/// `history` shows them in full. Each state it shows is the one a simulation of the same chart
/// reaches at that scan.
const MOVING: &str = "FUNCTION_BLOCK Blink
    INITIAL_STEP Off: END_STEP
    STEP On: END_STEP
    TRANSITION FROM Off TO On := Off.T >= T#6ms; END_TRANSITION
    TRANSITION FROM On TO Off := On.T >= T#4ms; END_TRANSITION
END_FUNCTION_BLOCK
PROGRAM Moving
    VAR
        Fb : Blink;
    END_VAR
    INITIAL_STEP A: Call(N); END_STEP
    ACTION Call: Fb(); END_ACTION
    STEP B: END_STEP
    STEP C: END_STEP
    STEP D: END_STEP
    TRANSITION FROM A TO (B, C) := TRUE; END_TRANSITION
    TRANSITION FROM (B, C) TO D := TRUE; END_TRANSITION
    TRANSITION FROM D TO A := TRUE; END_TRANSITION
    INITIAL_STEP Y: END_STEP
    STEP Z: END_STEP
    TRANSITION FROM Y TO Z := TRUE; END_TRANSITION
    TRANSITION FROM Z TO Y := TRUE; END_TRANSITION
END_PROGRAM
";

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn history_of_a_moving_chart_is_the_simulation_s() {
    let opts = SimOptions { period: 1_000, ..Default::default() };
    let sim = Simulation::from_source("moving.st", MOVING, None, opts).unwrap_or_else(|(_, d)| panic!("{d:?}"));
    // Started halted, so the client sees every overrun: on a loaded machine a scan can end
    // after the next deadline, the periods passed are skipped and scan numbers leave a gap
    // (docs/runtime.md, "Overruns"). The simulation below skips the same periods.
    let rt = Runtime::start(
        sim,
        RunOptions {
            monitor: Some("127.0.0.1:0".parse().unwrap()),
            token: Some(TOKEN.into()),
            limits: Limits { scans: Some(300), ..Default::default() },
            halted: true,
            ..Default::default()
        },
    )
    .unwrap();
    let mut c = Client::connect(rt.monitor_addr().unwrap(), Some(TOKEN)).await;
    let hello = c.until_type("hello").await;
    let names: Vec<String> =
        hello["steps"].as_array().unwrap().iter().map(|s| s["name"].as_str().unwrap().to_string()).collect();
    c.cmd(json!({"cmd": "continue"})).await;
    // The run ends after 300 scans and keeps its history for the clients still connected.
    c.until("the end of the run", |m| m["type"] == "state" && m["state"] == "STOP").await;
    let h = c.cmd(json!({"cmd": "history"})).await;
    let mut states = h["states"].as_array().unwrap().clone();
    assert_eq!(states.len(), 100);
    // The snapshot and the deltas sent while it ran show their scans in full too.
    let live: Vec<serde_json::Value> =
        c.seen.iter().filter(|m| m["type"] == "snapshot" || m["type"] == "delta").cloned().collect();
    assert!(live.len() >= 3, "{} states sent while running", live.len());
    states.extend(live);
    let skipped: std::collections::BTreeMap<u64, u64> = c
        .seen
        .iter()
        .filter(|m| m["type"] == "event" && m["kind"] == "overrun")
        .map(|m| (m["scan"].as_u64().unwrap(), m["skipped"].as_u64().unwrap()))
        .collect();
    // The same chart, simulated on the same grid.
    let mut sim = Simulation::from_source("moving.st", MOVING, None, opts).unwrap();
    let mut expected = std::collections::BTreeMap::new();
    let mut at = Vec::new();
    let mut scan = 0u64;
    for _ in 0..300 {
        sim.skip_to(scan);
        sim.advance().unwrap();
        sim.active_times(&mut at);
        let mut shown: Vec<(String, i64)> = at.iter().map(|&(s, t)| (names[s as usize].clone(), t)).collect();
        shown.sort();
        expected.insert(scan, shown);
        scan += 1 + skipped.get(&scan).copied().unwrap_or(0);
    }
    let mut fb_moved = false;
    for st in states {
        let scan = st["scan"].as_u64().unwrap();
        let mut got: Vec<(String, i64)> = st["active"]
            .as_array()
            .unwrap()
            .iter()
            .map(|a| (a["step"].as_str().unwrap().to_string(), a["elapsedUs"].as_i64().unwrap()))
            .collect();
        got.sort();
        let want = expected.get(&scan).unwrap_or_else(|| panic!("scan {scan} is not on the grid the run followed"));
        assert_eq!(&got, want, "scan {scan} ({} periods skipped in the run)", skipped.values().sum::<u64>());
        fb_moved |= got.iter().any(|(s, _)| s.ends_with("On"));
    }
    assert!(fb_moved, "the function block's chart moved within the history");
    rt.stop();
    rt.wait();
}
