//! Bookkeeping of a [`super::Simulation`] that costs what changes: the bounded log of the
//! situations a run passed (time analysis) and the active steps kept in name order.

use super::state::ChartState;
use super::ScanSink;

/// At most this many changes of situation are recorded for the time analysis; later ones are
/// counted.
pub const MAX_SITUATIONS: usize = 100_000;
/// At most this many step changes are recorded in all.
pub(crate) const MAX_CHANGES: usize = 1 << 21;
/// Marks a start entry: the instance entered its initial situation (first call or SFCInit).
const START: u32 = u32::MAX;
/// High bit of a change entry: the step is active after the scan.
const ACTIVE: u32 = 1 << 31;

/// The sequence of situations of a run, recorded only in scans in which the active set
/// changed, as the steps those scans touched with their state after the scan.
#[derive(Debug, Clone)]
pub(crate) struct SituationLog {
    pub(crate) enabled: bool,
    /// `(time, end of its entries in changes)` of each recorded scan.
    scans: Vec<(i64, u32)>,
    /// `(chart instance, step | ACTIVE)`, or `(chart instance, START)`.
    changes: Vec<(u32, u32)>,
    /// Changes of situation not recorded because the log was full.
    pub(crate) dropped: u64,
}

/// How long a log is (to come back to it after a trial scan).
#[derive(Debug, Clone, Copy)]
pub(crate) struct LogMark {
    scans: usize,
    changes: usize,
    dropped: u64,
}

impl SituationLog {
    /// A log that records nothing until enabled.
    pub(crate) fn new() -> SituationLog {
        SituationLog { enabled: false, scans: Vec::new(), changes: Vec::new(), dropped: 0 }
    }

    pub(crate) fn mark(&self) -> LogMark {
        LogMark { scans: self.scans.len(), changes: self.changes.len(), dropped: self.dropped }
    }

    pub(crate) fn rewind(&mut self, m: LogMark) {
        self.scans.truncate(m.scans);
        self.changes.truncate(m.changes);
        self.dropped = m.dropped;
    }

    /// Records the scan at `time` if its active set changed.
    pub(crate) fn record(&mut self, time: i64, sink: &ScanSink, charts: &[ChartState]) {
        if !self.enabled || !sink.moved {
            return;
        }
        // The last recorded scan may pass the change budget by its own changes.
        if self.scans.len() >= MAX_SITUATIONS || self.changes.len() >= MAX_CHANGES {
            self.dropped += 1;
            return;
        }
        let state = |st: &ChartState, s: u32| if st.steps[s as usize].x { s | ACTIVE } else { s };
        let mut starts = sink.starts.iter().peekable();
        for (k, &(c, t)) in sink.fired.iter().enumerate() {
            while let Some(&&(at, sc)) = starts.peek() {
                if at as usize > k {
                    break;
                }
                self.start(sc, &charts[sc as usize]);
                starts.next();
            }
            let st = &charts[c as usize];
            let tr = &st.plan.tr[t as usize];
            if tr.is_link() {
                self.changes.push((c, state(st, tr.from)));
                self.changes.push((c, state(st, tr.to)));
            } else {
                for &s in st.plan.pre.get(t).iter().chain(st.plan.post.get(t)) {
                    self.changes.push((c, state(st, s)));
                }
            }
        }
        for &(_, sc) in starts {
            self.start(sc, &charts[sc as usize]);
        }
        self.scans.push((time, self.changes.len() as u32));
    }

    fn start(&mut self, c: u32, st: &ChartState) {
        self.changes.push((c, START));
        self.changes.extend(st.active.iter().map(|&s| (c, s | ACTIVE)));
    }

