//! Steps 6–7 of a scan: ACTION_CONTROL for every live entity, then the bodies of the actions
//! with `A` TRUE.
//!
//! An entity is live while one of its steps is active or its block holds state; only live
//! entities are visited. The inputs of a block are a mask of qualifier bits; an entity without
//! timed associations (the usual N, S, R, P, P1, P0) skips the timers and the contention test.

use super::evolve::put_bool;
use super::plan::{qualifier_bit, ChartPlan};
use crate::code::{ChartCode, Ctx, DurationCode, Fault};
use crate::value::Value;
use crate::{Event, Profile};
use sfc_model::Qualifier;

const N: u16 = qualifier_bit(Qualifier::N);
const R: u16 = qualifier_bit(Qualifier::R);
const S: u16 = qualifier_bit(Qualifier::S);
const L: u16 = qualifier_bit(Qualifier::L);
const D: u16 = qualifier_bit(Qualifier::D);
const P: u16 = qualifier_bit(Qualifier::P);
const SD: u16 = qualifier_bit(Qualifier::SD);
const DS: u16 = qualifier_bit(Qualifier::DS);
const SL: u16 = qualifier_bit(Qualifier::SL);
const P1: u16 = qualifier_bit(Qualifier::P1);
const P0: u16 = qualifier_bit(Qualifier::P0);

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
    pub(crate) p_mem: bool,
    pub(crate) p1_mem: bool,
    p0_mem: bool,
    /// The duration of each timed qualifier (L, D, SD, DS, SL): the last one a winning
    /// association of that qualifier gave, so a stored SD/SL keeps its own duration after its
    /// step was left.
    t: [i64; 5],
    pub(crate) q: bool,
    /// `logix`: Q without a P association's pulse, whose fall is the end of the action's
    /// activity (a P action's second execution comes when its step is left, not when its pulse
    /// ends).
    core: bool,
    pub(crate) a: bool,
    pub(crate) live: bool,
}

