//! Witness replay: every fixture under `tests/replay/` states witnesses inline and what the
//! replay must find for them:
//!
//! - `(*! replay T1,T3 -> {S2,S4} *)`: a schedule exists and the active set after the last
//!   firing is exactly `{S2, S4}`; `unsafe S3` instead of `-> {…}` asks for an `unsafe` event
//!   of S3 in the last firing scan; with neither, the witness just has to fire. An optional
//!   `scans 1,202` gives the scan of each firing.
//! - `(*! blocked T1,T2 at 1 *)` (with an optional goal as above): no schedule, and the
//!   transition at position 1 of the witness is the one that cannot be fired (`at 2` for a
//!   two-transition witness means: both fire, the goal is not reached).
//!
//! Every schedule found is written as a scenario beside a copy of the chart and run with
//! `sfc_sim::scenario`, which must pass; the same scenario without its input changes must
//! fail whenever the schedule changes inputs, so the scenario's checks have teeth.

use sfc_analysis::replay::{replay, Goal, ReplayFailure, ReplayOptions, Schedule};
use sfc_model::{check_source, Chart, CheckOptions};
use std::path::{Path, PathBuf};

#[derive(Debug)]
struct Case {
    line: usize,
    witness: Vec<String>,
    goal: GoalText,
    scans: Option<Vec<u64>>,
    blocked_at: Option<usize>,
}

#[derive(Debug)]
enum GoalText {
    Situation(Vec<String>),
    Unsafe(String),
    Fired,
}

fn parse_cases(text: &str) -> Vec<Case> {
    let mut out = Vec::new();
    for (n, line) in text.lines().enumerate() {
        let Some(start) = line.find("(*!") else { continue };
        let Some(end) = line[start..].find("*)") else { panic!("line {}: unterminated directive", n + 1) };
        let body = line[start + 3..start + end].trim();
        let (kind, rest) = body.split_once(' ').unwrap_or((body, ""));
        let blocked = match kind {
            "replay" => false,
            "blocked" => true,
            other => panic!("line {}: unknown directive `{other}`", n + 1),
        };
        let mut words = rest.split_whitespace().peekable();
        let witness: Vec<String> = match words.peek() {
            Some(w) if !w.starts_with("->") && *w != "unsafe" && *w != "at" && *w != "scans" => {
                words.next().unwrap_or_default().split(',').filter(|s| !s.is_empty()).map(str::to_string).collect()
            }
            _ => Vec::new(),
        };
        let mut case = Case { line: n + 1, witness, goal: GoalText::Fired, scans: None, blocked_at: None };
        while let Some(w) = words.next() {
            match w {
                "->" => {
                    let set = words.next().unwrap_or_else(|| panic!("line {}: `->` without a set", n + 1));
                    let inner = set.trim_start_matches('{').trim_end_matches('}');
                    case.goal =
                        GoalText::Situation(inner.split(',').filter(|s| !s.is_empty()).map(str::to_string).collect());
                }
                "unsafe" => {
                    case.goal = GoalText::Unsafe(words.next().unwrap_or_else(|| panic!("line {}: step?", n + 1)).into())
                }
                "scans" => {
                    let list = words.next().unwrap_or_else(|| panic!("line {}: scans?", n + 1));
                    case.scans = Some(list.split(',').map(|s| s.parse().expect("scan number")).collect());
                }
                "at" => {
                    let k = words.next().unwrap_or_else(|| panic!("line {}: at?", n + 1));
                    case.blocked_at = Some(k.parse().expect("index"));
                }
                other => panic!("line {}: unexpected `{other}`", n + 1),
            }
        }
        assert_eq!(blocked, case.blocked_at.is_some(), "line {}: `blocked` needs `at N` (and only it)", n + 1);
        out.push(case);
    }
    out
}

fn chart_of(name: &str, text: &str) -> Chart {
    let checked = check_source(0, name, text, &CheckOptions { keep_types: true, ..Default::default() });
    let errors: Vec<String> = checked.diagnostics.iter().filter(|d| d.is_error()).map(|d| format!("{d:?}")).collect();
    assert!(errors.is_empty(), "{name} has errors: {errors:#?}");
    checked.charts.into_iter().next().unwrap_or_else(|| panic!("{name}: no chart"))
}