    /// The sequence of situations: `(time, active steps sorted by name)` for the initial
    /// situation and each change, the names given by `name(chart, step)`.
    pub(crate) fn sequence(&self, charts: &[ChartState], name: impl Fn(u32, u32) -> String) -> Vec<(i64, Vec<String>)> {
        let mut x: Vec<Vec<bool>> = charts.iter().map(|c| vec![false; c.steps.len()]).collect();
        let situation = |x: &Vec<Vec<bool>>| {
            let mut out = Vec::new();
            for (c, flags) in x.iter().enumerate() {
                for (s, &on) in flags.iter().enumerate() {
                    if on {
                        out.push(name(c as u32, s as u32));
                    }
                }
            }
            out.sort();
            out
        };
        let mut out: Vec<(i64, Vec<String>)> = Vec::new();
        let mut begin = 0usize;
        for &(time, end) in &self.scans {
            for &(c, e) in &self.changes[begin..end as usize] {
                let flags = &mut x[c as usize];
                if e == START {
                    flags.fill(false);
                } else {
                    flags[(e & !ACTIVE) as usize] = e & ACTIVE != 0;
                }
            }
            begin = end as usize;
            let now = situation(&x);
            if out.last().map(|l| &l.1) != Some(&now) {
                out.push((time, now));
            }
        }
        if out.is_empty() {
            out.push((0, Vec::new()));
        }
        out
    }
}

fn touched_by(st: &ChartState, t: u32) -> usize {
    st.plan.pre.get(t).len() + st.plan.post.get(t).len()
}

/// The active steps of every instance as ranks in the code-point order of their qualified
/// names, kept sorted from scan to scan: a scan that touched few steps patches the list, others
/// rebuild it.
#[derive(Debug, Clone)]
pub(crate) struct ActiveOrder {
    /// Rank of each step of each instance.
    pub(crate) rank: Vec<Vec<u32>>,
    /// Qualified step names by rank.
    pub(crate) names: Vec<String>,
    /// Ranks of the active steps, ascending, valid after scan `valid`.
    pub(crate) sorted: Vec<u32>,
    pub(crate) valid: Option<u64>,
}

/// A scan touching more steps than this rebuilds the sorted list instead of patching it.
const PATCH_LIMIT: usize = 32;

impl ActiveOrder {
    pub(crate) fn new(charts: &[ChartState]) -> ActiveOrder {
        let mut all: Vec<(String, u32, u32)> = Vec::new();
        for (c, st) in charts.iter().enumerate() {
            for (s, n) in st.plan.step_names.iter().enumerate() {
                all.push((st.qualify(n), c as u32, s as u32));
            }
        }
        all.sort();
        let mut rank: Vec<Vec<u32>> = charts.iter().map(|c| vec![0; c.steps.len()]).collect();
        for (r, (_, c, s)) in all.iter().enumerate() {
            rank[*c as usize][*s as usize] = r as u32;
        }
        ActiveOrder { rank, names: all.into_iter().map(|(n, _, _)| n).collect(), sorted: Vec::new(), valid: None }
    }

    /// Brings the sorted list up to date after scan `scan`, whose firings and starts are in
    /// `sink`.
    pub(crate) fn refresh(&mut self, scan: u64, sink: &ScanSink, charts: &[ChartState]) {
        if self.valid == Some(scan) {
            return;
        }
        let patchable = scan > 0
            && self.valid == Some(scan - 1)
            && sink.starts.is_empty()
            && sink.fired.iter().map(|&(c, t)| touched_by(&charts[c as usize], t)).sum::<usize>() <= PATCH_LIMIT;
        if patchable {
            for &(c, t) in &sink.fired {
                let st = &charts[c as usize];
                for &s in st.plan.pre.get(t).iter().chain(st.plan.post.get(t)) {
                    let r = self.rank[c as usize][s as usize];
                    match (self.sorted.binary_search(&r), st.steps[s as usize].x) {
                        (Ok(i), false) => {
                            self.sorted.remove(i);
                        }
                        (Err(i), true) => self.sorted.insert(i, r),
                        _ => {}
                    }
                }
            }
        } else {
            self.sorted.clear();
            for (c, st) in charts.iter().enumerate() {
                self.sorted.extend(st.active.iter().map(|&s| self.rank[c][s as usize]));
            }
            self.sorted.sort_unstable();
        }
        self.valid = Some(scan);
    }
}
