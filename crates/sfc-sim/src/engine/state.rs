//! The run-time state of one SFC instance: active steps, step records, action control blocks,
//! the time analysis and coverage counters, and the scratch buffers of the evolution.

use super::action::Control;
use super::plan::ChartPlan;
use crate::value::Value;
use std::sync::Arc;

/// Activations and active time of one step, for the time analysis. `min`/`max` start at the
/// extremes, so completing an activation is branch-free.
#[derive(Debug, Clone, Copy)]
pub(crate) struct StepTally {
    pub(crate) activations: u64,
    pub(crate) completed: u64,
    pub(crate) min: i64,
    pub(crate) max: i64,
    pub(crate) sum: i64,
}

impl Default for StepTally {
    fn default() -> Self {
        StepTally { activations: 0, completed: 0, min: i64::MAX, max: i64::MIN, sum: 0 }
    }
}

impl StepTally {
    /// Ends an activation that lasted `d` µs.
    #[inline(always)]
    pub(crate) fn complete(&mut self, d: i64) {
        self.completed += 1;
        self.min = self.min.min(d);
        self.max = self.max.max(d);
        // A sum of active times of one step cannot exceed the run's virtual time.
        self.sum = self.sum.wrapping_add(d);
    }
}

/// What the evolution reads and writes of one step, with its time analysis: one cache line.
#[derive(Debug, Clone, Copy, Default)]
pub(crate) struct StepState {
    /// While active: the chart clock when the step was activated (its elapsed time is
    /// `clock − t`, so advancing the time of every active step costs nothing); while inactive:
    /// the elapsed time it stopped at (a stopwatch frozen on deactivation).
    pub(crate) t: i64,
    /// Position in `ChartState::active` while active.
    pub(crate) pos: u32,
    /// Scratch: the evolution that activates it (member of `A`).
    pub(crate) amark: u32,
    pub(crate) x: bool,
    /// `sfc.timeout` already reported for the current activation.
    pub(crate) overdue: bool,
    /// Keep the `X` / `T` slot up to date: only when some code of the file may read it
    /// (otherwise [`crate::Simulation::get`] answers from the step state).
    pub(crate) mirror_x: bool,
    pub(crate) mirror_t: bool,
    /// `graph`: an S7-GRAPH supervision error holds the step (its transitions wait).
    pub(crate) held: bool,
    /// `graph`: the step's S7-GRAPH interlock is not satisfied (its "C" actions do not run).
    pub(crate) interlock_open: bool,
    /// `graph`: the step's supervision condition in the previous call (an error comes on its
    /// rising edge).
    pub(crate) supervision_was: bool,
    /// Time analysis: activations and active times.
    pub(crate) tally: StepTally,
}

/// Scratch marks of the general evolution (conflicts, divergences, unsafe firings).
#[derive(Debug, Clone, Copy, Default)]
pub(crate) struct StepMarks {
    /// The evolution in which a true transition leaving it was seen (conflict test).
    pub(crate) seen: u32,
    /// The evolution that deactivates it (member of `D`).
    pub(crate) dmark: u32,
    /// Accepted transitions activating it in this scan, or conflicting ones.
    pub(crate) hits: u8,
    /// Consumed by an accepted transition.
    pub(crate) consumed: bool,
}

