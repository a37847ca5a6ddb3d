//! ATMT/EATMT transition tables.
//!
//! * Fixtures `tests/atmt/NAME.st` with the expected output beside them, exact bytes:
//!   `NAME.atmt` / `NAME.eatmt` (plain build), `NAME.flat.atmt` / `NAME.flat.eatmt` (with
//!   flattening), or `….errors` (one `CODE line:column message` per error). `UPDATE_EXPECT=1`
//!   rewrites the existing expectation files.
//! * Differential tests: random sequential charts (and flattened parallel ones) run in the
//!   simulator and, through their table, in a small ATMT interpreter that follows the block as
//!   the REX SFC Editor manual describes it (the rules of the current state tested from the
//!   top, the first true condition switches the state, one switch per period; the timeout flag
//!   is set once the state has lasted longer than its timeout); same input sequences, same
//!   active state and timeout flag after every scan.
//!
//! `SFC_ATMT_CASES=N` changes the number of random cases (default 300).

use sfc_codegen::atmt::{build_table, flatten, parse_table, seconds, Rule};
use sfc_diagnostics::{Diagnostic, SourceFile};
use sfc_model::{check_source, Chart, CheckOptions, Limits, Target};
use sfc_sim::{SimOptions, Simulation, Value};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

fn dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/atmt")
}

fn checked(text: &str, target: Target) -> (sfc_model::Checked, Chart) {
    let c = check_source(0, "chart.st", text, &CheckOptions { target: Some(target), ..Default::default() });
    let chart = c.charts.first().cloned().expect("the fixture has an SFC POU");
    (c, chart)
}

fn render_errors(file: &SourceFile, diags: &[Diagnostic]) -> String {
    let mut out = String::new();
    for d in diags {
        let lc = file.line_col(d.span.start);
        writeln!(out, "{} {}:{} {}", d.code, lc.line, lc.column, d.message).unwrap();
    }
    out
}

/// Builds one fixture variant: the table text, or the rendered errors.
fn build_variant(text: &str, target: Target, flat: bool) -> Result<String, String> {
    let (c, chart) = checked(text, target);
    // The check must agree with the build: no errors but the ones flattening replaces.
    let check_errors: Vec<&Diagnostic> = c
        .diagnostics
        .iter()
        .filter(|d| d.is_error() && !(flat && matches!(d.code, "SFC0401" | "SFC0403" | "SFC0404" | "SFC0409")))
        .collect();
    match build_table(&chart, target, Limits::of(target, None, None), flat) {
        Ok(out) => {
            assert!(check_errors.is_empty(), "the check reports errors but the table was built: {check_errors:?}");
            assert!(!out.text.contains('\n'), "the table is one line");
            Ok(out.text)
        }
        Err(diags) => {
            assert!(diags.iter().all(|d| d.is_error()));
            Err(render_errors(&c.file, &diags))
        }
    }
}

#[test]
fn fixtures_match_expected() {
    let update = std::env::var_os("UPDATE_EXPECT").is_some();
    let mut ran = 0;
    let mut failures = Vec::new();
    let mut names: Vec<PathBuf> = std::fs::read_dir(dir())
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "st"))
        .collect();
    names.sort();
    for st in names {
        let text = std::fs::read_to_string(&st).unwrap();
        let stem = st.file_stem().unwrap().to_string_lossy().to_string();
        for (suffix, target, flat) in [
            ("atmt", Target::Atmt, false),
            ("eatmt", Target::Eatmt, false),
            ("flat.atmt", Target::Atmt, true),
            ("flat.eatmt", Target::Eatmt, true),
        ] {
            let table = dir().join(format!("{stem}.{suffix}"));
            let errors = dir().join(format!("{stem}.{suffix}.errors"));
            let (path, expected_ok) = if table.exists() {
                (table, true)
            } else if errors.exists() {
                (errors, false)
            } else {
                continue;
            };
            ran += 1;
            let got = build_variant(&text, target, flat);
            let (got_text, ok) = match &got {
                Ok(t) => (t.clone(), true),
                Err(e) => (e.clone(), false),
            };
            if update && ok == expected_ok {
                std::fs::write(&path, &got_text).unwrap();
                continue;
            }
            let want = std::fs::read_to_string(&path).unwrap();
            if ok != expected_ok || got_text != want {
                failures.push(format!(
                    "{}: expected {}:\n{want}\ngot {}:\n{got_text}",
                    path.display(),
                    if expected_ok { "a table" } else { "errors" },
                    if ok { "a table" } else { "errors" }
                ));
            }
        }
    }
    assert!(ran >= 8, "only {ran} fixture variants found");
    assert!(failures.is_empty(), "{}", failures.join("\n\n"));
}

