//! Differential test of the scan engine against the reference implementation in
//! `tests/reference/` (a direct, slow transcription of `semantics.md`).
//!
//! Random block-structured charts (sequences, selection and simultaneous divergences and
//! convergences with 2–3 branches, loops back to earlier steps, optional explicit priorities,
//! sometimes a second network or an unstructured jump that makes the net unsafe) are printed
//! as IEC text, run by the engine through the public `Simulation` API and by the reference with
//! the same random input schedule, and compared scan by scan: active steps, fired transitions,
//! events, action variables, counters of action bodies, `Action.Q`/`.A` and step times.
//!
//! `SFC_DIFF_CASES=N` changes the number of cases (default 300); `SFC_DIFF_CASE=K` runs case `K`
//! alone (as printed on failure); `SFC_DIFF_SEED=S` (decimal or `0x…`) runs one chart of up to
//! `SFC_DIFF_STEPS` (default 16) steps from seed `S`.

mod reference;

use reference::{Action, ActionKind, Assoc, Chart, Guard, Qual, RefEvent, Reference, Step, Transition};
use sfc_sim::{Event, SimOptions, Simulation, Value};
use std::collections::{HashMap, HashSet};
use std::fmt::Write as _;
use std::panic::{catch_unwind, AssertUnwindSafe};

const PERIOD: i64 = 10_000;
const SCANS: usize = 60;
const INPUTS: usize = 6;
const DEFAULT_CASES: usize = 300;

/// xorshift64: small, deterministic, no dependency.
struct Rng(u64);

impl Rng {
    fn new(seed: u64) -> Rng {
        Rng(if seed == 0 { 0x9E37_79B9_7F4A_7C15 } else { seed })
    }
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
    fn pick<T: Copy>(&mut self, items: &[T]) -> T {
        items[self.below(items.len())]
    }
}

fn case_seed(case: usize) -> u64 {
    (case as u64 + 1).wrapping_mul(0x2545_F491_4F6C_DD1D) ^ 0x5DEE_CE66_D1CE_5EED
}

// ---------------------------------------------------------------------------------------------
// Random charts

const DURATIONS_MS: [i64; 7] = [0, 10, 20, 25, 30, 50, 80];
const GUARD_TIMES_MS: [i64; 7] = [0, 10, 20, 25, 30, 40, 60];

struct Generator<'r> {
    rng: &'r mut Rng,
    chart: Chart,
    max_steps: usize,
    /// Every transition's (sorted from, sorted to, guard text): the checker rejects repeats.
    seen: HashSet<(Vec<usize>, Vec<usize>, String)>,
    /// The network of each step (one initial step per network).
    network: Vec<usize>,
    current_network: usize,
}

