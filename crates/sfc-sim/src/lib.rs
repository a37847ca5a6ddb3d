//! The SFC simulator: the scan engine of `semantics.md` (profile `iec` and the documented
//! deviations), ST/IL execution compiled to closures, scenarios, traces, condition analysis
//! ("why is this step stuck") and time analysis ("how long did each step take").
//!
//! Nothing here prints, exits or reads the clock: time is virtual (`scan · period`).

pub mod code;
pub mod codesys_check;
pub mod logix_check;
pub mod condition;
pub mod coverage;
pub mod engine;
pub mod explain;
pub mod matiec_check;
pub mod scenario;
mod temporal;
pub mod timespec;
pub mod trace;
pub mod value;

pub use engine::{
    ChartOutline, ErrorRecord, FaultPlace, MechanismRuns, MechanismView, Run, RunEnd, ScanSink, Simulation, Snapshot,
    StateStats, StepStats, TimeStats,
};
pub use explain::{StepReport, TransitionReport};
pub use value::{format_time, parse_time, write_time, Value};

use sfc_diagnostics::Span;

/// Which tool's behaviour to reproduce (`semantics.md`, "Profiles").
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub enum Profile {
    #[default]
    Iec,
    Matiec,
    Codesys,
    Grafcet,
    /// Studio 5000 (Logix 5000) SFC, as Rockwell's manual 1756-PM006 and the Logix Designer
    /// help describe it (docs/sim.md, "The `logix` profile").
    Logix,
    /// Siemens S7-GRAPH (TIA Portal), as the S7-GRAPH manual describes it (docs/sim.md, "The
    /// `graph` profile").
    Graph,
}

impl Profile {
    pub const ALL: [Profile; 6] =
        [Profile::Iec, Profile::Matiec, Profile::Codesys, Profile::Grafcet, Profile::Logix, Profile::Graph];
    /// Parses `iec`, `matiec`, `codesys`, `grafcet`, `logix`, `graph` (any case).
    pub fn from_name(s: &str) -> Option<Profile> {
        Profile::ALL.into_iter().find(|p| p.name().eq_ignore_ascii_case(s))
    }
    pub fn name(self) -> &'static str {
        match self {
            Profile::Iec => "iec",
            Profile::Matiec => "matiec",
            Profile::Codesys => "codesys",
            Profile::Grafcet => "grafcet",
            Profile::Logix => "logix",
            Profile::Graph => "graph",
        }
    }
}

/// Where the profile of a run came from, so that a command can say why it runs with it.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum ProfileSource {
    /// Nobody chose one and the file says nothing: `iec`.
    #[default]
    Default,
    /// The command line (`--profile`), or the caller's own setting.
    Option,
    /// `profile =` in the scenario.
    Scenario,
    /// The chart file is an export of a tool of the CODESYS family, which runs SFC by
    /// CODESYS's rules ([`file_profile`]).
    Vendor(sfc_plcopen::Vendor),
}

/// The profile a chart file runs with when neither the command line nor a scenario names one:
/// the rules of the tool that wrote it. A PLCopen XML export of CODESYS, TwinCAT or e!COCKPIT
/// ([`sfc_plcopen::Imported::vendor`]) runs with `codesys`; any other file (IEC text, Beremiz,
/// OpenPLC) with `iec`. `sfc sim`, `sfc test`, `sfc run` and the editor's simulations choose
/// through this one function.
pub fn file_profile(vendor: Option<sfc_plcopen::Vendor>) -> (Profile, ProfileSource) {
    match vendor {
        Some(v @ sfc_plcopen::Vendor::Studio5000) => (Profile::Logix, ProfileSource::Vendor(v)),
        Some(v @ sfc_plcopen::Vendor::TiaPortal) => (Profile::Graph, ProfileSource::Vendor(v)),
        Some(v) => (Profile::Codesys, ProfileSource::Vendor(v)),
        None => (Profile::Iec, ProfileSource::Default),
    }
}

/// The vendor whose rules a chart file runs by: an export's ([`sfc_plcopen::Imported::vendor`]),
/// or for IEC text, the export it was converted from ([`sfc_plcopen::text_vendor`]).
pub fn chart_vendor(text: &str, imported: Option<&sfc_plcopen::Imported>) -> Option<sfc_plcopen::Vendor> {
    match imported {
        Some(i) => i.vendor,
        None => sfc_plcopen::text_vendor(text),
    }
}

