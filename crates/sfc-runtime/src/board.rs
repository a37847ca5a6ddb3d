//! The board between a runtime (the scan thread, or the ATMT adapter) and the monitor clients:
//! the last 100 scan states, the event log, and the command channel. The runtime side never
//! waits on it: it publishes with `try_lock` and keeps what it could not publish for the next
//! scan; the clients copy `Arc`s out under the lock and build their JSON outside it.

use crate::jitter::StatsDigest;
use sfc_sim::Value;
use std::collections::VecDeque;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::{mpsc, Arc, Mutex};

/// How many scan states the runtime keeps for `history`.
pub const HISTORY: usize = 100;
/// At most this many states from one that lists the active steps in full to the next.
pub const KEY_EVERY: u64 = 32;
/// How many events the runtime keeps for clients that paused or lag.
pub const EVENT_LOG: usize = 1000;

/// What one scan left, in the numbers of the [`ChartInfo`].
///
/// The scan thread fills states in recycled buffers (the board hands back the states that fall
/// out of the history) and in the engine's own order: whoever reads a state sorts what it shows.
///
/// The active steps are published as a change where the scan only fired transitions: such a
/// state (`key` false) lists no active steps, and whoever reads it takes them from the state
/// before it and its fired transitions ([`Board::tail`], [`Tail::full`]). Every
/// [`KEY_EVERY`]th state, and any state after a start, SFCInit, restart or fault, lists them in
/// full (`key` true). A scan of a dense chart then costs the runtime a copy of what fired, not
/// of every active step.
#[derive(Debug, Clone, Default)]
pub struct ScanState {
    pub scan: u64,
    /// Virtual time, µs.
    pub time: i64,
    /// `active` lists every active step; otherwise it is empty and the active steps are those
    /// of the state of scan `base` changed by `fired`.
    pub key: bool,
    /// The scan of the state this one changes (when not `key`).
    pub base: u64,
    /// Each chart instance's clock (µs) after the scan ([`ChartInfo::charts`] order): a step
    /// that stays active gains what its chart's clock gained.
    pub clocks: Vec<i64>,
    /// Active steps with elapsed time (µs), in no particular order (when `key`; see [`Tail`]).
    pub active: Vec<(u32, i64)>,
    /// Transitions fired in this scan.
    pub fired: Vec<u32>,
    /// Guard values of the transitions leaving active steps, in no particular order; `None`
    /// when the guard faulted. Evaluated only while a monitor client is connected or the run is
    /// halted (a state recorded with nobody watching has none).
    pub guards: Vec<(u32, Option<bool>)>,
    /// The guards were evaluated for this state (someone was watching).
    pub guards_known: bool,
    /// Values of [`ChartInfo::variables`], same order.
    pub values: Vec<Value>,
    /// The actions (numbers of [`ChartInfo::actions`]) whose action control has `Q` or `A`
    /// TRUE: `(action, Q, A)`, in no particular order.
    pub actions: Vec<(u32, bool, bool)>,
    /// The elapsed time (µs) of every step, same order as [`ChartInfo::steps`]: an inactive
    /// step keeps the duration of its last activation (IEC 61131-3 `S.T`). Empty unless
    /// [`Hub::step_times`] asks for it (the active steps' times are in `active`).
    pub times: Vec<i64>,
    /// Forced variables (indices into [`ChartInfo::variables`]).
    pub forced: Vec<u32>,
}

/// A variable the monitor shows.
#[derive(Debug, Clone)]
pub struct VarInfo {
    pub name: String,
    /// IEC type name.
    pub ty: String,
    /// `%IX0.0` for a located variable.
    pub location: Option<String>,
    /// The value it takes in STOP and FAULT (outputs, and variables given a safe value).
    pub safe: Option<Value>,
    /// Where it belongs: inputs, outputs, locals or globals.
    pub section: Section,
}

/// The section of a variable, from its declaration block and its address: `VAR_INPUT` or
/// `AT %I…` is an input, `VAR_OUTPUT` or `AT %Q…` an output, `VAR_GLOBAL`/`VAR_EXTERNAL` a
/// global, anything else (`VAR`, `AT %M…`, `VAR_IN_OUT`, `VAR_TEMP`) a local.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Section {
    Input,
    Output,
    #[default]
    Local,
    Global,
}

impl Section {
    pub fn of(kind: Option<sfc_syntax::ast::VarKind>, location: Option<&str>) -> Section {
        use sfc_syntax::ast::VarKind;
        let loc = location.map(|l| l.trim_start_matches('%').to_ascii_uppercase());
        match (kind, loc.as_deref().and_then(|l| l.chars().next())) {
            (_, Some('I')) | (Some(VarKind::Input), _) => Section::Input,
            (_, Some('Q')) | (Some(VarKind::Output), _) => Section::Output,
            (Some(VarKind::Global | VarKind::External), _) => Section::Global,
            _ => Section::Local,
        }
    }
    /// The folder name in the OPC UA address space.
    pub fn name(self) -> &'static str {
        match self {
            Section::Input => "Inputs",
            Section::Output => "Outputs",
            Section::Local => "Locals",
            Section::Global => "Globals",
        }
    }
}

