//! The scan engine: `semantics.md` scan by scan for every SFC instance, action control, events,
//! profiles, chart control variables, and the [`Simulation`] driving one top-level POU.
//!
//! Per-scan cost grows with the active steps and the live actions, not with the chart: the
//! engine keeps the active steps as a list, tests only the transitions leaving them, and runs
//! action control only for actions that are associated with an active step or still hold
//! state (stored flags, running timers, pending final scans). What a run records beside the
//! scan (coverage, time analysis, the sequence of situations, the active steps in name order)
//! is updated when a step is activated or deactivated, never by a pass over the chart.
//!
//! Modules: `plan` (what the instances of one POU share), `state` (one instance), `evolve`
//! (one scan of one instance), `action` (ACTION_CONTROL and bodies), `situations` (the
//! bounded situation log and the name order), `monitor` (what a runtime needs beyond the scan).

use crate::code::{Ctx, Memory, PouBody, Program};
use crate::explain::StepReport;
use crate::value::Value;
use crate::{Event, Profile, RuntimeError, ScanRecord, SimOptions};
use sfc_diagnostics::{Diagnostic, SourceFile, Span};
use sfc_st::Type;
use std::sync::Arc;

mod action;
mod codesys;
mod graph;
mod logix;
mod evolve;
mod matiec;
mod mechanism;
mod monitor;
pub use monitor::ChartOutline;
mod plan;
mod situations;
mod state;

use evolve::code_of;
pub use evolve::run_chart;
pub use mechanism::{ErrorRecord, MechanismView, Run, RunEnd, StateStats, MAX_RUNS};
pub use plan::ChartPlan;
pub use situations::MAX_SITUATIONS;
use situations::{ActiveOrder, LogMark, SituationLog};
pub use state::ChartState;

pub(crate) use matiec::test_order as matiec_test_order;

/// What one scan did beside the memory: fired transitions and events from every chart
/// instance, and what the bookkeeping of a run needs to follow the active steps.
#[derive(Debug, Default)]
pub struct ScanSink {
    /// `(chart instance, transition)` in firing order.
    pub fired: Vec<(u32, u32)>,
    pub events: Vec<Event>,
    /// Steps whose `sfc.timeout` expired in this scan, `(chart instance, step)` (each
    /// activation of a step once).
    pub overdue: Vec<(u32, u32)>,
    /// Instances that entered their initial situation in this scan (first call, or reset by
    /// `SFCInit`): `(number of firings before it, chart instance)`.
    pub starts: Vec<(u32, u32)>,
    /// Some step was activated or deactivated in this scan (the situation changed).
    pub moved: bool,
    /// Where the scan faulted: the innermost chart instance and the action body or guard
    /// that was running (noted on the error path only).
    pub(crate) fault_site: Option<(u32, FaultSite)>,
}

/// The chart element whose code was running when a scan faulted.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum FaultSite {
    Action(usize),
    Guard(u32),
}

impl ScanSink {
    /// Empties the sink for the next scan, keeping its buffers.
    pub fn clear(&mut self) {
        self.fired.clear();
        self.events.clear();
        self.overdue.clear();
        self.starts.clear();
        self.moved = false;
        self.fault_site = None;
    }

    /// Notes where a fault happened, unless a nested chart already did.
    #[cold]
    pub(crate) fn note_fault(&mut self, chart: usize, site: FaultSite) {
        if self.fault_site.is_none() {
            self.fault_site = Some((chart as u32, site));
        }
    }
}

/// Activation count and active time of one step (time analysis).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct StepStats {
    /// Qualified step name.
    pub step: String,
    pub activations: u64,
    /// Over completed and current activations, µs; `None` when never active.
    pub min: Option<i64>,
    pub max: Option<i64>,
    pub mean: Option<i64>,
}

/// Time analysis of a run so far.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct TimeStats {
    /// Every step of every instance, in declaration order (top chart first).
    pub steps: Vec<StepStats>,
    /// The sequence of situations passed: `(time µs, active steps)` each time the active set
    /// changed, starting with the initial situation (empty when the simulation does not record
    /// situations, see [`Simulation::record_situations`]).
    pub sequence: Vec<(i64, Vec<String>)>,
    /// Later changes of situation that were not recorded: the log keeps the first
    /// [`MAX_SITUATIONS`].
    pub dropped: u64,
}

/// A simulation of one top-level POU of a checked file.
/// The run-time state of a [`Simulation`], taken by [`Simulation::snapshot`].
#[derive(Debug, Clone)]
pub struct Snapshot {
    mem: Vec<Value>,
    charts: Vec<ChartState>,
    record: ScanRecord,
    error: Option<RuntimeError>,
    next_scan: u64,
    log: LogMark,
}

pub struct Simulation {
    prog: Program,
    mem: Vec<Value>,
    top_frame: usize,
    charts: Vec<ChartState>,
    opts: SimOptions,
    source: SourceFile,
    /// For a chart imported from PLCopen XML: the XML and where each part of `source` came
    /// from in it, so runtime errors are located in the file the user has.
    located: Option<Arc<(SourceFile, sfc_plcopen::SourceMap)>>,
    top: usize,
    record: ScanRecord,
    sink: ScanSink,
    error: Option<RuntimeError>,
    next_scan: u64,
    /// The traced variables with their slots, resolved once.
    trace: Vec<(String, Type, usize)>,
    /// Qualified transition names of every instance.
    transition_qnames: Vec<Vec<String>>,
    /// The sequence of situations (time analysis).
    log: SituationLog,
    /// The active steps in name order.
    order: ActiveOrder,
    /// Scratch: the fired transitions of a scan in record order.
    fired_scratch: Vec<(u32, u32)>,
    /// Spare strings of the record's lists, reused so a record costs no allocation.
    spare: Vec<String>,
    /// Global number of the first transition of each instance.
    transition_base: Vec<u32>,
    /// Scratch sink of the monitor's guard evaluation.
    monitor_sink: ScanSink,
    /// Charges one scan may make ([`Simulation::set_scan_budget`]).
    budget: u64,
    /// Set from outside to stop the running scan ([`Simulation::interrupt_flag`]).
    interrupt: Option<Arc<std::sync::atomic::AtomicBool>>,
    /// Error records and runs of every SFC instance (the mechanisms).
    mech: mechanism::Mechanisms,
}

