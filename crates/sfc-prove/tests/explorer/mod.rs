//! An explicit-state explorer written apart from the prover: it runs the simulator itself on
//! every input combination, breadth first, keeping each distinct state once (the
//! simulator's own state key), and evaluates the properties with the scenario conditions. It
//! decides, up to a depth, whether and after which scan each property is first violated.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::indexing_slicing)] // test code: a panic is a failed test

use sfc_prove::props::{Bound, Kind, PropertyFile};
use sfc_sim::condition::Condition;
use sfc_sim::{Simulation, Value};
use std::collections::HashSet;

/// What the explorer found for one property.
#[derive(Debug, Clone, PartialEq)]
pub enum Found {
    /// First violated after this scan (a shortest run).
    ViolatedAt(usize),
    /// Not violated within this many scans (the depth asked for, or less when the state budget
    /// ran out first).
    NotWithin(usize),
    /// Reached (for `reachable … from_initial`) after this scan.
    ReachedAt(usize),
    /// This kind of property is not explored.
    Skipped,
    /// Too many input values to try.
    TooBig,
}

#[derive(Clone)]
struct Node {
    sim_state: sfc_sim::Snapshot,
    /// Per response property: (trigger value after the previous scan, waiting scans of the
    /// oldest pending trigger).
    monitors: Vec<(bool, Option<u64>)>,
}

enum Check {
    Always(Condition),
    Never(Condition),
    Response { after: Condition, expect: Condition, n: u64, slot: usize },
    ReachFrom(Condition),
    Range { name: String, lo: i128, hi: i128 },
    Fault,
    None,
}

/// The candidate values of a free input: BOOL both, small integer ranges every value.
fn domain(sim: &Simulation, name: &str, file: &PropertyFile) -> Option<Vec<Value>> {
    let ty = sim.type_of(name)?;
    if ty.is_bool() {
        return Some(vec![Value::Bool(false), Value::Bool(true)]);
    }
    let (lo, hi) = file
        .ranges
        .iter()
        .find(|r| r.name.text.eq_ignore_ascii_case(name))
        .map(|r| (r.lo, r.hi))
        .or_else(|| ty.int_range())?;
    if hi - lo > 15 {
        return None;
    }
    Some((lo..=hi).map(|v| Value::Int(v as i64)).collect())
}

