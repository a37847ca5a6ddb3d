//! Symbolic reachability with BDDs (`biodivine-lib-bdd`): breadth-first rings from the initial
//! state (so a violation is found at its shortest depth and its witness is read back through
//! the rings), backward fixpoints for "the goal can always be reached again", and the check
//! that a reachable set is an inductive invariant.
//!
//! Variables: the inputs first, then per state bit its current and next copy side by side
//! (each register's bits most significant first), so renaming next → current keeps the order
//! and is a relabelling of the diagram's nodes.

use crate::aig::{Lit, Node};
use crate::system::System;
use biodivine_lib_bdd::{op_function, Bdd, BddNode, BddVariable, BddVariableSet};
use std::collections::HashMap;
use std::time::Instant;

/// Why a symbolic computation stopped early.
#[derive(Debug, Clone)]
pub enum GiveUp {
    /// A diagram grew beyond the node limit.
    Nodes(usize),
    Time,
    /// The reached set counted more states than the budget allows.
    States(f64),
}

pub struct BddEngine {
    pub sys: System,
    vars: BddVariableSet,
    cur: Vec<BddVariable>,
    nxt: Vec<BddVariable>,
    input_of: HashMap<u32, BddVariable>,
    state_of: HashMap<u32, usize>,
    memo: HashMap<usize, Bdd>,
    /// `x'_k ⇔ f_k(x, i)` per state bit, and the variables to quantify after conjoining it.
    parts: Vec<Bdd>,
    /// The next variable each part defines.
    part_nxt: Vec<BddVariable>,
    q_after: Vec<Vec<BddVariable>>,
    q_first: Vec<BddVariable>,
    /// The next-state functions per state bit (over current and input variables).
    funcs: Vec<Bdd>,
    constraint: Bdd,
    /// The whole relation with the inputs quantified, `∃i. C ∧ ∧_k (x'_k ⇔ f_k)`, when it is
    /// small enough to build: an image is then one operation.
    mono: Option<Bdd>,
    cur_vars: Vec<BddVariable>,
    nxt_vars: Vec<BddVariable>,
    /// Relabelling tables (by variable index).
    to_cur: Vec<u16>,
    to_nxt: Vec<u16>,
    pub node_limit: usize,
    pub deadline: Instant,
    pub max_states: Option<f64>,
    n_extra: usize,
}

/// The result of a forward search.
#[derive(Clone)]
pub struct Reach {
    /// `rings[k]`: states first reached after `k` transitions (ring 0 is the initial state).
    pub rings: Vec<Bdd>,
    pub reached: Bdd,
    /// Stopped at a depth where `target` was met.
    pub hit: Option<usize>,
    pub complete: bool,
}

fn not_limit<T>(r: Option<T>, size: usize) -> Result<T, GiveUp> {
    r.ok_or(GiveUp::Nodes(size))
}

