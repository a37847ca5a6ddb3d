//! What a runtime needs from the simulator. The scan budget: every loop iteration, IL jump and
//! call is charged to the scan, nested loops together, so a runaway scan ends with a located
//! error; an interrupt flag set from another thread stops a scan that is still running;
//! `fault_place` names the action and steps; `restart` starts again from the initial values;
//! `retained` lists the RETAIN/PERSISTENT leaves.

use sfc_sim::code::{INTERRUPTED, SCAN_BUDGET};
use sfc_sim::{SimOptions, Simulation, Value};
use std::sync::atomic::Ordering;
use std::time::{Duration, Instant};

/// A chart whose step `Fill` runs action `Count`, a FOR loop of 10^6 × 10^6 iterations when
/// `Go` is TRUE.
const NESTED: &str = "PROGRAM Runaway
VAR Go : BOOL; i : DINT; j : DINT; n : LINT; END_VAR
INITIAL_STEP Idle: END_STEP
TRANSITION FROM Idle TO Fill := Go; END_TRANSITION
STEP Fill:
    Count(N);
END_STEP
TRANSITION FROM Fill TO Idle := FALSE; END_TRANSITION
ACTION Count:
    FOR i := 1 TO 1000000 DO
        FOR j := 1 TO 1000000 DO
            n := n + 1;
        END_FOR;
    END_FOR;
END_ACTION
END_PROGRAM
";

fn sim(text: &str) -> Simulation {
    Simulation::from_source("runaway.st", text, None, SimOptions::default()).unwrap_or_else(|(_, d)| panic!("{d:?}"))
}

#[test]
fn nested_loops_share_one_budget() {
    let mut s = sim(NESTED);
    s.scan();
    s.set("Go", Value::Bool(true)).unwrap();
    let started = Instant::now();
    s.scan(); // Idle -> Fill, and Count runs: one budget for both loops
    let e = s.error().expect("a runaway scan is an error").clone();
    eprintln!("budget of {SCAN_BUDGET} spent in {:?}", started.elapsed());
    assert!(e.message.starts_with("runaway scan: more than 10000000"), "{}", e.message);
    // The inner FOR, where the last charge was made.
    assert_eq!((e.line, e.column), (11, 9), "{e:?}");
    assert_eq!(s.get("n"), Some(Value::Int(10_000_000 - 10)), "each outer iteration is charged too");
    let place = s.fault_place().expect("the fault is in an action");
    assert_eq!(place.action.as_deref(), Some("Count"));
    assert_eq!(place.steps, vec!["Fill".to_string()]);
    // A restart clears the error and starts from the initial values, at a later scan.
    let next = s.next_scan();
    s.restart();
    assert!(s.error().is_none());
    assert_eq!(s.get("n"), Some(Value::Int(0)));
    assert_eq!(s.next_scan(), next);
    let rec = s.scan().clone();
    assert_eq!(rec.active, vec!["Idle".to_string()]);
}

#[test]
fn a_smaller_budget_stops_sooner() {
    let mut s = sim(NESTED);
    s.set_scan_budget(1000);
    s.scan();
    s.set("Go", Value::Bool(true)).unwrap();
    s.scan();
    let e = s.error().expect("runaway").clone();
    assert!(e.message.contains("more than 1000 loop iterations"), "{}", e.message);
    assert_eq!(s.get("n"), Some(Value::Int(1000 - 1)));
}

#[test]
fn an_interrupt_stops_a_running_scan() {
    let mut s = sim(NESTED);
    s.set_scan_budget(u64::MAX);
    let flag = s.interrupt_flag();
    s.scan();
    s.set("Go", Value::Bool(true)).unwrap();
    // Idle -> Fill, whose action runs in the same scan.
    let setter = std::thread::spawn(move || {
        std::thread::sleep(Duration::from_millis(100));
        let at = Instant::now();
        flag.store(true, Ordering::Relaxed);
        at
    });
    s.scan();
    let stopped = Instant::now();
    let set_at = setter.join().unwrap();
    let e = s.error().expect("interrupted").clone();
    assert_eq!(e.message, INTERRUPTED);
    assert_eq!(e.line, 11);
    eprintln!("the scan stopped {:?} after the flag was set", stopped.saturating_duration_since(set_at));
    assert!(stopped.saturating_duration_since(set_at) < Duration::from_secs(5));
}

#[test]
fn recursion_and_while_loops_are_charged() {
    // A WHILE loop calling a function that loops: the calls and both loops are charged.
    let text = "FUNCTION Inc : DINT
VAR_INPUT x : DINT; END_VAR
VAR k : DINT; END_VAR
k := 0;
WHILE k < 3 DO k := k + 1; END_WHILE;
Inc := x + 1;
END_FUNCTION
PROGRAM P
VAR n : DINT; END_VAR
WHILE TRUE DO
    n := Inc(n);
END_WHILE;
END_PROGRAM
";
    let mut s = Simulation::from_source("p.st", text, Some("P"), SimOptions::default()).unwrap();
    s.set_scan_budget(5000);
    s.scan();
    let e = s.error().expect("runaway").clone();
    assert!(e.message.starts_with("runaway scan"), "{}", e.message);
    // 5 charges per outer iteration (the loop, the call, three inner iterations).
    assert_eq!(s.get("n"), Some(Value::Int(1000)));
}

