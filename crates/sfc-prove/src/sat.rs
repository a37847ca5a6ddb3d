//! SAT-based checking of the one-scan relation with `rustsat` (BatSat backend): bounded model
//! checking from the initial state (shortest counterexamples first), 1-induction strengthened
//! by the net analysis' invariants (clauses and at-most-one constraints, the queries split
//! into one case per active step), and the constraint-by-constraint check of an inductive
//! invariant. The encoding is lazy (a frame's next state only as far as a query reads it) and
//! folds constants (the initial state, a case's step flags).

use crate::aig::{Aig, Lit, Node};
use crate::system::System;
use rustsat::solvers::{Solve, SolveIncremental, SolverResult};
use rustsat::types::{Clause, Lit as SLit, TernaryVal};
use std::cell::Cell;
use std::time::Instant;

thread_local! {
    /// When the SAT solver of this thread must give up (the property's time budget).
    static DEADLINE: Cell<Option<Instant>> = const { Cell::new(None) };
}

/// BatSat callbacks that stop the search at the thread's deadline.
#[derive(Default)]
pub struct Clock;

impl batsat::Callbacks for Clock {
    fn stop(&self) -> bool {
        DEADLINE.with(|d| d.get().is_some_and(|t| Instant::now() > t))
    }
}

/// The solver: BatSat with the deadline.
pub type BasicSolver = rustsat_batsat::Solver<Clock>;

/// Sets the deadline of the SAT calls of this thread.
pub fn set_deadline(t: Option<Instant>) {
    DEADLINE.with(|d| d.set(t));
}

/// Tseitin translation of AIG cones, one copy per time frame.
pub struct Unroller<'s> {
    pub sys: &'s System,
    pub solver: BasicSolver,
    next_var: u32,
    /// The literal standing for TRUE.
    tru: SLit,
    /// Per frame: AIG node → SAT literal (positive node). Frames beyond `nframes` are kept
    /// (cleared) for reuse after [`Unroller::reset`].
    frames: Vec<Vec<Option<SLit>>>,
    /// Per frame: the nodes set in it (to clear them on reset).
    touched: Vec<Vec<u32>>,
    nframes: usize,
    /// Per frame: SAT literal of each AIG variable that is an input.
    pub input_lits: Vec<Vec<(u32, SLit)>>,
    /// Per frame: whether its state is the previous frame's next state, encoded on demand.
    linked: Vec<bool>,
    /// AIG node → index in `sys.state`, for the state variables.
    state_of: Vec<Option<u32>>,
}