impl Generator<'_> {
    fn new_step(&mut self, initial: bool) -> usize {
        let n = self.chart.steps.len();
        self.chart.steps.push(Step { name: format!("S{n}"), initial, assocs: Vec::new() });
        self.network.push(self.current_network);
        n
    }

    fn guard(&mut self, from: &[usize], depth: u32) -> Guard {
        if depth < 2 && self.rng.chance(35) {
            return match self.rng.below(3) {
                0 => Guard::Not(Box::new(self.guard(from, depth + 1))),
                1 => Guard::And(Box::new(self.guard(from, depth + 1)), Box::new(self.guard(from, depth + 1))),
                _ => Guard::Or(Box::new(self.guard(from, depth + 1)), Box::new(self.guard(from, depth + 1))),
            };
        }
        match self.rng.below(24) {
            0 => Guard::True,
            1..=6 => Guard::StepTime(self.rng.pick(from), self.rng.pick(&GUARD_TIMES_MS) * 1000),
            // Flags and variables written by the chart itself: the guard sees the snapshot
            // (X before the firing, Q/A and variables of the previous scan).
            7 => Guard::StepFlag(self.rng.below(self.chart.steps.len())),
            8 | 9 => {
                let a = self.rng.below(self.chart.actions.len());
                match self.chart.actions[a].kind {
                    ActionKind::Variable => Guard::Variable(a),
                    ActionKind::Body { .. } => Guard::ActionFlag(a, self.rng.chance(50)),
                }
            }
            _ => Guard::Input(self.rng.below(INPUTS)),
        }
    }

    fn transition(&mut self, from: Vec<usize>, to: Vec<usize>) {
        let mut guard = self.guard(&from, 0);
        let key = |c: &Chart, g: &Guard| {
            let (mut f, mut t) = (from.clone(), to.clone());
            f.sort_unstable();
            t.sort_unstable();
            (f, t, c.guard_text(g).to_ascii_uppercase())
        };
        while self.seen.contains(&key(&self.chart, &guard)) {
            guard = Guard::And(Box::new(guard), Box::new(Guard::Input(self.rng.below(INPUTS))));
        }
        self.seen.insert(key(&self.chart, &guard));
        let name = format!("Tr{}", self.chart.transitions.len());
        self.chart.transitions.push(Transition { name, from, to, priority: None, guard });
    }

    /// A sequence starting at `entry`; returns its last step.
    fn sequence(&mut self, entry: usize, depth: u32) -> usize {
        let mut cur = entry;
        let mut chain = vec![entry];
        for _ in 0..1 + self.rng.below(3) {
            if self.chart.steps.len() >= self.max_steps {
                break;
            }
            match self.rng.below(10) {
                4 | 5 if depth < 2 => {
                    // selection divergence and convergence, sometimes with an empty branch
                    let join = self.new_step(false);
                    let mut ends = Vec::new();
                    for b in 0..2 + self.rng.below(2) {
                        if b > 0 && self.rng.chance(15) {
                            self.transition(vec![cur], vec![join]);
                            continue;
                        }
                        let first = self.new_step(false);
                        self.transition(vec![cur], vec![first]);
                        ends.push(self.sequence(first, depth + 1));
                    }
                    for e in ends {
                        self.transition(vec![e], vec![join]);
                    }
                    cur = join;
                    chain.push(join);
                }
                6 | 7 if depth < 2 => {
                    // simultaneous divergence and convergence
                    let firsts: Vec<usize> = (0..2 + self.rng.below(2)).map(|_| self.new_step(false)).collect();
                    self.transition(vec![cur], firsts.clone());
                    let ends: Vec<usize> = firsts.iter().map(|&f| self.sequence(f, depth + 1)).collect();
                    let join = self.new_step(false);
                    self.transition(ends, vec![join]);
                    cur = join;
                    chain.push(join);
                }
                8 | 9 if chain.len() >= 2 => {
                    // a loop back to an earlier step of this sequence (or a self-loop)
                    let target = self.rng.pick(&chain);
                    self.transition(vec![cur], vec![target]);
                }
                _ => {
                    let next = self.new_step(false);
                    self.transition(vec![cur], vec![next]);
                    cur = next;
                    chain.push(next);
                }
            }
        }
        cur
    }
}

/// A random chart with at most about `max_steps` steps.
fn generate(rng: &mut Rng, max_steps: usize) -> Chart {
    let mut actions = Vec::new();
    for i in 0..1 + rng.below(4) {
        actions.push(Action { name: format!("o{i}"), kind: ActionKind::Variable });
    }
    for i in 0..rng.below(3) {
        actions.push(Action {
            name: format!("a{i}"),
            kind: ActionKind::Body { counter: format!("c{i}"), qcopy: format!("q{i}") },
        });
    }
    let chart = Chart { pou: "Random".into(), inputs: INPUTS, steps: Vec::new(), transitions: Vec::new(), actions };
    let mut g = Generator { rng, chart, max_steps, seen: HashSet::new(), network: Vec::new(), current_network: 0 };
    let networks = if g.rng.chance(20) { 2 } else { 1 };
    for net in 0..networks {
        g.current_network = net;
        let init = g.new_step(true);
        let last = g.sequence(init, 0);
        g.transition(vec![last], vec![init]);
    }
    if g.rng.chance(20) {
        // an unstructured jump inside one network: may put a second token on a step (unsafe)
        // or never be enabled
        let from = g.rng.below(g.chart.steps.len());
        let same: Vec<usize> = (0..g.chart.steps.len()).filter(|&s| g.network[s] == g.network[from]).collect();
        let mut to = vec![g.rng.pick(&same)];
        let other = g.rng.pick(&same);
        if g.rng.chance(40) && other != to[0] {
            to.push(other);
        }
        g.transition(vec![from], to);
    }
    if g.rng.chance(35) {
        for t in 0..g.chart.transitions.len() {
            if g.rng.chance(50) {
                g.chart.transitions[t].priority = Some(1 + g.rng.below(3) as u32);
            }
        }
    }
    // Associations. ACTION_CONTROL keeps one duration per timed qualifier: the last one a
    // winning association of that qualifier gave (so a stored SD/SL keeps its own time after
    // its step was left); the reference does the same, and durations vary freely.
    for s in 0..g.chart.steps.len() {
        let n = g.rng.pick(&[0, 0, 1, 1, 2]);
        let mut used = Vec::new();
        for _ in 0..n {
            let action = g.rng.below(g.chart.actions.len());
            if used.contains(&action) {
                continue;
            }
            used.push(action);
            let qual = match g.chart.actions[action].kind {
                ActionKind::Variable => g.rng.pick(&Qual::FOR_VARIABLES),
                ActionKind::Body { .. } => g.rng.pick(&Qual::ALL),
            };
            let duration = if qual.timed() { g.rng.pick(&DURATIONS_MS) * 1000 } else { 0 };
            g.chart.steps[s].assocs.push(Assoc { action, qual, duration });
        }
    }
    g.chart
}

