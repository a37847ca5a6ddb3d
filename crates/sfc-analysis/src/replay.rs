//! Replays a witness of the net analysis in the simulator.
//!
//! The net analysis treats guards as free inputs; its witnesses are firing sequences, one
//! transition per scan. Here the real simulator (`sfc-sim`, profile `iec`, with ST/IL guards,
//! action bodies, step times and timers) is driven by an **input schedule** so that it fires
//! exactly the witness transitions in order — one per firing scan, with waiting scans in
//! between in which nothing fires — and reaches the reported situation. When no schedule is
//! found the finding cannot be confirmed and is reported as *possible*.
//!
//! # Inputs
//! A value the replay may set is a variable (or a field or constant-index element of one:
//! `Cmd.Start`, `Sensors[2]`) of the simulated POU or a global that the code never writes (no
//! assignment, IL store, output binding, in-out argument, BOOL-variable action, indicator,
//! function block instance, global written by a called user POU through `VAR_EXTERNAL`), that
//! is not `CONSTANT`; also an undeclared name the simulator resolves (the implicit inputs `C0`
//! of ATMT/EATMT charts, direct addresses `%IX2.4`) and the acknowledgement input
//! `SFCQuitError` (not `SFCInit`/`SFCPause`, which would stop the chart). Its type must be
//! BOOL, an integer, a bit string, REAL/LREAL, TIME/LTIME or an enumeration. Only inputs that
//! can influence a guard are used: read by a guard (*direct*), or read by an action body that
//! writes something a guard depends on, through any chain of such actions (*indirect*: they act
//! on later scans, since actions run after the transitions of a scan).
//!
//! Candidate values: BOOL both values; enumerations every value; integers 0 and, for every
//! constant the code compares the input with (in guards and relevant bodies, CASE labels, IL
//! `GT 50`, also inside an expression: `Level + 5 > 50` gives `Level` 49, 50, 51), `c-1, c, c+1`,
//! clamped to the type's range, constants flowing back through plain copies (`Target := Sel`
//! gives `Sel` the constants of `Target`); without any constant a ladder 0, 1, 10, 100, 1000 and
//! the maximum. REAL likewise; TIME `c ± 1ms` (`± 1us` when `c` is not whole milliseconds),
//! without constants 0, `T#1s`, `T#10s`. Strings and dates are left alone.
//!
//! # Search
//! For witness transition `w_k`, from the state after the previous firing:
//! 1. `w_k` must be enabled (its steps active): the active set cannot change while waiting,
//!    so otherwise it is blocked at once.
//! 2. **Firing round**: every valuation of the direct inputs of the enabled transitions, in
//!    order of the number of changed inputs (current values first), at most
//!    [`MAX_VALUATIONS`], is tried for one scan; success is a scan that fires exactly `[w_k]`
//!    (transitions of nested instances aside) with no runtime error. A valuation with a
//!    `conflict` event is used only when none without exists.
//! 3. Otherwise one **waiting scan** in which nothing fires, and the round again. What is held
//!    while waiting is a *plan*: a valuation of the direct and indirect inputs applied at the
//!    first waiting scan; plans are taken in order of changes (keeping every value first, which
//!    covers step times and timers), at most [`MAX_PLANS`]. A plan under which something fires
//!    while waiting is dropped. Plans advance in phases (every live plan waits up to 16 scans,
//!    then up to 256, then up to `max_wait_scans`), so a plan that needs a long wait does not
//!    starve one that needs a short wait with another input held.
//! 4. A plan is also dropped once [`STATIONARY_SCANS`] waiting scans in a row leave every
//!    observable value unchanged, when that proves waiting longer cannot help: no timed
//!    qualifier in the chart, no active step whose time is read or supervised, no user function
//!    block, every variable observable (standard function blocks are observed through all their
//!    members: a running TON changes its `ET`).
//! 5. **Backtracking**: the successful round yields alternatives — each firing valuation, then
//!    each combined with single changes of indirect inputs (a value captured on entry, e.g. by
//!    a P1 action, may decide a later guard; inputs read by the actions of the steps `w_k`
//!    enters come first) — at most [`MAX_ALTERNATIVES`]. When a later transition cannot be
//!    fired, the next alternative of the previous one is taken. Alternatives whose resulting
//!    states differ only in input values are equivalent (inputs can be set again at any scan)
//!    and are skipped when the state is fully observable.
//!
//! Everything is deterministic: inputs in order of first appearance (guards in declaration
//! order, then action bodies), candidates in ascending order, valuations by number of changes
//! then position. `max_tries` bounds the simulated scans of the whole replay; when it runs
//! out, a transition already found blocked at least as deep is reported rather than
//! [`ReplayFailure::Budget`]. Scan 0 runs with the declared initial values: the first input
//! change applies at scan 1, where transitions are first tested (so a value an initial step
//! captures in scan 0 is not searched).

#[path = "replay/facts.rs"]
mod facts;

use facts::Facts;
use sfc_model::{Chart, StepId, TransitionId};
use sfc_sim::value::Value;
use sfc_sim::{format_time, Event, ScanRecord, SimOptions, Simulation, Snapshot};
use sfc_st::{Type, Value as Const};
use std::fmt;

/// At most this many valuations are tried in one firing round.
pub const MAX_VALUATIONS: usize = 256;
/// At most this many waiting plans (held valuations) per witness transition.
pub const MAX_PLANS: usize = 16;
/// At most this many alternatives per witness transition for backtracking.
pub const MAX_ALTERNATIVES: usize = 16;
/// Waiting scans in a row with no observable change after which a time-free chart is
/// considered settled.
pub const STATIONARY_SCANS: u32 = 3;
/// Waiting limits of the phases before the last (`max_wait_scans`): every live plan waits up
/// to the first, then up to the second, …
const PHASES: [u64; 2] = [16, 256];
/// Composite variables with more leaf values than this are not observed.
const MAX_OBSERVED_LEAVES: usize = 4096;

/// One input change of a schedule: written before scan `scan` (at time `time`).
#[derive(Debug, Clone, PartialEq)]
pub struct ScheduledInput {
    pub scan: u64,
    /// µs (`scan · period`).
    pub time: i64,
    /// The variable as the simulator and scenarios name it (`Start`, `Cmd.Start`).
    pub name: String,
    pub value: Value,
    /// The value as an IEC literal (`TRUE`, `51`, `2.5`, `T#2s`, an enumeration value name).
    pub literal: String,
}

/// An input schedule under which the simulator follows a witness.
#[derive(Debug, Clone, PartialEq)]
pub struct Schedule {
    /// Scan period, µs.
    pub period: i64,
    /// Input changes in scan order (only changes: a value holds until changed).
    pub inputs: Vec<ScheduledInput>,
    /// The scan at which each witness transition fired.
    pub firings: Vec<u64>,
    /// The scan of the last firing (0 for an empty witness).
    pub last_scan: u64,
    /// The witness replayed.
    pub witness: Vec<TransitionId>,
    /// The active steps after each firing (all steps the simulator lists, sorted).
    pub situations: Vec<Vec<String>>,
    /// The active steps after the last scan (after scan 0 for an empty witness).
    pub final_active: Vec<String>,
    /// The chart file as passed to [`replay`] (the scenario names its file part).
    pub file: String,
    /// The simulated POU.
    pub pou: String,
}

