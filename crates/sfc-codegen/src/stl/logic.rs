//! Lowering of conditions (ST expressions, IL lists) and action bodies (BOOL and integer
//! assignments, IF, counter calls, IL load/store/set/reset) to S7-200 operands, with a located
//! diagnostic for everything that has no faithful S7-200 form.

use super::ir::{Addr, ArithOp, CmpOp, Val};
use super::vars::{bit_address, CounterKind, IntTy, Vars};
use super::TIMER_BASE_US;
use sfc_diagnostics::{Diagnostic, Span};
use sfc_model::{Chart, StepId};
use sfc_st::{const_eval, parse_il_op, IlOp, Value};
use sfc_syntax::ast::{BinaryOp, Expr, ExprKind, Ident, IlBody, IlInstruction, LiteralKind, Stmt, StmtKind, UnaryOp};
use std::collections::HashMap;

/// Largest preset of an S7-200 timer (`+32767`, 3276.7 s at 100 ms).
pub(crate) const MAX_PT: i64 = 32767;

/// An integer computation over S7-200 values; every node has the width of the whole
/// expression except below [`IntExpr::Widen`].
#[derive(Debug, Clone, PartialEq)]
pub(crate) enum IntExpr {
    Val(Val),
    Bin(ArithOp, Box<IntExpr>, Box<IntExpr>),
    /// `a MOD b` (as `a - (a / b) * b`).
    Mod(Box<IntExpr>, Box<IntExpr>),
    Neg(Box<IntExpr>),
    /// An INT widened to DINT (`ITD`).
    Widen(Box<IntExpr>),
}

impl IntExpr {
    pub(crate) fn reads(&self, v: Val) -> bool {
        match self {
            IntExpr::Val(x) => *x == v,
            IntExpr::Bin(_, a, b) | IntExpr::Mod(a, b) => a.reads(v) || b.reads(v),
            IntExpr::Neg(a) | IntExpr::Widen(a) => a.reads(v),
        }
    }
}

/// A comparison of two integers: a compare contact.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Compare {
    pub op: CmpOp,
    pub wide: bool,
    pub a: IntExpr,
    pub b: IntExpr,
    /// Source text, for comments.
    pub text: String,
}

