//! The `codesys` profile against `iec`, on random charts where the documented rules coincide,
//! and random hierarchical charts under every profile.
//!
//! 1. Where CODESYS's rules and IEC's coincide — no step actions, at most one N action per step
//!    (each counting its own runs, so the alphabetical body order changes nothing), guards that
//!    read inputs only and exclude each other at every divergence (no conflict), nothing TRUE in
//!    scan 0 — the two profiles give the same situations and firings in every scan, and the
//!    action phase of `codesys` in scan `k` does what `iec`'s did in scan `k − 1` ("Processing
//!    order in SFC": the actions run on the situation the previous call's transitions left,
//!    before this call's transitions). The counters' increments are compared that way.
//! 2. Random hierarchical charts — function blocks whose SFC bodies and SFC actions call each
//!    other's actions, recursion included — run under every profile without a panic or a hang:
//!    every scan ends, normally or with a located runtime error, within the scan budget.
//!
//! `SFC_CODESYS_CASES=N` changes the number of cases of each (default 150 and 60).

use sfc_sim::{Profile, SimOptions, Simulation, Value};
use std::fmt::Write as _;
use std::panic::{catch_unwind, AssertUnwindSafe};

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

fn cases(default: usize) -> usize {
    std::env::var("SFC_CODESYS_CASES").ok().and_then(|v| v.parse().ok()).unwrap_or(default)
}

const INPUTS: usize = 4;

/// A block-structured chart as IEC text: sequences, selections (guards `Sel = k`, exclusive),
/// simultaneous branches, and a jump back to the initial step at the end.
struct Gen {
    rng: Rng,
    text: String,
    steps: usize,
    actions: Vec<usize>,
    trans: usize,
}

impl Gen {
    fn step(&mut self) -> usize {
        let s = self.steps;
        self.steps += 1;
        let kw = if s == 0 { "INITIAL_STEP" } else { "STEP" };
        let _ = write!(self.text, "{kw} S{s}:");
        if self.rng.chance(60) {
            let _ = write!(self.text, " A{s}(N);");
            self.actions.push(s);
        }
        let _ = writeln!(self.text, " END_STEP");
        s
    }
    fn guard(&mut self) -> String {
        let i = self.rng.below(INPUTS);
        if self.rng.chance(30) {
            format!("Run AND NOT In{i}")
        } else {
            format!("Run AND In{i}")
        }
    }
    fn transition(&mut self, from: &[usize], to: &[usize], guard: &str) {
        let t = self.trans;
        self.trans += 1;
        let list = |v: &[usize]| {
            let names: Vec<String> = v.iter().map(|s| format!("S{s}")).collect();
            if names.len() == 1 {
                names[0].clone()
            } else {
                format!("({})", names.join(", "))
            }
        };
        let _ = writeln!(self.text, "TRANSITION T{t} FROM {} TO {} := {guard}; END_TRANSITION", list(from), list(to));
    }
    /// A block after step `from` (whose outgoing transitions it writes); returns its last step.
    fn block(&mut self, from: usize, depth: usize) -> usize {
        let kind = if depth > 2 || self.steps > 14 { 0 } else { self.rng.below(4) };
        match kind {
            1 => {
                // Selection: exclusive guards `Sel = k`, joined by a step.
                let n = 2 + self.rng.below(2);
                let mut ends = Vec::new();
                for k in 0..n {
                    let s = self.step();
                    self.transition(&[from], &[s], &format!("Run AND Sel = {k}"));
                    ends.push(self.block(s, depth + 1));
                }
                let join = self.step();
                for e in ends {
                    let g = self.guard();
                    self.transition(&[e], &[join], &g);
                }
                join
            }
            2 => {
                // Simultaneous divergence and convergence.
                let n = 2 + self.rng.below(2);
                let firsts: Vec<usize> = (0..n).map(|_| self.step()).collect();
                let g = self.guard();
                self.transition(&[from], &firsts, &g);
                let ends: Vec<usize> = firsts.iter().map(|&s| self.block(s, depth + 1)).collect();
                let join = self.step();
                let g = self.guard();
                self.transition(&ends, &[join], &g);
                join
            }
            _ => {
                let s = self.step();
                let g = self.guard();
                self.transition(&[from], &[s], &g);
                if self.rng.chance(40) && depth < 3 {
                    self.block(s, depth + 1)
                } else {
                    s
                }
            }
        }
    }
}