fn fixtures() -> Vec<PathBuf> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/replay");
    let mut files: Vec<PathBuf> = std::fs::read_dir(&dir)
        .expect("tests/replay")
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|x| x == "st"))
        .collect();
    files.sort();
    files
}

/// A fresh directory under the system's temporary directory.
fn scratch(tag: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("sfc-replay-{}-{tag}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("temp dir");
    dir
}

/// Writes the chart and the schedule's scenario, runs it, returns the failures (empty when it
/// passed).
fn run_scenario(dir: &Path, file: &str, text: &str, scenario: &str, tag: &str) -> Vec<String> {
    std::fs::write(dir.join(file), text).expect("write chart");
    let path = dir.join(format!("{tag}.scenario.toml"));
    std::fs::write(&path, scenario).expect("write scenario");
    match sfc_sim::scenario::run_path(&path) {
        Ok(outcome) => {
            let mut f = outcome.failures.clone();
            if let Some(e) = outcome.error {
                f.push(e);
            }
            f
        }
        Err(e) => vec![format!("invalid scenario: {e}\n{scenario}")],
    }
}

fn goal_of(chart: &Chart, g: &GoalText, where_: &str) -> Goal {
    let step = |n: &String| chart.step(n).unwrap_or_else(|| panic!("{where_}: no step {n}"));
    match g {
        GoalText::Situation(v) => Goal::Situation(v.iter().map(step).collect()),
        GoalText::Unsafe(s) => Goal::Unsafe(step(s)),
        GoalText::Fired => Goal::Fired,
    }
}

fn check_schedule(chart: &Chart, case: &Case, goal: &Goal, s: &Schedule, where_: &str) {
    assert_eq!(s.firings.len(), case.witness.len(), "{where_}: one firing per witness transition");
    assert!(s.firings.windows(2).all(|w| w[0] < w[1]), "{where_}: firings in increasing scans: {:?}", s.firings);
    assert!(s.firings.first().is_none_or(|&f| f >= 1), "{where_}: nothing fires in scan 0");
    if let Some(scans) = &case.scans {
        assert_eq!(&s.firings, scans, "{where_}: firing scans");
    }
    assert_eq!(s.last_scan, s.firings.last().copied().unwrap_or(0));
    assert!(s.inputs.windows(2).all(|w| w[0].scan <= w[1].scan), "{where_}: inputs in scan order");
    assert!(s.inputs.iter().all(|i| i.time == i.scan as i64 * s.period && i.scan >= 1 && i.scan <= s.last_scan));
    if let Goal::Situation(steps) = goal {
        let mut want: Vec<String> = steps.iter().map(|&x| chart.steps[x].name.clone()).collect();
        want.sort();
        assert_eq!(s.final_active, want, "{where_}: final situation");
    }
    let lines = s.describe(chart);
    for (k, name) in case.witness.iter().enumerate() {
        let line = format!("scan {}: {name} fires", s.firings[k]);
        assert!(lines.contains(&line), "{where_}: `{line}` missing from {lines:#?}");
    }
    for i in &s.inputs {
        assert!(lines.iter().any(|l| l.starts_with(&format!("scan {} (", i.scan)) && l.contains(&i.name)));
    }
}

#[test]
fn fixtures_replay_as_stated() {
    let opts = ReplayOptions::default();
    let mut count = 0;
    let mut failures: Vec<String> = Vec::new();
    for path in fixtures() {
        let file = path.file_name().and_then(|f| f.to_str()).unwrap_or("chart.st").to_string();
        let text = std::fs::read_to_string(&path).expect("read fixture");
        let chart = chart_of(&file, &text);
        let cases = parse_cases(&text);
        assert!(!cases.is_empty(), "{file}: no `(*! … *)` directive");
        let dir = scratch(file.trim_end_matches(".st"));
        for case in &cases {
            count += 1;
            let where_ = format!("{file}:{}", case.line);
            let witness: Vec<usize> = case
                .witness
                .iter()
                .map(|n| chart.transition(n).unwrap_or_else(|| panic!("{where_}: no transition {n}")))
                .collect();
            let goal = goal_of(&chart, &case.goal, &where_);
            let started = std::time::Instant::now();
            let result = replay(&file, &text, &chart, &witness, &goal, &opts);
            let took = started.elapsed();
            match (result, case.blocked_at) {
                (Ok(s), None) => {
                    check_schedule(&chart, case, &goal, &s, &where_);
                    let tag = format!("line{}", case.line);
                    let scenario = s.to_scenario(&chart, &goal, &format!("{where_}: {}", case.witness.join(", ")));
                    let f = run_scenario(&dir, &file, &text, &scenario, &tag);
                    if !f.is_empty() {
                        failures.push(format!("{where_}: the scenario fails:\n{}\n{scenario}", f.join("\n")));
                    }
                    if !s.inputs.is_empty() {
                        let mut bare = s.clone();
                        bare.inputs.clear();
                        let scenario = bare.to_scenario(&chart, &goal, "without inputs");
                        let f = run_scenario(&dir, &file, &text, &scenario, &format!("{tag}-bare"));
                        if f.is_empty() {
                            failures.push(format!("{where_}: the scenario passes even without its inputs"));
                        }
                    }
                    eprintln!("{where_}: replayed in {took:?}, firings {:?}", s.firings);
                }
                (Err(ReplayFailure::Blocked { index, reason }), Some(at)) => {
                    if index != at {
                        failures.push(format!("{where_}: blocked at {index}, expected {at}: {reason}"));
                    }
                    assert!(!reason.is_empty());
                    eprintln!("{where_}: blocked at {index} in {took:?}: {reason}");
                }
                (Ok(s), Some(at)) => {
                    failures.push(format!("{where_}: expected blocked at {at}, replayed: {:#?}", s.describe(&chart)))
                }
                (Err(e), _) => failures.push(format!("{where_}: {e:?}")),
            }
        }
        let _ = std::fs::remove_dir_all(&dir);
    }
    assert!(failures.is_empty(), "{}", failures.join("\n\n"));
    assert!(count >= 20, "only {count} cases");
}

#[test]
fn chart_with_errors_is_not_simulatable() {
    let text = "PROGRAM P\n    VAR_INPUT Go : BOOL; END_VAR\n    INITIAL_STEP S0: END_STEP\n    TRANSITION T1 FROM S0 TO S1 := Go; END_TRANSITION\n    STEP S1: END_STEP\nEND_PROGRAM\n";
    let chart = chart_of("p.st", text);
    let broken = text.replace(":= Go;", ":= Go + 1;");
    let r = replay("p.st", &broken, &chart, &[0], &Goal::Fired, &ReplayOptions::default());
    match r {
        Err(ReplayFailure::NotSimulatable(m)) => assert!(m.starts_with("SFC03"), "{m}"),
        other => panic!("expected NotSimulatable, got {other:?}"),
    }
    // The intact chart replays, and an out-of-range transition id is reported, not a panic.
    assert!(replay("p.st", text, &chart, &[0], &Goal::Fired, &ReplayOptions::default()).is_ok());
    let r = replay("p.st", text, &chart, &[7], &Goal::Fired, &ReplayOptions::default());
    assert!(matches!(r, Err(ReplayFailure::Blocked { index: 0, .. })), "{r:?}");
    let r = replay("p.st", text, &chart, &[0], &Goal::Unsafe(9), &ReplayOptions::default());
    assert!(matches!(r, Err(ReplayFailure::Blocked { index: 1, .. })), "{r:?}");
}

#[test]
fn empty_witness_checks_the_initial_situation() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/replay/parallel.st");
    let text = std::fs::read_to_string(&path).expect("fixture");
    let chart = chart_of("parallel.st", &text);
    let s0 = chart.step("S0").expect("S0");
    let s = replay("parallel.st", &text, &chart, &[], &Goal::Situation(vec![s0]), &ReplayOptions::default())
        .expect("initial situation");
    assert_eq!((s.last_scan, s.firings.len(), s.inputs.len()), (0, 0, 0));
    assert_eq!(s.final_active, vec!["S0".to_string()]);
    let s1 = chart.step("S1").expect("S1");
    let r = replay("parallel.st", &text, &chart, &[], &Goal::Situation(vec![s1]), &ReplayOptions::default());
    assert!(matches!(r, Err(ReplayFailure::Blocked { index: 0, .. })), "{r:?}");
}

