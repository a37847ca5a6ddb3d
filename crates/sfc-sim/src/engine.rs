//! The scan engine: `semantics.md` scan by scan for every SFC instance, action control, events,
//! profiles, chart control variables, and the [`Simulation`] driving one top-level POU.
//!
//! Per-scan cost grows with the active steps and the live actions, not with the chart: the
//! engine keeps the active steps as a list, tests only the transitions leaving them, and runs
//! action control only for actions that are associated with an active step or still hold
//! state (stored flags, running timers, pending final scans).

use crate::code::{ChartCode, Ctx, DurationCode, FastGuard, Fault, Memory, Place, PouBody, Program};
use crate::explain::StepReport;
use crate::value::Value;
use crate::{Event, Profile, RuntimeError, ScanRecord, SimOptions};
use sfc_diagnostics::{Diagnostic, SourceFile, Span};
use sfc_model::{ActionTarget, Qualifier};
use sfc_st::Type;
use std::sync::Arc;

mod matiec;
mod monitor;

pub(crate) use matiec::test_order as matiec_test_order;

/// Fired transitions and events collected during one scan (from every chart instance).
#[derive(Debug, Default)]
pub struct ScanSink {
    /// `(chart instance, transition)` in firing order.
    pub fired: Vec<(u32, u32)>,
    pub events: Vec<Event>,
    /// Where the scan faulted: the innermost chart instance and the action body or guard
    /// that was running (noted on the error path only).
    pub(crate) fault_site: Option<(u32, FaultSite)>,
}

/// The chart element whose code was running when a scan faulted.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum FaultSite {
    Action(usize),
    Guard(u32),
}

impl ScanSink {
    /// Notes where a fault happened, unless a nested chart already did.
    #[cold]
    fn note_fault(&mut self, chart: usize, site: FaultSite) {
        if self.fault_site.is_none() {
            self.fault_site = Some((chart as u32, site));
        }
    }
}

/// What drives an action control block: an ACTION, or a BOOL variable used as an action.
#[derive(Debug, Clone)]
pub(crate) struct Entity {
    pub(crate) name: String,
    pub(crate) action: Option<usize>,
    pub(crate) variable: Option<Place>,
    /// Associations in text order (step declaration order, then order inside the step).
    pub(crate) assocs: Vec<Assoc>,
}

#[derive(Debug, Clone)]
pub(crate) struct Assoc {
    pub(crate) step: u32,
    pub(crate) qualifier: Qualifier,
    pub(crate) duration: Option<DurationCode>,
}

/// A list per index, stored flat (compressed rows): `rows[i]` is `items[start[i]..start[i+1]]`.
#[derive(Debug, Clone, Default)]
pub(crate) struct Rows {
    start: Vec<u32>,
    items: Vec<u32>,
}

impl Rows {
    fn from_lists(lists: impl Iterator<Item = Vec<u32>>) -> Rows {
        let mut rows = Rows { start: vec![0], items: Vec::new() };
        for l in lists {
            rows.items.extend(l);
            rows.start.push(rows.items.len() as u32);
        }
        rows
    }
    #[inline]
    pub(crate) fn get(&self, i: u32) -> &[u32] {
        let i = i as usize;
        &self.items[self.start[i] as usize..self.start[i + 1] as usize]
    }
}

/// One transition as the evolution sees it.
#[derive(Debug, Clone, Copy)]
pub(crate) struct TrInfo {
    /// The guard, when it can be evaluated without calling its closure.
    guard: FastGuard,
    /// `from` and `to` of a transition between one step and one step; `from` is `u32::MAX` for
    /// the others.
    from: u32,
    to: u32,
    /// One preceding step: enabled whenever that step is active.
    single_pre: bool,
    /// Leaves a step that has other outgoing transitions: only such transitions can conflict.
    may_conflict: bool,
}

impl TrInfo {
    #[inline(always)]
    fn is_link(&self) -> bool {
        self.from != u32::MAX
    }
}

/// What every instance of one SFC POU shares: the net and the action control plan. Built once
/// per POU ([`ChartCode::plan`]).
#[derive(Debug)]
pub struct ChartPlan {
    pub(crate) outgoing: Rows,
    pub(crate) pre: Rows,
    pub(crate) post: Rows,
    /// What the evolution reads of each transition, packed so one transition is one load.
    tr: Vec<TrInfo>,
    /// Per step: its only outgoing transition when that transition has no other preceding
    /// step (a candidate whenever the step is active), `u32::MAX` otherwise.
    single_out: Vec<u32>,
    /// Frame offsets of the `X` and `T` slots of each step.
    x_slots: Vec<u32>,
    t_slots: Vec<u32>,
    /// Sort key of each transition for conflict resolution: explicit priorities first.
    pub(crate) order_key: Vec<(u8, i64, u32)>,
    pub(crate) explicit: Vec<bool>,
    pub(crate) initial: Vec<u32>,
    pub(crate) timeouts: Vec<Option<i64>>,
    pub(crate) supervised: bool,
    pub(crate) entities: Vec<Entity>,
    /// Entities each step associates, without repetition.
    pub(crate) step_entities: Rows,
    /// Entities that are BOOL variables: written with Q every scan.
    pub(crate) variable_entities: Vec<u32>,
    pub(crate) step_names: Vec<String>,
    /// The step names as STRING values (for SFCCurrentStep and SFCErrorStep, shared, so
    /// writing them allocates nothing).
    step_values: Vec<Value>,
    pub(crate) transition_names: Vec<String>,
    pub(crate) action_names: Vec<String>,
}

impl ChartPlan {
    pub(crate) fn new(code: &ChartCode) -> ChartPlan {
        let chart = &code.chart;
        let n = chart.steps.len();
        let dedup = |v: &[usize]| {
            let mut out: Vec<u32> = Vec::new();
            for &s in v {
                if !out.contains(&(s as u32)) {
                    out.push(s as u32);
                }
            }
            out
        };
        let mut outgoing = vec![Vec::new(); n];
        for (t, tr) in chart.transitions.iter().enumerate() {
            for s in dedup(&tr.from) {
                outgoing[s as usize].push(t as u32);
            }
        }
        let pre = Rows::from_lists(chart.transitions.iter().map(|t| dedup(&t.from)));
        let post = Rows::from_lists(chart.transitions.iter().map(|t| dedup(&t.to)));
        let order_key = chart
            .transitions
            .iter()
            .enumerate()
            .map(|(i, t)| match t.priority {
                Some(p) => (0u8, p, i as u32),
                None => (1u8, 0, i as u32),
            })
            .collect();
        let explicit = chart.transitions.iter().map(|t| t.priority.is_some()).collect();
        let mut entities: Vec<Entity> = chart
            .actions
            .iter()
            .enumerate()
            .map(|(i, a)| Entity { name: a.name.clone(), action: Some(i), variable: None, assocs: Vec::new() })
            .collect();
        let mut step_entities = vec![Vec::new(); n];
        let mut variable_entities = Vec::new();
        for (s, step) in chart.steps.iter().enumerate() {
            for (k, a) in step.associations.iter().enumerate() {
                let assoc_code = code.associations.get(s).and_then(|v| v.get(k));
                let e = match a.target {
                    ActionTarget::Action(id) => id,
                    ActionTarget::Variable => {
                        let Some(place) = assoc_code.and_then(|c| c.variable) else {
                            continue;
                        };
                        match entities.iter().position(|e| e.variable == Some(place)) {
                            Some(e) => e,
                            None => {
                                entities.push(Entity {
                                    name: assoc_code
                                        .and_then(|c| c.variable_name.clone())
                                        .unwrap_or_else(|| a.action.clone()),
                                    action: None,
                                    variable: Some(place),
                                    assocs: Vec::new(),
                                });
                                variable_entities.push((entities.len() - 1) as u32);
                                entities.len() - 1
                            }
                        }
                    }
                };
                entities[e].assocs.push(Assoc {
                    step: s as u32,
                    qualifier: a.qualifier,
                    duration: assoc_code.and_then(|c| c.duration),
                });
                if !step_entities[s].contains(&(e as u32)) {
                    step_entities[s].push(e as u32);
                }
            }
        }
        let timeouts: Vec<Option<i64>> = chart.steps.iter().map(|s| s.timeout).collect();
        let tr: Vec<TrInfo> = (0..chart.transitions.len() as u32)
            .map(|t| {
                let (from, to) = match (pre.get(t), post.get(t)) {
                    ([from], [to]) => (*from, *to),
                    _ => (u32::MAX, 0),
                };
                TrInfo {
                    guard: code.fast[t as usize],
                    from,
                    to,
                    single_pre: pre.get(t).len() == 1,
                    may_conflict: pre.get(t).iter().any(|&s| outgoing[s as usize].len() > 1),
                }
            })
            .collect();
        let single_out = outgoing
            .iter()
            .map(|o| match o.as_slice() {
                [t] if tr[*t as usize].single_pre => *t,
                _ => u32::MAX,
            })
            .collect();
        ChartPlan {
            outgoing: Rows::from_lists(outgoing.into_iter()),
            tr,
            single_out,
            x_slots: code.step_x.clone(),
            t_slots: code.step_t.clone(),
            pre,
            post,
            order_key,
            explicit,
            initial: chart.steps.iter().enumerate().filter(|(_, s)| s.initial).map(|(i, _)| i as u32).collect(),
            supervised: timeouts.iter().any(Option::is_some),
            timeouts,
            entities,
            step_entities: Rows::from_lists(step_entities.into_iter()),
            variable_entities,
            step_names: chart.steps.iter().map(|s| s.name.clone()).collect(),
            step_values: chart.steps.iter().map(|s| Value::Str(Arc::from(s.name.as_str()))).collect(),
            transition_names: chart.transitions.iter().map(|t| t.name.clone()).collect(),
            action_names: chart.actions.iter().map(|a| a.name.clone()).collect(),
        }
    }
}