/// The run-time state of one SFC instance.
#[derive(Debug, Clone)]
pub struct ChartState {
    /// Index of the POU in `Program::pous`.
    pub pou: usize,
    /// Absolute frame base.
    pub frame: usize,
    /// Instance path, `""` for the top POU; for the chart of an action written in SFC, the
    /// instance's path and the action's name (`Lift.ACT_Load`, `ACT_Count`).
    pub path: String,
    /// The path of the instance whose frame holds the chart's variables: `path` itself, or for
    /// the chart of an action written in SFC `path` without the action (`Lift`, `""`).
    pub(crate) var_path: String,
    pub(crate) plan: Arc<ChartPlan>,
    pub(crate) started: bool,
    pub(crate) last_time: i64,
    /// Chart time, µs: the sum of the time steps of the calls in which the chart was not paused.
    pub(crate) clock: i64,
    /// Active steps, in no particular order.
    pub(crate) active: Vec<u32>,
    /// `since[i]` is the activation clock of step `active[i]` (its `StepState::t`): the same
    /// figure kept beside the list, so copying the active steps with their times (a runtime's
    /// snapshot every scan) reads two short arrays instead of one cache line per step.
    pub(crate) since: Vec<i64>,
    pub(crate) steps: Vec<StepState>,
    pub(crate) marks: Vec<StepMarks>,
    /// Absolute memory slots of each step's `X` and `T`.
    pub(crate) slots: Vec<(u32, u32)>,
    /// The absolute first slot of each step's dialect members: a Logix chart's `Count` (how many
    /// times the step became active: its time analysis's activations, kept over SFCInit as
    /// Logix keeps it over an SFC Reset), then `FS`, `SA`, `LS` and `TMax` (ms); an S7-GRAPH
    /// chart's `U`.
    pub(crate) vendor_slots: Vec<u32>,
    pub(crate) members: crate::code::StepMembers,
    /// An S7-GRAPH chart's steps: how long the step has been disturbed (an interlock or a
    /// supervision error) in its activation, and since when it is disturbed now; its `U` is its
    /// time less this.
    pub(crate) disturbance: Vec<(i64, Option<i64>)>,
    /// `logix`: the steps left in the last evolution, whose last scan comes next.
    pub(crate) logix_left: Vec<u32>,
    /// Some step has a mirrored `X` or `T` slot / a mirrored `T` slot.
    pub(crate) any_mirror: bool,
    pub(crate) any_mirror_t: bool,
    /// How often each transition fired (coverage).
    pub(crate) fired_count: Vec<u64>,
    /// SFCInit held the chart in its initial situation at some time (its initial steps were
    /// active without an activation).
    pub(crate) held: bool,
    pub(crate) controls: Vec<Control>,
    pub(crate) live: Vec<u32>,
    /// Steps left by the last evolution (CODESYS body order), kept only under that profile.
    pub(crate) left: Vec<u32>,
    pub(crate) track_left: bool,
    /// Steps activated since the last action phase.
    pub(crate) entered: Vec<u32>,
    /// The active steps when the step actions last ran, sorted (charts with step actions only):
    /// the steps left and entered since are the difference.
    pub(crate) stepped: Vec<u32>,
    /// The active set changed since the last `finish_scan`.
    pub(crate) changed: bool,
    /// Keep `SFCCurrentStep` up to date in memory: only when some code of the file reads it
    /// (writing a STRING every scan costs more than the rest of a scan). Readers from outside
    /// (`Simulation::get`) get it computed.
    pub(crate) track_current: bool,
    // Scratch buffers, kept to avoid allocation per scan.
    pub(crate) stamp: Vec<u32>,
    /// Number of evolutions so far, modulo 2^32: the epoch marking scratch fields.
    pub(crate) evolutions: u32,
    pub(crate) cand: Vec<u32>,
    pub(crate) code_links: Vec<u32>,
    pub(crate) fire: Vec<u32>,
    pub(crate) accepted: Vec<u32>,
    pub(crate) order: Vec<u32>,
    pub(crate) run: Vec<u32>,
    pub(crate) current: Option<u32>,
    /// `SFCTip` in the previous call (its rising edge jogs the chart).
    pub(crate) tip_prev: bool,
    /// `SFCQuitError` in the previous call (`codesys`: its fall restarts the step times).
    pub(crate) quit_prev: bool,
    /// The `matiec` profile's own state (`engine/matiec.rs`).
    pub(crate) matiec: Option<Box<super::matiec::State>>,
}