/// The time analysis per run of one mechanism ([`Simulation::runs`]).
#[derive(Debug, Clone, PartialEq)]
pub struct MechanismRuns {
    /// Instance path, the POU's name for the top chart.
    pub instance: String,
    /// The runs kept (the last [`MAX_RUNS`] completed, then the one in progress).
    pub runs: Vec<Run>,
    /// Earlier runs not kept (they still count in `states`).
    pub dropped: u64,
    /// Per state: count, min, mean, max of its times over the runs.
    pub states: Vec<StateStats>,
    /// Runs ended by SFCInit.
    pub resets: u64,
}

/// Where in the chart a runtime error happened ([`Simulation::fault_place`]); names carry the
/// instance path of nested charts.
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub struct FaultPlace {
    /// The action whose body was running.
    pub action: Option<String>,
    /// The transition whose condition was being evaluated.
    pub transition: Option<String>,
    /// The active steps associated with that action, or the steps that transition leaves.
    pub steps: Vec<String>,
}

/// SFC0321 at a POU kept as written (not analysed), with why it is (its `sfc.verbatim`).
fn kept_as_written(v: &sfc_syntax::ast::Verbatim, message: String) -> Diagnostic {
    let why = v
        .attributes
        .iter()
        .rev()
        .find(|a| a.name.eq_ignore_ascii_case("sfc.verbatim"))
        .and_then(|a| a.value.as_deref())
        .map(sfc_syntax::attr_value::unescape)
        .filter(|w| !w.trim().is_empty() && w != "opaque");
    let mut d = Diagnostic::error("SFC0321", v.name.as_ref().map_or(v.span, |n| n.span), message);
    if let Some(w) = why {
        d = d.with_note(w);
    }
    d
}

/// The chart states of the SFC instances of a fresh memory (each instance's hidden slot set
/// to its index).
fn chart_states(prog: &Program, instances: Vec<crate::code::ChartInstance>, mem: &mut [Value]) -> Vec<ChartState> {
    let mut charts = Vec::with_capacity(instances.len());
    for (i, inst) in instances.into_iter().enumerate() {
        let PouBody::Chart(code) = &prog.pous[inst.pou].body else {
            continue;
        };
        let plan = code.plan_arc().clone();
        mem[inst.frame + code.chart_slot as usize] = Value::Int(i as i64);
        charts.push(ChartState::new(inst.pou, plan, inst.frame, inst.path, code.chart.action.as_deref()));
    }
    charts
}

impl Simulation {
    /// Checks `text` and compiles it for simulation of `pou` (by name, or the only SFC POU,
    /// or the only PROGRAM). Errors are the check diagnostics (or SFC0321 when `pou` does not
    /// name a simulatable POU), with the source to render them.
    pub fn from_source(
        name: &str,
        text: &str,
        pou: Option<&str>,
        opts: SimOptions,
    ) -> Result<Simulation, (SourceFile, Vec<Diagnostic>)> {
        let check_opts = sfc_model::CheckOptions { keep_types: true, ..Default::default() };
        let mut checked = sfc_model::check_source(0, name, text, &check_opts);
        // An error in another POU does not keep this one from running: only the errors of the
        // POU, of what it uses, and of the file's types and globals count.
        let top = match choose_pou(&checked.unit, &checked.charts, pou) {
            Ok(n) => n,
            Err(d) if checked.has_errors() => {
                let mut diags: Vec<Diagnostic> = checked.diagnostics.into_iter().filter(|d| d.is_error()).collect();
                diags.push(d);
                return Err((checked.file, diags));
            }
            Err(d) => return Err((checked.file, vec![d])),
        };
        if checked.has_errors() {
            let errors = sfc_model::errors_for(&checked, &top);
            if !errors.is_empty() {
                return Err((checked.file, errors));
            }
        }
        // Only what `top` uses is compiled: what cannot be simulated elsewhere in the file
        // (an error, a construct the simulator lacks) does not stop it.
        sfc_model::set_aside_unused(&mut checked, &top);
        // A block it uses that is kept as written (not analysed) cannot run: say which.
        let deps = sfc_model::dependencies(&checked.unit, &checked.file.text, &top);
        let kept = checked.unit.items.iter().find_map(|i| match i {
            sfc_syntax::ast::Item::Verbatim(v)
                if matches!(v.keyword.as_str(), "FUNCTION_BLOCK" | "FUNCTION" | "PROGRAM")
                    && v.name.as_ref().is_some_and(|n| !n.is(&top) && deps.contains(&n.text.to_ascii_uppercase())) =>
            {
                Some(v)
            }
            _ => None,
        });
        if let Some(v) = kept {
            let name = v.name.as_ref().map(|n| n.text.clone()).unwrap_or_default();
            let d = kept_as_written(
                v,
                format!("`{top}` uses `{name}`, which is kept as written, not analysed, so it cannot be simulated"),
            );
            return Err((checked.file, vec![d]));
        }
        let source = checked.file;
        // The POUs' charts, then the charts of their actions written in SFC.
        let mut charts = checked.charts;
        charts.extend(checked.action_charts);
        let prog = match Program::compile_with(&checked.unit, charts, &checked.expr_types, opts.profile) {
            Ok(p) => p,
            Err(mut d) => {
                // An action body compiled for several charts (the POU's and an action's chart)
                // reports its error once.
                d.dedup();
                return Err((source, d));
            }
        };
        let Some(top) = prog.pou(&top) else {
            let d = Diagnostic::error("SFC0321", Span::default(), format!("no POU named `{top}` to simulate"));
            return Err((source, vec![d]));
        };
        Ok(Simulation::new(prog, top, source, opts))
    }

