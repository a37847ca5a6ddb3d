//! IEC Structured Text from charts.
//!
//! * Fixtures `tests/st/NAME.st`: every chart of the file is translated (one after the other,
//!   so a chart FB and the PROGRAM calling it both end up plain ST); the result must pass
//!   `sfc_model::check_source` without errors and equal `NAME.st.expected` byte for byte (or,
//!   when the translation is refused, the rendered errors). `UPDATE_EXPECT=1` rewrites them.
//! * Differential tests: the original and the translation run in the simulator side by side,
//!   with the same inputs, compared after every scan: every declared variable of the simulated
//!   POU, every step's `X` and `T`, every action's `Q` and `A` (also inside chart instances),
//!   the chart control variables, and runtime errors. Inputs come from
//!   - every scenario of `examples/` and of the simulator's semantics fixtures (profile `iec`),
//!   - random inputs on the fixtures of `tests/st/`,
//!   - random block-structured charts (sequences, selections with priorities, simultaneous
//!     branches, loops, jumps; all eleven qualifiers with literal and variable durations, BOOL
//!     variables as actions, bodies in ST with RETURN and in IL with jumps, guards in ST and
//!     IL reading inputs, step times, step flags, action flags and counters; supervision
//!     times, SFCInit/SFCPause/SFCQuitError; sometimes the chart is a FUNCTION_BLOCK called by
//!     a PROGRAM only in some scans).
//!
//! The random charts come from `tests/support/random_chart.rs` (shared with
//! `sfc-cli/tests/st_compilers.rs`, which compiles them with MatIEC and STruC++).
//!
//! `SFC_ST_CASES=N` changes the number of random charts (default 200); `SFC_ST_CASE=K` runs
//! case `K` alone and prints both texts.

use sfc_codegen::st::{build_st_file, StDialect, StOptions};
use sfc_diagnostics::Diagnostic;
use sfc_model::{check_source, CheckOptions, Checked};
use sfc_sim::scenario::{self, Scenario};
use sfc_sim::{SimOptions, Simulation, Value};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

#[path = "support/random_chart.rs"]
mod random_chart;
use random_chart::{random_chart, RandomInputs, Rng};

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

fn check(name: &str, text: &str) -> Checked {
    check_source(0, name, text, &CheckOptions::default())
}

/// Translates every chart of `text` as `sfc build --target st` does (`build_st_file`: one after
/// the other, then the `iec` dialect's passes); the errors rendered as text. The result must
/// read back without errors and without warnings of its own, and hold no chart.
fn translate_all(name: &str, text: &str) -> Result<String, String> {
    let first = check(name, text);
    if first.has_errors() {
        return Err(render(&first, &first.diagnostics));
    }
    let (cur, _) = build_st_file(&first, None, &StOptions::default()).map_err(|d| render(&first, &d))?;
    let after = check(name, &cur);
    // (a warning the chart has already, such as an unused variable, may stay)
    let had = |d: &Diagnostic| first.diagnostics.iter().any(|f| f.code == d.code && f.message == d.message);
    let shown: Vec<Diagnostic> = after
        .diagnostics
        .iter()
        .filter(|d| d.is_error() || (d.severity == sfc_diagnostics::Severity::Warning && !had(d)))
        .cloned()
        .collect();
    assert!(shown.is_empty(), "the translation does not read back cleanly:\n{}\n{cur}", render_all(&after, &shown));
    assert!(after.charts.is_empty(), "charts are left: {:?}", after.charts.iter().map(|c| &c.pou).collect::<Vec<_>>());
    Ok(cur)
}

fn render_all(c: &Checked, diags: &[Diagnostic]) -> String {
    let mut out = String::new();
    for d in diags {
        let lc = c.file.line_col(d.span.start);
        writeln!(out, "{} {}:{} {}", d.code, lc.line, lc.column, d.message).unwrap();
    }
    out
}

fn render(c: &Checked, diags: &[Diagnostic]) -> String {
    let mut out = String::new();
    for d in diags.iter().filter(|d| d.is_error()) {
        let lc = c.file.line_col(d.span.start);
        writeln!(out, "{} {}:{} {}", d.code, lc.line, lc.column, d.message).unwrap();
    }
    out
}

