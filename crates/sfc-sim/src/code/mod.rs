//! Compiled code: the memory layout of every POU and the ST/IL of guards, action bodies, POU
//! bodies, user FUNCTIONs and FUNCTION_BLOCKs and the standard functions and function blocks,
//! compiled once into closures over a flat memory of [`Value`] slots.
//!
//! The contract with the scan engine (`crate::engine`):
//! * Memory is one `Vec<Value>`; the file's globals occupy slots `0..Program::globals.size`.
//!   Every variable is a run of consecutive slots in its POU's frame (arrays and structures
//!   flattened, function block instances nested as their own frame layout).
//! * An SFC POU's frame also holds, for each step, the slots `X` (BOOL) and `T` (TIME), for each
//!   action `Q` and `A` (BOOL), the implicit control variables ([`ControlSlots`]) and one hidden
//!   slot ([`ChartCode::chart_slot`]) holding `Value::Int(index)` of the instance's chart state
//!   in the engine. The engine writes X, T, Q, A; compiled code only reads them.
//! * Calling an instance of a FUNCTION_BLOCK whose body is SFC runs one scan of its chart:
//!   the compiled call copies the inputs, calls [`crate::engine::run_chart`], then copies the
//!   outputs.

use crate::engine::{ChartState, ScanSink};
use crate::value::Value;
use crate::Profile;
use sfc_diagnostics::Span;
use sfc_model::Chart;
use sfc_st::Type;
use sfc_syntax::ast::{PouKind, VarKind};

/// A fault of running code (division by zero, index out of range, …): stops the run.
#[derive(Debug, Clone, PartialEq)]
pub struct Fault {
    pub message: String,
    /// Where in the source (the operator, index expression, call, …).
    pub span: Span,
}

/// What compiled code runs against.
pub struct Ctx<'a> {
    pub mem: &'a mut Vec<Value>,
    pub prog: &'a Program,
    /// Chart states of every SFC instance, indexed by the value of its `chart_slot`.
    pub charts: &'a mut Vec<ChartState>,
    /// Fired transitions and events of nested charts, collected for the scan record.
    pub sink: &'a mut ScanSink,
    /// Virtual time of this scan, µs.
    pub now: i64,
    /// Number of this scan.
    pub scan: u64,
    pub profile: Profile,
    /// What this scan may still spend on loops, jumps and calls.
    pub budget: Budget<'a>,
}

/// Charges one scan may make (a loop iteration, an IL jump, a call of a user POU or action)
/// before it is stopped as a runaway (`docs/sim.md`).
pub const SCAN_BUDGET: u64 = 10_000_000;

/// Charges between two looks at the interrupt flag and the limit: the rarely taken branch.
const CHUNK: u64 = 4096;

/// The work budget of one scan: compiled code charges one unit on every loop back-edge, IL
/// jump and call (nested loops included), so a runaway scan ends with a located fault. The
/// charge is a counter decrement; every [`CHUNK`] charges the limit and the interrupt flag
/// (set by another thread, e.g. a watchdog) are looked at.
#[derive(Debug, Clone)]
pub struct Budget<'a> {
    /// Charges left before the next look.
    fuel: u32,
    /// Charges handed out so far in this scan.
    granted: u64,
    limit: u64,
    interrupt: Option<&'a std::sync::atomic::AtomicBool>,
}

impl Default for Budget<'_> {
    fn default() -> Self {
        Budget::new(SCAN_BUDGET, None)
    }
}

/// The message of a scan stopped by its interrupt flag.
pub const INTERRUPTED: &str = "scan interrupted";

