//! `sfc sim` and `sfc test`: running charts and scenarios, writing traces, printing the
//! condition and time analyses and coverage.

use sfc_diagnostics::{render_human, RenderOptions};
use sfc_sim::coverage::CoverageSet;
use sfc_sim::scenario::{self, Execution, Overrides, Recording, RunLength, Scenario, ScenarioError};
use sfc_sim::trace::{TraceFormat, TraceSink};
use sfc_sim::{format_time, Profile, Simulation, StepReport, TimeStats, TransitionReport};
use std::collections::HashSet;
use std::fmt::Write as _;
use std::io::{IsTerminal, Write};
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
fn report_load_error(e: &ScenarioError) -> u8 {
    let color = std::io::stderr().is_terminal();
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
        let _ = writeln!(err, "error: {e}");
    }
    e.exit_code()
}

/// One line per transition of a condition analysis.
fn transition_line(t: &TransitionReport) -> String {
    let mut line = format!("{} := {} is {}", t.transition, t.guard, if t.value { "TRUE" } else { "FALSE" });
    if !t.operands.is_empty() {
        let ops: Vec<String> = t.operands.iter().map(|(n, v)| format!("{n} = {v}")).collect();
        let _ = write!(line, " with {}", ops.join(", "));
    }
    if !t.change.is_empty() {
        let _ = write!(line, "; needs a change of {}", t.change.join(", "));
    }
    if !t.missing.is_empty() {
        let _ =
            write!(line, "; waits for step{} {}", if t.missing.len() == 1 { "" } else { "s" }, t.missing.join(", "));
    }
    if let Some(m) = &t.masked_by {
        let _ = write!(line, "; masked by {m}, which takes precedence");
    }
    line
}