impl ChartState {
    /// `action`: the action whose chart this is, for the chart of an action written in SFC.
    pub(crate) fn new(
        pou: usize,
        plan: Arc<ChartPlan>,
        frame: usize,
        path: String,
        action: Option<&str>,
    ) -> ChartState {
        let var_path = match action.and_then(|a| path.strip_suffix(a)) {
            Some(p) => p.strip_suffix('.').unwrap_or(p).to_string(),
            None => path.clone(),
        };
        let n = plan.step_names.len();
        let m = plan.entities.len();
        let nt = plan.transition_names.len();
        let steps = vec![StepState { mirror_x: true, mirror_t: true, ..StepState::default() }; n];
        let slots = (0..n)
            .map(|s| ((frame + plan.x_slots[s] as usize) as u32, (frame + plan.t_slots[s] as usize) as u32))
            .collect();
        ChartState {
            pou,
            frame,
            path,
            var_path,
            started: false,
            last_time: 0,
            clock: 0,
            active: Vec::new(),
            since: Vec::new(),
            steps,
            marks: vec![StepMarks::default(); n],
            slots,
            vendor_slots: plan.vendor_slots.iter().map(|&c| (frame + c as usize) as u32).collect(),
            members: plan.step_members,
            disturbance: if plan.step_members == crate::code::StepMembers::Graph {
                vec![(0, None); n]
            } else {
                Vec::new()
            },
            logix_left: Vec::new(),
            any_mirror: true,
            any_mirror_t: true,
            fired_count: vec![0; nt],
            held: false,
            controls: vec![Control::default(); m],
            live: Vec::new(),
            left: Vec::new(),
            track_left: true,
            entered: Vec::new(),
            stepped: Vec::new(),
            changed: true,
            track_current: true,
            stamp: vec![0; nt],
            evolutions: 0,
            cand: Vec::new(),
            code_links: Vec::new(),
            fire: Vec::new(),
            accepted: Vec::new(),
            order: Vec::new(),
            run: Vec::new(),
            current: None,
            tip_prev: false,
            quit_prev: false,
            matiec: None,
            plan,
        }
    }

    /// Takes over the coverage and time-analysis counters of `old` (a restart goes on
    /// counting over the whole run).
    pub(crate) fn carry_counts(&mut self, old: &ChartState) {
        for (a, b) in self.steps.iter_mut().zip(&old.steps) {
            a.tally = b.tally;
        }
        if self.fired_count.len() == old.fired_count.len() {
            self.fired_count.clone_from(&old.fired_count);
        }
        self.held |= old.held;
    }

    /// Decides which step slots are kept up to date in memory (`flags(step)` is `(x, t)`).
    pub(crate) fn set_mirrors(&mut self, mut flags: impl FnMut(u32) -> (bool, bool)) {
        for (s, step) in self.steps.iter_mut().enumerate() {
            (step.mirror_x, step.mirror_t) = flags(s as u32);
        }
        self.any_mirror = self.steps.iter().any(|s| s.mirror_x || s.mirror_t);
        self.any_mirror_t = self.steps.iter().any(|s| s.mirror_t);
    }

    /// `Path.Name`, or `Name` for the top chart.
    pub(crate) fn qualify(&self, name: &str) -> String {
        if self.path.is_empty() {
            name.to_string()
        } else {
            format!("{}.{name}", self.path)
        }
    }

    /// Starts a new evolution and returns its epoch (never 0: 0 marks nothing). When the
    /// counter wraps, every mark is cleared so an old mark cannot equal a new epoch.
    pub(crate) fn next_epoch(&mut self) -> u32 {
        self.evolutions = self.evolutions.wrapping_add(1);
        if self.evolutions == 0 {
            for step in &mut self.steps {
                step.amark = 0;
            }
            for m in &mut self.marks {
                m.seen = 0;
                m.dmark = 0;
            }
            self.stamp.fill(0);
            self.evolutions = 1;
        }
        self.evolutions
    }

    /// Sets the activation clock of active step `s` (its elapsed time becomes `clock − t`).
    pub(crate) fn set_since(&mut self, s: u32, t: i64) {
        let st = &mut self.steps[s as usize];
        debug_assert!(st.x, "only an active step has an activation time");
        st.t = t;
        self.since[st.pos as usize] = t;
    }

    /// The active list and its activation times agree with the step records (checked after
    /// every scan in debug builds).
    pub(crate) fn consistent(&self) -> bool {
        self.active.len() == self.since.len()
            && self.active.iter().zip(&self.since).enumerate().all(|(i, (&s, &t))| {
                let st = &self.steps[s as usize];
                st.x && st.pos as usize == i && st.t == t
            })
    }

