//! The scan thread: owns the simulation and runs it on the wall clock.
//!
//! Scan `k` is due at `origin + k·period` and runs at virtual time `k·period`. The thread
//! sleeps to that absolute deadline, measures how late it woke (start jitter) and how long the
//! scan took. A scan that ends after the next deadline is an overrun: the periods already
//! passed are skipped (the next scan is the first one whose deadline is still ahead, and the
//! simulation's virtual time jumps with it, so chart time keeps following the wall clock). With
//! a watchdog, a scan longer than the watchdog stops the run with an error.
//!
//! While halted the thread does not scan; it waits for commands. On `continue` the grid is
//! re-anchored so the next scan is due at once (virtual time does not count the halt).

use crate::board::{reply_err, reply_ok, BreakOp, BreakTarget, Command, Hub, Request, ScanState};
use crate::io::{Image, IoPoint, Role};
use crate::jitter::ScanStats;
use crate::protocol::{event_json, value_from_json, value_json};
use crate::{RunReport, Slot};
use sfc_sim::{Simulation, Value};
use std::collections::{BTreeMap, VecDeque};

/// States kept for reuse: the history's length and a few that clients may still hold.
const SPARE_STATES: usize = crate::board::HISTORY + 8;
use std::sync::mpsc::{Receiver, RecvTimeoutError};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

