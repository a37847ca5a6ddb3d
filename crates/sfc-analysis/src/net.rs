//! Net analysis: what a chart can do when every guard is a free input.
//!
//! # The model
//! A *situation* is the set of active steps; the initial situation is the set of initial steps. A
//! transition `t` is enabled in `X` when `pre(t) = from(t) ⊆ X`. In one scan any non-empty set `F`
//! of enabled transitions with pairwise disjoint presets may fire (guards are free, so the
//! conflict rule of `semantics.md` can always be made to accept exactly `F`): `D = ∪ pre`,
//! `A = ∪ post`, `X' = (X \ D) ∪ A`. The firing is **unsafe** at a step in `A ∩ (X \ D)` (activated
//! while active and not left in the same scan) or at a step activated by two transitions of `F`.
//! A step left and re-entered is not unsafe. Active steps are a set, so after an unsafe firing the
//! situation is still `X'` and the exploration goes on.
//!
//! # Interleaving, and where it is not enough
//! The lemma the design starts from — "every singleton `{t}` is a possible choice; an unsafe
//! firing of `F` implies an unsafe singleton firing from the same `X`; and as long as no unsafe
//! firing happened, firing `F` gives the same `X'` as firing its members one by one" — is checked
//! here, and it is **true for safe behaviour but false in two places once a chart is unsafe**:
//!
//! 1. *Same `X`* fails for a double activation of an inactive step: from `X = {a, b}` with
//!    `t1: a → s`, `t2: b → s`, firing `{t1, t2}` is unsafe at `s`, but neither singleton is.
//!    The step is still found: after `t1` alone, `t2` is enabled and activates `s` while active.
//!    So the *set* of unsafe steps is the same; only the witness is one scan longer, and a witness
//!    here always ends with a single transition that activates an active step.
//! 2. *Same `X'`* fails when the members of `F` feed each other's presets in a cycle. With
//!    `t1: a → (b, c)` and `t2: b → (a, d)` from `X = {a, b}`, firing both gives `{a, b, c, d}`
//!    without any unsafe activation (both `a` and `b` are left and re-entered), but every order of
//!    single firings loses `a` or `b` (and is unsafe). `{a, b, c, d}` is reachable under the set
//!    semantics and not by interleaving, so dead transitions, unreachable steps, lock-ups and the
//!    concurrency relation could all differ.
//!
//! The analysis therefore works on the exact set semantics, computed as interleaving **plus
//! group scans**. Call `t_i → t_j` an edge when `post(t_i) ∩ pre(t_j) ≠ ∅` and the presets are
//! disjoint. If the edges inside `F` have no cycle, firing `F`'s members consumers-first (in a
//! topological order against the edges) gives exactly `X'`, through situations that are reachable
//! themselves; if they form strongly connected parts, each part is fired as one *group scan* and
//! the rest one by one around it. So the reachable situations are exactly those reached by single
//! transitions and by groups `G` (`|G| ≥ 2`, pairwise disjoint presets, strongly connected in the
//! edge relation, all enabled). A group needs every member to post into the preset of another
//! enabled member, so each member alone is an unsafe firing: groups only ever fire from situations
//! that already show an unsafe finding, and safe charts never see one.
//!
//! Witnesses are the firing sequences of `sfc check --format json` (one transition per scan). A
//! shortest witness counts scans; among equally short ones the lexicographically smallest sequence
//! of scans (transitions compared by id, a scan by its ascending id list) is chosen, so every
//! method gives the same witness. A group scan (only after an unsafe firing, see above) appears in
//! the flat witness as its members in ascending order.
//!
//! # Methods (cheapest first)
//! 1. Every connected network (steps linked through transitions) is independent of the others
//!    and is analysed alone; its witnesses only use its own transitions.
//! 2. A **structural certificate** (`net/structure.rs`) reduces well-nested block structure to a
//!    single step; when it succeeds the network is safe, every step is reachable, no transition is
//!    dead, there is no lock-up, and the concurrency relation comes from the blocks.
//! 3. An **explicit breadth-first search** (`net/explicit.rs`) over bit-packed situations, with
//!    parent pointers for witnesses. [`analyze_net`] first tries it on at most 50,000 situations.
//! 4. A **symbolic search** (`net/symbolic.rs`) with BDDs (`biodivine-lib-bdd`) for networks whose
//!    situations do not fit: chained reachability, verdicts read off the reachable set, and
//!    backward breadth-first layers only when a finding needs a witness (or, when the network has
//!    no more situations than the budget, the explicit search run to the end for them).
//! 5. When the diagrams outgrow their node limit, the explicit search goes on with the whole of
//!    [`NetOptions::max_states`]; when that runs out too, the report is incomplete.
//!
//! Group scans are enumerated from each situation where unsafe-capable transitions feed each
//! other; when more than [`MAX_GROUP_CANDIDATES`] subsets would have to be tried from one
//! situation (charts that multiply tokens everywhere), the search stops there and the report is
//! incomplete.
//!
//! # Conventions for erroneous charts
//! Step ids outside the chart are ignored and duplicates removed. A transition whose `from` is
//! empty (after that) is treated as never enabled and reported **dead**. A transition with an
//! empty `to` consumes its preset and activates nothing. Several initial steps in one network are
//! all active at the start. A network without an initial step has all its steps unreachable and
//! its transitions dead.
//!
//! # Lock-ups are per network
//! A lock-up is a reachable situation of one network in which none of the network's transitions is
//! enabled while some of its active steps has an outgoing transition (the other networks may go on:
//! a network stuck while another loops forever is still reported). With one network this is the
//! chart-wide definition. A situation whose active steps have no outgoing transition at all is a
//! normal end.