/// What the replay must reach after the last witness transition.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Goal {
    /// The active set after the last firing, exactly (steps of the simulated chart).
    Situation(Vec<StepId>),
    /// The last firing emits an `unsafe` event for this step.
    Unsafe(StepId),
    /// Just fire the whole witness.
    Fired,
}

/// Bounds of the search.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ReplayOptions {
    /// Simulated scans in all (tries, waits and backtracking).
    pub max_tries: usize,
    /// Waiting scans before one witness transition, per waiting plan.
    pub max_wait_scans: u64,
}

impl Default for ReplayOptions {
    fn default() -> Self {
        ReplayOptions { max_tries: 20_000, max_wait_scans: 2_000 }
    }
}

/// Why no schedule was found.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum ReplayFailure {
    /// The chart does not compile for simulation: the first error.
    NotSimulatable(String),
    /// Witness transition `index` could not be fired alone (`index == witness.len()`: every
    /// transition fired but the goal was not reached).
    Blocked { index: usize, reason: String },
    /// The budget of simulated scans ran out while trying witness transition `index`.
    Budget { index: usize },
    /// A scan ran away (spent [`REPLAY_SCAN_BUDGET`]) while trying witness transition `index`:
    /// the replay stopped there; `error` locates the loop or call.
    Runaway { index: usize, error: sfc_sim::RuntimeError },
}

/// Loop iterations, jumps and calls one simulated scan of a replay may spend: a scan that
/// spends them runs away, which ends the replay (a runaway scan would make every try slow).
pub const REPLAY_SCAN_BUDGET: u64 = 1_000_000;

impl fmt::Display for ReplayFailure {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            ReplayFailure::NotSimulatable(m) => write!(f, "the chart cannot be simulated: {m}"),
            ReplayFailure::Blocked { reason, .. } => f.write_str(reason),
            ReplayFailure::Budget { index } => {
                write!(f, "the search budget ran out while looking for a way to fire witness transition {}", index + 1)
            }
            ReplayFailure::Runaway { error, .. } => {
                write!(f, "a scan ran away at line {}, column {}: {}", error.line, error.column, error.message)
            }
        }
    }
}

/// Finds an input schedule under which the simulator of `text` (file `name`, POU
/// `chart.pou`) fires `witness` transition by transition and reaches `goal`.
pub fn replay(
    name: &str,
    text: &str,
    chart: &Chart,
    witness: &[TransitionId],
    goal: &Goal,
    opts: &ReplayOptions,
) -> Result<Schedule, ReplayFailure> {
    let sim = match Simulation::from_source(name, text, Some(&chart.pou), SimOptions::default()) {
        Ok(mut sim) => {
            sim.set_scan_budget(REPLAY_SCAN_BUDGET);
            sim
        }
        Err((_, diags)) => {
            let first = diags.iter().find(|d| d.is_error()).or(diags.first());
            let msg = first.map_or_else(|| "unknown error".to_string(), |d| format!("{}: {}", d.code, d.message));
            return Err(ReplayFailure::NotSimulatable(msg));
        }
    };
    if let Some(k) = witness.iter().position(|&t| t >= chart.transitions.len()) {
        return Err(ReplayFailure::Blocked {
            index: k,
            reason: format!("the chart has no transition #{}", witness[k]),
        });
    }
    match goal {
        Goal::Situation(steps) if steps.iter().any(|&s| s >= chart.steps.len()) => {
            return Err(ReplayFailure::Blocked {
                index: witness.len(),
                reason: "the goal names a step the chart does not have".into(),
            });
        }
        Goal::Unsafe(s) if *s >= chart.steps.len() => {
            return Err(ReplayFailure::Blocked {
                index: witness.len(),
                reason: "the goal names a step the chart does not have".into(),
            });
        }
        _ => {}
    }
    let (unit, _) = sfc_syntax::parse(0, text);
    let facts = Facts::of(&unit, chart);
    let mut search = Search::new(sim, chart, facts, witness, opts);
    let result = search.run(goal);
    result.map(|mut s| {
        s.file = name.to_string();
        s
    })
}

// ---------------------------------------------------------------------------------------------
// Inputs and valuations

/// A value the replay may set, with its candidate values.
#[derive(Debug, Clone)]
struct Input {
    name: String,
    ty: Type,
    candidates: Vec<Value>,
}

/// Changes to inputs: `(input index, value)`, by ascending input index.
type Valuation = Vec<(usize, Value)>;

/// Valuations of the inputs `subset`, in order of the number of changes from `current`
/// (the empty valuation first), then by position; at most `cap`.
fn valuations(inputs: &[Input], subset: &[usize], current: &[Value], cap: usize) -> Vec<Valuation> {
    let alts: Vec<(usize, Vec<Value>)> = subset
        .iter()
        .filter_map(|&i| {
            let input = inputs.get(i)?;
            let cur = current.get(i);
            let a: Vec<Value> = input.candidates.iter().filter(|c| Some(*c) != cur).cloned().collect();
            (!a.is_empty()).then_some((i, a))
        })
        .collect();
    let mut out: Vec<Valuation> = vec![Vec::new()];
    for k in 1..=alts.len() {
        if out.len() >= cap {
            break;
        }
        let mut chosen: Vec<usize> = Vec::with_capacity(k);
        combos(&alts, k, 0, &mut chosen, &mut out, cap);
    }
    out.truncate(cap);
    out
}

/// Every choice of `k` inputs from `start` on (lexicographic), each with every alternative.
fn combos(
    alts: &[(usize, Vec<Value>)],
    k: usize,
    start: usize,
    chosen: &mut Vec<usize>,
    out: &mut Vec<Valuation>,
    cap: usize,
) {
    if out.len() >= cap {
        return;
    }
    if chosen.len() == k {
        // The product of the chosen inputs' alternatives, odometer order.
        let mut idx = vec![0usize; k];
        loop {
            if out.len() >= cap {
                return;
            }
            out.push(chosen.iter().zip(&idx).map(|(&c, &j)| (alts[c].0, alts[c].1[j].clone())).collect());
            let mut pos = k;
            loop {
                if pos == 0 {
                    return;
                }
                pos -= 1;
                idx[pos] += 1;
                if idx[pos] < alts[chosen[pos]].1.len() {
                    break;
                }
                idx[pos] = 0;
            }
        }
    }
    for i in start..alts.len() {
        if alts.len() - i < k - chosen.len() {
            break;
        }
        chosen.push(i);
        combos(alts, k, i + 1, chosen, out, cap);
        chosen.pop();
        if out.len() >= cap {
            return;
        }
    }
}

