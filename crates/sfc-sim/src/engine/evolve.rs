//! One scan of one SFC instance: chart control variables, time, steps 3–5 of `semantics.md`
//! (enabled and true transitions against one snapshot, conflicts, firing), the action phase,
//! supervision.
//!
//! The evolution has a fast path for the commonest shape of a chart: a step whose only outgoing
//! transition leads from it alone to one step (a sequence, a loop, the steps inside the branches
//! of a divergence). One pass over the active steps reads each such step's 16-byte link record,
//! evaluates its guard (inline when it reads one BOOL) and marks the target; when no target is
//! active or entered twice and no other transition is a candidate, a second pass fires the true
//! links in place: the entered step takes the left step's position in the active list, so
//! nothing is searched, sorted or moved. Everything else (divergences, convergences, conflicts,
//! unsafe firings, faults) takes the general path, which the fast path hands its candidates to.
//!
//! Step times cost nothing per scan: a step records the chart clock at its activation, and its
//! elapsed time is `clock − t` (see [`super::state::StepState`]).

use super::action::action_phase;
use super::plan::{guard_kind, ChartPlan, Link};
use super::state::ChartState;
use super::state::StepState;
use super::FaultSite;
use crate::code::{ChartCode, Ctx, FastGuard, Fault, PouBody, Program};
use crate::value::Value;
use crate::{Event, Profile};
use sfc_model::Qualifier;
use std::sync::Arc;

pub(crate) fn code_of(prog: &Program, pou: usize) -> &ChartCode {
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
    match ctx.profile {
        Profile::Matiec => return super::matiec::run(ctx, chart, code),
        Profile::Codesys => return super::codesys::run(ctx, chart, code),
        Profile::Logix => return super::logix::run(ctx, chart, code),
        Profile::Graph => return super::graph::run(ctx, chart, code),
        Profile::Iec | Profile::Grafcet => {}
    }
    let plan = code.plan();
    let frame = ctx.charts[chart].frame;
    let now = ctx.now;
    let ctl = code.control;
    if held_or_reset(ctx, chart, code) {
        return Ok(());
    }
    acknowledge(ctx, chart, code);
    if !ctx.charts[chart].started {
        start(ctx, chart, plan);
        publish_initial(ctx, chart);
        action_phase(ctx, chart, code, plan)?;
        set_trans(ctx, chart, code, false);
        finish_scan(ctx, chart, code, plan);
        return Ok(());
    }
    let paused = read_bool(ctx.mem, frame + ctl.pause as usize);
    let st = &mut ctx.charts[chart];
    let delta = now - st.last_time;
    st.last_time = now;
    // Step times advance unless paused: the clock moves, and only the mirrored `T` slots are
    // written.
    if !paused && delta != 0 {
        st.clock += delta;
        if st.any_mirror_t {
            for &s in &st.active {
                st.publish_t(ctx.mem, s);
            }
        }
    }
    let fired_before = ctx.sink.fired.len();
    if !paused {
        if ctx.profile == Profile::Grafcet {
            evolve_until_stable(ctx, chart, code, plan)?;
        } else {
            evolve(ctx, chart, code, plan)?;
        }
    }
    if code.control.trans.is_some() {
        let fired = ctx.sink.fired[fired_before..].iter().any(|f| f.0 == chart as u32);
        set_trans(ctx, chart, code, fired);
    }
    action_phase(ctx, chart, code, plan)?;
    finish_scan(ctx, chart, code, plan);
    Ok(())
}

/// `SFCQuitError` TRUE at the start of a call acknowledges `SFCError` (clears it).
pub(super) fn acknowledge(ctx: &mut Ctx<'_>, chart: usize, code: &ChartCode) {
    let frame = ctx.charts[chart].frame;
    let ctl = code.control;
    if read_bool(ctx.mem, frame + ctl.quit_error as usize) {
        ctx.mem[frame + ctl.error as usize] = Value::Bool(false);
    }
}

