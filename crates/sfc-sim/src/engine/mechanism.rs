//! The diagnostics of seed 003's "mechanisms" (every SFC instance): error records made when a
//! step's supervision time expires, with the continuation condition in words (terminals and
//! values at that moment), and the time analysis per run — an activation of the instance from
//! leaving its initial situation until it is back (normal end, error, or SFCInit reset), the
//! states passed with their times.
//!
//! Updated after a scan only when a step overran its `sfc.timeout` or the situation of some
//! instance changed: a scan in which nothing moved costs one test.

use super::state::ChartState;
use super::ScanSink;
use crate::value::{format_time, Value};

/// Completed runs kept per instance (older ones are counted, and stay in the statistics).
pub const MAX_RUNS: usize = 100;
/// States kept per run (later ones are counted).
pub const MAX_STATES: usize = 1000;
/// Error records kept per instance (older ones are counted).
pub const MAX_RECORDS: usize = 100;

/// The error record of a supervision timeout: made when a step's `sfc.timeout` expires, with
/// the condition that was not met, completed with the instance's error code once the chart
/// has reacted (left the step: its error step sets the code) or at once when the instance
/// names no error-code variable.
#[derive(Debug, Clone, PartialEq)]
pub struct ErrorRecord {
    /// The mechanism: the instance path (`Rev`), the POU's name for the top chart.
    pub instance: String,
    /// The step that waited too long (qualified).
    pub step: String,
    /// The value of the instance's error-code variable (`sfc.error_code`) when the record was
    /// completed; `None` when it has none or it held 0.
    pub code: Option<i64>,
    /// That variable (qualified), when the instance names one.
    pub code_variable: Option<String>,
    /// Each outgoing transition that was not satisfied at the timeout, with its condition in
    /// words: `(Rev.TKM2Closed, "KM2Fb (X12.3, %IX0.5) is FALSE; needs TRUE")`.
    pub conditions: Vec<(String, String)>,
    /// How long the step had been active when its supervision time expired, µs.
    pub waited: i64,
    /// Its supervision time, µs.
    pub timeout: i64,
    /// The scan and virtual time (µs) of the timeout.
    pub scan: u64,
    pub time: i64,
}

impl ErrorRecord {
    /// The continuation condition in words: the unmet transitions joined with ` or `.
    pub fn condition(&self) -> String {
        if self.conditions.is_empty() {
            return "no outgoing transition".to_string();
        }
        let parts: Vec<String> = self.conditions.iter().map(|(t, c)| format!("{t}: {c}")).collect();
        parts.join(" or ")
    }

    /// One line for an event log or an HMI: `Rev: error 405 in step Rev.CloseKM2 after
    /// T#1s100ms (supervision time T#1s); waiting for Rev.TKM2Closed: KM2Fb (%IX0.5) is FALSE;
    /// needs TRUE`.
    pub fn message(&self) -> String {
        let what = match self.code {
            Some(c) => format!("error {c}"),
            None => "supervision timeout".to_string(),
        };
        format!(
            "{}: {what} in step {} after {} (supervision time {}); waiting for {}",
            self.instance,
            self.step,
            format_time(self.waited),
            format_time(self.timeout),
            self.condition()
        )
    }

    /// The record as JSON: the trace's `supervision` event and the monitor's error record.
    pub fn to_json(&self) -> serde_json::Value {
        serde_json::json!({
            "kind": "supervision",
            "instance": self.instance,
            "step": self.step,
            "code": self.code,
            "code_variable": self.code_variable,
            "condition": self.condition(),
            "conditions": self.conditions.iter().map(|(t, c)| serde_json::json!({"transition": t, "condition": c})).collect::<Vec<_>>(),
            "waited": format_time(self.waited),
            "timeout": format_time(self.timeout),
            "scan": self.scan,
            "time": format_time(self.time),
            "message": self.message(),
        })
    }
}

/// How a run ended.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum RunEnd {
    /// Back in the initial situation through the chart's transitions.
    Normal,
    /// Back in the initial situation after an error record was made in the run (its code).
    Error(Option<i64>),
    /// SFCInit (or a restart) put the instance back into its initial situation.
    Reset,
}