#[test]
fn seed_example_comes_out_byte_for_byte() {
    let text = std::fs::read_to_string(dir().join("seed.st")).unwrap();
    let (_, chart) = checked(&text, Target::Atmt);
    let out = build_table(&chart, Target::Atmt, Limits::of(Target::Atmt, None, None), false).unwrap();
    assert_eq!(out.text.as_bytes(), b"3[0 0 1;1 1 2;2 2 1][8.1 2 1]");
    assert_eq!((out.states, out.rules, out.flattened), (3, 3, None));
    // Flattening a chart without simultaneous branches changes nothing.
    let flat = build_table(&chart, Target::Atmt, Limits::of(Target::Atmt, None, None), true).unwrap();
    assert_eq!(flat, out);
}

#[test]
fn seconds_are_the_shortest_decimal() {
    for (us, s) in [
        (8_100_000, "8.1"),
        (2_000_000, "2"),
        (0, "0"),
        (500_000, "0.5"),
        (1_500, "0.0015"),
        (1, "0.000001"),
        (120_000_000, "120"),
        (10_250_000, "10.25"),
    ] {
        assert_eq!(seconds(us), s);
    }
    let (rules, t) = parse_table("3[0 0 1;1 1 2;2 2 1][8.1 2 1]").unwrap();
    assert_eq!(rules[2], Rule { state: 2, condition: 2, next: 1 });
    assert_eq!(t, vec![8_100_000, 2_000_000, 1_000_000]);
    assert!(parse_table("2[0 0 1][0]").is_none(), "N must match the rules");
    assert_eq!(parse_table("0[][]"), Some((vec![], vec![])));
}

#[test]
fn flattening_reports_its_states_and_respects_the_limits() {
    let text = std::fs::read_to_string(dir().join("twin.st")).unwrap();
    let (_, chart) = checked(&text, Target::Eatmt);
    let limits = Limits::of(Target::Eatmt, None, None);
    let out = build_table(&chart, Target::Eatmt, limits, true).unwrap();
    assert_eq!((out.states, out.rules, out.flattened), (5, 6, Some(5)));
    let note = &out.notes[0];
    assert_eq!(note.code, "SFC0415");
    assert!(note.notes.iter().any(|n| n == "state 3 = {A1, B2}"), "{:?}", note.notes);
    let f = flatten(&chart, Target::Eatmt, limits).unwrap();
    assert_eq!(f.states.len(), 5);
    // Without flattening the AND branches are refused by the target rules.
    let plain = build_table(&chart, Target::Eatmt, limits, false).unwrap_err();
    assert!(plain.iter().all(|d| d.code == "SFC0404") && plain.len() == 2, "{plain:?}");
    // Over the state and rule limits (--nstep / --ntr).
    let err = build_table(&chart, Target::Eatmt, Limits::of(Target::Eatmt, Some(4), None), true).unwrap_err();
    assert_eq!(err[0].code, "SFC0412");
    assert!(matches!(&err[0].witness, Some(sfc_diagnostics::Witness::Firing(w)) if !w.is_empty()));
    let err = build_table(&chart, Target::Eatmt, Limits::of(Target::Eatmt, None, Some(5)), true).unwrap_err();
    assert_eq!(err[0].code, "SFC0413");
    // The refusal names both transitions and how the situation is reached.
    let text = std::fs::read_to_string(dir().join("invalid_parallel.st")).unwrap();
    let (_, chart) = checked(&text, Target::Atmt);
    let err = build_table(&chart, Target::Atmt, Limits::of(Target::Atmt, None, None), true).unwrap_err();
    assert_eq!(err[0].code, "SFC0411");
    assert!(err[0].message.contains("`T2` (C1) and `T3` (C2)"), "{}", err[0].message);
    assert_eq!(err[0].witness, Some(sfc_diagnostics::Witness::Firing(vec!["T1".into()])));
    assert_eq!(err[0].labels.len(), 1);
}

#[test]
fn blank_target_and_missing_initial_step_are_refused() {
    let text = std::fs::read_to_string(dir().join("seed.st")).unwrap();
    let (_, chart) = checked(&text, Target::Atmt);
    let err = build_table(&chart, Target::Blank, Limits::of(Target::Atmt, None, None), false).unwrap_err();
    assert_eq!(err[0].code, "SFC0410");
    let no_init = text.replace("INITIAL_STEP Init", "STEP Init");
    let (_, chart) = checked(&no_init, Target::Atmt);
    let err = build_table(&chart, Target::Atmt, Limits::of(Target::Atmt, None, None), false).unwrap_err();
    assert!(err.iter().any(|d| d.code == "SFC0410"), "{err:?}");
}

