//! An and-inverter graph: the bit-level form of one scan. Every node is a conjunction of two
//! literals, a variable (a latch of the state or a free input of the scan) or the constant
//! FALSE. Structural hashing and constant folding keep it small; both the BDD and the SAT
//! engines read it.

use std::collections::HashMap;

/// A literal: a node, possibly negated. `Lit::FALSE` and `Lit::TRUE` are the constants.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct Lit(pub u32);

impl Lit {
    pub const FALSE: Lit = Lit(0);
    pub const TRUE: Lit = Lit(1);
    #[inline]
    pub fn node(self) -> usize {
        (self.0 >> 1) as usize
    }
    #[inline]
    pub fn is_neg(self) -> bool {
        self.0 & 1 == 1
    }
    #[inline]
    pub fn not(self) -> Lit {
        Lit(self.0 ^ 1)
    }
    #[inline]
    pub fn from_bool(b: bool) -> Lit {
        if b {
            Lit::TRUE
        } else {
            Lit::FALSE
        }
    }
    #[inline]
    pub fn as_const(self) -> Option<bool> {
        match self.0 {
            0 => Some(false),
            1 => Some(true),
            _ => None,
        }
    }
    /// The positive literal of the same node.
    #[inline]
    pub fn positive(self) -> Lit {
        Lit(self.0 & !1)
    }
    #[inline]
    fn of(node: usize, neg: bool) -> Lit {
        Lit(((node as u32) << 1) | neg as u32)
    }
}

impl std::ops::Not for Lit {
    type Output = Lit;
    fn not(self) -> Lit {
        Lit(self.0 ^ 1)
    }
}

/// A node of the graph.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Node {
    False,
    /// Variable number `n` (see [`Aig::new_var`]).
    Var(u32),
    And(Lit, Lit),
}

/// The graph.
#[derive(Debug, Clone)]
pub struct Aig {
    nodes: Vec<Node>,
    strash: HashMap<(Lit, Lit), u32>,
    vars: Vec<u32>,
}

impl Default for Aig {
    fn default() -> Self {
        Aig::new()
    }
}

impl Aig {
    pub fn new() -> Aig {
        Aig { nodes: vec![Node::False], strash: HashMap::new(), vars: Vec::new() }
    }

    /// A fresh variable; returns its positive literal.
    pub fn new_var(&mut self) -> Lit {
        let id = self.vars.len() as u32;
        self.nodes.push(Node::Var(id));
        self.vars.push((self.nodes.len() - 1) as u32);
        Lit::of(self.nodes.len() - 1, false)
    }

    /// The positive literal of variable `v`.
    pub fn var_lit(&self, v: u32) -> Lit {
        Lit::of(self.vars[v as usize] as usize, false)
    }

    pub fn num_vars(&self) -> usize {
        self.vars.len()
    }

    pub fn num_nodes(&self) -> usize {
        self.nodes.len()
    }

    pub fn node(&self, i: usize) -> Node {
        self.nodes[i]
    }

    /// The variable a literal stands for, if it is a variable (or its negation).
    pub fn var_of(&self, l: Lit) -> Option<u32> {
        match self.nodes[l.node()] {
            Node::Var(v) => Some(v),
            _ => None,
        }
    }

    pub fn and(&mut self, a: Lit, b: Lit) -> Lit {
        if a == Lit::FALSE || b == Lit::FALSE || a == b.not() {
            return Lit::FALSE;
        }
        if a == Lit::TRUE || a == b {
            return b;
        }
        if b == Lit::TRUE {
            return a;
        }
        let (x, y) = if a < b { (a, b) } else { (b, a) };
        // One level of absorption: x ∧ (x ∧ z) = x ∧ z, x ∧ (¬x ∧ z) = FALSE.
        for (p, q) in [(x, y), (y, x)] {
            if let Node::And(c, d) = self.nodes[q.node()] {
                if !q.is_neg() {
                    if c == p || d == p {
                        return q;
                    }
                    if c == p.not() || d == p.not() {
                        return Lit::FALSE;
                    }
                }
            }
        }
        if let Some(&n) = self.strash.get(&(x, y)) {
            return Lit::of(n as usize, false);
        }
        self.nodes.push(Node::And(x, y));
        let n = (self.nodes.len() - 1) as u32;
        self.strash.insert((x, y), n);
        Lit::of(n as usize, false)
    }

    pub fn or(&mut self, a: Lit, b: Lit) -> Lit {
        let n = self.and(a.not(), b.not());
        n.not()
    }

    pub fn xor(&mut self, a: Lit, b: Lit) -> Lit {
        if let Some(c) = a.as_const() {
            return if c { b.not() } else { b };
        }
        if let Some(c) = b.as_const() {
            return if c { a.not() } else { a };
        }
        if a == b {
            return Lit::FALSE;
        }
        if a == b.not() {
            return Lit::TRUE;
        }
        let p = self.and(a, b.not());
        let q = self.and(a.not(), b);
        self.or(p, q)
    }

    pub fn xnor(&mut self, a: Lit, b: Lit) -> Lit {
        self.xor(a, b).not()
    }

    pub fn implies(&mut self, a: Lit, b: Lit) -> Lit {
        self.or(a.not(), b)
    }

    /// `if c then t else e`.
    pub fn ite(&mut self, c: Lit, t: Lit, e: Lit) -> Lit {
        if let Some(k) = c.as_const() {
            return if k { t } else { e };
        }
        if t == e {
            return t;
        }
        if t == Lit::TRUE {
            return self.or(c, e);
        }
        if t == Lit::FALSE {
            return self.and(c.not(), e);
        }
        if e == Lit::TRUE {
            return self.or(c.not(), t);
        }
        if e == Lit::FALSE {
            return self.and(c, t);
        }
        if t == e.not() {
            return self.xnor(c, t);
        }
        let p = self.and(c, t);
        let q = self.and(c.not(), e);
        self.or(p, q)
    }