// ---------------------------------------------------------------------------------------------
// Running both and comparing

fn event_key(e: &Event) -> String {
    match e {
        Event::Conflict { step, transitions } => format!("conflict {step} {transitions:?}"),
        Event::Unsafe { step, transitions } => format!("unsafe {step} {transitions:?}"),
        // The winner is fixed by semantics.md ("the first wins", "winner first"); how the
        // ignored associations are listed and how a qualifier is spelt is not, so only the
        // winner and its qualifier name are compared.
        Event::Contention { action, steps, qualifiers } => format!(
            "contention {action} winner {} {}",
            steps.first().map_or("", String::as_str),
            qualifiers.first().map_or(String::new(), |q| qualifier_name(q))
        ),
        Event::Error(err) => format!("error {} at {}:{}", err.message, err.line, err.column),
    }
}

fn ref_event_key(e: &RefEvent) -> String {
    match e {
        RefEvent::Conflict { step, transitions } => format!("conflict {step} {transitions:?}"),
        RefEvent::Unsafe { step, transitions } => format!("unsafe {step} {transitions:?}"),
        RefEvent::Contention { action, steps, qualifiers } => {
            format!("contention {action} winner {} {}", steps[0], qualifiers[0])
        }
    }
}

fn qualifier_name(q: &str) -> String {
    q.split(|c: char| !c.is_ascii_alphanumeric()).next().unwrap_or("").to_ascii_uppercase()
}

/// Events grouped by kind in the trace order (conflict, unsafe, contention, error); the order
/// inside one kind is not fixed by the spec, so it is sorted.
fn normalise(mut keys: Vec<String>) -> Vec<String> {
    let rank = |k: &String| ["conflict", "unsafe", "contention", "error"].iter().position(|p| k.starts_with(p));
    keys.sort_by(|a, b| rank(a).cmp(&rank(b)).then(a.cmp(b)));
    keys
}

fn schedule(rng: &mut Rng) -> Vec<[bool; INPUTS]> {
    let mut now = [false; INPUTS];
    for v in now.iter_mut() {
        *v = rng.chance(30);
    }
    let mut out = vec![now];
    for _ in 1..SCANS {
        for v in now.iter_mut() {
            if rng.chance(20) {
                *v = !*v;
            }
        }
        out.push(now);
    }
    out
}

fn show_schedule(s: &[[bool; INPUTS]]) -> String {
    let mut o = String::from("scan  i0..i5\n");
    for (k, row) in s.iter().enumerate() {
        let bits: String = row.iter().map(|b| if *b { '1' } else { '0' }).collect();
        writeln!(o, "{k:>4}  {bits}").unwrap();
    }
    o
}