/// The ACTION_CONTROL block of one entity (IEC 61131-3 2nd ed. 2.6.4.5) with its timers on
/// virtual time: a timer holds the time its input was first seen TRUE.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub(crate) struct Control {
    s_ff: bool,
    sd_ff: bool,
    ds_ff: bool,
    sl_ff: bool,
    l_tmr: Option<i64>,
    d_tmr: Option<i64>,
    sd_tmr: Option<i64>,
    ds_tmr: Option<i64>,
    sl_tmr: Option<i64>,
    p_mem: bool,
    p1_mem: bool,
    p0_mem: bool,
    /// The duration of each timed qualifier (L, D, SD, DS, SL): the last one a winning
    /// association of that qualifier gave, so a stored SD/SL keeps its own duration after its
    /// step was left.
    t: [i64; 5],
    pub(crate) q: bool,
    pub(crate) a: bool,
    live: bool,
}

/// The inputs of one ACTION_CONTROL block in one scan.
#[derive(Debug, Clone, Copy, Default)]
struct Inputs {
    n: bool,
    r: bool,
    s: bool,
    l: bool,
    d: bool,
    p: bool,
    sd: bool,
    ds: bool,
    sl: bool,
    p1: bool,
    p0: bool,
}

impl Inputs {
    fn set(&mut self, q: Qualifier, v: bool, or: bool) {
        let slot = match q {
            Qualifier::N => &mut self.n,
            Qualifier::R => &mut self.r,
            Qualifier::S => &mut self.s,
            Qualifier::L => &mut self.l,
            Qualifier::D => &mut self.d,
            Qualifier::P => &mut self.p,
            Qualifier::SD => &mut self.sd,
            Qualifier::DS => &mut self.ds,
            Qualifier::SL => &mut self.sl,
            Qualifier::P1 => &mut self.p1,
            Qualifier::P0 => &mut self.p0,
        };
        *slot = if or { *slot || v } else { v };
    }
}

/// TON on virtual time: `Q = elapsed ≥ PT`, elapsed counted from the scan the input rose.
fn ton(mem: &mut Option<i64>, input: bool, pt: i64, now: i64) -> bool {
    if !input {
        *mem = None;
        return false;
    }
    let start = *mem.get_or_insert(now);
    now - start >= pt
}

impl Control {
    /// One execution of the block; returns `(Q, A)`.
    fn update(&mut self, i: Inputs, now: i64, profile: Profile) -> (bool, bool) {
        let [t_l, t_d, t_sd, t_ds, t_sl] = self.t;
        let r = i.r;
        self.s_ff = !r && (self.s_ff || i.s);
        let l_q = ton(&mut self.l_tmr, i.l, t_l, now);
        let d_q = ton(&mut self.d_tmr, i.d, t_d, now);
        let p_q = i.p && !self.p_mem;
        self.p_mem = i.p;
        // MatIEC does not let R cancel a pending SD.
        let sd_reset = r && profile != Profile::Matiec;
        self.sd_ff = !sd_reset && (self.sd_ff || i.sd);
        let sd_q = ton(&mut self.sd_tmr, self.sd_ff, t_sd, now);
        let ds_q = ton(&mut self.ds_tmr, i.ds, t_ds, now);
        self.ds_ff = !r && (self.ds_ff || ds_q);
        self.sl_ff = !r && (self.sl_ff || i.sl);
        let sl_q = ton(&mut self.sl_tmr, self.sl_ff, t_sl, now);
        let q = !r && (i.n || (i.l && !l_q) || d_q || p_q || self.s_ff || sd_q || self.ds_ff || (self.sl_ff && !sl_q));
        let p1 = i.p1 && !self.p1_mem;
        let p0 = !i.p0 && self.p0_mem;
        self.p1_mem = i.p1;
        self.p0_mem = i.p0;
        let fell = self.q && !q && profile != Profile::Matiec;
        self.q = q;
        self.a = q || fell || p1 || p0;
        (self.q, self.a)
    }

    /// Holds no state: no flip-flop set, no timer running, no edge memory, Q and A FALSE.
    fn idle(&self) -> bool {
        !(self.s_ff
            || self.sd_ff
            || self.ds_ff
            || self.sl_ff
            || self.p_mem
            || self.p1_mem
            || self.p0_mem
            || self.q
            || self.a)
            && self.l_tmr.is_none()
            && self.d_tmr.is_none()
            && self.sd_tmr.is_none()
            && self.ds_tmr.is_none()
            && self.sl_tmr.is_none()
    }
}

/// Activations and active time of one step, for the time analysis.
#[derive(Debug, Clone, Copy, Default)]
struct StepTally {
    activations: u64,
    completed: u64,
    min: i64,
    max: i64,
    sum: i64,
}

/// The run-time state of one step, kept together so a step touches one cache line.
#[derive(Debug, Clone, Copy, Default)]
pub(crate) struct StepState {
    /// Elapsed time, µs (mirrored into the `T` slot).
    pub(crate) t: i64,
    /// Position in `ChartState::active` while active.
    pos: u32,
    pub(crate) x: bool,
    /// `sfc.timeout` already reported for the current activation.
    overdue: bool,
    /// Scratch: consumed by an accepted transition / member of the deactivated set.
    consumed: bool,
    /// Scratch: accepted transitions activating it in this scan, or conflicting ones.
    hits: u8,
    /// Scratch: the evolution in which a true transition leaving it was seen (conflict test).
    seen: u32,
    /// Scratch: the evolution that deactivates it (member of `D`).
    dmark: u32,
    /// Scratch: the evolution that activates it (member of `A`).
    amark: u32,
    /// Absolute memory slots of its `X` and `T`.
    x_slot: u32,
    t_slot: u32,
    /// Keep the `X` / `T` slot up to date: only when some code of the file may read it
    /// (otherwise [`Simulation::get`] answers from the step state).
    mirror_x: bool,
    mirror_t: bool,
    /// The step associates actions (its activation makes them live).
    has_entities: bool,
    /// Time analysis: activations and active times.
    tally: StepTally,
}

impl StepState {
    /// Ends the current activation in the time analysis.
    #[inline(always)]
    fn complete(&mut self) {
        let d = self.t;
        let tl = &mut self.tally;
        if tl.completed == 0 {
            tl.min = d;
            tl.max = d;
        } else {
            tl.min = tl.min.min(d);
            tl.max = tl.max.max(d);
        }
        tl.completed += 1;
        tl.sum = tl.sum.saturating_add(d);
    }
    #[inline]
    fn publish_x(&self, mem: &mut [Value], x: bool) {
        if self.mirror_x {
            put_bool(mem, self.x_slot as usize, x);
        }
    }
    #[inline]
    fn publish_t(&self, mem: &mut [Value]) {
        if self.mirror_t {
            put_time(mem, self.t_slot as usize, self.t);
        }
    }
}

/// The run-time state of one SFC instance.
#[derive(Debug, Clone)]
pub struct ChartState {
    /// Index of the POU in `Program::pous`.
    pub pou: usize,
    /// Absolute frame base.
    pub frame: usize,
    /// Instance path, `""` for the top POU.
    pub path: String,
    pub(crate) plan: Arc<ChartPlan>,
    started: bool,
    last_time: i64,
    /// Active steps, in no particular order.
    pub(crate) active: Vec<u32>,
    pub(crate) steps: Vec<StepState>,
    pub(crate) controls: Vec<Control>,
    live: Vec<u32>,
    /// Steps left by the last evolution (CODESYS body order), kept only under that profile.
    left: Vec<u32>,
    track_left: bool,
    /// Steps activated since the last action phase.
    entered: Vec<u32>,
    /// The active set changed since the last `finish_scan`.
    changed: bool,
    /// Keep `SFCCurrentStep` up to date in memory: only when some code of the file reads it
    /// (writing a STRING every scan costs more than the rest of a scan). Readers from outside
    /// (`Simulation::get`) get it computed.
    pub(crate) track_current: bool,
    // Scratch buffers, kept to avoid allocation per scan.
    stamp: Vec<u32>,
    /// Number of evolutions so far, modulo 2^32: the epoch marking scratch fields.
    evolutions: u32,
    cand: Vec<u32>,
    accepted: Vec<u32>,
    run: Vec<u32>,
    current: Option<u32>,
    /// `(time, transition)` of every firing, to rebuild the sequence of situations.
    pub(crate) log: Vec<(i64, u32)>,
    /// The `matiec` profile's own state (`engine/matiec.rs`).
    matiec: Option<Box<matiec::State>>,
}

/// At most this many firings are kept per instance for the sequence of situations.
const LOG_LIMIT: usize = 1 << 20;

impl ChartState {
    pub(crate) fn new(pou: usize, plan: Arc<ChartPlan>, frame: usize, path: String) -> ChartState {
        let n = plan.step_names.len();
        let m = plan.entities.len();
        let nt = plan.transition_names.len();
        let steps = (0..n)
            .map(|s| StepState {
                x_slot: (frame + plan.x_slots[s] as usize) as u32,
                t_slot: (frame + plan.t_slots[s] as usize) as u32,
                mirror_x: true,
                mirror_t: true,
                has_entities: !plan.step_entities.get(s as u32).is_empty(),
                ..StepState::default()
            })
            .collect();
        ChartState {
            pou,
            frame,
            path,
            started: false,
            last_time: 0,
            active: Vec::new(),
            steps,
            controls: vec![Control::default(); m],
            live: Vec::new(),
            left: Vec::new(),
            track_left: true,
            entered: Vec::new(),
            changed: true,
            track_current: true,
            stamp: vec![0; nt],
            evolutions: 0,
            cand: Vec::new(),
            accepted: Vec::new(),
            run: Vec::new(),
            current: None,
            log: Vec::new(),
            matiec: None,
            plan,
        }
    }

    /// `Path.Name`, or `Name` for the top chart.
    pub(crate) fn qualify(&self, name: &str) -> String {
        if self.path.is_empty() {
            name.to_string()
        } else {
            format!("{}.{name}", self.path)
        }
    }