    /// A simulation of the compiled POU `top`.
    pub fn new(prog: Program, top: usize, source: SourceFile, opts: SimOptions) -> Simulation {
        let Memory { mem, top_frame, charts: instances } = prog.instantiate(top);
        let mut mem = mem;
        let mut charts = chart_states(&prog, instances, &mut mem);
        let trace = prog.pous[top]
            .layout
            .vars
            .iter()
            .filter(|v| !v.implicit && v.size == 1 && v.ty.is_elementary())
            .filter_map(|v| prog.resolve(top, top_frame, &v.name).map(|(slot, _)| (v.name.clone(), v.ty.clone(), slot)))
            .collect();
        if opts.profile == Profile::Matiec {
            matiec::prepare(&prog, &mut charts, &source.text);
        }
        let lower = source.text.to_ascii_lowercase();
        let mentioned = lower.contains("sfccurrentstep");
        let flags = step_flags_read(&lower);
        for c in &mut charts {
            c.track_current = mentioned;
            c.track_left = opts.profile == Profile::Codesys;
            let plan = c.plan.clone();
            c.set_mirrors(|s| {
                let name = plan.step_names[s as usize].to_ascii_lowercase();
                (flags.contains(&(name.clone(), b'x')), flags.contains(&(name, b't')))
            });
        }
        let transition_qnames =
            charts.iter().map(|c| c.plan.transition_names.iter().map(|t| c.qualify(t)).collect()).collect();
        let order = ActiveOrder::new(&charts);
        let mut mech = mechanism::Mechanisms::new(&charts);
        mech.find_timer_guards(&prog, &charts);
        let transition_base = charts
            .iter()
            .scan(0u32, |base, c| {
                let b = *base;
                *base += c.plan.transition_names.len() as u32;
                Some(b)
            })
            .collect();
        let mut sim = Simulation {
            prog,
            mem,
            top_frame,
            charts,
            opts,
            source,
            located: None,
            top,
            record: ScanRecord::default(),
            sink: ScanSink::default(),
            error: None,
            next_scan: 0,
            trace,
            transition_qnames,
            log: SituationLog::new(),
            order,
            fired_scratch: Vec::new(),
            spare: Vec::new(),
            transition_base,
            monitor_sink: ScanSink::default(),
            budget: crate::code::SCAN_BUDGET,
            interrupt: None,
            mech,
        };
        sim.find_code_slots();
        sim
    }

    /// Starts the POU again from its declared initial values (a PLC's restart): memory, steps
    /// and action control as at scan 0, the error cleared. The scan counter goes on, so the
    /// first scan after a restart is the chart's scan 0 at a later virtual time. Coverage and
    /// time analysis go on over the whole run.
    pub fn restart(&mut self) {
        let now = self.next_time();
        self.mech.restart(now);
        let Memory { mut mem, charts: instances, .. } = self.prog.instantiate(self.top);
        let mut charts = chart_states(&self.prog, instances, &mut mem);
        if self.opts.profile == Profile::Matiec {
            matiec::prepare(&self.prog, &mut charts, &self.source.text);
        }
        for (new, old) in charts.iter_mut().zip(&self.charts) {
            new.track_current = old.track_current;
            new.track_left = old.track_left;
            new.set_mirrors(|s| old.steps.get(s as usize).map_or((false, false), |b| (b.mirror_x, b.mirror_t)));
            new.carry_counts(old);
        }
        self.mem = mem;
        self.order = ActiveOrder::new(&charts);
        self.charts = charts;
        self.error = None;
        self.record = ScanRecord::default();
        self.sink.clear();
    }

    /// Bounds every later scan to `limit` charges (loop iterations, IL jumps, calls; default
    /// [`crate::code::SCAN_BUDGET`]); a scan that spends it stops with a located runtime error.
    pub fn set_scan_budget(&mut self, limit: u64) {
        self.budget = limit.max(1);
    }

    /// A flag that, once set (from any thread), stops the running scan at its next look at its
    /// budget (within a few thousand loop iterations) with a runtime error whose message is
    /// [`crate::code::INTERRUPTED`], and every later scan at once until it is cleared.
    pub fn interrupt_flag(&mut self) -> Arc<std::sync::atomic::AtomicBool> {
        self.interrupt.get_or_insert_with(Default::default).clone()
    }

    /// Where the last runtime error happened in the chart: the action or transition whose code
    /// was running, and the active steps that run that action (or that the transition leaves).
    pub fn fault_place(&self) -> Option<FaultPlace> {
        let (c, site) = self.sink.fault_site?;
        let st = self.charts.get(c as usize)?;
        let plan = &st.plan;
        let code = code_of(&self.prog, st.pou);
        let active = |s: &u32| st.is_active(*s);
        let step_name = |s: u32| st.qualify(&plan.step_names[s as usize]);
        Some(match site {
            FaultSite::Action(a) => {
                let name = &code.chart.actions[a].name;
                let mut steps: Vec<u32> = plan
                    .entities
                    .iter()
                    .filter(|e| e.action == Some(a))
                    .flat_map(|e| e.assocs.iter().map(|x| x.step))
                    .filter(active)
                    .collect();
                steps.sort_unstable();
                steps.dedup();
                FaultPlace {
                    action: Some(st.qualify(name)),
                    transition: None,
                    steps: steps.into_iter().map(step_name).collect(),
                }
            }
            FaultSite::Guard(t) => FaultPlace {
                action: None,
                transition: Some(st.qualify(&plan.transition_names[t as usize])),
                steps: plan.pre.get(t).iter().copied().map(step_name).collect(),
            },
        })
    }

