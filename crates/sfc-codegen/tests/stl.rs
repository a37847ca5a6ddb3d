//! The S7-200 statement-list target, against the S7-200 model of `tests/s7200/`.
//!
//! - Fixtures `tests/stl/*.st`: a chart the target accepts has its expected programs beside it
//!   (`*.stl` set/reset, `*.scr.stl` SCR); a chart it refuses lists the expected diagnostics
//!   inline (`(*! SFC0812 *)` on the line where each starts) and keeps their rendering as
//!   `*.stderr`. Expectation files are rewritten with `UPDATE_EXPECT=1`.
//! - Differential tests, for both methods: every accepted fixture and 300 random charts (with
//!   timers, counters and integers) run in the simulator and, as generated statement list, in
//!   the S7-200 model with the same random inputs; active steps, every variable, counter and
//!   action flag must agree after every scan, scan 0 included. Scan periods are multiples of
//!   100 ms and also not (30, 70, 130, 250 ms, with the time base at an arbitrary phase): the
//!   model's 100 ms timers then count the ticks of the CPU's time base, so the simulator runs
//!   on that clock (`scan_at`, time = the ticks since the first scan × 100 ms) — the program
//!   must be exactly the chart with step times in whole ticks. Each timer and counter
//!   instruction must run at most once per scan.

mod s7200;

use s7200::{parse, Plc, ScrModel, ScrtReset};
use sfc_codegen::stl::{build_stl, StlMethod, StlOptions, StlProgram};
use sfc_diagnostics::{render_human, Diagnostic, RenderOptions};
use sfc_model::{check_source, CheckOptions};
use sfc_sim::{SimOptions, Simulation, Value};
use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

const MS: i64 = 1000;
const METHODS: [StlMethod; 2] = [StlMethod::SetReset, StlMethod::Scr];

// ---------------------------------------------------------------------------------------------
// Helpers

fn fixture_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/stl")
}

fn fixtures() -> Vec<PathBuf> {
    let mut out: Vec<PathBuf> = std::fs::read_dir(fixture_dir())
        .expect("tests/stl exists")
        .flatten()
        .map(|e| e.path())
        .filter(|p| p.extension().is_some_and(|x| x == "st"))
        .collect();
    out.sort();
    out
}

fn build(name: &str, text: &str, method: StlMethod) -> (sfc_model::Checked, Result<StlProgram, Vec<Diagnostic>>) {
    let checked = check_source(0, name, text, &CheckOptions::default());
    let result = match checked.charts.first() {
        Some(chart) => build_stl(&checked, chart, StlOptions { method }),
        None => Err(Vec::new()),
    };
    (checked, result)
}

/// The allocation table of a generated program: `//   ADDR kind name detail`.
#[derive(Debug, Default)]
struct Alloc {
    /// Variables: name, address, written from outside.
    vars: Vec<(String, String, bool)>,
    steps: Vec<(String, String)>,
    /// `Action.Q` / `Action.A` bits.
    flags: Vec<(String, String)>,
    /// Counter instances: name, address, kind.
    counters: Vec<(String, String, String)>,
}

fn allocation(stl: &str) -> Alloc {
    let mut a = Alloc::default();
    for line in stl.lines() {
        if line.starts_with("NETWORK") {
            break;
        }
        let Some(rest) = line.strip_prefix("//   ") else { continue };
        let f: Vec<&str> = rest.split_whitespace().collect();
        if f.len() < 3 {
            continue;
        }
        let (addr, kind, name) = (f[0].to_string(), f[1], f[2].to_string());
        match kind {
            "var" => a.vars.push((name, addr, rest.contains(", input"))),
            "step" => a.steps.push((name, addr)),
            "flag" if name.ends_with(".Q") || name.ends_with(".A") || name.ends_with(".QD") => {
                a.flags.push((name, addr))
            }
            "counter" => a.counters.push((name, addr, f.get(3).copied().unwrap_or("").to_string())),
            _ => {}
        }
    }
    a
}

/// xorshift64*: deterministic random numbers for inputs and charts.
struct Rng(u64);

impl Rng {
    fn new(seed: u64) -> Rng {
        Rng(seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1)
    }
    fn next(&mut self) -> u64 {
        let mut x = self.0;
        x ^= x >> 12;
        x ^= x << 25;
        x ^= x >> 27;
        self.0 = x;
        x.wrapping_mul(0x2545_F491_4F6C_DD1D)
    }
    fn below(&mut self, n: usize) -> usize {
        (self.next() % n.max(1) as u64) as usize
    }
    fn chance(&mut self, percent: u64) -> bool {
        self.next() % 100 < percent
    }
}

/// What a differential run exercised.
#[derive(Debug, Default)]
struct Coverage {
    fired: usize,
    steps: usize,
    steps_active: std::collections::BTreeSet<String>,
    /// Changes of compared variables and action flags from one scan to the next.
    changes: usize,
    compared: usize,
    /// Changes of integer variables and counters.
    number_changes: usize,
    /// `unsafe` and `conflict` events of the simulator.
    unsafe_events: usize,
    conflicts: usize,
    timer_runs: usize,
}

/// How one differential run is made.
#[derive(Debug, Clone, Copy)]
struct Run {
    period: i64,
    /// The S7-200 time base's offset from the first scan.
    phase: i64,
    scans: usize,
    seed: u64,
    scr_model: ScrModel,
    scrt_reset: ScrtReset,
}

impl Run {
    fn new(period: i64, scans: usize, seed: u64) -> Run {
        Run { period, phase: 0, scans, seed, scr_model: ScrModel::PowerOff, scrt_reset: ScrtReset::Immediate }
    }
}

/// The runs of a fixture or random chart: periods that are multiples of 100 ms and periods
/// that are not, with both readings of the SCR instructions.
fn runs(seed: u64, scans: usize) -> Vec<Run> {
    let mut out = Vec::new();
    for (k, (period, phase)) in
        [(100, 0), (200, 0), (30, 0), (70, 40), (130, 90), (250, 10), (100, 55)].into_iter().enumerate()
    {
        let mut r = Run::new(period * MS, scans, seed * 31 + k as u64);
        r.phase = phase * MS;
        if k % 2 == 1 {
            r.scr_model = ScrModel::Skip;
        }
        if k % 3 == 2 {
            r.scrt_reset = ScrtReset::AtScre;
        }
        out.push(r);
    }
    out
}