impl RunEnd {
    pub fn text(&self) -> String {
        match self {
            RunEnd::Normal => "normal".into(),
            RunEnd::Error(Some(c)) => format!("error {c}"),
            RunEnd::Error(None) => "error".into(),
            RunEnd::Reset => "reset".into(),
        }
    }
}

/// One run of a mechanism.
#[derive(Debug, Clone, PartialEq)]
pub struct Run {
    /// 1-based number of the run in the instance's life.
    pub number: u64,
    /// Virtual time it started (left the initial situation), µs.
    pub start: i64,
    /// The states passed in order: (active steps joined with ` + `, time in it µs).
    pub states: Vec<(String, i64)>,
    /// States not kept ([`MAX_STATES`]).
    pub dropped_states: u64,
    /// Start to end (or to now for the run in progress), µs.
    pub total: i64,
    /// `None` while in progress.
    pub end: Option<RunEnd>,
}

/// Count, min, mean, max of one state's times over the runs.
#[derive(Debug, Clone, PartialEq)]
pub struct StateStats {
    pub state: String,
    pub count: u64,
    pub min: i64,
    pub max: i64,
    pub mean: i64,
}

/// Everything the mechanisms view shows of one instance.
#[derive(Debug, Clone, PartialEq)]
pub struct MechanismView {
    /// Instance path (`Rev`), the POU's name for the top chart.
    pub instance: String,
    /// The function block (or program) it is an instance of.
    pub pou: String,
    /// The value of its activation bit (`sfc.activation`), when it names one.
    pub activation: Option<bool>,
    /// The activation bit's name (qualified).
    pub activation_variable: Option<String>,
    /// A run is in progress (the instance is out of its initial situation).
    pub running: bool,
    /// Active steps (qualified) with their times, µs.
    pub active: Vec<(String, i64)>,
    pub last_error: Option<ErrorRecord>,
    /// Runs started so far (the one in progress included).
    pub runs: u64,
    /// Runs ended by SFCInit.
    pub resets: u64,
    /// Error records made so far.
    pub errors: u64,
}

impl MechanismView {
    pub fn to_json(&self) -> serde_json::Value {
        serde_json::json!({
            "instance": self.instance,
            "pou": self.pou,
            "activation": self.activation,
            "activationVariable": self.activation_variable,
            "running": self.running,
            "active": self.active.iter().map(|(s, t)| serde_json::json!({"step": s, "time": format_time(*t), "timeUs": t})).collect::<Vec<_>>(),
            "lastError": self.last_error.as_ref().map(ErrorRecord::to_json),
            "runs": self.runs,
            "resets": self.resets,
            "errors": self.errors,
        })
    }
}

#[derive(Debug, Clone, Default)]
struct Tally {
    count: u64,
    min: i64,
    max: i64,
    sum: i64,
}

/// The per-instance bookkeeping.
#[derive(Debug, Clone, Default)]
pub(crate) struct Tracker {
    /// The run in progress and when its current state began.
    current: Option<(Run, i64, Vec<u32>)>,
    runs: std::collections::VecDeque<Run>,
    pub(crate) started_runs: u64,
    resets: u64,
    /// The current run saw an error record (its code once known).
    run_error: Option<Option<i64>>,
    pub(crate) records: std::collections::VecDeque<ErrorRecord>,
    pub(crate) record_count: u64,
    /// Records waiting for the chart's reaction: (record, step).
    pending: Vec<(ErrorRecord, u32)>,
    /// State name → tally, in order of first appearance.
    states: Vec<(String, Tally)>,
    /// The active set seen last (sorted).
    last: Vec<u32>,
}

/// The mechanisms of a simulation, one tracker per chart instance.
#[derive(Debug, Clone, Default)]
pub(crate) struct Mechanisms {
    pub(crate) trackers: Vec<Tracker>,
    /// Records completed in the last scan.
    pub(crate) fresh: Vec<ErrorRecord>,
}

/// The name of a state: the active steps (qualified, in step order) joined with ` + `.
fn state_name(st: &ChartState, steps: &[u32]) -> String {
    if steps.is_empty() {
        return "(no active step)".to_string();
    }
    let names: Vec<String> = steps.iter().map(|&s| st.qualify(&st.plan.step_names[s as usize])).collect();
    names.join(" + ")
}

