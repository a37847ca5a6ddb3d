//! Recovery of the block structure of a chart from its net.
//!
//! The net is a bipartite graph: steps lead to the transitions they enable, transitions to the
//! steps they activate. A *well-nested* chart is a tree of sequences: a sequence alternates steps
//! and transitions; after a step it may open a selection (several transitions, one per branch)
//! that closes again at one step; after a transition it may open a simultaneous divergence
//! (several steps, one per branch) that closes again at one transition whose predecessors are the
//! last steps of those branches. A link to a step that is drawn elsewhere (a loop back, or a
//! link across to another branch) becomes a *jump*.
//!
//! Convergences are found with post-dominators of the net without its back edges (the back
//! edges of a depth-first search from the initial steps, which become jumps):
//!
//! * a selection converges at the nearest node that all paths from its branches pass through,
//!   counting only the branches that meet another branch at all (a branch that loops back on
//!   its own does not keep the others from converging), and a transition that only jumps does
//!   not hide the convergence of an enclosing construct ([`PostDominators::convergence`]);
//! * simultaneous branches join at the nearest node that all their paths pass through, counting
//!   only paths that can still reach a node two branches share ([`PostDominators::join`]):
//!   loops, jumps out and dead ends inside a branch do not hide the join.
//!
//! The parser then checks what it finds: a simultaneous convergence must join exactly the last
//! steps of the branches that reach it, and no selection branch may run into a simultaneous
//! convergence (nor several alternatives into one). When that fails the chart is not well
//! nested: [`recover`] gives up and the layered layout draws it.
//!
//! A selection without a convergence whose branches all end at once but one lets that one
//! carry the sequence on below it (`Parser::main_branch`), so long chains of steps with
//! loop-back branches are not nested ever deeper.

use sfc_model::{Chart, StepId, TransitionId};

/// Deeper nesting of branches than this is drawn by the layered layout (the structured layout
/// recurses once per nesting level).
const MAX_NESTING: usize = 64;
/// Nesting depth from which selections without convergence carry the sequence on below them
/// (see `Parser::main_branch`).
const HOIST_DEPTH: usize = 24;

/// One element of a sequence.
#[derive(Debug, Clone, PartialEq)]
pub enum Elem {
    Step(StepId),
    Transition(TransitionId),
    /// The end of a sequence after `transition`: an arrow to `target`, which is drawn elsewhere.
    Jump {
        transition: TransitionId,
        target: StepId,
    },
    /// A selection divergence after a step: each branch starts with a transition. With
    /// `merges`, the branches that reach the convergence meet on a convergence line and the
    /// sequence goes on below it (with the convergence step, unless an enclosing construct
    /// places that step).
    Selection {
        branches: Vec<Branch>,
        merges: bool,
    },
    /// A simultaneous divergence after a transition: each branch starts with a step. With
    /// `merges`, the next element is the convergence transition.
    Simultaneous {
        branches: Vec<Branch>,
        merges: bool,
    },
}

/// One branch of a divergence.
#[derive(Debug, Clone, PartialEq)]
pub struct Branch {
    pub seq: Vec<Elem>,
    /// The branch ends at the convergence (rather than with a jump or a dead end).
    pub reaches: bool,
}

/// The recovered structure: one top-level sequence per root (initial steps first).
#[derive(Debug, Clone, PartialEq)]
pub struct Tree {
    pub roots: Vec<Vec<Elem>>,
}