/// Chart control at the start of a call: SFCInit puts the chart back into its initial situation
/// and holds it there (returns TRUE: the call ends); SFCReset (CODESYS; declared, or an
/// action's chart) puts it back and the call goes on processing it.
pub(super) fn held_or_reset(ctx: &mut Ctx<'_>, chart: usize, code: &ChartCode) -> bool {
    let frame = ctx.charts[chart].frame;
    let ctl = code.control;
    if read_bool(ctx.mem, frame + ctl.init as usize) {
        reset(ctx, chart, code);
        set_trans(ctx, chart, code, false);
        return true;
    }
    if ctl.reset.is_some_and(|r| read_bool(ctx.mem, frame + r as usize)) {
        reset(ctx, chart, code);
    }
    false
}

/// The first call of an instance (or the first after SFCInit/SFCReset): its initial steps
/// become active, the BOOL variables used as actions live.
pub(super) fn start(ctx: &mut Ctx<'_>, chart: usize, plan: &ChartPlan) {
    let now = ctx.now;
    let st = &mut ctx.charts[chart];
    st.started = true;
    st.last_time = now;
    for &s in &plan.initial {
        st.activate(s);
    }
    ctx.sink.starts.push((ctx.sink.fired.len() as u32, chart as u32));
    ctx.sink.moved |= !plan.initial.is_empty();
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
}

/// `SFCTrans` (when declared): whether a transition of this instance fired in this call.
#[inline]
pub(super) fn set_trans(ctx: &mut Ctx<'_>, chart: usize, code: &ChartCode, fired: bool) {
    if let Some(t) = code.control.trans {
        put_bool(ctx.mem, ctx.charts[chart].frame + t as usize, fired);
    }
}

/// Writes a BOOL slot in place (no drop glue for the old value on the hot path).
#[inline]
pub(crate) fn put_bool(mem: &mut [Value], slot: usize, b: bool) {
    match &mut mem[slot] {
        Value::Bool(x) => *x = b,
        other => *other = Value::Bool(b),
    }
}

/// Writes a TIME slot in place.
#[inline]
pub(crate) fn put_time(mem: &mut [Value], slot: usize, t: i64) {
    match &mut mem[slot] {
        Value::Time(x) => *x = t,
        other => *other = Value::Time(t),
    }
}

#[inline(always)]
pub(crate) fn read_bool(mem: &[Value], slot: usize) -> bool {
    matches!(mem.get(slot), Some(Value::Bool(true)))
}

