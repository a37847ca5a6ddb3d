//! The scan thread: owns the simulation and runs it on the wall clock.
//!
//! Scan `k` is due at `origin + k·period` and runs at virtual time `k·period`. The thread
//! sleeps to that absolute deadline, measures how late it woke (start jitter) and how long the
//! scan took. A scan that ends after the next deadline is an overrun: the periods already
//! passed are skipped (the next scan is the first one whose deadline is still ahead, and the
//! simulation's virtual time jumps with it, so chart time keeps following the wall clock).
//!
//! The run is in one of three states (`docs/runtime.md`, "States"): RUN (scanning, or halted by
//! the debugger), STOP and FAULT. A runtime error of the chart, or the watchdog (a supervisor
//! thread, `watchdog.rs`, that stops a scan still running at its deadline), puts it in FAULT;
//! an orderly end of the run (limit, Ctrl-C, SIGTERM) or a monitor `stop` in STOP. Entering
//! either puts the outputs to their safe values (`safe.rs`) and writes the retentive values
//! (`retain.rs`). A monitor `reset` restarts the chart, warm or cold, from any state.
//!
//! While halted the thread does not scan; it waits for commands. On `continue` the grid is
//! re-anchored so the next scan is due at once (virtual time does not count the halt).

// Indices here come from tables this crate builds at start (the Modbus map, the variables) or
// are checked against the frame length just before (Modbus PDUs); the runtime work of issue 14
// landed after the workspace lints, and its conversion to `get` is still to do (ARCHITECTURE.md).
#![allow(clippy::indexing_slicing)]

use crate::board::{reply_err, reply_ok, BreakOp, BreakTarget, Command, Hub, Request, RunState, ScanState};
use crate::io::{Image, IoPoint, Role};
use crate::jitter::ScanStats;
use crate::protocol::{event_json, value_from_json, value_json};
use crate::retain::Writer;
use crate::safe::SafeState;
use crate::watchdog::ScanClock;
use crate::{RunReport, Slot};
use sfc_sim::code::Retained;
use sfc_sim::{format_time, Simulation, Value};
use std::collections::{BTreeMap, VecDeque};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc::{Receiver, RecvTimeoutError};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

/// States kept for reuse: the history's length and a few that clients may still hold.
const SPARE_STATES: usize = crate::board::HISTORY + 8;

/// When to end a run.
#[derive(Debug, Clone, Copy, Default)]
pub struct Limits {
    /// Stop after this many scans.
    pub scans: Option<u64>,
    /// Stop after this much wall-clock time.
    pub duration: Option<Duration>,
    /// Stop a scan that runs longer than this, and enter FAULT.
    pub watchdog: Option<Duration>,
}

/// The retentive values of the run and their file.
pub(crate) struct RetainRun {
    /// The RETAIN and PERSISTENT leaves (also kept over a `reset` without a file).
    pub leaves: Vec<Retained>,
    /// Writes the file; `None` without one.
    pub writer: Option<Writer>,
    pub interval: Duration,
    pub next: Instant,
}

pub(crate) struct ScanThread {
    pub sim: Simulation,
    pub hub: Arc<Hub>,
    pub rx: Receiver<Request>,
    pub points: Arc<Vec<IoPoint>>,
    pub image: Arc<Mutex<Image>>,
    /// Slots of the monitor's variables (`ChartInfo::variables`).
    pub vars: Vec<Slot>,
    /// For each monitor variable, its I/O point when it has one.
    pub var_point: Vec<Option<usize>>,
    /// Following steps of each transition, initial steps.
    pub post: Vec<Vec<u32>>,
    pub initial: Vec<u32>,
    pub limits: Limits,
    pub halted: bool,
    pub realtime: bool,
    /// In FAULT, wait for a `reset` (something serves); otherwise the run ends.
    pub wait_in_fault: bool,
    pub safe: Arc<SafeState>,
    pub clock: Arc<ScanClock>,
    /// The simulation's interrupt flag (set by the watchdog and by `Runtime::stop`).
    pub interrupt: Arc<AtomicBool>,
    pub retain: RetainRun,
    // Run state.
    pub state: RunState,
    /// The message of the fault, in FAULT.
    pub fault: Option<String>,
    /// The grid must be re-anchored before the next scan (after a halt, stop or reset).
    pub reanchor: bool,
    /// The next scan is the chart's first (start, reset): its initial steps count as entered.
    pub restarted: bool,
    /// States published since the last that lists the active steps in full (`u64::MAX`: the
    /// next must list them, as the states before it were dropped).
    pub since_key: u64,
    /// Debug builds: each change checked against the engine.
    pub check: ChangeCheck,
    pub inputs: Vec<Value>,
    pub forced: Vec<(u32, Value)>,
    pub pending_sets: Vec<(u32, Value)>,
    pub breakpoints: BTreeMap<BreakTarget, bool>,
    pub stats: ScanStats,
    pub unpublished_states: VecDeque<Arc<ScanState>>,
    /// States that left the history, to be filled again.
    pub spare_states: Vec<Arc<ScanState>>,
    /// Events not yet published (an overrun as figures: it costs no allocation).
    pub unpublished_events: Vec<crate::board::Event>,
    /// Halts and resumes not yet published, in order.
    pub halt_change: Vec<(bool, String)>,
    /// The state of the last scan (to show safe values on it, and its guards to a client that
    /// connects while the run is halted).
    pub last_state: Option<Arc<ScanState>>,
    pub steps_requested: Vec<Request>,
    /// The mechanisms' error records not yet published ([`crate::board::Board::errors`]).
    pub unpublished_errors: Option<Vec<crate::board::MechanismErrors>>,
    /// Error records made since the process started (the Modbus block's count).
    pub records: u64,
    /// The newest error record with its count, until the Modbus image takes it.
    pub unwritten_record: Option<(u64, sfc_sim::ErrorRecord)>,
    /// The last fault's code and the faults since the start (the Modbus status block).
    pub fault_code: u16,
    pub faults: u64,
    /// What serves in FAULT and how this run can leave it, for the FAULT line.
    pub fault_ways: String,
    /// The status block as the image holds it (`None`: not written yet).
    pub status_written: Option<crate::io::Status>,
}

