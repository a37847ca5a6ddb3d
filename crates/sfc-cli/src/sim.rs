//! `sfc sim`: running a chart or a scenario, writing traces, printing runtime events and the
//! condition and time analyses.

use crate::term::{self, Progress};
use crate::Status;
use sfc_diagnostics::{render_human, RenderOptions};
use sfc_sim::scenario::{self, Execution, Overrides, Recording, RunLength, Scenario, ScenarioError};
use sfc_sim::trace::{TraceFormat, TraceSink};
use sfc_sim::{
    format_time, Event, MechanismRuns, MechanismView, Profile, RunEnd, ScanRecord, Simulation, StepReport, TimeStats,
    TransitionReport,
};
use std::fmt::Write as _;
use std::io::Write;
use std::path::{Path, PathBuf};

/// What `sfc sim` was asked to do (parsed by clap in `main.rs`).
pub struct SimRequest {
    pub file: PathBuf,
    pub scenario: Option<PathBuf>,
    pub period: Option<i64>,
    pub until: Option<i64>,
    pub scans: Option<u64>,
    pub trace: Option<PathBuf>,
    pub profile: Option<Profile>,
    pub pou: Option<String>,
    pub stats: bool,
    /// Every situation in order instead of the summary.
    pub stats_full: bool,
    pub explain: bool,
    pub json: bool,
    pub set: Vec<(String, String)>,
}

/// `--period`: a positive TIME literal.
pub fn parse_period(s: &str) -> Result<i64, String> {
    match sfc_sim::parse_time(s) {
        Some(t) if t > 0 => Ok(t),
        Some(_) => Err(format!("the scan period must be positive, found `{s}`")),
        None => Err(format!("`{s}` is not a TIME literal (write e.g. T#10ms)")),
    }
}

/// `--until`: a TIME literal, not negative.
pub fn parse_until(s: &str) -> Result<i64, String> {
    match sfc_sim::parse_time(s) {
        Some(t) if t >= 0 => Ok(t),
        Some(_) => Err(format!("`--until` must not be negative, found `{s}`")),
        None => Err(format!("`{s}` is not a TIME literal (write e.g. T#5s)")),
    }
}

/// `--set NAME=VALUE`.
pub fn parse_set(s: &str) -> Result<(String, String), String> {
    match s.split_once('=') {
        Some((name, value)) if !name.trim().is_empty() => Ok((name.trim().to_string(), value.to_string())),
        _ => Err(format!("expected NAME=VALUE, found `{s}`")),
    }
}

/// Prints a scenario or chart error the way `sfc check` prints diagnostics, returns the exit
/// status.
pub fn report_load_error(e: &ScenarioError) -> u8 {
    let color = term::color_stderr();
    let mut err = std::io::stderr().lock();
    if let Some(d) = &e.diagnostics {
        let (file, diags) = &**d;
        if let Some(f) = &e.file {
            let at = match e.line {
                Some(l) => format!("{f}:{l}"),
                None => f.clone(),
            };
            let _ = writeln!(err, "error: {at}: the chart `{}` has errors", file.name);
        }
        for diag in diags {
            let _ = writeln!(err, "{}", render_human(diag, std::slice::from_ref(file), RenderOptions { color }));
        }
        let n = diags.len();
        let _ = writeln!(err, "{n} error{} emitted", if n == 1 { "" } else { "s" });
    } else {
        drop(err);
        term::error(&e.to_string());
    }
    e.exit_code()
}

/// One line per transition of a condition analysis.
fn transition_line(t: &TransitionReport) -> String {
    let mut line = format!("{} := {} is {}", t.transition, t.guard, if t.value { "TRUE" } else { "FALSE" });
    if !t.operands.is_empty() {
        let _ = write!(line, " with {}", t.operands_text());
    }
    if !t.needs.is_empty() {
        let _ = write!(line, ": {}", t.needs.join(" and "));
    }
    if !t.missing.is_empty() {
        let _ =
            write!(line, "; waits for step{} {}", if t.missing.len() == 1 { "" } else { "s" }, t.missing.join(", "));
    }
    if !t.dwell.is_empty() {
        let _ = write!(line, "; waits for the minimum time of {}", t.dwell.join(", "));
    }
    if let Some(m) = &t.masked_by {
        let _ = write!(line, "; masked by {m}, which takes precedence");
    }
    line
}