    /// Starts a new evolution and returns its epoch (never 0: 0 marks nothing). When the
    /// counter wraps, every mark is cleared so an old mark cannot equal a new epoch.
    fn next_epoch(&mut self) -> u32 {
        self.evolutions = self.evolutions.wrapping_add(1);
        if self.evolutions == 0 {
            for step in &mut self.steps {
                step.seen = 0;
                step.dmark = 0;
                step.amark = 0;
            }
            self.stamp.fill(0);
            self.evolutions = 1;
        }
        self.evolutions
    }

    /// Whether step `s` is active.
    pub(crate) fn is_active(&self, s: u32) -> bool {
        self.steps[s as usize].x
    }

    /// Elapsed time of step `s`, µs.
    pub(crate) fn time(&self, s: u32) -> i64 {
        self.steps[s as usize].t
    }

    /// Activates `s` (or restarts its time if it stays active).
    fn activate(&mut self, s: u32) {
        let st = &mut self.steps[s as usize];
        if !st.x {
            st.x = true;
            st.pos = self.active.len() as u32;
            self.active.push(s);
        }
        st.t = 0;
        st.overdue = false;
        if st.has_entities {
            self.entered.push(s);
        }
        self.steps[s as usize].tally.activations += 1;
        self.changed = true;
    }

    fn deactivate(&mut self, s: u32) {
        let i = s as usize;
        let st = &mut self.steps[i];
        if !st.x {
            return;
        }
        st.x = false;
        let pos = st.pos as usize;
        self.active.swap_remove(pos);
        if let Some(&moved) = self.active.get(pos) {
            self.steps[moved as usize].pos = pos as u32;
        }
        self.complete(s);
    }

    /// Ends the current activation of `s` in the time analysis (the step is left, or left and
    /// re-entered).
    fn complete(&mut self, s: u32) {
        self.steps[s as usize].complete();
        self.changed = true;
    }
}

fn code_of(prog: &Program, pou: usize) -> &ChartCode {
    match &prog.pous[pou].body {
        PouBody::Chart(c) => c,
        PouBody::Code(_) => unreachable!("chart state of a POU without SFC body"),
    }
}

/// Runs one scan of the SFC instance `chart` (an index into `ctx.charts`), as a call of its
/// function block does. The first call is the instance's scan 0.
pub fn run_chart(ctx: &mut Ctx<'_>, chart: usize) -> Result<(), Fault> {
    let prog = ctx.prog;
    let code = code_of(prog, ctx.charts[chart].pou);
    if ctx.profile == Profile::Matiec {
        return matiec::run(ctx, chart, code);
    }
    let plan = code.plan();
    let frame = ctx.charts[chart].frame;
    let now = ctx.now;
    let ctl = code.control;
    // Chart control: SFCInit resets and holds the initial situation.
    if read_bool(ctx.mem, frame + ctl.init as usize) {
        reset(ctx, chart, code);
        return Ok(());
    }
    if read_bool(ctx.mem, frame + ctl.quit_error as usize) {
        ctx.mem[frame + ctl.error as usize] = Value::Bool(false);
    }
    let st = &mut ctx.charts[chart];
    if !st.started {
        st.started = true;
        st.last_time = now;
        for &s in &plan.initial {
            st.activate(s);
        }
        for &e in &plan.variable_entities {
            let c = &mut st.controls[e as usize];
            if !c.live {
                c.live = true;
                st.live.push(e);
            }
        }
        if ctx.profile == Profile::Matiec {
            // No activation edge for the initial step: its edge memories start as if it had
            // been active before.
            for &s in &plan.initial {
                for &e in plan.step_entities.get(s) {
                    let c = &mut st.controls[e as usize];
                    for a in plan.entities[e as usize].assocs.iter().filter(|a| a.step == s) {
                        match a.qualifier {
                            Qualifier::P => c.p_mem = true,
                            Qualifier::P1 => c.p1_mem = true,
                            _ => {}
                        }
                    }
                }
            }
        }
        publish_initial(ctx, chart);
        action_phase(ctx, chart, code, plan)?;
        finish_scan(ctx, chart, code, plan);
        return Ok(());
    }
    let paused = read_bool(ctx.mem, frame + ctl.pause as usize);
    let st = &mut ctx.charts[chart];
    let delta = now - st.last_time;
    st.last_time = now;
    // Step times advance unless paused; the evolution does it in its pass over the active steps.
    match ctx.profile {
        Profile::Codesys => {
            if !paused && delta != 0 {
                for &s in &st.active {
                    let step = &mut st.steps[s as usize];
                    step.t += delta;
                    step.publish_t(ctx.mem);
                }
            }
            action_phase(ctx, chart, code, plan)?;
            if !paused {
                evolve(ctx, chart, code, plan, 0)?;
            }
        }
        Profile::Grafcet => {
            if !paused {
                evolve_until_stable(ctx, chart, code, plan, delta)?;
            }
            action_phase(ctx, chart, code, plan)?;
        }
        Profile::Iec | Profile::Matiec => {
            if !paused {
                evolve(ctx, chart, code, plan, delta)?;
            }
            action_phase(ctx, chart, code, plan)?;
        }
    }
    finish_scan(ctx, chart, code, plan);
    Ok(())
}

/// Writes a BOOL slot in place (no drop glue for the old value on the hot path).
#[inline]
fn put_bool(mem: &mut [Value], slot: usize, b: bool) {
    match &mut mem[slot] {
        Value::Bool(x) => *x = b,
        other => *other = Value::Bool(b),
    }
}

/// Writes a TIME slot in place.
#[inline]
fn put_time(mem: &mut [Value], slot: usize, t: i64) {
    match &mut mem[slot] {
        Value::Time(x) => *x = t,
        other => *other = Value::Time(t),
    }
}

#[inline]
fn read_bool(mem: &[Value], slot: usize) -> bool {
    matches!(mem.get(slot), Some(Value::Bool(true)))
}

/// SFCInit: back to the initial situation with every action control block cleared; the next
/// call after SFCInit falls is the instance's scan 0 again.
fn reset(ctx: &mut Ctx<'_>, chart: usize, code: &ChartCode) {
    let plan = code.plan();
    let frame = ctx.charts[chart].frame;
    let st = &mut ctx.charts[chart];
    if !st.started && !st.active.is_empty() {
        return; // already held in the initial situation
    }
    while let Some(&s) = st.active.last() {
        st.deactivate(s);
    }
    st.left.clear();
    st.entered.clear();
    for c in st.controls.iter_mut() {
        *c = Control::default();
    }
    st.live.clear();
    st.started = false;
    for step in st.steps.iter_mut() {
        step.t = 0;
        step.overdue = false;
    }
    for &s in &plan.initial {
        let step = &mut st.steps[s as usize];
        step.x = true;
        step.pos = st.active.len() as u32;
        st.active.push(s);
    }
    st.changed = true;
    for (s, &off) in code.step_x.iter().enumerate() {
        ctx.mem[frame + off as usize] = Value::Bool(plan.initial.contains(&(s as u32)));
        ctx.mem[frame + code.step_t[s] as usize] = Value::Time(0);
    }
    for (&q, &a) in code.action_q.iter().zip(&code.action_a) {
        ctx.mem[frame + q as usize] = Value::Bool(false);
        ctx.mem[frame + a as usize] = Value::Bool(false);
    }
    for &e in &plan.variable_entities {
        if let Some(p) = plan.entities[e as usize].variable {
            ctx.mem[p.slot(frame)] = Value::Bool(false);
        }
    }
    ctx.mem[frame + code.control.error as usize] = Value::Bool(false);
    ctx.mem[frame + code.control.error_step as usize] = Value::Str(Arc::from(""));
    // SFCCurrentStep follows the initial situation while SFCInit holds it.
    let st = &mut ctx.charts[chart];
    if st.track_current {
        st.changed = false;
        let first = st.active.iter().copied().min();
        st.current = first;
        ctx.mem[frame + code.control.current_step as usize] = match first {
            Some(s) => plan.step_values[s as usize].clone(),
            None => Value::Str(Arc::from("")),
        };
    }
}

/// Evaluates the guard of `t` on the current memory: plain BOOL reads inline, the rest through
/// the compiled closure.
#[inline(always)]
fn eval_guard(ctx: &mut Ctx<'_>, code: &ChartCode, guard: FastGuard, frame: usize, t: u32) -> Result<bool, Fault> {
    match guard {
        FastGuard::Local(o, neg) => Ok(read_bool(ctx.mem, frame + o as usize) != neg),
        FastGuard::Global(g, neg) => Ok(read_bool(ctx.mem, g as usize) != neg),
        FastGuard::Const(b) => Ok(b),
        FastGuard::Code => (code.guards[t as usize])(ctx, frame),
    }
}