impl<'s> Unroller<'s> {
    pub fn new(sys: &'s System) -> Unroller<'s> {
        let mut u = Unroller {
            sys,
            solver: BasicSolver::default(),
            next_var: 0,
            tru: SLit::positive(0),
            frames: Vec::new(),
            touched: Vec::new(),
            nframes: 0,
            input_lits: Vec::new(),
            linked: Vec::new(),
            state_of: vec![None; sys.g.num_nodes()],
        };
        for (k, sv) in sys.state.iter().enumerate() {
            u.state_of[sv.lit.node()] = Some(k as u32);
        }
        u.tru = u.fresh();
        let t = u.tru;
        let _ = u.solver.add_unit(t);
        u
    }

    /// Starts over with a new solver and no frames, keeping the allocations.
    pub fn reset(&mut self) {
        for f in 0..self.nframes {
            for &n in &self.touched[f] {
                self.frames[f][n as usize] = None;
            }
            self.touched[f].clear();
        }
        self.nframes = 0;
        self.input_lits.clear();
        self.linked.clear();
        self.solver = BasicSolver::default();
        self.next_var = 0;
        self.tru = self.fresh();
        let t = self.tru;
        let _ = self.solver.add_unit(t);
    }

    pub fn fresh(&mut self) -> SLit {
        let v = self.next_var;
        self.next_var += 1;
        SLit::positive(v)
    }

    fn set(&mut self, f: usize, n: usize, x: SLit) {
        self.frames[f][n] = Some(x);
        self.touched[f].push(n as u32);
    }

    /// A new, empty frame.
    fn push_frame(&mut self, linked: bool) -> usize {
        if self.frames.len() <= self.nframes {
            self.frames.push(vec![None; self.sys.g.num_nodes()]);
            self.touched.push(Vec::new());
        }
        self.nframes += 1;
        self.input_lits.push(Vec::new());
        self.linked.push(linked);
        self.nframes - 1
    }

    /// Adds a frame whose state variables are `state` (SAT literals per system state var, in
    /// `sys.state` order), or fresh variables when `None`.
    pub fn add_frame(&mut self, state: Option<Vec<SLit>>) -> usize {
        let f = self.push_frame(false);
        let st = match state {
            Some(s) => s,
            None => (0..self.sys.state.len()).map(|_| self.fresh()).collect(),
        };
        let sys: &'s System = self.sys;
        for (k, sv) in sys.state.iter().enumerate() {
            self.set(f, sv.lit.node(), st[k]);
        }
        f
    }

    /// Adds a frame whose state is the next state of the last frame. Only what is asked of it
    /// is encoded (the next-state functions of the state bits its literals depend on), so a
    /// query about a few registers does not carry the whole scan.
    pub fn add_next_frame(&mut self) -> usize {
        self.push_frame(true)
    }

    /// The initial state's literals (constants).
    pub fn init_state(&self) -> Vec<SLit> {
        self.sys.state.iter().map(|sv| if sv.init { self.tru } else { !self.tru }).collect()
    }

    /// The SAT literal of AIG literal `l` in frame `f` (encoding its cone on demand).
    pub fn lit(&mut self, f: usize, l: Lit) -> SLit {
        let sys: &'s System = self.sys;
        let g: &Aig = &sys.g;
        if l.node() == 0 {
            return if l.is_neg() { self.tru } else { !self.tru };
        }
        if self.frames[f][l.node()].is_none() {
            // Iterative post-order over the cone, folding constants: a conjunction whose first
            // child (the older node, usually the condition) is FALSE is FALSE without its
            // other child, so what a scan does under a condition known to be false is never
            // encoded.
            let mut stack = vec![(l.node(), 0u8)];
            while let Some((n, stage)) = stack.pop() {
                if self.frames[f][n].is_some() {
                    continue;
                }
                match g.node(n) {
                    Node::False => {
                        let x = !self.tru;
                        self.set(f, n, x);
                    }
                    Node::Var(v) => match self.state_of[n] {
                        // A state bit of a linked frame: the previous frame's next state.
                        Some(k) if f > 0 && self.linked[f] => {
                            let next = sys.state[k as usize].next;
                            let x = self.lit(f - 1, next);
                            self.set(f, n, x);
                        }
                        // A variable that is not a state variable: an input of this frame.
                        _ => {
                            let x = self.fresh();
                            self.set(f, n, x);
                            self.input_lits[f].push((v, x));
                        }
                    },
                    Node::And(a, b) => {
                        let (first, second) = if a.node() <= b.node() { (a, b) } else { (b, a) };
                        match stage {
                            0 => {
                                stack.push((n, 1));
                                if self.frames[f][first.node()].is_none() {
                                    stack.push((first.node(), 0));
                                }
                            }
                            1 => {
                                if self.get(f, first) == !self.tru {
                                    {
                                        let x = !self.tru;
                                        self.set(f, n, x);
                                    }
                                    continue;
                                }
                                stack.push((n, 2));
                                if self.frames[f][second.node()].is_none() {
                                    stack.push((second.node(), 0));
                                }
                            }
                            _ => {
                                let (la, lb) = (self.get(f, first), self.get(f, second));
                                let (t, x) = (self.tru, !self.tru);
                                let out = if lb == x || la == !lb {
                                    x
                                } else if la == t || la == lb {
                                    lb
                                } else if lb == t {
                                    la
                                } else {
                                    let y = self.fresh();
                                    let _ = self.solver.add_binary(!y, la);
                                    let _ = self.solver.add_binary(!y, lb);
                                    let _ = self.solver.add_ternary(y, !la, !lb);
                                    y
                                };
                                self.set(f, n, out);
                            }
                        }
                    }
                }
            }
        }
        self.get(f, l)
    }

    fn get(&self, f: usize, l: Lit) -> SLit {
        let x = self.frames[f][l.node()].expect("encoded");
        if l.is_neg() {
            !x
        } else {
            x
        }
    }

    pub fn add_unit(&mut self, l: SLit) {
        let _ = self.solver.add_unit(l);
    }

    pub fn solve(&mut self, assumps: &[SLit]) -> SolverResult {
        self.solver.solve_assumps(assumps).unwrap_or(SolverResult::Interrupted)
    }

    pub fn value(&self, l: SLit) -> bool {
        matches!(self.solver.lit_val(l), Ok(TernaryVal::True))
    }

    /// The input valuation of frame `f` (AIG variable → value), from the last model.
    pub fn frame_inputs(&self, f: usize) -> Vec<(u32, bool)> {
        self.input_lits[f].iter().map(|&(v, x)| (v, self.value(x))).collect()
    }
}

/// The outcome of a bounded search.
pub enum Bmc {
    /// A path of this many scans reaches `bad`: the inputs of each scan (AIG variable values).
    Found(Vec<Vec<(u32, bool)>>),
    /// No path of at most `depth` scans reaches it.
    None { depth: usize },
}

/// Bounded model checking: the shortest path from the initial state to a state satisfying
/// `target` (a state predicate), searching depths 0, 1, 2, … up to `max_depth` or `deadline`.
pub fn bmc(sys: &System, target: Lit, max_depth: usize, deadline: Instant) -> Bmc {
    let mut u = Unroller::new(sys);
    let init = u.init_state();
    u.add_frame(Some(init));
    let mut depth = 0;
    loop {
        let t = u.lit(depth, target);
        match u.solve(&[t]) {
            SolverResult::Sat => {
                let trace = (0..depth).map(|f| u.frame_inputs(f)).collect();
                return Bmc::Found(trace);
            }
            // Stopped by the deadline: this depth is not searched.
            SolverResult::Interrupted => return Bmc::None { depth: depth.saturating_sub(1) },
            SolverResult::Unsat => {}
        }
        if depth >= max_depth || Instant::now() >= deadline {
            return Bmc::None { depth };
        }
        // Extend by one scan: the constraint of this frame, then the next frame.
        let c = u.lit(depth, sys.constraint);
        u.add_unit(c);
        u.add_next_frame();
        depth += 1;
    }
}

/// A candidate inductive invariant over state literals: clauses, and at-most-one constraints
/// (each says that at most one of its literals is true: the same as the pairwise clauses
/// `¬a ∨ ¬b` of its literals, in linear size — the net analysis' "never active together" over
/// the steps of a state machine).
#[derive(Debug, Clone, Default)]
pub struct Invariant {
    pub clauses: Vec<Vec<Lit>>,
    pub at_most_one: Vec<Vec<Lit>>,
}

impl Invariant {
    /// The invariant of the property alone (`¬bad`).
    pub fn of(bad: Lit) -> Invariant {
        Invariant { clauses: vec![vec![bad.not()]], at_most_one: Vec::new() }
    }

