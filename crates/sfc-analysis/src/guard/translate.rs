//! From transition conditions (ST expressions and IL lists) to boolean formulas over atoms.
//!
//! Atoms are shared by all guards of a chart, keyed case-insensitively:
//! * boolean atoms: BOOL variables and their access paths (`a.b`, `arr[2]`, `%IX0.1`,
//!   `Tmr.Q`, `Act.Q`), step flags `S.X`, and opaque boolean sub-expressions (function calls,
//!   arithmetic) keyed by their canonical printed form ([`super::print`]);
//! * numeric terms: a variable, a step time `S.T`, or any other non-constant term (`ABS(x)`,
//!   `a + b`) compared with a constant. Each comparison becomes one or two *thresholds* of the
//!   term (`v >= k`, and for REAL also `v > c`), which the analysis links by their order;
//! * relations between two non-constant terms (`a < b`, `a = b`, in one orientation chosen by
//!   the terms' keys), which the analysis keeps mutually exclusive (trichotomy).

use super::print::print;
use sfc_diagnostics::Span;
use sfc_model::{Chart, StepId};
use sfc_st::{const_eval, parse_il_op, IlOp, Scope, Type, Value};
use sfc_syntax::ast::{BinaryOp, Condition, Expr, ExprKind, Ident, IlBody, IlInstruction, LiteralKind, UnaryOp};
use std::cmp::Ordering;
use std::collections::{BTreeSet, HashMap, HashSet};

pub(super) type AtomId = usize;
pub(super) type NumId = usize;

/// Deeper than this a guard is not analysed (the parser caps expressions at 256 levels).
const MAX_DEPTH: u32 = 400;
/// An IL condition with more instructions than this is not analysed.
const MAX_IL_INSTRUCTIONS: usize = 512;

/// A threshold of a numeric term: `v >= k` for integer-valued terms (integers, TIME in µs,
/// enumeration indexes), `v >= c` (`false`) or `v > c` (`true`) for REAL terms.
#[derive(Debug, Clone, Copy)]
pub(super) enum Thr {
    Int(i128),
    Real(f64, bool),
}

impl Ord for Thr {
    fn cmp(&self, other: &Self) -> Ordering {
        match (self, other) {
            (Thr::Int(a), Thr::Int(b)) => a.cmp(b),
            (Thr::Real(a, s), Thr::Real(b, t)) => a.total_cmp(b).then(s.cmp(t)),
            (Thr::Int(_), Thr::Real(..)) => Ordering::Less,
            (Thr::Real(..), Thr::Int(_)) => Ordering::Greater,
        }
    }
}
impl PartialOrd for Thr {
    fn partial_cmp(&self, other: &Self) -> Option<Ordering> {
        Some(self.cmp(other))
    }
}
impl PartialEq for Thr {
    fn eq(&self, other: &Self) -> bool {
        self.cmp(other) == Ordering::Equal
    }
}
impl Eq for Thr {}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum AtomKind {
    /// A BOOL variable or path, or an opaque boolean sub-expression.
    Plain,
    /// `S.X`.
    StepFlag(StepId),
    /// One of `a < b`, `b < a`, `a = b` of the relation pair with this index.
    Relation(usize),
}

#[derive(Debug, Clone)]
pub(super) struct Atom {
    /// The name shown in witnesses.
    pub display: String,
    pub kind: AtomKind,
}

/// How a numeric term's value is read back for a witness.
#[derive(Debug, Clone, PartialEq)]
pub(super) enum NumKind {
    /// An integer or bit string; the witness is a JSON integer.
    Int,
    /// REAL/LREAL (dense); the witness is a JSON number.
    Real,
    /// TIME/LTIME in µs, or a step time; the witness is a TIME literal.
    Time,
    /// An enumeration, by value index; the witness is the value name.
    Enum(Vec<String>),
}

#[derive(Debug, Clone)]
pub(super) struct NumVar {
    pub display: String,
    pub kind: NumKind,
    /// Inclusive range of integer-valued kinds (unused for REAL).
    pub lo: i128,
    pub hi: i128,
}

/// A boolean formula over atoms and thresholds.
#[derive(Debug, Clone)]
pub(super) enum Formula {
    Const(bool),
    Atom(AtomId),
    Thr(NumId, Thr),
    Not(Box<Formula>),
    And(Box<Formula>, Box<Formula>),
    Or(Box<Formula>, Box<Formula>),
    Xor(Box<Formula>, Box<Formula>),
    Iff(Box<Formula>, Box<Formula>),
}

