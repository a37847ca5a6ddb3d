//! Scenario files (`*.scenario.toml`, `interfaces.md` "Scenario files"): loading with located
//! errors, binding the names and values to the chart, and running them against the engine.
//!
//! ```toml
//! chart = "blinker.st"     # relative to this file
//! pou = "Blinker"          # optional when the file has one SFC POU
//! period = "T#100ms"       # scan period, default T#10ms
//! profile = "iec"          # optional
//! until = "T#3s"           # or: scans = 30
//!
//! [[at]]
//! time = "T#0s"
//! set = { Start = true }
//!
//! [[at]]
//! time = "T#200ms"
//! expect = { active = ["S2"], Visible = true, "S2.T" = "T#100ms" }
//! ```
//!
//! Loading ([`load`]) parses the TOML, reads and checks the chart, and binds every name and
//! value to the chart's declarations, so a scenario that loads can only fail by behaviour.
//! Running ([`run`]) applies the `set` values of an entry before the first scan whose time is
//! `≥ time` and checks its `expect` values after that scan.

use crate::condition::Condition;
use crate::coverage::Coverage;
use crate::trace::{value_text, TraceHeader, TraceSink};
use crate::{
    file_profile, format_time, parse_time, Profile, ProfileSource, RuntimeError, ScanRecord, SimOptions, Simulation,
    Value,
};
use sfc_diagnostics::{render_human, Diagnostic, RenderOptions, SourceFile};
use sfc_st::Type;
use std::fmt;
use std::io;
use std::ops::Range;
use std::path::{Component, Path, PathBuf};
use std::sync::Arc;
use toml_edit::{Item, TableLike};

/// The default scan period, `T#10ms`.
pub const DEFAULT_PERIOD: i64 = 10_000;
/// Scans of `sfc sim` without a scenario and without `--scans`/`--until`.
pub const DEFAULT_SCANS: u64 = 100;

// ---------------------------------------------------------------------------------------------
// Errors

/// What kind of problem stopped a scenario from loading (decides the exit status).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ErrorKind {
    /// A file could not be read (exit 2).
    Io,
    /// A command-line value is wrong (`--set`; exit 2).
    Usage,
    /// The scenario file is not valid (exit 1).
    Invalid,
    /// The chart has errors (exit 1).
    Chart,
}

/// Why a scenario could not be loaded. `Display` gives `file:line:column: message` (as much of
/// the location as is known).
#[derive(Debug, Clone)]
pub struct ScenarioError {
    pub kind: ErrorKind,
    /// The file the error is in (the scenario, or the chart for a run without scenario).
    pub file: Option<String>,
    /// 1-based line and column in `file`.
    pub line: Option<u32>,
    pub column: Option<u32>,
    pub message: String,
    /// For [`ErrorKind::Chart`]: the chart's source and its error diagnostics (to render them
    /// in colour); `message` already holds them rendered without colour.
    pub diagnostics: Option<Box<(SourceFile, Vec<Diagnostic>)>>,
}

impl ScenarioError {
    fn new(kind: ErrorKind, file: Option<String>, message: impl Into<String>) -> Self {
        ScenarioError { kind, file, line: None, column: None, message: message.into(), diagnostics: None }
    }
    /// The exit status of the `sfc` command for this error: 2 for I/O and usage, else 1.
    pub fn exit_code(&self) -> u8 {
        match self.kind {
            ErrorKind::Io | ErrorKind::Usage => 2,
            ErrorKind::Invalid | ErrorKind::Chart => 1,
        }
    }
}

impl fmt::Display for ScenarioError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match (&self.file, self.line, self.column) {
            (Some(file), Some(l), Some(c)) => write!(f, "{file}:{l}:{c}: {}", self.message),
            (Some(file), Some(l), None) => write!(f, "{file}:{l}: {}", self.message),
            (Some(file), None, _) => write!(f, "{file}: {}", self.message),
            (None, _, _) => f.write_str(&self.message),
        }
    }
}

impl std::error::Error for ScenarioError {}

/// The name closest to `name`, for "did you mean" hints (the checker's rule).
pub use sfc_st::closest;

fn did_you_mean<'a>(name: &str, candidates: impl IntoIterator<Item = &'a str>) -> String {
    match closest(name, candidates) {
        Some(c) => format!("; did you mean `{c}`?"),
        None => String::new(),
    }
}

// ---------------------------------------------------------------------------------------------
// The scenario

/// How long a run lasts.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum RunLength {
    /// `scans = N`: scans `0 … N-1`.
    Scans(u64),
    /// `until = T`: every scan `k` with `k·Δ ≤ T`.
    Until(i64),
    /// Neither: up to the scan of the last `[[at]]` entry (scan 0 only when there is none).
    LastEntry,
}

/// One expected value.
#[derive(Debug, Clone, PartialEq)]
pub enum Expectation {
    /// `active = [...]`: the exact set of active steps (declared spellings, sorted).
    Active(Vec<String>),
    /// A variable, `Step.X`, `Step.T`, … with the value it must have and its type.
    Value { key: String, value: Value, ty: Type },
    /// An ST BOOL expression that must be TRUE (`expect = "Level > 10 AND NOT Alarm"`).
    Holds(Condition),
    /// `error_record = "text"` (or `"Rev.error_record"` for one instance): the latest error
    /// record of a supervision timeout so far contains `text` (its message, as `sfc sim`
    /// prints it).
    ErrorRecord { instance: Option<String>, text: String },
}

/// A kind of runtime event a scenario can forbid (`forbid = ["unsafe", "conflict"]`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum EventKind {
    Conflict,
    Unsafe,
    Contention,
    /// A step active longer than its `sfc.timeout`.
    Overdue,
    /// A runtime error (which fails a scenario anyway).
    Error,
}

impl EventKind {
    pub const ALL: [EventKind; 5] =
        [EventKind::Conflict, EventKind::Unsafe, EventKind::Contention, EventKind::Overdue, EventKind::Error];
    pub fn name(self) -> &'static str {
        match self {
            EventKind::Conflict => "conflict",
            EventKind::Unsafe => "unsafe",
            EventKind::Contention => "contention",
            EventKind::Overdue => "overdue",
            EventKind::Error => "error",
        }
    }
    /// Parses a kind name (any case).
    pub fn from_name(s: &str) -> Option<EventKind> {
        EventKind::ALL.into_iter().find(|k| k.name().eq_ignore_ascii_case(s))
    }
}

/// One `[[at]]` entry, bound to the chart.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Entry {
    /// µs.
    pub time: i64,
    /// Line of the entry in the scenario file (0 for `--set` values of the command line).
    pub line: u32,
    /// Values written before the entry's scan, in file order.
    pub set: Vec<(String, Value)>,
    /// Values checked after the entry's scan, in file order; with [`Entry::within`], the
    /// condition that must hold at some scan within that time.
    pub expect: Vec<Expectation>,
    /// `to`: the end of the entry's interval (inclusive, µs); without it, the end of the run.
    pub to: Option<i64>,
    /// Must hold after every scan of the interval (a conjunction).
    pub always: Vec<Expectation>,
    /// Must not hold (all together) after any scan of the interval.
    pub never: Vec<Expectation>,
    /// `within`: `expect` must hold at some scan at most this long (µs) after the entry's scan,
    /// or after each rising edge of `after` in the interval.
    pub within: Option<i64>,
    /// The trigger of a response: each scan in the interval where it becomes TRUE.
    pub after: Vec<Expectation>,
    /// Runtime events that fail the scenario when they happen in the interval.
    pub forbid: Vec<EventKind>,
}

impl Entry {
    /// Whether the entry checks anything over an interval (not just at its scan).
    pub fn is_temporal(&self) -> bool {
        !self.always.is_empty() || !self.never.is_empty() || self.within.is_some() || !self.forbid.is_empty()
    }
}

/// A loaded scenario: parsed, its chart read and checked, every name and value bound.
#[derive(Debug, Clone)]
pub struct Scenario {
    /// The scenario file (for a run without scenario file, the chart).
    pub path: PathBuf,
    /// How reports name it: the path as given.
    pub name: String,
    /// The chart file simulated (the scenario's `chart` resolved against the scenario's
    /// directory, or the chart given in [`Overrides::chart`]).
    pub chart: PathBuf,
    /// The chart the scenario file names (resolved), when it names one.
    pub scenario_chart: Option<PathBuf>,
    /// The simulated POU, as declared.
    pub pou: String,
    pub options: SimOptions,
    /// Who chose `options.profile`: the command line, the scenario, the tool that wrote the
    /// chart file (a CODESYS, TwinCAT or e!COCKPIT export runs with `codesys`,
    /// [`crate::file_profile`]), or nobody (`iec`). A command says so when it was the file.
    pub profile_source: ProfileSource,
    pub length: RunLength,
    /// In time order.
    pub entries: Vec<Entry>,
    /// Top-level `forbid`: runtime events that fail the scenario whenever they happen.
    pub forbid: Vec<EventKind>,
    /// Line of the top-level `forbid` (0 when there is none).
    pub forbid_line: u32,
    chart_text: String,
    /// For a PLCopen XML chart: the XML and what its import said (notes and warnings; an
    /// import error stops the load), for the command to show.
    pub import: Option<Box<(SourceFile, Vec<Diagnostic>)>>,
    /// For a PLCopen XML chart: the XML and where the chart text came from in it (runtime
    /// errors are located there).
    located: Option<Arc<(SourceFile, sfc_plcopen::SourceMap)>>,
}

