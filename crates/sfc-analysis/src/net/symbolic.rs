//! Symbolic search over the situations of one network with BDDs (`biodivine-lib-bdd`).
//!
//! One BDD variable per step, ordered depth-first along the transitions from the initial step, so
//! the steps of one sequence (and of one branch) are neighbours; a set of situations is a BDD over
//! them. The image of a set `S` by a scan with consumed steps `D` and activated steps `A` is
//! `∃(A \ D). S|D=1 ∧ [A = 1, D \ A = 0]` (restrict, quantify, conjoin).
//!
//! * **Reachability** by chaining: each sweep applies every transition in variable order to the
//!   growing set and adds the result at once, so a token runs along a whole sequence in one sweep;
//!   sweeps repeat until nothing grows. Group scans (see the module `net`) are added when some
//!   reachable situation enables a strongly connected group, and the sweeps resume.
//! * **Verdicts** from the reachable set `R`: a step is reachable when its variable can be 1 in `R`,
//!   a transition is dead when `R ∧ pre` is empty, a step `s` is unsafe when `R ∧ pre(t) ∧ s` is not
//!   empty for a transition `t` with `s ∈ post(t) \ pre(t)`, lock-ups are `R` without any enabled
//!   transition but with an active step that has one, and the concurrency row of `a` is the set of
//!   variables that can be 1 in `R|a=1` (read off the diagram in one pass).
//! * **Witnesses** only when there are findings. When the network has no more reachable
//!   situations than the explicit budget left, the caller is asked to run the explicit search
//!   instead (same witnesses, cheaper). Otherwise, per finding, breadth-first layers are built
//!   *backwards* from the target (situations at exactly `j` scans from it) until the initial
//!   situation is met, and the path is chosen forwards, taking at each scan the smallest scan label
//!   whose successor lies in the next layer: the lexicographically smallest shortest path, the
//!   same as the explicit search's. Backward layers only constrain the steps the target depends
//!   on; forward layers would count the progress of every concurrent branch (40 loops of 10 steps
//!   give layers of hundreds of thousands of nodes and minutes of work; backwards it takes
//!   milliseconds).
//!
//! Every diagram is kept under a node limit; when one would exceed it, or when group scans are
//! too many to enumerate, the search gives up and the caller falls back to the explicit budget.

use super::{groups_among, Net, Outcome, SearchMethod, MAX_LOCKUPS};
use biodivine_lib_bdd::{op_function, Bdd, BddPartialValuation, BddVariable, BddVariableSet};

struct Sym<'a> {
    net: &'a Net,
    n: usize,
    vars: BddVariableSet,
    /// Local step → variable.
    var: Vec<BddVariable>,
    limit: usize,
    /// Transitions in chaining order.
    order: Vec<u32>,
    pre_cube: Vec<Bdd>,
}

/// A scan: one transition or a group (ascending local transition ids).
type Label = Vec<u32>;

/// A scan with its image and pre-image ingredients.
struct Scan {
    label: Label,
    /// The variables of the consumed and activated steps.
    vars: Vec<BddVariable>,
    /// Consumed steps set to 1.
    restrict: Vec<(BddVariable, bool)>,
    /// Activated steps that were not consumed.
    quantify: Vec<BddVariable>,
    /// Activated steps 1, consumed-only steps 0.
    post_lits: Vec<(BddVariable, bool)>,
    effect: Bdd,
    pre_cube: Bdd,
}

impl<'a> Sym<'a> {
    fn cube(&self, lits: &[(BddVariable, bool)]) -> Bdd {
        self.vars.mk_conjunctive_clause(&BddPartialValuation::from_values(lits))
    }

    fn check(&self, b: Bdd) -> Option<Bdd> {
        (b.size() <= self.limit).then_some(b)
    }
    fn and(&self, a: &Bdd, b: &Bdd) -> Option<Bdd> {
        Bdd::binary_op_with_limit(self.limit, a, b, op_function::and)
    }
    fn or(&self, a: &Bdd, b: &Bdd) -> Option<Bdd> {
        Bdd::binary_op_with_limit(self.limit, a, b, op_function::or)
    }
    fn and_not(&self, a: &Bdd, b: &Bdd) -> Option<Bdd> {
        Bdd::binary_op_with_limit(self.limit, a, b, op_function::and_not)
    }

