//! Siemens S7-200 statement list (STL, Micro/WIN style) from a chart, for `--target stl`.
//!
//! # Method: set/reset with transition bits, not SCR
//!
//! The S7-200 SCR instructions (`LSCR`/`SCRT`/`SCRE`) cannot give the `iec` semantics of
//! `semantics.md`: `SCRT` sets the next step's S bit at once, so a segment further down the
//! program runs in the same scan (two evolutions in one scan), later transitions see the new
//! situation instead of the scan's snapshot, and a simultaneous convergence (several steps left
//! together) has no SCR form. The program therefore uses the set/reset method, in this order
//! every scan:
//!
//! 1. **First scan** (`SM0.1`): every step bit, action memory and timer is cleared and every
//!    BOOL variable that is not an input gets its declared initial value.
//! 2. **Step times**: the timer of each step-time comparison runs on its step bit (below).
//! 3. **Transitions**, in conflict order (explicit `PRIORITY` ascending, then declaration
//!    order): one M bit per transition, `fire := pre-steps AND guard AND NOT (fire bit of every
//!    transition earlier in that order that shares a pre-step)`. Every guard reads the step bits
//!    and variables as they are at this point, so all guards see one snapshot, and a step is
//!    consumed by at most one transition while parallel branches fire together.
//! 4. **Steps**, one network each: reset by the fire bits of the transitions leaving it, then
//!    set by those entering it (an initial step also by `SM0.1`), so a re-entered step stays
//!    active; its timers restart when it is entered and run again on the new step bit.
//! 5. **Action control** (IEC ACTION_CONTROL) of every action and BOOL variable used as an
//!    action, from the new step bits: N, S/R (reset dominant), P (`EU`), L/D/SD/DS/SL (TON),
//!    P1/P0 (`EU`/`ED`) and the final scan (`ED` of `Q`).
//! 6. **Action bodies** in declaration order, each statement under the action's `A` bit.
//!
//! One evolution per scan follows: a step set in step 4 is read by its outgoing transitions
//! only in the next scan.
//!
//! # Scan 0
//! The S7-200 has no separate initialisation scan: its first scan *is* IEC scan 0. In it the
//! step bits are all clear while the transitions are computed (so none fires), `SM0.1` then
//! sets the initial steps, and the actions see them rise, so P, P1, L, … on an initial step act
//! in the first scan exactly as in the simulator. PLC scan `k` therefore corresponds to
//! simulator scan `k`, at time `k · period`.
//!
//! # Timers
//! 100 ms timers only (`T37`–`T63`, `T101`–`T255` as TON; `T5`–`T31`, `T69`–`T95` as TONR): the
//! 1 ms and 10 ms timers are too few (10 in all) and update asynchronously to the scan.
//! `S.T >= c` is the bit of a timer with preset `c / 100 ms` on the step bit; `S.T > c` uses the
//! preset `c/100 ms + 1` (a step time advances in whole timer ticks); `<` and `<=` are the
//! negated contacts; `=` and `<>` combine the two. `c` must be a constant (literal or CONSTANT)
//! multiple of 100 ms up to 3276.7 s. A step whose time is read only by the transitions leaving
//! it uses a TON (only its active value matters); one whose time is read elsewhere (a guard of
//! another transition, an action body) uses a TONR, which keeps the frozen value of an inactive
//! step, reset by `R` when the step is entered. Each step timer is executed twice per scan: at
//! the top (so guards read the time elapsed up to this scan) and after its step bit changed (so
//! it starts in the scan of the activation, when `S.T` is `T#0s` in the simulator). The
//! program thus keeps `S.T` exact when the scan period is a multiple of 100 ms, and within one
//! timer tick otherwise. Durations of timed qualifiers obey the same rules (one TON per action).
//!
//! # Operands
//! Steps are S bits (`S0.0`–`S31.7`; beyond that M or V bits). BOOL variables `AT %IXb.i`,
//! `%QXb.i`, `%MXb.i` are `Ib.i`, `Qb.i`, `Mb.i`; every other BOOL variable gets a free M bit.
//! Transition bits, action memories and scratch bits take the next free M bits, then V bits.
//! The allocation table at the top of the output lists every address. Inputs (`VAR_INPUT`,
//! `VAR_IN_OUT`, anything in `%I`) are not initialised by the program: their value comes from
//! outside (the input image, or whoever writes the M bit); every other BOOL variable gets its
//! declared initial value in the first scan.
//!
//! # What is refused
//! Everything that is not BOOL logic over those bits: integer or REAL values, arithmetic,
//! function and function block calls, CASE/FOR/WHILE/REPEAT, timed qualifiers whose duration is
//! not a constant, two different timed associations of one action (the simulator's
//! `contention` rule has no fixed program form), the chart control variables (`SFCInit`, …).
//! Each gets an error (SFC0810–SFC0816) located on the element; nothing is dropped. Action
//! indicators are not code (the simulator ignores them too); `sfc.timeout` supervision is only
//! noted in a comment.