/// Settings that take precedence over the scenario file (`sfc sim` options).
#[derive(Debug, Clone, Default)]
pub struct Overrides {
    /// The chart to simulate instead of the scenario's `chart`.
    pub chart: Option<PathBuf>,
    pub pou: Option<String>,
    /// Scan period, µs.
    pub period: Option<i64>,
    pub profile: Option<Profile>,
    pub length: Option<RunLength>,
    /// `NAME=VALUE` writes before scan 0 (`--set`), value as text, converted by the type.
    pub set: Vec<(String, String)>,
}

impl Scenario {
    /// The chart's text as read when loading.
    pub fn chart_text(&self) -> &str {
        &self.chart_text
    }
    /// The chart file as shown in reports and diagnostics.
    pub fn chart_name(&self) -> String {
        self.chart.display().to_string()
    }
    /// The scan at which an entry of time `time` applies: the first `k` with `k·Δ ≥ time`.
    pub fn scan_of(&self, time: i64) -> u64 {
        let p = self.options.period.max(1);
        if time <= 0 {
            0
        } else {
            (time as u64).div_ceil(p as u64)
        }
    }
    /// How many scans a run has.
    pub fn total_scans(&self) -> u64 {
        let p = self.options.period.max(1);
        match self.length {
            RunLength::Scans(n) => n,
            RunLength::Until(t) if t < 0 => 0,
            RunLength::Until(t) => (t / p) as u64 + 1,
            RunLength::LastEntry => self.entries.iter().map(|e| self.last_scan_of(e) + 1).max().unwrap_or(1),
        }
    }
    /// The last scan with time `≤ t`.
    pub fn scan_at_or_before(&self, t: i64) -> u64 {
        let p = self.options.period.max(1);
        if t < 0 {
            0
        } else {
            (t / p) as u64
        }
    }
    /// The last scan an entry needs to be checked completely: its own scan, the end of its
    /// interval, or its deadline.
    pub fn last_scan_of(&self, e: &Entry) -> u64 {
        let mut last = self.scan_of(e.time);
        if let Some(to) = e.to {
            last = last.max(self.scan_at_or_before(to));
        }
        if let (Some(w), true) = (e.within, e.after.is_empty()) {
            let start = self.scan_of(e.time) as i64 * self.options.period;
            last = last.max(self.scan_at_or_before(start.saturating_add(w)));
        }
        last
    }
    /// Creates a new simulation of the scenario's chart.
    pub fn simulation(&self) -> Result<Simulation, ScenarioError> {
        let mut sim = compile(&self.chart_name(), &self.chart_text, Some(&self.pou), self.options)
            .map_err(|e| ScenarioError { file: Some(self.name.clone()), ..e })?;
        if let Some(l) = &self.located {
            sim.locate_faults_in(l.clone());
        }
        Ok(sim)
    }
    /// The key under which runs of this chart and POU merge their coverage.
    pub fn coverage_key(&self) -> String {
        let canon = std::fs::canonicalize(&self.chart).unwrap_or_else(|_| self.chart.clone());
        format!("{}::{}", canon.display(), self.pou.to_ascii_uppercase())
    }
}

// ---------------------------------------------------------------------------------------------
// Parsing the TOML (no chart needed)

/// A value as written in TOML.
#[derive(Debug, Clone, PartialEq)]
enum Raw {
    Bool(bool),
    Int(i64),
    Float(f64),
    Str(String),
    List(Vec<Raw>),
    /// A TOML date-time (never valid here).
    DateTime,
}

impl Raw {
    fn describe(&self) -> String {
        match self {
            Raw::Bool(b) => format!("the boolean {b}"),
            Raw::Int(i) => format!("the integer {i}"),
            Raw::Float(f) => format!("the float {f:?}"),
            Raw::Str(s) => format!("the string {s:?}"),
            Raw::List(_) => "an array".into(),
            Raw::DateTime => "a TOML date-time".into(),
        }
    }
}

#[derive(Debug, Clone)]
struct RawAssign {
    key: String,
    value: Raw,
    line: u32,
    column: u32,
}

/// A condition as written: a table of expected values and/or an ST expression.
#[derive(Debug, Clone, Default)]
struct RawCond {
    assigns: Vec<RawAssign>,
    /// `(text, line, column)`.
    expr: Option<(String, u32, u32)>,
}

impl RawCond {
    fn is_empty(&self) -> bool {
        self.assigns.is_empty() && self.expr.is_none()
    }
}

#[derive(Debug, Clone, Default)]
struct RawEntry {
    time: i64,
    line: u32,
    set: Vec<RawAssign>,
    expect: RawCond,
    to: Option<i64>,
    always: Option<RawCond>,
    never: Option<RawCond>,
    within: Option<i64>,
    after: Option<RawCond>,
    /// `(name, line, column)`.
    forbid: Vec<(String, u32, u32)>,
}

#[derive(Debug, Clone, Default)]
struct Parsed {
    /// `(value, line, column)`.
    chart: Option<(String, u32, u32)>,
    pou: Option<(String, u32, u32)>,
    period: Option<i64>,
    profile: Option<Profile>,
    length: Option<RunLength>,
    entries: Vec<RawEntry>,
    /// Top-level `forbid`: `(name, line, column)`, and the key's line.
    forbid: Vec<(String, u32, u32)>,
    forbid_line: u32,
}

struct Src<'a> {
    file: &'a str,
    text: &'a str,
}

const TOP_KEYS: [&str; 8] = ["chart", "pou", "period", "profile", "until", "scans", "forbid", "at"];
const ENTRY_KEYS: [&str; 9] = ["time", "set", "expect", "to", "always", "never", "within", "after", "forbid"];

impl Src<'_> {
    fn pos(&self, offset: usize) -> (u32, u32) {
        let offset = offset.min(self.text.len());
        let before = &self.text.as_bytes()[..offset];
        let line = before.iter().filter(|b| **b == b'\n').count() as u32 + 1;
        let start = before.iter().rposition(|b| *b == b'\n').map_or(0, |p| p + 1);
        let column = String::from_utf8_lossy(&before[start..]).chars().count() as u32 + 1;
        (line, column)
    }
    fn err(&self, span: Option<Range<usize>>, message: impl Into<String>) -> ScenarioError {
        let mut e = ScenarioError::new(ErrorKind::Invalid, Some(self.file.to_string()), message);
        if let Some(span) = span {
            let (l, c) = self.pos(span.start);
            e.line = Some(l);
            e.column = Some(c);
        }
        e
    }
    /// The span of `key` in `table`, else of its value.
    fn key_span(&self, table: &dyn TableLike, key: &str) -> Option<Range<usize>> {
        table.key(key).and_then(|k| k.span()).or_else(|| table.get(key).and_then(Item::span))
    }
    fn string(&self, table: &dyn TableLike, key: &str, item: &Item, what: &str) -> Result<String, ScenarioError> {
        match item.as_str() {
            Some(s) => Ok(s.to_string()),
            None => Err(self.err(
                item.span().or_else(|| self.key_span(table, key)),
                format!("`{key}` must be a string ({what}), found {}", type_name(item)),
            )),
        }
    }
    fn time(&self, table: &dyn TableLike, key: &str, item: &Item) -> Result<i64, ScenarioError> {
        let s = self.string(table, key, item, "a TIME literal such as \"T#100ms\"")?;
        parse_time(&s).ok_or_else(|| {
            self.err(
                item.span(),
                format!("`{key}`: `{s}` is not a TIME literal (write e.g. \"T#100ms\" or \"T#1s500ms\"; 1 us is the finest unit)"),
            )
        })
    }
}

/// What a TOML item is, in the words of an error message ("a string", "a table"…); the
/// property files of `sfc prove` report with the same words.
pub fn type_name(item: &Item) -> &'static str {
    match item {
        Item::None => "nothing",
        Item::Value(v) => match v {
            toml_edit::Value::String(_) => "a string",
            toml_edit::Value::Integer(_) => "an integer",
            toml_edit::Value::Float(_) => "a float",
            toml_edit::Value::Boolean(_) => "a boolean",
            toml_edit::Value::Datetime(_) => "a date-time",
            toml_edit::Value::Array(_) => "an array",
            toml_edit::Value::InlineTable(_) => "a table",
        },
        Item::Table(_) => "a table",
        Item::ArrayOfTables(_) => "an array of tables",
    }
}

fn raw_of(v: &toml_edit::Value) -> Raw {
    match v {
        toml_edit::Value::String(s) => Raw::Str(s.value().clone()),
        toml_edit::Value::Integer(i) => Raw::Int(*i.value()),
        toml_edit::Value::Float(f) => Raw::Float(*f.value()),
        toml_edit::Value::Boolean(b) => Raw::Bool(*b.value()),
        toml_edit::Value::Datetime(_) => Raw::DateTime,
        toml_edit::Value::Array(a) => Raw::List(a.iter().map(raw_of).collect()),
        // Flattened by the caller; an inline table inside an array is simply wrong.
        toml_edit::Value::InlineTable(_) => Raw::List(Vec::new()),
    }
}

/// Collects the assignments of a `set` or `expect` table; nested tables give dotted names
/// (`S2 = { T = "T#1s" }` is `S2.T`, as is the quoted key `"S2.T"`).
fn collect_assigns(src: &Src<'_>, table: &dyn TableLike, prefix: &str, out: &mut Vec<RawAssign>) {
    for (key, item) in table.iter() {
        let name = if prefix.is_empty() { key.to_string() } else { format!("{prefix}.{key}") };
        if let Some(inner) = item.as_table_like() {
            collect_assigns(src, inner, &name, out);
            continue;
        }
        let span = src.key_span(table, key).or_else(|| item.span());
        let (line, column) = span.map_or((0, 0), |s| src.pos(s.start));
        let value = item.as_value().map_or(Raw::List(Vec::new()), raw_of);
        out.push(RawAssign { key: name, value, line, column });
    }
}