fn not(f: Formula) -> Formula {
    match f {
        Formula::Const(b) => Formula::Const(!b),
        Formula::Not(inner) => *inner,
        f => Formula::Not(Box::new(f)),
    }
}
fn and(a: Formula, b: Formula) -> Formula {
    Formula::And(Box::new(a), Box::new(b))
}
fn or(a: Formula, b: Formula) -> Formula {
    Formula::Or(Box::new(a), Box::new(b))
}

/// Something a guard refers to, for its witness: a boolean atom or a numeric term.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub(super) enum Item {
    Atom(AtomId),
    Num(NumId),
}

/// A translated guard.
#[derive(Debug, Clone)]
pub(super) struct Guard {
    pub formula: Formula,
    /// Atoms and terms in order of first occurrence (the witness shows them in this order).
    pub items: Vec<Item>,
    /// The thresholds the formula uses.
    pub thresholds: BTreeSet<(NumId, Thr)>,
    /// The condition is a lone literal (`TRUE`, `FALSE`, `1`, `0`): deliberately constant.
    pub deliberate: bool,
}

/// The guard cannot be analysed (too deep, an error node, IL with jumps or stores, …).
#[derive(Debug, Clone, Copy)]
pub(super) struct Unknown;

type R<T> = Result<T, Unknown>;

/// The atoms and terms of one chart.
#[derive(Debug, Default)]
pub(super) struct Tables {
    pub atoms: Vec<Atom>,
    atom_index: HashMap<String, AtomId>,
    pub nums: Vec<NumVar>,
    num_index: HashMap<String, NumId>,
    pair_index: HashMap<(String, String), usize>,
}

#[derive(Default)]
struct Builder {
    items: Vec<Item>,
    seen: HashSet<Item>,
    thresholds: BTreeSet<(NumId, Thr)>,
}

impl Builder {
    fn use_item(&mut self, it: Item) {
        if self.seen.insert(it) {
            self.items.push(it);
        }
    }
}

/// Translates the guards of one chart, collecting atoms and terms in [`Tables`].
pub(super) struct Translator<'a, 'e> {
    pub chart: &'a Chart,
    pub scope: &'a Scope<'e>,
    pub expr_types: &'a HashMap<Span, Type>,
    pub tables: Tables,
    /// The chart's steps (`true`) and actions (`false`) by upper-case name, so a name in a
    /// guard is looked up in constant time (a chart may have ten thousand steps).
    pub names: HashMap<String, (bool, usize)>,
}

/// The name index of [`Translator::names`].
pub(super) fn chart_names(chart: &Chart) -> HashMap<String, (bool, usize)> {
    let mut names = HashMap::with_capacity(chart.steps.len() + chart.actions.len());
    for (i, a) in chart.actions.iter().enumerate().rev() {
        names.insert(a.name.to_ascii_uppercase(), (false, i));
    }
    // Steps first, and the first declaration wins (as `Chart::step` finds it).
    for (i, st) in chart.steps.iter().enumerate().rev() {
        names.insert(st.name.to_ascii_uppercase(), (true, i));
    }
    names
}

impl Translator<'_, '_> {
    /// `Ok(None)` for a missing condition.
    pub fn guard(&mut self, cond: &Condition) -> R<Option<Guard>> {
        let mut b = Builder::default();
        let (formula, deliberate) = match cond {
            Condition::Missing => return Ok(None),
            Condition::St(e) => (self.bool_f(e, &mut b, 0)?, lone_literal(e)),
            Condition::Il(body) => {
                let e = il_expr(body)?;
                let lone = body.instructions.iter().filter(|i| i.op.is_some()).count() == 1;
                (self.bool_f(&e, &mut b, 0)?, lone && lone_literal(&e))
            }
        };
        Ok(Some(Guard { formula, items: b.items, thresholds: b.thresholds, deliberate }))
    }

    // -----------------------------------------------------------------------------------------
    // Names and types

    /// `S.X` / `S.T` of a step of this chart.
    fn step_member(&self, e: &Expr) -> Option<(StepId, bool)> {
        let ExprKind::Member { base, member } = &e.kind else { return None };
        let ExprKind::Name(n) = &strip(base).kind else { return None };
        let s = match self.names.get(&n.text.to_ascii_uppercase()) {
            Some(&(true, s)) => s,
            _ => return None,
        };
        if member.is("X") {
            Some((s, true))
        } else if member.is("T") {
            Some((s, false))
        } else {
            None
        }
    }