#[test]
fn budget_is_respected() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/replay/step_time.st");
    let text = std::fs::read_to_string(&path).expect("fixture");
    let chart = chart_of("step_time.st", &text);
    let w = vec![chart.transition("TGo").expect("TGo"), chart.transition("TLong").expect("TLong")];
    let tight = ReplayOptions { max_tries: 100, ..ReplayOptions::default() };
    let r = replay("step_time.st", &text, &chart, &w, &Goal::Fired, &tight);
    assert!(matches!(r, Err(ReplayFailure::Budget { index: 1 })), "{r:?}");
    // Waiting is bounded too: 2.01 s are 201 scans, more than 150 allowed.
    let short = ReplayOptions { max_wait_scans: 150, ..ReplayOptions::default() };
    let r = replay("step_time.st", &text, &chart, &w, &Goal::Fired, &short);
    assert!(matches!(r, Err(ReplayFailure::Blocked { index: 1, .. })), "{r:?}");
    let enough = ReplayOptions { max_wait_scans: 200, ..ReplayOptions::default() };
    let s = replay("step_time.st", &text, &chart, &w, &Goal::Fired, &enough).expect("200 waits suffice");
    assert_eq!(s.firings, vec![1, 202]);
}

#[test]
fn describe_and_scenario_text() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/replay/compare.st");
    let text = std::fs::read_to_string(&path).expect("fixture");
    let chart = chart_of("compare.st", &text);
    let w: Vec<usize> = ["TFill", "THot", "TWait"].iter().map(|n| chart.transition(n).expect("t")).collect();
    let goal = Goal::Fired;
    let s = replay("some/dir/compare.st", &text, &chart, &w, &goal, &ReplayOptions::default()).expect("replays");
    let lines = s.describe(&chart);
    assert_eq!(
        lines,
        vec![
            "scan 1 (T#10ms): Level := 51",
            "scan 1: TFill fires",
            "scan 2 (T#20ms): Temp := 81.5",
            "scan 2: THot fires",
            "scan 3 (T#30ms): Delay := T#1s1ms",
            "scan 3 (T#30ms): Recipe := Wash",
            "scan 3: TWait fires",
            "scan 3: active steps Waiting",
        ]
    );
    let toml = s.to_scenario(&chart, &goal, "compare");
    assert!(toml.contains("chart = \"compare.st\"\n"), "{toml}");
    assert!(toml.contains("set = { \"Delay\" = \"T#1s1ms\", \"Recipe\" = \"Wash\" }"), "{toml}");
    assert!(toml.contains("set = { \"Temp\" = 81.5 }"), "{toml}");
    assert!(toml.contains("scans = 4\n"), "{toml}");
}

