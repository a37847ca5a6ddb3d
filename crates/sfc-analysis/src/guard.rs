//! Guard analysis: what the transition conditions of a chart allow, decided with binary
//! decision diagrams (`biodivine-lib-bdd`).
//!
//! For every chart it reports
//! * **non-exclusive alternatives** ([`GuardFindingKind::NonExclusive`]): two transitions
//!   that share a source step, whose source steps can all be active together, and whose guards
//!   can be TRUE in the same scan. Which one fires is then decided by priority or, without it,
//!   silently by declaration order;
//! * **incomplete alternatives** ([`GuardFindingKind::Incomplete`]): a step with two or more
//!   outgoing transitions and a valuation in which none of their guards is TRUE (the step
//!   waits; a note, since waiting is normal);
//! * **constant guards** ([`GuardFindingKind::AlwaysTrue`], [`GuardFindingKind::AlwaysFalse`]):
//!   a guard that is TRUE (FALSE) whatever the inputs once its source steps are active. A lone
//!   literal `TRUE`/`FALSE`/`1`/`0` is a deliberate choice and is not reported.
//!
//! Every non-exclusive and incomplete finding carries a witness: a valuation of everything
//! the guards involved refer to, under which the claim holds.
//!
//! ## Atoms and their theory
//! Guards become boolean formulas over atoms ([`translate`]): BOOL variables and access paths,
//! step flags `S.X`, opaque sub-expressions (function calls, arithmetic, FB outputs) keyed by
//! their printed form, comparisons of a term with a constant, and comparisons of two terms.
//! * A comparison `v op c` of an integer, REAL, TIME or enumeration term with a constant
//!   (literal or named CONSTANT, either side) becomes thresholds of `v` in order encoding:
//!   `v >= k` for integer-valued terms (`x > 5` is `x >= 6`, TIME in µs, enumerations by
//!   value index with `=`/`<>` only) and `v >= c` / `v > c` for REAL. The thresholds of one
//!   term are chained (`x >= 6 → x >= 3`), so `x > 5 AND x < 3` is unsatisfiable while
//!   `x >= 5 AND x <= 5` is not. The term's type range decides thresholds outside it
//!   (`USINT < 0` is FALSE); step times `S.T` are never negative. A term without a known type
//!   takes the kind of the constant (LINT range for integers).
//! * A comparison of two non-constant terms (`a > b`, `S.T >= Limit`) becomes one of the
//!   relation atoms `A < B`, `B < A`, `A = B` (in the order of the terms' keys); at most one of
//!   them is TRUE, and one is when all three occur. Transitivity across three terms is not
//!   modelled, nor any link between a relation and the thresholds of its terms (`x > 5`,
//!   `y < 3` and `x < y` are not seen to contradict each other): an over-approximation, such
//!   guards may be reported non-exclusive or incomplete.
//! * Step flags: when a query assumes the steps `P` active, `S.X` is TRUE for `S ∈ P`, FALSE
//!   for a step that cannot be active together with some step of `P` (the `together`
//!   relation), and free otherwise, two free flags that cannot be together never being TRUE
//!   at once. Step times stay free (≥ 0): a stopwatch keeps its value when the step is left.
//!
//! ## What is not analysed
//! A guard that cannot be translated (an error node, IL with jumps, stores, S/R, CAL or RET,
//! more than 512 IL instructions, nesting deeper than 400) or that needs more than
//! [`MAX_GUARD_VARS`] BDD variables, or whose BDD grows beyond [`BDD_NODE_LIMIT`] nodes, is
//! *unknown*: no finding involves it, and a divergence with an unknown or missing guard gets no
//! incomplete finding. A chart needing more than [`MAX_CHART_VARS`] variables in all leaves the
//! remaining guards unknown.
//!
//! ## Priorities
//! `explicit_priority` is TRUE when the order of the two transitions is fixed by PRIORITY:
//! both have one and they differ, or only one has one (prioritised transitions are tried
//! first, `semantics.md`). Both without PRIORITY, or with equal PRIORITY, leave the choice to
//! declaration order, which is the warning case.
//!
//! ## Order of findings
//! Non-exclusive pairs by `(first, second)` ascending, then incomplete steps by step id, then
//! constant guards by transition id.

mod print;
mod theory;
mod translate;