impl ScanThread {
    pub fn run(mut self) -> RunReport {
        let realtime = if self.realtime { priority::realtime().map(|()| true) } else { Ok(false) };
        priority::fine_timer();
        let period_us = self.sim.options().period.max(1) as u64;
        let period = Duration::from_micros(period_us);
        let at = |origin: Instant, k: u64| origin + Duration::from_micros(period_us.saturating_mul(k));
        let started = Instant::now();
        let mut origin = started;
        let mut k = self.sim.next_scan();
        self.inputs = self.points.iter().map(|p| p.slot.default_value()).collect();
        self.restarted = true;
        self.publish();
        loop {
            if self.hub.stopping() || self.limits.duration.is_some_and(|d| started.elapsed() >= d) {
                break;
            }
            if self.state == RunState::Run && self.limits.scans.is_some_and(|n| self.stats.scans >= n) {
                break;
            }
            if self.state == RunState::Fault && !self.wait_in_fault {
                break;
            }
            if self.reanchor {
                self.reanchor = false;
                k = self.sim.next_scan();
                origin =
                    Instant::now().checked_sub(Duration::from_micros(period_us.saturating_mul(k))).unwrap_or(origin);
            }
            if self.state != RunState::Run || self.halted {
                match self.rx.recv_timeout(Duration::from_millis(20)) {
                    Ok(r) => self.command(r),
                    Err(RecvTimeoutError::Timeout) => {}
                    Err(RecvTimeoutError::Disconnected) => self.halted = false,
                }
                self.drain();
                for r in std::mem::take(&mut self.steps_requested) {
                    if self.state != RunState::Run {
                        let _ = r.reply.try_send(reply_err(&r.id, format!("the runtime is in {}", self.state.name())));
                        continue;
                    }
                    let at_scan = self.sim.next_scan();
                    self.run_scan(at_scan, Instant::now());
                    // Halted, the thread may wait for the board: the reply comes after the state.
                    self.publish_blocking();
                    let _ = r.reply.try_send(reply_ok(&r.id, serde_json::json!({"scan": at_scan})));
                }
                if self.state == RunState::Run && !self.halted {
                    self.reanchor = true;
                }
                self.refresh_guards();
                self.publish();
                continue;
            }
            let deadline = at(origin, k);
            let now = Instant::now();
            if deadline > now {
                std::thread::sleep(deadline - now);
            }
            let start = Instant::now();
            self.stats.jitter.add(start.saturating_duration_since(deadline).as_micros() as u64);
            self.drain();
            if self.halted || self.state != RunState::Run || self.reanchor {
                self.publish();
                continue;
            }
            self.sim.skip_to(k);
            let end = self.run_scan(k, start);
            if self.state == RunState::Run {
                self.offer_retain(end);
            }
            let mut next = k + 1;
            if end > at(origin, next) {
                self.stats.overruns += 1;
                let behind = ((end - origin).as_micros() / period.as_micros()) as u64;
                next = behind + 1;
                self.stats.skipped += next - (k + 1);
                self.unpublished_events.push(crate::board::Event::Overrun {
                    scan: k,
                    scan_us: end.saturating_duration_since(start).as_micros() as u64,
                    skipped: next - (k + 1),
                });
            }
            k = next;
            self.publish();
        }
        // The end of the run: an orderly stop puts the outputs to their safe values (a fault
        // already did).
        let faulted = self.state == RunState::Fault;
        if !faulted {
            self.enter_safe_state(RunState::Stop, None, "end");
        } else {
            self.halt_change.push((true, "end".into()));
        }
        let values = crate::retain::capture(&self.sim, &self.retain.leaves);
        let last_scan = self.sim.next_scan().saturating_sub(1);
        if let Some(w) = self.retain.writer.take() {
            w.finish(last_scan, values);
        }
        self.publish_blocking();
        RunReport {
            stats: self.stats.clone(),
            error: self.fault.take(),
            dropped: 0,
            realtime,
            state: self.state,
            modbus: serde_json::Value::Null,
            notices: Vec::new(),
        }
    }

