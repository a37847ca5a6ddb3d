//! The answers of the HTTP API (`docs/editor.md`) as Rust types. The server writes its answers
//! as JSON; `tests/contract_api.rs` reads every kind of answer back into these types, which
//! refuse unknown fields, so they say exactly what the server sends. The editor's TypeScript
//! types (`web/src/contracts/api.ts`) are generated from them with ts-rs; a test fails when that
//! file is stale (`UPDATE_CONTRACTS=1 cargo test -p sfc-server contracts` writes it anew).

use serde::{Deserialize, Serialize};
use sfc_doc::EditorDoc;

/// `error`, `warning` or `note`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(test, derive(ts_rs::TS))]
#[serde(rename_all = "lowercase")]
pub enum Severity {
    Error,
    Warning,
    Note,
}

/// A diagnostic as the page receives it: `sfc check --format json` with camelCase keys, the
/// code's title, the blocks it concerns and, for a firing-sequence witness, the transition blocks.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[cfg_attr(test, derive(ts_rs::TS))]
#[serde(rename_all = "camelCase", deny_unknown_fields)]
pub struct Diag {
    pub code: String,
    pub severity: Severity,
    /// English message as `sfc check` prints it.
    pub message: String,
    /// English title of the code (the page translates it by `code`).
    pub title: String,
    pub file: String,
    pub line: u32,
    pub column: u32,
    pub end_line: u32,
    pub end_column: u32,
    /// The element name the diagnostic concerns (step, transition or action), if any.
    pub element: Option<String>,
    /// Ids of the blocks it concerns.
    pub element_ids: Vec<String>,
    pub notes: Vec<String>,
    /// Firing sequence (transition names) or variable valuation, for analysis findings.
    #[cfg_attr(test, ts(type = "string[] | Record<string, unknown> | null"))]
    pub witness: serde_json::Value,
    /// For a firing-sequence witness: the transition block ids, in firing order.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    #[cfg_attr(test, ts(optional))]
    pub witness_ids: Option<Vec<String>>,
    /// For a violated requirement (`sfc prove`): its witness, to replay in monitor mode.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    #[cfg_attr(test, ts(optional))]
    pub replay: Option<Replay>,
    /// The POU of the file the diagnostic lies in (its chart's, when it concerns a chart); absent
    /// for one outside every POU (a TYPE, the XML itself). The page lists it under that chart's
    /// tab, or under the file when no chart of the file is that POU.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    #[cfg_attr(test, ts(optional))]
    pub pou: Option<String>,
}

/// A witness of `sfc prove` as the monitor replays it: the inputs to set before each scan.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[cfg_attr(test, derive(ts_rs::TS))]
#[serde(deny_unknown_fields)]
pub struct Replay {
    /// Scan period, a TIME literal.
    pub period: String,
    /// Per scan: `[name, value]` pairs (only the inputs that change).
    #[cfg_attr(test, ts(type = "[string, boolean | number | string][][]"))]
    pub scans: Vec<Vec<(String, serde_json::Value)>>,
    /// The witness scenario file's text.
    pub scenario: String,
    /// The witness scenario file's name (`<chart>.<property>.witness.toml`).
    pub file: String,
}

/// How many properties got each verdict.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(test, derive(ts_rs::TS))]
#[serde(deny_unknown_fields)]
pub struct ProveSummary {
    pub holds: u32,
    pub violated: u32,
    pub unknown: u32,
}

/// `POST /api/prove`: one diagnostic per violated (SFC1002) or undecided (SFC1003) property,
/// or the property file's error (SFC1001); no summary when nothing was proved.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[cfg_attr(test, derive(ts_rs::TS))]
#[serde(rename_all = "camelCase", deny_unknown_fields)]
pub struct ProveResult {
    pub properties_file: String,
    pub diagnostics: Vec<Diag>,
    pub summary: Option<ProveSummary>,
}

/// `st` (textual SFC) or `xml` (PLCopen XML).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(test, derive(ts_rs::TS))]
#[serde(rename_all = "lowercase")]
pub enum FileFormat {
    St,
    Xml,
}

