//! The structural certificate: proves a network safe, live (every step reachable, no dead
//! transition) and free of lock-ups by reducing its block structure, without any search.
//!
//! # Macro-steps
//! The reduction works on a net of *macro-steps* (sets of original steps) and transitions between
//! them. A macro-step `M` has an *entry* (the steps a transition entering `M` activates) and, unless
//! it is *closed* (no transition leaves it), an *exit* (the steps a transition leaving `M` consumes);
//! every transition entering `M` activates exactly its entry and every transition leaving it
//! consumes exactly its exit, and no other transition touches its steps (it is private). Started
//! alone in its entry, with free guards, `M` satisfies:
//!
//! * **P1** no firing inside is unsafe;
//! * **P2** every step of `M` is active in some reachable situation and every transition inside is
//!   enabled in one;
//! * **P3** (not closed) from every reachable situation of `M` its exit situation is reachable;
//! * **P4** every reachable situation of `M` other than the exit has an enabled transition inside,
//!   and a situation of a closed `M` without one has no active step with an outgoing transition.
//!
//! A single step is such a macro-step. **Replacing** a macro-step by one step preserves everything
//! the analysis reports: if the reduced net is safe, `M` is never entered while active, so inside
//! it runs exactly as alone (P1); its internal moves touch nothing outside, so every reachable
//! situation of the reduced net with `M` active stands for all combinations with the situations of
//! `M` (P2), and the transitions leaving `M` become enabled exactly when its exit is reached, which
//! is always possible (P3); a situation without an enabled transition has every macro-step in its
//! exit (P4), so lock-ups correspond; two steps of `M` are together iff they are inside `M`, and a
//! step of `M` is together with an outside step iff `M` is.
//!
//! # Rules (each builds a macro-step satisfying P1–P4 from macro-steps satisfying them)
//! * **Sequence region** (sequences, selection divergences and convergences, loops and jumps of any
//!   shape): a connected set of macro-steps linked by transitions with one step before and one
//!   after, entered from outside (or initially active) at exactly one macro-step `e` and left
//!   towards the outside from at most one macro-step `x`, where every member is reachable from `e`
//!   and, when `x` exists, reaches `x`. One token moves inside, so it is safe (left and re-entered
//!   is not unsafe); P2–P4 follow from the reachability conditions. A single macro-step with loops
//!   on itself is the smallest case.
//! * **Simultaneous block**: macro-steps `B1..Bn` (`n ≥ 2`, none initial) all entered only by one
//!   transition `t` and all left only by one transition `u` (which may also touch other steps):
//!   the branches run independently, so the situations are the products of theirs (P1, P2), each
//!   reaches its exit (P3, so `u` is enabled), and a product with a branch before its exit has an
//!   enabled transition (P4). Concurrency: steps of different branches are together.
//! * **Open simultaneous block**: closed macro-steps `B1..Bn` (`n ≥ 2`) entered only by `t` and
//!   never left (each branch loops forever or ends in a final step).
//!
//! The network is certified when it reduces to one initially active macro-step with no transition
//! left. Anything else (a selection branch jumping out of a simultaneous branch, a branch that never
//! reaches its convergence, a transition activating nothing, two initial steps…) is left to the
//! search, which is always exact.

use super::Net;

/// Kind of a node of the block tree.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Kind {
    Leaf,
    /// Sequence region: its children are never active together.
    Excl,
    /// Simultaneous block: its children are pairwise together.
    Par,
}

/// The block tree of a certified network: two different steps are together iff their lowest
/// common ancestor is a simultaneous block.
#[derive(Debug, Clone)]
pub(crate) struct Tree {
    leaf: Vec<u32>,
    parent: Vec<u32>,
    depth: Vec<u32>,
    kind: Vec<Kind>,
}

const NONE: u32 = u32::MAX;

impl Tree {
    /// Whether local steps `a != b` lie in different branches of a common simultaneous block.
    pub(crate) fn parallel(&self, a: u32, b: u32) -> bool {
        let (Some(&x), Some(&y)) = (self.leaf.get(a as usize), self.leaf.get(b as usize)) else {
            return false;
        };
        let (mut x, mut y) = (x as usize, y as usize);
        while self.depth[x] > self.depth[y] {
            x = self.parent[x] as usize;
        }
        while self.depth[y] > self.depth[x] {
            y = self.parent[y] as usize;
        }
        while x != y {
            let (px, py) = (self.parent[x], self.parent[y]);
            if px == NONE || py == NONE {
                return false;
            }
            if px == py {
                return self.kind[px as usize] == Kind::Par;
            }
            x = px as usize;
            y = py as usize;
        }
        false
    }
}

struct Builder {
    kind: Vec<Kind>,
    parent: Vec<u32>,
    children: Vec<Vec<u32>>,
}