fn sorted_active(st: &ChartState) -> Vec<u32> {
    let mut a = st.active.clone();
    a.sort_unstable();
    a
}

impl Mechanisms {
    pub(crate) fn new(charts: &[ChartState]) -> Mechanisms {
        Mechanisms { trackers: charts.iter().map(|_| Tracker::default()).collect(), fresh: Vec::new() }
    }

    /// Whether the last scan needs any work here.
    #[inline]
    pub(crate) fn busy(&self, sink: &ScanSink) -> bool {
        sink.moved || !sink.overdue.is_empty() || self.trackers.iter().any(|t| !t.pending.is_empty())
    }

    /// New error records for the steps that overran in the last scan: `make(chart, step)`
    /// builds each (it reads the condition analysis); `code(chart)` reads an instance's error
    /// code variable.
    pub(crate) fn after_scan(
        &mut self,
        now: i64,
        sink: &ScanSink,
        charts: &[ChartState],
        mut make: impl FnMut(usize, u32) -> ErrorRecord,
        code: impl Fn(usize) -> (Option<String>, Option<i64>),
    ) {
        self.fresh.clear();
        for &(c, s) in &sink.overdue {
            let r = make(c as usize, s);
            let t = &mut self.trackers[c as usize];
            if t.current.is_some() {
                t.run_error = Some(None);
            }
            t.pending.push((r, s));
        }
        // Runs: the instances that were reset or moved.
        for (c, st) in charts.iter().enumerate() {
            let reset = sink.starts.iter().any(|&(_, sc)| sc as usize == c);
            let t = &mut self.trackers[c];
            let now_active = if sink.moved { sorted_active(st) } else { t.last.clone() };
            if reset {
                if t.current.is_some() {
                    t.end_run(st, now, RunEnd::Reset);
                    t.resets += 1;
                }
            } else if now_active != t.last {
                let initial = {
                    let mut i = st.plan.initial.clone();
                    i.sort_unstable();
                    i
                };
                match &mut t.current {
                    None => {
                        if now_active != initial {
                            t.started_runs += 1;
                            let run = Run {
                                number: t.started_runs,
                                start: now,
                                states: Vec::new(),
                                dropped_states: 0,
                                total: 0,
                                end: None,
                            };
                            t.current = Some((run, now, now_active.clone()));
                            t.run_error = None;
                        }
                    }
                    Some(_) => {
                        t.close_state(st, now);
                        if now_active == initial {
                            let end = match t.run_error.take() {
                                Some(code) => RunEnd::Error(code),
                                None => RunEnd::Normal,
                            };
                            t.end_run(st, now, end);
                        } else if let Some((_, since, set)) = &mut t.current {
                            *since = now;
                            set.clone_from(&now_active);
                        }
                    }
                }
            }
            t.last = now_active;
            // Pending records: complete once the chart has left the step (its error step has
            // set the code), was reset, or names no error code.
            if !t.pending.is_empty() {
                let (var, value) = code(c);
                let mut k = 0;
                while k < t.pending.len() {
                    let s = t.pending[k].1;
                    let done = var.is_none() || reset || !st.steps[s as usize].x;
                    if done {
                        let (mut r, _) = t.pending.remove(k);
                        r.code_variable.clone_from(&var);
                        r.code = value.filter(|&v| v != 0);
                        if let Some(e) = &mut t.run_error {
                            *e = e.or(r.code);
                        }
                        // An error that ended its run already: the run's end carries the code.
                        if let Some(last) = t.runs.back_mut() {
                            if last.end == Some(RunEnd::Error(None)) && last.start <= r.time {
                                last.end = Some(RunEnd::Error(r.code));
                            }
                        }
                        t.record_count += 1;
                        if t.records.len() == MAX_RECORDS {
                            t.records.pop_front();
                        }
                        t.records.push_back(r.clone());
                        self.fresh.push(r);
                    } else {
                        k += 1;
                    }
                }
            }
        }
    }

    /// Ends every run in progress as reset (a restart of the program).
    pub(crate) fn restart(&mut self, charts: &[ChartState], now: i64) {
        for (t, st) in self.trackers.iter_mut().zip(charts) {
            if t.current.is_some() {
                t.end_run(st, now, RunEnd::Reset);
                t.resets += 1;
            }
            t.pending.clear();
            t.last.clear();
        }
    }

