//! The networks of the program, in scan order (see the module doc of `stl`).

use super::emit::{Contact, Sink};
use super::ir::{Addr, Area, Ins, Op, Val};
use super::logic::{fmt_time, Logic, TimerUse};
use super::{Gen, StlMethod};
use sfc_model::{Qualifier, StepId};
use sfc_syntax::ast;
use std::fmt::Write as _;

impl Gen<'_> {
    pub(super) fn emit(&mut self) {
        self.first_scan_network();
        self.timer_network();
        self.quit_network();
        self.transition_networks();
        match self.method {
            StlMethod::SetReset => self.step_networks(),
            StlMethod::Scr => self.scr_networks(),
        }
        for i in 0..self.entities.len() {
            self.control_network(i);
        }
        self.body_networks();
        self.supervision_network();
    }

    /// `SM0.1`: clear the steps, the action memories, timers and counters; initial values.
    fn first_scan_network(&mut self) {
        let mut code = vec![Ins::on(Op::Ld, Addr::FIRST_SCAN, "first scan = IEC scan 0")];
        let steps: Vec<(Addr, String)> =
            self.steps.iter().enumerate().map(|(s, &a)| (a, self.step_name(s).to_string())).collect();
        reset_runs(&steps, false, "steps (initial ones are set after the transitions)", &mut code);
        let mut clear = Vec::new();
        let mut set = Vec::new();
        let mut words = Vec::new();
        for v in &self.vars.list {
            if v.is_input() || v.retain {
                continue;
            }
            if let Some(a) = v.addr {
                if matches!(v.init, Some(sfc_st::Value::Bool(true))) {
                    set.push((a, v.name.clone()));
                } else {
                    clear.push((a, v.name.clone()));
                }
            }
            if let (Some(val), Some(ty)) = (v.val, v.int_ty()) {
                let init = match v.init {
                    Some(sfc_st::Value::Int(i)) => ty.stored(i),
                    _ => 0,
                };
                words.push(Ins::vals(Op::Mov(ty.wide()), &[Val::Const(init), val], v.name.clone()));
            }
        }
        reset_runs(&clear, false, "variables, initial value FALSE", &mut code);
        reset_runs(&set, true, "variables, initial value TRUE", &mut code);
        let mut flags = Vec::new();
        for e in &self.entities {
            for (bit, what) in [
                (e.q, "Q"),
                (e.a, "A"),
                (e.s_ff, "S"),
                (e.sd_ff, "SD"),
                (e.ds_ff, "DS"),
                (e.sl_ff, "SL"),
                (e.pulse, "P"),
            ] {
                if let Some(b) = bit {
                    flags.push((b, format!("{}.{what}", e.name)));
                }
            }
        }
        for (s, sup) in self.supervised.iter().enumerate() {
            if let Some(sup) = sup {
                flags.push((sup.overdue, format!("{}.overdue", self.step_name(s))));
            }
        }
        for c in &self.counters.list {
            if let Some(qd) = c.qd {
                flags.push((qd, format!("{}.QD", self.vars.list[c.var].name)));
            }
        }
        reset_runs(&flags, false, "action control memories", &mut code);
        code.extend(words);
        let mut numbers: Vec<(u16, usize)> = self.timer_numbers.iter().enumerate().map(|(i, &n)| (n, i)).collect();
        numbers.sort_unstable();
        for run in runs(&numbers) {
            code.push(Ins::count(Op::Reset, Addr::Timer(run.0), run.1, "timers"));
        }
        let counters: Vec<(u16, usize)> = self.counter_numbers.iter().enumerate().map(|(i, &n)| (n, i)).collect();
        for run in runs(&counters) {
            code.push(Ins::count(Op::Reset, Addr::Counter(run.0), run.1, "counters"));
        }
        self.push_network(
            "first scan (SM0.1 = IEC scan 0): clear steps, action memories, timers, counters; initial values".into(),
            code,
        );
    }

    /// Every timer instruction, each exactly once per scan, before anything reads a timer: an
    /// S7-200 100 ms timer adds the time base's intervals since the previous scan at every
    /// execution. A step timer runs on its step bit; the timer of a timed qualifier on its
    /// input as the previous scan left it (action control ANDs the bit with the current input).
    fn timer_network(&mut self) {
        let mut code = Vec::new();
        self.emitter.new_network();
        for i in 0..self.timers.list.len() {
            let t = self.timers.list[i].clone();
            let input = match t.what {
                TimerUse::Step(s) => self.step_bit(s),
                TimerUse::Action(k) => self.timer_input(k),
            };
            self.emitter.logic(&input, &mut code);
            let op = if t.retentive { Op::Tonr } else { Op::Ton };
            code.push(Ins::boxed(op, Addr::Timer(i), Val::Const(i64::from(t.pt)), t.label.clone()));
        }
        self.push_network("timers: each executed exactly once per scan, before anything reads them".into(), code);
    }

    /// The input of the timer of entity `k`'s timed qualifier.
    fn timer_input(&self, k: usize) -> Logic {
        let e = &self.entities[k];
        let Some((q, _, _)) = e.timed else { return Logic::Const(false) };
        match q {
            Qualifier::SD => e.sd_ff.map_or(Logic::Const(false), |b| Logic::bit(b, format!("{}.SD", e.name))),
            Qualifier::SL => e.sl_ff.map_or(Logic::Const(false), |b| Logic::bit(b, format!("{}.SL", e.name))),
            _ => self.steps_with(k, q),
        }
    }

    /// OR of the step bits that associate entity `k` with qualifier `q`.
    fn steps_with(&self, k: usize, q: Qualifier) -> Logic {
        Logic::any(self.entities[k].steps_with(q).iter().map(|&s| self.step_bit(s)).collect())
    }

    /// `SFCQuitError` acknowledges `SFCError` before the transitions read it.
    fn quit_network(&mut self) {
        let (Some(q), Some(e)) = (self.sfc_quit, self.sfc_error) else { return };
        let (Some(qa), Some(ea)) = (self.vars.list[q].addr, self.vars.list[e].addr) else { return };
        let code = vec![
            Ins::on(Op::Ld, qa, self.vars.list[q].name.clone()),
            Ins::count(Op::Reset, ea, 1, self.vars.list[e].name.clone()),
        ];
        self.push_network("SFCQuitError acknowledges SFCError".into(), code);
    }

    /// The fire bit of every transition, in conflict order.
    fn transition_networks(&mut self) {
        let chart = self.chart;
        let mut order: Vec<usize> = (0..chart.transitions.len()).collect();
        order.sort_by_key(|&t| match chart.transitions[t].priority {
            Some(p) => (0, p, t),
            None => (1, 0, t),
        });
        let mut rank = vec![0; order.len()];
        for (k, &t) in order.iter().enumerate() {
            rank[t] = k;
        }
        let adj = chart.adjacency();
        for &t in &order {
            let tr = &chart.transitions[t];
            let Some(guard) = self.guards.get(t).cloned().flatten() else { continue };
            let mut items: Vec<Logic> = tr.from.iter().map(|&s| self.step_bit(s)).collect();
            items.push(guard);
            // Transitions earlier in conflict order that share a step with this one.
            let mut before: Vec<usize> =
                tr.from.iter().flat_map(|&s| adj.outgoing[s].iter().copied()).filter(|&u| rank[u] < rank[t]).collect();
            before.sort_by_key(|&u| rank[u]);
            before.dedup();
            for u in before {
                items.push(self.fire_bit(u).not());
            }
            let mut code = Vec::new();
            self.emitter.new_network();
            self.emitter.logic(&Logic::And(items), &mut code);
            code.push(Ins::on(Op::Out, self.fires[t], format!("{} fires", tr.name)));
            let mut title = format!("transition {}: {} -> {}", tr.name, self.names(&tr.from), self.names(&tr.to));
            if let Some(p) = tr.priority {
                let _ = write!(title, " (PRIORITY {p})");
            }
            let cond = match &tr.condition {
                ast::Condition::St(e) => Some(e.span),
                ast::Condition::Il(b) => Some(b.span),
                ast::Condition::Missing => None,
            };
            if let Some(span) = cond {
                let _ = write!(title, " := {}", super::snippet(&self.checked.file.text, span));
            }
            self.push_network(title, code);
        }
    }

    fn names(&self, v: &[StepId]) -> String {
        v.iter().map(|&s| self.step_name(s)).collect::<Vec<_>>().join(", ")
    }

    /// What entering step `s` restarts: its timers and its supervision flag.
    fn entry_resets(&self, s: StepId, code: &mut Vec<Ins>) {
        let name = self.step_name(s);
        for (i, t) in self.timers.list.iter().enumerate() {
            if t.what == TimerUse::Step(s) {
                code.push(Ins::count(Op::Reset, Addr::Timer(i), 1, format!("{name}.T restarts")));
            }
        }
        if let Some(sup) = self.supervised[s] {
            code.push(Ins::count(Op::Reset, sup.overdue, 1, format!("{name}.overdue")));
        }
    }

    /// The transitions entering step `s` (and the first scan for an initial step).
    fn entering(&self, s: StepId) -> Vec<Logic> {
        let adj = self.chart.adjacency();
        let mut v: Vec<Logic> = adj.incoming[s].iter().map(|&t| self.fire_bit(t)).collect();
        if self.chart.steps[s].initial {
            v.insert(0, Logic::bit(Addr::FIRST_SCAN, "first scan"));
        }
        v
    }

    /// Set/reset: each step is reset by the transitions leaving it, then set by those
    /// entering it; its timers restart on entry.
    fn step_networks(&mut self) {
        let chart = self.chart;
        let adj = chart.adjacency();
        for (s, step) in chart.steps.iter().enumerate() {
            let bit = self.steps[s];
            let mut code = Vec::new();
            self.emitter.new_network();
            let leaving: Vec<Logic> = adj.outgoing[s].iter().map(|&t| self.fire_bit(t)).collect();
            if !leaving.is_empty() {
                self.emitter.logic(&Logic::any(leaving), &mut code);
                code.push(Ins::count(Op::Reset, bit, 1, format!("leave {}", step.name)));
            }
            let entering = self.entering(s);
            if !entering.is_empty() {
                self.emitter.logic(&Logic::any(entering), &mut code);
                code.push(Ins::count(Op::Set, bit, 1, format!("enter {}", step.name)));
                self.entry_resets(s, &mut code);
            }
            let mut title = format!("step {}", step.name);
            if step.initial {
                title.push_str(" (initial)");
            }
            if let Some(limit) = step.timeout {
                let _ = write!(title, "; supervised: sfc.timeout {}", fmt_time(limit));
            }
            self.push_network(title, code);
        }
    }

    /// SCR: one segment per step with transitions; a transition lives in the segment of its
    /// first preceding step and moves the token on its fire bit: `SCRT` to each following step
    /// (it resets the segment's own bit), `R` of its other preceding steps. A transition back
    /// into its own first step sets the other following steps with `S` (an `SCRT` to the
    /// segment's own bit has no documented order of set and reset). After the segments, a step
    /// that a later segment could reset after an earlier one entered it is set again
    /// (`X' = (X \ D) ∪ A`), the initial steps are set in the first scan, and an entered step
    /// restarts its timers.
    fn scr_networks(&mut self) {
        let chart = self.chart;
        let first = |t: usize| chart.transitions[t].from.first().copied();
        for (s, step) in chart.steps.iter().enumerate() {
            let own: Vec<usize> = (0..chart.transitions.len()).filter(|&t| first(t) == Some(s)).collect();
            if own.is_empty() {
                continue;
            }
            let bit = self.steps[s];
            let mut title = format!("step {} (SCR segment)", step.name);
            if step.initial {
                title.push_str(", initial");
            }
            if let Some(limit) = step.timeout {
                let _ = write!(title, "; supervised: sfc.timeout {}", fmt_time(limit));
            }
            self.push_network(title, vec![Ins::on(Op::Lscr, bit, step.name.clone())]);
            for t in own {
                let tr = &chart.transitions[t];
                if self.guards.get(t).cloned().flatten().is_none() {
                    continue;
                }
                let mut code = vec![Ins::on(Op::Ld, self.fires[t], format!("{} fires", tr.name))];
                let stays = tr.to.contains(&s);
                for &n in &tr.to {
                    if n == s {
                        continue;
                    }
                    let op = if stays { Op::Set } else { Op::Scrt };
                    let note = format!("enter {}", self.step_name(n));
                    code.push(if stays {
                        Ins::count(op, self.steps[n], 1, note)
                    } else {
                        Ins::on(op, self.steps[n], note)
                    });
                }
                for &p in tr.from.iter().skip(1) {
                    if !tr.to.contains(&p) {
                        code.push(Ins::count(Op::Reset, self.steps[p], 1, format!("leave {}", self.step_name(p))));
                    }
                }
                if code.len() == 1 {
                    code.push(Ins::count(Op::Set, bit, 1, format!("{} stays active", step.name)));
                }
                let title = format!("  transition {}: {} -> {}", tr.name, self.names(&tr.from), self.names(&tr.to));
                self.push_network(title, code);
            }
            self.push_network(format!("end of segment {}", step.name), vec![Ins::bare(Op::Scre)]);
        }
        // Where each transition's segment is. With one token per network (no simultaneous
        // branch) a step cannot be entered and left in one scan by different transitions, so
        // no step needs setting again.
        let pos = |t: usize| first(t).unwrap_or(0);
        let single_token = chart.transitions.iter().all(|t| t.from.len() == 1 && t.to.len() == 1);
        for (s, step) in chart.steps.iter().enumerate() {
            let incoming = chart.incoming(s);
            let reset_later = !single_token
                && incoming.iter().any(|&t_in| {
                    (0..chart.transitions.len()).any(|t_out| {
                        t_out != t_in
                            && chart.transitions[t_out].from.contains(&s)
                            && !chart.transitions[t_out].to.contains(&s)
                            && pos(t_out) > pos(t_in)
                    })
                });
            let mut code = Vec::new();
            self.emitter.new_network();
            let mut why = Vec::new();
            if reset_later {
                self.emitter.logic(&Logic::any(self.entering(s)), &mut code);
                code.push(Ins::count(Op::Set, self.steps[s], 1, format!("enter {}", step.name)));
                why.push("set again: a later segment may reset it in the scan it is entered");
            } else if step.initial {
                code.push(Ins::on(Op::Ld, Addr::FIRST_SCAN, "first scan"));
                code.push(Ins::count(Op::Set, self.steps[s], 1, format!("enter {}", step.name)));
                why.push("initial step, set in the first scan");
            }
            let mut resets = Vec::new();
            self.entry_resets(s, &mut resets);
            if !resets.is_empty() && !incoming.is_empty() {
                let entered: Vec<Logic> = incoming.iter().map(|&t| self.fire_bit(t)).collect();
                self.emitter.logic(&Logic::any(entered), &mut code);
                code.extend(resets);
                why.push("restart its timers");
            }
            if why.is_empty() {
                continue;
            }
            self.push_network(format!("step {} entered: {}", step.name, why.join("; ")), code);
        }
    }

    /// ACTION_CONTROL of entity `i` (the simulator's `Control::update`, bit for bit).
    fn control_network(&mut self, i: usize) {
        let by_q: Vec<(Qualifier, Logic)> = Qualifier::ALL.iter().map(|&q| (q, self.steps_with(i, q))).collect();
        let st = |q: Qualifier| by_q.iter().find(|x| x.0 == q).map_or(Logic::Const(false), |x| x.1.clone());
        let e = &self.entities[i];
        let mut code = Vec::new();
        self.emitter.new_network();
        let (tq, _, us) = e.timed.unwrap_or((Qualifier::N, 0, 0));
        let timer = e.timer.map(Addr::Timer);
        let timer_of = |q: Qualifier| if tq == q { timer } else { None };
        let tbit = |t: Addr| Logic::bit(t, format!("{} {} timer", e.name, tq.name()));
        let mut parts: Vec<Logic> = Vec::new();
        let mut sets: Vec<(Logic, Addr, String)> = Vec::new();
        for (q, ff) in [(Qualifier::S, e.s_ff), (Qualifier::SD, e.sd_ff), (Qualifier::SL, e.sl_ff)] {
            if let Some(ff) = ff {
                sets.push((st(q), ff, format!("{}.{}", e.name, q.name())));
            }
        }
        if let Some(ff) = e.ds_ff {
            let input = match timer_of(Qualifier::DS) {
                Some(t) => Logic::And(vec![st(Qualifier::DS), tbit(t)]),
                None => st(Qualifier::DS),
            };
            sets.push((input, ff, format!("{}.DS", e.name)));
        }
        for (l, ff, note) in sets {
            self.emitter.logic(&l, &mut code);
            code.push(Ins::count(Op::Set, ff, 1, note));
        }
        let e = &self.entities[i];
        let ffs: Vec<(Addr, &str)> = [(e.s_ff, "S"), (e.sd_ff, "SD"), (e.ds_ff, "DS"), (e.sl_ff, "SL")]
            .into_iter()
            .filter_map(|(b, n)| b.map(|b| (b, n)))
            .collect();
        if e.has(Qualifier::R) && !ffs.is_empty() {
            self.emitter.logic(&st(Qualifier::R), &mut code);
            for (b, n) in &ffs {
                code.push(Ins::count(Op::Reset, *b, 1, format!("{}.{n} (R dominates)", e.name)));
            }
        }
        if let Some(p) = e.pulse {
            self.emitter.logic(&st(Qualifier::P), &mut code);
            code.push(Ins::bare(Op::Eu));
            code.push(Ins::on(Op::Out, p, format!("{}.P pulse", e.name)));
        }
        // Q := NOT R AND (N OR L_act OR D_act OR P OR S_FF OR SD_act OR DS_FF OR SL_act)
        if e.has(Qualifier::N) {
            parts.push(st(Qualifier::N));
        }
        if e.has(Qualifier::L) {
            if let Some(t) = timer_of(Qualifier::L) {
                parts.push(Logic::And(vec![st(Qualifier::L), tbit(t).not()]));
            }
        }
        if e.has(Qualifier::D) {
            parts.push(match timer_of(Qualifier::D) {
                Some(t) => Logic::And(vec![st(Qualifier::D), tbit(t)]),
                None => st(Qualifier::D),
            });
        }
        if let Some(p) = e.pulse {
            parts.push(Logic::bit(p, format!("{}.P pulse", e.name)));
        }
        if let Some(b) = e.s_ff {
            parts.push(Logic::bit(b, format!("{}.S", e.name)));
        }
        if let Some(b) = e.sd_ff {
            let ff = Logic::bit(b, format!("{}.SD", e.name));
            parts.push(match timer_of(Qualifier::SD) {
                Some(t) => Logic::And(vec![ff, tbit(t)]),
                None => ff,
            });
        }
        if let Some(b) = e.ds_ff {
            parts.push(Logic::bit(b, format!("{}.DS", e.name)));
        }
        if let (Some(b), Some(t)) = (e.sl_ff, timer_of(Qualifier::SL)) {
            parts.push(Logic::And(vec![Logic::bit(b, format!("{}.SL", e.name)), tbit(t).not()]));
        }
        let q = Logic::And(vec![Logic::any(parts), st(Qualifier::R).not()]);
        self.emitter.logic(&q, &mut code);
        let e = &self.entities[i];
        if let Some(target) = e.var_bit.or(e.q) {
            let note = if e.action.is_some() { format!("{}.Q", e.name) } else { e.name.clone() };
            code.push(Ins::on(Op::Out, target, note));
        }
        if let (Some(qb), Some(ab)) = (e.q, e.a) {
            // A := Q OR (Q fell: the final scan) OR P1 rising OR P0 falling.
            let qn = format!("{}.Q", e.name);
            code.push(Ins::on(Op::Ld, qb, qn.clone()));
            code.push(Ins::bare(Op::Ed));
            code.push(Ins::on(Op::O, qb, qn));
            let edges: Vec<(Qualifier, Op)> = [(Qualifier::P1, Op::Eu), (Qualifier::P0, Op::Ed)]
                .into_iter()
                .filter(|(q, _)| self.entities[i].has(*q))
                .collect();
            for (q, edge) in edges {
                self.emitter.logic(&st(q), &mut code);
                code.push(Ins::bare(edge));
                code.push(Ins::bare(Op::Old));
            }
            let e = &self.entities[i];
            code.push(Ins::on(Op::Out, ab, format!("{}.A", e.name)));
        }
        let e = &self.entities[i];
        let mut quals: Vec<String> = Vec::new();
        for (s, q) in &e.assocs {
            let mut t = format!("{} in {}", q.name(), self.chart.steps[*s].name);
            if q.is_timed() {
                let _ = write!(t, " ({})", fmt_time(us));
            }
            if !quals.contains(&t) {
                quals.push(t);
            }
        }
        let kind = if e.action.is_some() { "" } else { " (BOOL variable)" };
        let title = format!("action {}{kind}: {}", e.name, quals.join(", "));
        self.push_network(title, code);
    }

    /// The statements of each action body under the action's `A`, one network (or more, for a
    /// counter call) per statement.
    fn body_networks(&mut self) {
        let mut sink = Sink::default();
        for k in 0..self.entities.len() {
            let Some(a) = self.entities[k].a else { continue };
            let name = self.entities[k].name.clone();
            let ops = std::mem::take(&mut self.entities[k].body);
            for op in &ops {
                let text = match op {
                    super::logic::BodyOp::Assign { text, .. }
                    | super::logic::BodyOp::Move { text, .. }
                    | super::logic::BodyOp::If { text, .. }
                    | super::logic::BodyOp::Count { text, .. } => text.clone(),
                };
                sink.start(format!("body of {name} (while {name}.A): {text}"));
                self.emitter.new_network();
                let mut enable: Vec<Contact> = vec![(a, false, format!("{name}.A"))];
                self.emitter.body(std::slice::from_ref(op), &mut enable, &mut sink);
            }
            self.entities[k].body = ops;
        }
        sink.flush();
        for n in sink.networks {
            self.push_network(n.title, n.code);
        }
    }

    /// A step active longer than its `sfc.timeout` sets `SFCError`, once per activation.
    fn supervision_network(&mut self) {
        let Some(err) = self.sfc_error.and_then(|i| self.vars.list[i].addr) else { return };
        let mut code = Vec::new();
        for (s, sup) in self.supervised.iter().enumerate() {
            let Some(sup) = sup else { continue };
            let name = self.step_name(s).to_string();
            code.push(Ins::on(Op::Ld, self.steps[s], name.clone()));
            code.push(Ins::on(Op::A, Addr::Timer(sup.timer), format!("{name}.T > {}", fmt_time(sup.limit))));
            code.push(Ins::on(Op::An, sup.overdue, format!("{name}.overdue")));
            code.push(Ins::count(Op::Set, err, 1, "SFCError"));
            code.push(Ins::count(Op::Set, sup.overdue, 1, format!("{name}.overdue")));
        }
        self.push_network("supervision (sfc.timeout): a step active too long sets SFCError".into(), code);
    }
}