impl Builder {
    fn node(&mut self, kind: Kind) -> u32 {
        self.kind.push(kind);
        self.parent.push(NONE);
        self.children.push(Vec::new());
        (self.kind.len() - 1) as u32
    }
    /// A block of `kind` over `kids`; a child block of the same kind is flattened into it.
    fn combine(&mut self, kind: Kind, kids: &[u32]) -> u32 {
        let id = self.node(kind);
        let mut all = Vec::new();
        for &k in kids {
            if self.kind[k as usize] == kind {
                all.append(&mut self.children[k as usize]);
            } else {
                all.push(k);
            }
        }
        for &c in &all {
            self.parent[c as usize] = id;
        }
        self.children[id as usize] = all;
        id
    }
}

/// The reduction state.
struct Reduction {
    tree: Vec<u32>,
    initial: Vec<bool>,
    alive: Vec<bool>,
    pre: Vec<Vec<u32>>,
    post: Vec<Vec<u32>>,
    talive: Vec<bool>,
    b: Builder,
}

impl Reduction {
    fn new_node(&mut self, tree: u32, initial: bool) -> u32 {
        self.tree.push(tree);
        self.initial.push(initial);
        self.alive.push(true);
        (self.tree.len() - 1) as u32
    }

    /// Incoming and outgoing live transitions of every node.
    fn adjacency(&self) -> (Vec<Vec<u32>>, Vec<Vec<u32>>) {
        let n = self.tree.len();
        let (mut inc, mut out) = (vec![Vec::new(); n], vec![Vec::new(); n]);
        for t in 0..self.pre.len() {
            if !self.talive[t] {
                continue;
            }
            for &m in &self.pre[t] {
                out[m as usize].push(t as u32);
            }
            for &m in &self.post[t] {
                inc[m as usize].push(t as u32);
            }
        }
        (inc, out)
    }

    fn internal(&self, t: usize) -> bool {
        self.talive[t] && self.pre[t].len() == 1 && self.post[t].len() == 1
    }

    /// Collapses every sequence region that satisfies the conditions; true when anything changed.
    fn regions(&mut self) -> bool {
        let n = self.tree.len();
        let (inc, out) = self.adjacency();
        let mut uf: Vec<u32> = (0..n as u32).collect();
        fn find(p: &mut [u32], mut x: u32) -> u32 {
            while p[x as usize] != x {
                p[x as usize] = p[p[x as usize] as usize];
                x = p[x as usize];
            }
            x
        }
        let mut fwd: Vec<Vec<u32>> = vec![Vec::new(); n];
        let mut bwd: Vec<Vec<u32>> = vec![Vec::new(); n];
        let mut has_edge = vec![false; n];
        for t in 0..self.pre.len() {
            if !self.internal(t) {
                continue;
            }
            let (a, b) = (self.pre[t][0], self.post[t][0]);
            fwd[a as usize].push(b);
            bwd[b as usize].push(a);
            let (ra, rb) = (find(&mut uf, a), find(&mut uf, b));
            if ra != rb {
                uf[ra.max(rb) as usize] = ra.min(rb);
            }
        }
        let mut comps: Vec<Vec<u32>> = Vec::new();
        let mut comp_of = vec![NONE; n];
        for m in 0..n as u32 {
            if !self.alive[m as usize] {
                continue;
            }
            let r = find(&mut uf, m) as usize;
            if comp_of[r] == NONE {
                comp_of[r] = comps.len() as u32;
                comps.push(Vec::new());
            }
            comps[comp_of[r] as usize].push(m);
        }
        for t in 0..self.pre.len() {
            if self.internal(t) {
                let r = find(&mut uf, self.pre[t][0]) as usize;
                has_edge[comp_of[r] as usize] = true;
            }
        }
        let int: Vec<bool> = (0..self.pre.len()).map(|t| self.internal(t)).collect();
        let is_int = |t: u32| int[t as usize];
        let mut changed = false;
        let mut repl = vec![NONE; n];
        let mut mark = vec![0u32; n];
        let mut stamp = 0u32;
        for (ci, comp) in comps.iter().enumerate() {
            if comp.len() == 1 && !has_edge[ci] {
                continue;
            }
            let entries: Vec<u32> = comp
                .iter()
                .copied()
                .filter(|&m| self.initial[m as usize] || inc[m as usize].iter().any(|&t| !is_int(t)))
                .collect();
            let exits: Vec<u32> =
                comp.iter().copied().filter(|&m| out[m as usize].iter().any(|&t| !is_int(t))).collect();
            if entries.len() != 1 || exits.len() > 1 {
                continue;
            }
            let e = entries[0];
            // Every member reachable from the entry, and (with an exit) every member reaching it.
            let mut covers = |start: u32, adj: &[Vec<u32>]| {
                stamp += 1;
                mark[start as usize] = stamp;
                let mut stack = vec![start];
                let mut count = 1;
                while let Some(a) = stack.pop() {
                    for &b in &adj[a as usize] {
                        if mark[b as usize] != stamp {
                            mark[b as usize] = stamp;
                            count += 1;
                            stack.push(b);
                        }
                    }
                }
                count == comp.len()
            };
            if !covers(e, &fwd) {
                continue;
            }
            if let Some(&x) = exits.first() {
                if !covers(x, &bwd) {
                    continue;
                }
            }
            changed = true;
            for &m in comp {
                for &t in &out[m as usize] {
                    if is_int(t) {
                        self.talive[t as usize] = false;
                    }
                }
            }
            if comp.len() > 1 {
                let kids: Vec<u32> = comp.iter().map(|&m| self.tree[m as usize]).collect();
                let tree = self.b.combine(Kind::Excl, &kids);
                let init = self.initial[e as usize];
                let new = self.new_node(tree, init);
                for &m in comp {
                    self.alive[m as usize] = false;
                    repl[m as usize] = new;
                }
            }
        }
        if changed {
            for t in 0..self.pre.len() {
                if !self.talive[t] {
                    continue;
                }
                for v in [&mut self.pre[t], &mut self.post[t]] {
                    let mut touched = false;
                    for m in v.iter_mut() {
                        if let Some(&r) = repl.get(*m as usize) {
                            if r != NONE {
                                *m = r;
                                touched = true;
                            }
                        }
                    }
                    if touched {
                        v.sort_unstable();
                        v.dedup();
                    }
                }
            }
        }
        changed
    }