fn timeout_text(r: &StepReport) -> String {
    match r.timeout {
        // How long the step may still wait before its supervision time expires.
        Some(t) if t > r.elapsed => format!(", timeout {} ({} left)", format_time(t), format_time(t - r.elapsed)),
        Some(t) => format!(", timeout {} (expired)", format_time(t)),
        None => String::new(),
    }
}

/// The automatic report of a step that exceeded its `sfc.timeout` in `scan` at `time`.
fn overdue_text(scan: u64, time: i64, r: &StepReport) -> String {
    let names: Vec<&str> = r.transitions.iter().map(|t| t.transition.as_str()).collect();
    let waiting = if names.is_empty() { "no outgoing transition".to_string() } else { names.join(" or ") };
    let mut out = format!(
        "scan {}, {}: step {} active for {} (timeout {}): waiting for {waiting}",
        scan,
        format_time(time),
        r.step,
        format_time(r.elapsed),
        r.timeout.map_or_else(|| "none".to_string(), format_time)
    );
    for t in &r.transitions {
        let _ = write!(out, "\n  {}", transition_line(t));
    }
    out
}

fn explain_text(reports: &[StepReport], sim: &Simulation) -> String {
    let mut out = format!("condition analysis after scan {}:", sim.next_scan().saturating_sub(1));
    if reports.is_empty() {
        out.push_str("\n  no active step waits for a transition");
    }
    for r in reports {
        let _ = write!(out, "\n  step {} active for {}{}", r.step, format_time(r.elapsed), timeout_text(r));
        if r.transitions.is_empty() {
            out.push_str("\n    no outgoing transition");
        }
        for t in &r.transitions {
            let _ = write!(out, "\n    {}", transition_line(t));
        }
    }
    out
}

fn opt_time(t: Option<i64>) -> String {
    t.map_or_else(|| "-".to_string(), format_time)
}

/// The situations of a run grouped by their active steps, longest total time first:
/// `(active steps, times entered, total time µs)`; `end` is when the run ended.
fn situations(stats: &TimeStats, end: i64) -> Vec<(String, usize, i64)> {
    let mut groups: Vec<(String, usize, i64)> = Vec::new();
    let mut index: std::collections::HashMap<String, usize> = std::collections::HashMap::new();
    let mut it = stats.sequence.iter().peekable();
    while let Some((t, active)) = it.next() {
        let until = it.peek().map_or(end, |(next, _)| *next);
        let key = if active.is_empty() { "(no active step)".to_string() } else { active.join(" ") };
        let i = *index.entry(key.clone()).or_insert_with(|| {
            groups.push((key, 0, 0));
            groups.len() - 1
        });
        if let Some(g) = groups.get_mut(i) {
            g.1 += 1;
            g.2 += (until - t).max(0);
        }
    }
    // Stable: equal totals keep the order of first appearance.
    groups.sort_by(|a, b| b.2.cmp(&a.2));
    groups
}

/// How many situations `--stats` lists.
const TOP_SITUATIONS: usize = 10;