impl<'a> Budget<'a> {
    /// A budget of `limit` charges; a set `interrupt` stops the scan at its next look.
    pub fn new(limit: u64, interrupt: Option<&'a std::sync::atomic::AtomicBool>) -> Budget<'a> {
        Budget { fuel: 0, granted: 0, limit, interrupt }
    }

    /// Charges spent so far (at most [`CHUNK`] early).
    pub fn spent(&self) -> u64 {
        self.granted - u64::from(self.fuel)
    }

    /// Charges one unit; a fault at `span` when the budget is spent or the scan interrupted.
    #[inline(always)]
    pub(crate) fn charge(&mut self, span: Span) -> Result<(), Box<Fault>> {
        if self.fuel == 0 {
            return self.refuel(span);
        }
        self.fuel -= 1;
        Ok(())
    }

    #[cold]
    #[inline(never)]
    fn refuel(&mut self, span: Span) -> Result<(), Box<Fault>> {
        if self.interrupt.is_some_and(|i| i.load(std::sync::atomic::Ordering::Relaxed)) {
            return Err(Box::new(Fault { message: INTERRUPTED.to_string(), span }));
        }
        if self.granted >= self.limit {
            return Err(Box::new(Fault {
                message: format!("runaway scan: more than {} loop iterations, jumps and calls in one scan", self.limit),
                span,
            }));
        }
        let grant = CHUNK.min(self.limit - self.granted);
        self.granted += grant;
        self.fuel = (grant - 1) as u32;
        Ok(())
    }
}

/// A compiled transition condition; the `usize` is the frame base of the chart instance.
pub type Guard = Box<dyn Fn(&mut Ctx<'_>, usize) -> Result<bool, Fault> + Send + Sync>;
/// A compiled statement list (action body, POU body); the `usize` is the frame base.
pub type Block = Box<dyn Fn(&mut Ctx<'_>, usize) -> Result<(), Fault> + Send + Sync>;

/// Where a variable lives: in the frame (offset from the frame base) or among the globals
/// (absolute slot).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Place {
    Local(u32),
    Global(u32),
}

impl Place {
    /// The absolute slot for a frame starting at `base`.
    pub fn slot(self, base: usize) -> usize {
        match self {
            Place::Local(o) => base + o as usize,
            Place::Global(g) => g as usize,
        }
    }
}

/// One declared variable of a frame.
#[derive(Debug, Clone)]
pub struct VarSlot {
    /// The declared spelling.
    pub name: String,
    pub ty: Type,
    pub kind: VarKind,
    /// First slot, relative to the frame base (absolute for globals).
    pub offset: u32,
    /// Number of slots (1 for elementary types).
    pub size: u32,
    /// `AT %IX0.0`, as written.
    pub location: Option<String>,
    /// Not declared by the user: the SFC control variables and the ATMT/EATMT inputs.
    pub implicit: bool,
    /// Declared in a `RETAIN` block: restored on a warm start.
    pub retain: bool,
    /// Declared in a `PERSISTENT` block: restored on warm and cold starts.
    pub persistent: bool,
}

/// The slots of one frame.
#[derive(Debug, Clone, Default)]
pub struct Layout {
    /// Declared (and implicit) variables in declaration order.
    pub vars: Vec<VarSlot>,
    /// Slots of one frame, hidden slots included.
    pub size: u32,
}

/// One compiled POU.
pub struct PouCode {
    /// The declared spelling.
    pub name: String,
    pub kind: PouKind,
    pub layout: Layout,
    pub body: PouBody,
    /// The actions of a POU that is no chart, in declaration order (a chart's are in its
    /// [`ChartCode::bodies`]).
    pub actions: Vec<Block>,
    /// The charts of its actions written in SFC: indices of POUs named `Pou.Action`, placed
    /// after the file's POUs, whose chart lives in this POU's frame.
    pub subs: Vec<usize>,
    /// Terminal labels, the error-code variable and the inputs its calls pass.
    pub wiring: wiring::Wiring,
    /// Its methods and property accessors, run on an instance's frame.
    pub(crate) methods: Vec<MethodCode>,
    /// Its edge-triggered inputs: (input slot, previous value slot, rising), frame offsets.
    pub(crate) edges: Vec<(u32, u32, bool)>,
}

/// A compiled method (or property accessor): the fresh values of its variables, then its code.
pub(crate) struct MethodCode {
    pub init: Vec<compile::InitOp>,
    pub body: Block,
}

pub enum PouBody {
    /// ST or IL body (FUNCTIONs store their result in the variable named like the POU).
    Code(Block),
    Chart(Box<ChartCode>),
}

/// The duration of a timed association.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum DurationCode {
    Literal(i64),
    Variable(Place),
}

/// One association of a step, in the chart's order.
#[derive(Debug, Clone)]
pub struct AssocCode {
    pub duration: Option<DurationCode>,
    /// For a BOOL variable used as an action: where it lives.
    pub variable: Option<Place>,
    /// For a BOOL variable used as an action: its declared spelling.
    pub variable_name: Option<String>,
}

/// Frame offsets of the implicit control variables of an SFC instance (see `docs/sim.md`).
#[derive(Debug, Clone, Copy, Default)]
pub struct ControlSlots {
    /// `SFCInit : BOOL` (input): reset to the initial situation, and hold there while TRUE.
    pub init: u32,
    /// `SFCPause : BOOL` (input): no transition fires and step times stand still while TRUE.
    pub pause: u32,
    /// `SFCQuitError : BOOL` (input): acknowledges `SFCError`.
    pub quit_error: u32,
    /// `SFCError : BOOL` (output): a step stayed active longer than its `sfc.timeout`.
    pub error: u32,
    /// `SFCErrorStep : STRING` (output): the name of that step.
    pub error_step: u32,
    /// `SFCCurrentStep : STRING` (output): the first active step in declaration order.
    pub current_step: u32,
    /// `SFCReset : BOOL` (input) of the chart of an action written in SFC (CODESYS): back to
    /// the initial situation, which is then processed.
    pub reset: Option<u32>,
    /// CODESYS's SFC flags that act only when the POU declares them ("SFC flags"):
    /// `SFCEnableLimit : BOOL`, supervision only while TRUE;
    pub enable_limit: Option<u32>,
    /// `SFCErrorPOU : STRING`, the POU whose step timed out (set with `SFCError`);
    pub error_pou: Option<u32>,
    /// `SFCTrans : BOOL`, TRUE after a call in which a transition fired;
    pub trans: Option<u32>,
    /// `SFCTip`, `SFCTipMode : BOOL`, jogging: a rising edge of `SFCTip` fires the enabled
    /// transitions whatever their conditions; while `SFCTipMode` is TRUE only that does.
    pub tip: Option<u32>,
    pub tip_mode: Option<u32>,
    /// S7-GRAPH's block parameters that the `graph` profile follows when the POU declares them
    /// (the SimaticML import declares the standard interface): `ACK_EF` acknowledges
    /// supervision errors, `INIT_SQ` holds the sequence at its initial steps, `OFF_SQ` switches
    /// it off, `ERR_FLT` (output) is the group error.
    pub ack_ef: Option<u32>,
    pub init_sq: Option<u32>,
    pub off_sq: Option<u32>,
    pub err_flt: Option<u32>,
}

/// A guard the engine evaluates without calling its closure.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum FastGuard {
    /// A BOOL slot of the chart's frame, negated when the flag is set.
    Local(u32, bool),
    /// A BOOL global slot, negated when the flag is set.
    Global(u32, bool),
    Const(bool),
    /// Anything else: call the closure.
    Code,
}