    /// Collapses every simultaneous block (closed or converging) whose branches are single
    /// macro-steps; true when anything changed.
    fn blocks(&mut self) -> bool {
        let (inc, out) = self.adjacency();
        let mut ops: Vec<(u32, Option<u32>, Vec<u32>)> = Vec::new();
        for t in 0..self.pre.len() {
            if !self.talive[t] || self.post[t].len() < 2 {
                continue;
            }
            let mut cands: Vec<(Option<u32>, u32)> = Vec::new();
            for &b in &self.post[t] {
                let bi = b as usize;
                if self.initial[bi] || inc[bi].len() != 1 || inc[bi][0] != t as u32 {
                    continue;
                }
                match out[bi].len() {
                    0 => cands.push((None, b)),
                    1 => cands.push((Some(out[bi][0]), b)),
                    _ => {}
                }
            }
            cands.sort_unstable();
            let mut i = 0;
            while i < cands.len() {
                let mut j = i;
                while j < cands.len() && cands[j].0 == cands[i].0 {
                    j += 1;
                }
                if j - i >= 2 {
                    ops.push((t as u32, cands[i].0, cands[i..j].iter().map(|c| c.1).collect()));
                }
                i = j;
            }
        }
        let changed = !ops.is_empty();
        for (t, u, members) in ops {
            let kids: Vec<u32> = members.iter().map(|&m| self.tree[m as usize]).collect();
            let tree = self.b.combine(Kind::Par, &kids);
            let v = self.new_node(tree, false);
            for &m in &members {
                self.alive[m as usize] = false;
            }
            let swap = |list: &mut Vec<u32>| {
                list.retain(|m| !members.contains(m));
                list.push(v);
                list.sort_unstable();
            };
            swap(&mut self.post[t as usize]);
            if let Some(u) = u {
                swap(&mut self.pre[u as usize]);
            }
        }
        changed
    }
}

/// Tries to certify `net`; returns its block tree on success.
pub(crate) fn certify(net: &Net) -> Option<Tree> {
    if net.initial.len() != 1 {
        return None;
    }
    let n = net.steps.len();
    let mut b = Builder { kind: Vec::new(), parent: Vec::new(), children: Vec::new() };
    let leaves: Vec<u32> = (0..n).map(|_| b.node(Kind::Leaf)).collect();
    let mut initial = vec![false; n];
    for &s in &net.initial {
        initial[s as usize] = true;
    }
    let mut r = Reduction {
        tree: leaves.clone(),
        initial,
        alive: vec![true; n],
        pre: net.pre.clone(),
        post: net.post.clone(),
        talive: vec![true; net.pre.len()],
        b,
    };
    loop {
        let a = r.regions();
        let c = r.blocks();
        if !a && !c {
            break;
        }
    }
    if r.talive.iter().any(|&t| t) {
        return None;
    }
    let alive: Vec<usize> = (0..r.alive.len()).filter(|&m| r.alive[m]).collect();
    if alive.len() != 1 || !r.initial[alive[0]] {
        return None;
    }
    let root = r.tree[alive[0]];
    let Builder { kind, parent, children } = r.b;
    let mut depth = vec![0u32; kind.len()];
    let mut stack = vec![root];
    while let Some(m) = stack.pop() {
        for &c in &children[m as usize] {
            depth[c as usize] = depth[m as usize] + 1;
            stack.push(c);
        }
    }
    let mut parent = parent;
    parent[root as usize] = NONE;
    Some(Tree { leaf: leaves, parent, depth, kind })
}