/// The candidate values of an input of type `ty` compared with `consts`; `None` when the type
/// is not one the replay sets. Without any compared constant a number gets a ladder of
/// magnitudes (0, 1, 10, 100, 1000 and the type's maximum; TIME 0, `T#1s`, `T#10s`), so a
/// value that reaches a guard through arithmetic or a function still has a chance.
fn candidates(ty: &Type, consts: &[Const]) -> Option<Vec<Value>> {
    if let Type::Enum { values, .. } = ty {
        return Some(values.iter().map(|(_, o)| Value::Int(*o)).collect());
    }
    if ty.is_bool() {
        return Some(vec![Value::Bool(false), Value::Bool(true)]);
    }
    if ty.is_integer() || ty.is_bit() {
        let (lo, hi) = ty.int_range()?;
        let (lo, hi) = (lo.max(i128::from(i64::MIN)), hi.min(i128::from(i64::MAX)));
        let mut v: Vec<i128> = vec![0];
        for c in consts {
            let c = match c {
                Const::Int(i) => *i,
                Const::Bool(b) => i128::from(*b),
                Const::Real(r) if r.is_finite() => r.trunc() as i128,
                _ => continue,
            };
            v.extend([c.saturating_sub(1), c, c.saturating_add(1)]);
        }
        if consts.is_empty() {
            v.extend([1, 10, 100, 1000, hi]);
        }
        let mut v: Vec<i64> = v.into_iter().map(|x| x.clamp(lo, hi) as i64).collect();
        v.sort_unstable();
        v.dedup();
        return Some(v.into_iter().map(Value::Int).collect());
    }
    if ty.is_real() {
        let single = matches!(ty.base(), Type::Real);
        let round = |r: f64| if single { r as f32 as f64 } else { r };
        let mut v: Vec<f64> = vec![0.0];
        for c in consts {
            let c = match c {
                Const::Int(i) => *i as f64,
                Const::Real(r) if r.is_finite() => *r,
                _ => continue,
            };
            v.extend([c - 1.0, c, c + 1.0]);
        }
        if consts.is_empty() {
            v.extend([1.0, 10.0, 100.0, 1000.0]);
        }
        let mut v: Vec<f64> = v.into_iter().map(round).filter(|r| r.is_finite()).collect();
        v.sort_by(f64::total_cmp);
        v.dedup();
        return Some(v.into_iter().map(Value::Real).collect());
    }
    if ty.is_duration() {
        let mut v: Vec<i64> = vec![0];
        for c in consts {
            let Const::Time(t) = c else { continue };
            let d = if t % 1000 == 0 { 1000 } else { 1 };
            v.extend([t.saturating_sub(d), *t, t.saturating_add(d)]);
        }
        if consts.is_empty() {
            v.extend([1_000_000, 10_000_000]);
        }
        v.sort_unstable();
        v.dedup();
        return Some(v.into_iter().map(Value::Time).collect());
    }
    None
}

/// The IEC literal of a value of type `ty`.
fn literal(v: &Value, ty: &Type) -> String {
    match (v, ty) {
        (Value::Int(i), Type::Enum { values, .. }) => {
            values.iter().find(|(_, o)| o == i).map_or_else(|| i.to_string(), |(n, _)| n.clone())
        }
        (Value::Bool(b), _) => if *b { "TRUE" } else { "FALSE" }.to_string(),
        (Value::Int(i), _) => i.to_string(),
        (Value::Real(r), _) => real_text(*r),
        (Value::Time(t), _) => format_time(*t),
        (Value::Str(s), _) => format!("'{s}'"),
    }
}

/// A real as text that reads back as a real (`51.0`, `2.5`, `1e20`).
fn real_text(r: f64) -> String {
    if !r.is_finite() {
        return format!("{r}");
    }
    if r.abs() >= 1e15 || (r != 0.0 && r.abs() < 1e-4) {
        return format!("{r:e}");
    }
    let s = format!("{r}");
    if s.contains('.') {
        s
    } else {
        format!("{s}.0")
    }
}

// ---------------------------------------------------------------------------------------------
// Observing the state

/// What of the simulation's state can be read by name, to tell whether waiting changes
/// anything and whether two alternatives led to the same state.
///
/// Standard function blocks are observed through all their members, inputs included (a
/// TON's `IN` and `ET` show whether it runs, an R_TRIG's `CLK` is its edge memory). Hidden
/// are: action control timers (so charts with timed qualifiers never count as settled), step
/// times (so a state never counts as settled while a step whose time matters is active), and
/// the internals of user function blocks (so with one of those nothing is concluded).
#[derive(Debug, Clone, Default)]
struct Observer {
    paths: Vec<String>,
    /// Every variable could be expanded into observed leaves, and no user function block.
    complete: bool,
    timed_associations: bool,
    time_steps: std::collections::BTreeSet<StepId>,
}

impl Observer {
    fn new(sim: &Simulation, chart: &Chart, facts: &Facts) -> Observer {
        let mut o = Observer {
            paths: Vec::new(),
            complete: true,
            timed_associations: facts.timed_associations,
            time_steps: facts.time_steps.clone(),
        };
        let durations: std::collections::BTreeSet<&String> = facts.durations.iter().flatten().collect();
        let mut leaves = 0usize;
        for root in &facts.order {
            if facts.settable_root(root, true) && !durations.contains(root) {
                continue;
            }
            let Some((name, _, _)) = facts.declared.get(root) else { continue };
            // The simulator does not type a function block instance as a whole: its
            // declared type tells what it is.
            let ty = match (sim.type_of(name), facts.fb_types.get(root)) {
                (Some(t), _) => t,
                (None, Some(fb)) => Type::FunctionBlock(fb.clone()),
                (None, None) => {
                    o.complete = false;
                    continue;
                }
            };
            o.expand(sim, name.clone(), &ty, &mut leaves, 0);
        }
        for a in &chart.actions {
            o.paths.push(format!("{}.Q", a.name));
            o.paths.push(format!("{}.A", a.name));
        }
        o
    }