mod explicit;
mod structure;
mod symbolic;

use sfc_model::{Chart, StepId, TransitionId};

/// Limits of the analysis.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct NetOptions {
    /// Situations the explicit search may store (over all networks). The symbolic search is given
    /// `max(4 · max_states, 100,000)` BDD nodes per diagram.
    pub max_states: usize,
}

impl Default for NetOptions {
    fn default() -> Self {
        NetOptions { max_states: 1_000_000 }
    }
}

/// How the result was decided. With several networks the most expensive method used is reported.
#[derive(Debug, Clone, PartialEq)]
pub enum Method {
    /// No steps or no initial step: nothing to analyse.
    Empty,
    /// Every network was proven by its block structure, without search.
    Structure,
    /// Explicit search; `states` situations were stored (summed over the searched networks).
    Explicit { states: usize },
    /// Symbolic search; `states` is the number of reachable situations, counted per network and
    /// summed over the searched networks.
    Symbolic { states: f64 },
}

/// Which procedures [`analyze_net_with`] may use. [`analyze_net`] uses [`Strategy::Auto`]; the
/// other values exist so tests and benchmarks can compare the methods on the same chart.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Strategy {
    /// Certificate, then a short explicit search, then symbolic, then the rest of the explicit
    /// budget.
    #[default]
    Auto,
    /// Explicit search only (no certificate); incomplete when the state budget runs out.
    Explicit,
    /// Symbolic search only (no certificate); incomplete when the node budget runs out.
    Symbolic,
    /// The structural certificate only: networks it cannot prove are left undecided (the report
    /// is then incomplete). Costs linear time, never searches.
    Structure,
}

/// The result of [`analyze_net`].
#[derive(Debug, Clone)]
pub struct NetReport {
    pub method: Method,
    /// false when the state budget ran out before the search finished (then only the unsafe/lock-up
    /// findings found so far are listed, `unreachable`/`dead` are empty and `concurrency` is "unknown => true").
    pub complete: bool,
    /// Sorted by step id, one per step.
    pub unsafe_steps: Vec<UnsafeFinding>,
    /// Sorted.
    pub unreachable: Vec<StepId>,
    /// Sorted.
    pub dead: Vec<TransitionId>,
    /// Distinct lock-up situations, at most [`MAX_LOCKUPS`], shortest witnesses first.
    pub lockups: Vec<Lockup>,
    pub concurrency: Concurrency,
}

