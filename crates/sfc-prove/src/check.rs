//! The engines, in the order that settles most properties fastest: 1-induction strengthened
//! with the net analysis' invariants and the initial state's (its invariant re-checked
//! constraint by constraint), a short bounded search (refutations, shortest first),
//! 1-induction with less of the strengthening, BDD reachability (exact: the reachable set,
//! shortest witnesses), and a longer bounded search when the diagrams grow too large. What
//! none of them settles within the budget is `unknown`, with how far it got.

use crate::aig::Lit;
use crate::bdd::{BddEngine, GiveUp};
use crate::compile::Signal;
use crate::sat::{self, Invariant};
use crate::system::System;
use std::time::{Duration, Instant};

/// How much work a property may take.
#[derive(Debug, Clone, Copy)]
pub struct Budget {
    pub deadline: Instant,
    /// Reached states the symbolic search may hold (`--budget Nstates`).
    pub max_states: Option<f64>,
    pub node_limit: usize,
}

/// The verdict of one property.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Verdict {
    Holds,
    Violated,
    Unknown,
}

impl Verdict {
    pub fn name(self) -> &'static str {
        match self {
            Verdict::Holds => "holds",
            Verdict::Violated => "violated",
            Verdict::Unknown => "unknown",
        }
    }
}

/// What an engine concluded, before witnesses are replayed.
#[derive(Debug, Clone)]
pub struct Finding {
    pub verdict: Verdict,
    pub method: &'static str,
    /// Reachable states counted by the symbolic search.
    pub states: Option<f64>,
    /// The inductive invariant's size (clauses and at-most-one constraints, or diagram nodes of
    /// a reachable set), and whether the independent check passed.
    pub invariant: Option<(usize, bool)>,
    /// How many of the invariant's constraints are at-most-one constraints.
    pub at_most_one: usize,
    /// For violations (and reachable goals): the inputs of every scan from the initial state.
    pub trace: Option<Vec<Vec<(u32, bool)>>>,
    /// Scans searched without a violation (bounded searches).
    pub depth: Option<usize>,
    pub message: String,
}

impl Finding {
    fn new(verdict: Verdict, method: &'static str, message: impl Into<String>) -> Finding {
        Finding {
            verdict,
            method,
            states: None,
            invariant: None,
            at_most_one: 0,
            trace: None,
            depth: None,
            message: message.into(),
        }
    }
}

fn give_up_text(g: &GiveUp) -> String {
    match g {
        GiveUp::Nodes(n) => format!("a decision diagram grew beyond {n} nodes"),
        GiveUp::Time => "the time budget ran out".into(),
        GiveUp::States(s) => format!("the reached states ({s:.0}) exceed the state budget"),
    }
}

/// Development tracing of the engines' stages (`SFC_PROVE_TRACE=1`).
fn trace(what: &str, since: Instant) {
    if std::env::var_os("SFC_PROVE_TRACE").is_some() {
        eprintln!("[prove] {what}: {:?}", since.elapsed());
    }
}

/// The symbolic engine of the last cone, and its complete reachable set, for the next
/// property with the same cone.
#[derive(Default)]
pub struct Cache {
    key: Option<(Vec<u32>, usize)>,
    pub eng: Option<BddEngine>,
    pub reach: Option<crate::bdd::Reach>,
    /// The whole system with its constant state bits folded, and the map into it.
    simple: Option<(System, Vec<Lit>)>,
}

impl Cache {
    /// The cone of `roots` in the simplified system ([`System::simplify`], done once), and
    /// `roots` in it.
    fn reduce(&mut self, full: &System, roots: &[Lit]) -> (System, Vec<Lit>) {
        let (simple, map) = self.simple.get_or_insert_with(|| full.simplify());
        let roots: Vec<Lit> = roots.iter().map(|&r| crate::aig::Aig::map_lit(map, r)).collect();
        (simple.cone(&roots), roots)
    }