/// Steps 3–5: enabled and true transitions against one snapshot, conflicts, firing.
/// Returns whether anything fired.
/// `delta`: first advance the time of every active step by this much (in the same pass).
fn evolve(ctx: &mut Ctx<'_>, chart: usize, code: &ChartCode, plan: &ChartPlan, delta: i64) -> Result<bool, Fault> {
    let frame = ctx.charts[chart].frame;
    let (mut cand, epoch) = {
        let st = &mut ctx.charts[chart];
        let mut cand = std::mem::take(&mut st.cand);
        cand.clear();
        let epoch = st.next_epoch();
        for &s in &st.active {
            if delta != 0 {
                let step = &mut st.steps[s as usize];
                step.t += delta;
                step.publish_t(ctx.mem);
            }
            let only = plan.single_out[s as usize];
            if only != u32::MAX {
                cand.push(only);
                continue;
            }
            for &t in plan.outgoing.get(s) {
                // A transition with one preceding step is met only from that (active) step.
                if plan.tr[t as usize].single_pre {
                    cand.push(t);
                    continue;
                }
                let mark = &mut st.stamp[t as usize];
                if *mark == epoch {
                    continue;
                }
                *mark = epoch;
                if plan.pre.get(t).iter().all(|&p| st.steps[p as usize].x) {
                    cand.push(t);
                }
            }
        }
        (cand, epoch)
    };
    // Guards against the snapshot. They have no side effects, so their order does not matter;
    // when one faults, the first faulting guard in declaration order is reported.
    // The same pass notes whether the true transitions are all links and whether two of them
    // can share a step, so the firing needs no further pass to decide its path.
    let mut e_len = 0;
    let mut links_only = true;
    let mut may_conflict = false;
    for k in 0..cand.len() {
        let t = cand[k];
        let info = plan.tr[t as usize];
        match eval_guard(ctx, code, info.guard, frame, t) {
            Ok(true) => {
                cand[e_len] = t;
                e_len += 1;
                links_only &= info.is_link();
                may_conflict |= info.may_conflict;
            }
            Ok(false) => {}
            Err(f) => {
                let mut all = cand[k..].to_vec();
                all.sort_unstable();
                let (t, first) = all
                    .into_iter()
                    .find_map(|t| eval_guard(ctx, code, plan.tr[t as usize].guard, frame, t).err().map(|f| (t, f)))
                    .unwrap_or((t, f));
                ctx.sink.note_fault(chart, FaultSite::Guard(t));
                ctx.charts[chart].cand = cand;
                return Err(first);
            }
        }
    }
    cand.truncate(e_len);
    let st = &mut ctx.charts[chart];
    if cand.is_empty() {
        st.cand = cand;
        return Ok(false);
    }
    if cand.len() == 1 {
        let t = cand[0];
        // The common case, a transition between two steps of a sequence (or a self-loop) whose
        // target is not active: fire it without the general bookkeeping.
        let TrInfo { from, to, .. } = plan.tr[t as usize];
        if from != u32::MAX {
            if from == to || !st.steps[to as usize].x {
                st.cand = cand;
                st.left.clear();
                st.steps[to as usize].amark = epoch;
                take_link(st, ctx.mem, ctx.sink, chart, ctx.now, t, from, to, epoch);
                return Ok(true);
            }
        }
    }
    // Two true transitions sharing a step are a conflict; without one, all of them fire. Only
    // transitions leaving a divergence can share a step.
    let mut shared = false;
    if cand.len() > 1 && may_conflict {
        for &t in &cand {
            for &p in plan.pre.get(t) {
                let step = &mut st.steps[p as usize];
                shared |= step.seen == epoch;
                step.seen = epoch;
            }
        }
    }
    let accepted = if shared {
        cand.sort_unstable();
        let mut accepted = std::mem::take(&mut st.accepted);
        accepted.clear();
        resolve_conflicts(st, plan, &cand, &mut accepted, ctx.profile, &mut ctx.sink.events);
        st.cand = cand;
        accepted
    } else {
        cand
    };
    // Accepted transitions share no preceding step (always, except MatIEC's firing of every
    // true alternative); when they are all links, the link path fires them.
    if links_only && (!shared || ctx.profile != Profile::Matiec) {
        fire_links(ctx, chart, plan, &accepted, epoch);
    } else {
        fire_general(ctx, chart, plan, &accepted, epoch);
    }
    let st = &mut ctx.charts[chart];
    if shared {
        st.accepted = accepted;
    } else {
        st.cand = accepted;
    }
    Ok(true)
}

/// Step 5: fires the accepted transitions together. `D = ∪ pre` is marked with `dmark`,
/// `A = ∪ post` with `amark`; a step of `A` that is active and not in `D`, or that two
/// transitions activate, is unsafe. Steps of `D` not in `A` are deactivated, then every step of
/// `A` is activated once (a step left and re-entered stays active, its time restarts).
/// Also handles accepted transitions that share a preceding step (MatIEC accepts every true
/// alternative).
fn fire_general(ctx: &mut Ctx<'_>, chart: usize, plan: &ChartPlan, accepted: &[u32], epoch: u32) {
    let st = &mut ctx.charts[chart];
    for &t in accepted {
        for &s in plan.pre.get(t) {
            st.steps[s as usize].dmark = epoch;
        }
    }
    let mut unsafe_steps: Vec<u32> = Vec::new();
    for &t in accepted {
        for &s in plan.post.get(t) {
            let step = &mut st.steps[s as usize];
            if (step.amark == epoch || (step.x && step.dmark != epoch)) && !unsafe_steps.contains(&s) {
                unsafe_steps.push(s);
            }
            step.amark = epoch;
        }
    }
    if !unsafe_steps.is_empty() {
        unsafe_steps.sort_unstable();
        let mut in_order = accepted.to_vec();
        in_order.sort_unstable();
        for &s in &unsafe_steps {
            let trs = in_order
                .iter()
                .filter(|&&t| plan.post.get(t).contains(&s))
                .map(|&t| st.qualify(&plan.transition_names[t as usize]))
                .collect();
            ctx.sink.events.push(Event::Unsafe { step: st.qualify(&plan.step_names[s as usize]), transitions: trs });
        }
    }
    st.left.clear();
    for &t in accepted {
        for &s in plan.pre.get(t) {
            let step = &mut st.steps[s as usize];
            // Each step of D once (MatIEC may accept transitions sharing a step).
            if step.dmark != epoch {
                continue;
            }
            step.dmark = 0;
            if !step.x {
                continue;
            }
            if step.amark == epoch {
                st.complete(s);
            } else {
                st.deactivate(s);
                st.steps[s as usize].publish_x(ctx.mem, false);
            }
            st.left.push(s);
        }
    }
    let now = ctx.now;
    for &t in accepted {
        for &s in plan.post.get(t) {
            let step = &mut st.steps[s as usize];
            if step.amark == epoch {
                step.amark = 0;
                st.activate(s);
                let step = &st.steps[s as usize];
                step.publish_x(ctx.mem, true);
                step.publish_t(ctx.mem);
            }
        }
        if st.log.len() < LOG_LIMIT {
            st.log.push((now, t));
        }
        ctx.sink.fired.push((chart as u32, t));
    }
}

/// [`fire_general`] for disjoint transitions that each link one step to one step (sequences, loops, the
/// branches of a selection): the same rule without walking the pre/post lists.
#[inline(never)]
fn fire_links(ctx: &mut Ctx<'_>, chart: usize, plan: &ChartPlan, accepted: &[u32], epoch: u32) {
    let st = &mut ctx.charts[chart];
    // A = the entered steps (marked); two transitions entering one step are unsafe.
    let mut safe = true;
    let mut entering_active = false;
    for &t in accepted {
        let step = &mut st.steps[plan.tr[t as usize].to as usize];
        safe &= step.amark != epoch;
        entering_active |= step.x;
        step.amark = epoch;
    }
    // Entering an active step is unsafe unless that step is also left (D) in this scan; D is
    // only needed then.
    if safe && entering_active {
        for &t in accepted {
            st.steps[plan.tr[t as usize].from as usize].dmark = epoch;
        }
        for &t in accepted {
            let step = &st.steps[plan.tr[t as usize].to as usize];
            safe &= !step.x || step.dmark == epoch;
        }
    }
    if !safe {
        // Rare: clear the activation marks and take the general path, which names the unsafe
        // steps.
        for &t in accepted {
            st.steps[plan.tr[t as usize].to as usize].amark = 0;
        }
        return fire_general(ctx, chart, plan, accepted, epoch);
    }
    // One pass: each transition leaves its step and enters the next, which takes the left
    // step's place in `active`. A step of both D and A (left by one transition, entered by
    // another, or a self-loop) carries both marks: it is not deactivated, and its entry restarts
    // its time. The marks stay until the next epoch, so the order of the transitions does not
    // matter.
    st.left.clear();
    let now = ctx.now;
    for &t in accepted {
        let TrInfo { from, to, .. } = plan.tr[t as usize];
        take_link(st, ctx.mem, ctx.sink, chart, now, t, from, to, epoch);
    }
}

/// Fires the one-step-to-one-step transition `t`: leaves `from` (unless it carries the
/// activation mark of `epoch`: it is entered again in the same scan) and enters `to`, which
/// takes `from`'s place in the active list; the `X`/`T` slots, the time analysis, the action
/// queue and the firing log follow. The caller has checked that the firing is safe and marked
/// `to` with `epoch`. (`fire_links` stays out of line: inlined into `evolve`, it slows the
/// candidate loop down by a fifth.)
#[inline(always)]
#[allow(clippy::too_many_arguments)]
fn take_link(
    st: &mut ChartState,
    mem: &mut [Value],
    sink: &mut ScanSink,
    chart: usize,
    now: i64,
    t: u32,
    from: u32,
    to: u32,
    epoch: u32,
) {
    let step = &mut st.steps[from as usize];
    let mut free = None;
    if step.amark != epoch {
        step.x = false;
        free = Some(step.pos);
        step.publish_x(mem, false);
    }
    step.complete();
    st.changed = true;
    if st.track_left {
        st.left.push(from);
    }
    let step = &mut st.steps[to as usize];
    if !step.x {
        step.x = true;
        match free.take() {
            Some(pos) => {
                step.pos = pos;
                st.active[pos as usize] = to;
            }
            None => {
                step.pos = st.active.len() as u32;
                st.active.push(to);
            }
        }
    }
    step.t = 0;
    step.overdue = false;
    step.publish_x(mem, true);
    step.publish_t(mem);
    step.tally.activations += 1;
    if step.has_entities {
        st.entered.push(to);
    }
    if let Some(pos) = free {
        st.active.swap_remove(pos as usize);
        if let Some(&moved) = st.active.get(pos as usize) {
            st.steps[moved as usize].pos = pos;
        }
    }
    if st.log.len() < LOG_LIMIT {
        st.log.push((now, t));
    }
    sink.fired.push((chart as u32, t));
}