/// At most this many lock-up situations are reported.
pub const MAX_LOCKUPS: usize = 10;

/// A step that some reachable firing activates while it is active.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct UnsafeFinding {
    pub step: StepId,
    /// The transition whose firing activates `step` while active (the last of `witness`).
    pub transition: TransitionId,
    /// The shortest firing sequence from the initial situation, ending with `transition`.
    pub witness: Vec<TransitionId>,
}

/// A reachable situation of one network in which nothing can fire although some active step has
/// an outgoing transition.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Lockup {
    /// The active steps of the network, sorted.
    pub situation: Vec<StepId>,
    /// The shortest firing sequence from the initial situation reaching it.
    pub witness: Vec<TransitionId>,
}

/// Which steps can be active together in some reachable situation.
#[derive(Debug, Clone)]
pub struct Concurrency {
    /// Per chart step: its network and its index there (`u32::MAX` network for a step id the
    /// analysis never saw).
    place: Vec<(u32, u32)>,
    nets: Vec<NetConc>,
}

/// The concurrency relation inside one network.
#[derive(Debug, Clone)]
enum NetConc {
    /// Nothing of the network is reachable.
    Unreachable,
    /// The search did not finish: every pair may be together.
    Unknown,
    /// From the block structure: two different steps are together iff their lowest common block
    /// is a simultaneous one (they lie in different branches of it).
    Tree(structure::Tree),
    /// From a search: row `a` (of `words` words) holds the steps seen together with `a`; `reach`
    /// the reachable steps.
    Matrix { words: usize, reach: Vec<u64>, rows: Vec<u64> },
}

impl NetConc {
    fn reachable(&self, a: u32) -> bool {
        match self {
            NetConc::Unreachable => false,
            NetConc::Unknown | NetConc::Tree(_) => true,
            NetConc::Matrix { reach, .. } => bit(reach, a as usize),
        }
    }
    fn together(&self, a: u32, b: u32) -> bool {
        match self {
            NetConc::Unreachable => false,
            NetConc::Unknown => true,
            NetConc::Tree(t) => a == b || t.parallel(a, b),
            NetConc::Matrix { words, reach, rows } => {
                if a == b {
                    bit(reach, a as usize)
                } else {
                    let row = &rows[a as usize * words..(a as usize + 1) * words];
                    bit(row, b as usize)
                }
            }
        }
    }
}

impl Concurrency {
    /// Whether steps `a` and `b` are active together in some reachable situation; for `a == b`,
    /// whether `a` is reachable. Steps of different networks are together when both are
    /// reachable. When the search was incomplete the answer is `true` where it is unknown.
    pub fn together(&self, a: StepId, b: StepId) -> bool {
        let (Some(&(na, la)), Some(&(nb, lb))) = (self.place.get(a), self.place.get(b)) else {
            return false;
        };
        let (Some(neta), Some(netb)) = (self.nets.get(na as usize), self.nets.get(nb as usize)) else {
            return false;
        };
        if na != nb {
            return neta.reachable(la) && netb.reachable(lb);
        }
        neta.together(la, lb)
    }

    fn empty(steps: usize) -> Concurrency {
        Concurrency { place: vec![(u32::MAX, 0); steps], nets: Vec::new() }
    }
}

/// Analyses `chart` (see the module documentation).
pub fn analyze_net(chart: &Chart, opts: &NetOptions) -> NetReport {
    analyze_net_with(chart, opts, Strategy::Auto)
}