fn stats_text(stats: &TimeStats, full: bool, end: i64) -> String {
    let rows: Vec<[String; 5]> = stats
        .steps
        .iter()
        .map(|s| [s.step.clone(), s.activations.to_string(), opt_time(s.min), opt_time(s.mean), opt_time(s.max)])
        .collect();
    let head = ["step", "activations", "min", "mean", "max"].map(String::from);
    let mut widths = head.clone().map(|h| h.len());
    for r in &rows {
        for (w, c) in widths.iter_mut().zip(r) {
            *w = (*w).max(c.chars().count());
        }
    }
    let fmt_row = |r: &[String; 5]| {
        let mut l = format!("  {:<w$}", r[0], w = widths[0]);
        for (c, w) in r.iter().zip(widths).skip(1) {
            let _ = write!(l, "  {c:>w$}");
        }
        l.trim_end().to_string()
    };
    let mut out = String::from("time analysis:\n");
    out.push_str(&fmt_row(&head));
    for r in &rows {
        out.push('\n');
        out.push_str(&fmt_row(r));
    }
    if full {
        out.push_str("\nsituations:");
        let tw = stats.sequence.iter().map(|(t, _)| format_time(*t).len()).max().unwrap_or(0);
        for (t, active) in &stats.sequence {
            let steps = if active.is_empty() { "(no active step)".to_string() } else { active.join(" ") };
            let _ = write!(out, "\n  {:<tw$}  {steps}", format_time(*t));
        }
        return out;
    }
    let groups = situations(stats, end);
    let _ = write!(
        out,
        "\nsituations: {} entered, {} different; the longest in total:",
        stats.sequence.len(),
        groups.len()
    );
    let shown: Vec<&(String, usize, i64)> = groups.iter().take(TOP_SITUATIONS).collect();
    let tw = shown.iter().map(|g| format_time(g.2).len()).max().unwrap_or(0);
    let cw = shown.iter().map(|g| g.1.to_string().len()).max().unwrap_or(0);
    for (steps, count, total) in &shown {
        let times = if *count == 1 { "time " } else { "times" };
        let _ = write!(out, "\n  {:>tw$}  {count:>cw$} {times}  {steps}", format_time(*total));
    }
    if groups.len() > shown.len() {
        let _ =
            write!(out, "\n  … and {} more (--stats-full lists every situation in order)", groups.len() - shown.len());
    }
    if stats.dropped > 0 {
        let _ = write!(
            out,
            "\n  … {} later change{} of situation not recorded (the time analysis keeps the first {})",
            stats.dropped,
            if stats.dropped == 1 { "" } else { "s" },
            sfc_sim::engine::MAX_SITUATIONS
        );
    }
    out
}

/// A table with a header, left-aligned columns, two spaces apart.
fn table(head: &[&str], rows: &[Vec<String>]) -> String {
    let mut widths: Vec<usize> = head.iter().map(|h| h.chars().count()).collect();
    for r in rows {
        for (w, c) in widths.iter_mut().zip(r) {
            *w = (*w).max(c.chars().count());
        }
    }
    let line = |cells: Vec<String>| {
        let mut l = String::from(" ");
        for (c, w) in cells.iter().zip(&widths) {
            let pad = w.saturating_sub(c.chars().count());
            let _ = write!(l, " {c}{}", " ".repeat(pad + 1));
        }
        l.trim_end().to_string()
    };
    let mut out = line(head.iter().map(|h| h.to_string()).collect());
    for r in rows {
        out.push('\n');
        out.push_str(&line(r.clone()));
    }
    out
}

/// Every SFC instance at a glance: activation bit, active steps with their times, runs,
/// resets, error records and the last one.
pub fn mechanisms_text(mechs: &[MechanismView]) -> String {
    let rows: Vec<Vec<String>> = mechs
        .iter()
        .map(|m| {
            let steps: Vec<String> = m.active.iter().map(|(s, t)| format!("{s} ({})", format_time(*t))).collect();
            let activation = match (&m.activation_variable, m.activation) {
                (Some(_), Some(v)) => if v { "TRUE" } else { "FALSE" }.to_string(),
                _ => "-".to_string(),
            };
            vec![
                m.instance.clone(),
                m.pou.clone(),
                activation,
                if m.running { "running" } else { "idle" }.to_string(),
                if steps.is_empty() { "(none)".to_string() } else { steps.join(", ") },
                m.runs.to_string(),
                m.resets.to_string(),
                m.errors.to_string(),
            ]
        })
        .collect();
    let mut out = String::from("mechanisms:\n");
    out.push_str(&table(&["instance", "of", "activation", "state", "active steps", "runs", "resets", "errors"], &rows));
    for m in mechs {
        if let Some(e) = &m.last_error {
            let _ = write!(out, "\n  last error of {}: {}", m.instance, e.message());
        }
    }
    out
}

