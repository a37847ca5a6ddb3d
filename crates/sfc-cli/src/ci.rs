//! What CI servers read: JUnit XML of `sfc test` (GitLab `artifacts:reports:junit`, Jenkins)
//! and coverage as JSON, lcov or Cobertura (GitLab's coverage visualisation, Jenkins). Steps
//! are coverage lines (at the step's name), transitions are branches (at the transition's
//! header): a step is covered when it was ever active, a transition when it ever fired.

use sfc_sim::coverage::{Coverage, CoverageSet};
use std::fmt::Write as _;

/// `--coverage FORMAT`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum CoverageFormat {
    /// Steps never active and transitions never fired, per chart, on standard output.
    Text,
    /// sfc's own JSON (every step and transition with its line and whether it was covered).
    Json,
    /// lcov tracefile (`genhtml`, many CI servers).
    Lcov,
    /// Cobertura XML (GitLab `coverage_report`, Jenkins).
    Cobertura,
}

impl CoverageFormat {
    pub fn name(self) -> &'static str {
        match self {
            CoverageFormat::Text => "text",
            CoverageFormat::Json => "json",
            CoverageFormat::Lcov => "lcov",
            CoverageFormat::Cobertura => "cobertura",
        }
    }
}

/// How one scenario ended, for JUnit.
#[derive(Debug, Clone)]
pub enum CaseResult {
    Passed,
    /// Expectations failed, or the run stopped with a runtime error: `kind` is the failure type,
    /// `lines` the failure lines (the first one is the first differing expectation and its scan).
    Failed {
        kind: &'static str,
        lines: Vec<String>,
    },
    /// The scenario could not run (invalid file, chart with errors).
    Error {
        kind: &'static str,
        lines: Vec<String>,
    },
}

/// One scenario of a `sfc test` run.
#[derive(Debug, Clone)]
pub struct TestCase {
    /// The scenario file as shown.
    pub name: String,
    /// `chart.st (POU)`; empty when the scenario did not load.
    pub chart: String,
    pub seconds: f64,
    pub result: CaseResult,
}

/// Text for XML: the five special characters escaped, and characters XML 1.0 does not allow
/// dropped.
fn xml(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    for c in text.chars() {
        match c {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\'' => out.push_str("&apos;"),
            '\t' | '\n' | '\r' => out.push(c),
            c if (c as u32) < 0x20 || c == '\u{fffe}' || c == '\u{ffff}' => {}
            c => out.push(c),
        }
    }
    out
}

/// Days since 1970-01-01 → (year, month, day) in the proleptic Gregorian calendar.
fn civil(days: i64) -> (i64, u32, u32) {
    let z = days + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z.rem_euclid(146_097);
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let d = (doy - (153 * mp + 2) / 5 + 1) as u32;
    let m = if mp < 10 { mp + 3 } else { mp - 9 } as u32;
    (yoe + era * 400 + i64::from(m <= 2), m, d)
}

/// Now in UTC as `2026-11-27T14:03:09` (JUnit's timestamp has no zone).
fn timestamp() -> String {
    let secs = std::time::SystemTime::now().duration_since(std::time::UNIX_EPOCH).map_or(0, |d| d.as_secs() as i64);
    let (y, m, d) = civil(secs.div_euclid(86_400));
    let s = secs.rem_euclid(86_400);
    format!("{y:04}-{m:02}-{d:02}T{:02}:{:02}:{:02}", s / 3600, s / 60 % 60, s % 60)
}

/// The machine's name, or `localhost` when it cannot be had.
fn hostname() -> String {
    #[cfg(unix)]
    {
        let mut buf = [0u8; 256];
        // SAFETY: the buffer is valid for its length; gethostname writes at most that much.
        let rc = unsafe { libc::gethostname(buf.as_mut_ptr().cast(), buf.len()) };
        if rc == 0 {
            let end = buf.iter().position(|b| *b == 0).unwrap_or(buf.len());
            let name = String::from_utf8_lossy(buf.get(..end).unwrap_or_default()).trim().to_string();
            if !name.is_empty() {
                return name;
            }
        }
    }
    "localhost".to_string()
}