/// [`analyze_net`] with a chosen [`Strategy`].
pub fn analyze_net_with(chart: &Chart, opts: &NetOptions, strategy: Strategy) -> NetReport {
    let nsteps = chart.steps.len();
    let empty = |concurrency| NetReport {
        method: Method::Empty,
        complete: true,
        unsafe_steps: Vec::new(),
        unreachable: Vec::new(),
        dead: Vec::new(),
        lockups: Vec::new(),
        concurrency,
    };
    if nsteps == 0 || !chart.steps.iter().any(|s| s.initial) {
        return empty(Concurrency::empty(nsteps));
    }
    let prep = prepare(chart);
    let mut remaining = opts.max_states.max(1);
    let node_limit = opts.max_states.saturating_mul(4).max(100_000);

    let mut complete = true;
    let mut structure_only = true;
    let mut explicit_states = 0usize;
    let mut symbolic_states: Option<f64> = None;
    let mut unsafe_steps: Vec<UnsafeFinding> = Vec::new();
    let mut unreachable: Vec<StepId> = Vec::new();
    let mut dead: Vec<TransitionId> = prep.never_enabled.clone();
    let mut lockups: Vec<(Vec<Vec<TransitionId>>, Lockup)> = Vec::new();
    let mut nets_conc = Vec::with_capacity(prep.nets.len());

    for net in &prep.nets {
        let global_t = |t: u32| net.trans[t as usize];
        let global_path = |p: &[Vec<u32>]| -> Vec<Vec<TransitionId>> {
            p.iter().map(|l| l.iter().map(|&t| global_t(t)).collect()).collect()
        };
        if net.initial.is_empty() {
            unreachable.extend(net.steps.iter().copied());
            dead.extend(net.trans.iter().copied());
            nets_conc.push(NetConc::Unreachable);
            continue;
        }
        if matches!(strategy, Strategy::Auto | Strategy::Structure) {
            if let Some(tree) = structure::certify(net) {
                nets_conc.push(NetConc::Tree(tree));
                continue;
            }
        }
        if strategy == Strategy::Structure {
            complete = false;
            nets_conc.push(NetConc::Unknown);
            continue;
        }
        structure_only = false;
        let outcome = match strategy {
            Strategy::Explicit => {
                let mut s = explicit::Search::new(net);
                s.run(remaining);
                s.outcome()
            }
            Strategy::Symbolic => match symbolic::run(net, node_limit, None) {
                symbolic::Symbolic::Done(o) => o,
                _ => Outcome::unknown(net),
            },
            Strategy::Auto | Strategy::Structure => {
                let mut s = explicit::Search::new(net);
                s.run(remaining.min(PROBE_STATES));
                if s.finished() {
                    s.outcome()
                } else {
                    match symbolic::run(net, node_limit, Some(remaining)) {
                        symbolic::Symbolic::Done(o) => o,
                        symbolic::Symbolic::PreferExplicit => {
                            s.run(remaining);
                            if s.finished() {
                                s.outcome()
                            } else {
                                match symbolic::run(net, node_limit, None) {
                                    symbolic::Symbolic::Done(o) => o,
                                    _ => s.outcome(),
                                }
                            }
                        }
                        symbolic::Symbolic::GaveUp => {
                            s.run(remaining);
                            s.outcome()
                        }
                    }
                }
            }
        };
        match outcome.method {
            SearchMethod::Explicit(n) => {
                explicit_states += n;
                remaining = remaining.saturating_sub(n).max(1);
            }
            SearchMethod::Symbolic(c) => *symbolic_states.get_or_insert(0.0) += c,
        }
        complete &= outcome.complete;
        for (s, path, t) in &outcome.unsafe_steps {
            let mut witness: Vec<TransitionId> = global_path(path).into_iter().flatten().collect();
            witness.push(global_t(*t));
            unsafe_steps.push(UnsafeFinding { step: net.steps[*s as usize], transition: global_t(*t), witness });
        }
        for (sit, path) in &outcome.lockups {
            let gp = global_path(path);
            let mut situation: Vec<StepId> = sit.iter().map(|&s| net.steps[s as usize]).collect();
            situation.sort_unstable();
            let witness = gp.iter().flatten().copied().collect();
            lockups.push((gp, Lockup { situation, witness }));
        }
        if outcome.complete {
            for (l, &r) in outcome.reachable.iter().enumerate() {
                if !r {
                    unreachable.push(net.steps[l]);
                }
            }
            for (l, &e) in outcome.enabled.iter().enumerate() {
                if !e {
                    dead.push(net.trans[l]);
                }
            }
        }
        nets_conc.push(match outcome.conc {
            Some((words, reach, rows)) if outcome.complete => NetConc::Matrix { words, reach, rows },
            _ => NetConc::Unknown,
        });
    }

    unsafe_steps.sort_by_key(|f| f.step);
    lockups.sort_by(|a, b| (a.0.len(), &a.0).cmp(&(b.0.len(), &b.0)));
    lockups.truncate(MAX_LOCKUPS);
    let method = if let Some(states) = symbolic_states {
        Method::Symbolic { states: states + explicit_states as f64 }
    } else if structure_only {
        Method::Structure
    } else {
        Method::Explicit { states: explicit_states }
    };
    if complete {
        unreachable.sort_unstable();
        dead.sort_unstable();
        dead.dedup();
    } else {
        unreachable.clear();
        dead.clear();
    }
    NetReport {
        method,
        complete,
        unsafe_steps,
        unreachable,
        dead,
        lockups: lockups.into_iter().map(|l| l.1).collect(),
        concurrency: Concurrency { place: prep.place, nets: nets_conc },
    }
}

