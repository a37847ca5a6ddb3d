//! What a runtime and its monitor need from a simulation beyond the scan itself (used by
//! `sfc-runtime`): forced variables, guard values, elapsed step times and located variables.
//!
//! Steps and transitions are numbered globally here: every step (transition) of every chart
//! instance in the order of [`Simulation::step_names`] ([`Simulation::transition_names`]), so a
//! runtime can keep a scan's state as plain numbers and name them only when it talks.

use super::{code_of, fit, ScanSink, Simulation, StepStats, TimeStats};
use crate::code::{Ctx, FastGuard};
use crate::value::{format_time, Value};
use crate::{Event, Profile};
use sfc_st::Type;

/// The steps (qualified name, initial) and transitions (qualified name, preceding steps,
/// following steps) of [`Simulation::outline`], in global numbers.
/// One chart instance of [`Simulation::chart_outline`]: the ranges are global numbers.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ChartOutline {
    /// Instance path (`Rev`), the POU's name for the top chart.
    pub instance: String,
    /// Instance path, `""` for the top chart.
    pub path: String,
    /// The program or function block it is an instance of.
    pub pou: String,
    pub steps: std::ops::Range<u32>,
    pub transitions: std::ops::Range<u32>,
    pub actions: std::ops::Range<u32>,
}

pub type OutlineParts = (Vec<(String, bool)>, Vec<(String, Vec<u32>, Vec<u32>)>);

// The module is private to `engine`, so its API uses only types the crate already exports:
// a variable handle is its absolute memory slot with its type, which [`Simulation::write_slot`]
// and [`Simulation::read_slot`] check.

impl Simulation {
    /// Resolves a writable elementary variable (not a step or action flag) once: its memory
    /// slot and type.
    pub fn handle(&self, name: &str) -> Option<(usize, Type)> {
        if self.is_chart_flag(name) {
            return None;
        }
        let (slot, ty) = self.prog.resolve(self.top, self.top_frame, name)?;
        ty.is_elementary().then_some((slot, ty))
    }

    /// Writes the slot of a [`Simulation::handle`]; the value must fit `ty` (as in
    /// [`Simulation::set`]).
    pub fn write_slot(&mut self, slot: usize, ty: &Type, value: Value) -> Result<(), String> {
        let v = fit(value, ty).map_err(|why| format!("{ty}: {why}"))?;
        let cell = self.mem.get_mut(slot).ok_or_else(|| format!("no memory slot {slot}"))?;
        *cell = v;
        Ok(())
    }

    /// `value` converted to a value of `ty` as [`Simulation::set`] would store it, or why it
    /// does not fit.
    pub fn fit_to(ty: &Type, value: Value) -> Result<Value, String> {
        fit(value, ty).map_err(|why| format!("{ty}: {why}"))
    }

    /// The declaration block (`VAR_INPUT`, `VAR`, …) of a variable of the simulated POU, or
    /// `VAR_GLOBAL` for a global one; `None` for a name it does not declare.
    pub fn declared_kind(&self, name: &str) -> Option<sfc_syntax::ast::VarKind> {
        let top = &self.prog.pous.get(self.top)?.layout.vars;
        if let Some(v) = top.iter().find(|v| v.name.eq_ignore_ascii_case(name)) {
            return Some(v.kind);
        }
        self.prog
            .globals
            .vars
            .iter()
            .any(|v| v.name.eq_ignore_ascii_case(name))
            .then_some(sfc_syntax::ast::VarKind::Global)
    }

    /// Reads the slot of a [`Simulation::handle`].
    pub fn read_slot(&self, slot: usize) -> Option<&Value> {
        self.mem.get(slot)
    }