    fn is_chart_name(&self, id: &Ident) -> bool {
        self.names.contains_key(&id.text.to_ascii_uppercase())
    }

    /// The type of an expression: as the checker recorded it, else from the declarations.
    fn type_of(&self, e: &Expr) -> Option<Type> {
        if e.span != Span::default() {
            if let Some(t) = self.expr_types.get(&e.span) {
                if !t.is_error() {
                    return Some(t.clone());
                }
            }
        }
        match &e.kind {
            ExprKind::Paren(i) => self.type_of(i),
            ExprKind::Name(id) => {
                if self.is_chart_name(id) {
                    return None;
                }
                self.scope.variable(&id.text).map(|v| v.ty.clone()).filter(|t| !t.is_error())
            }
            ExprKind::Member { base, member } => {
                if let Some((_, x)) = self.step_member(e) {
                    return Some(if x { Type::Bool } else { Type::Time });
                }
                if let ExprKind::Name(n) = &strip(base).kind {
                    if self.chart.action(&n.text).is_some() {
                        return Some(Type::Bool);
                    }
                }
                let bt = self.type_of(base)?;
                match &bt {
                    Type::Struct { fields, .. } => fields.iter().find(|(n, _)| member.is(n)).map(|(_, t)| t.clone()),
                    Type::FunctionBlock(_) => {
                        let fb = self.scope.env().fb_of(&bt)?;
                        fb.var(&member.text).map(|v| v.ty.clone())
                    }
                    t if (t.is_integer() || t.is_bit()) && member.text.bytes().all(|c| c.is_ascii_digit()) => {
                        Some(Type::Bool)
                    }
                    _ => None,
                }
            }
            ExprKind::Index { base, .. } => match self.type_of(base)? {
                Type::Array { elem, .. } => Some(*elem),
                _ => None,
            },
            ExprKind::Address(a) => match a.size.to_ascii_uppercase() {
                'X' => Some(Type::Bool),
                'B' => Some(Type::Byte),
                'W' => Some(Type::Word),
                'D' => Some(Type::DWord),
                'L' => Some(Type::LWord),
                _ => None,
            },
            ExprKind::Literal(l) => match l.kind {
                LiteralKind::Bool(_) => Some(Type::Bool),
                _ => None,
            },
            _ => None,
        }
    }

    /// A variable access path with constant indexes: `(key, display)`.
    fn path(&self, e: &Expr, depth: u32) -> Option<(String, String)> {
        if depth > MAX_DEPTH {
            return None;
        }
        match &e.kind {
            ExprKind::Paren(i) => self.path(i, depth + 1),
            ExprKind::Name(id) => {
                if self.is_chart_name(id) {
                    return None;
                }
                Some((id.key(), id.text.clone()))
            }
            ExprKind::Address(a) => Some((a.text.to_ascii_uppercase(), a.text.clone())),
            ExprKind::Member { base, member } => {
                let (k, d) = self.path(base, depth + 1)?;
                Some((format!("{k}.{}", member.key()), format!("{d}.{}", member.text)))
            }
            ExprKind::Index { base, indices } => {
                let (mut k, mut d) = self.path(base, depth + 1)?;
                k.push('[');
                d.push('[');
                for (i, ix) in indices.iter().enumerate() {
                    let v = const_eval(ix, self.scope)?.as_int()?;
                    if i > 0 {
                        k.push(',');
                        d.push_str(", ");
                    }
                    k.push_str(&v.to_string());
                    d.push_str(&print(ix, false)?);
                }
                k.push(']');
                d.push(']');
                Some((k, d))
            }
            _ => None,
        }
    }

    /// Whether an expression is BOOL (by its type, or by its form when the type is unknown).
    fn boolish(&self, e: &Expr, depth: u32) -> bool {
        if depth > MAX_DEPTH {
            return false;
        }
        if let Some(t) = self.type_of(e) {
            return t.is_bool();
        }
        match &e.kind {
            ExprKind::Paren(i) => self.boolish(i, depth + 1),
            ExprKind::Literal(l) => matches!(l.kind, LiteralKind::Bool(_)),
            ExprKind::Unary { op: UnaryOp::Not, operand } => self.boolish(operand, depth + 1),
            ExprKind::Binary { op, lhs, rhs } => match op {
                BinaryOp::And | BinaryOp::AndThen | BinaryOp::Or | BinaryOp::OrElse | BinaryOp::Xor => {
                    self.boolish(lhs, depth + 1) || self.boolish(rhs, depth + 1)
                }
                BinaryOp::Eq | BinaryOp::Ne | BinaryOp::Lt | BinaryOp::Gt | BinaryOp::Le | BinaryOp::Ge => true,
                _ => false,
            },
            ExprKind::Member { .. } => self.step_member(e).is_some_and(|(_, x)| x),
            _ => false,
        }
    }