    /// Its size: clauses and at-most-one constraints.
    pub fn len(&self) -> usize {
        self.clauses.len() + self.at_most_one.len()
    }

    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    pub fn extend(&mut self, other: &Invariant) {
        self.clauses.extend(other.clauses.iter().cloned());
        self.at_most_one.extend(other.at_most_one.iter().cloned());
    }
}

/// 1-induction: `inv ∧ C ∧ T ⇒ ¬bad'` where `inv` holds the property itself and its
/// strengthening, case by case (see [`cases`]). `Some(true)` when it holds, `Some(false)` when
/// a scan from a state of `inv` reaches `bad`, `None` when the deadline stopped the solver.
pub fn inductive(sys: &System, inv: &Invariant, bad: Lit) -> Option<bool> {
    let mut u = Unroller::new(sys);
    for case in cases(sys, inv) {
        one_scan_from(&mut u, inv, &case);
        let b = u.lit(1, bad);
        if b == !u.tru {
            continue;
        }
        match u.solve(&[b]) {
            SolverResult::Unsat => {}
            SolverResult::Sat => return Some(false),
            SolverResult::Interrupted => return None,
        }
    }
    Some(true)
}

/// A case of a query: values of some state variables (AIG variable numbers) in frame 0.
type Case = Vec<(u32, bool)>;

/// The cases a query about one scan from a state of `inv` is split into: over the largest
/// at-most-one constraint (of three literals or more), none of its literals true, or exactly
/// one of them — the step of the state machine that is active. Under the constraint these
/// cases are every state. Each case is encoded on its own with those state bits as constants,
/// which [`Unroller::lit`] folds away: the scan becomes what the one active step does, instead
/// of a scan in which any set of steps may be active and every action may run after every
/// other (the chained arithmetic that makes the whole query hard). Without such a constraint,
/// one case that fixes nothing.
fn cases(sys: &System, inv: &Invariant) -> Vec<Case> {
    let Some(group) = inv.at_most_one.iter().filter(|g| g.len() >= 3).max_by_key(|g| g.len()) else {
        return vec![Vec::new()];
    };
    // The value of a member's variable that makes the member (a literal) true or false.
    let vars: Vec<(u32, bool)> = group.iter().filter_map(|&l| sys.g.var_of(l).map(|v| (v, !l.is_neg()))).collect();
    let distinct: std::collections::HashSet<u32> = vars.iter().map(|&(v, _)| v).collect();
    if vars.len() != group.len() || distinct.len() != vars.len() {
        return vec![Vec::new()];
    }
    let none: Case = vars.iter().map(|&(v, pos)| (v, !pos)).collect();
    let mut out = vec![none];
    for k in 0..vars.len() {
        out.push(vars.iter().enumerate().map(|(i, &(v, pos))| (v, if i == k { pos } else { !pos })).collect());
    }
    out
}

impl Unroller<'_> {
    /// Asserts that at most one of `lits` (frame 0) is true: a sequential ladder, `s_i` for
    /// "one of the first i is true" (3 clauses per literal, arc-consistent under propagation),
    /// over the literals that are not constants (a case's step flags are).
    fn at_most_one(&mut self, lits: &[Lit]) {
        let no = !self.tru;
        let xs: Vec<SLit> = lits.iter().map(|&l| self.lit(0, l)).filter(|&x| x != no).collect();
        let trues = xs.iter().filter(|&&x| x == self.tru).count();
        if trues > 1 {
            let f = !self.tru;
            self.add_unit(f);
            return;
        }
        if trues == 1 {
            for &x in &xs {
                if x != self.tru {
                    let _ = self.solver.add_unit(!x);
                }
            }
            return;
        }
        let mut prev: Option<SLit> = None;
        for x in xs {
            let s = self.fresh();
            let _ = self.solver.add_binary(!x, s);
            if let Some(p) = prev {
                let _ = self.solver.add_binary(!p, s);
                let _ = self.solver.add_binary(!p, !x);
            }
            prev = Some(s);
        }
    }