mod emit;
mod ir;
mod logic;
mod vars;

use emit::{Contact, Emitter};
use ir::{Addr, Area, Ins, Network, Op, Resolve};
use logic::{fmt_time, BodyOp, Logic, Lowerer, Site, TimerUse, Timers, MAX_PT};
use sfc_diagnostics::{Diagnostic, Span};
use sfc_model::{ActionTarget, Chart, Checked, Duration, Qualifier, StepId};
use sfc_syntax::ast::{self, Item};
use std::collections::{BTreeSet, HashSet};
use std::fmt::Write as _;
use vars::Vars;

/// Resolution of every timer the program uses (100 ms).
pub(crate) const TIMER_BASE_US: i64 = 100_000;

/// 100 ms TON/TOF timer numbers of the S7-200 (CPU 22x).
fn ton_numbers() -> impl Iterator<Item = u16> {
    (37..=63).chain(101..=255)
}
/// 100 ms TONR timer numbers.
fn tonr_numbers() -> impl Iterator<Item = u16> {
    (5..=31).chain(69..=95)
}

/// Builds the statement list of `chart` (one of `checked.charts`). Fails with the file's errors
/// when it has any, or with a located diagnostic for each part of the chart that S7-200 bit
/// logic cannot express.
pub fn build_stl(checked: &Checked, chart: &Chart) -> Result<String, Vec<Diagnostic>> {
    if checked.has_errors() {
        return Err(checked.diagnostics.iter().filter(|d| d.is_error()).cloned().collect());
    }
    let Some(Item::Pou(pou)) = checked.unit.items.get(chart.item) else {
        return Err(vec![Diagnostic::error(
            "SFC0810",
            chart.name_span,
            format!("the declaration of `{}` is not in the checked file", chart.pou),
        )]);
    };
    let mut g = Gen::new(checked, chart, pou);
    g.run();
    if g.diags.is_empty() {
        Ok(g.print())
    } else {
        sfc_diagnostics::sort(&mut g.diags);
        g.diags.dedup();
        Err(g.diags)
    }
}

/// An action or a BOOL variable used as an action: one ACTION_CONTROL block.
struct Entity {
    name: String,
    /// The ACTION, or `None` for a BOOL variable (whose bit is `var_bit`).
    action: Option<usize>,
    var_bit: Option<Addr>,
    /// Associations: step, qualifier.
    assocs: Vec<(StepId, Qualifier)>,
    /// The one timed qualifier and its preset (100 ms units; 0 = no delay).
    timed: Option<(Qualifier, i64)>,
    timer: Option<usize>,
    s_ff: Option<Addr>,
    sd_ff: Option<Addr>,
    ds_ff: Option<Addr>,
    sl_ff: Option<Addr>,
    pulse: Option<Addr>,
    /// `Q` and `A` bits of an ACTION.
    q: Option<Addr>,
    a: Option<Addr>,
    body: Vec<BodyOp>,
}

impl Entity {
    fn steps_with(&self, q: Qualifier) -> Vec<StepId> {
        let mut v: Vec<StepId> = self.assocs.iter().filter(|a| a.1 == q).map(|a| a.0).collect();
        v.dedup();
        v
    }
    fn has(&self, q: Qualifier) -> bool {
        self.assocs.iter().any(|a| a.1 == q)
    }
}

/// A row of the allocation table.
struct Row {
    addr: Addr,
    kind: &'static str,
    name: String,
    detail: String,
}

/// Hands out free bits: M first (skipping located ones), then V.
struct Pool {
    used_m: BTreeSet<u32>,
    next_m: u32,
    next_v: u32,
}

impl Pool {
    fn take(&mut self) -> Option<Addr> {
        let m_bits = (vars::last_byte(Area::M) + 1) * 8;
        while self.next_m < m_bits {
            let n = self.next_m;
            self.next_m += 1;
            if !self.used_m.contains(&n) {
                return Some(Addr::from_linear(Area::M, n));
            }
        }
        let v_bits = (vars::last_byte(Area::V) + 1) * 8;
        if self.next_v < v_bits {
            self.next_v += 1;
            return Some(Addr::from_linear(Area::V, self.next_v - 1));
        }
        None
    }
}

struct Gen<'a> {
    checked: &'a Checked,
    chart: &'a Chart,
    vars: Vars,
    diags: Vec<Diagnostic>,
    pool: Pool,
    steps: Vec<Addr>,
    fires: Vec<Addr>,
    /// `Q`/`A` bits by action.
    action_bits: Vec<Option<(Addr, Addr)>>,
    entities: Vec<Entity>,
    guards: Vec<Option<Logic>>,
    timers: Timers,
    /// Timer numbers by timer-table index.
    timer_numbers: Vec<u16>,
    temps: Vec<Addr>,
    networks: Vec<Network>,
    emitter: Emitter,
    exhausted: bool,
}

