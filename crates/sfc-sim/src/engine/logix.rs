//! The `logix` profile: one call of an SFC routine as a Logix 5000 controller executes it
//! (Studio 5000 Logix Designer; Rockwell's "Logix 5000 Controllers Sequential Function Charts"
//! programming manual, 1756-PM006).
//!
//! docs/sim.md, "The `logix` profile", cites the page of each rule, and
//! `crates/sfc-sim/tests/logix/` holds a fixture per rule with its trace derived by hand.
//!
//! One call ("Controller Properties dialog box - SFC Execution tab"):
//! 1. The actions of the active steps execute ("Execute the currently active step(s)"): first
//!    the last scan of the steps left in the previous call, whose actions execute as the
//!    controller's "Last Scan of Active Steps" setting says ([`super::action`], `Rules`), then
//!    the first or a later scan of the others.
//! 2. The transitions below the active steps are tested on what the actions left, and fire; a
//!    step activated here executes in the next call.
//! 3. "Execute until FALSE transition" (`sfc.logix.exec` `UntilFalse`): while a transition
//!    fired, 1 and 2 are repeated in the same call; a chart that never stops advancing would
//!    trip the controller's watchdog, here an error after [`MAX_EVOLUTIONS`] evolutions.
//!
//! sfc's own chart control (`SFCQuitError`, then the supervision of `sfc.timeout` setting
//! `SFCError`) comes first in the call, before 1.
//!
//! The first call activates the initial steps and executes them like any call.

use super::action::run_iec_actions;
use super::evolve::{
    acknowledge, advance_clock, check_times, evolve, held_or_reset, publish_initial, set_trans, start,
    update_current_step,
};
use crate::code::{ChartCode, Ctx, Fault};

/// Evolutions one call of a chart set to "Execute until FALSE transition" may make before the
/// simulator stops it as the controller's watchdog would.
pub(crate) const MAX_EVOLUTIONS: usize = 10_000;

/// One call of the SFC instance `chart` under the `logix` profile.
pub(super) fn run(ctx: &mut Ctx<'_>, chart: usize, code: &ChartCode) -> Result<(), Fault> {
    let plan = code.plan();
    let now = ctx.now;
    if held_or_reset(ctx, chart, code) {
        return Ok(());
    }
    if !ctx.charts[chart].started {
        start(ctx, chart, plan);
        publish_initial(ctx, chart);
    }
    advance_clock(ctx, chart, now);
    // sfc's supervision (`sfc.timeout`, docs/sim.md "Chart control variables"): acknowledged
    // at the start of the call, checked with the step timers, before the actions, as Logix
    // updates a step's timer and its alarms when it scans the step.
    acknowledge(ctx, chart, code);
    if plan.supervised {
        check_times(ctx, chart, code, plan);
    }
    let fired_before = ctx.sink.fired.len();
    let mut evolutions = 0;
    let bits = ctx.charts[chart].members == crate::code::StepMembers::Logix;
    loop {
        if bits {
            scan_bits(ctx, chart, true);
        }
        let st = &ctx.charts[chart];
        if !st.entered.is_empty() || !st.live.is_empty() {
            run_iec_actions(ctx, chart, code, plan)?;
        }
        let before = if bits { ctx.charts[chart].active.clone() } else { Vec::new() };
        if bits {
            scan_bits(ctx, chart, false);
        }
        let fired = evolve(ctx, chart, code, plan)?;
        if bits {
            let st = &mut ctx.charts[chart];
            let left: Vec<u32> = before.into_iter().filter(|s| !st.active.contains(s)).collect();
            st.logix_left = left;
        }
        if !(fired && code.chart.logix.until_false) {
            break;
        }
        evolutions += 1;
        if evolutions >= MAX_EVOLUTIONS {
            return Err(Fault {
                message: format!(
                    "\"Execute until FALSE transition\": the chart was still advancing after {MAX_EVOLUTIONS} \
                     evolutions in one call (a controller's watchdog would fault)"
                ),
                span: code.chart.name_span,
            });
        }
    }
    let fired = ctx.sink.fired[fired_before..].iter().any(|f| f.0 == chart as u32);
    set_trans(ctx, chart, code, fired);
    let st = &ctx.charts[chart];
    if st.changed && st.track_current {
        update_current_step(ctx, chart, code, plan);
    }
    Ok(())
}

/// The scan bits of a Logix chart's steps (1756-PM006, SFC_STEP members): around the actions of
/// a call (`on`), `FS` is on in a step's first scan, `LS` in its last (the scan after it was
/// left), `SA` while it is active in the scans between; "once a step finishes executing the code
/// within its actions, the FS or the LS or both bits are reset" (after, `!on`), and `SA` goes
/// off with the last scan. `TMax` follows the step's time at each scan of its actions.
fn scan_bits(ctx: &mut Ctx<'_>, chart: usize, on: bool) {
    let st = &mut ctx.charts[chart];
    let put = |mem: &mut [crate::value::Value], st: &super::state::ChartState, s: u32, k: usize, v: bool| {
        if let Some(&base) = st.vendor_slots.get(s as usize) {
            super::evolve::put_bool(mem, base as usize + k, v);
        }
    };
    if on {
        for &s in &st.active {
            let first = st.entered.contains(&s);
            put(ctx.mem, st, s, 1, first);
            put(ctx.mem, st, s, 2, !first);
            put(ctx.mem, st, s, 3, false);
            // TMax: the longest time the step has been active, in ms ("for diagnostic
            // purposes"; kept until a restart at the initial step).
            if let Some(&base) = st.vendor_slots.get(s as usize) {
                let ms = st.time(s) / 1000;
                let slot = &mut ctx.mem[base as usize + 4];
                match slot {
                    crate::value::Value::Int(m) if *m >= ms => {}
                    _ => *slot = crate::value::Value::Int(ms),
                }
            }
        }
        for &s in &st.logix_left {
            put(ctx.mem, st, s, 1, false);
            put(ctx.mem, st, s, 2, false);
            put(ctx.mem, st, s, 3, true);
        }
    } else {
        for s in 0..st.vendor_slots.len() as u32 {
            put(ctx.mem, st, s, 1, false);
            put(ctx.mem, st, s, 3, false);
        }
        st.logix_left.clear();
    }
}