fn mask(addr: &str) -> u64 {
    if addr.contains('D') {
        0xFFFF_FFFF
    } else {
        0xFFFF
    }
}

/// Runs `text` in the simulator and its statement list in the S7-200 model for `run.scans`
/// scans with random inputs; the first difference is an error with the history that led to it.
fn differential(name: &str, text: &str, stl: &str, run: Run) -> Result<Coverage, String> {
    differential_pou(name, text, None, stl, run)
}

/// [`differential`] of the POU `pou` of the file.
fn differential_pou(name: &str, text: &str, pou: Option<&str>, stl: &str, run: Run) -> Result<Coverage, String> {
    let opts = SimOptions { period: run.period, ..Default::default() };
    let mut sim = match Simulation::from_source(name, text, pou, opts) {
        Ok(s) => s,
        Err((_, d)) => return Err(format!("{name}: the simulator refuses the chart: {d:?}")),
    };
    let prog = parse(stl).map_err(|e| format!("{name}: the model refuses the program: {e}"))?;
    let mut plc = Plc::new(prog);
    plc.phase = run.phase;
    plc.scr_model = run.scr_model;
    plc.scrt_reset = run.scrt_reset;
    let alloc = allocation(stl);
    let is_word = |a: &str| a.contains('W') || a.contains('D');
    let inputs: Vec<&(String, String, bool)> = alloc.vars.iter().filter(|v| v.2).collect();
    let outputs: Vec<&(String, String, bool)> = alloc.vars.iter().filter(|v| !v.2).collect();
    let mut rng = Rng::new(run.seed);
    let mut values: Vec<i64> =
        inputs.iter().map(|v| if is_word(&v.1) { rng.below(20) as i64 } else { i64::from(rng.chance(50)) }).collect();
    let mut history = String::new();
    let mut cov = Coverage { steps: alloc.steps.len(), ..Default::default() };
    let mut last: Vec<i64> = Vec::new();
    let mut last_numbers: Vec<i64> = Vec::new();
    let ticks = |t: i64| (t + run.phase).div_euclid(100 * MS);
    for k in 0..run.scans {
        for (i, (vname, addr, _)) in inputs.iter().enumerate() {
            if k > 0 && rng.chance(30) {
                values[i] = if is_word(addr) { rng.below(20) as i64 } else { 1 - values[i] };
            }
            if is_word(addr) {
                sim.set(vname, Value::Int(values[i])).map_err(|e| format!("{name}: set {vname}: {e}"))?;
                plc.set_value(addr, values[i]).map_err(|e| format!("{name}: set {addr}: {e}"))?;
            } else {
                sim.set(vname, Value::Bool(values[i] == 1)).map_err(|e| format!("{name}: set {vname}: {e}"))?;
                plc.set(addr, values[i] == 1).map_err(|e| format!("{name}: set {addr}: {e}"))?;
            }
        }
        let t = k as i64 * run.period;
        // The simulator on the S7-200's clock: whole 100 ms ticks since the first scan.
        let record = sim.scan_at((ticks(t) - ticks(0)) * 100 * MS).clone();
        if let Some(e) = sim.error() {
            return Err(format!("{name}: simulator error in scan {k}: {}", e.message));
        }
        plc.scan(t).map_err(|e| format!("{name}: S7-200 error in scan {k}: {e}"))?;
        for (&(kind, n), &count) in plc.executions() {
            if count > 1 {
                return Err(format!("{name}: scan {k}: the instruction of {kind}{n} ran {count} times"));
            }
            if kind == 'T' {
                cov.timer_runs += 1;
            }
        }
        let ins: Vec<String> = inputs.iter().zip(&values).map(|((n, _, _), v)| format!("{n}={v}")).collect();
        let mut plc_active: Vec<String> = Vec::new();
        for (s, addr) in &alloc.steps {
            if plc.get(addr)? {
                plc_active.push(s.clone());
            }
        }
        plc_active.sort();
        let _ = writeln!(
            history,
            "scan {k} (t = {} ms): inputs {} | sim active {:?} fired {:?}",
            t / MS,
            ins.join(" "),
            record.active,
            record.fired
        );
        cov.fired += record.fired.len();
        for ev in &record.events {
            match ev {
                sfc_sim::Event::Unsafe { .. } => cov.unsafe_events += 1,
                sfc_sim::Event::Conflict { .. } => cov.conflicts += 1,
                _ => {}
            }
        }
        cov.steps_active.extend(record.active.iter().cloned());
        let mut diffs = Vec::new();
        if plc_active != record.active {
            diffs.push(format!("active steps: sim {:?}, plc {:?}", record.active, plc_active));
        }
        let mut now = Vec::new();
        let mut numbers = Vec::new();
        for (vname, addr) in outputs.iter().map(|v| (&v.0, &v.1)).chain(alloc.flags.iter().map(|f| (&f.0, &f.1))) {
            if is_word(addr) {
                let s = sim.get(vname).and_then(|v| v.as_int());
                let p = plc.value(addr)?;
                let m = mask(addr);
                if s.map(|s| s as u64 & m) != Some(p as u64 & m) {
                    diffs.push(format!("{vname} ({addr}): sim {s:?}, plc {p}"));
                }
                numbers.push(p);
                now.push(p);
            } else {
                let s = sim.get(vname).and_then(|v| v.as_bool());
                let p = plc.get(addr)?;
                if s != Some(p) {
                    diffs.push(format!("{vname} ({addr}): sim {s:?}, plc {p}"));
                }
                now.push(i64::from(p));
            }
            cov.compared += 1;
        }
        for (cname, addr, kind) in &alloc.counters {
            let (q, cv) = match kind.as_str() {
                "CTUD" => ("QU", true),
                "CTD" => ("Q", false),
                _ => ("Q", true),
            };
            let s = sim.get(&format!("{cname}.{q}")).and_then(|v| v.as_bool());
            let p = plc.get(addr)?;
            if s != Some(p) {
                diffs.push(format!("{cname}.{q} ({addr}): sim {s:?}, plc {p}"));
            }
            if cv {
                let s = sim.get(&format!("{cname}.CV")).and_then(|v| v.as_int());
                let p = plc.value(addr)?;
                if s != Some(p) {
                    diffs.push(format!("{cname}.CV ({addr}): sim {s:?}, plc {p}"));
                }
                numbers.push(p);
            }
            now.push(i64::from(p));
            cov.compared += 1;
        }
        cov.changes += now.iter().zip(&last).filter(|(a, b)| a != b).count();
        cov.number_changes += usize::from(numbers.iter().zip(&last_numbers).any(|(a, b)| a != b));
        last = now;
        last_numbers = numbers;
        if !diffs.is_empty() {
            return Err(format!(
                "{name}: scan {k} (t = {} ms, period {} ms, phase {} ms, {:?}/{:?}) differs:\n  {}\nhistory:\n{history}",
                t / MS,
                run.period / MS,
                run.phase / MS,
                run.scr_model,
                run.scrt_reset,
                diffs.join("\n  ")
            ));
        }
    }
    Ok(cov)
}

