//! The SimaticML fixtures under `tests/fixtures/` (written for sfc in the shape of TIA Portal
//! exports, see `tests/README.md`): each one's imported text and diagnostics are kept beside it
//! (`<name>.expected.st`, `<name>.diags`, rewritten with `SFC_BLESS=1`), the text parses, and an
//! independent count of the XML (steps, transitions, non-empty actions, branches, read with
//! roxmltree here) matches what the text holds.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::indexing_slicing)] // test code: a panic is a failed test

use sfc_diagnostics::SourceFile;
use sfc_syntax::ast::{Body, Item, SfcElement};
use std::collections::HashSet;
mod common;
use common::{fixture_dir, fixtures};
use std::path::Path;

fn snapshot(path: &Path, actual: &str) -> Result<(), String> {
    if std::env::var_os("SFC_BLESS").is_some() {
        std::fs::write(path, actual).unwrap();
        return Ok(());
    }
    let expected = std::fs::read_to_string(path).unwrap_or_default();
    if expected == actual {
        Ok(())
    } else {
        Err(format!(
            "{} differs (SFC_BLESS=1 rewrites it):\n--- expected\n{expected}\n--- actual\n{actual}",
            path.display()
        ))
    }
}

fn render(diags: &[sfc_diagnostics::Diagnostic], xml: &str) -> String {
    let file = SourceFile::new("x", xml);
    let mut out = String::new();
    for d in diags {
        let lc = file.line_col(d.span.start);
        out.push_str(&format!("{} {} {}:{} {}\n", d.severity.as_str(), d.code, lc.line, lc.column, d.message));
    }
    out
}

/// What the XML holds, counted here with roxmltree alone.
#[derive(Debug, PartialEq, Default)]
struct Counts {
    steps: usize,
    transitions: usize,
    actions: usize,
    branches: usize,
}

fn count_xml(xml: &str) -> (Counts, usize) {
    let doc = roxmltree::Document::parse(xml.trim_start_matches('\u{feff}')).unwrap();
    let named = |n: &'static str| doc.descendants().filter(move |d| d.is_element() && d.tag_name().name() == n);
    let c = Counts {
        steps: named("Step").count(),
        transitions: named("Transition").count(),
        actions: named("Action").filter(|a| a.children().any(|t| t.is_element())).count(),
        branches: named("Branch").count(),
    };
    (c, named("EndConnection").count())
}

/// What the imported text holds: steps (without the final steps of sequence ends), transitions,
/// action associations plus the actions kept unassociated (`sfc.s7graph.step`), branches named
/// in `sfc.s7graph.branch`.
fn count_text(text: &str) -> (Counts, usize) {
    let (unit, _) = sfc_syntax::parse(0, text);
    let mut c = Counts::default();
    let mut ends = 0;
    let mut branches = HashSet::new();
    for item in &unit.items {
        let Item::Pou(p) = item else { continue };
        let Body::Sfc(elements) = &p.body else { continue };
        for e in elements {
            match e {
                SfcElement::Step(s) => {
                    if s.attributes.iter().any(|a| a.name == "sfc.s7graph.end") {
                        ends += 1;
                    } else {
                        c.steps += 1;
                    }
                    c.actions += s.associations.len();
                }
                SfcElement::Transition(t) => {
                    c.transitions += 1;
                    for a in t.attributes.iter().filter(|a| a.name == "sfc.s7graph.branch") {
                        for part in a.value.as_deref().unwrap_or("").split("; ") {
                            let mut w = part.split(' ');
                            branches.insert(w.nth(1).unwrap_or("").to_string());
                        }
                    }
                }
                SfcElement::Action(a) => {
                    if a.attributes.iter().any(|x| x.name == "sfc.s7graph.step") {
                        c.actions += 1;
                    }
                }
            }
        }
    }
    c.branches = branches.len();
    (c, ends)
}

fn one(path: &Path) -> Result<(), String> {
    let xml = std::fs::read_to_string(path).unwrap();
    let out = sfc_simaticml::import(0, &xml);
    let stem = path.file_stem().unwrap().to_str().unwrap();
    snapshot(&path.with_file_name(format!("{stem}.expected.st")), &out.text)?;
    snapshot(&path.with_file_name(format!("{stem}.diags")), &render(&out.diagnostics, &xml))?;
    let errors = out.diagnostics.iter().any(|d| d.is_error());
    if stem.starts_with("error_") != errors {
        return Err(format!("{stem}: errors {errors}: {}", render(&out.diagnostics, &xml)));
    }
    let (_, perrs) = sfc_syntax::parse(0, &out.text);
    if let Some(e) = perrs.iter().find(|d| d.is_error()) {
        return Err(format!("{stem}: the imported text does not parse: {e:?}\n{}", out.text));
    }
    let (want, want_ends) = count_xml(&xml);
    let (got, got_ends) = count_text(&out.text);
    if want != got || want_ends != got_ends {
        return Err(format!("{stem}: XML holds {want:?} + {want_ends} ends, the text {got:?} + {got_ends} ends"));
    }
    Ok(())
}

