//! One scan of an SFC instance (`semantics.md` steps 2–8, `docs/sim.md` chart control
//! variables), symbolically: step times, enabled and true transitions against one snapshot,
//! conflict resolution by priority and declaration order, firing, ACTION_CONTROL of every action
//! with its timers and the contention rule, action bodies in declaration order, supervision.

use super::{Enc, Role, Slot};
use crate::aig::Lit;
use crate::word::Word;
use sfc_model::{ActionTarget, Duration, Qualifier};
use sfc_st::Type;

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

/// The symbolic state of one SFC instance.
#[derive(Debug, Clone)]
pub struct ChartEnc {
    pub inst: usize,
    /// Index into `Checked::charts`.
    pub chart: usize,
    pub path: String,
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
}

impl ChartEnc {
    /// The key of step `s`'s time counter in the plan.
    pub fn time_key(path: &str, step: &str) -> String {
        format!("{}{}#T", if path.is_empty() { String::new() } else { format!("{path}.") }, step).to_ascii_uppercase()
    }

    pub(crate) fn new(e: &mut Enc<'_>, inst: usize, chart_idx: usize, path: &str) -> ChartEnc {
        let chart = &e.checked.charts[chart_idx];
        let qual = |n: &str| if path.is_empty() { n.to_string() } else { format!("{path}.{n}") };
        let started = e.new_reg(
            format!("{} (chart started)", if path.is_empty() { chart.pou.clone() } else { path.to_string() }),
            Type::Bool,
            Role::Hidden,
            0,
            None,
        );
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
        let gap = if path.is_empty() {
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
        ChartEnc { inst, chart: chart_idx, path: path.to_string(), started, x, t, overdue, gap, entities, q, a }
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

    fn control_var(&self, c: usize, name: &str) -> Option<usize> {
        self.instance_reg(self.charts[c].inst, name)
    }

    /// One call of chart instance `c` (the top chart once per scan, a nested one per call of
    /// its instance), under the current path condition.
    pub(crate) fn run_chart(&mut self, c: usize, top: bool) {
        let ch = self.charts[c].clone();
        let chart = self.chart_of(c);
        let outer_pc = self.pc;
        let init = self.control_var(c, "SFCInit").map_or(Lit::FALSE, |r| self.bool_reg(r));
        let pause = self.control_var(c, "SFCPause").map_or(Lit::FALSE, |r| self.bool_reg(r));
        let quit = self.control_var(c, "SFCQuitError").map_or(Lit::FALSE, |r| self.bool_reg(r));
        let error = self.control_var(c, "SFCError");
        // The time elapsed since the previous call, in scans.
        let delta = match ch.gap {
            Some(g) => {
                let d = self.mem[g].clone();
                self.write_reg(g, Word::constant(0, d.width()));
                d
            }
            None => Word::constant(1, 2),
        };
        // SFCInit: back to the initial situation and hold it.
        let pc_init = self.g.and(outer_pc, init);
        if pc_init != Lit::FALSE {
            self.pc = pc_init;
            let started = self.bool_reg(ch.started);
            let any = self.g.or_all(ch.x.iter().map(|&r| self.mem[r].bits[0]));
            let held = self.g.and(started.not(), any);
            self.pc = self.g.and(pc_init, held.not());
            self.reset_chart(c);
        }
        let pc_run = self.g.and(outer_pc, init.not());
        self.pc = pc_run;
        if let Some(er) = error {
            let p = self.g.and(pc_run, quit);
            self.pc = p;
            self.write_reg(er, Word::constant(0, 1));
            self.pc = pc_run;
        }
        let started = self.bool_reg(ch.started);
        // First call: activate the initial steps.
        let pc_first = self.g.and(pc_run, started.not());
        if pc_first != Lit::FALSE {
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
        // Later calls: the evolution, unless paused.
        let pc_evolve = {
            let a = self.g.and(pc_run, started);
            self.g.and(a, pause.not())
        };
        if pc_evolve != Lit::FALSE {
            self.pc = pc_evolve;
            self.evolve(c, &delta, top);
        }
        self.pc = pc_run;
        self.action_phase(c);
        self.pc = pc_run;
        self.supervise(c, error);
        self.pc = outer_pc;
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
        if let Some(er) = self.control_var(c, "SFCError") {
            self.write_reg(er, Word::constant(0, 1));
        }
        self.write_reg(ch.started, Word::constant(0, 1));
    }

    /// Steps 2–5 of a scan under the current path condition.
    fn evolve(&mut self, c: usize, delta: &Word, _top: bool) {
        let ch = self.charts[c].clone();
        let chart = self.chart_of(c);
        let pc = self.pc;
        // Step times advance for the active steps.
        for s in 0..chart.steps.len() {
            if let Some(t) = ch.t[s] {
                let x = self.bool_reg(ch.x[s]);
                let cw = self.mem[t].clone();
                let inc = self.sat_inc(&cw, delta, t);
                let w = self.ops().ite(x, &inc, &cw);
                self.write_reg(t, w);
            }
        }
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
        // Conflicts: explicit priorities first (ascending), then declaration order.
        let mut order: Vec<usize> = (0..n).collect();
        order.sort_by_key(|&t| match chart.transitions[t].priority {
            Some(p) => (0u8, p, t),
            None => (1u8, 0, t),
        });
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
    }

    /// Steps 6–7: ACTION_CONTROL of every entity, then the bodies with `A` in declaration order.
    fn action_phase(&mut self, c: usize) {
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
        // Bodies in declaration order of the actions.
        run.sort_by_key(|r| r.0);
        let pc = self.pc;
        for (act, a) in run {
            if a == Lit::FALSE {
                continue;
            }
            self.pc = self.g.and(pc, a);
            let body = &chart.actions[act].body;
            self.run_action_body(ch.inst, body);
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
    fn supervise(&mut self, c: usize, error: Option<usize>) {
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
