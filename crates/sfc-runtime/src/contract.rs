//! The monitor protocol's messages (`docs/monitor.md`) as Rust types. `protocol.rs` writes the
//! messages as JSON; `tests/contract.rs` reads the ones a running chart sends back into these
//! types (which refuse unknown fields), so they say exactly what is sent. The editor's
//! TypeScript types (`web/src/contracts/monitor.ts`) are generated from them with ts-rs; a test
//! fails when that file is stale (`UPDATE_CONTRACTS=1 cargo test -p sfc-runtime contracts`).

use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

/// A variable's value: BOOL as a boolean, integers and reals as numbers, TIME as `T#…`, strings.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[cfg_attr(test, derive(ts_rs::TS))]
#[serde(untagged)]
pub enum MonValue {
    Bool(bool),
    Number(f64),
    Text(String),
}

#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(test, derive(ts_rs::TS))]
#[serde(deny_unknown_fields)]
pub struct StepInfo {
    pub name: String,
    pub initial: bool,
}

#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(test, derive(ts_rs::TS))]
#[serde(deny_unknown_fields)]
pub struct TransitionInfo {
    pub name: String,
    pub from: Vec<String>,
    pub to: Vec<String>,
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[cfg_attr(test, derive(ts_rs::TS))]
#[serde(deny_unknown_fields)]
pub struct VariableInfo {
    pub name: String,
    /// IEC type name (BOOL, INT, UDINT, TIME, REAL, STRING …).
    #[serde(rename = "type")]
    pub ty: String,
    /// `%IX0.0` for a located variable.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    #[cfg_attr(test, ts(optional))]
    pub location: Option<String>,
    /// The output's safe value (`sfc.safe` or the run configuration; FALSE/0 by default), for
    /// the outputs of `sfc run`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    #[cfg_attr(test, ts(optional))]
    pub safe: Option<MonValue>,
}

/// The runtime's state (`docs/runtime.md`, "States").
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(test, derive(ts_rs::TS))]
pub enum RunState {
    #[serde(rename = "RUN")]
    Run,
    #[serde(rename = "STOP")]
    Stop,
    #[serde(rename = "FAULT")]
    Fault,
}

/// What put the runtime in FAULT: the watchdog or a runtime error, and where the scan was.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(test, derive(ts_rs::TS))]
#[serde(rename_all = "camelCase", deny_unknown_fields)]
pub struct Fault {
    /// `watchdog` or `error`.
    pub kind: String,
    pub message: String,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    #[cfg_attr(test, ts(optional, type = "number"))]
    pub scan: Option<u64>,
    /// How long the scan had run when it was stopped (watchdog).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    #[cfg_attr(test, ts(optional, type = "number"))]
    pub scan_us: Option<u64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    #[cfg_attr(test, ts(optional, type = "number"))]
    pub watchdog_us: Option<u64>,
    /// The active step the scan was in (the first of `steps`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    #[cfg_attr(test, ts(optional))]
    pub step: Option<String>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    #[cfg_attr(test, ts(optional))]
    pub steps: Option<Vec<String>>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    #[cfg_attr(test, ts(optional))]
    pub action: Option<String>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    #[cfg_attr(test, ts(optional))]
    pub transition: Option<String>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    #[cfg_attr(test, ts(optional))]
    pub line: Option<u32>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    #[cfg_attr(test, ts(optional))]
    pub column: Option<u32>,
}