    /// Whether the sequence of situations is recorded for [`Simulation::stats`] (off by
    /// default: a run that never asks for it pays nothing). Recording is bounded: the first
    /// 100,000 changes of situation are kept, later ones counted in [`TimeStats::dropped`].
    pub fn record_situations(&mut self, on: bool) {
        self.log.enabled = on;
    }

    /// The checked source (the IEC text; to render diagnostics).
    pub fn source(&self) -> &SourceFile {
        &self.source
    }

    /// Locates runtime errors in the XML of the pair, the PLCopen file the checked source was
    /// imported from (the map says where each part of the text came from).
    pub fn locate_faults_in(&mut self, xml_and_map: Arc<(SourceFile, sfc_plcopen::SourceMap)>) {
        self.located = Some(xml_and_map);
    }

    /// The file runtime errors are located in (their span, line and column), to render them:
    /// the PLCopen XML for an imported chart, else the checked source.
    pub fn fault_source(&self) -> &SourceFile {
        self.located.as_ref().map_or(&self.source, |l| &l.0)
    }
    /// The declared name of the simulated POU.
    pub fn pou_name(&self) -> &str {
        &self.prog.pous[self.top].name
    }
    pub fn options(&self) -> SimOptions {
        self.opts
    }
    /// The number of the scan that [`Simulation::scan`] runs next (0 before the first).
    pub fn next_scan(&self) -> u64 {
        self.next_scan
    }
    /// The virtual time of the next scan, µs.
    pub fn next_time(&self) -> i64 {
        self.next_scan as i64 * self.opts.period
    }

    /// Runs the next scan without building its record (the fast path for benchmarks and the
    /// runtime). Returns the error that stopped the run, if any.
    pub fn advance(&mut self) -> Result<(), &RuntimeError> {
        self.advance_at(self.next_time())
    }

    /// Runs the next scan at virtual time `now` (µs, not before the previous scan's) instead of
    /// `scan · period`: for comparing with targets whose clock ticks differently (an S7-200
    /// 100 ms timer sees time in whole ticks of its time base).
    pub fn advance_at(&mut self, now: i64) -> Result<(), &RuntimeError> {
        if self.error.is_some() {
            return Err(self.error.as_ref().unwrap());
        }
        self.sink.clear();
        let scan = self.next_scan;
        let result = {
            let mut ctx = Ctx {
                mem: &mut self.mem,
                prog: &self.prog,
                charts: &mut self.charts,
                sink: &mut self.sink,
                now,
                scan,
                profile: self.opts.profile,
                budget: crate::code::Budget::new(self.budget, self.interrupt.as_deref()),
            };
            match &self.prog.pous[self.top].body {
                PouBody::Chart(_) => run_chart(&mut ctx, 0),
                PouBody::Code(block) => block(&mut ctx, self.top_frame),
            }
        };
        self.next_scan += 1;
        debug_assert!(self.charts.iter().all(|c| c.consistent()), "active list and activation times disagree");
        self.log.record(now, &self.sink, &self.charts);
        if self.mech.busy(&self.sink) {
            self.track_mechanisms(now, scan);
        } else if !self.mech.fresh.is_empty() {
            self.mech.fresh.clear();
        }
        if let Err(fault) = result {
            let span = match &self.located {
                Some(l) => {
                    let r = l.1.to_xml(fault.span);
                    Span::new(fault.span.file, r.start, r.end)
                }
                None => fault.span,
            };
            let lc = self.fault_source().line_col(span.start);
            let e = RuntimeError { message: fault.message, span, line: lc.line, column: lc.column, scan, time: now };
            self.sink.events.push(Event::Error(e.clone()));
            self.error = Some(e);
            return Err(self.error.as_ref().unwrap());
        }
        Ok(())
    }

    /// Runs the next scan. When it faults, the record holds the `error` event and
    /// [`Simulation::error`] is set; once stopped, `scan` runs nothing and returns that record.
    /// The record's lists reuse their strings from scan to scan: a scan without events
    /// allocates nothing once the lists have grown.
    pub fn scan(&mut self) -> &ScanRecord {
        self.scan_at(self.next_time())
    }

    /// [`Simulation::scan`] at virtual time `time` (see [`Simulation::advance_at`]).
    pub fn scan_at(&mut self, time: i64) -> &ScanRecord {
        if self.error.is_some() {
            return &self.record;
        }
        let scan = self.next_scan;
        let _ = self.advance_at(time);
        self.record.scan = scan;
        self.record.time = time;
        std::mem::swap(&mut self.record.events, &mut self.sink.events);
        if !self.mech.fresh.is_empty() || !self.record.errors.is_empty() {
            self.record.errors.clone_from(&self.mech.fresh);
        }
        self.sink.events.clear();
        self.record.events.sort_by_key(Event::rank);
        // Within one chart's evolution, `fired` is in declaration order.
        let fired = &mut self.fired_scratch;
        fired.clear();
        fired.extend_from_slice(&self.sink.fired);
        let mut k = 0;
        while k < fired.len() {
            let c = fired[k].0;
            let end = fired[k..].iter().position(|f| f.0 != c).map_or(fired.len(), |n| k + n);
            fired[k..end].sort_unstable();
            k = end;
        }
        let names = &self.transition_qnames;
        fill_names(
            &mut self.record.fired,
            &mut self.spare,
            fired.iter().map(|&(c, t)| names[c as usize][t as usize].as_str()),
        );
        self.order.refresh(scan, &self.sink, &self.charts);
        let order = &self.order;
        fill_names(
            &mut self.record.active,
            &mut self.spare,
            order.sorted.iter().map(|&r| order.names[r as usize].as_str()),
        );
        &self.record
    }