/// A compiled chart.
/// The step members a POU's dialect adds to IEC's `X` and `T`, in their frame slots.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub enum StepMembers {
    #[default]
    Iec,
    /// `sfc.dialect 'logix'`: `Count`, `FS`, `SA`, `LS`, `TMax`.
    Logix,
    /// `sfc.dialect 'graph'`: `U`, the step's time without disturbance.
    Graph,
}

impl StepMembers {
    /// The members of the POU `pou` and how many slots a step needs for them.
    pub(crate) fn of(pou: &sfc_syntax::ast::Pou) -> (StepMembers, u32) {
        if sfc_st::is_dialect(pou, "logix") {
            (StepMembers::Logix, 5)
        } else if sfc_st::is_dialect(pou, "graph") {
            (StepMembers::Graph, 1)
        } else {
            (StepMembers::Iec, 0)
        }
    }
}

pub struct ChartCode {
    /// The model; its conditions and bodies are compiled below and are not used at run time.
    pub chart: Chart,
    /// Per step: frame offsets of `X` and `T`.
    pub step_x: Vec<u32>,
    pub step_t: Vec<u32>,
    /// Per step, the frame offset of the first of the step members its POU's dialect adds
    /// ([`StepMembers`]); empty for other charts.
    pub step_vendor: Vec<u32>,
    pub step_members: StepMembers,
    /// Per action: frame offsets of `Q` and `A`.
    pub action_q: Vec<u32>,
    pub action_a: Vec<u32>,
    /// Per transition, in the chart's order.
    pub guards: Vec<Guard>,
    /// Per transition: the same guard when it is a plain BOOL read, which the engine
    /// evaluates inline (no call).
    pub fast: Vec<FastGuard>,
    /// Per action, in the chart's order.
    pub bodies: Vec<Block>,
    /// Per step: S7-GRAPH's interlock and supervision (`sfc.s7graph.interlock`,
    /// `.supervision`), compiled as guards.
    pub interlocks: Vec<Option<Guard>>,
    pub supervisions: Vec<Option<Guard>>,
    /// Per step, per association (same order as `chart.steps[s].associations`).
    pub associations: Vec<Vec<AssocCode>>,
    /// Per step: its step actions (CODESYS's entry, step and exit actions), in the order
    /// written; empty for most charts.
    pub step_actions: Vec<Vec<(sfc_syntax::ast::StepActionKind, Block)>>,
    pub control: ControlSlots,
    /// Hidden slot holding `Value::Int(i)`: this instance's index in `Ctx::charts`.
    pub chart_slot: u32,
    /// The engine's plan of the net and its action control, built on first use.
    pub plan: std::sync::OnceLock<std::sync::Arc<crate::engine::ChartPlan>>,
}