impl BddEngine {
    pub fn new(sys: System, node_limit: usize, deadline: Instant) -> Result<BddEngine, GiveUp> {
        // Inputs: every AIG variable in the cone that is not a state variable.
        let state_vars: HashMap<u32, usize> =
            sys.state.iter().enumerate().filter_map(|(i, s)| sys.g.var_of(s.lit).map(|v| (v, i))).collect();
        let mut roots: Vec<Lit> = sys.state.iter().map(|s| s.next).collect();
        roots.push(sys.constraint);
        let support = sys.g.support(&roots);
        let inputs: Vec<u32> = support.into_iter().filter(|v| !state_vars.contains_key(v)).collect();
        // Order: inputs, then state bits grouped by register, most significant bit first.
        let mut order: Vec<usize> = (0..sys.state.len()).collect();
        order.sort_by_key(|&i| (sys.state[i].reg, std::cmp::Reverse(sys.state[i].bit)));
        let n = inputs.len() + 2 * sys.state.len();
        if n > u16::MAX as usize - 1 {
            return Err(GiveUp::Nodes(n));
        }
        let vars = BddVariableSet::new_anonymous(n as u16);
        let mut input_of = HashMap::new();
        for (k, &v) in inputs.iter().enumerate() {
            input_of.insert(v, BddVariable::from_index(k));
        }
        let mut cur = vec![BddVariable::from_index(0); sys.state.len()];
        let mut nxt = cur.clone();
        let mut to_cur: Vec<u16> = (0..n as u16).collect();
        let mut to_nxt: Vec<u16> = (0..n as u16).collect();
        for (pos, &i) in order.iter().enumerate() {
            let c = inputs.len() + 2 * pos;
            cur[i] = BddVariable::from_index(c);
            nxt[i] = BddVariable::from_index(c + 1);
            to_cur[c + 1] = c as u16;
            to_nxt[c] = (c + 1) as u16;
        }
        let mut e = BddEngine {
            vars,
            cur,
            nxt,
            input_of,
            state_of: state_vars,
            memo: HashMap::new(),
            parts: Vec::new(),
            part_nxt: Vec::new(),
            q_after: Vec::new(),
            q_first: Vec::new(),
            funcs: Vec::new(),
            constraint: BddVariableSet::new_anonymous(1).mk_true(),
            mono: None,
            cur_vars: Vec::new(),
            nxt_vars: Vec::new(),
            to_cur,
            to_nxt,
            node_limit,
            deadline,
            max_states: None,
            n_extra: inputs.len() + sys.state.len(),
            sys,
        };
        let c = e.sys.constraint;
        e.constraint = e.of(c)?;
        let mut funcs = Vec::new();
        let mut parts = Vec::new();
        let nexts: Vec<Lit> = e.sys.state.iter().map(|s| s.next).collect();
        for (k, next) in nexts.into_iter().enumerate() {
            let f = e.of(next)?;
            let x = e.vars.mk_var(e.nxt[k]);
            let p = not_limit(Bdd::binary_op_with_limit(node_limit, &x, &f, op_function::iff), node_limit)?;
            funcs.push(f);
            parts.push(p);
            if Instant::now() > deadline {
                return Err(GiveUp::Time);
            }
        }
        // Quantification schedule: a current or input variable goes after the last part that
        // mentions it (parts in the BDD variable order of their next variable).
        let mut porder: Vec<usize> = (0..parts.len()).collect();
        porder.sort_by_key(|&k| e.nxt[k].to_index());
        let parts: Vec<Bdd> = porder.iter().map(|&k| parts[k].clone()).collect();
        e.part_nxt = porder.iter().map(|&k| e.nxt[k]).collect();
        let mut last: HashMap<BddVariable, usize> = HashMap::new();
        for (j, p) in parts.iter().enumerate() {
            for v in p.support_set() {
                if e.is_nxt(v) {
                    continue;
                }
                last.insert(v, j);
            }
        }
        let mut q_after = vec![Vec::new(); parts.len()];
        let mut q_first = Vec::new();
        let all_quant: Vec<BddVariable> = e.cur.iter().copied().chain(e.input_of.values().copied()).collect();
        for v in all_quant {
            match last.get(&v) {
                Some(&j) => q_after[j].push(v),
                None => q_first.push(v),
            }
        }
        e.parts = parts;
        e.q_after = q_after;
        e.q_first = q_first;
        e.funcs = funcs;
        e.cur_vars = e.cur.clone();
        e.nxt_vars = e.nxt.clone();
        // The monolithic relation, if it stays small: the parts are conjoined pairwise (a
        // balanced tree keeps the intermediate diagrams small), then the inputs quantified.
        let limit = (node_limit / 10).clamp(10_000, 200_000);
        let mut level: Vec<Bdd> = e.parts.clone();
        level.push(e.constraint.clone());
        let mut ok = true;
        while level.len() > 1 && ok {
            let mut next = Vec::with_capacity(level.len() / 2 + 1);
            let mut it = level.into_iter();
            while let Some(a) = it.next() {
                match it.next() {
                    Some(b) => match Bdd::binary_op_with_limit(limit, &a, &b, op_function::and) {
                        Some(c) => next.push(c),
                        None => {
                            ok = false;
                            break;
                        }
                    },
                    None => next.push(a),
                }
            }
            level = next;
            if Instant::now() > deadline {
                return Err(GiveUp::Time);
            }
        }
        if ok {
            if let Some(a) = level.pop() {
                let inputs: Vec<BddVariable> = e.input_of.values().copied().collect();
                let a = if inputs.is_empty() { a } else { a.exists(&inputs) };
                if a.size() <= limit {
                    e.mono = Some(a);
                }
            }
        }
        Ok(e)
    }

    fn is_nxt(&self, v: BddVariable) -> bool {
        self.to_cur[v.to_index()] as usize != v.to_index()
    }