    fn expand(&mut self, sim: &Simulation, path: String, ty: &Type, leaves: &mut usize, depth: u32) {
        if depth > 8 || *leaves > MAX_OBSERVED_LEAVES {
            self.complete = false;
            return;
        }
        match ty {
            Type::FunctionBlock(fb) => match sfc_st::stdlib::std_function_block(fb) {
                Some(members) => {
                    for (m, _, t) in members {
                        self.expand(sim, format!("{path}.{m}"), &t, leaves, depth + 1);
                    }
                }
                // A user function block: its internals (possibly a chart with step times)
                // are not followed.
                None => self.complete = false,
            },
            Type::Array { dims, elem } => {
                let mut count: usize = 1;
                for (lo, hi) in dims {
                    let n = hi.checked_sub(*lo).and_then(|d| d.checked_add(1)).and_then(|d| usize::try_from(d).ok());
                    count = match n.and_then(|n| count.checked_mul(n)) {
                        Some(c) => c,
                        None => {
                            self.complete = false;
                            return;
                        }
                    };
                }
                if count.saturating_add(*leaves) > MAX_OBSERVED_LEAVES {
                    self.complete = false;
                    return;
                }
                let mut idx: Vec<i64> = dims.iter().map(|d| d.0).collect();
                for _ in 0..count {
                    let text = idx.iter().map(i64::to_string).collect::<Vec<_>>().join(",");
                    self.expand(sim, format!("{path}[{text}]"), elem, leaves, depth + 1);
                    for d in (0..dims.len()).rev() {
                        if idx[d] < dims[d].1 {
                            idx[d] += 1;
                            break;
                        }
                        idx[d] = dims[d].0;
                    }
                }
            }
            Type::Struct { fields, .. } => {
                for (f, t) in fields {
                    self.expand(sim, format!("{path}.{f}"), t, leaves, depth + 1);
                }
            }
            Type::Error => {}
            _ => {
                if sim.get(&path).is_some() {
                    *leaves += 1;
                    self.paths.push(path);
                } else {
                    self.complete = false;
                }
            }
        }
    }

    fn observe(&self, sim: &Simulation) -> Vec<Value> {
        let mut out: Vec<Value> = self.paths.iter().map(|p| sim.get(p).unwrap_or(Value::Bool(false))).collect();
        out.extend(sim.active().into_iter().map(|s| Value::Str(s.into())));
        out
    }

    /// With these steps active and nothing firing, does an unchanged observation mean that
    /// waiting longer changes nothing?
    fn detects_settling(&self, active: &[StepId]) -> bool {
        self.complete && !self.timed_associations && !active.iter().any(|s| self.time_steps.contains(s))
    }

    /// Two states equal on the observed values (inputs aside) behave alike: they differ at
    /// most in values the replay can set again.
    fn identifies_states(&self) -> bool {
        self.complete
    }
}

// ---------------------------------------------------------------------------------------------
// The search

/// One witness transition being fired: where its firing round starts and its alternatives.
struct Level {
    /// Input changes of the waiting scans before the firing.
    wait_inputs: Vec<ScheduledInput>,
    /// The state the firing scan starts from.
    fire_from: Snapshot,
    alternatives: Vec<Valuation>,
    next: usize,
    seen: Vec<Vec<Value>>,
    /// The alternative taken: its input changes, scan and record.
    fire_inputs: Vec<ScheduledInput>,
    scan: u64,
    record: ScanRecord,
}

/// A valuation held while waiting, with how far its waiting got (plans are resumed phase by
/// phase so a plan that needs a long wait does not starve the others).
struct Plan {
    valuation: Valuation,
    /// Where the plan's next round starts (`None`: the level's start).
    state: Option<Snapshot>,
    waited: u64,
    wait_inputs: Vec<ScheduledInput>,
    last_obs: Option<Vec<Value>>,
    same: u32,
    /// The state after the last round's scan without changes, when nothing fired in it.
    idle: Option<Snapshot>,
    done: bool,
}

enum LevelFail {
    Blocked(String),
    Budget,
}

/// What went wrong in the rounds of one witness transition, for the reason of `Blocked`.
#[derive(Default)]
struct Trouble {
    together: Option<Vec<String>>,
    instead: Option<Vec<String>>,
    error: Option<String>,
    wait_fires: Option<Vec<String>>,
    settled: bool,
    waited: u64,
    plans: usize,
}

struct Search<'a> {
    sim: Simulation,
    chart: &'a Chart,
    facts: Facts,
    witness: &'a [TransitionId],
    opts: &'a ReplayOptions,
    inputs: Vec<Input>,
    /// Per transition, the inputs its guard reads.
    direct: Vec<Vec<usize>>,
    /// Inputs read by relevant action bodies (and durations), not necessarily by a guard.
    indirect: Vec<usize>,
    observer: Observer,
    scans: usize,
    /// The runaway scan that ended the search.
    runaway: Option<sfc_sim::RuntimeError>,
}

/// The error of a scan that spent its budget.
fn runaway_of(sim: &Simulation) -> Option<sfc_sim::RuntimeError> {
    sim.error().filter(|e| e.message.starts_with("runaway scan")).cloned()
}

impl<'a> Search<'a> {
    fn new(
        sim: Simulation,
        chart: &'a Chart,
        facts: Facts,
        witness: &'a [TransitionId],
        opts: &'a ReplayOptions,
    ) -> Self {
        let observer = Observer::new(&sim, chart, &facts);
        let mut s = Search {
            sim,
            chart,
            facts,
            witness,
            opts,
            inputs: Vec::new(),
            direct: Vec::new(),
            indirect: Vec::new(),
            observer,
            scans: 0,
            runaway: None,
        };
        s.collect_inputs();
        s
    }

    /// The input for a path read by the code, creating it on first use.
    fn input_of(&mut self, p: &facts::PathRef) -> Option<usize> {
        if let Some(i) = self.inputs.iter().position(|i| i.name.eq_ignore_ascii_case(&p.text)) {
            return Some(i);
        }
        // A path the simulator resolves has a root it resolves.
        let ty = self.sim.type_of(&p.text)?;
        if !self.facts.settable_root(&p.root, true) {
            return None;
        }
        let consts = self.facts.constants.get(&p.key).map(Vec::as_slice).unwrap_or(&[]);
        let cands = candidates(&ty, consts)?;
        self.inputs.push(Input { name: p.text.clone(), ty, candidates: cands });
        Some(self.inputs.len() - 1)
    }

    fn collect_inputs(&mut self) {
        let guards: Vec<Vec<facts::PathRef>> = self.facts.guards.iter().map(|g| g.reads.clone()).collect();
        for reads in guards {
            let mut d = Vec::new();
            for p in &reads {
                if let Some(i) = self.input_of(p) {
                    if !d.contains(&i) {
                        d.push(i);
                    }
                }
            }
            d.sort_unstable();
            self.direct.push(d);
        }
        let mut reads: Vec<facts::PathRef> = Vec::new();
        for &a in &self.facts.relevant_actions.clone() {
            if let Some(u) = self.facts.actions.get(a) {
                reads.extend(u.reads.iter().cloned());
            }
            for d in self.facts.durations.get(a).cloned().unwrap_or_default() {
                if let Some((name, _, _)) = self.facts.declared.get(&d) {
                    reads.push(facts::PathRef { key: d.clone(), text: name.clone(), root: d.clone() });
                }
            }
        }
        for p in &reads {
            if let Some(i) = self.input_of(p) {
                if !self.indirect.contains(&i) {
                    self.indirect.push(i);
                }
            }
        }
        self.indirect.sort_unstable();
    }