fn parse_text(file: &str, text: &str) -> Result<Parsed, ScenarioError> {
    let src = Src { file, text };
    let doc = toml_edit::Document::parse(text.to_string()).map_err(|e| {
        let mut err = src.err(e.span(), format!("TOML syntax error: {}", e.message().trim()));
        if err.line.is_none() {
            err.line = Some(1);
        }
        err
    })?;
    let root: &dyn TableLike = doc.as_table();
    let mut p = Parsed::default();
    for (key, item) in root.iter() {
        let span = src.key_span(root, key);
        match key {
            "chart" | "pou" => {
                let s = src.string(root, key, item, if key == "chart" { "a path" } else { "a POU name" })?;
                let (l, c) = span.clone().map_or((1, 1), |s| src.pos(s.start));
                if key == "chart" {
                    p.chart = Some((s, l, c));
                } else {
                    p.pou = Some((s, l, c));
                }
            }
            "period" => {
                let t = src.time(root, key, item)?;
                if t <= 0 {
                    return Err(src.err(item.span(), format!("`period` must be positive, found {}", format_time(t))));
                }
                p.period = Some(t);
            }
            "profile" => {
                let s = src.string(root, key, item, "iec, matiec, codesys, grafcet, logix or graph")?;
                p.profile = Some(Profile::from_name(&s).ok_or_else(|| {
                    src.err(item.span(), format!("unknown profile `{s}` (expected iec, matiec, codesys, grafcet, logix or graph)"))
                })?);
            }
            "until" | "scans" => {
                if p.length.is_some() {
                    return Err(src.err(span, "`until` and `scans` are both given: use one of them"));
                }
                if key == "until" {
                    let t = src.time(root, key, item)?;
                    if t < 0 {
                        return Err(
                            src.err(item.span(), format!("`until` must not be negative, found {}", format_time(t)))
                        );
                    }
                    p.length = Some(RunLength::Until(t));
                } else {
                    let n = item.as_integer().ok_or_else(|| {
                        src.err(item.span(), format!("`scans` must be an integer, found {}", type_name(item)))
                    })?;
                    if n < 0 {
                        return Err(src.err(item.span(), format!("`scans` must not be negative, found {n}")));
                    }
                    p.length = Some(RunLength::Scans(n as u64));
                }
            }
            "at" => p.entries = parse_entries(&src, root, item)?,
            "forbid" => {
                p.forbid = parse_forbid(&src, root, item)?;
                p.forbid_line = span.clone().map_or(1, |s| src.pos(s.start).0);
            }
            other => {
                let hint = did_you_mean(other, TOP_KEYS);
                return Err(src.err(
                    span,
                    format!(
                        "unknown key `{other}` (expected chart, pou, period, profile, until, scans, forbid or [[at]]){hint}"
                    ),
                ));
            }
        }
    }
    Ok(p)
}

fn parse_entries(src: &Src<'_>, root: &dyn TableLike, item: &Item) -> Result<Vec<RawEntry>, ScenarioError> {
    let mut tables: Vec<(&dyn TableLike, Option<Range<usize>>)> = Vec::new();
    match item {
        Item::ArrayOfTables(a) => {
            for t in a.iter() {
                tables.push((t, t.span()));
            }
        }
        Item::Value(toml_edit::Value::Array(a)) => {
            for v in a.iter() {
                match v.as_inline_table() {
                    Some(t) => tables.push((t, t.span())),
                    None => {
                        return Err(src.err(v.span(), "each `at` entry must be a table with `time`, `set` and `expect`"))
                    }
                }
            }
        }
        _ => {
            return Err(src.err(
                src.key_span(root, "at").or_else(|| item.span()),
                format!("`at` must be an array of tables (write `[[at]]`), found {}", type_name(item)),
            ))
        }
    }
    let mut entries: Vec<RawEntry> = Vec::new();
    for (table, span) in tables {
        let (line, _) = span.clone().map_or((1, 1), |s| src.pos(s.start));
        let mut time = None;
        let mut set = Vec::new();
        let mut raw = RawEntry::default();
        let mut to_span = None;
        let mut within_span = None;
        for (key, item) in table.iter() {
            let kspan = src.key_span(table, key);
            match key {
                "time" => {
                    let t = src.time(table, key, item)?;
                    if t < 0 {
                        return Err(
                            src.err(item.span(), format!("`time` must not be negative, found {}", format_time(t)))
                        );
                    }
                    time = Some((t, item.span()));
                }
                "set" => {
                    let Some(inner) = item.as_table_like() else {
                        return Err(src.err(
                            kspan,
                            format!("`{key}` must be a table such as {{ Start = true }}, found {}", type_name(item)),
                        ));
                    };
                    collect_assigns(src, inner, "", &mut set);
                }
                "expect" => raw.expect = parse_cond(src, key, kspan, item)?,
                "always" => raw.always = Some(parse_cond(src, key, kspan, item)?),
                "never" => raw.never = Some(parse_cond(src, key, kspan, item)?),
                "after" => raw.after = Some(parse_cond(src, key, kspan, item)?),
                "to" | "within" => {
                    let t = src.time(table, key, item)?;
                    if t < 0 {
                        return Err(
                            src.err(item.span(), format!("`{key}` must not be negative, found {}", format_time(t)))
                        );
                    }
                    if key == "to" {
                        raw.to = Some(t);
                        to_span = item.span();
                    } else {
                        raw.within = Some(t);
                        within_span = kspan;
                    }
                }
                "forbid" => raw.forbid = parse_forbid(src, table, item)?,
                other => {
                    let hint = did_you_mean(other, ENTRY_KEYS);
                    return Err(src.err(
                        kspan,
                        format!(
                            "unknown key `{other}` in an [[at]] entry (expected time, set, expect, to, always, never, within, after or forbid){hint}"
                        ),
                    ));
                }
            }
        }
        let Some((time, tspan)) = time else {
            return Err(src.err(span, "an [[at]] entry needs a `time`, such as time = \"T#100ms\""));
        };
        if let Some(to) = raw.to {
            if to < time {
                return Err(src.err(
                    to_span,
                    format!("`to` ({}) comes before the entry's `time` ({})", format_time(to), format_time(time)),
                ));
            }
            if raw.always.is_none() && raw.never.is_none() && raw.forbid.is_empty() && raw.after.is_none() {
                return Err(
                    src.err(to_span, "`to` ends an interval: give `always`, `never`, `forbid` or `after` with it")
                );
            }
            if raw.within.is_some() && raw.after.is_none() {
                return Err(src.err(
                    to_span,
                    "`within` without `after` counts from the entry's `time`; `to` bounds the triggers of `after`",
                ));
            }
        }
        if raw.within.is_some() && raw.expect.is_empty() {
            return Err(src.err(within_span, "`within` needs an `expect`: the condition that must hold in time"));
        }
        if raw.after.is_some() && raw.within.is_none() {
            return Err(src.err(span, "`after` needs a `within`: how long `expect` may take after the trigger"));
        }
        if let Some(prev) = entries.last() {
            if time < prev.time {
                return Err(src.err(
                    tspan,
                    format!(
                        "`time` goes backwards: {} comes after {} (line {}); [[at]] entries must be in time order",
                        format_time(time),
                        format_time(prev.time),
                        prev.line
                    ),
                ));
            }
        }
        entries.push(RawEntry { time, line, set, ..raw });
    }
    Ok(entries)
}

/// `expect`, `always`, `never`, `after`: a table of values, or an ST BOOL expression.
fn parse_cond(src: &Src<'_>, key: &str, kspan: Option<Range<usize>>, item: &Item) -> Result<RawCond, ScenarioError> {
    if let Some(inner) = item.as_table_like() {
        let mut c = RawCond::default();
        collect_assigns(src, inner, "", &mut c.assigns);
        return Ok(c);
    }
    if let Some(text) = item.as_str() {
        let (line, column) = item.span().or(kspan.clone()).map_or((0, 0), |s| src.pos(s.start));
        return Ok(RawCond { assigns: Vec::new(), expr: Some((text.to_string(), line, column)) });
    }
    Err(src.err(
        kspan,
        format!(
            "`{key}` must be a table such as {{ Motor = true }} or an ST condition such as \"NOT (Fwd AND Rev)\", found {}",
            type_name(item)
        ),
    ))
}

/// `forbid = ["unsafe", "conflict"]`.
fn parse_forbid(src: &Src<'_>, table: &dyn TableLike, item: &Item) -> Result<Vec<(String, u32, u32)>, ScenarioError> {
    let names = EventKind::ALL.map(EventKind::name);
    let Some(list) = item.as_array() else {
        return Err(src.err(
            src.key_span(table, "forbid").or_else(|| item.span()),
            format!(
                "`forbid` must be an array of event kinds such as [\"unsafe\", \"conflict\"], found {}",
                type_name(item)
            ),
        ));
    };
    let mut out = Vec::new();
    for v in list.iter() {
        let Some(name) = v.as_str() else {
            return Err(src.err(v.span(), "`forbid` holds event kinds as strings, such as \"unsafe\""));
        };
        if EventKind::from_name(name).is_none() {
            let hint = did_you_mean(name, names);
            return Err(src.err(
                v.span(),
                format!("unknown event kind `{name}` in `forbid` (expected {}){hint}", names.join(", ")),
            ));
        }
        let (l, c) = v.span().map_or((0, 0), |s| src.pos(s.start));
        out.push((name.to_string(), l, c));
    }
    Ok(out)
}