/// Situations the explicit search may try before the symbolic search is preferred.
const PROBE_STATES: usize = 50_000;

/// One connected network with local step and transition numbers (ascending in the chart's).
#[derive(Debug, Clone)]
pub(crate) struct Net {
    /// Local step → chart step.
    pub steps: Vec<StepId>,
    /// Local transition → chart transition.
    pub trans: Vec<TransitionId>,
    /// Sorted local steps.
    pub pre: Vec<Vec<u32>>,
    pub post: Vec<Vec<u32>>,
    pub initial: Vec<u32>,
    /// Local step → local transitions that have it in their preset.
    pub out: Vec<Vec<u32>>,
    /// Local step → local transitions that have it in their postset.
    pub inc: Vec<Vec<u32>>,
}

/// The chart cut into networks.
struct Prepared {
    nets: Vec<Net>,
    /// Transitions with an empty (or entirely invalid) `from`.
    never_enabled: Vec<TransitionId>,
    /// Per chart step: (network, local index).
    place: Vec<(u32, u32)>,
}

fn prepare(chart: &Chart) -> Prepared {
    let n = chart.steps.len();
    let clean = |v: &[StepId]| {
        let mut v: Vec<StepId> = v.iter().copied().filter(|&s| s < n).collect();
        v.sort_unstable();
        v.dedup();
        v
    };
    let from: Vec<Vec<StepId>> = chart.transitions.iter().map(|t| clean(&t.from)).collect();
    let to: Vec<Vec<StepId>> = chart.transitions.iter().map(|t| clean(&t.to)).collect();
    let mut parent: Vec<usize> = (0..n).collect();
    fn find(p: &mut [usize], mut x: usize) -> usize {
        while p[x] != x {
            p[x] = p[p[x]];
            x = p[x];
        }
        x
    }
    let mut never_enabled = Vec::new();
    for t in 0..from.len() {
        if from[t].is_empty() {
            never_enabled.push(t);
            continue;
        }
        let first = from[t][0];
        for &s in from[t].iter().chain(to[t].iter()) {
            let (a, b) = (find(&mut parent, first), find(&mut parent, s));
            if a != b {
                parent[a.max(b)] = a.min(b);
            }
        }
    }
    let mut place = vec![(u32::MAX, 0u32); n];
    let mut root_net = vec![u32::MAX; n];
    let mut nets: Vec<Net> = Vec::new();
    for (s, step) in chart.steps.iter().enumerate() {
        let r = find(&mut parent, s);
        if root_net[r] == u32::MAX {
            root_net[r] = nets.len() as u32;
            nets.push(Net {
                steps: Vec::new(),
                trans: Vec::new(),
                pre: Vec::new(),
                post: Vec::new(),
                initial: Vec::new(),
                out: Vec::new(),
                inc: Vec::new(),
            });
        }
        let k = root_net[r];
        let net = &mut nets[k as usize];
        let local = net.steps.len() as u32;
        place[s] = (k, local);
        net.steps.push(s);
        net.out.push(Vec::new());
        net.inc.push(Vec::new());
        if step.initial {
            net.initial.push(local);
        }
    }
    for t in 0..from.len() {
        if from[t].is_empty() {
            continue;
        }
        let k = place[from[t][0]].0 as usize;
        let net = &mut nets[k];
        let lt = net.trans.len() as u32;
        net.trans.push(t);
        let pre: Vec<u32> = from[t].iter().map(|&s| place[s].1).collect();
        let post: Vec<u32> = to[t].iter().map(|&s| place[s].1).collect();
        for &s in &pre {
            net.out[s as usize].push(lt);
        }
        for &s in &post {
            net.inc[s as usize].push(lt);
        }
        net.pre.push(pre);
        net.post.push(post);
    }
    Prepared { nets, never_enabled, place }
}