/// Recovers the block structure, or `None` when the chart is not well nested.
pub fn recover(chart: &Chart) -> Option<Tree> {
    let net = Net::new(chart);
    let pdom = net.post_dominators();
    let mut parser = Parser {
        chart,
        net: &net,
        pdom,
        placed_step: vec![false; net.ns],
        placed_transition: vec![false; net.nt],
        stops: Vec::new(),
    };
    let mut roots = Vec::new();
    for s in net.root_order() {
        if parser.placed_step[s] {
            continue;
        }
        parser.placed_step[s] = true;
        let mut seq = vec![Elem::Step(s)];
        parser.sequence(&mut seq, Cursor::Step(s), 0).ok()?;
        roots.push(seq);
    }
    for t in 0..net.nt {
        if parser.placed_transition[t] {
            continue;
        }
        // A transition with predecessors is placed below them; only one without any (an
        // erroneous chart) starts a sequence of its own.
        if !chart.transitions[t].from.is_empty() {
            return None;
        }
        parser.placed_transition[t] = true;
        let mut seq = vec![Elem::Transition(t)];
        parser.sequence(&mut seq, Cursor::Transition(t), 0).ok()?;
        roots.push(seq);
    }
    let tree = Tree { roots };
    tree.draws_each_once(net.ns, net.nt).then_some(tree)
}

impl Tree {
    /// Whether every step and transition appears exactly once (a safety net: the parser only
    /// places what is not placed yet).
    fn draws_each_once(&self, ns: usize, nt: usize) -> bool {
        let mut steps = vec![0u32; ns];
        let mut transitions = vec![0u32; nt];
        let mut stack: Vec<&[Elem]> = self.roots.iter().map(|r| r.as_slice()).collect();
        while let Some(seq) = stack.pop() {
            for e in seq {
                match e {
                    Elem::Step(s) => steps[*s] += 1,
                    Elem::Transition(t) => transitions[*t] += 1,
                    Elem::Jump { .. } => {}
                    Elem::Selection { branches, .. } | Elem::Simultaneous { branches, .. } => {
                        stack.extend(branches.iter().map(|b| b.seq.as_slice()));
                    }
                }
            }
        }
        steps.iter().chain(&transitions).all(|&c| c == 1)
    }
}

/// The net as a graph: node `s` is step `s`, node `ns + t` is transition `t`.
pub struct Net {
    pub ns: usize,
    pub nt: usize,
    /// Successors of every node, in declaration order, without duplicates.
    pub succ: Vec<Vec<usize>>,
    /// Outgoing transitions of every step.
    pub outgoing: Vec<Vec<TransitionId>>,
    pub initial: Vec<bool>,
    pub has_incoming: Vec<bool>,
}

impl Net {
    pub fn new(chart: &Chart) -> Net {
        let ns = chart.steps.len();
        let nt = chart.transitions.len();
        let mut succ = vec![Vec::new(); ns + nt];
        let mut outgoing = vec![Vec::new(); ns];
        let mut has_incoming = vec![false; ns];
        for (t, tr) in chart.transitions.iter().enumerate() {
            for &s in &tr.from {
                if s < ns && !outgoing[s].contains(&t) {
                    outgoing[s].push(t);
                    succ[s].push(ns + t);
                }
            }
            for &d in &tr.to {
                if d < ns && !succ[ns + t].contains(&d) {
                    succ[ns + t].push(d);
                    has_incoming[d] = true;
                }
            }
        }
        let initial = chart.steps.iter().map(|s| s.initial).collect();
        Net { ns, nt, succ, outgoing, initial, has_incoming }
    }

    /// Steps in the order they start sequences: initial steps, then steps nothing leads to, then
    /// the rest, each group in declaration order.
    pub fn root_order(&self) -> Vec<StepId> {
        let mut order: Vec<StepId> = (0..self.ns).filter(|&s| self.initial[s]).collect();
        order.extend((0..self.ns).filter(|&s| !self.initial[s] && !self.has_incoming[s]));
        order.extend((0..self.ns).filter(|&s| !self.initial[s] && self.has_incoming[s]));
        order
    }

