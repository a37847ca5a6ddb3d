//! The `matiec` profile: one scan of a chart as the C code that MatIEC's `iec2c` generates for
//! it (stage 4, `generate_c_sfc.cc`), transcribed phase by phase, bugs included. Beremiz and
//! OpenPLC v3 run SFC through that code.
//!
//! The body MatIEC emits for a chart, per call:
//! 1. `elapsed = now − lasttick`; for each step `prev_state = X`, and `T += elapsed` if `X`.
//! 2. For each action: `state = set = reset = 0`; the SD/DS/SL countdowns (`set_remaining_time`,
//!    `reset_remaining_time`) run down by `elapsed` and raise `set` / `reset` when they reach 0.
//! 3. Transitions are tested in MatIEC's list order ([`test_order`]): a transition whose steps
//!    are all active takes the value of its condition; with an explicit PRIORITY a TRUE one clears
//!    its preceding steps at once, so later tests see them inactive. No first-scan guard.
//! 4. Preceding steps of the fired unprioritised transitions are cleared (declaration order).
//! 5. Following steps of every fired transition are set, their `T` restarted.
//! 6. Associations, step by step in declaration order, each writing on its own (`active`,
//!    `activated = active && !prev_state`, `desactivated = !active && prev_state`): N writes 1
//!    while active and 0 on deactivation; L/D compare the step's own `T`; P/P1 write 1 when
//!    activated, else 0; P0 1 when deactivated, else 0; S/R raise `set`/`reset`; SD/DS load
//!    `set_remaining_time` on activation (DS clears it on deactivation); SL raises `set` and
//!    loads `reset_remaining_time` on activation. An action's writes go to its `state`; a BOOL
//!    variable's go to the variable itself.
//! 7. For each action: `set` stores, `reset` unstores (reset last), `state |= stored`.
//! 8. BOOL variables: `reset` writes FALSE, else `set` writes TRUE; then the bodies of the actions
//!    whose `state` is TRUE run, in declaration order.
//!
//! Times are MatIEC's [`Timespec`]s (literal durations truncated as the C computes them); the
//! `X`, `T`, `Q`, `A` slots are published for the compiled code (`Q = A = state`).

use super::evolve::{code_of, finish_scan, publish_initial, put_bool, read_bool, reset};
use super::plan::ChartPlan;
use super::state::ChartState;
use crate::code::{ChartCode, Ctx, DurationCode, FastGuard, Fault, Place, Program};
use crate::timespec::Timespec;
use crate::value::Value;
use crate::Event;
use sfc_model::{ActionTarget, Qualifier};
use std::sync::Arc;

/// A duration of a timed association, as the generated C holds it.
#[derive(Debug, Clone, Copy)]
pub(crate) enum Dur {
    Literal(Timespec),
    Variable(Place),
}

/// `__action_list[i]`: one per action, then one per BOOL variable used as an action.
#[derive(Debug, Clone, Copy, Default)]
struct ActionState {
    state: bool,
    set: bool,
    reset: bool,
    stored: bool,
    set_remaining: Timespec,
    reset_remaining: Timespec,
}

/// What MatIEC keeps of one chart instance, beside the step flags.
#[derive(Debug, Clone)]
pub(crate) struct State {
    /// Per step, per association: the duration (timed qualifiers only).
    durations: Arc<Vec<Vec<Option<Dur>>>>,
    /// Transitions in the order the generated code tests them.
    order: Arc<Vec<u32>>,
    x: Vec<bool>,
    prev: Vec<bool>,
    t: Vec<Timespec>,
    tr: Vec<bool>,
    actions: Vec<ActionState>,
    lasttick: Timespec,
    /// Held by SFCInit: the next call starts the chart again.
    restarted: bool,
}

/// The order of `transition_list`: each transition is appended, except that one with a PRIORITY
/// `p` is inserted before the first element (from the front) whose priority exceeds `p`,
/// unprioritised ones counting as priority 0.
pub(crate) fn test_order(chart: &sfc_model::Chart) -> Vec<u32> {
    let mut list: Vec<(i64, u32)> = Vec::new();
    for (i, t) in chart.transitions.iter().enumerate() {
        match t.priority {
            Some(p) => {
                let at = list.iter().position(|&(q, _)| q > p).unwrap_or(list.len());
                list.insert(at, (p, i as u32));
            }
            None => list.push((0, i as u32)),
        }
    }
    list.into_iter().map(|(_, t)| t).collect()
}

