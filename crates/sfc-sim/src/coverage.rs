//! Coverage of a set of runs: which steps were ever active and which transitions ever fired,
//! merged over the runs of one chart file and POU.
//!
//! The engine counts activations and firings as they happen
//! ([`Simulation::coverage_counts`]); a run's coverage is read once at its end
//! ([`Coverage::record_run`]), so coverage costs nothing per scan.

use crate::{ScanRecord, Simulation};
use std::collections::HashMap;

/// A fixed number of bits: one per step or transition.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct Bits {
    words: Vec<u64>,
    len: usize,
}

impl Bits {
    /// `len` bits, all clear.
    pub fn new(len: usize) -> Bits {
        Bits { words: vec![0; len.div_ceil(64)], len }
    }
    pub fn len(&self) -> usize {
        self.len
    }
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }
    /// Bit `i` (false beyond the end).
    pub fn get(&self, i: usize) -> bool {
        i < self.len && self.words[i / 64] >> (i % 64) & 1 == 1
    }
    /// Sets bit `i` (`i < len`).
    pub fn set(&mut self, i: usize) {
        assert!(i < self.len, "bit {i} of {}", self.len);
        self.words[i / 64] |= 1 << (i % 64);
    }
    /// Appends one bit.
    pub fn push(&mut self, b: bool) {
        if self.len.is_multiple_of(64) {
            self.words.push(0);
        }
        self.len += 1;
        if b {
            self.set(self.len - 1);
        }
    }
    /// The number of set bits.
    pub fn count_ones(&self) -> usize {
        self.words.iter().map(|w| w.count_ones() as usize).sum()
    }
    /// Every bit, in order.
    pub fn iter(&self) -> impl Iterator<Item = bool> + '_ {
        (0..self.len).map(|i| self.get(i))
    }
    /// The indices of the set bits, ascending.
    pub fn ones(&self) -> impl Iterator<Item = usize> + '_ {
        self.iter().enumerate().filter(|(_, b)| *b).map(|(i, _)| i)
    }
}

impl std::ops::Index<usize> for Bits {
    type Output = bool;
    fn index(&self, i: usize) -> &bool {
        assert!(i < self.len, "bit {i} of {}", self.len);
        if self.get(i) {
            &true
        } else {
            &false
        }
    }
}

/// Steps ever active and transitions ever fired in the runs of one chart (file and POU).
#[derive(Debug, Clone, Default)]
pub struct Coverage {
    /// Identity of the chart for merging: the canonical chart path and the POU (upper case).
    pub key: String,
    /// The chart file as shown in reports.
    pub chart: String,
    /// Declared name of the POU.
    pub pou: String,
    /// Every step (qualified), in declaration order.
    pub steps: Vec<String>,
    /// Every transition (qualified), in declaration order.
    pub transitions: Vec<String>,
    /// Bit `i`: `steps[i]` was active after some scan.
    pub step_hit: Bits,
    /// Bit `i`: `transitions[i]` fired in some scan.
    pub transition_hit: Bits,
    /// Activations of each step over the runs (at least 1 for a step that was active without an
    /// activation: an initial step held by SFCInit; from [`Coverage::record`], at least 1 per
    /// hit).
    pub step_count: Vec<u64>,
    /// Firings of each transition over the runs.
    pub transition_count: Vec<u64>,
    /// Number of runs merged.
    pub runs: usize,
    step_index: HashMap<String, usize>,
    transition_index: HashMap<String, usize>,
}

impl PartialEq for Coverage {
    fn eq(&self, other: &Self) -> bool {
        self.key == other.key
            && self.chart == other.chart
            && self.pou == other.pou
            && self.steps == other.steps
            && self.transitions == other.transitions
            && self.step_hit == other.step_hit
            && self.transition_hit == other.transition_hit
            && self.step_count == other.step_count
            && self.transition_count == other.transition_count
            && self.runs == other.runs
    }
}

fn percent(hit: usize, total: usize) -> usize {
    if total == 0 {
        return 100;
    }
    let p = (hit * 100 + total / 2) / total;
    // Never round a partial coverage up to 100 % or a non-zero one down to 0 %.
    if hit < total {
        p.min(99).max(usize::from(hit > 0))
    } else {
        p
    }
}