/// The static description of what a runtime runs (the `hello` message).
#[derive(Debug, Clone)]
pub struct ChartInfo {
    /// `sfc run` or `atmt`.
    pub runtime: &'static str,
    /// The simulator's profile (`iec`, `codesys`, …); `None` for the ATMT adapter, which runs
    /// no chart of its own.
    pub profile: Option<&'static str>,
    pub pou: String,
    /// Scan period, µs (0 when the runtime does not scan on a grid: the ATMT adapter).
    pub period: i64,
    /// Step names and whether each is initial.
    pub steps: Vec<(String, bool)>,
    /// Transition names with their preceding and following steps.
    pub transitions: Vec<(String, Vec<u32>, Vec<u32>)>,
    pub variables: Vec<VarInfo>,
    /// The runtime can halt, single-step, force and write (`false` for the ATMT adapter).
    pub control: bool,
    /// The chart instances (the top POU's chart and each SFC function block instance, the
    /// mechanisms) with the numbers of their steps, transitions and actions; empty for a
    /// runtime that has no such structure (the ATMT adapter: one chart of all steps).
    pub charts: Vec<sfc_sim::ChartOutline>,
    /// Every action (and BOOL variable used as an action) of every chart instance, qualified,
    /// with whether it is a variable.
    pub actions: Vec<(String, bool)>,
}

impl ChartInfo {
    pub fn step_index(&self, name: &str) -> Option<u32> {
        self.steps.iter().position(|(n, _)| n.eq_ignore_ascii_case(name)).map(|i| i as u32)
    }
    pub fn transition_index(&self, name: &str) -> Option<u32> {
        self.transitions.iter().position(|(n, _, _)| n.eq_ignore_ascii_case(name)).map(|i| i as u32)
    }
    /// The name of step `s` (empty for a number the chart does not have).
    pub fn step_name(&self, s: u32) -> String {
        self.steps.get(s as usize).map(|s| s.0.clone()).unwrap_or_default()
    }
    /// The name of transition `t` (empty for a number the chart does not have).
    pub fn transition_name(&self, t: u32) -> String {
        self.transitions.get(t as usize).map(|t| t.0.clone()).unwrap_or_default()
    }
    /// The name of variable `v` (empty for a number the chart does not have).
    pub fn variable_name(&self, v: u32) -> String {
        self.variables.get(v as usize).map(|v| v.name.clone()).unwrap_or_default()
    }
}

/// Puts the safe values in place of the chart's when `state` is STOP or FAULT: the one rule
/// every view of the process image follows (`docs/runtime.md`, "Safe state"). A forced output
/// shows its safe value too.
pub fn shown_values(info: &ChartInfo, state: RunState, values: &mut [Value]) {
    if state == RunState::Run {
        return;
    }
    for (v, slot) in info.variables.iter().zip(values.iter_mut()) {
        if let Some(s) = &v.safe {
            slot.clone_from(s);
        }
    }
}

/// What [`Hub::image`] returns: one consistent reading of the run.
#[derive(Debug, Clone)]
pub struct ImageView {
    pub state: RunState,
    /// Counts changes of `state` (and of its fault).
    pub state_seq: u64,
    pub halted: bool,
    /// The fault, in FAULT.
    pub fault: Option<serde_json::Value>,
    /// The newest scan in full, with the safe values in place in STOP and FAULT (`None` before
    /// the first state is published).
    pub scan: Option<Arc<ScanState>>,
    /// Error records per chart instance.
    pub errors: Arc<Vec<MechanismErrors>>,
    /// The scan thread's statistics.
    pub digest: Option<StatsDigest>,
}

impl ImageView {
    /// The scan number of the values (0 before the first).
    pub fn scan_number(&self) -> u64 {
        self.scan.as_ref().map_or(0, |s| s.scan)
    }

