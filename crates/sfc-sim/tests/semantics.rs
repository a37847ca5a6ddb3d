//! The semantics suite. Every `tests/semantics/*.scenario.toml` is a small chart with the
//! scan-by-scan expectations that `semantics.md` implies, derived by hand (see the folder's
//! README.md for the rule each one checks). The Rust tests below check what a scenario cannot
//! express: events, the order of `fired`, and runtime errors.

use sfc_sim::scenario::run_path;
use sfc_sim::{Event, ScanRecord, SimOptions, Simulation, Value};
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::path::{Path, PathBuf};

fn folder() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/semantics")
}

fn files_ending(suffix: &str) -> Vec<PathBuf> {
    let mut files: Vec<PathBuf> = std::fs::read_dir(folder())
        .expect("tests/semantics exists")
        .map(|e| e.unwrap().path())
        .filter(|p| p.file_name().and_then(|n| n.to_str()).is_some_and(|n| n.ends_with(suffix)))
        .collect();
    files.sort();
    files
}

#[test]
fn scenarios() {
    let files = files_ending(".scenario.toml");
    assert!(!files.is_empty(), "no scenario in {}", folder().display());
    let mut report = Vec::new();
    let mut passed = 0;
    for path in &files {
        let name = path.file_name().unwrap().to_string_lossy().into_owned();
        match catch_unwind(AssertUnwindSafe(|| run_path(path))) {
            Ok(Ok(outcome)) if outcome.passed() => passed += 1,
            Ok(Ok(outcome)) => {
                report.push(format!("{name}:"));
                report.extend(outcome.failures.iter().map(|f| format!("    {f}")));
                if let Some(e) = &outcome.error {
                    report.push(format!("    stopped: {e}"));
                }
            }
            Ok(Err(e)) => report.push(format!("{name}: does not load: {e}")),
            Err(panic) => {
                let msg = panic
                    .downcast_ref::<String>()
                    .cloned()
                    .or_else(|| panic.downcast_ref::<&str>().map(|s| s.to_string()))
                    .unwrap_or_default();
                report.push(format!("{name}: panicked: {msg}"));
            }
        }
    }
    assert!(report.is_empty(), "{passed} passed, {} failed\n{}", files.len() - passed, report.join("\n"));
}

/// Tidy: every chart has its iec scenario and a line in README.md, and every scenario says
/// which rule it checks (a comment quoting semantics.md).
#[test]
fn every_fixture_is_documented() {
    let readme = std::fs::read_to_string(folder().join("README.md")).expect("tests/semantics/README.md");
    for chart in files_ending(".st") {
        let stem = chart.file_stem().unwrap().to_string_lossy().into_owned();
        assert!(folder().join(format!("{stem}.scenario.toml")).exists(), "{stem}.st has no {stem}.scenario.toml");
        assert!(readme.contains(&format!("{stem}.st")), "README.md does not list {stem}.st");
    }
    for scenario in files_ending(".scenario.toml") {
        let text = std::fs::read_to_string(&scenario).unwrap();
        assert!(text.starts_with('#'), "{} does not start with a comment naming its rule", scenario.display());
    }
}

// ---------------------------------------------------------------------------------------------
// Events, fired order and runtime errors

fn sim_of_text(name: &str, text: &str) -> Simulation {
    match Simulation::from_source(name, text, None, SimOptions::default()) {
        Ok(sim) => sim,
        Err((_, diags)) => panic!("{name} does not compile: {diags:#?}"),
    }
}

fn sim_of(fixture: &str) -> Simulation {
    let text = std::fs::read_to_string(folder().join(fixture)).unwrap();
    sim_of_text(fixture, &text)
}

/// Sets the given inputs and runs one scan.
fn scan(sim: &mut Simulation, set: &[(&str, bool)]) -> ScanRecord {
    for (name, v) in set {
        sim.set(name, Value::Bool(*v)).unwrap_or_else(|e| panic!("set {name}: {e}"));
    }
    sim.scan().clone()
}

fn strings(v: &[&str]) -> Vec<String> {
    v.iter().map(|s| s.to_string()).collect()
}

fn conflict(step: &str, transitions: &[&str]) -> Event {
    Event::Conflict { step: step.into(), transitions: strings(transitions) }
}

fn unsafe_(step: &str, transitions: &[&str]) -> Event {
    Event::Unsafe { step: step.into(), transitions: strings(transitions) }
}