/// States of a run `--stats` lists (`--stats-full`: every state kept).
const STATES_SHOWN: usize = 12;

/// The time analysis per run: each run's states with their times and how it ended, then per
/// state its count, min, mean and max over the runs.
pub fn runs_text(all: &[MechanismRuns], full: bool) -> String {
    let mut out = String::new();
    for m in all {
        if !out.is_empty() {
            out.push('\n');
        }
        let count = |f: &dyn Fn(&RunEnd) -> bool| m.runs.iter().filter(|r| r.end.as_ref().is_some_and(f)).count();
        let normal = count(&|e| *e == RunEnd::Normal);
        let error = count(&|e| matches!(e, RunEnd::Error(_)));
        let reset = count(&|e| *e == RunEnd::Reset);
        let open = m.runs.iter().filter(|r| r.end.is_none()).count();
        let _ = write!(
            out,
            "runs of {}: {} ({normal} normal, {error} error, {reset} reset{})",
            m.instance,
            m.runs.len() as u64 + m.dropped,
            if open > 0 { ", 1 in progress" } else { "" }
        );
        if m.dropped > 0 {
            let _ = write!(out, "; the first {} not listed", m.dropped);
        }
        let shown = if full { m.runs.len() } else { 20 };
        let skip = m.runs.len().saturating_sub(shown);
        if skip > 0 {
            let _ = write!(out, "\n  … {skip} earlier runs not shown (--stats-full lists them)");
        }
        let rows: Vec<Vec<String>> = m.runs[skip..]
            .iter()
            .map(|r| {
                let shown_states = if full { r.states.len() } else { r.states.len().min(STATES_SHOWN) };
                let states: Vec<String> =
                    r.states[..shown_states].iter().map(|(s, t)| format!("{s} {}", format_time(*t))).collect();
                let mut states = states.join(" → ");
                let more = (r.states.len() - shown_states) as u64 + r.dropped_states;
                if more > 0 {
                    let _ = write!(states, " → … {more} more state{}", if more == 1 { "" } else { "s" });
                }
                vec![
                    r.number.to_string(),
                    format_time(r.start),
                    format_time(r.total),
                    r.end.as_ref().map_or_else(|| "in progress".to_string(), RunEnd::text),
                    states,
                ]
            })
            .collect();
        if !rows.is_empty() {
            out.push('\n');
            out.push_str(&table(&["run", "start", "total", "ended", "states passed"], &rows));
        }
        if !m.states.is_empty() {
            let _ = write!(out, "\nstates of {} over its runs:\n", m.instance);
            let rows: Vec<Vec<String>> = m
                .states
                .iter()
                .map(|k| {
                    vec![
                        k.state.clone(),
                        k.count.to_string(),
                        format_time(k.min),
                        format_time(k.mean),
                        format_time(k.max),
                    ]
                })
                .collect();
            out.push_str(&table(&["state", "count", "min", "mean", "max"], &rows));
        }
    }
    out
}

/// Runtime events shown per kind before `sfc sim` only counts them.
const EVENTS_SHOWN: usize = 10;