/// Explores the chart's state space up to `depth` scans under `profile`. `inputs`: the free inputs (as the
/// prover reports them). Returns one result per property of `names` (the prover's order:
/// `no runtime error`, ranges, then the file's properties).
pub fn explore(
    chart_name: &str,
    chart_text: &str,
    pou: &str,
    period: i64,
    file: &PropertyFile,
    inputs: &[String],
    names: &[String],
    depth: usize,
    max_states: usize,
    profile: sfc_sim::Profile,
) -> Vec<Found> {
    let opts = sfc_sim::SimOptions { period, profile };
    let Ok(sim) = Simulation::from_source(chart_name, chart_text, Some(pou), opts) else {
        return vec![Found::Skipped; names.len()];
    };
    // Inputs and their values.
    let mut doms: Vec<(String, Vec<Value>)> = Vec::new();
    for i in inputs {
        match domain(&sim, i, file) {
            Some(d) => doms.push((i.clone(), d)),
            None => return vec![Found::TooBig; names.len()],
        }
    }
    let assume: Vec<Condition> = match file.assume.iter().map(|a| Condition::parse(&a.src.text, &sim)).collect() {
        Ok(v) => v,
        Err(_) => return vec![Found::Skipped; names.len()],
    };
    // The checks, in the prover's order of names.
    let mut responses = 0;
    let mut checks = Vec::new();
    for n in names {
        let c = if n == "no runtime error" {
            Check::Fault
        } else if let Some(rest) = n.strip_prefix("range of ") {
            let var = rest.split(" (").next().unwrap_or("").to_string();
            match file.ranges.iter().find(|r| r.name.text.eq_ignore_ascii_case(&var)) {
                Some(r) => Check::Range { name: var, lo: r.lo, hi: r.hi },
                None => Check::None,
            }
        } else {
            match file.properties.iter().find(|p| &p.name == n) {
                None => Check::None,
                Some(p) => {
                    let cond = |t: &str| Condition::parse(t, &sim).ok();
                    match &p.kind {
                        Kind::Always(x) => cond(&x.src.text).map_or(Check::None, Check::Always),
                        Kind::Never(x) => cond(&x.src.text).map_or(Check::None, Check::Never),
                        Kind::Response { after, expect, bound } => {
                            let n = match bound {
                                Bound::Scans(n) => *n,
                                Bound::Time(t) => (*t / period) as u64,
                            };
                            match (cond(&after.src.text), cond(&expect.src.text)) {
                                (Some(a), Some(e)) => {
                                    responses += 1;
                                    Check::Response { after: a, expect: e, n, slot: responses - 1 }
                                }
                                _ => Check::None,
                            }
                        }
                        Kind::Reachable { goal, from_initial: true } => {
                            cond(&goal.src.text).map_or(Check::None, Check::ReachFrom)
                        }
                        Kind::Reachable { .. } => Check::None,
                    }
                }
            }
        };
        checks.push(c);
    }
    let mut result: Vec<Option<Found>> =
        checks.iter().map(|c| if matches!(c, Check::None) { Some(Found::Skipped) } else { None }).collect();
    let mut frontier = vec![Node { sim_state: sim.snapshot(), monitors: vec![(false, None); responses] }];
    let mut sim = sim;
    // Every combination of input values.
    let combos: usize = doms.iter().map(|(_, d)| d.len()).product();
    // Every state seen so far, at any depth: breadth first, a state met again later has
    // nothing new to show (its successors were reached as early or earlier).
    let mut seen: HashSet<String> = HashSet::new();
    for scan in 0..depth {
        let mut next: Vec<Node> = Vec::new();
        for node in &frontier {
            for k in 0..combos {
                sim.restore(&node.sim_state);
                let mut rem = k;
                for (name, d) in &doms {
                    let v = d[rem % d.len()].clone();
                    rem /= d.len();
                    let _ = sim.set(name, v);
                }
                if !assume.iter().all(|a| a.eval(&sim).unwrap_or(false)) {
                    continue;
                }
                sim.scan();
                let mut monitors = node.monitors.clone();
                let mut left_range = false;
                for (i, c) in checks.iter().enumerate() {
                    let violated = match c {
                        Check::Always(p) => !p.eval(&sim).unwrap_or(true),
                        Check::Never(p) => p.eval(&sim).unwrap_or(false),
                        Check::Fault => sim.error().is_some(),
                        Check::Range { name, lo, hi } => {
                            let v = sim.get(name).and_then(|v| v.as_int()).unwrap_or(0) as i128;
                            let out = v < *lo || v > *hi;
                            left_range |= out;
                            out
                        }
                        Check::Response { after, expect, n, slot } => {
                            let a = after.eval(&sim).unwrap_or(false);
                            let x = expect.eval(&sim).unwrap_or(false);
                            let (prev, pending) = monitors[*slot];
                            let trig = a && !prev;
                            let new_pending = if x {
                                None
                            } else if let Some(age) = pending {
                                Some(age + 1)
                            } else if trig {
                                Some(0)
                            } else {
                                None
                            };
                            monitors[*slot] = (a, new_pending);
                            new_pending.is_some_and(|age| age >= *n)
                        }
                        Check::ReachFrom(g) => {
                            if result[i].is_none() && g.eval(&sim).unwrap_or(false) {
                                result[i] = Some(Found::ReachedAt(scan));
                            }
                            false
                        }
                        Check::None => false,
                    };
                    if violated && result[i].is_none() {
                        result[i] = Some(Found::ViolatedAt(scan));
                    }
                }
                // A run that faulted or left a range has no next scan (as in the prover).
                if sim.error().is_some() || left_range {
                    continue;
                }
                // The inputs' values after the scan do not matter (the next scan sets every one
                // of them anew, and the properties have been evaluated): with a canonical value
                // states that differ only there are one state.
                for (name, d) in &doms {
                    let _ = sim.set(name, d[0].clone());
                }
                let key = format!("{}{:?}", sim.state_key(), monitors);
                if seen.insert(key) {
                    next.push(Node { sim_state: sim.snapshot(), monitors });
                }
            }
        }
        if seen.len() > max_states {
            // Every state after scans 0..=scan was checked: what is not decided yet is not
            // violated (reached) within scan + 1 scans.
            return result.into_iter().map(|r| r.unwrap_or(Found::NotWithin(scan + 1))).collect();
        }
        frontier = next;
        if result.iter().all(Option::is_some) || frontier.is_empty() {
            break;
        }
    }
    result.into_iter().map(|r| r.unwrap_or(Found::NotWithin(depth))).collect()
}

#[allow(dead_code)]
pub fn describe(f: &Found) -> String {
    format!("{f:?}")
}