use biodivine_lib_bdd::{op_function, Bdd, BddValuation, BddVariable, BddVariableSet};
use sfc_model::{Chart, StepId, TransitionId};
use sfc_st::{Scope, Type, TypeEnv};
use sfc_syntax::ast::{Item as AstItem, SourceUnit, Span};
use std::collections::{BTreeMap, BTreeSet, HashMap, HashSet};
use translate::{AtomKind, Formula, Guard, Item, NumId, Tables, Thr, Translator};

/// At most this many BDD variables (atoms and thresholds) in one guard.
pub const MAX_GUARD_VARS: usize = 128;
/// At most this many BDD variables in one chart.
pub const MAX_CHART_VARS: usize = 30_000;
/// A BDD operation whose result would exceed this many nodes is abandoned (guard unknown, or
/// no finding for the query).
pub const BDD_NODE_LIMIT: usize = 200_000;

/// What was found about the guards of a chart.
#[derive(Debug, Clone, PartialEq)]
pub enum GuardFindingKind {
    /// Both guards can be TRUE while both transitions are enabled; `first` is declared first.
    NonExclusive { first: TransitionId, second: TransitionId, explicit_priority: bool },
    /// With the step active, none of its outgoing guards can be TRUE.
    Incomplete { step: StepId },
    /// The guard is TRUE whenever its source steps are active.
    AlwaysTrue { transition: TransitionId },
    /// The guard is never TRUE while its source steps are active (the transition is dead).
    AlwaysFalse { transition: TransitionId },
}

/// A finding with its witness: source-level names (`x`, `a.b`, `S1.X`, `S1.T`, `ABS(x)`,
/// `a < b`) with their values (BOOL as `true`/`false`, integers as numbers, REAL as numbers,
/// TIME as a literal such as `"T#5s"`, enumerations as the value name). The witness lists
/// every atom and term of the guards involved, in order of first occurrence; it is empty for
/// [`GuardFindingKind::AlwaysTrue`] and [`GuardFindingKind::AlwaysFalse`].
#[derive(Debug, Clone, PartialEq)]
pub struct GuardFinding {
    pub kind: GuardFindingKind,
    pub witness: Vec<(String, serde_json::Value)>,
}

/// What the analysis needs besides the chart.
#[derive(Clone)]
pub struct GuardContext<'a> {
    /// The checked file (declarations of the chart's POU, types, globals, constants).
    pub unit: &'a SourceUnit,
    /// Expression types recorded by the checker (`keep_types`); may be empty.
    pub expr_types: &'a HashMap<Span, Type>,
    /// Whether two distinct steps can be active at the same time.
    pub together: &'a dyn Fn(StepId, StepId) -> bool,
}

impl std::fmt::Debug for GuardContext<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("GuardContext")
            .field("items", &self.unit.items.len())
            .field("expr_types", &self.expr_types.len())
            .finish_non_exhaustive()
    }
}

/// Analyses the guards of one chart (see the module documentation).
pub fn analyze_guards(chart: &Chart, cx: &GuardContext) -> Vec<GuardFinding> {
    let (env, _) = TypeEnv::from_unit(cx.unit);
    let scope = match cx.unit.items.get(chart.item) {
        Some(AstItem::Pou(p)) if p.name.is(&chart.pou) => Scope::for_pou(&env, p),
        _ => cx
            .unit
            .items
            .iter()
            .find_map(|i| match i {
                AstItem::Pou(p) if p.name.is(&chart.pou) => Some(Scope::for_pou(&env, p)),
                _ => None,
            })
            .unwrap_or_else(|| Scope::globals_only(&env)),
    };
    let mut tr = Translator {
        chart,
        scope: &scope,
        expr_types: cx.expr_types,
        tables: Tables::default(),
        names: translate::chart_names(chart),
    };
    let guards: Vec<Option<Guard>> = chart.transitions.iter().map(|t| tr.guard(&t.condition).ok().flatten()).collect();
    let tables = tr.tables;
    let engine = Engine::new(chart, cx.together, tables, guards);
    engine.run()
}

/// The guards of one chart as BDDs over one variable set.
struct Engine<'a> {
    chart: &'a Chart,
    together: &'a dyn Fn(StepId, StepId) -> bool,
    tables: Tables,
    guards: Vec<Option<Guard>>,
    vars: BddVariableSet,
    atom_var: Vec<Option<BddVariable>>,
    thr_var: BTreeMap<(NumId, Thr), BddVariable>,
    bdds: Vec<Option<Bdd>>,
    /// Source steps of each transition, deduplicated, valid ids only.
    from: Vec<Vec<StepId>>,
}

