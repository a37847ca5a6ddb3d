//! Edits made on the example charts, one at a time: the diff names exactly the edit (a step
//! renamed with its references, a condition changed, a step moved), and a chart equals itself.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::indexing_slicing)] // test code: a panic is a failed test

use sfc_diff::{diff, Kind};
use std::path::Path;

fn check(text: &str) -> sfc_model::Checked {
    sfc_model::check_source(0, "chart.st", text, &Default::default())
}

fn examples() -> Vec<String> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples");
    ["blinker/blinker.st", "carwash/carwash.st", "spindle/spindle.st", "traffic/traffic.st"]
        .iter()
        .map(|f| std::fs::read_to_string(root.join(f)).unwrap())
        .collect()
}

/// `text` with the identifier `from` (any case, whole words, outside comments too: the examples'
/// comments name steps, which a rename by hand would leave or change alike) renamed `to`.
fn rename(text: &str, from: &str, to: &str) -> String {
    let mut out = String::new();
    let mut word = String::new();
    for c in text.chars().chain(std::iter::once('\n')) {
        if c.is_ascii_alphanumeric() || c == '_' {
            word.push(c);
            continue;
        }
        out.push_str(if word.eq_ignore_ascii_case(from) { to } else { &word });
        word.clear();
        out.push(c);
    }
    out.pop();
    out
}

#[test]
fn a_chart_equals_itself() {
    for text in examples() {
        let c = check(&text);
        assert!(diff(&c, &check(&text)).equal());
    }
}

#[test]
fn every_step_renamed_is_one_rename() {
    for text in examples() {
        let c = check(&text);
        for chart in &c.charts {
            for s in &chart.steps {
                let to = format!("{}Renamed", s.name);
                let edited = rename(&text, &s.name, &to);
                let d = diff(&c, &check(&edited));
                assert_eq!(d.changes.len(), 1, "{} in {}: {:#?}", s.name, chart.pou, d.changes);
                let ch = &d.changes[0];
                assert_eq!((ch.kind, ch.element, ch.new.as_deref()), (Kind::Renamed, "step", Some(to.as_str())), "{ch:?}");
            }
        }
    }
}

#[test]
fn every_condition_changed_is_one_change() {
    for text in examples() {
        let c = check(&text);
        for chart in &c.charts {
            for t in &chart.transitions {
                let sfc_syntax::ast::Condition::St(e) = &t.condition else { continue };
                let (a, b) = (e.span.start as usize, e.span.end as usize);
                let edited = format!("{}NOT ({}){}", &text[..a], &text[a..b], &text[b..]);
                let d = diff(&c, &check(&edited));
                assert_eq!(d.changes.len(), 1, "{} in {}: {:#?}", t.name, chart.pou, d.changes);
                let ch = &d.changes[0];
                assert_eq!((ch.kind, ch.element, ch.what.as_str(), ch.name.as_str()), (Kind::Changed, "transition", "condition", t.name.as_str()));
            }
        }
    }
}

#[test]
fn every_step_moved_is_layout_only() {
    for text in examples() {
        let c = check(&text);
        for chart in &c.charts {
            for s in &chart.steps {
                // The step's line, with a place before it.
                let at = s.span.start as usize;
                let line = text[..at].rfind('\n').map_or(0, |k| k + 1);
                let edited = format!("{}{{attribute 'sfc.x' := '999'}}\n{}", &text[..line], &text[line..]);
                let d = diff(&c, &check(&edited));
                assert!(d.equal(), "{} in {}: {:#?}", s.name, chart.pou, d.changes);
                assert!(d.layout.iter().any(|l| l.element == format!("step {}", s.name)), "{:?}", d.layout);
            }
        }
    }
}

#[test]
fn spacing_of_code_is_no_change_but_a_string_is() {
    let a = "PROGRAM P\n    VAR x : INT; s : STRING; END_VAR\n    x := x+1;\n    s := 'abc';\nEND_PROGRAM\n";
    let b = "PROGRAM P\n    VAR x : INT; s : STRING; END_VAR\n    x   :=  x + 1 ;\n    s := 'abc';\nEND_PROGRAM\n";
    assert!(diff(&check(a), &check(b)).equal());
    let c = a.replace("'abc'", "'ABC'");
    let d = diff(&check(a), &check(&c));
    assert_eq!(d.changes.len(), 1, "{:?}", d.changes);
}