fn display_name(path: &Path) -> String {
    format!("tests/stl/{}", path.file_name().and_then(|f| f.to_str()).unwrap_or("?"))
}

/// Compares with the file beside the fixture, or rewrites it with UPDATE_EXPECT=1.
fn expect_file(path: &Path, actual: &str) -> Result<(), String> {
    if std::env::var_os("UPDATE_EXPECT").is_some() {
        std::fs::write(path, actual).map_err(|e| e.to_string())?;
        return Ok(());
    }
    let expected = std::fs::read_to_string(path).unwrap_or_default();
    if expected != actual {
        return Err(format!(
            "{} differs (run with UPDATE_EXPECT=1 to accept)\n--- expected\n{expected}\n--- actual\n{actual}",
            path.display()
        ));
    }
    Ok(())
}

/// Expected `(line, code)` pairs from `(*! CODE *)` comments.
fn expectations(text: &str) -> BTreeMap<(usize, String), usize> {
    let mut out = BTreeMap::new();
    for (i, line) in text.lines().enumerate() {
        let mut rest = line;
        while let Some(start) = rest.find("(*!") {
            let after = &rest[start + 3..];
            let end = after.find("*)").unwrap_or(after.len());
            for code in after[..end].split_whitespace().filter(|w| w.starts_with("SFC")) {
                *out.entry((i + 1, code.to_string())).or_insert(0) += 1;
            }
            rest = &after[end..];
        }
    }
    out
}

fn render(diags: &[Diagnostic], file: &sfc_diagnostics::SourceFile) -> String {
    diags.iter().map(|d| render_human(d, std::slice::from_ref(file), RenderOptions::default()) + "\n").collect()
}

// ---------------------------------------------------------------------------------------------
// Fixtures