    /// Consumed and activated steps of a scan.
    fn sets(&self, label: &[u32]) -> (Vec<u32>, Vec<u32>) {
        let mut d: Vec<u32> = label.iter().flat_map(|&t| self.net.pre[t as usize].iter().copied()).collect();
        let mut a: Vec<u32> = label.iter().flat_map(|&t| self.net.post[t as usize].iter().copied()).collect();
        d.sort_unstable();
        d.dedup();
        a.sort_unstable();
        a.dedup();
        (d, a)
    }

    /// Everything the image and pre-image of a scan need, computed once.
    fn scan(&self, label: &[u32]) -> Scan {
        let (d, a) = self.sets(label);
        let restrict: Vec<(BddVariable, bool)> = d.iter().map(|&x| (self.var[x as usize], true)).collect();
        let quantify: Vec<BddVariable> =
            a.iter().filter(|x| d.binary_search(x).is_err()).map(|&x| self.var[x as usize]).collect();
        let mut post_lits: Vec<(BddVariable, bool)> = a.iter().map(|&x| (self.var[x as usize], true)).collect();
        post_lits.extend(d.iter().filter(|x| a.binary_search(x).is_err()).map(|&x| (self.var[x as usize], false)));
        Scan {
            label: label.to_vec(),
            vars: d.iter().chain(a.iter()).map(|&x| self.var[x as usize]).collect(),
            effect: self.cube(&post_lits),
            pre_cube: self.cube(&restrict),
            restrict,
            quantify,
            post_lits,
        }
    }

    fn image(&self, s: &Bdd, sc: &Scan) -> Option<Bdd> {
        let r = s.restrict(&sc.restrict);
        if r.is_false() {
            return Some(r);
        }
        let r = if sc.quantify.is_empty() { r } else { self.check(r.exists(&sc.quantify))? };
        self.and(&r, &sc.effect)
    }

    fn preimage(&self, s: &Bdd, sc: &Scan) -> Option<Bdd> {
        let r = s.restrict(&sc.post_lits);
        if r.is_false() {
            return Some(r);
        }
        self.and(&r, &sc.pre_cube)
    }

    /// Variables (by index) that are 1 in some satisfying valuation of `b`.
    fn true_vars(&self, b: &Bdd) -> Vec<bool> {
        let nv = self.n;
        let mut out = vec![false; nv];
        if b.is_false() {
            return out;
        }
        let level = |p: biodivine_lib_bdd::BddPointer| b.var_of(p).to_index().min(nv);
        let mut diff = vec![0i64; nv + 1];
        let free = |lo: usize, hi: usize, diff: &mut Vec<i64>| {
            if lo < hi {
                diff[lo] += 1;
                diff[hi] -= 1;
            }
        };
        let root = b.root_pointer();
        free(0, level(root), &mut diff);
        let mut seen = vec![false; b.size()];
        let mut stack = vec![root];
        while let Some(p) = stack.pop() {
            if p.is_terminal() || seen[p.to_index()] {
                continue;
            }
            seen[p.to_index()] = true;
            let v = level(p);
            let (lo, hi) = (b.low_link_of(p), b.high_link_of(p));
            if !hi.is_zero() {
                out[v] = true;
                free(v + 1, level(hi), &mut diff);
                stack.push(hi);
            }
            if !lo.is_zero() {
                free(v + 1, level(lo), &mut diff);
                stack.push(lo);
            }
        }
        let mut acc = 0i64;
        for (v, o) in out.iter_mut().enumerate() {
            acc += diff[v];
            if acc > 0 {
                *o = true;
            }
        }
        out
    }