impl<'a> Gen<'a> {
    fn new(checked: &'a Checked, chart: &'a Chart, pou: &'a ast::Pou) -> Gen<'a> {
        let vars = Vars::collect(&checked.unit, pou);
        Gen {
            checked,
            chart,
            vars,
            diags: Vec::new(),
            pool: Pool { used_m: BTreeSet::new(), next_m: 0, next_v: 0 },
            steps: Vec::new(),
            fires: Vec::new(),
            action_bits: Vec::new(),
            entities: Vec::new(),
            guards: Vec::new(),
            timers: Timers::default(),
            timer_numbers: Vec::new(),
            temps: Vec::new(),
            networks: Vec::new(),
            emitter: Emitter::default(),
            exhausted: false,
        }
    }

    fn run(&mut self) {
        self.declarations();
        self.allocate_bits();
        self.build_entities();
        self.lower();
        if !self.diags.is_empty() {
            return;
        }
        self.allocate_timers();
        if !self.diags.is_empty() {
            return;
        }
        self.emit();
        self.allocate_temps();
    }

    fn take_bit(&mut self) -> Addr {
        match self.pool.take() {
            Some(a) => a,
            None => {
                if !self.exhausted {
                    self.exhausted = true;
                    self.diags.push(Diagnostic::error(
                        "SFC0815",
                        self.chart.name_span,
                        format!(
                            "`{}` needs more bits than the S7-200 bit memory M0.0–M31.7 and V0.0–V{}.7 hold",
                            self.chart.pou,
                            vars::last_byte(Area::V)
                        ),
                    ));
                }
                Addr::Bit(Area::V, 0, 0)
            }
        }
    }

    /// Located BOOL variables get their bit; declared chart control variables are refused.
    fn declarations(&mut self) {
        for i in 0..self.vars.list.len() {
            let v = &self.vars.list[i];
            if sfc_st::is_sfc_control_variable(&v.name) {
                let msg = format!(
                    "the chart control variable `{}` is not implemented by the S7-200 program (it would hold, \
                     pause or supervise the chart)",
                    v.name
                );
                self.diags.push(Diagnostic::error("SFC0816", v.span, msg).with_element(v.name.clone()));
                continue;
            }
            if !v.is_bit() {
                continue;
            }
            let Some(loc) = &v.location else { continue };
            match vars::bit_address(loc) {
                Ok(addr) => {
                    if let Some((Area::M, n)) = addr.linear() {
                        self.pool.used_m.insert(n);
                    }
                    self.vars.list[i].addr = Some(addr);
                }
                Err(msg) => {
                    let d = Diagnostic::error("SFC0814", loc.span, msg).with_element(v.name.clone());
                    self.diags.push(d);
                }
            }
        }
    }

    /// Bits of unlocated variables, steps, transitions, and the `Q`/`A` bits of actions.
    fn allocate_bits(&mut self) {
        for i in 0..self.vars.list.len() {
            let v = &self.vars.list[i];
            if v.is_bit() && v.location.is_none() && !sfc_st::is_sfc_control_variable(&v.name) {
                let a = self.take_bit();
                self.vars.list[i].addr = Some(a);
            }
        }
        let s_bits = (vars::last_byte(Area::S) + 1) * 8;
        for s in 0..self.chart.steps.len() {
            let a = if (s as u32) < s_bits { Addr::from_linear(Area::S, s as u32) } else { self.take_bit() };
            self.steps.push(a);
        }
        for _ in 0..self.chart.transitions.len() {
            let a = self.take_bit();
            self.fires.push(a);
        }
        let associated: BTreeSet<usize> = self
            .chart
            .steps
            .iter()
            .flat_map(|s| s.associations.iter())
            .filter_map(|a| match a.target {
                ActionTarget::Action(id) => Some(id),
                ActionTarget::Variable => None,
            })
            .collect();
        for id in 0..self.chart.actions.len() {
            let bits = if associated.contains(&id) {
                let q = self.take_bit();
                let a = self.take_bit();
                Some((q, a))
            } else {
                None
            };
            self.action_bits.push(bits);
        }
    }

    /// One entity per associated action (declaration order), then per BOOL variable used as
    /// an action (declaration order of the variables).
    fn build_entities(&mut self) {
        let chart = self.chart;
        let mut seen: HashSet<String> = HashSet::new();
        let mut order: Vec<(bool, usize, String)> = Vec::new();
        for step in &chart.steps {
            for a in &step.associations {
                let key = a.action.to_ascii_uppercase();
                if !seen.insert(key.clone()) {
                    continue;
                }
                let (is_var, idx) = match a.target {
                    ActionTarget::Action(id) => (false, id),
                    ActionTarget::Variable => (true, self.vars.get(&a.action).unwrap_or(usize::MAX)),
                };
                order.push((is_var, idx, key));
            }
        }
        order.sort_by_key(|(is_var, idx, _)| (*is_var, *idx));
        for (is_var, idx, key) in order {
            let (name, action, var_bit) = if is_var {
                match self.vars.list.get(idx) {
                    Some(v) => (v.name.clone(), None, v.addr),
                    None => (key.clone(), None, None),
                }
            } else {
                (chart.actions.get(idx).map(|a| a.name.clone()).unwrap_or_default(), Some(idx), None)
            };
            let (q, a) = match action.and_then(|id| self.action_bits.get(id).copied().flatten()) {
                Some((q, a)) => (Some(q), Some(a)),
                None => (None, None),
            };
            let mut e = Entity {
                name,
                action,
                var_bit,
                assocs: Vec::new(),
                timed: None,
                timer: None,
                s_ff: None,
                sd_ff: None,
                ds_ff: None,
                sl_ff: None,
                pulse: None,
                q,
                a,
                body: Vec::new(),
            };
            let mut first_timed: Option<(Qualifier, i64, Span)> = None;
            for (s, step) in chart.steps.iter().enumerate() {
                for assoc in step.associations.iter().filter(|x| x.action.eq_ignore_ascii_case(&key)) {
                    e.assocs.push((s, assoc.qualifier));
                    if !assoc.qualifier.is_timed() {
                        continue;
                    }
                    let Some(pt) = self.duration(assoc.duration.as_ref(), assoc.span, &e.name) else { continue };
                    match first_timed {
                        None => first_timed = Some((assoc.qualifier, pt, assoc.span)),
                        Some((q0, pt0, span0)) if (q0, pt0) != (assoc.qualifier, pt) => {
                            let msg = format!(
                                "`{}` already has the timed association {} with {} in another step; two different \
                                 timed associations of one action contend at run time, which the S7-200 program \
                                 does not reproduce",
                                e.name,
                                q0.name(),
                                fmt_time(pt0 * TIMER_BASE_US)
                            );
                            let d = Diagnostic::error("SFC0813", assoc.span, msg)
                                .with_element(e.name.clone())
                                .with_label(span0, "first timed association");
                            self.diags.push(d);
                        }
                        Some(_) => {}
                    }
                }
            }
            e.timed = first_timed.map(|(q, pt, _)| (q, pt));
            let need = |q: Qualifier| e.assocs.iter().any(|a| a.1 == q);
            let (s, sd, ds, sl, p) =
                (need(Qualifier::S), need(Qualifier::SD), need(Qualifier::DS), need(Qualifier::SL), need(Qualifier::P));
            e.s_ff = s.then(|| self.take_bit());
            e.sd_ff = sd.then(|| self.take_bit());
            e.ds_ff = ds.then(|| self.take_bit());
            e.sl_ff = sl.then(|| self.take_bit());
            e.pulse = p.then(|| self.take_bit());
            if is_var {
                self.check_variable_action(&e, &key);
            }
            if let Some((q, pt)) = e.timed {
                if pt > 0 {
                    let label = format!("{} {} {}", e.name, q.name(), fmt_time(pt * TIMER_BASE_US));
                    e.timer = Some(self.timers.action(self.entities.len(), pt as u16, label));
                }
            }
            self.entities.push(e);
        }
    }

    /// The preset of a timed association, in 100 ms units.
    fn duration(&mut self, d: Option<&Duration>, span: Span, element: &str) -> Option<i64> {
        let us = match d {
            Some(Duration::Literal(us)) => Some(*us),
            Some(Duration::Variable(name)) => match self.vars.get(name).and_then(|i| {
                let v = &self.vars.list[i];
                if v.constant {
                    v.init
                } else {
                    None
                }
            }) {
                Some(sfc_st::Value::Time(us)) => Some(us),
                _ => {
                    let msg = format!(
                        "the duration `{name}` is not a constant: an S7-200 timer preset must be known when the \
                         program is generated (write a literal, or declare `{name}` CONSTANT)"
                    );
                    self.diags.push(Diagnostic::error("SFC0813", span, msg).with_element(element));
                    return None;
                }
            },
            None => None,
        };
        let Some(us) = us else {
            self.diags
                .push(Diagnostic::error("SFC0813", span, "a timed qualifier without a duration").with_element(element));
            return None;
        };
        if us < 0 || us % TIMER_BASE_US != 0 || us / TIMER_BASE_US > MAX_PT {
            let msg = format!(
                "the duration {} is not a multiple of 100 ms between T#0s and T#54m36s700ms, the presets of an \
                 S7-200 100 ms timer",
                fmt_time(us)
            );
            self.diags.push(Diagnostic::error("SFC0813", span, msg).with_element(element));
            return None;
        }
        Some(us / TIMER_BASE_US)
    }

    /// Guards and action bodies to bit logic.
    fn lower(&mut self) {
        let chart = self.chart;
        let mut low = Lowerer {
            chart,
            vars: &self.vars,
            steps: &self.steps,
            actions: &self.action_bits,
            timers: &mut self.timers,
            diags: &mut self.diags,
            text: &self.checked.file.text,
        };
        for tr in &chart.transitions {
            let site = Site { element: &tr.name, guard_of: Some(&tr.from) };
            let g = match &tr.condition {
                ast::Condition::St(e) => low.expr(e, &site),
                ast::Condition::Il(b) => low.il_condition(b, &site),
                ast::Condition::Missing => None,
            };
            self.guards.push(g);
        }
        for e in &mut self.entities {
            let Some(id) = e.action else { continue };
            let act = &chart.actions[id];
            let site = Site { element: &act.name, guard_of: None };
            let body = match &act.body {
                ast::ActionBody::St(stmts) => low.st_body(stmts, &site),
                ast::ActionBody::Il(b) => low.il_body(b, &site),
            };
            e.body = body.unwrap_or_default();
        }
    }

    /// Timer numbers: step timers TON or TONR as their readers need, action timers TON.
    fn allocate_timers(&mut self) {
        let mut ton = ton_numbers();
        let mut tonr = tonr_numbers();
        let mut short = (0usize, 0usize);
        for t in &self.timers.list {
            let n = if t.retentive { tonr.next() } else { ton.next() };
            match n {
                Some(n) => self.timer_numbers.push(n),
                None => {
                    if t.retentive {
                        short.1 += 1;
                    } else {
                        short.0 += 1;
                    }
                    self.timer_numbers.push(0);
                }
            }
        }
        if short != (0, 0) {
            let msg = format!(
                "`{}` needs {} TON and {} TONR 100 ms timers; the S7-200 has 182 TON (T37–T63, T101–T255) and 54 \
                 TONR (T5–T31, T69–T95)",
                self.chart.pou,
                self.timers.list.iter().filter(|t| !t.retentive).count(),
                self.timers.list.iter().filter(|t| t.retentive).count()
            );
            self.diags.push(Diagnostic::error("SFC0815", self.chart.name_span, msg));
        }
    }

    fn allocate_temps(&mut self) {
        for _ in 0..self.emitter.max_temps {
            let a = self.take_bit();
            self.temps.push(a);
        }
    }

    /// A BOOL variable driven by action control must be a bit the program may write.
    fn check_variable_action(&mut self, e: &Entity, key: &str) {
        let span = self
            .chart
            .steps
            .iter()
            .flat_map(|s| s.associations.iter())
            .find(|a| a.action.eq_ignore_ascii_case(key))
            .map_or(self.chart.name_span, |a| a.span);
        match e.var_bit {
            Some(Addr::Bit(Area::I, byte, bit)) => {
                let msg = format!("`{}` is the input I{byte}.{bit}: an action cannot drive the input image", e.name);
                self.diags.push(Diagnostic::error("SFC0814", span, msg).with_element(e.name.clone()));
            }
            Some(_) => {}
            None => {
                // A variable whose location was refused has its own diagnostic already.
                let located = self.vars.get(key).is_some_and(|i| self.vars.list[i].location.is_some());
                if !located {
                    let msg = format!("`{}` is not a BOOL variable the S7-200 program can drive", e.name);
                    self.diags.push(Diagnostic::error("SFC0811", span, msg).with_element(e.name.clone()));
                }
            }
        }
    }

    fn step_name(&self, s: StepId) -> &str {
        &self.chart.steps[s].name
    }

    fn fire_bit(&self, t: usize) -> Logic {
        Logic::bit(self.fires[t], format!("{} fires", self.chart.transitions[t].name))
    }

    fn push_network(&mut self, title: String, code: Vec<Ins>) {
        if !code.is_empty() {
            self.networks.push(Network { title, code });
        }
    }

    fn emit(&mut self) {
        self.first_scan_network();
        self.step_time_network();
        self.transition_networks();
        self.step_networks();
        for i in 0..self.entities.len() {
            self.control_network(i);
        }
        self.body_networks();
    }

    /// `SM0.1`: clear the steps, the action memories and the timers; initial values.
    fn first_scan_network(&mut self) {
        let mut code = vec![Ins::on(Op::Ld, Addr::FIRST_SCAN, "first scan = IEC scan 0")];
        let steps: Vec<(Addr, String)> =
            self.steps.iter().enumerate().map(|(s, &a)| (a, self.step_name(s).to_string())).collect();
        reset_runs(&steps, false, "steps (initial ones are set after the transitions)", &mut code);
        let mut clear = Vec::new();
        let mut set = Vec::new();
        for v in &self.vars.list {
            let Some(a) = v.addr else { continue };
            if v.is_input() {
                continue;
            }
            if matches!(v.init, Some(sfc_st::Value::Bool(true))) {
                set.push((a, v.name.clone()));
            } else {
                clear.push((a, v.name.clone()));
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
        reset_runs(&flags, false, "action control memories", &mut code);
        let mut numbers: Vec<u16> = self.timer_numbers.clone();
        numbers.sort_unstable();
        let mut i = 0;
        while i < numbers.len() {
            let mut j = i + 1;
            while j < numbers.len() && numbers[j] == numbers[j - 1] + 1 && j - i < 255 {
                j += 1;
            }
            let first = self.timer_numbers.iter().position(|&n| n == numbers[i]).unwrap_or(0);
            code.push(Ins::on(Op::Reset((j - i) as u16), Addr::Timer(first), "timers"));
            i = j;
        }
        self.push_network("first scan (SM0.1 = IEC scan 0): clear steps, action memories and timers".into(), code);
    }

    /// The step timers, before the transitions read them.
    fn step_time_network(&mut self) {
        let mut code = Vec::new();
        for (i, t) in self.timers.list.iter().enumerate() {
            let TimerUse::Step(s) = t.what else { continue };
            code.push(Ins::on(Op::Ld, self.steps[s], self.step_name(s)));
            let op = if t.retentive { Op::Tonr(t.pt) } else { Op::Ton(t.pt) };
            code.push(Ins::on(op, Addr::Timer(i), t.label.clone()));
        }
        self.push_network("step times: advance before the transitions read them".into(), code);
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
            let mut items: Vec<Logic> =
                tr.from.iter().map(|&s| Logic::bit(self.steps[s], self.step_name(s).to_string())).collect();
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
            let names = |v: &[StepId]| v.iter().map(|&s| self.step_name(s)).collect::<Vec<_>>().join(", ");
            let mut title = format!("transition {}: {} -> {}", tr.name, names(&tr.from), names(&tr.to));
            if let Some(p) = tr.priority {
                let _ = write!(title, " (PRIORITY {p})");
            }
            let cond = match &tr.condition {
                ast::Condition::St(e) => Some(e.span),
                ast::Condition::Il(b) => Some(b.span),
                ast::Condition::Missing => None,
            };
            if let Some(span) = cond {
                let _ = write!(title, " := {}", snippet(&self.checked.file.text, span));
            }
            self.push_network(title, code);
        }
    }

    /// Each step: reset by the transitions leaving it, then set by those entering it; its timers
    /// restart on entry and run on the new step bit.
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
                code.push(Ins::on(Op::Reset(1), bit, format!("leave {}", step.name)));
            }
            let mut entering: Vec<Logic> = adj.incoming[s].iter().map(|&t| self.fire_bit(t)).collect();
            if step.initial {
                entering.insert(0, Logic::bit(Addr::FIRST_SCAN, "first scan"));
            }
            let timers: Vec<usize> =
                (0..self.timers.list.len()).filter(|&i| self.timers.list[i].what == TimerUse::Step(s)).collect();
            if !entering.is_empty() {
                self.emitter.logic(&Logic::any(entering), &mut code);
                code.push(Ins::on(Op::Set(1), bit, format!("enter {}", step.name)));
                for &i in &timers {
                    code.push(Ins::on(Op::Reset(1), Addr::Timer(i), format!("{}.T restarts", step.name)));
                }
            }
            for &i in &timers {
                let t = &self.timers.list[i];
                code.push(Ins::on(Op::Ld, bit, step.name.clone()));
                let op = if t.retentive { Op::Tonr(t.pt) } else { Op::Ton(t.pt) };
                code.push(Ins::on(op, Addr::Timer(i), t.label.clone()));
            }
            let mut title = format!("step {}", step.name);
            if step.initial {
                title.push_str(" (initial)");
            }
            if let Some(limit) = step.timeout {
                let _ = write!(title, "; its sfc.timeout {} is not supervised here", fmt_time(limit));
            }
            self.push_network(title, code);
        }
    }

    /// ACTION_CONTROL of entity `i` (the simulator's `Control::update`, bit for bit).
    fn control_network(&mut self, i: usize) {
        let e = &self.entities[i];
        let (steps, chart) = (&self.steps, self.chart);
        let st = |q: Qualifier| {
            Logic::any(e.steps_with(q).iter().map(|&s| Logic::bit(steps[s], chart.steps[s].name.clone())).collect())
        };
        let mut code = Vec::new();
        let em = &mut self.emitter;
        em.new_network();
        let (tq, pt) = e.timed.unwrap_or((Qualifier::N, 0));
        let timer = e.timer.map(Addr::Timer);
        let timer_of = |q: Qualifier| if tq == q { timer } else { None };
        for (q, ff) in [(Qualifier::S, e.s_ff), (Qualifier::SD, e.sd_ff), (Qualifier::SL, e.sl_ff)] {
            if let Some(ff) = ff {
                em.logic(&st(q), &mut code);
                code.push(Ins::on(Op::Set(1), ff, format!("{}.{}", e.name, q.name())));
            }
        }
        if let Some(ff) = e.ds_ff {
            em.logic(&st(Qualifier::DS), &mut code);
            if let Some(t) = timer_of(Qualifier::DS) {
                code.push(Ins::on(Op::Ton(pt as u16), t, format!("{} DS delay", e.name)));
                code.push(Ins::on(Op::Ld, t, format!("{} DS delay", e.name)));
            }
            code.push(Ins::on(Op::Set(1), ff, format!("{}.DS", e.name)));
        }
        let ffs: Vec<(Addr, &str)> = [(e.s_ff, "S"), (e.sd_ff, "SD"), (e.ds_ff, "DS"), (e.sl_ff, "SL")]
            .into_iter()
            .filter_map(|(b, n)| b.map(|b| (b, n)))
            .collect();
        if e.has(Qualifier::R) && !ffs.is_empty() {
            em.logic(&st(Qualifier::R), &mut code);
            for (b, n) in &ffs {
                code.push(Ins::on(Op::Reset(1), *b, format!("{}.{n} (R dominates)", e.name)));
            }
        }
        if let Some(t) = timer {
            let input = match tq {
                Qualifier::L | Qualifier::D => Some(st(tq)),
                Qualifier::SD => e.sd_ff.map(|b| Logic::bit(b, format!("{}.SD", e.name))),
                Qualifier::SL => e.sl_ff.map(|b| Logic::bit(b, format!("{}.SL", e.name))),
                _ => None,
            };
            if let Some(input) = input {
                em.logic(&input, &mut code);
                code.push(Ins::on(
                    Op::Ton(pt as u16),
                    t,
                    format!("{} {} {}", e.name, tq.name(), fmt_time(pt * TIMER_BASE_US)),
                ));
            }
        }
        if let Some(p) = e.pulse {
            em.logic(&st(Qualifier::P), &mut code);
            code.push(Ins::bare(Op::Eu));
            code.push(Ins::on(Op::Out, p, format!("{}.P pulse", e.name)));
        }
        // Q := NOT R AND (N OR L_act OR D_act OR P OR S_FF OR SD_act OR DS_FF OR SL_act)
        let mut parts: Vec<Logic> = Vec::new();
        if e.has(Qualifier::N) {
            parts.push(st(Qualifier::N));
        }
        let tbit = |t: Addr| Logic::bit(t, format!("{} {} timer", e.name, tq.name()));
        if e.has(Qualifier::L) {
            if let Some(t) = timer_of(Qualifier::L) {
                parts.push(Logic::And(vec![st(Qualifier::L), tbit(t).not()]));
            }
        }
        if e.has(Qualifier::D) {
            parts.push(match timer_of(Qualifier::D) {
                Some(t) => tbit(t),
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
            parts.push(match timer_of(Qualifier::SD) {
                Some(t) => tbit(t),
                None => Logic::bit(b, format!("{}.SD", e.name)),
            });
        }
        if let Some(b) = e.ds_ff {
            parts.push(Logic::bit(b, format!("{}.DS", e.name)));
        }
        if let (Some(b), Some(t)) = (e.sl_ff, timer_of(Qualifier::SL)) {
            parts.push(Logic::And(vec![Logic::bit(b, format!("{}.SL", e.name)), tbit(t).not()]));
        }
        let q = Logic::And(vec![Logic::any(parts), st(Qualifier::R).not()]);
        em.logic(&q, &mut code);
        let target = e.var_bit.or(e.q);
        if let Some(target) = target {
            let note = if e.action.is_some() { format!("{}.Q", e.name) } else { e.name.clone() };
            code.push(Ins::on(Op::Out, target, note));
        }
        if let (Some(qb), Some(ab)) = (e.q, e.a) {
            // A := Q OR (Q fell: the final scan) OR P1 rising OR P0 falling.
            let qn = format!("{}.Q", e.name);
            code.push(Ins::on(Op::Ld, qb, qn.clone()));
            code.push(Ins::bare(Op::Ed));
            code.push(Ins::on(Op::O, qb, qn));
            for (q, edge) in [(Qualifier::P1, Op::Eu), (Qualifier::P0, Op::Ed)] {
                if e.has(q) {
                    em.logic(&st(q), &mut code);
                    code.push(Ins::bare(edge));
                    code.push(Ins::bare(Op::Old));
                }
            }
            code.push(Ins::on(Op::Out, ab, format!("{}.A", e.name)));
        }
        let mut quals: Vec<String> = Vec::new();
        for (s, q) in &e.assocs {
            let mut t = format!("{} in {}", q.name(), chart.steps[*s].name);
            if q.is_timed() {
                let _ = write!(t, " ({})", fmt_time(pt * TIMER_BASE_US));
            }
            if !quals.contains(&t) {
                quals.push(t);
            }
        }
        let kind = if e.action.is_some() { "" } else { " (BOOL variable)" };
        let title = format!("action {}{kind}: {}", e.name, quals.join(", "));
        self.push_network(title, code);
    }

    /// The statements of each action body, one network per statement, under the action's `A`.
    fn body_networks(&mut self) {
        let mut out = Vec::new();
        for e in &self.entities {
            let Some(a) = e.a else { continue };
            for op in &e.body {
                let text = match op {
                    BodyOp::Assign { text, .. } | BodyOp::If { text, .. } => text.clone(),
                };
                let mut code = Vec::new();
                self.emitter.new_network();
                let mut enable: Vec<Contact> = vec![(a, false, format!("{}.A", e.name))];
                self.emitter.body(std::slice::from_ref(op), &mut enable, &mut code);
                out.push((format!("body of {} (while {}.A): {text}", e.name, e.name), code));
            }
        }
        for (title, code) in out {
            self.push_network(title, code);
        }
    }

    /// The allocation table, the notes and the networks.
    fn print(&self) -> String {
        let chart = self.chart;
        let mut out = String::new();
        let _ = writeln!(
            out,
            "// S7-200 statement list for {} {} ({}), generated by sfc (--target stl).",
            chart.pou_kind.keyword(),
            chart.pou,
            self.checked.file.name
        );
        for line in [
            "// Set/reset method: each scan first computes one bit per transition from the step bits and",
            "// inputs as they are at the start of the scan (conflicts: PRIORITY, then declaration order),",
            "// then resets and sets the steps, then runs action control and action bodies on the new",
            "// steps: one evolution per scan. The first scan (SM0.1) is IEC scan 0: no transition fires,",
            "// the initial steps are set and their actions see the activation. Timers: 100 ms base.",
            "//",
            "// Allocation (address, kind, name, declaration):",
        ] {
            out.push_str(line);
            out.push('\n');
        }
        let r = Resolve { timers: &self.timer_numbers, temps: &self.temps };
        let mut rows: Vec<Row> = Vec::new();
        for v in &self.vars.list {
            if let Some(a) = v.addr {
                let mut detail = v.kind_text();
                if v.is_input() {
                    detail.push_str(", input");
                }
                rows.push(Row { addr: a, kind: "var", name: v.name.clone(), detail });
            }
        }
        for (s, step) in chart.steps.iter().enumerate() {
            let detail = if step.initial { "initial step" } else { "" };
            rows.push(Row { addr: self.steps[s], kind: "step", name: step.name.clone(), detail: detail.into() });
        }
        for (t, tr) in chart.transitions.iter().enumerate() {
            let names = |v: &[StepId]| v.iter().map(|&s| self.step_name(s)).collect::<Vec<_>>().join(",");
            let detail = format!("fires: {} -> {}", names(&tr.from), names(&tr.to));
            rows.push(Row { addr: self.fires[t], kind: "fire", name: tr.name.clone(), detail });
        }
        for e in &self.entities {
            for (bit, what, detail) in [
                (e.q, "Q", "action output"),
                (e.a, "A", "action body runs"),
                (e.s_ff, "S", "stored (S)"),
                (e.sd_ff, "SD", "stored (SD)"),
                (e.ds_ff, "DS", "stored (DS)"),
                (e.sl_ff, "SL", "stored (SL)"),
                (e.pulse, "P", "pulse (P)"),
            ] {
                if let Some(b) = bit {
                    rows.push(Row { addr: b, kind: "flag", name: format!("{}.{what}", e.name), detail: detail.into() });
                }
            }
        }
        for (i, t) in self.timers.list.iter().enumerate() {
            let (name, what) = match t.what {
                TimerUse::Step(s) => {
                    (format!("{}.T", self.step_name(s)), format!(">= {}", fmt_time(i64::from(t.pt) * TIMER_BASE_US)))
                }
                TimerUse::Action(k) => {
                    let e = &self.entities[k];
                    let q = e.timed.map_or("", |(q, _)| q.name());
                    (format!("{}.{q}", e.name), fmt_time(i64::from(t.pt) * TIMER_BASE_US))
                }
            };
            let kind = if t.retentive { "TONR" } else { "TON" };
            let detail = format!("{kind} +{} x 100 ms: {what}", t.pt);
            rows.push(Row { addr: Addr::Timer(i), kind: "timer", name, detail });
        }
        for (i, &a) in self.temps.iter().enumerate() {
            rows.push(Row { addr: a, kind: "temp", name: format!("#{i}"), detail: "scratch within a network".into() });
        }
        for row in &rows {
            let line = format!("//   {:<8} {:<6} {:<24} {}", r.text(row.addr), row.kind, row.name, row.detail);
            out.push_str(line.trim_end());
            out.push('\n');
        }
        let unmapped: Vec<String> = self
            .vars
            .list
            .iter()
            .filter(|v| v.addr.is_none())
            .map(|v| {
                format!("{} ({}{})", v.name, if v.constant { "CONSTANT " } else { "" }, v.ty.as_deref().unwrap_or("?"))
            })
            .collect();
        if !unmapped.is_empty() {
            let _ = writeln!(
                out,
                "// Not in the program (constants are folded; the chart reads no other variable): {}.",
                unmapped.join(", ")
            );
        }
        for (id, bits) in self.action_bits.iter().enumerate() {
            if bits.is_none() {
                let _ = writeln!(
                    out,
                    "// Action {} is associated with no step: it never runs and has no code.",
                    chart.actions[id].name
                );
            }
        }
        out.push('\n');
        ir::print_networks(&self.networks, &r, &mut out);
        out
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
        let op = if set { Op::Set(n) } else { Op::Reset(n) };
        code.push(Ins::on(op, Addr::from_linear(sorted[i].0, sorted[i].1), note));
        i = j;
    }
}

fn snippet(text: &str, span: Span) -> String {
    let s = ir::one_line(text.get(span.range()).unwrap_or(""));
    if s.chars().count() > 60 {
        let mut t: String = s.chars().take(57).collect();
        t.push_str("...");
        t
    } else {
        s
    }
}