/// The text of the note (`note: …`) a command prints when it runs a chart with the profile its file's vendor chose
/// ([`ProfileSource::Vendor`]): `doing` is what it did (`simulated`, `running`), `file` the chart
/// file as shown, `instead` how to choose IEC 61131-3's rules instead (`--profile iec`).
/// `simulated with profile codesys: lift.xml is a TwinCAT export, and TwinCAT runs SFC by
/// CODESYS's rules (--profile iec to use IEC 61131-3's)`.
pub fn vendor_profile_note(doing: &str, file: &str, vendor: sfc_plcopen::Vendor, instead: &str) -> String {
    // A text converted from an export (`sfc build X.xml --target text`) says where it came from.
    let lower = file.to_ascii_lowercase();
    let is = if lower.ends_with(".xml") || lower.ends_with(".l5x") { "is" } else { "was converted from" };
    let why = match vendor {
        sfc_plcopen::Vendor::Codesys => {
            format!("{file} {is} a CODESYS export ({instead} to use IEC 61131-3's rules)")
        }
        sfc_plcopen::Vendor::Studio5000 => {
            return format!(
                "{doing} with profile logix: {file} {is} a Studio 5000 export, and Logix controllers run SFC by \
                 Rockwell's rules ({instead} to use IEC 61131-3's)"
            );
        }
        sfc_plcopen::Vendor::TiaPortal => {
            return format!(
                "{doing} with profile graph: {file} {is} a TIA Portal export of an S7-GRAPH block, which runs by \
                 S7-GRAPH's rules ({instead} to use IEC 61131-3's)"
            );
        }
        v => {
            let a = if v.name().starts_with(['a', 'e', 'i', 'o', 'u', 'A', 'E', 'I', 'O', 'U']) { "an" } else { "a" };
            format!("{file} {is} {a} {v} export, and {v} runs SFC by CODESYS's rules ({instead} to use IEC 61131-3's)")
        }
    };
    format!("{doing} with profile codesys: {why}")
}

/// How to simulate.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct SimOptions {
    /// Scan period Δ in microseconds (default `T#10ms`).
    pub period: i64,
    pub profile: Profile,
}

impl Default for SimOptions {
    fn default() -> Self {
        SimOptions { period: 10_000, profile: Profile::Iec }
    }
}

/// A runtime event of one scan (`interfaces.md`, "Traces"). Names of steps, transitions and
/// actions of nested SFC instances carry the instance path (`Rev.OpenKM1`).
#[derive(Debug, Clone, PartialEq)]
pub enum Event {
    /// Two or more true transitions without explicit priority share `step`.
    Conflict { step: String, transitions: Vec<String> },
    /// `step` was activated while active, or by two transitions of one scan.
    Unsafe { step: String, transitions: Vec<String> },
    /// Timed associations of `action` on several active steps differ; the first wins.
    Contention { action: String, steps: Vec<String>, qualifiers: Vec<String> },
    /// A runtime error stopped the run.
    Error(RuntimeError),
}

impl Event {
    /// Position in the trace's event order: conflict, unsafe, contention, error.
    pub fn rank(&self) -> u8 {
        match self {
            Event::Conflict { .. } => 0,
            Event::Unsafe { .. } => 1,
            Event::Contention { .. } => 2,
            Event::Error(_) => 3,
        }
    }
    /// The event's kind as the trace and scenario files name it (`conflict`, `unsafe`,
    /// `contention`, `error`).
    pub fn kind(&self) -> &'static str {
        match self {
            Event::Conflict { .. } => "conflict",
            Event::Unsafe { .. } => "unsafe",
            Event::Contention { .. } => "contention",
            Event::Error(_) => "error",
        }
    }

    /// One line for people: `step S2 activated again (by T1)`.
    pub fn describe(&self) -> String {
        match self {
            Event::Conflict { step, transitions } => format!(
                "step {step} has {} true transitions without priority: {}",
                transitions.len(),
                transitions.join(", ")
            ),
            Event::Unsafe { step, transitions } => {
                format!("step {step} gets a second token (from {})", transitions.join(", "))
            }
            Event::Contention { action, steps, qualifiers } => {
                let pairs: Vec<String> = steps.iter().zip(qualifiers).map(|(s, q)| format!("{q} in {s}")).collect();
                let first = pairs.first().cloned().unwrap_or_default();
                format!("action {action} has timed qualifiers that differ: {} ({first} wins)", pairs.join(", "))
            }
            Event::Error(e) => format!("runtime error: {} (line {}, column {})", e.message, e.line, e.column),
        }
    }

    /// The JSON object of the trace format.
    pub fn to_json(&self) -> serde_json::Value {
        use serde_json::json;
        match self {
            Event::Conflict { step, transitions } => {
                json!({"kind": "conflict", "step": step, "transitions": transitions})
            }
            Event::Unsafe { step, transitions } => json!({"kind": "unsafe", "step": step, "transitions": transitions}),
            Event::Contention { action, steps, qualifiers } => {
                json!({"kind": "contention", "action": action, "steps": steps, "qualifiers": qualifiers})
            }
            Event::Error(e) => json!({"kind": "error", "message": e.message, "line": e.line, "column": e.column,
                "scan": e.scan, "time": format_time(e.time)}),
        }
    }
}

/// A fault that stopped the run, located in the source.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct RuntimeError {
    pub message: String,
    pub span: Span,
    /// 1-based line and column of `span.start`.
    pub line: u32,
    pub column: u32,
    pub scan: u64,
    /// Virtual time of the faulting scan, µs.
    pub time: i64,
}

/// What one scan did.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct ScanRecord {
    pub scan: u64,
    /// Virtual time, µs.
    pub time: i64,
    /// Active steps after the scan, sorted by code points (nested instances as `Path.Step`).
    pub active: Vec<String>,
    /// Transitions fired in this scan, in declaration order (top chart first, then nested
    /// instances in the order they ran).
    pub fired: Vec<String>,
    /// Events in the order conflict, unsafe, contention, error.
    pub events: Vec<Event>,
    /// Error records completed in this scan (supervision timeouts with their condition),
    /// written after the events as `{"kind":"supervision",…}`.
    pub errors: Vec<ErrorRecord>,
}