    fn check(&self, b: Bdd) -> Result<Bdd, GiveUp> {
        if b.size() > self.node_limit {
            return Err(GiveUp::Nodes(b.size()));
        }
        if Instant::now() > self.deadline {
            return Err(GiveUp::Time);
        }
        Ok(b)
    }

    /// The BDD of an AIG literal over current-state and input variables.
    pub fn of(&mut self, l: Lit) -> Result<Bdd, GiveUp> {
        let g = &self.sys.g;
        let mut stack = vec![(l.node(), false)];
        while let Some((n, expanded)) = stack.pop() {
            if self.memo.contains_key(&n) {
                continue;
            }
            let b = match g.node(n) {
                Node::False => self.vars.mk_false(),
                Node::Var(v) => match self.state_of.get(&v) {
                    Some(&k) => self.vars.mk_var(self.cur[k]),
                    None => match self.input_of.get(&v) {
                        Some(&x) => self.vars.mk_var(x),
                        // A variable outside the cone: any value (it cannot matter).
                        None => self.vars.mk_false(),
                    },
                },
                Node::And(a, b) => {
                    if !expanded {
                        stack.push((n, true));
                        for c in [a.node(), b.node()] {
                            if !self.memo.contains_key(&c) {
                                stack.push((c, false));
                            }
                        }
                        continue;
                    }
                    let x = self.lit_of(a);
                    let y = self.lit_of(b);
                    not_limit(Bdd::binary_op_with_limit(self.node_limit, &x, &y, op_function::and), self.node_limit)?
                }
            };
            self.memo.insert(n, b);
            if Instant::now() > self.deadline {
                return Err(GiveUp::Time);
            }
        }
        Ok(self.lit_of(l))
    }

    fn lit_of(&self, l: Lit) -> Bdd {
        let b = &self.memo[&l.node()];
        if l.is_neg() {
            b.not()
        } else {
            b.clone()
        }
    }

    fn relabel(&self, b: &Bdd, table: &[u16]) -> Bdd {
        let mut nodes = b.clone().to_nodes();
        for node in nodes.iter_mut().skip(2) {
            let i = node.var.to_index();
            node.var = BddVariable::from_index(table[i] as usize);
        }
        let nodes: Vec<BddNode> = nodes;
        Bdd::from_nodes(&nodes).unwrap_or_else(|_| b.clone())
    }

    /// The initial state.
    pub fn init(&self) -> Bdd {
        let mut acc = self.vars.mk_true();
        for (k, s) in self.sys.state.iter().enumerate() {
            let lit = self.vars.mk_literal(self.cur[k], s.init);
            acc = acc.and(&lit);
        }
        acc
    }

    /// States reachable in one scan from `s`.
    pub fn image(&self, s: &Bdd) -> Result<Bdd, GiveUp> {
        if let Some(t) = &self.mono {
            let acc = self.check(Bdd::binary_op_with_exists(s, t, op_function::and, &self.cur_vars))?;
            return Ok(self.relabel(&acc, &self.to_cur));
        }
        let mut acc = self.check(s.and(&self.constraint))?;
        if !self.q_first.is_empty() {
            acc = acc.exists(&self.q_first);
        }
        for (j, p) in self.parts.iter().enumerate() {
            acc = if self.q_after[j].is_empty() {
                self.check(acc.and(p))?
            } else {
                self.check(Bdd::binary_op_with_exists(&acc, p, op_function::and, &self.q_after[j]))?
            };
            if acc.is_false() {
                return Ok(acc);
            }
        }
        Ok(self.relabel(&acc, &self.to_cur))
    }

    /// States with a successor in `z` (one scan).
    pub fn preimage(&self, z: &Bdd) -> Result<Bdd, GiveUp> {
        let zn = self.relabel(z, &self.to_nxt);
        if let Some(t) = &self.mono {
            return self.check(Bdd::binary_op_with_exists(&zn, t, op_function::and, &self.nxt_vars));
        }
        let support = zn.support_set();
        let mut acc = self.check(zn.and(&self.constraint))?;
        // Only the parts whose next variable `z` mentions matter (∃x'. x' ⇔ f is TRUE).
        for (j, p) in self.parts.iter().enumerate() {
            let v = self.part_nxt[j];
            if !support.contains(&v) {
                continue;
            }
            acc = self.check(Bdd::binary_op_with_exists(&acc, p, op_function::and, &[v]))?;
            if acc.is_false() {
                return Ok(acc);
            }
        }
        let inputs: Vec<BddVariable> = self.input_of.values().copied().collect();
        self.check(acc.exists(&inputs))
    }