    /// Every located variable of elementary type of the simulated POU, then the global ones, in
    /// declaration order: (name, or the address for a nameless declaration; address as
    /// written; slot; type).
    pub fn located_vars(&self) -> Vec<(String, String, usize, Type)> {
        let top = &self.prog.pous[self.top].layout.vars;
        let local = top.iter().filter_map(|v| {
            let loc = v.location.as_ref()?;
            (v.size == 1 && v.ty.is_elementary()).then(|| {
                let name = if v.name.is_empty() { loc.clone() } else { v.name.clone() };
                (name, loc.clone(), self.top_frame + v.offset as usize, v.ty.clone())
            })
        });
        let global = self.prog.globals.vars.iter().filter_map(|v| {
            let loc = v.location.as_ref()?;
            (v.size == 1 && v.ty.is_elementary()).then(|| {
                let name = if v.name.is_empty() { loc.clone() } else { v.name.clone() };
                (name, loc.clone(), v.offset as usize, v.ty.clone())
            })
        });
        let mut out: Vec<(String, String, usize, Type)> = local.chain(global).collect();
        // A direct address used in code and declared with AT resolves to one slot: keep it once.
        let mut seen = std::collections::HashSet::new();
        out.retain(|l| seen.insert(l.2));
        out
    }

    /// The RETAIN and PERSISTENT values of the simulated POU and the globals, as elementary
    /// leaves with their slots (at most 65,536); see [`crate::code::Program::retained`].
    pub fn retained(&self) -> Vec<crate::code::Retained> {
        self.prog.retained(self.top, self.top_frame, 65_536)
    }

    /// Moves the scan counter forward to `scan` (virtual time `scan · period`): periods a
    /// wall-clock runtime missed are skipped rather than run late. Never moves backwards.
    pub fn skip_to(&mut self, scan: u64) {
        self.next_scan = self.next_scan.max(scan);
    }

    /// Steps and transitions with their links, in global numbers.
    pub fn outline(&self) -> OutlineParts {
        let mut out: OutlineParts = Default::default();
        let mut base = 0u32;
        for c in &self.charts {
            let plan = &c.plan;
            for (s, name) in plan.step_names.iter().enumerate() {
                out.0.push((c.qualify(name), plan.initial.contains(&(s as u32))));
            }
            for (t, name) in plan.transition_names.iter().enumerate() {
                let t = t as u32;
                let pre = plan.pre.get(t).iter().map(|&s| base + s).collect();
                let post = plan.post.get(t).iter().map(|&s| base + s).collect();
                out.1.push((c.qualify(name), pre, post));
            }
            base += plan.step_names.len() as u32;
        }
        out
    }

    /// Every chart instance (the top POU's chart first when it has one, then the SFC function
    /// block instances in the order of [`Simulation::outline`]) with the global numbers of its
    /// steps, transitions and actions.
    pub fn chart_outline(&self) -> Vec<ChartOutline> {
        let (mut s, mut t, mut a) = (0u32, 0u32, 0u32);
        self.charts
            .iter()
            .enumerate()
            .map(|(c, st)| {
                let plan = &st.plan;
                let (ns, nt, na) =
                    (plan.step_names.len() as u32, plan.transition_names.len() as u32, plan.entities.len() as u32);
                let out = ChartOutline {
                    instance: self.instance_name(c),
                    path: st.path.clone(),
                    pou: self.prog.pous.get(st.pou).map(|p| p.name.clone()).unwrap_or_default(),
                    steps: s..s + ns,
                    transitions: t..t + nt,
                    actions: a..a + na,
                };
                (s, t, a) = (s + ns, t + nt, a + na);
                out
            })
            .collect()
    }

    /// Every action of every chart instance in global numbers (see [`Simulation::chart_outline`]):
    /// its qualified name and whether it is a BOOL variable used as an action (IEC 61131-3
    /// allows one in an action association) rather than an action block.
    pub fn action_outline(&self) -> Vec<(String, bool)> {
        self.charts
            .iter()
            .flat_map(|c| c.plan.entities.iter().map(|e| (c.qualify(&e.name), e.action.is_none())))
            .collect()
    }

    /// The outputs of the action control of every action whose `Q` or `A` is TRUE (IEC
    /// 61131-3: `Q` the qualifier logic's output, `A` it or its final scan, which runs the
    /// body), in global numbers, in no particular order: `(action, Q, A)`.
    pub fn action_states(&self, out: &mut Vec<(u32, bool, bool)>) {
        out.clear();
        let mut base = 0u32;
        for c in &self.charts {
            match &c.matiec {
                Some(m) => {
                    for (e, q) in m.action_flags().enumerate() {
                        if q {
                            out.push((base + e as u32, true, true));
                        }
                    }
                }
                None => {
                    for (e, k) in c.controls.iter().enumerate() {
                        if k.q || k.a {
                            out.push((base + e as u32, k.q, k.a));
                        }
                    }
                }
            }
            base += c.plan.entities.len() as u32;
        }
    }