/// The duration of each association: literals from their text in `source` (truncated as
/// `__time_to_timespec` computes them), variables by place.
pub(crate) fn durations(code: &ChartCode, source: Option<&str>) -> Vec<Vec<Option<Dur>>> {
    let chart = &code.chart;
    chart
        .steps
        .iter()
        .enumerate()
        .map(|(s, step)| {
            step.associations
                .iter()
                .enumerate()
                .map(|(k, a)| {
                    if !a.qualifier.is_timed() {
                        return None;
                    }
                    match code.associations.get(s).and_then(|v| v.get(k)).and_then(|c| c.duration) {
                        Some(DurationCode::Variable(p)) => Some(Dur::Variable(p)),
                        Some(DurationCode::Literal(us)) => {
                            let text = source.and_then(|src| src.get(a.span.start as usize..a.span.end as usize));
                            let exact = text.and_then(duration_text).and_then(|t| Timespec::from_literal(&t));
                            Some(Dur::Literal(exact.unwrap_or_else(|| Timespec::from_us(us))))
                        }
                        None => Some(Dur::Literal(Timespec::ZERO)),
                    }
                })
                .collect()
        })
        .collect()
}

/// The duration literal of an association's text (`Act(L, T#30ms, Ind)` → `T#30ms`).
fn duration_text(assoc: &str) -> Option<String> {
    let inner = assoc.split_once('(')?.1;
    let after = inner.split_once(',')?.1;
    let lit = after.split([',', ')']).next()?.trim();
    lit.contains('#').then(|| lit.to_string())
}

impl State {
    /// The state (Q) of each action, in the order of the chart's entities.
    pub(crate) fn action_flags(&self) -> impl Iterator<Item = bool> + '_ {
        self.actions.iter().map(|a| a.state)
    }

    pub(crate) fn new(code: &ChartCode, durations: Arc<Vec<Vec<Option<Dur>>>>, order: Arc<Vec<u32>>) -> State {
        let chart = &code.chart;
        let n = chart.steps.len();
        State {
            durations,
            order,
            x: chart.steps.iter().map(|s| s.initial).collect(),
            prev: vec![false; n],
            t: vec![Timespec::ZERO; n],
            tr: vec![false; chart.transitions.len()],
            actions: vec![ActionState::default(); code.plan().entities.len()],
            lasttick: Timespec::ZERO,
            restarted: false,
        }
    }
}

/// The `Value` of a TIME slot under this profile.
#[inline]
pub(crate) fn time_value(t: Timespec) -> Value {
    Value::Time(t.pack())
}

fn read_time(mem: &[Value], slot: usize) -> Timespec {
    match mem.get(slot) {
        Some(Value::Time(v)) => Timespec::unpack(*v),
        _ => Timespec::ZERO,
    }
}

/// One call of the chart instance `chart` under the `matiec` profile.
pub(crate) fn run(ctx: &mut Ctx<'_>, chart: usize, code: &ChartCode) -> Result<(), Fault> {
    let plan = code.plan();
    let frame = ctx.charts[chart].frame;
    let ctl = code.control;
    if read_bool(ctx.mem, frame + ctl.init as usize) {
        reset(ctx, chart, code);
        let st = &mut ctx.charts[chart];
        if let Some(m) = st.matiec.as_mut() {
            let (durations, order) = (m.durations.clone(), m.order.clone());
            **m = State::new(code, durations, order);
            m.restarted = true;
        }
        st.entered.clear();
        return Ok(());
    }
    if read_bool(ctx.mem, frame + ctl.quit_error as usize) {
        ctx.mem[frame + ctl.error as usize] = Value::Bool(false);
    }
    let now = Timespec::from_us(ctx.now);
    let mut m = match ctx.charts[chart].matiec.take() {
        Some(m) => m,
        None => Box::new(State::new(code, Arc::new(durations(code, None)), Arc::new(test_order(&code.chart)))),
    };
    // `__lasttick_time` is set when the program is initialised (time 0); after SFCInit, when
    // the chart starts again.
    if m.restarted {
        m.restarted = false;
        m.lasttick = now;
    }
    if !ctx.charts[chart].started {
        let st = &mut ctx.charts[chart];
        st.started = true;
        st.last_time = ctx.now;
        for &s in &plan.initial {
            if !st.steps[s as usize].x {
                st.activate(s);
            }
        }
        st.entered.clear();
        ctx.sink.starts.push((ctx.sink.fired.len() as u32, chart as u32));
        ctx.sink.moved |= !plan.initial.is_empty();
        publish_initial(ctx, chart);
    }
    let result = scan(ctx, chart, code, plan, &mut m, now);
    sync(ctx, chart, plan, &m);
    ctx.charts[chart].matiec = Some(m);
    result?;
    finish_scan(ctx, chart, code, plan);
    Ok(())
}