/// The outcome of a satisfiability query.
enum Sat {
    Yes(BddValuation),
    No,
    /// Too large to decide.
    Unknown,
}

impl<'a> Engine<'a> {
    fn new(
        chart: &'a Chart,
        together: &'a dyn Fn(StepId, StepId) -> bool,
        tables: Tables,
        mut guards: Vec<Option<Guard>>,
    ) -> Self {
        // Allocate BDD variables guard by guard, so each guard's variables are adjacent.
        let mut atom_var: Vec<Option<usize>> = vec![None; tables.atoms.len()];
        let mut thr_var: BTreeMap<(NumId, Thr), usize> = BTreeMap::new();
        let mut count = 0usize;
        for slot in guards.iter_mut() {
            let Some(g) = slot else { continue };
            let atoms: Vec<usize> = g
                .items
                .iter()
                .filter_map(|i| match i {
                    Item::Atom(a) => Some(*a),
                    Item::Num(_) => None,
                })
                .collect();
            if atoms.len() + g.thresholds.len() > MAX_GUARD_VARS {
                *slot = None;
                continue;
            }
            let new = atoms.iter().filter(|a| atom_var.get(**a).is_some_and(|v| v.is_none())).count()
                + g.thresholds.iter().filter(|t| !thr_var.contains_key(t)).count();
            if count + new > MAX_CHART_VARS {
                *slot = None;
                continue;
            }
            for a in atoms {
                if atom_var[a].is_none() {
                    atom_var[a] = Some(count);
                    count += 1;
                }
            }
            for t in &g.thresholds {
                if !thr_var.contains_key(t) {
                    thr_var.insert(*t, count);
                    count += 1;
                }
            }
        }
        // `count` is at most MAX_CHART_VARS, far below the library's limit of u16::MAX - 1.
        let vars = BddVariableSet::new_anonymous(count as u16);
        let atom_var = atom_var.into_iter().map(|v| v.map(BddVariable::from_index)).collect();
        let thr_var = thr_var.into_iter().map(|(k, v)| (k, BddVariable::from_index(v))).collect();
        let from = chart
            .transitions
            .iter()
            .map(|t| {
                let set: BTreeSet<StepId> = t.from.iter().copied().filter(|s| *s < chart.steps.len()).collect();
                set.into_iter().collect()
            })
            .collect();
        let mut e = Engine { chart, together, tables, guards, vars, atom_var, thr_var, bdds: Vec::new(), from };
        let bdds: Vec<Option<Bdd>> = e.guards.iter().map(|g| g.as_ref().and_then(|g| e.build(&g.formula))).collect();
        for (g, b) in e.guards.iter_mut().zip(&bdds) {
            if b.is_none() {
                *g = None;
            }
        }
        e.bdds = bdds;
        e
    }

    fn build(&self, f: &Formula) -> Option<Bdd> {
        let bin = |a: &Formula, b: &Formula, op: fn(Option<bool>, Option<bool>) -> Option<bool>| {
            let (x, y) = (self.build(a)?, self.build(b)?);
            Bdd::binary_op_with_limit(BDD_NODE_LIMIT, &x, &y, op)
        };
        match f {
            Formula::Const(true) => Some(self.vars.mk_true()),
            Formula::Const(false) => Some(self.vars.mk_false()),
            Formula::Atom(a) => Some(self.vars.mk_var((*self.atom_var.get(*a)?)?)),
            Formula::Thr(n, t) => Some(self.vars.mk_var(*self.thr_var.get(&(*n, *t))?)),
            Formula::Not(x) => Some(self.build(x)?.not()),
            Formula::And(a, b) => bin(a, b, op_function::and),
            Formula::Or(a, b) => bin(a, b, op_function::or),
            Formula::Xor(a, b) => bin(a, b, op_function::xor),
            Formula::Iff(a, b) => bin(a, b, op_function::iff),
        }
    }

    fn and(&self, a: &Bdd, b: &Bdd) -> Option<Bdd> {
        Bdd::binary_op_with_limit(BDD_NODE_LIMIT, a, b, op_function::and)
    }

    fn can_be_together(&self, steps: &[StepId]) -> bool {
        steps.iter().enumerate().all(|(i, &a)| steps[i + 1..].iter().all(|&b| a == b || (self.together)(a, b)))
    }