    /// The elapsed time (µs) of every step in global numbers: of an active step since its
    /// activation, of an inactive one the duration of its last activation (IEC 61131-3: `S.T`
    /// keeps it until the step is activated again; `T#0s` for a step never active).
    pub fn step_times(&self, out: &mut Vec<i64>) {
        out.clear();
        for c in &self.charts {
            out.extend((0..c.plan.step_names.len() as u32).map(|s| c.time(s)));
        }
    }

    /// The active steps with their elapsed times (µs), in global numbers, ascending.
    pub fn active_times(&self, out: &mut Vec<(u32, i64)>) {
        self.active_times_unsorted(out);
        out.sort_unstable();
    }

    /// [`Simulation::active_times`] in no particular order: a copy of the engine's active lists,
    /// so a runtime publishing every scan leaves the sorting to whoever reads it.
    pub fn active_times_unsorted(&self, out: &mut Vec<(u32, i64)>) {
        out.clear();
        let mut base = 0u32;
        for c in &self.charts {
            let clock = c.clock;
            out.extend(c.active.iter().zip(&c.since).map(|(&s, &t)| (base + s, clock - t)));
            base += c.plan.step_names.len() as u32;
        }
    }

    /// Whether the last scan changed the active steps only by firing the transitions
    /// [`Simulation::fired_ids`] lists: the steps before them left, the steps after them
    /// entered (elapsed time 0), every other active step's time advanced by its chart's clock
    /// ([`Simulation::chart_clocks`]). Not so when a chart started or was reset (SFCInit), under
    /// the `matiec` profile (which keeps its own step times), or when the scan faulted. A
    /// runtime then publishes the active steps in full rather than as a change.
    pub fn situation_follows_fired(&self) -> bool {
        self.sink.starts.is_empty() && self.error.is_none() && self.opts.profile != Profile::Matiec
    }

    /// Each chart instance's clock (µs, the time its active steps' elapsed times run on), in the
    /// order of [`Simulation::chart_outline`].
    pub fn chart_clocks(&self, out: &mut Vec<i64>) {
        out.clear();
        out.extend(self.charts.iter().map(|c| c.clock));
    }

    /// The transitions the last scan fired, in global numbers, in firing order.
    pub fn fired_ids(&self, out: &mut Vec<u32>) {
        out.clear();
        let bases = &self.transition_base;
        out.extend(self.sink.fired.iter().map(|&(c, t)| bases[c as usize] + t));
    }

    /// The value of the guard of every transition leaving an active step, as
    /// [`Simulation::guard_values`] computes it (`None` for a guard that faults), in no
    /// particular order and without repetition; guards that read one BOOL are read inline.
    pub fn guard_states(&mut self, out: &mut Vec<(u32, Option<bool>)>) {
        out.clear();
        let mut sink = std::mem::take(&mut self.monitor_sink);
        sink.clear();
        let now = (self.next_time() - self.opts.period).max(0);
        for c in 0..self.charts.len() {
            let base = self.transition_base[c];
            let (pou, frame) = (self.charts[c].pou, self.charts[c].frame);
            let epoch = self.charts[c].next_epoch();
            let plan = self.charts[c].plan.clone();
            for k in 0..self.charts[c].active.len() {
                let s = self.charts[c].active[k];
                for &t in plan.outgoing.get(s) {
                    // Each transition once (one leaving several active steps is met from each).
                    if plan.pre.get(t).len() > 1 {
                        let st = &mut self.charts[c];
                        if st.stamp[t as usize] == epoch {
                            continue;
                        }
                        st.stamp[t as usize] = epoch;
                    }
                    let v = match plan.tr[t as usize].guard {
                        FastGuard::Local(o, neg) => Some(bool_at(&self.mem, frame + o as usize) != neg),
                        FastGuard::Global(g, neg) => Some(bool_at(&self.mem, g as usize) != neg),
                        FastGuard::Const(b) => Some(b),
                        FastGuard::Code => {
                            let mut ctx = Ctx {
                                mem: &mut self.mem,
                                prog: &self.prog,
                                charts: &mut self.charts,
                                sink: &mut sink,
                                now,
                                scan: self.next_scan.saturating_sub(1),
                                profile: self.opts.profile,
                                budget: crate::code::Budget::new(self.budget, self.interrupt.as_deref()),
                            };
                            let code = code_of(ctx.prog, pou);
                            (code.guards[t as usize])(&mut ctx, frame).ok()
                        }
                    };
                    out.push((base + t, v));
                }
            }
        }
        self.monitor_sink = sink;
    }