/// Compares the engine with the reference after one scan; one line per difference.
fn compare(
    chart: &Chart,
    sim: &Simulation,
    rec: &sfc_sim::ScanRecord,
    want: &reference::RefRecord,
    r: &Reference,
) -> Vec<String> {
    let mut diffs = Vec::new();
    if rec.active != want.active {
        diffs.push(format!("active: engine {:?}, reference {:?}", rec.active, want.active));
    }
    if rec.fired != want.fired {
        diffs.push(format!("fired: engine {:?}, reference {:?}", rec.fired, want.fired));
    }
    let got = normalise(rec.events.iter().map(event_key).collect());
    let exp = normalise(want.events.iter().map(ref_event_key).collect());
    if got != exp {
        diffs.push(format!("events: engine {:?}, reference {:?} (reference in full: {:?})", got, exp, want.events));
    }
    let mut check = |key: String, expected: Value| {
        let actual = sim.get(&key);
        let same = match (&actual, &expected) {
            (Some(Value::Time(a) | Value::Int(a)), Value::Time(b) | Value::Int(b)) => a == b,
            (Some(a), b) => a == b,
            (None, _) => false,
        };
        if !same {
            diffs.push(format!("{key}: engine {actual:?}, reference {expected:?}"));
        }
    };
    for (ai, action) in chart.actions.iter().enumerate() {
        match &action.kind {
            ActionKind::Variable => check(action.name.clone(), Value::Bool(r.vars[ai])),
            ActionKind::Body { counter, qcopy } => {
                check(counter.clone(), Value::Int(r.counters[ai]));
                check(qcopy.clone(), Value::Bool(r.qcopies[ai]));
                check(format!("{}.Q", action.name), Value::Bool(r.q(ai)));
                check(format!("{}.A", action.name), Value::Bool(r.a(ai)));
            }
        }
    }
    for (s, step) in chart.steps.iter().enumerate() {
        check(format!("{}.T", step.name), Value::Time(r.step_time(s)));
    }
    diffs
}

/// Runs one case; `Err` holds the full report.
fn run_case(case: usize, seed: u64, max_steps: usize) -> Result<(), String> {
    let mut rng = Rng::new(seed);
    let chart = generate(&mut rng, max_steps);
    let inputs = schedule(&mut rng);
    let text = chart.text();
    let header = |what: &str| {
        format!("differential case {case} (rerun it alone with SFC_DIFF_CASE={case}): {what}\n\nchart:\n{text}")
    };
    let mut sim = match catch_unwind(AssertUnwindSafe(|| {
        Simulation::from_source("random.st", &text, None, SimOptions { period: PERIOD, ..SimOptions::default() })
    })) {
        Ok(Ok(sim)) => sim,
        Ok(Err((_, diags))) => {
            let list: Vec<String> = diags.iter().map(|d| format!("{d:?}")).collect();
            return Err(header(&format!("the generated chart does not compile:\n{}", list.join("\n"))));
        }
        Err(_) => return Err(header("Simulation::from_source panicked")),
    };
    sim.record_situations(true);
    let mut reference = Reference::new(&chart, PERIOD);
    let mut history = String::new();
    let mut records: Vec<reference::RefRecord> = Vec::new();
    for (k, row) in inputs.iter().enumerate() {
        for (i, &v) in row.iter().enumerate() {
            if let Err(e) = sim.set(&format!("i{i}"), Value::Bool(v)) {
                return Err(header(&format!("set i{i} failed before scan {k}: {e}")));
            }
            reference.set(i, v);
        }
        let rec = match catch_unwind(AssertUnwindSafe(|| sim.scan().clone())) {
            Ok(rec) => rec,
            Err(_) => {
                return Err(format!(
                    "{}\ninput schedule:\n{}\nreference up to the previous scan:\n{history}\nthe engine panicked in scan {k}",
                    header("engine panic"),
                    show_schedule(&inputs[..=k])
                ))
            }
        };
        let want = reference.scan();
        records.push(want.clone());
        let diffs = compare(&chart, &sim, &rec, &want, &reference);
        writeln!(history, "{k:>4}  active {:?} fired {:?} events {:?}", want.active, want.fired, want.events).unwrap();
        if !diffs.is_empty() {
            return Err(format!(
                "{}\ninput schedule (up to the difference):\n{}\nreference trace:\n{history}\nfirst difference in scan {k} (T#{}ms):\n  {}",
                header(&format!("engine and reference differ in scan {k}")),
                show_schedule(&inputs[..=k]),
                k as i64 * PERIOD / 1000,
                diffs.join("\n  ")
            ));
        }
    }
    let diffs = compare_bookkeeping(&chart, &sim, &records);
    if !diffs.is_empty() {
        return Err(format!(
            "{}\ninput schedule:\n{}\nreference trace:\n{history}\n  {}",
            header("the run's bookkeeping (coverage, time analysis) differs from the reference"),
            show_schedule(&inputs),
            diffs.join("\n  ")
        ));
    }
    Ok(())
}