/// The `hello` message.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[cfg_attr(test, derive(ts_rs::TS))]
#[serde(rename_all = "camelCase", deny_unknown_fields)]
pub struct Hello {
    #[cfg_attr(test, ts(type = "\"hello\""))]
    #[serde(rename = "type")]
    pub kind: String,
    pub protocol: String,
    pub version: u32,
    pub runtime: String,
    /// The simulator's profile (`iec`, `matiec`, `codesys`, `grafcet`, `logix`, `graph`; `docs/sim.md`,
    /// "Profiles"); absent for the ATMT adapter.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    #[cfg_attr(test, ts(optional))]
    pub profile: Option<String>,
    pub pou: String,
    pub period: String,
    /// False when the runtime can only be watched (no halt, step, force or set).
    pub control: bool,
    pub token_required: bool,
    pub authorized: bool,
    pub halted: bool,
    /// RUN, STOP or FAULT (`docs/runtime.md`, "States").
    pub state: RunState,
    /// In FAULT, what caused it; null otherwise.
    pub fault: Option<Fault>,
    pub history: u32,
    pub steps: Vec<StepInfo>,
    pub transitions: Vec<TransitionInfo>,
    pub variables: Vec<VariableInfo>,
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[cfg_attr(test, derive(ts_rs::TS))]
#[serde(rename_all = "camelCase", deny_unknown_fields)]
pub struct ActiveStep {
    pub step: String,
    pub elapsed: String,
    #[cfg_attr(test, ts(type = "number"))]
    pub elapsed_us: i64,
}

/// One scan's state in full (a `snapshot`, a `history` entry, or deltas merged).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[cfg_attr(test, derive(ts_rs::TS))]
#[serde(rename_all = "camelCase")]
pub struct ScanState {
    #[cfg_attr(test, ts(type = "number"))]
    pub scan: u64,
    pub time: String,
    #[cfg_attr(test, ts(type = "number"))]
    pub time_us: i64,
    pub active: Vec<ActiveStep>,
    pub fired: Vec<String>,
    /// Guard of every transition leaving an active step; null when evaluating it faulted.
    pub guards: BTreeMap<String, Option<bool>>,
    pub vars: BTreeMap<String, MonValue>,
    pub forced: Vec<String>,
}

/// The `snapshot` message: the latest state in full.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[cfg_attr(test, derive(ts_rs::TS))]
#[serde(rename_all = "camelCase", deny_unknown_fields)]
pub struct Snapshot {
    #[cfg_attr(test, ts(type = "\"snapshot\""))]
    #[serde(rename = "type")]
    pub kind: String,
    #[cfg_attr(test, ts(type = "number"))]
    pub scan: u64,
    pub time: String,
    #[cfg_attr(test, ts(type = "number"))]
    pub time_us: i64,
    pub active: Vec<ActiveStep>,
    pub fired: Vec<String>,
    pub guards: BTreeMap<String, Option<bool>>,
    pub vars: BTreeMap<String, MonValue>,
    pub forced: Vec<String>,
    pub halted: bool,
    /// RUN, STOP or FAULT (`sfc run`); in STOP and FAULT `vars` shows the outputs' safe values.
    pub state: RunState,
    /// In FAULT, what caused it; null otherwise.
    pub fault: Option<Fault>,
    /// Scan statistics of the runtime (free form).
    #[cfg_attr(test, ts(type = "Record<string, unknown> | null"))]
    pub stats: serde_json::Value,
}

/// The `delta` message: what changed since the last message (`guards`, `vars`, `forced` and
/// `fired` only when they did).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[cfg_attr(test, derive(ts_rs::TS))]
#[serde(rename_all = "camelCase", deny_unknown_fields)]
pub struct Delta {
    #[cfg_attr(test, ts(type = "\"delta\""))]
    #[serde(rename = "type")]
    pub kind: String,
    #[cfg_attr(test, ts(type = "number"))]
    pub scan: u64,
    pub time: String,
    #[cfg_attr(test, ts(type = "number"))]
    pub time_us: i64,
    pub active: Vec<ActiveStep>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    #[cfg_attr(test, ts(optional))]
    pub fired: Option<Vec<String>>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    #[cfg_attr(test, ts(optional))]
    pub guards: Option<BTreeMap<String, Option<bool>>>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    #[cfg_attr(test, ts(optional))]
    pub vars: Option<BTreeMap<String, MonValue>>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    #[cfg_attr(test, ts(optional))]
    pub forced: Option<Vec<String>>,
}

/// The `state` message: the runtime entered RUN, STOP or FAULT.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[cfg_attr(test, derive(ts_rs::TS))]
#[serde(rename_all = "camelCase", deny_unknown_fields)]
pub struct StateMessage {
    #[cfg_attr(test, ts(type = "\"state\""))]
    #[serde(rename = "type")]
    pub kind: String,
    pub state: RunState,
    /// In FAULT, what caused it; null otherwise.
    pub fault: Option<Fault>,
    /// The last scan that ran.
    #[cfg_attr(test, ts(type = "number"))]
    pub scan: u64,
    /// The outputs as they are now (their safe values in STOP and FAULT).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    #[cfg_attr(test, ts(optional))]
    pub outputs: Option<BTreeMap<String, MonValue>>,
}

#[cfg(test)]
mod tests {
    use super::*;
    use ts_rs::TS;

    fn declarations() -> String {
        let cfg = ts_rs::Config::default();
        let mut out = String::from(
            "// GENERATED from crates/sfc-runtime/src/contract.rs by ts-rs: do not edit.\n\
             // `UPDATE_CONTRACTS=1 cargo test -p sfc-runtime contracts` writes it anew; the test fails when it is stale.\n\n",
        );
        for decl in [
            MonValue::decl(&cfg),
            StepInfo::decl(&cfg),
            TransitionInfo::decl(&cfg),
            VariableInfo::decl(&cfg),
            RunState::decl(&cfg),
            Fault::decl(&cfg),
            Hello::decl(&cfg),
            ActiveStep::decl(&cfg),
            ScanState::decl(&cfg),
            Snapshot::decl(&cfg),
            Delta::decl(&cfg),
            StateMessage::decl(&cfg),
        ] {
            out.push_str("export ");
            out.push_str(&decl);
            out.push_str("\n\n");
        }
        out.trim_end().to_string() + "\n"
    }

    #[test]
    fn contracts_are_current() {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../web/src/contracts/monitor.ts");
        let now = declarations();
        if std::env::var_os("UPDATE_CONTRACTS").is_some() {
            std::fs::create_dir_all(path.parent().unwrap()).unwrap();
            std::fs::write(&path, &now).unwrap();
            return;
        }
        let committed = std::fs::read_to_string(&path).unwrap_or_default();
        assert!(
            committed == now,
            "{} is stale: run `UPDATE_CONTRACTS=1 cargo test -p sfc-runtime contracts`",
            path.display()
        );
    }
}