    /// Depth-first search from the roots (then from any node not yet reached): the discovery
    /// index of every node and, for every node, which of its successor links are back edges.
    pub fn dfs(&self) -> (Vec<usize>, Vec<Vec<bool>>) {
        let n = self.ns + self.nt;
        let mut disc = vec![usize::MAX; n];
        let mut on_stack = vec![false; n];
        let mut back: Vec<Vec<bool>> = self.succ.iter().map(|s| vec![false; s.len()]).collect();
        let mut next = 0;
        let starts = self.root_order().into_iter().chain(self.ns..n);
        for start in starts {
            if disc[start] != usize::MAX {
                continue;
            }
            disc[start] = next;
            next += 1;
            on_stack[start] = true;
            let mut stack: Vec<(usize, usize)> = vec![(start, 0)];
            while let Some(top) = stack.last_mut() {
                let (v, i) = *top;
                if i < self.succ[v].len() {
                    top.1 += 1;
                    let w = self.succ[v][i];
                    if disc[w] == usize::MAX {
                        disc[w] = next;
                        next += 1;
                        on_stack[w] = true;
                        stack.push((w, 0));
                    } else if on_stack[w] {
                        back[v][i] = true;
                    }
                } else {
                    on_stack[v] = false;
                    stack.pop();
                }
            }
        }
        (disc, back)
    }

    /// The post-dominator tree of the net without its back edges (see [`PostDominators`]).
    /// Cooper, Harvey and Kennedy's intersection, done in one pass because the graph is acyclic:
    /// every node after all its successors.
    pub fn post_dominators(&self) -> PostDominators {
        let n = self.ns + self.nt;
        let exit = n;
        let (_, back) = self.dfs();
        let fwd: Vec<Vec<usize>> =
            (0..n).map(|v| self.succ[v].iter().zip(&back[v]).filter(|(_, &b)| !b).map(|(&w, _)| w).collect()).collect();
        // Topological order (Kahn), then nodes in reverse.
        let mut indeg = vec![0usize; n];
        for f in &fwd {
            for &w in f {
                indeg[w] += 1;
            }
        }
        let mut order: Vec<usize> = (0..n).filter(|&v| indeg[v] == 0).collect();
        let mut i = 0;
        while i < order.len() {
            let v = order[i];
            i += 1;
            for &w in &fwd[v] {
                indeg[w] -= 1;
                if indeg[w] == 0 {
                    order.push(w);
                }
            }
        }
        let mut topo = vec![0usize; n];
        for (p, &v) in order.iter().enumerate() {
            topo[v] = p;
        }
        let mut idom = vec![exit; n + 1];
        let mut depth = vec![1usize; n + 1];
        depth[exit] = 0;
        for &v in order.iter().rev() {
            if fwd[v].is_empty() && !self.succ[v].is_empty() {
                idom[v] = LOOPS;
                continue;
            }
            let mut new = LOOPS;
            for &w in &fwd[v] {
                if idom[w] == LOOPS {
                    continue;
                }
                new = if new == LOOPS { w } else { intersect(&idom, &depth, new, w) };
            }
            if new == LOOPS {
                new = exit;
            }
            idom[v] = new;
            depth[v] = depth[new] + 1;
        }
        PostDominators { idom, depth, exit, fwd, topo }
    }
}

/// Marks a node all of whose links go back up at once (a jump).
const LOOPS: usize = usize::MAX;

/// The post-dominator tree of the net without its back edges. Nodes without successors there
/// lead to a virtual exit node `ns + nt`, except that a link straight back up (a transition
/// that only jumps) does not count: a step with one branch going on and one looping back at
/// once is post-dominated by the branch going on, so the loop of a branch inside a larger
/// construct does not hide where that construct converges.
pub struct PostDominators {
    idom: Vec<usize>,
    depth: Vec<usize>,
    exit: usize,
    /// Successors without back edges, and the topological position of every node.
    fwd: Vec<Vec<usize>>,
    topo: Vec<usize>,
}

impl PostDominators {
    /// The convergence of a selection whose branches start at `starts`: the nearest node that
    /// every path from the branches that meet at all passes through. Branches that meet no
    /// other branch (they end with jumps of their own) do not count, so a selection with a
    /// branch that loops back still converges where its other branches meet. `None` when fewer
    /// than two branches meet.
    pub fn convergence(&self, starts: &[usize]) -> Option<usize> {
        let mut meets = vec![false; starts.len()];
        for i in 0..starts.len() {
            for j in i + 1..starts.len() {
                let (a, b) = (starts[i], starts[j]);
                if self.idom[a] != LOOPS
                    && self.idom[b] != LOOPS
                    && intersect(&self.idom, &self.depth, a, b) != self.exit
                {
                    meets[i] = true;
                    meets[j] = true;
                }
            }
        }
        let mut members = starts.iter().zip(&meets).filter(|(_, &m)| m).map(|(&s, _)| s);
        let first = members.next()?;
        let c = members.fold(first, |c, s| intersect(&self.idom, &self.depth, c, s));
        (c != self.exit && !starts.contains(&c)).then_some(c)
    }