fn timeout_text(r: &StepReport) -> String {
    match r.timeout {
        Some(t) => format!(", timeout {}", format_time(t)),
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

fn stats_text(stats: &TimeStats) -> String {
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
    out.push_str("\nsituations:");
    let tw = stats.sequence.iter().map(|(t, _)| format_time(*t).len()).max().unwrap_or(0);
    for (t, active) in &stats.sequence {
        let steps = if active.is_empty() { "(no active step)".to_string() } else { active.join(" ") };
        let _ = write!(out, "\n  {:<tw$}  {steps}", format_time(*t));
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
                eprintln!(
                    "error: cannot tell the trace format of `{}`: use a `.jsonl`, `.csv` or `.vcd` file, or `-` for JSON lines on standard output",
                    p.display()
                );
                return 2;
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
    if let Some(named) = &scen.scenario_chart {
        let canon = |p: &Path| std::fs::canonicalize(p).unwrap_or_else(|_| p.to_path_buf());
        if canon(named) != canon(&scen.chart) {
            eprintln!(
                "warning: simulating `{}` with the scenario `{}`, which names the chart `{}`",
                scen.chart.display(),
                scen.name,
                named.display()
            );
        }
    }
    let trace_to_stdout = r.trace.as_deref().is_some_and(|p| p.as_os_str() == "-");
    let mut sink = match (&r.trace, trace_format) {
        (Some(p), Some(f)) => match open_trace(p, f) {
            Ok(s) => Some(s),
            Err(e) => {
                eprintln!("error: {e}");
                return 2;
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
    let json = r.json;
    let mut on_scan = |sim: &Simulation| {
        // Reports are built only for steps that have just overrun (the engine notes each
        // activation's overrun once: a step reports again only after it was left or restarted
        // and overran again). Asking costs nothing in the other scans.
        if !sim.any_newly_overdue() {
            return;
        }
        let scan = sim.next_scan() - 1;
        let time = scan as i64 * sim.options().period;
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
    let recording = Recording { situations: r.stats };
    let Execution { outcome, sim, trace_error } = scenario::execute(&scen, trace_ref, &mut on_scan, recording);
    drop(sink);
    if let Some(e) = trace_error {
        let name = r.trace.as_deref().map_or_else(String::new, |p| p.display().to_string());
        eprintln!("error: cannot write the trace `{name}`: {e}");
        return 2;
    }
    let Some(sim) = sim else {
        eprintln!("error: {}", outcome.error.as_deref().unwrap_or("the chart cannot be simulated"));
        return 1;
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
        });
        if r.scenario.is_some() {
            v["scenario"] = outcome.name.clone().into();
            v["passed"] = outcome.passed().into();
            v["failures"] = outcome.failures.clone().into();
        }
        if r.stats {
            v["stats"] = sim.stats().to_json();
        }
        if r.explain {
            v["explain"] = sim.explain().iter().map(|r| r.to_json()).collect::<Vec<_>>().into();
        }
        report(&v.to_string());
    } else {
        if r.stats {
            report(&stats_text(&sim.stats()));
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
        }
    }
    u8::from(!outcome.passed())
}

/// Every `*.scenario.toml` under `dir`, recursively (hidden directories skipped).
fn walk(dir: &Path, out: &mut Vec<PathBuf>) -> std::io::Result<()> {
    let mut entries: Vec<_> = std::fs::read_dir(dir)?.filter_map(Result::ok).collect();
    entries.sort_by_key(|e| e.file_name());
    for e in entries {
        let path = e.path();
        let name = e.file_name().to_string_lossy().into_owned();
        let Ok(ft) = e.file_type() else { continue };
        if ft.is_dir() {
            if !name.starts_with('.') {
                walk(&path, out)?;
            }
        } else if name.ends_with(".scenario.toml") && path.is_file() {
            out.push(path);
        }
    }
    Ok(())
}

fn indent(text: &str) -> String {
    text.lines().map(|l| format!("    {l}")).collect::<Vec<_>>().join("\n")
}

/// `sfc test`.
pub fn test(paths: &[PathBuf], coverage: bool) -> u8 {
    let mut files: Vec<PathBuf> = Vec::new();
    for p in paths {
        if p.is_dir() {
            let mut found = Vec::new();
            if let Err(e) = walk(p, &mut found) {
                eprintln!("error: cannot read the directory `{}`: {e}", p.display());
                return 2;
            }
            found.sort();
            files.extend(found);
        } else if p.is_file() {
            files.push(p.clone());
        } else {
            eprintln!("error: `{}` does not exist", p.display());
            return 2;
        }
    }
    let mut seen = HashSet::new();
    files.retain(|f| seen.insert(std::fs::canonicalize(f).unwrap_or_else(|_| f.clone())));
    if files.is_empty() {
        let shown: Vec<String> = paths.iter().map(|p| format!("`{}`", p.display())).collect();
        eprintln!("error: no scenario files (`*.scenario.toml`) under {}", shown.join(", "));
        return 2;
    }
    let (mut passed, mut failed) = (0usize, 0usize);
    let mut cov = CoverageSet::new();
    let mut out = std::io::stdout().lock();
    for f in &files {
        // `sfc test .` names `a/b.scenario.toml`, not `./a/b.scenario.toml`.
        let mut shown: PathBuf = f.components().filter(|c| !matches!(c, std::path::Component::CurDir)).collect();
        if shown.as_os_str().is_empty() {
            shown = f.clone();
        }
        let name = shown.display().to_string();
        let outcome = match scenario::load(&shown) {
            Ok(s) => scenario::run(&s, None),
            Err(e) => {
                failed += 1;
                let _ = writeln!(out, "FAIL {name}\n{}", indent(&e.to_string()));
                continue;
            }
        };
        if outcome.scans > 0 || !outcome.coverage.steps.is_empty() {
            cov.add(&outcome.coverage);
        }
        if outcome.passed() {
            passed += 1;
            let _ = writeln!(out, "PASS {name}");
        } else {
            failed += 1;
            let _ = writeln!(out, "FAIL {name}");
            for fl in &outcome.failures {
                let _ = writeln!(out, "{}", indent(fl));
            }
            if let Some(e) = &outcome.error {
                let _ = writeln!(out, "{}", indent(e));
            }
        }
    }
    if coverage {
        let _ = writeln!(out, "coverage:");
        for c in &cov.charts {
            let _ = writeln!(out, "{}", c.report().lines().map(|l| format!("  {l}")).collect::<Vec<_>>().join("\n"));
        }
    }
    let _ = writeln!(out, "{passed} passed, {failed} failed");
    let _ = out.flush();
    u8::from(failed > 0)
}