    /// Runs scan `k` (started at `start`) under the watchdog; a fault enters FAULT. Returns
    /// when it ended.
    fn run_scan(&mut self, k: u64, start: Instant) -> Instant {
        if self.limits.watchdog.is_some() {
            self.clock.begin(start, k);
        }
        let result = self.scan_once();
        let end = Instant::now();
        self.clock.end();
        let took = end.saturating_duration_since(start);
        self.stats.duration.add(took.as_micros() as u64);
        self.stats.duration_ns.add(took.as_nanos() as u64);
        let tripped = self.clock.tripped.load(Ordering::Relaxed);
        if !tripped && matches!(&result, Err(e) if e.message == sfc_sim::code::INTERRUPTED) {
            // Interrupted by an orderly stop (Ctrl-C, SIGTERM): not a fault.
            return end;
        }
        match self.limits.watchdog {
            Some(w) if tripped || took > w => self.watchdog_fault(k, took, w),
            _ => {
                if let Err(e) = result {
                    self.error_fault(&e);
                }
            }
        }
        end
    }

    /// Where the fault happened: `step`, `steps`, `action`, `transition`, `line`, `column`.
    fn fault_place(&self, e: Option<&sfc_sim::RuntimeError>, j: &mut serde_json::Value, text: &mut String) {
        if let Some(place) = self.sim.fault_place() {
            if let Some(a) = &place.action {
                j["action"] = serde_json::json!(a);
                text.push_str(&format!(" in action {a}"));
            }
            if let Some(t) = &place.transition {
                j["transition"] = serde_json::json!(t);
                text.push_str(&format!(" in the condition of {t}"));
            }
            if let Some(s) = place.steps.first() {
                j["step"] = serde_json::json!(s);
                let more = if place.steps.len() > 1 {
                    format!(" (and {})", place.steps[1..].join(", "))
                } else {
                    String::new()
                };
                text.push_str(&format!(" of step {s}{more}"));
            }
            j["steps"] = serde_json::json!(place.steps);
        }
        if let Some(e) = e {
            j["line"] = serde_json::json!(e.line);
            j["column"] = serde_json::json!(e.column);
            text.push_str(&format!(", line {} column {}", e.line, e.column));
        }
    }

    fn watchdog_fault(&mut self, k: u64, took: Duration, w: Duration) {
        let err = self.sim.error().cloned();
        let stopped = err.as_ref().is_some_and(|e| e.message == sfc_sim::code::INTERRUPTED);
        let mut j = serde_json::json!({
            "kind": "watchdog", "scan": k, "scanUs": took.as_micros() as u64, "watchdogUs": w.as_micros() as u64,
        });
        let ms = |d: Duration| format!("{:.1} ms", d.as_secs_f64() * 1000.0);
        let mut text = if stopped {
            format!(
                "watchdog: scan {k} ran past the watchdog of {} and was stopped after {} ({} past its deadline)",
                format_time(w.as_micros() as i64),
                ms(took),
                ms(took.saturating_sub(w))
            )
        } else {
            format!(
                "watchdog: scan {k} took {}, more than the watchdog of {}",
                ms(took),
                format_time(w.as_micros() as i64)
            )
        };
        if stopped {
            self.fault_place(err.as_ref(), &mut j, &mut text);
        } else if let Some(e) = err.as_ref() {
            // The scan also faulted on its own.
            text.push_str(&format!("; it faulted at line {} column {}: {}", e.line, e.column, e.message));
        }
        j["message"] = serde_json::json!(text);
        self.unpublished_events.push(j.clone().into());
        self.fault_code = crate::io::FAULT_WATCHDOG;
        self.enter_fault(j, text);
    }

    fn error_fault(&mut self, e: &sfc_sim::RuntimeError) {
        let mut j = serde_json::json!({"kind": "error", "scan": e.scan, "message": e.message});
        let mut text = format!("error: {}:{}: {} (scan {})", e.line, e.column, e.message, e.scan);
        let mut place = String::new();
        self.fault_place(None, &mut j, &mut place);
        j["line"] = serde_json::json!(e.line);
        j["column"] = serde_json::json!(e.column);
        text.push_str(&place);
        self.fault_code = crate::io::FAULT_ERROR;
        self.enter_fault(j, text);
    }

    /// Enters FAULT: safe outputs, retentive values written, the fault on the board and for the
    /// operator.
    fn enter_fault(&mut self, fault: serde_json::Value, text: String) {
        self.faults += 1;
        self.hub.notice(text.clone());
        self.fault = Some(text);
        let values = crate::retain::capture(&self.sim, &self.retain.leaves);
        if let Some(w) = &mut self.retain.writer {
            w.offer(self.sim.next_scan().saturating_sub(1), values);
        }
        self.enter_safe_state(RunState::Fault, Some(fault), "fault");
        if self.wait_in_fault {
            self.hub.notice(format!(
                "sfc run: FAULT: outputs at their safe values ({}); {}",
                self.safe.summary(8),
                self.fault_ways
            ));
        }
    }

