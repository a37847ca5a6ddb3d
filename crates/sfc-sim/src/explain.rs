//! Condition analysis ("why is this step stuck?"), as S7-GRAPH's criteria analysis: for each
//! outgoing transition of an active step, the guard with the value of each operand, the
//! smallest set of operands whose change would make it true, missing synchronisation
//! partners, and masking by a transition of higher priority.

use crate::code::{Ctx, PouBody, Program};
use crate::engine::{ChartState, ScanSink};
use crate::value::{format_time, Value};
use sfc_diagnostics::SourceFile;
use sfc_syntax::ast::{BinaryOp, Condition, Expr, ExprKind, LiteralKind, UnaryOp};

/// Why one transition does not fire.
#[derive(Debug, Clone, PartialEq)]
pub struct TransitionReport {
    /// Qualified transition name.
    pub transition: String,
    /// The guard as written.
    pub guard: String,
    /// Its value now.
    pub value: bool,
    /// Each operand (variable, `S.X`, `S.T`, comparison) with its value as text.
    pub operands: Vec<(String, String)>,
    /// Smallest set of operands whose change would make the guard true, each as
    /// `operand → value` (empty when it is true or when no change of operands can).
    pub change: Vec<String>,
    /// Steps of the transition's pre-set that are not active (synchronisation partners).
    pub missing: Vec<String>,
    /// A transition that takes precedence (higher priority or earlier declaration) and is
    /// enabled and true, so this one would not fire anyway.
    pub masked_by: Option<String>,
    /// Preceding steps still inside their minimum time (`sfc.min_time`), as
    /// `Hold (T#20ms of T#30ms)`: the transition waits for them even when TRUE.
    pub dwell: Vec<String>,
    /// The terminal of each operand wired to the machine, `(operand, "X12.3, %IX0.5")`
    /// (`sfc.terminal` label and AT address, an input of a block followed to its caller).
    pub terminals: Vec<(String, String)>,
    /// The condition in words, one entry per operand that must change, with its terminal and
    /// its value now: `KM2Fb (X12.3, %IX0.5) is FALSE; needs TRUE` (empty when the guard is
    /// true or no change of operands makes it true).
    pub needs: Vec<String>,
}

impl TransitionReport {
    /// An operand as a service technician reads it: `KM2Fb (X12.3, %IX0.5)`, or the operand
    /// alone when it has no terminal.
    pub fn operand_with_terminal(&self, operand: &str) -> String {
        match self.terminals.iter().find(|(o, _)| o == operand) {
            Some((_, t)) => format!("{operand} ({t})"),
            None => operand.to_string(),
        }
    }

    /// The continuation condition in words: the `needs` joined with ` and `, or, when none
    /// can be named, the guard and its value (`Settle.T >= SettleDelay is FALSE`).
    pub fn condition_text(&self) -> String {
        if !self.needs.is_empty() {
            return self.needs.join(" and ");
        }
        if self.guard.is_empty() {
            return "no condition".to_string();
        }
        format!("{} is {}", self.guard, if self.value { "TRUE" } else { "FALSE" })
    }

    /// The operands with their terminals and values: `KM2Fb (%IX0.5) = FALSE, SFCError = TRUE`.
    pub fn operands_text(&self) -> String {
        let ops: Vec<String> =
            self.operands.iter().map(|(o, v)| format!("{} = {v}", self.operand_with_terminal(o))).collect();
        ops.join(", ")
    }
}

/// Why one active step has not been left.
#[derive(Debug, Clone, PartialEq)]
pub struct StepReport {
    /// Qualified step name.
    pub step: String,
    /// How long it has been active, µs.
    pub elapsed: i64,
    /// Its `sfc.timeout`, µs.
    pub timeout: Option<i64>,
    pub transitions: Vec<TransitionReport>,
}