#[test]
fn every_fixture_imports_as_expected_and_counts_match() {
    let paths = fixtures();
    assert!(paths.len() >= 12, "fixtures missing: {paths:?}");
    let failures: Vec<String> = paths.iter().filter_map(|p| one(p).err()).collect();
    assert!(failures.is_empty(), "{}", failures.join("\n\n"));
}

#[test]
fn the_fixtures_cover_the_namespaces_and_versions() {
    let all: String = fixtures().iter().map(|p| std::fs::read_to_string(p).unwrap()).collect();
    for ns in ["Graph/v1\"", "Graph/v4\"", "Graph/v5\"", "Graph/v6\""] {
        assert!(all.contains(ns), "no fixture in {ns}");
    }
    for v in ["<GraphVersion>2.0<", "<GraphVersion>4.0<", "<GraphVersion>6.0<"] {
        assert!(all.contains(v), "no fixture with {v}");
    }
    for ev in ["S1", "S0", "V1", "V0", "L1", "L0", "A1", "R1"] {
        assert!(all.contains(&format!("Event=\"{ev}\"")), "no action with event {ev}");
    }
    for t in [
        "AltBegin",
        "AltEnd",
        "SimBegin",
        "SimEnd",
        "<EndConnection />",
        ">Jump<",
        "Interlock=\"true\"",
        "ProgrammingLanguage=\"FBD\"",
    ] {
        assert!(all.contains(t), "no fixture with {t}");
    }
}

#[test]
fn malformed_xml_is_one_located_error() {
    let out =
        sfc_simaticml::import(2, "<Document>\n  <Engineering version=\"V20\" />\n  <SW.Blocks.FB>\n</Document>\n");
    assert_eq!(out.diagnostics.len(), 1);
    let d = &out.diagnostics[0];
    assert_eq!((d.code, d.span.file), ("SFC0701", 2));
}

#[test]
fn a_broken_network_is_located_on_its_part() {
    let path = fixture_dir().join("conveyor_handover_v6.xml");
    let xml = std::fs::read_to_string(path).unwrap().replacen("<Part Name=\"O\"", "<Part Name=\"PBox\"", 1);
    let out = sfc_simaticml::import(0, &xml);
    let d = out.diagnostics.iter().find(|d| d.code == "SFC0743").expect("SFC0743");
    let at = xml.find("<Part Name=\"PBox\"").unwrap() as u32;
    assert_eq!(d.span.start, at, "{d:?}");
    assert!(d.message.contains("`PBox`"), "{}", d.message);
}

#[test]
fn a_cycle_in_a_network_is_an_error_not_a_hang() {
    let path = fixture_dir().join("fbd_conditions_v4.xml");
    let xml = std::fs::read_to_string(path).unwrap();
    // Wire the first O box's output back into its own first input.
    let pat = "<Part Name=\"O\" UId=\"";
    let at = xml.find(pat).unwrap();
    let uid: String = xml[at + pat.len()..].chars().take_while(|c| c.is_ascii_digit()).collect();
    let cyc = xml.replacen("<IdentCon UId=\"21\" />", &format!("<NameCon UId=\"{uid}\" Name=\"out\" />"), 1);
    let out = sfc_simaticml::import(0, &cyc);
    assert!(
        out.diagnostics.iter().any(|d| d.code == "SFC0743" && d.message.contains("cycle")),
        "{:?}",
        out.diagnostics
    );
}

#[test]
fn a_supervision_that_is_not_st_is_a_located_error() {
    let path = fixture_dir().join("action_events_v5.xml");
    let xml = std::fs::read_to_string(path).unwrap().replacen(
        "<ConstantValue>T#5S</ConstantValue>",
        "<ConstantValue>T#5S)</ConstantValue>",
        1,
    );
    let out = sfc_simaticml::import(0, &xml);
    let d = out.diagnostics.iter().find(|d| d.code == "SFC0750").expect("SFC0750");
    let step = xml.find("Init=\"false\" Name=\"Work\"").unwrap();
    let at = (step + xml[step..].find("<Supervision ").unwrap()) as u32;
    assert_eq!(d.span.start, at, "{d:?}");
}

#[test]
fn a_tag_named_like_a_variable_of_the_block_gets_its_own_name() {
    let path = fixture_dir().join("conveyor_handover_v6.xml");
    // The PLC tag "PartAtEnd" beside the block's input PartAtEnd.
    let xml = std::fs::read_to_string(path).unwrap().replacen(
        "<Component Name=\"HandoverDB\" /><Component Name=\"Override\" />",
        "<Component Name=\"PartAtEnd\" />",
        1,
    );
    let out = sfc_simaticml::import(0, &xml);
    assert!(out.text.contains("PartAtEnd_1 : BOOL; (* \"PartAtEnd\" *)"), "{}", out.text);
    let (_, errs) = sfc_syntax::parse(0, &out.text);
    assert!(errs.iter().all(|d| !d.is_error()), "{errs:?}");
}