/// What a search found in one network (local numbers).
#[derive(Debug, Clone)]
pub(crate) struct Outcome {
    pub complete: bool,
    pub method: SearchMethod,
    /// Per local step (meaningful when complete).
    pub reachable: Vec<bool>,
    /// Per local transition: enabled in some reachable situation (meaningful when complete).
    pub enabled: Vec<bool>,
    /// (step, scans before the last firing, the unsafe transition), sorted by step.
    pub unsafe_steps: Vec<(u32, Vec<Vec<u32>>, u32)>,
    /// (situation, scans), shortest first, at most [`MAX_LOCKUPS`].
    pub lockups: Vec<(Vec<u32>, Vec<Vec<u32>>)>,
    /// (words per row, reachable steps, rows): the concurrency matrix.
    pub conc: Option<(usize, Vec<u64>, Vec<u64>)>,
}

#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum SearchMethod {
    Explicit(usize),
    Symbolic(f64),
}

impl Outcome {
    /// Nothing could be decided.
    fn unknown(net: &Net) -> Outcome {
        Outcome {
            complete: false,
            method: SearchMethod::Symbolic(0.0),
            reachable: vec![true; net.steps.len()],
            enabled: vec![true; net.trans.len()],
            unsafe_steps: Vec::new(),
            lockups: Vec::new(),
            conc: None,
        }
    }
}

pub(crate) fn bit(v: &[u64], i: usize) -> bool {
    v.get(i / 64).is_some_and(|w| w >> (i % 64) & 1 == 1)
}

pub(crate) fn set_bit(v: &mut [u64], i: usize) {
    if let Some(w) = v.get_mut(i / 64) {
        *w |= 1 << (i % 64);
    }
}