#[test]
fn fixtures_build_or_refuse_as_expected() {
    let mut failures = Vec::new();
    let all = fixtures();
    assert!(all.len() >= 8, "fixtures missing: {all:?}");
    for path in all {
        let text = std::fs::read_to_string(&path).expect("fixture is UTF-8");
        let name = display_name(&path);
        let expected = expectations(&text);
        for method in METHODS {
            let (checked, result) = build(&name, &text, method);
            let ext = match method {
                StlMethod::SetReset => "stl",
                StlMethod::Scr => "scr.stl",
            };
            match result {
                Ok(p) => {
                    if !expected.is_empty() {
                        failures.push(format!("{name}: expected diagnostics {expected:?}, but the program was built"));
                    }
                    let mut out = p.text.clone();
                    if !p.warnings.is_empty() {
                        out.push_str("// --- warnings\n");
                        for line in render(&p.warnings, &checked.file).lines() {
                            out.push_str("// ");
                            out.push_str(line);
                            out.push('\n');
                        }
                    }
                    if let Err(e) = expect_file(&path.with_extension(ext), &out) {
                        failures.push(e);
                    }
                    if !p.text.is_ascii() {
                        failures.push(format!("{name}: the program is not ASCII"));
                    }
                    if !p.symbols.starts_with("Symbol,Address,Comment\n") {
                        failures.push(format!("{name}: symbol table header"));
                    }
                }
                Err(diags) => {
                    if method == StlMethod::Scr {
                        continue; // the same refusal, reported once
                    }
                    if diags.is_empty() {
                        failures.push(format!("{name}: refused without a diagnostic"));
                        continue;
                    }
                    let mut got = BTreeMap::new();
                    for d in &diags {
                        let line = checked.file.line_col(d.span.start).line as usize;
                        *got.entry((line, d.code.to_string())).or_insert(0) += 1;
                        if !d.code.starts_with("SFC081") {
                            failures.push(format!("{name}: unexpected non-STL diagnostic {} {}", d.code, d.message));
                        }
                        if d.element.is_none() && d.code != "SFC0815" {
                            failures.push(format!("{name}: {} has no element: {}", d.code, d.message));
                        }
                    }
                    if got != expected {
                        failures.push(format!("{name}: diagnostics {got:?}, expected {expected:?}"));
                    }
                    if let Err(e) = expect_file(&path.with_extension("stderr"), &render(&diags, &checked.file)) {
                        failures.push(e);
                    }
                }
            }
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n\n"));
}

#[test]
fn accepted_fixtures_agree_with_the_s7200_model() {
    let mut ran = 0;
    for path in fixtures() {
        let text = std::fs::read_to_string(&path).expect("fixture is UTF-8");
        let name = display_name(&path);
        for method in METHODS {
            let Ok(p) = build(&name, &text, method).1 else { continue };
            let mut reached = std::collections::BTreeSet::new();
            let mut steps = 0;
            for run in runs(ran as u64 + 1, 400) {
                match differential(&name, &text, &p.text, run) {
                    Ok(c) => {
                        reached.extend(c.steps_active);
                        steps = c.steps;
                    }
                    Err(e) => panic!("{method:?}: {e}\n--- program\n{}", p.text),
                }
            }
            eprintln!("{name} ({method:?}): {} of {steps} steps reached", reached.len());
            assert_eq!(reached.len(), steps, "{name}: random inputs did not reach every step");
            ran += 1;
        }
    }
    assert!(ran >= 16, "only {ran} fixture programs were accepted");
}

#[test]
fn the_refused_fixtures_are_refused_by_this_target_only() {
    // A refused fixture must still be a valid chart: the refusal is the target's.
    for path in fixtures() {
        let text = std::fs::read_to_string(&path).expect("fixture is UTF-8");
        let (checked, result) = build(&display_name(&path), &text, StlMethod::SetReset);
        if result.is_err() {
            assert!(!checked.has_errors(), "{}: {:?}", path.display(), checked.diagnostics);
        }
    }
}

// ---------------------------------------------------------------------------------------------
// Random charts

/// A random block-structured chart: sequences, selections (with and without PRIORITY),
/// simultaneous branches, loops back, over BOOL and INT inputs (VAR_INPUT and `AT %IX`), with
/// N, S, R, P, L, D, SD, DS, SL, P1, P0 associations to BOOL outputs and to actions whose bodies
/// assign BOOL and integer expressions (also under IF) and call counters (CTU, CTD, CTUD),
/// guards with AND/OR/NOT/XOR/=/<>, integer comparisons, step flags, action flags, counter
/// outputs, step-time comparisons (also not multiples of 100 ms, also against a TIME variable),
/// and supervised steps whose `SFCError` a guard reads.
struct ChartGen {
    rng: Rng,
    inputs: Vec<String>,
    outputs: Vec<(String, Option<(&'static str, u32)>)>,
    actions: Vec<(String, Option<(&'static str, u32)>)>,
    /// Counters: name, kind, the action that calls it.
    counters: Vec<(String, &'static str, usize)>,
    steps: Vec<(String, bool, Vec<String>)>,
    timeouts: Vec<Option<u32>>,
    transitions: Vec<String>,
    seen: std::collections::HashSet<(Vec<usize>, Vec<usize>, String)>,
    supervised: bool,
}

const TIMED: [&str; 5] = ["L", "D", "SD", "DS", "SL"];

impl ChartGen {
    fn new(seed: u64) -> ChartGen {
        let mut rng = Rng::new(seed);
        let n_in = 2 + rng.below(4);
        let inputs = (0..n_in).map(|i| format!("In{i}")).collect();
        let n_out = 2 + rng.below(4);
        let mut outputs = Vec::new();
        for i in 0..n_out {
            let timed = rng.chance(40).then(|| (TIMED[rng.below(5)], rng.below(6) as u32));
            outputs.push((format!("Out{i}"), timed));
        }
        let n_act = rng.below(4);
        let mut actions = Vec::new();
        for i in 0..n_act {
            let timed = rng.chance(40).then(|| (TIMED[rng.below(5)], rng.below(6) as u32));
            actions.push((format!("Act{i}"), timed));
        }
        let mut counters = Vec::new();
        if n_act > 0 {
            for (i, kind) in ["CTU", "CTD", "CTUD"].into_iter().enumerate() {
                if rng.chance(35) {
                    let a = rng.below(n_act);
                    counters.push((format!("Cnt{i}"), kind, a));
                }
            }
        }
        ChartGen {
            rng,
            inputs,
            outputs,
            actions,
            counters,
            steps: Vec::new(),
            timeouts: Vec::new(),
            transitions: Vec::new(),
            seen: Default::default(),
            supervised: false,
        }
    }

    fn new_step(&mut self, initial: bool) -> usize {
        let i = self.steps.len();
        let mut assocs = Vec::new();
        for _ in 0..self.rng.below(4) {
            let to_action = !self.actions.is_empty() && self.rng.chance(40);
            let (name, timed) = if to_action {
                self.actions[self.rng.below(self.actions.len())].clone()
            } else {
                self.outputs[self.rng.below(self.outputs.len())].clone()
            };
            let mut quals = vec!["N", "N", "S", "R", "P"];
            if to_action {
                quals.extend(["P1", "P0", "N"]);
            }
            let a = match timed {
                Some((q, d)) if self.rng.chance(40) => {
                    // Also durations that are not multiples of 100 ms, and a TIME variable.
                    if d == 5 {
                        format!("{name}({q}, Delay)")
                    } else {
                        format!("{name}({q}, T#{}ms)", d * 100 + if d % 2 == 1 { 50 } else { 0 })
                    }
                }
                _ => format!("{name}({})", quals[self.rng.below(quals.len())]),
            };
            assocs.push(a);
        }
        self.steps.push((format!("S{i}"), initial, assocs));
        let timeout = self.rng.chance(12).then(|| 3 + self.rng.below(6) as u32);
        self.supervised |= timeout.is_some();
        self.timeouts.push(timeout);
        i
    }

    fn time_cmp(&mut self, step: usize, exact: bool) -> String {
        let ops = if exact { ["=", "<>", "=", "<>"] } else { [">=", ">", "<", "<="] };
        let op = ops[self.rng.below(ops.len())];
        // `< T#0s` never holds: lower bounds may be 0, upper bounds start at 100 ms.
        let least = usize::from(op.starts_with('<'));
        let odd = if !exact && self.rng.chance(30) { 50 } else { 0 };
        if !exact && self.rng.chance(10) {
            return format!("(S{step}.T {op} Delay)");
        }
        format!("(S{step}.T {op} T#{}ms)", (least + self.rng.below(9 - least)) * 100 + odd)
    }

    fn int_cmp(&mut self) -> String {
        let ops = ["<", "<=", ">", ">=", "=", "<>"];
        let op = ops[self.rng.below(ops.len())];
        match self.rng.below(4) {
            0 => format!("(Level {op} {})", self.rng.below(20)),
            1 => format!("(Count {op} {})", self.rng.below(6)),
            2 => format!("(Total {op} DINT#{})", self.rng.below(30)),
            _ => format!("(Level + Count {op} 12)"),
        }
    }

    fn leaf(&mut self, from: usize) -> String {
        match self.rng.below(20) {
            0..=6 => self.inputs[self.rng.below(self.inputs.len())].clone(),
            7 | 8 => format!("NOT {}", self.inputs[self.rng.below(self.inputs.len())]),
            9 | 10 => self.time_cmp(from, false),
            11 => self.time_cmp(from, true),
            12 => {
                // Another step's time (a TONR in the program): mostly comparisons that hold
                // while that step has not run long, so the chart does not get stuck on them.
                let s = self.rng.below(self.steps.len());
                let ops = ["<", "<=", "<>", "<", ">="];
                let op = ops[self.rng.below(ops.len())];
                format!("(S{s}.T {op} T#{}ms)", 100 * (1 + self.rng.below(8)))
            }
            13 => {
                let s = self.rng.below(self.steps.len());
                if self.rng.chance(50) {
                    format!("S{s}.X")
                } else {
                    format!("NOT S{s}.X")
                }
            }
            14 if !self.actions.is_empty() => {
                let a = self.actions[self.rng.below(self.actions.len())].0.clone();
                format!("{a}.{}", if self.rng.chance(50) { "Q" } else { "A" })
            }
            15 => self.outputs[self.rng.below(self.outputs.len())].0.clone(),
            16 if self.rng.chance(30) => "TRUE".to_string(),
            17 | 18 => self.int_cmp(),
            19 if !self.counters.is_empty() => {
                let (n, kind, _) = self.counters[self.rng.below(self.counters.len())].clone();
                match kind {
                    "CTUD" => match self.rng.below(3) {
                        0 => format!("{n}.QU"),
                        1 => format!("{n}.QD"),
                        _ => format!("({n}.CV > 1)"),
                    },
                    "CTU" if self.rng.chance(50) => format!("({n}.CV >= 2)"),
                    _ => format!("{n}.Q"),
                }
            }
            _ => self.inputs[self.rng.below(self.inputs.len())].clone(),
        }
    }

    fn expr(&mut self, from: usize, depth: u32) -> String {
        if depth == 0 || self.rng.chance(45) {
            return self.leaf(from);
        }
        let a = self.expr(from, depth - 1);
        let b = self.expr(from, depth - 1);
        match self.rng.below(8) {
            0 | 1 => format!("({a} AND {b})"),
            2..=4 => format!("({a} OR {b})"),
            5 => format!("({a} XOR {b})"),
            6 => format!("NOT ({a} {} {b})", if self.rng.chance(50) { "=" } else { "<>" }),
            _ => format!("NOT ({a} AND {b})"),
        }
    }

    fn transition(&mut self, from: Vec<usize>, to: Vec<usize>, priority: Option<u32>) {
        self.transition_with(from, to, priority, None);
    }

    fn transition_with(&mut self, from: Vec<usize>, to: Vec<usize>, priority: Option<u32>, fixed: Option<String>) {
        let n = self.transitions.len();
        let mut guard = String::new();
        for attempt in 0..20 {
            if let Some(g) = &fixed {
                guard = g.clone();
                self.seen.insert((from.clone(), to.clone(), guard.clone()));
                break;
            }
            guard = if self.rng.chance(8) { "TRUE".to_string() } else { self.expr(from[0], 2) };
            if self.supervised && self.rng.chance(10) {
                guard = format!("({guard}) AND NOT SFCError");
            }
            if self.rng.chance(60) {
                // An escape on two inputs (true in a quarter of the scans), so that most
                // charts keep moving and the comparison covers most steps.
                let a = self.rng.below(self.inputs.len());
                let b = (a + 1 + self.rng.below(self.inputs.len() - 1)) % self.inputs.len();
                guard = format!("{guard} OR ({} AND NOT {})", self.inputs[a], self.inputs[b]);
            }
            if attempt == 19 {
                guard = format!("({guard}) OR (S{}.T > T#{}ms)", from[0], (n + 1) * 100);
            }
            // SFC0215: the same steps and condition twice is a warning (the copy never fires).
            if self.seen.insert((from.clone(), to.clone(), guard.clone())) {
                break;
            }
        }
        let list = |v: &[usize]| {
            let names: Vec<String> = v.iter().map(|s| format!("S{s}")).collect();
            if names.len() == 1 {
                names[0].clone()
            } else {
                format!("({})", names.join(", "))
            }
        };
        let prio = priority.map(|p| format!(" (PRIORITY := {p})")).unwrap_or_default();
        self.transitions.push(format!(
            "    TRANSITION Tr{n}{prio} FROM {} TO {}\n        := {guard};\n    END_TRANSITION\n",
            list(&from),
            list(&to)
        ));
    }

    fn block(&mut self, entry: usize, depth: u32) -> usize {
        let mut cur = entry;
        for _ in 0..1 + self.rng.below(2) {
            let kind = if depth == 0 { 0 } else { self.rng.below(5) };
            cur = match kind {
                1 => {
                    // Selection divergence and convergence.
                    let k = 2 + self.rng.below(2);
                    let prioritised = self.rng.chance(40);
                    let mut ends = Vec::new();
                    for _ in 0..k {
                        let b = self.new_step(false);
                        let p = (prioritised && self.rng.chance(70)).then(|| 1 + self.rng.below(3) as u32);
                        self.transition(vec![cur], vec![b], p);
                        ends.push(self.block(b, depth - 1));
                    }
                    let j = self.new_step(false);
                    for e in ends {
                        self.transition(vec![e], vec![j], None);
                    }
                    j
                }
                2 => {
                    // Simultaneous divergence and convergence.
                    let k = 2 + self.rng.below(2);
                    let starts: Vec<usize> = (0..k).map(|_| self.new_step(false)).collect();
                    self.transition(vec![cur], starts.clone(), None);
                    let ends: Vec<usize> = starts.into_iter().map(|b| self.block(b, depth - 1)).collect();
                    let j = self.new_step(false);
                    self.transition(ends, vec![j], None);
                    j
                }
                3 => {
                    // A loop back to the block's entry.
                    let x = self.block(cur, depth - 1);
                    self.transition(vec![x], vec![cur], None);
                    x
                }
                4 => {
                    // A self-loop (re-entry restarts the step time).
                    let s = self.new_step(false);
                    self.transition(vec![cur], vec![s], None);
                    // Prioritised, so its guard holds rarely: it must not hold the token.
                    let p = 1 + self.rng.below(2) as u32;
                    let a = self.inputs[self.rng.below(self.inputs.len())].clone();
                    let b = self.inputs[self.rng.below(self.inputs.len())].clone();
                    let g = format!("{a} AND NOT {b} AND (S{s}.T >= T#{}ms)", 100 * (1 + self.rng.below(5)));
                    self.transition_with(vec![s], vec![s], Some(p), Some(g));
                    s
                }
                _ => {
                    let s = self.new_step(false);
                    self.transition(vec![cur], vec![s], None);
                    s
                }
            };
        }
        cur
    }

    fn statement(&mut self, s: usize) -> String {
        let target = self.outputs[self.rng.below(self.outputs.len())].0.clone();
        match self.rng.below(9) {
            0 => {
                let c = self.expr(s, 2);
                let v = self.expr(s, 2);
                let other = self.outputs[self.rng.below(self.outputs.len())].0.clone();
                let mut out = format!("        IF {c} THEN\n            {target} := {v};\n");
                if self.rng.chance(50) {
                    let c2 = self.expr(s, 1);
                    let _ = writeln!(out, "        ELSIF {c2} THEN\n            Count := Count - 1;");
                }
                let _ = writeln!(out, "        ELSE\n            {other} := TRUE;\n        END_IF;");
                out
            }
            1 => "        Count := Count + 1;\n".into(),
            2 => format!("        Total := Total + Count * {};\n", 1 + self.rng.below(3)),
            3 => "        Count := (Count + Level) MOD 7;\n".into(),
            4 => format!("        Total := Total - {};\n", self.rng.below(100)),
            5 => "        Count := Level / 3 - Count;\n".into(),
            _ => {
                let v = self.expr(s, 2);
                format!("        {target} := {v};\n")
            }
        }
    }

    fn body(&mut self, action: usize) -> String {
        let mut out = String::new();
        for _ in 0..1 + self.rng.below(3) {
            let s = self.rng.below(self.steps.len());
            out.push_str(&self.statement(s));
        }
        let calls: Vec<(String, &'static str)> =
            self.counters.iter().filter(|c| c.2 == action).map(|c| (c.0.clone(), c.1)).collect();
        for (n, kind) in calls {
            let a = self.inputs[self.rng.below(self.inputs.len())].clone();
            let b = self.inputs[self.rng.below(self.inputs.len())].clone();
            let call = match kind {
                "CTU" => format!("{n}(CU := {a}, R := {b} AND NOT {a}, PV := 3);"),
                "CTD" => format!("{n}(CD := {a}, LD := {b} AND NOT {a}, PV := 2);"),
                _ => format!("{n}(CU := {a}, CD := {b}, R := Count > 5, PV := 2);"),
            };
            if self.rng.chance(30) {
                let c = self.expr(0, 1);
                let _ = writeln!(out, "        IF {c} THEN\n            {call}\n        END_IF;");
            } else {
                let _ = writeln!(out, "        {call}");
            }
        }
        out
    }

    fn generate(mut self, seed: u64) -> String {
        let s0 = self.new_step(true);
        let end = self.block(s0, 2);
        self.transition(vec![end], vec![s0], None);
        if self.rng.chance(30) {
            // Jumps across the structure: out of a simultaneous branch they make the chart
            // unsafe (a step set again while active), which both sides must treat alike.
            for _ in 0..1 + self.rng.below(2) {
                let a = self.rng.below(self.steps.len());
                let b = self.rng.below(self.steps.len());
                self.transition(vec![a], vec![b], None);
            }
        }
        if self.rng.chance(20) {
            // A second network with its own initial step.
            let s = self.new_step(true);
            let e = self.block(s, 1);
            self.transition(vec![e], vec![s], None);
        }
        let mut text = format!("PROGRAM Random{seed}\n    VAR_INPUT\n        Level : INT;\n");
        let located: Vec<bool> = self.inputs.iter().map(|_| self.rng.chance(40)).collect();
        for (i, n) in self.inputs.iter().enumerate() {
            if !located[i] {
                let _ = writeln!(text, "        {n} : BOOL;");
            }
        }
        text.push_str("    END_VAR\n    VAR\n        Count : INT;\n        Total : DINT := 5;\n");
        text.push_str("        Delay : TIME := T#300ms;\n");
        for (n, kind, _) in &self.counters {
            let _ = writeln!(text, "        {n} : {kind};");
        }
        for (i, n) in self.inputs.iter().enumerate() {
            if located[i] {
                let _ = writeln!(text, "        {n} AT %IX0.{i} : BOOL;");
            }
        }
        for (i, (n, _)) in self.outputs.iter().enumerate() {
            match i % 3 {
                0 => {
                    let _ = writeln!(text, "        {n} AT %QX1.{i} : BOOL;");
                }
                1 => {
                    let _ = writeln!(text, "        {n} : BOOL := TRUE;");
                }
                _ => {
                    let _ = writeln!(text, "        {n} : BOOL;");
                }
            }
        }
        text.push_str("    END_VAR\n\n");
        for (i, (name, initial, assocs)) in self.steps.iter().enumerate() {
            if let Some(t) = self.timeouts[i] {
                let _ = writeln!(text, "    {{attribute 'sfc.timeout' := 'T#{}ms'}}", t * 100);
            }
            let kw = if *initial { "INITIAL_STEP" } else { "STEP" };
            let _ = writeln!(text, "    {kw} {name}:");
            for a in assocs {
                let _ = writeln!(text, "        {a};");
            }
            text.push_str("    END_STEP\n\n");
        }
        for t in &self.transitions {
            text.push_str(t);
            text.push('\n');
        }
        let names: Vec<String> = self.actions.iter().map(|a| a.0.clone()).collect();
        for (k, name) in names.into_iter().enumerate() {
            let body = self.body(k);
            let _ = writeln!(text, "    ACTION {name}:\n{body}    END_ACTION\n");
        }
        text.push_str("END_PROGRAM\n");
        text
    }
}

#[test]
fn random_charts_agree_with_the_s7200_model() {
    let charts: u64 = std::env::var("STL_RANDOM_CHARTS").ok().and_then(|v| v.parse().ok()).unwrap_or(300);
    let dump = std::env::var("STL_DUMP").ok().and_then(|v| v.parse::<u64>().ok());
    for method in METHODS {
        let (mut scans_total, mut fired, mut steps, mut active, mut changes, mut compared) = (0, 0, 0, 0, 0, 0);
        let (mut unsafe_events, mut conflicts, mut numbers, mut counters, mut timer_runs) = (0, 0, 0, 0, 0);
        let mut built = 0;
        for seed in 1..=charts {
            let text = ChartGen::new(seed).generate(seed);
            let name = format!("random{seed}.st");
            if dump == Some(seed) {
                eprintln!("{text}");
            }
            let (checked, result) = build(&name, &text, method);
            assert!(!checked.has_errors(), "generated chart {seed} does not check: {:?}\n{text}", checked.diagnostics);
            let p = match result {
                Ok(p) => p,
                Err(d) => panic!("random chart {seed} refused: {d:?}\n{text}"),
            };
            built += 1;
            counters += allocation(&p.text).counters.len();
            // Each chart on one period; over the charts every kind of period and reading.
            let all = runs(seed, 300);
            let run = all[(seed as usize) % all.len()];
            match differential(&name, &text, &p.text, run) {
                Ok(c) => {
                    fired += c.fired;
                    steps += c.steps;
                    active += c.steps_active.len();
                    changes += c.changes;
                    compared += c.compared;
                    numbers += c.number_changes;
                    unsafe_events += c.unsafe_events;
                    conflicts += c.conflicts;
                    timer_runs += c.timer_runs;
                }
                Err(e) => panic!("{method:?}: {e}\n--- chart\n{text}\n--- program\n{}", p.text),
            }
            scans_total += run.scans;
        }
        eprintln!(
            "{method:?}: {built} random charts, {scans_total} scans: {fired} firings, {active} of {steps} steps \
             reached, {changes} changes in {compared} compared values ({numbers} scans with integer changes), \
             {counters} counters, {timer_runs} timer executions, {unsafe_events} unsafe and {conflicts} conflict \
             events"
        );
        // The comparison must have something to compare: charts that evolve and values that move.
        assert!(fired > scans_total / 4, "too few firings: {fired}");
        assert!(active * 10 > steps * 6, "too few steps reached: {active} of {steps}");
        assert!(changes * 20 > compared, "outputs hardly change: {changes} of {compared}");
        assert!(numbers > scans_total / 20, "integers hardly change: {numbers}");
        assert!(counters > charts as usize / 3 && timer_runs > 0, "too few counters or timers");
        assert!(unsafe_events > 0 && conflicts > 0, "no unsafe or no conflicting situation was compared");
    }
}

/// The differential test must be able to fail: a program whose transitions see the steps they
/// set in the same scan (the SCR trap) is caught, and so is a timer executed twice per scan.
#[test]
fn the_differential_test_detects_a_wrong_program() {
    let text = std::fs::read_to_string(fixture_dir().join("carwash_textbook.st")).expect("fixture");
    let stl = build("carwash_textbook.st", &text, StlMethod::SetReset).1.expect("accepted").text;
    // Move the step networks before the transition networks: two evolutions per scan.
    let networks: Vec<&str> = stl.split("\nNETWORK ").collect();
    let (mut head, mut trans, mut steps, mut rest) = (Vec::new(), Vec::new(), Vec::new(), Vec::new());
    for (i, n) in networks.iter().enumerate() {
        if i == 0 {
            head.push(n.to_string());
        } else if n.contains("// transition") {
            trans.push(format!("NETWORK {n}"));
        } else if n.contains("// step ") {
            steps.push(format!("NETWORK {n}"));
        } else {
            rest.push(format!("NETWORK {n}"));
        }
    }
    let first = rest.remove(0);
    let wrong = [head, vec![first], steps, trans, rest].concat().join("\n");
    let caught = (1..=5).filter(|&seed| differential("wrong", &text, &wrong, Run::new(100 * MS, 200, seed)).is_err());
    assert!(caught.count() > 0, "a program with two evolutions per scan passed the differential test");
    // A wrong timer preset.
    let text = std::fs::read_to_string(fixture_dir().join("step_times.st")).expect("fixture");
    let stl = build("step_times.st", &text, StlMethod::SetReset).1.expect("accepted").text;
    let wrong = stl.replacen(", +", ", +1", 1);
    assert_ne!(wrong, stl);
    assert!(
        (1..=5).any(|seed| differential("wrong", &text, &wrong, Run::new(100 * MS, 300, seed)).is_err()),
        "a wrong timer preset passed"
    );
    // The step timers executed a second time after the step networks (the old generator's
    // form): caught by the count of executions, and by the time they gain.
    let mut twice = stl.clone();
    let timers: Vec<&str> = stl
        .split("\nNETWORK ")
        .find(|n| n.contains("// timers: each"))
        .expect("a timer network")
        .lines()
        .skip(1)
        .collect();
    let _ = write!(twice, "NETWORK 999 // timers again\n{}\n", timers.join("\n"));
    let e = differential("twice", &text, &twice, Run::new(100 * MS, 300, 1)).expect_err("caught");
    assert!(e.contains("ran 2 times"), "{e}");
}

// ---------------------------------------------------------------------------------------------
// The project's own charts and the limits of the S7-200

fn st_files(dir: &Path, out: &mut Vec<PathBuf>) {
    let Ok(rd) = std::fs::read_dir(dir) else { return };
    for e in rd.flatten() {
        let p = e.path();
        if p.is_dir() {
            st_files(&p, out);
        } else if p.extension().is_some_and(|x| x == "st") {
            out.push(p);
        }
    }
}

/// Every chart of the valid fixtures, the simulator's semantics fixtures and the examples is
/// either built, and then agrees with the S7-200 model, or refused with located STL diagnostics.
#[test]
fn project_charts_build_and_agree_or_are_refused() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let mut files = Vec::new();
    for d in ["tests/fixtures/valid", "crates/sfc-sim/tests/semantics", "examples"] {
        st_files(&root.join(d), &mut files);
    }
    files.sort();
    assert!(files.len() > 40, "{files:?}");
    let (mut built, mut refused) = (Vec::new(), 0);
    for path in files {
        let text = std::fs::read_to_string(&path).expect("UTF-8");
        let name = path.strip_prefix(&root).unwrap_or(&path).display().to_string();
        let checked = check_source(0, &name, &text, &CheckOptions::default());
        if checked.has_errors() {
            continue;
        }
        for chart in &checked.charts {
            for method in METHODS {
                match build_stl(&checked, chart, StlOptions { method }) {
                    Ok(p) => {
                        parse(&p.text).unwrap_or_else(|e| panic!("{name}: {e}"));
                        // The simulator runs the chart's POU.
                        if checked.charts.len() == 1 {
                            for run in [Run::new(100 * MS, 300, 11), Run::new(70 * MS, 300, 12)] {
                                if let Err(e) = differential_pou(&name, &text, Some(&chart.pou), &p.text, run) {
                                    panic!("{method:?}: {e}\n--- program\n{}", p.text);
                                }
                            }
                            built.push(format!("{name} ({})", method.name()));
                        }
                    }
                    Err(diags) => {
                        refused += 1;
                        assert!(!diags.is_empty(), "{name}: refused without a diagnostic");
                        for d in &diags {
                            // SFC081x: the S7-200's limits; SFC0806: CODESYS's actions not generated.
                            assert!(
                                d.code.starts_with("SFC081") || d.code == "SFC0806",
                                "{name}: {} {}",
                                d.code,
                                d.message
                            );
                            assert!(d.span.end > d.span.start, "{name}: {} without a location", d.code);
                            assert!(sfc_diagnostics::explain(d.code).is_some(), "{} is not registered", d.code);
                        }
                    }
                }
            }
        }
    }
    eprintln!("project charts: {} built and compared ({}), {refused} refused", built.len(), built.join(", "));
    assert!(built.len() >= 30, "only {} project charts were built: {built:?}", built.len());
}

/// More than 256 steps: the steps go on in M bits; more than the M area: V bits. The program
/// still agrees with the model. The SCR method, which needs S bits, refuses the chart.
#[test]
fn long_charts_overflow_into_m_and_v_bits() {
    let n = 600;
    let mut text = String::from("PROGRAM Long\n    VAR_INPUT\n        Go : BOOL;\n    END_VAR\n");
    text.push_str("    VAR_OUTPUT\n        Odd : BOOL;\n    END_VAR\n");
    text.push_str("    INITIAL_STEP S0: END_STEP\n");
    for i in 1..n {
        let _ = writeln!(text, "    STEP S{i}:{} END_STEP", if i % 2 == 1 { " Odd(N);" } else { "" });
    }
    for i in 0..n {
        let guard = if i % 3 == 0 { "Go" } else { "TRUE" };
        let _ = writeln!(text, "    TRANSITION FROM S{i} TO S{} := {guard}; END_TRANSITION", (i + 1) % n);
    }
    text.push_str("END_PROGRAM\n");
    let stl = build("long.st", &text, StlMethod::SetReset).1.expect("a long chart is built").text;
    let alloc = allocation(&stl);
    assert_eq!(alloc.steps[255].1, "S31.7");
    assert!(alloc.steps[256].1.starts_with('M'), "{:?}", alloc.steps[256]);
    assert!(stl.contains("//   V"), "transition bits continue in V memory");
    differential("long.st", &text, &stl, Run::new(100 * MS, 1500, 3)).unwrap_or_else(|e| panic!("{e}"));
    let scr = build("long.st", &text, StlMethod::Scr).1.expect_err("refused");
    assert_eq!(scr.iter().map(|d| d.code).collect::<Vec<_>>(), vec!["SFC0815"], "{scr:?}");
}

/// Every distinct step-time constant takes a timer: beyond the S7-200's 182 TON the chart is
/// refused with SFC0815, not compiled with a timer twice.
#[test]
fn too_many_timers_are_refused() {
    let mut text = String::from("PROGRAM Timers\n    INITIAL_STEP S0: END_STEP\n    STEP S1: END_STEP\n");
    for i in 1..=200 {
        let _ = writeln!(text, "    TRANSITION FROM S0 TO S1 := S0.T >= T#{}ms; END_TRANSITION", i * 100);
    }
    text.push_str("    TRANSITION FROM S1 TO S0 := TRUE; END_TRANSITION\nEND_PROGRAM\n");
    let diags = build("timers.st", &text, StlMethod::SetReset).1.expect_err("refused");
    assert_eq!(diags.iter().map(|d| d.code).collect::<Vec<_>>(), vec!["SFC0815"], "{diags:?}");
    assert!(diags[0].message.contains("200 TON"), "{}", diags[0].message);
}

/// A file with errors is not compiled: its errors come back.
#[test]
fn a_file_with_errors_returns_them() {
    let text = "PROGRAM Bad\n    INITIAL_STEP S0: END_STEP\n    TRANSITION FROM S0 TO S9 := Nope; END_TRANSITION\nEND_PROGRAM\n";
    let (checked, result) = build("bad.st", text, StlMethod::SetReset);
    let diags = result.expect_err("refused");
    assert!(checked.has_errors());
    assert!(!diags.is_empty() && diags.iter().all(|d| d.is_error() && !d.code.starts_with("SFC081")), "{diags:?}");
}

/// The symbol table: one row per operand, valid unique Micro/WIN symbols, quoted CSV.
#[test]
fn symbol_table_is_valid_csv_for_micro_win() {
    let text = std::fs::read_to_string(fixture_dir().join("carwash_textbook.st")).expect("fixture");
    let p = build("carwash_textbook.st", &text, StlMethod::Scr).1.expect("accepted");
    let mut lines = p.symbols.lines();
    assert_eq!(lines.next(), Some("Symbol,Address,Comment"));
    let mut seen = std::collections::HashSet::new();
    let mut rows = 0;
    for line in lines {
        let sym = line.split(',').next().unwrap();
        assert!(sym.len() <= 23 && !sym.starts_with(|c: char| c.is_ascii_digit()), "{sym}");
        assert!(sym.chars().all(|c| c.is_ascii_alphanumeric() || c == '_'), "{sym}");
        assert!(seen.insert(sym.to_ascii_uppercase()), "duplicate {sym}");
        rows += 1;
    }
    assert_eq!(rows, p.text.lines().filter(|l| l.starts_with("//   ")).count());
    assert!(p.symbols.contains("StartButton,I0.0,"));
}

/// docs/targets.md shows the seed 002 car wash in both methods: exactly the programs the
/// generator writes today.
#[test]
fn the_documented_car_wash_is_the_generated_one() {
    let doc = std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("../../docs/targets.md")).unwrap();
    let text = std::fs::read_to_string(fixture_dir().join("carwash_textbook.st")).expect("fixture");
    for method in METHODS {
        let p = build("carwash_textbook.st", &text, method).1.expect("accepted");
        // The first line names the file as given; the rest must be on the page as it is.
        let program: String = p.text.lines().skip(1).map(|l| format!("{l}\n")).collect();
        assert!(doc.contains(program.trim_end()), "docs/targets.md does not show the {method:?} program:\n{}", p.text);
    }
}