/// Charts a user wrote: the examples and the valid fixtures of the checker.
fn user_charts() -> Vec<PathBuf> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let mut out = Vec::new();
    let mut dirs = vec![root.join("examples"), root.join("tests/fixtures/valid")];
    while let Some(d) = dirs.pop() {
        let Ok(rd) = std::fs::read_dir(&d) else { continue };
        for e in rd.flatten() {
            let p = e.path();
            if p.is_dir() {
                dirs.push(p);
            } else if p.extension().is_some_and(|x| x == "st") {
                out.push(p);
            }
        }
    }
    out.sort();
    out
}

/// A walk of the net with guards as free inputs (one enabled transition per step, chosen by
/// a fixed pseudo-random sequence), as the net analysis would produce a witness.
fn net_walk(chart: &Chart, len: usize, seed: &mut u64) -> (Vec<usize>, Vec<usize>) {
    let mut active: Vec<usize> = chart.initial_steps();
    let mut witness = Vec::new();
    for _ in 0..len {
        let enabled: Vec<usize> = (0..chart.transitions.len())
            .filter(|&t| {
                let f = &chart.transitions[t].from;
                !f.is_empty() && f.iter().all(|s| active.contains(s))
            })
            .collect();
        if enabled.is_empty() {
            break;
        }
        *seed = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        let t = enabled[((*seed >> 33) as usize) % enabled.len()];
        active.retain(|s| !chart.transitions[t].from.contains(s));
        for &s in &chart.transitions[t].to {
            if !active.contains(&s) {
                active.push(s);
            }
        }
        witness.push(t);
    }
    active.sort_unstable();
    (witness, active)
}