// ---------------------------------------------------------------------------------------------
// Binding names and values to the chart

fn compile(chart_name: &str, text: &str, pou: Option<&str>, opts: SimOptions) -> Result<Simulation, ScenarioError> {
    compile_located(chart_name, text, None, pou, opts)
}

/// [`compile`], with the errors of a PLCopen chart located in its XML.
fn compile_located(
    chart_name: &str,
    text: &str,
    imported: Option<&sfc_plcopen::Imported>,
    pou: Option<&str>,
    opts: SimOptions,
) -> Result<Simulation, ScenarioError> {
    Simulation::from_source(chart_name, text, pou, opts).map_err(|(file, diags)| {
        let mut errors: Vec<Diagnostic> = diags.iter().filter(|d| d.is_error()).cloned().collect();
        if errors.is_empty() {
            errors = diags;
        }
        match imported {
            Some(i) => {
                let errors = errors.iter().map(|d| sfc_plcopen::relocate(d, &i.map, 0)).collect();
                chart_errors(chart_name, i.xml.clone(), errors)
            }
            None => chart_errors(chart_name, file, errors),
        }
    })
}

/// The chart's errors as a [`ErrorKind::Chart`] error.
fn chart_errors(chart_name: &str, file: SourceFile, errors: Vec<Diagnostic>) -> ScenarioError {
    let rendered: Vec<String> = errors
        .iter()
        .map(|d| render_human(d, std::slice::from_ref(&file), RenderOptions { color: false }).trim_end().to_string())
        .collect();
    let n = errors.len();
    let message =
        format!("the chart `{chart_name}` has {n} error{}:\n{}", if n == 1 { "" } else { "s" }, rendered.join("\n"));
    ScenarioError { diagnostics: Some(Box::new((file, errors))), ..ScenarioError::new(ErrorKind::Chart, None, message) }
}

/// What a value of `ty` is written as, for error messages.
fn expected_form(ty: &Type) -> String {
    if let Type::Enum { values, .. } = ty {
        let names: Vec<&str> = values.iter().map(|(n, _)| n.as_str()).collect();
        return format!("one of {}", names.join(", "));
    }
    match ty.base() {
        Type::Bool => "true or false".into(),
        t if t.is_integer() || t.is_bit() => "an integer".into(),
        t if t.is_real() => "a number".into(),
        t if t.is_duration() => "a TIME literal such as \"T#1s500ms\"".into(),
        Type::Date => "a DATE literal such as \"D#2024-03-01\"".into(),
        Type::TimeOfDay => "a TIME_OF_DAY literal such as \"TOD#12:30:00\"".into(),
        Type::DateAndTime => "a DATE_AND_TIME literal such as \"DT#2024-03-01-12:30:00\"".into(),
        t if t.is_string() => "a string".into(),
        _ => "an elementary value".into(),
    }
}

/// Converts a scenario value to a value of `ty`; the error says what was expected.
fn convert(raw: &Raw, ty: &Type) -> Result<Value, String> {
    let mismatch = || format!("expected {}, found {}", expected_form(ty), raw.describe());
    if let Type::Enum { values, .. } = ty {
        return match raw {
            Raw::Str(s) => {
                let name = s.rsplit('#').next().unwrap_or(s);
                values
                    .iter()
                    .find(|(n, _)| n.eq_ignore_ascii_case(name))
                    .map(|(_, o)| Value::Int(*o))
                    .ok_or_else(mismatch)
            }
            Raw::Int(i) if values.iter().any(|(_, o)| o == i) => Ok(Value::Int(*i)),
            _ => Err(mismatch()),
        };
    }
    let b = ty.base();
    match raw {
        Raw::Bool(v) if b.is_bool() => Ok(Value::Bool(*v)),
        Raw::Int(i) if !b.is_bool() && (b.is_integer() || b.is_bit() || matches!(ty, Type::Subrange { .. })) => {
            if let Some((lo, hi)) = ty.int_range() {
                if i128::from(*i) < lo || i128::from(*i) > hi {
                    return Err(format!("{i} is out of the range of {ty} ({lo}..{hi})"));
                }
            }
            Ok(Value::Int(*i))
        }
        Raw::Int(i) if b.is_real() => Ok(Value::Real(round_real(*i as f64, ty))),
        Raw::Float(f) if b.is_real() => Ok(Value::Real(round_real(*f, ty))),
        Raw::Str(s) if b.is_duration() => parse_time(s)
            .map(Value::Time)
            .ok_or_else(|| format!("`{s}` is not a TIME literal (write e.g. \"T#1s500ms\"; 1 us is the finest unit)")),
        Raw::Str(s) if b.is_date() => {
            use sfc_syntax::ast::LiteralKind;
            match sfc_syntax::literal::decode_typed(s.trim(), Default::default()) {
                Ok((LiteralKind::Date(days), _)) if matches!(b, Type::Date) => Ok(Value::Int(days * 86_400_000_000)),
                Ok((LiteralKind::TimeOfDay(us), _)) if matches!(b, Type::TimeOfDay) => Ok(Value::Int(us)),
                Ok((LiteralKind::DateAndTime(us), _)) if matches!(b, Type::DateAndTime) => Ok(Value::Int(us)),
                _ => Err(mismatch()),
            }
        }
        Raw::Str(s) if b.is_string() => {
            let len = match b {
                Type::String { len } | Type::WString { len } => *len,
                _ => None,
            };
            if let Some(max) = len {
                if s.chars().count() > max as usize {
                    return Err(format!("the string is longer than the {max} characters of {ty}"));
                }
            }
            Ok(Value::Str(s.as_str().into()))
        }
        _ => Err(mismatch()),
    }
}

fn round_real(x: f64, ty: &Type) -> f64 {
    if matches!(ty.base(), Type::Real) {
        f64::from(x as f32)
    } else {
        x
    }
}

/// A value of `ty` written as text the way `--set` takes it (`TRUE`, `0`, `-5`, `16#FF`,
/// `2.5`, `T#1s`, `'text'`, an enumeration value), checked against the type; the error says
/// what was expected.
pub fn value_from_text(text: &str, ty: &Type) -> Result<Value, String> {
    convert(&raw_from_text(text, ty), ty)
}

/// Reads a `--set` value written on the command line as the TOML value it stands for.
fn raw_from_text(text: &str, ty: &Type) -> Raw {
    let t = text.trim();
    let b = ty.base();
    if b.is_bool() {
        return match t.to_ascii_uppercase().as_str() {
            "TRUE" | "1" => Raw::Bool(true),
            "FALSE" | "0" => Raw::Bool(false),
            _ => Raw::Str(t.to_string()),
        };
    }
    if b.is_integer() || b.is_bit() || ty.is_enum() || matches!(ty, Type::Subrange { .. }) {
        if let Ok(i) = t.replace('_', "").parse::<i64>() {
            return Raw::Int(i);
        }
        let (neg, body) = t.strip_prefix('-').map_or((false, t), |r| (true, r));
        if body.contains('#') {
            if let Ok(u) = sfc_syntax::literal::decode_int(body, Default::default()) {
                if let Ok(i) = i64::try_from(u) {
                    return Raw::Int(if neg { -i } else { i });
                }
            }
        }
        return Raw::Str(t.to_string());
    }
    if b.is_real() {
        if let Ok(f) = t.replace('_', "").parse::<f64>() {
            return Raw::Float(f);
        }
    }
    if b.is_string() {
        for q in ['\'', '"'] {
            if t.len() >= 2 && t.starts_with(q) && t.ends_with(q) {
                return Raw::Str(t[1..t.len() - 1].to_string());
            }
        }
        return Raw::Str(text.to_string());
    }
    Raw::Str(t.to_string())
}

struct Binder<'a> {
    sim: &'a Simulation,
    file: &'a str,
    chart: &'a str,
    steps: Vec<String>,
    names: Vec<String>,
}