/// Coverage, activations, active times and the sequence of situations of a whole run, derived
/// from the reference's records, against what the engine kept.
fn compare_bookkeeping(chart: &Chart, sim: &Simulation, records: &[reference::RefRecord]) -> Vec<String> {
    let mut diffs = Vec::new();
    let step_index: HashMap<&str, usize> = chart.steps.iter().enumerate().map(|(i, s)| (s.name.as_str(), i)).collect();
    let tr_index: HashMap<&str, usize> =
        chart.transitions.iter().enumerate().map(|(i, t)| (t.name.as_str(), i)).collect();
    let n = chart.steps.len();
    let mut activations = vec![0u64; n];
    let mut firings = vec![0u64; chart.transitions.len()];
    let mut started: Vec<Option<u64>> = vec![None; n];
    let mut durations: Vec<Vec<i64>> = vec![Vec::new(); n];
    let mut sequence: Vec<(i64, Vec<String>)> = Vec::new();
    for (k, rec) in records.iter().enumerate() {
        let k = k as u64;
        let mut entered = HashSet::new();
        let mut left = HashSet::new();
        if k == 0 {
            entered.extend(rec.active.iter().map(|a| step_index[a.as_str()]));
        }
        for t in &rec.fired {
            let t = tr_index[t.as_str()];
            firings[t] += 1;
            left.extend(chart.transitions[t].from.iter().copied());
            entered.extend(chart.transitions[t].to.iter().copied());
        }
        for &s in &left {
            if let Some(j) = started[s].take() {
                durations[s].push((k - j) as i64 * PERIOD);
            }
        }
        for &s in &entered {
            activations[s] += 1;
            started[s] = Some(k);
        }
        let mut now = rec.active.clone();
        now.sort();
        if sequence.last().map(|l| &l.1) != Some(&now) {
            sequence.push((k as i64 * PERIOD, now));
        }
    }
    let last = records.len() as u64 - 1;
    for s in 0..n {
        if let Some(j) = started[s] {
            durations[s].push((last - j) as i64 * PERIOD);
        }
    }
    let (step_hits, tr_hits) = sim.coverage_counts();
    let ever: HashSet<&str> = records.iter().flat_map(|r| r.active.iter().map(String::as_str)).collect();
    for (s, step) in chart.steps.iter().enumerate() {
        let want = if activations[s] == 0 && ever.contains(step.name.as_str()) { 1 } else { activations[s] };
        if step_hits[s] != want {
            diffs.push(format!("coverage of step {}: engine {}, reference {want}", step.name, step_hits[s]));
        }
    }
    if tr_hits != firings {
        diffs.push(format!("firings per transition: engine {tr_hits:?}, reference {firings:?}"));
    }
    let stats = sim.stats();
    for (s, st) in stats.steps.iter().enumerate() {
        let d = &durations[s];
        let want = (
            activations[s],
            d.iter().copied().min(),
            d.iter().copied().max(),
            (!d.is_empty()).then(|| d.iter().sum::<i64>() / d.len() as i64),
        );
        let got = (st.activations, st.min, st.max, st.mean);
        if got != want {
            diffs.push(format!("time analysis of {}: engine {got:?}, reference {want:?}", st.step));
        }
    }
    if stats.sequence != sequence {
        diffs.push(format!("situations: engine {:?}, reference {sequence:?}", stats.sequence));
    }
    diffs
}

fn parse_seed(s: &str) -> Option<u64> {
    let s = s.trim();
    match s.strip_prefix("0x").or_else(|| s.strip_prefix("0X")) {
        Some(hex) => u64::from_str_radix(hex, 16).ok(),
        None => s.parse().ok(),
    }
}