    /// Puts the outputs to their safe values (process image, and the state the monitor shows)
    /// and the board into `state`.
    fn enter_safe_state(&mut self, state: RunState, fault: Option<serde_json::Value>, reason: &str) {
        self.state = state;
        {
            let mut img = self.image.lock().unwrap_or_else(|e| e.into_inner());
            for (i, v) in &self.safe.points {
                img.put(&self.points[*i], v);
            }
            let scan = self.unpublished_states.back().or(self.last_state.as_ref()).map_or(0, |s| s.scan);
            let status = self.status(scan);
            write_status(&mut self.status_written, &mut img, status);
        }
        // The newest state with the safe values in place of the chart's: the state not yet
        // published (the scan that faulted), or the one on the board.
        let pending = self.unpublished_states.pop_back();
        let last = pending.clone().or_else(|| self.last_state.clone());
        let mut b = self.hub.lock();
        if let Some(last) = last {
            let mut st = (*last).clone();
            crate::board::shown_values(&self.hub.info, state, &mut st.values);
            let st = Arc::new(st);
            if pending.is_some() {
                self.unpublished_states.push_back(st.clone());
            } else {
                b.replace_latest(st.clone());
            }
            self.last_state = Some(st);
        }
        // The state changes with the values, under one lock: no view pairs the new state with
        // the chart's values.
        while let Some(s) = self.unpublished_states.pop_front() {
            b.push_state(s, |old| {
                if Arc::strong_count(&old) == 1 && self.spare_states.len() < SPARE_STATES {
                    self.spare_states.push(old);
                }
            });
        }
        b.set_state(state, fault);
        drop(b);
        self.halt_change.push((true, reason.to_string()));
    }

    /// Every retain interval, after a completed scan: the retentive values to the writer when
    /// they changed.
    fn offer_retain(&mut self, now: Instant) {
        if now < self.retain.next {
            return;
        }
        self.retain.next = now + self.retain.interval;
        if let Some(w) = &mut self.retain.writer {
            let values = crate::retain::capture(&self.sim, &self.retain.leaves);
            w.offer(self.sim.next_scan().saturating_sub(1), values);
        }
    }

    /// Restarts the chart (monitor `reset`): RETAIN and PERSISTENT values kept when warm, only
    /// PERSISTENT when cold; then RUN.
    fn reset(&mut self, cold: bool) -> serde_json::Value {
        let kept: Vec<(usize, sfc_st::Type, Value)> = self
            .retain
            .leaves
            .iter()
            .filter(|l| !cold || l.persistent)
            .map(|l| (l.slot, l.ty.clone(), self.sim.read_slot(l.slot).cloned().unwrap_or_default()))
            .collect();
        self.sim.restart();
        for (slot, ty, v) in kept {
            let _ = self.sim.write_slot(slot, &ty, v);
        }
        self.interrupt.store(false, Ordering::Relaxed);
        self.clock.tripped.store(false, Ordering::Relaxed);
        let was = self.state;
        self.state = RunState::Run;
        self.fault = None;
        self.restarted = true;
        self.reanchor = true;
        self.hub.lock().set_state(RunState::Run, None);
        if self.halted || was != RunState::Run {
            self.halted = false;
            self.halt_change.push((false, String::new()));
        }
        self.note_errors();
        let mode = if cold { "cold" } else { "warm" };
        let scan = self.sim.next_scan();
        self.unpublished_events.push(serde_json::json!({"kind": "reset", "mode": mode, "scan": scan}).into());
        self.hub.notice(format!("sfc run: {mode} restart from {}: RUN again at scan {scan}", was.name()));
        serde_json::json!({"state": "RUN", "mode": mode, "scan": scan})
    }

    /// The last error record and count of each mechanism, for the board (rare: after a scan
    /// that completed a record, and after a restart).
    fn note_errors(&mut self) {
        let list = self
            .sim
            .mechanisms()
            .into_iter()
            .map(|m| crate::board::MechanismErrors { last: m.last_error, count: m.errors })
            .collect();
        self.unpublished_errors = Some(list);
    }

    /// Handles every waiting command without blocking.
    fn drain(&mut self) {
        while let Ok(r) = self.rx.try_recv() {
            self.command(r);
        }
    }