    // -----------------------------------------------------------------------------------------
    // Atoms

    fn atom(&mut self, key: String, display: String, kind: AtomKind, b: &mut Builder) -> Formula {
        let id = match self.tables.atom_index.get(&key) {
            Some(&id) => id,
            None => {
                let id = self.tables.atoms.len();
                self.tables.atoms.push(Atom { display, kind });
                self.tables.atom_index.insert(key, id);
                id
            }
        };
        b.use_item(Item::Atom(id));
        Formula::Atom(id)
    }

    fn opaque(&mut self, e: &Expr, b: &mut Builder) -> R<Formula> {
        let key = print(e, true).ok_or(Unknown)?;
        let display = print(e, false).ok_or(Unknown)?;
        Ok(self.atom(key, display, AtomKind::Plain, b))
    }

    fn step_flag(&mut self, s: StepId, b: &mut Builder) -> Formula {
        let name = self.chart.steps.get(s).map(|st| st.name.as_str()).unwrap_or("?");
        self.atom(format!("\u{1}X\u{1}{s}"), format!("{name}.X"), AtomKind::StepFlag(s), b)
    }

    // -----------------------------------------------------------------------------------------
    // Boolean expressions

    fn bool_f(&mut self, e: &Expr, b: &mut Builder, depth: u32) -> R<Formula> {
        if depth > MAX_DEPTH {
            return Err(Unknown);
        }
        let d = depth + 1;
        match &e.kind {
            ExprKind::Paren(i) => self.bool_f(i, b, d),
            ExprKind::Literal(l) => match l.kind {
                LiteralKind::Bool(v) => Ok(Formula::Const(v)),
                LiteralKind::Int(v @ (0 | 1)) => Ok(Formula::Const(v == 1)),
                _ => Err(Unknown),
            },
            ExprKind::Unary { op: UnaryOp::Not, operand } => Ok(not(self.bool_f(operand, b, d)?)),
            ExprKind::Binary { op, lhs, rhs } => match op {
                BinaryOp::And | BinaryOp::AndThen => Ok(and(self.bool_f(lhs, b, d)?, self.bool_f(rhs, b, d)?)),
                BinaryOp::Or | BinaryOp::OrElse => Ok(or(self.bool_f(lhs, b, d)?, self.bool_f(rhs, b, d)?)),
                BinaryOp::Xor => Ok(Formula::Xor(Box::new(self.bool_f(lhs, b, d)?), Box::new(self.bool_f(rhs, b, d)?))),
                BinaryOp::Eq | BinaryOp::Ne | BinaryOp::Lt | BinaryOp::Gt | BinaryOp::Le | BinaryOp::Ge => {
                    self.compare(*op, lhs, rhs, b, d)
                }
                _ => self.opaque(e, b),
            },
            ExprKind::Call { callee, args } => self.call(e, callee, args, b, d),
            ExprKind::Name(_) | ExprKind::Member { .. } | ExprKind::Index { .. } | ExprKind::Address(_) => {
                self.bool_leaf(e, b)
            }
            ExprKind::Error | ExprKind::MemberCall { .. } | ExprKind::Deref(_) => Err(Unknown),
            ExprKind::Unary { .. } => self.opaque(e, b),
        }
    }

    fn bool_leaf(&mut self, e: &Expr, b: &mut Builder) -> R<Formula> {
        if let Some(v) = const_eval(e, self.scope) {
            return match v {
                Value::Bool(v) => Ok(Formula::Const(v)),
                Value::Int(v @ (0 | 1)) => Ok(Formula::Const(v == 1)),
                _ => Err(Unknown),
            };
        }
        if let Some((s, x)) = self.step_member(e) {
            // `S.T` where a BOOL is expected does not type-check.
            return if x { Ok(self.step_flag(s, b)) } else { Err(Unknown) };
        }
        match self.path(e, 0) {
            Some((key, display)) => Ok(self.atom(key, display, AtomKind::Plain, b)),
            None => self.opaque(e, b),
        }
    }

