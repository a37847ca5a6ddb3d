//! The L5X fixtures under `tests/fixtures/` (written for these tests in the shape Studio 5000
//! exports): each one's imported text (`NAME.expected.st`) and diagnostics (`NAME.diags`, the
//! import's and those of checking the text, at their L5X line and column) are kept beside it and
//! rewritten with `SFC_BLESS=1`. The fixtures of `tests/fixtures/` import without errors; those
//! of `tests/fixtures/errors/` with the errors their `.diags` show. For every fixture an
//! independent count of the XML's elements (with roxmltree) is compared with the chart the text
//! holds.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::indexing_slicing)] // test code: a panic is a failed test

use sfc_diagnostics::{render_human, Diagnostic, RenderOptions, SourceFile};
use std::path::{Path, PathBuf};

fn dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures")
}

fn l5x_files(d: &Path) -> Vec<PathBuf> {
    let mut v: Vec<PathBuf> = std::fs::read_dir(d)
        .unwrap()
        .flatten()
        .map(|e| e.path())
        .filter(|p| p.extension().is_some_and(|x| x.eq_ignore_ascii_case("l5x")))
        .collect();
    v.sort();
    v
}

fn snapshot(path: &Path, actual: &str) -> Result<(), String> {
    if std::env::var_os("SFC_BLESS").is_some() {
        std::fs::write(path, actual).map_err(|e| e.to_string())?;
        return Ok(());
    }
    let expected = std::fs::read_to_string(path).unwrap_or_default();
    if expected != actual {
        return Err(format!(
            "{} differs (run with SFC_BLESS=1 to accept)\n--- expected\n{expected}\n--- actual\n{actual}",
            path.display()
        ));
    }
    Ok(())
}

/// The import's diagnostics and those of checking its text, located in the XML.
fn diagnostics(xml: &str) -> (sfc_l5x::Output, sfc_model::Checked, Vec<Diagnostic>) {
    let out = sfc_l5x::import(0, xml);
    let checked = sfc_model::check_source(1, "imported", &out.text, &Default::default());
    let mut diags = out.diagnostics.clone();
    for d in &checked.diagnostics {
        let mut d = d.clone();
        d.span = out.map.span_to_xml(d.span, 0);
        for l in &mut d.labels {
            l.span = out.map.span_to_xml(l.span, 0);
        }
        diags.push(d);
    }
    sfc_diagnostics::sort(&mut diags);
    diags.dedup();
    (out, checked, diags)
}

/// Counts in the XML: SFC routines, steps, transitions, actions, stops.
fn count_xml(xml: &str) -> [usize; 5] {
    let doc = roxmltree::Document::parse(xml).unwrap();
    let n = |name: &str| {
        doc.descendants()
            .filter(|d| d.has_tag_name(name))
            .filter(|d| d.ancestors().any(|a| a.has_tag_name("SFCContent")))
            .count()
    };
    let routines = doc
        .descendants()
        .filter(|d| d.has_tag_name("Routine") && d.attribute("Type") == Some("SFC"))
        .filter(|d| d.ancestors().any(|a| a.has_tag_name("Program")))
        .count();
    [routines, n("Step"), n("Transition"), n("Action"), n("Stop")]
}

/// The same counts in the imported text: charts, steps that are not stops, transitions (with
/// those kept in `sfc.loose`), action associations, stops (`sfc.logix.stop`).
fn count_text(checked: &sfc_model::Checked, text: &str) -> [usize; 5] {
    let charts = &checked.charts;
    let stops = text.matches("{attribute 'sfc.logix.stop' := 'true'}").count();
    let steps: usize = charts.iter().map(|c| c.steps.len()).sum();
    let loose = text.matches("{attribute 'sfc.loose'").count();
    [
        charts.len(),
        steps - stops,
        charts.iter().map(|c| c.transitions.len()).sum::<usize>() + loose,
        charts.iter().flat_map(|c| &c.steps).map(|s| s.associations.len()).sum(),
        stops,
    ]
}

fn one(path: &Path, errors_expected: bool) -> Result<(), String> {
    let name = path.file_name().unwrap().to_str().unwrap();
    let xml = std::fs::read_to_string(path).map_err(|e| e.to_string())?;
    let (out, checked, diags) = diagnostics(&xml);
    let rel = if errors_expected { format!("tests/fixtures/errors/{name}") } else { format!("tests/fixtures/{name}") };
    let file = SourceFile::new(&rel, xml.as_str());
    let rendered: String =
        diags.iter().map(|d| render_human(d, std::slice::from_ref(&file), RenderOptions::default()) + "\n").collect();
    let stem = path.with_extension("");
    snapshot(&stem.with_extension("expected.st"), &out.text)?;
    snapshot(&stem.with_extension("diags"), &rendered)?;
    let has_errors = diags.iter().any(Diagnostic::is_error);
    if has_errors != errors_expected {
        return Err(format!("{name}: errors expected: {errors_expected}, found:\n{rendered}"));
    }
    let (a, b) = (count_xml(&xml), count_text(&checked, &out.text));
    if a != b {
        return Err(format!(
            "{name}: [routines, steps, transitions, actions, stops] in the XML {a:?}, in the text {b:?}"
        ));
    }
    Ok(())
}