    /// One scan: inputs in, chart, outputs out, monitor state and breakpoints. Costs what the
    /// scan changed: the state is filled in a recycled buffer, guards are evaluated only while
    /// someone watches, and nothing is allocated unless something happened (an event, a
    /// breakpoint, a write from a client).
    fn scan_once(&mut self) -> Result<(), sfc_sim::RuntimeError> {
        let first = std::mem::take(&mut self.restarted);
        // Inputs: the image when it is free, else the last copy (the scan never waits).
        if !self.points.is_empty() {
            if let Ok(mut img) = self.image.try_lock() {
                for (i, (p, input)) in self.points.iter().zip(self.inputs.iter_mut()).enumerate() {
                    if p.role == Role::Input {
                        if let Some(v) = img.client.get(i) {
                            input.clone_from(v);
                        }
                    }
                }
                if !img.memory_writes.is_empty() {
                    for i in std::mem::take(&mut img.memory_writes) {
                        let Some(p) = self.points.get(i) else { continue };
                        let v = img.get(p);
                        // A rejected value is impossible: the map only admits types of the
                        // register size.
                        let _ = self.sim.write_slot(p.slot.index, &p.slot.ty, v);
                    }
                }
            }
            for (p, input) in self.points.iter().zip(&self.inputs) {
                if p.role == Role::Input {
                    let _ = self.sim.write_slot(p.slot.index, &p.slot.ty, input.clone());
                }
            }
        }
        if !self.pending_sets.is_empty() {
            for (var, v) in std::mem::take(&mut self.pending_sets) {
                if let Some(s) = self.vars.get(var as usize) {
                    let _ = self.sim.write_slot(s.index, &s.ty, v);
                }
            }
        }
        self.apply_forces();
        let result = self.sim.advance().map_err(|e| e.clone());
        self.apply_forces();
        if !self.points.is_empty() {
            if let Ok(mut img) = self.image.try_lock() {
                for (i, p) in self.points.iter().enumerate().filter(|(_, p)| p.role != Role::Input) {
                    // A client's write to memory that arrived while the chart ran is applied
                    // before the next scan; copying the chart's value over it would lose it.
                    if p.role == Role::Memory && img.memory_writes.contains(&i) {
                        continue;
                    }
                    if let Some(v) = self.sim.read_slot(p.slot.index) {
                        img.put(p, v);
                    }
                }
                // The status names the scan whose outputs the image now holds.
                let status = self.status(self.sim.next_scan().saturating_sub(1));
                write_status(&mut self.status_written, &mut img, status);
            }
        }
        self.stats.scans += 1;
        // The state, in a buffer the board handed back when it fell out of the history.
        let mut arc = self.take_state();
        let Some(st) = Arc::get_mut(&mut arc) else {
            return result;
        };
        st.scan = self.sim.next_scan() - 1;
        st.time = self.sim.next_time() - self.sim.options().period;
        self.sim.fired_ids(&mut st.fired);
        self.sim.chart_clocks(&mut st.clocks);
        // The active steps: in full now and then, or after anything but firing transitions
        // changed them; otherwise as the change the fired transitions made.
        let base = self.last_state.as_ref().map(|s| s.scan);
        st.key =
            first || base.is_none() || self.since_key >= crate::board::KEY_EVERY || !self.sim.situation_follows_fired();
        st.base = base.unwrap_or(0);
        if st.key {
            self.sim.active_times_unsorted(&mut st.active);
            self.since_key = 1;
        } else {
            st.active.clear();
            self.since_key += 1;
        }
        if cfg!(debug_assertions) {
            self.check.check(&self.hub.info, &self.sim, st);
        }
        st.guards_known = self.hub.connected.load(Ordering::Relaxed) > 0
            || self.halted
            || self.hub.guards_always.load(Ordering::Relaxed);
        if st.guards_known {
            self.sim.guard_states(&mut st.guards);
        } else {
            st.guards.clear();
        }
        st.values.truncate(self.vars.len());
        for (i, s) in self.vars.iter().enumerate() {
            let v = self.sim.read_slot(s.index);
            match (st.values.get_mut(i), v) {
                (Some(slot), Some(v)) => slot.clone_from(v),
                (Some(slot), None) => *slot = Value::default(),
                (None, v) => st.values.push(v.cloned().unwrap_or_default()),
            }
        }
        st.forced.clear();
        st.forced.extend(self.forced.iter().map(|f| f.0));
        self.sim.action_states(&mut st.actions);
        if self.hub.step_times.load(Ordering::Relaxed) {
            self.sim.step_times(&mut st.times);
        } else {
            st.times.clear();
        }
        let scan = st.scan;
        if !self.sim.last_events().is_empty() {
            let mut events: Vec<&sfc_sim::Event> = self
                .sim
                .last_events()
                .iter()
                // A scan stopped by the watchdog is told as a `watchdog` event.
                .filter(|e| !matches!(e, sfc_sim::Event::Error(x) if x.message == sfc_sim::code::INTERRUPTED))
                .collect();
            events.sort_by_key(|e| e.rank());
            for e in events {
                let mut j = event_json(e);
                crate::board::put(&mut j, "scan", serde_json::json!(scan));
                self.unpublished_events.push(j.into());
            }
        }
        // Error records of supervision timeouts: an event for the monitor, a line in the log.
        for r in self.sim.fresh_error_records() {
            let mut j = r.to_json();
            crate::board::put(&mut j, "timeoutScan", serde_json::json!(r.scan));
            crate::board::put(&mut j, "scan", serde_json::json!(scan));
            self.unpublished_events.push(j.into());
            self.hub.notice(format!("sfc run: scan {scan}: error record: {}", r.message()));
            self.records += 1;
            self.unwritten_record = Some((self.records, r.clone()));
        }
        // The newest record into the Modbus block, when the image is free (else after a later scan).
        if self.unwritten_record.is_some() {
            if let Ok(mut img) = self.image.try_lock() {
                if let Some((count, r)) = self.unwritten_record.take() {
                    let regs = crate::io::record_registers(count, &r, img.order);
                    img.set_record(&regs);
                }
            }
        }
        if !self.sim.fresh_error_records().is_empty() {
            self.note_errors();
        }
        // Breakpoints: a step is hit when a fired transition enters it (or it starts the chart),
        // a transition when it fires.
        if !self.breakpoints.is_empty() {
            let mut hits: Vec<BreakTarget> = Vec::new();
            let mut entered: Vec<u32> =
                st.fired.iter().filter_map(|&t| self.post.get(t as usize)).flatten().copied().collect();
            if first {
                entered.extend(self.initial.iter().copied());
            }
            entered.sort_unstable();
            entered.dedup();
            for s in entered {
                if self.breakpoints.get(&BreakTarget::Step(s)) == Some(&true) {
                    hits.push(BreakTarget::Step(s));
                }
            }
            let mut fired = st.fired.clone();
            fired.sort_unstable();
            fired.dedup();
            for t in fired {
                if self.breakpoints.get(&BreakTarget::Transition(t)) == Some(&true) {
                    hits.push(BreakTarget::Transition(t));
                }
            }
            for h in &hits {
                let (kind, name) = self.target_name(*h);
                self.unpublished_events
                    .push(serde_json::json!({"kind": "breakpoint", kind: name, "scan": scan}).into());
            }
            if !hits.is_empty() && !self.halted {
                self.halted = true;
                self.halt_change.push((true, "breakpoint".into()));
            }
        }
        self.last_state = Some(arc.clone());
        self.unpublished_states.push_back(arc);
        if self.unpublished_states.len() > crate::board::HISTORY {
            // The oldest go, up to the next state in full (the changes after a dropped state
            // could not be shown).
            if let Some(old) = self.unpublished_states.pop_front() {
                self.recycle(old);
            }
            while self.unpublished_states.front().is_some_and(|s| !s.key) {
                if let Some(old) = self.unpublished_states.pop_front() {
                    self.recycle(old);
                }
            }
            if self.unpublished_states.is_empty() {
                self.since_key = u64::MAX;
            }
        }
        result
    }