    /// A literal that, assumed, says at least two of `lits` are true in frame 1 (the constant
    /// TRUE or FALSE when the folded literals decide it).
    fn two_of(&mut self, lits: &[Lit]) -> SLit {
        let no = !self.tru;
        let ys: Vec<SLit> = lits.iter().map(|&l| self.lit(1, l)).filter(|&y| y != no).collect();
        let trues = ys.iter().filter(|&&y| y == self.tru).count();
        if trues > 1 {
            return self.tru;
        }
        if ys.len() < 2 {
            return !self.tru;
        }
        // p_i → (one of the first i is true); t_i → p_{i-1} ∧ lit_i; act → some t_i.
        let act = self.fresh();
        let mut goal = vec![!act];
        let mut prev: Option<SLit> = None;
        for y in ys {
            let p = self.fresh();
            match prev {
                None => {
                    let _ = self.solver.add_binary(!p, y);
                }
                Some(q) => {
                    let _ = self.solver.add_ternary(!p, q, y);
                    let t = self.fresh();
                    let _ = self.solver.add_binary(!t, q);
                    let _ = self.solver.add_binary(!t, y);
                    goal.push(t);
                }
            }
            prev = Some(p);
        }
        let _ = self.solver.add_clause(Clause::from_iter(goal));
        act
    }
}