#[test]
fn retentive_values_are_listed_as_leaves() {
    let text = "TYPE Recipe : STRUCT Speed : INT; Time : TIME; END_STRUCT; END_TYPE
FUNCTION_BLOCK Pump
VAR RETAIN Hours : UDINT; END_VAR
VAR PERSISTENT Starts : UDINT; END_VAR
VAR Running : BOOL; END_VAR
Running := NOT Running;
END_FUNCTION_BLOCK
VAR_GLOBAL RETAIN Total : LREAL; END_VAR
PROGRAM P
VAR_EXTERNAL Total : LREAL; END_VAR
VAR RETAIN Counts : ARRAY[1..2] OF DINT; R : Recipe; Timer : TON; END_VAR
VAR PERSISTENT Serial : STRING[8]; END_VAR
VAR P1 : Pump; Scratch : INT; END_VAR
P1();
Total := Total + 1.0;
END_PROGRAM
";
    let s = Simulation::from_source("p.st", text, Some("P"), SimOptions::default())
        .unwrap_or_else(|(_, d)| panic!("{d:?}"));
    let list: Vec<(String, String, bool)> =
        s.retained().iter().map(|r| (r.name.clone(), r.ty.to_string(), r.persistent)).collect();
    let want = [
        ("Counts[1]", "DINT", false),
        ("Counts[2]", "DINT", false),
        ("R.Speed", "INT", false),
        ("R.Time", "TIME", false),
        ("Timer.IN", "BOOL", false),
        ("Timer.PT", "TIME", false),
        ("Timer.Q", "BOOL", false),
        ("Timer.ET", "TIME", false),
        ("Serial", "STRING[8]", true),
        ("P1.Hours", "UDINT", false),
        ("P1.Starts", "UDINT", true),
        ("Total", "LREAL", false),
    ];
    let want: Vec<(String, String, bool)> = want.iter().map(|(n, t, p)| (n.to_string(), t.to_string(), *p)).collect();
    assert_eq!(list, want);
    // Each leaf's slot is the one the simulator resolves for its name.
    for r in s.retained() {
        assert_eq!(s.handle(&r.name).map(|h| h.0), Some(r.slot), "{}", r.name);
    }
}

/// A program with a chart of its own and an SFC function block instance (a mechanism).
const MECHANISM: &str = "FUNCTION_BLOCK Mover
VAR_INPUT Go : BOOL; END_VAR
VAR_OUTPUT Busy : BOOL; n : INT; END_VAR
INITIAL_STEP Rest: END_STEP
TRANSITION TGo FROM Rest TO Move := Go; END_TRANSITION
STEP Move:
    Busy(N);
    Count(P1);
END_STEP
TRANSITION TBack FROM Move TO Rest := NOT Go; END_TRANSITION
ACTION Count:
    n := n + 1;
END_ACTION
END_FUNCTION_BLOCK
PROGRAM Line
VAR Start : BOOL; M : Mover; END_VAR
INITIAL_STEP Wait: END_STEP
TRANSITION TStart FROM Wait TO Run := Start; END_TRANSITION
STEP Run:
    Drive(N);
END_STEP
TRANSITION TStop FROM Run TO Wait := FALSE; END_TRANSITION
ACTION Drive:
    M(Go := TRUE);
END_ACTION
END_PROGRAM
";

/// `chart_outline` numbers each instance's steps, transitions and actions globally;
/// `action_states` gives Q and A of the action control (P1: A for one scan, Q never);
/// `step_times` keeps the T of a step left (IEC 61131-3) and 0 for one never active.
#[test]
fn chart_outline_action_states_and_step_times() {
    let opts = SimOptions { period: 100_000, ..SimOptions::default() };
    let mut s =
        Simulation::from_source("line.st", MECHANISM, Some("Line"), opts).unwrap_or_else(|(_, d)| panic!("{d:?}"));
    let charts = s.chart_outline();
    let shape: Vec<(&str, &str, &str, std::ops::Range<u32>, std::ops::Range<u32>, std::ops::Range<u32>)> = charts
        .iter()
        .map(|c| {
            (
                c.instance.as_str(),
                c.path.as_str(),
                c.pou.as_str(),
                c.steps.clone(),
                c.transitions.clone(),
                c.actions.clone(),
            )
        })
        .collect();
    assert_eq!(shape, vec![("Line", "", "Line", 0..2, 0..2, 0..1), ("M", "M", "Mover", 2..4, 2..4, 1..3)]);
    let actions = s.action_outline();
    let names: Vec<(&str, bool)> = actions.iter().map(|(n, v)| (n.as_str(), *v)).collect();
    assert_eq!(names, vec![("Drive", false), ("M.Count", false), ("M.Busy", true)], "action blocks, then variables");
    let (steps, _) = s.outline();
    let step = |n: &str| steps.iter().position(|s| s.0 == n).unwrap();
    let mut qa = Vec::new();
    let mut times = Vec::new();
    s.scan();
    s.set("Start", Value::Bool(true)).unwrap();
    s.scan(); // Wait -> Run: Drive calls M, whose chart starts in Rest
    s.scan(); // M: Rest -> Move
    s.action_states(&mut qa);
    qa.sort_unstable();
    assert_eq!(qa, vec![(0, true, true), (1, false, true), (2, true, true)], "Drive, M.Count (P1), M.Busy (N)");
    s.scan();
    s.action_states(&mut qa);
    qa.sort_unstable();
    assert_eq!(qa, vec![(0, true, true), (2, true, true)], "P1's A lasted one scan");
    s.step_times(&mut times);
    assert_eq!(times.len(), 4);
    assert_eq!(times[step("Wait")], 100_000, "Wait was active for one period and keeps it");
    assert_eq!(times[step("M.Move")], 100_000, "M.Move active since the last scan");
    s.scan();
    s.step_times(&mut times);
    assert_eq!(times[step("Wait")], 100_000, "still the duration of its last activation");
    assert_eq!(times[step("M.Move")], 200_000);
}