/// `examples/blinker/blinker.scenario.toml` → `examples.blinker` (JUnit's class name: the
/// scenario's folder, so CI servers group scenarios by folder).
fn classname(name: &str) -> String {
    let parent = std::path::Path::new(name).parent().map(|p| p.display().to_string()).unwrap_or_default();
    let dotted = parent.replace(['/', '\\'], ".").trim_matches('.').to_string();
    if dotted.is_empty() {
        "sfc".to_string()
    } else {
        dotted
    }
}

/// The JUnit XML of a `sfc test` run: one `testsuite` (`sfc test`) with one `testcase` per
/// scenario. Valid against the common JUnit schemas (Ant's as written by windyroad, and
/// Jenkins'): every attribute they require, `properties` first, `system-out` and
/// `system-err` last.
pub fn junit(cases: &[TestCase], seconds: f64) -> String {
    let failures = cases.iter().filter(|c| matches!(c.result, CaseResult::Failed { .. })).count();
    let errors = cases.iter().filter(|c| matches!(c.result, CaseResult::Error { .. })).count();
    let mut out = String::from("<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n");
    // The aggregate carries no attributes: Ant's schema (windyroad) declares none on
    // `testsuites` and refuses any; the totals are on the one `testsuite`.
    let _ = writeln!(out, "<testsuites>");
    let _ = writeln!(
        out,
        "  <testsuite name=\"sfc test\" package=\"sfc\" id=\"0\" timestamp=\"{}\" hostname=\"{}\" tests=\"{}\" failures=\"{failures}\" errors=\"{errors}\" skipped=\"0\" time=\"{seconds:.3}\">",
        timestamp(),
        xml(&hostname()),
        cases.len()
    );
    let _ = writeln!(out, "    <properties>");
    let _ = writeln!(out, "      <property name=\"sfc.version\" value=\"{}\"/>", xml(crate::VERSION));
    let _ = writeln!(out, "    </properties>");
    for c in cases {
        let open = format!(
            "    <testcase name=\"{}\" classname=\"{}\" time=\"{:.3}\"",
            xml(&c.name),
            xml(&classname(&c.name)),
            c.seconds
        );
        match &c.result {
            CaseResult::Passed => {
                let _ = writeln!(out, "{open}/>");
            }
            CaseResult::Failed { kind, lines } | CaseResult::Error { kind, lines } => {
                let tag = if matches!(c.result, CaseResult::Failed { .. }) { "failure" } else { "error" };
                let first = lines.first().map(|l| l.lines().next().unwrap_or_default()).unwrap_or_default();
                let mut body = String::new();
                if !c.chart.is_empty() {
                    let _ = writeln!(body, "chart: {}", c.chart);
                }
                for l in lines {
                    let _ = writeln!(body, "{l}");
                }
                let _ = writeln!(out, "{open}>");
                let _ = writeln!(
                    out,
                    "      <{tag} message=\"{}\" type=\"{}\">{}</{tag}>",
                    xml(first),
                    xml(kind),
                    xml(&body)
                );
                let _ = writeln!(out, "    </testcase>");
            }
        }
    }
    let _ = writeln!(out, "    <system-out></system-out>");
    let _ = writeln!(out, "    <system-err></system-err>");
    let _ = writeln!(out, "  </testsuite>");
    let _ = writeln!(out, "</testsuites>");
    out
}

/// One step or transition of a chart with where it is declared.
struct Item {
    step: bool,
    name: String,
    /// 1-based line of its declaration; `None` when it cannot be found.
    line: Option<u32>,
    hit: bool,
}

