//! `sfc sim` and `sfc test` against their contract (`interfaces.md`: "The sfc command",
//! "Scenario files", "Traces"): exit codes, the last line of `sfc test`, the three trace
//! formats, scenario failures, and a located message for every kind of bad scenario.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn sfc_in(dir: &Path, args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_sfc")).args(args).current_dir(dir).output().expect("sfc runs")
}

fn sfc(args: &[&str]) -> Output {
    sfc_in(&root(), args)
}

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

fn temp_dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("sfc-sim-test-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn stdout(o: &Output) -> String {
    String::from_utf8_lossy(&o.stdout).into_owned()
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

fn both(o: &Output) -> String {
    format!("--- stdout\n{}--- stderr\n{}", stdout(o), stderr(o))
}

fn last_line(o: &Output) -> String {
    stdout(o).lines().last().unwrap_or_default().to_string()
}

/// A temporary directory holding a copy of the blinker example.
fn blinker_dir(name: &str) -> PathBuf {
    let d = temp_dir(name);
    std::fs::copy(root().join("examples/blinker/blinker.st"), d.join("blinker.st")).unwrap();
    d
}

const COUNTER: &str = "PROGRAM Counter
    VAR_INPUT
        Run : BOOL;
    END_VAR
    VAR
        Count : INT;
    END_VAR
    INITIAL_STEP Idle: END_STEP
    TRANSITION FROM Idle TO Counting := Run; END_TRANSITION
    STEP Counting: Inc(N); END_STEP
    TRANSITION FROM Counting TO Idle := Count >= 5; END_TRANSITION
    ACTION Inc:
        Count := Count + 1;
    END_ACTION
END_PROGRAM
";

const DIVIDER: &str = "PROGRAM Divider
    VAR_INPUT
        Go : BOOL;
    END_VAR
    VAR
        x : INT := 10;
        d : INT;
    END_VAR
    INITIAL_STEP Idle: END_STEP
    TRANSITION FROM Idle TO Work := Go; END_TRANSITION
    STEP Work: Calc(N); END_STEP
    TRANSITION FROM Work TO Idle := x > 100; END_TRANSITION
    ACTION Calc:
        x := x / d;
    END_ACTION
END_PROGRAM
";

const WATCH: &str = "PROGRAM Watch
    VAR_INPUT
        Done : BOOL;
    END_VAR
    INITIAL_STEP Start: END_STEP
    TRANSITION FROM Start TO Wait := TRUE; END_TRANSITION
    {attribute 'sfc.timeout' := 'T#50ms'}
    STEP Wait: END_STEP
    TRANSITION FROM Wait TO Start := Done; END_TRANSITION
END_PROGRAM
";

const TWO_POUS: &str = "PROGRAM A
    INITIAL_STEP S1: END_STEP
    STEP S2: END_STEP
    TRANSITION FROM S1 TO S2 := TRUE; END_TRANSITION
    TRANSITION FROM S2 TO S1 := TRUE; END_TRANSITION
END_PROGRAM

PROGRAM B
    INITIAL_STEP S1: END_STEP
    STEP S2: END_STEP
    TRANSITION FROM S1 TO S2 := TRUE; END_TRANSITION
    TRANSITION FROM S2 TO S1 := TRUE; END_TRANSITION
END_PROGRAM
";

const BROKEN: &str = "PROGRAM P\n    VAR_INPUT Start : BOOL; END_VAR\n    INITIAL_STEP S1: END_STEP\n    STEP S2: END_STEP\n    TRANSITION T1 FROM S1 TO S3 := Start; END_TRANSITION\n    TRANSITION T2 FROM S2 TO S1 := Start; END_TRANSITION\nEND_PROGRAM\n";

// ---------------------------------------------------------------------------------------------
// Usage and I/O errors: no engine needed to get these right.

#[test]
fn help_exits_0() {
    for sub in ["sim", "test"] {
        let out = sfc(&[sub, "--help"]);
        assert_eq!(out.status.code(), Some(0), "{}", both(&out));
    }
}

#[test]
fn sim_usage_and_io_errors_exit_2() {
    let ex = "examples/blinker/blinker.st";
    let cases: &[(&[&str], &str)] = &[
        (&["sim", "/nonexistent/chart.st"], "cannot read the chart"),
        (&["sim", ex, "--period", "10ms"], "not a TIME literal"),
        (&["sim", ex, "--period", "T#0s"], "must be positive"),
        (&["sim", ex, "--profile", "beckhoff"], "beckhoff"),
        (&["sim", ex, "--until", "T#1s", "--scans", "3"], "cannot be used with"),
        (&["sim", ex, "--trace", "out.txt"], "cannot tell the trace format"),
        (&["sim", ex, "--scenario", "/nonexistent/s.scenario.toml"], "cannot read the scenario"),
        (&["sim", ex, "--set", "Start"], "NAME=VALUE"),
        (&["sim"], "FILE"),
    ];
    for (args, msg) in cases {
        let out = sfc(args);
        assert_eq!(out.status.code(), Some(2), "{args:?}\n{}", both(&out));
        assert!(stderr(&out).contains(msg), "{args:?}: expected `{msg}` in\n{}", both(&out));
    }
}

#[test]
fn test_without_scenarios_or_with_a_missing_path_exits_2() {
    let empty = temp_dir("empty");
    let out = sfc(&["test", empty.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(2), "{}", both(&out));
    assert!(stderr(&out).contains("no scenario files"), "{}", both(&out));
    let out = sfc(&["test", "/nonexistent/dir"]);
    assert_eq!(out.status.code(), Some(2), "{}", both(&out));
    assert!(stderr(&out).contains("does not exist"), "{}", both(&out));
    assert_eq!(sfc(&["test"]).status.code(), Some(2));
}

/// Scenario files that fail before the chart is compiled: each gives its located message,
/// a FAIL line and exit 1 under `sfc test`, exit 1 under `sfc sim --scenario`.
#[test]
fn malformed_scenarios_give_located_errors() {
    let d = blinker_dir("malformed");
    let cases: &[(&str, &str, &[&str])] = &[
        ("syntax", "chart = \"blinker.st\"\nuntil = \n", &["syntax.scenario.toml:2:", "TOML syntax error"]),
        (
            "unknown_key",
            "chart = \"blinker.st\"\nperiods = \"T#10ms\"\n",
            &["unknown_key.scenario.toml:2:1: unknown key `periods`", "did you mean `period`?"],
        ),
        (
            "entry_key",
            "chart = \"blinker.st\"\n[[at]]\ntime = \"T#0s\"\nexpcet = { Visible = true }\n",
            &["entry_key.scenario.toml:4:1: unknown key `expcet` in an [[at]] entry"],
        ),
        (
            "backwards",
            "chart = \"blinker.st\"\n[[at]]\ntime = \"T#1s\"\n[[at]]\ntime = \"T#500ms\"\n",
            &["backwards.scenario.toml:5:8: `time` goes backwards: T#500ms comes after T#1s"],
        ),
        (
            "both",
            "chart = \"blinker.st\"\nuntil = \"T#1s\"\nscans = 10\n",
            &["both.scenario.toml:3:1: `until` and `scans` are both given"],
        ),
        (
            "bad_time",
            "chart = \"blinker.st\"\nperiod = \"100ms\"\n",
            &["bad_time.scenario.toml:2:10:", "`100ms` is not a TIME literal"],
        ),
        (
            "fine_time",
            "chart = \"blinker.st\"\nuntil = \"T#1ns\"\n",
            &["fine_time.scenario.toml:2:9:", "not a TIME literal"],
        ),
        ("bad_profile", "chart = \"blinker.st\"\nprofile = \"s7\"\n", &["unknown profile `s7`"]),
        (
            "no_time",
            "chart = \"blinker.st\"\n[[at]]\nset = { Start = true }\n",
            &["no_time.scenario.toml:2:1:", "needs a `time`"],
        ),
        ("no_chart", "scans = 3\n", &["no_chart.scenario.toml:1: missing `chart"]),
    ];
    for (name, text, msgs) in cases {
        let f = d.join(format!("{name}.scenario.toml"));
        std::fs::write(&f, text).unwrap();
        let out = sfc_in(&d, &["test", &format!("{name}.scenario.toml")]);
        assert_eq!(out.status.code(), Some(1), "{name}\n{}", both(&out));
        let s = stdout(&out);
        assert!(s.starts_with(&format!("FAIL {name}.scenario.toml\n")), "{name}\n{}", both(&out));
        for m in *msgs {
            assert!(s.contains(m), "{name}: expected `{m}` in\n{}", both(&out));
        }
        assert_eq!(last_line(&out), "0 passed, 1 failed");
        // `sfc sim` with the same scenario: the message on stderr, exit 1 (there the chart is
        // the command's FILE, so a scenario without `chart` is fine).
        if *name == "no_chart" {
            continue;
        }
        let out = sfc_in(&d, &["sim", "blinker.st", "--scenario", &format!("{name}.scenario.toml")]);
        assert_eq!(out.status.code(), Some(1), "{name}\n{}", both(&out));
        for m in *msgs {
            assert!(stderr(&out).contains(m), "{name}: expected `{m}` on stderr\n{}", both(&out));
        }
    }
}

#[test]
fn a_missing_chart_fails_the_scenario() {
    let d = temp_dir("missing-chart");
    std::fs::write(d.join("m.scenario.toml"), "chart = \"nope.st\"\nscans = 2\n").unwrap();
    let out = sfc_in(&d, &["test", "."]);
    assert_eq!(out.status.code(), Some(1), "{}", both(&out));
    assert!(stdout(&out).starts_with("FAIL m.scenario.toml\n"), "{}", both(&out));
    assert!(stdout(&out).contains("m.scenario.toml:1:1: cannot read the chart `nope.st`"), "{}", both(&out));
    assert_eq!(last_line(&out), "0 passed, 1 failed");
}

// ---------------------------------------------------------------------------------------------
// Running scenarios (needs the engine)

#[test]
fn test_runs_the_blinker_example() {
    let out = sfc(&["test", "examples/blinker"]);
    assert_eq!(out.status.code(), Some(0), "{}", both(&out));
    assert_eq!(stdout(&out), "PASS examples/blinker/blinker.scenario.toml\n1 passed, 0 failed\n");
}

#[test]
fn test_reports_coverage_per_chart() {
    let out = sfc(&["test", "--coverage", "examples/blinker"]);
    assert_eq!(out.status.code(), Some(0), "{}", both(&out));
    let s = stdout(&out);
    assert!(s.contains("examples/blinker/blinker.st (Blinker): steps 3/3 (100%), transitions 4/4 (100%)"), "{s}");
    assert_eq!(last_line(&out), "1 passed, 0 failed");

    // A run that never leaves S1: S2, S3 never active, nothing fired.
    let d = blinker_dir("coverage");
    std::fs::write(d.join("idle.scenario.toml"), "chart = \"blinker.st\"\nscans = 5\n").unwrap();
    let out = sfc_in(&d, &["test", "--coverage", "."]);
    assert_eq!(out.status.code(), Some(0), "{}", both(&out));
    let s = stdout(&out);
    assert!(s.contains("blinker.st (Blinker): steps 1/3 (33%), transitions 0/4 (0%)"), "{s}");
    assert!(s.contains("never active: S2, S3"), "{s}");
    assert!(s.contains("never fired: T1, T2, T4, T5"), "{s}");
}

#[test]
fn failed_expectations_name_scenario_time_key_expected_and_actual() {
    let d = blinker_dir("failing");
    std::fs::write(
        d.join("a_good.scenario.toml"),
        "chart = \"blinker.st\"\nperiod = \"T#100ms\"\n[[at]]\ntime = \"T#0s\"\nexpect = { active = [\"S1\"], Visible = false }\n",
    )
    .unwrap();
    std::fs::write(
        d.join("b_bad.scenario.toml"),
        "chart = \"blinker.st\"\nperiod = \"T#100ms\"\nscans = 3\n\n[[at]]\ntime = \"T#0s\"\nset = { Start = true }\n\n[[at]]\ntime = \"T#100ms\"\nexpect = { active = [\"S3\"], Visible = false, \"S2.X\" = false }\n\n[[at]]\ntime = \"T#5s\"\nexpect = { Visible = true }\n",
    )
    .unwrap();
    let out = sfc_in(&d, &["test", "."]);
    assert_eq!(out.status.code(), Some(1), "{}", both(&out));
    let s = stdout(&out);
    let lines: Vec<&str> = s.lines().collect();
    assert_eq!(lines[0], "PASS a_good.scenario.toml", "{s}");
    assert_eq!(lines[1], "FAIL b_bad.scenario.toml", "{s}");
    assert!(
        s.contains("b_bad.scenario.toml:9: at T#100ms (scan 1): `active`: expected [\"S3\"], actual [\"S2\"]"),
        "{s}"
    );
    assert!(s.contains("b_bad.scenario.toml:9: at T#100ms (scan 1): `Visible`: expected false, actual true"), "{s}");
    assert!(s.contains("b_bad.scenario.toml:9: at T#100ms (scan 1): `S2.X`: expected false, actual true"), "{s}");
    assert!(s.contains("b_bad.scenario.toml:13: at T#5s (scan 50): expectation never reached: the run ended after scan 2 (T#200ms)"), "{s}");
    assert_eq!(last_line(&out), "1 passed, 1 failed");
}

#[test]
fn scenarios_bound_to_the_chart_give_located_errors() {
    let d = blinker_dir("binding");
    std::fs::write(d.join("broken.st"), BROKEN).unwrap();
    std::fs::write(d.join("two.st"), TWO_POUS).unwrap();
    let cases: &[(&str, &str, &[&str])] = &[
        (
            "unknown_var",
            "chart = \"blinker.st\"\n[[at]]\ntime = \"T#0s\"\nset = { Strat = true }\n",
            &["unknown_var.scenario.toml:4:9: unknown variable `Strat`", "did you mean `Start`?"],
        ),
        (
            "wrong_type",
            "chart = \"blinker.st\"\n[[at]]\ntime = \"T#0s\"\nset = { Start = 1 }\n",
            &["wrong_type.scenario.toml:4:9: `Start` is BOOL: expected true or false, found the integer 1"],
        ),
        (
            "wrong_time",
            "chart = \"blinker.st\"\n[[at]]\ntime = \"T#0s\"\nexpect = { \"S2.T\" = 5 }\n",
            &["wrong_time.scenario.toml:4:12: `S2.T` is TIME: expected a TIME literal"],
        ),
        (
            "unknown_step",
            "chart = \"blinker.st\"\n[[at]]\ntime = \"T#0s\"\nexpect = { active = [\"S4\"] }\n",
            &["unknown step `S4` in `active`"],
        ),
        (
            "chart_errors",
            "chart = \"broken.st\"\n",
            &["chart_errors.scenario.toml:1:1: the chart `", "error[SFC0208]: undeclared step `S3`"],
        ),
        ("ambiguous", "chart = \"two.st\"\n", &["ambiguous.scenario.toml:1:1: the chart `", "error[SFC"]),
        (
            "no_such_pou",
            "chart = \"two.st\"\npou = \"C\"\n",
            &["no_such_pou.scenario.toml:2:1: the chart `", "error[SFC"],
        ),
    ];
    for (name, text, msgs) in cases {
        std::fs::write(d.join(format!("{name}.scenario.toml")), text).unwrap();
        let out = sfc_in(&d, &["test", &format!("{name}.scenario.toml")]);
        assert_eq!(out.status.code(), Some(1), "{name}\n{}", both(&out));
        let s = stdout(&out);
        assert!(s.starts_with(&format!("FAIL {name}.scenario.toml\n")), "{name}\n{}", both(&out));
        for m in *msgs {
            assert!(s.contains(m), "{name}: expected `{m}` in\n{}", both(&out));
        }
        assert_eq!(last_line(&out), "0 passed, 1 failed");
    }
    // The POU picked from two: fine.
    std::fs::write(d.join("pick.scenario.toml"), "chart = \"two.st\"\npou = \"B\"\nscans = 2\n").unwrap();
    let out = sfc_in(&d, &["test", "pick.scenario.toml"]);
    assert_eq!(out.status.code(), Some(0), "{}", both(&out));
}

// ---------------------------------------------------------------------------------------------
// `sfc sim`

#[test]
fn sim_with_the_blinker_scenario_passes() {
    let out = sfc(&["sim", "examples/blinker/blinker.st", "--scenario", "examples/blinker/blinker.scenario.toml"]);
    assert_eq!(out.status.code(), Some(0), "{}", both(&out));
    let s = stdout(&out);
    assert!(s.contains("PASS examples/blinker/blinker.scenario.toml"), "{s}");
    assert!(s.contains("active steps: S1"), "{s}");
}

#[test]
fn sim_without_scenario_runs_100_scans() {
    let out = sfc(&["sim", "examples/blinker/blinker.st", "--trace", "-"]);
    assert_eq!(out.status.code(), Some(0), "{}", both(&out));
    let s = stdout(&out);
    assert_eq!(s.lines().count(), 100, "{s}");
    assert!(s.lines().last().unwrap().starts_with("{\"scan\":99,\"time\":\"T#990ms\","), "{s}");
    let out = sfc(&["sim", "examples/blinker/blinker.st", "--period", "T#100ms", "--until", "T#1s", "--trace", "-"]);
    assert_eq!(stdout(&out).lines().count(), 11, "{}", both(&out));
}

#[test]
fn chart_errors_exit_1() {
    let d = temp_dir("broken");
    std::fs::write(d.join("broken.st"), BROKEN).unwrap();
    let out = sfc_in(&d, &["sim", "broken.st"]);
    assert_eq!(out.status.code(), Some(1), "{}", both(&out));
    assert!(stderr(&out).contains("error[SFC0208]: undeclared step `S3`"), "{}", both(&out));
    assert!(stderr(&out).contains("broken.st:5:30"), "{}", both(&out));
}

#[test]
fn unknown_set_variable_exits_2_with_a_suggestion() {
    let out = sfc(&["sim", "examples/blinker/blinker.st", "--set", "Strat=TRUE"]);
    assert_eq!(out.status.code(), Some(2), "{}", both(&out));
    assert!(
        stderr(&out).contains("unknown variable `Strat`") && stderr(&out).contains("did you mean `Start`?"),
        "{}",
        both(&out)
    );
    let out = sfc(&["sim", "examples/blinker/blinker.st", "--set", "Start=maybe"]);
    assert_eq!(out.status.code(), Some(2), "{}", both(&out));
    assert!(stderr(&out).contains("`Start` is BOOL"), "{}", both(&out));
}

#[test]
fn json_lines_trace_has_the_contract_object() {
    let out = sfc(&[
        "sim",
        "examples/blinker/blinker.st",
        "--period",
        "T#100ms",
        "--scans",
        "8",
        "--set",
        "Start=TRUE",
        "--trace",
        "-",
    ]);
    assert_eq!(out.status.code(), Some(0), "{}", both(&out));
    let s = stdout(&out);
    let lines: Vec<&str> = s.lines().collect();
    assert_eq!(lines.len(), 8, "only JSON lines on stdout when the trace goes there:\n{s}");
    assert_eq!(
        lines[0],
        r#"{"scan":0,"time":"T#0s","active":["S1"],"fired":[],"vars":{"Start":true,"Stop":false,"TimeOn":"T#500ms","TimeOff":"T#500ms","Visible":false},"events":[]}"#
    );
    assert_eq!(
        lines[1],
        r#"{"scan":1,"time":"T#100ms","active":["S2"],"fired":["T1"],"vars":{"Start":true,"Stop":false,"TimeOn":"T#500ms","TimeOff":"T#500ms","Visible":true},"events":[]}"#
    );
    assert!(lines[7].starts_with(r#"{"scan":7,"time":"T#700ms","active":["S3"],"fired":["T2"],"#), "{}", lines[7]);
    for l in &lines {
        let v: serde_json::Value = serde_json::from_str(l).expect("each line is JSON");
        let keys = ["\"scan\":", "\"time\":", "\"active\":", "\"fired\":", "\"vars\":", "\"events\":"];
        let pos: Vec<usize> = keys.iter().map(|k| l.find(k).expect("key present")).collect();
        assert!(pos.windows(2).all(|w| w[0] < w[1]), "keys out of order: {l}");
        assert_eq!(v.as_object().unwrap().len(), 6);
    }
}

#[test]
fn csv_and_vcd_traces() {
    let d = blinker_dir("traces");
    let base = ["sim", "blinker.st", "--period", "T#100ms", "--scans", "10", "--set", "Start=TRUE", "--trace"];
    let out = sfc_in(&d, &[&base[..], &["t.csv"]].concat());
    assert_eq!(out.status.code(), Some(0), "{}", both(&out));
    assert!(stdout(&out).contains("active steps:"), "the summary goes to stdout: {}", both(&out));
    let csv = std::fs::read_to_string(d.join("t.csv")).unwrap();
    let rows: Vec<&str> = csv.lines().collect();
    assert_eq!(rows[0], "scan,time,active,Start,Stop,TimeOn,TimeOff,Visible");
    assert_eq!(rows[1], "0,T#0s,S1,TRUE,FALSE,T#500ms,T#500ms,FALSE");
    assert_eq!(rows[2], "1,T#100ms,S2,TRUE,FALSE,T#500ms,T#500ms,TRUE");
    assert_eq!(rows.len(), 11);

    let out = sfc_in(&d, &[&base[..], &["t.vcd"]].concat());
    assert_eq!(out.status.code(), Some(0), "{}", both(&out));
    let vcd = std::fs::read_to_string(d.join("t.vcd")).unwrap();
    for needle in [
        "$timescale 1 us $end\n",
        "$scope module Blinker $end\n",
        "$var wire 1 ! S1 $end\n",
        "$var wire 1 \" S2 $end\n",
        "$var wire 1 # S3 $end\n",
        " Start $end\n",
        " Visible $end\n",
        "$upscope $end\n$enddefinitions $end\n#0\n$dumpvars\n",
        "#100000\n",
    ] {
        assert!(vcd.contains(needle), "missing {needle:?} in\n{vcd}");
    }
    // Steps and BOOL variables only: TIME variables get no wire.
    assert_eq!(vcd.matches("$var ").count(), 6, "{vcd}");
    let times: Vec<i64> = vcd.lines().filter_map(|l| l.strip_prefix('#')).map(|t| t.parse().unwrap()).collect();
    assert!(times.windows(2).all(|w| w[0] < w[1]), "{times:?}");
}

#[test]
fn vcd_integer_variables() {
    let d = temp_dir("vcd-int");
    std::fs::write(d.join("counter.st"), COUNTER).unwrap();
    let out = sfc_in(&d, &["sim", "counter.st", "--scans", "10", "--set", "Run=TRUE", "--trace", "c.vcd"]);
    assert_eq!(out.status.code(), Some(0), "{}", both(&out));
    let vcd = std::fs::read_to_string(d.join("c.vcd")).unwrap();
    // Steps Idle `!`, Counting `"`, then Run `#` and Count `$`.
    assert!(vcd.contains("$var wire 1 # Run $end\n"), "{vcd}");
    assert!(vcd.contains("$var integer 16 $ Count $end\n"), "{vcd}");
    assert!(vcd.contains("b0 $\n") && vcd.contains("b1 $\n") && vcd.contains("b101 $\n"), "{vcd}");
}

#[test]
fn runtime_errors_stop_the_run_and_exit_1() {
    let d = temp_dir("runtime");
    std::fs::write(d.join("div.st"), DIVIDER).unwrap();
    let out = sfc_in(&d, &["sim", "div.st", "--scans", "10", "--set", "Go=TRUE", "--trace", "t.jsonl"]);
    assert_eq!(out.status.code(), Some(1), "{}", both(&out));
    let err = stderr(&out);
    assert!(err.contains("error: division by zero"), "{err}");
    assert!(err.contains("--> div.st:14:"), "{err}");
    assert!(err.contains("scan 1") && err.contains("T#10ms"), "{err}");
    let trace = std::fs::read_to_string(d.join("t.jsonl")).unwrap();
    let last = trace.lines().last().unwrap();
    assert_eq!(trace.lines().count(), 2, "the faulting scan is the last row:\n{trace}");
    assert!(last.contains(r#""events":[{"kind":"error","message":"division by zero","line":14,"#), "{last}");

    // In a scenario: the run fails, later expectations are never reached.
    std::fs::write(
        d.join("div.scenario.toml"),
        "chart = \"div.st\"\n[[at]]\ntime = \"T#0s\"\nset = { Go = true }\n[[at]]\ntime = \"T#100ms\"\nexpect = { active = [\"Work\"] }\n",
    )
    .unwrap();
    let out = sfc_in(&d, &["test", "div.scenario.toml"]);
    assert_eq!(out.status.code(), Some(1), "{}", both(&out));
    let s = stdout(&out);
    assert!(s.contains("expectation never reached: the run stopped at scan 1 (T#10ms) with a runtime error"), "{s}");
    assert!(s.contains("error: division by zero"), "{s}");
    assert_eq!(last_line(&out), "0 passed, 1 failed");
}

#[test]
fn overdue_steps_are_reported_once() {
    let d = temp_dir("overdue");
    std::fs::write(d.join("watch.st"), WATCH).unwrap();
    let out = sfc_in(&d, &["sim", "watch.st", "--scans", "30"]);
    assert_eq!(out.status.code(), Some(0), "{}", both(&out));
    let s = stdout(&out);
    assert_eq!(s.matches("step Wait active for").count(), 1, "{s}");
    assert!(s.contains("(timeout T#50ms): waiting for T2"), "{s}");
    assert!(s.contains("Done"), "{s}");
}

#[test]
fn stats_and_explain() {
    let args = ["sim", "examples/blinker/blinker.st", "--period", "T#100ms", "--scans", "12", "--set", "Start=TRUE"];
    let out = sfc(&[&args[..], &["--stats", "--explain"]].concat());
    assert_eq!(out.status.code(), Some(0), "{}", both(&out));
    let s = stdout(&out);
    assert!(s.contains("time analysis:") && s.contains("situations:"), "{s}");
    assert!(s.contains("condition analysis"), "{s}");
    let out = sfc(&[&args[..], &["--stats", "--explain", "--format", "json"]].concat());
    assert_eq!(out.status.code(), Some(0), "{}", both(&out));
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).expect("stdout is one JSON document");
    assert_eq!(v["pou"], "Blinker");
    assert_eq!(v["scans"], 12);
    assert!(v["stats"]["steps"].as_array().unwrap().iter().any(|s| s["step"] == "S2"), "{v}");
    assert_eq!(v["stats"]["sequence"][0]["time"], "T#0s");
    assert!(v["explain"].is_array(), "{v}");
}

/// The issue's promise: every example has a scenario and `sfc test examples/` passes them all.
#[test]
fn every_example_has_a_passing_scenario() {
    let examples = root().join("examples");
    let mut dirs: Vec<_> =
        std::fs::read_dir(&examples).unwrap().map(|e| e.unwrap().path()).filter(|p| p.is_dir()).collect();
    dirs.sort();
    for dir in &dirs {
        let has = std::fs::read_dir(dir)
            .unwrap()
            .any(|e| e.unwrap().file_name().to_string_lossy().ends_with(".scenario.toml"));
        assert!(has, "{} has no scenario", dir.display());
    }
    let out = sfc(&["test", "examples"]);
    let s = stdout(&out);
    assert_eq!(out.status.code(), Some(0), "{s}");
    assert!(s.ends_with(" passed, 0 failed\n"), "{s}");
}

/// A runaway nested loop ends the simulation with a located error (the scan's budget of loop
/// iterations and calls, nested loops together), instead of hanging.
#[test]
fn a_runaway_nested_loop_is_a_located_error() {
    let o = sfc(&["sim", "crates/sfc-cli/tests/run/runaway.st", "--set", "Go=TRUE", "--scans", "3"]);
    assert_eq!(o.status.code(), Some(1), "{}", both(&o));
    let err = stderr(&o);
    assert!(
        err.contains("error: runaway scan: more than 10000000 loop iterations, jumps and calls in one scan"),
        "{err}"
    );
    assert!(err.contains("--> crates/sfc-cli/tests/run/runaway.st:43:13") && err.contains("at scan 1"), "{err}");
}

/// A PLCopen chart simulates as the text it imports to; what the import says is shown, and a
/// chart error is located in the XML the user has, not in the imported text.
#[test]
fn a_plcopen_chart_shows_its_import_notes_and_errors_in_the_xml() {
    let corpus = root().join("../shared/corpus/beremiz/svghmi_traffic_light.plc.xml");
    let out = sfc(&["sim", corpus.to_str().unwrap(), "--scans", "3"]);
    assert_eq!(out.status.code(), Some(0), "{}", both(&out));
    assert!(stderr(&out).contains("note[SFC0714]: type `HMI_BOOL` is not declared in the file"), "{}", both(&out));
    assert!(stdout(&out).contains("active steps: trafic_light_sequence0.Standstill"), "{}", both(&out));
    // A runtime error is located in the XML: the line of the action's body there.
    let dir = temp_dir("plcopen-fault");
    let xml = dir.join("dz.xml");
    let st = root().join("crates/sfc-cli/tests/run/divide_by_zero.st");
    let out = sfc(&["build", st.to_str().unwrap(), "--target", "plcopen", "-o", xml.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(0), "{}", both(&out));
    let text = std::fs::read_to_string(&xml).unwrap();
    let (n, line) = text.lines().enumerate().find(|(_, l)| l.contains("Q := 10 / Zero;")).expect("the body in the XML");
    let column = line.find("10 / Zero").unwrap() + 1;
    let out = sfc(&["sim", xml.to_str().unwrap(), "--scans", "3"]);
    assert!(stderr(&out).contains(&format!("dz.xml:{}:{column}\n", n + 1)), "{}", both(&out));
    assert!(stderr(&out).contains(line.trim_end()), "the XML line shown: {}", both(&out));
    // `sfc test` of a scenario on it shows the notes too, once for the chart.
    let dir = temp_dir("plcopen-test");
    std::fs::copy(&corpus, dir.join("light.xml")).unwrap();
    for n in ["a", "b"] {
        std::fs::write(dir.join(format!("{n}.scenario.toml")), "chart = \"light.xml\"\nscans = 3\n").unwrap();
    }
    let out = sfc_in(&dir, &["test", "."]);
    assert_eq!(out.status.code(), Some(0), "{}", both(&out));
    assert_eq!(
        stderr(&out).matches("note[SFC0714]: type `HMI_BOOL` is not declared in the file").count(),
        1,
        "{}",
        both(&out)
    );
    assert!(stdout(&out).contains("2 passed"), "{}", both(&out));
    let dir = temp_dir("plcopen-error");
    let bad = dir.join("bad.xml");
    let xml = std::fs::read_to_string(&corpus)
        .unwrap()
        .replace("<expression>SwitchButton</expression>", "<expression>NoSuchButton</expression>");
    std::fs::write(&bad, xml).unwrap();
    let out = sfc(&["sim", bad.to_str().unwrap(), "--scans", "3"]);
    assert_eq!(out.status.code(), Some(1), "{}", both(&out));
    assert!(stderr(&out).contains("bad.xml:1348:27"), "the error at its XML line: {}", both(&out));
    assert!(stderr(&out).contains("<expression>NoSuchButton</expression>"), "{}", both(&out));
}

/// `--pou` of a POU kept as written (CODESYS object orientation the simulator does not run yet)
/// says so, with why, instead of "no POU named"; a name nowhere in the file lists every POU,
/// those kept as written too.
#[test]
fn pou_kept_as_written_says_why_it_cannot_be_simulated() {
    let d = temp_dir("verbatim-pou");
    let file = d.join("plant.st");
    std::fs::write(
        &file,
        "{attribute 'sfc.verbatim' := 'not analysed: it has methods (CODESYS object orientation)'}\n\
         FUNCTION_BLOCK Axis\n    METHOD MoveTo : BOOL\n    END_METHOD\nEND_FUNCTION_BLOCK\n\n\
         PROGRAM Main\n    VAR\n        Go : BOOL;\n    END_VAR\n    INITIAL_STEP Idle: END_STEP\n    \
         TRANSITION FROM Idle TO Run := Go; END_TRANSITION\n    STEP Run: END_STEP\n    \
         TRANSITION FROM Run TO Idle := NOT Go; END_TRANSITION\nEND_PROGRAM\n",
    )
    .unwrap();
    let out = sfc_in(&d, &["sim", "plant.st", "--pou", "Axis", "--scans", "1"]);
    let err = stderr(&out);
    assert_eq!(out.status.code(), Some(2), "{}", both(&out));
    assert!(err.contains("`Axis` is kept as written, not analysed, so it cannot be simulated"), "{err}");
    assert!(err.contains("it has methods (CODESYS object orientation)"), "{err}");
    let out = sfc_in(&d, &["sim", "plant.st", "--pou", "Conveyor", "--scans", "1"]);
    let err = stderr(&out);
    assert!(err.contains("no POU named `Conveyor`"), "{err}");
    assert!(err.contains("the file declares: Main, Axis (kept as written, not analysed)"), "{err}");
    let out = sfc_in(&d, &["sim", "plant.st", "--pou", "Main", "--scans", "2"]);
    assert_eq!(out.status.code(), Some(0), "the sound POU runs: {}", both(&out));
}

/// Interfaces through the binary: the semantics fixture's scenario passes under `sfc sim`, and
/// a call through an interface that designates nothing stops the run with a located fault.
#[test]
fn interfaces_dispatch_through_the_binary() {
    let dir = root().join("crates/sfc-sim/tests/semantics");
    let out = sfc_in(&dir, &["sim", "55_interfaces.st", "--scenario", "55_interfaces.scenario.toml"]);
    assert_eq!(out.status.code(), Some(0), "{}", both(&out));
    assert!(stdout(&out).contains("PASS 55_interfaces.scenario.toml"), "{}", both(&out));

    let d = temp_dir("interface-none");
    std::fs::write(
        d.join("none.st"),
        "INTERFACE I_Dev\n    METHOD Poll : INT\n    END_METHOD\nEND_INTERFACE\n\n\
         PROGRAM Main\n    VAR\n        Dev : I_Dev;\n        x : INT;\n    END_VAR\n    x := Dev.Poll();\nEND_PROGRAM\n",
    )
    .unwrap();
    let out = sfc_in(&d, &["sim", "none.st", "--scans", "1"]);
    assert_eq!(out.status.code(), Some(1), "{}", both(&out));
    assert!(stderr(&out).contains("an interface that designates nothing (0) is used"), "{}", both(&out));
    assert!(stderr(&out).contains("none.st:11:10"), "{}", both(&out));
}

/// Pointer arithmetic is checked but not simulated (addresses are variables here, not bytes):
/// `sim` of the POU says so at the expression, and a POU that does not use it still runs.
#[test]
fn pointer_arithmetic_says_it_is_not_simulated() {
    let d = temp_dir("pointer-arithmetic");
    std::fs::write(
        d.join("ptr.st"),
        "PROGRAM Shift\n    VAR\n        p : POINTER TO BYTE;\n        b : ARRAY [0..3] OF BYTE;\n    END_VAR\n    \
         p := ADR(b) + 2;\nEND_PROGRAM\n\nPROGRAM Index\n    VAR\n        p : POINTER TO BYTE;\n        \
         b : ARRAY [0..3] OF BYTE;\n        x : BYTE;\n    END_VAR\n    p := ADR(b);\n    p[2] := 7;\n    x := b[2];\nEND_PROGRAM\n",
    )
    .unwrap();
    let out = sfc_in(&d, &["check", "ptr.st"]);
    assert_eq!(out.status.code(), Some(0), "pointer arithmetic type-checks: {}", both(&out));
    let out = sfc_in(&d, &["sim", "ptr.st", "--pou", "Shift", "--scans", "1"]);
    assert_eq!(out.status.code(), Some(1), "{}", both(&out));
    assert!(stderr(&out).contains("pointer arithmetic is not simulated"), "{}", both(&out));
    assert!(stderr(&out).contains("ptr.st:6:10"), "{}", both(&out));
    let out = sfc_in(&d, &["sim", "ptr.st", "--pou", "Index", "--scans", "1", "--trace", "-"]);
    assert_eq!(out.status.code(), Some(0), "{}", both(&out));
    assert!(stdout(&out).contains("\"x\":7"), "{}", both(&out));
}

/// The `codesys` profile, rule by rule (`crates/sfc-sim/tests/codesys/`): each chart run
/// through the binary with its scenario gives exactly the trace derived by hand from CODESYS's
/// online help and written beside it (`*.trace.csv`), and its scenario passes.
#[test]
fn codesys_rules_give_the_traces_derived_by_hand() {
    rules_give_the_traces_derived_by_hand("codesys", 12);
}

/// The `logix` profile, rule by rule (`crates/sfc-sim/tests/logix/`): the same, with the traces
/// derived by hand from Rockwell's SFC manual (1756-PM006) and Logix Designer's help.
#[test]
fn logix_rules_give_the_traces_derived_by_hand() {
    rules_give_the_traces_derived_by_hand("logix", 11);
}

/// The `graph` profile, rule by rule (`crates/sfc-sim/tests/graph/`): the traces derived by hand
/// from the S7-GRAPH manual.
#[test]
fn graph_rules_give_the_traces_derived_by_hand() {
    rules_give_the_traces_derived_by_hand("graph", 10);
}

fn rules_give_the_traces_derived_by_hand(profile: &str, at_least: usize) {
    let dir = root().join("crates/sfc-sim/tests").join(profile);
    let out_dir = temp_dir(&format!("{profile}-rules"));
    let mut charts: Vec<PathBuf> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "st"))
        .collect();
    charts.sort();
    assert!(charts.len() >= at_least, "the {profile} fixtures: {}", charts.len());
    let readme = std::fs::read_to_string(dir.join("README.md")).unwrap();
    let mut failures = Vec::new();
    for chart in &charts {
        let stem = chart.file_stem().unwrap().to_string_lossy().into_owned();
        assert!(readme.contains(&format!("`{stem}.st`")), "{stem} is listed in README.md");
        let scenario = dir.join(format!("{stem}.scenario.toml"));
        let expected = std::fs::read_to_string(dir.join(format!("{stem}.trace.csv")))
            .unwrap_or_else(|_| panic!("{stem}.trace.csv beside the chart"));
        let trace = out_dir.join(format!("{stem}.csv"));
        let o = sfc(&[
            "sim",
            chart.to_str().unwrap(),
            "--scenario",
            scenario.to_str().unwrap(),
            "--trace",
            trace.to_str().unwrap(),
        ]);
        if !o.status.success() {
            failures.push(format!("{stem}: exit {:?}\n{}", o.status.code(), both(&o)));
            continue;
        }
        let actual = std::fs::read_to_string(&trace).unwrap();
        if actual != expected {
            failures.push(format!("{stem}: trace differs\n--- expected\n{expected}--- actual\n{actual}"));
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

/// `sfc check --profile logix` warns where a Logix controller behaves differently from IEC
/// 61131-3: the first call's transitions (SFC0921), P (SFC0922), and under "Don't scan" the
/// missing final run of N, L and D actions (SFC0923), which "Programmatic reset" keeps; a chart
/// set to "Automatic reset" is told that its postscan is not simulated (SFC0604).
#[test]
fn check_profile_logix_lists_the_differences() {
    let dir = root().join("crates/sfc-sim/tests/logix");
    let codes = |file: &str| -> Vec<String> {
        let o = sfc(&["check", "--profile", "logix", "--format", "json", dir.join(file).to_str().unwrap()]);
        let out = String::from_utf8_lossy(&o.stdout).into_owned();
        let mut codes: Vec<String> =
            out.split("\"code\": \"").skip(1).map(|s| s.split('"').next().unwrap().to_string()).collect();
        codes.sort();
        codes.dedup();
        codes
    };
    assert_eq!(codes("02_dont_scan.st"), ["SFC0921", "SFC0922", "SFC0923"]);
    let programmatic = codes("03_programmatic_reset.st");
    assert!(
        programmatic.contains(&"SFC0922".to_string()) && !programmatic.contains(&"SFC0923".to_string()),
        "{programmatic:?}"
    );
    let text = "{attribute 'sfc.dialect' := 'logix'}\n{attribute 'sfc.logix.lastscan' := 'AutomaticReset'}\n\
        PROGRAM P\nVAR_INPUT Go : BOOL; END_VAR\nINITIAL_STEP A: END_STEP\n\
        TRANSITION FROM A TO B := Go; END_TRANSITION\nSTEP B: END_STEP\n\
        TRANSITION FROM B TO A := NOT Go; END_TRANSITION\nEND_PROGRAM\n";
    let d = temp_dir("logix-auto");
    std::fs::write(d.join("auto.st"), text).unwrap();
    let o = sfc(&["check", d.join("auto.st").to_str().unwrap()]);
    let err = both(&o);
    assert!(err.contains("warning[SFC0604]") && err.contains("simulated as \"Don't scan\""), "{err}");
    std::fs::write(d.join("bad.st"), text.replace("AutomaticReset", "Automatic")).unwrap();
    let o = sfc(&["check", d.join("bad.st").to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(1), "{}", both(&o));
    assert!(both(&o).contains("error[SFC0601]"), "{}", both(&o));
}

/// A chart file marked `sfc.dialect 'logix'` (imported or converted from an L5X export) runs
/// with `logix` when neither the command line nor the scenario names a profile, and says so;
/// `--profile iec` runs IEC 61131-3's rules instead, which differ in the first call.
#[test]
fn a_logix_chart_runs_with_logix_and_says_so() {
    let chart = root().join("crates/sfc-sim/tests/logix/09_file_chooses_logix.st");
    let o = sfc(&["sim", chart.to_str().unwrap(), "--scans", "2", "--set", "Start=TRUE", "--trace", "-"]);
    assert!(o.status.success(), "{}", both(&o));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("simulated with profile logix:") && err.contains("was converted from a Studio 5000 export"),
        "{err}"
    );
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(out.lines().next().unwrap().contains(r#""active":["Running"]"#), "first call fires: {out}");
    let o = sfc(&[
        "sim",
        chart.to_str().unwrap(),
        "--scans",
        "2",
        "--set",
        "Start=TRUE",
        "--trace",
        "-",
        "--profile",
        "iec",
    ]);
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(out.lines().next().unwrap().contains(r#""active":["Stopped"]"#), "IEC's scan 0 fires nothing: {out}");
    assert!(!String::from_utf8_lossy(&o.stderr).contains("profile logix"));
}

/// A machine in the shape of a CODESYS export (eleven function blocks whose SFC actions call
/// each other's actions, step actions, N and R on an SFC action) driven through its modes under
/// `codesys`, with expectations on steps of nested charts by path.
#[test]
fn the_bottling_line_runs_through_its_modes() {
    let o = sfc(&["test", "tests/corpus/real/codesys/bottling_line_modes.scenario.toml"]);
    assert!(o.status.success(), "{}", both(&o));
    assert!(stdout(&o).contains("1 passed"), "{}", both(&o));
}

/// `--explain` says when a TRUE transition waits for its step's minimum time (`sfc.min_time`).
#[test]
fn explain_names_a_minimum_time_being_waited_for() {
    let o = sfc(&[
        "sim",
        "crates/sfc-sim/tests/codesys/10_minimum_time.st",
        "--profile",
        "codesys",
        "--set",
        "Go=TRUE",
        "--scans",
        "3",
        "--explain",
    ]);
    assert!(o.status.success(), "{}", both(&o));
    assert!(
        both(&o).contains("T2 := Go is TRUE with Go = TRUE; waits for the minimum time of Hold (T#20ms of T#30ms)"),
        "{}",
        both(&o)
    );
}

/// `sfc check --profile codesys` warns where the chart behaves differently under CODESYS, or
/// where CODESYS refuses it (SFC0911–SFC0913), located in the chart; without the profile, not.
#[test]
fn check_with_the_codesys_profile_warns_of_the_differences() {
    let chart = "crates/sfc-cli/tests/codesys/differences.st";
    let o = sfc(&["check", chart, "--profile", "codesys", "--color", "never"]);
    assert!(o.status.success(), "warnings only: {}", both(&o));
    let text = both(&o);
    for expected in [
        "warning[SFC0911]: the PRIORITY of TB is ignored under CODESYS",
        "warning[SFC0912]: TA is already tested in the first call under CODESYS",
        "warning[SFC0912]: TB is already tested in the first call under CODESYS",
        "warning[SFC0913]: `Blink` is associated in `Cell`'s chart and in the chart of its action `Seq`",
    ] {
        assert!(text.contains(expected), "missing {expected:?}\n{text}");
    }
    let plain = both(&sfc(&["check", chart, "--color", "never"]));
    assert!(!plain.contains("SFC091"), "{plain}");
}

/// A CODESYS export converted to text (`sfc build X.xml --target text`) still runs by CODESYS's
/// rules, and says so; an IEC text written by hand does not.
#[test]
fn text_converted_from_a_codesys_export_runs_with_codesys() {
    let d = temp_dir("converted");
    let st = d.join("final_scan.st");
    let o = sfc(&[
        "build",
        "crates/sfc-cli/tests/profile/final_scan.codesys.xml",
        "--target",
        "text",
        "-o",
        st.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", both(&o));
    let o = sfc(&["sim", st.to_str().unwrap(), "--scans", "2"]);
    assert!(o.status.success(), "{}", both(&o));
    assert!(stderr(&o).contains("was converted from a CODESYS export (--profile iec"), "{}", both(&o));
    assert!(stdout(&o).contains("profile codesys"), "{}", both(&o));
    let o = sfc(&["sim", st.to_str().unwrap(), "--scans", "2", "--profile", "iec"]);
    assert!(!stderr(&o).contains("converted from"), "{}", both(&o));
    let o = sfc(&["sim", "examples/blinker/blinker.st", "--scans", "2"]);
    assert!(stdout(&o).contains("profile iec") && !stderr(&o).contains("note: simulated with"), "{}", both(&o));
}