    /// The outputs (`VAR_OUTPUT` and `%Q…`) with the values this reading shows.
    pub fn outputs<'a>(&'a self, info: &'a ChartInfo) -> impl Iterator<Item = (&'a VarInfo, Option<&'a Value>)> {
        info.variables
            .iter()
            .enumerate()
            .filter(|(_, v)| v.section == Section::Output)
            .map(|(i, v)| (v, self.scan.as_ref().and_then(|s| s.values.get(i))))
    }

    /// `sfc run --report`'s line: state, scan, the outputs, the statistics.
    pub fn report_text(&self, info: &ChartInfo) -> String {
        let mut out = self.state.name().to_string();
        if self.halted && self.state == RunState::Run {
            out.push_str(" (halted)");
        }
        match &self.scan {
            Some(s) => out.push_str(&format!(", scan {}", s.scan)),
            None => out.push_str(", before the first scan"),
        }
        let outputs: Vec<String> = self
            .outputs(info)
            .map(|(v, x)| format!("{}={}", v.name, x.map_or("?".to_string(), crate::safe::literal)))
            .collect();
        if !outputs.is_empty() {
            const SHOWN: usize = 12;
            let more = outputs.len().saturating_sub(SHOWN);
            out.push_str("; outputs ");
            out.push_str(&outputs.iter().take(SHOWN).cloned().collect::<Vec<_>>().join(", "));
            if more > 0 {
                out.push_str(&format!(" and {more} more (--report-format json lists them all)"));
            }
        }
        if let Some(d) = &self.digest {
            out.push_str("; ");
            out.push_str(&d.summary());
        }
        out
    }

    /// `sfc run --report --report-format json`'s object.
    pub fn report_json(&self, info: &ChartInfo) -> serde_json::Value {
        let outputs: serde_json::Map<String, serde_json::Value> = self
            .outputs(info)
            .map(|(v, x)| (v.name.clone(), x.map_or(serde_json::Value::Null, crate::protocol::value_json)))
            .collect();
        serde_json::json!({
            "state": self.state.name(),
            "halted": self.halted,
            "scan": self.scan.as_ref().map(|s| s.scan),
            "fault": self.fault,
            "outputs": outputs,
            "stats": self.digest.as_ref().map(StatsDigest::to_json),
        })
    }
}

/// Sets `key` of a JSON object (`j` is always one where this is used; anything else is left as
/// it is rather than panicking).
pub fn put(j: &mut serde_json::Value, key: &str, value: serde_json::Value) {
    if let Some(o) = j.as_object_mut() {
        o.insert(key.to_string(), value);
    }
}

/// How many halts and resumes the board keeps for clients between two ticks.
pub const HALT_LOG: usize = 64;

/// One halt or resume of the runtime.
#[derive(Debug, Clone)]
pub struct HaltChange {
    pub seq: u64,
    pub halted: bool,
    /// `halt`, `breakpoint`, `error` or `end`; empty for a resume.
    pub reason: String,
}

/// A runtime event (`docs/monitor.md`, "event").
#[derive(Debug, Clone)]
pub struct LoggedEvent {
    pub seq: u64,
    pub event: Event,
}

/// A runtime event as the runtime side records it: the frequent ones as plain figures (their
/// JSON is made by the clients that show them), the others in their JSON form.
#[derive(Debug, Clone)]
pub enum Event {
    /// A scan ended after the next deadline; `skipped` periods were skipped.
    Overrun {
        scan: u64,
        scan_us: u64,
        skipped: u64,
    },
    Json(Arc<serde_json::Value>),
}

impl Event {
    /// The event's JSON object (`{"kind":…,…}`).
    pub fn to_json(&self) -> serde_json::Value {
        match self {
            Event::Overrun { scan, scan_us, skipped } => {
                serde_json::json!({"kind": "overrun", "scan": scan, "scanUs": scan_us, "skipped": skipped})
            }
            Event::Json(j) => (**j).clone(),
        }
    }
}

impl From<serde_json::Value> for Event {
    fn from(j: serde_json::Value) -> Event {
        Event::Json(Arc::new(j))
    }
}

/// The state of a runtime (`docs/runtime.md`, "States").
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum RunState {
    /// Scanning (or halted by the debugger: `halted` says so).
    #[default]
    Run,
    /// Stopped in order (end of the run, Ctrl-C, SIGTERM, a monitor `stop`): outputs at their
    /// safe values.
    Stop,
    /// Stopped by the watchdog or a runtime error: outputs at their safe values, Modbus and the
    /// monitor still serving, until a monitor `reset`.
    Fault,
}

impl RunState {
    pub fn name(self) -> &'static str {
        match self {
            RunState::Run => "RUN",
            RunState::Stop => "STOP",
            RunState::Fault => "FAULT",
        }
    }
}