/// The steps and transitions of a coverage with their lines: the chart file is read and
/// checked again to find the declarations (nested instances `Rev.OpenKM1` by the last part,
/// in the file's other charts; the steps of an action written in SFC, `Lift.ACT_Load.Waiting`,
/// in the chart of the action the part before names).
fn items(c: &Coverage) -> Vec<Item> {
    let text = std::fs::read_to_string(&c.chart).unwrap_or_default();
    // A PLCopen XML chart is checked as the text it imports to; lines are the XML's.
    let iec = sfc_driver::IecText::of(std::path::Path::new(&c.chart), &text);
    let checked = sfc_model::check_source(0, &c.chart, &iec.text, &Default::default());
    let line_at = |span: sfc_diagnostics::Span| match &iec.imported {
        Some(i) => i.xml.line_col(i.map.span_to_xml(span, 0).start).line,
        None => checked.file.line_col(span.start).line,
    };
    let top = checked.charts.iter().position(|ch| ch.pou.eq_ignore_ascii_case(&c.pou));
    let line_of = |name: &str, step: bool| -> Option<u32> {
        let (nested, leaf) = match name.rsplit_once('.') {
            Some((_, leaf)) => (true, leaf),
            None => (false, name),
        };
        let order: Vec<&sfc_model::chart::Chart> = match (nested, top) {
            (false, Some(t)) => checked.charts.get(t).into_iter().collect(),
            _ => checked
                .charts
                .iter()
                .enumerate()
                .filter(|(i, _)| Some(*i) != top || !nested)
                .map(|(_, ch)| ch)
                .collect(),
        };
        let find = |ch: &&sfc_model::chart::Chart| {
            let span = if step {
                ch.steps.iter().find(|s| s.name.eq_ignore_ascii_case(leaf)).map(|s| s.name_span)
            } else {
                ch.transitions.iter().find(|t| t.name.eq_ignore_ascii_case(leaf)).map(|t| t.header_span)
            }?;
            Some(line_at(span))
        };
        let action = name.rsplit('.').nth(1);
        let in_action = action.and_then(|a| {
            checked
                .action_charts
                .iter()
                .filter(|ch| ch.action.as_deref().is_some_and(|x| x.eq_ignore_ascii_case(a)))
                .collect::<Vec<_>>()
                .iter()
                .find_map(find)
        });
        in_action.or_else(|| order.iter().find_map(find))
    };
    // Built on the coverage's public accessors: the names and which were never hit.
    let never_active = c.never_active();
    let never_fired = c.never_fired();
    let mut out = Vec::new();
    for s in &c.steps {
        out.push(Item {
            step: true,
            line: line_of(s, true),
            hit: !never_active.contains(&s.as_str()),
            name: s.clone(),
        });
    }
    for t in &c.transitions {
        out.push(Item {
            step: false,
            line: line_of(t, false),
            hit: !never_fired.contains(&t.as_str()),
            name: t.clone(),
        });
    }
    out
}

fn rate(hit: usize, total: usize) -> f64 {
    if total == 0 {
        1.0
    } else {
        hit as f64 / total as f64
    }
}

/// Coverage in a machine format.
pub fn coverage(set: &CoverageSet, format: CoverageFormat) -> String {
    match format {
        CoverageFormat::Text => set.report(),
        CoverageFormat::Json => coverage_json(set),
        CoverageFormat::Lcov => lcov(set),
        CoverageFormat::Cobertura => cobertura(set),
    }
}

fn counts(hit: usize, total: usize) -> serde_json::Value {
    let percent = if total == 0 { 100.0 } else { (hit as f64 * 1000.0 / total as f64).round() / 10.0 };
    serde_json::json!({ "covered": hit, "total": total, "percent": percent })
}

