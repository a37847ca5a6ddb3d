//! Siemens S7-200 statement list (STL, Micro/WIN style) from a chart, for `--target stl`.
//!
//! Two methods, chosen with [`StlMethod`]; both give the `iec` semantics of `semantics.md`
//! (one evolution per scan, every guard on one snapshot, a step consumed by one transition,
//! parallel branches together), checked against a model of the S7-200 (`tests/s7200/`):
//!
//! - **set/reset** (default): one network per step resets its S bit when a transition leaves
//!   it and sets it when one enters it.
//! - **SCR** (seed 002, section 3.4): one `LSCR`/`SCRE` segment per step; its transitions move
//!   the token with `SCRT` (several `SCRT` for a simultaneous divergence, `R` of the other
//!   steps of a simultaneous convergence). `SCRT` sets the next step's bit at once, so a
//!   segment further down runs in the same scan: the conditions are therefore computed before
//!   any segment runs (one fire bit per transition, from the scan's snapshot), and a segment
//!   only moves the token on those bits, which keeps one evolution per scan.
//!
//! Every scan, in this order:
//!
//! 1. **First scan** (`SM0.1`, IEC scan 0): steps, action memories, timers, counters cleared;
//!    variables that are not inputs (nor RETAIN) get their initial values.
//! 2. **Timers**, each executed exactly once per scan (an S7-200 100 ms timer adds the time
//!    base's intervals at every execution): step times on the step bits, supervision times,
//!    and the timers of the timed qualifiers on their inputs as the previous scan left them.
//! 3. `SFCQuitError` acknowledges `SFCError`.
//! 4. **Transitions**, in conflict order: `fire := pre-steps AND guard AND NOT (fire bit of
//!    every earlier transition sharing a pre-step)`.
//! 5. **Steps**: set/reset networks or SCR segments; a step entered restarts its timers.
//! 6. **Action control** (IEC ACTION_CONTROL) from the new step bits.
//! 7. **Action bodies** under each action's `A` bit: BOOL and integer assignments, IF, counter
//!    calls (skipped with `JMP` when the body does not run).
//! 8. **Supervision**: a step active longer than its `sfc.timeout` sets `SFCError`.
//!
//! What has no faithful S7-200 form is refused with a located error (SFC0810–SFC0816);
//! a TIME variable used as a preset is folded to its initial value with a warning (SFC0817).

mod emit;
mod ir;
mod logic;
mod networks;
mod vars;

use emit::Emitter;
use ir::{Addr, Area, Network, Resolve, Val};
use logic::{fmt_time, BodyOp, Counters, Logic, Lowerer, Site, TimerUse, Timers, MAX_PT};
use sfc_diagnostics::{Diagnostic, Span};
use sfc_model::{ActionTarget, Chart, Checked, Duration, Qualifier, StepId};
use sfc_syntax::ast::{self, Item, VarKind};
use std::collections::{BTreeSet, HashSet};
use std::fmt::Write as _;
use vars::Vars;

/// Resolution of every timer the program uses (100 ms).
pub(crate) const TIMER_BASE_US: i64 = 100_000;

/// How the program moves the steps.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum StlMethod {
    /// Set/reset of the step bits, one network per step.
    #[default]
    SetReset,
    /// `LSCR`/`SCRT`/`SCRE` segments, one per step.
    Scr,
}

impl StlMethod {
    /// The name on the command line (`setreset`, `scr`).
    pub fn name(self) -> &'static str {
        match self {
            StlMethod::SetReset => "setreset",
            StlMethod::Scr => "scr",
        }
    }
    pub fn from_name(s: &str) -> Option<StlMethod> {
        [StlMethod::SetReset, StlMethod::Scr].into_iter().find(|m| m.name() == s)
    }
}

/// Options of the STL target.
#[derive(Debug, Clone, Copy, Default)]
pub struct StlOptions {
    pub method: StlMethod,
}

/// A generated program.
#[derive(Debug, Clone, PartialEq)]
pub struct StlProgram {
    /// The statement list, to paste into Micro/WIN's STL editor.
    pub text: String,
    /// The symbol table as CSV (`Symbol,Address,Comment`).
    pub symbols: String,
    /// Warnings (TIME variables folded to their initial value, …).
    pub warnings: Vec<Diagnostic>,
}

/// 100 ms TON/TOF timer numbers of the S7-200 (CPU 22x).
fn ton_numbers() -> impl Iterator<Item = u16> {
    (37..=63).chain(101..=255)
}
/// 100 ms TONR timer numbers.
fn tonr_numbers() -> impl Iterator<Item = u16> {
    (5..=31).chain(69..=95)
}