    /// Evaluates `b` on a situation given per local step.
    fn eval(&self, b: &Bdd, x: &[bool]) -> bool {
        let mut val = vec![false; self.n];
        for (s, &on) in x.iter().enumerate() {
            val[self.var[s].to_index()] = on;
        }
        let mut p = b.root_pointer();
        while !p.is_terminal() {
            let v = b.var_of(p).to_index();
            p = if val.get(v).copied().unwrap_or(false) { b.high_link_of(p) } else { b.low_link_of(p) };
        }
        p.is_one()
    }

    fn situation_cube(&self, x: &[bool]) -> Bdd {
        let lits: Vec<(BddVariable, bool)> = x.iter().enumerate().map(|(s, &on)| (self.var[s], on)).collect();
        self.cube(&lits)
    }

    fn enabled_in(&self, x: &[bool], label: &[u32]) -> bool {
        label.iter().all(|&t| self.net.pre[t as usize].iter().all(|&s| x[s as usize]))
    }

    fn fire(&self, x: &[bool], label: &[u32]) -> Vec<bool> {
        let (d, a) = self.sets(label);
        let mut y = x.to_vec();
        for s in d {
            y[s as usize] = false;
        }
        for s in a {
            y[s as usize] = true;
        }
        y
    }

    /// The lexicographically smallest among the shortest paths from the initial situation `x0`
    /// into `target`, and its end: backward breadth-first layers `B_j` (situations at exactly `j`
    /// scans from `target`) until `x0` is met at `B_d`, then forwards, at each scan the smallest
    /// label whose successor lies in the next layer. Every successor of a reachable situation is
    /// reachable, so distances need no restriction to the reachable set, and the layers only
    /// constrain the steps the target depends on: they stay small where forward layers (which
    /// count the progress of every concurrent branch) would not, and scans touching none of
    /// those steps are skipped. `None` when a diagram would exceed the limit.
    fn nearest(&self, x0: &[bool], labels: &[Scan], target: &Bdd) -> Option<(Vec<Label>, Vec<bool>)> {
        let mut layers = vec![target.clone()];
        let mut seen = target.clone();
        while !self.eval(layers.last()?, x0) {
            let last = layers.last()?;
            // A scan touching no variable the layer depends on leads from the layer into itself.
            let support = last.support_set();
            let mut pre = self.vars.mk_false();
            for l in labels {
                if !l.vars.iter().any(|v| support.contains(v)) {
                    continue;
                }
                let p = self.preimage(last, l)?;
                if !p.is_false() {
                    pre = self.or(&pre, &p)?;
                }
            }
            let new = self.and_not(&pre, &seen)?;
            if new.is_false() {
                return None;
            }
            seen = self.or(&seen, &new)?;
            layers.push(new);
        }
        let d = layers.len() - 1;
        let mut x = x0.to_vec();
        let mut path = Vec::with_capacity(d);
        for i in 0..d {
            let goal = &layers[d - 1 - i];
            let step = labels.iter().find_map(|sc| {
                if !self.enabled_in(&x, &sc.label) {
                    return None;
                }
                let y = self.fire(&x, &sc.label);
                self.eval(goal, &y).then_some((sc.label.clone(), y))
            })?;
            path.push(step.0);
            x = step.1;
        }
        Some((path, x))
    }
}

/// What [`run`] concluded.
pub(crate) enum Symbolic {
    Done(Outcome),
    /// There are findings that need witnesses and no more than the given number of reachable
    /// situations: the explicit search is the cheaper way to the same witnesses.
    PreferExplicit,
    /// A diagram would exceed the node limit (or the network has more steps than BDD variables).
    GaveUp,
}

/// Runs the symbolic search. With `explicit_witnesses = Some(k)`, stops before the witness phase
/// when the network has at most `k` reachable situations (see [`Symbolic::PreferExplicit`]).
pub(crate) fn run(net: &Net, limit: usize, explicit_witnesses: Option<usize>) -> Symbolic {
    match search(net, limit, explicit_witnesses) {
        Some(Some(o)) => Symbolic::Done(o),
        Some(None) => Symbolic::PreferExplicit,
        None => Symbolic::GaveUp,
    }
}

