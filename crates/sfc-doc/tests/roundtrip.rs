//! The lossless round trip on every chart we have: the examples, the valid fixtures, the
//! invalid fixtures that still have a chart, and the PLCopen corpus imported to text. For every
//! document `d` that `open` returns: `open(to_text(d)) == d`, the saved text is a fixed point
//! (`to_text(open(to_text(d))) == to_text(d)`), it parses, it is in the style of `sfc fmt`
//! where the input's declarations are, and its chart has the same FROM/TO step sets as the
//! original text.

use sfc_doc::{open, to_text, EditorDoc};
use sfc_model::{check_source, CheckOptions};
use std::path::{Path, PathBuf};

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

fn files(dir: &Path, ext: &str) -> Vec<PathBuf> {
    let mut out = Vec::new();
    let Ok(rd) = std::fs::read_dir(dir) else { return out };
    for e in rd.flatten() {
        let p = e.path();
        if p.is_dir() {
            out.extend(files(&p, ext));
        } else if p.to_string_lossy().ends_with(ext) {
            out.push(p);
        }
    }
    out.sort();
    out
}

/// FROM/TO of every transition, by step names (upper case, sorted).
fn structure(text: &str) -> Vec<Vec<(Vec<String>, Vec<String>)>> {
    let checked = check_source(0, "x", text, &CheckOptions::default());
    checked
        .charts
        .iter()
        .map(|c| {
            c.transitions
                .iter()
                .map(|t| {
                    let names = |l: &[usize]| {
                        let mut v: Vec<String> = l.iter().map(|&s| c.steps[s].name.to_ascii_uppercase()).collect();
                        v.sort();
                        v
                    };
                    (names(&t.from), names(&t.to))
                })
                .collect()
        })
        .collect()
}

fn diff(a: &EditorDoc, b: &EditorDoc) -> String {
    let a = serde_json::to_string_pretty(a).unwrap();
    let b = serde_json::to_string_pretty(b).unwrap();
    for (i, (x, y)) in a.lines().zip(b.lines()).enumerate() {
        if x != y {
            return format!("line {i}: `{x}` != `{y}`");
        }
    }
    format!("lengths {} / {}", a.len(), b.len())
}

/// Checks one text; returns a failure description.
fn round_trip(name: &str, text: &str, same_structure: bool, canonical: bool) -> Result<usize, String> {
    let opened = open(0, name, text);
    let original = structure(text);
    // A POU in ST holding actions written in SFC opens too; `structure` lists the charts.
    let mut chart_index = 0;
    for (k, d) in opened.charts.iter().enumerate() {
        let w = to_text(d);
        let (_, diags) = sfc_syntax::parse(0, &w.text);
        // A note (a CODESYS name read in a POU marked so) is no parse failure.
        if let Some(e) = diags.iter().find(|d| d.code != "SFC0013") {
            return Err(format!("{name} chart {k}: saved text does not parse: {}\n{}", e.message, w.text));
        }
        let (unit, _) = sfc_syntax::parse(0, &w.text);
        if canonical && sfc_syntax::print::print(&unit) != w.text {
            return Err(format!("{name} chart {k}: saved text is not in `sfc fmt` style\n{}", w.text));
        }
        let again = open(0, name, &w.text);
        if again.charts.len() != 1 {
            return Err(format!("{name} chart {k}: saved text has {} charts\n{}", again.charts.len(), w.text));
        }
        if again.charts[0] != *d {
            return Err(format!("{name} chart {k}: open(to_text(d)) != d: {}\n{}", diff(d, &again.charts[0]), w.text));
        }
        let w2 = to_text(&again.charts[0]);
        if w2.text != w.text {
            return Err(format!("{name} chart {k}: to_text is not a fixed point\n{}\n----\n{}", w.text, w2.text));
        }
        if same_structure && d.body.is_none() {
            let saved = structure(&w.text);
            if saved.first() != original.get(chart_index) {
                return Err(format!(
                    "{name} chart {k}: FROM/TO changed\n{:?}\n{:?}",
                    original.get(chart_index),
                    saved.first()
                ));
            }
        }
        if d.body.is_none() {
            chart_index += 1;
        }
    }
    Ok(opened.charts.len())
}

/// `canonical`: the saved texts must be in the style of `sfc fmt` (true where the inputs'
/// declarations are).
fn run(paths: Vec<(String, String, bool)>, canonical: bool) -> usize {
    let mut failures = Vec::new();
    let mut charts = 0;
    for (name, text, same) in &paths {
        match round_trip(name, text, *same, canonical) {
            Ok(n) => charts += n,
            Err(e) => failures.push(e),
        }
    }
    assert!(failures.is_empty(), "{} of {} files failed:\n{}", failures.len(), paths.len(), failures.join("\n\n"));
    charts
}

