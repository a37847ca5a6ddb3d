//! Lowering of conditions (ST expressions, IL lists) and action bodies (BOOL assignments, IF,
//! IL load/store/set/reset) to bit logic over S7-200 operands, with a located diagnostic for
//! everything that has no faithful bit-logic form.

use super::ir::{one_line, Addr};
use super::vars::{bit_address, Vars};
use super::TIMER_BASE_US;
use sfc_diagnostics::{Diagnostic, Span};
use sfc_model::{Chart, StepId};
use sfc_st::{const_eval, parse_il_op, IlOp, Value};
use sfc_syntax::ast::{BinaryOp, Expr, ExprKind, IlBody, IlInstruction, Stmt, StmtKind, UnaryOp};
use std::collections::HashMap;

/// Largest preset of an S7-200 timer (`+32767`, 3276.7 s at 100 ms).
pub(crate) const MAX_PT: i64 = 32767;

/// A BOOL expression over bits.
#[derive(Debug, Clone, PartialEq)]
pub(crate) enum Logic {
    Const(bool),
    /// A contact: the bit, whether it is negated, and its symbolic name (for comments).
    Bit(Addr, bool, String),
    Not(Box<Logic>),
    And(Vec<Logic>),
    Or(Vec<Logic>),
    Xor(Box<Logic>, Box<Logic>),
}

impl Logic {
    pub(crate) fn bit(a: Addr, name: impl Into<String>) -> Logic {
        Logic::Bit(a, false, name.into())
    }
    pub(crate) fn not(self) -> Logic {
        match self {
            Logic::Const(b) => Logic::Const(!b),
            Logic::Bit(a, n, s) => Logic::Bit(a, !n, s),
            Logic::Not(x) => *x,
            other => Logic::Not(Box::new(other)),
        }
    }
    /// OR of bits (FALSE when there are none).
    pub(crate) fn any(bits: Vec<Logic>) -> Logic {
        match bits.len() {
            0 => Logic::Const(false),
            1 => bits.into_iter().next().unwrap_or(Logic::Const(false)),
            _ => Logic::Or(bits),
        }
    }
    /// Whether evaluating it reads `a`.
    pub(crate) fn reads(&self, a: Addr) -> bool {
        match self {
            Logic::Const(_) => false,
            Logic::Bit(b, _, _) => *b == a,
            Logic::Not(x) => x.reads(a),
            Logic::And(v) | Logic::Or(v) => v.iter().any(|x| x.reads(a)),
            Logic::Xor(x, y) => x.reads(a) || y.reads(a),
        }
    }
}

/// One statement of an action body, lowered.
#[derive(Debug, Clone, PartialEq)]
pub(crate) enum BodyOp {
    /// `target := value` (the value is computed before the bit changes).
    Assign { target: Addr, name: String, value: Logic, text: String },
    /// `IF c1 THEN … ELSIF c2 THEN … ELSE … END_IF`
    If { branches: Vec<(Logic, Vec<BodyOp>)>, else_body: Vec<BodyOp>, text: String },
}

/// What a timer of the timer table is for.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum TimerUse {
    /// `step.T >= pt · 100 ms`.
    Step(StepId),
    /// The L/D/SD/DS/SL timer of action-control entity `n`.
    Action(usize),
}

/// A timer the program needs; its number is chosen once all are known.
#[derive(Debug, Clone)]
pub(crate) struct TimerEntry {
    pub what: TimerUse,
    /// TONR (keeps its value while the step is inactive) instead of TON.
    pub retentive: bool,
    /// Preset in 100 ms units.
    pub pt: u16,
    pub label: String,
}

#[derive(Debug, Default)]
pub(crate) struct Timers {
    pub list: Vec<TimerEntry>,
    by_step: HashMap<(StepId, u16), usize>,
}

