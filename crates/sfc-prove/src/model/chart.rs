//! One call of an SFC instance (`semantics.md` steps 2–8, `docs/sim.md` chart control
//! variables, step actions, actions written in SFC and the profiles), symbolically.
//!
//! A call is a sequence of phases ([`Enc::run_chart`]), each a method of its own:
//! 1. *control*: SFCInit (reset and hold), SFCReset (an action's chart: reset, then processed as
//!    its scan 0), SFCQuitError;
//! 2. *start*: the first call activates the initial steps (the chart's scan 0);
//! 3. *clock*: later calls advance the step times of the active steps by the time since the
//!    previous call, unless paused;
//! 4. *evolution* (unless paused): enabled and true transitions against one snapshot, conflicts
//!    (`iec`: explicit priorities, then declaration order; `codesys`: declaration order only),
//!    firing;
//! 5. *actions*: CODESYS's step actions (exit, entry, step action), then ACTION_CONTROL of every
//!    action with its timers and the contention rule, then the bodies (`iec`: declaration order;
//!    `codesys`: alphabetical, those of actions of steps left in the previous call first); a
//!    body written in SFC runs one scan of its chart;
//! 6. *supervision*.
//!
//! `iec` runs 4 before 5, `codesys` 5 before 4 ([`Enc::run_chart`] says the order in one
//! place, so a profile's further rules are a phase more or a phase moved).

use super::{Enc, Role, Slot};
use crate::aig::Lit;
use crate::word::Word;
use sfc_model::{ActionTarget, Duration, Qualifier};
use sfc_st::Type;

/// How many runs of charts one scan's encoding may hold.
const MAX_CHART_RUNS: usize = 4096;

/// The five timed qualifiers, in the order of ACTION_CONTROL's duration array.
const TIMED: [Qualifier; 5] = [Qualifier::L, Qualifier::D, Qualifier::SD, Qualifier::DS, Qualifier::SL];

fn timed_index(q: Qualifier) -> Option<usize> {
    TIMED.iter().position(|&t| t == q)
}

/// The duration of an association.
#[derive(Debug, Clone)]
pub enum DurEnc {
    Literal(i64),
    Reg(usize),
    /// A duration the model cannot read (not a TIME variable): free.
    Unknown,
}

#[derive(Debug, Clone)]
pub struct AssocEnc {
    pub step: usize,
    pub qualifier: Qualifier,
    pub duration: Option<DurEnc>,
}

/// A timer of ACTION_CONTROL: running flag and elapsed scans.
#[derive(Debug, Clone, Copy)]
pub struct TimerRegs {
    pub running: usize,
    pub count: usize,
}

/// The registers of one ACTION_CONTROL block.
#[derive(Debug, Clone)]
pub struct ControlRegs {
    pub s_ff: usize,
    pub sd_ff: usize,
    pub ds_ff: usize,
    pub sl_ff: usize,
    pub tmr: [Option<TimerRegs>; 5],
    /// The duration each timed qualifier runs with (the last winner's), when it can differ
    /// from one association to another.
    pub dur: [Option<usize>; 5],
    pub p_mem: usize,
    pub p1_mem: usize,
    pub p0_mem: usize,
    pub q: usize,
    pub a: usize,
}

/// An action, or a BOOL variable used as an action.
#[derive(Debug, Clone)]
pub struct EntityEnc {
    pub name: String,
    pub action: Option<usize>,
    pub variable: Option<usize>,
    pub assocs: Vec<AssocEnc>,
    pub ctl: ControlRegs,
}

/// The registers of a chart's SFC flags (the instance's variables for a POU's chart, the
/// chart's own hidden flags for an action written in SFC).
#[derive(Debug, Clone, Default)]
pub struct FlagRegs {
    pub init: Option<usize>,
    pub pause: Option<usize>,
    pub quit: Option<usize>,
    pub error: Option<usize>,
    /// SFCReset (charts of actions only).
    pub reset: Option<usize>,
}

/// The symbolic state of one SFC instance.
#[derive(Debug, Clone)]
pub struct ChartEnc {
    pub inst: usize,
    /// Index into the file's charts: `Checked::charts`, then `Checked::action_charts`
    /// ([`chart_at`]).
    pub chart: usize,
    /// The chart's path as the simulator names it: the instance path (`""` for the top POU,
    /// `Rev`), and for an action written in SFC the action after it (`Cyl.ACT_Extend`).
    pub path: String,
    /// The action whose chart this is.
    pub action: Option<String>,
    pub flags: FlagRegs,
    pub started: usize,
    pub x: Vec<usize>,
    /// Elapsed scans of each step whose time anything reads.
    pub t: Vec<Option<usize>>,
    pub overdue: Vec<Option<usize>>,
    /// Scans since the previous call (nested instances).
    pub gap: Option<usize>,
    pub entities: Vec<EntityEnc>,
    /// Q and A of each action (by action index).
    pub q: Vec<usize>,
    pub a: Vec<usize>,
    /// Per step with step actions: active when the step actions last ran.
    pub stepped: Vec<Option<usize>>,
    /// `codesys`: per step associated with an action, left by the previous call's evolution
    /// (such actions' bodies run first).
    pub left: Vec<Option<usize>>,
    /// `codesys`: SFCQuitError in the previous call (its fall restarts the active steps' times).
    pub quit_prev: Option<usize>,
}

/// Chart `idx` of the file: `Checked::charts`, then `Checked::action_charts`.
pub fn chart_at(checked: &sfc_model::Checked, idx: usize) -> &sfc_model::Chart {
    match checked.charts.get(idx) {
        Some(c) => c,
        None => &checked.action_charts[idx - checked.charts.len()],
    }
}