    /// `AND(a, b, …)`, `NOT(a)`, `GT(a, b, …)` and the like; other calls are opaque.
    fn call(&mut self, e: &Expr, callee: &Ident, args: &[sfc_syntax::ast::Arg], b: &mut Builder, d: u32) -> R<Formula> {
        let positional: Option<Vec<&Expr>> = args
            .iter()
            .map(|a| if a.name.is_none() && !a.output && !a.negated { a.value.as_ref() } else { None })
            .collect();
        let Some(vals) = positional else { return self.opaque(e, b) };
        let name = callee.key();
        let logic = match name.as_str() {
            "AND" => Some(BinaryOp::And),
            "OR" => Some(BinaryOp::Or),
            "XOR" => Some(BinaryOp::Xor),
            _ => None,
        };
        if let Some(op) = logic {
            if vals.len() >= 2 {
                let mut acc = self.bool_f(vals[0], b, d)?;
                for v in &vals[1..] {
                    let f = self.bool_f(v, b, d)?;
                    acc = match op {
                        BinaryOp::And => and(acc, f),
                        BinaryOp::Or => or(acc, f),
                        _ => Formula::Xor(Box::new(acc), Box::new(f)),
                    };
                }
                return Ok(acc);
            }
        }
        if name == "NOT" && vals.len() == 1 {
            return Ok(not(self.bool_f(vals[0], b, d)?));
        }
        let cmp = match name.as_str() {
            "GT" => Some(BinaryOp::Gt),
            "GE" => Some(BinaryOp::Ge),
            "EQ" => Some(BinaryOp::Eq),
            "NE" => Some(BinaryOp::Ne),
            "LT" => Some(BinaryOp::Lt),
            "LE" => Some(BinaryOp::Le),
            _ => None,
        };
        if let Some(op) = cmp {
            // Extensible comparisons: GT(a, b, c) = a > b AND b > c (NE takes exactly two).
            if vals.len() == 2 || (vals.len() > 2 && op != BinaryOp::Ne) {
                let mut acc: Option<Formula> = None;
                for w in vals.windows(2) {
                    let f = self.compare(op, w[0], w[1], b, d)?;
                    acc = Some(match acc {
                        None => f,
                        Some(a) => and(a, f),
                    });
                }
                if let Some(f) = acc {
                    return Ok(f);
                }
            }
        }
        self.opaque(e, b)
    }

    // -----------------------------------------------------------------------------------------
    // Comparisons

    fn compare(&mut self, op: BinaryOp, lhs: &Expr, rhs: &Expr, b: &mut Builder, d: u32) -> R<Formula> {
        if d > MAX_DEPTH {
            return Err(Unknown);
        }
        if matches!(op, BinaryOp::Eq | BinaryOp::Ne) && (self.boolish(lhs, 0) || self.boolish(rhs, 0)) {
            let f = Formula::Iff(Box::new(self.bool_f(lhs, b, d)?), Box::new(self.bool_f(rhs, b, d)?));
            return Ok(if op == BinaryOp::Ne { not(f) } else { f });
        }
        let ca = const_eval(lhs, self.scope);
        let cb = const_eval(rhs, self.scope);
        match (ca, cb) {
            (Some(x), Some(y)) => const_compare(op, x, y).map(Formula::Const).ok_or(Unknown),
            (None, Some(c)) => match self.num_cmp(lhs, op, c, b)? {
                Some(f) => Ok(f),
                None => self.relation(op, lhs, rhs, b),
            },
            (Some(c), None) => match self.num_cmp(rhs, flip(op), c, b)? {
                Some(f) => Ok(f),
                None => self.relation(op, lhs, rhs, b),
            },
            (None, None) => {
                if let Some(f) = self.enum_cmp(op, lhs, rhs, b)? {
                    return Ok(f);
                }
                if let Some(f) = self.enum_cmp(flip(op), rhs, lhs, b)? {
                    return Ok(f);
                }
                self.relation(op, lhs, rhs, b)
            }
        }
    }