impl Timers {
    /// The timer whose bit is `step.T >= pt · 100 ms`; retentive once any reader needs the value
    /// while the step is inactive.
    fn step(&mut self, step: StepId, pt: u16, retentive: bool, label: String) -> usize {
        if let Some(&i) = self.by_step.get(&(step, pt)) {
            self.list[i].retentive |= retentive;
            return i;
        }
        let i = self.list.len();
        self.list.push(TimerEntry { what: TimerUse::Step(step), retentive, pt, label });
        self.by_step.insert((step, pt), i);
        i
    }
    pub(crate) fn action(&mut self, entity: usize, pt: u16, label: String) -> usize {
        self.list.push(TimerEntry { what: TimerUse::Action(entity), retentive: false, pt, label });
        self.list.len() - 1
    }
}

/// Where an expression is read.
pub(crate) struct Site<'s> {
    /// The chart element, for the diagnostics' `element`.
    pub element: &'s str,
    /// For a transition condition: the steps it leaves. A step time read there is needed only
    /// while the step is active (a TON suffices); anywhere else the frozen value of an inactive
    /// step may be read (a TONR keeps it).
    pub guard_of: Option<&'s [StepId]>,
}

/// The IL current result.
enum Cr {
    None,
    Bool(Logic),
    /// `LD S1.T`: a step time, waiting for its comparison.
    Time(StepId, Span),
}

/// Resolves names to bits and lowers code; reports what cannot be lowered.
pub(crate) struct Lowerer<'a> {
    pub chart: &'a Chart,
    pub vars: &'a Vars,
    /// Bit of each step.
    pub steps: &'a [Addr],
    /// `Q` and `A` bits of each action (`None`: the action is never associated, both FALSE).
    pub actions: &'a [Option<(Addr, Addr)>],
    pub timers: &'a mut Timers,
    pub diags: &'a mut Vec<Diagnostic>,
    pub text: &'a str,
}