    /// The engine for `sys`: the cached one when the cone is the same, else a new one.
    fn engine(&mut self, sys: &System, budget: &Budget) -> Result<&mut BddEngine, GiveUp> {
        let key = (sys.state_vars(), sys.g.num_nodes());
        if self.key.as_ref() != Some(&key) || self.eng.is_none() {
            self.eng = None;
            self.reach = None;
            self.key = None;
            let e = BddEngine::new(sys.clone(), budget.node_limit, budget.deadline)?;
            self.eng = Some(e);
            self.key = Some(key);
        }
        let eng = self.eng.as_mut().expect("engine");
        eng.deadline = budget.deadline;
        eng.max_states = budget.max_states;
        Ok(eng)
    }
}

/// The strengthening `strengthen` (over the full system's state variables) restricted to the
/// state bits of `sys`: clauses over other bits are left out, at-most-one constraints keep
/// their members in `sys` (and are left out below two).
fn restrict(full: &System, sys: &System, strengthen: &Invariant) -> Invariant {
    let vars: std::collections::HashSet<u32> = sys.state_vars().into_iter().collect();
    // The same variable numbers stand in the reduced graph.
    let map = |l: Lit| -> Option<Lit> {
        let v = full.g.var_of(l)?;
        vars.contains(&v).then(|| if l.is_neg() { sys.g.var_lit(v).not() } else { sys.g.var_lit(v) })
    };
    let clauses = strengthen.clauses.iter().filter_map(|cl| cl.iter().map(|&l| map(l)).collect()).collect();
    let at_most_one = strengthen
        .at_most_one
        .iter()
        .map(|g| g.iter().filter_map(|&l| map(l)).collect::<Vec<Lit>>())
        .filter(|g| g.len() >= 2)
        .collect();
    Invariant { clauses, at_most_one }
}

/// Why 1-induction gave no proof.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum NoProof {
    /// A scan from a state of the invariant reaches `bad`: with fewer clauses it would too.
    NotInductive,
    /// The invariant failed its independent check (a part of the strengthening is not
    /// inductive): a smaller one may pass.
    CheckFailed,
    /// The deadline stopped the solver.
    Undecided,
}

/// 1-induction with `inv`, and the independent check of the invariant: the finding when both
/// pass. The check runs until `deadline` (the property's), whatever the deadline of the
/// induction.
fn induction(sys: &System, inv: &Invariant, bad: Lit, t0: Instant, deadline: Instant) -> Result<Finding, NoProof> {
    let ind = sat::inductive(sys, inv, bad);
    trace(&format!("1-induction ({} clauses, {} at-most-one): {ind:?}", inv.clauses.len(), inv.at_most_one.len()), t0);
    match ind {
        Some(true) => {}
        Some(false) => return Err(NoProof::NotInductive),
        None => return Err(NoProof::Undecided),
    }
    // Only a certificate that passes the independent check is a proof; otherwise the next
    // engine decides.
    sat::set_deadline(Some(deadline));
    let checked = sat::check_invariant(sys, inv);
    trace(&format!("independent check: {checked:?}"), t0);
    if checked.is_err() {
        return Err(NoProof::CheckFailed);
    }
    let mut f = Finding::new(
        Verdict::Holds,
        "1-induction",
        if inv.len() == 1 {
            "the property is inductive".to_string()
        } else {
            "the property is inductive together with the net invariants".to_string()
        },
    );
    f.invariant = Some((inv.len(), true));
    f.at_most_one = inv.at_most_one.len();
    Ok(f)
}