impl<'a> Binder<'a> {
    fn new(sim: &'a Simulation, file: &'a str, chart: &'a str) -> Self {
        let steps = sim.step_names();
        let mut names: Vec<String> = sim.trace_vars().into_iter().map(|(n, _)| n).collect();
        for s in &steps {
            names.push(format!("{s}.X"));
            names.push(format!("{s}.T"));
            // A step of an action's chart is also read through its instance, as the POU's
            // code reads it (`Lift.Gripping.X` for `Lift.ACT_Load.Gripping`).
            if let Some(short) = without_action(s).filter(|a| sim.type_of(&format!("{a}.X")).is_some()) {
                names.push(format!("{short}.X"));
                names.push(format!("{short}.T"));
            }
        }
        Binder { sim, file, chart, steps, names }
    }
    /// The step whose name without its action's is `name` (`Lift.ACT_Load.Gripping` for
    /// `Lift.Gripping`): how `active` names the steps of an action's chart.
    fn step_of_action(&self, name: &str) -> Option<&str> {
        self.steps.iter().find(|s| without_action(s).is_some_and(|a| a.eq_ignore_ascii_case(name))).map(String::as_str)
    }
    fn err(&self, a: &RawAssign, message: String) -> ScenarioError {
        let mut e = ScenarioError::new(ErrorKind::Invalid, Some(self.file.to_string()), message);
        if a.line > 0 {
            e.line = Some(a.line);
            e.column = Some(a.column);
        }
        e
    }
    fn step(&self, name: &str) -> Option<&str> {
        self.steps.iter().find(|s| s.eq_ignore_ascii_case(name)).map(String::as_str)
    }
    fn type_of(&self, a: &RawAssign) -> Result<Type, ScenarioError> {
        match self.sim.type_of(&a.key) {
            Some(ty) => Ok(ty),
            None => {
                let hint = did_you_mean(&a.key, self.names.iter().map(String::as_str));
                Err(self.err(
                    a,
                    format!(
                        "unknown variable `{}` in the chart `{}` (POU {}){hint}",
                        a.key,
                        self.chart,
                        self.sim.pou_name()
                    ),
                ))
            }
        }
    }
    fn value(&self, a: &RawAssign, ty: &Type) -> Result<Value, ScenarioError> {
        convert(&a.value, ty).map_err(|m| self.err(a, format!("`{}` is {ty}: {m}", a.key)))
    }
    fn set(&self, a: &RawAssign) -> Result<(String, Value), ScenarioError> {
        if a.key.eq_ignore_ascii_case("active") && self.sim.type_of(&a.key).is_none() {
            return Err(self.err(a, "`active` can only be expected, not set".into()));
        }
        if let Some((base, field)) = a.key.rsplit_once('.') {
            if self.step(base).is_some() && (field.eq_ignore_ascii_case("X") || field.eq_ignore_ascii_case("T")) {
                return Err(self.err(a, format!("`{}` belongs to the step `{base}` and cannot be set", a.key)));
            }
        }
        let ty = self.type_of(a)?;
        Ok((a.key.clone(), self.value(a, &ty)?))
    }
    fn expect(&self, a: &RawAssign) -> Result<Expectation, ScenarioError> {
        let record_key = a.key.eq_ignore_ascii_case("error_record")
            || a.key.len() > 13 && a.key[a.key.len() - 13..].eq_ignore_ascii_case(".error_record");
        if record_key && self.sim.type_of(&a.key).is_none() {
            let Raw::Str(text) = &a.value else {
                return Err(self.err(
                    a,
                    format!("`{}` must be a text the error record contains; found {}", a.key, a.value.describe()),
                ));
            };
            let instance = a.key.rsplit_once('.').map(|(i, _)| i.to_string());
            if let Some(i) = &instance {
                if !self.sim.mechanisms().iter().any(|m| m.instance.eq_ignore_ascii_case(i)) {
                    return Err(self.err(a, format!("`{i}` is not an SFC instance of {}", self.sim.pou_name())));
                }
            }
            return Ok(Expectation::ErrorRecord { instance, text: text.clone() });
        }
        if a.key == "active" {
            let Raw::List(items) = &a.value else {
                return Err(self.err(
                    a,
                    format!(
                        "`active` must be an array of step names, such as active = [\"S1\"]; found {}",
                        a.value.describe()
                    ),
                ));
            };
            let mut steps = Vec::new();
            for item in items {
                let Raw::Str(s) = item else {
                    return Err(
                        self.err(a, format!("`active` must hold step names (strings), found {}", item.describe()))
                    );
                };
                match self.step(s) {
                    Some(step) => steps.push(step.to_string()),
                    None => {
                        let hint = match self.step_of_action(s) {
                            Some(full) => format!(
                                "; did you mean `{full}`? (`active` names the steps of an action's chart with the action, as traces do)"
                            ),
                            None => did_you_mean(s, self.steps.iter().map(String::as_str)),
                        };
                        return Err(
                            self.err(a, format!("unknown step `{s}` in `active` (POU {}){hint}", self.sim.pou_name()))
                        );
                    }
                }
            }
            steps.sort();
            steps.dedup();
            return Ok(Expectation::Active(steps));
        }
        let ty = self.type_of(a)?;
        let value = self.value(a, &ty)?;
        Ok(Expectation::Value { key: a.key.clone(), value, ty })
    }
    /// A table of values and/or an ST condition, as a conjunction.
    fn cond(&self, c: &RawCond) -> Result<Vec<Expectation>, ScenarioError> {
        let mut out = Vec::new();
        for a in &c.assigns {
            out.push(self.expect(a)?);
        }
        if let Some((text, line, column)) = &c.expr {
            let cond = Condition::parse(text, self.sim).map_err(|m| {
                let mut e = ScenarioError::new(ErrorKind::Invalid, Some(self.file.to_string()), m);
                if *line > 0 {
                    e.line = Some(*line);
                    e.column = Some(*column);
                }
                e
            })?;
            out.push(Expectation::Holds(cond));
        }
        Ok(out)
    }
}

/// A qualified step name without its next-to-last part (`Lift.ACT_Load.Gripping` →
/// `Lift.Gripping`): the spelling of a step of an action's chart through its instance.
fn without_action(step: &str) -> Option<String> {
    let (rest, leaf) = step.rsplit_once('.')?;
    Some(match rest.rsplit_once('.') {
        Some((path, _action)) => format!("{path}.{leaf}"),
        None => leaf.to_string(),
    })
}

/// Loads a scenario file: parses it, reads and checks its chart, binds names and values.
pub fn load(path: &Path) -> Result<Scenario, ScenarioError> {
    load_with(path, &Overrides::default())
}

fn clean(path: &Path) -> PathBuf {
    let cleaned: PathBuf = path.components().filter(|c| !matches!(c, Component::CurDir)).collect();
    if cleaned.as_os_str().is_empty() {
        PathBuf::from(".")
    } else {
        cleaned
    }
}

fn read_text(path: &Path, what: &str) -> Result<String, (ErrorKind, String)> {
    let bytes =
        std::fs::read(path).map_err(|e| (ErrorKind::Io, format!("cannot read {what} `{}`: {e}", path.display())))?;
    // UTF-8 with or without a byte order mark, or Latin-1 / Windows-1252.
    Ok(sfc_syntax::encoding::decode(&bytes).text)
}

/// A chart file as the IEC text to simulate: a PLCopen XML chart is simulated as the text it
/// imports to, with the import kept to locate diagnostics in the XML.
fn read_chart(path: &Path) -> Result<(String, Option<sfc_plcopen::Imported>), ScenarioError> {
    let text = read_text(path, "the chart").map_err(|(k, m)| ScenarioError::new(k, None, m))?;
    let xml = path.extension().is_some_and(|e| e.eq_ignore_ascii_case("xml"))
        || text.trim_start_matches('\u{feff}').trim_start().starts_with('<');
    if !xml {
        return Ok((text, None));
    }
    let imported = sfc_plcopen::import(0, &path.display().to_string(), &text);
    let errors: Vec<Diagnostic> = imported.diagnostics.iter().filter(|d| d.is_error()).cloned().collect();
    if !errors.is_empty() {
        return Err(chart_errors(&path.display().to_string(), imported.xml.clone(), errors));
    }
    Ok((imported.text.clone(), Some(imported)))
}

/// What the import of a PLCopen chart said, for [`Scenario::import`].
fn import_notes(imported: &Option<sfc_plcopen::Imported>) -> Option<Box<(SourceFile, Vec<Diagnostic>)>> {
    imported.as_ref().filter(|i| !i.diagnostics.is_empty()).map(|i| Box::new((i.xml.clone(), i.diagnostics.clone())))
}

/// Where runtime errors of an imported chart are located: its XML and the import's map.
fn located(imported: &Option<sfc_plcopen::Imported>) -> Option<Arc<(SourceFile, sfc_plcopen::SourceMap)>> {
    imported.as_ref().map(|i| Arc::new((i.xml.clone(), i.map.clone())))
}

/// A POU that does not exist or cannot be chosen (SFC0321) is a usage error when the command
/// line chose it (`--pou`, or a chart given without scenario), not a problem of the chart.
fn pou_choice_is_usage(mut e: ScenarioError) -> ScenarioError {
    if e.diagnostics.as_ref().is_some_and(|d| !d.1.is_empty() && d.1.iter().all(|d| d.code == "SFC0321")) {
        e.kind = ErrorKind::Usage;
    }
    e
}

/// Loads a scenario file with command-line settings taking precedence.
pub fn load_with(path: &Path, o: &Overrides) -> Result<Scenario, ScenarioError> {
    let text = read_text(path, "the scenario").map_err(|(k, m)| ScenarioError::new(k, None, m))?;
    load_parts(path, &text, o, None)
}

/// Loads a scenario from its text as if it were the file `path` (its `chart` is resolved
/// against `path`'s directory); `chart_text`, when given, is used instead of reading the chart.
/// Replays a scenario before it is written (the witnesses of `sfc prove`).
pub fn load_text(path: &Path, text: &str, chart_text: Option<&str>) -> Result<Scenario, ScenarioError> {
    load_parts(path, text, &Overrides::default(), chart_text)
}