    /// While halted or stopped: a client that connected after the last scan gets the guards of
    /// the state it sees (the newest state is published again with them).
    fn refresh_guards(&mut self) {
        if self.hub.connected.load(Ordering::Relaxed) == 0 {
            return;
        }
        let Some(newest) = &self.last_state else { return };
        if newest.guards_known {
            return;
        }
        let mut st = (**newest).clone();
        self.sim.guard_states(&mut st.guards);
        st.guards_known = true;
        let st = Arc::new(st);
        self.last_state = Some(st.clone());
        match self.unpublished_states.back_mut() {
            Some(last) if last.scan == st.scan => *last = st,
            _ => self.hub.lock().replace_latest(st),
        }
    }

    /// A state to fill: a recycled one nobody else holds, or a new one.
    fn take_state(&mut self) -> Arc<ScanState> {
        while let Some(mut s) = self.spare_states.pop() {
            if Arc::get_mut(&mut s).is_some() {
                return s;
            }
        }
        Arc::new(ScanState::default())
    }

    /// Keeps a state that left the history for reuse (while no client still holds it, it is
    /// filled again; otherwise it is dropped when the client lets go).
    fn recycle(&mut self, s: Arc<ScanState>) {
        if Arc::strong_count(&s) == 1 && self.spare_states.len() < SPARE_STATES {
            self.spare_states.push(s);
        }
    }

    /// Forcing a located input shows the forced value to Modbus clients (the other points
    /// show it through the scan's outputs).
    fn force_input(&mut self, var: u32, v: Option<Value>) {
        if let Some(i) = self.var_point[var as usize].filter(|&i| self.points[i].role == Role::Input) {
            let mut img = self.image.lock().unwrap_or_else(|e| e.into_inner());
            img.force(i, &self.points[i], v);
        }
    }

    fn apply_forces(&mut self) {
        for (var, v) in &self.forced {
            if let Some(s) = self.vars.get(*var as usize) {
                let _ = self.sim.write_slot(s.index, &s.ty, v.clone());
            }
        }
    }

    fn target_name(&self, t: BreakTarget) -> (&'static str, String) {
        match t {
            BreakTarget::Step(s) => ("step", self.hub.info.step_name(s)),
            BreakTarget::Transition(t) => ("transition", self.hub.info.transition_name(t)),
        }
    }

    fn breakpoint_list(&self) -> serde_json::Value {
        let list: Vec<serde_json::Value> = self
            .breakpoints
            .iter()
            .map(|(&t, &enabled)| {
                let (kind, name) = self.target_name(t);
                serde_json::json!({"kind": kind, "name": name, "enabled": enabled})
            })
            .collect();
        serde_json::Value::Array(list)
    }