/// What the action control does beyond IEC 61131-3 for the profile of the run.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct Rules {
    pub(crate) profile: Profile,
    /// `logix`: the chart's "Last Scan of Active Steps" setting.
    pub(crate) last_scan: sfc_model::LastScan,
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
    /// One execution of the block on the input mask `i`; returns `(Q, A)`.
    fn update(&mut self, i: u16, now: i64, rules: Rules) -> (bool, bool) {
        let profile = rules.profile;
        let on = |b: u16| i & b != 0;
        let [t_l, t_d, t_sd, t_ds, t_sl] = self.t;
        let r = on(R);
        self.s_ff = !r && (self.s_ff || on(S));
        let l_q = ton(&mut self.l_tmr, on(L), t_l, now);
        let d_q = ton(&mut self.d_tmr, on(D), t_d, now);
        let p_q = on(P) && !self.p_mem;
        let p_fell = !on(P) && self.p_mem;
        self.p_mem = on(P);
        // MatIEC does not let R cancel a pending SD.
        let sd_reset = r && profile != Profile::Matiec;
        self.sd_ff = !sd_reset && (self.sd_ff || on(SD));
        let sd_q = ton(&mut self.sd_tmr, self.sd_ff, t_sd, now);
        let ds_q = ton(&mut self.ds_tmr, on(DS), t_ds, now);
        self.ds_ff = !r && (self.ds_ff || ds_q);
        self.sl_ff = !r && (self.sl_ff || on(SL));
        let sl_q = ton(&mut self.sl_tmr, self.sl_ff, t_sl, now);
        let core = !r && (on(N) || (on(L) && !l_q) || d_q || self.s_ff || sd_q || self.ds_ff || (self.sl_ff && !sl_q));
        self.edges(i, core, core || (!r && p_q), p_fell, rules)
    }

    /// [`Control::update`] of a block without timed associations: its timers never run and its
    /// SD/DS/SL flip-flops are never set.
    #[inline]
    fn update_untimed(&mut self, i: u16, rules: Rules) -> (bool, bool) {
        let r = i & R != 0;
        self.s_ff = !r && (self.s_ff || i & S != 0);
        let p = i & P != 0;
        let p_q = p && !self.p_mem;
        let p_fell = !p && self.p_mem;
        self.p_mem = p;
        let core = !r && (i & N != 0 || self.s_ff);
        self.edges(i, core, core || (!r && p_q), p_fell, rules)
    }

    /// P1/P0 edges, the final scan, and the outputs. `core` is Q without a P pulse; `p_fell`
    /// says a P association's step was left.
    #[inline(always)]
    fn edges(&mut self, i: u16, core: bool, q: bool, p_fell: bool, rules: Rules) -> (bool, bool) {
        let (i1, i0) = (i & P1 != 0, i & P0 != 0);
        let p1 = i1 && !self.p1_mem;
        let p0 = !i0 && self.p0_mem;
        self.p1_mem = i1;
        self.p0_mem = i0;
        let fell = match rules.profile {
            // S7-GRAPH executes an action while it is active and not after (manual 13.5: an
            // N action's assignment "is executed in every cycle while the step is active").
            Profile::Matiec | Profile::Graph => false,
            // Logix: a P action executes when its step is activated and when it is left
            // ("Assign a qualifier to an action"); the last scan of the others is the
            // controller's setting: under "Don't scan" only P and P0 actions execute, under
            // "Programmatic reset" every action executes once more with its Q bit off.
            Profile::Logix => {
                let last = self.core && !core && rules.last_scan == sfc_model::LastScan::ProgrammaticReset;
                last || p_fell
            }
            _ => self.q && !q,
        };
        self.q = q;
        self.core = core;
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

/// Steps 6–7: action control for every live entity, then the bodies with `A` TRUE.
#[inline(always)]
pub(crate) fn action_phase(ctx: &mut Ctx<'_>, chart: usize, code: &ChartCode, plan: &ChartPlan) -> Result<(), Fault> {
    if plan.step_actions {
        step_actions(ctx, chart, code)?;
    }
    let st = &ctx.charts[chart];
    if st.entered.is_empty() && st.live.is_empty() {
        return Ok(()); // no action holds state and none was activated
    }
    run_iec_actions(ctx, chart, code, plan)
}

/// CODESYS's step actions, before the IEC actions (CODESYS, "Processing order in SFC"): the
/// exit actions of the steps left since they last ran, the entry actions of the steps entered,
/// then the step (main) action of every active step; each group in step order.
pub(crate) fn step_actions(ctx: &mut Ctx<'_>, chart: usize, code: &ChartCode) -> Result<(), Fault> {
    use sfc_syntax::ast::StepActionKind as K;
    let st = &mut ctx.charts[chart];
    let mut now: Vec<u32> = st.active.clone();
    now.sort_unstable();
    let before = std::mem::replace(&mut st.stepped, now.clone());
    let frame = st.frame;
    let left = before.iter().filter(|s| now.binary_search(s).is_err());
    let entered = now.iter().filter(|s| before.binary_search(s).is_err());
    let mut todo: Vec<(u32, K)> = left.map(|&s| (s, K::Exit)).collect();
    todo.extend(entered.map(|&s| (s, K::Entry)));
    todo.extend(now.iter().map(|&s| (s, K::Main)));
    for (s, kind) in todo {
        for (_, body) in code.step_actions[s as usize].iter().filter(|(k, _)| *k == kind) {
            body(ctx, frame)?;
        }
    }
    Ok(())
}

/// Action control for every live entity, then the bodies with `A` TRUE (see [`action_phase`]).
pub(crate) fn run_iec_actions(
    ctx: &mut Ctx<'_>,
    chart: usize,
    code: &ChartCode,
    plan: &ChartPlan,
) -> Result<(), Fault> {
    let now = ctx.now;
    let profile = ctx.profile;
    let rules = Rules { profile, last_scan: code.chart.logix.last_scan };
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
    // MatIEC: an action's qualifier inputs are last-writer-wins across its associations.
    let or = profile != Profile::Matiec;
    let mut k = 0;
    while k < st.live.len() {
        let e = st.live[k] as usize;
        let ent = &plan.entities[e];
        let mut inputs = 0u16;
        let mut any_active = false;
        // `graph`: an association that depends on the interlock is off while its step's is open.
        let gated = profile == Profile::Graph;
        let (q, a) = if ent.untimed {
            for a in &ent.assocs {
                let step = &st.steps[a.step as usize];
                let active = step.x && !(gated && a.interlocked && step.interlock_open);
                // Kept live while its step is active, so it comes back when the interlock closes.
                any_active |= step.x;
                if or {
                    inputs |= if active { a.bit } else { 0 };
                } else {
                    inputs = (inputs & !a.bit) | if active { a.bit } else { 0 };
                }
            }
            st.controls[e].update_untimed(inputs, rules)
        } else {
            let mut winner: Option<(u32, Qualifier, i64)> = None;
            let mut contenders: Vec<(u32, Qualifier)> = Vec::new();
            for a in &ent.assocs {
                let step = &st.steps[a.step as usize];
                let active = step.x && !(gated && a.interlocked && step.interlock_open);
                // Kept live while its step is active, so it comes back when the interlock closes.
                any_active |= step.x;
                if a.qualifier.is_timed() {
                    if !active {
                        if !or {
                            inputs &= !a.bit;
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
                            inputs |= a.bit;
                        }
                        Some((_, q, d)) if q == a.qualifier && d == dur => inputs |= a.bit,
                        Some(_) => contenders.push((a.step, a.qualifier)),
                    }
                } else if or {
                    inputs |= if active { a.bit } else { 0 };
                } else {
                    inputs = (inputs & !a.bit) | if active { a.bit } else { 0 };
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
            st.controls[e].update(inputs, now, rules)
        };
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
        let c = &mut st.controls[e];
        if !any_active && ent.variable.is_none() && c.idle() {
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
        run.sort_unstable_by_key(|&e| {
            let ent = &plan.entities[e as usize];
            (!ent.assocs.iter().any(|a| left.contains(&a.step)), plan.alpha_rank[e as usize])
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
                ctx.sink.note_fault(chart, super::FaultSite::Action(id));
                ctx.charts[chart].run = run;
                return Err(f);
            }
        }
    }
    ctx.charts[chart].run = run;
    Ok(())
}