/// Step 4 for two or more true transitions: `conflict` events, then acceptance in priority
/// order, each step consumed once (MatIEC: a true transition without priority always fires;
/// CODESYS: no priorities, declaration order).
fn resolve_conflicts(
    st: &mut ChartState,
    plan: &ChartPlan,
    cand: &[u32],
    accepted: &mut Vec<u32>,
    profile: Profile,
    events: &mut Vec<Event>,
) {
    let codesys = profile == Profile::Codesys;
    let explicit = |t: u32| !codesys && plan.explicit[t as usize];
    for &t in cand {
        if !explicit(t) {
            for &s in plan.pre.get(t) {
                let step = &mut st.steps[s as usize];
                step.hits = step.hits.saturating_add(1);
            }
        }
    }
    let mut steps: Vec<u32> = Vec::new();
    for &t in cand {
        for &s in plan.pre.get(t) {
            if st.steps[s as usize].hits >= 2 && !steps.contains(&s) {
                steps.push(s);
            }
        }
    }
    for &t in cand {
        for &s in plan.pre.get(t) {
            st.steps[s as usize].hits = 0;
        }
    }
    steps.sort_unstable();
    for s in steps {
        let trs = cand
            .iter()
            .filter(|&&t| !explicit(t) && plan.pre.get(t).contains(&s))
            .map(|&t| st.qualify(&plan.transition_names[t as usize]))
            .collect();
        events.push(Event::Conflict { step: st.qualify(&plan.step_names[s as usize]), transitions: trs });
    }
    let mut order = cand.to_vec();
    if !codesys {
        order.sort_unstable_by_key(|&t| plan.order_key[t as usize]);
    }
    for &t in &order {
        let pre = plan.pre.get(t);
        let free = pre.iter().all(|&s| !st.steps[s as usize].consumed);
        if free || (profile == Profile::Matiec && !explicit(t)) {
            for &s in pre {
                st.steps[s as usize].consumed = true;
            }
            accepted.push(t);
        }
    }
    for &t in accepted.iter() {
        for &s in plan.pre.get(t) {
            st.steps[s as usize].consumed = false;
        }
    }
    accepted.sort_unstable();
}

/// GRAFCET (IEC 60848): evolve on frozen inputs until nothing fires; a situation met twice
/// is an endless cycle and stops the run.
fn evolve_until_stable(
    ctx: &mut Ctx<'_>,
    chart: usize,
    code: &ChartCode,
    plan: &ChartPlan,
    mut delta: i64,
) -> Result<(), Fault> {
    let mut seen: Vec<Vec<u32>> = Vec::new();
    loop {
        let mut now_active = ctx.charts[chart].active.clone();
        now_active.sort_unstable();
        if seen.contains(&now_active) {
            return Err(Fault {
                message: "the situation never becomes stable (GRAFCET evolution cycles on frozen inputs)".into(),
                span: code.chart.name_span,
            });
        }
        seen.push(now_active);
        let fired = evolve(ctx, chart, code, plan, delta)?;
        delta = 0;
        if !fired {
            return Ok(());
        }
    }
}

/// Every `(name, b'x' | b't')` such that the (lowercase) source text contains `name.x` /
/// `name.t` (spaces allowed around the dot) with `name` a whole identifier: the step flags
/// that some code may read. Comments and strings count too, which only keeps more slots
/// up to date than needed.
fn step_flags_read(lower: &str) -> std::collections::HashSet<(String, u8)> {
    let b = lower.as_bytes();
    let ident = |c: u8| c.is_ascii_alphanumeric() || c == b'_';
    let mut out = std::collections::HashSet::new();
    for (i, _) in lower.match_indices('.') {
        let mut k = i + 1;
        while k < b.len() && b[k] == b' ' {
            k += 1;
        }
        let flag = match b.get(k) {
            Some(&c @ (b'x' | b't')) if !b.get(k + 1).is_some_and(|&n| ident(n)) => c,
            _ => continue,
        };
        let mut end = i;
        while end > 0 && b[end - 1] == b' ' {
            end -= 1;
        }
        let mut start = end;
        while start > 0 && ident(b[start - 1]) {
            start -= 1;
        }
        if start < end {
            out.insert((lower[start..end].to_string(), flag));
        }
    }
    out
}

/// Writes the `X` and `T` slots of the initial steps (evolutions write them as they fire).
fn publish_initial(ctx: &mut Ctx<'_>, chart: usize) {
    let st = &ctx.charts[chart];
    for &s in &st.active {
        let step = &st.steps[s as usize];
        put_bool(ctx.mem, step.x_slot as usize, true);
        put_time(ctx.mem, step.t_slot as usize, step.t);
    }
}

/// Steps 6–7: action control for every live entity, then the bodies with `A` TRUE.
#[inline(always)]
fn action_phase(ctx: &mut Ctx<'_>, chart: usize, code: &ChartCode, plan: &ChartPlan) -> Result<(), Fault> {
    let st = &ctx.charts[chart];
    if st.entered.is_empty() && st.live.is_empty() {
        return Ok(()); // no action holds state and none was activated
    }
    run_actions(ctx, chart, code, plan)
}

fn run_actions(ctx: &mut Ctx<'_>, chart: usize, code: &ChartCode, plan: &ChartPlan) -> Result<(), Fault> {
    let now = ctx.now;
    let profile = ctx.profile;
    let frame = ctx.charts[chart].frame;
    let st = &mut ctx.charts[chart];
    // Entities of newly active steps become live; they stay live while one of their steps is
    // active or they hold state.
    for &s in &st.entered {
        for &e in plan.step_entities.get(s) {
            let c = &mut st.controls[e as usize];
            if !c.live {
                c.live = true;
                st.live.push(e);
            }
        }
    }
    st.entered.clear();
    if st.live.is_empty() {
        return Ok(());
    }
    let mut run = std::mem::take(&mut st.run);
    run.clear();
    let mut k = 0;
    while k < st.live.len() {
        let e = st.live[k] as usize;
        let ent = &plan.entities[e];
        let mut inputs = Inputs::default();
        let or = profile != Profile::Matiec;
        let mut winner: Option<(u32, Qualifier, i64)> = None;
        let mut contenders: Vec<(u32, Qualifier)> = Vec::new();
        let mut any_active = false;
        for a in &ent.assocs {
            let active = st.steps[a.step as usize].x;
            any_active |= active;
            if a.qualifier.is_timed() {
                if !active {
                    if !or {
                        inputs.set(a.qualifier, false, false);
                    }
                    continue;
                }
                let dur = match a.duration {
                    Some(DurationCode::Literal(d)) => d,
                    Some(DurationCode::Variable(p)) => match &ctx.mem[p.slot(frame)] {
                        Value::Time(d) => *d,
                        _ => 0,
                    },
                    None => 0,
                };
                match winner {
                    None => {
                        winner = Some((a.step, a.qualifier, dur));
                        inputs.set(a.qualifier, true, or);
                    }
                    Some((_, q, d)) if q == a.qualifier && d == dur => inputs.set(a.qualifier, true, true),
                    Some(_) => contenders.push((a.step, a.qualifier)),
                }
            } else {
                inputs.set(a.qualifier, active, or);
            }
        }
        if let Some((ws, wq, d)) = winner {
            let k = match wq {
                Qualifier::L => 0,
                Qualifier::D => 1,
                Qualifier::SD => 2,
                Qualifier::DS => 3,
                _ => 4,
            };
            st.controls[e].t[k] = d;
            if !contenders.is_empty() {
                let mut steps = vec![st.qualify(&plan.step_names[ws as usize])];
                let mut quals = vec![wq.name().to_string()];
                for (s, q) in &contenders {
                    steps.push(st.qualify(&plan.step_names[*s as usize]));
                    quals.push(q.name().to_string());
                }
                ctx.sink.events.push(Event::Contention { action: st.qualify(&ent.name), steps, qualifiers: quals });
            }
        }
        let c = &mut st.controls[e];
        let (q, a) = c.update(inputs, now, profile);
        match (ent.action, ent.variable) {
            (Some(id), _) => {
                put_bool(ctx.mem, frame + code.action_q[id] as usize, q);
                put_bool(ctx.mem, frame + code.action_a[id] as usize, a);
                if a {
                    run.push(e as u32);
                }
            }
            (None, Some(p)) => put_bool(ctx.mem, p.slot(frame), q),
            (None, None) => {}
        }
        if c.idle() && ent.variable.is_none() && !any_active {
            c.live = false;
            st.live.swap_remove(k);
        } else {
            k += 1;
        }
    }
    // Bodies: declaration order of the actions (entity index = action index), or CODESYS
    // order: alphabetical, those of steps left in the previous scan first.
    if profile == Profile::Codesys && run.len() > 1 {
        let left = &st.left;
        run.sort_by_cached_key(|&e| {
            let ent = &plan.entities[e as usize];
            (!ent.assocs.iter().any(|a| left.contains(&a.step)), ent.name.to_ascii_uppercase())
        });
    } else if run.len() > 1 {
        run.sort_unstable();
    }
    if profile == Profile::Codesys {
        st.left.clear();
    }
    for &e in &run {
        if let Some(id) = plan.entities[e as usize].action {
            if let Err(f) = (code.bodies[id])(ctx, frame) {
                ctx.sink.note_fault(chart, FaultSite::Action(id));
                ctx.charts[chart].run = run;
                return Err(f);
            }
        }
    }
    ctx.charts[chart].run = run;
    Ok(())
}

/// After the scan: supervision times, SFCError/SFCErrorStep, SFCCurrentStep.
#[inline(always)]
fn finish_scan(ctx: &mut Ctx<'_>, chart: usize, code: &ChartCode, plan: &ChartPlan) {
    let st = &ctx.charts[chart];
    if plan.supervised || (st.changed && st.track_current) {
        supervise(ctx, chart, code, plan);
    }
}

fn supervise(ctx: &mut Ctx<'_>, chart: usize, code: &ChartCode, plan: &ChartPlan) {
    let frame = ctx.charts[chart].frame;
    let st = &mut ctx.charts[chart];
    if plan.supervised {
        let mut expired: Option<u32> = None;
        for &s in &st.active {
            if let Some(limit) = plan.timeouts[s as usize] {
                let step = &mut st.steps[s as usize];
                if step.t > limit && !step.overdue {
                    step.overdue = true;
                    if expired.is_none_or(|f| s < f) {
                        expired = Some(s);
                    }
                }
            }
        }
        if let Some(s) = expired {
            ctx.mem[frame + code.control.error as usize] = Value::Bool(true);
            ctx.mem[frame + code.control.error_step as usize] = plan.step_values[s as usize].clone();
        }
    }
    if st.changed && st.track_current {
        st.changed = false;
        let first = st.active.iter().copied().min();
        if first != st.current {
            st.current = first;
            ctx.mem[frame + code.control.current_step as usize] = match first {
                Some(s) => plan.step_values[s as usize].clone(),
                None => Value::Str(Arc::from("")),
            };
        }
    }
}

