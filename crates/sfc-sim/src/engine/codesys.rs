//! The `codesys` profile: one call of an SFC instance as CODESYS and TwinCAT process it.
//!
//! Each rule comes from CODESYS's online help (the same pages in Beckhoff's TwinCAT 3 help);
//! docs/sim.md, "The `codesys` profile", cites the page of each, and
//! `crates/sfc-sim/tests/codesys/` holds a fixture per rule with its trace derived by hand.
//!
//! One call ("Processing order in SFC"):
//! 1. `SFCInit` TRUE: back to the initial situation, held there, nothing processed ("SFC
//!    flags"); `SFCReset` TRUE: the same, then processed on.
//! 2. `SFCQuitError` TRUE or `SFCPause` TRUE: the call processes nothing (step times stand
//!    still); `SFCQuitError` clears `SFCError`, and its fall restarts the times of the active
//!    steps ("SFC flags").
//! 3. The time check: an active step over its maximum time (`sfc.timeout`) sets `SFCError`
//!    (the first timeout only, until acknowledged), when `SFCEnableLimit` is TRUE or not
//!    declared.
//! 4. The exit actions of the steps left in the previous call, the entry actions of the steps
//!    entered, the step (main) actions of the active steps ([`super::action::step_actions`]).
//! 5. The IEC actions: action control for every live action, then the bodies alphabetically,
//!    in two passes: those of steps deactivated in the previous call, then the others
//!    ([`super::action::action_phase`]).
//! 6. The transitions: a successor is activated when its step is active, the transition TRUE
//!    and the step's minimum time (`sfc.min_time`) elapsed; alternatives left to right, the
//!    first TRUE one wins; jogging with `SFCTip`/`SFCTipMode`.
//!
//! The first call of an instance activates its initial steps and then runs 3–6 like any other
//! ("Processing order in SFC": "In the first cycle after calling a POU in SFC, the initial step
//! is automatically activated and the step action is executed").

use super::action::{run_iec_actions, step_actions};
use super::evolve::{
    check_times, evolve, held_or_reset, publish_initial, read_bool, set_trans, start, update_current_step,
};
use crate::code::{ChartCode, Ctx, Fault};
use crate::value::Value;
use std::sync::Arc;

/// One call of the SFC instance `chart` under the `codesys` profile.
pub(super) fn run(ctx: &mut Ctx<'_>, chart: usize, code: &ChartCode) -> Result<(), Fault> {
    let plan = code.plan();
    let frame = ctx.charts[chart].frame;
    let now = ctx.now;
    let ctl = code.control;
    // 1. SFCInit holds the initial situation; SFCReset resets it and goes on.
    if held_or_reset(ctx, chart, code) {
        return Ok(());
    }
    // 2. SFCQuitError: while TRUE the error is cleared and the chart paused; its fall restarts
    // the times of the active steps.
    let quit = read_bool(ctx.mem, frame + ctl.quit_error as usize);
    let st = &mut ctx.charts[chart];
    let quit_fell = st.quit_prev && !quit;
    st.quit_prev = quit;
    if quit {
        ctx.mem[frame + ctl.error as usize] = Value::Bool(false);
        ctx.mem[frame + ctl.error_step as usize] = Value::Str(Arc::from(""));
        if let Some(p) = ctl.error_pou {
            ctx.mem[frame + p as usize] = Value::Str(Arc::from(""));
        }
    }
    let paused = quit || read_bool(ctx.mem, frame + ctl.pause as usize);
    let st = &mut ctx.charts[chart];
    let first = !st.started;
    if first {
        start(ctx, chart, plan);
        publish_initial(ctx, chart);
    }
    let st = &mut ctx.charts[chart];
    let delta = now - st.last_time;
    st.last_time = now;
    if !paused && delta != 0 {
        st.clock += delta;
    }
    if quit_fell {
        // "If the variable is reset to FALSE, all previous times in the active steps are reset."
        let clock = st.clock;
        let active = st.active.clone();
        for s in active {
            st.set_since(s, clock);
            st.steps[s as usize].overdue = false;
        }
    }
    if st.any_mirror_t && (delta != 0 || quit_fell) {
        for &s in &st.active {
            st.publish_t(ctx.mem, s);
        }
    }
    if paused {
        // Nothing is processed; a first call has only activated the initial steps.
        set_trans(ctx, chart, code, false);
        let st = &ctx.charts[chart];
        if first && st.changed && st.track_current {
            update_current_step(ctx, chart, code, plan);
        }
        return Ok(());
    }
    // 3. The time check, on the steps active in this call.
    if plan.supervised {
        check_times(ctx, chart, code, plan);
    }
    // 4–5. Step actions, then the IEC actions.
    if plan.step_actions {
        step_actions(ctx, chart, code)?;
    }
    let st = &ctx.charts[chart];
    if !st.entered.is_empty() || !st.live.is_empty() {
        run_iec_actions(ctx, chart, code, plan)?;
    }
    // 6. The transitions.
    let fired_before = ctx.sink.fired.len();
    evolve(ctx, chart, code, plan)?;
    let fired = ctx.sink.fired[fired_before..].iter().any(|f| f.0 == chart as u32);
    set_trans(ctx, chart, code, fired);
    let st = &ctx.charts[chart];
    if st.changed && st.track_current {
        update_current_step(ctx, chart, code, plan);
    }
    Ok(())
}