    /// The current values of the inputs `subset`, indexed by input (the others are not read:
    /// a placeholder stands there, so charts with many inputs do not pay for all of them).
    fn current(&self, subset: &[usize]) -> Vec<Value> {
        let mut out = vec![Value::Bool(false); self.inputs.len()];
        for &i in subset {
            if let (Some(slot), Some(input)) = (out.get_mut(i), self.inputs.get(i)) {
                *slot = self.sim.get(&input.name).unwrap_or(Value::Bool(false));
            }
        }
        out
    }

    /// Writes the changes of `v` that differ from the current values; returns them.
    fn apply(&mut self, v: &Valuation) -> Vec<ScheduledInput> {
        let mut out = Vec::new();
        let scan = self.sim.next_scan();
        let time = self.sim.next_time();
        for (i, value) in v {
            let Some(input) = self.inputs.get(*i) else { continue };
            if self.sim.get(&input.name).as_ref() == Some(value) {
                continue;
            }
            if self.sim.set(&input.name, value.clone()).is_ok() {
                out.push(ScheduledInput {
                    scan,
                    time,
                    name: input.name.clone(),
                    value: value.clone(),
                    literal: literal(value, &input.ty),
                });
            }
        }
        out
    }

    /// One scan within the budget.
    fn scan(&mut self) -> Option<ScanRecord> {
        if self.scans >= self.opts.max_tries {
            return None;
        }
        self.scans += 1;
        let rec = self.sim.scan().clone();
        if let Some(e) = runaway_of(&self.sim) {
            self.runaway = Some(e);
            self.scans = self.opts.max_tries;
            return None;
        }
        Some(rec)
    }

    /// Steps of the simulated chart active now.
    fn active_ids(&self) -> Vec<StepId> {
        self.sim.active().iter().filter(|n| !n.contains('.')).filter_map(|n| self.chart.step(n)).collect()
    }

    fn top_fired(rec: &ScanRecord) -> Vec<String> {
        rec.fired.iter().filter(|n| !n.contains('.')).cloned().collect()
    }

    fn error_of(rec: &ScanRecord) -> Option<String> {
        rec.events.iter().find_map(|e| match e {
            Event::Error(err) => Some(format!("{} (line {})", err.message, err.line)),
            _ => None,
        })
    }

    fn names(&self, steps: &[StepId]) -> String {
        let v: Vec<&str> = steps.iter().filter_map(|&s| self.chart.steps.get(s)).map(|s| s.name.as_str()).collect();
        if v.is_empty() {
            "none".to_string()
        } else {
            v.join(", ")
        }
    }

    fn run(&mut self, goal: &Goal) -> Result<Schedule, ReplayFailure> {
        let Some(first) = self.scan() else { return Err(self.give_up(0, None)) };
        if let Some(e) = Self::error_of(&first) {
            return Err(ReplayFailure::Blocked {
                index: 0,
                reason: format!("a runtime error stops the chart in scan 0: {e}"),
            });
        }
        let mut stack: Vec<Level> = Vec::new();
        let mut deepest: Option<(usize, String)> = None;
        let note = |deepest: &mut Option<(usize, String)>, k: usize, r: String| {
            if deepest.as_ref().is_none_or(|(d, _)| k > *d) {
                *deepest = Some((k, r));
            }
        };
        loop {
            let k = stack.len();
            if k == self.witness.len() {
                let rec = stack.last().map_or(&first, |l| &l.record).clone();
                match self.check_goal(goal, &rec) {
                    Ok(()) => return Ok(self.schedule(&stack, &first)),
                    Err(r) => note(&mut deepest, k, r),
                }
            } else {
                match self.search_level(k) {
                    Ok(level) => stack.push(level),
                    Err(LevelFail::Blocked(r)) => note(&mut deepest, k, r),
                    Err(LevelFail::Budget) => return Err(self.give_up(k, deepest)),
                }
            }
            // Take the next alternative of the innermost level that has one.
            loop {
                let depth = stack.len();
                let Some(top) = stack.last_mut() else {
                    let (index, reason) = deepest.unwrap_or((0, "no schedule found".to_string()));
                    return Err(ReplayFailure::Blocked { index, reason });
                };
                let w = self.witness[depth - 1];
                match Self::next_alternative(
                    &mut self.sim,
                    &self.inputs,
                    &self.observer,
                    (&mut self.scans, &mut self.runaway),
                    self.opts,
                    top,
                    w,
                    self.chart,
                ) {
                    Some(true) => break,
                    Some(false) => {
                        stack.pop();
                    }
                    None => return Err(self.give_up(depth - 1, deepest)),
                }
            }
        }
    }

    /// The failure when the budget runs out at `index`: a blocked transition found deeper (or
    /// as deep) is the better answer.
    fn give_up(&mut self, index: usize, deepest: Option<(usize, String)>) -> ReplayFailure {
        if let Some(error) = self.runaway.take() {
            return ReplayFailure::Runaway { index, error };
        }
        match deepest {
            Some((d, reason)) if d >= index => ReplayFailure::Blocked {
                index: d,
                reason: format!("{reason} (the search budget ran out while backtracking)"),
            },
            _ => ReplayFailure::Budget { index },
        }
    }

    fn check_goal(&self, goal: &Goal, rec: &ScanRecord) -> Result<(), String> {
        let last = self.witness.last().and_then(|&t| self.chart.transitions.get(t)).map(|t| t.name.as_str());
        let after = match last {
            Some(t) => format!("after {t} fired"),
            None => "after scan 0".to_string(),
        };
        match goal {
            Goal::Fired => Ok(()),
            Goal::Situation(steps) => {
                let mut want: Vec<StepId> = steps.clone();
                want.sort_unstable();
                want.dedup();
                let mut have: Vec<StepId> =
                    rec.active.iter().filter(|n| !n.contains('.')).filter_map(|n| self.chart.step(n)).collect();
                have.sort_unstable();
                if have == want {
                    Ok(())
                } else {
                    Err(format!(
                        "{after} the active steps are {{{}}}, not {{{}}}",
                        self.names(&have),
                        self.names(&want)
                    ))
                }
            }
            Goal::Unsafe(s) => {
                let name = self.chart.steps.get(*s).map(|s| s.name.as_str()).unwrap_or("?");
                let hit = rec
                    .events
                    .iter()
                    .any(|e| matches!(e, Event::Unsafe { step, .. } if step.eq_ignore_ascii_case(name)));
                if hit {
                    Ok(())
                } else {
                    Err(format!("{after} no `unsafe` event was emitted for step {name}"))
                }
            }
        }
    }