    /// The join of simultaneous branches starting at `starts`: the nearest node every path
    /// from the branches passes through, where only paths that can still reach a node shared by
    /// two branches count. Whatever a branch does on its own (loops, jumps out, dead ends) does
    /// not hide the join, which simultaneous branches must have to be drawn as a block. This
    /// looks at the part of the net below the divergence, once per simultaneous divergence.
    pub fn join(&self, starts: &[usize]) -> Option<usize> {
        let n = self.fwd.len();
        let mut count = vec![0u8; n];
        let mut seen = vec![usize::MAX; n];
        let mut region = Vec::new();
        for (i, &s) in starts.iter().enumerate() {
            let mut stack = vec![s];
            while let Some(v) = stack.pop() {
                if v >= n || seen[v] == i {
                    continue;
                }
                seen[v] = i;
                if count[v] == 0 {
                    region.push(v);
                }
                count[v] = count[v].saturating_add(1);
                stack.extend(self.fwd[v].iter().copied());
            }
        }
        region.sort_by_key(|&v| std::cmp::Reverse(self.topo[v]));
        // Nodes that can still reach a shared node, and their post-dominators among themselves.
        let mut live = vec![false; n];
        let exit = n;
        let mut idom = vec![exit; n + 1];
        let mut depth = vec![1usize; n + 1];
        depth[exit] = 0;
        for &v in &region {
            live[v] = count[v] >= 2 || self.fwd[v].iter().any(|&w| live[w]);
            if !live[v] {
                continue;
            }
            let mut new = LOOPS;
            for &w in self.fwd[v].iter().filter(|&&w| live[w]) {
                new = if new == LOOPS { w } else { intersect(&idom, &depth, new, w) };
            }
            if new == LOOPS {
                new = exit;
            }
            idom[v] = new;
            depth[v] = depth[new] + 1;
        }
        let mut members = starts.iter().copied().filter(|&s| s < n && live[s]);
        let first = members.next()?;
        let mut c = first;
        let mut count_members = 1;
        for s in members {
            c = intersect(&idom, &depth, c, s);
            count_members += 1;
        }
        (count_members > 1 && c != exit && !starts.contains(&c)).then_some(c)
    }
}

/// The nearest common ancestor of `a` and `b` in the post-dominator tree.
fn intersect(idom: &[usize], depth: &[usize], mut a: usize, mut b: usize) -> usize {
    while a != b {
        if depth[a] > depth[b] || (depth[a] == depth[b] && a > b) {
            a = idom[a];
        } else {
            b = idom[b];
        }
    }
    a
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Stop {
    Step(StepId),
    Transition(TransitionId),
}

#[derive(Debug, Clone, Copy)]
enum Cursor {
    /// The sequence has just placed this step.
    Step(StepId),
    /// The sequence has just placed this transition.
    Transition(TransitionId),
}

enum End {
    /// Nothing follows: a dead end or a jump.
    Open,
    /// The sequence arrived at the convergence of the construct it is a branch of; when that
    /// is a simultaneous convergence, these are the steps that lead into it.
    Reached(Vec<StepId>),
}

/// The chart is not well nested.
struct NotNested;

struct Parser<'a> {
    chart: &'a Chart,
    net: &'a Net,
    pdom: PostDominators,
    placed_step: Vec<bool>,
    placed_transition: Vec<bool>,
    /// Convergences of the enclosing constructs, innermost last.
    stops: Vec<Stop>,
}