    /// The numeric term for `term` (created on first use, typed from the declarations, else
    /// from the constant it is compared with); `None` when it cannot be compared with `c`.
    fn num_term(&mut self, term: &Expr, c: Value) -> R<Option<NumId>> {
        let (key, display, step_time) = match self.step_member(term) {
            Some((s, false)) => {
                let name = self.chart.steps.get(s).map(|st| st.name.as_str()).unwrap_or("?");
                (format!("\u{1}T\u{1}{s}"), format!("{name}.T"), true)
            }
            Some((_, true)) => return Ok(None),
            None => {
                let (k, d) = match self.path(term, 0) {
                    Some(p) => p,
                    None => (print(term, true).ok_or(Unknown)?, print(term, false).ok_or(Unknown)?),
                };
                (k, d, false)
            }
        };
        if let Some(&id) = self.tables.num_index.get(&key) {
            return Ok(Some(id));
        }
        let (kind, lo, hi) = if step_time {
            // A step time is a stopwatch: never negative.
            (NumKind::Time, 0, i128::from(i64::MAX))
        } else {
            match self.type_of(term) {
                Some(t) if t.is_bool() => return Ok(None),
                Some(t) if t.is_integer() || t.is_bit() => match t.int_range() {
                    Some((lo, hi)) => (NumKind::Int, lo, hi),
                    None => return Ok(None),
                },
                Some(t) if t.is_real() => (NumKind::Real, 0, 0),
                Some(t) if t.is_duration() => (NumKind::Time, i128::from(i64::MIN), i128::from(i64::MAX)),
                Some(_) => return Ok(None),
                None => match c {
                    Value::Int(_) => (NumKind::Int, i128::from(i64::MIN), i128::from(i64::MAX)),
                    Value::Real(_) => (NumKind::Real, 0, 0),
                    Value::Time(_) => (NumKind::Time, i128::from(i64::MIN), i128::from(i64::MAX)),
                    Value::Bool(_) => return Ok(None),
                },
            }
        };
        let id = self.tables.nums.len();
        self.tables.nums.push(NumVar { display, kind, lo, hi });
        self.tables.num_index.insert(key, id);
        Ok(Some(id))
    }

    /// `term op c` on a numeric term; `None` when the kinds do not fit.
    fn num_cmp(&mut self, term: &Expr, op: BinaryOp, c: Value, b: &mut Builder) -> R<Option<Formula>> {
        let Some(id) = self.num_term(term, c)? else { return Ok(None) };
        let Some(nv) = self.tables.nums.get(id) else { return Ok(None) };
        // (ge, gt): the thresholds meaning `term >= c` and `term > c`.
        let (ge, gt) = match (&nv.kind, c) {
            (NumKind::Int, Value::Int(i)) => (Thr::Int(i), Thr::Int(i.saturating_add(1))),
            (NumKind::Int, Value::Real(r)) if r.is_finite() && r.abs() < 1e30 => {
                (Thr::Int(r.ceil() as i128), Thr::Int((r.floor() as i128).saturating_add(1)))
            }
            (NumKind::Time, Value::Time(us)) => (Thr::Int(i128::from(us)), Thr::Int(i128::from(us).saturating_add(1))),
            (NumKind::Real, Value::Int(i)) => (Thr::Real(i as f64 + 0.0, false), Thr::Real(i as f64 + 0.0, true)),
            (NumKind::Real, Value::Real(r)) if !r.is_nan() => {
                // `+ 0.0` turns -0.0 into 0.0, so the two zeros are one threshold.
                (Thr::Real(r + 0.0, false), Thr::Real(r + 0.0, true))
            }
            _ => return Ok(None),
        };
        b.use_item(Item::Num(id));
        Ok(Some(self.thresholds_formula(id, op, ge, gt, b)))
    }

    /// `term op <enum value>` for a term of an enumerated type (`=` and `<>` only).
    fn enum_cmp(&mut self, op: BinaryOp, term: &Expr, value: &Expr, b: &mut Builder) -> R<Option<Formula>> {
        if !matches!(op, BinaryOp::Eq | BinaryOp::Ne) {
            return Ok(None);
        }
        let Some(Type::Enum { values, .. }) = self.type_of(term) else { return Ok(None) };
        let name = match &strip(value).kind {
            ExprKind::Literal(l) => match &l.kind {
                LiteralKind::Enum(id) => id.clone(),
                _ => return Ok(None),
            },
            ExprKind::Name(id) if self.scope.variable(&id.text).is_none() && !self.is_chart_name(id) => id.clone(),
            _ => return Ok(None),
        };
        let Some(index) = values.iter().position(|(v, _)| name.is(v)) else { return Ok(None) };
        let Some((key, display)) = self.path(term, 0) else { return Ok(None) };
        let names: Vec<String> = values.iter().map(|(v, _)| v.clone()).collect();
        let id = match self.tables.num_index.get(&key) {
            Some(&id) => id,
            None => {
                let id = self.tables.nums.len();
                let hi = names.len() as i128 - 1;
                self.tables.nums.push(NumVar { display, kind: NumKind::Enum(names), lo: 0, hi });
                self.tables.num_index.insert(key, id);
                id
            }
        };
        if !matches!(self.tables.nums.get(id).map(|n| &n.kind), Some(NumKind::Enum(_))) {
            return Ok(None);
        }
        b.use_item(Item::Num(id));
        let i = index as i128;
        Ok(Some(self.thresholds_formula(id, op, Thr::Int(i), Thr::Int(i + 1), b)))
    }

