//! Stopping a run whose scan runs away (what the editor's *Stop simulation* does): the scan is
//! interrupted and the scan thread ends, instead of being left spinning on a core.

use sfc_runtime::board::RunState;
use sfc_runtime::{RunOptions, Runtime};
use sfc_sim::{SimOptions, Simulation};
use std::time::{Duration, Instant};

const RUNAWAY: &str = "PROGRAM Spin
VAR i : DINT; j : DINT; n : LINT; END_VAR
INITIAL_STEP S:
    Loop(N);
END_STEP
ACTION Loop:
    FOR i := 1 TO 1000000 DO
        FOR j := 1 TO 1000000 DO
            n := n + 1;
        END_FOR;
    END_FOR;
END_ACTION
END_PROGRAM
";

#[test]
fn a_stopped_run_ends_even_while_its_scan_runs_away() {
    let mut sim = Simulation::from_source("spin.st", RUNAWAY, None, SimOptions::default()).unwrap();
    // Without a watchdog and with no budget to speak of, only the stop can end this scan.
    sim.set_scan_budget(u64::MAX);
    let rt = Runtime::start(sim, RunOptions { monitor: Some("127.0.0.1:0".parse().unwrap()), ..Default::default() })
        .unwrap();
    std::thread::sleep(Duration::from_millis(300));
    assert!(!rt.is_finished(), "the first scan is still running");
    let asked = Instant::now();
    rt.stop();
    let mut waited = Duration::ZERO;
    while !rt.is_finished() {
        assert!(waited < Duration::from_secs(20), "the scan thread did not end");
        std::thread::sleep(Duration::from_millis(5));
        waited += Duration::from_millis(5);
    }
    println!("the scan thread ended {:?} after the stop", asked.elapsed());
    let report = rt.wait();
    assert_eq!(report.state, RunState::Stop, "a stop is not a fault: {:?}", report.error);
    assert_eq!(report.error, None);
}