/// Checks a safety property: `bad` never holds in a reachable state.
pub fn safety(full: &System, bad: Lit, strengthen: &Invariant, budget: &Budget, cache: &mut Cache) -> Finding {
    let t0 = Instant::now();
    sat::set_deadline(Some(budget.deadline));
    let (sys, roots) = cache.reduce(full, &[bad]);
    let bad = roots[0];
    trace(&format!("cone of {} state bits, {} nodes", sys.state.len(), sys.g.num_nodes()), t0);
    if bad == Lit::FALSE {
        let mut f = Finding::new(Verdict::Holds, "structure", "the property holds by construction");
        f.invariant = Some((0, true));
        return f;
    }
    let extra = restrict(full, &sys, strengthen);
    let property = Invariant::of(bad);
    let mut all = property.clone();
    all.extend(&extra);
    let all_fits = extra.clauses.len() <= 5000;
    // 1. 1-induction with every invariant the net analysis and the initial state give, before
    // any search: a property that holds is usually proved here, and a state machine's
    // "at most one step" makes the induction step one small problem per step. A quarter of the
    // budget at most: a violated property goes on to the bounded search.
    let mut first = None;
    if all_fits && !extra.is_empty() {
        let quarter = budget.deadline.saturating_duration_since(Instant::now()) / 4;
        sat::set_deadline(Some(Instant::now() + quarter));
        let got = induction(&sys, &all, bad, t0, budget.deadline);
        sat::set_deadline(Some(budget.deadline));
        match got {
            Ok(f) => return f,
            Err(why) => first = Some(why),
        }
    }
    // 2. A short bounded search: most violations are shallow.
    let quick =
        Instant::now() + Duration::from_millis(150).min(budget.deadline.saturating_duration_since(Instant::now()) / 4);
    let mut searched = 0;
    match sat::bmc(&sys, bad, 12, quick.min(budget.deadline)) {
        sat::Bmc::Found(trace) => {
            let mut f = Finding::new(Verdict::Violated, "bounded model checking", "");
            f.trace = Some(trace);
            return f;
        }
        sat::Bmc::None { depth } => searched = searched.max(depth),
    }
    trace(&format!("bmc to depth {searched}"), t0);
    // 3. 1-induction with less: the property alone, then with the invariants near the steps
    // it names, then (when the first try ran out of time) with all of them. None of them can
    // succeed when the first try found a scan from its invariant to `bad`.
    let near: std::collections::HashSet<u32> = sys.g.support(&[bad]).into_iter().collect();
    let is_near = |l: &Lit| sys.g.var_of(*l).is_some_and(|v| near.contains(&v));
    let close = Invariant {
        clauses: extra.clauses.iter().filter(|c| c.iter().any(is_near)).cloned().collect(),
        at_most_one: extra.at_most_one.iter().filter(|g| g.iter().any(is_near)).cloned().collect(),
    };
    let mut tries = Vec::new();
    if first != Some(NoProof::NotInductive) {
        tries.push(property);
        if !close.is_empty() {
            let mut with = Invariant::of(bad);
            with.extend(&close);
            tries.push(with);
        }
        if first == Some(NoProof::Undecided) {
            tries.push(all);
        }
    }
    for inv in &tries {
        if Instant::now() >= budget.deadline {
            break;
        }
        if let Ok(f) = induction(&sys, inv, bad, t0, budget.deadline) {
            return f;
        }
    }
    // 4. Symbolic reachability (the engine and a complete reachable set are shared by the
    // properties with the same cone), with two thirds of the time left: the deeper bounded
    // search after it gets the rest (a diagram that grows too slowly would take it all).
    let left = budget.deadline.saturating_duration_since(Instant::now());
    let symbolic = Budget { deadline: Instant::now() + left * 2 / 3, ..*budget };
    let reason = match cache.engine(&sys, &symbolic) {
        Ok(eng) => {
            trace(&format!("BDD engine ready (relation {})", eng.relation_size()), t0);
            let known = cache.reach.clone();
            let eng = cache.eng.as_mut().expect("engine just made");
            match eng.predicate(bad) {
                Ok(badb) => match known.map_or_else(|| eng.reach(Some(&badb)), Ok) {
                    Ok(mut r) => {
                        if r.complete {
                            cache.reach = Some(r.clone());
                            r.hit = r.rings.iter().position(|ring| !ring.and(&badb).is_false());
                        }
                        let eng = cache.eng.as_ref().expect("engine");
                        if r.hit.is_some() {
                            let trace = eng.path_to(&r, &badb);
                            let mut f = Finding::new(Verdict::Violated, "BDD reachability", "");
                            if trace.is_none() {
                                f.verdict = Verdict::Unknown;
                                f.message =
                                    "the symbolic search met a violation but could not read its path back".into();
                            }
                            f.trace = trace;
                            return f;
                        }
                        let states = eng.count(&r.reached);
                        let checked = eng.check_inductive(&r.reached, &badb).unwrap_or(false);
                        let mut f = Finding::new(
                            if checked { Verdict::Holds } else { Verdict::Unknown },
                            "BDD reachability",
                            if checked {
                                format!("no reachable state violates it ({} scans to the fixpoint)", r.rings.len())
                            } else {
                                "the reachable set failed its own inductiveness check".to_string()
                            },
                        );
                        f.states = Some(states);
                        f.invariant = Some((r.reached.size(), checked));
                        return f;
                    }
                    Err(g) => give_up_text(&g),
                },
                Err(g) => give_up_text(&g),
            }
        }
        Err(g) => give_up_text(&g),
    };
    // 5. What time is left: a deeper bounded search.
    match sat::bmc(&sys, bad, usize::MAX, budget.deadline) {
        sat::Bmc::Found(trace) => {
            let mut f = Finding::new(Verdict::Violated, "bounded model checking", "");
            f.trace = Some(trace);
            f
        }
        sat::Bmc::None { depth } => {
            let mut f = Finding::new(
                Verdict::Unknown,
                "bounded model checking",
                format!("no violation within {} scans ({reason})", group(depth.max(searched))),
            );
            f.depth = Some(depth.max(searched));
            f
        }
    }
}