/// Activation count and active time of one step (time analysis).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct StepStats {
    /// Qualified step name.
    pub step: String,
    pub activations: u64,
    /// Over completed and current activations, µs; `None` when never active.
    pub min: Option<i64>,
    pub max: Option<i64>,
    pub mean: Option<i64>,
}

/// Time analysis of a run so far.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct TimeStats {
    /// Every step of every instance, in declaration order (top chart first).
    pub steps: Vec<StepStats>,
    /// The sequence of situations passed: `(time µs, active steps)` each time the active set
    /// changed, starting with the initial situation.
    pub sequence: Vec<(i64, Vec<String>)>,
}

/// A simulation of one top-level POU of a checked file.
/// The run-time state of a [`Simulation`], taken by [`Simulation::snapshot`].
#[derive(Debug, Clone)]
pub struct Snapshot {
    mem: Vec<Value>,
    charts: Vec<ChartState>,
    record: ScanRecord,
    error: Option<RuntimeError>,
    next_scan: u64,
}

pub struct Simulation {
    prog: Program,
    mem: Vec<Value>,
    top_frame: usize,
    charts: Vec<ChartState>,
    opts: SimOptions,
    source: SourceFile,
    top: usize,
    record: ScanRecord,
    sink: ScanSink,
    error: Option<RuntimeError>,
    next_scan: u64,
    /// The traced variables with their slots, resolved once.
    trace: Vec<(String, Type, usize)>,
    /// Charges one scan may make ([`Simulation::set_scan_budget`]).
    budget: u64,
    /// Set from outside to stop the running scan ([`Simulation::interrupt_flag`]).
    interrupt: Option<Arc<std::sync::atomic::AtomicBool>>,
}

/// Where in the chart a runtime error happened ([`Simulation::fault_place`]); names carry the
/// instance path of nested charts.
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub struct FaultPlace {
    /// The action whose body was running.
    pub action: Option<String>,
    /// The transition whose condition was being evaluated.
    pub transition: Option<String>,
    /// The active steps associated with that action, or the steps that transition leaves.
    pub steps: Vec<String>,
}

/// The chart states of the SFC instances of a fresh memory (each instance's hidden slot set
/// to its index).
fn chart_states(prog: &Program, instances: Vec<crate::code::ChartInstance>, mem: &mut [Value]) -> Vec<ChartState> {
    let mut charts = Vec::with_capacity(instances.len());
    for (i, inst) in instances.into_iter().enumerate() {
        let PouBody::Chart(code) = &prog.pous[inst.pou].body else {
            continue;
        };
        let plan = code.plan_arc().clone();
        mem[inst.frame + code.chart_slot as usize] = Value::Int(i as i64);
        charts.push(ChartState::new(inst.pou, plan, inst.frame, inst.path));
    }
    charts
}

impl Simulation {
    /// Checks `text` and compiles it for simulation of `pou` (by name, or the only SFC POU,
    /// or the only PROGRAM). Errors are the check diagnostics (or SFC0321 when `pou` does not
    /// name a simulatable POU), with the source to render them.
    pub fn from_source(
        name: &str,
        text: &str,
        pou: Option<&str>,
        opts: SimOptions,
    ) -> Result<Simulation, (SourceFile, Vec<Diagnostic>)> {
        let check_opts = sfc_model::CheckOptions { keep_types: true, ..Default::default() };
        let mut checked = sfc_model::check_source(0, name, text, &check_opts);
        // An error in another POU does not keep this one from running: only the errors of the
        // POU, of what it uses, and of the file's types and globals count.
        let top = match choose_pou(&checked.unit, &checked.charts, pou) {
            Ok(n) => n,
            Err(d) if checked.has_errors() => {
                let mut diags: Vec<Diagnostic> = checked.diagnostics.into_iter().filter(|d| d.is_error()).collect();
                diags.push(d);
                return Err((checked.file, diags));
            }
            Err(d) => return Err((checked.file, vec![d])),
        };
        if checked.has_errors() {
            let errors = sfc_model::errors_for(&checked, &top);
            if !errors.is_empty() {
                return Err((checked.file, errors));
            }
            sfc_model::set_aside_unrelated(&mut checked, &top);
        }
        let source = checked.file;
        let prog = match Program::compile_with(&checked.unit, checked.charts, &checked.expr_types, opts.profile) {
            Ok(p) => p,
            Err(d) => return Err((source, d)),
        };
        let Some(top) = prog.pou(&top) else {
            let d = Diagnostic::error("SFC0321", Span::default(), format!("no POU named `{top}` to simulate"));
            return Err((source, vec![d]));
        };
        Ok(Simulation::new(prog, top, source, opts))
    }

    /// A simulation of the compiled POU `top`.
    pub fn new(prog: Program, top: usize, source: SourceFile, opts: SimOptions) -> Simulation {
        let Memory { mem, top_frame, charts: instances } = prog.instantiate(top);
        let mut mem = mem;
        let mut charts = chart_states(&prog, instances, &mut mem);
        let trace = prog.pous[top]
            .layout
            .vars
            .iter()
            .filter(|v| !v.implicit && v.size == 1 && v.ty.is_elementary())
            .filter_map(|v| prog.resolve(top, top_frame, &v.name).map(|(slot, _)| (v.name.clone(), v.ty.clone(), slot)))
            .collect();
        if opts.profile == Profile::Matiec {
            matiec::prepare(&prog, &mut charts, &source.text);
        }
        let lower = source.text.to_ascii_lowercase();
        let mentioned = lower.contains("sfccurrentstep");
        let flags = step_flags_read(&lower);
        for c in &mut charts {
            c.track_current = mentioned;
            c.track_left = opts.profile == Profile::Codesys;
            for (step, name) in c.steps.iter_mut().zip(&c.plan.step_names) {
                let name = name.to_ascii_lowercase();
                step.mirror_x = flags.contains(&(name.clone(), b'x'));
                step.mirror_t = flags.contains(&(name, b't'));
            }
        }
        Simulation {
            prog,
            mem,
            top_frame,
            charts,
            opts,
            source,
            top,
            record: ScanRecord::default(),
            sink: ScanSink::default(),
            error: None,
            next_scan: 0,
            trace,
            budget: crate::code::SCAN_BUDGET,
            interrupt: None,
        }
    }

    /// Starts the POU again from its declared initial values (a PLC's restart): memory, steps
    /// and action control as at scan 0, the error cleared. The scan counter goes on, so the
    /// first scan after a restart is the chart's scan 0 at a later virtual time.
    pub fn restart(&mut self) {
        let Memory { mut mem, charts: instances, .. } = self.prog.instantiate(self.top);
        let mut charts = chart_states(&self.prog, instances, &mut mem);
        for (new, old) in charts.iter_mut().zip(&self.charts) {
            new.track_current = old.track_current;
            new.track_left = old.track_left;
            for (a, b) in new.steps.iter_mut().zip(&old.steps) {
                a.mirror_x = b.mirror_x;
                a.mirror_t = b.mirror_t;
            }
        }
        self.mem = mem;
        self.charts = charts;
        self.error = None;
        self.record = ScanRecord::default();
        self.sink.fired.clear();
        self.sink.events.clear();
        self.sink.fault_site = None;
    }

    /// Bounds every later scan to `limit` charges (loop iterations, IL jumps, calls; default
    /// [`crate::code::SCAN_BUDGET`]); a scan that spends it stops with a located runtime error.
    pub fn set_scan_budget(&mut self, limit: u64) {
        self.budget = limit.max(1);
    }

    /// A flag that, once set (from any thread), stops the running scan at its next look at its
    /// budget (within a few thousand loop iterations) with a runtime error whose message is
    /// [`crate::code::INTERRUPTED`], and every later scan at once until it is cleared.
    pub fn interrupt_flag(&mut self) -> Arc<std::sync::atomic::AtomicBool> {
        self.interrupt.get_or_insert_with(Default::default).clone()
    }

    /// Where the last runtime error happened in the chart: the action or transition whose code
    /// was running, and the active steps that run that action (or that the transition leaves).
    pub fn fault_place(&self) -> Option<FaultPlace> {
        let (c, site) = self.sink.fault_site?;
        let st = self.charts.get(c as usize)?;
        let plan = &st.plan;
        let code = code_of(&self.prog, st.pou);
        let active = |s: &u32| st.steps[*s as usize].x;
        let step_name = |s: u32| st.qualify(&plan.step_names[s as usize]);
        Some(match site {
            FaultSite::Action(a) => {
                let name = &code.chart.actions[a].name;
                let mut steps: Vec<u32> = plan
                    .entities
                    .iter()
                    .filter(|e| e.action == Some(a))
                    .flat_map(|e| e.assocs.iter().map(|x| x.step))
                    .filter(active)
                    .collect();
                steps.sort_unstable();
                steps.dedup();
                FaultPlace {
                    action: Some(st.qualify(name)),
                    transition: None,
                    steps: steps.into_iter().map(step_name).collect(),
                }
            }
            FaultSite::Guard(t) => FaultPlace {
                action: None,
                transition: Some(st.qualify(&plan.transition_names[t as usize])),
                steps: plan.pre.get(t).iter().copied().map(step_name).collect(),
            },
        })
    }

    /// The checked source (to render runtime errors and diagnostics).
    pub fn source(&self) -> &SourceFile {
        &self.source
    }
    /// The declared name of the simulated POU.
    pub fn pou_name(&self) -> &str {
        &self.prog.pous[self.top].name
    }
    pub fn options(&self) -> SimOptions {
        self.opts
    }
    /// The number of the scan that [`Simulation::scan`] runs next (0 before the first).
    pub fn next_scan(&self) -> u64 {
        self.next_scan
    }
    /// The virtual time of the next scan, µs.
    pub fn next_time(&self) -> i64 {
        self.next_scan as i64 * self.opts.period
    }

