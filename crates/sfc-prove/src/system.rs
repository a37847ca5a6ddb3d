//! The transition system the engines check: state bits with their next-state functions and
//! initial values, the free inputs, and the constraint (assumptions) — all literals of one AIG.
//! [`System::cone`] keeps only what a property depends on (cone of influence);
//! [`System::simplify`] folds the state bits that never change.

use crate::aig::{Aig, Lit};
use crate::model::Model;
use std::collections::HashSet;

/// One bit of the state.
#[derive(Debug, Clone, Copy)]
pub struct StateVar {
    /// The current-state literal (a positive AIG variable).
    pub lit: Lit,
    pub next: Lit,
    pub init: bool,
    /// The register and bit it belongs to.
    pub reg: usize,
    pub bit: usize,
}

#[derive(Debug, Clone)]
pub struct System {
    pub g: Aig,
    pub state: Vec<StateVar>,
    /// The constraint every scan's inputs must satisfy (over state and inputs).
    pub constraint: Lit,
}

impl System {
    /// Every state bit of the model, with the extra constraint `constraint`.
    pub fn from_model(m: &Model, constraint: Lit) -> System {
        let mut state = Vec::new();
        for (r, lits) in m.latch.iter().enumerate() {
            let reg = &m.regs[r];
            for (b, &l) in lits.iter().enumerate() {
                if l.as_const().is_some() {
                    continue;
                }
                let init = b < 127 && (reg.init >> b) & 1 == 1;
                state.push(StateVar { lit: l, next: m.next[r][b], init, reg: r, bit: b });
            }
        }
        System { g: m.g.clone(), state, constraint }
    }

    /// The state bits `roots` (and the constraint) depend on, transitively through the
    /// next-state functions.
    pub fn cone(&self, roots: &[Lit]) -> System {
        let var_index: std::collections::HashMap<u32, usize> =
            self.state.iter().enumerate().filter_map(|(i, s)| self.g.var_of(s.lit).map(|v| (v, i))).collect();
        let mut keep: HashSet<usize> = HashSet::new();
        let mut frontier: Vec<Lit> = roots.to_vec();
        frontier.push(self.constraint);
        while !frontier.is_empty() {
            let sup = self.g.support(&frontier);
            frontier.clear();
            for v in sup {
                if let Some(&i) = var_index.get(&v) {
                    if keep.insert(i) {
                        frontier.push(self.state[i].next);
                    }
                }
            }
        }
        let mut idx: Vec<usize> = keep.into_iter().collect();
        idx.sort_unstable();
        System {
            g: self.g.clone(),
            state: idx.into_iter().map(|i| self.state[i]).collect(),
            constraint: self.constraint,
        }
    }

    /// The system with the state bits that never leave their initial value (found by
    /// three-valued simulation from the initial state) replaced by constants, and the map of
    /// this graph's literals into the new one ([`Aig::map_lit`]). Variable numbers are kept,
    /// so traces carry over. Computed once for all properties: a bit the simulation finds
    /// constant is constant whatever the property, and the cone of a property (closed under
    /// dependency) gets the same constants as when simulated alone.
    pub fn simplify(&self) -> (System, Vec<Lit>) {
        let mut vals: Vec<Option<bool>> = vec![None; self.g.num_vars()];
        for s in &self.state {
            if let Some(v) = self.g.var_of(s.lit) {
                vals[v as usize] = Some(s.init);
            }
        }
        loop {
            let t = self.g.eval_ternary(&vals);
            let mut changed = false;
            for s in &self.state {
                let Some(v) = self.g.var_of(s.lit) else { continue };
                if vals[v as usize].is_none() {
                    continue;
                }
                let nv = t[s.next.node()].map(|b| b ^ s.next.is_neg());
                if nv != vals[v as usize] {
                    vals[v as usize] = None;
                    changed = true;
                }
            }
            if !changed {
                break;
            }
        }
        let subst: std::collections::HashMap<u32, Lit> = self
            .state
            .iter()
            .filter_map(|s| {
                let v = self.g.var_of(s.lit)?;
                vals[v as usize].map(|b| (v, Lit::from_bool(b)))
            })
            .collect();
        let (g, map) = self.g.rebuild(&subst);
        let state: Vec<StateVar> = self
            .state
            .iter()
            .filter(|s| self.g.var_of(s.lit).is_some_and(|v| !subst.contains_key(&v)))
            .map(|s| StateVar { lit: Aig::map_lit(&map, s.lit), next: Aig::map_lit(&map, s.next), ..*s })
            .collect();
        let constraint = Aig::map_lit(&map, self.constraint);
        (System { g, state, constraint }, map)
    }

    /// AIG variables of the state bits.
    pub fn state_vars(&self) -> Vec<u32> {
        self.state.iter().filter_map(|s| self.g.var_of(s.lit)).collect()
    }

    /// Evaluates one scan: given the state (AIG var values of the state bits) and the inputs,
    /// the table of every node's value.
    pub fn eval(&self, state: &[bool], inputs: &[(u32, bool)]) -> Vec<bool> {
        let mut vals = vec![false; self.g.num_vars()];
        for (k, s) in self.state.iter().enumerate() {
            if let Some(v) = self.g.var_of(s.lit) {
                vals[v as usize] = state[k];
            }
        }
        for &(v, b) in inputs {
            if (v as usize) < vals.len() {
                vals[v as usize] = b;
            }
        }
        self.g.eval_all(&vals)
    }

    pub fn init_state(&self) -> Vec<bool> {
        self.state.iter().map(|s| s.init).collect()
    }
}