#[test]
fn engine_agrees_with_reference_on_random_charts() {
    let env = |name: &str| std::env::var(name).ok();
    let cases = env("SFC_DIFF_CASES").and_then(|s| s.parse().ok()).unwrap_or(DEFAULT_CASES);
    // Small charts first, so the first failure tends to be a small one.
    let size = |case: usize| 3 + case * 14 / cases.max(1);
    if let Some(seed) = env("SFC_DIFF_SEED").and_then(|s| parse_seed(&s)) {
        let steps = env("SFC_DIFF_STEPS").and_then(|s| s.parse().ok()).unwrap_or(16);
        if let Err(report) = run_case(0, seed, steps) {
            panic!("{report}");
        }
        return;
    }
    let only: Option<usize> = env("SFC_DIFF_CASE").and_then(|s| s.parse().ok());
    for case in (0..cases).filter(|c| only.is_none_or(|o| o == *c)) {
        if let Err(report) = run_case(case, case_seed(case), size(case)) {
            panic!("{report}");
        }
    }
}

// ---------------------------------------------------------------------------------------------
// The reference checked against hand-derived values (the same derivations as the fixtures in
// tests/semantics/), so that a disagreement points at the engine, not at the reference.

fn step(name: &str, initial: bool, assocs: Vec<Assoc>) -> Step {
    Step { name: name.into(), initial, assocs }
}

fn tr(name: &str, from: &[usize], to: &[usize], guard: Guard) -> Transition {
    Transition { name: name.into(), from: from.to_vec(), to: to.to_vec(), priority: None, guard }
}

fn assoc(action: usize, qual: Qual, ms: i64) -> Assoc {
    Assoc { action, qual, duration: ms * 1000 }
}

fn var(name: &str) -> Action {
    Action { name: name.into(), kind: ActionKind::Variable }
}

fn body(name: &str, i: usize) -> Action {
    Action { name: name.into(), kind: ActionKind::Body { counter: format!("c{i}"), qcopy: format!("q{i}") } }
}

fn bools(s: &str) -> Vec<bool> {
    s.chars().map(|c| c == '1').collect()
}

#[test]
fn reference_qualifier_timings() {
    // S0 -> S1 in scan 1 (i0), S1 -> S2 in scan 6 (i1), S2 -> S0 in scan 8 (i2); delta = 10 ms.
    let chart = Chart {
        pou: "Qualifiers".into(),
        inputs: 3,
        steps: vec![
            step("S0", true, vec![]),
            step(
                "S1",
                false,
                vec![
                    assoc(0, Qual::L, 30),
                    assoc(1, Qual::D, 30),
                    assoc(2, Qual::SD, 30),
                    assoc(3, Qual::DS, 30),
                    assoc(4, Qual::SL, 30),
                    assoc(5, Qual::P, 0),
                    assoc(6, Qual::N, 0),
                    assoc(7, Qual::P1, 0),
                ],
            ),
            step("S2", false, vec![assoc(2, Qual::R, 0), assoc(3, Qual::R, 0), assoc(7, Qual::P0, 0)]),
        ],
        transitions: vec![
            tr("T0", &[0], &[1], Guard::Input(0)),
            tr("T1", &[1], &[2], Guard::Input(1)),
            tr("T2", &[2], &[0], Guard::Input(2)),
        ],
        actions: vec![
            var("oL"),
            var("oD"),
            var("oSD"),
            var("oDS"),
            var("oSL"),
            var("oP"),
            body("aN", 0),
            body("aP", 1),
        ],
    };
    let mut r = Reference::new(&chart, PERIOD);
    let mut rows: Vec<Vec<bool>> = vec![Vec::new(); 6];
    let (mut n_runs, mut p_runs, mut active) = (Vec::new(), Vec::new(), Vec::new());
    for k in 0..10 {
        r.set(0, k == 1);
        r.set(1, k == 6);
        r.set(2, k == 8);
        let rec = r.scan();
        for (a, row) in rows.iter_mut().enumerate() {
            row.push(r.vars[a]);
        }
        n_runs.push(r.counters[6]);
        p_runs.push(r.counters[7]);
        active.push(rec.active.join(","));
    }
    assert_eq!(active, ["S0", "S1", "S1", "S1", "S1", "S1", "S2", "S2", "S0", "S0"]);
    assert_eq!(rows[0], bools("0111000000"), "L T#30ms: ceil(30/10) = 3 scans");
    assert_eq!(rows[1], bools("0000110000"), "D T#30ms: from elapsed 30 ms while active");
    assert_eq!(rows[2], bools("0000110000"), "SD T#30ms: stored, delayed, reset by R");
    assert_eq!(rows[3], bools("0000110000"), "DS T#30ms: delayed, stored, reset by R");
    assert_eq!(rows[4], bools("0111000000"), "SL T#30ms");
    assert_eq!(rows[5], bools("0100000000"), "P");
    assert_eq!(n_runs, [0, 1, 2, 3, 4, 5, 6, 6, 6, 6], "N with its final scan in scan 6");
    assert_eq!(p_runs, [0, 1, 1, 1, 1, 1, 1, 1, 2, 2], "P1 on S1, P0 on S2");
}

