//! Flattening a chart with simultaneous branches into one ATMT/EATMT automaton.
//!
//! Each reachable situation (set of active steps) of the chart becomes a state; state 0 is the
//! initial situation, the others are numbered in the order they are first met, breadth first,
//! following the rules of each state in table order. Step tags are not used.
//!
//! **What is supported, exactly.** The guards are the chart's condition inputs, free in every
//! scan. From a situation `M`, the `iec` evolution (`semantics.md`: all enabled transitions whose
//! guard is true, accepted in priority order with disjoint pre-sets, fired together) maps each
//! valuation of the inputs the enabled transitions test to a successor situation, or to "no
//! change". The block can only express a *decision list*: the rules of a state, tested in
//! order, each on ONE input (EATMT: or its negation), the first true one wins, none = stay.
//! For every reachable situation the flattening computes that map over all valuations (at most
//! 16 distinct inputs per situation: 65,536 valuations) and synthesises a decision list that
//! reproduces it exactly (the greedy construction of Rivest, which finds a list whenever one
//! exists: take the first literal, in the priority order of the transitions, on whose
//! valuations the map is constant and not "stay"; remove them; repeat until only "stay" is
//! left). So the table behaves exactly like the chart under `iec`, scan for scan, for every
//! input sequence. That covers:
//! - situations in which the enabled transitions all conflict (share a step): the rules are
//!   simply the transitions in priority order;
//! - parallel branches that wait on the same input, or (EATMT) on an input and its negation;
//! - branches that are not enabled at the same time (one waits for a step of the other).
//!
//! When two transitions with different inputs can fire in the same scan (typically two parallel
//! branches waiting for `C1` and `C2`), the successor depends on `C1 AND C2`, which no rule can
//! test: the flattening refuses with SFC0411, naming the transitions and the firing sequence
//! that reaches the situation, rather than producing an automaton that would interleave the two
//! firings over two scans (that differs from the chart whenever both inputs are TRUE together).
//! A list that would need a rule leading back to the same state without any firing (to shadow
//! later rules) is refused the same way: such a rule would restart the block's timeout.
//!
//! **Timeouts.** The block has one supervision timer per state, restarted by every state change.
//! A flattened state gets the smallest `sfc.timeout` among its steps (0 if none has one): the
//! first supervision that can expire. Because a move of one parallel branch changes the state,
//! it restarts the supervision of the steps of the other branches too; a note says so.

use super::Rule;
use sfc_diagnostics::{Diagnostic, Witness};
use sfc_model::{condition_input, Chart, Limits, StepId, Target, TransitionId};
use std::collections::HashMap;

/// At most this many distinct condition inputs may be tested by the transitions enabled in one
/// situation (the flattening enumerates their valuations).
pub const MAX_INPUTS_PER_SITUATION: usize = 16;

/// The flattened automaton.
#[derive(Debug, Clone, PartialEq)]
pub struct Flattened {
    /// The steps of each state (sorted step ids), indexed by state number.
    pub states: Vec<Vec<StepId>>,
    /// The rules, by state, in the order the block tests them.
    pub rules: Vec<Rule>,
    /// The timeout of each state, µs (0 = none).
    pub timeouts: Vec<i64>,
}

impl Flattened {
    /// A note listing the situation each state number stands for.
    pub fn notes(&self, chart: &Chart) -> Vec<Diagnostic> {
        let mut d = Diagnostic::note_diag(
            "SFC0415",
            chart.name_span,
            format!(
                "chart `{}` was flattened into {} states (one per reachable situation)",
                chart.pou,
                self.states.len()
            ),
        )
        .with_element(&chart.pou);
        for (i, s) in self.states.iter().enumerate() {
            d = d.with_note(format!("state {i} = {}", situation(chart, s)));
        }
        d = d.with_note(
            "a state's timeout is the smallest sfc.timeout of its steps; every state change restarts it, \
             also a move of another parallel branch",
        );
        if chart.steps.iter().any(|s| s.tag.is_some()) {
            d = d.with_note("step tags are not used by the flattening: states are numbered as listed here");
        }
        vec![d]
    }
}