    /// Searches how to fire witness transition `k` from the current state.
    fn search_level(&mut self, k: usize) -> Result<Level, LevelFail> {
        let w = self.witness[k];
        let tr = &self.chart.transitions[w];
        let tname = tr.name.clone();
        let active = self.active_ids();
        if tr.from.is_empty() {
            return Err(LevelFail::Blocked(format!("{tname} has no step before it: it can never fire")));
        }
        let missing: Vec<StepId> = tr.from.iter().copied().filter(|s| !active.contains(s)).collect();
        if !missing.is_empty() {
            return Err(LevelFail::Blocked(format!(
                "{tname} is not enabled: step{} {} not active (active: {})",
                if missing.len() > 1 { "s" } else { "" },
                self.names(&missing),
                self.names(&active)
            )));
        }
        let enabled: Vec<TransitionId> = (0..self.chart.transitions.len())
            .filter(|&t| {
                let from = &self.chart.transitions[t].from;
                !from.is_empty() && from.iter().all(|s| active.contains(s))
            })
            .collect();
        let mut d: Vec<usize> = enabled.iter().flat_map(|&t| self.direct.get(t).cloned().unwrap_or_default()).collect();
        d.sort_unstable();
        d.dedup();
        let mut u: Vec<usize> = d.iter().chain(self.indirect.iter()).copied().collect();
        u.sort_unstable();
        u.dedup();
        // The active set does not change while waiting, so neither does whether time matters.
        let settles = self.observer.detects_settling(&active);
        let start = self.sim.snapshot();
        let mut plans: Vec<Plan> = valuations(&self.inputs, &u, &self.current(&u), MAX_PLANS)
            .into_iter()
            .map(|v| Plan {
                valuation: v,
                state: None,
                waited: 0,
                wait_inputs: Vec::new(),
                last_obs: None,
                same: 0,
                idle: None,
                done: false,
            })
            .collect();
        let mut trouble = Trouble { plans: plans.len(), ..Trouble::default() };
        let mut limits: Vec<u64> = PHASES.iter().copied().filter(|&l| l < self.opts.max_wait_scans).collect();
        limits.push(self.opts.max_wait_scans);
        for limit in limits {
            for plan in plans.iter_mut().filter(|p| !p.done) {
                // A resumed plan stops right after a round: do not repeat it.
                let mut resumed = false;
                match plan.state.take() {
                    Some(s) => {
                        self.sim.restore(&s);
                        resumed = true;
                    }
                    None => self.sim.restore(&start),
                }
                loop {
                    if !std::mem::take(&mut resumed) {
                        if let Some(level) = self.firing_round(w, &d, plan, &mut trouble)? {
                            return Ok(level);
                        }
                    }
                    if plan.waited >= self.opts.max_wait_scans {
                        plan.done = true;
                        break;
                    }
                    if plan.waited >= limit {
                        plan.state = Some(self.sim.snapshot());
                        break;
                    }
                    if !self.waiting_scan(plan, &mut trouble)? {
                        plan.done = true;
                        break;
                    }
                    if settles {
                        let obs = self.observer.observe(&self.sim);
                        if plan.last_obs.as_ref() == Some(&obs) {
                            plan.same += 1;
                            if plan.same >= STATIONARY_SCANS {
                                trouble.settled = true;
                                plan.done = true;
                                break;
                            }
                        } else {
                            plan.same = 0;
                            plan.last_obs = Some(obs);
                        }
                    }
                }
            }
        }
        self.sim.restore(&start);
        Err(LevelFail::Blocked(self.reason(w, &trouble)))
    }

    /// Tries every valuation of the direct inputs `d` for one scan from the current state.
    /// A level when some fires exactly `tname`; otherwise the simulation is left in the
    /// state after the scan without changes when nothing fired in it (the next waiting scan
    /// of a plan that changes nothing), or in the round's start state.
    fn firing_round(
        &mut self,
        w: TransitionId,
        d: &[usize],
        plan: &mut Plan,
        trouble: &mut Trouble,
    ) -> Result<Option<Level>, LevelFail> {
        let tname = self.chart.transitions.get(w).map(|t| t.name.clone()).unwrap_or_default();
        let round = self.sim.snapshot();
        let vals = valuations(&self.inputs, d, &self.current(d), MAX_VALUATIONS);
        let mut clean: Vec<Valuation> = Vec::new();
        let mut conflicting: Vec<Valuation> = Vec::new();
        plan.idle = None;
        for v in vals {
            self.sim.restore(&round);
            self.apply(&v);
            let Some(rec) = self.scan() else { return Err(LevelFail::Budget) };
            if let Some(e) = Self::error_of(&rec) {
                trouble.error.get_or_insert(e);
                continue;
            }
            let fired = Self::top_fired(&rec);
            if fired.len() == 1 && fired[0] == tname {
                if rec.events.iter().any(|e| matches!(e, Event::Conflict { .. })) {
                    conflicting.push(v);
                } else {
                    clean.push(v);
                }
            } else if fired.contains(&tname) {
                trouble.together.get_or_insert(fired);
            } else if !fired.is_empty() {
                let seen = trouble.instead.get_or_insert_with(Vec::new);
                for f in fired {
                    if !seen.contains(&f) {
                        seen.push(f);
                    }
                }
            } else if v.is_empty() {
                plan.idle = Some(self.sim.snapshot());
            }
        }
        self.sim.restore(&round);
        if clean.is_empty() && conflicting.is_empty() {
            return Ok(None);
        }
        clean.extend(conflicting);
        let alternatives = self.alternatives(&clean, d, w);
        Ok(Some(Level {
            wait_inputs: plan.wait_inputs.clone(),
            fire_from: round,
            alternatives,
            next: 0,
            seen: Vec::new(),
            fire_inputs: Vec::new(),
            scan: 0,
            record: ScanRecord::default(),
        }))
    }

    /// One waiting scan of `plan` from the current state (the start of a round): its changes
    /// at the first, nothing new after. `false` when something fires or faults in it.
    fn waiting_scan(&mut self, plan: &mut Plan, trouble: &mut Trouble) -> Result<bool, LevelFail> {
        if plan.waited == 0 && !plan.valuation.is_empty() {
            let v = plan.valuation.clone();
            let ins = self.apply(&v);
            let Some(rec) = self.scan() else { return Err(LevelFail::Budget) };
            if let Some(e) = Self::error_of(&rec) {
                trouble.error.get_or_insert(e);
                return Ok(false);
            }
            let fired = Self::top_fired(&rec);
            if !fired.is_empty() {
                trouble.wait_fires.get_or_insert(fired);
                return Ok(false);
            }
            plan.wait_inputs.extend(ins);
        } else {
            // The scan without changes was run by the round already.
            match plan.idle.take() {
                Some(s) => self.sim.restore(&s),
                None => return Ok(false),
            }
        }
        plan.waited += 1;
        trouble.waited = trouble.waited.max(plan.waited);
        Ok(true)
    }