// ---------------------------------------------------------------------------------------------
// Fixtures

fn fixtures() -> Vec<PathBuf> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/st");
    let mut v: Vec<PathBuf> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "st"))
        .collect();
    v.sort();
    v
}

#[test]
fn fixtures_match_expected() {
    let update = std::env::var_os("UPDATE_EXPECT").is_some();
    let mut failures = Vec::new();
    let all = fixtures();
    assert!(all.len() >= 6, "fixtures missing");
    for path in all {
        let text = std::fs::read_to_string(&path).unwrap();
        let got = match translate_all(&path.display().to_string(), &text) {
            Ok(t) => t,
            Err(e) => format!("(* refused *)\n{e}"),
        };
        let exp_path = PathBuf::from(format!("{}.expected", path.display()));
        if update {
            std::fs::write(&exp_path, &got).unwrap();
            continue;
        }
        let want = std::fs::read_to_string(&exp_path).unwrap_or_default();
        if want != got {
            failures.push(format!("{}: differs from {}\n{got}", path.display(), exp_path.display()));
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n\n"));
}

#[test]
fn time_literals_are_canonical() {
    use sfc_codegen::st::time_literal;
    assert_eq!(time_literal(0), "T#0s");
    assert_eq!(time_literal(1_500_000), "T#1s500ms");
    assert_eq!(time_literal(2_500), "T#2ms500us");
    assert_eq!(time_literal(-200_000), "T#-200ms");
    assert_eq!(time_literal(90_061_001_001), "T#1d1h1m1s1ms1us");
}

/// `tests/st/dialects/NAME.st`: the file as each `--st-dialect` writes it, equal to
/// `NAME.st.DIALECT.expected` (`UPDATE_EXPECT=1` rewrites them).
#[test]
fn dialects_match_expected() {
    let update = std::env::var_os("UPDATE_EXPECT").is_some();
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/st/dialects");
    let mut failures = Vec::new();
    let mut n = 0;
    for e in std::fs::read_dir(&dir).unwrap() {
        let path = e.unwrap().path();
        if path.extension().is_none_or(|e| e != "st") {
            continue;
        }
        let text = std::fs::read_to_string(&path).unwrap();
        let c = check(&path.display().to_string(), &text);
        assert!(!c.has_errors(), "{}: {}", path.display(), render(&c, &c.diagnostics));
        for dialect in StDialect::ALL {
            n += 1;
            let got = match build_st_file(&c, None, &StOptions { dialect }) {
                Ok((t, notes)) => {
                    let notes: Vec<String> =
                        notes.iter().map(|d| format!("(* {}: {} *)\n", d.code, d.message)).collect();
                    format!("{}{t}", notes.concat())
                }
                Err(d) => format!("(* refused *)\n{}", render(&c, &d)),
            };
            let exp = PathBuf::from(format!("{}.{}.expected", path.display(), dialect.name()));
            if update {
                std::fs::write(&exp, &got).unwrap();
            } else if std::fs::read_to_string(&exp).unwrap_or_default() != got {
                failures.push(format!("{}: differs from {}\n{got}", path.display(), exp.display()));
            }
        }
    }
    assert!(n >= 4, "no dialect fixtures");
    assert!(failures.is_empty(), "{}", failures.join("\n\n"));
}

#[test]
fn matiec_literals_are_exact_in_floating_point() {
    use sfc_codegen::st::matiec_time_literal;
    assert_eq!(matiec_time_literal(0), "T#0s");
    assert_eq!(matiec_time_literal(8_000), "T#8.0000005ms");
    assert_eq!(matiec_time_literal(1_008_000), "T#1s8.0000005ms");
    assert_eq!(matiec_time_literal(533_333), "T#533.3330005ms");
    assert_eq!(matiec_time_literal(-8_000), "T#-8.0000005ms");
    // whole units and 1/64 s steps are exact in binary: written as they are
    assert_eq!(matiec_time_literal(90_000_000), "T#1m30s");
    assert_eq!(matiec_time_literal(1_250_000), "T#1s250ms");
    assert_eq!(matiec_time_literal(15_625), "T#15.625ms");
    assert_eq!(matiec_time_literal(86_400_500_000), "T#1d500ms");
    // The value MatIEC computes: seconds + milliseconds / 1000 in floating point (here f64, the
    // coarsest of the types it is compiled with), times 10^9, truncated: exact for every value.
    for us in (0..3_000_000i64).step_by(997).chain([8_000, 1_000, 2_000, 4_000, 16_000, 1_008_000, 999_999]) {
        let lit = matiec_time_literal(us);
        let body = lit.trim_start_matches("T#");
        let (mut secs, mut ms) = (0f64, 0f64);
        let mut rest = body;
        for (unit, scale) in [("d", 86_400.0), ("h", 3_600.0), ("m", 60.0)] {
            if let Some(i) = rest.find(unit).filter(|&i| !rest[i..].starts_with("ms")) {
                secs += rest[..i].parse::<f64>().unwrap() * scale;
                rest = &rest[i + unit.len()..];
            }
        }
        if let Some(i) = rest.find('s').filter(|&i| !rest[..i].ends_with('m')) {
            secs += rest[..i].parse::<f64>().unwrap();
            rest = &rest[i + 1..];
        }
        if let Some(v) = rest.strip_suffix("ms") {
            ms = v.parse().unwrap();
        }
        let total = secs + ms / 1e3;
        let ns = ((total - total.trunc()) * 1e9) as i64 + total.trunc() as i64 * 1_000_000_000;
        assert_eq!(ns, us * 1000, "{lit}");
    }
}

// ---------------------------------------------------------------------------------------------
// Running both

/// The names compared after every scan, resolved once against the original simulation.
struct Probe {
    keys: Vec<String>,
}

impl Probe {
    fn new(orig: &Simulation, checked: &Checked, generated: &Simulation) -> Probe {
        let mut keys: Vec<String> = orig.trace_vars().into_iter().map(|(n, _)| n).collect();
        let steps = orig.step_names();
        for s in &steps {
            keys.push(format!("{s}.X"));
            keys.push(format!("{s}.T"));
        }
        // Instance prefixes of every chart: those under which all its steps exist.
        for chart in &checked.charts {
            let Some(first) = chart.steps.first() else { continue };
            let prefixes: Vec<String> = steps
                .iter()
                .filter_map(|q| {
                    let p = q.strip_suffix(&first.name)?;
                    (p.is_empty() || p.ends_with('.')).then(|| p.to_string())
                })
                .filter(|p| chart.steps.iter().all(|s| steps.contains(&format!("{p}{}", s.name))))
                .collect();
            for p in prefixes {
                for a in &chart.actions {
                    keys.push(format!("{p}{}.Q", a.name));
                    keys.push(format!("{p}{}.A", a.name));
                }
                for (v, _, _) in sfc_st::sfc_control_variables() {
                    let k = format!("{p}{v}");
                    if generated.type_of(&k).is_some() {
                        keys.push(k);
                    }
                }
            }
        }
        Probe { keys }
    }

    fn diffs(&self, a: &Simulation, b: &Simulation) -> Vec<String> {
        let mut out = Vec::new();
        for k in &self.keys {
            let (x, y) = (a.get(k), b.get(k));
            if format!("{x:?}") != format!("{y:?}") {
                out.push(format!("{k}: chart {x:?}, translation {y:?}"));
            }
        }
        out
    }
}

/// A run of the original and of the translation: `inputs(scan)` gives the writes before each
/// scan. Returns a report of the first divergence.
fn run_pair(
    name: &str,
    original: &str,
    translated: &str,
    pou: Option<&str>,
    opts: SimOptions,
    scans: u64,
    inputs: &mut dyn FnMut(u64) -> Vec<(String, Value)>,
) -> Result<(), String> {
    let mut a = Simulation::from_source(name, original, pou, opts).map_err(|(_, d)| format!("original: {d:?}"))?;
    let pou = a.pou_name().to_string();
    let mut b =
        Simulation::from_source(name, translated, Some(&pou), opts).map_err(|(_, d)| format!("translation: {d:?}"))?;
    let checked = check(name, original);
    let probe = Probe::new(&a, &checked, &b);
    let mut log = String::new();
    for scan in 0..scans {
        for (k, v) in inputs(scan) {
            let ra = a.set(&k, v.clone());
            let rb = b.set(&k, v.clone());
            if ra.is_ok() != rb.is_ok() {
                return Err(format!("scan {scan}: setting {k}: chart {ra:?}, translation {rb:?}"));
            }
            if ra.is_ok() {
                write!(log, "{k}={v:?} ").unwrap();
            }
        }
        let ra = a.scan().clone();
        b.scan();
        writeln!(log, "| scan {scan}: {:?} fired {:?}", ra.active, ra.fired).unwrap();
        let diffs = probe.diffs(&a, &b);
        if !diffs.is_empty() {
            return Err(format!(
                "scan {scan} ({} µs):\n  {}\nrun:\n{log}",
                scan as i64 * opts.period,
                diffs.join("\n  ")
            ));
        }
        match (a.error(), b.error()) {
            (None, None) => {}
            (Some(_), Some(_)) => return Ok(()),
            (x, y) => return Err(format!("scan {scan}: runtime error: chart {x:?}, translation {y:?}\n{log}")),
        }
    }
    Ok(())
}

/// Every `*.scenario.toml` under `dir` whose profile is `iec`.
fn scenarios(dir: &Path) -> Vec<Scenario> {
    random_chart::scenario_files(dir)
        .into_iter()
        .map(|p| scenario::load(&p).unwrap_or_else(|e| panic!("{}: {}", p.display(), e.message)))
        .filter(|s| s.options.profile == sfc_sim::Profile::Iec)
        .collect()
}

#[test]
fn examples_and_semantics_scenarios_behave_identically() {
    let mut list = scenarios(&root().join("examples"));
    let examples = list.len();
    list.extend(scenarios(&root().join("crates/sfc-sim/tests/semantics")));
    assert!(examples >= 4 && list.len() >= 30, "{examples} example scenarios, {} in all", list.len());
    let mut failures = Vec::new();
    for s in &list {
        let name = s.chart_name();
        let translated = match translate_all(&name, s.chart_text()) {
            Ok(t) => t,
            // CODESYS's SFC actions and step actions are refused by the ST target (SFC0806):
            // refused, not translated wrongly.
            Err(e) if e.contains("SFC0806") => continue,
            // AND_THEN/OR_ELSE over a call: IEC ST has no short-circuit operator (SFC0809).
            Err(e) if e.contains("SFC0809") => continue,
            Err(e) => {
                failures.push(format!("{}: not translated:\n{e}", s.name));
                continue;
            }
        };
        let entries = s.entries.clone();
        let period = s.options.period.max(1);
        let mut applied = 0;
        let mut inputs = |scan: u64| {
            let now = scan as i64 * period;
            let mut out = Vec::new();
            while applied < entries.len() && entries[applied].time <= now {
                out.extend(entries[applied].set.iter().cloned());
                applied += 1;
            }
            out
        };
        if let Err(e) =
            run_pair(&name, s.chart_text(), &translated, Some(&s.pou), s.options, s.total_scans(), &mut inputs)
        {
            failures.push(format!("{} ({}): {e}\n{translated}", s.name, s.pou));
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n\n"));
}

/// not written by the chart are flipped at random).
fn random_inputs(sim: &Simulation, checked: &Checked) -> Vec<String> {
    let written: Vec<String> = checked
        .charts
        .iter()
        .flat_map(|c| c.steps.iter().flat_map(|s| s.associations.iter().map(|a| a.action.to_ascii_uppercase())))
        .collect();
    sim.trace_vars()
        .into_iter()
        .filter(|(n, t)| *t == sfc_st::Type::Bool && !written.contains(&n.to_ascii_uppercase()))
        .map(|(n, _)| n)
        .collect()
}

#[test]
fn fixtures_behave_identically_on_random_inputs() {
    let mut rng = Rng(0x57C0_DE0A_7A7E_0003);
    let mut failures = Vec::new();
    for path in fixtures() {
        let text = std::fs::read_to_string(&path).unwrap();
        let name = path.display().to_string();
        let Ok(translated) = translate_all(&name, &text) else { continue };
        let Ok(sim) = Simulation::from_source(&name, &text, None, SimOptions::default()) else { continue };
        let inputs = random_inputs(&sim, &check(&name, &text));
        for round in 0..5 {
            let mut values = vec![false; inputs.len()];
            let seq: Vec<Vec<(String, Value)>> = (0..300)
                .map(|_| {
                    let mut w = Vec::new();
                    for (k, v) in values.iter_mut().enumerate() {
                        let p = if inputs[k].to_ascii_uppercase().starts_with("SFC") { 3 } else { 15 };
                        if rng.chance(p) {
                            *v = !*v;
                            w.push((inputs[k].clone(), Value::Bool(*v)));
                        }
                    }
                    w
                })
                .collect();
            let mut f = |scan: u64| seq[scan as usize].clone();
            if let Err(e) = run_pair(&name, &text, &translated, None, SimOptions::default(), 300, &mut f) {
                failures.push(format!("{name} round {round}: {e}"));
                break;
            }
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n\n"));
}

// ---------------------------------------------------------------------------------------------
// Random charts

#[test]
fn random_charts_behave_identically() {
    let cases: usize = std::env::var("SFC_ST_CASES").ok().and_then(|v| v.parse().ok()).unwrap_or(200);
    let only: Option<usize> = std::env::var("SFC_ST_CASE").ok().and_then(|v| v.parse().ok());
    let mut failures = Vec::new();
    for case in 0..cases {
        if only.is_some_and(|o| o != case) {
            continue;
        }
        let mut rng = Rng::for_case(case);
        let (text, fb) = random_chart(&mut rng, 14);
        let c = check("random.st", &text);
        if c.has_errors() {
            failures
                .push(format!("case {case}: the random chart does not check:\n{}\n{text}", render(&c, &c.diagnostics)));
            continue;
        }
        let translated = match translate_all("random.st", &text) {
            Ok(t) => t,
            Err(e) => {
                failures.push(format!("case {case}: not translated:\n{e}\n{text}"));
                continue;
            }
        };
        if only.is_some() {
            println!("{text}\n----\n{translated}");
        }
        let mut schedule = RandomInputs::new(&text, fb);
        let mut inputs =
            |scan: u64| schedule.next(&mut rng, scan).into_iter().map(|(n, b)| (n, Value::Bool(b))).collect::<Vec<_>>();
        let pou = if fb { "Main" } else { "Chart" };
        if let Err(e) = run_pair("random.st", &text, &translated, Some(pou), SimOptions::default(), 120, &mut inputs) {
            failures.push(format!("case {case}: {e}\n{text}\n----\n{translated}"));
        }
        if failures.len() >= 3 {
            break;
        }
    }
    assert!(failures.is_empty(), "{} failures; first:\n{}", failures.len(), failures.join("\n\n=====\n"));
}

#[test]
fn a_large_chart_translates() {
    let n: usize = std::env::var("SFC_ST_LARGE").ok().and_then(|v| v.parse().ok()).unwrap_or(600);
    let mut t = String::from("PROGRAM Big\n    VAR_INPUT Go : BOOL; END_VAR\n    VAR_OUTPUT Count : INT; END_VAR\n");
    for s in 0..n {
        let kw = if s == 0 { "INITIAL_STEP" } else { "STEP" };
        writeln!(t, "    {kw} S{s}: Tick(N); END_STEP").unwrap();
        writeln!(t, "    TRANSITION FROM S{s} TO S{} := Go AND S{s}.T >= T#10ms; END_TRANSITION", (s + 1) % n).unwrap();
        if s % 10 == 0 {
            writeln!(t, "    TRANSITION (PRIORITY := 1) FROM S{s} TO S0 := NOT Go; END_TRANSITION").unwrap();
        }
    }
    t.push_str("    ACTION Tick: Count := Count + 1; END_ACTION\nEND_PROGRAM\n");
    let c = check("big.st", &t);
    let started = std::time::Instant::now();
    let (direct, _) = build_st_file(&c, None, &StOptions::default()).unwrap();
    let took = started.elapsed();
    let out = translate_all("big.st", &t).unwrap();
    assert_eq!(direct, out);
    println!("{n} steps: build_st took {took:?}, {} bytes", out.len());
    if n <= 600 {
        // (the comparison reads every step of both simulations by name after each scan)
        let mut inputs = |scan: u64| vec![("Go".to_string(), Value::Bool(scan % 7 >= 1))];
        run_pair("big.st", &t, &out, None, SimOptions::default(), 60, &mut inputs).unwrap();
    }
}