/// `{A, B}` with the declared step names.
fn situation(chart: &Chart, steps: &[StepId]) -> String {
    let names: Vec<&str> = steps.iter().map(|&s| chart.steps[s].name.as_str()).collect();
    format!("{{{}}}", names.join(", "))
}

/// A literal: a position in the situation's input list and whether it is negated.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
struct Lit {
    pos: usize,
    negated: bool,
}

impl Lit {
    fn holds(self, valuation: u32) -> bool {
        ((valuation >> self.pos) & 1 == 1) != self.negated
    }
}

/// "No transition fires" in the map of a situation.
const STAY: u32 = u32::MAX;

/// Flattens `chart` (see the module doc). The caller has checked the target rules other than
/// the state count, the AND branches and the tags.
pub fn flatten(chart: &Chart, target: Target, limits: Limits) -> Result<Flattened, Vec<Diagnostic>> {
    let mut order: Vec<TransitionId> = (0..chart.transitions.len()).collect();
    order.sort_by_key(|&i| match chart.transitions[i].priority {
        Some(p) => (0u8, p, i),
        None => (1u8, 0, i),
    });
    let pre: Vec<Vec<StepId>> = chart.transitions.iter().map(|t| sorted(&t.from)).collect();
    let post: Vec<Vec<StepId>> = chart.transitions.iter().map(|t| sorted(&t.to)).collect();
    let inputs: Vec<Option<(u32, bool)>> =
        chart.transitions.iter().map(|t| condition_input(&t.condition, target).map(|c| (c.index, c.negated))).collect();

    let mut states: Vec<Vec<StepId>> = vec![sorted(&chart.initial_steps())];
    let mut index: HashMap<Vec<StepId>, u32> = HashMap::new();
    index.insert(states[0].clone(), 0);
    // How each state was first reached: (previous state, transitions fired), for witnesses.
    let mut reached: Vec<Option<(u32, Vec<TransitionId>)>> = vec![None];
    let mut rules: Vec<Rule> = Vec::new();
    let mut k = 0;
    while k < states.len() {
        let m = states[k].clone();
        let active = |s: &StepId| m.binary_search(s).is_ok();
        let enabled: Vec<TransitionId> = order
            .iter()
            .copied()
            .filter(|&t| inputs[t].is_some() && !pre[t].is_empty() && pre[t].iter().all(active))
            .collect();
        // The distinct inputs tested, in priority order of first use.
        let mut vars: Vec<u32> = Vec::new();
        for &t in &enabled {
            if let Some((i, _)) = inputs[t] {
                if !vars.contains(&i) {
                    vars.push(i);
                }
            }
        }
        if vars.len() > MAX_INPUTS_PER_SITUATION {
            return Err(vec![Diagnostic::error(
                "SFC0414",
                chart.name_span,
                format!(
                    "in the situation {} the enabled transitions test {} different inputs; flattening \
                     handles at most {MAX_INPUTS_PER_SITUATION} per situation",
                    situation(chart, &m),
                    vars.len()
                ),
            )
            .with_element(&chart.pou)
            .with_witness(Witness::Firing(witness(chart, &reached, k as u32)))]);
        }
        let lit_of = |t: TransitionId| -> Lit {
            let (i, negated) = inputs[t].unwrap_or((0, false));
            Lit { pos: vars.iter().position(|&v| v == i).unwrap_or(0), negated }
        };
        // The map: valuation -> successor (index into `succ`) or STAY.
        let n = 1u32 << vars.len();
        let mut succ: Vec<(Vec<StepId>, Vec<TransitionId>)> = Vec::new();
        let mut label: Vec<u32> = Vec::with_capacity(n as usize);
        for v in 0..n {
            let fired = accept(&enabled, &pre, |t| lit_of(t).holds(v));
            if fired.is_empty() {
                label.push(STAY);
                continue;
            }
            let next = successor(&m, &fired, &pre, &post);
            let id = match succ.iter().position(|(s, _)| *s == next) {
                Some(i) => i,
                None => {
                    succ.push((next, fired));
                    succ.len() - 1
                }
            };
            label.push(id as u32);
        }
        // Candidate literals: each enabled transition's own, in priority order, then (EATMT)
        // the complements.
        let mut cands: Vec<Lit> = Vec::new();
        for &t in &enabled {
            let l = lit_of(t);
            if !cands.contains(&l) {
                cands.push(l);
            }
        }
        if target == Target::Eatmt {
            for pos in 0..vars.len() {
                for negated in [false, true] {
                    let l = Lit { pos, negated };
                    if !cands.contains(&l) {
                        cands.push(l);
                    }
                }
            }
        }
        let mut remaining: Vec<u32> = (0..n).collect();
        loop {
            if remaining.iter().all(|&v| label[v as usize] == STAY) {
                break;
            }
            let pick = cands.iter().copied().find_map(|l| {
                let mut lab = None;
                for &v in &remaining {
                    if !l.holds(v) {
                        continue;
                    }
                    match lab {
                        None => lab = Some(label[v as usize]),
                        Some(x) if x == label[v as usize] => {}
                        Some(_) => return None,
                    }
                }
                lab.filter(|&x| x != STAY).map(|x| (l, x))
            });
            let Some((lit, to)) = pick else {
                let why =
                    Why { m: &m, remaining: &remaining, label: &label, succ: &succ, vars: &vars, enabled: &enabled };
                return Err(vec![refusal(chart, target, &why, &reached, k as u32, &lit_of)]);
            };
            let (next, fired) = &succ[to as usize];
            let id = match index.get(next) {
                Some(&i) => i,
                None => {
                    let i = states.len() as u32;
                    if states.len() >= (limits.states as usize).min(super::MAX_STATE_NUMBERS) {
                        return Err(vec![Diagnostic::error(
                            "SFC0412",
                            chart.name_span,
                            format!(
                                "flattening `{}` gives more than {} states: the situation {} would be state {i}",
                                chart.pou,
                                states.len(),
                                situation(chart, next)
                            ),
                        )
                        .with_element(&chart.pou)
                        .with_note("the limit is the block's state count (`--nstep` overrides it)")
                        .with_witness(Witness::Firing({
                            let mut w = witness(chart, &reached, k as u32);
                            w.extend(fired.iter().map(|&t| chart.transitions[t].name.clone()));
                            w
                        }))]);
                    }
                    states.push(next.clone());
                    index.insert(next.clone(), i);
                    reached.push(Some((k as u32, fired.clone())));
                    i
                }
            };
            let code = if lit.negated { 1000 + vars[lit.pos] } else { vars[lit.pos] };
            rules.push(Rule { state: k as u32, condition: code, next: id });
            remaining.retain(|&v| !lit.holds(v));
        }
        k += 1;
    }
    if rules.len() as u64 > u64::from(limits.rules) {
        return Err(vec![Diagnostic::error(
            "SFC0413",
            chart.name_span,
            format!(
                "the flattened automaton of `{}` has {} rules, more than the {} of the block",
                chart.pou,
                rules.len(),
                limits.rules
            ),
        )
        .with_element(&chart.pou)
        .with_note("the limit is the block's rule count (`--ntr` overrides it)")]);
    }
    let timeouts = states
        .iter()
        .map(|s| s.iter().filter_map(|&st| chart.steps[st].timeout).filter(|&t| t > 0).min().unwrap_or(0))
        .collect();
    Ok(Flattened { states, rules, timeouts })
}