    /// Runs the next scan without building its record (the fast path for benchmarks and the
    /// runtime). Returns the error that stopped the run, if any.
    pub fn advance(&mut self) -> Result<(), &RuntimeError> {
        self.advance_at(self.next_time())
    }

    /// Runs the next scan at virtual time `now` (µs, not before the previous scan's) instead of
    /// `scan · period`: for comparing with targets whose clock ticks differently (an S7-200
    /// 100 ms timer sees time in whole ticks of its time base).
    pub fn advance_at(&mut self, now: i64) -> Result<(), &RuntimeError> {
        if self.error.is_some() {
            return Err(self.error.as_ref().unwrap());
        }
        self.sink.fired.clear();
        self.sink.events.clear();
        self.sink.fault_site = None;
        let scan = self.next_scan;
        let result = {
            let mut ctx = Ctx {
                mem: &mut self.mem,
                prog: &self.prog,
                charts: &mut self.charts,
                sink: &mut self.sink,
                now,
                scan,
                profile: self.opts.profile,
                budget: crate::code::Budget::new(self.budget, self.interrupt.as_deref()),
            };
            match &self.prog.pous[self.top].body {
                PouBody::Chart(_) => run_chart(&mut ctx, 0),
                PouBody::Code(block) => block(&mut ctx, self.top_frame),
            }
        };
        self.next_scan += 1;
        if let Err(fault) = result {
            let lc = self.source.line_col(fault.span.start);
            let e = RuntimeError {
                message: fault.message,
                span: fault.span,
                line: lc.line,
                column: lc.column,
                scan,
                time: now,
            };
            self.sink.events.push(Event::Error(e.clone()));
            self.error = Some(e);
            return Err(self.error.as_ref().unwrap());
        }
        Ok(())
    }

    /// Runs the next scan. When it faults, the record holds the `error` event and
    /// [`Simulation::error`] is set; once stopped, `scan` runs nothing and returns that record.
    pub fn scan(&mut self) -> &ScanRecord {
        self.scan_at(self.next_time())
    }

    /// [`Simulation::scan`] at virtual time `time` (see [`Simulation::advance_at`]).
    pub fn scan_at(&mut self, time: i64) -> &ScanRecord {
        if self.error.is_some() {
            return &self.record;
        }
        let scan = self.next_scan;
        let _ = self.advance_at(time);
        let mut events = std::mem::take(&mut self.sink.events);
        events.sort_by_key(Event::rank);
        // Within one chart's evolution, `fired` is in declaration order.
        let mut k = 0;
        while k < self.sink.fired.len() {
            let c = self.sink.fired[k].0;
            let end = self.sink.fired[k..].iter().position(|f| f.0 != c).map_or(self.sink.fired.len(), |n| k + n);
            self.sink.fired[k..end].sort_unstable();
            k = end;
        }
        let fired = self
            .sink
            .fired
            .iter()
            .map(|&(c, t)| {
                let st = &self.charts[c as usize];
                st.qualify(&st.plan.transition_names[t as usize])
            })
            .collect();
        self.record = ScanRecord { scan, time, active: self.active(), fired, events };
        &self.record
    }

    /// The whole run-time state (variables, steps, action control, time, last record), so a
    /// search (the analyzer's witness replay) can try a scan and come back.
    pub fn snapshot(&self) -> Snapshot {
        Snapshot {
            mem: self.mem.clone(),
            charts: self.charts.clone(),
            record: self.record.clone(),
            error: self.error.clone(),
            next_scan: self.next_scan,
        }
    }

    /// A canonical text of the run-time state — variables, active steps, step times,
    /// supervision flags, action control blocks, chart bookkeeping — without history (time
    /// analysis, firing log, scratch marks): two runs in the same state after the same scan have
    /// equal keys. Used to explore state spaces with the simulator (the prover's independent
    /// cross-check in the test suite).
    pub fn state_key(&self) -> String {
        use std::fmt::Write;
        let mut s = String::new();
        let _ = write!(s, "{:?}|{:?}|", self.mem, self.error.as_ref().map(|e| (&e.message, e.scan)));
        for c in &self.charts {
            let mut active = c.active.clone();
            active.sort_unstable();
            let _ = write!(s, "{}:{}:{active:?}:", c.started, c.last_time);
            for st in &c.steps {
                let _ = write!(s, "{},{},{};", st.x, st.t, st.overdue);
            }
            for ct in &c.controls {
                let _ = write!(s, "{ct:?};");
            }
            s.push('|');
        }
        s
    }

    /// Returns to a state taken with [`Simulation::snapshot`] of this simulation.
    pub fn restore(&mut self, snap: &Snapshot) {
        self.mem.clone_from(&snap.mem);
        self.charts.clone_from(&snap.charts);
        self.record = snap.record.clone();
        self.error = snap.error.clone();
        self.next_scan = snap.next_scan;
        self.sink.fired.clear();
        self.sink.events.clear();
    }

    /// The record of the last scan run.
    pub fn record(&self) -> &ScanRecord {
        &self.record
    }
    /// The runtime error that stopped the run.
    pub fn error(&self) -> Option<&RuntimeError> {
        self.error.as_ref()
    }

    /// Writes a variable (`Start`, `Rev.Start`, `Cells[2]`, global names), as an input change:
    /// the value must have the variable's type (an `Int` is accepted for REAL/LREAL, and is
    /// range-checked for the integer types). Step and action flags cannot be written.
    pub fn set(&mut self, name: &str, value: Value) -> Result<(), String> {
        if self.is_chart_flag(name) {
            return Err(format!("`{name}` is a step or action flag: the chart sets it"));
        }
        let Some((slot, ty)) = self.prog.resolve(self.top, self.top_frame, name) else {
            return Err(format!("no variable `{name}` in `{}`", self.pou_name()));
        };
        let v = fit(value, &ty).map_err(|why| format!("`{name}` is {}: {why}", type_name(&ty)))?;
        self.mem[slot] = self.inward(v);
        Ok(())
    }

    fn is_chart_flag(&self, name: &str) -> bool {
        let Some((base, member)) = name.rsplit_once('.') else {
            return false;
        };
        if !["X", "T", "Q", "A"].iter().any(|m| m.eq_ignore_ascii_case(member)) {
            return false;
        }
        let (path, leaf) = match base.rsplit_once('.') {
            Some((p, l)) => (p, l),
            None => ("", base),
        };
        self.charts.iter().any(|c| {
            c.path.eq_ignore_ascii_case(path)
                && (c.plan.step_names.iter().any(|s| s.eq_ignore_ascii_case(leaf))
                    || c.plan.action_names.iter().any(|a| a.eq_ignore_ascii_case(leaf)))
        })
    }

    /// Reads a variable, `Step.X`, `Step.T`, `Action.Q`, `Action.A`, also inside nested
    /// instances (`Rev.Busy`, `Rev.OpenKM1.X`). Case-insensitive.
    pub fn get(&self, name: &str) -> Option<Value> {
        let (slot, _) = self.prog.resolve(self.top, self.top_frame, name)?;
        if let Some(v) = self.current_step_of(name).or_else(|| self.unmirrored_step_value(slot)) {
            return Some(v);
        }
        self.mem.get(slot).map(|v| self.outward(v))
    }

    /// A value of memory as users see it: TIME in µs (under `matiec` memory holds MatIEC's
    /// packed timespecs, `crate::timespec`).
    fn outward(&self, v: &Value) -> Value {
        match v {
            Value::Time(t) if self.prog.matiec_time => Value::Time(crate::timespec::Timespec::unpack(*t).to_us()),
            _ => v.clone(),
        }
    }
    /// The inverse of [`Simulation::outward`].
    fn inward(&self, v: Value) -> Value {
        match v {
            Value::Time(us) if self.prog.matiec_time => Value::Time(crate::timespec::Timespec::from_us(us).pack()),
            _ => v,
        }
    }

    /// `[Path.]SFCCurrentStep` computed from the chart state (see `ChartState::track_current`).
    /// The `X` or `T` of a step whose slot is not mirrored in memory, from the step state.
    fn unmirrored_step_value(&self, slot: usize) -> Option<Value> {
        self.charts.iter().flat_map(|c| &c.steps).find_map(|s| {
            if !s.mirror_x && s.x_slot as usize == slot {
                Some(Value::Bool(s.x))
            } else if !s.mirror_t && s.t_slot as usize == slot {
                Some(Value::Time(s.t))
            } else {
                None
            }
        })
    }

    fn current_step_of(&self, name: &str) -> Option<Value> {
        let (path, leaf) = match name.rsplit_once('.') {
            Some((p, l)) => (p, l),
            None => ("", name),
        };
        if !leaf.eq_ignore_ascii_case("SFCCurrentStep") {
            return None;
        }
        let st = self.charts.iter().find(|c| c.path.eq_ignore_ascii_case(path))?;
        let first = st.active.iter().copied().min();
        Some(Value::Str(Arc::from(first.map(|s| st.plan.step_names[s as usize].as_str()).unwrap_or(""))))
    }
    /// The type of what [`Simulation::get`] reads.
    pub fn type_of(&self, name: &str) -> Option<Type> {
        self.prog.resolve(self.top, self.top_frame, name).map(|(_, t)| t)
    }

    /// Active steps now, sorted by code points (nested instances as `Path.Step`).
    pub fn active(&self) -> Vec<String> {
        let mut out: Vec<String> = Vec::new();
        for st in &self.charts {
            for &s in &st.active {
                out.push(st.qualify(&st.plan.step_names[s as usize]));
            }
        }
        out.sort();
        out
    }