    /// The formula of `v op c` given the thresholds for `v >= c` and `v > c` (only those the
    /// operator needs are registered).
    fn thresholds_formula(&mut self, id: NumId, op: BinaryOp, ge: Thr, gt: Thr, b: &mut Builder) -> Formula {
        match op {
            BinaryOp::Ge => self.threshold(id, ge, b),
            BinaryOp::Gt => self.threshold(id, gt, b),
            BinaryOp::Lt => not(self.threshold(id, ge, b)),
            BinaryOp::Le => not(self.threshold(id, gt, b)),
            BinaryOp::Eq => and(self.threshold(id, ge, b), not(self.threshold(id, gt, b))),
            _ => not(and(self.threshold(id, ge, b), not(self.threshold(id, gt, b)))),
        }
    }

    /// One threshold as a formula: constant when the term's range decides it.
    fn threshold(&mut self, id: NumId, t: Thr, b: &mut Builder) -> Formula {
        if let (Thr::Int(k), Some(nv)) = (t, self.tables.nums.get(id)) {
            if k <= nv.lo {
                return Formula::Const(true);
            }
            if k > nv.hi {
                return Formula::Const(false);
            }
        }
        b.thresholds.insert((id, t));
        Formula::Thr(id, t)
    }

    /// A comparison of two non-constant terms, as relation atoms `A < B`, `B < A`, `A = B`.
    fn relation(&mut self, op: BinaryOp, lhs: &Expr, rhs: &Expr, b: &mut Builder) -> R<Formula> {
        let ka = print(lhs, true).ok_or(Unknown)?;
        let kb = print(rhs, true).ok_or(Unknown)?;
        if ka == kb {
            return Ok(Formula::Const(matches!(op, BinaryOp::Eq | BinaryOp::Le | BinaryOp::Ge)));
        }
        let da = print(lhs, false).ok_or(Unknown)?;
        let db = print(rhs, false).ok_or(Unknown)?;
        let swapped = ka > kb;
        let ((ka, da), (kb, db)) = if swapped { ((kb, db), (ka, da)) } else { ((ka, da), (kb, db)) };
        let next = self.tables.pair_index.len();
        let pair = *self.tables.pair_index.entry((ka.clone(), kb.clone())).or_insert(next);
        let kind = AtomKind::Relation(pair);
        let key_ab = format!("\u{1}<\u{1}{ka}\u{1}{kb}");
        let key_ba = format!("\u{1}<\u{1}{kb}\u{1}{ka}");
        let key_eq = format!("\u{1}=\u{1}{ka}\u{1}{kb}");
        // `lhs < rhs` is `A < B` unless the sides were swapped.
        let (lt, gt) =
            if swapped { ((key_ba, &db, &da), (key_ab, &da, &db)) } else { ((key_ab, &da, &db), (key_ba, &db, &da)) };
        let f = match op {
            BinaryOp::Lt => self.atom(lt.0, format!("{} < {}", lt.1, lt.2), kind, b),
            BinaryOp::Gt => self.atom(gt.0, format!("{} < {}", gt.1, gt.2), kind, b),
            BinaryOp::Ge => not(self.atom(lt.0, format!("{} < {}", lt.1, lt.2), kind, b)),
            BinaryOp::Le => not(self.atom(gt.0, format!("{} < {}", gt.1, gt.2), kind, b)),
            BinaryOp::Eq => self.atom(key_eq, format!("{da} = {db}"), kind, b),
            _ => not(self.atom(key_eq, format!("{da} = {db}"), kind, b)),
        };
        Ok(f)
    }
}

fn strip(e: &Expr) -> &Expr {
    let mut e = e;
    while let ExprKind::Paren(i) = &e.kind {
        e = i;
    }
    e
}

/// `TRUE`, `FALSE`, `1`, `0` (in parentheses or not): a deliberately constant guard.
fn lone_literal(e: &Expr) -> bool {
    match &strip(e).kind {
        ExprKind::Literal(l) => matches!(l.kind, LiteralKind::Bool(_) | LiteralKind::Int(0 | 1)),
        _ => false,
    }
}