// ---------------------------------------------------------------------------------------------
// The interpreter of the block and the differential tests

const PERIOD: i64 = 10_000;
const SCANS: usize = 80;

/// The REX ATMT/EATMT block as the manual describes it.
struct Block {
    rules: Vec<Rule>,
    timeouts: Vec<i64>,
    state: u32,
    /// Time spent in the current state, µs.
    elapsed: i64,
}

impl Block {
    fn new(table: &str) -> Block {
        let (rules, timeouts) = parse_table(table).expect("a well-formed table");
        Block { rules, timeouts, state: 0, elapsed: 0 }
    }
    /// One period: the first rule of the current state whose condition holds switches.
    fn period(&mut self, input: &dyn Fn(u32) -> bool) {
        for r in self.rules.iter().filter(|r| r.state == self.state) {
            let holds = if r.condition >= 1000 { !input(r.condition - 1000) } else { input(r.condition) };
            if holds {
                self.state = r.next;
                self.elapsed = 0;
                return;
            }
        }
        self.elapsed += PERIOD;
    }
    /// The `tout` output.
    fn timed_out(&self) -> bool {
        let t = self.timeouts.get(self.state as usize).copied().unwrap_or(0);
        t > 0 && self.elapsed > t
    }
}

struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        let mut x = self.0;
        x ^= x << 13;
        x ^= x >> 7;
        x ^= x << 17;
        self.0 = x;
        x
    }
    fn below(&mut self, n: usize) -> usize {
        (self.next() % n as u64) as usize
    }
    fn chance(&mut self, percent: usize) -> bool {
        self.below(100) < percent
    }
}

fn cases() -> usize {
    std::env::var("SFC_ATMT_CASES").ok().and_then(|v| v.parse().ok()).unwrap_or(300)
}

/// The spelling of input `i` (maybe negated) in a condition.
fn input_text(rng: &mut Rng, target: Target, i: u32, negated: bool) -> String {
    let name = match target {
        Target::Atmt => format!("C{i}"),
        _ if i >= 16 && rng.chance(50) => format!("c{}.{}", i / 16, i % 16),
        _ => format!("c{i}"),
    };
    match (negated, rng.below(2)) {
        (false, _) => name,
        (true, 0) => format!("NOT {name}"),
        (true, _) => format!("!{name}"),
    }
}

const TIMEOUTS: [&str; 5] = ["T#20ms", "T#50ms", "T#0.1s", "T#35ms", "T#1s"];

/// A random sequential chart: a chain through all steps plus random extra transitions
/// (branches, jumps back, self-loops), random conditions, priorities, tags and timeouts.
fn sequential_chart(rng: &mut Rng, target: Target) -> String {
    let n = 2 + rng.below(9);
    let inputs: Vec<u32> = match target {
        Target::Atmt => (0..5).collect(),
        _ => vec![0, 1, 2, 17, 18],
    };
    let mut tags: Vec<Option<u32>> = vec![None; n];
    if rng.chance(30) {
        // distinct tags, the initial step 0, sometimes leaving gaps
        let mut free: Vec<u32> = (1..(n as u32 + 3)).collect();
        tags[0] = Some(0);
        for tag in tags.iter_mut().skip(1) {
            if rng.chance(70) {
                let k = rng.below(free.len());
                *tag = Some(free.remove(k));
            }
        }
        // untagged steps take the free numbers in order: keep them below the limit
    }
    let mut trans: Vec<(usize, usize, u32, bool, Option<i64>)> = Vec::new();
    let add = |rng: &mut Rng, from: usize, to: usize, trans: &mut Vec<(usize, usize, u32, bool, Option<i64>)>| {
        for _ in 0..4 {
            let i = inputs[rng.below(inputs.len())];
            let neg = target == Target::Eatmt && rng.chance(30);
            if trans.iter().any(|t| t.0 == from && t.1 == to && t.2 == i && t.3 == neg) {
                continue;
            }
            let prio = if rng.chance(25) { Some(rng.below(4) as i64) } else { None };
            trans.push((from, to, i, neg, prio));
            return;
        }
    };
    for s in 0..n - 1 {
        add(rng, s, s + 1, &mut trans);
    }
    for _ in 0..rng.below(n + 2) {
        let (from, to) = (rng.below(n), rng.below(n));
        add(rng, from, to, &mut trans);
    }
    if rng.chance(70) {
        add(rng, n - 1, 0, &mut trans);
    }
    let mut text = format!("{{attribute 'sfc.target' := '{}'}}\nPROGRAM Random\n", target.name());
    for (s, tag) in tags.iter().enumerate() {
        if let Some(tag) = tag {
            writeln!(text, "    {{attribute 'sfc.tag' := '{tag}'}}").unwrap();
        }
        if rng.chance(40) {
            writeln!(text, "    {{attribute 'sfc.timeout' := '{}'}}", TIMEOUTS[rng.below(TIMEOUTS.len())]).unwrap();
        }
        let kw = if s == 0 { "INITIAL_STEP" } else { "STEP" };
        writeln!(text, "    {kw} S{s}: END_STEP").unwrap();
        for (k, t) in trans.iter().enumerate().filter(|(_, t)| t.0 == s) {
            let prio = t.4.map(|p| format!(" (PRIORITY := {p})")).unwrap_or_default();
            let cond = input_text(rng, target, t.2, t.3);
            writeln!(text, "    TRANSITION Tr{k}{prio} FROM S{} TO S{} := {cond}; END_TRANSITION", t.0, t.1).unwrap();
        }
    }
    text.push_str("END_PROGRAM\n");
    text
}