/// One scan from any state that satisfies `inv`, the input constraint and `case`: frame 0
/// is that state (the case's bits constants), frame 1 the state after the scan.
fn one_scan_from(u: &mut Unroller<'_>, inv: &Invariant, case: &[(u32, bool)]) {
    let sys = u.sys;
    u.reset();
    let mut fixed: Vec<Option<bool>> = vec![None; sys.g.num_vars()];
    for &(v, b) in case {
        fixed[v as usize] = Some(b);
    }
    let state: Vec<SLit> = sys
        .state
        .iter()
        .map(|sv| match sys.g.var_of(sv.lit).and_then(|v| fixed[v as usize]) {
            Some(true) => u.tru,
            Some(false) => !u.tru,
            None => u.fresh(),
        })
        .collect();
    u.add_frame(Some(state));
    for cl in &inv.clauses {
        let c: Vec<SLit> = cl.iter().map(|&l| u.lit(0, l)).collect();
        let _ = u.solver.add_clause(Clause::from_iter(c));
    }
    for g in &inv.at_most_one {
        u.at_most_one(g);
    }
    let c = u.lit(0, sys.constraint);
    u.add_unit(c);
    u.add_next_frame();
}

/// The independent check of an inductive invariant: the initial state satisfies every clause
/// and every at-most-one constraint (evaluated directly), and for each of them SAT calls show
/// that no scan from a state of `inv ∧ C` falsifies it: for a clause, the negation of its
/// literals in the next state; for an at-most-one constraint, two of its literals true in the
/// next state. The calls are made case by case ([`cases`]: together, every state), on one
/// encoding per case, under assumptions.
/// Returns the number of constraints checked, or the first one that fails (clauses first).
pub fn check_invariant(sys: &System, inv: &Invariant) -> Result<usize, usize> {
    // Initial state: evaluate the AIG with the state variables at their initial values.
    let mut vals = vec![false; sys.g.num_vars()];
    for sv in &sys.state {
        if let Some(v) = sys.g.var_of(sv.lit) {
            vals[v as usize] = sv.init;
        }
    }
    let table = sys.g.eval_all(&vals);
    for (k, cl) in inv.clauses.iter().enumerate() {
        if !cl.iter().any(|&l| Aig::value(&table, l)) {
            return Err(k);
        }
    }
    for (k, g) in inv.at_most_one.iter().enumerate() {
        if g.iter().filter(|&&l| Aig::value(&table, l)).count() > 1 {
            return Err(inv.clauses.len() + k);
        }
    }
    // A literal whose next-state function is the constant that makes it true holds after
    // every scan (the "scan 0 done" flag): its clause needs no search.
    let next_of: std::collections::HashMap<u32, Lit> =
        sys.state.iter().filter_map(|sv| sys.g.var_of(sv.lit).map(|v| (v, sv.next))).collect();
    let true_next = |l: Lit| {
        sys.g
            .var_of(l)
            .and_then(|v| next_of.get(&v))
            .is_some_and(|&n| n == if l.is_neg() { Lit::FALSE } else { Lit::TRUE })
    };
    let mut failed: Option<usize> = None;
    let mut u = Unroller::new(sys);
    for case in cases(sys, inv) {
        one_scan_from(&mut u, inv, &case);
        for (k, cl) in inv.clauses.iter().enumerate() {
            if cl.iter().any(|&l| true_next(l)) {
                continue;
            }
            let negated: Vec<SLit> = cl.iter().map(|&l| !u.lit(1, l)).collect();
            if negated.contains(&!u.tru) {
                continue;
            }
            if u.solve(&negated) != SolverResult::Unsat {
                failed = Some(failed.map_or(k, |f| f.min(k)));
                break;
            }
        }
        if failed.is_some() {
            break;
        }
        for (k, g) in inv.at_most_one.iter().enumerate() {
            let two = u.two_of(g);
            if two == !u.tru {
                continue;
            }
            if u.solve(&[two]) != SolverResult::Unsat {
                failed = Some(inv.clauses.len() + k);
                break;
            }
        }
        if failed.is_some() {
            break;
        }
    }
    match failed {
        Some(k) => Err(k),
        None => Ok(inv.len()),
    }
}