impl ChartEnc {
    /// The key of step `s`'s time counter in the plan.
    pub fn time_key(path: &str, step: &str) -> String {
        format!("{}{}#T", if path.is_empty() { String::new() } else { format!("{path}.") }, step).to_ascii_uppercase()
    }

    /// The chart `chart_idx` ([`chart_at`]) of instance `inst`, named `path` (see
    /// [`ChartEnc::path`]).
    pub(crate) fn new(e: &mut Enc<'_>, inst: usize, chart_idx: usize, path: &str) -> ChartEnc {
        let chart = chart_at(e.checked, chart_idx);
        let qual = |n: &str| if path.is_empty() { n.to_string() } else { format!("{path}.{n}") };
        let started = e.new_reg(
            format!("{} (chart started)", if path.is_empty() { chart.pou.clone() } else { path.to_string() }),
            Type::Bool,
            Role::Hidden,
            0,
            None,
        );
        // The flags: the instance's variables, or the action chart's own.
        let flags = match &chart.action {
            None => FlagRegs {
                init: e.instance_reg(inst, "SFCInit"),
                pause: e.instance_reg(inst, "SFCPause"),
                quit: e.instance_reg(inst, "SFCQuitError"),
                error: e.instance_reg(inst, "SFCError"),
                reset: None,
            },
            Some(_) => {
                let mut flag =
                    |n: &str| Some(e.new_reg(format!("{path}.{n} (flag)"), Type::Bool, Role::Hidden, 0, None));
                FlagRegs {
                    init: flag("SFCInit"),
                    pause: flag("SFCPause"),
                    quit: flag("SFCQuitError"),
                    error: flag("SFCError"),
                    reset: flag("SFCReset"),
                }
            }
        };
        let mut x = Vec::new();
        let mut t = Vec::new();
        let mut overdue = Vec::new();
        let period = e.setup.period;
        for s in &chart.steps {
            x.push(e.new_reg(format!("{}.X", qual(&s.name)), Type::Bool, Role::Hidden, 0, None));
            let key = ChartEnc::time_key(path, &s.name);
            // A supervised step's time is compared with its timeout.
            if let Some(limit) = s.timeout {
                let need = (limit.max(0) / period.max(1)) as u64 + 1;
                let cur = e.learned.need.entry(key.clone()).or_insert(0);
                *cur = (*cur).max(need);
            }
            let read = !e.plan.final_pass || e.plan.bounds.contains_key(&key);
            t.push(if read { Some(e.counter_reg(&format!("{}.T (scans)", qual(&s.name)), &key)) } else { None });
            overdue.push(if s.timeout.is_some() {
                Some(e.new_reg(format!("{} (timeout reported)", qual(&s.name)), Type::Bool, Role::Hidden, 0, None))
            } else {
                None
            });
        }
        let gap = if path.is_empty() && chart.action.is_none() {
            None
        } else {
            let key = format!("{}#GAP", path.to_ascii_uppercase());
            Some(e.counter_reg(&format!("{path} (scans since its last call)"), &key))
        };
        let mut q = Vec::new();
        let mut a = Vec::new();
        for act in &chart.actions {
            q.push(e.new_reg(format!("{}.Q", qual(&act.name)), Type::Bool, Role::Hidden, 0, None));
            a.push(e.new_reg(format!("{}.A", qual(&act.name)), Type::Bool, Role::Hidden, 0, None));
        }
        // Entities: the actions in declaration order, then BOOL variables used as actions in
        // order of first association.
        let mut ents: Vec<(String, Option<usize>, Option<usize>, Vec<AssocEnc>)> =
            chart.actions.iter().enumerate().map(|(i, act)| (act.name.clone(), Some(i), None, Vec::new())).collect();
        for (si, s) in chart.steps.iter().enumerate() {
            for asc in &s.associations {
                let ent = match asc.target {
                    ActionTarget::Action(id) => id,
                    ActionTarget::Variable => {
                        let Some(r) = e.instance_bool_reg(inst, &asc.action) else {
                            e.note(format!(
                                "`{}` used as an action is not a BOOL variable the model holds",
                                asc.action
                            ));
                            continue;
                        };
                        match ents.iter().position(|en| en.2 == Some(r)) {
                            Some(k) => k,
                            None => {
                                ents.push((asc.action.clone(), None, Some(r), Vec::new()));
                                ents.len() - 1
                            }
                        }
                    }
                };
                let duration = asc.duration.as_ref().map(|d| match d {
                    Duration::Literal(us) => DurEnc::Literal(*us),
                    Duration::Variable(name) => match e.instance_reg(inst, name) {
                        // A parameter nothing writes is its initial value.
                        Some(r) if e.regs[r].constant => DurEnc::Literal(e.regs[r].init as i64),
                        Some(r) => DurEnc::Reg(r),
                        None => DurEnc::Unknown,
                    },
                });
                ents[ent].3.push(AssocEnc { step: si, qualifier: asc.qualifier, duration });
            }
        }
        let mut entities = Vec::new();
        for (k, (name, action, variable, assocs)) in ents.into_iter().enumerate() {
            let label = qual(&name);
            let b =
                |e: &mut Enc<'_>, what: &str| e.new_reg(format!("{label} ({what})"), Type::Bool, Role::Hidden, 0, None);
            let s_ff = b(e, "S flip-flop");
            let sd_ff = b(e, "SD flip-flop");
            let ds_ff = b(e, "DS flip-flop");
            let sl_ff = b(e, "SL flip-flop");
            let p_mem = b(e, "P edge memory");
            let p1_mem = b(e, "P1 edge memory");
            let p0_mem = b(e, "P0 edge memory");
            let (qr, ar) = match action {
                Some(i) => (q[i], a[i]),
                None => (b(e, "Q"), b(e, "A")),
            };
            let mut tmr = [None; 5];
            let mut dur = [None; 5];
            for (ti, &tq) in TIMED.iter().enumerate() {
                let used: Vec<&AssocEnc> = assocs.iter().filter(|a| a.qualifier == tq).collect();
                if used.is_empty() {
                    continue;
                }
                let key = format!("{}#{}#{}", path.to_ascii_uppercase(), k, tq.name());
                let running = b(e, &format!("{} timer running", tq.name()));
                let count = e.counter_reg(&format!("{label} ({} timer, scans)", tq.name()), &key);
                tmr[ti] = Some(TimerRegs { running, count });
                // The bound: the largest duration this qualifier can run with.
                let mut need: u64 = 1;
                let mut literals: Vec<i64> = Vec::new();
                let mut variable_dur = false;
                for a in &used {
                    match &a.duration {
                        Some(DurEnc::Literal(us)) => {
                            literals.push(*us);
                            need = need.max(ceil_div(*us, period));
                        }
                        Some(DurEnc::Reg(r)) => {
                            variable_dur = true;
                            let (_, hi) = e.mem[*r].bounds(true);
                            need = need.max(ceil_div(hi.min(i64::MAX as i128) as i64, period));
                        }
                        Some(DurEnc::Unknown) => variable_dur = true,
                        None => literals.push(0),
                    }
                }
                let cur = e.learned.need.entry(key).or_insert(0);
                *cur = (*cur).max(need);
                literals.sort_unstable();
                literals.dedup();
                if variable_dur || literals.len() > 1 {
                    dur[ti] =
                        Some(e.new_reg(format!("{label} ({} duration)", tq.name()), Type::Time, Role::Hidden, 0, None));
                }
            }
            entities.push(EntityEnc {
                name: name.clone(),
                action,
                variable,
                assocs,
                ctl: ControlRegs { s_ff, sd_ff, ds_ff, sl_ff, tmr, dur, p_mem, p1_mem, p0_mem, q: qr, a: ar },
            });
        }
        let mut stepped = Vec::new();
        for s in &chart.steps {
            stepped.push(if s.step_actions.is_empty() {
                None
            } else {
                Some(e.new_reg(format!("{} (step actions ran)", qual(&s.name)), Type::Bool, Role::Hidden, 0, None))
            });
        }
        // CODESYS's body order depends on the steps left only when two bodies may run.
        let mut left = vec![None; chart.steps.len()];
        if e.setup.profile == sfc_sim::Profile::Codesys && chart.actions.len() > 1 {
            for en in entities.iter().filter(|en| en.action.is_some()) {
                for asc in &en.assocs {
                    if left[asc.step].is_none() {
                        let name = format!("{} (left in the previous call)", qual(&chart.steps[asc.step].name));
                        left[asc.step] = Some(e.new_reg(name, Type::Bool, Role::Hidden, 0, None));
                    }
                }
            }
        }
        let quit_prev = (e.setup.profile == sfc_sim::Profile::Codesys && flags.quit.is_some()).then(|| {
            e.new_reg(
                format!("{} (SFCQuitError in the previous call)", qual("chart")),
                Type::Bool,
                Role::Hidden,
                0,
                None,
            )
        });
        ChartEnc {
            quit_prev,
            inst,
            chart: chart_idx,
            path: path.to_string(),
            action: chart.action.clone(),
            flags,
            started,
            x,
            t,
            overdue,
            gap,
            entities,
            q,
            a,
            stepped,
            left,
        }
    }
}