    /// The whole run-time state (variables, steps, action control, time, last record), so a
    /// search (the analyzer's witness replay) can try a scan and come back. Without the
    /// mechanisms' history (error records, runs), which goes on.
    pub fn snapshot(&self) -> Snapshot {
        Snapshot {
            mem: self.mem.clone(),
            charts: self.charts.clone(),
            record: self.record.clone(),
            error: self.error.clone(),
            next_scan: self.next_scan,
            log: self.log.mark(),
        }
    }

    /// A canonical text of the run-time state — variables, active steps, step times,
    /// supervision flags, action control blocks, chart bookkeeping (the steps active when the
    /// step actions last ran; under `codesys` the steps the last evolution left) — without
    /// history (time analysis, firing log, scratch marks): two runs in the same state after the
    /// same scan have equal keys, and two runs with equal keys go on alike. Used to explore
    /// state spaces with the simulator (the prover's independent cross-check in the test
    /// suite).
    pub fn state_key(&self) -> String {
        use std::fmt::Write;
        let mut s = String::new();
        let _ = write!(s, "{:?}|{:?}|", self.mem, self.error.as_ref().map(|e| (&e.message, e.scan)));
        for c in &self.charts {
            let mut active = c.active.clone();
            active.sort_unstable();
            let _ = write!(s, "{}:{}:{active:?}:{}{}:", c.started, c.last_time, c.tip_prev, c.quit_prev);
            // What the next action phase reads besides the active steps: the steps active when
            // the step actions last ran, and (`codesys`) the steps the last evolution left.
            let _ = write!(s, "{:?}:", c.stepped);
            if c.track_left {
                let mut left = c.left.clone();
                left.sort_unstable();
                let _ = write!(s, "{left:?}:");
            }
            for st in &c.steps {
                let _ = write!(s, "{},{},{};", st.x, st.t, st.overdue);
            }
            for ct in &c.controls {
                let _ = write!(s, "{ct:?};");
            }
            s.push('|');
        }
        s
    }

    /// Returns to a state taken with [`Simulation::snapshot`] of this simulation.
    pub fn restore(&mut self, snap: &Snapshot) {
        self.mem.clone_from(&snap.mem);
        self.charts.clone_from(&snap.charts);
        self.record = snap.record.clone();
        self.error = snap.error.clone();
        self.next_scan = snap.next_scan;
        self.sink.clear();
        self.log.rewind(snap.log);
        // The mechanisms' history (error records, runs) is not part of a snapshot: a search
        // that tries scans and comes back does not read it, and copying it at every node
        // would make the search slower.
        self.mech.fresh.clear();
        self.order.valid = None;
    }

    /// The record of the last scan run.
    pub fn record(&self) -> &ScanRecord {
        &self.record
    }
    /// The runtime error that stopped the run.
    pub fn error(&self) -> Option<&RuntimeError> {
        self.error.as_ref()
    }

    /// Writes a variable (`Start`, `Rev.Start`, `Cells[2]`, global names), as an input change:
    /// the value must have the variable's type (an `Int` is accepted for REAL/LREAL, and is
    /// range-checked for the integer types). Step and action flags cannot be written.
    pub fn set(&mut self, name: &str, value: Value) -> Result<(), String> {
        if self.is_chart_flag(name) {
            return Err(format!("`{name}` is a step or action flag: the chart sets it"));
        }
        let Some((slot, ty)) = self.prog.resolve(self.top, self.top_frame, name) else {
            return Err(format!("no variable `{name}` in `{}`", self.pou_name()));
        };
        let v = fit(value, &ty).map_err(|why| format!("`{name}` is {}: {why}", type_name(&ty)))?;
        self.mem[slot] = self.inward(v);
        Ok(())
    }

    fn is_chart_flag(&self, name: &str) -> bool {
        let Some((base, member)) = name.rsplit_once('.') else {
            return false;
        };
        if !["X", "T", "Q", "A", "_X", "_T"].iter().any(|m| m.eq_ignore_ascii_case(member)) {
            return false;
        }
        let (path, leaf) = match base.rsplit_once('.') {
            Some((p, l)) => (p, l),
            None => ("", base),
        };
        // CODESYS's `_<action>.x`.
        let leaf = match leaf.strip_prefix('_') {
            Some(a) if self.charts.iter().any(|c| c.plan.action_names.iter().any(|n| n.eq_ignore_ascii_case(a))) => a,
            _ => leaf,
        };
        self.charts.iter().any(|c| {
            c.path.eq_ignore_ascii_case(path)
                && (c.plan.step_names.iter().any(|s| s.eq_ignore_ascii_case(leaf))
                    || c.plan.action_names.iter().any(|a| a.eq_ignore_ascii_case(leaf)))
        })
    }

    /// Reads a variable, `Step.X`, `Step.T`, `Action.Q`, `Action.A`, also inside nested
    /// instances (`Rev.Busy`, `Rev.OpenKM1.X`). Case-insensitive.
    pub fn get(&self, name: &str) -> Option<Value> {
        let (slot, _) = self.resolve_name(name)?;
        if let Some(v) = self.current_step_of(name).or_else(|| self.unmirrored_step_value(slot)) {
            return Some(v);
        }
        self.mem.get(slot).map(|v| self.outward(v))
    }

    /// A value of memory as users see it: TIME in µs (under `matiec` memory holds MatIEC's
    /// packed timespecs, `crate::timespec`).
    fn outward(&self, v: &Value) -> Value {
        match v {
            Value::Time(t) if self.prog.matiec_time => Value::Time(crate::timespec::Timespec::unpack(*t).to_us()),
            _ => v.clone(),
        }
    }
    /// The inverse of [`Simulation::outward`].
    fn inward(&self, v: Value) -> Value {
        match v {
            Value::Time(us) if self.prog.matiec_time => Value::Time(crate::timespec::Timespec::from_us(us).pack()),
            _ => v,
        }
    }