fn sorted(v: &[StepId]) -> Vec<StepId> {
    let mut v = v.to_vec();
    v.sort_unstable();
    v.dedup();
    v
}

/// Step 4 of `semantics.md`: walk the true transitions in priority order, accept those whose
/// pre-set shares no step with an accepted one. Returns them in declaration order.
fn accept(enabled: &[TransitionId], pre: &[Vec<StepId>], truth: impl Fn(TransitionId) -> bool) -> Vec<TransitionId> {
    let mut consumed: Vec<StepId> = Vec::new();
    let mut fired = Vec::new();
    for &t in enabled {
        if truth(t) && pre[t].iter().all(|s| !consumed.contains(s)) {
            consumed.extend(&pre[t]);
            fired.push(t);
        }
    }
    fired.sort_unstable();
    fired
}

/// Step 5: `(M \ ∪pre) ∪ ∪post`, sorted.
fn successor(m: &[StepId], fired: &[TransitionId], pre: &[Vec<StepId>], post: &[Vec<StepId>]) -> Vec<StepId> {
    let mut out: Vec<StepId> = m.iter().copied().filter(|s| !fired.iter().any(|&t| pre[t].contains(s))).collect();
    for &t in fired {
        out.extend(&post[t]);
    }
    sorted(&out)
}