/// When to end a run.
#[derive(Debug, Clone, Copy, Default)]
pub struct Limits {
    /// Stop after this many scans.
    pub scans: Option<u64>,
    /// Stop after this much wall-clock time.
    pub duration: Option<Duration>,
    /// Stop with an error when one scan takes longer.
    pub watchdog: Option<Duration>,
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
    // Run state.
    pub inputs: Vec<Value>,
    pub forced: Vec<(u32, Value)>,
    pub pending_sets: Vec<(u32, Value)>,
    pub breakpoints: BTreeMap<BreakTarget, bool>,
    pub stats: ScanStats,
    pub unpublished_states: VecDeque<Arc<ScanState>>,
    /// States that left the history, to be filled again.
    pub spare_states: Vec<Arc<ScanState>>,
    /// The state of the last scan.
    pub newest: Option<Arc<ScanState>>,
    pub unpublished_events: Vec<crate::board::Event>,
    /// Halts and resumes not yet published, in order.
    pub halt_change: Vec<(bool, String)>,
    pub error: Option<String>,
    pub steps_requested: Vec<Request>,
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
        self.publish();
        while !self.hub.stopping() {
            if self.limits.scans.is_some_and(|n| self.stats.scans >= n)
                || self.limits.duration.is_some_and(|d| started.elapsed() >= d)
            {
                break;
            }
            if self.halted {
                match self.rx.recv_timeout(Duration::from_millis(20)) {
                    Ok(r) => self.command(r),
                    Err(RecvTimeoutError::Timeout) => {}
                    Err(RecvTimeoutError::Disconnected) => self.halted = false,
                }
                self.drain();
                for r in std::mem::take(&mut self.steps_requested) {
                    if self.error.is_some() {
                        let _ = r.reply.try_send(reply_err(&r.id, "the run stopped on an error"));
                        continue;
                    }
                    self.scan_once();
                    k = self.sim.next_scan();
                    // Halted, the thread may wait for the board: the reply comes after the state.
                    self.publish_blocking();
                    let _ = r.reply.try_send(reply_ok(&r.id, serde_json::json!({"scan": k - 1})));
                }
                if self.error.is_some() {
                    break;
                }
                self.refresh_guards();
                if !self.halted {
                    origin = Instant::now()
                        .checked_sub(Duration::from_micros(period_us.saturating_mul(k)))
                        .unwrap_or(origin);
                }
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
            if self.halted {
                self.publish();
                continue;
            }
            self.sim.skip_to(k);
            self.scan_once();
            let end = Instant::now();
            let took = end - start;
            self.stats.duration.add(took.as_micros() as u64);
            self.stats.duration_ns.add(took.as_nanos() as u64);
            if self.error.is_some() {
                break;
            }
            if let Some(w) = self.limits.watchdog {
                if took > w {
                    let msg = format!(
                        "watchdog: scan {k} took {} µs, more than the watchdog of {} µs",
                        took.as_micros(),
                        w.as_micros()
                    );
                    self.unpublished_events
                        .push(serde_json::json!({"kind": "watchdog", "message": msg, "scan": k}).into());
                    self.error = Some(msg);
                    break;
                }
            }
            let mut next = k + 1;
            if end > at(origin, next) {
                self.stats.overruns += 1;
                let behind = ((end - origin).as_micros() / period.as_micros()) as u64;
                next = behind + 1;
                self.stats.skipped += next - (k + 1);
                self.unpublished_events.push(crate::board::Event::Overrun {
                    scan: k,
                    scan_us: took.as_micros() as u64,
                    skipped: next - (k + 1),
                });
            }
            k = next;
            self.publish();
        }
        self.halt_change.push((true, if self.error.is_some() { "error".into() } else { "end".into() }));
        self.publish_blocking();
        RunReport { stats: self.stats.clone(), error: self.error.take(), dropped: 0, realtime }
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
    fn scan_once(&mut self) {
        let first = self.sim.next_scan() == 0 || self.stats.scans == 0;
        // Inputs: the image when it is free, else the last copy (the scan never waits).
        if let Ok(mut img) = self.image.try_lock() {
            for (i, p) in self.points.iter().enumerate() {
                if p.role == Role::Input {
                    self.inputs[i] = img.get(p);
                }
            }
            if !img.memory_writes.is_empty() {
                let writes = std::mem::take(&mut img.memory_writes);
                for &i in &writes {
                    let p = &self.points[i];
                    let v = img.get(p);
                    // A rejected value is impossible: the map only admits 16-bit types.
                    let _ = self.sim.write_slot(p.slot.index, &p.slot.ty, v);
                }
            }
        }
        for (i, p) in self.points.iter().enumerate() {
            if p.role == Role::Input {
                let _ = self.sim.write_slot(p.slot.index, &p.slot.ty, self.inputs[i].clone());
            }
        }
        if !self.pending_sets.is_empty() {
            for (var, v) in std::mem::take(&mut self.pending_sets) {
                let s = &self.vars[var as usize];
                let _ = self.sim.write_slot(s.index, &s.ty, v);
            }
        }
        self.apply_forces();
        let result = self.sim.advance().map_err(|e| e.clone());
        self.apply_forces();
        if !self.points.is_empty() {
            if let Ok(mut img) = self.image.try_lock() {
                for p in self.points.iter().filter(|p| p.role != Role::Input) {
                    if let Some(v) = self.sim.read_slot(p.slot.index) {
                        img.put(p, v);
                    }
                }
            }
        }
        self.stats.scans += 1;
        // The state, in a buffer the board handed back when it fell out of the history.
        let mut arc = self.take_state();
        let st = Arc::get_mut(&mut arc).expect("a recycled state is not shared");
        st.scan = self.sim.next_scan() - 1;
        st.time = self.sim.next_time() - self.sim.options().period;
        self.sim.active_times_unsorted(&mut st.active);
        self.sim.fired_ids(&mut st.fired);
        st.guards_known = self.hub.connected.load(std::sync::atomic::Ordering::Relaxed) > 0 || self.halted;
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
        let scan = st.scan;
        if !self.sim.last_events().is_empty() {
            let mut events: Vec<&sfc_sim::Event> = self.sim.last_events().iter().collect();
            events.sort_by_key(|e| e.rank());
            for e in events {
                let mut j = event_json(e);
                j["scan"] = serde_json::json!(scan);
                self.unpublished_events.push(j.into());
            }
        }
        // Breakpoints: a step is hit when a fired transition enters it (or it starts the chart),
        // a transition when it fires.
        if !self.breakpoints.is_empty() {
            let mut hits: Vec<BreakTarget> = Vec::new();
            let mut entered: Vec<u32> = st.fired.iter().flat_map(|&t| self.post[t as usize].iter().copied()).collect();
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
        if let Err(e) = result {
            self.error = Some(format!("{}:{}: {} (scan {})", e.line, e.column, e.message, e.scan));
        }
        self.newest = Some(arc.clone());
        self.unpublished_states.push_back(arc);
        if self.unpublished_states.len() > crate::board::HISTORY {
            if let Some(old) = self.unpublished_states.pop_front() {
                self.recycle(old);
            }
        }
    }

    /// While halted: a client that connected after the last scan gets the guards of the state
    /// it sees (the newest state is published again with them).
    fn refresh_guards(&mut self) {
        if self.hub.connected.load(std::sync::atomic::Ordering::Relaxed) == 0 {
            return;
        }
        let Some(newest) = &self.newest else { return };
        if newest.guards_known {
            return;
        }
        let mut st = (**newest).clone();
        self.sim.guard_states(&mut st.guards);
        st.guards_known = true;
        let st = Arc::new(st);
        self.newest = Some(st.clone());
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

    fn apply_forces(&mut self) {
        for (var, v) in &self.forced {
            let s = &self.vars[*var as usize];
            let _ = self.sim.write_slot(s.index, &s.ty, v.clone());
        }
    }

    fn target_name(&self, t: BreakTarget) -> (&'static str, String) {
        match t {
            BreakTarget::Step(s) => ("step", self.hub.info.steps[s as usize].0.clone()),
            BreakTarget::Transition(t) => ("transition", self.hub.info.transitions[t as usize].0.clone()),
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
                if self.error.is_some() {
                    Err("the run stopped on an error".into())
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
                value_json(&v)
            }),
            Command::Unforce { var } => {
                match var {
                    Some(var) => self.forced.retain(|f| f.0 != var),
                    None => self.forced.clear(),
                }
                Ok(serde_json::Value::Null)
            }
            Command::Set { var, value } => self.convert(var, &value).map(|v| {
                match self.var_point[var as usize] {
                    // A located input keeps the value in the image until a client writes it.
                    Some(i) if self.points[i].role == Role::Input => {
                        self.inputs[i] = v.clone();
                        if let Ok(mut img) = self.image.lock() {
                            img.put(&self.points[i], &v);
                        }
                    }
                    _ => self.pending_sets.push((var, v.clone())),
                }
                value_json(&v)
            }),
            Command::Explain { step } => match self.sim.explain_step(&step) {
                Some(report) => {
                    let mut j = report.to_json();
                    j["elapsedUs"] = serde_json::json!(report.elapsed);
                    j["timeoutUs"] = serde_json::json!(report.timeout);
                    j["lines"] = serde_json::json!(report.lines());
                    j["scan"] = serde_json::json!(self.sim.next_scan().saturating_sub(1));
                    Ok(j)
                }
                None => Err(format!("step `{step}` is not active: only an active step can be stuck")),
            },
            Command::Timing => {
                let stats = self.sim.stats();
                let steps: Vec<serde_json::Value> = stats.steps.iter().map(|s| s.to_json()).collect();
                Ok(serde_json::json!({"scan": self.sim.next_scan().saturating_sub(1), "steps": steps}))
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
        let s = &self.vars[var as usize];
        let info = &self.hub.info.variables[var as usize];
        let v = value_from_json(value).ok_or_else(|| format!("`{}`: {value} is not a value", info.name))?;
        Simulation::fit_to(&s.ty, v).map_err(|e| format!("`{}` is {e}", info.name))
    }

    /// Publishes what is waiting, without waiting for the lock.
    fn publish(&mut self) {
        let hub = self.hub.clone();
        let locked = hub.board.try_lock();
        if let Ok(mut b) = locked {
            self.flush(&mut b);
        }
    }

    fn publish_blocking(&mut self) {
        let hub = self.hub.clone();
        let mut b = hub.lock();
        self.flush(&mut b);
    }

    fn flush(&mut self, b: &mut crate::board::Board) {
        while let Some(s) = self.unpublished_states.pop_front() {
            if let Some(old) = b.push_state(s) {
                self.recycle(old);
            }
        }
        for e in self.unpublished_events.drain(..) {
            b.push_event(e);
        }
        for (halted, reason) in self.halt_change.drain(..) {
            b.push_halt(halted, reason);
        }
        if self.stats.scans.is_multiple_of(50) || b.halted {
            b.digest = Some(self.stats.digest());
        }
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