/// Checks a reachability property.
pub fn reach(full: &System, goal: Lit, from_initial: bool, budget: &Budget, cache: &mut Cache) -> Finding {
    sat::set_deadline(Some(budget.deadline));
    let (sys, roots) = cache.reduce(full, &[goal]);
    let goal = roots[0];
    if from_initial {
        // EF goal: a path reaching it is a witness that it holds.
        if let sat::Bmc::Found(trace) =
            sat::bmc(&sys, goal, 12, budget.deadline.min(Instant::now() + Duration::from_millis(150)))
        {
            let mut f = Finding::new(Verdict::Holds, "bounded model checking", "reached from the initial situation");
            f.trace = Some(trace);
            return f;
        }
    }
    let eng = match cache.engine(&sys, budget) {
        Ok(e) => e,
        Err(g) => return unknown_reach(&sys, goal, from_initial, budget, &g),
    };
    let goalb = match eng.predicate(goal) {
        Ok(b) => b,
        Err(g) => return unknown_reach(&sys, goal, from_initial, budget, &g),
    };
    if !from_initial {
        // AG EF: the states that can reach the goal, backwards over the whole state space.
        // When they contain the initial state and no scan leaves them, they are an inductive
        // invariant and every reachable state can reach the goal.
        let all = eng.vars_true();
        if let Ok(can) = eng.can_reach(&goalb, &all) {
            let init = eng.init();
            if !init.and_not(&can).is_false() {
                // Even the initial state cannot reach the goal.
                return trapped_path(eng, &can, &init, budget);
            }
            if let Ok(true) = eng.closed(&can) {
                let mut f = Finding::new(
                    Verdict::Holds,
                    "BDD backward reachability",
                    "the states from which the goal can be reached contain the initial state and no scan leads out of them",
                );
                f.invariant = Some((can.size(), true));
                return f;
            }
            // Some state of the set can leave it: search forwards for a reachable trap.
            let target = can.not().and_not(&init);
            return match eng.reach(Some(&target)) {
                Ok(r) if r.hit.is_some() => {
                    let mut f = Finding::new(
                        Verdict::Violated,
                        "BDD reachability",
                        "a reachable situation cannot reach the goal any more",
                    );
                    f.trace = eng.path_to(&r, &target);
                    f
                }
                Ok(r) => {
                    let states = eng.count(&r.reached);
                    let mut f = Finding::new(
                        Verdict::Holds,
                        "BDD reachability",
                        format!("from each of the {} reachable states the goal can be reached", fmt_states(states)),
                    );
                    f.states = Some(states);
                    f
                }
                Err(g) => {
                    Finding::new(Verdict::Unknown, "BDD reachability", format!("not decided: {}", give_up_text(&g)))
                }
            };
        }
    }
    let r = match eng.reach(None) {
        Ok(r) => r,
        Err(g) => return unknown_reach(&sys, goal, from_initial, budget, &g),
    };
    let states = eng.count(&r.reached);
    if from_initial {
        return match eng.path_to(&r, &goalb) {
            Some(trace) => {
                let mut f = Finding::new(Verdict::Holds, "BDD reachability", "reached from the initial situation");
                f.trace = Some(trace);
                f.states = Some(states);
                f
            }
            None => {
                let mut f = Finding::new(
                    Verdict::Violated,
                    "BDD reachability",
                    format!(
                        "no reachable situation satisfies the goal ({} reachable states of what the goal depends on)",
                        fmt_states(states)
                    ),
                );
                f.states = Some(states);
                f
            }
        };
    }
    let can = match eng.can_reach(&goalb, &r.reached) {
        Ok(b) => b,
        Err(g) => return unknown_reach(&sys, goal, from_initial, budget, &g),
    };
    let trapped = r.reached.and_not(&can);
    if trapped.is_false() {
        let mut f = Finding::new(
            Verdict::Holds,
            "BDD reachability",
            format!("from each of the {} reachable states the goal can be reached", fmt_states(states)),
        );
        f.states = Some(states);
        return f;
    }
    let mut f = Finding::new(
        Verdict::Violated,
        "BDD reachability",
        format!(
            "{} of the {} reachable states cannot reach the goal any more",
            fmt_states(eng.count(&trapped)),
            fmt_states(states)
        ),
    );
    f.states = Some(states);
    f.trace = eng.path_to(&r, &trapped.and_not(&eng.init()));
    f
}