#[test]
fn reference_contention_as_in_fixture_26() {
    let chart = Chart {
        pou: "Contention".into(),
        inputs: 1,
        steps: vec![
            step("Init1", true, vec![]),
            step("LimitStep", false, vec![assoc(0, Qual::L, 30)]),
            step("DelayStep", false, vec![assoc(0, Qual::D, 20)]),
            step("LimitDone", false, vec![]),
            step("DelayDone", false, vec![]),
        ],
        transitions: vec![
            tr("TSplit1", &[0], &[1, 2], Guard::Input(0)),
            tr("TLimit", &[1], &[3], Guard::StepTime(1, 40_000)),
            tr("TDelay", &[2], &[4], Guard::StepTime(2, 100_000)),
        ],
        actions: vec![var("Out")],
    };
    let mut r = Reference::new(&chart, PERIOD);
    let mut out = Vec::new();
    let mut contention_scans = Vec::new();
    for k in 0..12 {
        r.set(0, k == 1);
        let rec = r.scan();
        out.push(r.vars[0]);
        if let Some(RefEvent::Contention { action, steps, .. }) = rec.events.first() {
            assert_eq!(
                (action.as_str(), steps.as_slice()),
                ("Out", &["LimitStep".to_string(), "DelayStep".to_string()][..])
            );
            contention_scans.push(k);
        }
    }
    assert_eq!(out, bools("011100011110"));
    assert_eq!(contention_scans, [1, 2, 3, 4]);
}

#[test]
fn reference_unsafe_conflict_and_self_loop() {
    // fixture 12, network 2: two transitions enter Meet in one scan
    let unsafe_chart = Chart {
        pou: "Unsafe".into(),
        inputs: 1,
        steps: vec![
            step("Init2", true, vec![]),
            step("Left2", false, vec![]),
            step("Right2", false, vec![]),
            step("Meet2", false, vec![]),
        ],
        transitions: vec![
            tr("TSplit2", &[0], &[1, 2], Guard::Input(0)),
            tr("TLeft2", &[1], &[3], Guard::StepTime(1, 10_000)),
            tr("TRight2", &[2], &[3], Guard::StepTime(2, 10_000)),
        ],
        actions: vec![],
    };
    let mut r = Reference::new(&unsafe_chart, PERIOD);
    r.scan();
    r.set(0, true);
    assert_eq!(r.scan().active, ["Left2", "Right2"]);
    let rec = r.scan();
    assert_eq!(rec.active, ["Meet2"]);
    assert_eq!(rec.fired, ["TLeft2", "TRight2"]);
    assert_eq!(
        rec.events,
        [RefEvent::Unsafe { step: "Meet2".into(), transitions: vec!["TLeft2".into(), "TRight2".into()] }]
    );

    // fixture 07 with an explicit priority added on a third alternative (fixture 09)
    let mut conflict_chart = Chart {
        pou: "Conflict".into(),
        inputs: 1,
        steps: vec![
            step("Init", true, vec![]),
            step("A", false, vec![]),
            step("B", false, vec![]),
            step("C", false, vec![]),
        ],
        transitions: vec![
            tr("TA", &[0], &[1], Guard::Input(0)),
            tr("TB", &[0], &[2], Guard::Input(0)),
            tr("TC", &[0], &[3], Guard::Input(0)),
        ],
        actions: vec![],
    };
    conflict_chart.transitions[1].priority = Some(5);
    let mut r = Reference::new(&conflict_chart, PERIOD);
    r.scan();
    r.set(0, true);
    let rec = r.scan();
    assert_eq!(rec.active, ["B"]);
    assert_eq!(rec.events, [RefEvent::Conflict { step: "Init".into(), transitions: vec!["TA".into(), "TC".into()] }]);

    // fixture 11: a self-loop restarts S.T, not the activation edge nor the L/D timers
    let loop_chart = Chart {
        pou: "SelfLoop".into(),
        inputs: 1,
        steps: vec![
            step("Init", true, vec![]),
            step("Work", false, vec![assoc(0, Qual::P, 0), assoc(1, Qual::L, 50), assoc(2, Qual::D, 40)]),
        ],
        transitions: vec![tr("TGo", &[0], &[1], Guard::Input(0)), tr("TLoop", &[1], &[1], Guard::StepTime(1, 20_000))],
        actions: vec![var("Pulse"), var("Lit"), var("Late")],
    };
    let mut r = Reference::new(&loop_chart, PERIOD);
    let (mut pulse, mut lit, mut late, mut fired) = (Vec::new(), Vec::new(), Vec::new(), Vec::new());
    for k in 0..8 {
        r.set(0, k == 1);
        let rec = r.scan();
        assert!(rec.events.is_empty(), "scan {k}: a self-loop is not unsafe");
        pulse.push(r.vars[0]);
        lit.push(r.vars[1]);
        late.push(r.vars[2]);
        fired.push(rec.fired.join(","));
    }
    assert_eq!(fired, ["", "TGo", "", "TLoop", "", "TLoop", "", "TLoop"]);
    assert_eq!(pulse, bools("01000000"));
    assert_eq!(lit, bools("01111100"));
    assert_eq!(late, bools("00000111"));
}