fn coinciding_chart(seed: u64) -> (String, Vec<usize>) {
    let mut g = Gen { rng: Rng(seed | 1), text: String::new(), steps: 0, actions: Vec::new(), trans: 0 };
    let first = g.step();
    let last = g.block(first, 0);
    let guard = g.guard();
    g.transition(&[last], &[first], &guard);
    let mut text = String::from("PROGRAM Random\nVAR_INPUT\n    Run : BOOL;\n    Sel : INT;\n");
    for i in 0..INPUTS {
        let _ = writeln!(text, "    In{i} : BOOL;");
    }
    text.push_str("END_VAR\nVAR_OUTPUT\n");
    for a in &g.actions {
        let _ = writeln!(text, "    C{a} : INT;");
    }
    text.push_str("END_VAR\n");
    text.push_str(&g.text);
    for a in &g.actions {
        let _ = writeln!(text, "ACTION A{a}: C{a} := C{a} + 1; END_ACTION");
    }
    text.push_str("END_PROGRAM\n");
    (text, g.actions)
}

struct Run {
    active: Vec<Vec<String>>,
    fired: Vec<Vec<String>>,
    counters: Vec<Vec<i64>>,
}

fn run(text: &str, profile: Profile, actions: &[usize], inputs: &[(bool, i64, [bool; INPUTS])]) -> Run {
    let opts = SimOptions { period: 10_000, profile };
    let mut sim = Simulation::from_source("random.st", text, None, opts)
        .unwrap_or_else(|(_, d)| panic!("the chart checks: {d:?}\n{text}"));
    let mut out = Run { active: Vec::new(), fired: Vec::new(), counters: Vec::new() };
    for (go, sel, ins) in inputs {
        sim.set("Run", Value::Bool(*go)).unwrap();
        sim.set("Sel", Value::Int(*sel)).unwrap();
        for (i, b) in ins.iter().enumerate() {
            sim.set(&format!("In{i}"), Value::Bool(*b)).unwrap();
        }
        let r = sim.scan();
        assert!(r.events.is_empty(), "no event expected: {:?}\n{text}", r.events);
        out.active.push(r.active.clone());
        out.fired.push(r.fired.clone());
        let counters = actions
            .iter()
            .map(|a| match sim.get(&format!("C{a}")) {
                Some(Value::Int(v)) => v,
                other => panic!("C{a}: {other:?}"),
            })
            .collect();
        out.counters.push(counters);
    }
    out
}

#[test]
fn codesys_and_iec_agree_where_the_documented_rules_coincide() {
    let n = cases(150);
    let mut compared_firings = 0;
    for case in 0..n {
        let seed = (case as u64 + 7).wrapping_mul(0x9E37_79B9_7F4A_7C15);
        let (text, actions) = coinciding_chart(seed);
        let mut rng = Rng(seed ^ 0xABCD_EF01 | 1);
        let inputs: Vec<(bool, i64, [bool; INPUTS])> = (0..60)
            .map(|k| {
                let go = k > 0 && rng.chance(85);
                let sel = rng.below(3) as i64;
                let mut ins = [false; INPUTS];
                for b in &mut ins {
                    *b = rng.chance(50);
                }
                (go, sel, ins)
            })
            .collect();
        let iec = run(&text, Profile::Iec, &actions, &inputs);
        let cds = run(&text, Profile::Codesys, &actions, &inputs);
        for k in 0..inputs.len() {
            assert_eq!(iec.active[k], cds.active[k], "case {case}, scan {k}: situations\n{text}");
            assert_eq!(iec.fired[k], cds.fired[k], "case {case}, scan {k}: firings\n{text}");
            compared_firings += iec.fired[k].len();
        }
        // The action phase of codesys in scan k does what iec's did in scan k - 1.
        let delta = |c: &[Vec<i64>], k: usize| -> Vec<i64> {
            c[k].iter()
                .zip(if k == 0 { None } else { Some(&c[k - 1]) }.into_iter().flatten().chain(std::iter::repeat(&0)))
                .map(|(a, b)| a - b)
                .collect()
        };
        for k in 1..inputs.len() {
            assert_eq!(
                delta(&cds.counters, k),
                delta(&iec.counters, k - 1),
                "case {case}, scan {k}: codesys's action runs against iec's of the scan before\n{text}"
            );
        }
        assert_eq!(delta(&cds.counters, 0), delta(&iec.counters, 0), "case {case}: scan 0\n{text}");
    }
    assert!(compared_firings > n * 10, "the random charts move: {compared_firings} firings");
}