    /// `[Path.]SFCCurrentStep` computed from the chart state (see `ChartState::track_current`).
    /// The `X` or `T` of a step whose slot is not mirrored in memory, from the step state.
    fn unmirrored_step_value(&self, slot: usize) -> Option<Value> {
        self.charts.iter().find_map(|c| {
            c.steps.iter().zip(&c.slots).enumerate().find_map(|(s, (step, &(x_slot, t_slot)))| {
                if !step.mirror_x && x_slot as usize == slot {
                    Some(Value::Bool(step.x))
                } else if !step.mirror_t && t_slot as usize == slot {
                    Some(Value::Time(c.time(s as u32)))
                } else {
                    None
                }
            })
        })
    }

    fn current_step_of(&self, name: &str) -> Option<Value> {
        let (path, leaf) = match name.rsplit_once('.') {
            Some((p, l)) => (p, l),
            None => ("", name),
        };
        if !leaf.eq_ignore_ascii_case("SFCCurrentStep") {
            return None;
        }
        let st = self.charts.iter().find(|c| c.path.eq_ignore_ascii_case(path))?;
        let cur = evolve::current_step(self.opts.profile, &st.active);
        Some(Value::Str(Arc::from(cur.map(|s| st.plan.step_names[s as usize].as_str()).unwrap_or(""))))
    }
    /// The type of what [`Simulation::get`] reads.
    pub fn type_of(&self, name: &str) -> Option<Type> {
        self.resolve_name(name).map(|(_, t)| t)
    }

    /// A name as the top POU's code resolves it, or the `X`/`T` of a step named as traces name
    /// it: a step of the chart of an action written in SFC carries the action's name
    /// (`Lift.ACT_Load.Gripping.X`, where the POU's code reads `Lift.Gripping.X`).
    fn resolve_name(&self, name: &str) -> Option<(usize, Type)> {
        self.prog.resolve(self.top, self.top_frame, name).or_else(|| self.step_flag(name))
    }

    /// The slot and type of `Path.Step.X` / `Path.Step.T`, `Path` a chart instance's path as
    /// [`Simulation::step_names`] qualifies its steps.
    fn step_flag(&self, name: &str) -> Option<(usize, Type)> {
        let (base, member) = name.trim().rsplit_once('.')?;
        let x = member.eq_ignore_ascii_case("X");
        if !x && !member.eq_ignore_ascii_case("T") {
            return None;
        }
        let (path, leaf) = base.rsplit_once('.').unwrap_or(("", base));
        self.charts.iter().find_map(|c| {
            if !c.path.eq_ignore_ascii_case(path) {
                return None;
            }
            let s = c.plan.step_names.iter().position(|n| n.eq_ignore_ascii_case(leaf))?;
            let (xs, ts) = *c.slots.get(s)?;
            Some(if x { (xs as usize, Type::Bool) } else { (ts as usize, Type::Time) })
        })
    }

    /// Active steps now, sorted by code points (nested instances as `Path.Step`).
    pub fn active(&self) -> Vec<String> {
        let order = &self.order;
        if self.next_scan > 0 && order.valid == Some(self.next_scan - 1) {
            return order.sorted.iter().map(|&r| order.names[r as usize].clone()).collect();
        }
        let mut ranks: Vec<u32> = Vec::new();
        for (c, st) in self.charts.iter().enumerate() {
            ranks.extend(st.active.iter().map(|&s| order.rank[c][s as usize]));
        }
        ranks.sort_unstable();
        ranks.into_iter().map(|r| order.names[r as usize].clone()).collect()
    }

    /// The number of active steps now (every instance).
    pub fn active_count(&self) -> usize {
        self.charts.iter().map(|c| c.active.len()).sum()
    }

