//! SAT-based checking of the one-scan relation with `rustsat` (BatSat backend): bounded model
//! checking from the initial state (shortest counterexamples first), 1-induction strengthened
//! by the net analysis' invariants, and the clause-by-clause check of an inductive invariant.

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
    /// Per frame: AIG node → SAT literal (positive node).
    frames: Vec<Vec<Option<SLit>>>,
    /// Per frame: SAT literal of each AIG variable that is an input.
    pub input_lits: Vec<Vec<(u32, SLit)>>,
}

impl<'s> Unroller<'s> {
    pub fn new(sys: &'s System) -> Unroller<'s> {
        let mut u = Unroller {
            sys,
            solver: BasicSolver::default(),
            next_var: 0,
            tru: SLit::positive(0),
            frames: Vec::new(),
            input_lits: Vec::new(),
        };
        u.tru = u.fresh();
        let t = u.tru;
        let _ = u.solver.add_unit(t);
        u
    }

    pub fn fresh(&mut self) -> SLit {
        let v = self.next_var;
        self.next_var += 1;
        SLit::positive(v)
    }

    /// Adds a frame whose state variables are `state` (SAT literals per system state var, in
    /// `sys.state` order), or fresh variables when `None`.
    pub fn add_frame(&mut self, state: Option<Vec<SLit>>) -> usize {
        let n = self.sys.g.num_nodes();
        let mut map = vec![None; n];
        let st = match state {
            Some(s) => s,
            None => (0..self.sys.state.len()).map(|_| self.fresh()).collect(),
        };
        for (k, sv) in self.sys.state.iter().enumerate() {
            map[sv.lit.node()] = Some(st[k]);
        }
        self.frames.push(map);
        self.input_lits.push(Vec::new());
        self.frames.len() - 1
    }

    /// The initial state's literals (constants).
    pub fn init_state(&self) -> Vec<SLit> {
        self.sys.state.iter().map(|sv| if sv.init { self.tru } else { !self.tru }).collect()
    }

    /// The SAT literal of AIG literal `l` in frame `f` (encoding its cone on demand).
    pub fn lit(&mut self, f: usize, l: Lit) -> SLit {
        let g: &Aig = &self.sys.g;
        if l.node() == 0 {
            return if l.is_neg() { self.tru } else { !self.tru };
        }
        if self.frames[f][l.node()].is_none() {
            // Iterative post-order over the cone.
            let mut stack = vec![(l.node(), false)];
            while let Some((n, expanded)) = stack.pop() {
                if self.frames[f][n].is_some() {
                    continue;
                }
                match g.node(n) {
                    Node::False => {
                        self.frames[f][n] = Some(!self.tru);
                    }
                    Node::Var(v) => {
                        // A variable that is not a state variable: an input of this frame.
                        let x = self.fresh();
                        self.frames[f][n] = Some(x);
                        self.input_lits[f].push((v, x));
                    }
                    Node::And(a, b) => {
                        if !expanded {
                            stack.push((n, true));
                            for c in [a.node(), b.node()] {
                                if self.frames[f][c].is_none() {
                                    stack.push((c, false));
                                }
                            }
                            continue;
                        }
                        let la = self.get(f, a);
                        let lb = self.get(f, b);
                        let x = self.fresh();
                        let _ = self.solver.add_binary(!x, la);
                        let _ = self.solver.add_binary(!x, lb);
                        let _ = self.solver.add_ternary(x, !la, !lb);
                        self.frames[f][n] = Some(x);
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

    /// The next-state literals of frame `f` (the state of frame `f + 1`).
    pub fn next_state(&mut self, f: usize) -> Vec<SLit> {
        let nexts: Vec<Lit> = self.sys.state.iter().map(|s| s.next).collect();
        nexts.into_iter().map(|l| self.lit(f, l)).collect()
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
        if u.solve(&[t]) == SolverResult::Sat {
            let trace = (0..depth).map(|f| u.frame_inputs(f)).collect();
            return Bmc::Found(trace);
        }
        if depth >= max_depth || Instant::now() >= deadline {
            return Bmc::None { depth };
        }
        // Extend by one scan: the constraint of this frame, then the next frame.
        let c = u.lit(depth, sys.constraint);
        u.add_unit(c);
        let next = u.next_state(depth);
        u.add_frame(Some(next));
        depth += 1;
    }
}

/// 1-induction: `inv ∧ C ∧ T ⇒ ¬bad'` where `inv` is a list of clauses over state literals
/// (the property itself and its strengthening). Returns true when it holds.
pub fn inductive(sys: &System, inv: &[Vec<Lit>], bad: Lit) -> bool {
    let mut u = one_scan_from(sys, inv);
    let b = u.lit(1, bad);
    u.solve(&[b]) == SolverResult::Unsat
}

/// One scan from any state that satisfies `inv` (clauses over state literals) and the input
/// constraint: frame 0 is that state, frame 1 the state after the scan.
fn one_scan_from<'s>(sys: &'s System, inv: &[Vec<Lit>]) -> Unroller<'s> {
    let mut u = Unroller::new(sys);
    u.add_frame(None);
    for cl in inv {
        let c: Vec<SLit> = cl.iter().map(|&l| u.lit(0, l)).collect();
        let _ = u.solver.add_clause(Clause::from_iter(c));
    }
    let c = u.lit(0, sys.constraint);
    u.add_unit(c);
    let next = u.next_state(0);
    u.add_frame(Some(next));
    u
}

/// The independent check of an inductive invariant (a conjunction of clauses over state
/// literals): the initial state satisfies every clause (evaluated directly), and for every
/// clause a SAT call (on one encoding, under assumptions) shows that `inv ∧ C ∧ T` cannot
/// falsify it in the next state.
/// Returns the number of clauses checked, or the first clause that fails.
pub fn check_invariant(sys: &System, inv: &[Vec<Lit>]) -> Result<usize, usize> {
    // Initial state: evaluate the AIG with the state variables at their initial values.
    let mut vals = vec![false; sys.g.num_vars()];
    for sv in &sys.state {
        if let Some(v) = sys.g.var_of(sv.lit) {
            vals[v as usize] = sv.init;
        }
    }
    let table = sys.g.eval_all(&vals);
    for (k, cl) in inv.iter().enumerate() {
        if !cl.iter().any(|&l| Aig::value(&table, l)) {
            return Err(k);
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
    // One encoding of `inv ∧ C ∧ T`; each clause is then refuted under assumptions (the
    // negation of its literals in the next state), which the solver answers incrementally.
    let mut u = one_scan_from(sys, inv);
    for (k, cl) in inv.iter().enumerate() {
        if cl.iter().any(|&l| true_next(l)) {
            continue;
        }
        let negated: Vec<SLit> = cl.iter().map(|&l| !u.lit(1, l)).collect();
        if u.solve(&negated) != SolverResult::Unsat {
            return Err(k);
        }
    }
    Ok(inv.len())
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
