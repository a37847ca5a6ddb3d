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
/// How many events the runtime keeps for clients that paused or lag.
pub const EVENT_LOG: usize = 1000;

/// What one scan left, in the numbers of the [`ChartInfo`].
///
/// The scan thread fills states in recycled buffers (the board hands back the states that fall
/// out of the history) and in the engine's own order: whoever reads a state sorts what it shows.
#[derive(Debug, Clone, Default)]
pub struct ScanState {
    pub scan: u64,
    /// Virtual time, µs.
    pub time: i64,
    /// Active steps with elapsed time (µs), in no particular order.
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
    /// were made, as the monitor's `mechanisms` and the run log tell them.
    pub errors: Vec<MechanismErrors>,
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
    /// Adds a state to the history; returns the state that fell out of it, for reuse.
    pub fn push_state(&mut self, s: Arc<ScanState>) -> Option<Arc<ScanState>> {
        let old = if self.history.len() == HISTORY { self.history.pop_front() } else { None };
        self.history.push_back(s);
        old
    }
    /// Replaces the newest state by a fuller copy of it (its guards evaluated).
    pub fn replace_latest(&mut self, s: Arc<ScanState>) {
        match self.history.back_mut() {
            Some(last) if last.scan == s.scan => *last = s,
            _ => {
                let _ = self.push_state(s);
            }
        }
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
}

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
        };
        (Arc::new(hub), rx)
    }

    /// Sends a command to the runtime side; `false` when the run has ended.
    pub fn send(&self, r: Request) -> bool {
        let tx = self.commands.lock().unwrap_or_else(|e| e.into_inner()).clone();
        tx.is_some_and(|tx| tx.send(r).is_ok())
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