    /// The firing valuations, then each combined with single changes of the indirect inputs
    /// it leaves alone, up to [`MAX_ALTERNATIVES`]. Inputs read by the actions of the steps
    /// `w` enters come first: those actions run in the firing scan and may capture them.
    fn alternatives(&self, successes: &[Valuation], direct: &[usize], w: TransitionId) -> Vec<Valuation> {
        let mut out: Vec<Valuation> = successes.iter().take(MAX_ALTERNATIVES).cloned().collect();
        let current = self.current(&self.indirect);
        let mut entry_reads: Vec<String> = Vec::new();
        if let Some(tr) = self.chart.transitions.get(w) {
            for &s in &tr.to {
                let Some(step) = self.chart.steps.get(s) else { continue };
                for a in &step.associations {
                    if let sfc_model::ActionTarget::Action(id) = a.target {
                        if let Some(u) = self.facts.actions.get(id) {
                            entry_reads.extend(u.reads.iter().map(|r| r.key.clone()));
                        }
                    }
                }
            }
        }
        let (mut first, rest): (Vec<usize>, Vec<usize>) =
            self.indirect.iter().copied().filter(|i| !direct.contains(i)).partition(|&i| {
                self.inputs.get(i).is_some_and(|inp| entry_reads.iter().any(|k| k.eq_ignore_ascii_case(&inp.name)))
            });
        first.extend(rest);
        'outer: for s in successes {
            for &i in &first {
                if s.iter().any(|(j, _)| *j == i) {
                    continue;
                }
                let Some(input) = self.inputs.get(i) else { continue };
                for c in &input.candidates {
                    if Some(c) == current.get(i) {
                        continue;
                    }
                    if out.len() >= MAX_ALTERNATIVES {
                        break 'outer;
                    }
                    let mut v = s.clone();
                    v.push((i, c.clone()));
                    v.sort_by_key(|(j, _)| *j);
                    out.push(v);
                }
            }
        }
        out
    }

    /// Fires the next alternative of `level`. `Some(false)` when none is left, `None` when
    /// the budget ran out.
    #[allow(clippy::too_many_arguments)]
    fn next_alternative(
        sim: &mut Simulation,
        inputs: &[Input],
        observer: &Observer,
        (scans, runaway): (&mut usize, &mut Option<sfc_sim::RuntimeError>),
        opts: &ReplayOptions,
        level: &mut Level,
        w: TransitionId,
        chart: &Chart,
    ) -> Option<bool> {
        let tname = chart.transitions.get(w).map(|t| t.name.as_str()).unwrap_or("");
        while level.next < level.alternatives.len() {
            let alt = level.alternatives[level.next].clone();
            level.next += 1;
            sim.restore(&level.fire_from);
            let scan = sim.next_scan();
            let time = sim.next_time();
            let mut changes = Vec::new();
            for (i, value) in &alt {
                let Some(input) = inputs.get(*i) else { continue };
                if sim.get(&input.name).as_ref() == Some(value) {
                    continue;
                }
                if sim.set(&input.name, value.clone()).is_ok() {
                    changes.push(ScheduledInput {
                        scan,
                        time,
                        name: input.name.clone(),
                        value: value.clone(),
                        literal: literal(value, &input.ty),
                    });
                }
            }
            if *scans >= opts.max_tries {
                return None;
            }
            *scans += 1;
            let rec = sim.scan().clone();
            if let Some(e) = runaway_of(sim) {
                *runaway = Some(e);
                *scans = opts.max_tries;
                return None;
            }
            let fired: Vec<&String> = rec.fired.iter().filter(|n| !n.contains('.')).collect();
            if Self::error_of(&rec).is_some() || fired.len() != 1 || fired[0] != tname {
                continue;
            }
            if observer.identifies_states() {
                let obs = observer.observe(sim);
                if level.seen.contains(&obs) {
                    continue;
                }
                level.seen.push(obs);
            }
            level.fire_inputs = changes;
            level.scan = scan;
            level.record = rec;
            return Some(true);
        }
        Some(false)
    }

    fn reason(&mut self, w: TransitionId, t: &Trouble) -> String {
        let tr = &self.chart.transitions[w];
        let name = tr.name.clone();
        let mut parts: Vec<String> = Vec::new();
        if let Some(f) = &t.together {
            parts.push(format!(
                "it fires only together with {}",
                f.iter().filter(|n| **n != name).cloned().collect::<Vec<_>>().join(", ")
            ));
        }
        if let Some(f) = &t.instead {
            parts.push(format!("{} fire{} instead", f.join(", "), if f.len() == 1 { "s" } else { "" }));
        }
        if let Some(f) = &t.wait_fires {
            if t.instead.as_ref() != Some(f) {
                parts.push(format!("while waiting {} fire{}", f.join(", "), if f.len() == 1 { "s" } else { "" }));
            }
        }
        if let Some(e) = &t.error {
            parts.push(format!("runtime error: {e}"));
        }
        if parts.is_empty() {
            parts.push("no input valuation makes its guard true".to_string());
        }
        let waited = if t.settled {
            format!("the chart settles after {} waiting scan{}", t.waited, if t.waited == 1 { "" } else { "s" })
        } else {
            format!("waited up to {} scan{}", t.waited, if t.waited == 1 { "" } else { "s" })
        };
        let inputs = if self.inputs.is_empty() {
            "no settable input influences the guards".to_string()
        } else {
            format!("{} input plan{} tried", t.plans, if t.plans == 1 { "" } else { "s" })
        };
        // The guard as the simulator sees it now.
        let guard = tr
            .from
            .first()
            .and_then(|&s| self.chart.steps.get(s))
            .and_then(|s| self.sim.explain_step(&s.name))
            .and_then(|r| {
                let prefix = format!("{name}:");
                r.lines()
                    .into_iter()
                    .find(|l| l.starts_with(&prefix))
                    .map(|l| l.split_whitespace().collect::<Vec<_>>().join(" "))
            });
        let mut out = format!("{name} cannot fire alone: {} ({waited}, {inputs})", parts.join("; "));
        if let Some(g) = guard {
            out.push_str(&format!("; {g}"));
        }
        out
    }

    fn schedule(&self, stack: &[Level], first: &ScanRecord) -> Schedule {
        let mut inputs = Vec::new();
        let mut firings = Vec::new();
        let mut situations = Vec::new();
        for l in stack {
            inputs.extend(l.wait_inputs.iter().cloned());
            inputs.extend(l.fire_inputs.iter().cloned());
            firings.push(l.scan);
            situations.push(l.record.active.clone());
        }
        Schedule {
            period: self.sim.options().period,
            inputs,
            last_scan: firings.last().copied().unwrap_or(0),
            firings,
            witness: self.witness.to_vec(),
            final_active: stack.last().map_or_else(|| first.active.clone(), |l| l.record.active.clone()),
            situations,
            file: String::new(),
            pou: self.chart.pou.clone(),
        }
    }
}

// ---------------------------------------------------------------------------------------------
// Presenting a schedule