/// The firing sequence (transition names) that first reached state `k`.
fn witness(chart: &Chart, reached: &[Option<(u32, Vec<TransitionId>)>], mut k: u32) -> Vec<String> {
    let mut parts: Vec<&[TransitionId]> = Vec::new();
    while let Some(Some((prev, fired))) = reached.get(k as usize) {
        parts.push(fired);
        k = *prev;
    }
    parts.iter().rev().flat_map(|f| f.iter().map(|&t| chart.transitions[t].name.clone())).collect()
}

/// The state of a failed decision-list synthesis.
struct Why<'a> {
    m: &'a [StepId],
    remaining: &'a [u32],
    label: &'a [u32],
    succ: &'a [(Vec<StepId>, Vec<TransitionId>)],
    vars: &'a [u32],
    enabled: &'a [TransitionId],
}

/// Why the map of situation `m` is no decision list: preferably two transitions with different
/// inputs that fire together.
fn refusal(
    chart: &Chart,
    target: Target,
    why: &Why<'_>,
    reached: &[Option<(u32, Vec<TransitionId>)>],
    k: u32,
    lit_of: &dyn Fn(TransitionId) -> Lit,
) -> Diagnostic {
    let Why { m, remaining, label, succ, vars, enabled } = *why;
    let together = remaining
        .iter()
        .filter(|&&v| label[v as usize] != STAY)
        .map(|&v| &succ[label[v as usize] as usize].1)
        .find(|f| f.len() >= 2 && f.iter().any(|&t| lit_of(t) != lit_of(f[0])));
    let input = |t: TransitionId| {
        let l = lit_of(t);
        let i = vars.get(l.pos).copied().unwrap_or(0);
        match (target, l.negated) {
            (Target::Atmt, _) => format!("C{i}"),
            (_, false) => format!("c{i}"),
            (_, true) => format!("NOT c{i}"),
        }
    };
    let w = Witness::Firing(witness(chart, reached, k));
    match together {
        Some(f) => {
            let a = &chart.transitions[f[0]];
            let names: Vec<String> =
                f.iter().map(|&t| format!("`{}` ({})", chart.transitions[t].name, input(t))).collect();
            let mut d = Diagnostic::error(
                "SFC0411",
                a.header_span,
                format!(
                    "in the situation {}, transitions {} can fire in the same scan: an ATMT/EATMT rule tests one \
                     condition, so the flattened automaton cannot follow the chart",
                    situation(chart, m),
                    names.join(" and ")
                ),
            )
            .with_element(&a.name)
            .with_note(
                "make the branches wait on the same input, make their conditions exclusive (EATMT: `c1` and \
                 `NOT c1`), or sequence them",
            )
            .with_witness(w);
            for &t in &f[1..] {
                d = d.with_label(chart.transitions[t].header_span, "fires in the same scan");
            }
            d
        }
        None => {
            let span = enabled.first().map_or(chart.name_span, |&t| chart.transitions[t].header_span);
            Diagnostic::error(
                "SFC0411",
                span,
                format!(
                    "the evolution from the situation {} cannot be written as rules that each test one condition",
                    situation(chart, m)
                ),
            )
            .with_element(&chart.pou)
            .with_witness(w)
        }
    }
}
