//! The `graph` profile: one call of an S7-GRAPH function block as the S7-GRAPH manual
//! describes it (Siemens, "S7-GRAPH for S7-300/400, Programming Sequential Control Systems",
//! C79000-G7076-C526-01, read for TIA Portal's GRAPH with the block interface TIA exports).
//!
//! docs/sim.md, "The `graph` profile", cites the page of each rule, and
//! `crates/sfc-sim/tests/graph/` holds a fixture per rule with its trace derived by hand.
//!
//! One call:
//! 1. `INIT_SQ` TRUE puts the sequence back to its initial steps and holds it there (14.2).
//!    `OFF_SQ` TRUE switches the sequencer off: every step is deactivated and the action
//!    control cleared, as INIT_SQ clears it; the sequence stays off until INIT_SQ.
//! 2. The permanent instructions before the sequencer (actions marked `sfc.s7graph.permanent`
//!    'pre'), every call (6.3).
//! 3. The supervisions of the active steps: the condition rising (or TRUE as the step is
//!    activated) is a supervision error, which holds the step (its transitions do not switch)
//!    until, with "Acknowledge errors" (`sfc.s7graph.ack_required`, on by default), `ACK_EF`
//!    acknowledges it, even while the condition still holds, or, without, the condition is gone
//!    (7.10, 13.5).
//! 4. The transitions switch (as IEC's evolution; 6.1, 6.7).
//! 5. The interlocks of the active steps, the entered ones included: while a step's interlock
//!    is not satisfied, its interlock-dependent actions ("C", named in the step's attribute
//!    `sfc.s7graph.interlocked`) do not run; the transitions do not depend on it (14.2). The
//!    supervisions of the entered steps too.
//! 6. The actions (IEC action control, the "C" ones gated by 5), then once each the event
//!    actions (`sfc.s7graph.step`, `sfc.s7graph.event`) of the step events of this call: V1 a
//!    supervision error comes (or is there when the step is activated), V0 it goes, A1 it is
//!    acknowledged, L1 the interlock stops being satisfied (or is not at activation), L0 it is
//!    satisfied again (13.3, 13.5).
//! 7. The permanent instructions after the sequencer ('post').
//! 8. `ERR_FLT`, when declared: some active step has an interlock or supervision error (15.12).
//!
//! sfc's own chart control works as in every profile: `SFCQuitError` acknowledges `SFCError`
//! at the start of the call (after 1), and the supervision of `sfc.timeout` sets it after 6.
//!
//! The first call activates the initial steps and runs 5–8 (no transition switches in it, as in
//! IEC's scan 0).

use super::action::run_iec_actions;
use super::evolve::{
    acknowledge, advance_clock, check_times, evolve, held_or_reset, publish_initial, put_bool, read_bool, reset, set_trans,
    start, update_current_step,
};
use super::plan::{ChartPlan, GraphEvent};
use crate::code::{ChartCode, Ctx, Fault};

/// One call of the S7-GRAPH block instance `chart` under the `graph` profile.
pub(super) fn run(ctx: &mut Ctx<'_>, chart: usize, code: &ChartCode) -> Result<(), Fault> {
    let plan = code.plan();
    let frame = ctx.charts[chart].frame;
    let now = ctx.now;
    let ctl = code.control;
    // 1. INIT_SQ holds the initial situation (and so does a declared SFCInit).
    if ctl.init_sq.is_some_and(|s| read_bool(ctx.mem, frame + s as usize)) {
        reset(ctx, chart, code);
        set_trans(ctx, chart, code, false);
        group_error(ctx, chart, code);
        return Ok(());
    }
    if held_or_reset(ctx, chart, code) {
        group_error(ctx, chart, code);
        return Ok(());
    }
    let first = !ctx.charts[chart].started;
    if first {
        start(ctx, chart, plan);
        publish_initial(ctx, chart);
    }
    advance_clock(ctx, chart, now);
    publish_u(ctx, chart);
    // OFF_SQ switches the sequencer off: every step is left; it stays off until INIT_SQ.
    if ctl.off_sq.is_some_and(|s| read_bool(ctx.mem, frame + s as usize)) && !ctx.charts[chart].active.is_empty() {
        switch_off(ctx, chart, code);
    }
    acknowledge(ctx, chart, code);
    // 2. Permanent instructions before the sequencer.
    for &a in &plan.permanent_pre {
        (code.bodies[a])(ctx, frame)?;
    }
    let fired_before = ctx.sink.fired.len();
    let mut events = Vec::new();
    if !first {
        // 3–4. Supervision errors hold their steps; then the transitions.
        conditions(ctx, chart, code, false, &mut events)?;
        evolve(ctx, chart, code, plan)?;
    }
    publish_u(ctx, chart);
    // 5. Interlocks (and the supervisions of the steps just entered).
    conditions(ctx, chart, code, true, &mut events)?;
    note_disturbances(ctx, chart);
    let fired = ctx.sink.fired[fired_before..].iter().any(|f| f.0 == chart as u32);
    set_trans(ctx, chart, code, fired);
    // 6. Actions.
    let st = &ctx.charts[chart];
    if !st.entered.is_empty() || !st.live.is_empty() {
        run_iec_actions(ctx, chart, code, plan)?;
    }
    // The actions of the step events raised in this call.
    event_actions(ctx, chart, code, plan, &events)?;
    // sfc's supervision of `sfc.timeout` (SFCError), after the actions as in IEC's scan.
    if plan.supervised {
        check_times(ctx, chart, code, plan);
    }
    // 7. Permanent instructions after the sequencer.
    for &a in &plan.permanent_post {
        (code.bodies[a])(ctx, frame)?;
    }
    // 8. The group error.
    group_error(ctx, chart, code);
    let st = &ctx.charts[chart];
    if st.changed && st.track_current {
        update_current_step(ctx, chart, code, plan);
    }
    Ok(())
}