/// SFCInit: back to the initial situation with every action control block cleared; the next
/// call after SFCInit falls is the instance's scan 0 again.
pub(crate) fn reset(ctx: &mut Ctx<'_>, chart: usize, code: &ChartCode) {
    let plan = code.plan();
    let frame = ctx.charts[chart].frame;
    let st = &mut ctx.charts[chart];
    if !st.started && st.held {
        return; // already held in the initial situation
    }
    while let Some(&s) = st.active.last() {
        st.deactivate(s);
    }
    st.left.clear();
    st.entered.clear();
    st.stepped.clear();
    for c in st.controls.iter_mut() {
        *c = Default::default();
    }
    st.live.clear();
    st.started = false;
    st.held = true;
    for step in st.steps.iter_mut() {
        step.t = 0;
        step.overdue = false;
        step.held = false;
        step.interlock_open = false;
        step.supervision_was = false;
    }
    for d in st.disturbance.iter_mut() {
        *d = (0, None);
    }
    for &s in &plan.initial {
        let clock = st.clock;
        let step = &mut st.steps[s as usize];
        step.x = true;
        step.t = clock;
        step.pos = st.active.len() as u32;
        st.active.push(s);
        st.since.push(clock);
    }
    st.changed = true;
    ctx.sink.starts.push((ctx.sink.fired.len() as u32, chart as u32));
    ctx.sink.moved = true;
    for (s, &off) in code.step_x.iter().enumerate() {
        ctx.mem[frame + off as usize] = Value::Bool(plan.is_initial[s]);
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
    if let Some(p) = code.control.error_pou {
        ctx.mem[frame + p as usize] = Value::Str(Arc::from(""));
    }
    // SFCCurrentStep follows the initial situation while SFCInit holds it.
    let st = &mut ctx.charts[chart];
    if st.track_current {
        st.changed = false;
        let first = current_step(ctx.profile, &st.active);
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

/// When a guard faults, the first faulting guard in declaration order among `cands` (the
/// candidates whose guards are closures) is the error; the sink notes its transition.
fn first_fault(ctx: &mut Ctx<'_>, chart: usize, code: &ChartCode, plan: &ChartPlan, cands: &[u32], f: Fault) -> Fault {
    let frame = ctx.charts[chart].frame;
    let mut all = cands.to_vec();
    all.sort_unstable();
    let first =
        all.into_iter().find_map(|t| eval_guard(ctx, code, plan.tr[t as usize].guard, frame, t).err().map(|f| (t, f)));
    match first {
        Some((t, f)) => {
            ctx.sink.note_fault(chart, FaultSite::Guard(t));
            f
        }
        None => f,
    }
}

/// Steps 3–5: enabled and true transitions against one snapshot, conflicts, firing.
/// Returns whether anything fired.
pub(super) fn evolve(ctx: &mut Ctx<'_>, chart: usize, code: &ChartCode, plan: &ChartPlan) -> Result<bool, Fault> {
    if code.control.tip.is_some() || code.control.tip_mode.is_some() {
        if let Some(fired) = jog(ctx, chart, code, plan) {
            return Ok(fired);
        }
    }
    let frame = ctx.charts[chart].frame;
    // Pass 1 over the active steps: links with inline guards are tested and their targets
    // marked; links with compiled guards and the transitions of other steps are collected.
    // Nothing fires yet, so every guard sees the snapshot.
    let st = &mut ctx.charts[chart];
    let epoch = st.next_epoch();
    let mut fire = std::mem::take(&mut st.fire);
    let mut code_links = std::mem::take(&mut st.code_links);
    let mut cand = std::mem::take(&mut st.cand);
    fire.clear();
    code_links.clear();
    cand.clear();
    let mut complex = {
        let ChartState { active, steps, stamp, clock, .. } = st;
        let clock = *clock;
        let found = test_links(&plan.link, ctx.mem, frame, active, steps, epoch, &mut fire, &mut code_links);
        // The transitions of steps without link (their positions were noted in `cand`).
        if found.general {
            for k in 0..code_links.len() {
                if code_links[k] & GENERAL != 0 {
                    let s = active[(code_links[k] & !GENERAL) as usize];
                    collect_general(plan, steps, stamp, epoch, clock, s, &mut cand);
                }
            }
            code_links.retain(|&i| i & GENERAL == 0);
        }
        found.complex
    };
    // Pass 1, continued: the compiled guards (links first, then the general candidates).
    let mut faulted = None;
    for &i in &code_links {
        let i = i as usize;
        let s = ctx.charts[chart].active[i];
        let l = plan.link[s as usize];
        match (code.guards[l.t as usize])(ctx, frame) {
            Ok(true) => {
                let st = &mut ctx.charts[chart];
                let to = &mut st.steps[l.to as usize];
                complex |= (to.x && l.to != s) | (to.amark == epoch);
                to.amark = epoch;
                fire.push(i as u32);
            }
            Ok(false) => {}
            Err(f) => {
                faulted = Some(f);
                break;
            }
        }
    }
    let mut e_len = 0;
    let mut may_conflict = false;
    if faulted.is_none() {
        for k in 0..cand.len() {
            let t = cand[k];
            let info = plan.tr[t as usize];
            match eval_guard(ctx, code, info.guard, frame, t) {
                Ok(true) => {
                    cand[e_len] = t;
                    e_len += 1;
                    may_conflict |= info.may_conflict;
                }
                Ok(false) => {}
                Err(f) => {
                    faulted = Some(f);
                    break;
                }
            }
        }
    }
    if let Some(f) = faulted {
        // Guards have no side effects, so their order does not matter; the first faulting
        // guard in declaration order among those with closures is reported.
        let st = &ctx.charts[chart];
        let mut with_code: Vec<u32> = code_links.iter().map(|&i| plan.link[st.active[i as usize] as usize].t).collect();
        with_code.extend(cand.iter().copied().filter(|&t| plan.tr[t as usize].guard == FastGuard::Code));
        let err = first_fault(ctx, chart, code, plan, &with_code, f);
        let st = &mut ctx.charts[chart];
        (st.fire, st.code_links, st.cand) = (fire, code_links, cand);
        return Err(err);
    }
    cand.truncate(e_len);
    let st = &mut ctx.charts[chart];
    if cand.is_empty() && !complex {
        // Fast path: every true transition is a link to a step that is neither active nor
        // entered by another one.
        let fired = !fire.is_empty();
        if fired {
            if st.any_mirror || plan.any_entities || st.track_left || !st.vendor_slots.is_empty() {
                fire_simple::<true>(st, ctx.mem, &mut ctx.sink.fired, &mut ctx.sink.moved, chart, plan, &fire);
            } else {
                fire_simple::<false>(st, ctx.mem, &mut ctx.sink.fired, &mut ctx.sink.moved, chart, plan, &fire);
            }
        }
        (st.fire, st.code_links, st.cand) = (fire, code_links, cand);
        return Ok(fired);
    }
    // General path: the true links join the other true transitions, under a fresh epoch (the
    // marks of pass 1 no longer count).
    for &i in &fire {
        let t = plan.link[st.active[i as usize] as usize].t;
        cand.push(t);
        may_conflict |= plan.tr[t as usize].may_conflict;
    }
    let epoch = st.next_epoch();
    let result = fire_candidates(ctx, chart, plan, &mut cand, may_conflict, epoch);
    let st = &mut ctx.charts[chart];
    (st.fire, st.code_links, st.cand) = (fire, code_links, cand);
    Ok(result)
}

/// Marks a position in the list of [`test_links`] as a step without link.
const GENERAL: u32 = 1 << 31;

/// What pass 1 found beside the true links.
struct Found {
    /// A target is active (other than a self-loop) or entered twice: the general path must
    /// judge the firing.
    complex: bool,
    /// Some active step has no link.
    general: bool,
}

/// Pass 1 over the active steps for links with inline guards: each true one has its position
/// pushed to `fire` and its target marked with `epoch`. Positions of links with compiled
/// guards are pushed to `later`, and those of steps without link too, with the `GENERAL` bit.
#[inline(never)]
#[allow(clippy::too_many_arguments)]
fn test_links(
    links: &[Link],
    mem: &[Value],
    frame: usize,
    active: &[u32],
    steps: &mut [StepState],
    epoch: u32,
    fire: &mut Vec<u32>,
    later: &mut Vec<u32>,
) -> Found {
    assert_eq!(links.len(), steps.len(), "one link record per step");
    // Locals, so the loop keeps them in registers.
    let mut out = std::mem::take(fire);
    out.reserve(active.len());
    let mut complex = false;
    let mut general = false;
    for (i, &s) in active.iter().enumerate() {
        // SAFETY: an active entry is a step of this chart (`s < steps.len() == links.len()`,
        // the engine only ever stores step indices in `active`).
        let l = unsafe { *at(links, s) };
        let v = if l.kind == guard_kind::GLOBAL {
            read_bool(mem, l.slot as usize)
        } else if l.kind == guard_kind::LOCAL {
            read_bool(mem, frame + l.slot as usize)
        } else if l.kind == guard_kind::CONST {
            l.slot != 0
        } else {
            let general_step = l.kind != guard_kind::CODE;
            general |= general_step;
            later.push(i as u32 | if general_step { GENERAL } else { 0 });
            continue;
        };
        if v != l.neg {
            // SAFETY: a link's target is a step of its chart (checked by `ChartPlan::new`).
            let to = unsafe { at_mut(steps, l.to) };
            complex |= (to.x & (l.to != s)) | (to.amark == epoch);
            to.amark = epoch;
            out.push(i as u32);
        }
    }
    *fire = out;
    Found { complex, general }
}

/// `&v[i]` without the bounds check, for the two hot loops of the evolution, whose indices are
/// step and transition numbers of the plan. Debug builds (the tests) check them.
///
/// # Safety
/// `i < v.len()`.
#[inline(always)]
unsafe fn at<T>(v: &[T], i: u32) -> &T {
    debug_assert!((i as usize) < v.len(), "index {i} out of {}", v.len());
    // SAFETY: the caller guarantees `i < v.len()`.
    unsafe { v.get_unchecked(i as usize) }
}

/// `&mut v[i]` without the bounds check (see [`at`]).
///
/// # Safety
/// `i < v.len()`.
#[inline(always)]
unsafe fn at_mut<T>(v: &mut [T], i: u32) -> &mut T {
    debug_assert!((i as usize) < v.len(), "index {i} out of {}", v.len());
    // SAFETY: the caller guarantees `i < v.len()`.
    unsafe { v.get_unchecked_mut(i as usize) }
}

/// The candidates of a step without link: its outgoing transitions that are enabled (a
/// transition with one preceding step is met only from that, active, step), and whose preceding
/// steps have all been active for their minimum time (`sfc.min_time`).
#[inline(never)]
fn collect_general(
    plan: &ChartPlan,
    steps: &[super::state::StepState],
    stamp: &mut [u32],
    epoch: u32,
    clock: i64,
    s: u32,
    cand: &mut Vec<u32>,
) {
    let waited = |p: u32| {
        !steps[p as usize].held && plan.min_times[p as usize].is_none_or(|m| clock - steps[p as usize].t >= m)
    };
    for &t in plan.outgoing.get(s) {
        if plan.tr[t as usize].single_pre {
            if waited(s) {
                cand.push(t);
            }
            continue;
        }
        let mark = &mut stamp[t as usize];
        if *mark == epoch {
            continue;
        }
        *mark = epoch;
        if plan.pre.get(t).iter().all(|&p| steps[p as usize].x && waited(p)) {
            cand.push(t);
        }
    }
}

/// Fires the true links at positions `fire` of the active list, each from its step to a step
/// that is neither active nor entered by another (checked in pass 1): the entered step takes
/// the left step's position. `SLOW` also writes mirrored slots, queues entered steps for the
/// action phase and notes left steps for the CODESYS body order.
#[inline(never)]
fn fire_simple<const SLOW: bool>(
    st: &mut ChartState,
    mem: &mut [Value],
    fired: &mut Vec<(u32, u32)>,
    moved: &mut bool,
    chart: usize,
    plan: &ChartPlan,
    fire: &[u32],
) {
    let clock = st.clock;
    let mut any_move = false;
    let base = fired.len();
    fired.resize(base + fire.len(), (0, 0));
    {
        let links = &plan.link[..];
        let ChartState { active, since, steps, fired_count, .. } = &mut *st;
        let (active, since, steps, fired_count) =
            (&mut active[..], &mut since[..], &mut steps[..], &mut fired_count[..]);
        assert!(links.len() == steps.len() && fire.len() <= active.len(), "one link record per step");
        assert!(since.len() == active.len(), "one activation time per active step");
        for (&i, out) in fire.iter().zip(&mut fired[base..]) {
            // SAFETY: `i` is a position in `active` found by pass 1, which nothing has changed
            // since; `from` and `to` are steps and `l.t` a transition of this chart (checked
            // by `ChartPlan::new`), and `fired_count` has one entry per transition.
            unsafe {
                let slot = at_mut(active, i);
                let from = *slot;
                let l = *at(links, from);
                *slot = l.to;
                *at_mut(since, i) = clock;
                let f = at_mut(steps, from);
                let d = clock - f.t;
                f.x = false;
                f.t = d;
                f.tally.complete(d);
                let e = at_mut(steps, l.to);
                e.x = true;
                e.t = clock;
                e.pos = i;
                e.overdue = false;
                e.tally.activations += 1;
                *at_mut(fired_count, l.t) += 1;
                *out = (chart as u32, l.t);
                any_move |= from != l.to;
            }
        }
    }
    if SLOW {
        st.left.clear();
        for &(_, t) in &fired[base..] {
            let (from, to) = (plan.tr[t as usize].from, plan.tr[t as usize].to);
            if from != to {
                st.publish_x(mem, from, false);
            }
            st.publish_x(mem, to, true);
            st.publish_t(mem, to);
            if let Some(d) = st.disturbance.get_mut(to as usize) {
                *d = (0, None);
            }
            if plan.has_entities[to as usize] {
                st.entered.push(to);
            }
            if st.track_left {
                st.left.push(from);
            }
        }
    }
    st.changed = true;
    *moved |= any_move;
}

/// The general path of steps 4–5 for the true transitions `cand` (declaration order not
/// required): conflicts, then firing. `may_conflict`: some candidate leaves a divergence.
fn fire_candidates(
    ctx: &mut Ctx<'_>,
    chart: usize,
    plan: &ChartPlan,
    cand: &mut [u32],
    may_conflict: bool,
    epoch: u32,
) -> bool {
    let st = &mut ctx.charts[chart];
    if cand.is_empty() {
        return false;
    }
    // Two true transitions sharing a step are a conflict; without one, all of them fire. Only
    // transitions leaving a divergence can share a step.
    let mut shared = false;
    if cand.len() > 1 && may_conflict {
        for &t in cand.iter() {
            for &p in plan.pre.get(t) {
                let m = &mut st.marks[p as usize];
                shared |= m.seen == epoch;
                m.seen = epoch;
            }
        }
    }
    let mut accepted = std::mem::take(&mut st.accepted);
    accepted.clear();
    if shared {
        cand.sort_unstable();
        resolve_conflicts(st, plan, cand, &mut accepted, ctx.profile, &mut ctx.sink.events);
    } else {
        accepted.extend_from_slice(cand);
    }
    fire_general(ctx, chart, plan, &accepted, epoch);
    ctx.charts[chart].accepted = accepted;
    true
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
            st.marks[s as usize].dmark = epoch;
        }
    }
    let mut unsafe_steps: Vec<u32> = Vec::new();
    for &t in accepted {
        for &s in plan.post.get(t) {
            let dmark = st.marks[s as usize].dmark;
            let step = &mut st.steps[s as usize];
            if (step.amark == epoch || (step.x && dmark != epoch)) && !unsafe_steps.contains(&s) {
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
    let mut moved = false;
    for &t in accepted {
        for &s in plan.pre.get(t) {
            // Each step of D once (MatIEC may accept transitions sharing a step).
            if st.marks[s as usize].dmark != epoch {
                continue;
            }
            st.marks[s as usize].dmark = 0;
            if !st.steps[s as usize].x {
                continue;
            }
            if st.steps[s as usize].amark == epoch {
                st.complete(s);
            } else {
                st.deactivate(s);
                st.publish_x(ctx.mem, s, false);
                moved = true;
            }
            st.left.push(s);
        }
    }
    for &t in accepted {
        for &s in plan.post.get(t) {
            if st.steps[s as usize].amark == epoch {
                st.steps[s as usize].amark = 0;
                moved |= st.activate(s);
                st.publish_x(ctx.mem, s, true);
                st.publish_t(ctx.mem, s);
            }
        }
        st.fired_count[t as usize] += 1;
        ctx.sink.fired.push((chart as u32, t));
    }
    ctx.sink.moved |= moved;
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
                let m = &mut st.marks[s as usize];
                m.hits = m.hits.saturating_add(1);
            }
        }
    }
    let mut steps: Vec<u32> = Vec::new();
    for &t in cand {
        for &s in plan.pre.get(t) {
            if st.marks[s as usize].hits >= 2 && !steps.contains(&s) {
                steps.push(s);
            }
        }
    }
    for &t in cand {
        for &s in plan.pre.get(t) {
            st.marks[s as usize].hits = 0;
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
    let mut order = std::mem::take(&mut st.order);
    order.clear();
    order.extend_from_slice(cand);
    if !codesys {
        order.sort_unstable_by_key(|&t| plan.order_key[t as usize]);
    }
    for &t in &order {
        let pre = plan.pre.get(t);
        let free = pre.iter().all(|&s| !st.marks[s as usize].consumed);
        if free || (profile == Profile::Matiec && !explicit(t)) {
            for &s in pre {
                st.marks[s as usize].consumed = true;
            }
            accepted.push(t);
        }
    }
    st.order = order;
    for &t in accepted.iter() {
        for &s in plan.pre.get(t) {
            st.marks[s as usize].consumed = false;
        }
    }
    accepted.sort_unstable();
}

/// GRAFCET (IEC 60848): evolve on frozen inputs until nothing fires; a situation met twice
/// is an endless cycle and stops the run.
fn evolve_until_stable(ctx: &mut Ctx<'_>, chart: usize, code: &ChartCode, plan: &ChartPlan) -> Result<(), Fault> {
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
        let fired = evolve(ctx, chart, code, plan)?;
        if !fired {
            return Ok(());
        }
    }
}

/// A call's time: the chart clock advances by the time since the last call, and the mirrored `T`
/// slots of the active steps follow (the `logix` and `graph` profiles' calls, which never pause).
pub(super) fn advance_clock(ctx: &mut Ctx<'_>, chart: usize, now: i64) {
    let st = &mut ctx.charts[chart];
    let delta = now - st.last_time;
    st.last_time = now;
    if delta != 0 {
        st.clock += delta;
        if st.any_mirror_t {
            for &s in &st.active {
                st.publish_t(ctx.mem, s);
            }
        }
    }
}

/// Writes the `X` and `T` slots of the initial steps (evolutions write them as they fire).
pub(crate) fn publish_initial(ctx: &mut Ctx<'_>, chart: usize) {
    let st = &ctx.charts[chart];
    for s in 0..st.vendor_slots.len() {
        let Some(&base) = st.vendor_slots.get(s) else { continue };
        match st.members {
            crate::code::StepMembers::Logix => {
                st.publish_count(ctx.mem, s as u32);
                if !matches!(ctx.mem[base as usize + 4], Value::Int(_)) {
                    ctx.mem[base as usize + 4] = Value::Int(0);
                }
            }
            crate::code::StepMembers::Graph => {
                if !matches!(ctx.mem[base as usize], Value::Time(_)) {
                    ctx.mem[base as usize] = Value::Time(0);
                }
            }
            crate::code::StepMembers::Iec => {}
        }
    }
    for &s in &st.active {
        let (x_slot, t_slot) = st.slots[s as usize];
        put_bool(ctx.mem, x_slot as usize, true);
        put_time(ctx.mem, t_slot as usize, st.time(s));
    }
}

/// After the scan: supervision times, SFCError/SFCErrorStep, SFCCurrentStep.
#[inline(always)]
pub(crate) fn finish_scan(ctx: &mut Ctx<'_>, chart: usize, code: &ChartCode, plan: &ChartPlan) {
    if plan.supervised {
        check_times(ctx, chart, code, plan);
    }
    let st = &ctx.charts[chart];
    if st.changed && st.track_current {
        update_current_step(ctx, chart, code, plan);
    }
}

/// Supervision: each activation of an active step whose time is over its `sfc.timeout` is
/// noted once; the first (in declaration order) sets `SFCError`, `SFCErrorStep` and, when
/// declared, `SFCErrorPOU`. With `SFCEnableLimit` declared, only while it is TRUE. Under
/// `codesys` a timeout is registered only while `SFCError` is FALSE ("SFC flags": a second
/// timeout is not registered until `SFCError` is reset).
pub(super) fn check_times(ctx: &mut Ctx<'_>, chart: usize, code: &ChartCode, plan: &ChartPlan) {
    let frame = ctx.charts[chart].frame;
    let ctl = code.control;
    if ctl.enable_limit.is_some_and(|e| !read_bool(ctx.mem, frame + e as usize)) {
        return;
    }
    let latched = ctx.profile == Profile::Codesys && read_bool(ctx.mem, frame + ctl.error as usize);
    let st = &mut ctx.charts[chart];
    let mut expired: Option<u32> = None;
    let clock = st.clock;
    for &s in &st.active {
        if let Some(limit) = plan.timeouts[s as usize] {
            let step = &mut st.steps[s as usize];
            if clock - step.t > limit && !step.overdue {
                step.overdue = true;
                ctx.sink.overdue.push((chart as u32, s));
                if expired.is_none_or(|f| s < f) {
                    expired = Some(s);
                }
            }
        }
    }
    if let Some(s) = expired.filter(|_| !latched) {
        ctx.mem[frame + ctl.error as usize] = Value::Bool(true);
        ctx.mem[frame + ctl.error_step as usize] = plan.step_values[s as usize].clone();
        if let Some(p) = ctl.error_pou {
            ctx.mem[frame + p as usize] = Value::Str(Arc::from(code.chart.pou.as_str()));
        }
    }
}

/// The step `SFCCurrentStep` names: the first active step in declaration order; under
/// `codesys` the last ("SFC flags": in parallel branches, the step of the rightmost branch).
pub(crate) fn current_step(profile: Profile, active: &[u32]) -> Option<u32> {
    if profile == Profile::Codesys {
        active.iter().copied().max()
    } else {
        active.iter().copied().min()
    }
}

/// Writes `SFCCurrentStep` after the situation changed.
pub(super) fn update_current_step(ctx: &mut Ctx<'_>, chart: usize, code: &ChartCode, plan: &ChartPlan) {
    let frame = ctx.charts[chart].frame;
    let st = &mut ctx.charts[chart];
    st.changed = false;
    let cur = current_step(ctx.profile, &st.active);
    if cur != st.current {
        st.current = cur;
        ctx.mem[frame + code.control.current_step as usize] = match cur {
            Some(s) => plan.step_values[s as usize].clone(),
            None => Value::Str(Arc::from("")),
        };
    }
}

/// Jogging (CODESYS's `SFCTip`, `SFCTipMode`, when declared): a rising edge of `SFCTip` fires,
/// for each active step in declaration order, its first enabled outgoing transition whatever
/// its condition (a step consumed once); while `SFCTipMode` is TRUE the conditions are not
/// evaluated and only that moves the chart. Returns `None` when the evolution is the normal one.
fn jog(ctx: &mut Ctx<'_>, chart: usize, code: &ChartCode, plan: &ChartPlan) -> Option<bool> {
    let frame = ctx.charts[chart].frame;
    let ctl = code.control;
    let tip = ctl.tip.is_some_and(|t| read_bool(ctx.mem, frame + t as usize));
    let mode = ctl.tip_mode.is_some_and(|t| read_bool(ctx.mem, frame + t as usize));
    let st = &mut ctx.charts[chart];
    let edge = tip && !st.tip_prev;
    st.tip_prev = tip;
    if !edge {
        return if mode { Some(false) } else { None };
    }
    let mut active = st.active.clone();
    active.sort_unstable();
    let mut accepted: Vec<u32> = Vec::new();
    let mut consumed: Vec<u32> = Vec::new();
    for s in active {
        if consumed.contains(&s) {
            continue;
        }
        let t = plan
            .outgoing
            .get(s)
            .iter()
            .copied()
            .find(|&t| plan.pre.get(t).iter().all(|&p| st.steps[p as usize].x && !consumed.contains(&p)));
        if let Some(t) = t {
            consumed.extend_from_slice(plan.pre.get(t));
            accepted.push(t);
        }
    }
    if accepted.is_empty() {
        return Some(false);
    }
    accepted.sort_unstable();
    let epoch = st.next_epoch();
    fire_general(ctx, chart, plan, &accepted, epoch);
    Some(true)
}