fn put_x(ctx: &mut Ctx<'_>, code: &ChartCode, frame: usize, s: usize, v: bool) {
    put_bool(ctx.mem, frame + code.step_x[s] as usize, v);
}

fn scan(
    ctx: &mut Ctx<'_>,
    chart: usize,
    code: &ChartCode,
    plan: &ChartPlan,
    m: &mut State,
    now: Timespec,
) -> Result<(), Fault> {
    let frame = ctx.charts[chart].frame;
    let paused = read_bool(ctx.mem, frame + code.control.pause as usize);
    // 1. Elapsed time, previous states, step times.
    let elapsed = now.sub(m.lasttick);
    m.lasttick = now;
    {
        // The engine's chart clock (step times of the time analysis) follows the same calls.
        let st = &mut ctx.charts[chart];
        if !paused {
            st.clock += ctx.now - st.last_time;
        }
        st.last_time = ctx.now;
    }
    for s in 0..m.x.len() {
        m.prev[s] = m.x[s];
        if m.x[s] && !paused {
            m.t[s] = m.t[s].add(elapsed);
            ctx.mem[frame + code.step_t[s] as usize] = time_value(m.t[s]);
        }
    }
    // 2. Actions initialisation: the SD/DS/SL countdowns.
    for a in m.actions.iter_mut() {
        a.state = false;
        a.set = false;
        a.reset = false;
        if a.set_remaining > Timespec::ZERO {
            a.set_remaining = a.set_remaining.sub(elapsed);
            if a.set_remaining <= Timespec::ZERO {
                a.set_remaining = Timespec::ZERO;
                a.set = true;
            }
        }
        if a.reset_remaining > Timespec::ZERO {
            a.reset_remaining = a.reset_remaining.sub(elapsed);
            if a.reset_remaining <= Timespec::ZERO {
                a.reset_remaining = Timespec::ZERO;
                a.reset = true;
            }
        }
    }
    // 3. Transition tests in list order; a TRUE prioritised transition clears its steps at once.
    let order = m.order.clone();
    for &t in order.iter() {
        let tu = t as usize;
        let pre = plan.pre.get(t);
        if !paused && pre.iter().all(|&s| m.x[s as usize]) {
            let v = match plan.tr[tu].guard {
                FastGuard::Local(o, neg) => read_bool(ctx.mem, frame + o as usize) != neg,
                FastGuard::Global(g, neg) => read_bool(ctx.mem, g as usize) != neg,
                FastGuard::Const(b) => b,
                FastGuard::Code => (code.guards[tu])(ctx, frame)?,
            };
            m.tr[tu] = v;
            if v && plan.explicit[tu] {
                for &s in pre {
                    m.x[s as usize] = false;
                    put_x(ctx, code, frame, s as usize, false);
                }
            }
        } else {
            m.tr[tu] = false;
        }
    }
    // Events: two fired unprioritised transitions sharing a step (both fire), and a step
    // receiving a token it already holds.
    let st = &ctx.charts[chart];
    let ntr = m.tr.len();
    for s in 0..m.x.len() as u32 {
        let takers: Vec<u32> =
            plan.outgoing.get(s).iter().copied().filter(|&t| m.tr[t as usize] && !plan.explicit[t as usize]).collect();
        if takers.len() >= 2 {
            let mut trs = takers;
            trs.sort_unstable();
            ctx.sink.events.push(Event::Conflict {
                step: st.qualify(&plan.step_names[s as usize]),
                transitions: trs.iter().map(|&t| st.qualify(&plan.transition_names[t as usize])).collect(),
            });
        }
    }
    // 4. Reset steps of the fired unprioritised transitions.
    for t in 0..ntr {
        if m.tr[t] && !plan.explicit[t] {
            for &s in plan.pre.get(t as u32) {
                m.x[s as usize] = false;
                put_x(ctx, code, frame, s as usize, false);
            }
        }
    }
    // 5. Set steps.
    let mut hits = vec![0u8; m.x.len()];
    let mut unsafe_by: Vec<(u32, Vec<u32>)> = Vec::new();
    for t in 0..ntr {
        if !m.tr[t] {
            continue;
        }
        for &s in plan.post.get(t as u32) {
            let su = s as usize;
            let was = m.x[su];
            hits[su] = hits[su].saturating_add(1);
            if was || hits[su] > 1 {
                match unsafe_by.iter_mut().find(|(x, _)| *x == s) {
                    Some((_, v)) => v.push(t as u32),
                    None => unsafe_by.push((s, vec![t as u32])),
                }
            }
            m.x[su] = true;
            m.t[su] = Timespec::ZERO;
            put_x(ctx, code, frame, su, true);
            ctx.mem[frame + code.step_t[su] as usize] = time_value(Timespec::ZERO);
        }
    }
    if !unsafe_by.is_empty() {
        let st = &ctx.charts[chart];
        unsafe_by.sort_unstable_by_key(|(s, _)| *s);
        for (s, mut trs) in unsafe_by {
            // Name every fired transition entering the step.
            trs.extend((0..ntr as u32).filter(|&t| m.tr[t as usize] && plan.post.get(t).contains(&s)));
            trs.sort_unstable();
            trs.dedup();
            ctx.sink.events.push(Event::Unsafe {
                step: st.qualify(&plan.step_names[s as usize]),
                transitions: trs.iter().map(|&t| st.qualify(&plan.transition_names[t as usize])).collect(),
            });
        }
    }
    // Fired transitions, in declaration order.
    {
        let st = &mut ctx.charts[chart];
        for t in 0..ntr as u32 {
            if m.tr[t as usize] {
                st.fired_count[t as usize] += 1;
                ctx.sink.fired.push((chart as u32, t));
            }
        }
    }
    // 6. Associations, step by step.
    for (s, step) in code.chart.steps.iter().enumerate() {
        if step.associations.is_empty() {
            continue;
        }
        let active = m.x[s];
        let activated = active && !m.prev[s];
        let desactivated = !active && m.prev[s];
        for (k, a) in step.associations.iter().enumerate() {
            let Some(e) = entity_of(code, plan, s, k) else { continue };
            let variable = plan.entities[e].variable;
            let dur = || match m.durations[s][k] {
                Some(Dur::Literal(t)) => t,
                Some(Dur::Variable(p)) => read_time(ctx.mem, p.slot(frame)),
                None => Timespec::ZERO,
            };
            // An action's writes go to `state`, a variable's to the variable.
            let mut write: Option<bool> = None;
            match a.qualifier {
                Qualifier::N => {
                    if active {
                        write = Some(true);
                    }
                    if desactivated {
                        write = Some(false);
                    }
                }
                Qualifier::S => {
                    if active {
                        m.actions[e].set = true;
                    }
                }
                Qualifier::R => {
                    if active {
                        m.actions[e].reset = true;
                    }
                }
                Qualifier::L => {
                    let d = dur();
                    if active && m.t[s] < d {
                        write = Some(true);
                    } else if desactivated || active {
                        write = Some(false);
                    }
                }
                Qualifier::D => {
                    let d = dur();
                    if active && m.t[s] >= d {
                        write = Some(true);
                    } else if desactivated {
                        write = Some(false);
                    }
                }
                Qualifier::P | Qualifier::P1 => write = Some(activated),
                Qualifier::P0 => write = Some(desactivated),
                Qualifier::SL => {
                    if activated {
                        m.actions[e].set = true;
                        m.actions[e].reset_remaining = dur();
                    }
                }
                Qualifier::SD | Qualifier::DS => {
                    if activated {
                        m.actions[e].set_remaining = dur();
                    }
                    if a.qualifier == Qualifier::DS && desactivated {
                        m.actions[e].set_remaining = Timespec::ZERO;
                    }
                }
            }
            if let Some(v) = write {
                match variable {
                    Some(p) => ctx.mem[p.slot(frame)] = Value::Bool(v),
                    None => m.actions[e].state = v,
                }
            }
        }
    }
    // 7. Actions state evaluation.
    for a in m.actions.iter_mut() {
        if a.set {
            a.set_remaining = Timespec::ZERO;
            a.stored = true;
        }
        if a.reset {
            a.reset_remaining = Timespec::ZERO;
            a.stored = false;
        }
        a.state |= a.stored;
    }
    // (CODESYS's step actions, which MatIEC does not know, run before its actions as in every
    // profile: docs/sim.md, "Step actions".)
    if plan.step_actions {
        super::action::step_actions(ctx, chart, code)?;
    }
    // 8. Actions execution: variables, then the bodies.
    for &e in &plan.variable_entities {
        let a = m.actions[e as usize];
        if let Some(p) = plan.entities[e as usize].variable {
            if a.reset {
                ctx.mem[p.slot(frame)] = Value::Bool(false);
            } else if a.set {
                ctx.mem[p.slot(frame)] = Value::Bool(true);
            }
        }
    }
    for (e, ent) in plan.entities.iter().enumerate() {
        if let Some(id) = ent.action {
            let on = m.actions[e].state;
            put_bool(ctx.mem, frame + code.action_q[id] as usize, on);
            put_bool(ctx.mem, frame + code.action_a[id] as usize, on);
        }
    }
    for (e, ent) in plan.entities.iter().enumerate() {
        if let Some(id) = ent.action {
            if m.actions[e].state {
                (code.bodies[id])(ctx, frame)?;
            }
        }
    }
    Ok(())
}