fn coverage_json(set: &CoverageSet) -> String {
    let (mut sh, mut st, mut th, mut tt) = (0, 0, 0, 0);
    let charts: Vec<serde_json::Value> = set
        .charts
        .iter()
        .map(|c| {
            let items = items(c);
            let (s_hit, s_all) = (c.steps_hit(), c.steps.len());
            let (t_hit, t_all) = (c.transitions_hit(), c.transitions.len());
            sh += s_hit;
            st += s_all;
            th += t_hit;
            tt += t_all;
            serde_json::json!({
                "chart": c.chart,
                "pou": c.pou,
                "runs": c.runs,
                "steps": counts(s_hit, s_all),
                "transitions": counts(t_hit, t_all),
                "items": items.iter().map(|i| serde_json::json!({
                    "kind": if i.step { "step" } else { "transition" },
                    "name": i.name,
                    "line": i.line,
                    "covered": i.hit,
                })).collect::<Vec<_>>(),
            })
        })
        .collect();
    let v = serde_json::json!({
        "tool": format!("sfc {}", crate::VERSION),
        "charts": charts,
        "steps": counts(sh, st),
        "transitions": counts(th, tt),
    });
    format!("{v:#}\n")
}

fn lcov(set: &CoverageSet) -> String {
    let mut out = String::new();
    // One record per file: the POUs of one file share it.
    let mut files: Vec<&str> = Vec::new();
    for c in &set.charts {
        if !files.contains(&c.chart.as_str()) {
            files.push(&c.chart);
        }
    }
    for file in files {
        let _ = writeln!(out, "TN:sfc");
        let _ = writeln!(out, "SF:{file}");
        let mut lines: std::collections::BTreeMap<u32, bool> = std::collections::BTreeMap::new();
        let mut branches: Vec<(u32, bool)> = Vec::new();
        for c in set.charts.iter().filter(|c| c.chart == file) {
            for i in items(c) {
                let Some(line) = i.line else { continue };
                if i.step {
                    let e = lines.entry(line).or_insert(false);
                    *e |= i.hit;
                } else {
                    branches.push((line, i.hit));
                }
            }
        }
        for (n, (line, hit)) in branches.iter().enumerate() {
            let _ = writeln!(out, "BRDA:{line},0,{n},{}", u8::from(*hit));
        }
        let _ = writeln!(out, "BRF:{}", branches.len());
        let _ = writeln!(out, "BRH:{}", branches.iter().filter(|b| b.1).count());
        for (line, hit) in &lines {
            let _ = writeln!(out, "DA:{line},{}", u8::from(*hit));
        }
        let _ = writeln!(out, "LF:{}", lines.len());
        let _ = writeln!(out, "LH:{}", lines.values().filter(|h| **h).count());
        let _ = writeln!(out, "end_of_record");
    }
    out
}