    /// The events of the last scan (conflict, unsafe, contention, error), unsorted.
    pub fn last_events(&self) -> &[Event] {
        &self.sink.events
    }

    /// The value of the guard of every transition leaving an active step (enabled or not),
    /// evaluated on the memory as the last scan left it, in global numbers, ascending; `Err`
    /// holds the message of a guard that faults.
    pub fn guard_values(&mut self, out: &mut Vec<(u32, Result<bool, String>)>) {
        out.clear();
        let bases = self.transition_bases();
        let mut sink = ScanSink::default();
        let now = (self.next_time() - self.opts.period).max(0);
        for (c, &base) in bases.iter().enumerate() {
            let mut ts: Vec<u32> = {
                let st = &self.charts[c];
                st.active.iter().flat_map(|&s| st.plan.outgoing.get(s).iter().copied()).collect()
            };
            ts.sort_unstable();
            ts.dedup();
            let pou = self.charts[c].pou;
            let frame = self.charts[c].frame;
            let mut ctx = Ctx {
                mem: &mut self.mem,
                prog: &self.prog,
                charts: &mut self.charts,
                sink: &mut sink,
                now,
                scan: self.next_scan.saturating_sub(1),
                profile: self.opts.profile,
                budget: crate::code::Budget::new(self.budget, self.interrupt.as_deref()),
            };
            for t in ts {
                let code = code_of(ctx.prog, pou);
                // The compiled closure exists for every guard (the engine's inline fast paths
                // are shortcuts of it).
                let v = (code.guards[t as usize])(&mut ctx, frame).map_err(|f| f.message);
                out.push((base + t, v));
            }
        }
    }

    fn transition_bases(&self) -> Vec<u32> {
        self.transition_base.clone()
    }
}

fn bool_at(mem: &[Value], slot: usize) -> bool {
    matches!(mem.get(slot), Some(Value::Bool(true)))
}

impl StepStats {
    /// The step's time analysis as JSON: `{"step","activations","min","mean","max"}` as TIME
    /// literals (`null` when never active), with the microseconds beside them (`minUs`, …).
    pub fn to_json(&self) -> serde_json::Value {
        let lit = |v: Option<i64>| v.map_or(serde_json::Value::Null, |x| serde_json::json!(format_time(x)));
        serde_json::json!({
            "step": self.step,
            "activations": self.activations,
            "min": lit(self.min),
            "mean": lit(self.mean),
            "max": lit(self.max),
            "minUs": self.min,
            "meanUs": self.mean,
            "maxUs": self.max,
        })
    }
}

impl TimeStats {
    /// The time analysis as JSON: `{"steps":[StepStats::to_json…],"sequence":[{"time","active"}…],
    /// "dropped":N}` (the form of `sfc sim --format json`, plus the microseconds; `dropped`
    /// counts the changes of situation after the recorded ones).
    pub fn to_json(&self) -> serde_json::Value {
        serde_json::json!({
            "steps": self.steps.iter().map(StepStats::to_json).collect::<Vec<_>>(),
            "sequence": self
                .sequence
                .iter()
                .map(|(time, active)| serde_json::json!({"time": format_time(*time), "timeUs": time, "active": active}))
                .collect::<Vec<_>>(),
            "dropped": self.dropped,
        })
    }
}