/// `a op b` is `b flip(op) a`.
fn flip(op: BinaryOp) -> BinaryOp {
    match op {
        BinaryOp::Lt => BinaryOp::Gt,
        BinaryOp::Gt => BinaryOp::Lt,
        BinaryOp::Le => BinaryOp::Ge,
        BinaryOp::Ge => BinaryOp::Le,
        o => o,
    }
}

fn const_compare(op: BinaryOp, a: Value, b: Value) -> Option<bool> {
    let ord = match (a, b) {
        (Value::Int(x), Value::Int(y)) => x.cmp(&y),
        (Value::Time(x), Value::Time(y)) => x.cmp(&y),
        (Value::Bool(x), Value::Bool(y)) => x.cmp(&y),
        (Value::Real(x), Value::Real(y)) => x.partial_cmp(&y)?,
        (Value::Int(x), Value::Real(y)) => (x as f64).partial_cmp(&y)?,
        (Value::Real(x), Value::Int(y)) => x.partial_cmp(&(y as f64))?,
        _ => return None,
    };
    Some(match op {
        BinaryOp::Eq => ord == Ordering::Equal,
        BinaryOp::Ne => ord != Ordering::Equal,
        BinaryOp::Lt => ord == Ordering::Less,
        BinaryOp::Gt => ord == Ordering::Greater,
        BinaryOp::Le => ord != Ordering::Greater,
        BinaryOp::Ge => ord != Ordering::Less,
        _ => return None,
    })
}

// ---------------------------------------------------------------------------------------------
// IL

fn synth(kind: ExprKind) -> Expr {
    // Synthesised nodes have the default span, which the type lookup skips.
    Expr { kind, span: Span::default() }
}

/// The current result of an IL condition as one expression (`LD a AND( b OR c ) GT 5` is
/// `(a AND (b OR c)) > 5`). Jumps, labels that are jump targets, stores, S/R, CAL and RET
/// make the condition [`Unknown`].
fn il_expr(body: &IlBody) -> R<Expr> {
    let mut budget = MAX_IL_INSTRUCTIONS;
    il_list(&body.instructions, None, &mut budget, 0)?.ok_or(Unknown)
}

fn il_list(instrs: &[IlInstruction], start: Option<Expr>, budget: &mut usize, depth: u32) -> R<Option<Expr>> {
    if depth > 64 {
        return Err(Unknown);
    }
    let mut cr = start;
    for ins in instrs {
        let Some(op) = &ins.op else { continue };
        *budget = budget.checked_sub(1).ok_or(Unknown)?;
        cr = Some(match parse_il_op(&op.text) {
            None => {
                // A function call: the current result is the first argument.
                let first = cr.take().ok_or(Unknown)?;
                let mut args = vec![first];
                args.extend(ins.operands.iter().cloned());
                let args = args
                    .into_iter()
                    .map(|v| sfc_syntax::ast::Arg {
                        name: None,
                        output: false,
                        negated: false,
                        span: v.span,
                        value: Some(v),
                    })
                    .collect();
                synth(ExprKind::Call { callee: op.clone(), args })
            }
            Some((IlOp::Ld, neg, false)) => {
                let v = il_operand(ins, budget, depth)?;
                if neg {
                    synth(ExprKind::Unary { op: UnaryOp::Not, operand: Box::new(v) })
                } else {
                    v
                }
            }
            Some((IlOp::Binary(bop), neg, false)) => {
                let l = cr.take().ok_or(Unknown)?;
                let mut r = il_operand(ins, budget, depth)?;
                if neg {
                    r = synth(ExprKind::Unary { op: UnaryOp::Not, operand: Box::new(r) });
                }
                synth(ExprKind::Binary { op: bop, lhs: Box::new(l), rhs: Box::new(r) })
            }
            Some((IlOp::Not, false, false)) if ins.operands.is_empty() && ins.nested.is_none() => {
                let v = cr.take().ok_or(Unknown)?;
                synth(ExprKind::Unary { op: UnaryOp::Not, operand: Box::new(v) })
            }
            _ => return Err(Unknown),
        });
    }
    Ok(cr)
}

/// The operand of an instruction; a parenthesised list counts as one.
fn il_operand(ins: &IlInstruction, budget: &mut usize, depth: u32) -> R<Expr> {
    if let Some(nested) = &ins.nested {
        let start = ins.operands.first().cloned();
        let v = il_list(nested, start, budget, depth + 1)?.ok_or(Unknown)?;
        // Keep the grouping visible to the printer.
        return Ok(synth(ExprKind::Paren(Box::new(v))));
    }
    match ins.operands.as_slice() {
        [e] => Ok(e.clone()),
        _ => Err(Unknown),
    }
}