/// Evaluates the supervisions of the active steps (a supervision error, made by the condition's
/// rising edge, holds its step until acknowledged, or gone when no acknowledgement is
/// required), and with `interlocks` their interlocks too; the
/// step events this raises (V1, V0, A1, L1, L0) are added to `events`.
fn conditions(
    ctx: &mut Ctx<'_>,
    chart: usize,
    code: &ChartCode,
    interlocks: bool,
    events: &mut Vec<(u32, GraphEvent)>,
) -> Result<(), Fault> {
    let frame = ctx.charts[chart].frame;
    let ack = code.control.ack_ef.is_some_and(|s| read_bool(ctx.mem, frame + s as usize));
    let needs_ack = code.chart.s7graph.ack_required;
    let mut k = 0;
    while let Some(&s) = ctx.charts[chart].active.get(k) {
        k += 1;
        let fresh = ctx.charts[chart].entered.contains(&s);
        let su = s as usize;
        if let Some(g) = &code.supervisions[su] {
            let condition = g(ctx, frame)?;
            let step = &mut ctx.charts[chart].steps[su];
            let was = step.held && !fresh;
            let rising = condition && (fresh || !step.supervision_was);
            step.supervision_was = condition;
            if was {
                // The error leaves the state when it "is eliminated or acknowledged" (13.5,
                // V0): acknowledged with ACK_EF when acknowledgement is required (the condition
                // may still hold: it makes an error again only when it rises again), else gone.
                let ends = if needs_ack { ack } else { !condition };
                if ends {
                    step.held = false;
                    events.push((s, GraphEvent::V0));
                    if needs_ack {
                        events.push((s, GraphEvent::A1));
                    }
                }
            } else if rising {
                step.held = true;
                events.push((s, GraphEvent::V1));
            } else if fresh {
                step.held = false;
            }
        }
        if interlocks {
            if let Some(g) = &code.interlocks[su] {
                let satisfied = g(ctx, frame)?;
                let step = &mut ctx.charts[chart].steps[su];
                let was_open = step.interlock_open && !fresh;
                step.interlock_open = !satisfied;
                match (was_open, !satisfied) {
                    (false, true) => events.push((s, GraphEvent::L1)),
                    (true, false) => events.push((s, GraphEvent::L0)),
                    _ => {}
                }
            }
        }
    }
    Ok(())
}

/// Runs, once each, the event actions of the events raised in this call, in declaration order;
/// an interlock-dependent one only while its step's interlock is satisfied.
fn event_actions(ctx: &mut Ctx<'_>, chart: usize, code: &ChartCode, plan: &ChartPlan, events: &[(u32, GraphEvent)]) -> Result<(), Fault> {
    if events.is_empty() {
        return Ok(());
    }
    let frame = ctx.charts[chart].frame;
    for &(step, event, action, interlocked) in &plan.event_actions {
        if !events.contains(&(step, event)) {
            continue;
        }
        if interlocked && ctx.charts[chart].steps[step as usize].interlock_open {
            continue;
        }
        (code.bodies[action])(ctx, frame)?;
    }
    Ok(())
}

/// `ERR_FLT` (when declared): some active step has an interlock or a supervision error.
fn group_error(ctx: &mut Ctx<'_>, chart: usize, code: &ChartCode) {
    let Some(slot) = code.control.err_flt else { return };
    let st = &ctx.charts[chart];
    let error = st.active.iter().any(|&s| {
        let step = &st.steps[s as usize];
        step.held || step.interlock_open
    });
    let frame = st.frame;
    put_bool(ctx.mem, frame + slot as usize, error);
}

/// `OFF_SQ`: every step is left and the action control cleared (as by INIT_SQ, without the
/// initial steps): the sequence has no active step until INIT_SQ puts it back.
fn switch_off(ctx: &mut Ctx<'_>, chart: usize, code: &ChartCode) {
    reset(ctx, chart, code);
    let frame = ctx.charts[chart].frame;
    let st = &mut ctx.charts[chart];
    while let Some(&s) = st.active.last() {
        st.deactivate(s);
    }
    st.started = true;
    st.held = false;
    st.changed = true;
    for &off in &code.step_x {
        put_bool(ctx.mem, frame + off as usize, false);
    }
}

/// Writes each active step's `U` (15.11: "step activation time without disturbance"): its time
/// less the time it has been disturbed, by an interlock or a supervision error, in this
/// activation.
fn publish_u(ctx: &mut Ctx<'_>, chart: usize) {
    let st = &ctx.charts[chart];
    if st.disturbance.is_empty() {
        return;
    }
    for &s in &st.active {
        let (Some(&slot), Some(&(past, since))) = (st.vendor_slots.get(s as usize), st.disturbance.get(s as usize))
        else {
            continue;
        };
        let now = since.map_or(0, |t0| st.clock - t0);
        ctx.mem[slot as usize] = crate::value::Value::Time((st.time(s) - past - now).max(0));
    }
}

/// After the interlocks and supervisions of a call: a step whose disturbance began starts
/// counting it, one whose disturbance ended adds it up.
fn note_disturbances(ctx: &mut Ctx<'_>, chart: usize) {
    let st = &mut ctx.charts[chart];
    if st.disturbance.is_empty() {
        return;
    }
    let clock = st.clock;
    for &s in &st.active {
        let disturbed = st.steps.get(s as usize).is_some_and(|x| x.held || x.interlock_open);
        let Some(d) = st.disturbance.get_mut(s as usize) else { continue };
        match (disturbed, d.1) {
            (true, None) => d.1 = Some(clock),
            (false, Some(t0)) => *d = (d.0 + clock - t0, None),
            _ => {}
        }
    }
}
