//! Coverage of a set of runs: which steps were ever active and which transitions ever fired,
//! merged over the runs of one chart file and POU.

use crate::{ScanRecord, Simulation};
use std::collections::HashMap;

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
    /// `step_hit[i]`: `steps[i]` was active after some scan.
    pub step_hit: Vec<bool>,
    /// `transition_hit[i]`: `transitions[i]` fired in some scan.
    pub transition_hit: Vec<bool>,
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
            step_hit: vec![false; steps.len()],
            transition_hit: vec![false; transitions.len()],
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

    fn hit_step(&mut self, name: &str) {
        match self.step_index.get(name) {
            Some(&i) => self.step_hit[i] = true,
            None => {
                self.step_index.insert(name.to_string(), self.steps.len());
                self.steps.push(name.to_string());
                self.step_hit.push(true);
            }
        }
    }

    fn hit_transition(&mut self, name: &str) {
        match self.transition_index.get(name) {
            Some(&i) => self.transition_hit[i] = true,
            None => {
                self.transition_index.insert(name.to_string(), self.transitions.len());
                self.transitions.push(name.to_string());
                self.transition_hit.push(true);
            }
        }
    }

    /// Counts the active steps and fired transitions of one scan.
    pub fn record(&mut self, record: &ScanRecord) {
        for s in &record.active {
            self.hit_step(s);
        }
        for t in &record.fired {
            self.hit_transition(t);
        }
    }

    /// Adds the hits of another run of the same chart (names unknown here are added).
    pub fn merge(&mut self, other: &Coverage) {
        if self.runs == 0 && self.steps.is_empty() && self.transitions.is_empty() {
            *self = other.clone();
            return;
        }
        for (s, &hit) in other.steps.iter().zip(&other.step_hit) {
            if hit {
                self.hit_step(s);
            } else if !self.step_index.contains_key(s) {
                self.step_index.insert(s.clone(), self.steps.len());
                self.steps.push(s.clone());
                self.step_hit.push(false);
            }
        }
        for (t, &hit) in other.transitions.iter().zip(&other.transition_hit) {
            if hit {
                self.hit_transition(t);
            } else if !self.transition_index.contains_key(t) {
                self.transition_index.insert(t.clone(), self.transitions.len());
                self.transitions.push(t.clone());
                self.transition_hit.push(false);
            }
        }
        self.runs += other.runs;
    }

    pub fn steps_hit(&self) -> usize {
        self.step_hit.iter().filter(|h| **h).count()
    }

    pub fn transitions_hit(&self) -> usize {
        self.transition_hit.iter().filter(|h| **h).count()
    }

    /// Steps never active, in declaration order.
    pub fn never_active(&self) -> Vec<&str> {
        self.steps.iter().zip(&self.step_hit).filter(|(_, h)| !**h).map(|(s, _)| s.as_str()).collect()
    }

    /// Transitions never fired, in declaration order.
    pub fn never_fired(&self) -> Vec<&str> {
        self.transitions.iter().zip(&self.transition_hit).filter(|(_, h)| !**h).map(|(s, _)| s.as_str()).collect()
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