/// `mdi` (charts in tabs) or `host` (one chart for a host application).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(test, derive(ts_rs::TS))]
#[serde(rename_all = "lowercase")]
pub enum SessionMode {
    Mdi,
    Host,
}

/// Host mode as the session reports it.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(test, derive(ts_rs::TS))]
#[serde(deny_unknown_fields)]
pub struct HostInfo {
    #[cfg_attr(test, ts(type = "\"atmt\" | \"eatmt\""))]
    pub fb: String,
    pub nstep: u32,
    pub ntr: u32,
    pub file: String,
    pub result: String,
}

/// `GET /api/session`.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(test, derive(ts_rs::TS))]
#[serde(deny_unknown_fields)]
pub struct Session {
    pub mode: SessionMode,
    pub version: String,
    /// Directories named on the command line (absolute): their charts are served.
    pub roots: Vec<String>,
    /// Files named on the command line (absolute): served alone.
    pub open: Vec<String>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    #[cfg_attr(test, ts(optional))]
    pub host: Option<HostInfo>,
}

/// One entry of `GET /api/files`.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(test, derive(ts_rs::TS))]
#[serde(deny_unknown_fields)]
pub struct FileEntry {
    pub path: String,
    pub format: FileFormat,
}

/// `POST /api/open`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[cfg_attr(test, derive(ts_rs::TS))]
#[serde(deny_unknown_fields)]
pub struct OpenResult {
    pub path: String,
    pub format: FileFormat,
    #[cfg_attr(test, ts(type = "Array<EditorDoc>"))]
    pub charts: Vec<EditorDoc>,
    pub diagnostics: Vec<Diag>,
    /// Hash of the file's bytes when read; sent back on save to detect changes made outside.
    pub hash: String,
    /// Every POU of the file in order (the project tree), charts or not.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    #[cfg_attr(test, ts(optional))]
    pub pous: Option<Vec<PouEntry>>,
}

/// A POU of an opened file, as the project tree lists it.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[cfg_attr(test, derive(ts_rs::TS))]
#[serde(rename_all = "camelCase", deny_unknown_fields)]
pub struct PouEntry {
    pub name: String,
    /// `program`, `functionBlock` or `function`.
    pub kind: String,
    /// The body's language: `SFC`, `ST` or `IL`.
    pub language: String,
    /// Whether the editor opens it as a chart (its body, or an action, is written in SFC).
    pub chart: bool,
    /// Its actions, in order.
    pub actions: Vec<PouAction>,
    /// Its chart's transitions by name (an unnamed one `T<n>`), in order.
    pub transitions: Vec<String>,
}

/// An action of a POU: whether it is written in SFC (a chart of its own).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[cfg_attr(test, derive(ts_rs::TS))]
#[serde(rename_all = "camelCase", deny_unknown_fields)]
pub struct PouAction {
    pub name: String,
    pub sfc: bool,
}

/// `POST /api/save`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[cfg_attr(test, derive(ts_rs::TS))]
#[serde(deny_unknown_fields)]
pub struct SaveResult {
    pub path: String,
    pub hash: String,
    pub diagnostics: Vec<Diag>,
}

/// A build target of `POST /api/build`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(test, derive(ts_rs::TS))]
#[serde(rename_all = "lowercase")]
pub enum BuildTarget {
    Atmt,
    Eatmt,
    St,
    Stl,
    Plcopen,
    Svg,
    Text,
}

/// One rule of a transition table.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(test, derive(ts_rs::TS))]
#[serde(deny_unknown_fields)]
pub struct TableRule {
    pub state: u32,
    /// The input index, `1000 + index` when negated.
    pub condition: u32,
    pub next: u32,
}

/// A transition table: its rules and the timeout of each state in seconds.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[cfg_attr(test, derive(ts_rs::TS))]
#[serde(deny_unknown_fields)]
pub struct Table {
    pub rules: Vec<TableRule>,
    pub timeouts: Vec<f64>,
}