/// Builds the statement list of `chart` (one of `checked.charts`). Fails with the file's errors
/// when it has any, or with a located diagnostic for each part of the chart that the S7-200
/// program cannot express.
pub fn build_stl(checked: &Checked, chart: &Chart, opts: StlOptions) -> Result<StlProgram, Vec<Diagnostic>> {
    if checked.has_errors() {
        return Err(checked.diagnostics.iter().filter(|d| d.is_error()).cloned().collect());
    }
    let refused = crate::codesys_actions(Some(checked), chart, "the STL target");
    if !refused.is_empty() {
        return Err(refused);
    }
    let Some(Item::Pou(pou)) = checked.unit.items.get(chart.item) else {
        return Err(vec![Diagnostic::error(
            "SFC0810",
            chart.name_span,
            format!("the declaration of `{}` is not in the checked file", chart.pou),
        )]);
    };
    let mut g = Gen::new(checked, chart, pou, opts);
    g.run();
    if g.diags.is_empty() {
        let text = g.print();
        let symbols = g.symbols();
        sfc_diagnostics::sort(&mut g.warnings);
        Ok(StlProgram { text, symbols, warnings: g.warnings })
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
    /// The one timed qualifier and its preset (100 ms ticks; 0 = no delay) and duration.
    timed: Option<(Qualifier, i64, i64)>,
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

/// A row of the allocation table (and of the symbol table).
struct Row {
    addr: String,
    kind: &'static str,
    name: String,
    /// Symbol for Micro/WIN's symbol table (made valid and unique later).
    symbol: String,
    detail: String,
}

/// Hands out free memory: bits from M first (skipping located ones), then V; words and
/// double words from V.
struct Pool {
    used_m: BTreeSet<u32>,
    next_m: u32,
    /// Next free V byte.
    next_v: u32,
    /// The V byte being handed out bit by bit, and the next bit in it.
    v_bits: Option<(u32, u8)>,
}

impl Pool {
    fn bit(&mut self) -> Option<Addr> {
        let m_bits = (vars::last_byte(Area::M) + 1) * 8;
        while self.next_m < m_bits {
            let n = self.next_m;
            self.next_m += 1;
            if !self.used_m.contains(&n) {
                return Some(Addr::from_linear(Area::M, n));
            }
        }
        let (byte, bit) = match self.v_bits {
            Some((b, k)) if k < 8 => (b, k),
            _ => (self.bytes(1)?, 0),
        };
        self.v_bits = Some((byte, bit + 1));
        Some(Addr::Bit(Area::V, byte, bit))
    }
    /// `n` bytes of V (2 or 4 aligned to 2), the first byte's address.
    fn bytes(&mut self, n: u32) -> Option<u32> {
        if n > 1 && self.next_v % 2 == 1 {
            self.next_v += 1;
        }
        let at = self.next_v;
        if at + n > vars::last_byte(Area::V) + 1 {
            return None;
        }
        self.next_v += n;
        Some(at)
    }
}

/// The supervision of a step with an `sfc.timeout`: its timer and its reported flag.
#[derive(Clone, Copy)]
struct Supervision {
    timer: usize,
    overdue: Addr,
    limit: i64,
}

struct Gen<'a> {
    checked: &'a Checked,
    chart: &'a Chart,
    method: StlMethod,
    vars: Vars,
    diags: Vec<Diagnostic>,
    warnings: Vec<Diagnostic>,
    pool: Pool,
    steps: Vec<Addr>,
    fires: Vec<Addr>,
    /// `Q`/`A` bits by action.
    action_bits: Vec<Option<(Addr, Addr)>>,
    entities: Vec<Entity>,
    guards: Vec<Option<Logic>>,
    timers: Timers,
    counters: Counters,
    /// Timer numbers by timer-table index.
    timer_numbers: Vec<u16>,
    counter_numbers: Vec<u16>,
    supervised: Vec<Option<Supervision>>,
    /// The `QD` bit of each CTUD instance, by variable index.
    ctud_qd: std::collections::HashMap<usize, Addr>,
    /// `SFCError`, `SFCQuitError` (variable indexes).
    sfc_error: Option<usize>,
    sfc_quit: Option<usize>,
    temps: Vec<Addr>,
    temp_words: Vec<u32>,
    temp_dwords: Vec<u32>,
    networks: Vec<Network>,
    emitter: Emitter,
    exhausted: bool,
}

impl<'a> Gen<'a> {
    fn new(checked: &'a Checked, chart: &'a Chart, pou: &'a ast::Pou, opts: StlOptions) -> Gen<'a> {
        let vars = Vars::collect(&checked.unit, pou);
        Gen {
            checked,
            chart,
            method: opts.method,
            vars,
            diags: Vec::new(),
            warnings: Vec::new(),
            pool: Pool { used_m: BTreeSet::new(), next_m: 0, next_v: 0, v_bits: None },
            steps: Vec::new(),
            fires: Vec::new(),
            action_bits: Vec::new(),
            entities: Vec::new(),
            guards: Vec::new(),
            timers: Timers::default(),
            counters: Counters::default(),
            timer_numbers: Vec::new(),
            counter_numbers: Vec::new(),
            supervised: Vec::new(),
            ctud_qd: Default::default(),
            sfc_error: None,
            sfc_quit: None,
            temps: Vec::new(),
            temp_words: Vec::new(),
            temp_dwords: Vec::new(),
            networks: Vec::new(),
            emitter: Emitter::default(),
            exhausted: false,
        }
    }

    fn run(&mut self) {
        self.control_variables();
        self.declarations();
        self.allocate();
        self.build_entities();
        self.supervision();
        self.lower();
        self.fold_warnings();
        if !self.diags.is_empty() {
            return;
        }
        self.allocate_timers_and_counters();
        if !self.diags.is_empty() {
            return;
        }
        self.emit();
        self.allocate_temps();
        if self.emitter.labels > 256 {
            let msg = format!("`{}` needs more than the 256 jump labels of the S7-200", self.chart.pou);
            self.diags.push(Diagnostic::error("SFC0815", self.chart.name_span, msg));
        }
    }

    fn exhausted(&mut self) {
        if !self.exhausted {
            self.exhausted = true;
            self.diags.push(Diagnostic::error(
                "SFC0815",
                self.chart.name_span,
                format!(
                    "`{}` needs more memory than the S7-200 bit memory M0.0-M31.7 and variable memory \
                     VB0-VB{} hold",
                    self.chart.pou,
                    vars::last_byte(Area::V)
                ),
            ));
        }
    }

    fn take_bit(&mut self) -> Addr {
        match self.pool.bit() {
            Some(a) => a,
            None => {
                self.exhausted();
                Addr::Bit(Area::V, 0, 0)
            }
        }
    }

    fn take_value(&mut self, wide: bool) -> Val {
        match self.pool.bytes(if wide { 4 } else { 2 }) {
            Some(at) if wide => Val::DWord(Area::V, at),
            Some(at) => Val::Word(Area::V, at),
            None => {
                self.exhausted();
                Val::Word(Area::V, 0)
            }
        }
    }

    /// The chart control variables of `docs/sim.md`: `SFCError` (set by supervision, readable
    /// by the chart) and `SFCQuitError` (acknowledges it) are implemented, declared or
    /// implicit; `SFCInit`, `SFCPause`, `SFCErrorStep` and `SFCCurrentStep` are refused where
    /// they are declared or read.
    fn control_variables(&mut self) {
        const UNSUPPORTED: [&str; 4] = ["SFCInit", "SFCPause", "SFCErrorStep", "SFCCurrentStep"];
        let why = |name: &str| {
            format!(
                "the chart control variable `{name}` is not implemented by the S7-200 program (it would {}); \
                 SFCError and SFCQuitError are",
                match name.to_ascii_uppercase().as_str() {
                    "SFCINIT" => "hold the chart in its initial situation",
                    "SFCPAUSE" => "freeze the evolution and the step times",
                    _ => "hold a STRING, which S7-200 bit and word memory has no form for",
                }
            )
        };
        for v in &self.vars.list {
            if UNSUPPORTED.iter().any(|u| u.eq_ignore_ascii_case(&v.name)) {
                let d = Diagnostic::error("SFC0816", v.span, why(&v.name)).with_element(v.name.clone());
                self.diags.push(d);
            }
        }
        let mut used: Vec<(String, Span)> = Vec::new();
        for t in &self.chart.transitions {
            condition_names(&t.condition, &mut used);
        }
        for a in &self.chart.actions {
            match &a.body {
                ast::ActionBody::St(stmts) => stmt_names(stmts, &mut used),
                ast::ActionBody::Il(b) => il_names(b, &mut used),
                ast::ActionBody::Sfc(_) => {}
            }
        }
        let mut referenced: HashSet<String> = HashSet::new();
        for (name, span) in used {
            if !sfc_st::is_sfc_control_variable(&name) || self.vars.get(&name).is_some() {
                continue;
            }
            if UNSUPPORTED.iter().any(|u| u.eq_ignore_ascii_case(&name)) {
                self.diags.push(Diagnostic::error("SFC0816", span, why(&name)).with_element(name.clone()));
            } else {
                referenced.insert(name.to_ascii_uppercase());
            }
        }
        let supervised = self.chart.steps.iter().any(|s| s.timeout.is_some());
        let span = self.chart.name_span;
        if supervised || referenced.contains("SFCERROR") || referenced.contains("SFCQUITERROR") {
            let error = match self.vars.get("SFCError") {
                Some(i) => i,
                None => self.vars.add_implicit("SFCError", VarKind::Output, span),
            };
            let quit = match self.vars.get("SFCQuitError") {
                Some(i) => i,
                None => self.vars.add_implicit("SFCQuitError", VarKind::Input, span),
            };
            self.sfc_error = Some(error);
            self.sfc_quit = Some(quit);
        } else {
            self.sfc_error = self.vars.get("SFCError");
            self.sfc_quit = self.vars.get("SFCQuitError");
        }
    }

    /// Located variables get their operand; other kinds than BOOL, integers, TIME and counters
    /// are noted as not in the program.
    fn declarations(&mut self) {
        for i in 0..self.vars.list.len() {
            let v = &self.vars.list[i];
            let Some(loc) = &v.location else { continue };
            let name = v.name.clone();
            if v.is_bit() {
                match vars::bit_address(loc) {
                    Ok(addr) => {
                        if let Some((Area::M, n)) = addr.linear() {
                            self.pool.used_m.insert(n);
                        }
                        self.vars.list[i].addr = Some(addr);
                    }
                    Err(msg) => {
                        let d = Diagnostic::error("SFC0814", loc.span, msg).with_element(name);
                        self.diags.push(d);
                    }
                }
            } else if let (Some(ty), true) = (v.int_ty(), v.is_word()) {
                match vars::value_address(loc, ty.wide()) {
                    Ok(val) => {
                        if let Val::Word(Area::M, b) | Val::DWord(Area::M, b) = val {
                            for k in b * 8..(b + if ty.wide() { 4 } else { 2 }) * 8 {
                                self.pool.used_m.insert(k);
                            }
                        }
                        self.vars.list[i].val = Some(val);
                    }
                    Err(msg) => {
                        let d = Diagnostic::error("SFC0814", loc.span, msg).with_element(name);
                        self.diags.push(d);
                    }
                }
            }
        }
    }

    /// Bits and words of unlocated variables, step bits, fire bits, `Q`/`A` bits.
    fn allocate(&mut self) {
        for i in 0..self.vars.list.len() {
            let v = &self.vars.list[i];
            if v.location.is_some() {
                continue;
            }
            if v.is_bit() {
                let a = self.take_bit();
                self.vars.list[i].addr = Some(a);
            } else if let (Some(ty), true) = (v.int_ty(), v.is_word()) {
                let val = self.take_value(ty.wide());
                self.vars.list[i].val = Some(val);
            } else if v.counter() == Some(vars::CounterKind::Ctud) {
                let qd = self.take_bit();
                self.ctud_qd.insert(i, qd);
            }
        }
        let s_bits = (vars::last_byte(Area::S) + 1) * 8;
        for s in 0..self.chart.steps.len() {
            let a = if (s as u32) < s_bits { Addr::from_linear(Area::S, s as u32) } else { self.take_bit() };
            self.steps.push(a);
        }
        if self.method == StlMethod::Scr && self.chart.steps.len() as u32 > s_bits {
            let msg = format!(
                "the SCR method needs an S bit per step and the S7-200 has {s_bits} (S0.0-S31.7); `{}` has {} steps: \
                 build with --stl-method setreset",
                self.chart.pou,
                self.chart.steps.len()
            );
            self.diags.push(Diagnostic::error("SFC0815", self.chart.name_span, msg));
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
            let mut first_timed: Option<(Qualifier, i64, i64, Span)> = None;
            for (s, step) in chart.steps.iter().enumerate() {
                for assoc in step.associations.iter().filter(|x| x.action.eq_ignore_ascii_case(&key)) {
                    e.assocs.push((s, assoc.qualifier));
                    if !assoc.qualifier.is_timed() {
                        continue;
                    }
                    let Some((pt, us)) = self.duration(assoc.duration.as_ref(), assoc.span, &e.name) else { continue };
                    match first_timed {
                        None => first_timed = Some((assoc.qualifier, pt, us, assoc.span)),
                        Some((q0, _, us0, span0)) if (q0, us0) != (assoc.qualifier, us) => {
                            let msg = format!(
                                "`{}` already has the timed association {} with {} in another step; two different \
                                 timed associations of one action contend at run time, which the S7-200 program \
                                 does not reproduce",
                                e.name,
                                q0.name(),
                                fmt_time(us0)
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
            e.timed = first_timed.map(|(q, pt, us, _)| (q, pt, us));
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
            if let Some((q, pt, us)) = e.timed {
                if pt > 0 {
                    let label = format!("{} {} {}", e.name, q.name(), fmt_time(us));
                    e.timer = Some(self.timers.action(self.entities.len(), pt as u16, label));
                }
            }
            self.entities.push(e);
        }
    }

    /// The preset of a timed association in 100 ms ticks (⌈d / 100 ms⌉: a 100 ms timer counts
    /// whole ticks), and the duration.
    fn duration(&mut self, d: Option<&Duration>, span: Span, element: &str) -> Option<(i64, i64)> {
        let us = match d {
            Some(Duration::Literal(us)) => *us,
            Some(Duration::Variable(name)) => {
                let v = self.vars.get(name).map(|i| &self.vars.list[i]);
                match v {
                    Some(v) if v.constant => match v.init {
                        Some(sfc_st::Value::Time(us)) => us,
                        _ => 0,
                    },
                    Some(v) if v.is_time() => {
                        let i = self.vars.get(name).unwrap_or(0);
                        let mut f = self.vars.folded.borrow_mut();
                        if !f.contains(&i) {
                            f.push(i);
                        }
                        match self.vars.list[i].init {
                            Some(sfc_st::Value::Time(us)) => us,
                            _ => 0,
                        }
                    }
                    _ => {
                        let msg = format!("the duration `{name}` is not a TIME variable or constant");
                        self.diags.push(Diagnostic::error("SFC0813", span, msg).with_element(element));
                        return None;
                    }
                }
            }
            None => {
                let msg = "a timed qualifier without a duration";
                self.diags.push(Diagnostic::error("SFC0813", span, msg).with_element(element));
                return None;
            }
        };
        let pt = if us <= 0 { 0 } else { (us + TIMER_BASE_US - 1) / TIMER_BASE_US };
        if pt > MAX_PT {
            let msg = format!(
                "the duration {} needs a preset beyond +32767, the maximum of an S7-200 100 ms timer (T#54m36s700ms)",
                fmt_time(us)
            );
            self.diags.push(Diagnostic::error("SFC0813", span, msg).with_element(element));
            return None;
        }
        Some((pt, us))
    }

    /// `sfc.timeout`: a timer whose bit is `S.T > timeout` and a reported flag per step.
    fn supervision(&mut self) {
        for (s, step) in self.chart.steps.iter().enumerate() {
            let Some(limit) = step.timeout else {
                self.supervised.push(None);
                continue;
            };
            let pt = limit.div_euclid(TIMER_BASE_US) + 1;
            if pt > MAX_PT {
                let msg = format!(
                    "the supervision time {} of `{}` is beyond the 3276.7 s of an S7-200 100 ms timer",
                    fmt_time(limit),
                    step.name
                );
                self.diags.push(Diagnostic::error("SFC0812", step.name_span, msg).with_element(step.name.clone()));
                self.supervised.push(None);
                continue;
            }
            let label = format!("{}.T > {} (sfc.timeout)", step.name, fmt_time(limit));
            let timer = self.timers.step(s, pt as u16, false, label);
            let overdue = self.take_bit();
            self.supervised.push(Some(Supervision { timer, overdue, limit }));
        }
    }

    /// Guards and action bodies to logic.
    fn lower(&mut self) {
        let chart = self.chart;
        let mut low = Lowerer {
            chart,
            vars: &self.vars,
            steps: &self.steps,
            actions: &self.action_bits,
            ctud_qd: &self.ctud_qd,
            timers: &mut self.timers,
            counters: &mut self.counters,
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
                // Refused before generation (SFC0806, `sfc-driver`).
                ast::ActionBody::Sfc(_) => None,
            };
            e.body = body.unwrap_or_default();
        }
    }

    /// A warning for each TIME variable read as a timer preset.
    fn fold_warnings(&mut self) {
        let folded = self.vars.folded.borrow().clone();
        for i in folded {
            let v = &self.vars.list[i];
            let init = match v.init {
                Some(sfc_st::Value::Time(us)) => fmt_time(us),
                _ => "T#0s".to_string(),
            };
            let mut msg = format!(
                "`{}` is a TIME variable: the S7-200 program uses its initial value {init} as a timer preset, fixed \
                 when the program is generated",
                v.name
            );
            if v.is_input() {
                msg.push_str("; the value given at run time is ignored");
            }
            let d = Diagnostic::warning("SFC0817", v.span, msg)
                .with_element(v.name.clone())
                .with_note("declare it CONSTANT to say so, or change the preset and build again");
            self.warnings.push(d);
        }
        for v in &self.vars.list {
            let nonzero = match v.init {
                Some(sfc_st::Value::Bool(b)) => b,
                Some(sfc_st::Value::Int(i)) => i != 0,
                _ => false,
            };
            if v.retain && nonzero && (v.is_bit() || v.is_word()) {
                let msg = format!(
                    "`{}` is RETAIN: the S7-200 program does not give it its initial value in the first scan (it \
                     keeps what the retentive memory holds); set it once by hand",
                    v.name
                );
                self.warnings.push(Diagnostic::warning("SFC0817", v.span, msg).with_element(v.name.clone()));
            }
        }
    }

    /// Timer numbers (step timers TON or TONR as their readers need, others TON) and counter
    /// numbers (C0 upwards).
    fn allocate_timers_and_counters(&mut self) {
        let mut ton = ton_numbers();
        let mut tonr = tonr_numbers();
        let mut short = false;
        for t in &self.timers.list {
            let n = if t.retentive { tonr.next() } else { ton.next() };
            short |= n.is_none();
            self.timer_numbers.push(n.unwrap_or(0));
        }
        if short {
            let msg = format!(
                "`{}` needs {} TON and {} TONR 100 ms timers; the S7-200 has 182 TON (T37-T63, T101-T255) and 54 \
                 TONR (T5-T31, T69-T95)",
                self.chart.pou,
                self.timers.list.iter().filter(|t| !t.retentive).count(),
                self.timers.list.iter().filter(|t| t.retentive).count()
            );
            self.diags.push(Diagnostic::error("SFC0815", self.chart.name_span, msg));
        }
        if self.counters.list.len() > 256 {
            let msg = format!("`{}` needs more than the 256 counters of the S7-200", self.chart.pou);
            self.diags.push(Diagnostic::error("SFC0815", self.chart.name_span, msg));
        }
        self.counter_numbers = (0..self.counters.list.len() as u16).collect();
    }

    fn allocate_temps(&mut self) {
        for _ in 0..self.emitter.max_temps {
            let a = self.take_bit();
            self.temps.push(a);
        }
        for _ in 0..self.emitter.max_words {
            if let Val::Word(_, at) = self.take_value(false) {
                self.temp_words.push(at);
            }
        }
        for _ in 0..self.emitter.max_dwords {
            if let Val::DWord(_, at) = self.take_value(true) {
                self.temp_dwords.push(at);
            }
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

    fn step_bit(&self, s: StepId) -> Logic {
        Logic::bit(self.steps[s], self.step_name(s).to_string())
    }

    fn push_network(&mut self, title: String, code: Vec<ir::Ins>) {
        if !code.is_empty() {
            self.networks.push(Network { title, code });
        }
    }

    fn resolve(&self) -> Resolve<'_> {
        Resolve {
            timers: &self.timer_numbers,
            counters: &self.counter_numbers,
            temps: &self.temps,
            temp_words: &self.temp_words,
            temp_dwords: &self.temp_dwords,
        }
    }

    /// Every allocated operand, for the allocation table and the symbol table.
    fn rows(&self) -> Vec<Row> {
        let chart = self.chart;
        let r = self.resolve();
        let mut rows: Vec<Row> = Vec::new();
        for v in &self.vars.list {
            let addr = match (v.addr, v.val) {
                (Some(a), _) => r.text(a),
                (None, Some(val)) => r.value(val),
                _ => continue,
            };
            let mut detail = v.kind_text();
            if v.is_input() {
                detail.push_str(", input");
            }
            rows.push(Row { addr, kind: "var", name: v.name.clone(), symbol: v.name.clone(), detail });
        }
        for (s, step) in chart.steps.iter().enumerate() {
            let detail = if step.initial { "initial step" } else { "step" };
            rows.push(Row {
                addr: r.text(self.steps[s]),
                kind: "step",
                name: step.name.clone(),
                symbol: step.name.clone(),
                detail: detail.into(),
            });
        }
        for (t, tr) in chart.transitions.iter().enumerate() {
            let names = |v: &[StepId]| v.iter().map(|&s| self.step_name(s)).collect::<Vec<_>>().join(",");
            let detail = format!("fires: {} -> {}", names(&tr.from), names(&tr.to));
            rows.push(Row {
                addr: r.text(self.fires[t]),
                kind: "fire",
                name: tr.name.clone(),
                symbol: format!("{}_fires", tr.name),
                detail,
            });
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
                    rows.push(Row {
                        addr: r.text(b),
                        kind: "flag",
                        name: format!("{}.{what}", e.name),
                        symbol: format!("{}_{what}", e.name),
                        detail: detail.into(),
                    });
                }
            }
        }
        for (s, sup) in self.supervised.iter().enumerate() {
            if let Some(sup) = sup {
                rows.push(Row {
                    addr: r.text(sup.overdue),
                    kind: "flag",
                    name: format!("{}.overdue", self.step_name(s)),
                    symbol: format!("{}_overdue", self.step_name(s)),
                    detail: format!("sfc.timeout {} reported", fmt_time(sup.limit)),
                });
            }
        }
        for c in &self.counters.list {
            if let Some(qd) = c.qd {
                let name = &self.vars.list[c.var].name;
                rows.push(Row {
                    addr: r.text(qd),
                    kind: "flag",
                    name: format!("{name}.QD"),
                    symbol: format!("{name}_QD"),
                    detail: "CTUD output QD (CV <= 0 at the last call)".into(),
                });
            }
        }
        for (i, t) in self.timers.list.iter().enumerate() {
            let (name, symbol) = match t.what {
                TimerUse::Step(s) => (format!("{}.T", self.step_name(s)), format!("{}_T{}", self.step_name(s), t.pt)),
                TimerUse::Action(k) => {
                    let e = &self.entities[k];
                    let q = e.timed.map_or("", |(q, _, _)| q.name());
                    (format!("{}.{q}", e.name), format!("{}_{q}_timer", e.name))
                }
            };
            let kind = if t.retentive { "TONR" } else { "TON" };
            let detail = format!("{kind} +{} x 100 ms: {}", t.pt, t.label);
            rows.push(Row { addr: r.text(Addr::Timer(i)), kind: "timer", name, symbol, detail });
        }
        for (i, c) in self.counters.list.iter().enumerate() {
            let v = &self.vars.list[c.var];
            let detail = format!("{} {}", c.kind.name(), if c.call.is_some() { "" } else { "(never called)" });
            rows.push(Row {
                addr: r.text(Addr::Counter(i)),
                kind: "counter",
                name: v.name.clone(),
                symbol: v.name.clone(),
                detail: detail.trim_end().to_string(),
            });
        }
        for (i, &a) in self.temps.iter().enumerate() {
            rows.push(Row {
                addr: r.text(a),
                kind: "temp",
                name: format!("#{i}"),
                symbol: format!("sfc_scratch{i}"),
                detail: "scratch bit within a network".into(),
            });
        }
        for (i, &at) in self.temp_words.iter().enumerate() {
            rows.push(Row {
                addr: format!("VW{at}"),
                kind: "temp",
                name: format!("#W{i}"),
                symbol: format!("sfc_scratchW{i}"),
                detail: "scratch word within a network".into(),
            });
        }
        for (i, &at) in self.temp_dwords.iter().enumerate() {
            rows.push(Row {
                addr: format!("VD{at}"),
                kind: "temp",
                name: format!("#D{i}"),
                symbol: format!("sfc_scratchD{i}"),
                detail: "scratch double word within a network".into(),
            });
        }
        rows
    }

    /// The header, the allocation table and the networks.
    fn print(&self) -> String {
        let chart = self.chart;
        let mut out = String::new();
        let _ = writeln!(
            out,
            "// S7-200 statement list for {} {} ({}), generated by sfc (--target stl --stl-method {}).",
            chart.pou_kind.keyword(),
            chart.pou,
            ir::ascii(&self.checked.file.name),
            self.method.name()
        );
        let method: &[&str] = match self.method {
            StlMethod::SetReset => &[
                "// Method: SET/RESET. Each step is an S bit that its own network resets when a transition leaves",
                "// it and sets when one enters it. Chosen as the default because it has a form for every",
                "// chart (simultaneous divergence and convergence, re-entered steps) and reads like ladder logic.",
            ],
            StlMethod::Scr => &[
                "// Method: SCR (LSCR/SCRT/SCRE, seed 002 section 3.4). Each step is an SCR segment whose",
                "// transitions move the token with SCRT (several SCRT for a simultaneous divergence, R of the",
                "// other steps of a simultaneous convergence). SCRT sets the next S bit at once, so a segment",
                "// further down would run in the same scan: every condition is therefore computed before the",
                "// first segment (one fire bit per transition), and the segments move the token only on those",
                "// bits -- one evolution per scan, as IEC 61131-3 requires.",
            ],
        };
        for line in method {
            out.push_str(line);
            out.push('\n');
        }
        for line in [
            "// Each scan: timers (each executed exactly once), transitions from the scan's snapshot (conflicts:",
            "// PRIORITY, then declaration order), steps, action control, action bodies, supervision. The",
            "// first scan (SM0.1) is IEC scan 0: no transition fires, the initial steps are set and their",
            "// actions see the activation. Timers: 100 ms base; a step time counts whole 100 ms ticks.",
            "// Paste into STEP 7-Micro/WIN's STL editor (main program); the symbol table comes with --symbols.",
            "//",
            "// Allocation (address, kind, name, declaration):",
        ] {
            out.push_str(line);
            out.push('\n');
        }
        for row in self.rows() {
            let line = format!("//   {:<8} {:<7} {:<24} {}", row.addr, row.kind, row.name, row.detail);
            out.push_str(&ir::ascii(line.trim_end()));
            out.push('\n');
        }
        let unmapped: Vec<String> = self
            .vars
            .list
            .iter()
            .filter(|v| v.addr.is_none() && v.val.is_none() && v.counter().is_none())
            .map(|v| {
                format!("{} ({}{})", v.name, if v.constant { "CONSTANT " } else { "" }, v.ty.as_deref().unwrap_or("?"))
            })
            .collect();
        if !unmapped.is_empty() {
            let _ = writeln!(
                out,
                "// Not in the program (constants and TIME presets are folded; the chart reads no other variable): {}.",
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
        ir::print_networks(&self.networks, &self.resolve(), &mut out);
        out
    }

    /// Micro/WIN's symbol table as CSV: `Symbol,Address,Comment`. Symbols are made valid for
    /// Micro/WIN (letters, digits and `_`, not starting with a digit, at most 23 characters)
    /// and unique (case-insensitively).
    fn symbols(&self) -> String {
        let mut out = String::from("Symbol,Address,Comment\n");
        let mut taken: HashSet<String> = HashSet::new();
        for row in self.rows() {
            let sym = unique_symbol(&row.symbol, &mut taken);
            let comment = ir::ascii(&format!("{} {}: {}", row.kind, row.name, row.detail));
            let _ = writeln!(out, "{},{},{}", csv_field(&sym), csv_field(&row.addr), csv_field(&comment));
        }
        out
    }
}

/// A symbol name valid in Micro/WIN, unique among `taken`.
fn unique_symbol(name: &str, taken: &mut HashSet<String>) -> String {
    const MAX: usize = 23;
    let mut base: String = name.chars().map(|c| if c.is_ascii_alphanumeric() { c } else { '_' }).collect();
    if base.is_empty() || base.starts_with(|c: char| c.is_ascii_digit()) {
        base.insert(0, '_');
    }
    base.truncate(MAX);
    let mut sym = base.clone();
    let mut k = 2;
    while !taken.insert(sym.to_ascii_uppercase()) {
        let suffix = format!("_{k}");
        let mut b = base.clone();
        b.truncate(MAX - suffix.len());
        sym = b + &suffix;
        k += 1;
    }
    sym
}

/// RFC 4180 quoting where needed.
fn csv_field(s: &str) -> String {
    if s.contains([',', '"', '\n', '\r']) {
        format!("\"{}\"", s.replace('"', "\"\""))
    } else {
        s.to_string()
    }
}

/// The source text of a span on one line, shortened for comments and messages.
pub(crate) fn snippet(text: &str, span: Span) -> String {
    let s = ir::one_line(text.get(span.range()).unwrap_or(""));
    if s.chars().count() > 60 {
        let mut t: String = s.chars().take(57).collect();
        t.push_str("...");
        t
    } else {
        s
    }
}

/// Names read in a condition, with their spans.
fn condition_names(c: &ast::Condition, out: &mut Vec<(String, Span)>) {
    match c {
        ast::Condition::St(e) => expr_names(e, out),
        ast::Condition::Il(b) => il_names(b, out),
        ast::Condition::Missing => {}
    }
}

fn il_names(b: &ast::IlBody, out: &mut Vec<(String, Span)>) {
    fn list(ins: &[ast::IlInstruction], out: &mut Vec<(String, Span)>) {
        for i in ins {
            for e in &i.operands {
                expr_names(e, out);
            }
            if let Some(n) = &i.nested {
                list(n, out);
            }
        }
    }
    list(&b.instructions, out);
}

fn stmt_names(stmts: &[ast::Stmt], out: &mut Vec<(String, Span)>) {
    use ast::StmtKind as K;
    for s in stmts {
        match &s.kind {
            K::Assign { target, value } => {
                expr_names(target, out);
                expr_names(value, out);
            }
            K::Call(e) => expr_names(e, out),
            K::If { branches, else_body } => {
                for (c, b) in branches {
                    expr_names(c, out);
                    stmt_names(b, out);
                }
                if let Some(b) = else_body {
                    stmt_names(b, out);
                }
            }
            K::Case { selector, arms, else_body } => {
                expr_names(selector, out);
                for a in arms {
                    stmt_names(&a.body, out);
                }
                if let Some(b) = else_body {
                    stmt_names(b, out);
                }
            }
            K::For { from, to, by, body, .. } => {
                expr_names(from, out);
                expr_names(to, out);
                if let Some(b) = by {
                    expr_names(b, out);
                }
                stmt_names(body, out);
            }
            K::While { cond, body } | K::Repeat { body, until: cond } => {
                expr_names(cond, out);
                stmt_names(body, out);
            }
            _ => {}
        }
    }
}

fn expr_names(e: &ast::Expr, out: &mut Vec<(String, Span)>) {
    use ast::ExprKind as K;
    match &e.kind {
        K::Name(id) => out.push((id.text.clone(), e.span)),
        K::Member { base, .. } => expr_names(base, out),
        K::Index { base, indices } => {
            expr_names(base, out);
            for i in indices {
                expr_names(i, out);
            }
        }
        K::Call { args, .. } => {
            for a in args {
                if let Some(v) = &a.value {
                    expr_names(v, out);
                }
            }
        }
        K::Unary { operand, .. } => expr_names(operand, out),
        K::Binary { lhs, rhs, .. } => {
            expr_names(lhs, out);
            expr_names(rhs, out);
        }
        K::Paren(i) => expr_names(i, out),
        _ => {}
    }
}
