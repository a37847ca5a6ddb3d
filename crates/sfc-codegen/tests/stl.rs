//! The S7-200 statement-list target.
//!
//! - Fixtures `tests/stl/*.st`: a chart the target accepts has its expected program beside it
//!   as `*.stl`; a chart it refuses lists the expected diagnostics inline (`(*! SFC0812 *)` on
//!   the line where each starts) and keeps their rendering as `*.stderr`. Both files are
//!   rewritten with `UPDATE_EXPECT=1`.
//! - Differential test: every accepted fixture and a few hundred random block-structured charts
//!   run in the simulator and, as generated statement list, in the S7-200 interpreter of
//!   `s7200/` with the same random inputs and scan period; active steps, every variable and
//!   every action's `Q`/`A` must agree after every scan, scan 0 included.
//! - The interpreter itself is checked on hand-written programs.

mod s7200;

use s7200::{parse, Plc};
use sfc_codegen::stl::build_stl;
use sfc_diagnostics::{render_human, Diagnostic, RenderOptions};
use sfc_model::{check_source, CheckOptions};
use sfc_sim::{SimOptions, Simulation, Value};
use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

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

fn build(name: &str, text: &str) -> (sfc_model::Checked, Result<String, Vec<Diagnostic>>) {
    let checked = check_source(0, name, text, &CheckOptions { keep_types: true, ..Default::default() });
    let result = match checked.charts.first() {
        Some(chart) => build_stl(&checked, chart),
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
            "flag" if name.ends_with(".Q") || name.ends_with(".A") => a.flags.push((name, addr)),
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
    /// `unsafe` and `conflict` events of the simulator.
    unsafe_events: usize,
    conflicts: usize,
}

/// Runs `text` in the simulator and its statement list in the interpreter for `scans` scans
/// with random inputs; the first difference is an error with the history that led to it.
fn differential(name: &str, text: &str, stl: &str, period: i64, scans: usize, seed: u64) -> Result<Coverage, String> {
    let opts = SimOptions { period, ..Default::default() };
    let mut sim = match Simulation::from_source(name, text, None, opts) {
        Ok(s) => s,
        Err((_, d)) => return Err(format!("{name}: the simulator refuses the chart: {d:?}")),
    };
    let prog = parse(stl).map_err(|e| format!("{name}: the interpreter refuses the program: {e}"))?;
    let mut plc = Plc::new(prog);
    let alloc = allocation(stl);
    let inputs: Vec<&(String, String, bool)> = alloc.vars.iter().filter(|v| v.2).collect();
    let outputs: Vec<&(String, String, bool)> = alloc.vars.iter().filter(|v| !v.2).collect();
    let mut rng = Rng::new(seed);
    let mut values: Vec<bool> = inputs.iter().map(|_| rng.chance(50)).collect();
    let mut history = String::new();
    let mut cov = Coverage { steps: alloc.steps.len(), ..Default::default() };
    let mut last: Vec<bool> = Vec::new();
    for k in 0..scans {
        for (i, (vname, addr, _)) in inputs.iter().enumerate() {
            if k > 0 && rng.chance(30) {
                values[i] = !values[i];
            }
            sim.set(vname, Value::Bool(values[i])).map_err(|e| format!("{name}: set {vname}: {e}"))?;
            plc.set(addr, values[i]).map_err(|e| format!("{name}: set {addr}: {e}"))?;
        }
        let record = sim.scan().clone();
        if let Some(e) = sim.error() {
            return Err(format!("{name}: simulator error in scan {k}: {}", e.message));
        }
        plc.scan(k as i64 * period).map_err(|e| format!("{name}: interpreter error in scan {k}: {e}"))?;
        let ins: Vec<String> =
            inputs.iter().zip(&values).map(|((n, _, _), v)| format!("{n}={}", u8::from(*v))).collect();
        let mut plc_active: Vec<String> = Vec::new();
        for (s, addr) in &alloc.steps {
            if plc.get(addr)? {
                plc_active.push(s.clone());
            }
        }
        plc_active.sort();
        let _ = writeln!(
            history,
            "scan {k}: inputs {} | sim active {:?} fired {:?}",
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
        for (vname, addr) in outputs.iter().map(|v| (&v.0, &v.1)).chain(alloc.flags.iter().map(|f| (&f.0, &f.1))) {
            let s = sim.get(vname).and_then(|v| v.as_bool());
            let p = plc.get(addr)?;
            if s != Some(p) {
                diffs.push(format!("{vname} ({addr}): sim {s:?}, plc {p}"));
            }
            now.push(p);
            cov.compared += 1;
        }
        cov.changes += now.iter().zip(&last).filter(|(a, b)| a != b).count();
        last = now;
        if !diffs.is_empty() {
            return Err(format!(
                "{name}: scan {k} (t = {} ms) differs:\n  {}\nhistory:\n{history}",
                k as i64 * period / 1000,
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
        let (checked, result) = build(&name, &text);
        let expected = expectations(&text);
        match result {
            Ok(stl) => {
                if !expected.is_empty() {
                    failures.push(format!("{name}: expected diagnostics {expected:?}, but the program was built"));
                }
                if let Err(e) = expect_file(&path.with_extension("stl"), &stl) {
                    failures.push(e);
                }
            }
            Err(diags) => {
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
                let rendered: String = diags
                    .iter()
                    .map(|d| render_human(d, std::slice::from_ref(&checked.file), RenderOptions::default()) + "\n")
                    .collect();
                if let Err(e) = expect_file(&path.with_extension("stderr"), &rendered) {
                    failures.push(e);
                }
            }
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n\n"));
}

#[test]
fn accepted_fixtures_agree_with_the_simulator() {
    let mut ran = 0;
    for path in fixtures() {
        let text = std::fs::read_to_string(&path).expect("fixture is UTF-8");
        let name = display_name(&path);
        let Ok(stl) = build(&name, &text).1 else { continue };
        let mut reached = std::collections::BTreeSet::new();
        let mut steps = 0;
        for (seed, period) in [(1, 100_000), (2, 100_000), (3, 200_000), (4, 300_000), (5, 100_000)] {
            match differential(&name, &text, &stl, period, 400, seed) {
                Ok(c) => {
                    reached.extend(c.steps_active);
                    steps = c.steps;
                }
                Err(e) => panic!("{e}\n--- program\n{stl}"),
            }
        }
        eprintln!("{name}: {} of {steps} steps reached", reached.len());
        assert_eq!(reached.len(), steps, "{name}: random inputs did not reach every step");
        ran += 1;
    }
    assert!(ran >= 6, "only {ran} fixtures were accepted");
}

#[test]
fn the_refused_fixtures_are_refused_by_this_target_only() {
    // A refused fixture must still be a valid chart: the refusal is the target's.
    for path in fixtures() {
        let text = std::fs::read_to_string(&path).expect("fixture is UTF-8");
        let (checked, result) = build(&display_name(&path), &text);
        if result.is_err() {
            assert!(!checked.has_errors(), "{}: {:?}", path.display(), checked.diagnostics);
        }
    }
}

// ---------------------------------------------------------------------------------------------
// Random charts

/// A random block-structured chart: sequences, selections (with and without PRIORITY),
/// simultaneous branches, loops back, over BOOL inputs (VAR_INPUT and `AT %IX`), with N, S,
/// R, P, L, D, SD, DS, SL, P1, P0 associations to BOOL outputs and to actions whose bodies
/// assign BOOL expressions (also under IF), guards with AND/OR/NOT/XOR/=/<>, step flags,
/// action flags and step-time comparisons (multiples of 100 ms).
struct ChartGen {
    rng: Rng,
    inputs: Vec<String>,
    outputs: Vec<(String, Option<(&'static str, u32)>)>,
    actions: Vec<(String, Option<(&'static str, u32)>)>,
    steps: Vec<(String, bool, Vec<String>)>,
    transitions: Vec<String>,
    seen: std::collections::HashSet<(Vec<usize>, Vec<usize>, String)>,
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
        ChartGen { rng, inputs, outputs, actions, steps: Vec::new(), transitions: Vec::new(), seen: Default::default() }
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
                quals.extend(["P1", "P0"]);
            }
            let a = match timed {
                Some((q, d)) if self.rng.chance(40) => format!("{name}({q}, T#{}ms)", d * 100),
                _ => format!("{name}({})", quals[self.rng.below(quals.len())]),
            };
            assocs.push(a);
        }
        self.steps.push((format!("S{i}"), initial, assocs));
        i
    }

    fn time_cmp(&mut self, step: usize, exact: bool) -> String {
        let ops = if exact { ["=", "<>", "=", "<>"] } else { [">=", ">", "<", "<="] };
        let op = ops[self.rng.below(ops.len())];
        // `< T#0s` never holds: lower bounds may be 0, upper bounds start at 100 ms.
        let least = usize::from(op.starts_with('<'));
        format!("(S{step}.T {op} T#{}ms)", (least + self.rng.below(9 - least)) * 100)
    }

    fn leaf(&mut self, from: usize) -> String {
        match self.rng.below(17) {
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
        let guard = None;
        self.transition_with(from, to, priority, guard);
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

    fn body(&mut self) -> String {
        let mut out = String::new();
        for _ in 0..1 + self.rng.below(3) {
            let s = self.rng.below(self.steps.len());
            let target = self.outputs[self.rng.below(self.outputs.len())].0.clone();
            if self.rng.chance(25) {
                let c = self.expr(s, 2);
                let v = self.expr(s, 2);
                let other = self.outputs[self.rng.below(self.outputs.len())].0.clone();
                let _ = writeln!(out, "        IF {c} THEN\n            {target} := {v};");
                if self.rng.chance(50) {
                    let c2 = self.expr(s, 1);
                    let _ = writeln!(out, "        ELSIF {c2} THEN\n            {other} := NOT {other};");
                }
                let _ = writeln!(out, "        ELSE\n            {other} := TRUE;\n        END_IF;");
            } else {
                let v = self.expr(s, 2);
                let _ = writeln!(out, "        {target} := {v};");
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
        let mut text = format!("PROGRAM Random{seed}\n    VAR_INPUT\n");
        let located: Vec<bool> = self.inputs.iter().map(|_| self.rng.chance(40)).collect();
        for (i, n) in self.inputs.iter().enumerate() {
            if !located[i] {
                let _ = writeln!(text, "        {n} : BOOL;");
            }
        }
        text.push_str("    END_VAR\n    VAR\n");
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
        for (name, initial, assocs) in &self.steps {
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
        for name in names {
            let body = self.body();
            let _ = writeln!(text, "    ACTION {name}:\n{body}    END_ACTION\n");
        }
        text.push_str("END_PROGRAM\n");
        text
    }
}

#[test]
fn random_charts_agree_with_the_simulator() {
    let charts: u64 = std::env::var("STL_RANDOM_CHARTS").ok().and_then(|v| v.parse().ok()).unwrap_or(300);
    let (mut scans_total, mut fired, mut steps, mut active, mut changes, mut compared) = (0, 0, 0, 0, 0, 0);
    let (mut unsafe_events, mut conflicts) = (0, 0);
    for seed in 1..=charts {
        let text = ChartGen::new(seed).generate(seed);
        let name = format!("random{seed}.st");
        if std::env::var("STL_DUMP").ok().and_then(|v| v.parse::<u64>().ok()) == Some(seed) {
            eprintln!("{text}");
        }
        let (checked, result) = build(&name, &text);
        assert!(!checked.has_errors(), "generated chart {seed} does not check: {:?}\n{text}", checked.diagnostics);
        let stl = match result {
            Ok(s) => s,
            Err(d) => panic!("random chart {seed} refused: {d:?}\n{text}"),
        };
        let period = [100_000, 100_000, 200_000][(seed % 3) as usize];
        match differential(&name, &text, &stl, period, 400, seed * 7919) {
            Ok(c) => {
                fired += c.fired;
                steps += c.steps;
                active += c.steps_active.len();
                if std::env::var_os("STL_DEBUG").is_some() {
                    eprintln!("chart {seed}: {} of {} steps, {} firings", c.steps_active.len(), c.steps, c.fired);
                }
                changes += c.changes;
                compared += c.compared;
                unsafe_events += c.unsafe_events;
                conflicts += c.conflicts;
            }
            Err(e) => panic!("{e}\n--- chart\n{text}\n--- program\n{stl}"),
        }
        scans_total += 400;
    }
    eprintln!(
        "{charts} random charts, {scans_total} scans: {fired} firings, {active} of {steps} steps reached, \
         {changes} changes in {compared} compared values, {unsafe_events} unsafe and {conflicts} conflict events"
    );
    // The comparison must have something to compare: charts that evolve and outputs that move.
    assert!(fired > scans_total / 4, "too few firings: {fired}");
    assert!(active * 10 > steps * 6, "too few steps reached: {active} of {steps}");
    assert!(changes * 20 > compared, "outputs hardly change: {changes} of {compared}");
    assert!(unsafe_events > 0 && conflicts > 0, "no unsafe or no conflicting situation was compared");
}

/// The differential test must be able to fail: a program whose transitions see the steps they
/// set in the same scan (the SCR trap) is caught.
#[test]
fn the_differential_test_detects_a_wrong_program() {
    let text = std::fs::read_to_string(fixture_dir().join("carwash_textbook.st")).expect("fixture");
    let stl = build("carwash_textbook.st", &text).1.expect("accepted");
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
    let mut caught = 0;
    for seed in 1..=5 {
        if differential("wrong", &text, &wrong, 100_000, 200, seed).is_err() {
            caught += 1;
        }
    }
    assert!(caught > 0, "a program with two evolutions per scan passed the differential test");
    // And a program with a wrong timer preset.
    let text = std::fs::read_to_string(fixture_dir().join("step_times.st")).expect("fixture");
    let stl = build("step_times.st", &text).1.expect("accepted");
    let wrong = stl.replacen(", +", ", +1", 1);
    assert_ne!(wrong, stl);
    assert!(
        (1..=5).any(|seed| differential("wrong", &text, &wrong, 100_000, 300, seed).is_err()),
        "a wrong timer preset passed"
    );
}

// ---------------------------------------------------------------------------------------------
// The interpreter on hand-written programs

#[test]
fn interpreter_logic_stack() {
    let prog = parse(
        "NETWORK 1\n\
         LD I0.0\nLD I0.1\nO I0.2\nALD\n= Q0.0\n\
         NETWORK 2\n\
         LD I0.0\nLPS\nA I0.1\n= Q0.1\nLRD\nAN I0.1\n= Q0.2\nLPP\nNOT\n= Q0.3\n\
         NETWORK 3\n\
         LDN I0.0\nA I0.1\nLD I0.0\nAN I0.1\nOLD\n= Q0.4\n",
    )
    .expect("parses");
    let mut plc = Plc::new(prog);
    for (a, b, c) in [(false, false, false), (true, false, true), (true, true, false), (false, true, true)] {
        plc.set("I0.0", a).unwrap();
        plc.set("I0.1", b).unwrap();
        plc.set("I0.2", c).unwrap();
        plc.scan(0).unwrap();
        assert_eq!(plc.get("Q0.0").unwrap(), a && (b || c));
        assert_eq!(plc.get("Q0.1").unwrap(), a && b);
        assert_eq!(plc.get("Q0.2").unwrap(), a && !b);
        assert_eq!(plc.get("Q0.3").unwrap(), !a);
        assert_eq!(plc.get("Q0.4").unwrap(), a != b);
    }
    // The stack holds 9 levels: a tenth load loses the bottom, which ALD then cannot read.
    let mut deep = String::from("NETWORK 1\n");
    for _ in 0..10 {
        deep.push_str("LD I0.0\n");
    }
    deep.push_str(&"ALD\n".repeat(9));
    assert!(Plc::new(parse(&deep).unwrap()).scan(0).is_err());
    // Each network starts with an undefined stack.
    assert!(Plc::new(parse("NETWORK 1\nA I0.0\n= Q0.0\n").unwrap()).scan(0).is_err());
    assert!(parse("LDI I0.0\n").is_err(), "immediate instructions are not modelled");
    assert!(Plc::new(parse("LD SM0.0\n= I0.0\n").unwrap()).scan(0).is_err(), "inputs are read-only");
}

#[test]
fn interpreter_set_reset_edges_first_scan() {
    let prog = parse(
        "NETWORK 1\nLD SM0.1\nS M0.0, 3\n\
         NETWORK 2\nLD I0.0\nR M0.1, 2\n\
         NETWORK 3\nLD I0.1\nEU\n= Q0.0\n\
         NETWORK 4\nLD I0.1\nED\n= Q0.1\n\
         NETWORK 5\nLD SM0.0\n= Q0.2\n",
    )
    .expect("parses");
    let mut plc = Plc::new(prog);
    plc.set("I0.1", true).unwrap();
    plc.scan(0).unwrap();
    assert!(plc.get("M0.0").unwrap() && plc.get("M0.1").unwrap() && plc.get("M0.2").unwrap());
    assert!(plc.get("Q0.0").unwrap(), "EU: rising edge in the first scan");
    assert!(!plc.get("Q0.1").unwrap());
    assert!(plc.get("Q0.2").unwrap());
    plc.set("I0.0", true).unwrap();
    plc.scan(1).unwrap();
    assert!(plc.get("M0.0").unwrap() && !plc.get("M0.1").unwrap() && !plc.get("M0.2").unwrap());
    assert!(!plc.get("Q0.0").unwrap(), "EU: one scan only");
    plc.set("I0.1", false).unwrap();
    plc.scan(2).unwrap();
    assert!(plc.get("Q0.1").unwrap(), "ED: falling edge");
    plc.scan(3).unwrap();
    assert!(!plc.get("Q0.1").unwrap());
    assert!(!plc.get("SM0.1").unwrap());
}

#[test]
fn interpreter_timers() {
    let prog = parse("NETWORK 1\nLD I0.0\nTON T37, +3\nNETWORK 2\nLD I0.1\nTONR T5, +4\nNETWORK 3\nLD I0.2\nR T5, 1\n")
        .expect("parses");
    let mut plc = Plc::new(prog);
    let ms = 1000;
    plc.set("I0.0", true).unwrap();
    plc.set("I0.1", true).unwrap();
    let mut t37 = Vec::new();
    let mut t5 = Vec::new();
    for k in 0..8i64 {
        if k == 2 {
            plc.set("I0.1", false).unwrap();
        }
        if k == 4 {
            plc.set("I0.1", true).unwrap();
            plc.set("I0.0", false).unwrap();
        }
        plc.scan(k * 100 * ms).unwrap();
        t37.push((plc.timer_value(37), plc.get("T37").unwrap()));
        t5.push((plc.timer_value(5), plc.get("T5").unwrap()));
    }
    // TON: counts from its first enabled execution, clears when disabled.
    assert_eq!(&t37[..5], &[(0, false), (1, false), (2, false), (3, true), (0, false)]);
    // TONR: holds while disabled (scans 2, 3), continues, bit at 4.
    assert_eq!(t5, vec![(0, false), (1, false), (1, false), (1, false), (1, false), (2, false), (3, false), (4, true)]);
    plc.set("I0.2", true).unwrap();
    plc.scan(800 * ms).unwrap();
    assert_eq!((plc.timer_value(5), plc.get("T5").unwrap()), (0, false), "R clears a TONR");
    assert!(parse("TON T5, +3").is_ok() && Plc::new(parse("LD SM0.0\nTON T5, +3").unwrap()).scan(0).is_err());
}

/// The SCR instructions, on the pattern of the textbook's figure 3-35: S0.1 and S0.2 alternate
/// on I0.0, each segment drives its output; `SCRT` changes the S bits at once, so a segment
/// later in the program runs in the same scan (why the generator does not use SCR).
#[test]
fn interpreter_scr_segments() {
    let prog = parse(
        "NETWORK 1\nLD SM0.1\nS S0.1, 1\n\
         NETWORK 2\nLSCR S0.1\n\
         NETWORK 3\nLD SM0.0\n= Q0.1\n\
         NETWORK 4\nLD I0.0\nSCRT S0.2\n\
         NETWORK 5\nSCRE\n\
         NETWORK 6\nLSCR S0.2\n\
         NETWORK 7\nLD SM0.0\n= Q0.2\n\
         NETWORK 8\nLD I0.1\nSCRT S0.1\n\
         NETWORK 9\nSCRE\n",
    )
    .expect("parses");
    let mut plc = Plc::new(prog);
    plc.scan(0).unwrap();
    assert!(plc.get("S0.1").unwrap() && plc.get("Q0.1").unwrap() && !plc.get("S0.2").unwrap());
    plc.set("I0.0", true).unwrap();
    plc.set("I0.1", true).unwrap();
    plc.scan(1).unwrap();
    // S0.1 -> S0.2 and, in the same scan, S0.2 -> S0.1 again: two evolutions in one scan.
    assert!(plc.get("S0.1").unwrap() && !plc.get("S0.2").unwrap());
    assert!(plc.get("Q0.2").unwrap(), "the segment of S0.2 ran in the scan S0.2 was set");
    plc.set("I0.1", false).unwrap();
    plc.scan(2).unwrap();
    assert!(!plc.get("S0.1").unwrap() && plc.get("S0.2").unwrap());
    assert!(Plc::new(parse("NETWORK 1\nLD SM0.0\nSCRT S0.1\n").unwrap()).scan(0).is_err());
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
/// either built, and then agrees with the simulator, or refused with located STL diagnostics.
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
        let checked = check_source(0, &name, &text, &CheckOptions { keep_types: true, ..Default::default() });
        if checked.has_errors() {
            continue;
        }
        for chart in &checked.charts {
            match build_stl(&checked, chart) {
                Ok(stl) => {
                    parse(&stl).unwrap_or_else(|e| panic!("{name}: {e}"));
                    // The simulator runs the file's only SFC POU (or its only PROGRAM).
                    if checked.charts.len() == 1 {
                        if let Err(e) = differential(&name, &text, &stl, 100_000, 300, 11) {
                            panic!("{e}\n--- program\n{stl}");
                        }
                        built.push(name.clone());
                    }
                }
                Err(diags) => {
                    refused += 1;
                    assert!(!diags.is_empty(), "{name}: refused without a diagnostic");
                    for d in &diags {
                        assert!(d.code.starts_with("SFC081"), "{name}: {} {}", d.code, d.message);
                        assert!(d.span.end > d.span.start, "{name}: {} without a location", d.code);
                        assert!(sfc_diagnostics::explain(d.code).is_some(), "{} is not registered", d.code);
                    }
                }
            }
        }
    }
    eprintln!("project charts: {} built and compared ({}), {refused} refused", built.len(), built.join(", "));
    assert!(built.len() >= 15, "only {} project charts were built: {built:?}", built.len());
}

/// More than 256 steps: the steps go on in M bits; more than the M area: V bits. The program
/// still agrees with the simulator.
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
    let stl = build("long.st", &text).1.expect("a long chart is built");
    let alloc = allocation(&stl);
    assert_eq!(alloc.steps[255].1, "S31.7");
    assert!(alloc.steps[256].1.starts_with('M'), "{:?}", alloc.steps[256]);
    assert!(stl.contains("//   V"), "transition bits continue in V memory");
    differential("long.st", &text, &stl, 100_000, 1500, 3).unwrap_or_else(|e| panic!("{e}"));
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
    let diags = build("timers.st", &text).1.expect_err("refused");
    assert_eq!(diags.iter().map(|d| d.code).collect::<Vec<_>>(), vec!["SFC0815"], "{diags:?}");
    assert!(diags[0].message.contains("200 TON"), "{}", diags[0].message);
}

/// A file with errors is not compiled: its errors come back.
#[test]
fn a_file_with_errors_returns_them() {
    let text = "PROGRAM Bad\n    INITIAL_STEP S0: END_STEP\n    TRANSITION FROM S0 TO S9 := Nope; END_TRANSITION\nEND_PROGRAM\n";
    let (checked, result) = build("bad.st", text);
    let diags = result.expect_err("refused");
    assert!(checked.has_errors());
    assert!(!diags.is_empty() && diags.iter().all(|d| d.is_error() && !d.code.starts_with("SFC081")), "{diags:?}");
}