impl StepReport {
    /// One line per transition: `TKM2Closed: KM2Fb is FALSE (needs KM2Fb → TRUE)`.
    pub fn lines(&self) -> Vec<String> {
        let mut out = Vec::new();
        for t in &self.transitions {
            let mut line = format!("{}: {}", t.transition, t.guard);
            if t.value {
                line.push_str(" is TRUE");
            } else {
                line.push_str(" is FALSE");
            }
            if !t.operands.is_empty() {
                line.push_str(&format!(" [{}]", t.operands_text()));
            }
            if !t.needs.is_empty() {
                line.push_str(&format!(": {}", t.needs.join(" and ")));
            }
            if !t.change.is_empty() {
                line.push_str(&format!("; fires when {}", t.change.join(" and ")));
            }
            if !t.missing.is_empty() {
                line.push_str(&format!(
                    "; waits for step{} {} to be active",
                    if t.missing.len() > 1 { "s" } else { "" },
                    t.missing.join(", ")
                ));
            }
            if !t.dwell.is_empty() {
                line.push_str(&format!("; waits for the minimum time of {}", t.dwell.join(", ")));
            }
            if let Some(m) = &t.masked_by {
                line.push_str(&format!("; masked by {m}, which takes precedence"));
            }
            out.push(line);
        }
        if self.transitions.is_empty() {
            out.push("no outgoing transition: the sequence ends here".to_string());
        }
        out
    }

    /// The report as JSON (for `--format json` and the editor).
    pub fn to_json(&self) -> serde_json::Value {
        serde_json::json!({
            "step": self.step,
            "elapsed": format_time(self.elapsed),
            "timeout": self.timeout.map(format_time),
            "transitions": self.transitions.iter().map(|t| serde_json::json!({
                "transition": t.transition,
                "guard": t.guard,
                "value": t.value,
                "operands": t.operands.iter().map(|(o, v)| {
                    let terminal = t.terminals.iter().find(|(n, _)| n == o).map(|(_, x)| x.clone());
                    serde_json::json!({"operand": o, "value": v, "terminal": terminal})
                }).collect::<Vec<_>>(),
                "needs": t.needs,
                "condition": t.condition_text(),
                "change": t.change,
                "missing": t.missing,
                "masked_by": t.masked_by,
                "dwell": t.dwell,
            })).collect::<Vec<_>>(),
        })
    }
}

/// What the analysis reads: the simulation's program and memory, unchanged.
pub(crate) struct View<'a> {
    pub(crate) prog: &'a Program,
    pub(crate) mem: &'a [Value],
    pub(crate) charts: &'a [ChartState],
    pub(crate) source: &'a SourceFile,
    pub(crate) top: usize,
    pub(crate) top_frame: usize,
    pub(crate) now: i64,
    pub(crate) profile: crate::Profile,
}

/// A guard as a boolean formula over atoms.
enum Formula {
    Atom(usize),
    Const(bool),
    Not(Box<Formula>),
    And(Box<Formula>, Box<Formula>),
    Or(Box<Formula>, Box<Formula>),
    Xor(Box<Formula>, Box<Formula>),
}

impl Formula {
    fn eval(&self, atoms: &[Option<bool>], flip: u32) -> Option<bool> {
        Some(match self {
            Formula::Atom(i) => atoms[*i]? ^ (flip >> i & 1 == 1),
            Formula::Const(b) => *b,
            Formula::Not(f) => !f.eval(atoms, flip)?,
            Formula::And(a, b) => a.eval(atoms, flip)? && b.eval(atoms, flip)?,
            Formula::Or(a, b) => a.eval(atoms, flip)? || b.eval(atoms, flip)?,
            Formula::Xor(a, b) => a.eval(atoms, flip)? ^ b.eval(atoms, flip)?,
        })
    }
}

struct Atoms<'v, 'a> {
    view: &'v View<'a>,
    path: &'v str,
    texts: Vec<String>,
    values: Vec<Option<bool>>,
    operands: Vec<(String, String)>,
    terminals: Vec<(String, String)>,
}