    /// The runs of instance `c` (completed ones kept, then the one in progress up to `now`),
    /// the runs not kept, the per-state statistics, resets.
    pub(crate) fn runs(&self, c: usize, st: &ChartState, now: i64) -> (Vec<Run>, u64, Vec<StateStats>, u64) {
        let t = &self.trackers[c];
        let mut runs: Vec<Run> = t.runs.iter().cloned().collect();
        if let Some((run, since, set)) = &t.current {
            let mut r = run.clone();
            if r.states.len() < MAX_STATES {
                r.states.push((state_name(st, set), (now - since).max(0)));
            }
            r.total = (now - r.start).max(0);
            runs.push(r);
        }
        let done = t.runs.len() as u64 + u64::from(t.current.is_some());
        let stats = t
            .states
            .iter()
            .map(|(name, k)| StateStats {
                state: name.clone(),
                count: k.count,
                min: k.min,
                max: k.max,
                mean: if k.count > 0 { k.sum / k.count as i64 } else { 0 },
            })
            .collect();
        (runs, t.started_runs.saturating_sub(done), stats, t.resets)
    }

    pub(crate) fn view(
        &self,
        c: usize,
        st: &ChartState,
        instance: String,
        pou: String,
        activation: (Option<String>, Option<bool>),
    ) -> MechanismView {
        let t = &self.trackers[c];
        let mut active: Vec<(String, i64)> =
            sorted_active(st).into_iter().map(|s| (st.qualify(&st.plan.step_names[s as usize]), st.time(s))).collect();
        active.sort();
        MechanismView {
            instance,
            pou,
            activation: activation.1,
            activation_variable: activation.0,
            running: t.current.is_some(),
            active,
            last_error: t.records.back().cloned().or_else(|| t.pending.last().map(|p| p.0.clone())),
            runs: t.started_runs,
            resets: t.resets,
            errors: t.record_count + t.pending.len() as u64,
        }
    }
}

impl Tracker {
    fn close_state(&mut self, st: &ChartState, now: i64) {
        let Some((run, since, set)) = &mut self.current else { return };
        let d = (now - *since).max(0);
        let name = state_name(st, set);
        match self.states.iter_mut().find(|(n, _)| *n == name) {
            Some((_, k)) => {
                k.count += 1;
                k.min = k.min.min(d);
                k.max = k.max.max(d);
                k.sum = k.sum.saturating_add(d);
            }
            None => {
                if self.states.len() < MAX_STATES {
                    self.states.push((name.clone(), Tally { count: 1, min: d, max: d, sum: d }));
                }
            }
        }
        if run.states.len() < MAX_STATES {
            run.states.push((name, d));
        } else {
            run.dropped_states += 1;
        }
    }

    fn end_run(&mut self, st: &ChartState, now: i64, end: RunEnd) {
        if end == RunEnd::Reset {
            self.close_state(st, now);
            self.run_error = None;
        }
        let Some((mut run, _, _)) = self.current.take() else { return };
        run.total = (now - run.start).max(0);
        run.end = Some(end);
        if self.runs.len() == MAX_RUNS {
            self.runs.pop_front();
        }
        self.runs.push_back(run);
    }
}

/// The value of an error-code variable as an integer.
pub(crate) fn code_value(v: &Value) -> Option<i64> {
    match v {
        Value::Int(i) => Some(*i),
        Value::Bool(b) => Some(i64::from(*b)),
        Value::Real(r) => Some(*r as i64),
        _ => None,
    }
}

impl super::Simulation {
    /// The instance's name as the mechanisms view shows it.
    fn instance_name(&self, c: usize) -> String {
        let st = &self.charts[c];
        if st.path.is_empty() {
            self.prog.pous[st.pou].name.clone()
        } else {
            st.path.clone()
        }
    }

    /// A variable of instance `c` by its declared name, qualified (`Rev.ErrorCode`).
    fn instance_var(&self, c: usize, name: &str) -> String {
        let st = &self.charts[c];
        if st.path.is_empty() {
            name.to_string()
        } else {
            format!("{}.{name}", st.path)
        }
    }