fn st_inputs(dir: &Path, same: bool) -> Vec<(String, String, bool)> {
    files(dir, ".st")
        .into_iter()
        .map(|p| (p.display().to_string(), std::fs::read_to_string(&p).unwrap(), same))
        .collect()
}

#[test]
fn examples_round_trip() {
    let charts = run(st_inputs(&root().join("examples"), true), true);
    assert!(charts >= 4, "only {charts} charts");
}

#[test]
fn examples_with_crlf_line_ends_round_trip() {
    let inputs = st_inputs(&root().join("examples"), true)
        .into_iter()
        .map(|(name, text, same)| (format!("{name} (CRLF)"), text.replace('\n', "\r\n"), same))
        .collect();
    run(inputs, false);
}

#[test]
fn valid_fixtures_round_trip() {
    let charts = run(st_inputs(&root().join("tests/fixtures/valid"), true), false);
    assert!(charts >= 5, "only {charts} charts");
}

#[test]
fn invalid_fixtures_round_trip() {
    // Files with errors still open when they have a chart; their documents round-trip too
    // (the FROM/TO lists may differ where the original names undeclared steps).
    run(st_inputs(&root().join("tests/fixtures/invalid"), false), false);
}

#[test]
fn corpus_round_trips() {
    let corpus = root().join("../shared/corpus");
    let mut inputs = st_inputs(&corpus, false);
    for p in files(&corpus, ".txt") {
        inputs.push((p.display().to_string(), std::fs::read_to_string(&p).unwrap(), true));
    }
    for p in files(&corpus, ".xml") {
        let xml = std::fs::read_to_string(&p).unwrap();
        let imported = sfc_plcopen::import(0, &p.display().to_string(), &xml);
        inputs.push((format!("{} (imported)", p.display()), imported.text, true));
    }
    run(inputs, false);
}

/// Every chart of the files in the shapes of other tools (`tests/corpus/real`) opens in the
/// editor and saves back equal.
#[test]
fn real_tool_files_open_and_round_trip() {
    let mut inputs = Vec::new();
    for p in files(&root().join("tests/corpus/real"), ".xml") {
        let xml = std::fs::read_to_string(&p).unwrap();
        let imported = sfc_plcopen::import(0, &p.display().to_string(), &xml);
        inputs.push((format!("{} (imported)", p.display()), imported.text, true));
    }
    assert!(inputs.len() >= 25);
    let charts = run(inputs, false);
    assert!(charts >= 30, "{charts} charts opened");
}

/// A chart being drawn in another tool: its unconnected transitions (`sfc.loose` from the
/// PLCopen import) are drawn at their places, wired to the step they were wired to, reported
/// as not yet in the chart, and kept by a save (in `sfc.loose` and `sfc.graph`).
#[test]
fn unconnected_transitions_of_an_imported_chart_are_drawn_and_kept() {
    let p = root().join("crates/sfc-plcopen/tests/fixtures/drawing_in_progress.xml");
    let xml = std::fs::read_to_string(&p).unwrap();
    let imported = sfc_plcopen::import(0, "drawing.xml", &xml);
    let opened = open(0, "drawing.st", &imported.text);
    let doc = &opened.charts[0];
    let transitions: Vec<_> =
        doc.elements.iter().filter(|e| e.kind == Some(sfc_doc::ElementKind::Transition)).collect();
    assert_eq!(transitions.len(), 5);
    let conditions: Vec<_> = transitions.iter().filter_map(|e| e.condition.as_deref()).collect();
    for c in ["Level > 80", "Empty AND NOT Start", ""] {
        assert!(conditions.contains(&c), "{conditions:?}");
    }
    let level = transitions.iter().find(|e| e.condition.as_deref() == Some("Level > 80")).unwrap();
    assert_eq!((level.x, level.y), (370.0 + 10.0 - 20.0, 100.0), "kept where it was drawn");
    let draining = doc.elements.iter().find(|e| e.name == "Draining").unwrap();
    assert!(doc.connections.iter().any(|c| c.source == level.id && c.target == draining.id));
    let problems = sfc_doc::problems(doc);
    assert_eq!(problems.iter().filter(|p| p.code == "SFC0204").count(), 3, "{problems:?}");
    let saved = to_text(doc).text;
    assert_eq!(saved.matches("{attribute 'sfc.loose'").count(), 3, "{saved}");
    round_trip("drawing.st", &imported.text, false, false).unwrap();
    let again = open(0, "saved.st", &saved);
    assert_eq!(again.charts[0], *doc);
}