    fn command(&mut self, r: Request) {
        let answer: Result<serde_json::Value, String> = match r.command {
            Command::Halt => {
                if !self.halted {
                    self.halted = true;
                    self.halt_change.push((true, "halt".into()));
                }
                Ok(serde_json::json!({"scan": self.sim.next_scan()}))
            }
            Command::Continue => {
                if self.state == RunState::Fault {
                    Err("the runtime is in FAULT: `reset` restarts it".into())
                } else if self.state == RunState::Stop {
                    Err("the runtime is in STOP: `start` runs it again".into())
                } else {
                    if self.halted {
                        self.halted = false;
                        self.halt_change.push((false, String::new()));
                    }
                    Ok(serde_json::Value::Null)
                }
            }
            Command::Step => {
                if !self.halted {
                    Err("`step` runs one scan of a halted runtime: halt first".into())
                } else {
                    // Answered after the scan ran.
                    self.steps_requested.push(r);
                    return;
                }
            }
            Command::Breakpoint { op, target } => match (op, target) {
                (BreakOp::DeleteAll, _) => {
                    self.breakpoints.clear();
                    Ok(())
                }
                (_, None) => Err("name a step or transition".to_string()),
                (BreakOp::Set, Some(t)) => {
                    self.breakpoints.insert(t, true);
                    Ok(())
                }
                (op, Some(t)) => match self.breakpoints.get_mut(&t) {
                    None => Err(format!("no breakpoint on {} `{}`", self.target_name(t).0, self.target_name(t).1)),
                    Some(e) => {
                        match op {
                            BreakOp::Disable => *e = false,
                            BreakOp::Enable => *e = true,
                            _ => {
                                self.breakpoints.remove(&t);
                            }
                        }
                        Ok(())
                    }
                },
            }
            .map(|()| self.breakpoint_list()),
            Command::Breakpoints => Ok(self.breakpoint_list()),
            Command::Force { var, value } => self.convert(var, &value).map(|v| {
                self.forced.retain(|f| f.0 != var);
                self.forced.push((var, v.clone()));
                let s = &self.vars[var as usize];
                let _ = self.sim.write_slot(s.index, &s.ty, v.clone());
                self.force_input(var, Some(v.clone()));
                value_json(&v)
            }),
            Command::Unforce { var } => {
                let released: Vec<u32> = match var {
                    Some(var) => vec![var],
                    None => self.forced.iter().map(|f| f.0).collect(),
                };
                self.forced.retain(|f| !released.contains(&f.0));
                for v in released {
                    self.force_input(v, None);
                }
                Ok(serde_json::Value::Null)
            }
            Command::Reset { cold } => Ok(self.reset(cold)),
            Command::Stop => match self.state {
                RunState::Run => {
                    self.hub.notice("sfc run: STOP (monitor `stop`): outputs at their safe values");
                    let values = crate::retain::capture(&self.sim, &self.retain.leaves);
                    if let Some(w) = &mut self.retain.writer {
                        w.offer(self.sim.next_scan().saturating_sub(1), values);
                    }
                    self.enter_safe_state(RunState::Stop, None, "stop");
                    Ok(serde_json::json!({"state": "STOP"}))
                }
                s => Err(format!("the runtime is in {} already", s.name())),
            },
            Command::Start => match self.state {
                RunState::Stop => {
                    self.state = RunState::Run;
                    self.reanchor = true;
                    self.hub.lock().set_state(RunState::Run, None);
                    self.halted = false;
                    self.halt_change.push((false, String::new()));
                    self.hub.notice("sfc run: RUN (monitor `start`)");
                    Ok(serde_json::json!({"state": "RUN"}))
                }
                RunState::Fault => Err("the runtime is in FAULT: `reset` restarts it".into()),
                RunState::Run => Err("the runtime is in RUN already".into()),
            },
            Command::Set { var, value } => self.convert(var, &value).map(|v| {
                let point = self.var_point.get(var as usize).copied().flatten();
                match point.and_then(|i| Some((i, self.points.get(i)?))) {
                    // A located input keeps the value in the image until a client writes it.
                    Some((i, p)) if p.role == Role::Input => {
                        if let Some(input) = self.inputs.get_mut(i) {
                            *input = v.clone();
                        }
                        if let Ok(mut img) = self.image.lock() {
                            img.write_input(i, &self.points[i], v.clone());
                        }
                    }
                    // The last value per variable: while halted or in STOP no scan takes them.
                    _ => match self.pending_sets.iter_mut().find(|(w, _)| *w == var) {
                        Some(pending) => pending.1 = v.clone(),
                        None => self.pending_sets.push((var, v.clone())),
                    },
                }
                value_json(&v)
            }),
            Command::Explain { step } => match self.sim.explain_step(&step) {
                Some(report) => {
                    let mut j = report.to_json();
                    crate::board::put(&mut j, "elapsedUs", serde_json::json!(report.elapsed));
                    crate::board::put(&mut j, "timeoutUs", serde_json::json!(report.timeout));
                    crate::board::put(&mut j, "lines", serde_json::json!(report.lines()));
                    crate::board::put(&mut j, "scan", serde_json::json!(self.sim.next_scan().saturating_sub(1)));
                    Ok(j)
                }
                None => Err(format!("step `{step}` is not active: only an active step can be stuck")),
            },
            Command::Timing => {
                let stats = self.sim.stats();
                let steps: Vec<serde_json::Value> = stats.steps.iter().map(|s| s.to_json()).collect();
                let runs: Vec<serde_json::Value> = self.sim.runs().iter().map(|m| m.to_json()).collect();
                Ok(
                    serde_json::json!({"scan": self.sim.next_scan().saturating_sub(1), "steps": steps, "mechanisms": runs}),
                )
            }
            Command::Mechanisms => {
                let list: Vec<serde_json::Value> = self.sim.mechanisms().iter().map(|m| m.to_json()).collect();
                let records: Vec<serde_json::Value> =
                    self.sim.error_records().iter().map(sfc_sim::ErrorRecord::to_json).collect();
                Ok(serde_json::json!({
                    "scan": self.sim.next_scan().saturating_sub(1),
                    "mechanisms": list,
                    "errorRecords": records,
                }))
            }
        };
        let line = match answer {
            Ok(v) => reply_ok(&r.id, v),
            Err(e) => reply_err(&r.id, e),
        };
        let _ = r.reply.try_send(line);
    }

    /// A JSON value as the variable's value, checked against its type.
    fn convert(&self, var: u32, value: &serde_json::Value) -> Result<Value, String> {
        let (Some(s), Some(info)) = (self.vars.get(var as usize), self.hub.info.variables.get(var as usize)) else {
            return Err(format!("no variable number {var}"));
        };
        let v = value_from_json(value).ok_or_else(|| format!("`{}`: {value} is not a value", info.name))?;
        Simulation::fit_to(&s.ty, v).map_err(|e| format!("`{}` is {e}", info.name))
    }