    pub fn and_all(&mut self, lits: impl IntoIterator<Item = Lit>) -> Lit {
        let mut acc = Lit::TRUE;
        for l in lits {
            acc = self.and(acc, l);
            if acc == Lit::FALSE {
                break;
            }
        }
        acc
    }

    pub fn or_all(&mut self, lits: impl IntoIterator<Item = Lit>) -> Lit {
        let mut acc = Lit::FALSE;
        for l in lits {
            acc = self.or(acc, l);
            if acc == Lit::TRUE {
                break;
            }
        }
        acc
    }

    /// Evaluates literals under a valuation of the variables (`vals[v]`), for every node up to
    /// the largest needed. Used by trace replay and tests.
    pub fn eval_all(&self, vals: &[bool]) -> Vec<bool> {
        let mut out = vec![false; self.nodes.len()];
        for (i, n) in self.nodes.iter().enumerate() {
            out[i] = match *n {
                Node::False => false,
                Node::Var(v) => vals.get(v as usize).copied().unwrap_or(false),
                Node::And(a, b) => (out[a.node()] ^ a.is_neg()) && (out[b.node()] ^ b.is_neg()),
            };
        }
        out
    }

    /// The value of `l` in a table made by [`Aig::eval_all`].
    #[inline]
    pub fn value(table: &[bool], l: Lit) -> bool {
        table[l.node()] ^ l.is_neg()
    }

    /// The nodes `roots` depend on, in topological order (children first).
    pub fn cone(&self, roots: &[Lit]) -> Vec<usize> {
        let mut seen = vec![false; self.nodes.len()];
        let mut order = Vec::new();
        let mut stack: Vec<(usize, bool)> = roots.iter().map(|l| (l.node(), false)).collect();
        while let Some((n, expanded)) = stack.pop() {
            if expanded {
                order.push(n);
                continue;
            }
            if seen[n] {
                continue;
            }
            seen[n] = true;
            stack.push((n, true));
            if let Node::And(a, b) = self.nodes[n] {
                for c in [a.node(), b.node()] {
                    if !seen[c] {
                        stack.push((c, false));
                    }
                }
            }
        }
        order
    }

    /// The variables `roots` depend on.
    pub fn support(&self, roots: &[Lit]) -> Vec<u32> {
        let mut out: Vec<u32> = self
            .cone(roots)
            .into_iter()
            .filter_map(|n| match self.nodes[n] {
                Node::Var(v) => Some(v),
                _ => None,
            })
            .collect();
        out.sort_unstable();
        out
    }
}

impl Aig {
    /// A copy of the graph with some variables replaced by literals (constants), keeping every
    /// variable's number; returns the new graph and a map from old to new literals.
    pub fn rebuild(&self, subst: &std::collections::HashMap<u32, Lit>) -> (Aig, Vec<Lit>) {
        let mut g = Aig::new();
        for _ in 0..self.vars.len() {
            g.new_var();
        }
        let mut map: Vec<Lit> = vec![Lit::FALSE; self.nodes.len()];
        let tr = |map: &[Lit], l: Lit| -> Lit {
            let m = map[l.node()];
            if l.is_neg() {
                m.not()
            } else {
                m
            }
        };
        for (i, n) in self.nodes.iter().enumerate() {
            map[i] = match *n {
                Node::False => Lit::FALSE,
                Node::Var(v) => subst.get(&v).copied().unwrap_or_else(|| g.var_lit(v)),
                Node::And(a, b) => {
                    let (x, y) = (tr(&map, a), tr(&map, b));
                    g.and(x, y)
                }
            };
        }
        (g, map)
    }

    /// Maps a literal through a table made by [`Aig::rebuild`].
    pub fn map_lit(map: &[Lit], l: Lit) -> Lit {
        let m = map[l.node()];
        if l.is_neg() {
            m.not()
        } else {
            m
        }
    }

    /// Three-valued evaluation (`None` = unknown) of every node given some variable values.
    pub fn eval_ternary(&self, vals: &[Option<bool>]) -> Vec<Option<bool>> {
        let mut out: Vec<Option<bool>> = vec![None; self.nodes.len()];
        for (i, n) in self.nodes.iter().enumerate() {
            out[i] = match *n {
                Node::False => Some(false),
                Node::Var(v) => vals.get(v as usize).copied().flatten(),
                Node::And(a, b) => {
                    let x = out[a.node()].map(|v| v ^ a.is_neg());
                    let y = out[b.node()].map(|v| v ^ b.is_neg());
                    match (x, y) {
                        (Some(false), _) | (_, Some(false)) => Some(false),
                        (Some(true), Some(true)) => Some(true),
                        _ => None,
                    }
                }
            };
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn folding_and_hashing() {
        let mut g = Aig::new();
        let a = g.new_var();
        let b = g.new_var();
        assert_eq!(g.and(a, Lit::TRUE), a);
        assert_eq!(g.and(a, a.not()), Lit::FALSE);
        let x = g.and(a, b);
        assert_eq!(g.and(b, a), x);
        assert_eq!(g.and(a, x), x);
        let y = g.xor(a, b);
        let t = g.eval_all(&[true, false]);
        assert!(!Aig::value(&t, x));
        assert!(Aig::value(&t, y));
    }
}