fn load_parts(path: &Path, text: &str, o: &Overrides, given_chart: Option<&str>) -> Result<Scenario, ScenarioError> {
    let name = path.display().to_string();
    let parsed = parse_text(&name, text)?;
    let scenario_chart = parsed.chart.as_ref().map(|(c, _, _)| clean(&path.parent().unwrap_or(Path::new("")).join(c)));
    let chart = match (&o.chart, &scenario_chart) {
        (Some(c), _) => clean(c),
        (None, Some(c)) => c.clone(),
        (None, None) => {
            return Err(ScenarioError {
                line: Some(1),
                ..ScenarioError::new(
                    ErrorKind::Invalid,
                    Some(name),
                    "missing `chart = \"FILE\"` (the chart to simulate, relative to this file)",
                )
            })
        }
    };
    // Where to point for a problem with the chart: the key that named it, if any.
    let locate = |key: Option<&(String, u32, u32)>, e: ScenarioError| match key {
        Some((_, l, c)) => ScenarioError { file: Some(name.clone()), line: Some(*l), column: Some(*c), ..e },
        None => ScenarioError { file: Some(name.clone()), ..e },
    };
    let chart_key = if o.chart.is_none() { parsed.chart.as_ref() } else { None };
    let (chart_text, imported) = match given_chart {
        Some(t) => (t.to_string(), None),
        None => read_chart(&chart).map_err(|e| match (chart_key, &e.kind) {
            (Some(_), ErrorKind::Io) => locate(chart_key, e),
            _ => e,
        })?,
    };
    let (profile, profile_source) = match (o.profile, parsed.profile) {
        (Some(p), _) => (p, ProfileSource::Option),
        (None, Some(p)) => (p, ProfileSource::Scenario),
        (None, None) => file_profile(crate::chart_vendor(&chart_text, imported.as_ref())),
    };
    let options = SimOptions { period: o.period.or(parsed.period).unwrap_or(DEFAULT_PERIOD), profile };
    let pou = o.pou.clone().or_else(|| parsed.pou.as_ref().map(|p| p.0.clone()));
    let chart_name = chart.display().to_string();
    let sim = compile_located(&chart_name, &chart_text, imported.as_ref(), pou.as_deref(), options).map_err(|e| {
        let pou_key = if o.pou.is_none() { parsed.pou.as_ref() } else { None };
        let e = if o.pou.is_some() { pou_choice_is_usage(e) } else { e };
        locate(pou_key.or(chart_key), e)
    })?;
    let binder = Binder::new(&sim, &name, &chart_name);
    let mut entries = command_line_sets(&sim, o)?.into_iter().collect::<Vec<_>>();
    for raw in &parsed.entries {
        let mut entry = Entry { time: raw.time, line: raw.line, to: raw.to, within: raw.within, ..Entry::default() };
        for a in &raw.set {
            entry.set.push(binder.set(a)?);
        }
        entry.expect = binder.cond(&raw.expect)?;
        let cond = |c: &Option<RawCond>| c.as_ref().map_or(Ok(Vec::new()), |c| binder.cond(c));
        entry.always = cond(&raw.always)?;
        entry.never = cond(&raw.never)?;
        entry.after = cond(&raw.after)?;
        entry.forbid = raw.forbid.iter().filter_map(|(n, _, _)| EventKind::from_name(n)).collect();
        entries.push(entry);
    }
    Ok(Scenario {
        path: path.to_path_buf(),
        name,
        chart,
        scenario_chart,
        pou: sim.pou_name().to_string(),
        options,
        profile_source,
        length: o.length.or(parsed.length).unwrap_or(RunLength::LastEntry),
        entries,
        forbid: parsed.forbid.iter().filter_map(|(n, _, _)| EventKind::from_name(n)).collect(),
        forbid_line: parsed.forbid_line,
        chart_text,
        import: import_notes(&imported),
        located: located(&imported),
    })
}

/// The `--set` values as an entry at time 0.
fn command_line_sets(sim: &Simulation, o: &Overrides) -> Result<Option<Entry>, ScenarioError> {
    if o.set.is_empty() {
        return Ok(None);
    }
    let binder = Binder::new(sim, "", "");
    let mut entry = Entry::default();
    for (key, text) in &o.set {
        let ty = sim.type_of(key);
        let raw = ty.as_ref().map_or(Raw::Str(text.clone()), |t| raw_from_text(text, t));
        let a = RawAssign { key: key.clone(), value: raw, line: 0, column: 0 };
        let bound = binder.set(&a).map_err(|e| {
            let message = match ty {
                None => format!(
                    "`--set {key}={text}`: unknown variable `{key}` in POU {}{}",
                    sim.pou_name(),
                    did_you_mean(key, binder.names.iter().map(String::as_str))
                ),
                Some(_) => format!("`--set {key}={text}`: {}", e.message),
            };
            ScenarioError::new(ErrorKind::Usage, None, message)
        })?;
        entry.set.push(bound);
    }
    Ok(Some(entry))
}

/// A run of a chart without scenario file (`sfc sim FILE`): the overrides' settings, `--set`
/// values before scan 0, [`DEFAULT_SCANS`] scans unless told otherwise.
pub fn for_chart(chart: &Path, o: &Overrides) -> Result<Scenario, ScenarioError> {
    let chart = clean(chart);
    let chart_name = chart.display().to_string();
    let (chart_text, imported) = read_chart(&chart)?;
    let (profile, profile_source) = match o.profile {
        Some(p) => (p, ProfileSource::Option),
        None => file_profile(crate::chart_vendor(&chart_text, imported.as_ref())),
    };
    let options = SimOptions { period: o.period.unwrap_or(DEFAULT_PERIOD), profile };
    let sim = compile_located(&chart_name, &chart_text, imported.as_ref(), o.pou.as_deref(), options)
        .map_err(pou_choice_is_usage)?;
    let entries = command_line_sets(&sim, o)?.into_iter().collect();
    Ok(Scenario {
        path: chart.clone(),
        name: chart_name,
        chart,
        scenario_chart: None,
        pou: sim.pou_name().to_string(),
        options,
        profile_source,
        length: o.length.unwrap_or(RunLength::Scans(DEFAULT_SCANS)),
        entries,
        forbid: Vec::new(),
        forbid_line: 0,
        chart_text,
        import: import_notes(&imported),
        located: located(&imported),
    })
}

// ---------------------------------------------------------------------------------------------
// Running

/// The result of running one scenario.
#[derive(Debug, Clone)]
pub struct Outcome {
    /// The scenario as named in reports (its path as given).
    pub name: String,
    /// Failed and unreached expectations, and values that could not be set, one line each.
    pub failures: Vec<String>,
    /// What stopped the run: a runtime error (rendered like rustc), or a chart that no longer
    /// compiles.
    pub error: Option<String>,
    pub coverage: Coverage,
    /// Scans run.
    pub scans: u64,
}

impl Outcome {
    pub fn passed(&self) -> bool {
        self.failures.is_empty() && self.error.is_none()
    }
}

/// A run with what the command line needs beyond the outcome.
pub struct Execution {
    pub outcome: Outcome,
    /// The simulation after the last scan (`None` when the chart failed to compile).
    pub sim: Option<Simulation>,
    /// The first error writing the trace (tracing stops there; the run goes on).
    pub trace_error: Option<io::Error>,
}

/// Renders a runtime error like rustc:
///
/// ```text
/// error: division by zero
///  --> chart.st:12:8
///    |
/// 12 |     x := a / b;
///    |            ^
///    = note: at scan 3, T#30ms
/// ```
pub fn render_runtime_error(err: &RuntimeError, source: &SourceFile) -> String {
    let line_no = err.line.max(1);
    let gutter = line_no.to_string().len();
    let pad = " ".repeat(gutter);
    let text = if line_no <= source.line_count() { source.line_text(line_no) } else { "" };
    let text = text.trim_end_matches(['\r', '\n']);
    let col = err.column.max(1) as usize;
    let width = source.slice(err.span).chars().take_while(|c| *c != '\n').count().max(1);
    let width = width.min(text.chars().count().saturating_sub(col - 1).max(1));
    let mut out = format!("error: {}\n{pad}--> {}:{}:{}\n", err.message, source.name, line_no, err.column.max(1));
    if !text.is_empty() {
        out.push_str(&format!("{pad} |\n{line_no} | {text}\n{pad} | {}{}\n", " ".repeat(col - 1), "^".repeat(width)));
    }
    out.push_str(&format!("{pad} = note: at scan {}, {}", err.scan, format_time(err.time)));
    out
}

fn show(v: &Value, ty: &Type) -> String {
    match (v, ty) {
        (Value::Int(i), Type::Enum { values, .. }) => {
            values.iter().find(|(_, o)| o == i).map_or_else(|| i.to_string(), |(n, _)| n.clone())
        }
        (Value::Bool(b), _) => b.to_string(),
        (Value::Str(s), _) => format!("{:?}", &**s),
        _ => value_text(v, ty),
    }
}

fn show_steps(steps: &[String]) -> String {
    format!("[{}]", steps.iter().map(|s| format!("{s:?}")).collect::<Vec<_>>().join(", "))
}

fn same(expected: &Value, actual: &Value, ty: &Type) -> bool {
    match (expected, actual) {
        (Value::Real(a), Value::Real(b)) => {
            if a == b || (a.is_nan() && b.is_nan()) {
                return true;
            }
            let tol = if matches!(ty.base(), Type::Real) { 1e-6 } else { 1e-12 };
            (a - b).abs() <= tol * a.abs().max(b.abs())
        }
        (Value::Real(a), Value::Int(b)) | (Value::Int(b), Value::Real(a)) => *a == *b as f64,
        (Value::Time(a) | Value::Int(a), Value::Time(b) | Value::Int(b)) => a == b,
        (Value::Bool(a), Value::Int(b)) | (Value::Int(b), Value::Bool(a)) => i64::from(*a) == *b,
        _ => expected == actual,
    }
}