    /// The steps whose `sfc.timeout` expired in the last scan (qualified; each activation of a
    /// step once), so a caller can report each overrun when it happens without asking every
    /// step every scan.
    pub fn newly_overdue(&self) -> impl Iterator<Item = String> + '_ {
        self.sink
            .overdue
            .iter()
            .map(|&(c, s)| self.order.names[self.order.rank[c as usize][s as usize] as usize].clone())
    }

    /// Whether the last scan saw a step's `sfc.timeout` expire (cheap: no names are built).
    pub fn any_newly_overdue(&self) -> bool {
        !self.sink.overdue.is_empty()
    }

    /// Coverage of the run so far, in the order of [`Simulation::step_names`] and
    /// [`Simulation::transition_names`]: per step its activations (at least 1 for an initial
    /// step that SFCInit held active, 0 when never active), per transition its firings. Kept by
    /// the engine as steps are entered and transitions fire; reading it costs one pass.
    pub fn coverage_counts(&self) -> (Vec<u64>, Vec<u64>) {
        let mut steps = Vec::new();
        let mut transitions = Vec::new();
        for c in &self.charts {
            steps.extend((0..c.steps.len() as u32).map(|s| {
                let n = c.steps[s as usize].tally.activations;
                if n == 0 && c.covered(s) {
                    1
                } else {
                    n
                }
            }));
            transitions.extend_from_slice(&c.fired_count);
        }
        (steps, transitions)
    }

    /// The variables a trace shows: every declared variable of elementary type of the top
    /// POU, in declaration order, with its declared name and type.
    pub fn trace_vars(&self) -> Vec<(String, Type)> {
        self.trace.iter().map(|(name, ty, _)| (name.clone(), ty.clone())).collect()
    }
    /// Current values of [`Simulation::trace_vars`], same order.
    pub fn trace_values(&self) -> Vec<Value> {
        self.trace.iter().map(|&(_, _, slot)| self.outward(&self.mem[slot])).collect()
    }
    /// [`Simulation::trace_values`] into `out`, reusing its room.
    pub fn trace_values_into(&self, out: &mut Vec<Value>) {
        out.truncate(self.trace.len());
        for (i, &(_, _, slot)) in self.trace.iter().enumerate() {
            let v = &self.mem[slot];
            match out.get_mut(i) {
                Some(o) if !self.prog.matiec_time => o.clone_from(v),
                Some(o) => *o = self.outward(v),
                None => out.push(self.outward(v)),
            }
        }
    }
    /// Every step (qualified), in declaration order, top chart first.
    pub fn step_names(&self) -> Vec<String> {
        self.charts.iter().flat_map(|c| c.plan.step_names.iter().map(|s| c.qualify(s))).collect()
    }
    /// Every transition (qualified), in declaration order, top chart first.
    pub fn transition_names(&self) -> Vec<String> {
        self.charts.iter().flat_map(|c| c.plan.transition_names.iter().map(|s| c.qualify(s))).collect()
    }

    /// Condition analysis of every active step now: why each outgoing transition does not fire.
    pub fn explain(&self) -> Vec<StepReport> {
        let mut out = Vec::new();
        for (i, st) in self.charts.iter().enumerate() {
            let mut act = st.active.clone();
            act.sort_unstable();
            for s in act {
                out.push(crate::explain::report(self.explain_view(), i, s));
            }
        }
        out
    }
    /// Condition analysis of the active steps whose `sfc.timeout` has expired.
    pub fn overdue(&self) -> Vec<StepReport> {
        self.overdue_at().into_iter().map(|(c, s)| crate::explain::report(self.explain_view(), c, s)).collect()
    }

    /// The active steps whose `sfc.timeout` has expired (qualified, sorted by chart and step):
    /// cheap enough to ask every scan, unlike their reports.
    pub fn overdue_steps(&self) -> Vec<String> {
        self.overdue_at()
            .into_iter()
            .map(|(c, s)| self.charts[c].qualify(&self.charts[c].plan.step_names[s as usize]))
            .collect()
    }

    /// Condition analysis of one active step, by qualified name (`Rev.OpenKM1`).
    pub fn explain_step(&self, step: &str) -> Option<StepReport> {
        self.charts.iter().enumerate().find_map(|(c, st)| {
            let s = st
                .active
                .iter()
                .copied()
                .find(|&s| st.qualify(&st.plan.step_names[s as usize]).eq_ignore_ascii_case(step))?;
            Some(crate::explain::report(self.explain_view(), c, s))
        })
    }

    fn overdue_at(&self) -> Vec<(usize, u32)> {
        let mut out = Vec::new();
        for (c, st) in self.charts.iter().enumerate() {
            if !st.plan.supervised {
                continue;
            }
            let mut act: Vec<u32> = st
                .active
                .iter()
                .copied()
                .filter(|&s| st.plan.timeouts[s as usize].is_some_and(|limit| st.time(s) > limit))
                .collect();
            act.sort_unstable();
            out.extend(act.into_iter().map(|s| (c, s)));
        }
        out
    }

    fn explain_view(&self) -> crate::explain::View<'_> {
        self.explain_view_at(self.next_time() - self.opts.period)
    }

    fn explain_view_at(&self, now: i64) -> crate::explain::View<'_> {
        crate::explain::View {
            prog: &self.prog,
            mem: &self.mem,
            charts: &self.charts,
            source: &self.source,
            top: self.top,
            top_frame: self.top_frame,
            now,
            profile: self.opts.profile,
        }
    }

    /// Time analysis of the run so far.
    pub fn stats(&self) -> TimeStats {
        let mut steps = Vec::new();
        for st in &self.charts {
            for (s, name) in st.plan.step_names.iter().enumerate() {
                let tl = st.steps[s].tally;
                let mut count = tl.completed;
                let (mut min, mut max, mut sum) = (tl.min, tl.max, tl.sum);
                if st.steps[s].x {
                    let d = st.time(s as u32);
                    min = min.min(d);
                    max = max.max(d);
                    sum = sum.saturating_add(d);
                    count += 1;
                }
                let some = count > 0;
                steps.push(StepStats {
                    step: st.qualify(name),
                    activations: tl.activations,
                    min: some.then_some(min),
                    max: some.then_some(max),
                    mean: some.then(|| sum / count as i64),
                });
            }
        }
        let order = &self.order;
        let sequence = if self.log.enabled || self.log.dropped > 0 {
            self.log.sequence(&self.charts, |c, s| order.names[order.rank[c as usize][s as usize] as usize].clone())
        } else {
            Vec::new()
        };
        TimeStats { steps, sequence, dropped: self.log.dropped }
    }
}

/// Every `(name, b'x' | b't')` such that the (lowercase) source text contains `name.x` /
/// `name.t` (spaces allowed around the dot) with `name` a whole identifier: the step flags
/// that some code may read. Comments and strings count too, which only keeps more slots
/// up to date than needed.
fn step_flags_read(lower: &str) -> std::collections::HashSet<(String, u8)> {
    let b = lower.as_bytes();
    let ident = |c: u8| c.is_ascii_alphanumeric() || c == b'_';
    let mut out = std::collections::HashSet::new();
    for (i, _) in lower.match_indices('.') {
        let mut k = i + 1;
        while k < b.len() && b[k] == b' ' {
            k += 1;
        }
        // CODESYS's `_x` and `_t` read the same flags; S7-GRAPH's `U` is kept with `T`.
        if b.get(k) == Some(&b'_') {
            k += 1;
        }
        let flag = match b.get(k) {
            Some(&c @ (b'x' | b't')) if !b.get(k + 1).is_some_and(|&n| ident(n)) => c,
            Some(b'u') if !b.get(k + 1).is_some_and(|&n| ident(n)) => b't',
            _ => continue,
        };
        let mut end = i;
        while end > 0 && b[end - 1] == b' ' {
            end -= 1;
        }
        let mut start = end;
        while start > 0 && ident(b[start - 1]) {
            start -= 1;
        }
        if start < end {
            out.insert((lower[start..end].to_string(), flag));
        }
    }
    out
}