impl Atoms<'_, '_> {
    fn formula(&mut self, e: &Expr, depth: u32) -> Formula {
        if depth > 64 {
            return self.atom(e);
        }
        match &e.kind {
            ExprKind::Paren(inner) => self.formula(inner, depth + 1),
            ExprKind::Unary { op: UnaryOp::Not, operand } => Formula::Not(Box::new(self.formula(operand, depth + 1))),
            ExprKind::Binary { op: BinaryOp::And | BinaryOp::AndThen, lhs, rhs } => {
                Formula::And(Box::new(self.formula(lhs, depth + 1)), Box::new(self.formula(rhs, depth + 1)))
            }
            ExprKind::Binary { op: BinaryOp::Or | BinaryOp::OrElse, lhs, rhs } => {
                Formula::Or(Box::new(self.formula(lhs, depth + 1)), Box::new(self.formula(rhs, depth + 1)))
            }
            ExprKind::Binary { op: BinaryOp::Xor, lhs, rhs } => {
                Formula::Xor(Box::new(self.formula(lhs, depth + 1)), Box::new(self.formula(rhs, depth + 1)))
            }
            ExprKind::Literal(l) => match l.kind {
                LiteralKind::Bool(b) => Formula::Const(b),
                _ => self.atom(e),
            },
            _ => self.atom(e),
        }
    }

    fn atom(&mut self, e: &Expr) -> Formula {
        let text = self.view.source.slice(e.span).to_string();
        if let Some(i) = self.texts.iter().position(|t| *t == text) {
            return Formula::Atom(i);
        }
        let value = match &e.kind {
            ExprKind::Binary { op, lhs, rhs } => {
                let l = self.operand(lhs);
                let r = self.operand(rhs);
                match (l, r) {
                    (Some(l), Some(r)) => compare(*op, &l, &r),
                    _ => None,
                }
            }
            _ => match self.operand(e) {
                Some(Value::Bool(b)) => Some(b),
                _ => None,
            },
        };
        self.texts.push(text);
        self.values.push(value);
        Formula::Atom(self.texts.len() - 1)
    }

    /// The value of a simple operand (a name, member path, literal), recorded for the report.
    fn operand(&mut self, e: &Expr) -> Option<Value> {
        let v = match &e.kind {
            ExprKind::Paren(inner) => return self.operand(inner),
            ExprKind::Literal(l) => {
                return match &l.kind {
                    LiteralKind::Bool(b) => Some(Value::Bool(*b)),
                    LiteralKind::Int(i) => i64::try_from(*i).ok().map(Value::Int),
                    LiteralKind::Real(r) => Some(Value::Real(*r)),
                    LiteralKind::Duration(d) => Some(Value::Time(*d)),
                    LiteralKind::String { value, .. } => Some(Value::Str(value.as_str().into())),
                    _ => None,
                };
            }
            ExprKind::Unary { op: UnaryOp::Neg, operand } => {
                return match self.operand(operand)? {
                    Value::Int(i) => Some(Value::Int(i.wrapping_neg())),
                    Value::Real(r) => Some(Value::Real(-r)),
                    Value::Time(t) => Some(Value::Time(t.wrapping_neg())),
                    _ => None,
                };
            }
            ExprKind::Name(_) | ExprKind::Member { .. } | ExprKind::Index { .. } => {
                let text: String = self.view.source.slice(e.span).split_whitespace().collect();
                let full = if self.path.is_empty() { text.clone() } else { format!("{}.{text}", self.path) };
                let (slot, _) = self.view.prog.resolve(self.view.top, self.view.top_frame, &full)?;
                let v = match self.view.mem.get(slot)? {
                    Value::Time(t) if self.view.prog.matiec_time => {
                        Value::Time(crate::timespec::Timespec::unpack(*t).to_us())
                    }
                    v => v.clone(),
                };
                if !self.operands.iter().any(|(o, _)| *o == text) {
                    if let Some(t) = self.view.prog.terminal(self.view.top, &full).and_then(|t| t.text()) {
                        self.terminals.push((text.clone(), t));
                    }
                    self.operands.push((text, show(&v)));
                }
                return Some(v);
            }
            _ => None,
        };
        v
    }
}