/// Events in trace order (conflict, unsafe, contention, error), sorted inside one kind, which
/// the spec does not order.
fn sorted(mut events: Vec<Event>) -> Vec<Event> {
    events.sort_by(|a, b| a.rank().cmp(&b.rank()).then_with(|| format!("{a:?}").cmp(&format!("{b:?}"))));
    events
}

/// `(action, steps)` of a contention event, with the qualifiers reduced to their names.
fn contention_of(e: &Event) -> Option<(String, Vec<String>, Vec<String>)> {
    match e {
        Event::Contention { action, steps, qualifiers } => Some((
            action.clone(),
            steps.clone(),
            qualifiers
                .iter()
                .map(|q| q.split(|c: char| !c.is_ascii_alphanumeric()).next().unwrap_or("").to_ascii_uppercase())
                .collect(),
        )),
        _ => None,
    }
}

#[test]
fn scan0_fires_nothing() {
    // semantics.md, "Initialisation (scan 0)": "evaluates no transitions"
    let mut sim = sim_of("01_scan0_no_transitions.st");
    let r0 = scan(&mut sim, &[]);
    assert_eq!((r0.scan, r0.time), (0, 0));
    assert_eq!(r0.active, ["Init"]);
    assert!(r0.fired.is_empty() && r0.events.is_empty(), "{r0:?}");
    let r1 = scan(&mut sim, &[]);
    assert_eq!((r1.scan, r1.time), (1, 10_000));
    assert_eq!(r1.fired, ["TLeave"]);
}

#[test]
fn conflict_lists_the_true_alternatives_without_priority() {
    // semantics.md, step 4 and "conflict event": one per step, the transitions of E without
    // explicit priority that share it, in declaration order. TMiddle is FALSE: not listed.
    let mut sim = sim_of("07_conflict_declaration_order.st");
    scan(&mut sim, &[]);
    let r1 = scan(&mut sim, &[("Go", true)]);
    assert_eq!(r1.fired, ["TZulu"]);
    assert_eq!(r1.events, [conflict("Init", &["TZulu", "TAlpha"])]);
    let r2 = scan(&mut sim, &[]);
    assert!(r2.events.is_empty(), "{r2:?}");
}

#[test]
fn explicit_priorities_give_no_conflict() {
    // semantics.md: "Equal explicit priorities give no event."
    let mut sim = sim_of("08_priority_explicit.st");
    scan(&mut sim, &[]);
    let r1 = scan(&mut sim, &[("Go", true)]);
    assert_eq!(r1.fired, ["THigh", "TFirst"], "fired in declaration order");
    assert!(r1.events.is_empty(), "{:?}", r1.events);
}

#[test]
fn mixed_priorities() {
    // semantics.md: the conflict event lists the unprioritised TRUE transitions "even when a
    // prioritised transition takes the step"; none when only one is unprioritised.
    let mut sim = sim_of("09_priority_mixed.st");
    scan(&mut sim, &[]);
    let r1 = scan(&mut sim, &[("Go", true)]);
    assert_eq!(r1.fired, ["T1b", "T2b", "T3b"]);
    assert_eq!(sorted(r1.events), [conflict("Init1", &["T1a", "T1c"]), conflict("Init3", &["T3b", "T3c"])]);
}

#[test]
fn parallel_branches_fire_in_one_scan() {
    // semantics.md, step 4: "parallel sequences still evolve simultaneously"; fired in
    // declaration order; a convergence fires once its last branch has arrived.
    let mut sim = sim_of("10_simultaneous.st");
    let mut fired = Vec::new();
    for k in 0..7 {
        let r = scan(&mut sim, &[("Go", (1..6).contains(&k))]);
        assert!(r.events.is_empty(), "scan {k}: {:?}", r.events);
        fired.push(r.fired.join(","));
    }
    assert_eq!(fired, ["", "TSplit", "TA,TC", "", "TB", "TJoin", "TBack"]);
}

#[test]
fn self_loop_is_not_unsafe() {
    // semantics.md, step 5: a step in A n D "stays active ... A step left and re-entered is not
    // unsafe."
    let mut sim = sim_of("11_self_loop.st");
    let mut fired = Vec::new();
    for k in 0..11 {
        let r = scan(&mut sim, &[("Go", k >= 1), ("Stop", k >= 10)]);
        assert!(r.events.is_empty(), "scan {k}: {:?}", r.events);
        fired.push(r.fired.join(","));
    }
    assert_eq!(fired, ["", "TGo", "", "TLoop", "", "TLoop", "", "TLoop", "", "TLoop", "TEnd"]);
}