/// Why an expectation does not hold after the last scan (`None` when it holds):
/// ``"`Visible`: expected true, actual false"``.
pub(crate) fn mismatch(sim: &Simulation, x: &Expectation) -> Option<String> {
    match x {
        Expectation::Active(want) => {
            let mut got = sim.active();
            got.sort();
            (&got != want).then(|| format!("`active`: expected {}, actual {}", show_steps(want), show_steps(&got)))
        }
        Expectation::Value { key, value, ty } => match sim.get(key) {
            Some(got) if same(value, &got, ty) => None,
            Some(got) => Some(format!("`{key}`: expected {}, actual {}", show(value, ty), show(&got, ty))),
            None => Some(format!("`{key}`: expected {}, but it cannot be read", show(value, ty))),
        },
        Expectation::Holds(c) => match c.eval(sim) {
            Ok(true) => None,
            Ok(false) => Some(format!("`{}` is FALSE ({})", c.text, c.operands(sim))),
            Err(m) => Some(format!("`{}` cannot be evaluated: {m}", c.text)),
        },
        Expectation::ErrorRecord { instance, text } => {
            let key = record_key(instance);
            let latest = sim
                .error_records()
                .into_iter()
                .rfind(|r| instance.as_ref().is_none_or(|i| r.instance.eq_ignore_ascii_case(i)));
            match latest {
                Some(r) if r.message().contains(text.as_str()) => None,
                Some(r) => {
                    Some(format!("`{key}`: expected a record containing \"{text}\", actual \"{}\"", r.message()))
                }
                None => Some(format!("`{key}`: expected a record containing \"{text}\", but no error record was made")),
            }
        }
    }
}

fn record_key(instance: &Option<String>) -> String {
    match instance {
        Some(i) => format!("{i}.error_record"),
        None => "error_record".to_string(),
    }
}

/// How a conjunction that holds looks now, for `never`: ``"`Fwd` = true, `Rev` = true"``.
pub(crate) fn holding(sim: &Simulation, xs: &[Expectation]) -> String {
    xs.iter()
        .map(|x| match x {
            Expectation::Active(want) => format!("`active` = {}", show_steps(want)),
            Expectation::Value { key, value, ty } => format!("`{key}` = {}", show(value, ty)),
            Expectation::Holds(c) => format!("`{}` is TRUE ({})", c.text, c.operands(sim)),
            Expectation::ErrorRecord { instance, text } => format!("`{}` contains \"{text}\"", record_key(instance)),
        })
        .collect::<Vec<_>>()
        .join(" and ")
}

/// Runs a loaded scenario, feeding `trace` if given.
pub fn run(s: &Scenario, trace: Option<&mut dyn TraceSink>) -> Outcome {
    execute(s, trace, &mut |_, _| {}, Recording::default()).outcome
}

/// Loads and runs a scenario file, without trace.
pub fn run_path(path: &Path) -> Result<Outcome, ScenarioError> {
    Ok(run(&load(path)?, None))
}

/// What a run records beyond its outcome and coverage.
#[derive(Debug, Clone, Copy, Default)]
pub struct Recording {
    /// The sequence of situations, for [`Simulation::stats`] (`sfc sim --stats`).
    pub situations: bool,
    /// A record of every scan for `on_scan` (its fired transitions and events), even without
    /// a trace.
    pub records: bool,
}