/// AG EF fails already from the start: the shortest path to any state after scan 0.
fn trapped_path(eng: &BddEngine, can: &biodivine_lib_bdd::Bdd, init: &biodivine_lib_bdd::Bdd, _b: &Budget) -> Finding {
    let target = can.not().and_not(init);
    let mut f = Finding::new(
        Verdict::Violated,
        "BDD backward reachability",
        "the goal cannot be reached from the initial situation",
    );
    if let Ok(r) = eng.reach(Some(&target)) {
        f.trace = eng.path_to(&r, &target);
    }
    f
}

fn unknown_reach(sys: &System, goal: Lit, from_initial: bool, budget: &Budget, g: &GiveUp) -> Finding {
    if from_initial {
        if let sat::Bmc::Found(trace) = sat::bmc(sys, goal, usize::MAX, budget.deadline) {
            let mut f = Finding::new(Verdict::Holds, "bounded model checking", "reached from the initial situation");
            f.trace = Some(trace);
            return f;
        }
    }
    Finding::new(Verdict::Unknown, "BDD reachability", format!("not decided: {}", give_up_text(g)))
}

/// A count with thousands separators (`2,000`).
pub fn group(n: usize) -> String {
    let s = n.to_string();
    let mut out = String::new();
    for (i, c) in s.chars().enumerate() {
        if i > 0 && (s.len() - i).is_multiple_of(3) {
            out.push(',');
        }
        out.push(c);
    }
    out
}

/// A state count: exact below 10^15, else in scientific notation.
pub fn fmt_states(s: f64) -> String {
    if s < 1e15 {
        group(s.round() as usize)
    } else {
        format!("{s:.3e}")
    }
}

/// Checks one compiled property.
pub fn check(full: &System, signal: &Signal, strengthen: &Invariant, budget: &Budget, cache: &mut Cache) -> Finding {
    match signal {
        Signal::Safety { bad } => safety(full, *bad, strengthen, budget, cache),
        Signal::Reach { goal, from_initial } => reach(full, *goal, *from_initial, budget, cache),
    }
}