impl Lowerer<'_> {
    fn err(&mut self, code: &'static str, span: Span, msg: impl Into<String>, site: &Site<'_>) {
        self.diags.push(Diagnostic::error(code, span, msg).with_element(site.element));
    }

    /// The source text of a span, on one line, shortened for comments and messages.
    pub(crate) fn snippet(&self, span: Span) -> String {
        let s = one_line(self.text.get(span.range()).unwrap_or(""));
        if s.chars().count() > 60 {
            let mut t: String = s.chars().take(57).collect();
            t.push_str("...");
            t
        } else {
            s
        }
    }

    /// A BOOL expression.
    pub(crate) fn expr(&mut self, e: &Expr, site: &Site<'_>) -> Option<Logic> {
        match &e.kind {
            ExprKind::Paren(inner) => self.expr(inner, site),
            ExprKind::Literal(_) => match const_eval(e, self.vars) {
                Some(Value::Bool(b)) => Some(Logic::Const(b)),
                _ => {
                    let msg =
                        format!("`{}` is not a BOOL value: S7-200 bit logic has only contacts", self.snippet(e.span));
                    self.err("SFC0810", e.span, msg, site);
                    None
                }
            },
            ExprKind::Name(id) => self.name(&id.text, e.span, site),
            ExprKind::Address(a) => match bit_address(a) {
                Ok(addr) => Some(Logic::bit(addr, a.text.clone())),
                Err(msg) => {
                    self.err("SFC0814", e.span, msg, site);
                    None
                }
            },
            ExprKind::Member { base, member } => self.member(base, &member.text, e.span, site),
            ExprKind::Unary { op: UnaryOp::Not, operand } => Some(self.expr(operand, site)?.not()),
            ExprKind::Binary { op, lhs, rhs } => match op {
                BinaryOp::And | BinaryOp::AndThen | BinaryOp::Or | BinaryOp::OrElse | BinaryOp::Xor => {
                    let l = self.expr(lhs, site);
                    let r = self.expr(rhs, site);
                    let (l, r) = (l?, r?);
                    Some(match op {
                        BinaryOp::And | BinaryOp::AndThen => Logic::And(vec![l, r]),
                        BinaryOp::Or | BinaryOp::OrElse => Logic::Or(vec![l, r]),
                        _ => Logic::Xor(Box::new(l), Box::new(r)),
                    })
                }
                BinaryOp::Eq | BinaryOp::Ne | BinaryOp::Lt | BinaryOp::Gt | BinaryOp::Le | BinaryOp::Ge => {
                    self.compare(*op, lhs, rhs, e.span, site)
                }
                _ => {
                    let msg = format!(
                        "arithmetic (`{}`) cannot be expressed in S7-200 bit logic: `{}`",
                        op.symbol(),
                        self.snippet(e.span)
                    );
                    self.err("SFC0810", e.span, msg, site);
                    None
                }
            },
            ExprKind::Unary { .. } => {
                let msg = format!("arithmetic cannot be expressed in S7-200 bit logic: `{}`", self.snippet(e.span));
                self.err("SFC0810", e.span, msg, site);
                None
            }
            ExprKind::Call { callee, .. } => {
                let msg = format!("the call of `{}` cannot be expressed in S7-200 bit logic", callee.text);
                self.err("SFC0810", e.span, msg, site);
                None
            }
            ExprKind::Index { .. } => {
                let msg = format!("array elements (`{}`) are not bits of the S7-200 program", self.snippet(e.span));
                self.err("SFC0810", e.span, msg, site);
                None
            }
            // A syntax error, already reported.
            ExprKind::Error => None,
        }
    }

    fn name(&mut self, name: &str, span: Span, site: &Site<'_>) -> Option<Logic> {
        if let Some(i) = self.vars.get(name) {
            let v = &self.vars.list[i];
            if !v.is_bool() {
                let msg = format!(
                    "`{}` is {}: only BOOL variables can be read by S7-200 bit logic",
                    v.name,
                    v.ty.as_deref().unwrap_or("not an elementary type")
                );
                self.err("SFC0810", span, msg, site);
                return None;
            }
            if v.constant {
                return Some(Logic::Const(matches!(v.init, Some(Value::Bool(true)))));
            }
            // A variable without a bit had its location refused at its declaration.
            let addr = v.addr?;
            return Some(Logic::bit(addr, v.name.clone()));
        }
        if sfc_st::is_sfc_control_variable(name) {
            let msg = format!("the chart control variable `{name}` is not implemented by the S7-200 program");
            self.err("SFC0816", span, msg, site);
            return None;
        }
        let msg = if self.chart.step(name).is_some() {
            format!("a step is not a value: write `{name}.X` for its flag")
        } else {
            format!("`{name}` is not a BOOL variable the S7-200 program can read")
        };
        self.err("SFC0810", span, msg, site);
        None
    }

    fn member(&mut self, base: &Expr, member: &str, span: Span, site: &Site<'_>) -> Option<Logic> {
        if let ExprKind::Name(id) = &base.kind {
            if let Some(s) = self.chart.step(&id.text) {
                if member.eq_ignore_ascii_case("X") {
                    let addr = *self.steps.get(s)?;
                    return Some(Logic::bit(addr, format!("{}.X", self.chart.steps[s].name)));
                }
                if member.eq_ignore_ascii_case("T") {
                    let msg = format!(
                        "the step time `{}` can only be compared with a constant duration (`{}.T >= T#5s`)",
                        self.snippet(span),
                        self.chart.steps[s].name
                    );
                    self.err("SFC0812", span, msg, site);
                    return None;
                }
            }
            if let Some(a) = self.chart.action(&id.text) {
                let q = member.eq_ignore_ascii_case("Q");
                if q || member.eq_ignore_ascii_case("A") {
                    let name = format!("{}.{}", self.chart.actions[a].name, if q { "Q" } else { "A" });
                    return Some(match self.actions.get(a).copied().flatten() {
                        Some((qa, aa)) => Logic::bit(if q { qa } else { aa }, name),
                        None => Logic::Const(false),
                    });
                }
            }
        }
        let msg = format!("`{}` cannot be read by the S7-200 program", self.snippet(span));
        self.err("SFC0810", span, msg, site);
        None
    }

    /// `S.T` (possibly in parentheses).
    fn step_time(&self, e: &Expr) -> Option<StepId> {
        match &e.kind {
            ExprKind::Paren(inner) => self.step_time(inner),
            ExprKind::Member { base, member } if member.text.eq_ignore_ascii_case("T") => match &base.kind {
                ExprKind::Name(id) => self.chart.step(&id.text),
                _ => None,
            },
            _ => None,
        }
    }

    fn compare(&mut self, op: BinaryOp, lhs: &Expr, rhs: &Expr, span: Span, site: &Site<'_>) -> Option<Logic> {
        if let Some(s) = self.step_time(lhs) {
            return self.time_compare(s, op, rhs, span, site);
        }
        if let Some(s) = self.step_time(rhs) {
            let flipped = match op {
                BinaryOp::Lt => BinaryOp::Gt,
                BinaryOp::Gt => BinaryOp::Lt,
                BinaryOp::Le => BinaryOp::Ge,
                BinaryOp::Ge => BinaryOp::Le,
                other => other,
            };
            return self.time_compare(s, flipped, lhs, span, site);
        }
        if matches!(op, BinaryOp::Eq | BinaryOp::Ne) {
            // BOOL = BOOL is XNOR, BOOL <> BOOL is XOR; anything else is not bit logic.
            let mark = self.diags.len();
            let l = self.expr(lhs, site);
            let r = self.expr(rhs, site);
            if let (Some(l), Some(r)) = (l, r) {
                let x = Logic::Xor(Box::new(l), Box::new(r));
                return Some(if op == BinaryOp::Eq { x.not() } else { x });
            }
            self.diags.truncate(mark);
        }
        let msg = format!(
            "the comparison `{}` cannot be expressed in S7-200 bit logic (only BOOL values and step times \
             compared with constants)",
            self.snippet(span)
        );
        self.err("SFC0810", span, msg, site);
        None
    }

    /// `step.T op c` with `c` a constant duration, through timer bits: `T >= c` is the bit of a
    /// timer with preset `c`; `T > c` is `T >= c + 100 ms` (step times advance in whole timer
    /// ticks); `<` and `<=` are the negated contacts; `=` and `<>` combine two timers.
    fn time_compare(&mut self, s: StepId, op: BinaryOp, other: &Expr, span: Span, site: &Site<'_>) -> Option<Logic> {
        let c = match const_eval(other, self.vars) {
            Some(Value::Time(c)) => c,
            _ => {
                let msg = format!(
                    "`{}` is not a constant duration: an S7-200 timer preset must be known when the program is \
                     generated (write a literal, or declare the variable CONSTANT)",
                    self.snippet(other.span)
                );
                self.err("SFC0812", other.span, msg, site);
                return None;
            }
        };
        if c % TIMER_BASE_US != 0 {
            let msg = format!(
                "{} is not a multiple of 100 ms, the resolution of the S7-200 timers used for step times",
                fmt_time(c)
            );
            self.err("SFC0812", other.span, msg, site);
            return None;
        }
        let n = c / TIMER_BASE_US;
        let needed = match op {
            BinaryOp::Ge | BinaryOp::Lt => n,
            _ => n + 1,
        };
        if needed > MAX_PT {
            let msg = format!(
                "`{}` needs a timer preset of {needed} × 100 ms, beyond the S7-200 maximum of +32767 (3276.7 s)",
                self.snippet(span)
            );
            self.err("SFC0812", span, msg, site);
            return None;
        }
        let retentive = !site.guard_of.is_some_and(|pre| pre.contains(&s));
        let step_name = self.chart.steps[s].name.clone();
        let ge = |k: i64, timers: &mut Timers| -> Logic {
            if k <= 0 {
                return Logic::Const(true);
            }
            let pt = k as u16;
            let label = format!("{step_name}.T >= {}", fmt_time(k * TIMER_BASE_US));
            let t = timers.step(s, pt, retentive, label.clone());
            Logic::bit(Addr::Timer(t), label)
        };
        Some(match op {
            BinaryOp::Ge => ge(n, self.timers),
            BinaryOp::Gt => ge(n + 1, self.timers),
            BinaryOp::Lt => ge(n, self.timers).not(),
            BinaryOp::Le => ge(n + 1, self.timers).not(),
            BinaryOp::Eq => Logic::And(vec![ge(n, self.timers), ge(n + 1, self.timers).not()]),
            _ => Logic::Or(vec![ge(n, self.timers).not(), ge(n + 1, self.timers)]),
        })
    }

    // ---------------------------------------------------------------------------------------
    // IL

    /// An IL transition condition: the current result at the end of the list.
    pub(crate) fn il_condition(&mut self, body: &IlBody, site: &Site<'_>) -> Option<Logic> {
        match self.il_list(&body.instructions, Cr::None, site, None)? {
            Cr::Bool(l) => Some(l),
            Cr::Time(_, span) => {
                self.err("SFC0812", span, "a step time alone is not a condition: compare it with a duration", site);
                None
            }
            Cr::None => {
                self.err("SFC0810", body.span, "the IL condition computes no result", site);
                None
            }
        }
    }

    /// Runs the expression operators of an instruction list (LD, AND, OR, XOR and their N forms,
    /// NOT, the comparisons of a step time). With `body`, the stores (ST, STN, S, R) become
    /// statements; without it they, and everything else, are refused.
    fn il_list(
        &mut self,
        list: &[IlInstruction],
        mut cr: Cr,
        site: &Site<'_>,
        mut body: Option<&mut Vec<BodyOp>>,
    ) -> Option<Cr> {
        let mut ok = true;
        for ins in list {
            // Label-only lines and the closing `)` of a nested list.
            let Some(op_id) = &ins.op else { continue };
            let parsed = parse_il_op(&op_id.text);
            let Some((op, neg, conditional)) = parsed else {
                let msg = format!("the IL operator `{}` cannot be translated to S7-200 bit logic", op_id.text);
                self.err("SFC0810", ins.span, msg, site);
                return None;
            };
            match op {
                IlOp::Ld => match self.il_operand(ins, site) {
                    Some(Cr::Bool(l)) => cr = Cr::Bool(if neg { l.not() } else { l }),
                    Some(Cr::Time(s, span)) if !neg => cr = Cr::Time(s, span),
                    Some(_) => {
                        self.err("SFC0812", ins.span, "`LDN` of a step time is not a BOOL value", site);
                        ok = false;
                    }
                    None => ok = false,
                },
                IlOp::Binary(b @ (BinaryOp::And | BinaryOp::Or | BinaryOp::Xor)) => {
                    let value = match &ins.nested {
                        Some(nested) => {
                            let first = match ins.operands.first() {
                                Some(_) => self.il_operand(ins, site),
                                None => Some(Cr::None),
                            };
                            match first {
                                Some(start) => self.il_list(nested, start, site, None),
                                None => None,
                            }
                        }
                        None => self.il_operand(ins, site),
                    };
                    match (&mut cr, value) {
                        (Cr::Bool(l), Some(Cr::Bool(v))) => {
                            let v = if neg { v.not() } else { v };
                            let l = std::mem::replace(l, Logic::Const(false));
                            cr = Cr::Bool(match b {
                                BinaryOp::And => Logic::And(vec![l, v]),
                                BinaryOp::Or => Logic::Or(vec![l, v]),
                                _ => Logic::Xor(Box::new(l), Box::new(v)),
                            });
                        }
                        (_, None) => ok = false,
                        _ => {
                            let msg = format!("`{}` needs BOOL operands here", op_id.text);
                            self.err("SFC0810", ins.span, msg, site);
                            ok = false;
                        }
                    }
                }
                IlOp::Binary(
                    cmp @ (BinaryOp::Eq | BinaryOp::Ne | BinaryOp::Lt | BinaryOp::Gt | BinaryOp::Le | BinaryOp::Ge),
                ) => match (&cr, ins.operands.first(), &ins.nested) {
                    (Cr::Time(s, _), Some(operand), None) => {
                        let (s, span) = (*s, ins.span);
                        match self.time_compare(s, cmp, operand, span, site) {
                            Some(l) => cr = Cr::Bool(l),
                            None => ok = false,
                        }
                    }
                    _ => {
                        let msg = format!(
                            "`{}` cannot be expressed in S7-200 bit logic (only a step time compared with a constant)",
                            self.snippet(ins.span)
                        );
                        self.err("SFC0810", ins.span, msg, site);
                        ok = false;
                    }
                },
                IlOp::Not => match &mut cr {
                    Cr::Bool(l) => {
                        let l = std::mem::replace(l, Logic::Const(false));
                        cr = Cr::Bool(l.not());
                    }
                    _ => {
                        self.err("SFC0810", ins.span, "`NOT` needs a BOOL current result", site);
                        ok = false;
                    }
                },
                IlOp::St | IlOp::Set | IlOp::Reset if body.is_some() && !conditional => {
                    let Some(ops) = body.as_deref_mut() else { continue };
                    let Some(target) = ins.operands.first() else { continue };
                    let Some((addr, name)) = self.target(target, site) else {
                        ok = false;
                        continue;
                    };
                    let Cr::Bool(value) = &cr else {
                        let msg = format!("`{}` stores no BOOL result", self.snippet(ins.span));
                        self.err("SFC0811", ins.span, msg, site);
                        ok = false;
                        continue;
                    };
                    let text = self.snippet(ins.span);
                    if op == IlOp::St {
                        let value = if neg { value.clone().not() } else { value.clone() };
                        ops.push(BodyOp::Assign { target: addr, name: name.clone(), value, text });
                        // The current result is now the stored bit (or its negation).
                        let l = Logic::bit(addr, name);
                        cr = Cr::Bool(if neg { l.not() } else { l });
                    } else {
                        if value.reads(addr) {
                            let msg = format!(
                                "`{}`: the current result reads `{name}` itself, so it would change under the store",
                                text
                            );
                            self.err("SFC0811", ins.span, msg, site);
                            ok = false;
                            continue;
                        }
                        let set = op == IlOp::Set;
                        let assign =
                            BodyOp::Assign { target: addr, name, value: Logic::Const(set), text: text.clone() };
                        ops.push(BodyOp::If { branches: vec![(value.clone(), vec![assign])], else_body: vec![], text });
                    }
                }
                _ => {
                    let msg = if body.is_some() {
                        format!(
                            "the IL instruction `{}` cannot be translated (S7-200 action bodies: LD, AND, OR, XOR, \
                             NOT, ST, S, R on BOOL variables)",
                            self.snippet(ins.span)
                        )
                    } else {
                        format!("the IL instruction `{}` cannot be part of a condition", self.snippet(ins.span))
                    };
                    let code = if body.is_some() { "SFC0811" } else { "SFC0810" };
                    self.err(code, ins.span, msg, site);
                    ok = false;
                }
            }
        }
        ok.then_some(cr)
    }

    fn il_operand(&mut self, ins: &IlInstruction, site: &Site<'_>) -> Option<Cr> {
        let Some(e) = ins.operands.first() else {
            let msg = format!("`{}` has no operand", self.snippet(ins.span));
            self.err("SFC0810", ins.span, msg, site);
            return None;
        };
        if let Some(s) = self.step_time(e) {
            return Some(Cr::Time(s, e.span));
        }
        self.expr(e, site).map(Cr::Bool)
    }

    // ---------------------------------------------------------------------------------------
    // Action bodies

    /// A variable an action body writes.
    fn target(&mut self, e: &Expr, site: &Site<'_>) -> Option<(Addr, String)> {
        match &e.kind {
            ExprKind::Paren(inner) => self.target(inner, site),
            ExprKind::Name(id) => {
                let Some(i) = self.vars.get(&id.text) else {
                    let msg = format!("`{}` is not a BOOL variable the S7-200 program can write", id.text);
                    self.err("SFC0811", e.span, msg, site);
                    return None;
                };
                let v = &self.vars.list[i];
                if !v.is_bit() {
                    let msg = format!(
                        "`{}` is {}: the S7-200 program assigns BOOL variables only",
                        v.name,
                        if v.constant {
                            "a constant".to_string()
                        } else {
                            v.ty.clone().unwrap_or_else(|| "not BOOL".to_string())
                        }
                    );
                    self.err("SFC0811", e.span, msg, site);
                    return None;
                }
                let (name, addr) = (v.name.clone(), v.addr?);
                self.writable(addr, &name, e.span, site)?;
                Some((addr, name))
            }
            ExprKind::Address(a) => match bit_address(a) {
                Ok(addr) => {
                    self.writable(addr, &a.text, e.span, site)?;
                    Some((addr, a.text.clone()))
                }
                Err(msg) => {
                    self.err("SFC0814", e.span, msg, site);
                    None
                }
            },
            _ => {
                let msg = format!("`{}` cannot be assigned by the S7-200 program", self.snippet(e.span));
                self.err("SFC0811", e.span, msg, site);
                None
            }
        }
    }

    fn writable(&mut self, addr: Addr, name: &str, span: Span, site: &Site<'_>) -> Option<()> {
        if let Addr::Bit(super::ir::Area::I, byte, bit) = addr {
            let msg = format!("`{name}` is the input I{byte}.{bit}: the program cannot write the input image");
            self.err("SFC0814", span, msg, site);
            return None;
        }
        Some(())
    }

    /// An ST action body.
    pub(crate) fn st_body(&mut self, stmts: &[Stmt], site: &Site<'_>) -> Option<Vec<BodyOp>> {
        let mut out = Vec::new();
        let mut ok = true;
        for s in stmts {
            match &s.kind {
                StmtKind::Empty => {}
                StmtKind::Assign { target, value } => {
                    // The value is lowered only for a BOOL target: one diagnostic per statement.
                    let t = self.target(target, site);
                    let v = match t {
                        Some(_) => self.expr(value, site),
                        None => None,
                    };
                    match (t, v) {
                        (Some((target, name)), Some(value)) => {
                            out.push(BodyOp::Assign { target, name, value, text: self.snippet(s.span) })
                        }
                        _ => ok = false,
                    }
                }
                StmtKind::If { branches, else_body } => {
                    let mut lowered = Vec::new();
                    for (c, body) in branches {
                        let c = self.expr(c, site);
                        let b = self.st_body(body, site);
                        match (c, b) {
                            (Some(c), Some(b)) => lowered.push((c, b)),
                            _ => ok = false,
                        }
                    }
                    let e = match else_body {
                        Some(b) => self.st_body(b, site),
                        None => Some(Vec::new()),
                    };
                    let head = self.text.get(s.span.range()).and_then(|t| t.lines().next()).unwrap_or("IF");
                    let text = one_line(head);
                    match e {
                        Some(else_body) if ok => out.push(BodyOp::If { branches: lowered, else_body, text }),
                        _ => ok = false,
                    }
                }
                other => {
                    let what = match other {
                        StmtKind::Call(_) => "a call (function or function block)",
                        StmtKind::Case { .. } => "CASE",
                        StmtKind::For { .. } => "FOR",
                        StmtKind::While { .. } => "WHILE",
                        StmtKind::Repeat { .. } => "REPEAT",
                        StmtKind::Exit => "EXIT",
                        StmtKind::Return => "RETURN",
                        _ => "this statement",
                    };
                    let msg = format!(
                        "{what} cannot be translated: S7-200 action bodies are BOOL assignments and IF statements"
                    );
                    self.err("SFC0811", s.span, msg, site);
                    ok = false;
                }
            }
        }
        ok.then_some(out)
    }

    /// An IL action body.
    pub(crate) fn il_body(&mut self, body: &IlBody, site: &Site<'_>) -> Option<Vec<BodyOp>> {
        let mut ops = Vec::new();
        self.il_list(&body.instructions, Cr::None, site, Some(&mut ops))?;
        Some(ops)
    }
}

/// `T#1m30s`, `T#500ms`, `T#0s`, `-T#1s`.
pub(crate) fn fmt_time(us: i64) -> String {
    if us < 0 {
        return format!("-{}", fmt_time(us.checked_neg().unwrap_or(i64::MAX)));
    }
    let mut rest = us;
    let mut s = String::from("T#");
    for (unit, name) in
        [(86_400_000_000, "d"), (3_600_000_000, "h"), (60_000_000, "m"), (1_000_000, "s"), (1_000, "ms")]
    {
        if rest >= unit {
            s.push_str(&format!("{}{name}", rest / unit));
            rest %= unit;
        }
    }
    if rest > 0 {
        s.push_str(&format!("{rest}us"));
    }
    if s.len() == 2 {
        s.push_str("0s");
    }
    s
}