#[test]
fn net_walks_of_user_charts_replay_or_fail_cleanly() {
    let opts = ReplayOptions::default();
    let mut seed = std::env::var("SFC_REPLAY_SEED").ok().and_then(|s| s.parse().ok()).unwrap_or(20_240_601u64);
    let (mut replayed, mut blocked, mut budget, mut charts) = (0, 0, 0, 0);
    let mut slowest = std::time::Duration::ZERO;
    let mut failures = Vec::new();
    for path in user_charts() {
        let text = std::fs::read_to_string(&path).expect("read");
        let name = path.file_name().and_then(|f| f.to_str()).unwrap_or("chart.st").to_string();
        let checked = check_source(0, &name, &text, &CheckOptions { keep_types: true, ..Default::default() });
        if checked.has_errors() {
            continue;
        }
        let dir = scratch(&format!("walk-{}", name.trim_end_matches(".st")));
        for chart in &checked.charts {
            charts += 1;
            for walk in 0..4 {
                let (witness, situation) = net_walk(chart, 1 + walk * 2, &mut seed);
                let goal = Goal::Situation(situation);
                let started = std::time::Instant::now();
                let r = replay(&name, &text, chart, &witness, &goal, &opts);
                slowest = slowest.max(started.elapsed());
                let again = replay(&name, &text, chart, &witness, &goal, &opts);
                let names: Vec<&str> = witness.iter().map(|&t| chart.transitions[t].name.as_str()).collect();
                let where_ = format!("{name} ({}) walk {}", chart.pou, names.join(","));
                if r != again {
                    failures.push(format!("{where_}: not deterministic"));
                }
                match r {
                    Ok(s) => {
                        replayed += 1;
                        let scenario = s.to_scenario(chart, &goal, &where_);
                        let f = run_scenario(&dir, &name, &text, &scenario, &format!("{}-{walk}", chart.pou));
                        if !f.is_empty() {
                            failures.push(format!("{where_}: scenario fails: {}\n{scenario}", f.join("\n")));
                        }
                    }
                    Err(ReplayFailure::Blocked { index, reason }) => {
                        blocked += 1;
                        eprintln!("{where_}: blocked at {index}: {reason}");
                    }
                    Err(ReplayFailure::Budget { .. }) => budget += 1,
                    Err(ReplayFailure::Runaway { error, .. }) => {
                        failures.push(format!("{where_}: a scan ran away: {error:?}"));
                    }
                    Err(ReplayFailure::NotSimulatable(m)) => {
                        // A chart of another POU than the one simulated alone, or a target
                        // chart the simulator does not run: allowed, but say which.
                        eprintln!("{where_}: not simulatable: {m}");
                    }
                }
            }
        }
        let _ = std::fs::remove_dir_all(&dir);
    }
    eprintln!(
        "{charts} charts: {replayed} walks replayed, {blocked} blocked, {budget} out of budget; slowest {slowest:?}"
    );
    assert!(failures.is_empty(), "{}", failures.join("\n\n"));
    assert!(replayed >= 40, "only {replayed} walks replayed");
}