    fn guard(&self, t: TransitionId) -> Option<(&Guard, &Bdd)> {
        Some((self.guards.get(t)?.as_ref()?, self.bdds.get(t)?.as_ref()?))
    }

    /// The theory of the atoms and thresholds used by the guards `ts`, with the steps `active`
    /// assumed active.
    fn context(&self, ts: &[TransitionId], active: &[StepId]) -> Option<Bdd> {
        let mut atoms: BTreeSet<usize> = BTreeSet::new();
        let mut thresholds: BTreeSet<(NumId, Thr)> = BTreeSet::new();
        for &t in ts {
            let (g, _) = self.guard(t)?;
            for it in &g.items {
                if let Item::Atom(a) = it {
                    atoms.insert(*a);
                }
            }
            thresholds.extend(g.thresholds.iter().copied());
        }
        let mut ctx = self.vars.mk_true();
        // Order of the thresholds of each term.
        let mut prev: Option<(NumId, BddVariable)> = None;
        for (n, t) in &thresholds {
            let v = *self.thr_var.get(&(*n, *t))?;
            if let Some((pn, pv)) = prev {
                if pn == *n {
                    ctx = self.and(&ctx, &self.vars.mk_var(v).imp(&self.vars.mk_var(pv)))?;
                }
            }
            prev = Some((*n, v));
        }
        // Relations: at most one of `A < B`, `B < A`, `A = B`; one of them when all occur.
        let mut pairs: BTreeMap<usize, Vec<BddVariable>> = BTreeMap::new();
        let mut free_steps: Vec<(StepId, BddVariable)> = Vec::new();
        for &a in &atoms {
            let var = (*self.atom_var.get(a)?)?;
            match self.tables.atoms.get(a)?.kind {
                AtomKind::Plain => {}
                AtomKind::Relation(p) => pairs.entry(p).or_default().push(var),
                AtomKind::StepFlag(s) => {
                    if active.contains(&s) {
                        ctx = self.and(&ctx, &self.vars.mk_var(var))?;
                    } else if active.iter().any(|&r| !(self.together)(s, r)) {
                        ctx = self.and(&ctx, &self.vars.mk_not_var(var))?;
                    } else {
                        free_steps.push((s, var));
                    }
                }
            }
        }
        for vs in pairs.values() {
            for (i, a) in vs.iter().enumerate() {
                for b in &vs[i + 1..] {
                    ctx = self.and(&ctx, &self.vars.mk_var(*a).and(&self.vars.mk_var(*b)).not())?;
                }
            }
            if vs.len() == 3 {
                let any = vs.iter().fold(self.vars.mk_false(), |acc, v| acc.or(&self.vars.mk_var(*v)));
                ctx = self.and(&ctx, &any)?;
            }
        }
        for (i, (s, a)) in free_steps.iter().enumerate() {
            for (u, b) in &free_steps[i + 1..] {
                if s != u && !(self.together)(*s, *u) {
                    ctx = self.and(&ctx, &self.vars.mk_var(*a).and(&self.vars.mk_var(*b)).not())?;
                }
            }
        }
        Some(ctx)
    }

    /// Whether `f` is satisfiable under the theory of the guards `ts` with `active` active.
    fn sat(&self, f: &Bdd, ts: &[TransitionId], active: &[StepId]) -> Sat {
        if f.is_false() {
            return Sat::No;
        }
        let Some(ctx) = self.context(ts, active) else { return Sat::Unknown };
        match self.and(f, &ctx) {
            None => Sat::Unknown,
            Some(r) => match r.sat_witness() {
                Some(v) => Sat::Yes(v),
                None => Sat::No,
            },
        }
    }