fn compare(op: BinaryOp, l: &Value, r: &Value) -> Option<bool> {
    use std::cmp::Ordering;
    let ord = match (l, r) {
        (Value::Int(a), Value::Int(b)) | (Value::Time(a), Value::Time(b)) => a.cmp(b),
        (Value::Time(a), Value::Int(b)) | (Value::Int(a), Value::Time(b)) => a.cmp(b),
        (Value::Bool(a), Value::Bool(b)) => a.cmp(b),
        (Value::Str(a), Value::Str(b)) => a.cmp(b),
        (a, b) => a.as_real()?.partial_cmp(&b.as_real()?)?,
    };
    Some(match op {
        BinaryOp::Eq => ord == Ordering::Equal,
        BinaryOp::Ne => ord != Ordering::Equal,
        BinaryOp::Lt => ord == Ordering::Less,
        BinaryOp::Le => ord != Ordering::Greater,
        BinaryOp::Gt => ord == Ordering::Greater,
        BinaryOp::Ge => ord != Ordering::Less,
        _ => return None,
    })
}

/// A value as the user writes it.
pub fn show(v: &Value) -> String {
    match v {
        Value::Bool(b) => if *b { "TRUE" } else { "FALSE" }.to_string(),
        Value::Int(i) => i.to_string(),
        Value::Real(r) => format!("{r}"),
        Value::Time(t) => format_time(*t),
        Value::Str(s) => format!("'{s}'"),
    }
}

/// The smallest set of atoms to flip that makes the formula true (atoms with unknown values
/// are never flipped). Sets up to four atoms are searched.
fn smallest_change(f: &Formula, values: &[Option<bool>]) -> Option<u32> {
    let n = values.len().min(24);
    if f.eval(values, 0) == Some(true) {
        return Some(0);
    }
    let known: Vec<u32> = (0..n as u32).filter(|&i| values[i as usize].is_some()).collect();
    for size in 1..=known.len().min(4) {
        let mut pick: Vec<usize> = (0..size).collect();
        loop {
            let mask = pick.iter().fold(0u32, |m, &k| m | 1 << known[k]);
            if f.eval(values, mask) == Some(true) {
                return Some(mask);
            }
            // next combination
            let mut i = size;
            loop {
                if i == 0 {
                    break;
                }
                i -= 1;
                if pick[i] < known.len() - size + i {
                    pick[i] += 1;
                    for j in i + 1..size {
                        pick[j] = pick[j - 1] + 1;
                    }
                    break;
                }
                if i == 0 {
                    pick.clear();
                    break;
                }
            }
            if pick.is_empty() {
                break;
            }
        }
    }
    None
}

/// The compiled guards of one chart instance, evaluated on one copy of the memory (guards
/// have no side effects, but compiled code runs against a mutable context).
struct Guards<'v, 'a> {
    view: &'v View<'a>,
    chart: usize,
    mem: Vec<Value>,
    charts: Vec<ChartState>,
}

impl Guards<'_, '_> {
    fn value(&mut self, t: u32) -> Option<bool> {
        let st = &self.view.charts[self.chart];
        let PouBody::Chart(code) = &self.view.prog.pous[st.pou].body else { return None };
        let mut sink = ScanSink::default();
        let mut ctx = Ctx {
            mem: &mut self.mem,
            prog: self.view.prog,
            charts: &mut self.charts,
            sink: &mut sink,
            now: self.view.now,
            scan: 0,
            profile: self.view.profile,
            budget: Default::default(),
        };
        (code.guards[t as usize])(&mut ctx, st.frame).ok()
    }
}