/// The runtime events of a run: the first few of each kind printed as they happen, all counted.
#[derive(Default)]
struct EventLog {
    /// `(kind, count)` in the order conflict, unsafe, contention.
    counts: Vec<(&'static str, usize)>,
    json: Vec<serde_json::Value>,
}

impl EventLog {
    fn count(&mut self, kind: &'static str) -> usize {
        match self.counts.iter_mut().find(|(k, _)| *k == kind) {
            Some((_, n)) => {
                *n += 1;
                *n
            }
            None => {
                self.counts.push((kind, 1));
                1
            }
        }
    }
    /// `events: 3 unsafe, 120 conflict`.
    fn summary(&self) -> Option<String> {
        if self.counts.is_empty() {
            return None;
        }
        let parts: Vec<String> = self.counts.iter().map(|(k, n)| format!("{n} {k}")).collect();
        Some(format!("events: {}", parts.join(", ")))
    }
}

/// Opens the trace output: a file (created or truncated) or, for `-`, standard output.
fn open_trace(path: &Path, format: TraceFormat) -> Result<Box<dyn TraceSink>, String> {
    if path.as_os_str() == "-" {
        return Ok(format.writer(std::io::BufWriter::new(std::io::stdout())));
    }
    let f = std::fs::File::create(path).map_err(|e| format!("cannot create the trace `{}`: {e}", path.display()))?;
    Ok(format.writer(std::io::BufWriter::new(f)))
}

/// `sfc sim`.
pub fn sim(r: SimRequest) -> u8 {
    let trace_format = match &r.trace {
        Some(p) => match TraceFormat::from_path(p) {
            Some(f) => Some(f),
            None => {
                term::error(&format!(
                    "cannot tell the trace format of `{}`: use a `.jsonl`, `.csv` or `.vcd` file, or `-` for JSON lines on standard output",
                    p.display()
                ));
                return Status::Usage.code();
            }
        },
        None => None,
    };
    let length = match (r.scans, r.until) {
        (Some(n), _) => Some(RunLength::Scans(n)),
        (None, Some(t)) => Some(RunLength::Until(t)),
        (None, None) => None,
    };
    let overrides =
        Overrides { chart: None, pou: r.pou.clone(), period: r.period, profile: r.profile, length, set: r.set.clone() };
    let loaded = match &r.scenario {
        Some(s) => scenario::load_with(s, &Overrides { chart: Some(r.file.clone()), ..overrides }),
        None => scenario::for_chart(&r.file, &overrides),
    };
    let scen: Scenario = match loaded {
        Ok(s) => s,
        Err(e) => return report_load_error(&e),
    };
    // A PLCopen chart: what its import said (notes, warnings), as `check` shows it.
    if let Some(import) = &scen.import {
        term::print_diagnostics(&import.1, std::slice::from_ref(&import.0));
    }
    // The profile came from the file (a CODESYS, TwinCAT or e!COCKPIT export): said.
    if let sfc_sim::ProfileSource::Vendor(v) = scen.profile_source {
        let instead =
            if r.scenario.is_some() { "--profile iec, or profile = \"iec\" in the scenario," } else { "--profile iec" };
        term::note(&sfc_sim::vendor_profile_note("simulated", &scen.chart_name(), v, instead));
    }
    // A chart that is not UTF-8 was read as Latin-1 / Windows-1252: said, as `check` says it.
    if let Ok(decoded) = sfc_driver::read_source(&scen.chart) {
        if let Some(w) = sfc_syntax::encoding::warning(0, &decoded) {
            let file = sfc_diagnostics::SourceFile::new(scen.chart_name(), decoded.text.clone());
            term::print_diagnostics(&[w], &[file]);
        }
    }
    if let Some(named) = &scen.scenario_chart {
        let canon = |p: &Path| std::fs::canonicalize(p).unwrap_or_else(|_| p.to_path_buf());
        if canon(named) != canon(&scen.chart) {
            term::warning(&format!(
                "simulating `{}` with the scenario `{}`, which names the chart `{}`",
                scen.chart.display(),
                scen.name,
                named.display()
            ));
        }
    }
    let trace_to_stdout = r.trace.as_deref().is_some_and(|p| p.as_os_str() == "-");
    let mut sink = match (&r.trace, trace_format) {
        (Some(p), Some(f)) => match open_trace(p, f) {
            Ok(s) => Some(s),
            Err(e) => {
                term::error(&e);
                return Status::Usage.code();
            }
        },
        _ => None,
    };
    // Reports go to stdout unless the trace does.
    let report = |text: &str| {
        if trace_to_stdout {
            eprintln!("{text}");
        } else {
            println!("{text}");
        }
    };
    let mut overdue_json: Vec<serde_json::Value> = Vec::new();
    let mut records_json: Vec<serde_json::Value> = Vec::new();
    let json = r.json;
    let mut events = EventLog::default();
    let mut progress = Progress::new(scen.total_scans(), "scans");
    let period = scen.options.period;
    let mut on_scan = |sim: &Simulation, rec: Option<&ScanRecord>| {
        let scan = sim.next_scan() - 1;
        let time = rec.map_or(scan as i64 * period, |r| r.time);
        progress.set(scan + 1, || format_time(time));
        // Runtime events: the first few of each kind as they happen (errors are reported at
        // the end, rustc-like). Without a record the engine's list is read (unsorted).
        let happened = match rec {
            Some(r) => &r.events[..],
            None => sim.last_events(),
        };
        if !happened.is_empty() {
            let mut list: Vec<&Event> = happened.iter().filter(|e| !matches!(e, Event::Error(_))).collect();
            list.sort_by_key(|e| e.rank());
            for e in list {
                let n = events.count(e.kind());
                if n > EVENTS_SHOWN {
                    continue;
                }
                if json {
                    let mut v = e.to_json();
                    v["scan"] = scan.into();
                    v["time"] = format_time(time).into();
                    events.json.push(v);
                } else {
                    report(&format!("scan {scan}, {}: {}: {}", format_time(time), e.kind(), e.describe()));
                }
            }
        }
        // Error records of supervision timeouts, as they are completed.
        for rec in sim.fresh_error_records() {
            if json {
                records_json.push(rec.to_json());
            } else {
                report(&format!("scan {scan}, {}: error record: {}", format_time(time), rec.message()));
            }
        }
        // Reports are built only for steps that have just overrun (the engine notes each
        // activation's overrun once: a step reports again only after it was left or restarted
        // and overran again). Asking costs nothing in the other scans.
        if !sim.any_newly_overdue() {
            return;
        }
        for step in sim.newly_overdue() {
            let Some(x) = &sim.explain_step(&step) else { continue };
            if json {
                let mut v = x.to_json();
                v["scan"] = scan.into();
                v["time"] = format_time(time).into();
                overdue_json.push(v);
            } else {
                report(&overdue_text(scan, time, x));
            }
        }
    };
    let trace_ref: Option<&mut dyn TraceSink> = match sink.as_mut() {
        Some(b) => Some(&mut **b),
        None => None,
    };
    let recording = Recording { situations: r.stats, records: false };
    let Execution { outcome, sim, trace_error } = scenario::execute(&scen, trace_ref, &mut on_scan, recording);
    progress.finish();
    drop(sink);
    if let Some(e) = trace_error {
        let name = r.trace.as_deref().map_or_else(String::new, |p| p.display().to_string());
        term::error(&format!("cannot write the trace `{name}`: {e}"));
        return Status::Usage.code();
    }
    let Some(sim) = sim else {
        term::error(outcome.error.as_deref().unwrap_or("the chart cannot be simulated"));
        return Status::Findings.code();
    };
    if let Some(e) = &outcome.error {
        eprintln!("{e}");
    }
    let last_time = (outcome.scans as i64 - 1).max(0) * scen.options.period;
    if json {
        let mut v = serde_json::json!({
            "pou": sim.pou_name(),
            "scans": outcome.scans,
            "time": format_time(last_time),
            "active": sim.active(),
            "error": sim.error().map(|e| serde_json::json!({
                "message": e.message, "line": e.line, "column": e.column, "scan": e.scan, "time": format_time(e.time)
            })),
            "overdue": overdue_json,
            "error_records": records_json,
            "events": events.json,
            "event_counts": events.counts.iter().map(|(k, n)| ((*k).to_string(), serde_json::json!(n))).collect::<serde_json::Map<_, _>>(),
        });
        // The profile and who chose it: "option" (--profile), "scenario", "vendor" (the file is a
        // CODESYS, TwinCAT or e!COCKPIT export, named in "vendor") or "default".
        v["profile"] = scen.options.profile.name().into();
        v["profile_source"] = match scen.profile_source {
            sfc_sim::ProfileSource::Default => "default",
            sfc_sim::ProfileSource::Option => "option",
            sfc_sim::ProfileSource::Scenario => "scenario",
            sfc_sim::ProfileSource::Vendor(_) => "vendor",
        }
        .into();
        if let sfc_sim::ProfileSource::Vendor(vendor) = scen.profile_source {
            v["vendor"] = vendor.name().into();
        }
        if r.scenario.is_some() {
            v["scenario"] = outcome.name.clone().into();
            v["passed"] = outcome.passed().into();
            v["failures"] = outcome.failures.clone().into();
        }
        if r.stats {
            let stats = sim.stats();
            let mut j = stats.to_json();
            let end = last_time + scen.options.period;
            j["situations"] = situations(&stats, end)
                .iter()
                .take(if r.stats_full { usize::MAX } else { TOP_SITUATIONS })
                .map(|(active, count, total)| serde_json::json!({"active": active, "count": count, "total": format_time(*total)}))
                .collect::<Vec<_>>()
                .into();
            j["situations_entered"] = stats.sequence.len().into();
            if !r.stats_full {
                // The whole sequence only with --stats-full: an hour of a blinker is 7,000 entries.
                if let Some(seq) = j.get_mut("sequence").and_then(|s| s.as_array_mut()) {
                    seq.truncate(TOP_SITUATIONS);
                }
            }
            v["stats"] = j;
            v["mechanisms"] = sim.mechanisms().iter().map(MechanismView::to_json).collect::<Vec<_>>().into();
            v["runs"] = sim.runs().iter().map(MechanismRuns::to_json).collect::<Vec<_>>().into();
        }
        if r.explain {
            v["explain"] = sim.explain().iter().map(|r| r.to_json()).collect::<Vec<_>>().into();
        }
        report(&v.to_string());
    } else {
        for (kind, n) in &events.counts {
            if *n > EVENTS_SHOWN {
                report(&format!(
                    "… {} more `{kind}` events not shown (--trace OUT.jsonl writes every one)",
                    n - EVENTS_SHOWN
                ));
            }
        }
        if r.stats {
            report(&stats_text(&sim.stats(), r.stats_full, last_time + scen.options.period));
            report(&mechanisms_text(&sim.mechanisms()));
            report(&runs_text(&sim.runs(), r.stats_full));
        }
        if r.explain {
            report(&explain_text(&sim.explain(), &sim));
        }
        if r.scenario.is_some() {
            if outcome.passed() {
                report(&format!("PASS {}", outcome.name));
            } else {
                let mut text = format!("FAIL {}", outcome.name);
                for f in &outcome.failures {
                    let _ = write!(text, "\n  {f}");
                }
                report(&text);
            }
        }
        if !trace_to_stdout {
            let active = sim.active();
            println!(
                "simulated {}: {} scan{}, last at {} (period {}, profile {})",
                sim.pou_name(),
                outcome.scans,
                if outcome.scans == 1 { "" } else { "s" },
                format_time(last_time),
                format_time(scen.options.period),
                scen.options.profile.name()
            );
            println!("active steps: {}", if active.is_empty() { "(none)".to_string() } else { active.join(" ") });
            if let Some(line) = events.summary() {
                println!("{line}");
            }
        } else if let Some(line) = events.summary() {
            eprintln!("{line}");
        }
    }
    if outcome.passed() {
        Status::Ok.code()
    } else {
        Status::Findings.code()
    }
}