/// Shared, lock-protected part of the board.
#[derive(Debug, Default)]
pub struct Board {
    /// RUN, STOP or FAULT, and a count of changes (so a client tells each one).
    pub state: RunState,
    pub state_seq: u64,
    /// What stopped the run, in FAULT: `{"kind","message","scan","step","steps","action",
    /// "transition","line","column"}`.
    pub fault: Option<serde_json::Value>,
    pub history: VecDeque<Arc<ScanState>>,
    pub events: VecDeque<LoggedEvent>,
    pub next_event: u64,
    /// Scanning is stopped (halt, breakpoint, error or end of run).
    pub halted: bool,
    /// Why, when halted.
    pub reason: String,
    /// Every halt and resume, in order (the last [`HALT_LOG`]): a client that looks only every
    /// tick still tells each one, even a resume followed by a breakpoint hit within a tick.
    pub halts: VecDeque<HaltChange>,
    pub next_halt: u64,
    /// Statistics as JSON (the ATMT adapter's).
    pub stats: serde_json::Value,
    /// The scan thread's statistics as figures (their JSON is made by whoever reads them).
    pub digest: Option<StatsDigest>,
    /// Per chart instance ([`ChartInfo::charts`]): its last completed error record and how many
    /// were made, as the monitor's `mechanisms` and the run log tell them (a new list each
    /// time one changes, so a reader copies a pointer).
    pub errors: Arc<Vec<MechanismErrors>>,
}

/// The error records of one mechanism (`docs/runtime.md`, "OPC UA").
#[derive(Debug, Clone, Default)]
pub struct MechanismErrors {
    pub last: Option<sfc_sim::ErrorRecord>,
    pub count: u64,
}

impl Board {
    /// Enters `state` (with the fault that caused it, in FAULT).
    pub fn set_state(&mut self, state: RunState, fault: Option<serde_json::Value>) {
        if self.state != state || self.fault != fault {
            self.state = state;
            self.fault = fault;
            self.state_seq += 1;
        }
    }
    /// Adds a state to the history and hands the states that fell out of it to `gone`, for
    /// reuse. The history keeps at least [`HISTORY`] states and always starts with a key state
    /// (so each of its states can be shown in full): the oldest states leave it a key state's
    /// run at a time, when the next key state comes (so at most about `HISTORY + 2·KEY_EVERY`
    /// states are kept).
    pub fn push_state(&mut self, s: Arc<ScanState>, mut gone: impl FnMut(Arc<ScanState>)) {
        if !s.key && self.history.is_empty() {
            // Nothing to change: a state that cannot be shown is not kept.
            gone(s);
            return;
        }
        let key = s.key;
        self.history.push_back(s);
        while key && self.history.len() > HISTORY {
            let next_key = self.history.iter().skip(1).position(|s| s.key).map_or(self.history.len(), |i| i + 1);
            if self.history.len() - next_key < HISTORY {
                break;
            }
            for _ in 0..next_key {
                if let Some(old) = self.history.pop_front() {
                    gone(old);
                }
            }
        }
    }
    /// Replaces the newest state by a fuller copy of it (its guards evaluated).
    pub fn replace_latest(&mut self, s: Arc<ScanState>) {
        match self.history.back_mut() {
            Some(last) if last.scan == s.scan => *last = s,
            _ => self.push_state(s, drop),
        }
    }
    /// The states of the history from position `i` (all of them for 0), with the states before
    /// them back to a key state: to be shown in full with [`Tail::full`], outside the lock.
    pub fn tail(&self, i: usize) -> Tail {
        let i = i.min(self.history.len());
        let mut from = i;
        while from > 0 && self.history.get(from).is_none_or(|s| !s.key) {
            from -= 1;
        }
        Tail { states: self.history.range(from..).cloned().collect(), skip: i - from }
    }
    /// The newest state (see [`Board::tail`]).
    pub fn tail_latest(&self) -> Tail {
        self.tail(self.history.len().saturating_sub(1))
    }
    /// The states newer than scan `after` (see [`Board::tail`]).
    pub fn tail_after(&self, after: u64) -> Tail {
        self.tail(self.history.partition_point(|s| s.scan <= after))
    }
    /// The latest statistics as JSON (`docs/monitor.md`, "stats").
    pub fn stats_json(&self) -> serde_json::Value {
        match &self.digest {
            Some(d) => d.to_json(),
            None => self.stats.clone(),
        }
    }
    /// Records a halt (`halted`, with its reason) or a resume.
    pub fn push_halt(&mut self, halted: bool, reason: String) {
        if self.halts.len() == HALT_LOG {
            self.halts.pop_front();
        }
        self.halted = halted;
        self.reason.clone_from(&reason);
        self.halts.push_back(HaltChange { seq: self.next_halt, halted, reason });
        self.next_halt += 1;
    }
    pub fn push_event(&mut self, event: impl Into<Event>) {
        if self.events.len() == EVENT_LOG {
            self.events.pop_front();
        }
        self.events.push_back(LoggedEvent { seq: self.next_event, event: event.into() });
        self.next_event += 1;
    }
}