/// Completes a trace of one scan: values for every input variable such that the constraint
/// holds in `state`, keeping the `fixed` values. `state` gives the AIG variable values of the
/// state. None when no input satisfies the constraint.
pub fn complete_inputs(sys: &System, state: &[(u32, bool)], fixed: &[(u32, bool)]) -> Option<Vec<(u32, bool)>> {
    let mut u = Unroller::new(sys);
    let st: Vec<SLit> = sys
        .state
        .iter()
        .map(|sv| {
            let v =
                sys.g.var_of(sv.lit).and_then(|v| state.iter().find(|(x, _)| *x == v).map(|p| p.1)).unwrap_or(sv.init);
            if v {
                u.tru
            } else {
                !u.tru
            }
        })
        .collect();
    u.add_frame(Some(st));
    let c = u.lit(0, sys.constraint);
    let mut assumps = vec![c];
    for &(v, b) in fixed {
        let l = sys.g.var_lit(v);
        let x = u.lit(0, l);
        assumps.push(if b { x } else { !x });
    }
    if u.solve(&assumps) != SolverResult::Sat {
        return None;
    }
    Some(u.frame_inputs(0))
}

/// Whether some valuation of the variables makes `l` TRUE (the graph alone, no state or
/// constraint): used to stop unrolling a loop once it cannot run another iteration.
pub fn satisfiable(g: &Aig, l: Lit) -> bool {
    if let Some(c) = l.as_const() {
        return c;
    }
    let mut solver = BasicSolver::default();
    let mut map: std::collections::HashMap<usize, SLit> = std::collections::HashMap::new();
    let mut next = 0u32;
    let mut fresh = || {
        next += 1;
        SLit::positive(next - 1)
    };
    for n in g.cone(&[l]) {
        let x = fresh();
        if let Node::And(a, b) = g.node(n) {
            let get = |m: &std::collections::HashMap<usize, SLit>, y: Lit| {
                let v = m.get(&y.node()).copied().unwrap_or(x);
                if y.is_neg() {
                    !v
                } else {
                    v
                }
            };
            let (la, lb) = (get(&map, a), get(&map, b));
            let _ = solver.add_binary(!x, la);
            let _ = solver.add_binary(!x, lb);
            let _ = solver.add_ternary(x, !la, !lb);
        } else if let Node::False = g.node(n) {
            let _ = solver.add_unit(!x);
        }
        map.insert(n, x);
    }
    let root = map[&l.node()];
    let goal = if l.is_neg() { !root } else { root };
    solver.solve_assumps(&[goal]).map_or(true, |r| r != SolverResult::Unsat)
}