    /// Nodes of the monolithic relation (0 when partitioned).
    pub fn relation_size(&self) -> usize {
        self.mono.as_ref().map_or(0, |b| b.size())
    }

    pub fn vars_true(&self) -> Bdd {
        self.vars.mk_true()
    }

    /// Whether no scan leads from a state of `b` out of it.
    pub fn closed(&self, b: &Bdd) -> Result<bool, GiveUp> {
        let img = self.image(b)?;
        Ok(img.and_not(b).is_false())
    }

    /// Number of states in a set over the current variables.
    pub fn count(&self, b: &Bdd) -> f64 {
        b.cardinality() / 2f64.powi(self.n_extra as i32)
    }

    /// Breadth-first search from the initial state, stopping at the first ring meeting
    /// `target` (when given).
    pub fn reach(&self, target: Option<&Bdd>) -> Result<Reach, GiveUp> {
        let init = self.init();
        let mut reached = init.clone();
        let mut rings = vec![init.clone()];
        let mut frontier = init;
        loop {
            if let Some(t) = target {
                if !frontier.and(t).is_false() {
                    let hit = rings.len() - 1;
                    return Ok(Reach { rings, reached, hit: Some(hit), complete: false });
                }
            }
            let img = self.image(&frontier)?;
            let new = self.check(img.and_not(&reached))?;
            if new.is_false() {
                return Ok(Reach { rings, reached, hit: None, complete: true });
            }
            reached = self.check(reached.or(&new))?;
            if let Some(max) = self.max_states {
                let c = self.count(&reached);
                if c > max {
                    return Err(GiveUp::States(c));
                }
            }
            rings.push(new.clone());
            frontier = new;
        }
    }

    /// The states from which `goal` can be reached (backward fixpoint), within `within`.
    pub fn can_reach(&self, goal: &Bdd, within: &Bdd) -> Result<Bdd, GiveUp> {
        let mut b = goal.and(within);
        let mut frontier = b.clone();
        loop {
            let pre = self.preimage(&frontier)?;
            let new = self.check(pre.and(within).and_not(&b))?;
            if new.is_false() {
                return Ok(b);
            }
            b = self.check(b.or(&new))?;
            frontier = new;
        }
    }

    /// The shortest path from the initial state to a state of `target` through the rings:
    /// the inputs of every scan (AIG variable values) and the state values at the end.
    pub fn path_to(&self, reach: &Reach, target: &Bdd) -> Option<Vec<Vec<(u32, bool)>>> {
        let depth = reach.rings.iter().position(|r| !r.and(target).is_false())?;
        let last = reach.rings[depth].and(target).sat_witness()?;
        let mut state: Vec<bool> = self.cur.iter().map(|&v| last.value(v)).collect();
        let mut inputs_rev: Vec<Vec<(u32, bool)>> = Vec::new();
        for k in (0..depth).rev() {
            // A state of ring k with inputs whose successor is `state`.
            let mut acc = reach.rings[k].and(&self.constraint);
            for (j, f) in self.funcs.iter().enumerate() {
                acc = if state[j] { acc.and(f) } else { acc.and_not(f) };
                if acc.is_false() {
                    return None;
                }
            }
            let w = acc.sat_witness()?;
            let ins: Vec<(u32, bool)> = self.input_of.iter().map(|(&v, &x)| (v, w.value(x))).collect();
            inputs_rev.push(ins);
            state = self.cur.iter().map(|&v| w.value(v)).collect();
        }
        inputs_rev.reverse();
        Some(inputs_rev)
    }

    /// The BDD of a state predicate.
    pub fn predicate(&mut self, l: Lit) -> Result<Bdd, GiveUp> {
        self.of(l)
    }

    /// Whether `inv` is an inductive invariant containing the initial state and excluding
    /// `bad`: checked with one image computation (the BDD check of a reachable set).
    pub fn check_inductive(&self, inv: &Bdd, bad: &Bdd) -> Result<bool, GiveUp> {
        if !self.init().and_not(inv).is_false() {
            return Ok(false);
        }
        let img = self.image(inv)?;
        Ok(img.and_not(inv).is_false() && inv.and(bad).is_false())
    }
}