fn search(net: &Net, limit: usize, explicit_witnesses: Option<usize>) -> Option<Option<Outcome>> {
    let n = net.steps.len();
    if n == 0 || n >= u16::MAX as usize {
        return None;
    }
    let nt = net.pre.len();
    // Depth-first variable order from the initial steps.
    let mut pos = vec![usize::MAX; n];
    let mut seq = Vec::with_capacity(n);
    let starts: Vec<u32> = net.initial.iter().copied().chain(0..n as u32).collect();
    for &s0 in &starts {
        let mut stack = vec![s0];
        while let Some(s) = stack.pop() {
            if pos[s as usize] != usize::MAX {
                continue;
            }
            pos[s as usize] = seq.len();
            seq.push(s);
            for &t in net.out[s as usize].iter().rev() {
                for &p in net.post[t as usize].iter().rev() {
                    if pos[p as usize] == usize::MAX {
                        stack.push(p);
                    }
                }
            }
        }
    }
    let vars = BddVariableSet::new_anonymous(n as u16);
    let var: Vec<BddVariable> = (0..n).map(|s| BddVariable::from_index(pos[s])).collect();
    let mut order: Vec<u32> = (0..nt as u32).collect();
    order.sort_by_key(|&t| (net.pre[t as usize].iter().map(|&s| pos[s as usize]).min().unwrap_or(usize::MAX), t));
    let mut sym = Sym { net, n, vars, var, limit: limit.max(16), order, pre_cube: Vec::new() };
    sym.pre_cube = (0..nt)
        .map(|t| {
            let lits: Vec<(BddVariable, bool)> = net.pre[t].iter().map(|&s| (sym.var[s as usize], true)).collect();
            sym.cube(&lits)
        })
        .collect();
    let mut init_x = vec![false; n];
    for &s in &net.initial {
        init_x[s as usize] = true;
    }
    let init = sym.situation_cube(&init_x);

    // Reachability by chaining, with group scans as they appear.
    let mut r = init.clone();
    let mut groups: Vec<Label> = Vec::new();
    let singles: Vec<Scan> = (0..nt as u32).map(|t| sym.scan(&[t])).collect();
    loop {
        let group_scans: Vec<Scan> = groups.iter().map(|g| sym.scan(g)).collect();
        let mut grew = true;
        while grew {
            grew = false;
            let labels = sym.order.iter().map(|&t| &singles[t as usize]).chain(group_scans.iter());
            for l in labels {
                let img = sym.image(&r, l)?;
                let new = sym.and_not(&img, &r)?;
                if !new.is_false() {
                    r = sym.or(&r, &new)?;
                    grew = true;
                }
            }
        }
        let mut capable = Vec::new();
        for t in 0..nt {
            let restrict: Vec<(BddVariable, bool)> = net.pre[t].iter().map(|&s| (sym.var[s as usize], true)).collect();
            let rt = r.restrict(&restrict);
            if rt.is_false() {
                continue;
            }
            let tv = sym.true_vars(&rt);
            if net.post[t].iter().any(|s| net.pre[t].binary_search(s).is_err() && tv[sym.var[*s as usize].to_index()]) {
                capable.push(t as u32);
            }
        }
        let mut found: Vec<Label> = Vec::new();
        for g in groups_among(net, &capable)? {
            let (d, _) = sym.sets(&g);
            let restrict: Vec<(BddVariable, bool)> = d.iter().map(|&s| (sym.var[s as usize], true)).collect();
            if !r.restrict(&restrict).is_false() {
                found.push(g);
            }
        }
        if found == groups {
            break;
        }
        groups = found;
    }

    // Verdicts.
    let reach_var = sym.true_vars(&r);
    let reachable: Vec<bool> = (0..n).map(|s| reach_var[sym.var[s].to_index()]).collect();
    let mut enabled = vec![false; nt];
    let mut unsafe_by: Vec<Vec<u32>> = vec![Vec::new(); n];
    for (t, en) in enabled.iter_mut().enumerate() {
        let restrict: Vec<(BddVariable, bool)> = net.pre[t].iter().map(|&s| (sym.var[s as usize], true)).collect();
        let rt = r.restrict(&restrict);
        if rt.is_false() {
            continue;
        }
        *en = true;
        let tv = sym.true_vars(&rt);
        for &s in &net.post[t] {
            if net.pre[t].binary_search(&s).is_err() && tv[sym.var[s as usize].to_index()] {
                unsafe_by[s as usize].push(t as u32);
            }
        }
    }
    let mut any_enabled = sym.vars.mk_false();
    for c in &sym.pre_cube {
        any_enabled = sym.or(&any_enabled, c)?;
    }
    let mut has_out = sym.vars.mk_false();
    for s in 0..n {
        if !net.out[s].is_empty() {
            has_out = sym.or(&has_out, &sym.vars.mk_var(sym.var[s]))?;
        }
    }
    let locked = sym.and(&sym.and_not(&r, &any_enabled)?, &has_out)?;

    let w = n.div_ceil(64).max(1);
    let mut reach_bits = vec![0u64; w];
    let mut rows = vec![0u64; n * w];
    for a in 0..n {
        if !reachable[a] {
            continue;
        }
        super::set_bit(&mut reach_bits, a);
        let ra = r.var_restrict(sym.var[a], true);
        let mut tv = sym.true_vars(&ra);
        tv[sym.var[a].to_index()] = true;
        for b in 0..n {
            if tv[sym.var[b].to_index()] {
                super::set_bit(&mut rows[a * w..(a + 1) * w], b);
            }
        }
    }

    // Witnesses, by breadth-first layers, only for the findings.
    let mut unsafe_steps: Vec<(u32, Vec<Label>, u32)> = Vec::new();
    let mut lockups: Vec<(Vec<u32>, Vec<Label>)> = Vec::new();
    let pending: Vec<u32> = (0..n as u32).filter(|&s| !unsafe_by[s as usize].is_empty()).collect();
    let mut lock_left = if locked.is_false() { 0 } else { MAX_LOCKUPS };
    let count = r.cardinality();
    if (!pending.is_empty() || lock_left > 0) && explicit_witnesses.is_some_and(|k| count <= k as f64) {
        return Some(None);
    }
    if !pending.is_empty() || lock_left > 0 {
        let mut labels: Vec<Scan> = singles.into_iter().chain(groups.iter().map(|g| sym.scan(g))).collect();
        labels.sort_by(|a, b| a.label.cmp(&b.label));
        // Per pending step: the situations from which some transition activates it while active.
        let mut cap: Vec<Bdd> = Vec::new();
        for &s in &pending {
            let mut c = sym.vars.mk_false();
            for &t in &unsafe_by[s as usize] {
                c = sym.or(&c, &sym.and(&sym.pre_cube[t as usize], &sym.vars.mk_var(sym.var[s as usize]))?)?;
            }
            cap.push(c);
        }
        for (i, &s) in pending.iter().enumerate() {
            let (path, x) = sym.nearest(&init_x, &labels, &cap[i])?;
            let t =
                *unsafe_by[s as usize].iter().filter(|&&t| sym.enabled_in(&x, &[t])).min().filter(|_| x[s as usize])?;
            unsafe_steps.push((s, path, t));
        }
        // Situations without an enabled transition but with an active step that has one; the
        // nearest of them are reachable (the reachable set need not be part of the target).
        let mut left = sym.and_not(&has_out, &any_enabled)?;
        let mut left_reachable = locked.clone();
        while lock_left > 0 && !left_reachable.is_false() {
            let (path, x) = sym.nearest(&init_x, &labels, &left)?;
            let found = sym.situation_cube(&x);
            left = sym.and_not(&left, &found)?;
            left_reachable = sym.and_not(&left_reachable, &found)?;
            lockups.push(((0..n as u32).filter(|&s| x[s as usize]).collect(), path));
            lock_left -= 1;
        }
        unsafe_steps.sort_by_key(|u| u.0);
    }
    Some(Some(Outcome {
        complete: true,
        method: SearchMethod::Symbolic(count),
        reachable,
        enabled,
        unsafe_steps,
        lockups,
        conc: Some((w, reach_bits, rows)),
    }))
}
