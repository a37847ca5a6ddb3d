//! The messages a running chart sends read back into the types of `sfc_runtime::contract`
//! (which refuse unknown fields), from which the editor's TypeScript types are generated.

mod common;

use common::{carwash, Client};
use sfc_runtime::contract::{Delta, Hello, Snapshot};

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn messages_fit_the_contract_types() {
    let rt = carwash(10_000, false);
    let mut c = Client::connect(rt.monitor_addr().unwrap(), None).await;
    let hello = c.until_type("hello").await;
    let h: Hello = serde_json::from_value(hello.clone()).unwrap_or_else(|e| panic!("hello: {e}\n{hello:#}"));
    assert_eq!(h.pou, "CarWash");
    let snap = c.until_type("snapshot").await;
    let _: Snapshot = serde_json::from_value(snap.clone()).unwrap_or_else(|e| panic!("snapshot: {e}\n{snap:#}"));
    for _ in 0..3 {
        let d = c.until_type("delta").await;
        let _: Delta = serde_json::from_value(d.clone()).unwrap_or_else(|e| panic!("delta: {e}\n{d:#}"));
    }
    drop(c);
    rt.stop();
    let _ = rt.wait();
}

/// The first state a client sees is a full `snapshot` (with `halted`, `state`, `fault` and
/// `stats`) even when no scan had been recorded when it connected: a client faster than the
/// first scan once got a bare one. A runtime started halted has no state until `step`, so it
/// shows that case every time.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn the_first_snapshot_is_whole_however_early_the_client() {
    for halted in [true, false] {
        let rt = carwash(10_000, halted);
        let mut c = Client::connect(rt.monitor_addr().unwrap(), Some(common::TOKEN)).await;
        c.until_type("hello").await;
        if halted {
            assert_eq!(c.cmd(serde_json::json!({"cmd": "step"})).await["ok"], true);
        }
        let snap = c.until_type("snapshot").await;
        let s: Snapshot = serde_json::from_value(snap.clone()).unwrap_or_else(|e| panic!("snapshot: {e}\n{snap:#}"));
        assert_eq!(s.halted, halted, "{snap:#}");
        drop(c);
        rt.stop();
        let _ = rt.wait();
    }
}

/// A scan that runs away under the watchdog: the `state` message, the `hello` and the
/// `snapshot` in FAULT, with the fault, fit the types too.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn fault_messages_fit_the_contract_types() {
    use sfc_runtime::contract::{Fault, MonValue, RunState, StateMessage};
    use sfc_runtime::{Limits, RunOptions, Runtime};
    use sfc_sim::{SimOptions, Simulation};
    use std::time::Duration;
    // A few scans in Idle (so the late client gets a snapshot), then a scan that runs away.
    const RUNAWAY: &str = "PROGRAM Spin
VAR Motor AT %QX0.0 : BOOL; c : INT; i : DINT; j : DINT; n : LINT; END_VAR
INITIAL_STEP Idle:
    Count(N);
END_STEP
STEP Busy:
    Loop(N);
END_STEP
TRANSITION FROM Idle TO Busy := c >= 3; END_TRANSITION
TRANSITION FROM Busy TO Idle := FALSE; END_TRANSITION
ACTION Count:
    c := c + 1;
END_ACTION
ACTION Loop:
    Motor := TRUE;
    FOR i := 1 TO 1000000 DO
        FOR j := 1 TO 1000000 DO
            n := n + 1;
        END_FOR;
    END_FOR;
END_ACTION
END_PROGRAM
";
    let mut sim = Simulation::from_source("spin.st", RUNAWAY, None, SimOptions::default()).unwrap();
    sim.set_scan_budget(u64::MAX);
    let rt = Runtime::start(
        sim,
        RunOptions {
            monitor: Some("127.0.0.1:0".parse().unwrap()),
            token: Some(common::TOKEN.into()),
            // Generous: on a loaded machine an ordinary scan of Idle may take tens of
            // milliseconds, and that overrun would be the fault (without a running step).
            limits: Limits { watchdog: Some(Duration::from_millis(400)), ..Default::default() },
            wait_in_fault: true,
            ..Default::default()
        },
    )
    .unwrap();
    let addr = rt.monitor_addr().unwrap();
    let mut c = Client::connect(addr, None).await;
    let state = c.until("a FAULT state", |m| m["type"] == "state" && m["state"] == "FAULT").await;
    let s: StateMessage = serde_json::from_value(state.clone()).unwrap_or_else(|e| panic!("state: {e}\n{state:#}"));
    assert_eq!(s.state, RunState::Fault);
    let fault: Fault = s.fault.unwrap_or_else(|| panic!("a FAULT names its fault: {state:#}"));
    assert_eq!(fault.kind, "watchdog");
    assert_eq!(fault.step.as_deref(), Some("Busy"));
    assert_eq!(s.outputs.as_ref().and_then(|o| o.get("Motor")), Some(&MonValue::Bool(false)), "{state:#}");
    // A client that connects now learns the fault from the hello and the snapshot.
    let mut late = Client::connect(addr, None).await;
    let hello = late.until_type("hello").await;
    let h: Hello = serde_json::from_value(hello.clone()).unwrap_or_else(|e| panic!("hello: {e}\n{hello:#}"));
    assert_eq!(h.state, RunState::Fault);
    assert!(h.fault.is_some(), "{hello:#}");
    assert!(h.variables.iter().any(|v| v.name == "Motor" && v.safe.is_some()), "{hello:#}");
    let snap = late.until_type("snapshot").await;
    let sn: Snapshot = serde_json::from_value(snap.clone()).unwrap_or_else(|e| panic!("snapshot: {e}\n{snap:#}"));
    assert_eq!(sn.state, RunState::Fault);
    assert_eq!(sn.vars.get("Motor"), Some(&MonValue::Bool(false)), "the safe value: {snap:#}");
    drop((c, late));
    rt.stop();
    let _ = rt.wait();
}