/// A BOOL expression over bits and compare contacts.
#[derive(Debug, Clone, PartialEq)]
pub(crate) enum Logic {
    Const(bool),
    /// A contact: the bit, whether it is negated, and its symbolic name (for comments).
    Bit(Addr, bool, String),
    Cmp(Compare),
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
            Logic::Cmp(c) => Logic::Cmp(Compare { op: c.op.negate(), ..c }),
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
    /// Whether evaluating it reads bit `a`.
    pub(crate) fn reads(&self, a: Addr) -> bool {
        match self {
            Logic::Const(_) | Logic::Cmp(_) => false,
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
    /// `target := value` for a BOOL (the value is computed before the bit changes).
    Assign { target: Addr, name: String, value: Logic, text: String },
    /// `target := value` for an integer.
    Move { target: Val, wide: bool, name: String, value: IntExpr, text: String },
    /// `IF c1 THEN … ELSIF c2 THEN … ELSE … END_IF`
    If { branches: Vec<(Logic, Vec<BodyOp>)>, else_body: Vec<BodyOp>, text: String },
    /// A call of a counter block: its S7-200 counter instruction, skipped (JMP) in the scans
    /// in which the call does not run, as an IEC block that is not called.
    Count {
        counter: usize,
        kind: CounterKind,
        up: Logic,
        down: Logic,
        reset: Logic,
        preset: Val,
        /// CTUD: the bit that holds `QD` (`CV <= 0` as of the last call).
        qd: Option<Addr>,
        text: String,
    },
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
    pub(crate) fn step(&mut self, step: StepId, pt: u16, retentive: bool, label: String) -> usize {
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

/// A counter instance of the chart (a variable of type CTU, CTD or CTUD).
#[derive(Debug, Clone)]
pub(crate) struct CounterEntry {
    pub var: usize,
    pub kind: CounterKind,
    /// Where it is called (one call site at most).
    pub call: Option<Span>,
    /// CTUD: the bit that holds `QD` (an IEC output keeps its value between calls; the S7-200
    /// CTUD has only the `QU` bit).
    pub qd: Option<Addr>,
}

#[derive(Debug, Default)]
pub(crate) struct Counters {
    pub list: Vec<CounterEntry>,
}

impl Counters {
    fn of(&mut self, var: usize, kind: CounterKind) -> usize {
        if let Some(i) = self.list.iter().position(|c| c.var == var) {
            return i;
        }
        self.list.push(CounterEntry { var, kind, call: None, qd: None });
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

/// An assignment target.
enum Target {
    Bit(Addr, String),
    Word(Val, IntTy, String),
}

/// Resolves names to operands and lowers code; reports what cannot be lowered.
pub(crate) struct Lowerer<'a> {
    pub chart: &'a Chart,
    pub vars: &'a Vars,
    /// Bit of each step.
    pub steps: &'a [Addr],
    /// `Q` and `A` bits of each action (`None`: the action is never associated, both FALSE).
    pub actions: &'a [Option<(Addr, Addr)>],
    /// The `QD` bit of each CTUD instance, by variable index.
    pub ctud_qd: &'a HashMap<usize, Addr>,
    pub timers: &'a mut Timers,
    pub counters: &'a mut Counters,
    pub diags: &'a mut Vec<Diagnostic>,
    pub text: &'a str,
}

impl Lowerer<'_> {
    fn err(&mut self, code: &'static str, span: Span, msg: impl Into<String>, site: &Site<'_>) {
        self.diags.push(Diagnostic::error(code, span, msg).with_element(site.element));
    }

    /// The source text of a span, on one line, shortened for comments and messages.
    pub(crate) fn snippet(&self, span: Span) -> String {
        super::snippet(self.text, span)
    }

    /// A BOOL expression.
    pub(crate) fn expr(&mut self, e: &Expr, site: &Site<'_>) -> Option<Logic> {
        match &e.kind {
            ExprKind::Paren(inner) => self.expr(inner, site),
            ExprKind::Literal(_) => match const_eval(e, self.vars) {
                Some(Value::Bool(b)) => Some(Logic::Const(b)),
                _ => {
                    let msg = format!("`{}` is not a BOOL value", self.snippet(e.span));
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
                    if let Some(Value::Bool(b)) = const_eval(e, self.vars) {
                        return Some(Logic::Const(b));
                    }
                    self.compare(*op, lhs, rhs, e.span, site)
                }
                _ => {
                    let msg = format!("`{}` is a number, not a BOOL condition", self.snippet(e.span));
                    self.err("SFC0810", e.span, msg, site);
                    None
                }
            },
            ExprKind::Unary { .. } => {
                let msg = format!("`{}` is a number, not a BOOL condition", self.snippet(e.span));
                self.err("SFC0810", e.span, msg, site);
                None
            }
            ExprKind::Call { callee: Ident { text, .. }, .. }
            | ExprKind::MemberCall { member: Ident { text, .. }, .. } => {
                let msg = format!(
                    "the call of `{text}` cannot be translated to the S7-200 program (only counter blocks, called \
                     as a statement in an action)"
                );
                self.err("SFC0810", e.span, msg, site);
                None
            }
            ExprKind::Index { .. } => {
                let msg = format!("array elements (`{}`) are not operands of the S7-200 program", self.snippet(e.span));
                self.err("SFC0810", e.span, msg, site);
                None
            }
            ExprKind::Deref(_) => {
                let msg = format!("pointers (`{}`) are not operands of the S7-200 program", self.snippet(e.span));
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
                    "`{}` is {}: a condition needs a BOOL (compare a number: `{} > 0`)",
                    v.name,
                    v.ty.as_deref().unwrap_or("not an elementary type"),
                    v.name
                );
                self.err("SFC0810", span, msg, site);
                return None;
            }
            if v.constant {
                return Some(Logic::Const(matches!(v.init, Some(Value::Bool(true)))));
            }
            // A variable without a bit had its location (or its kind) refused at its declaration.
            let addr = v.addr?;
            return Some(Logic::bit(addr, v.name.clone()));
        }
        if sfc_st::is_sfc_control_variable(name) {
            // Refused where it is declared or collected (SFC0816).
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

    /// A counter instance `name`, if the variable is one.
    fn counter(&mut self, name: &str) -> Option<(usize, CounterKind)> {
        let i = self.vars.get(name)?;
        let kind = self.vars.list[i].counter()?;
        let c = self.counters.of(i, kind);
        self.counters.list[c].qd = self.ctud_qd.get(&i).copied();
        Some((c, kind))
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
                        "the step time `{}` can only be compared with a duration (`{}.T >= T#5s`)",
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
            if let Some((c, kind)) = self.counter(&id.text) {
                let m = member.to_ascii_uppercase();
                let name = format!("{}.{m}", id.text);
                match (kind, m.as_str()) {
                    (CounterKind::Ctu | CounterKind::Ctd, "Q") | (CounterKind::Ctud, "QU") => {
                        return Some(Logic::bit(Addr::Counter(c), name));
                    }
                    (CounterKind::Ctud, "QD") => {
                        let qd = self.counters.list[c].qd?;
                        return Some(Logic::bit(qd, name));
                    }
                    _ => {}
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
        if matches!(op, BinaryOp::Eq | BinaryOp::Ne) && (self.is_bool(lhs) || self.is_bool(rhs)) {
            // BOOL = BOOL is XNOR, BOOL <> BOOL is XOR.
            let l = self.expr(lhs, site);
            let r = self.expr(rhs, site);
            let x = Logic::Xor(Box::new(l?), Box::new(r?));
            return Some(if op == BinaryOp::Eq { x.not() } else { x });
        }
        let cmp = match op {
            BinaryOp::Eq => CmpOp::Eq,
            BinaryOp::Ne => CmpOp::Ne,
            BinaryOp::Lt => CmpOp::Lt,
            BinaryOp::Le => CmpOp::Le,
            BinaryOp::Gt => CmpOp::Gt,
            _ => CmpOp::Ge,
        };
        let mark = self.diags.len();
        // One diagnostic per comparison: the right side is judged only when the left is fine.
        let (a, ta) = self.int_expr(lhs, site)?;
        let (b, tb) = self.int_expr(rhs, site)?;
        let ((a, b), ty) = self.unify(a, ta, b, tb, span, site)?;
        if !ty.signed() && !matches!(cmp, CmpOp::Eq | CmpOp::Ne) {
            let msg = format!(
                "`{}` compares {} values by size; the S7-200 compare contacts are signed, so only = and <> \
                 are exact for unsigned types (declare the variables INT or DINT)",
                self.snippet(span),
                ty.name()
            );
            self.err("SFC0810", span, msg, site);
            return None;
        }
        debug_assert_eq!(self.diags.len(), mark);
        Some(Logic::Cmp(Compare { op: cmp, wide: ty.wide(), a, b, text: self.snippet(span) }))
    }

    /// Whether `e` is a BOOL operand (so `=` is XNOR).
    fn is_bool(&self, e: &Expr) -> bool {
        match &e.kind {
            ExprKind::Paren(i) => self.is_bool(i),
            ExprKind::Literal(l) => matches!(l.kind, LiteralKind::Bool(_)),
            ExprKind::Name(id) => self.vars.get(&id.text).is_some_and(|i| self.vars.list[i].is_bool()),
            ExprKind::Address(a) => a.size.eq_ignore_ascii_case(&'X'),
            ExprKind::Member { base, member } => {
                let m = member.text.to_ascii_uppercase();
                match &base.kind {
                    ExprKind::Name(id) => {
                        (self.chart.step(&id.text).is_some() && m == "X")
                            || (self.chart.action(&id.text).is_some() && (m == "Q" || m == "A"))
                            || (self.vars.get(&id.text).is_some_and(|i| self.vars.list[i].counter().is_some())
                                && m.starts_with('Q'))
                    }
                    _ => false,
                }
            }
            ExprKind::Unary { op: UnaryOp::Not, .. } => true,
            ExprKind::Binary { op, .. } => matches!(
                op,
                BinaryOp::And
                    | BinaryOp::AndThen
                    | BinaryOp::Or
                    | BinaryOp::OrElse
                    | BinaryOp::Xor
                    | BinaryOp::Eq
                    | BinaryOp::Ne
                    | BinaryOp::Lt
                    | BinaryOp::Gt
                    | BinaryOp::Le
                    | BinaryOp::Ge
            ),
            _ => false,
        }
    }

    /// Brings two operands to one type: an untyped literal takes the other's type, an INT
    /// operand of a DINT operation is widened (`ITD`).
    fn unify(
        &mut self,
        a: IntExpr,
        ta: Option<IntTy>,
        b: IntExpr,
        tb: Option<IntTy>,
        span: Span,
        site: &Site<'_>,
    ) -> Option<((IntExpr, IntExpr), IntTy)> {
        let fit = |e: IntExpr, ty: IntTy| match e {
            IntExpr::Val(Val::Const(c)) => IntExpr::Val(Val::Const(ty.stored(i128::from(c)))),
            other => other,
        };
        let ty = match (ta, tb) {
            (Some(x), Some(y)) if x == y => x,
            (Some(IntTy::Int), Some(IntTy::DInt)) => return Some(((IntExpr::Widen(Box::new(a)), b), IntTy::DInt)),
            (Some(IntTy::DInt), Some(IntTy::Int)) => return Some(((a, IntExpr::Widen(Box::new(b))), IntTy::DInt)),
            (Some(x), Some(y)) => {
                let msg = format!(
                    "`{}` mixes {} and {}: convert one of them explicitly (only INT widens to DINT here)",
                    self.snippet(span),
                    x.name(),
                    y.name()
                );
                self.err("SFC0810", span, msg, site);
                return None;
            }
            (Some(x), None) | (None, Some(x)) => x,
            (None, None) => {
                let big = |e: &IntExpr| matches!(e, IntExpr::Val(Val::Const(c)) if !(-32768..=32767).contains(c));
                if big(&a) || big(&b) {
                    IntTy::DInt
                } else {
                    IntTy::Int
                }
            }
        };
        Some(((fit(a, ty), fit(b, ty)), ty))
    }

    /// An integer expression; the type is `None` for an untyped literal (it takes the type of
    /// the other operand).
    pub(crate) fn int_expr(&mut self, e: &Expr, site: &Site<'_>) -> Option<(IntExpr, Option<IntTy>)> {
        if let Some(v) = const_eval(e, self.vars) {
            let Value::Int(i) = v else {
                let msg = format!("`{}` is not an integer", self.snippet(e.span));
                self.err("SFC0810", e.span, msg, site);
                return None;
            };
            let typed = match &e.kind {
                ExprKind::Literal(l) => l.type_prefix.as_deref().and_then(IntTy::of),
                ExprKind::Name(id) => self.vars.get(&id.text).and_then(|k| self.vars.list[k].int_ty()),
                _ => None,
            };
            let c = match typed {
                Some(t) => t.stored(i),
                None => match i64::try_from(i) {
                    Ok(c) if (-(1i64 << 31)..(1i64 << 32)).contains(&c) => c,
                    _ => {
                        let msg = format!("`{}` does not fit 32 bits", self.snippet(e.span));
                        self.err("SFC0810", e.span, msg, site);
                        return None;
                    }
                },
            };
            return Some((IntExpr::Val(Val::Const(c)), typed));
        }
        match &e.kind {
            ExprKind::Paren(inner) => self.int_expr(inner, site),
            ExprKind::Name(id) => {
                let Some(i) = self.vars.get(&id.text) else {
                    let msg = format!("`{}` is not a variable the S7-200 program can read", id.text);
                    self.err("SFC0810", e.span, msg, site);
                    return None;
                };
                let v = &self.vars.list[i];
                match (v.int_ty(), v.val) {
                    (Some(ty), Some(val)) => Some((IntExpr::Val(val), Some(ty))),
                    (Some(_), None) => None, // its location was refused at the declaration
                    (None, _) => {
                        let msg = format!(
                            "`{}` is {}: the S7-200 program computes with INT, UINT, WORD, DINT, UDINT and DWORD",
                            v.name,
                            v.ty.as_deref().unwrap_or("not an elementary type")
                        );
                        self.err("SFC0810", e.span, msg, site);
                        None
                    }
                }
            }
            ExprKind::Member { base, member } => {
                if let ExprKind::Name(id) = &base.kind {
                    if let Some((c, kind)) = self.counter(&id.text) {
                        if member.text.eq_ignore_ascii_case("CV") {
                            if kind == CounterKind::Ctd {
                                let msg = format!(
                                    "`{}.CV`: an S7-200 CTD stops at 0 where the IEC CTD counts on below 0, so its \
                                     count is not read here (its Q is)",
                                    id.text
                                );
                                self.err("SFC0810", e.span, msg, site);
                                return None;
                            }
                            return Some((IntExpr::Val(Val::Counter(c)), Some(IntTy::Int)));
                        }
                    }
                }
                let msg = format!("`{}` is not a number the S7-200 program can read", self.snippet(e.span));
                self.err("SFC0810", e.span, msg, site);
                None
            }
            ExprKind::Unary { op: UnaryOp::Neg, operand } => {
                let (x, t) = self.int_expr(operand, site)?;
                if t.is_some_and(|t| !t.signed()) {
                    let msg = format!("`{}` negates an unsigned value", self.snippet(e.span));
                    self.err("SFC0810", e.span, msg, site);
                    return None;
                }
                Some((IntExpr::Neg(Box::new(x)), t))
            }
            ExprKind::Unary { op: UnaryOp::Plus, operand } => self.int_expr(operand, site),
            ExprKind::Binary { op, lhs, rhs }
                if matches!(op, BinaryOp::Add | BinaryOp::Sub | BinaryOp::Mul | BinaryOp::Div | BinaryOp::Mod) =>
            {
                let l = self.int_expr(lhs, site);
                let r = self.int_expr(rhs, site);
                let ((a, ta), (b, tb)) = (l?, r?);
                let ((a, b), ty) = self.unify(a, ta, b, tb, e.span, site)?;
                let typed = if ta.is_none() && tb.is_none() { None } else { Some(ty) };
                if matches!(op, BinaryOp::Div | BinaryOp::Mod) {
                    if !matches!(b, IntExpr::Val(Val::Const(c)) if c != 0) {
                        let msg = format!(
                            "`{}` divides by a variable: when it is 0 the IEC chart stops with a runtime error while \
                             the S7-200 goes on with the old value, so the program divides by constants only",
                            self.snippet(e.span)
                        );
                        self.err("SFC0810", e.span, msg, site);
                        return None;
                    }
                    if !ty.signed() {
                        let msg = format!(
                            "`{}` divides {} values; the S7-200 divides signed numbers (declare INT or DINT)",
                            self.snippet(e.span),
                            ty.name()
                        );
                        self.err("SFC0810", e.span, msg, site);
                        return None;
                    }
                }
                let node = match op {
                    BinaryOp::Add => IntExpr::Bin(ArithOp::Add, Box::new(a), Box::new(b)),
                    BinaryOp::Sub => IntExpr::Bin(ArithOp::Sub, Box::new(a), Box::new(b)),
                    BinaryOp::Mul => IntExpr::Bin(ArithOp::Mul, Box::new(a), Box::new(b)),
                    BinaryOp::Div => IntExpr::Bin(ArithOp::Div, Box::new(a), Box::new(b)),
                    _ => IntExpr::Mod(Box::new(a), Box::new(b)),
                };
                Some((node, typed))
            }
            _ => {
                let msg = format!("`{}` cannot be computed by the S7-200 program", self.snippet(e.span));
                self.err("SFC0810", e.span, msg, site);
                None
            }
        }
    }

    /// A duration known when the program is generated: a literal, a CONSTANT or (with a
    /// warning, by the caller) a TIME variable's initial value.
    pub(crate) fn duration(&mut self, e: &Expr, site: &Site<'_>) -> Option<i64> {
        match self.vars.eval_folding(e) {
            Some(Value::Time(c)) => Some(c),
            _ => {
                let msg = format!(
                    "`{}` is not a duration known when the program is generated: an S7-200 timer preset is a \
                     constant (write a literal, a CONSTANT, or a TIME variable that the chart does not write)",
                    self.snippet(e.span)
                );
                self.err("SFC0812", e.span, msg, site);
                None
            }
        }
    }

    /// `step.T op c` with `c` a duration known now, through timer bits. A 100 ms timer counts
    /// whole ticks of the CPU's time base, so `T >= c` is the bit of a timer with preset
    /// ⌈c / 100 ms⌉ and `T > c` the one with ⌊c / 100 ms⌋ + 1; `<` and `<=` are the negated
    /// contacts; `=` and `<>` (a multiple of 100 ms only) combine two timers.
    fn time_compare(&mut self, s: StepId, op: BinaryOp, other: &Expr, span: Span, site: &Site<'_>) -> Option<Logic> {
        let c = self.duration(other, site)?;
        let exact = c % TIMER_BASE_US == 0;
        if matches!(op, BinaryOp::Eq | BinaryOp::Ne) && !exact {
            let msg = format!(
                "`{}`: a step time counts whole 100 ms timer ticks, so = and <> need a multiple of 100 ms",
                self.snippet(span)
            );
            self.err("SFC0812", other.span, msg, site);
            return None;
        }
        let ge_pt = c.div_euclid(TIMER_BASE_US) + i64::from(!exact && c > 0);
        let gt_pt = c.div_euclid(TIMER_BASE_US) + 1;
        let needed = match op {
            BinaryOp::Ge | BinaryOp::Lt => ge_pt,
            _ => gt_pt,
        };
        if needed > MAX_PT {
            let msg = format!(
                "`{}` needs a timer preset of {needed} x 100 ms, beyond the S7-200 maximum of +32767 (3276.7 s)",
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
            BinaryOp::Ge => ge(ge_pt, self.timers),
            BinaryOp::Gt => ge(gt_pt, self.timers),
            BinaryOp::Lt => ge(ge_pt, self.timers).not(),
            BinaryOp::Le => ge(gt_pt, self.timers).not(),
            BinaryOp::Eq => Logic::And(vec![ge(ge_pt, self.timers), ge(gt_pt, self.timers).not()]),
            _ => Logic::Or(vec![ge(ge_pt, self.timers).not(), ge(gt_pt, self.timers)]),
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
                    let Some((addr, name)) = self.bit_target(target, site) else {
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

    /// A BOOL variable an IL body writes.
    fn bit_target(&mut self, e: &Expr, site: &Site<'_>) -> Option<(Addr, String)> {
        match self.target(e, site)? {
            Target::Bit(a, n) => Some((a, n)),
            Target::Word(_, ty, n) => {
                let msg = format!("`{n}` is {}: IL bodies store BOOL variables only here", ty.name());
                self.err("SFC0811", e.span, msg, site);
                None
            }
        }
    }

    /// A variable an action body writes.
    fn target(&mut self, e: &Expr, site: &Site<'_>) -> Option<Target> {
        match &e.kind {
            ExprKind::Paren(inner) => self.target(inner, site),
            ExprKind::Name(id) => {
                let Some(i) = self.vars.get(&id.text) else {
                    let msg = format!("`{}` is not a variable the S7-200 program can write", id.text);
                    self.err("SFC0811", e.span, msg, site);
                    return None;
                };
                let v = &self.vars.list[i];
                if v.constant {
                    let msg = format!("`{}` is a constant", v.name);
                    self.err("SFC0811", e.span, msg, site);
                    return None;
                }
                if v.is_bit() {
                    let (name, addr) = (v.name.clone(), v.addr?);
                    self.writable(addr, &name, e.span, site)?;
                    return Some(Target::Bit(addr, name));
                }
                if let (Some(ty), true) = (v.int_ty(), v.is_word()) {
                    let (name, val) = (v.name.clone(), v.val?);
                    if let Val::Word(super::ir::Area::I, _) | Val::DWord(super::ir::Area::I, _) = val {
                        let msg = format!("`{name}` is in the input image: the program cannot write it");
                        self.err("SFC0814", e.span, msg, site);
                        return None;
                    }
                    return Some(Target::Word(val, ty, name));
                }
                let msg = if v.is_time() {
                    format!(
                        "`{}` is TIME: the S7-200 program uses TIME variables as timer presets fixed at their \
                         initial value, so the chart cannot change them",
                        v.name
                    )
                } else {
                    format!(
                        "`{}` is {}: the S7-200 program assigns BOOL and integer variables",
                        v.name,
                        v.ty.as_deref().unwrap_or("not an elementary type")
                    )
                };
                self.err("SFC0811", e.span, msg, site);
                None
            }
            ExprKind::Address(a) => match bit_address(a) {
                Ok(addr) => {
                    self.writable(addr, &a.text, e.span, site)?;
                    Some(Target::Bit(addr, a.text.clone()))
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

    /// `C(CU := …, R := …, PV := …)` of a counter instance.
    fn counter_call(&mut self, call: &Expr, span: Span, site: &Site<'_>) -> Option<BodyOp> {
        let ExprKind::Call { callee, args } = &call.kind else { return None };
        let Some((c, kind)) = self.counter(&callee.text) else {
            let msg = format!(
                "the call of `{}` cannot be translated: the S7-200 program calls counter blocks (CTU, CTD, CTUD) only",
                callee.text
            );
            self.err("SFC0811", span, msg, site);
            return None;
        };
        if let Some(first) = self.counters.list[c].call {
            let d = Diagnostic::error(
                "SFC0811",
                span,
                format!(
                    "`{}` is called a second time: an S7-200 counter instruction must run at most once per scan, \
                     so each counter block has one call",
                    callee.text
                ),
            )
            .with_element(site.element)
            .with_label(first, "first call");
            self.diags.push(d);
            return None;
        }
        self.counters.list[c].call = Some(span);
        let (mut up, mut down, mut reset, mut preset) =
            (Logic::Const(false), Logic::Const(false), Logic::Const(false), Val::Const(0));
        let mut ok = true;
        for a in args {
            let (Some(name), false, Some(value)) = (&a.name, a.output, &a.value) else {
                let msg = format!(
                    "`{}`: write the counter's inputs by name (`CU := x`); outputs are read as `{}.Q`",
                    self.snippet(a.span),
                    callee.text
                );
                self.err("SFC0811", a.span, msg, site);
                ok = false;
                continue;
            };
            let n = name.text.to_ascii_uppercase();
            match (kind, n.as_str()) {
                (CounterKind::Ctu | CounterKind::Ctud, "CU") => match self.expr(value, site) {
                    Some(l) => up = l,
                    None => ok = false,
                },
                (CounterKind::Ctd | CounterKind::Ctud, "CD") => match self.expr(value, site) {
                    Some(l) => down = l,
                    None => ok = false,
                },
                (CounterKind::Ctu | CounterKind::Ctud, "R") | (CounterKind::Ctd, "LD") => {
                    match self.expr(value, site) {
                        Some(l) => reset = l,
                        None => ok = false,
                    }
                }
                (CounterKind::Ctud, "LD") => match const_eval(value, self.vars) {
                    Some(Value::Bool(false)) => {}
                    _ => {
                        let msg = "the S7-200 CTUD has no load input: `LD` must be FALSE".to_string();
                        self.err("SFC0811", a.span, msg, site);
                        ok = false;
                    }
                },
                (_, "PV") => match self.int_expr(value, site) {
                    Some((IntExpr::Val(v), t)) if t.is_none_or(|t| t == IntTy::Int) => {
                        if kind == CounterKind::Ctd && !matches!(v, Val::Const(c) if c >= 0) {
                            let msg = "an S7-200 CTD counts down to 0: its PV must be a constant >= 0".to_string();
                            self.err("SFC0811", a.span, msg, site);
                            ok = false;
                        } else {
                            preset = v;
                        }
                    }
                    Some(_) => {
                        let msg = "the preset of a counter is an INT variable or constant".to_string();
                        self.err("SFC0811", a.span, msg, site);
                        ok = false;
                    }
                    None => ok = false,
                },
                _ => {
                    let msg = format!("`{}` is not an input of {}", name.text, kind.name());
                    self.err("SFC0811", a.span, msg, site);
                    ok = false;
                }
            }
        }
        let qd = self.counters.list[c].qd;
        ok.then(|| BodyOp::Count { counter: c, kind, up, down, reset, preset, qd, text: self.snippet(span) })
    }

    /// An ST action body.
    pub(crate) fn st_body(&mut self, stmts: &[Stmt], site: &Site<'_>) -> Option<Vec<BodyOp>> {
        let mut out = Vec::new();
        let mut ok = true;
        for s in stmts {
            match &s.kind {
                StmtKind::Empty => {}
                StmtKind::Assign { target, value } => {
                    // The value is lowered only for a known target: one diagnostic per statement.
                    let text = self.snippet(s.span);
                    match self.target(target, site) {
                        Some(Target::Bit(t, name)) => match self.expr(value, site) {
                            Some(v) => out.push(BodyOp::Assign { target: t, name, value: v, text }),
                            None => ok = false,
                        },
                        Some(Target::Word(t, ty, name)) => match self.int_expr(value, site) {
                            Some((v, vt)) => {
                                let v = match (vt, v) {
                                    (None, IntExpr::Val(Val::Const(c))) => {
                                        IntExpr::Val(Val::Const(ty.stored(i128::from(c))))
                                    }
                                    (None, v) => v,
                                    (Some(x), v) if x == ty => v,
                                    (Some(IntTy::Int), v) if ty == IntTy::DInt => IntExpr::Widen(Box::new(v)),
                                    (Some(x), _) => {
                                        let msg = format!(
                                            "`{text}` assigns {} to {} `{name}`: convert explicitly",
                                            x.name(),
                                            ty.name()
                                        );
                                        self.err("SFC0811", s.span, msg, site);
                                        ok = false;
                                        continue;
                                    }
                                };
                                out.push(BodyOp::Move { target: t, wide: ty.wide(), name, value: v, text });
                            }
                            None => ok = false,
                        },
                        None => ok = false,
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
                    let text = super::ir::one_line(head);
                    match e {
                        Some(else_body) if ok => out.push(BodyOp::If { branches: lowered, else_body, text }),
                        _ => ok = false,
                    }
                }
                StmtKind::Call(call) => match self.counter_call(call, s.span, site) {
                    Some(op) => out.push(op),
                    None => ok = false,
                },
                other => {
                    let what = match other {
                        StmtKind::Case { .. } => "CASE",
                        StmtKind::For { .. } => "FOR",
                        StmtKind::While { .. } => "WHILE",
                        StmtKind::Repeat { .. } => "REPEAT",
                        StmtKind::Exit => "EXIT",
                        StmtKind::Return => "RETURN",
                        _ => "this statement",
                    };
                    let msg = format!(
                        "{what} cannot be translated: S7-200 action bodies are assignments, IF statements and \
                         counter calls"
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