    /// The witness of a valuation: every atom and term of the guards `ts`.
    fn witness(&self, ts: &[TransitionId], val: &BddValuation) -> Vec<(String, serde_json::Value)> {
        let mut out: Vec<(String, serde_json::Value)> = Vec::new();
        let mut seen_items: HashSet<Item> = HashSet::new();
        let mut seen_names: HashSet<String> = HashSet::new();
        let mut thresholds: BTreeSet<(NumId, Thr)> = BTreeSet::new();
        for &t in ts {
            if let Some((g, _)) = self.guard(t) {
                thresholds.extend(g.thresholds.iter().copied());
            }
        }
        for &t in ts {
            let Some((g, _)) = self.guard(t) else { continue };
            for it in &g.items {
                if !seen_items.insert(*it) {
                    continue;
                }
                let entry = match *it {
                    Item::Atom(a) => {
                        let (Some(atom), Some(Some(var))) = (self.tables.atoms.get(a), self.atom_var.get(a)) else {
                            continue;
                        };
                        (atom.display.clone(), serde_json::Value::Bool(val.value(*var)))
                    }
                    Item::Num(n) => {
                        let Some(nv) = self.tables.nums.get(n) else { continue };
                        let ts: Vec<(Thr, bool)> = thresholds
                            .range((n, Thr::Int(i128::MIN))..)
                            .take_while(|(m, _)| *m == n)
                            .filter_map(|(_, t)| self.thr_var.get(&(n, *t)).map(|v| (*t, val.value(*v))))
                            .collect();
                        (nv.display.clone(), theory::value_of(nv, &ts))
                    }
                };
                if seen_names.insert(entry.0.to_ascii_uppercase()) {
                    out.push(entry);
                }
            }
        }
        out
    }

    fn run(&self) -> Vec<GuardFinding> {
        let mut findings = Vec::new();
        let n_steps = self.chart.steps.len();
        let mut outgoing: Vec<Vec<TransitionId>> = vec![Vec::new(); n_steps];
        for (t, from) in self.from.iter().enumerate() {
            for &s in from {
                outgoing[s].push(t);
            }
        }
        // Non-exclusive pairs.
        let mut pairs: BTreeSet<(TransitionId, TransitionId)> = BTreeSet::new();
        for out in &outgoing {
            for (i, &a) in out.iter().enumerate() {
                for &b in &out[i + 1..] {
                    if a != b {
                        pairs.insert((a.min(b), a.max(b)));
                    }
                }
            }
        }
        for (t1, t2) in pairs {
            let (Some((_, b1)), Some((_, b2))) = (self.guard(t1), self.guard(t2)) else { continue };
            let active: Vec<StepId> =
                self.from[t1].iter().chain(&self.from[t2]).copied().collect::<BTreeSet<_>>().into_iter().collect();
            if !self.can_be_together(&active) {
                continue;
            }
            let Some(both) = self.and(b1, b2) else { continue };
            if let Sat::Yes(v) = self.sat(&both, &[t1, t2], &active) {
                let p1 = self.chart.transitions[t1].priority;
                let p2 = self.chart.transitions[t2].priority;
                let explicit_priority = match (p1, p2) {
                    (Some(a), Some(b)) => a != b,
                    (None, None) => false,
                    _ => true,
                };
                findings.push(GuardFinding {
                    kind: GuardFindingKind::NonExclusive { first: t1, second: t2, explicit_priority },
                    witness: self.witness(&[t1, t2], &v),
                });
            }
        }
        // Incomplete alternatives.
        for (s, out) in outgoing.iter().enumerate() {
            if out.len() < 2 {
                continue;
            }
            let live: Vec<TransitionId> =
                out.iter().copied().filter(|&t| self.can_be_together(&self.from[t])).collect();
            if live.is_empty() || live.iter().any(|&t| self.guard(t).is_none()) {
                continue;
            }
            let mut none = Some(self.vars.mk_true());
            for &t in &live {
                none = match (none, self.guard(t)) {
                    (Some(acc), Some((_, b))) => {
                        Bdd::binary_op_with_limit(BDD_NODE_LIMIT, &acc, b, op_function::and_not)
                    }
                    _ => None,
                };
            }
            let Some(none) = none else { continue };
            if let Sat::Yes(v) = self.sat(&none, &live, &[s]) {
                findings.push(GuardFinding {
                    kind: GuardFindingKind::Incomplete { step: s },
                    witness: self.witness(&live, &v),
                });
            }
        }
        // Constant guards.
        for t in 0..self.chart.transitions.len() {
            let Some((g, b)) = self.guard(t) else { continue };
            if g.deliberate || self.from[t].is_empty() || !self.can_be_together(&self.from[t]) {
                continue;
            }
            let active = &self.from[t];
            if let Sat::No = self.sat(&b.not(), &[t], active) {
                findings
                    .push(GuardFinding { kind: GuardFindingKind::AlwaysTrue { transition: t }, witness: Vec::new() });
            } else if let Sat::No = self.sat(b, &[t], active) {
                findings
                    .push(GuardFinding { kind: GuardFindingKind::AlwaysFalse { transition: t }, witness: Vec::new() });
            }
        }
        findings
    }
}