impl Parser<'_> {
    fn innermost(&self, stop: Stop) -> bool {
        self.stops.last() == Some(&stop)
    }

    /// Continues `seq` after `cur` until it ends. Sequences are followed in a loop; only
    /// branches recurse, so long charts need no deep stack.
    fn sequence(&mut self, seq: &mut Vec<Elem>, mut cur: Cursor, depth: usize) -> Result<End, NotNested> {
        if depth > MAX_NESTING {
            return Err(NotNested);
        }
        loop {
            match cur {
                Cursor::Step(s) => {
                    let outs = self.net.outgoing[s].clone();
                    match outs.as_slice() {
                        [] => return Ok(End::Open),
                        &[t] => {
                            if self.innermost(Stop::Transition(t)) {
                                return Ok(End::Reached(vec![s]));
                            }
                            self.claim_transition(t)?;
                            seq.push(Elem::Transition(t));
                            cur = Cursor::Transition(t);
                        }
                        _ => {
                            for &t in &outs {
                                self.check_free_transition(t)?;
                            }
                            let starts: Vec<usize> = outs.iter().map(|&t| self.net.ns + t).collect();
                            let c = self.pdom.convergence(&starts).unwrap_or(usize::MAX);
                            let conv = (c < self.net.ns
                                && !self.placed_step[c]
                                && (!self.stops.contains(&Stop::Step(c)) || self.innermost(Stop::Step(c))))
                            .then_some(c);
                            if let Some(c) = conv {
                                self.stops.push(Stop::Step(c));
                            }
                            // Without a convergence, one branch may carry the sequence on (see
                            // `main_branch`): it keeps only its transition here, and the
                            // sequence continues after the selection, in this loop.
                            let main = if conv.is_none() { self.main_branch(&outs, depth) } else { None };
                            for &t in &outs {
                                self.placed_transition[t] = true;
                            }
                            let mut branches = Vec::with_capacity(outs.len());
                            let mut ends = Vec::new();
                            for (i, &t) in outs.iter().enumerate() {
                                if main == Some(i) {
                                    branches.push(Branch { seq: vec![Elem::Transition(t)], reaches: true });
                                    continue;
                                }
                                let mut b = vec![Elem::Transition(t)];
                                let end = self.sequence(&mut b, Cursor::Transition(t), depth + 1)?;
                                let reaches = matches!(end, End::Reached(_));
                                if let End::Reached(e) = end {
                                    ends.extend(e);
                                }
                                branches.push(Branch { seq: b, reaches });
                            }
                            if conv.is_some() {
                                self.stops.pop();
                            }
                            if let Some(i) = main {
                                seq.push(Elem::Selection { branches, merges: true });
                                cur = Cursor::Transition(outs[i]);
                                continue;
                            }
                            let reaching = branches.iter().filter(|b| b.reaches).count();
                            let merges = reaching > 0;
                            // Without a convergence of its own, branches may still reach the
                            // enclosing one: one branch just goes on to it, several meet on a
                            // convergence line first. Several alternatives joining a
                            // simultaneous convergence would each be required: not nested.
                            if conv.is_none() && reaching > 1 && !matches!(self.stops.last(), Some(Stop::Step(_))) {
                                return Err(NotNested);
                            }
                            seq.push(Elem::Selection { branches, merges });
                            match conv {
                                _ if !merges => return Ok(End::Open),
                                Some(c) if !self.innermost(Stop::Step(c)) => {
                                    self.placed_step[c] = true;
                                    seq.push(Elem::Step(c));
                                    cur = Cursor::Step(c);
                                }
                                _ => return Ok(End::Reached(ends)),
                            }
                        }
                    }
                }
                Cursor::Transition(t) => {
                    let to = self.chart.transitions[t].to.clone();
                    match to.as_slice() {
                        [] => return Ok(End::Open),
                        &[d] => {
                            if self.innermost(Stop::Step(d)) {
                                return Ok(End::Reached(Vec::new()));
                            }
                            if self.placed_step[d] || self.stops.contains(&Stop::Step(d)) {
                                seq.push(Elem::Jump { transition: t, target: d });
                                return Ok(End::Open);
                            }
                            self.placed_step[d] = true;
                            seq.push(Elem::Step(d));
                            cur = Cursor::Step(d);
                        }
                        _ => {
                            for &d in &to {
                                if self.placed_step[d] || self.stops.contains(&Stop::Step(d)) {
                                    return Err(NotNested);
                                }
                            }
                            let conv = self.pdom.join(&to).and_then(|j| j.checked_sub(self.net.ns)).filter(|&j| {
                                j < self.net.nt
                                    && !self.placed_transition[j]
                                    && self.chart.transitions[j].from.len() > 1
                                    && !self.stops.contains(&Stop::Transition(j))
                            });
                            if let Some(j) = conv {
                                self.stops.push(Stop::Transition(j));
                            }
                            // All heads are taken before any branch is followed, so a branch that
                            // leads to another head jumps there.
                            for &d in &to {
                                self.placed_step[d] = true;
                            }
                            let mut branches = Vec::with_capacity(to.len());
                            let mut ends = Vec::new();
                            for &d in &to {
                                let mut b = vec![Elem::Step(d)];
                                let end = self.sequence(&mut b, Cursor::Step(d), depth + 1)?;
                                let reaches = matches!(end, End::Reached(_));
                                if let End::Reached(e) = end {
                                    ends.extend(e);
                                }
                                branches.push(Branch { seq: b, reaches });
                            }
                            if conv.is_some() {
                                self.stops.pop();
                            }
                            let Some(j) = conv else {
                                // Branches end with jumps; none can reach an enclosing
                                // convergence (a branch reaching it alone would leave the others'
                                // tokens behind).
                                if branches.iter().any(|b| b.reaches) {
                                    return Err(NotNested);
                                }
                                seq.push(Elem::Simultaneous { branches, merges: false });
                                return Ok(End::Open);
                            };
                            // The convergence must join exactly the ends of the reaching branches.
                            let mut from = self.chart.transitions[j].from.clone();
                            from.sort_unstable();
                            from.dedup();
                            ends.sort_unstable();
                            if from != ends {
                                return Err(NotNested);
                            }
                            self.placed_transition[j] = true;
                            seq.push(Elem::Simultaneous { branches, merges: true });
                            seq.push(Elem::Transition(j));
                            cur = Cursor::Transition(j);
                        }
                    }
                }
            }
        }
    }

    /// The branch of a selection without convergence that carries the sequence on below the
    /// selection instead of inside a branch: the only branch that does not end at once (with a
    /// jump, a dead end or at a convergence), or, once branches are nested [`HOIST_DEPTH`]
    /// deep, the first such branch. Nesting every selection of a long chain with loop-back
    /// branches would otherwise grow with the chain; nested branches draw more compactly, so
    /// they are kept where nesting is shallow.
    fn main_branch(&self, outs: &[TransitionId], depth: usize) -> Option<usize> {
        let goes_on: Vec<usize> = outs
            .iter()
            .enumerate()
            .filter(|(_, &t)| match self.chart.transitions[t].to.as_slice() {
                [] => false,
                &[d] => !self.placed_step[d] && !self.stops.contains(&Stop::Step(d)),
                _ => true,
            })
            .map(|(i, _)| i)
            .collect();
        match goes_on.as_slice() {
            &[i] => Some(i),
            [i, ..] if depth >= HOIST_DEPTH => Some(*i),
            _ => None,
        }
    }

    /// A transition that may be drawn right below the step just placed: not drawn yet, not the
    /// convergence of an enclosing construct, and with that step as its only predecessor.
    fn check_free_transition(&self, t: TransitionId) -> Result<(), NotNested> {
        if self.placed_transition[t]
            || self.stops.contains(&Stop::Transition(t))
            || self.chart.transitions[t].from.len() > 1
        {
            return Err(NotNested);
        }
        Ok(())
    }

    fn claim_transition(&mut self, t: TransitionId) -> Result<(), NotNested> {
        self.check_free_transition(t)?;
        self.placed_transition[t] = true;
        Ok(())
    }
}
