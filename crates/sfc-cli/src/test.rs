//! `sfc test PATH…`: run every `*.scenario.toml` under the paths, one line per scenario and
//! `N passed, N failed` last; JUnit XML (`--junit`), coverage as text, JSON, lcov or Cobertura
//! (`--coverage FORMAT -o FILE`), and `--deny warnings` (chart warnings and runtime events
//! fail a scenario).

use crate::ci::{self, CaseResult, CoverageFormat, TestCase};
use crate::term::{self, paint, plural, Progress};
use crate::{DenyArg, Status};
use sfc_sim::coverage::CoverageSet;
use sfc_sim::scenario;
use sfc_sim::{Event, ScanRecord, Simulation};
use std::collections::HashMap;
use std::io::Write;
use std::path::{Component, Path, PathBuf};
use std::time::Instant;

#[derive(clap::Args)]
pub struct TestArgs {
    /// Scenario files, or directories searched recursively for `*.scenario.toml`.
    #[arg(required = true)]
    paths: Vec<PathBuf>,
    /// Coverage of steps and transitions per chart: `text` (the default, printed before the last
    /// line) or, written to `-o FILE`, `json`, `lcov` or `cobertura` (GitLab, Jenkins).
    #[arg(long, value_enum, value_name = "FORMAT", num_args = 0..=1, default_missing_value = "text")]
    coverage: Option<CoverageFormat>,
    /// Where `--coverage json|lcov|cobertura` writes.
    #[arg(short = 'o', long = "output", value_name = "FILE", requires = "coverage")]
    output: Option<PathBuf>,
    /// Write the results as JUnit XML (GitLab `artifacts:reports:junit`, Jenkins).
    #[arg(long, value_name = "OUT.xml")]
    junit: Option<PathBuf>,
    /// Fail a scenario on warnings too: warnings of its chart (`sfc check`) and runtime events
    /// (conflict, unsafe, contention) during its run.
    #[arg(long, short = 'D', value_enum, value_name = "LINTS")]
    deny: Vec<DenyArg>,
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

/// The warnings of a chart (`sfc check`, analysis included), rendered; cached per file.
fn chart_warnings(cache: &mut HashMap<PathBuf, Vec<String>>, s: &scenario::Scenario) -> Vec<String> {
    let key = std::fs::canonicalize(&s.chart).unwrap_or_else(|_| s.chart.clone());
    cache
        .entry(key)
        .or_insert_with(|| {
            let opts = sfc_model::CheckOptions { analysis: true, ..Default::default() };
            // The chart as `sfc check` reads it (a PLCopen file as XML, its encoding warned of).
            let decoded = match sfc_driver::read_source(&s.chart) {
                Ok(d) => d,
                Err(e) => return vec![format!("{} (denied by --deny warnings)", e.message)],
            };
            let (file, _, mut diags) = sfc_driver::check_any(0, &s.chart, &decoded.text, &opts);
            diags.extend(sfc_syntax::encoding::warning(0, &decoded));
            diags
                .iter()
                .filter(|d| d.severity == sfc_diagnostics::Severity::Warning)
                .map(|d| {
                    let lc = file.line_col(d.span.start);
                    format!(
                        "{}:{}:{}: warning[{}]: {} (denied by --deny warnings)",
                        file.name, lc.line, lc.column, d.code, d.message
                    )
                })
                .collect()
        })
        .clone()
}

/// `sfc test`.
pub fn test(a: TestArgs) -> u8 {
    if let (Some(f), None) = (a.coverage, &a.output) {
        if f != CoverageFormat::Text {
            term::error(&format!("`--coverage {}` writes a file: give it with -o FILE", f.name()));
            return Status::Usage.code();
        }
    }
    let mut status = Status::Ok;
    let mut files: Vec<PathBuf> = Vec::new();
    for p in &a.paths {
        if p.is_dir() {
            let mut found = Vec::new();
            if let Err(e) = walk(p, &mut found) {
                term::error(&format!("cannot read the directory `{}`: {e}", p.display()));
                status = Status::Usage;
                continue;
            }
            if found.is_empty() {
                term::error(&format!("no scenario files (`*.scenario.toml`) under `{}`", p.display()));
                status = Status::Usage;
            }
            found.sort();
            files.extend(found);
        } else if p.is_file() {
            files.push(p.clone());
        } else {
            term::error(&format!("`{}` does not exist", p.display()));
            status = Status::Usage;
        }
    }
    let mut seen = std::collections::HashSet::new();
    files.retain(|f| seen.insert(std::fs::canonicalize(f).unwrap_or_else(|_| f.clone())));
    if files.is_empty() {
        if status == Status::Ok {
            let shown: Vec<String> = a.paths.iter().map(|p| format!("`{}`", p.display())).collect();
            term::error(&format!("no scenario files (`*.scenario.toml`) under {}", shown.join(", ")));
        }
        return Status::Usage.code();
    }
    let deny = a.deny.contains(&DenyArg::Warnings);
    let color = term::color_stdout();
    let (mut passed, mut failed) = (0usize, 0usize);
    let mut cov = CoverageSet::new();
    let mut cases: Vec<TestCase> = Vec::new();
    let mut warnings_cache = HashMap::new();
    let mut imports_shown = std::collections::HashSet::new();
    let mut vendors_shown = std::collections::HashSet::new();
    let started = Instant::now();
    let mut progress = Progress::new(files.len() as u64, "scenarios");
    let mut out = std::io::stdout().lock();
    for (i, f) in files.iter().enumerate() {
        // `sfc test .` names `a/b.scenario.toml`, not `./a/b.scenario.toml`.
        let mut shown: PathBuf = f.components().filter(|c| !matches!(c, Component::CurDir)).collect();
        if shown.as_os_str().is_empty() {
            shown = f.clone();
        }
        let name = shown.display().to_string();
        let case_start = Instant::now();
        let s = match scenario::load(&shown) {
            Ok(s) => s,
            Err(e) => {
                failed += 1;
                let _ = writeln!(out, "{} {name}\n{}", paint(color, "1;31", "FAIL"), indent(&e.to_string()));
                cases.push(TestCase {
                    name: name.clone(),
                    chart: String::new(),
                    seconds: case_start.elapsed().as_secs_f64(),
                    result: CaseResult::Error { kind: "invalid scenario", lines: vec![e.to_string()] },
                });
                progress.set(i as u64 + 1, || name.clone());
                continue;
            }
        };
        // A PLCopen chart: what its import said (notes, warnings) on standard error, as `check`
        // and `sim` show it, once per chart file.
        if let Some(import) = &s.import {
            if imports_shown.insert(std::fs::canonicalize(&s.chart).unwrap_or_else(|_| s.chart.clone())) {
                progress.suspend(|| term::print_diagnostics(&import.1, std::slice::from_ref(&import.0)));
            }
        }
        // A chart run with the profile its file's vendor chose (no `profile` in the scenario):
        // said once per chart file.
        if let sfc_sim::ProfileSource::Vendor(v) = s.profile_source {
            if vendors_shown.insert(std::fs::canonicalize(&s.chart).unwrap_or_else(|_| s.chart.clone())) {
                let note =
                    sfc_sim::vendor_profile_note("simulated", &s.chart_name(), v, "profile = \"iec\" in the scenario");
                progress.suspend(|| term::note(&note));
            }
        }
        let mut runtime_events: Vec<String> = Vec::new();
        let total = s.total_scans();
        let period = s.options.period;
        let mut on_scan = |sim: &Simulation, rec: Option<&ScanRecord>| {
            let scan = sim.next_scan() - 1;
            progress.set(i as u64, || format!("{name}: scan {}/{total}", scan + 1));
            if deny {
                // The scan's events: from its record when one was built, else the engine's list.
                let happened = match rec {
                    Some(r) => &r.events[..],
                    None => sim.last_events(),
                };
                if happened.is_empty() {
                    return;
                }
                let time = rec.map_or(scan as i64 * period, |r| r.time);
                let mut list: Vec<&Event> = happened.iter().filter(|e| !matches!(e, Event::Error(_))).collect();
                list.sort_by_key(|e| e.rank());
                for e in list {
                    runtime_events.push(format!(
                        "{}: at {} (scan {}): runtime event `{}`: {} (denied by --deny warnings)",
                        name,
                        sfc_sim::format_time(time),
                        scan,
                        e.kind(),
                        e.describe()
                    ));
                }
            }
        };
        let outcome = scenario::execute(&s, None, &mut on_scan, scenario::Recording::default()).outcome;
        progress.set(i as u64 + 1, || name.clone());
        if outcome.scans > 0 || !outcome.coverage.steps.is_empty() {
            cov.add(&outcome.coverage);
        }
        let mut failures = outcome.failures.clone();
        if deny {
            failures.extend(chart_warnings(&mut warnings_cache, &s));
            // One line per kind of event is enough to tell what happened.
            let mut kinds: Vec<String> = Vec::new();
            let total_events = runtime_events.len();
            for e in runtime_events {
                let kind = e.split('`').nth(1).unwrap_or("").to_string();
                if !kinds.contains(&kind) {
                    kinds.push(kind);
                    failures.push(e);
                }
            }
            if total_events > kinds.len() {
                failures.push(format!("{name}: {} runtime events in all", total_events));
            }
        }
        let chart = format!("{} ({})", s.chart_name(), s.pou);
        let seconds = case_start.elapsed().as_secs_f64();
        if failures.is_empty() && outcome.error.is_none() {
            passed += 1;
            let _ = writeln!(out, "{} {name}", paint(color, "1;32", "PASS"));
            cases.push(TestCase { name, chart, seconds, result: CaseResult::Passed });
        } else {
            failed += 1;
            let _ = writeln!(out, "{} {name}", paint(color, "1;31", "FAIL"));
            for fl in &failures {
                let _ = writeln!(out, "{}", indent(fl));
            }
            if let Some(e) = &outcome.error {
                let _ = writeln!(out, "{}", indent(e));
            }
            let mut lines = failures;
            lines.extend(outcome.error.clone());
            let kind =
                if outcome.error.is_some() && outcome.failures.is_empty() { "runtime error" } else { "expectation" };
            cases.push(TestCase { name, chart, seconds, result: CaseResult::Failed { kind, lines } });
        }
    }
    progress.finish();
    let _ = out.flush();
    if let Some(path) = &a.junit {
        let xml = ci::junit(&cases, started.elapsed().as_secs_f64());
        if let Err(e) = sfc_driver::write_atomically(path, xml.as_bytes()) {
            term::error(&format!("cannot write `{}`: {e}", path.display()));
            status = Status::Usage;
        }
    }
    match (a.coverage, &a.output) {
        (Some(CoverageFormat::Text), None) => {
            let _ = writeln!(out, "coverage:");
            for c in &cov.charts {
                let _ =
                    writeln!(out, "{}", c.report().lines().map(|l| format!("  {l}")).collect::<Vec<_>>().join("\n"));
            }
        }
        (Some(format), Some(path)) => {
            let text = ci::coverage(&cov, format);
            if let Err(e) = sfc_driver::write_atomically(path, text.as_bytes()) {
                term::error(&format!("cannot write `{}`: {e}", path.display()));
                status = Status::Usage;
            } else {
                eprintln!("coverage of {} written to `{}`", plural(cov.charts.len(), "chart"), path.display());
            }
        }
        _ => {}
    }
    let _ = writeln!(out, "{passed} passed, {failed} failed");
    let _ = out.flush();
    if failed > 0 {
        status = status.max(Status::Findings);
    }
    status.code()
}