/// The report for active step `s` of chart instance `chart`.
pub(crate) fn report(view: View<'_>, chart: usize, s: u32) -> StepReport {
    let st = &view.charts[chart];
    let plan = &st.plan;
    let PouBody::Chart(code) = &view.prog.pous[st.pou].body else { unreachable!("chart instance without chart") };
    let mut transitions = Vec::new();
    let outgoing = plan.outgoing.get(s);
    // CODESYS ignores PRIORITY: declaration order alone decides.
    let precedes = |a: u32, b: u32| {
        if view.profile == crate::Profile::Codesys {
            a < b
        } else {
            plan.order_key[a as usize] < plan.order_key[b as usize]
        }
    };
    let mut guards = Guards { view: &view, chart, mem: view.mem.to_vec(), charts: view.charts.to_vec() };
    let mut values: Vec<(u32, Option<bool>)> = Vec::new();
    let mut value_of = |t: u32| match values.iter().find(|v| v.0 == t) {
        Some(v) => v.1,
        None => {
            let v = guards.value(t);
            values.push((t, v));
            v
        }
    };
    for &t in outgoing {
        let tr = &code.chart.transitions[t as usize];
        let (guard, value, operands, change, terminals, needs) = match &tr.condition {
            Condition::St(e) => {
                let mut atoms = Atoms {
                    view: &view,
                    // The variables of an action's chart are its instance's.
                    path: &st.var_path,
                    texts: Vec::new(),
                    values: Vec::new(),
                    operands: Vec::new(),
                    terminals: Vec::new(),
                };
                let f = atoms.formula(e, 0);
                let value = value_of(t).unwrap_or(false);
                let flips: Vec<(usize, bool)> = if value {
                    Vec::new()
                } else {
                    match smallest_change(&f, &atoms.values) {
                        Some(mask) => (0..atoms.texts.len())
                            .filter(|&i| mask >> i & 1 == 1)
                            .map(|i| (i, !atoms.values[i].unwrap_or(false)))
                            .collect(),
                        None => Vec::new(),
                    }
                };
                let word = |b: bool| if b { "TRUE" } else { "FALSE" };
                let change =
                    flips.iter().map(|&(i, to)| format!("{} → {}", atoms.texts[i], word(to))).collect::<Vec<_>>();
                let needs = flips
                    .iter()
                    .map(|&(i, to)| {
                        let text = &atoms.texts[i];
                        let named = match atoms.terminals.iter().find(|(o, _)| o == text) {
                            Some((_, t)) => format!("{text} ({t})"),
                            None => text.clone(),
                        };
                        format!("{named} is {}; needs {}", word(!to), word(to))
                    })
                    .collect::<Vec<_>>();
                // Comparisons are operands too: show their values.
                let mut operands = atoms.operands;
                for (text, v) in atoms.texts.iter().zip(&atoms.values) {
                    if !operands.iter().any(|(o, _)| o == text) {
                        operands.push((text.clone(), v.map(|b| show(&Value::Bool(b))).unwrap_or_else(|| "?".into())));
                    }
                }
                (view.source.slice(e.span).to_string(), value, operands, change, atoms.terminals, needs)
            }
            Condition::Il(il) => {
                let value = value_of(t).unwrap_or(false);
                (view.source.slice(il.span).trim().to_string(), value, Vec::new(), Vec::new(), Vec::new(), Vec::new())
            }
            Condition::Missing => (String::new(), false, Vec::new(), Vec::new(), Vec::new(), Vec::new()),
        };
        let missing: Vec<String> = plan
            .pre
            .get(t)
            .iter()
            .filter(|&&p| !st.is_active(p))
            .map(|&p| st.qualify(&plan.step_names[p as usize]))
            .collect();
        let masked_by = outgoing
            .iter()
            .filter(|&&o| o != t && precedes(o, t))
            .find(|&&o| plan.pre.get(o).iter().all(|&p| st.is_active(p)) && value_of(o) == Some(true))
            .map(|&o| st.qualify(&plan.transition_names[o as usize]));
        let dwell: Vec<String> = plan
            .pre
            .get(t)
            .iter()
            .filter(|&&p| st.is_active(p))
            .filter_map(|&p| {
                let min = plan.min_times[p as usize]?;
                (st.time(p) < min).then(|| {
                    format!(
                        "{} ({} of {})",
                        st.qualify(&plan.step_names[p as usize]),
                        format_time(st.time(p)),
                        format_time(min)
                    )
                })
            })
            .collect();
        transitions.push(TransitionReport {
            dwell,
            transition: st.qualify(&plan.transition_names[t as usize]),
            guard,
            value,
            operands,
            change,
            missing,
            masked_by,
            terminals,
            needs,
        });
    }
    StepReport {
        step: st.qualify(&plan.step_names[s as usize]),
        elapsed: st.time(s),
        timeout: plan.timeouts[s as usize],
        transitions,
    }
}