#[test]
fn every_fixture_imports_as_expected_and_counts_match() {
    let main = l5x_files(&dir());
    assert!(main.len() >= 12, "fixtures missing: {main:?}");
    let errors = l5x_files(&dir().join("errors"));
    assert!(errors.len() >= 3, "error fixtures missing: {errors:?}");
    let failures: Vec<String> =
        main.iter().map(|p| one(p, false)).chain(errors.iter().map(|p| one(p, true))).filter_map(Result::err).collect();
    assert!(failures.is_empty(), "{}", failures.join("\n\n"));
}

/// Every transition of every fixture: its condition's first characters in the text map back
/// onto the same characters in the CDATA of the L5X (exactly, not onto the element).
#[test]
fn conditions_map_onto_their_cdata() {
    for p in l5x_files(&dir()) {
        let xml = std::fs::read_to_string(&p).unwrap();
        let out = sfc_l5x::import(0, &xml);
        for (at, _) in out.text.match_indices("\n        := ") {
            let start = at + "\n        := ".len();
            let word: String =
                out.text[start..].chars().take_while(|c| c.is_ascii_alphanumeric() || *c == '_').collect();
            if word.is_empty() || word == "FALSE" {
                continue;
            }
            let span = sfc_diagnostics::Span::new(0, start as u32, (start + word.len()) as u32);
            let r = out.map.to_xml(span);
            let found = &xml[r.start as usize..r.end as usize];
            // A step member rewritten (`Filling.DN` → `(Filling.T >= …)`) maps onto the original.
            assert!(
                found == word || found.starts_with(word.trim_start_matches("TIME_TO_DINT")),
                "{}: `{word}` maps to `{found}`",
                p.display()
            );
        }
    }
}

#[test]
fn malformed_xml_gives_one_located_error() {
    let xml = "\u{feff}<?xml version=\"1.0\" encoding=\"UTF-8\" standalone=\"yes\"?>\n<RSLogix5000Content SchemaRevision=\"1.0\">\n<Controller Name=\"C\">\n</Programs>\n</RSLogix5000Content>\n";
    let out = sfc_l5x::import(0, xml);
    assert!(out.text.is_empty());
    assert_eq!(out.diagnostics.len(), 1, "{:?}", out.diagnostics);
    let d = &out.diagnostics[0];
    assert_eq!(d.code, "SFC0701");
    let lc = SourceFile::new("m", xml).line_col(d.span.start);
    assert_eq!(lc.line, 4, "{d:?}");
}

#[test]
fn selection_priorities_follow_x_not_leg_order() {
    let xml = std::fs::read_to_string(dir().join("selection.L5X")).unwrap();
    let text = sfc_l5x::import(0, &xml).text;
    // Tran_001 (X=200) is on the leg listed second, Tran_000 (X=420) on the first.
    assert!(text.contains("TRANSITION Tran_001 (PRIORITY := 1) FROM Wait TO Metal"), "{text}");
    assert!(text.contains("TRANSITION Tran_000 (PRIORITY := 2) FROM Wait TO Plastic"), "{text}");
}

#[test]
fn step_members_are_rewritten_with_the_tag_presets() {
    let xml = std::fs::read_to_string(dir().join("tank_fill.L5X")).unwrap();
    let text = sfc_l5x::import(0, &xml).text;
    assert!(text.contains("Tank1.Level >= Tank1.HighLimit OR (Filling.T >= T#5000ms)"), "{text}");
    assert!(text.contains("TIME_TO_DINT(Settle.T) >= 2000"), "{text}");
}

#[test]
fn every_qualifier_and_the_boolean_action() {
    let xml = std::fs::read_to_string(dir().join("qualifiers.L5X")).unwrap();
    let text = sfc_l5x::import(0, &xml).text;
    for q in [
        "(N)",
        "(S)",
        "(R)",
        "(L, T#500ms)",
        "(D, T#500ms)",
        "(P)",
        "(P1)",
        "(P0)",
        "(SL, T#700ms)",
        "(SD, T#300ms)",
        "(DS, T#400ms)",
    ] {
        assert!(text.contains(q), "{q} missing:\n{text}");
    }
    assert!(text.contains("{attribute 'sfc.logix.boolean' := 'true'}\n    ACTION Action_010: END_ACTION"), "{text}");
    assert!(text.contains("Action_001(R);"), "{text}");
}

#[test]
fn programs_routines_and_controller_settings() {
    let xml = std::fs::read_to_string(dir().join("two_programs.L5X")).unwrap();
    let out = sfc_l5x::import(0, &xml);
    assert!(out.text.contains("PROGRAM Line1_Sequence") && out.text.contains("PROGRAM Line2_Sequence"), "{}", out.text);
    assert!(out.text.contains("{attribute 'sfc.logix.routine' := 'Line2/Sequence'}"), "{}", out.text);
    assert_eq!(out.diagnostics.iter().filter(|d| d.code == "SFC0720").count(), 2);
    // A program export has no controller settings: Studio's defaults, one note for the file.
    let xml = std::fs::read_to_string(dir().join("selection.L5X")).unwrap();
    let out = sfc_l5x::import(0, &xml);
    assert!(out.text.contains("{attribute 'sfc.logix.exec' := 'CurrentActive'}"), "{}", out.text);
    let notes: Vec<_> = out.diagnostics.iter().filter(|d| d.code == "SFC0720").collect();
    assert_eq!(notes.len(), 1, "{notes:?}");
    assert!(notes[0].message.contains("Program export carries no controller SFC settings"), "{notes:?}");
}