    /// Whether step `s` is active.
    pub(crate) fn is_active(&self, s: u32) -> bool {
        self.steps[s as usize].x
    }

    /// Elapsed time of step `s`, µs (frozen since its deactivation when inactive).
    #[inline]
    pub(crate) fn time(&self, s: u32) -> i64 {
        let step = &self.steps[s as usize];
        if step.x {
            self.clock - step.t
        } else {
            step.t
        }
    }

    /// Whether step `s` was ever active after a call (coverage).
    pub(crate) fn covered(&self, s: u32) -> bool {
        self.steps[s as usize].tally.activations > 0
            || self.steps[s as usize].x
            || (self.held && self.plan.is_initial[s as usize])
    }

    /// Activates `s` (or restarts its time if it stays active). Returns whether the active set
    /// changed.
    pub(crate) fn activate(&mut self, s: u32) -> bool {
        let clock = self.clock;
        let st = &mut self.steps[s as usize];
        let flipped = !st.x;
        if flipped {
            st.x = true;
            st.pos = self.active.len() as u32;
            self.active.push(s);
            self.since.push(clock);
        } else {
            self.since[st.pos as usize] = clock;
        }
        st.t = clock;
        st.overdue = false;


        if self.plan.has_entities[s as usize] {
            self.entered.push(s);
        }
        self.steps[s as usize].tally.activations += 1;
        if let Some(d) = self.disturbance.get_mut(s as usize) {
            *d = (0, None);
        }
        self.changed = true;
        flipped
    }

    /// Deactivates `s` (its time freezes). Returns whether it was active.
    pub(crate) fn deactivate(&mut self, s: u32) -> bool {
        let i = s as usize;
        if !self.steps[i].x {
            return false;
        }
        self.complete(s);
        let st = &mut self.steps[i];
        st.x = false;
        let pos = st.pos as usize;
        self.active.swap_remove(pos);
        self.since.swap_remove(pos);
        if let Some(&moved) = self.active.get(pos) {
            self.steps[moved as usize].pos = pos as u32;
        }
        true
    }

    /// Ends the current activation of active step `s` in the time analysis (the step is left,
    /// or left and re-entered); the step's record then holds the frozen time.
    pub(crate) fn complete(&mut self, s: u32) {
        let i = s as usize;
        let d = self.clock - self.steps[i].t;
        self.steps[i].t = d;
        self.steps[i].tally.complete(d);
        self.changed = true;
    }

    /// Writes the `X` slot of `s` when it is mirrored.
    #[inline]
    pub(crate) fn publish_x(&self, mem: &mut [Value], s: u32, x: bool) {
        if self.steps[s as usize].mirror_x {
            super::evolve::put_bool(mem, self.slots[s as usize].0 as usize, x);
        }
        if x && self.members == crate::code::StepMembers::Logix {
            self.publish_count(mem, s);
        }
    }

    /// Writes the `Count` slot of `s` (a Logix chart's step).
    #[inline]
    pub(crate) fn publish_count(&self, mem: &mut [Value], s: u32) {
        if let (Some(&slot), Some(step)) = (self.vendor_slots.get(s as usize), self.steps.get(s as usize)) {
            mem[slot as usize] = Value::Int(i64::try_from(step.tally.activations).unwrap_or(i64::MAX));
        }
    }

    /// Writes the `T` slot of `s` when it is mirrored.
    #[inline]
    pub(crate) fn publish_t(&self, mem: &mut [Value], s: u32) {
        if self.steps[s as usize].mirror_t {
            super::evolve::put_time(mem, self.slots[s as usize].1 as usize, self.time(s));
            // An S7-GRAPH step's `U`: its `T` until the `graph` profile, which models
            // disturbances, subtracts them.
            if self.members == crate::code::StepMembers::Graph {
                if let Some(&u) = self.vendor_slots.get(s as usize) {
                    super::evolve::put_time(mem, u as usize, self.time(s));
                }
            }
        }
    }
}