impl Coverage {
    /// An empty coverage (one run, nothing hit yet) over the given universe.
    pub fn new(
        key: impl Into<String>,
        chart: impl Into<String>,
        pou: impl Into<String>,
        steps: Vec<String>,
        transitions: Vec<String>,
    ) -> Coverage {
        let step_index = steps.iter().enumerate().map(|(i, s)| (s.clone(), i)).collect();
        let transition_index = transitions.iter().enumerate().map(|(i, s)| (s.clone(), i)).collect();
        Coverage {
            key: key.into(),
            chart: chart.into(),
            pou: pou.into(),
            step_hit: Bits::new(steps.len()),
            transition_hit: Bits::new(transitions.len()),
            step_count: vec![0; steps.len()],
            transition_count: vec![0; transitions.len()],
            steps,
            transitions,
            runs: 1,
            step_index,
            transition_index,
        }
    }

    /// An empty coverage of the steps and transitions of a simulation.
    pub fn of(sim: &Simulation, key: impl Into<String>, chart: impl Into<String>) -> Coverage {
        Coverage::new(key, chart, sim.pou_name(), sim.step_names(), sim.transition_names())
    }

    /// The coverage of a simulation's run so far, read from the engine's counters.
    pub fn of_run(sim: &Simulation, key: impl Into<String>, chart: impl Into<String>) -> Coverage {
        let mut c = Coverage::of(sim, key, chart);
        c.record_run(sim);
        c
    }

    /// Adds the activations and firings a simulation counted ([`Simulation::coverage_counts`])
    /// to this coverage of the same simulation (made by [`Coverage::of`]).
    pub fn record_run(&mut self, sim: &Simulation) {
        let (steps, transitions) = sim.coverage_counts();
        for (i, n) in steps.into_iter().enumerate().filter(|(_, n)| *n > 0) {
            self.hit_step_at(i, n);
        }
        for (i, n) in transitions.into_iter().enumerate().filter(|(_, n)| *n > 0) {
            self.hit_transition_at(i, n);
        }
    }

    fn hit_step_at(&mut self, i: usize, n: u64) {
        if i < self.steps.len() && n > 0 {
            self.step_hit.set(i);
            self.step_count[i] += n;
        }
    }

    fn hit_transition_at(&mut self, i: usize, n: u64) {
        if i < self.transitions.len() && n > 0 {
            self.transition_hit.set(i);
            self.transition_count[i] += n;
        }
    }

    fn hit_step(&mut self, name: &str, n: u64) {
        match self.step_index.get(name) {
            Some(&i) => self.hit_step_at(i, n),
            None => {
                self.step_index.insert(name.to_string(), self.steps.len());
                self.steps.push(name.to_string());
                self.step_hit.push(n > 0);
                self.step_count.push(n);
            }
        }
    }

    fn hit_transition(&mut self, name: &str, n: u64) {
        match self.transition_index.get(name) {
            Some(&i) => self.hit_transition_at(i, n),
            None => {
                self.transition_index.insert(name.to_string(), self.transitions.len());
                self.transitions.push(name.to_string());
                self.transition_hit.push(n > 0);
                self.transition_count.push(n);
            }
        }
    }

    /// Counts the active steps and fired transitions of one scan (for records that did not come
    /// from a run of this crate's engine; a run's coverage is better read at its end with
    /// [`Coverage::record_run`]).
    pub fn record(&mut self, record: &ScanRecord) {
        for s in &record.active {
            match self.step_index.get(s.as_str()) {
                Some(&i) if self.step_hit.get(i) => {}
                _ => self.hit_step(s, 1),
            }
        }
        for t in &record.fired {
            self.hit_transition(t, 1);
        }
    }

    /// Adds the hits of another run of the same chart (names unknown here are added).
    pub fn merge(&mut self, other: &Coverage) {
        if self.runs == 0 && self.steps.is_empty() && self.transitions.is_empty() {
            *self = other.clone();
            return;
        }
        // A hit counts at least once, also when a caller set the bit without a count.
        for (i, s) in other.steps.iter().enumerate() {
            let n = if other.step_hit.get(i) { other.step_count.get(i).copied().unwrap_or(0).max(1) } else { 0 };
            self.hit_step(s, n);
        }
        for (i, t) in other.transitions.iter().enumerate() {
            let n = if other.transition_hit.get(i) {
                other.transition_count.get(i).copied().unwrap_or(0).max(1)
            } else {
                0
            };
            self.hit_transition(t, n);
        }
        self.runs += other.runs;
    }

    pub fn steps_hit(&self) -> usize {
        self.step_hit.count_ones()
    }