/// `POST /api/build`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[cfg_attr(test, derive(ts_rs::TS))]
#[serde(rename_all = "camelCase", deny_unknown_fields)]
pub struct BuildResult {
    pub ok: bool,
    pub diagnostics: Vec<Diag>,
    /// The built text (the one-line table for atmt/eatmt).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    #[cfg_attr(test, ts(optional))]
    pub output: Option<String>,
    /// atmt/eatmt: the table and the timeout vector.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    #[cfg_attr(test, ts(optional))]
    pub table: Option<Table>,
    /// Host mode: the result file written.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    #[cfg_attr(test, ts(optional))]
    pub result_written: Option<String>,
}

/// What `POST /api/compare` compares the chart with: the file as saved on disk, or as in git
/// HEAD.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(test, derive(ts_rs::TS))]
#[serde(rename_all = "lowercase")]
pub enum CompareAgainst {
    Saved,
    Head,
}

/// What became of an element (`sfc diff`'s kinds).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(test, derive(ts_rs::TS))]
#[serde(rename_all = "lowercase")]
pub enum ChangeKind {
    Added,
    Removed,
    Renamed,
    Changed,
}

/// One change of meaning, as `sfc diff --format json` gives it, with the blocks of the chart
/// on the canvas it concerns.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(test, derive(ts_rs::TS))]
#[serde(rename_all = "camelCase", deny_unknown_fields)]
pub struct CompareChange {
    /// `pou`, `variable`, `step`, `transition`, `action` or `body`.
    pub element: String,
    /// The element's name (the old one when renamed or removed).
    pub name: String,
    pub kind: ChangeKind,
    /// For a change, what changed (`condition`, `steps`, `actions`, `type`, `attribute NAME` …).
    pub what: String,
    pub old: Option<String>,
    pub new: Option<String>,
    /// Ids of the blocks of the current chart it concerns (`step:NAME`, `transition:NAME`, the
    /// action blocks naming an action); none for a variable, the POU, or a removed element.
    pub element_ids: Vec<String>,
}

/// `POST /api/compare`.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(test, derive(ts_rs::TS))]
#[serde(deny_unknown_fields)]
pub struct CompareResult {
    pub against: CompareAgainst,
    /// What the chart was compared with: the file's path, `PATH@HEAD` for git HEAD.
    pub file: String,
    pub pou: String,
    /// Equal in meaning (the layout may differ).
    pub equal: bool,
    /// Added, renamed and changed elements.
    pub changes: Vec<CompareChange>,
    /// Removed elements: the current chart has no block for them.
    pub removed: Vec<CompareChange>,
    /// How many blocks of the chart have another place or size than in the chart the file
    /// opens as (steps and transitions matched by name, through renames).
    pub layout: u32,
    /// A side with errors compared as far as it could be read.
    pub notes: Vec<String>,
}

/// `GET /api/settings` and the answer of `POST /api/settings`: the editor's settings as kept in
/// the user's config directory (`editor.json`), so they outlast the run (and its port).
#[derive(Debug, Clone, Default, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(test, derive(ts_rs::TS))]
#[serde(deny_unknown_fields)]
pub struct Settings {
    /// The language chosen in the status bar (`cs`, `en`, `de`); none: the browser's.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    #[cfg_attr(test, ts(optional))]
    pub language: Option<String>,
    /// Charts opened lately, newest first, as the page opened them (at most 20).
    pub recent: Vec<String>,
    /// The monitor's watch list per chart (its POU's name), at most 200 names each.
    pub watch: std::collections::BTreeMap<String, Vec<String>>,
}

/// `POST /api/settings`: what changes. An absent field stays as it is; `language: null` clears
/// the choice, `recent` replaces the list, and each chart of `watch` gets its list (`null`
/// removes it).
#[derive(Debug, Clone, Default, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(test, derive(ts_rs::TS))]
#[serde(deny_unknown_fields)]
pub struct SettingsUpdate {
    #[serde(default, with = "present", skip_serializing_if = "Option::is_none")]
    #[cfg_attr(test, ts(optional, type = "string | null"))]
    pub language: Option<Option<String>>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    #[cfg_attr(test, ts(optional))]
    pub recent: Option<Vec<String>>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    #[cfg_attr(test, ts(optional, type = "{ [chart in string]?: string[] | null }"))]
    pub watch: Option<std::collections::BTreeMap<String, Option<Vec<String>>>>,
}