/// Every chart the checker's fixtures hold, errors included, and the public corpus: the
/// replay answers (a schedule, blocked, budget or not simulatable) and never panics.
#[test]
fn never_panics_on_any_fixture() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let mut files = Vec::new();
    let mut dirs =
        vec![root.join("tests/fixtures"), root.join("../shared/corpus/matiec"), root.join("../shared/corpus/verifaps")];
    while let Some(d) = dirs.pop() {
        let Ok(rd) = std::fs::read_dir(&d) else {
            eprintln!("skipping {} (missing)", d.display());
            continue;
        };
        for e in rd.flatten() {
            let p = e.path();
            if p.is_dir() {
                dirs.push(p);
            } else if p.extension().is_some_and(|x| x == "st" || x == "txt") {
                files.push(p);
            }
        }
    }
    files.sort();
    let opts = ReplayOptions { max_tries: 2_000, max_wait_scans: 300 };
    let mut seed = 7u64;
    let (mut runs, mut not_sim) = (0, 0);
    for path in files {
        let Ok(text) = std::fs::read_to_string(&path) else { continue };
        let name = path.file_name().and_then(|f| f.to_str()).unwrap_or("x.st").to_string();
        let checked = check_source(0, &name, &text, &CheckOptions { keep_types: true, ..Default::default() });
        for chart in &checked.charts {
            let (witness, situation) = net_walk(chart, 4, &mut seed);
            for goal in
                [Goal::Situation(situation.clone()), Goal::Fired, Goal::Unsafe(situation.first().copied().unwrap_or(0))]
            {
                runs += 1;
                if let Err(ReplayFailure::NotSimulatable(_)) = replay(&name, &text, chart, &witness, &goal, &opts) {
                    not_sim += 1;
                }
            }
        }
    }
    eprintln!("{runs} replays, {not_sim} not simulatable");
    assert!(runs > 100 && not_sim > 0 && not_sim < runs, "{runs} runs, {not_sim} not simulatable");
}

/// A witness whose first firing enters a step with a loop that never ends: the replay stops at
/// that scan with a located runaway instead of trying every input for every scan, and
/// `sfc check` reports the loop (SFC0510) beside the finding, which stays possible.
#[test]
fn a_runaway_scan_ends_the_replay_with_its_location() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/replay/fig68_unsafe.st");
    let text = std::fs::read_to_string(&path).expect("fixture");
    let text = text
        .replace("        g : BOOL;\n    END_VAR", "        g : BOOL;\n    END_VAR\n    VAR n : DINT; END_VAR")
        .replace("    STEP K2: END_STEP", "    STEP K2:\n        Spin(N);\n    END_STEP")
        .replace(
            "END_PROGRAM",
            "    ACTION Spin:\n        WHILE a DO n := n + 1; END_WHILE;\n    END_ACTION\nEND_PROGRAM",
        );
    let chart = chart_of("spin.st", &text);
    let w: Vec<usize> = ["T1", "T3", "T4", "T5", "T1"].iter().map(|n| chart.transition(n).unwrap()).collect();
    let k1 = chart.step("K1").unwrap();
    let started = std::time::Instant::now();
    let r = replay("spin.st", &text, &chart, &w, &Goal::Unsafe(k1), &ReplayOptions::default());
    eprintln!("the replay ended in {:?}", started.elapsed());
    let line = text.lines().position(|l| l.contains("WHILE a DO")).unwrap() as u32 + 1;
    match r {
        Err(ReplayFailure::Runaway { index: 0, error }) => {
            assert_eq!(error.line, line, "{error:?}");
            assert!(error.message.starts_with("runaway scan"), "{}", error.message);
        }
        other => panic!("expected a runaway at the first firing, got {other:?}"),
    }
    let checked =
        sfc_analysis::check_source(0, "spin.st", &text, &CheckOptions { analysis: true, ..Default::default() });
    let runaway = checked.diagnostics.iter().find(|d| d.code == "SFC0510").expect("SFC0510 reported");
    assert_eq!(checked.file.line_col(runaway.span.start).line, line);
    let unsafe_ = checked.diagnostics.iter().find(|d| d.code == "SFC0501").expect("the unsafe finding");
    assert!(unsafe_.notes.iter().any(|n| n.starts_with("possible:") && n.contains("ran away")), "{:?}", unsafe_.notes);
}