    /// The status block for the values of scan `scan`.
    fn status(&self, scan: u64) -> crate::io::Status {
        crate::io::Status {
            state: match self.state {
                RunState::Run => 0,
                RunState::Stop => 1,
                RunState::Fault => 2,
            },
            // As the board says (OPC UA's Halted, the monitor): nothing scans in STOP and FAULT either.
            halted: self.halted || self.state != RunState::Run,
            scan,
            fault: self.fault_code,
            faults: self.faults,
        }
    }

    /// The status block after a change that no scan wrote (halt, continue, stop, start, reset),
    /// when the image is free (else at the next try).
    fn sync_status(&mut self) {
        if self.points.is_empty() {
            return;
        }
        let scan = self.last_state.as_ref().map_or(0, |s| s.scan);
        let status = self.status(scan);
        if self.status_written == Some(status) {
            return;
        }
        let image = self.image.clone();
        if let Ok(mut img) = image.try_lock() {
            write_status(&mut self.status_written, &mut img, status);
        };
    }

    /// Publishes what is waiting, without waiting for the lock.
    fn publish(&mut self) {
        self.sync_status();
        let hub = self.hub.clone();
        let locked = hub.board.try_lock();
        if let Ok(mut b) = locked {
            self.flush(&mut b);
        }
    }

    fn publish_blocking(&mut self) {
        self.sync_status();
        let hub = self.hub.clone();
        let mut b = hub.lock();
        self.flush(&mut b);
    }

    fn flush(&mut self, b: &mut crate::board::Board) {
        while let Some(s) = self.unpublished_states.pop_front() {
            b.push_state(s, |old| self.recycle(old));
        }
        for e in self.unpublished_events.drain(..) {
            b.push_event(e);
        }
        for (halted, reason) in self.halt_change.drain(..) {
            b.push_halt(halted, reason);
        }
        if let Some(errors) = self.unpublished_errors.take() {
            b.errors = Arc::new(errors);
        }
        if self.stats.scans.is_multiple_of(50) || b.halted {
            b.digest = Some(self.stats.digest());
        }
    }
}

/// Writes the status block into the image when it differs from what `written` says the image
/// holds.
fn write_status(written: &mut Option<crate::io::Status>, img: &mut Image, status: crate::io::Status) {
    if *written != Some(status) {
        img.set_status(&status);
        *written = Some(status);
    }
}

/// Debug builds: checks each change the scan thread publishes against the engine (the change
/// applied to the state before it gives the engine's active steps and times). Its lists are
/// kept from scan to scan, so the check allocates nothing per scan either.
#[derive(Debug, Default)]
pub struct ChangeCheck {
    change: crate::board::Change,
    /// The engine's situation after the previous scan (`None` before the first).
    prev: Option<Situation>,
    truth: Vec<(u32, i64)>,
    got: Vec<(u32, i64)>,
}

/// The engine's active steps, chart clocks, time and scan after a scan.
#[derive(Debug, Default)]
struct Situation {
    active: Vec<(u32, i64)>,
    clocks: Vec<i64>,
    time: i64,
    scan: u64,
}

impl ChangeCheck {
    fn check(&mut self, info: &crate::board::ChartInfo, sim: &sfc_sim::Simulation, st: &ScanState) {
        sim.active_times_unsorted(&mut self.truth);
        self.truth.sort_unstable();
        if let (false, Some(p)) = (st.key, self.prev.as_ref()) {
            self.change.apply(info, (&p.active, &p.clocks, p.time), st, &mut self.got);
            self.got.sort_unstable();
            assert_eq!(
                self.got, self.truth,
                "scan {}: the change from scan {} is not the engine's situation",
                st.scan, p.scan
            );
        }
        let prev = self.prev.get_or_insert_with(Default::default);
        prev.active.clone_from(&self.truth);
        prev.clocks.clone_from(&st.clocks);
        (prev.time, prev.scan) = (st.time, st.scan);
    }
}

/// Scheduling of the scan thread.
#[cfg(target_os = "linux")]
mod priority {
    /// `SCHED_FIFO` priority 50 for the calling thread: it then preempts ordinary threads
    /// (compilers, the network side) as soon as its deadline comes. The kernel's real-time
    /// throttling still leaves others 5% of each CPU if a chart loops forever.
    pub fn realtime() -> Result<(), String> {
        let param = libc::sched_param { sched_priority: 50 };
        // SAFETY: plain system call on the calling thread with a valid parameter block.
        let r = unsafe { libc::sched_setscheduler(0, libc::SCHED_FIFO, &param) };
        if r == 0 {
            Ok(())
        } else {
            Err(format!("real-time priority refused: {}", std::io::Error::last_os_error()))
        }
    }

    /// Timer slack of 1 ns: the sleep to the next deadline ends on time, not up to 50 µs later.
    pub fn fine_timer() {
        // SAFETY: prctl with an integer argument changes only this thread's timer slack.
        unsafe {
            libc::prctl(libc::PR_SET_TIMERSLACK, 1 as libc::c_ulong);
        }
    }
}

#[cfg(not(target_os = "linux"))]
mod priority {
    pub fn realtime() -> Result<(), String> {
        Err("real-time priority is implemented for Linux only".into())
    }
    pub fn fine_timer() {}
}