    /// The variables a trace shows: every declared variable of elementary type of the top
    /// POU, in declaration order, with its declared name and type.
    pub fn trace_vars(&self) -> Vec<(String, Type)> {
        self.trace.iter().map(|(name, ty, _)| (name.clone(), ty.clone())).collect()
    }
    /// Current values of [`Simulation::trace_vars`], same order.
    pub fn trace_values(&self) -> Vec<Value> {
        self.trace.iter().map(|&(_, _, slot)| self.outward(&self.mem[slot])).collect()
    }
    /// Every step (qualified), in declaration order, top chart first.
    pub fn step_names(&self) -> Vec<String> {
        self.charts.iter().flat_map(|c| c.plan.step_names.iter().map(|s| c.qualify(s))).collect()
    }
    /// Every transition (qualified), in declaration order, top chart first.
    pub fn transition_names(&self) -> Vec<String> {
        self.charts.iter().flat_map(|c| c.plan.transition_names.iter().map(|s| c.qualify(s))).collect()
    }

    /// Condition analysis of every active step now: why each outgoing transition does not fire.
    pub fn explain(&self) -> Vec<StepReport> {
        let mut out = Vec::new();
        for (i, st) in self.charts.iter().enumerate() {
            let mut act = st.active.clone();
            act.sort_unstable();
            for s in act {
                out.push(crate::explain::report(self.explain_view(), i, s));
            }
        }
        out
    }
    /// Condition analysis of the active steps whose `sfc.timeout` has expired.
    pub fn overdue(&self) -> Vec<StepReport> {
        self.overdue_at().into_iter().map(|(c, s)| crate::explain::report(self.explain_view(), c, s)).collect()
    }

    /// The active steps whose `sfc.timeout` has expired (qualified, sorted by chart and step):
    /// cheap enough to ask every scan, unlike their reports.
    pub fn overdue_steps(&self) -> Vec<String> {
        self.overdue_at()
            .into_iter()
            .map(|(c, s)| self.charts[c].qualify(&self.charts[c].plan.step_names[s as usize]))
            .collect()
    }

    /// Condition analysis of one active step, by qualified name (`Rev.OpenKM1`).
    pub fn explain_step(&self, step: &str) -> Option<StepReport> {
        self.charts.iter().enumerate().find_map(|(c, st)| {
            let s = st
                .active
                .iter()
                .copied()
                .find(|&s| st.qualify(&st.plan.step_names[s as usize]).eq_ignore_ascii_case(step))?;
            Some(crate::explain::report(self.explain_view(), c, s))
        })
    }

    fn overdue_at(&self) -> Vec<(usize, u32)> {
        let mut out = Vec::new();
        for (c, st) in self.charts.iter().enumerate() {
            if !st.plan.supervised {
                continue;
            }
            let mut act: Vec<u32> = st
                .active
                .iter()
                .copied()
                .filter(|&s| st.plan.timeouts[s as usize].is_some_and(|limit| st.time(s) > limit))
                .collect();
            act.sort_unstable();
            out.extend(act.into_iter().map(|s| (c, s)));
        }
        out
    }

    fn explain_view(&self) -> crate::explain::View<'_> {
        crate::explain::View {
            prog: &self.prog,
            mem: &self.mem,
            charts: &self.charts,
            source: &self.source,
            top: self.top,
            top_frame: self.top_frame,
            now: self.next_time() - self.opts.period,
            profile: self.opts.profile,
        }
    }

    /// Time analysis of the run so far.
    pub fn stats(&self) -> TimeStats {
        let mut steps = Vec::new();
        for st in &self.charts {
            for (s, name) in st.plan.step_names.iter().enumerate() {
                let tl = st.steps[s].tally;
                let mut count = tl.completed;
                let (mut min, mut max, mut sum) = (tl.min, tl.max, tl.sum);
                if st.steps[s].x {
                    let d = st.steps[s].t;
                    if count == 0 {
                        min = d;
                        max = d;
                    } else {
                        min = min.min(d);
                        max = max.max(d);
                    }
                    sum = sum.saturating_add(d);
                    count += 1;
                }
                let some = count > 0;
                steps.push(StepStats {
                    step: st.qualify(name),
                    activations: tl.activations,
                    min: some.then_some(min),
                    max: some.then_some(max),
                    mean: some.then(|| sum / count as i64),
                });
            }
        }
        TimeStats { steps, sequence: self.sequence() }
    }

    /// Rebuilds the sequence of situations from the firing logs of all instances.
    fn sequence(&self) -> Vec<(i64, Vec<String>)> {
        let mut x: Vec<Vec<bool>> = self
            .charts
            .iter()
            .map(|c| {
                let mut v = vec![false; c.plan.step_names.len()];
                if c.started || !c.log.is_empty() || c.steps.iter().any(|s| s.tally.activations > 0) {
                    for &s in &c.plan.initial {
                        v[s as usize] = true;
                    }
                }
                v
            })
            .collect();
        let names = |x: &Vec<Vec<bool>>| {
            let mut out = Vec::new();
            for (c, flags) in self.charts.iter().zip(x) {
                for (s, &on) in flags.iter().enumerate() {
                    if on {
                        out.push(c.qualify(&c.plan.step_names[s]));
                    }
                }
            }
            out.sort();
            out
        };
        let mut events: Vec<(i64, usize, usize, u32)> = Vec::new();
        for (c, st) in self.charts.iter().enumerate() {
            for (k, &(time, t)) in st.log.iter().enumerate() {
                events.push((time, c, k, t));
            }
        }
        events.sort_by_key(|&(time, c, k, _)| (time, c, k));
        let mut out = vec![(0, names(&x))];
        let mut i = 0;
        while i < events.len() {
            let time = events[i].0;
            // All firings of one scan form one step of the sequence.
            let mut j = i;
            while j < events.len() && events[j].0 == time {
                j += 1;
            }
            for &(_, c, _, t) in &events[i..j] {
                let plan = &self.charts[c].plan;
                for &s in plan.pre.get(t) {
                    x[c][s as usize] = false;
                }
            }
            for &(_, c, _, t) in &events[i..j] {
                let plan = &self.charts[c].plan;
                for &s in plan.post.get(t) {
                    x[c][s as usize] = true;
                }
            }
            let now = names(&x);
            if out.last().map(|l| &l.1) != Some(&now) {
                out.push((time, now));
            }
            i = j;
        }
        out
    }
}

/// Picks the POU to simulate: the named one, else the only SFC POU, else the only PROGRAM.
fn choose_pou(
    unit: &sfc_syntax::ast::SourceUnit,
    charts: &[sfc_model::Chart],
    pou: Option<&str>,
) -> Result<String, Diagnostic> {
    use sfc_syntax::ast::{Item, PouKind};
    let pous: Vec<&sfc_syntax::ast::Pou> =
        unit.items.iter().filter_map(|i| if let Item::Pou(p) = i { Some(p) } else { None }).collect();
    if let Some(name) = pou {
        return match pous.iter().find(|p| p.name.is(name)) {
            Some(p) if p.kind == PouKind::Function => Err(Diagnostic::error(
                "SFC0321",
                p.name.span,
                format!("`{}` is a FUNCTION: simulate a PROGRAM or FUNCTION_BLOCK", p.name.text),
            )),
            Some(p) => Ok(p.name.text.clone()),
            None => {
                let names: Vec<&str> = pous.iter().map(|p| p.name.text.as_str()).collect();
                Err(Diagnostic::error("SFC0321", Span::default(), format!("no POU named `{name}` in this file"))
                    .with_note(format!("the file declares: {}", names.join(", "))))
            }
        };
    }
    let programs: Vec<&&sfc_syntax::ast::Pou> = pous.iter().filter(|p| p.kind == PouKind::Program).collect();
    if programs.len() == 1 {
        return Ok(programs[0].name.text.clone());
    }
    if charts.len() == 1 {
        return Ok(charts[0].pou.clone());
    }
    let names: Vec<&str> = pous.iter().filter(|p| p.kind != PouKind::Function).map(|p| p.name.text.as_str()).collect();
    if names.is_empty() {
        return Err(Diagnostic::error(
            "SFC0321",
            Span::default(),
            "the file has no SFC POU to simulate (and no PROGRAM)",
        )
        .with_note("a chart is a PROGRAM or FUNCTION_BLOCK whose body is steps and transitions"));
    }
    Err(Diagnostic::error("SFC0321", Span::default(), "choose the POU to simulate (`pou` / `--pou`)")
        .with_note(format!("candidates: {}", names.join(", "))))
}

fn type_name(ty: &Type) -> String {
    ty.to_string()
}

/// Converts a written value to the slot value of `ty`, or says why it does not fit.
pub(crate) fn fit(value: Value, ty: &Type) -> Result<Value, String> {
    let base = ty.base();
    match (&value, base) {
        (Value::Bool(_), Type::Bool) => Ok(value),
        (Value::Int(i), _) if ty.is_integer() || ty.is_bit() || matches!(ty, Type::Subrange { .. }) => {
            match ty.int_range() {
                Some((lo, hi)) if (i128::from(*i) < lo || i128::from(*i) > hi) => {
                    Err(format!("{i} is out of range {lo}..{hi}"))
                }
                _ => Ok(value),
            }
        }
        (Value::Int(i), _) if ty.is_real() => Ok(real_of(*i as f64, ty)),
        (Value::Real(r), _) if ty.is_real() => Ok(real_of(*r, ty)),
        (Value::Time(_), _) if ty.is_duration() => Ok(value),
        (Value::Str(_), _) if ty.is_string() => Ok(value),
        (Value::Int(_), Type::Enum { .. }) => Ok(value),
        _ => Err(format!("cannot take {}", describe(&value))),
    }
}

fn real_of(r: f64, ty: &Type) -> Value {
    if matches!(ty.base(), Type::Real) {
        Value::Real(r as f32 as f64)
    } else {
        Value::Real(r)
    }
}

fn describe(v: &Value) -> String {
    match v {
        Value::Bool(b) => format!("the BOOL {}", if *b { "TRUE" } else { "FALSE" }),
        Value::Int(i) => format!("the integer {i}"),
        Value::Real(r) => format!("the real {r}"),
        Value::Time(t) => format!("the TIME {}", crate::format_time(*t)),
        Value::Str(s) => format!("the string '{s}'"),
    }
}