/// A random chart with a simultaneous divergence into two or three branches of one to three
/// steps (some with a selection inside), joined by a simultaneous convergence. Branch
/// conditions come from a small pool so that many charts can be flattened exactly. Returns the
/// chart for the table and the same chart for the simulator, which refuses AND branches in an
/// ATMT/EATMT chart: there without target, its inputs declared, `!` written `NOT`.
fn parallel_chart(rng: &mut Rng, target: Target) -> (String, String) {
    let pool: Vec<(u32, bool)> = match target {
        Target::Atmt => vec![(1, false), (2, false)],
        _ => vec![(1, false), (1, true), (2, false)],
    };
    let mut text = format!("{{attribute 'sfc.target' := '{}'}}\nPROGRAM Random\n", target.name());
    let mut steps = vec!["Idle".to_string()];
    let mut trs: Vec<(Vec<String>, Vec<String>, String)> = Vec::new();
    let mut firsts = Vec::new();
    let mut ends = Vec::new();
    for b in 0..2 + rng.below(2) {
        let len = 1 + rng.below(3);
        let names: Vec<String> = (0..len).map(|i| format!("B{b}S{i}")).collect();
        steps.extend(names.iter().cloned());
        for w in names.windows(2) {
            let (i, neg) = pool[rng.below(pool.len())];
            trs.push((vec![w[0].clone()], vec![w[1].clone()], input_text(rng, target, i, neg)));
            if rng.chance(20) {
                // an alternative back to the branch's first step
                let (i, neg) = pool[rng.below(pool.len())];
                trs.push((vec![w[1].clone()], vec![names[0].clone()], input_text(rng, target, i, neg)));
            }
        }
        firsts.push(names[0].clone());
        ends.push(names[len - 1].clone());
    }
    trs.insert(0, (vec!["Idle".into()], firsts, input_text(rng, target, 0, false)));
    trs.push((ends, vec!["Idle".into()], input_text(rng, target, 3, false)));
    for (i, s) in steps.iter().enumerate() {
        if rng.chance(30) {
            writeln!(text, "    {{attribute 'sfc.timeout' := '{}'}}", TIMEOUTS[rng.below(TIMEOUTS.len())]).unwrap();
        }
        let kw = if i == 0 { "INITIAL_STEP" } else { "STEP" };
        writeln!(text, "    {kw} {s}: END_STEP").unwrap();
    }
    let mut seen = std::collections::HashSet::new();
    for (k, (from, to, cond)) in trs.iter().enumerate() {
        if !seen.insert((from.clone(), to.clone(), cond.to_ascii_uppercase())) {
            continue;
        }
        let list = |v: &Vec<String>| if v.len() > 1 { format!("({})", v.join(", ")) } else { v[0].clone() };
        writeln!(text, "    TRANSITION Tr{k} FROM {} TO {} := {cond}; END_TRANSITION", list(from), list(to)).unwrap();
    }
    text.push_str("END_PROGRAM\n");
    let names: Vec<String> =
        (0..4).map(|i| if target == Target::Atmt { format!("C{i}") } else { format!("c{i}") }).collect();
    let sim_text = text
        .replace(&format!("{{attribute 'sfc.target' := '{}'}}\n", target.name()), "")
        .replace("PROGRAM Random\n", &format!("PROGRAM Random\n    VAR_INPUT {} : BOOL; END_VAR\n", names.join(", ")))
        .replace('!', "NOT ");
    (text, sim_text)
}