fn cobertura(set: &CoverageSet) -> String {
    struct Class {
        name: String,
        file: String,
        /// line → (step hits, step count, transitions fired, transitions)
        lines: std::collections::BTreeMap<u32, (usize, usize, usize, usize)>,
    }
    let classes: Vec<Class> = set
        .charts
        .iter()
        .map(|c| {
            let mut lines = std::collections::BTreeMap::new();
            for i in items(c) {
                let Some(line) = i.line else { continue };
                let e: &mut (usize, usize, usize, usize) = lines.entry(line).or_default();
                if i.step {
                    e.0 += usize::from(i.hit);
                    e.1 += 1;
                } else {
                    e.2 += usize::from(i.hit);
                    e.3 += 1;
                }
            }
            Class { name: c.pou.clone(), file: c.chart.clone(), lines }
        })
        .collect();
    // Lines are steps; branches are transitions (the counts of `sfc test --coverage`).
    let sum = |f: fn(&(usize, usize, usize, usize)) -> usize, cl: &Class| cl.lines.values().map(f).sum::<usize>();
    let (lh, lv, bh, bv) = classes.iter().fold((0, 0, 0, 0), |acc, cl| {
        (acc.0 + sum(|e| e.0, cl), acc.1 + sum(|e| e.1, cl), acc.2 + sum(|e| e.2, cl), acc.3 + sum(|e| e.3, cl))
    });
    let stamp = std::time::SystemTime::now().duration_since(std::time::UNIX_EPOCH).map_or(0, |d| d.as_secs());
    let mut out = String::from("<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n");
    out.push_str("<!DOCTYPE coverage SYSTEM \"http://cobertura.sourceforge.net/xml/coverage-04.dtd\">\n");
    let _ = writeln!(
        out,
        "<coverage line-rate=\"{:.4}\" branch-rate=\"{:.4}\" lines-covered=\"{lh}\" lines-valid=\"{lv}\" branches-covered=\"{bh}\" branches-valid=\"{bv}\" complexity=\"0\" version=\"{}\" timestamp=\"{stamp}\">",
        rate(lh, lv),
        rate(bh, bv),
        xml(&format!("sfc {}", crate::VERSION))
    );
    out.push_str("  <sources>\n    <source>.</source>\n  </sources>\n  <packages>\n");
    // One package per folder, as Cobertura groups classes.
    let mut packages: Vec<String> = Vec::new();
    for cl in &classes {
        let p = package_of(&cl.file);
        if !packages.contains(&p) {
            packages.push(p);
        }
    }
    for p in packages {
        let members: Vec<&Class> = classes.iter().filter(|cl| package_of(&cl.file) == p).collect();
        let (plh, plv, pbh, pbv) = members.iter().fold((0, 0, 0, 0), |acc, cl| {
            (acc.0 + sum(|e| e.0, cl), acc.1 + sum(|e| e.1, cl), acc.2 + sum(|e| e.2, cl), acc.3 + sum(|e| e.3, cl))
        });
        let _ = writeln!(
            out,
            "    <package name=\"{}\" line-rate=\"{:.4}\" branch-rate=\"{:.4}\" complexity=\"0\">\n      <classes>",
            xml(&p),
            rate(plh, plv),
            rate(pbh, pbv)
        );
        for cl in members {
            let _ = writeln!(
                out,
                "        <class name=\"{}\" filename=\"{}\" line-rate=\"{:.4}\" branch-rate=\"{:.4}\" complexity=\"0\">\n          <methods/>\n          <lines>",
                xml(&cl.name),
                xml(&cl.file),
                rate(sum(|e| e.0, cl), sum(|e| e.1, cl)),
                rate(sum(|e| e.2, cl), sum(|e| e.3, cl))
            );
            for (line, (shit, sall, thit, tall)) in &cl.lines {
                let hits = usize::from(*shit > 0 || *thit > 0);
                if let Some(pct) = (*thit * 100).checked_div(*tall) {
                    let _ = writeln!(
                        out,
                        "            <line number=\"{line}\" hits=\"{hits}\" branch=\"true\" condition-coverage=\"{pct}% ({thit}/{tall})\"/>"
                    );
                } else {
                    let _ = writeln!(
                        out,
                        "            <line number=\"{line}\" hits=\"{}\" branch=\"false\"/>",
                        usize::from(*shit > 0 && *sall > 0)
                    );
                }
            }
            out.push_str("          </lines>\n        </class>\n");
        }
        out.push_str("      </classes>\n    </package>\n");
    }
    out.push_str("  </packages>\n</coverage>\n");
    out
}

/// `examples/tank/tank.st` → `examples.tank`.
fn package_of(file: &str) -> String {
    let parent = std::path::Path::new(file).parent().map(|p| p.display().to_string()).unwrap_or_default();
    let p = parent.replace(['/', '\\'], ".").trim_matches('.').to_string();
    if p.is_empty() {
        ".".to_string()
    } else {
        p
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn calendar() {
        assert_eq!(civil(0), (1970, 1, 1));
        assert_eq!(civil(19_723), (2024, 1, 1));
        assert_eq!(civil(-1), (1969, 12, 31));
        assert_eq!(civil(11_016), (2000, 2, 29));
    }

    #[test]
    fn escapes() {
        assert_eq!(xml("a<b & \"c\"\u{1b}[0m"), "a&lt;b &amp; &quot;c&quot;[0m");
        assert_eq!(classname("examples/blinker/blinker.scenario.toml"), "examples.blinker");
        assert_eq!(classname("x.scenario.toml"), "sfc");
    }
}