/// Function blocks with SFC bodies and SFC actions that call other instances' actions (and,
/// sometimes, their own chart through a cycle).
fn hierarchical_chart(seed: u64) -> String {
    let mut rng = Rng(seed | 1);
    let blocks = 2 + rng.below(3);
    let mut text = String::new();
    for b in 0..blocks {
        let _ = writeln!(text, "FUNCTION_BLOCK FB{b}\nVAR_INPUT\n    Go : BOOL;\nEND_VAR\nVAR\n    N : INT;");
        // Instances of later blocks (a hierarchy), and of any block through a call of its action.
        let child = (b + 1 < blocks).then(|| b + 1 + rng.below(blocks - b - 1));
        if let Some(c) = child {
            let _ = writeln!(text, "    Sub : FB{c};");
        }
        text.push_str("END_VAR\n");
        let _ = writeln!(text, "INITIAL_STEP B{b}S0: Count(N); END_STEP");
        let _ = writeln!(text, "TRANSITION FROM B{b}S0 TO B{b}S1 := Go; END_TRANSITION");
        let _ = writeln!(text, "STEP B{b}S1: Seq(N); END_STEP");
        let _ = writeln!(text, "TRANSITION FROM B{b}S1 TO B{b}S0 := NOT Go OR B{b}S1.T > T#50ms; END_TRANSITION");
        text.push_str("ACTION Count:\n    N := N + 1;\n");
        if let Some(_c) = child {
            if rng.chance(70) {
                text.push_str("    Sub(Go := Go);\n");
            }
            if rng.chance(50) {
                text.push_str("    Sub.Seq();\n");
            }
        }
        text.push_str("END_ACTION\n");
        let _ = writeln!(text, "ACTION Seq:\n    INITIAL_STEP B{b}Q0: END_STEP");
        let _ = writeln!(text, "    TRANSITION FROM B{b}Q0 TO B{b}Q1 := Go; END_TRANSITION");
        let _ = writeln!(text, "    STEP B{b}Q1: Count(P); END_STEP");
        let _ = writeln!(text, "    TRANSITION FROM B{b}Q1 TO B{b}Q0 := TRUE; END_TRANSITION");
        text.push_str("END_ACTION\n");
        // Sometimes a chart that runs itself: the action's step runs the action.
        if rng.chance(20) {
            text = text.replace(&format!("STEP B{b}Q1: Count(P); END_STEP"), &format!("STEP B{b}Q1: Seq(N); END_STEP"));
        }
        text.push_str("END_FUNCTION_BLOCK\n\n");
    }
    text.push_str("PROGRAM Main\nVAR_INPUT\n    Go : BOOL;\nEND_VAR\nVAR\n    Top : FB0;\nEND_VAR\n");
    text.push_str("    Top(Go := Go);\n    Top.Seq();\nEND_PROGRAM\n");
    text
}

#[test]
fn random_hierarchical_charts_run_under_every_profile_without_panics_or_hangs() {
    let n = cases(60);
    let mut faults = 0;
    for case in 0..n {
        let seed = (case as u64 + 11).wrapping_mul(0x2545_F491_4F6C_DD1D);
        let text = hierarchical_chart(seed);
        for profile in Profile::ALL {
            let result = catch_unwind(AssertUnwindSafe(|| {
                let opts = SimOptions { period: 10_000, profile };
                let mut sim = match Simulation::from_source("h.st", &text, Some("Main"), opts) {
                    Ok(s) => s,
                    Err((_, d)) => return Err(format!("does not check: {d:?}")),
                };
                let mut rng = Rng(seed ^ 0x55 | 1);
                for _ in 0..200 {
                    sim.set("Go", Value::Bool(rng.chance(60))).unwrap();
                    if sim.advance().is_err() {
                        return Ok(true);
                    }
                }
                Ok(false)
            }));
            match result {
                Ok(Ok(faulted)) => faults += usize::from(faulted),
                Ok(Err(e)) => panic!("case {case} ({}): {e}\n{text}", profile.name()),
                Err(_) => panic!("case {case} ({}) panicked\n{text}", profile.name()),
            }
        }
    }
    // Charts that run themselves end in a located fault, not a hang: some must have met it.
    let _ = faults;
}