/// The entity (`__action_list` index) that association `k` of step `s` drives.
fn entity_of(code: &ChartCode, plan: &ChartPlan, s: usize, k: usize) -> Option<usize> {
    match code.chart.steps[s].associations[k].target {
        ActionTarget::Action(id) => Some(id),
        ActionTarget::Variable => {
            let place = code.associations.get(s)?.get(k)?.variable?;
            plan.entities.iter().position(|e| e.variable == Some(place))
        }
    }
}

/// Brings the engine's step states (active list, times, statistics) in line with MatIEC's flags.
fn sync(ctx: &mut Ctx<'_>, chart: usize, plan: &ChartPlan, m: &State) {
    let fired: Vec<u32> = (0..m.tr.len() as u32).filter(|&t| m.tr[t as usize]).collect();
    let st = &mut ctx.charts[chart];
    let mut entered = vec![false; m.x.len()];
    for &t in &fired {
        for &s in plan.post.get(t) {
            entered[s as usize] = true;
        }
    }
    let mut moved = false;
    for s in 0..m.x.len() {
        let was = st.steps[s].x;
        let now = m.x[s];
        if was && !now {
            moved |= st.deactivate(s as u32);
        } else if now && entered[s] {
            if was {
                st.complete(s as u32);
            }
            moved |= st.activate(s as u32);
        }
        // An active step's record holds the clock at its activation (see `StepState::t`).
        if st.steps[s].x {
            st.set_since(s as u32, st.clock - m.t[s].to_us());
        }
    }
    st.entered.clear();
    ctx.sink.moved |= moved;
}

/// Gives every chart instance its MatIEC state, with association durations read from their
/// text in `source` (the truncation depends on how a literal is written: `T#30ms` and
/// `T#0.03s` differ).
pub(crate) fn prepare(prog: &Program, charts: &mut [ChartState], source: &str) {
    let mut per_pou: Vec<Option<(Arc<Vec<Vec<Option<Dur>>>>, Arc<Vec<u32>>)>> = vec![None; prog.pous.len()];
    for st in charts.iter_mut() {
        let code = code_of(prog, st.pou);
        let (durs, order) = per_pou[st.pou]
            .get_or_insert_with(|| (Arc::new(durations(code, Some(source))), Arc::new(test_order(&code.chart))))
            .clone();
        st.matiec = Some(Box::new(State::new(code, durs, order)));
    }
}