#[test]
fn unsafe_events() {
    // semantics.md, step 5: unsafe for a step in A n (X \ D), and for a step activated by two or
    // more accepted transitions of the same scan.
    let mut sim = sim_of("12_unsafe.st");
    scan(&mut sim, &[]);
    let r1 = scan(&mut sim, &[("Go", true)]);
    assert!(r1.events.is_empty(), "{r1:?}");
    let r2 = scan(&mut sim, &[]);
    assert_eq!(r2.fired, ["TLeft1", "TLeft2", "TRight2"]);
    assert_eq!(r2.events, [unsafe_("Meet2", &["TLeft2", "TRight2"])]);
    let r3 = scan(&mut sim, &[]);
    assert_eq!(r3.fired, ["TRight1"]);
    assert_eq!(r3.events, [unsafe_("Meet1", &["TRight1"])]);
    for k in 4..6 {
        let r = scan(&mut sim, &[]);
        assert!(r.events.is_empty(), "scan {k}: {r:?}");
    }
}

#[test]
fn left_and_reentered_is_not_unsafe() {
    let mut sim = sim_of("13_left_and_reentered.st");
    scan(&mut sim, &[]);
    scan(&mut sim, &[("Go", true)]);
    let r2 = scan(&mut sim, &[("Go", false), ("Shift", true)]);
    assert_eq!(r2.fired, ["TMiddle", "TFront"], "declaration order");
    assert_eq!(r2.active, ["Middle", "Rear"]);
    assert!(r2.events.is_empty(), "{:?}", r2.events);
}

#[test]
fn contention_events() {
    // semantics.md, "Contention": timed associations in text order; when two differ in qualifier
    // or duration, `contention` is emitted, winner first. Equal ones (Eq) do not contend.
    let mut sim = sim_of("26_contention.st");
    let r0 = scan(&mut sim, &[]);
    assert!(r0.events.is_empty(), "{r0:?}");
    for k in 1..=5 {
        let r = scan(&mut sim, &[("Go", k == 1)]);
        assert!(r.events.iter().all(|e| matches!(e, Event::Contention { .. })), "scan {k}: {:?}", r.events);
        let mut got: Vec<_> = r.events.iter().filter_map(contention_of).collect();
        got.sort();
        let out = ("Out".to_string(), strings(&["LimitStep", "DelayStep"]), strings(&["L", "D"]));
        let dur = ("Dur".to_string(), strings(&["ShortStep", "LongStep"]), strings(&["L", "L"]));
        let want = match k {
            1..=3 => vec![dur, out],
            4 => vec![out],
            _ => vec![],
        };
        assert_eq!(got, want, "scan {k}");
    }
}