impl ChartCode {
    /// The engine's plan of this chart.
    #[inline]
    pub fn plan(&self) -> &crate::engine::ChartPlan {
        self.plan_arc()
    }
    pub(crate) fn plan_arc(&self) -> &std::sync::Arc<crate::engine::ChartPlan> {
        self.plan.get_or_init(|| std::sync::Arc::new(crate::engine::ChartPlan::new(self)))
    }
}

/// A retentive elementary value ([`Program::retained`]).
#[derive(Debug, Clone, PartialEq)]
pub struct Retained {
    /// The path as [`Program::resolve`] reads it: `Washes`, `Counts[2]`, `Pump.Hours`.
    pub name: String,
    pub ty: Type,
    /// Absolute memory slot.
    pub slot: usize,
    /// `PERSISTENT`: kept over cold starts too; otherwise `RETAIN`: over warm starts only.
    pub persistent: bool,
}

/// `None` for a variable that is not retentive, else whether it is persistent.
pub(crate) fn class_of(retain: bool, persistent: bool) -> Option<bool> {
    (retain || persistent).then_some(persistent)
}

/// Every POU of a file, compiled.
pub struct Program {
    pub pous: Vec<PouCode>,
    /// The file's VAR_GLOBAL variables; absolute slots `0..globals.size`.
    pub globals: Layout,
    /// Frame templates, initial-value code and standard block layouts used by compiled code,
    /// [`Program::instantiate`] and [`Program::resolve`].
    pub(crate) support: compile::Support,
    /// Compiled for the `matiec` profile: TIME slots hold MatIEC's packed timespecs
    /// (`crate::timespec`), which [`crate::Simulation`] shows and takes as µs.
    pub matiec_time: bool,
}

/// Memory ready for the first scan of one top-level POU.
pub struct Memory {
    /// Initial values of every slot (globals, the top frame, nested instances).
    pub mem: Vec<Value>,
    /// Frame base of the top POU.
    pub top_frame: usize,
    /// Every SFC instance in memory: the top POU (if it is SFC) first, path `""`; nested
    /// instances by their path (`Rev`, `Cells[2].Seq`), in declaration order, depth first.
    pub charts: Vec<ChartInstance>,
}

/// An SFC instance found while laying out memory.
#[derive(Debug, Clone)]
pub struct ChartInstance {
    /// Index in `Program::pous`.
    pub pou: usize,
    /// Absolute frame base.
    pub frame: usize,
    /// Instance path from the top POU: `""` for the top itself, `Rev`, `Cells[2].Seq`.
    pub path: String,
}

thread_local! {
    /// Set while [`Program::compile_with`] compiles for the `matiec` profile: TIME values are
    /// then MatIEC's timespecs packed into `Value::Time` (`crate::timespec`).
    static MATIEC_TIME: std::cell::Cell<bool> = const { std::cell::Cell::new(false) };
}

/// Whether the code being compiled holds TIME as MatIEC's packed timespecs.
pub(crate) fn matiec_time() -> bool {
    MATIEC_TIME.with(|f| f.get())
}

/// A TIME value in µs as the code compiled now holds it.
pub(crate) fn time_of_us(us: i64) -> i64 {
    if matiec_time() {
        crate::timespec::Timespec::from_us(us).pack()
    } else {
        us
    }
}

mod call;
mod compile;
mod convert;
mod expr;
mod il;
mod init;
mod method;
mod ops;
mod place;
mod resolve;
mod rt;
mod stdfb;
mod stdfn;
mod stmt;
mod texpr;
mod unit;
pub mod wiring;