    /// The error-code variable of instance `c` (qualified) and its value now.
    fn error_code_of(&self, c: usize) -> (Option<String>, Option<i64>) {
        let st = &self.charts[c];
        let Some(name) = &self.prog.pous[st.pou].wiring.error_code else { return (None, None) };
        let q = self.instance_var(c, name);
        let v = self.get(&q).as_ref().and_then(code_value);
        (Some(q), v)
    }

    pub(super) fn track_mechanisms(&mut self, now: i64, scan: u64) {
        let mut mech = std::mem::take(&mut self.mech);
        {
            let this = &*self;
            let make = |c: usize, s: u32| {
                let report = crate::explain::report(this.explain_view_at(now), c, s);
                ErrorRecord {
                    instance: this.instance_name(c),
                    step: report.step.clone(),
                    code: None,
                    code_variable: None,
                    conditions: report
                        .transitions
                        .iter()
                        .filter(|t| !t.value)
                        .map(|t| (t.transition.clone(), t.condition_text()))
                        .collect(),
                    waited: report.elapsed,
                    timeout: report.timeout.unwrap_or(0),
                    scan,
                    time: now,
                }
            };
            mech.after_scan(now, &this.sink, &this.charts, make, |c| this.error_code_of(c));
        }
        self.mech = mech;
    }

    /// The error records completed in the last scan (see [`ErrorRecord`]).
    pub fn fresh_error_records(&self) -> &[ErrorRecord] {
        &self.mech.fresh
    }

    /// Every error record kept, completed ones then those waiting for the chart's reaction, in
    /// order of their timeouts.
    pub fn error_records(&self) -> Vec<ErrorRecord> {
        let mut out: Vec<ErrorRecord> = Vec::new();
        for t in &self.mech.trackers {
            out.extend(t.records.iter().cloned());
            out.extend(t.pending.iter().map(|p| p.0.clone()));
        }
        out.sort_by_key(|r| (r.scan, r.step.clone()));
        out
    }

    /// Every SFC instance of the program with its state, last error record and run count
    /// (seed 003's "which mechanisms are active and in which state").
    pub fn mechanisms(&self) -> Vec<MechanismView> {
        (0..self.charts.len())
            .map(|c| {
                let st = &self.charts[c];
                let activation = match &self.prog.pous[st.pou].wiring.activation {
                    Some(name) => {
                        let q = self.instance_var(c, name);
                        let v = matches!(self.get(&q), Some(Value::Bool(true)));
                        (Some(q), Some(v))
                    }
                    None => (None, None),
                };
                self.mech.view(c, st, self.instance_name(c), self.prog.pous[st.pou].name.clone(), activation)
            })
            .collect()
    }

    /// The time analysis per run of every instance, up to the last scan.
    pub fn runs(&self) -> Vec<super::MechanismRuns> {
        let now = (self.next_time() - self.opts.period).max(0);
        (0..self.charts.len())
            .map(|c| {
                let (runs, dropped, states, resets) = self.mech.runs(c, &self.charts[c], now);
                super::MechanismRuns { instance: self.instance_name(c), runs, dropped, states, resets }
            })
            .collect()
    }
}

impl super::MechanismRuns {
    /// The time analysis per run as JSON (`sfc sim --stats --format json`, the monitor's
    /// `timing`): times as TIME literals, and in µs where a client computes with them.
    pub fn to_json(&self) -> serde_json::Value {
        serde_json::json!({
            "instance": self.instance,
            "dropped": self.dropped,
            "resets": self.resets,
            "runs": self.runs.iter().map(|r| serde_json::json!({
                "run": r.number,
                "start": format_time(r.start),
                "total": format_time(r.total),
                "totalUs": r.total,
                "ended": r.end.as_ref().map(RunEnd::text),
                "states": r.states.iter().map(|(s, t)| serde_json::json!({"state": s, "time": format_time(*t), "timeUs": t})).collect::<Vec<_>>(),
                "dropped_states": r.dropped_states,
            })).collect::<Vec<_>>(),
            "states": self.states.iter().map(|k| serde_json::json!({
                "state": k.state, "count": k.count,
                "min": format_time(k.min), "mean": format_time(k.mean), "max": format_time(k.max),
                "minUs": k.min, "meanUs": k.mean, "maxUs": k.max,
            })).collect::<Vec<_>>(),
        })
    }
}