/// States of the history with what is needed to show them in full ([`Board::tail`]).
#[derive(Debug, Default)]
pub struct Tail {
    states: Vec<Arc<ScanState>>,
    /// The first `skip` states are only there to show the others.
    skip: usize,
}

impl Tail {
    /// The states with their active steps in full (a key state as it is, the others computed
    /// from the one before them, with one running list: only the states asked for are copied).
    pub fn full(self, info: &ChartInfo) -> Vec<Arc<ScanState>> {
        let mut out = Vec::with_capacity(self.states.len().saturating_sub(self.skip));
        let mut change = Change::default();
        let (mut cur, mut next) = (Vec::new(), Vec::new());
        let mut prev: Option<&Arc<ScanState>> = None;
        for (k, st) in self.states.iter().enumerate() {
            if st.key {
                cur.clone_from(&st.active);
            } else if let Some(p) = prev.filter(|p| p.scan != st.scan) {
                // (A state of the same scan as the one before it is a copy of it, with its
                // guards or safe values filled in: the same active steps.)
                debug_assert_eq!(p.scan, st.base, "a change is read after the state it changes");
                change.apply(info, (&cur, &p.clocks, p.time), st, &mut next);
                std::mem::swap(&mut cur, &mut next);
            }
            if k >= self.skip {
                out.push(if st.key {
                    st.clone()
                } else {
                    let mut c = (**st).clone();
                    c.active.clone_from(&cur);
                    c.key = true;
                    Arc::new(c)
                });
            }
            prev = Some(st);
        }
        out
    }
    /// The newest state as published (a change or in full).
    pub fn newest(&self) -> Option<&Arc<ScanState>> {
        self.states.last()
    }
    /// The states asked for as published (a change lists no active steps, but what it fired).
    pub fn published(&self) -> &[Arc<ScanState>] {
        self.states.get(self.skip..).unwrap_or_default()
    }
    /// The newest state in full.
    pub fn last(self, info: &ChartInfo) -> Option<Arc<ScanState>> {
        let skip = self.states.len().checked_sub(1)?;
        Tail { skip, ..self }.full(info).pop()
    }
}

/// The lists [`Change::apply`] works with, kept to be used again.
#[derive(Debug, Default)]
pub struct Change {
    gone: Vec<u32>,
    entered: Vec<u32>,
}

impl Change {
    /// The active steps after `st` (a change) into `out`, from the state before it given as its
    /// active steps, chart clocks and time: the steps before its fired transitions leave, those
    /// after them enter with elapsed time 0, and every other step's time advances by its
    /// chart's clock.
    pub fn apply(
        &mut self,
        info: &ChartInfo,
        (prev_active, prev_clocks, prev_time): (&[(u32, i64)], &[i64], i64),
        st: &ScanState,
        out: &mut Vec<(u32, i64)>,
    ) {
        let Change { gone, entered } = self;
        gone.clear();
        entered.clear();
        for &t in &st.fired {
            if let Some((_, pre, post)) = info.transitions.get(t as usize) {
                gone.extend_from_slice(pre);
                entered.extend_from_slice(post);
            }
        }
        gone.extend_from_slice(entered);
        gone.sort_unstable();
        gone.dedup();
        entered.sort_unstable();
        entered.dedup();
        let advance = |s: u32| {
            let c = info.charts.partition_point(|c| c.steps.end <= s);
            match (st.clocks.get(c), prev_clocks.get(c)) {
                (Some(now), Some(then)) => now - then,
                _ => st.time - prev_time,
            }
        };
        out.clear();
        out.extend(
            prev_active.iter().filter(|(s, _)| gone.binary_search(s).is_err()).map(|&(s, t)| (s, t + advance(s))),
        );
        out.extend(entered.iter().map(|&s| (s, 0)));
    }
}

/// A command a client sends to the runtime side.
#[derive(Debug)]
pub enum Command {
    Halt,
    Continue,
    Step,
    Breakpoint {
        op: BreakOp,
        target: Option<BreakTarget>,
    },
    Breakpoints,
    Force {
        var: u32,
        value: serde_json::Value,
    },
    Unforce {
        var: Option<u32>,
    },
    Set {
        var: u32,
        value: serde_json::Value,
    },
    /// Condition analysis of an active step (its name as in [`ChartInfo::steps`]).
    Explain {
        step: String,
    },
    /// Time analysis per step and per run of each mechanism.
    Timing,
    /// Every SFC instance at a glance (activation bit, active steps, runs, last error record).
    Mechanisms,
    /// Restarts the chart from its initial values (RETAIN kept when warm, PERSISTENT always),
    /// from any state; leaves FAULT.
    Reset {
        cold: bool,
    },
    /// RUN → STOP: scanning stops, outputs go to their safe values.
    Stop,
    /// STOP → RUN: scanning goes on where it stopped.
    Start,
}