/// `R first, n` (or `S`) over runs of consecutive bits of one area.
fn reset_runs(bits: &[(Addr, String)], set: bool, what: &str, code: &mut Vec<Ins>) {
    let mut sorted: Vec<(Area, u32, &str)> =
        bits.iter().filter_map(|(a, n)| a.linear().map(|(area, k)| (area, k, n.as_str()))).collect();
    sorted.sort_unstable();
    sorted.dedup_by_key(|x| (x.0, x.1));
    let mut i = 0;
    while i < sorted.len() {
        let mut j = i + 1;
        while j < sorted.len() && sorted[j].0 == sorted[i].0 && sorted[j].1 == sorted[j - 1].1 + 1 && j - i < 255 {
            j += 1;
        }
        let n = (j - i) as u16;
        let note = if n == 1 { sorted[i].2.to_string() } else { what.to_string() };
        let op = if set { Op::Set } else { Op::Reset };
        code.push(Ins::count(op, Addr::from_linear(sorted[i].0, sorted[i].1), n, note));
        i = j;
    }
}

/// Runs of consecutive numbers (sorted `(number, table index)`): `(table index of the first,
/// length)`.
fn runs(sorted: &[(u16, usize)]) -> Vec<(usize, u16)> {
    let mut out = Vec::new();
    let mut i = 0;
    while i < sorted.len() {
        let mut j = i + 1;
        while j < sorted.len() && sorted[j].0 == sorted[j - 1].0 + 1 && j - i < 255 {
            j += 1;
        }
        out.push((sorted[i].1, (j - i) as u16));
        i = j;
    }
    out
}