#[test]
fn events_come_in_trace_order() {
    // interfaces.md, "Traces": events "in the order conflict, unsafe, contention, error", here
    // all three in scan 2 of a chart that declares them in the opposite order.
    let text = "
PROGRAM Kinds
    VAR_INPUT
        Go : BOOL;
    END_VAR
    VAR_OUTPUT
        Out : BOOL;
    END_VAR

    INITIAL_STEP Init2: END_STEP

    TRANSITION TSplit FROM Init2 TO (Left, Right)
        := Go;
    END_TRANSITION

    STEP Left: END_STEP

    STEP Right: END_STEP

    TRANSITION TLeft FROM Left TO Meet
        := Left.T >= T#10ms;
    END_TRANSITION

    TRANSITION TRight FROM Right TO Meet
        := Right.T >= T#10ms;
    END_TRANSITION

    {attribute 'sfc.final' := 'true'}
    STEP Meet:
        Out(D, T#50ms);
    END_STEP

    INITIAL_STEP Init1: END_STEP

    TRANSITION TA FROM Init1 TO A1
        := Left.X;
    END_TRANSITION

    TRANSITION TB FROM Init1 TO B1
        := Left.X;
    END_TRANSITION

    {attribute 'sfc.final' := 'true'}
    STEP A1:
        Out(L, T#50ms);
    END_STEP

    {attribute 'sfc.final' := 'true'}
    STEP B1: END_STEP
END_PROGRAM
";
    let mut sim = sim_of_text("kinds.st", text);
    scan(&mut sim, &[]);
    scan(&mut sim, &[("Go", true)]);
    let r2 = scan(&mut sim, &[]);
    assert_eq!(r2.active, ["A1", "Meet"]);
    assert_eq!(r2.events.len(), 3, "{:?}", r2.events);
    assert_eq!(r2.events[0], conflict("Init1", &["TA", "TB"]));
    assert_eq!(r2.events[1], unsafe_("Meet", &["TLeft", "TRight"]));
    assert_eq!(
        contention_of(&r2.events[2]),
        Some(("Out".to_string(), strings(&["Meet", "A1"]), strings(&["D", "L"]))),
        "Meet is declared before A1, so its D wins"
    );
}

const FAULTY: &str = "PROGRAM Faulty
    VAR_INPUT
        Go : BOOL;
    END_VAR
    VAR_OUTPUT
        Ticks : INT;
        Before : INT;
        After : INT;
        Zero : INT;
    END_VAR

    INITIAL_STEP Init:
        Tick(N);
    END_STEP

    TRANSITION TGo FROM Init TO Broken
        := Go;
    END_TRANSITION

    STEP Broken:
        Divide(N);
    END_STEP

    TRANSITION TBack FROM Broken TO Init
        := NOT Go;
    END_TRANSITION

    ACTION Tick:
        Ticks := Ticks + 1;
    END_ACTION

    ACTION Divide:
        Before := 1;
        After := 10 / Zero;
        After := 2;
    END_ACTION
END_PROGRAM
";

/// 1-based line of the first line containing `needle`, and the 1-based columns where the
/// statement on it starts and ends.
fn locate(text: &str, needle: &str) -> (u32, u32, u32) {
    let (i, line) = text.lines().enumerate().find(|(_, l)| l.contains(needle)).unwrap();
    let start = line.len() - line.trim_start().len() + 1;
    (i as u32 + 1, start as u32, line.trim_end().len() as u32)
}

fn int(sim: &Simulation, name: &str) -> i64 {
    sim.get(name).and_then(|v| v.as_int()).unwrap_or_else(|| panic!("{name} is not readable"))
}

#[test]
fn runtime_error_stops_the_run() {
    // semantics.md: "A runtime error stops the run after writing the faulting scan (the
    // statements before the fault have executed) with an error event"; "Division by zero ...
    // stop[s] the chart with a runtime error that names the source location, the scan and the
    // time". Simulation::scan: "once stopped, scan runs nothing and returns that record".
    let mut sim = sim_of_text("faulty.st", FAULTY);
    scan(&mut sim, &[]);
    scan(&mut sim, &[]);
    assert!(sim.error().is_none());
    let r2 = scan(&mut sim, &[("Go", true)]);
    assert_eq!(r2.scan, 2);
    assert_eq!(r2.active, ["Broken"], "the faulting scan is written");
    assert_eq!(r2.fired, ["TGo"]);
    let err = sim.error().expect("division by zero sets Simulation::error").clone();
    assert_eq!((err.scan, err.time), (2, 20_000));
    let (line, first, last) = locate(FAULTY, "After := 10 / Zero;");
    assert_eq!(err.line, line, "{err:?}");
    assert!((first..=last).contains(&err.column), "column {} outside the statement ({first}..={last})", err.column);
    assert!(err.message.to_ascii_lowercase().contains("zero"), "{}", err.message);
    assert_eq!(r2.events.last(), Some(&Event::Error(err.clone())));
    // Statements before the fault ran (Tick's final scan, then Divide up to the division);
    // nothing after it.
    assert_eq!(int(&sim, "Ticks"), 3);
    assert_eq!(int(&sim, "Before"), 1);
    assert_eq!(int(&sim, "After"), 0);
    // Later scans do nothing.
    for _ in 0..3 {
        let r = scan(&mut sim, &[]);
        assert_eq!(r.scan, 2, "a stopped run returns the faulting record");
        assert_eq!(sim.active(), ["Broken"]);
        assert_eq!(int(&sim, "Ticks"), 3);
        assert_eq!(sim.error(), Some(&err));
    }
}

#[test]
fn both_operands_are_evaluated_even_to_a_fault() {
    // semantics.md: "AND, OR, XOR evaluate both operands"; "division or MOD by zero is a runtime
    // error". FALSE AND x still evaluates x; FALSE AND_THEN x does not.
    let text = "PROGRAM Operands
    VAR_OUTPUT
        Zero : INT;
        Safe : BOOL;
        Flag : BOOL := TRUE;
    END_VAR

    INITIAL_STEP Init:
        Evaluate(P1);
    END_STEP

    ACTION Evaluate:
        Safe := FALSE AND_THEN (10 MOD Zero > 1);
        Flag := FALSE AND (10 MOD Zero > 1);
    END_ACTION
END_PROGRAM
";
    let mut sim = sim_of_text("operands.st", text);
    let r0 = scan(&mut sim, &[]);
    let err = sim.error().expect("MOD by zero in the right operand of AND is evaluated").clone();
    assert_eq!(err.scan, 0);
    assert_eq!(err.line, locate(text, "Flag := FALSE AND").0, "{err:?}");
    assert!(matches!(r0.events.last(), Some(Event::Error(_))));
    assert_eq!(sim.get("Flag"), Some(Value::Bool(true)), "the faulting assignment did not complete");
}

#[test]
fn scenario_expectation_after_a_runtime_error_fails() {
    // interfaces.md, "Scenario files": "an expectation never reached (run too short, or stopped
    // by an error) fails."
    let dir = std::env::temp_dir().join(format!("sfc-semantics-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join("faulty.st"), FAULTY).unwrap();
    let scenario = dir.join("faulty.scenario.toml");
    std::fs::write(
        &scenario,
        "chart = \"faulty.st\"\nuntil = \"T#50ms\"\n\n[[at]]\ntime = \"T#20ms\"\nset = { Go = true }\n\n\
         [[at]]\ntime = \"T#40ms\"\nexpect = { Ticks = 3 }\n",
    )
    .unwrap();
    let outcome = run_path(&scenario).expect("the scenario loads");
    std::fs::remove_dir_all(&dir).ok();
    assert!(!outcome.passed());
    assert!(outcome.error.is_some(), "the runtime error is reported: {outcome:?}");
    assert!(outcome.failures.iter().any(|f| f.contains("40ms")), "the expectation at T#40ms fails: {outcome:?}");
}

#[test]
fn unnamed_transitions_are_named_by_position() {
    // semantics.md, "Names": "An unnamed transition is named T<n>, n its 1-based position among
    // the POU's TRANSITION declarations; if that name is taken, the first free T<n>_1, ..."
    let text = "PROGRAM Unnamed
    VAR_INPUT
        Go : BOOL;
    END_VAR
    VAR
        T2 : INT;
    END_VAR

    INITIAL_STEP Init: END_STEP

    TRANSITION FROM Init TO Next
        := Go AND T2 = 0;
    END_TRANSITION

    STEP Next: END_STEP

    TRANSITION FROM Next TO Init
        := NOT Go;
    END_TRANSITION
END_PROGRAM
";
    let mut sim = sim_of_text("unnamed.st", text);
    scan(&mut sim, &[]);
    assert_eq!(scan(&mut sim, &[("Go", true)]).fired, ["T1"]);
    assert_eq!(scan(&mut sim, &[("Go", false)]).fired, ["T2_1"]);
    assert_eq!(sim.transition_names(), ["T1", "T2_1"]);
}

#[test]
fn guards_with_side_effects_do_not_compile() {
    // semantics.md, step 3: "a guard that calls a function block or assigns is a compile error"
    let text = "PROGRAM SideEffect
    VAR_INPUT
        Go : BOOL;
    END_VAR
    VAR
        Edge : R_TRIG;
    END_VAR

    INITIAL_STEP Init: END_STEP

    TRANSITION TGo FROM Init TO Next
        := Edge(CLK := Go);
    END_TRANSITION

    STEP Next: END_STEP

    TRANSITION TBack FROM Next TO Init
        := NOT Go;
    END_TRANSITION
END_PROGRAM
";
    match Simulation::from_source("side_effect.st", text, None, SimOptions::default()) {
        Ok(_) => panic!("a guard calling a function block compiled"),
        Err((_, diags)) => assert!(diags.iter().any(|d| d.is_error()), "{diags:#?}"),
    }
}

#[test]
fn array_index_out_of_range_is_a_runtime_error() {
    // semantics.md, "Structured Text": "Division by zero, array index out of range and similar
    // faults stop the chart with a runtime error that names the source location, the scan and
    // the time; nothing is silently ignored."
    let text = "PROGRAM OutOfRange
    VAR_INPUT
        Index : INT;
    END_VAR
    VAR_OUTPUT
        Cells : ARRAY [1..3] OF INT;
        Writes : INT;
    END_VAR

    INITIAL_STEP Init:
        Store(N);
    END_STEP

    ACTION Store:
        Writes := Writes + 1;
        Cells[Index] := Writes;
    END_ACTION
END_PROGRAM
";
    let mut sim = sim_of_text("out_of_range.st", text);
    sim.set("Index", Value::Int(2)).unwrap();
    scan(&mut sim, &[]);
    assert!(sim.error().is_none());
    sim.set("Index", Value::Int(4)).unwrap();
    let r1 = sim.scan().clone();
    let err = sim.error().expect("index 4 of ARRAY [1..3] stops the run").clone();
    assert_eq!((err.scan, err.time), (1, 10_000));
    assert_eq!(err.line, locate(text, "Cells[Index] := Writes;").0, "{err:?}");
    assert_eq!(r1.events.last(), Some(&Event::Error(err)));
    assert_eq!(int(&sim, "Writes"), 2, "the statement before the fault ran");
}

/// The `codesys` profile's fixtures (`tests/codesys/`, one per documented rule) pass their
/// scenarios; their hand-derived traces are compared through the binary (sfc-cli's sim_cli).
#[test]
fn codesys_rules() {
    profile_rules("codesys", 12);
}

/// The `logix` profile's fixtures (`tests/logix/`), likewise.
#[test]
fn logix_rules() {
    profile_rules("logix", 11);
}

/// The `graph` profile's fixtures (`tests/graph/`), likewise.
#[test]
fn graph_rules() {
    profile_rules("graph", 10);
}

fn profile_rules(profile: &str, at_least: usize) {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests").join(profile);
    let mut files: Vec<PathBuf> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.to_string_lossy().ends_with(".scenario.toml"))
        .collect();
    files.sort();
    assert!(files.len() >= at_least);
    for path in &files {
        let outcome = run_path(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
        assert!(outcome.passed(), "{}: {:?} {:?}", path.display(), outcome.failures, outcome.error);
    }
}

/// `logix` with "Execute until FALSE transition": a chart that can advance for ever in one call
/// is stopped with an error, where the controller's watchdog would fault.
#[test]
fn logix_until_false_without_a_false_transition_stops_like_a_watchdog() {
    let text = "{attribute 'sfc.dialect' := 'logix'}
{attribute 'sfc.logix.exec' := 'UntilFalse'}
PROGRAM Spin
INITIAL_STEP A: END_STEP
TRANSITION FROM A TO B := TRUE; END_TRANSITION
STEP B: END_STEP
TRANSITION FROM B TO A := TRUE; END_TRANSITION
END_PROGRAM
";
    let opts = SimOptions { profile: sfc_sim::Profile::Logix, ..SimOptions::default() };
    let mut sim = match Simulation::from_source("spin.st", text, None, opts) {
        Ok(s) => s,
        Err((_, d)) => panic!("{d:#?}"),
    };
    sim.scan();
    let err = sim.error().expect("the call never ends").clone();
    assert!(err.message.contains("Execute until FALSE transition"), "{err:?}");
}

/// `codesys`: a call with SFCPause TRUE processes nothing, the first one included (it only
/// activates the initial steps); the first call after the pause runs the actions and tests the
/// transitions (docs/sim.md, "The `codesys` profile", "SFC flags").
#[test]
fn codesys_pause_holds_the_first_call_too() {
    let text = "PROGRAM P\nVAR_INPUT SFCPause : BOOL; END_VAR\nVAR_OUTPUT Runs : INT; END_VAR\n\
                INITIAL_STEP S: Count(N); END_STEP\nTRANSITION FROM S TO T := TRUE; END_TRANSITION\n\
                STEP T: END_STEP\nTRANSITION FROM T TO S := FALSE; END_TRANSITION\n\
                ACTION Count: Runs := Runs + 1; END_ACTION\nEND_PROGRAM\n";
    let opts = SimOptions { period: 10_000, profile: sfc_sim::Profile::Codesys };
    let mut sim = Simulation::from_source("p.st", text, None, opts).map_err(|(_, d)| d).unwrap();
    sim.set("SFCPause", Value::Bool(true)).unwrap();
    for _ in 0..2 {
        let r = sim.scan();
        assert_eq!(r.active, vec!["S".to_string()]);
        assert!(r.fired.is_empty());
        assert_eq!(sim.get("Runs"), Some(Value::Int(0)));
    }
    sim.set("SFCPause", Value::Bool(false)).unwrap();
    let r = sim.scan();
    assert_eq!(r.active, vec!["T".to_string()]);
    assert_eq!(sim.get("Runs"), Some(Value::Int(1)));
}