/// A field that may be absent (`None`, the default), `null` (`Some(None)`) or a value.
mod present {
    use serde::{Deserialize, Deserializer, Serialize, Serializer};

    pub fn serialize<S: Serializer, T: Serialize>(v: &Option<Option<T>>, s: S) -> Result<S::Ok, S::Error> {
        match v {
            Some(x) => x.serialize(s),
            None => s.serialize_none(),
        }
    }

    pub fn deserialize<'de, D: Deserializer<'de>, T: Deserialize<'de>>(d: D) -> Result<Option<Option<T>>, D::Error> {
        Option::<T>::deserialize(d).map(Some)
    }
}

/// The side `POST /api/resolve` takes of a merge conflict: ours (the element as written, the
/// mark removed) or theirs (the element's text replaced by theirs, removed when they removed it).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(test, derive(ts_rs::TS))]
#[serde(rename_all = "lowercase")]
pub enum ConflictSide {
    Ours,
    Theirs,
}

/// `POST /api/resolve`: the chart with one merge conflict resolved (not written to its file),
/// and the diagnostics of its text as `POST /api/open` gives them.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[cfg_attr(test, derive(ts_rs::TS))]
#[serde(deny_unknown_fields)]
pub struct ResolveResult {
    #[cfg_attr(test, ts(type = "EditorDoc"))]
    pub doc: EditorDoc,
    pub diagnostics: Vec<Diag>,
}

#[cfg(test)]
mod tests {
    use super::*;
    use ts_rs::TS;

    fn declarations() -> String {
        let cfg = ts_rs::Config::default();
        let mut out = String::from(
            "// GENERATED from crates/sfc-server/src/contract.rs by ts-rs: do not edit.\n\
             // `UPDATE_CONTRACTS=1 cargo test -p sfc-server contracts` writes it anew; the test fails when it is stale.\n\
             import type { EditorDoc } from './doc';\n\n",
        );
        for decl in [
            Severity::decl(&cfg),
            Diag::decl(&cfg),
            FileFormat::decl(&cfg),
            SessionMode::decl(&cfg),
            HostInfo::decl(&cfg),
            Session::decl(&cfg),
            FileEntry::decl(&cfg),
            PouAction::decl(&cfg),
            PouEntry::decl(&cfg),
            OpenResult::decl(&cfg),
            SaveResult::decl(&cfg),
            BuildTarget::decl(&cfg),
            TableRule::decl(&cfg),
            Table::decl(&cfg),
            BuildResult::decl(&cfg),
            Replay::decl(&cfg),
            ProveSummary::decl(&cfg),
            ProveResult::decl(&cfg),
            CompareAgainst::decl(&cfg),
            ChangeKind::decl(&cfg),
            CompareChange::decl(&cfg),
            CompareResult::decl(&cfg),
            ConflictSide::decl(&cfg),
            ResolveResult::decl(&cfg),
            Settings::decl(&cfg),
            SettingsUpdate::decl(&cfg),
        ] {
            out.push_str("export ");
            out.push_str(&decl);
            out.push_str("\n\n");
        }
        out.trim_end().to_string() + "\n"
    }

    #[test]
    fn contracts_are_current() {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../web/src/contracts/api.ts");
        let now = declarations();
        if std::env::var_os("UPDATE_CONTRACTS").is_some() {
            std::fs::create_dir_all(path.parent().unwrap()).unwrap();
            std::fs::write(&path, &now).unwrap();
            return;
        }
        let committed = std::fs::read_to_string(&path).unwrap_or_default();
        assert!(
            committed == now,
            "{} is stale: run `UPDATE_CONTRACTS=1 cargo test -p sfc-server contracts`",
            path.display()
        );
    }
}