/// The strongly connected subsets (`≥ 2` members, pairwise disjoint presets) of `cands` in the
/// edge relation `post(a) ∩ pre(b) ≠ ∅`, each sorted, all sorted; `None` when there are more than 64
/// candidates or more than [`MAX_GROUP_CANDIDATES`] subsets would have to be tried.
pub(crate) fn groups_among(net: &Net, cands: &[u32]) -> Option<Vec<Vec<u32>>> {
    let k = cands.len();
    if k < 2 {
        return Some(Vec::new());
    }
    if k > 64 {
        return None;
    }
    let meets = |a: &[u32], b: &[u32]| a.iter().any(|s| b.binary_search(s).is_ok());
    let mut edge = vec![0u64; k];
    let mut redge = vec![0u64; k];
    let mut clash = vec![0u64; k];
    for i in 0..k {
        for j in 0..k {
            if i == j {
                continue;
            }
            let (a, b) = (cands[i] as usize, cands[j] as usize);
            if meets(&net.pre[a], &net.pre[b]) {
                clash[i] |= 1 << j;
            } else if meets(&net.post[a], &net.pre[b]) {
                edge[i] |= 1 << j;
                redge[j] |= 1 << i;
            }
        }
    }
    // Reachability closure, then the strongly connected components.
    let mut reach: Vec<u64> = (0..k).map(|i| edge[i] | 1 << i).collect();
    loop {
        let mut grew = false;
        for i in 0..k {
            let mut r = reach[i];
            let mut bits = reach[i];
            while bits != 0 {
                let j = bits.trailing_zeros() as usize;
                bits &= bits - 1;
                r |= reach[j];
            }
            if r != reach[i] {
                reach[i] = r;
                grew = true;
            }
        }
        if !grew {
            break;
        }
    }
    let closed = |mask: u64, adj: &[u64]| {
        let start = mask & mask.wrapping_neg();
        let (mut seen, mut frontier) = (start, start);
        while frontier != 0 {
            let i = frontier.trailing_zeros() as usize;
            frontier &= frontier - 1;
            let new = adj[i] & mask & !seen;
            seen |= new;
            frontier |= new;
        }
        seen == mask
    };
    let mut out = Vec::new();
    let mut budget = MAX_GROUP_CANDIDATES;
    let mut done = 0u64;
    for i in 0..k {
        if done >> i & 1 == 1 {
            continue;
        }
        let comp: u64 = (0..k).filter(|&j| reach[i] >> j & 1 == 1 && reach[j] >> i & 1 == 1).fold(0, |m, j| m | 1 << j);
        done |= comp;
        if comp.count_ones() < 2 {
            continue;
        }
        let members: Vec<usize> = (0..k).filter(|&j| comp >> j & 1 == 1).collect();
        // Depth-first over the subsets of the component: `chosen` members are in, members outside
        // `possible` are out. A member of a strongly connected subset has an edge into and an
        // edge from the subset, so members without both inside `possible` are dropped (repeatedly);
        // members whose preset meets a chosen one's are dropped too.
        let peel = |mut p: u64| loop {
            let mut q = p;
            let mut bits = p;
            while bits != 0 {
                let i = bits.trailing_zeros() as usize;
                bits &= bits - 1;
                if edge[i] & p == 0 || redge[i] & p == 0 {
                    q &= !(1 << i);
                }
            }
            if q == p {
                break p;
            }
            p = q;
        };
        let mut stack: Vec<(usize, u64, u64)> = vec![(0, 0, comp)];
        while let Some((idx, chosen, possible)) = stack.pop() {
            if budget == 0 {
                return None;
            }
            budget -= 1;
            let possible = peel(possible);
            if chosen & !possible != 0 || possible.count_ones() < 2 {
                continue;
            }
            let Some(pos) =
                (idx..members.len()).find(|&i| possible >> members[i] & 1 == 1 && chosen >> members[i] & 1 == 0)
            else {
                if chosen.count_ones() >= 2 && closed(chosen, &edge) && closed(chosen, &redge) {
                    out.push((0..k).filter(|&j| chosen >> j & 1 == 1).map(|j| cands[j]).collect::<Vec<u32>>());
                }
                continue;
            };
            let c = members[pos];
            stack.push((pos + 1, chosen, possible & !(1 << c)));
            stack.push((pos + 1, chosen | 1 << c, possible & !clash[c]));
        }
    }
    for g in &mut out {
        g.sort_unstable();
    }
    out.sort();
    Some(out)
}

/// Subsets of unsafe-capable transitions that may be tried as group scans from one situation;
/// beyond it the search reports itself incomplete.
pub const MAX_GROUP_CANDIDATES: usize = 1 << 10;