    pub fn transitions_hit(&self) -> usize {
        self.transition_hit.count_ones()
    }

    /// Steps never active, in declaration order.
    pub fn never_active(&self) -> Vec<&str> {
        self.steps.iter().zip(self.step_hit.iter()).filter(|(_, h)| !*h).map(|(s, _)| s.as_str()).collect()
    }

    /// Transitions never fired, in declaration order.
    pub fn never_fired(&self) -> Vec<&str> {
        self.transitions.iter().zip(self.transition_hit.iter()).filter(|(_, h)| !*h).map(|(s, _)| s.as_str()).collect()
    }

    /// `steps 7/9 (78%), transitions 10/12 (83%)`.
    pub fn summary(&self) -> String {
        let (s, st) = (self.steps_hit(), self.steps.len());
        let (t, tt) = (self.transitions_hit(), self.transitions.len());
        format!("steps {s}/{st} ({}%), transitions {t}/{tt} ({}%)", percent(s, st), percent(t, tt))
    }

    /// The report of `sfc test --coverage` for this chart:
    ///
    /// ```text
    /// examples/tank/tank.st (Tank): steps 7/9 (78%), transitions 10/12 (83%)
    ///   never active: Drain, Alarm
    ///   never fired: T7, T9
    /// ```
    pub fn report(&self) -> String {
        let mut out = format!("{} ({}): {}", self.chart, self.pou, self.summary());
        let na = self.never_active();
        if !na.is_empty() {
            out.push_str(&format!("\n  never active: {}", na.join(", ")));
        }
        let nf = self.never_fired();
        if !nf.is_empty() {
            out.push_str(&format!("\n  never fired: {}", nf.join(", ")));
        }
        out
    }
}

/// Coverage of several charts, merged by [`Coverage::key`], in order of first appearance.
#[derive(Debug, Clone, Default)]
pub struct CoverageSet {
    pub charts: Vec<Coverage>,
}

impl CoverageSet {
    pub fn new() -> Self {
        CoverageSet::default()
    }
    /// Merges one run into the coverage of its chart.
    pub fn add(&mut self, run: &Coverage) {
        match self.charts.iter_mut().find(|c| c.key == run.key) {
            Some(c) => c.merge(run),
            None => self.charts.push(run.clone()),
        }
    }
    /// The reports of every chart, one after the other.
    pub fn report(&self) -> String {
        self.charts.iter().map(Coverage::report).collect::<Vec<_>>().join("\n")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn names(v: &[&str]) -> Vec<String> {
        v.iter().map(|s| s.to_string()).collect()
    }

    fn rec(active: &[&str], fired: &[&str]) -> ScanRecord {
        ScanRecord { active: names(active), fired: names(fired), ..Default::default() }
    }

    #[test]
    fn counts_and_merges() {
        let universe = || Coverage::new("k", "c.st", "P", names(&["S1", "S2", "S3"]), names(&["T1", "T2", "T3", "T4"]));
        let mut a = universe();
        a.record(&rec(&["S1"], &[]));
        a.record(&rec(&["S2"], &["T1"]));
        assert_eq!(a.summary(), "steps 2/3 (67%), transitions 1/4 (25%)");
        assert_eq!(a.never_active(), vec!["S3"]);
        let mut b = universe();
        b.record(&rec(&["S3"], &["T2", "T4"]));
        let mut set = CoverageSet::new();
        set.add(&a);
        set.add(&b);
        assert_eq!(set.charts.len(), 1);
        let c = &set.charts[0];
        assert_eq!(c.runs, 2);
        assert_eq!(c.summary(), "steps 3/3 (100%), transitions 3/4 (75%)");
        assert_eq!(c.report(), "c.st (P): steps 3/3 (100%), transitions 3/4 (75%)\n  never fired: T3");
        let other = Coverage::new("k2", "d.st", "Q", names(&["A"]), vec![]);
        set.add(&other);
        assert_eq!(set.charts.len(), 2);
        assert!(set.report().contains("d.st (Q): steps 0/1 (0%), transitions 0/0 (100%)\n  never active: A"));
    }

    #[test]
    fn percentages_never_lie_at_the_edges() {
        assert_eq!(percent(7, 9), 78);
        assert_eq!(percent(999, 1000), 99);
        assert_eq!(percent(1, 1000), 1);
        assert_eq!(percent(0, 5), 0);
        assert_eq!(percent(5, 5), 100);
    }
}
