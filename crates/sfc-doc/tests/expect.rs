//! Snapshot tests, data-driven: every `snapshots/*.st` opens to the document in `*.doc.json`
//! and saves as `*.saved.st`; every hand-made (edited) document `edits/*.json` saves as
//! `*.saved.st` with the problems in `*.problems`, and opening that text gives the document
//! back (ids normalised). `UPDATE_EXPECT=1` rewrites the expected files.

use sfc_doc::{normalize_ids, open, to_text, EditorDoc, Written};
use std::path::{Path, PathBuf};

fn dir(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests").join(name)
}

fn inputs(d: &Path, ext: &str) -> Vec<PathBuf> {
    let mut v: Vec<PathBuf> = std::fs::read_dir(d)
        .unwrap()
        .flatten()
        .map(|e| e.path())
        .filter(|p| p.to_string_lossy().ends_with(ext) && !p.to_string_lossy().ends_with(".saved.st"))
        .collect();
    v.sort();
    v
}

/// Compares `actual` with the file at `path` (or writes it under `UPDATE_EXPECT=1`).
fn expect(path: &Path, actual: &str, failures: &mut Vec<String>) {
    if std::env::var_os("UPDATE_EXPECT").is_some() {
        let tmp = path.with_extension("tmp");
        std::fs::write(&tmp, actual).unwrap();
        std::fs::rename(&tmp, path).unwrap();
        return;
    }
    match std::fs::read_to_string(path) {
        Ok(expected) if expected == actual => {}
        Ok(expected) => {
            let line = expected.lines().zip(actual.lines()).position(|(a, b)| a != b).unwrap_or(0);
            failures.push(format!(
                "{}: differs at line {}:\n  expected: {:?}\n  actual:   {:?}",
                path.display(),
                line + 1,
                expected.lines().nth(line),
                actual.lines().nth(line)
            ))
        }
        Err(_) => failures.push(format!("{}: missing (run with UPDATE_EXPECT=1)", path.display())),
    }
}

/// The comments of a text, in order (pragmas are not comments).
fn comments(text: &str) -> Vec<String> {
    let (unit, _) = sfc_syntax::parse(0, text);
    unit.trivia
        .into_iter()
        .filter(|t| {
            matches!(t.kind, sfc_syntax::ast::TriviaKind::BlockComment | sfc_syntax::ast::TriviaKind::LineComment)
        })
        .map(|t| t.text)
        .collect()
}

fn problems(w: &Written) -> String {
    w.problems.iter().map(|p| format!("{} {}: {}\n", p.code, p.element, p.message)).collect()
}

/// `open(to_text(d))` gives `d` back (ids normalised) and the text is a fixed point.
fn round_trip(name: &str, d: &EditorDoc, w: &Written, failures: &mut Vec<String>) {
    let (_, diags) = sfc_syntax::parse(0, &w.text);
    if !diags.is_empty() {
        failures.push(format!("{name}: saved text does not parse: {}", diags[0].message));
    }
    let again = open(0, name, &w.text);
    match again.charts.as_slice() {
        [c] if *c == normalize_ids(d) => {
            if to_text(c).text != w.text {
                failures.push(format!("{name}: the saved text is not a fixed point"));
            }
        }
        [c] => failures.push(format!(
            "{name}: reopened document differs:\n{}\n----\n{}",
            serde_json::to_string(&normalize_ids(d)).unwrap(),
            serde_json::to_string(c).unwrap()
        )),
        other => failures.push(format!("{name}: reopened text has {} charts", other.len())),
    }
}

#[test]
fn charts_open_and_save_as_expected() {
    let mut failures = Vec::new();
    let files = inputs(&dir("snapshots"), ".st");
    assert!(files.len() >= 4);
    for p in files {
        let text = std::fs::read_to_string(&p).unwrap();
        let name = p.file_name().unwrap().to_string_lossy().to_string();
        let opened = open(0, &name, &text);
        assert!(opened.diagnostics.iter().all(|d| !d.is_error()), "{name}: {:?}", opened.diagnostics);
        assert_eq!(opened.charts.len(), 1, "{name}");
        let d = &opened.charts[0];
        let stem = p.with_extension("");
        expect(
            &stem.with_extension("doc.json"),
            &format!("{}\n", serde_json::to_string_pretty(d).unwrap()),
            &mut failures,
        );
        let w = to_text(d);
        expect(&stem.with_extension("saved.st"), &w.text, &mut failures);
        assert!(w.problems.is_empty(), "{name}: {:?}", w.problems);
        round_trip(&name, d, &w, &mut failures);
        // Saved into its file, the chart keeps every comment of the file.
        let file = sfc_doc::splice(&text, d);
        for c in comments(&text) {
            if comments(&file).iter().filter(|k| **k == c).count()
                != comments(&text).iter().filter(|k| **k == c).count()
            {
                failures.push(format!("{name}: the saved file lost the comment {c:?}:\n{file}"));
            }
        }
        // The saved text checks like the original: no new diagnostics.
        let before = opened.diagnostics.len();
        let after = sfc_model::check_source(0, &name, &w.text, &Default::default()).diagnostics;
        assert!(after.len() <= before, "{name}: saving adds diagnostics: {after:?}");
    }
    assert!(failures.is_empty(), "{}", failures.join("\n\n"));
}

#[test]
fn edited_documents_save_and_open_again() {
    let mut failures = Vec::new();
    let files = inputs(&dir("edits"), ".json");
    assert!(files.len() >= 3);
    for p in files {
        let name = p.file_name().unwrap().to_string_lossy().to_string();
        let d: EditorDoc = serde_json::from_str(&std::fs::read_to_string(&p).unwrap()).unwrap();
        let w = to_text(&d);
        let stem = p.with_extension("");
        expect(&stem.with_extension("saved.st"), &w.text, &mut failures);
        expect(&stem.with_extension("problems"), &problems(&w), &mut failures);
        round_trip(&name, &d, &w, &mut failures);
    }
    assert!(failures.is_empty(), "{}", failures.join("\n\n"));
}