impl Schedule {
    /// Human lines for the diagnostic notes: `scan 1 (T#10ms): Start := TRUE`, `scan 1: T1
    /// fires`, in scan order, then the active steps reached.
    pub fn describe(&self, chart: &Chart) -> Vec<String> {
        let mut out = Vec::new();
        let mut scans: Vec<u64> = self.inputs.iter().map(|i| i.scan).chain(self.firings.iter().copied()).collect();
        scans.sort_unstable();
        scans.dedup();
        for s in scans {
            for i in self.inputs.iter().filter(|i| i.scan == s) {
                out.push(format!("scan {s} ({}): {} := {}", format_time(i.time), i.name, i.literal));
            }
            for (k, _) in self.firings.iter().enumerate().filter(|(_, f)| **f == s) {
                let name = self.witness.get(k).and_then(|&t| chart.transitions.get(t)).map_or("?", |t| t.name.as_str());
                out.push(format!("scan {s}: {name} fires"));
            }
        }
        out.push(format!(
            "scan {}: active steps {}",
            self.last_scan,
            if self.final_active.is_empty() { "none".to_string() } else { self.final_active.join(", ") }
        ));
        out
    }

    /// A `*.scenario.toml` text that sets the inputs at their times and expects, after each
    /// firing, the active steps, and at the last scan the goal (for [`Goal::Unsafe`] also the
    /// step's `X`). The scenario names the chart by the file part of the name given to
    /// [`replay`]: write it beside the chart.
    pub fn to_scenario(&self, chart: &Chart, goal: &Goal, title: &str) -> String {
        let file = std::path::Path::new(&self.file)
            .file_name()
            .map_or_else(|| self.file.clone(), |f| f.to_string_lossy().into_owned());
        let mut out = String::new();
        for line in title.lines() {
            out.push_str(&format!("# {line}\n"));
        }
        let names: Vec<&str> =
            self.witness.iter().filter_map(|&t| chart.transitions.get(t)).map(|t| t.name.as_str()).collect();
        out.push_str(&format!(
            "# Generated by the witness replay of sfc-analysis: fires {} one scan at a time.\n",
            if names.is_empty() { "nothing".to_string() } else { names.join(", ") }
        ));
        out.push_str(&format!("chart = {}\n", toml_string(&file)));
        out.push_str(&format!("pou = {}\n", toml_string(&self.pou)));
        out.push_str(&format!("period = {}\n", toml_string(&format_time(self.period))));
        out.push_str("profile = \"iec\"\n");
        out.push_str(&format!("scans = {}\n", self.last_scan + 1));
        let mut scans: Vec<u64> = self.inputs.iter().map(|i| i.scan).chain(self.firings.iter().copied()).collect();
        scans.push(self.last_scan);
        scans.sort_unstable();
        scans.dedup();
        for s in scans {
            out.push_str("\n[[at]]\n");
            out.push_str(&format!("time = {}\n", toml_string(&format_time(s as i64 * self.period))));
            let sets: Vec<String> = self
                .inputs
                .iter()
                .filter(|i| i.scan == s)
                .map(|i| format!("{} = {}", toml_string(&i.name), toml_value(&i.value, &i.literal)))
                .collect();
            if !sets.is_empty() {
                out.push_str(&format!("set = {{ {} }}\n", sets.join(", ")));
            }
            let mut expect: Vec<String> = Vec::new();
            let fired_here = self.firings.iter().rposition(|f| *f == s);
            let active = if s == self.last_scan {
                Some(&self.final_active)
            } else {
                fired_here.and_then(|k| self.situations.get(k))
            };
            if let Some(a) = active {
                expect.push(format!("active = [{}]", a.iter().map(|n| toml_string(n)).collect::<Vec<_>>().join(", ")));
            }
            if s == self.last_scan {
                if let Goal::Unsafe(step) = goal {
                    if let Some(st) = chart.steps.get(*step) {
                        expect.push(format!("{} = true", toml_string(&format!("{}.X", st.name))));
                    }
                }
            }
            if !expect.is_empty() {
                out.push_str(&format!("expect = {{ {} }}\n", expect.join(", ")));
            }
        }
        out
    }
}

/// A TOML basic string.
fn toml_string(s: &str) -> String {
    let mut out = String::from("\"");
    for c in s.chars() {
        match c {
            '"' => out.push_str("\\\""),
            '\\' => out.push_str("\\\\"),
            '\n' => out.push_str("\\n"),
            '\t' => out.push_str("\\t"),
            c if (c as u32) < 0x20 => out.push_str(&format!("\\u{:04X}", c as u32)),
            c => out.push(c),
        }
    }
    out.push('"');
    out
}

/// A value as the scenario format writes it: booleans and numbers as TOML values, TIME and
/// enumeration values as strings.
fn toml_value(v: &Value, literal: &str) -> String {
    match v {
        Value::Bool(b) => b.to_string(),
        Value::Int(i) if literal.parse::<i64>().is_ok() => i.to_string(),
        Value::Int(_) => toml_string(literal),
        Value::Real(r) if r.is_finite() => real_text(*r),
        Value::Real(r) if r.is_nan() => "nan".to_string(),
        Value::Real(r) => if *r > 0.0 { "inf" } else { "-inf" }.to_string(),
        Value::Time(t) => toml_string(&format_time(*t)),
        Value::Str(s) => toml_string(s),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn bool_input(name: &str) -> Input {
        Input { name: name.into(), ty: Type::Bool, candidates: vec![Value::Bool(false), Value::Bool(true)] }
    }

    #[test]
    fn valuations_fewest_changes_first() {
        let inputs = vec![bool_input("A"), bool_input("B"), bool_input("C")];
        let cur = vec![Value::Bool(false); 3];
        let v = valuations(&inputs, &[0, 1, 2], &cur, 100);
        assert_eq!(v.len(), 8);
        assert!(v[0].is_empty());
        assert_eq!(v[1], vec![(0, Value::Bool(true))]);
        assert_eq!(v[3], vec![(2, Value::Bool(true))]);
        assert_eq!(v[4], vec![(0, Value::Bool(true)), (1, Value::Bool(true))]);
        assert_eq!(v[7].len(), 3);
        assert_eq!(valuations(&inputs, &[0, 1, 2], &cur, 5).len(), 5);
        assert_eq!(valuations(&inputs, &[], &cur, 5), vec![Vec::new()]);
    }

    #[test]
    fn integer_candidates_are_clamped() {
        let c = candidates(&Type::USInt, &[Const::Int(0), Const::Int(255), Const::Int(50)]).unwrap_or_default();
        let ints: Vec<i64> = c.iter().filter_map(Value::as_int).collect();
        assert_eq!(ints, vec![0, 1, 49, 50, 51, 254, 255]);
        let t = candidates(&Type::Time, &[Const::Time(2_000_000)]).unwrap_or_default();
        assert_eq!(t, vec![Value::Time(0), Value::Time(1_999_000), Value::Time(2_000_000), Value::Time(2_001_000)]);
        assert!(candidates(&Type::String { len: None }, &[]).is_none());
    }

    #[test]
    fn reals_read_back() {
        assert_eq!(real_text(51.0), "51.0");
        assert_eq!(real_text(2.5), "2.5");
        assert_eq!(real_text(1e20), "1e20");
        assert_eq!(toml_value(&Value::Int(2), "Auto"), "\"Auto\"");
        assert_eq!(toml_value(&Value::Int(-3), "-3"), "-3");
    }
}
