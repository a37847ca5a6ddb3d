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
    /// Its supervision time (`sfc.timeout`), µs; `None` when the chart's own timer guard
    /// (`by`) ended the wait.
    pub timeout: Option<i64>,
    /// The transition whose timer guard (`OpenKM1.T > T#1s …`) led out of the step, when the
    /// chart supervises the wait itself.
    pub by: Option<String>,
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
        let limit = match (&self.by, self.timeout) {
            (Some(t), _) => format!("timer guard of {t}"),
            (None, Some(t)) => format!("supervision time {}", format_time(t)),
            (None, None) => "supervision time".to_string(),
        };
        format!(
            "{}: {what} in step {} after {} ({limit}); waiting for {}",
            self.instance,
            self.step,
            format_time(self.waited),
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
            "timeout": self.timeout.map(format_time),
            "by": self.by,
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

#[derive(Debug, Clone, Copy, Default)]
struct Tally {
    count: u64,
    min: i64,
    max: i64,
    sum: i64,
}

/// A run as kept: states by number (see `Tracker::states`).
#[derive(Debug, Clone, Default)]
struct RunRec {
    number: u64,
    start: i64,
    states: Vec<(u32, i64)>,
    dropped_states: u64,
    total: i64,
    end: Option<RunEnd>,
}

/// The per-instance bookkeeping. Nothing here allocates in a scan once its lists have grown:
/// states are numbered (a set of active steps is looked up by slice), and the run that falls
/// out of the kept ones lends its list to the next run.
#[derive(Debug, Clone, Default)]
pub(crate) struct Tracker {
    /// The initial steps, sorted.
    initial: Vec<u32>,
    /// The run in progress, when its current state began, and that state's number.
    current: Option<(RunRec, i64, u32)>,
    runs: std::collections::VecDeque<RunRec>,
    pub(crate) started_runs: u64,
    resets: u64,
    /// The current run saw an error record (its code once known).
    run_error: Option<Option<i64>>,
    pub(crate) records: std::collections::VecDeque<ErrorRecord>,
    pub(crate) record_count: u64,
    /// Records waiting for the chart's reaction: (record, step).
    pending: Vec<(ErrorRecord, u32)>,
    /// The states met, by number: the active steps (sorted) and their times over runs.
    states: Vec<(Vec<u32>, Tally)>,
    state_ids: std::collections::HashMap<Vec<u32>, u32>,
    /// The last two states entered (ids into `states`; compared by content, so the initial
    /// zeros are harmless).
    recent: [u32; 2],
    /// The active set seen last (sorted).
    last: Vec<u32>,
    /// A list to reuse for the next run.
    spare: Vec<(u32, i64)>,
    /// The instance's error code at the end of the last scan looked at.
    code_before: Option<i64>,
}

/// The mechanisms of a simulation, one tracker per chart instance.
#[derive(Debug, Clone, Default)]
pub(crate) struct Mechanisms {
    pub(crate) trackers: Vec<Tracker>,
    /// Per instance and transition: the step whose wait its timer guard supervises (a step
    /// with several outgoing transitions and no `sfc.timeout`, left by a transition whose
    /// guard reads the step's own `T`).
    timer_guards: Vec<Vec<Option<u32>>>,
    /// Whether any instance has a timer guard.
    any_timer_guard: bool,
    /// The memory slot of each instance's error-code variable (`sfc.error_code`).
    pub(crate) code_slots: Vec<Option<usize>>,
    /// Records completed in the last scan.
    pub(crate) fresh: Vec<ErrorRecord>,
    /// Scratch: an instance's active steps, sorted.
    scratch: Vec<u32>,
}

/// The name of a state: the active steps (qualified, in step order) joined with ` + `.
fn state_name(st: &ChartState, steps: &[u32]) -> String {
    if steps.is_empty() {
        return "(no active step)".to_string();
    }
    let names: Vec<String> = steps.iter().map(|&s| st.qualify(&st.plan.step_names[s as usize])).collect();
    names.join(" + ")
}

impl Mechanisms {
    pub(crate) fn new(charts: &[ChartState]) -> Mechanisms {
        Mechanisms {
            trackers: charts
                .iter()
                .map(|c| {
                    let mut initial = c.plan.initial.clone();
                    initial.sort_unstable();
                    Tracker { initial, ..Default::default() }
                })
                .collect(),
            timer_guards: Vec::new(),
            any_timer_guard: false,
            code_slots: Vec::new(),
            fresh: Vec::new(),
            scratch: Vec::new(),
        }
    }

    /// Whether the last scan needs any work here.
    #[inline]
    pub(crate) fn busy(&self, sink: &ScanSink) -> bool {
        sink.moved || !sink.overdue.is_empty() || self.trackers.iter().any(|t| !t.pending.is_empty())
    }

    /// New error records for the steps that overran in the last scan, or were left by a timer
    /// guard into an error step (the instance's error code became non-zero in that scan):
    /// `make(chart, step, transition)` builds each (it reads the condition analysis);
    /// `code(chart)` names an instance's error code variable and reads it, `code_now(chart)`
    /// only reads it. Then the runs.
    pub(crate) fn after_scan(
        &mut self,
        now: i64,
        sink: &ScanSink,
        charts: &[ChartState],
        mut make: impl FnMut(usize, u32, Option<u32>) -> ErrorRecord,
        code: impl Fn(usize) -> (Option<String>, Option<i64>),
        code_now: impl Fn(usize) -> Option<i64>,
    ) {
        self.fresh.clear();
        for &(c, s) in &sink.overdue {
            let r = make(c as usize, s, None);
            self.note_record(c as usize, r, s);
        }
        for &(c, t) in if self.any_timer_guard { &sink.fired[..] } else { &[] } {
            let Some(s) = self.timer_guards.get(c as usize).and_then(|g| g.get(t as usize)).copied().flatten() else {
                continue;
            };
            let now_code = code_now(c as usize).filter(|&v| v != 0);
            if now_code.is_none() || now_code == self.trackers[c as usize].code_before {
                continue; // a timed step, not a supervised wait into an error step
            }
            let r = make(c as usize, s, Some(t));
            self.note_record(c as usize, r, s);
        }
        for (c, st) in charts.iter().enumerate() {
            let reset = sink.starts.iter().any(|&(_, sc)| sc as usize == c);
            let t = &mut self.trackers[c];
            if reset && t.current.is_some() {
                t.end_run(now, RunEnd::Reset);
                t.resets += 1;
            }
            // Nothing moved: every instance's active set is the one seen last.
            if sink.moved {
                // The active steps, sorted: the engine's list itself when it is in order (a step
                // entered takes the left one's place, so it often is), else a sorted copy.
                let cur: &[u32] = if st.active.is_sorted() {
                    &st.active
                } else {
                    self.scratch.clear();
                    self.scratch.extend_from_slice(&st.active);
                    self.scratch.sort_unstable();
                    &self.scratch
                };
                if cur != t.last.as_slice() {
                    // (A reset ended the run above; the new active set is only noted.)
                    if !reset {
                        if t.current.is_some() {
                            t.close_state(now);
                            if cur == t.initial.as_slice() {
                                let end = match t.run_error.take() {
                                    Some(code) => RunEnd::Error(code),
                                    None => RunEnd::Normal,
                                };
                                t.end_run(now, end);
                            } else {
                                let id = t.state_id(cur);
                                if let Some((_, since, state)) = &mut t.current {
                                    *since = now;
                                    *state = id;
                                }
                            }
                        } else if cur != t.initial.as_slice() {
                            t.started_runs += 1;
                            let mut states = std::mem::take(&mut t.spare);
                            states.clear();
                            let run = RunRec { number: t.started_runs, start: now, states, ..Default::default() };
                            let id = t.state_id(cur);
                            t.current = Some((run, now, id));
                            t.run_error = None;
                        }
                    }
                    t.last.clear();
                    t.last.extend_from_slice(cur);
                }
            }
            t.code_before = code_now(c);
            // Pending records: complete once the chart has left the step (its error step has
            // set the code), was reset, or names no error code.
            if !t.pending.is_empty() {
                let (var, value) = code(c);
                let mut k = 0;
                while k < t.pending.len() {
                    let s = t.pending[k].1;
                    if var.is_some() && !reset && st.steps[s as usize].x {
                        k += 1;
                        continue;
                    }
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
                }
            }
        }
    }

    fn note_record(&mut self, c: usize, r: ErrorRecord, s: u32) {
        let t = &mut self.trackers[c];
        if t.current.is_some() {
            t.run_error = Some(None);
        }
        t.pending.push((r, s));
    }

    /// Ends every run in progress as reset (a restart of the program).
    pub(crate) fn restart(&mut self, now: i64) {
        for t in &mut self.trackers {
            if t.current.is_some() {
                t.end_run(now, RunEnd::Reset);
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
        let names: Vec<String> = t.states.iter().map(|(steps, _)| state_name(st, steps)).collect();
        let public = |r: &RunRec| Run {
            number: r.number,
            start: r.start,
            states: r.states.iter().map(|&(id, d)| (names[id as usize].clone(), d)).collect(),
            dropped_states: r.dropped_states,
            total: r.total,
            end: r.end.clone(),
        };
        let mut runs: Vec<Run> = t.runs.iter().map(public).collect();
        if let Some((run, since, state)) = &t.current {
            let mut r = public(run);
            if r.states.len() < MAX_STATES {
                r.states.push((names[*state as usize].clone(), (now - since).max(0)));
            }
            r.total = (now - r.start).max(0);
            runs.push(r);
        }
        let done = t.runs.len() as u64 + u64::from(t.current.is_some());
        let stats = t
            .states
            .iter()
            .zip(&names)
            .filter(|((_, k), _)| k.count > 0)
            .map(|((_, k), name)| StateStats {
                state: name.clone(),
                count: k.count,
                min: k.min,
                max: k.max,
                mean: k.sum / k.count as i64,
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
            st.active.iter().map(|&s| (st.qualify(&st.plan.step_names[s as usize]), st.time(s))).collect();
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
    /// The number of the state with these active steps (sorted), numbering it when new.
    fn state_id(&mut self, steps: &[u32]) -> u32 {
        // A chart often goes back to the state it was in before the last one (a loop, a
        // waiting step): compared first, which costs less than hashing a big active set.
        for &id in &self.recent {
            if self.states.get(id as usize).is_some_and(|(s, _)| s.as_slice() == steps) {
                self.recent = [id, self.recent[0]];
                return id;
            }
        }
        let id = match self.state_ids.get(steps) {
            Some(&id) => id,
            None => {
                let id = self.states.len() as u32;
                self.states.push((steps.to_vec(), Tally::default()));
                self.state_ids.insert(steps.to_vec(), id);
                id
            }
        };
        self.recent = [id, self.recent[0]];
        id
    }

    fn close_state(&mut self, now: i64) {
        let Some((run, since, state)) = &mut self.current else { return };
        let d = (now - *since).max(0);
        let k = &mut self.states[*state as usize].1;
        if k.count == 0 {
            *k = Tally { count: 1, min: d, max: d, sum: d };
        } else {
            k.count += 1;
            k.min = k.min.min(d);
            k.max = k.max.max(d);
            k.sum = k.sum.saturating_add(d);
        }
        if run.states.len() < MAX_STATES {
            run.states.push((*state, d));
        } else {
            run.dropped_states += 1;
        }
    }

    fn end_run(&mut self, now: i64, end: RunEnd) {
        if end == RunEnd::Reset {
            self.close_state(now);
            self.run_error = None;
        }
        let Some((mut run, _, _)) = self.current.take() else { return };
        run.total = (now - run.start).max(0);
        run.end = Some(end);
        if self.runs.len() == MAX_RUNS {
            if let Some(old) = self.runs.pop_front() {
                self.spare = old.states;
            }
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
    pub(crate) fn instance_name(&self, c: usize) -> String {
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
        // The chart of an action written in SFC reads its instance's variables.
        if st.var_path.is_empty() {
            name.to_string()
        } else {
            format!("{}.{name}", st.var_path)
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

    /// Resolves each instance's error-code variable to its slot once.
    pub(super) fn find_code_slots(&mut self) {
        let slots = (0..self.charts.len())
            .map(|c| {
                let name = self.prog.pous[self.charts[c].pou].wiring.error_code.as_ref()?;
                let q = self.instance_var(c, name);
                self.prog.resolve(self.top, self.top_frame, &q).map(|(slot, _)| slot)
            })
            .collect();
        self.mech.code_slots = slots;
    }

    fn mech_code_slot(&self, c: usize) -> Option<usize> {
        self.code_slots_ref().get(c).copied().flatten()
    }

    pub(super) fn track_mechanisms(&mut self, now: i64, scan: u64) {
        let mut mech = std::mem::take(&mut self.mech);
        let slots = std::mem::take(&mut mech.code_slots);
        self.mech.code_slots = slots;
        {
            let this = &*self;
            let make = |c: usize, s: u32, by: Option<u32>| {
                let report = crate::explain::report(this.explain_view_at(now), c, s);
                let by = by.map(|t| this.charts[c].qualify(&this.charts[c].plan.transition_names[t as usize]));
                ErrorRecord {
                    instance: this.instance_name(c),
                    step: report.step.clone(),
                    code: None,
                    code_variable: None,
                    conditions: report
                        .transitions
                        .iter()
                        .filter(|t| !t.value && Some(&t.transition) != by.as_ref())
                        .map(|t| (t.transition.clone(), t.condition_text()))
                        .collect(),
                    waited: report.elapsed,
                    timeout: report.timeout,
                    by,
                    scan,
                    time: now,
                }
            };
            let code_now = |c: usize| {
                let slot = this.mech_code_slot(c)?;
                this.mem.get(slot).and_then(code_value)
            };
            mech.after_scan(now, &this.sink, &this.charts, make, |c| this.error_code_of(c), code_now);
        }
        mech.code_slots = std::mem::take(&mut self.mech.code_slots);
        self.mech = mech;
    }

    fn code_slots_ref(&self) -> &[Option<usize>] {
        &self.mech.code_slots
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

/// Whether `e` reads `step.T` (case-insensitive).
fn reads_step_time(e: &sfc_syntax::ast::Expr, step: &str, depth: u32) -> bool {
    use sfc_syntax::ast::ExprKind;
    if depth > 64 {
        return false;
    }
    match &e.kind {
        ExprKind::Member { base, member } => {
            (member.text.eq_ignore_ascii_case("T")
                && matches!(&base.kind, ExprKind::Name(n) if n.text.eq_ignore_ascii_case(step)))
                || reads_step_time(base, step, depth + 1)
        }
        ExprKind::Paren(x) | ExprKind::Unary { operand: x, .. } => reads_step_time(x, step, depth + 1),
        ExprKind::Binary { lhs, rhs, .. } => {
            reads_step_time(lhs, step, depth + 1) || reads_step_time(rhs, step, depth + 1)
        }
        ExprKind::Index { base, indices } => {
            reads_step_time(base, step, depth + 1) || indices.iter().any(|i| reads_step_time(i, step, depth + 1))
        }
        ExprKind::Call { args, .. } => {
            args.iter().any(|a| a.value.as_ref().is_some_and(|v| reads_step_time(v, step, depth + 1)))
        }
        _ => false,
    }
}

impl Mechanisms {
    /// Finds the timer guards of every instance (see `timer_guards`).
    pub(crate) fn find_timer_guards(&mut self, prog: &crate::code::Program, charts: &[ChartState]) {
        self.timer_guards = charts
            .iter()
            .map(|st| {
                let crate::code::PouBody::Chart(code) = &prog.pous[st.pou].body else { return Vec::new() };
                let plan = &st.plan;
                (0..plan.transition_names.len() as u32)
                    .map(|t| {
                        let pre = plan.pre.get(t);
                        let &[s] = pre else { return None };
                        if plan.outgoing.get(s).len() < 2 || plan.timeouts[s as usize].is_some() {
                            return None;
                        }
                        let sfc_syntax::ast::Condition::St(e) = &code.chart.transitions.get(t as usize)?.condition
                        else {
                            return None;
                        };
                        reads_step_time(e, &plan.step_names[s as usize], 0).then_some(s)
                    })
                    .collect::<Vec<_>>()
            })
            // An instance without timer guard keeps no list: its fired transitions are not
            // looked at after each scan.
            .map(|g| if g.iter().all(Option::is_none) { Vec::new() } else { g })
            .collect();
        self.any_timer_guard = self.timer_guards.iter().any(|g| !g.is_empty());
    }
}