impl Command {
    /// Whether a client without the run's token may send it (it only reads the run).
    pub fn watches(&self) -> bool {
        matches!(self, Command::Breakpoints | Command::Explain { .. } | Command::Timing | Command::Mechanisms)
    }
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum BreakOp {
    Set,
    Disable,
    Enable,
    Delete,
    DeleteAll,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum BreakTarget {
    Step(u32),
    Transition(u32),
}

/// A command with where its reply goes: the client's bounded outgoing queue. The runtime
/// answers with `try_send`; a client whose queue is full is being dropped anyway.
#[derive(Debug)]
pub struct Request {
    pub id: serde_json::Value,
    pub command: Command,
    pub reply: tokio::sync::mpsc::Sender<String>,
}

/// What the runtime side and the network side share.
#[derive(Debug)]
pub struct Hub {
    pub info: ChartInfo,
    pub board: Mutex<Board>,
    pub commands: Mutex<Option<mpsc::Sender<Request>>>,
    /// The secret a client needs to force or write.
    pub token: String,
    /// Set to end the run (the scan thread and the supervisor watch it).
    pub stop: AtomicBool,
    /// Set once the run has ended and told its clients: the network side closes.
    pub closing: AtomicBool,
    /// Monitor clients dropped for misbehaving (flooding, garbage, slow reading).
    pub dropped: AtomicU64,
    /// Monitor connections (the limit counts them, handshakes included).
    pub connected: AtomicU64,
    /// Monitor sessions past their handshake; at the end of the run the network side waits
    /// for them to send the end and close.
    pub sessions: AtomicU64,
    /// Lines for the operator (`sfc run` prints them on standard error): the watchdog, faults,
    /// retain, a server that cannot accept. The oldest go when nobody reads them.
    pub notices: Mutex<VecDeque<String>>,
    /// The simulation's interrupt flag (`sfc run`): a stop interrupts a scan that runs away.
    pub interrupt_flag: std::sync::OnceLock<Arc<AtomicBool>>,
    /// Failed tokens per client address (`access.rs`).
    pub guesses: Mutex<crate::access::Guesses>,
    /// Evaluate the guards of enabled transitions in every scan, watched or not (an OPC UA
    /// server publishes them).
    pub guards_always: AtomicBool,
    /// Copy every step's time into each state (an OPC UA server publishes the `T` of
    /// inactive steps; nothing else reads it, so without one the scan leaves it empty).
    pub step_times: AtomicBool,
    /// The newest state in full, as [`Hub::image`] rebuilt it last.
    latest_full: Mutex<Option<FullState>>,
}

/// The newest state as published, whether the safe values were put in, the state in full.
type FullState = (Arc<ScanState>, bool, Arc<ScanState>);

/// Notices kept when nobody reads them.
const NOTICES: usize = 256;

impl Hub {
    pub fn new(info: ChartInfo, token: String) -> (Arc<Hub>, mpsc::Receiver<Request>) {
        let (tx, rx) = mpsc::channel();
        let hub = Hub {
            info,
            board: Mutex::new(Board::default()),
            commands: Mutex::new(Some(tx)),
            token,
            stop: AtomicBool::new(false),
            closing: AtomicBool::new(false),
            dropped: AtomicU64::new(0),
            connected: AtomicU64::new(0),
            sessions: AtomicU64::new(0),
            notices: Mutex::new(VecDeque::new()),
            interrupt_flag: std::sync::OnceLock::new(),
            guesses: Mutex::new(Default::default()),
            guards_always: AtomicBool::new(false),
            step_times: AtomicBool::new(false),
            latest_full: Mutex::new(None),
        };
        (Arc::new(hub), rx)
    }

    /// The newest state of `tail` in full, with the safe values in place when the run is in
    /// `state` STOP or FAULT (the cache holds the last one built).
    fn full_of(&self, tail: Tail, state: RunState) -> Option<Arc<ScanState>> {
        let newest = tail.newest()?.clone();
        let overlay = state != RunState::Run;
        {
            let cached = self.latest_full.lock().unwrap_or_else(|e| e.into_inner());
            if let Some((src, with_safe, full)) = cached.as_ref() {
                if Arc::ptr_eq(src, &newest) && *with_safe == overlay {
                    return Some(full.clone());
                }
            }
        }
        let mut full = tail.last(&self.info)?;
        if overlay {
            let mut st = (*full).clone();
            shown_values(&self.info, RunState::Stop, &mut st.values);
            full = Arc::new(st);
        }
        *self.latest_full.lock().unwrap_or_else(|e| e.into_inner()) = Some((newest, overlay, full.clone()));
        Some(full)
    }

    /// The process image as every view shows it (Modbus's status block, OPC UA, the monitor's
    /// snapshot, `--report`): the run's state and the newest scan's values, the safe values in
    /// place of the chart's in STOP and FAULT (`docs/runtime.md`, "One process image"). The
    /// state and the scan are read under one lock, so a view never pairs FAULT with the values
    /// of a scan that ran before it without its safe values.
    pub fn image(&self) -> ImageView {
        let (tail, state, state_seq, halted, fault, errors, digest) = {
            let b = self.lock();
            (b.tail_latest(), b.state, b.state_seq, b.halted, b.fault.clone(), b.errors.clone(), b.digest)
        };
        let scan = self.full_of(tail, state);
        ImageView { state, state_seq, halted, fault, scan, errors, digest }
    }

    /// Sends a command to the runtime side; `false` when the run has ended.
    pub fn send(&self, r: Request) -> bool {
        let tx = self.commands.lock().unwrap_or_else(|e| e.into_inner()).clone();
        tx.is_some_and(|tx| tx.send(r).is_ok())
    }

    /// Hands a command to the runtime side without waiting for its reply (OPC UA methods and
    /// writes, the Modbus reset); `false` when the run has ended.
    pub fn command(&self, command: Command) -> bool {
        let (reply, _) = tokio::sync::mpsc::channel(1);
        self.send(Request { id: serde_json::Value::Null, command, reply })
    }

    /// Adds a line for the operator.
    pub fn notice(&self, line: impl Into<String>) {
        let mut n = self.notices.lock().unwrap_or_else(|e| e.into_inner());
        if n.len() == NOTICES {
            n.pop_front();
        }
        n.push_back(line.into());
    }

    /// Takes the lines not read yet.
    pub fn take_notices(&self) -> Vec<String> {
        self.notices.lock().unwrap_or_else(|e| e.into_inner()).drain(..).collect()
    }

    /// Interrupts the running scan (a stop of a runtime whose scan may run away).
    pub fn interrupt(&self) {
        if let Some(f) = self.interrupt_flag.get() {
            f.store(true, Ordering::Relaxed);
        }
    }

    pub fn stopping(&self) -> bool {
        self.stop.load(Ordering::Relaxed)
    }

    /// The network side closes (after the end of the run was told).
    pub fn closing(&self) -> bool {
        self.closing.load(Ordering::Relaxed)
    }

    /// Locks the board (a poisoned lock only means a client task panicked while copying).
    pub fn lock(&self) -> std::sync::MutexGuard<'_, Board> {
        self.board.lock().unwrap_or_else(|e| e.into_inner())
    }
}

/// Makes a reply line `{"type":"reply","re":id,"ok":true,"result":…}`.
pub fn reply_ok(id: &serde_json::Value, result: serde_json::Value) -> String {
    serde_json::json!({"type": "reply", "re": id, "ok": true, "result": result}).to_string()
}

/// Makes an error reply line `{"type":"reply","re":id,"ok":false,"error":…}`.
pub fn reply_err(id: &serde_json::Value, error: impl Into<String>) -> String {
    serde_json::json!({"type": "reply", "re": id, "ok": false, "error": error.into()}).to_string()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Two charts: `A0 ⇄ B0` (steps 0, 1; transitions 0, 1) and `A1 → {B1, C1} → A1` (a
    /// simultaneous divergence: steps 2, 3, 4; transitions 2, 3).
    fn info() -> ChartInfo {
        let outline =
            |instance: &str, steps: std::ops::Range<u32>, transitions: std::ops::Range<u32>| sfc_sim::ChartOutline {
                instance: instance.into(),
                path: String::new(),
                pou: instance.into(),
                steps,
                transitions,
                actions: 0..0,
            };
        ChartInfo {
            runtime: "sfc run",
            profile: Some("iec"),
            pou: "P".into(),
            period: 10_000,
            steps: ["A0", "B0", "A1", "B1", "C1"].iter().map(|s| (s.to_string(), s.starts_with('A'))).collect(),
            transitions: vec![
                ("T0".into(), vec![0], vec![1]),
                ("T1".into(), vec![1], vec![0]),
                ("T2".into(), vec![2], vec![3, 4]),
                ("T3".into(), vec![3, 4], vec![2]),
            ],
            variables: Vec::new(),
            control: true,
            charts: vec![outline("P", 0..2, 0..2), outline("Fb", 2..5, 2..4)],
            actions: Vec::new(),
        }
    }

    fn state(scan: u64, key: bool, fired: &[u32], clocks: [i64; 2], active: &[(u32, i64)]) -> Arc<ScanState> {
        Arc::new(ScanState {
            scan,
            time: scan as i64 * 10_000,
            key,
            base: scan.saturating_sub(1),
            clocks: clocks.to_vec(),
            active: if key { active.to_vec() } else { Vec::new() },
            fired: fired.to_vec(),
            ..Default::default()
        })
    }

    fn sorted(st: &ScanState) -> Vec<(u32, i64)> {
        let mut a = st.active.clone();
        a.sort_unstable();
        a
    }

    #[test]
    fn changes_are_shown_in_full_from_the_key_state_before_them() {
        let info = info();
        let mut b = Board::default();
        // Scan 1 fires T0 and T2; the function block's chart is not called in scan 2 (its clock
        // stands still); scan 3 fires T1 and T3, and is then published again with its guards.
        let states = [
            state(0, true, &[], [0, 0], &[(0, 0), (2, 0)]),
            state(1, false, &[0, 2], [10_000, 10_000], &[]),
            state(2, false, &[], [20_000, 10_000], &[]),
            state(3, false, &[1, 3], [30_000, 20_000], &[]),
        ];
        for s in &states {
            b.push_state(s.clone(), |_| panic!("nothing leaves a short history"));
        }
        let mut again = (*states[3]).clone();
        again.guards_known = true;
        b.replace_latest(Arc::new(again));
        let full = b.tail(0).full(&info);
        let got: Vec<Vec<(u32, i64)>> = full.iter().map(|s| sorted(s)).collect();
        assert_eq!(
            got,
            vec![
                vec![(0, 0), (2, 0)],
                vec![(1, 0), (3, 0), (4, 0)],
                vec![(1, 10_000), (3, 0), (4, 0)],
                vec![(0, 0), (2, 0)],
            ]
        );
        assert!(full.iter().all(|s| s.key));
        assert!(full[3].guards_known, "the copy with its guards is the one shown");
        // Any part of the history, and the newest state alone.
        assert_eq!(sorted(&b.tail(2).full(&info)[0]), vec![(1, 10_000), (3, 0), (4, 0)]);
        assert_eq!(b.tail_after(1).full(&info).len(), 2);
        assert_eq!(sorted(&b.tail_latest().last(&info).expect("a state")), vec![(0, 0), (2, 0)]);
        assert!(Board::default().tail_latest().last(&info).is_none());
    }

    /// An overrun skips periods: the scan numbers leave a gap, and a change is read after the
    /// state of the scan it changes (its `base`), not of the scan number before it.
    #[test]
    fn a_change_after_skipped_periods_is_read_from_the_scan_before_the_gap() {
        let info = info();
        let mut b = Board::default();
        let mut after_gap = (*state(3, false, &[0], [30_000, 30_000], &[])).clone();
        after_gap.base = 0;
        for s in [
            state(0, true, &[], [0, 0], &[(0, 0), (2, 0)]),
            Arc::new(after_gap),
            state(4, false, &[], [40_000, 40_000], &[]),
        ] {
            b.push_state(s, |_| panic!("nothing leaves a short history"));
        }
        let got: Vec<(u64, Vec<(u32, i64)>)> =
            b.tail_after(1).full(&info).iter().map(|s| (s.scan, sorted(s))).collect();
        assert_eq!(got, vec![(3, vec![(1, 0), (2, 30_000)]), (4, vec![(1, 10_000), (2, 40_000)])]);
    }

    #[test]
    fn the_history_keeps_its_length_and_starts_with_a_state_in_full() {
        let info = info();
        let mut b = Board::default();
        let mut gone = Vec::new();
        // A change that cannot be shown (no state before it) is not kept.
        b.push_state(state(0, false, &[0], [0, 0], &[]), |s| gone.push(s.scan));
        assert!(b.history.is_empty() && gone == [0]);
        gone.clear();
        for k in 1..=400u64 {
            let key = k % KEY_EVERY == 1;
            // The key states (odd scans) have B0 active: T1 leaves it in even scans, T0 in odd ones.
            let fired: &[u32] = if k % 2 == 0 { &[1] } else { &[0] };
            b.push_state(state(k, key, if key { &[] } else { fired }, [k as i64, 0], &[(k as u32 % 2, 0)]), |s| {
                gone.push(s.scan)
            });
            assert!(b.history.len() >= HISTORY.min(k as usize), "scan {k}: {} states", b.history.len());
            assert!(b.history.len() < HISTORY + 2 * KEY_EVERY as usize, "scan {k}: {} states", b.history.len());
            assert!(b.history[0].key, "scan {k}: the history starts with a change");
        }
        // The states that left are the oldest, in order, each once.
        assert_eq!(gone, (1..=gone.len() as u64).collect::<Vec<_>>());
        let full = b.tail(0).full(&info);
        assert_eq!(full.len(), b.history.len());
        assert!(full.iter().all(|s| s.active == [(s.scan as u32 % 2, 0)]), "B0 in odd scans, A0 in even ones");
    }
}