/// Runs the chart in the simulator and the table in the block on the same random inputs;
/// `state_steps[k]` are the (sorted) steps state `k` stands for.
fn run_both(text: &str, target: Target, table: &str, state_steps: &[Vec<String>], rng: &mut Rng, timeouts: bool) {
    let mut sim =
        match Simulation::from_source("random.st", text, None, SimOptions { period: PERIOD, ..Default::default() }) {
            Ok(s) => s,
            Err((_, d)) => panic!("the simulator rejects the chart: {d:?}\n{text}"),
        };
    let mut block = Block::new(table);
    let used: Vec<u32> = {
        let mut v: Vec<u32> = block.rules.iter().map(|r| r.condition % 1000).collect();
        v.sort_unstable();
        v.dedup();
        v
    };
    let name = |i: u32| if target == Target::Atmt { format!("C{i}") } else { format!("c{i}") };
    let mut values = vec![false; 256];
    let mut log = String::new();
    for scan in 0..SCANS {
        if scan > 0 {
            for &i in &used {
                if rng.chance(30) {
                    values[i as usize] = !values[i as usize];
                    sim.set(&name(i), Value::Bool(values[i as usize])).unwrap();
                }
            }
        }
        let rec = sim.scan().clone();
        assert!(sim.error().is_none());
        if scan > 0 {
            block.period(&|i| values[i as usize]);
        }
        let want = state_steps.get(block.state as usize).cloned().unwrap_or_default();
        let mut got = rec.active.clone();
        got.sort();
        let on: Vec<String> = used.iter().filter(|&&i| values[i as usize]).map(|&i| name(i)).collect();
        writeln!(log, "scan {scan}: inputs {on:?} -> chart {got:?}, table state {} {want:?}", block.state).unwrap();
        assert_eq!(got, want, "scan {scan}: the table and the chart disagree\n{table}\n{text}\n{log}");
        if timeouts {
            let overdue = !sim.overdue_steps().is_empty();
            assert_eq!(overdue, block.timed_out(), "scan {scan}: timeout flag\n{table}\n{text}\n{log}");
        }
    }
}

#[test]
fn random_sequential_charts_agree_with_the_simulator() {
    let mut rng = Rng(0x51C0_DE0A_7A7E_0001);
    for case in 0..cases() {
        let target = if case % 2 == 0 { Target::Atmt } else { Target::Eatmt };
        let text = sequential_chart(&mut rng, target);
        let (c, chart) = checked(&text, target);
        assert!(!c.has_errors(), "case {case}: {:?}\n{text}", c.diagnostics);
        let out = match build_table(&chart, target, Limits::of(target, None, None), false) {
            Ok(o) => o,
            Err(d) => panic!("case {case}: {d:?}\n{text}"),
        };
        let numbers = chart.state_numbers();
        let mut state_steps = vec![Vec::new(); out.states];
        for (s, &k) in numbers.iter().enumerate() {
            state_steps[k as usize].push(chart.steps[s].name.clone());
        }
        run_both(&text, target, &out.text, &state_steps, &mut rng, true);
    }
}

#[test]
fn random_parallel_charts_flattened_agree_with_the_simulator() {
    let mut rng = Rng(0x51C0_DE0A_7A7E_0002);
    let (mut built, mut refused) = (0, 0);
    for case in 0..cases() {
        let target = if case % 3 == 0 { Target::Atmt } else { Target::Eatmt };
        let (text, sim_text) = parallel_chart(&mut rng, target);
        let (_, chart) = checked(&text, target);
        let limits = Limits::of(target, Some(256), None);
        let out = match build_table(&chart, target, limits, true) {
            Ok(o) => o,
            Err(d) => {
                assert!(d.iter().all(|d| d.code == "SFC0411"), "case {case}: {d:?}\n{text}");
                refused += 1;
                continue;
            }
        };
        built += 1;
        let f = flatten(&chart, target, limits).unwrap();
        assert_eq!(out.flattened, Some(f.states.len()));
        let state_steps: Vec<Vec<String>> = f
            .states
            .iter()
            .map(|s| {
                let mut v: Vec<String> = s.iter().map(|&i| chart.steps[i].name.clone()).collect();
                v.sort();
                v
            })
            .collect();
        run_both(&sim_text, target, &out.text, &state_steps, &mut rng, false);
    }
    println!("{built} parallel charts flattened and compared, {refused} refused (SFC0411)");
    assert!(built >= cases() / 3, "only {built} of {} parallel charts could be flattened ({refused} refused)", cases());
}