/// Refills `dst` with `names`, reusing the strings it holds (and spare ones), so a list of
/// names that does not grow costs no allocation.
fn fill_names<'a>(dst: &mut Vec<String>, spare: &mut Vec<String>, names: impl Iterator<Item = &'a str>) {
    let mut n = 0;
    for name in names {
        if n < dst.len() {
            if dst[n] != name {
                dst[n].clear();
                dst[n].push_str(name);
            }
        } else {
            let mut s = spare.pop().unwrap_or_default();
            s.clear();
            s.push_str(name);
            dst.push(s);
        }
        n += 1;
    }
    spare.extend(dst.drain(n..));
}

/// Picks the POU to simulate: the named one, else the only SFC POU, else the only PROGRAM.
fn choose_pou(
    unit: &sfc_syntax::ast::SourceUnit,
    charts: &[sfc_model::Chart],
    pou: Option<&str>,
) -> Result<String, Diagnostic> {
    use sfc_syntax::ast::{Item, PouKind};
    let pous: Vec<&sfc_syntax::ast::Pou> =
        unit.items.iter().filter_map(|i| if let Item::Pou(p) = i { Some(p) } else { None }).collect();
    if let Some(name) = pou {
        return match pous.iter().find(|p| p.name.is(name)) {
            Some(p) if p.kind == PouKind::Function => Err(Diagnostic::error(
                "SFC0321",
                p.name.span,
                format!("`{}` is a FUNCTION: simulate a PROGRAM or FUNCTION_BLOCK", p.name.text),
            )),
            Some(p) => Ok(p.name.text.clone()),
            None => {
                // A POU kept as written (not analysed) is there, but cannot be simulated: say so.
                let kept: Vec<&sfc_syntax::ast::Verbatim> = unit
                    .items
                    .iter()
                    .filter_map(|i| match i {
                        Item::Verbatim(v)
                            if matches!(v.keyword.as_str(), "PROGRAM" | "FUNCTION_BLOCK" | "FUNCTION") =>
                        {
                            Some(v)
                        }
                        _ => None,
                    })
                    .collect();
                if let Some(v) = kept.iter().find(|v| v.name.as_ref().is_some_and(|n| n.is(name))) {
                    return Err(kept_as_written(
                        v,
                        format!("`{name}` is kept as written, not analysed, so it cannot be simulated"),
                    ));
                }
                let mut names: Vec<String> = pous.iter().map(|p| p.name.text.clone()).collect();
                names.extend(
                    kept.iter()
                        .filter_map(|v| v.name.as_ref())
                        .map(|n| format!("{} (kept as written, not analysed)", n.text)),
                );
                let list = if names.is_empty() { "no POU".to_string() } else { names.join(", ") };
                Err(Diagnostic::error("SFC0321", Span::default(), format!("no POU named `{name}` in this file"))
                    .with_note(format!("the file declares: {list}")))
            }
        };
    }
    let programs: Vec<&&sfc_syntax::ast::Pou> = pous.iter().filter(|p| p.kind == PouKind::Program).collect();
    if programs.len() == 1 {
        return Ok(programs[0].name.text.clone());
    }
    if charts.len() == 1 {
        return Ok(charts[0].pou.clone());
    }
    let names: Vec<&str> = pous.iter().filter(|p| p.kind != PouKind::Function).map(|p| p.name.text.as_str()).collect();
    if names.is_empty() {
        return Err(Diagnostic::error(
            "SFC0321",
            Span::default(),
            "the file has no SFC POU to simulate (and no PROGRAM)",
        )
        .with_note("a chart is a PROGRAM or FUNCTION_BLOCK whose body is steps and transitions"));
    }
    Err(Diagnostic::error("SFC0321", Span::default(), "choose the POU to simulate (`pou` / `--pou`)")
        .with_note(format!("candidates: {}", names.join(", "))))
}

fn type_name(ty: &Type) -> String {
    ty.to_string()
}

/// Converts a written value to the slot value of `ty`, or says why it does not fit.
pub(crate) fn fit(value: Value, ty: &Type) -> Result<Value, String> {
    let base = ty.base();
    match (&value, base) {
        (Value::Bool(_), Type::Bool) => Ok(value),
        (Value::Int(i), _) if ty.is_integer() || ty.is_bit() || matches!(ty, Type::Subrange { .. }) => {
            match ty.int_range() {
                Some((lo, hi)) if (i128::from(*i) < lo || i128::from(*i) > hi) => {
                    Err(format!("{i} is out of range {lo}..{hi}"))
                }
                _ => Ok(value),
            }
        }
        (Value::Int(i), _) if ty.is_real() => Ok(real_of(*i as f64, ty)),
        (Value::Real(r), _) if ty.is_real() => Ok(real_of(*r, ty)),
        (Value::Time(_), _) if ty.is_duration() => Ok(value),
        (Value::Str(_), _) if ty.is_string() => Ok(value),
        (Value::Int(_), Type::Enum { .. }) => Ok(value),
        _ => Err(format!("cannot take {}", describe(&value))),
    }
}

fn real_of(r: f64, ty: &Type) -> Value {
    if matches!(ty.base(), Type::Real) {
        Value::Real(r as f32 as f64)
    } else {
        Value::Real(r)
    }
}

fn describe(v: &Value) -> String {
    match v {
        Value::Bool(b) => format!("the BOOL {}", if *b { "TRUE" } else { "FALSE" }),
        Value::Int(i) => format!("the integer {i}"),
        Value::Real(r) => format!("the real {r}"),
        Value::Time(t) => format!("the TIME {}", crate::format_time(*t)),
        Value::Str(s) => format!("the string '{s}'"),
    }
}