/// Runs a loaded scenario, feeding `trace` if given and calling `on_scan` after every scan
/// with the simulation ([`Simulation::next_scan`] is then one past the scan that ran) and the
/// scan's record when one was built (with a trace, interval checks or [`Recording::records`]).
///
/// A scan costs what the engine costs: without a trace no record is built, coverage is read
/// from the engine's counters at the end, and the values of expectations are read only at
/// their times.
pub fn execute(
    s: &Scenario,
    mut trace: Option<&mut dyn TraceSink>,
    on_scan: &mut dyn FnMut(&Simulation, Option<&ScanRecord>),
    recording: Recording,
) -> Execution {
    let mut outcome =
        Outcome { name: s.name.clone(), failures: Vec::new(), error: None, coverage: Coverage::default(), scans: 0 };
    let mut sim = match s.simulation() {
        Ok(sim) => sim,
        Err(e) => {
            outcome.error = Some(e.message);
            return Execution { outcome, sim: None, trace_error: None };
        }
    };
    sim.record_situations(recording.situations);
    outcome.coverage = Coverage::of(&sim, s.coverage_key(), s.chart_name());
    let mut trace_error = None;
    let mut values = Vec::new();
    if let Some(t) = trace.as_deref_mut() {
        if let Err(e) = t.header(&TraceHeader::of(&sim)) {
            trace_error = Some(e);
        }
    }
    let here = |e: &Entry| if e.line > 0 { format!("{}:{}", s.name, e.line) } else { format!("{} (--set)", s.name) };
    let total = s.total_scans();
    let (mut applied, mut checked) = (0usize, 0usize);
    // Failures with the scan they concern, so the report lists them in time order.
    let mut failures: Vec<(u64, String)> = Vec::new();
    let mut watch = crate::temporal::Watch::new(s);
    let watching = !watch.is_idle();
    for _ in 0..total {
        let now = sim.next_time();
        while applied < s.entries.len() && s.entries[applied].time <= now {
            let e = &s.entries[applied];
            for (name, value) in &e.set {
                if let Err(m) = sim.set(name, value.clone()) {
                    failures.push((
                        sim.next_scan(),
                        format!("{}: at {}: cannot set `{name}`: {m}", here(e), format_time(e.time)),
                    ));
                }
            }
            applied += 1;
        }
        let scan = sim.next_scan();
        let tracing = trace.is_some() && trace_error.is_none();
        let recorded = tracing || watching || recording.records;
        if recorded {
            sim.scan();
            if let (true, Some(t)) = (tracing, trace.as_deref_mut()) {
                sim.trace_values_into(&mut values);
                if let Err(e) = t.scan(sim.record(), &values) {
                    trace_error = Some(e);
                }
            }
        } else {
            let _ = sim.advance();
        }
        outcome.scans += 1;
        on_scan(&sim, recorded.then(|| sim.record()));
        while checked < applied {
            let e = &s.entries[checked];
            // With `within`, `expect` is a deadline, checked by the watch.
            if e.within.is_none() {
                for x in &e.expect {
                    if let Some(m) = mismatch(&sim, x) {
                        let at = format!("{}: at {} (scan {})", here(e), format_time(e.time), scan);
                        failures.push((scan, format!("{at}: {m}")));
                    }
                }
            }
            checked += 1;
        }
        if watching {
            watch.after_scan(&sim, sim.record());
        }
        if let Some(err) = sim.error() {
            outcome.error = Some(render_runtime_error(err, sim.fault_source()));
            break;
        }
    }
    let end = match (sim.error(), outcome.scans) {
        (Some(err), _) => {
            format!("the run stopped at scan {} ({}) with a runtime error", err.scan, format_time(err.time))
        }
        (None, 0) => "the run has no scans".to_string(),
        (None, n) => format!("the run ended after scan {} ({})", n - 1, format_time((n as i64 - 1) * s.options.period)),
    };
    outcome.coverage.record_run(&sim);
    for e in &s.entries[checked..] {
        if !e.expect.is_empty() && e.within.is_none() {
            failures.push((
                s.scan_of(e.time),
                format!(
                    "{}: at {} (scan {}): expectation never reached: {end}",
                    here(e),
                    format_time(e.time),
                    s.scan_of(e.time)
                ),
            ));
        }
    }
    failures.extend(watch.finish(outcome.scans, &end));
    failures.sort_by_key(|(scan, _)| *scan);
    outcome.failures.extend(failures.into_iter().map(|(_, f)| f));
    if trace_error.is_none() {
        if let Some(t) = trace {
            if let Err(e) = t.finish() {
                trace_error = Some(e);
            }
        }
    }
    Execution { outcome, sim: Some(sim), trace_error }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(text: &str) -> Result<Parsed, ScenarioError> {
        parse_text("t.scenario.toml", text)
    }

    fn err(text: &str) -> String {
        parse(text).expect_err("an error").to_string()
    }

    const GOOD: &str = r#"
chart = "blinker.st"
pou = "Blinker"
period = "T#100ms"
profile = "codesys"
until = "T#2s"

[[at]]
time = "T#0s"
set = { Start = true }
expect = { active = ["S1"], Visible = false }

[[at]]
time = "T#600ms"
expect = { active = ["S2"], "S2.T" = "T#500ms", S3 = { X = false } }

[[at]]
time = "T#600ms"
[at.set]
Level = 12
Speed = 1.5
"#;

    #[test]
    fn parses_the_contract_example() {
        let p = parse(GOOD).unwrap();
        assert_eq!(p.chart.as_ref().unwrap().0, "blinker.st");
        assert_eq!(p.chart.as_ref().unwrap().1, 2);
        assert_eq!(p.pou.unwrap().0, "Blinker");
        assert_eq!(p.period, Some(100_000));
        assert_eq!(p.profile, Some(Profile::Codesys));
        assert_eq!(p.length, Some(RunLength::Until(2_000_000)));
        assert_eq!(p.entries.len(), 3);
        assert_eq!(p.entries[0].line, 8);
        assert_eq!(p.entries[0].set[0].key, "Start");
        assert_eq!(p.entries[0].set[0].value, Raw::Bool(true));
        assert_eq!(p.entries[0].expect.assigns[0].value, Raw::List(vec![Raw::Str("S1".into())]));
        let keys: Vec<&str> = p.entries[1].expect.assigns.iter().map(|a| a.key.as_str()).collect();
        assert_eq!(keys, ["active", "S2.T", "S3.X"]);
        assert_eq!(p.entries[1].expect.assigns[1].line, 15);
        assert_eq!(p.entries[2].set[0].value, Raw::Int(12));
        assert_eq!(p.entries[2].set[1].value, Raw::Float(1.5));
        let scans = parse("chart = \"x.st\"\nscans = 30\n").unwrap();
        assert_eq!(scans.length, Some(RunLength::Scans(30)));
        let inline = parse("chart = \"x.st\"\nat = [{ time = \"T#1s\", set = { A = 1 } }]\n").unwrap();
        assert_eq!(inline.entries[0].time, 1_000_000);
    }

    #[test]
    fn located_errors() {
        assert!(
            err("chart = \"x.st\"\nuntil = \n").starts_with("t.scenario.toml:2:"),
            "{}",
            err("chart = \"x.st\"\nuntil = \n")
        );
        assert!(err("chart = \"x.st\"\nuntil = \n").contains("TOML syntax error"));
        assert_eq!(
            err("chart = \"x.st\"\n\nchrat = 1\n"),
            "t.scenario.toml:3:1: unknown key `chrat` (expected chart, pou, period, profile, until, scans, forbid or [[at]]); did you mean `chart`?"
        );
        assert_eq!(
            err("chart = \"x.st\"\nuntil = \"T#1s\"\nscans = 3\n"),
            "t.scenario.toml:3:1: `until` and `scans` are both given: use one of them"
        );
        assert!(
            err("period = \"100ms\"\n").starts_with("t.scenario.toml:1:10: `period`: `100ms` is not a TIME literal")
        );
        assert!(err("period = \"T#0s\"\n").contains("`period` must be positive"));
        assert!(err("period = \"T#1ns\"\n").contains("not a TIME literal"));
        assert!(err("profile = \"beckhoff\"\n")
            .contains("unknown profile `beckhoff` (expected iec, matiec, codesys, grafcet, logix or graph)"));
        assert!(err("scans = \"3\"\n").contains("`scans` must be an integer, found a string"));
        assert!(err("scans = -3\n").contains("`scans` must not be negative"));
        assert!(err("chart = 3\n").contains("`chart` must be a string"));
        let back = err("[[at]]\ntime = \"T#1s\"\n\n[[at]]\ntime = \"T#500ms\"\n");
        assert_eq!(
            back,
            "t.scenario.toml:5:8: `time` goes backwards: T#500ms comes after T#1s (line 1); [[at]] entries must be in time order"
        );
        assert!(err("[[at]]\nset = { A = 1 }\n").starts_with("t.scenario.toml:1:1: an [[at]] entry needs a `time`"));
        assert!(err("[[at]]\ntime = \"T#0s\"\nexpcet = { A = 1 }\n").contains(
            "3:1: unknown key `expcet` in an [[at]] entry (expected time, set, expect, to, always, never, within, after or forbid); did you mean `expect`?"
        ));
        assert!(err("[[at]]\ntime = \"T#0s\"\nset = 1\n").contains("`set` must be a table"));
        assert!(err("[at]\ntime = \"T#0s\"\n").contains("`at` must be an array of tables"));
        assert!(err("chart = \"a\"\nchart = \"b\"\n").contains("TOML syntax error"));
    }

    #[test]
    fn interval_keys() {
        let p = parse(
            "forbid = [\"unsafe\", \"CONFLICT\"]\n[[at]]\ntime = \"T#1s\"\nto = \"T#5s\"\nalways = \"NOT (Fwd AND Rev)\"\nnever = { Alarm = true }\n[[at]]\ntime = \"T#0s\"\nafter = \"DoorCmd\"\nwithin = \"T#2s\"\nexpect = { DoorClosed = true }\n",
        );
        assert!(p.is_err(), "time goes backwards");
        let p = parse(
            "forbid = [\"unsafe\", \"CONFLICT\"]\n[[at]]\ntime = \"T#1s\"\nto = \"T#5s\"\nalways = \"NOT (Fwd AND Rev)\"\nnever = { Alarm = true }\n[[at]]\ntime = \"T#6s\"\nafter = \"DoorCmd\"\nwithin = \"T#2s\"\nexpect = { DoorClosed = true }\n",
        )
        .unwrap();
        assert_eq!(p.forbid.iter().map(|f| f.0.as_str()).collect::<Vec<_>>(), ["unsafe", "CONFLICT"]);
        assert_eq!(p.forbid_line, 1);
        assert_eq!(p.entries[0].to, Some(5_000_000));
        assert_eq!(p.entries[0].always.as_ref().unwrap().expr.as_ref().unwrap().0, "NOT (Fwd AND Rev)");
        assert_eq!(p.entries[0].never.as_ref().unwrap().assigns[0].key, "Alarm");
        assert_eq!(p.entries[1].within, Some(2_000_000));
        assert!(p.entries[1].after.is_some());
        assert!(err("forbid = [\"unsave\"]\n").contains("unknown event kind `unsave` in `forbid` (expected conflict, unsafe, contention, overdue, error); did you mean `unsafe`?"));
        assert!(err("[[at]]\ntime = \"T#2s\"\nto = \"T#1s\"\nalways = { A = true }\n")
            .contains("`to` (T#1s) comes before the entry's `time` (T#2s)"));
        assert!(err("[[at]]\ntime = \"T#2s\"\nto = \"T#3s\"\n").contains("`to` ends an interval"));
        assert!(err("[[at]]\ntime = \"T#2s\"\nwithin = \"T#3s\"\n").contains("`within` needs an `expect`"));
        assert!(
            err("[[at]]\ntime = \"T#2s\"\nafter = \"A\"\nexpect = { B = true }\n").contains("`after` needs a `within`")
        );
        assert!(err("[[at]]\ntime = \"T#2s\"\nalways = 3\n")
            .contains("`always` must be a table such as { Motor = true } or an ST condition"));
    }

    #[test]
    fn equal_times_are_allowed() {
        assert_eq!(parse("[[at]]\ntime = \"T#1s\"\n[[at]]\ntime = \"T#1000ms\"\n").unwrap().entries.len(), 2);
    }

    #[test]
    fn converts_values_by_type() {
        assert_eq!(convert(&Raw::Bool(true), &Type::Bool), Ok(Value::Bool(true)));
        assert!(convert(&Raw::Int(1), &Type::Bool)
            .unwrap_err()
            .contains("expected true or false, found the integer 1"));
        assert_eq!(convert(&Raw::Int(-5), &Type::Int), Ok(Value::Int(-5)));
        assert!(convert(&Raw::Int(300), &Type::SInt).unwrap_err().contains("out of the range of SINT"));
        assert_eq!(convert(&Raw::Int(2), &Type::Real), Ok(Value::Real(2.0)));
        assert_eq!(convert(&Raw::Float(0.1), &Type::Real), Ok(Value::Real(f64::from(0.1f32))));
        assert_eq!(convert(&Raw::Float(0.1), &Type::LReal), Ok(Value::Real(0.1)));
        assert!(convert(&Raw::Float(0.5), &Type::Int).is_err());
        assert_eq!(convert(&Raw::Str("T#1s500ms".into()), &Type::Time), Ok(Value::Time(1_500_000)));
        assert!(convert(&Raw::Str("1s".into()), &Type::Time).unwrap_err().contains("not a TIME literal"));
        assert_eq!(convert(&Raw::Str("hi".into()), &Type::String { len: None }), Ok(Value::Str("hi".into())));
        assert!(convert(&Raw::Str("hello".into()), &Type::String { len: Some(3) }).is_err());
        assert_eq!(convert(&Raw::Str("D#1970-01-02".into()), &Type::Date), Ok(Value::Int(86_400_000_000)));
        let colour = Type::Enum {
            name: Some("Colour".into()),
            base: None,
            values: vec![("Red".into(), 0), ("Green".into(), 1)],
        };
        assert_eq!(convert(&Raw::Str("green".into()), &colour), Ok(Value::Int(1)));
        assert_eq!(convert(&Raw::Str("Colour#Red".into()), &colour), Ok(Value::Int(0)));
        assert!(convert(&Raw::Str("Blue".into()), &colour).unwrap_err().contains("one of Red, Green"));
    }

    #[test]
    fn command_line_texts() {
        assert_eq!(raw_from_text("TRUE", &Type::Bool), Raw::Bool(true));
        assert_eq!(raw_from_text("0", &Type::Bool), Raw::Bool(false));
        assert_eq!(raw_from_text("16#FF", &Type::Byte), Raw::Int(255));
        assert_eq!(raw_from_text("-12", &Type::Int), Raw::Int(-12));
        assert_eq!(raw_from_text("2.5", &Type::LReal), Raw::Float(2.5));
        assert_eq!(raw_from_text("'a b'", &Type::String { len: None }), Raw::Str("a b".into()));
        assert_eq!(raw_from_text("T#2s", &Type::Time), Raw::Str("T#2s".into()));
    }

    #[test]
    fn comparisons() {
        assert!(same(&Value::Real(0.1), &Value::Real(f64::from(0.1f32)), &Type::Real));
        assert!(!same(&Value::Real(0.1), &Value::Real(0.1001), &Type::Real));
        assert!(same(&Value::Real(0.3), &Value::Real(0.1 + 0.2), &Type::LReal));
        assert!(same(&Value::Time(5), &Value::Int(5), &Type::Time));
        assert!(!same(&Value::Bool(true), &Value::Bool(false), &Type::Bool));
    }

    #[test]
    fn suggestions() {
        assert_eq!(closest("Strat", ["Start", "Stop"]), Some("Start"));
        assert_eq!(closest("Q", ["X"]), None);
        assert_eq!(closest("Visble", ["Visible"]), Some("Visible"));
    }

    #[test]
    fn runtime_errors_render_like_rustc() {
        let src = SourceFile::new("c.st", "PROGRAM P\n    x := a / b;\nEND_PROGRAM\n");
        let err = RuntimeError {
            message: "division by zero".into(),
            span: sfc_diagnostics::Span::new(0, 19, 24),
            line: 2,
            column: 10,
            scan: 3,
            time: 30_000,
        };
        assert_eq!(
            render_runtime_error(&err, &src),
            "error: division by zero\n --> c.st:2:10\n  |\n2 |     x := a / b;\n  |          ^^^^^\n  = note: at scan 3, T#30ms"
        );
    }
}