#[test]
fn generated_charts_are_well_formed_and_varied() {
    // Independent of the engine: the generator's output must be a chart the checker accepts,
    // and the cases together must reach what the comparison is meant to exercise.
    let mut seen: HashMap<&str, usize> = HashMap::new();
    for case in 0..DEFAULT_CASES {
        let mut rng = Rng::new(case_seed(case));
        let chart = generate(&mut rng, 3 + case * 14 / DEFAULT_CASES);
        let inputs = schedule(&mut rng);
        let text = chart.text();
        let checked = sfc_model::check_source(0, "random.st", &text, &sfc_model::CheckOptions::default());
        let errors: Vec<String> =
            checked.diagnostics.iter().filter(|d| d.is_error()).map(|d| format!("{d:?}")).collect();
        assert!(errors.is_empty(), "case {case}: {errors:#?}\n{text}");
        if chart.transitions.iter().any(|t| t.to.len() > 1) {
            *seen.entry("simultaneous divergence").or_default() += 1;
        }
        if chart.transitions.iter().any(|t| t.priority.is_some()) {
            *seen.entry("explicit priority").or_default() += 1;
        }
        let mut r = Reference::new(&chart, PERIOD);
        for row in &inputs {
            for (i, &v) in row.iter().enumerate() {
                r.set(i, v);
            }
            let rec = r.scan();
            for e in &rec.events {
                let kind = match e {
                    RefEvent::Conflict { .. } => "conflict",
                    RefEvent::Unsafe { .. } => "unsafe",
                    RefEvent::Contention { .. } => "contention",
                };
                *seen.entry(kind).or_default() += 1;
            }
            for name in &rec.fired {
                let t = chart.transitions.iter().find(|t| &t.name == name).unwrap();
                if t.from.len() > 1 {
                    *seen.entry("convergence fired").or_default() += 1;
                }
                if t.from == t.to {
                    *seen.entry("self-loop fired").or_default() += 1;
                }
            }
            if (0..chart.actions.len()).any(|a| r.a(a) && !r.q(a)) {
                *seen.entry("final scan").or_default() += 1;
            }
        }
    }
    eprintln!("generator coverage: {seen:?}");
    for what in [
        "simultaneous divergence",
        "explicit priority",
        "conflict",
        "unsafe",
        "contention",
        "convergence fired",
        "self-loop fired",
        "final scan",
    ] {
        assert!(seen.get(what).copied().unwrap_or(0) > 0, "no case reaches {what}: {seen:?}");
    }
}