fn ceil_div(us: i64, period: i64) -> u64 {
    if us <= 0 {
        0
    } else {
        ((us as i128 + period as i128 - 1) / period as i128).min(super::MAX_COUNT as i128) as u64
    }
}

impl Enc<'_> {
    /// The BOOL register of variable `name` of instance `inst`.
    pub(crate) fn instance_bool_reg(&self, inst: usize, name: &str) -> Option<usize> {
        let r = self.instance_reg(inst, name)?;
        (self.regs[r].ty.base() == &Type::Bool).then_some(r)
    }

    /// The register of elementary variable `name` of instance `inst` (or a global).
    pub(crate) fn instance_reg(&self, inst: usize, name: &str) -> Option<usize> {
        let v = self.insts[inst]
            .vars
            .iter()
            .find(|v| v.name.eq_ignore_ascii_case(name))
            .or_else(|| self.globals.iter().find(|g| g.name.eq_ignore_ascii_case(name)))?;
        match v.slot {
            Slot::Leaf(r) => Some(r),
            _ => None,
        }
    }

    /// Step `s`'s time counter word (scans).
    fn step_count(&self, c: usize, s: usize) -> Option<Word> {
        self.charts[c].t[s].map(|r| self.mem[r].clone())
    }

    /// Advances the ACTION_CONTROL timers and the call gap of chart `c` by one scan boundary.
    pub(crate) fn tick_chart_timers(&mut self, c: usize) {
        let ents = self.charts[c].entities.clone();
        for en in &ents {
            for t in en.ctl.tmr.iter().flatten() {
                let run = self.bool_reg(t.running);
                let cw = self.mem[t.count].clone();
                let one = Word::constant(1, cw.width());
                let inc = self.sat_inc(&cw, &one, t.count);
                let w = self.ops().ite(run, &inc, &cw);
                self.set_reg(t.count, w);
            }
        }
        if let Some(g) = self.charts[c].gap {
            let cw = self.mem[g].clone();
            let one = Word::constant(1, cw.width());
            let inc = self.sat_inc(&cw, &one, g);
            self.set_reg(g, inc);
        }
    }

    fn flag(&self, r: Option<usize>) -> Lit {
        r.map_or(Lit::FALSE, |r| self.bool_reg(r))
    }

    /// One call of chart instance `c` (the top chart once per scan, a nested one per call of
    /// its instance, an action's chart per run of the action), under the current path
    /// condition: the phases in the profile's order.
    pub(crate) fn run_chart(&mut self, c: usize) {
        // Each run of a chart is encoded where it happens (calls, associations, and under
        // `codesys` both body passes): bounded, so nested actions written in SFC cannot make the
        // encoding grow without end.
        self.chart_runs += 1;
        if self.chart_runs > MAX_CHART_RUNS {
            self.refused.get_or_insert(format!(
                "the chart is run in more than {MAX_CHART_RUNS} places of one scan (actions written in SFC nested in each other), which `prove` does not encode"
            ));
            return;
        }
        if self.running.contains(&c) {
            // The sim stops such a run with a fault at its 200th nested run.
            let name = self.charts[c].action.clone().unwrap_or_default();
            self.refused.get_or_insert(format!(
                "the chart of action `{name}` runs itself (through its steps' actions), which `prove` does not model"
            ));
            return;
        }
        self.running.push(c);
        let outer_pc = self.pc;
        let delta = self.call_gap(c);
        let pause = self.flag(self.charts[c].flags.pause);
        let pc_run = self.control_phase(c, outer_pc);
        let started = self.bool_reg(self.charts[c].started);
        let pc_first = self.g.and(pc_run, started.not());
        self.start_phase(c, pc_first);
        match self.setup.profile {
            sfc_sim::Profile::Codesys => {
                // docs/sim.md, "The `codesys` profile": SFCPause and SFCQuitError pause the whole
                // call; the time check comes before the actions; the first call tests the
                // transitions too.
                let quit = self.flag(self.charts[c].flags.quit);
                let paused = self.g.or(pause, quit);
                let pc_go = self.g.and(pc_run, paused.not());
                let pc_clock = self.g.and(pc_go, started);
                self.clock_phase(c, pc_clock, &delta);
                // SFCQuitError's fall: the times of the active steps restart (and their
                // supervision with them).
                if let Some(qp) = self.charts[c].quit_prev {
                    let prev = self.bool_reg(qp);
                    let fell = self.g.and(prev, quit.not());
                    let pc_fell = self.g.and(pc_run, fell);
                    if pc_fell != Lit::FALSE {
                        let ch = self.charts[c].clone();
                        self.pc = pc_fell;
                        for s in 0..ch.x.len() {
                            let x = self.bool_reg(ch.x[s]);
                            if let Some(t) = ch.t[s] {
                                let cw = self.mem[t].clone();
                                let zero = Word::constant(0, cw.width());
                                let w = self.ops().ite(x, &zero, &cw);
                                self.write_reg(t, w);
                            }
                            if let Some(o) = ch.overdue[s] {
                                let ov = self.bool_reg(o);
                                let v = self.g.and(ov, x.not());
                                self.write_reg(o, Word::from_bit(v, 1));
                            }
                        }
                    }
                    self.pc = pc_run;
                    self.write_reg(qp, Word::from_bit(quit, 1));
                }
                self.pc = pc_go;
                self.supervise(c);
                self.pc = pc_go;
                self.action_phase(c);
                self.evolution_phase(c, pc_go);
            }
            _ => {
                let pc_evolve = {
                    let a = self.g.and(pc_run, started);
                    self.g.and(a, pause.not())
                };
                self.clock_phase(c, pc_evolve, &delta);
                self.evolution_phase(c, pc_evolve);
                self.pc = pc_run;
                self.action_phase(c);
                self.pc = pc_run;
                self.supervise(c);
            }
        }
        self.pc = outer_pc;
        self.running.pop();
    }

    /// The time elapsed since the previous call, in scans (1 for the top chart); the call
    /// gap starts again.
    fn call_gap(&mut self, c: usize) -> Word {
        match self.charts[c].gap {
            Some(g) => {
                let d = self.mem[g].clone();
                self.write_reg(g, Word::constant(0, d.width()));
                d
            }
            None => Word::constant(1, 2),
        }
    }

    /// SFCInit (back to the initial situation and held there: the call ends), SFCReset (back
    /// to it, and the call goes on as the chart's scan 0), SFCQuitError. Returns the path
    /// condition under which the call goes on.
    fn control_phase(&mut self, c: usize, outer_pc: Lit) -> Lit {
        let flags = self.charts[c].flags.clone();
        let init = self.flag(flags.init);
        let reset = self.flag(flags.reset);
        let quit = self.flag(flags.quit);
        let pc_init = self.g.and(outer_pc, init);
        self.reset_unless_held(c, pc_init);
        let pc_run = self.g.and(outer_pc, init.not());
        let pc_reset = self.g.and(pc_run, reset);
        self.reset_unless_held(c, pc_reset);
        if let Some(er) = flags.error {
            self.pc = self.g.and(pc_run, quit);
            self.write_reg(er, Word::constant(0, 1));
        }
        self.pc = pc_run;
        pc_run
    }

    /// Resets chart `c` under `pc`, unless it is held in its initial situation already (not
    /// started, its initial steps active).
    fn reset_unless_held(&mut self, c: usize, pc: Lit) {
        if pc == Lit::FALSE {
            return;
        }
        let ch = self.charts[c].clone();
        self.pc = pc;
        let started = self.bool_reg(ch.started);
        let any = self.g.or_all(ch.x.iter().map(|&r| self.mem[r].bits[0]));
        let held = self.g.and(started.not(), any);
        self.pc = self.g.and(pc, held.not());
        self.reset_chart(c);
    }

    /// The first call (or the first after SFCInit, SFCReset): the initial steps become active.
    fn start_phase(&mut self, c: usize, pc_first: Lit) {
        if pc_first == Lit::FALSE {
            return;
        }
        let ch = self.charts[c].clone();
        let chart = self.chart_of(c);
        self.pc = pc_first;
        self.write_reg(ch.started, Word::constant(1, 1));
        for (s, step) in chart.steps.iter().enumerate() {
            if step.initial {
                self.write_reg(ch.x[s], Word::constant(1, 1));
                if let Some(t) = ch.t[s] {
                    let w = self.mem[t].width();
                    self.write_reg(t, Word::constant(0, w));
                }
                if let Some(o) = ch.overdue[s] {
                    self.write_reg(o, Word::constant(0, 1));
                }
            }
        }
    }

    /// Later calls, unless paused: the active steps' times advance by `delta` scans.
    fn clock_phase(&mut self, c: usize, pc_evolve: Lit, delta: &Word) {
        if pc_evolve == Lit::FALSE {
            return;
        }
        let ch = self.charts[c].clone();
        self.pc = pc_evolve;
        for s in 0..ch.x.len() {
            if let Some(t) = ch.t[s] {
                let x = self.bool_reg(ch.x[s]);
                let cw = self.mem[t].clone();
                let inc = self.sat_inc(&cw, delta, t);
                let w = self.ops().ite(x, &inc, &cw);
                self.write_reg(t, w);
            }
        }
    }

    fn reset_chart(&mut self, c: usize) {
        let ch = self.charts[c].clone();
        let chart = self.chart_of(c);
        for (s, step) in chart.steps.iter().enumerate() {
            self.write_reg(ch.x[s], Word::constant(step.initial as i128, 1));
            if let Some(t) = ch.t[s] {
                let w = self.mem[t].width();
                self.write_reg(t, Word::constant(0, w));
            }
            if let Some(o) = ch.overdue[s] {
                self.write_reg(o, Word::constant(0, 1));
            }
        }
        for r in ch.stepped.iter().chain(&ch.left).flatten() {
            self.write_reg(*r, Word::constant(0, 1));
        }
        for en in &ch.entities {
            let k = &en.ctl;
            for r in [k.s_ff, k.sd_ff, k.ds_ff, k.sl_ff, k.p_mem, k.p1_mem, k.p0_mem, k.q, k.a] {
                self.write_reg(r, Word::constant(0, 1));
            }
            for t in k.tmr.iter().flatten() {
                self.write_reg(t.running, Word::constant(0, 1));
                let w = self.mem[t.count].width();
                self.write_reg(t.count, Word::constant(0, w));
            }
            for d in k.dur.iter().flatten() {
                let w = self.mem[*d].width();
                self.write_reg(*d, Word::constant(0, w));
            }
            if let Some(v) = en.variable {
                self.write_reg(v, Word::constant(0, 1));
            }
        }
        if let Some(er) = ch.flags.error {
            self.write_reg(er, Word::constant(0, 1));
        }
        self.write_reg(ch.started, Word::constant(0, 1));
    }

    /// Steps 3–5 under `pc`: enabled and true transitions, conflicts, firing.
    fn evolution_phase(&mut self, c: usize, pc: Lit) {
        if pc == Lit::FALSE {
            return;
        }
        self.pc = pc;
        let ch = self.charts[c].clone();
        let chart = self.chart_of(c);
        // Enabled and true transitions, against one snapshot.
        let n = chart.transitions.len();
        let mut e_true = vec![Lit::FALSE; n];
        let inst = ch.inst;
        for (t, tr) in chart.transitions.iter().enumerate() {
            let mut pre: Vec<usize> = tr.from.clone();
            pre.sort_unstable();
            pre.dedup();
            let enabled = self.g.and_all(pre.iter().map(|&s| self.mem[ch.x[s]].bits[0]));
            if enabled == Lit::FALSE {
                continue;
            }
            self.pc = self.g.and(pc, enabled);
            self.guard_of = Some((c, t));
            let g = self.guard(inst, c, &tr.condition, &tr.name);
            self.guard_of = None;
            e_true[t] = self.g.and(enabled, g);
        }
        self.pc = pc;
        // Conflicts: explicit priorities first (ascending), then declaration order; CODESYS has
        // no priorities: declaration order (the leftmost alternative).
        let mut order: Vec<usize> = (0..n).collect();
        if self.setup.profile != sfc_sim::Profile::Codesys {
            order.sort_by_key(|&t| match chart.transitions[t].priority {
                Some(p) => (0u8, p, t),
                None => (1u8, 0, t),
            });
        }
        let mut consumed = vec![Lit::FALSE; chart.steps.len()];
        let mut accepted = vec![Lit::FALSE; n];
        for &t in &order {
            if e_true[t] == Lit::FALSE {
                continue;
            }
            let tr = &chart.transitions[t];
            let free = self.g.and_all(tr.from.iter().map(|&s| consumed[s].not()));
            let acc = self.g.and(e_true[t], free);
            accepted[t] = acc;
            for &s in &tr.from {
                consumed[s] = self.g.or(consumed[s], acc);
            }
        }
        // Firing: X' = (X \ D) ∪ A; entered steps restart their time.
        let mut d = vec![Lit::FALSE; chart.steps.len()];
        let mut a = vec![Lit::FALSE; chart.steps.len()];
        for (t, tr) in chart.transitions.iter().enumerate() {
            if accepted[t] == Lit::FALSE {
                continue;
            }
            for &s in &tr.from {
                d[s] = self.g.or(d[s], accepted[t]);
            }
            for &s in &tr.to {
                a[s] = self.g.or(a[s], accepted[t]);
            }
        }
        // A step time that only the step's own outgoing guards read does not matter while the
        // step is inactive: it is kept at 0 then (fewer states, the same behaviour).
        for s in 0..chart.steps.len() {
            let Some(t) = ch.t[s] else { continue };
            let key = ChartEnc::time_key(&ch.path, &chart.steps[s].name);
            if !self.plan.dead_inactive.contains(&key) {
                continue;
            }
            let x = self.bool_reg(ch.x[s]);
            let keep = self.g.and(x, d[s].not());
            let active = self.g.or(keep, a[s]);
            let cw = self.mem[t].clone();
            let z = Word::constant(0, cw.width());
            let w = self.ops().ite(active, &cw, &z);
            self.write_reg(t, w);
        }
        for s in 0..chart.steps.len() {
            if d[s] == Lit::FALSE && a[s] == Lit::FALSE {
                continue;
            }
            let x = self.bool_reg(ch.x[s]);
            let keep = self.g.and(x, d[s].not());
            let nx = self.g.or(keep, a[s]);
            self.write_reg(ch.x[s], Word::from_bit(nx, 1));
            if let Some(t) = ch.t[s] {
                let cw = self.mem[t].clone();
                let z = Word::constant(0, cw.width());
                let w = self.ops().ite(a[s], &z, &cw);
                self.write_reg(t, w);
            }
            if let Some(o) = ch.overdue[s] {
                let ov = self.bool_reg(o);
                let nov = self.g.and(ov, a[s].not());
                self.write_reg(o, Word::from_bit(nov, 1));
            }
        }
        // CODESYS: the steps this evolution left order the next call's bodies.
        for (s, l) in ch.left.iter().enumerate() {
            if let Some(l) = *l {
                self.write_reg(l, Word::from_bit(d[s], 1));
            }
        }
    }

    /// CODESYS's step actions, before the IEC actions: the exit actions of the steps left since
    /// the step actions last ran, the entry actions of the steps entered since, then the step
    /// action of every active step; each group in step order; no action control (the
    /// simulator's `engine/action.rs::step_actions`).
    fn step_actions(&mut self, c: usize) {
        use sfc_syntax::ast::StepActionKind as K;
        let ch = self.charts[c].clone();
        if ch.stepped.iter().all(Option::is_none) {
            return;
        }
        let chart = self.chart_of(c);
        let pc = self.pc;
        let now: Vec<(usize, Lit, Lit)> = ch
            .stepped
            .iter()
            .enumerate()
            .filter_map(|(s, r)| r.map(|r| (s, self.bool_reg(ch.x[s]), self.bool_reg(r))))
            .collect();
        for kind in [K::Exit, K::Entry, K::Main] {
            for &(s, x, before) in &now {
                let cond = match kind {
                    K::Exit => self.g.and(before, x.not()),
                    K::Entry => self.g.and(x, before.not()),
                    K::Main => x,
                };
                for sa in chart.steps[s].step_actions.iter().filter(|a| a.kind == kind) {
                    self.pc = self.g.and(pc, cond);
                    if self.pc == Lit::FALSE {
                        continue;
                    }
                    self.run_step_action(ch.inst, sa);
                }
            }
        }
        self.pc = pc;
        for &(s, x, _) in &now {
            if let Some(r) = ch.stepped[s] {
                self.write_reg(r, Word::from_bit(x, 1));
            }
        }
    }

    /// Steps 6–7: the step actions, ACTION_CONTROL of every entity, then the bodies with `A`
    /// (`iec`: in declaration order; `codesys`: alphabetically, those of actions of steps left
    /// in the previous call first).
    fn action_phase(&mut self, c: usize) {
        self.step_actions(c);
        let ch = self.charts[c].clone();
        let chart = self.chart_of(c);
        let period = self.setup.period;
        let mut run: Vec<(usize, Lit)> = Vec::new();
        for en in &ch.entities {
            let mut inputs = [Lit::FALSE; 11];
            let qi = |q: Qualifier| Qualifier::ALL.iter().position(|&x| x == q).unwrap_or(0);
            // Contention among the timed associations of active steps, in text order.
            let mut found = Lit::FALSE;
            let mut win_q = [Lit::FALSE; 5];
            let mut win_d: Option<Word> = None;
            for asc in &en.assocs {
                let x = self.mem[ch.x[asc.step]].bits[0];
                match timed_index(asc.qualifier) {
                    None => {
                        let k = qi(asc.qualifier);
                        inputs[k] = self.g.or(inputs[k], x);
                    }
                    Some(ti) => {
                        let d = self.duration_word(asc.duration.as_ref());
                        let winner = self.g.and(x, found.not());
                        let same_d = match &win_d {
                            Some(w) => self.ops().eq(w, &d),
                            None => Lit::FALSE,
                        };
                        let joins = {
                            let a = self.g.and(x, found);
                            let b = self.g.and(a, win_q[ti]);
                            self.g.and(b, same_d)
                        };
                        let k = qi(asc.qualifier);
                        let on = self.g.or(winner, joins);
                        inputs[k] = self.g.or(inputs[k], on);
                        win_d = Some(match win_d {
                            None => d.clone(),
                            Some(w) => self.ops().ite(winner, &d, &w),
                        });
                        for (j, wq) in win_q.iter_mut().enumerate() {
                            let is = Lit::from_bool(j == ti);
                            *wq = self.g.ite(winner, is, *wq);
                        }
                        found = self.g.or(found, x);
                    }
                }
            }
            let k = &en.ctl;
            // The duration each timer runs with: the winner's, kept in a register when it varies.
            let mut tdur: [Option<Word>; 5] = [None, None, None, None, None];
            for ti in 0..5 {
                if k.tmr[ti].is_none() {
                    continue;
                }
                let literal = en.assocs.iter().find(|a| timed_index(a.qualifier) == Some(ti));
                tdur[ti] = Some(match k.dur[ti] {
                    Some(r) => {
                        let cur = self.mem[r].clone();
                        let nw = match &win_d {
                            Some(w) => {
                                let cond = self.g.and(found, win_q[ti]);
                                self.ops().ite(cond, w, &cur)
                            }
                            None => cur,
                        };
                        self.write_reg(r, nw.clone());
                        nw
                    }
                    None => self.duration_word(literal.and_then(|a| a.duration.as_ref())),
                });
            }
            let b = |e: &Enc<'_>, r: usize| e.mem[r].bits[0];
            let i = |q: Qualifier| inputs[qi(q)];
            let r = i(Qualifier::R);
            let s_ff = {
                let o = self.g.or(b(self, k.s_ff), i(Qualifier::S));
                self.g.and(r.not(), o)
            };
            let l_q = self.ton(k.tmr[0], i(Qualifier::L), tdur[0].as_ref(), period);
            let d_q = self.ton(k.tmr[1], i(Qualifier::D), tdur[1].as_ref(), period);
            let p_q = self.g.and(i(Qualifier::P), b(self, k.p_mem).not());
            let sd_ff = {
                let o = self.g.or(b(self, k.sd_ff), i(Qualifier::SD));
                self.g.and(r.not(), o)
            };
            let sd_q = self.ton(k.tmr[2], sd_ff, tdur[2].as_ref(), period);
            let ds_q = self.ton(k.tmr[3], i(Qualifier::DS), tdur[3].as_ref(), period);
            let ds_ff = {
                let o = self.g.or(b(self, k.ds_ff), ds_q);
                self.g.and(r.not(), o)
            };
            let sl_ff = {
                let o = self.g.or(b(self, k.sl_ff), i(Qualifier::SL));
                self.g.and(r.not(), o)
            };
            let sl_q = self.ton(k.tmr[4], sl_ff, tdur[4].as_ref(), period);
            let q = {
                let l_on = self.g.and(i(Qualifier::L), l_q.not());
                let sl_on = self.g.and(sl_ff, sl_q.not());
                let any = self.g.or_all([i(Qualifier::N), l_on, d_q, p_q, s_ff, sd_q, ds_ff, sl_on]);
                self.g.and(r.not(), any)
            };
            let p1 = self.g.and(i(Qualifier::P1), b(self, k.p1_mem).not());
            let p0 = self.g.and(i(Qualifier::P0).not(), b(self, k.p0_mem));
            let fell = self.g.and(b(self, k.q), q.not());
            let a = self.g.or_all([q, fell, p1, p0]);
            self.write_reg(k.s_ff, Word::from_bit(s_ff, 1));
            self.write_reg(k.sd_ff, Word::from_bit(sd_ff, 1));
            self.write_reg(k.ds_ff, Word::from_bit(ds_ff, 1));
            self.write_reg(k.sl_ff, Word::from_bit(sl_ff, 1));
            self.write_reg(k.p_mem, Word::from_bit(i(Qualifier::P), 1));
            self.write_reg(k.p1_mem, Word::from_bit(i(Qualifier::P1), 1));
            self.write_reg(k.p0_mem, Word::from_bit(i(Qualifier::P0), 1));
            self.write_reg(k.q, Word::from_bit(q, 1));
            self.write_reg(k.a, Word::from_bit(a, 1));
            if let Some(v) = en.variable {
                self.write_reg(v, Word::from_bit(q, 1));
            }
            if let Some(act) = en.action {
                run.push((act, a));
            }
        }
        let pc = self.pc;
        if self.setup.profile == sfc_sim::Profile::Codesys {
            // Alphabetical order (the simulator's `alpha_rank`), in two passes when some step
            // may have been left: first the actions of steps left in the previous call.
            run.sort_by_cached_key(|r| (chart.actions[r.0].name.to_ascii_uppercase(), r.0));
            let left_of = |e: &mut Enc<'_>, act: usize| -> Lit {
                let Some(en) = ch.entities.iter().find(|en| en.action == Some(act)) else { return Lit::FALSE };
                let ls: Vec<Lit> = en.assocs.iter().filter_map(|a| ch.left[a.step]).map(|r| e.bool_reg(r)).collect();
                e.g.or_all(ls)
            };
            let lefts: Vec<Lit> = run.iter().map(|&(act, _)| left_of(self, act)).collect();
            for first in [true, false] {
                for (&(act, a), &l) in run.iter().zip(&lefts) {
                    let group = if first { l } else { l.not() };
                    let cond = self.g.and(a, group);
                    if cond == Lit::FALSE {
                        continue;
                    }
                    self.pc = self.g.and(pc, cond);
                    self.run_action(ch.inst, &chart.actions[act].name, &chart.actions[act].body);
                }
            }
            self.pc = pc;
            for r in ch.left.iter().flatten() {
                self.write_reg(*r, Word::constant(0, 1));
            }
        } else {
            // Bodies in declaration order of the actions.
            run.sort_by_key(|r| r.0);
            for (act, a) in run {
                if a == Lit::FALSE {
                    continue;
                }
                self.pc = self.g.and(pc, a);
                self.run_action(ch.inst, &chart.actions[act].name, &chart.actions[act].body);
            }
        }
        self.pc = pc;
    }

    /// A duration as a TIME word (µs).
    fn duration_word(&mut self, d: Option<&DurEnc>) -> Word {
        match d {
            None => Word::constant(0, 64),
            Some(DurEnc::Literal(us)) => Word::constant(*us as i128, 64),
            Some(DurEnc::Reg(r)) => {
                let r = *r;
                let w = self.mem[r].clone();
                w.resize(64, self.regs[r].signed)
            }
            Some(DurEnc::Unknown) => {
                self.note("an association duration that is not a TIME variable is free");
                self.fresh("association duration", 64, true, None)
            }
        }
    }

    /// An ACTION_CONTROL timer: `Q = elapsed ≥ PT`, the elapsed time counted from the scan the
    /// input was first seen TRUE. Updates the timer registers.
    fn ton(&mut self, regs: Option<super::chart::TimerRegs>, input: Lit, pt: Option<&Word>, period: i64) -> Lit {
        let Some(tr) = regs else { return Lit::FALSE };
        let pt = pt.cloned().unwrap_or_else(|| Word::constant(0, 64));
        let running = self.bool_reg(tr.running);
        let count = self.mem[tr.count].clone();
        // Not running: the timer starts now with elapsed 0.
        let zero = Word::constant(0, count.width());
        let el = self.ops().ite(running, &count, &zero);
        let q = self.elapsed_ge(&el, &pt, period, tr.count);
        let out = self.g.and(input, q);
        let new_count = self.ops().ite(input, &el, &zero);
        self.write_reg(tr.running, Word::from_bit(input, 1));
        self.write_reg(tr.count, new_count);
        out
    }

    /// `count · Δ ≥ pt` for a saturating counter register `creg` (exact below the bound; at the
    /// bound the real time is at least `bound · Δ`).
    pub(crate) fn elapsed_ge(&mut self, count: &Word, pt: &Word, period: i64, creg: usize) -> Lit {
        let bound = self.regs[creg].range.map_or(super::MAX_COUNT as i128, |r| r.1);
        if let Some(k) = pt.as_const(true) {
            if k <= 0 {
                return Lit::TRUE;
            }
            let need = (k + period as i128 - 1) / period as i128;
            if need > bound {
                // The bound is too small for this duration (an early pass): never reached.
                return Lit::FALSE;
            }
            let c = Word::constant(need, count.width());
            return self.ops().ult(count, &c).not();
        }
        let w = 96;
        let cw = count.resize(w, false);
        let p = Word::constant(period as i128, w);
        let t = self.ops().mul(&cw, &p);
        let ptw = pt.resize(w, true);
        let lt = self.ops().slt(&t, &ptw);
        let exact = lt.not();
        // At the bound the elapsed time may be larger than `bound · Δ`.
        let (_, hi) = pt.bounds(true);
        if hi > bound * period as i128 {
            self.note("a timer's duration may exceed the modelled bound; beyond it the timer is free");
            let sat = {
                let b = Word::constant(bound, count.width());
                self.ops().eq(count, &b)
            };
            let free = self.fresh("timer beyond its bound", 1, false, None).bits[0];
            let either = self.g_or(exact, free);
            return self.g.ite(sat, either, exact);
        }
        exact
    }

    fn g_or(&mut self, a: Lit, b: Lit) -> Lit {
        self.g.or(a, b)
    }

    /// Step 8's supervision: `S.T > timeout` of an active step sets SFCError once per activation.
    fn supervise(&mut self, c: usize) {
        let error = self.charts[c].flags.error;
        let ch = self.charts[c].clone();
        let chart = self.chart_of(c);
        let period = self.setup.period;
        let mut any = Lit::FALSE;
        for (s, step) in chart.steps.iter().enumerate() {
            let (Some(limit), Some(o), Some(t)) = (step.timeout, ch.overdue[s], ch.t[s]) else { continue };
            let x = self.bool_reg(ch.x[s]);
            let cw = self.mem[t].clone();
            // count·Δ > limit  ⇔  count ≥ ⌊limit/Δ⌋ + 1
            let need = (limit.max(-1) as i128).div_euclid(period as i128) + 1;
            let bound = self.regs[t].range.map_or(0, |r| r.1);
            let over = if need <= 0 {
                Lit::TRUE
            } else if need > bound {
                Lit::FALSE
            } else {
                let k = Word::constant(need, cw.width());
                self.ops().ult(&cw, &k).not()
            };
            let ov = self.bool_reg(o);
            let fire = {
                let a = self.g.and(x, over);
                self.g.and(a, ov.not())
            };
            if fire == Lit::FALSE {
                continue;
            }
            let nov = self.g.or(ov, fire);
            self.write_reg(o, Word::from_bit(nov, 1));
            any = self.g.or(any, fire);
        }
        if let Some(er) = error {
            if any != Lit::FALSE {
                let cur = self.bool_reg(er);
                let v = self.g.or(cur, any);
                self.write_reg(er, Word::from_bit(v, 1));
            }
        }
        let _ = Slot::Opaque(Type::Bool);
    }

    /// `S.X` of chart `c`.
    pub(crate) fn step_x(&self, c: usize, s: usize) -> Lit {
        self.mem[self.charts[c].x[s]].bits[0]
    }

    /// The counter of step `s` of chart `c`, if its time is modelled.
    pub(crate) fn step_time_count(&self, c: usize, s: usize) -> Option<Word> {
        self.step_count(c, s)
    }
}
