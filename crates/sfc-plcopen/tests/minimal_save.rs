//! Saving a POU into a PLCopen file changes only what changed (`sfc_plcopen::patch_pou`): on
//! the Beremiz exports of the shared corpus (`../shared/corpus/beremiz/*.plc.xml`,
//! `../shared/corpus/matiec/SFC_TEST.xml`, read where they are), the PLCopen files of the
//! repository's own corpus (`tests/corpus/real`) and a Beremiz-style fixture
//! (`tests/fixtures/minimal_save/`), for every SFC POU:
//! - the POU as imported, saved unchanged, gives the file byte for byte;
//! - a step moved by 40 changes only the `<position>` line of that step, a transition moved
//!   only its own; the element ids, `executionOrderId` and `addData` stay.
//!
//! On the fixture also: an action block and a jump moved, a condition edited and a step renamed
//! in place, and an added step, which replaces the POU.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::indexing_slicing)] // test code: a panic is a failed test

mod common;
use common::*;
use sfc_plcopen::Patched;
use sfc_syntax::ast::{Item, Pou, SfcElement, SourceUnit};
use std::path::{Path, PathBuf};

fn fixture() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/minimal_save/beremiz_style.xml")
}

/// The files of the shared corpus this test is about; `None` (with a note) when it is missing.
fn shared_files() -> Option<Vec<PathBuf>> {
    let dir = corpus_dir()?;
    let mut out: Vec<PathBuf> = std::fs::read_dir(dir.join("beremiz"))
        .map(|rd| rd.flatten().map(|e| e.path()).filter(|p| p.to_string_lossy().ends_with(".plc.xml")).collect())
        .unwrap_or_default();
    out.sort();
    out.push(dir.join("matiec/SFC_TEST.xml"));
    let out: Vec<PathBuf> = out.into_iter().filter(|p| p.is_file()).collect();
    if out.is_empty() {
        eprintln!("skipped: no Beremiz export in {}", dir.display());
        return None;
    }
    Some(out)
}

/// The PLCopen files of the repository's corpus drawn by tools that keep a layout.
fn repo_files() -> Vec<PathBuf> {
    let mut out = Vec::new();
    for tool in ["beremiz", "beremiz_old", "openplc", "tc6_v10", "codesys", "ecockpit"] {
        if let Ok(rd) = std::fs::read_dir(root().join("tests/corpus/real").join(tool)) {
            out.extend(rd.flatten().map(|e| e.path()).filter(|p| p.extension().is_some_and(|x| x == "xml")));
        }
    }
    out.sort();
    out
}

/// The POUs of a parsed text.
fn pous(unit: &SourceUnit) -> impl Iterator<Item = &Pou> {
    unit.items.iter().filter_map(|i| if let Item::Pou(p) = i { Some(p) } else { None })
}

/// The text of POU `p` (its attribute pragmas included), as the editor would save it alone.
fn pou_text<'t>(text: &'t str, p: &Pou) -> &'t str {
    let start = p.attributes.iter().map(|a| a.span.start).fold(p.span.start, u32::min);
    &text[start as usize..p.span.end as usize]
}

fn check(text: &str) -> sfc_model::Checked {
    check_text("pou.st", text)
}

/// `text` with the attribute `name` of the element spanning `at` (its pragmas) set to `value`.
fn set_attr(text: &str, attrs: &[sfc_syntax::ast::Attribute], name: &str, value: &str) -> String {
    let a = attrs.iter().rev().find(|a| a.name == name).unwrap_or_else(|| panic!("no {name}"));
    let mut out = text.to_string();
    out.replace_range(a.span.start as usize..a.span.end as usize, &format!("{{attribute '{name}' := '{value}'}}"));
    out
}

fn num(attrs: &[sfc_syntax::ast::Attribute], name: &str) -> f64 {
    attrs.iter().rev().find(|a| a.name == name).and_then(|a| a.value.as_deref()).unwrap().parse().unwrap()
}

/// The 1-based numbers of the lines that differ between two texts of as many lines.
fn changed_lines(a: &str, b: &str) -> Vec<usize> {
    let (la, lb): (Vec<&str>, Vec<&str>) = (a.lines().collect(), b.lines().collect());
    assert_eq!(la.len(), lb.len(), "the number of lines changed");
    la.iter().zip(&lb).enumerate().filter(|(_, (x, y))| x != y).map(|(i, _)| i + 1).collect()
}

/// The line of the `<position>` of the file's element that the import wrote at `at` of the text.
fn position_line(xml: &str, imported: &sfc_plcopen::Imported, at: u32) -> usize {
    let r = imported.map.to_xml(sfc_diagnostics::Span::new(0, at, at + 1));
    let doc = roxmltree::Document::parse(xml).unwrap();
    let el = doc.descendants().find(|n| n.is_element() && n.range().start == r.start as usize).unwrap();
    let pos = el.children().find(|c| c.tag_name().name() == "position").unwrap();
    xml[..pos.range().start].matches('\n').count() + 1
}

/// Moves `e` of POU `p` (text `pt`) by 40 and 40, saves, and checks that only its `<position>`
/// line changed, to the new numbers. Returns a description of a failure.
fn move_one(
    name: &str,
    xml: &str,
    imported: &sfc_plcopen::Imported,
    p: &Pou,
    pt: &str,
    e: &SfcElement,
) -> Result<(), String> {
    let (attrs, at, what) = match e {
        SfcElement::Step(s) => (&s.attributes, s.span.start, format!("step {}", s.name.text)),
        SfcElement::Transition(t) => {
            (&t.attributes, t.span.start, format!("transition {:?}", t.name.as_ref().map(|n| &n.text)))
        }
        SfcElement::Action(_) => unreachable!(),
    };
    let base = p.attributes.iter().map(|a| a.span.start).fold(p.span.start, u32::min) as usize;
    let local: Vec<sfc_syntax::ast::Attribute> = attrs
        .iter()
        .map(|a| {
            let mut a = a.clone();
            a.span.start -= base as u32;
            a.span.end -= base as u32;
            a
        })
        .collect();
    let (x, y) = (num(&local, "sfc.x") + 40.0, num(&local, "sfc.y") + 40.0);
    // The later pragma first, so the earlier one's span stays valid.
    let moved = set_attr(pt, &local, "sfc.y", &sfc_plcopen_fmt(y));
    let moved = set_attr(&moved, &local, "sfc.x", &sfc_plcopen_fmt(x));
    let (out, how) = sfc_plcopen::patch_pou(xml, &p.name.text, &check(&moved)).map_err(|e| format!("{e:?}"))?;
    if how != Patched::InPlace {
        return Err(format!("{name}: {}: {what} moved: written {how:?}", p.name.text));
    }
    let lines = changed_lines(xml, &out);
    let expected = position_line(xml, imported, at);
    if lines != [expected] {
        return Err(format!("{name}: {}: {what} moved: lines {lines:?} changed, not just {expected}", p.name.text));
    }
    let line = out.lines().nth(expected - 1).unwrap();
    let want = [format!("x=\"{}\"", sfc_plcopen_fmt(x)), format!("y=\"{}\"", sfc_plcopen_fmt(y))];
    if !want.iter().all(|w| line.contains(w.as_str())) {
        return Err(format!("{name}: {what}: line {expected} is `{line}`"));
    }
    Ok(())
}

fn sfc_plcopen_fmt(v: f64) -> String {
    if v.fract() == 0.0 {
        format!("{}", v as i64)
    } else {
        format!("{v}")
    }
}

/// Every SFC POU of a file: unchanged, then one step moved, then one transition moved.
/// Returns the number of POUs tried, of elements moved, and the failures.
fn round_trips(path: &Path) -> (usize, usize, Vec<String>) {
    let name = path.display().to_string();
    let xml = std::fs::read_to_string(path).unwrap();
    let imported = sfc_plcopen::import(0, &name, &xml);
    let (unit, _) = sfc_syntax::parse(0, &imported.text);
    let mut failures = Vec::new();
    let mut tried = 0;
    let mut moved = 0;
    for p in pous(&unit).filter(|p| p.body.sfc().is_some()) {
        tried += 1;
        let pt = pou_text(&imported.text, p);
        match sfc_plcopen::patch_pou(&xml, &p.name.text, &check(pt)) {
            Ok((out, how)) if out == xml && how == Patched::Unchanged => {}
            Ok((_, how)) => failures.push(format!("{name}: {}: saved unchanged, written {how:?}", p.name.text)),
            Err(e) => failures.push(format!("{name}: {}: saved unchanged: {e:?}", p.name.text)),
        }
        let placed = |a: &[sfc_syntax::ast::Attribute]| a.iter().any(|a| a.name == "sfc.x");
        let elements = p.body.sfc().unwrap_or_default();
        let step = elements.iter().find(|e| matches!(e, SfcElement::Step(s) if placed(&s.attributes)));
        let transition = elements.iter().find(|e| matches!(e, SfcElement::Transition(t) if placed(&t.attributes)));
        for e in [step, transition].into_iter().flatten() {
            moved += 1;
            if let Err(f) = move_one(&name, &xml, &imported, p, pt, e) {
                failures.push(f);
            }
        }
    }
    (tried, moved, failures)
}

#[test]
fn beremiz_exports_of_the_shared_corpus_change_only_what_moved() {
    let Some(files) = shared_files() else { return };
    let (mut tried, mut moved) = (0, 0);
    let mut failures = Vec::new();
    for f in &files {
        let (n, m, mut fails) = round_trips(f);
        tried += n;
        moved += m;
        failures.append(&mut fails);
    }
    eprintln!("{} files, {tried} SFC POUs, {moved} elements moved", files.len());
    assert!(tried >= 3, "expected the SFC POUs of the corpus, found {tried}");
    assert_eq!(moved, 2 * tried, "a step and a transition of each POU");
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

#[test]
fn files_of_the_repository_corpus_change_only_what_moved() {
    let files = repo_files();
    let (mut tried, mut moved) = (0, 0);
    let mut failures = Vec::new();
    for f in &files {
        let (n, m, mut fails) = round_trips(f);
        tried += n;
        moved += m;
        failures.append(&mut fails);
    }
    eprintln!("{} files, {tried} SFC POUs, {moved} elements moved", files.len());
    assert!(tried >= 30 && moved >= 20, "{tried} POUs, {moved} moves");
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

#[test]
fn the_fixture_changes_only_what_moved() {
    let (tried, moved, failures) = round_trips(&fixture());
    assert_eq!((tried, moved), (1, 2));
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

/// The fixture's POU `Filler` as imported: the file, the import, and the POU's text.
fn filler() -> (String, String) {
    let xml = std::fs::read_to_string(fixture()).unwrap();
    let imported = sfc_plcopen::import(0, "beremiz_style.xml", &xml);
    let (unit, _) = sfc_syntax::parse(0, &imported.text);
    let p = pous(&unit).find(|p| p.name.text == "Filler").unwrap();
    let text = pou_text(&imported.text, p).to_string();
    (xml, text)
}

/// Saves `text` as POU `Filler` into `xml`.
fn save(xml: &str, text: &str) -> (String, Patched) {
    let checked = check(text);
    sfc_plcopen::patch_pou(xml, "Filler", &checked).unwrap()
}

/// The lines of `b` that differ from `a`'s.
fn diff(a: &str, b: &str) -> Vec<(String, String)> {
    changed_lines(a, b)
        .into_iter()
        .map(|n| (a.lines().nth(n - 1).unwrap().trim().to_string(), b.lines().nth(n - 1).unwrap().trim().to_string()))
        .collect()
}

#[test]
fn action_blocks_and_jumps_move_in_place() {
    let (xml, text) = filler();
    let moved = text.replace(
        "{attribute 'sfc.actionblock' := '170 100 160 40 2'}",
        "{attribute 'sfc.actionblock' := '210 140 160 40 2'}",
    );
    assert_ne!(moved, text);
    let (out, how) = save(&xml, &moved);
    assert_eq!(how, Patched::InPlace);
    assert_eq!(
        diff(&xml, &out),
        [("<position x=\"170\" y=\"100\"/>".into(), "<position x=\"210\" y=\"140\"/>".into())]
    );
    // The one jump both transitions lead to: one place.
    let moved = text.replace("'Init 90 330'", "'Init 130 370'");
    assert_eq!(moved.matches("'Init 130 370'").count(), 2);
    let (out, how) = save(&xml, &moved);
    assert_eq!(how, Patched::InPlace);
    assert_eq!(diff(&xml, &out), [("<position x=\"90\" y=\"330\"/>".into(), "<position x=\"130\" y=\"370\"/>".into())]);
    // Laid side by side (the editor draws one jump per transition; issue 36): the file's one
    // jump keeps its place, and nothing else changes.
    let spread = text.replacen("'Init 90 330'", "'Init 130 330'", 1);
    assert_eq!(spread.matches("'Init 90 330'").count(), 1);
    let (out, _) = save(&xml, &spread);
    assert_eq!(out, xml);
    // Resized: the element's own `width` and `height`.
    let resized = text.replacen("{attribute 'sfc.w' := '80'}", "{attribute 'sfc.w' := '100'}", 1);
    let (out, how) = save(&xml, &resized);
    assert_eq!(how, Patched::InPlace);
    let d = diff(&xml, &out);
    assert_eq!(d.len(), 1, "{d:?}");
    assert!(
        d[0].0.contains("width=\"80\"") && d[0].1.contains("width=\"100\"") && d[0].1.contains("executionOrderId"),
        "{d:?}"
    );
}

#[test]
fn a_condition_edited_is_written_in_its_cdata() {
    let (xml, text) = filler();
    let edited = text.replace(":= Start AND NOT Full;", ":= Start AND NOT Full AND Level < 90;");
    assert_ne!(edited, text);
    let (out, how) = save(&xml, &edited);
    assert_eq!(how, Patched::InPlace);
    assert_eq!(
        diff(&xml, &out),
        [(
            "<xhtml:p><![CDATA[Start AND NOT Full]]></xhtml:p>".into(),
            "<xhtml:p><![CDATA[Start AND NOT Full AND Level < 90]]></xhtml:p>".into()
        )]
    );
}

#[test]
fn a_renamed_step_is_renamed_in_place() {
    let (xml, text) = filler();
    let renamed = text
        .replace("INITIAL_STEP Init:", "INITIAL_STEP Idle:")
        .replace("FROM Init ", "FROM Idle ")
        .replace("TO Init", "TO Idle");
    let renamed = renamed.replace("'Init 90 330'", "'Idle 90 330'");
    let (out, how) = save(&xml, &renamed);
    assert_eq!(how, Patched::InPlace, "{out}");
    let d = diff(&xml, &out);
    assert_eq!(d.len(), 2, "{d:?}");
    assert!(d[0].1.contains("name=\"Idle\"") && d[0].1.contains("localId=\"1\""), "{d:?}");
    assert!(d[1].1.contains("targetName=\"Idle\""), "{d:?}");
}

#[test]
fn other_changes_replace_the_pou() {
    let (xml, text) = filler();
    let added = text.replace("END_PROGRAM", "    STEP Extra: END_STEP\n\nEND_PROGRAM");
    let (out, how) = save(&xml, &added);
    assert_eq!(how, Patched::Replaced);
    assert!(out.contains("name=\"Extra\""));
    // The other POU and the headers are kept as they were.
    let other = xml.find("<pou name=\"Helper\"").unwrap();
    let end = xml[other..].find("</pou>").unwrap() + other;
    assert!(out.contains(&xml[other..end]));
}

#[test]
fn vendor_attributes_and_data_stay_when_moving() {
    let (xml, text) = filler();
    let (out, _) = save(&xml, &text.replacen("{attribute 'sfc.x' := '40'}", "{attribute 'sfc.x' := '80'}", 1));
    for kept in ["executionOrderId=\"3\"", "<addData>", "beremiz:tool", "localId=\"12\""] {
        assert_eq!(out.matches(kept).count(), xml.matches(kept).count(), "{kept}");
    }
}

#[test]
fn a_size_the_file_does_not_hold_is_not_added() {
    let (xml, _) = filler();
    // The initial step without `width` and `height` (PLCopen makes them optional).
    let xml = xml.replace(
        "<step localId=\"1\" name=\"Init\" initialStep=\"true\" height=\"30\" width=\"80\" executionOrderId=\"1\">",
        "<step localId=\"1\" name=\"Init\" initialStep=\"true\" executionOrderId=\"1\">",
    );
    let imported = sfc_plcopen::import(0, "sizeless.xml", &xml);
    let (unit, _) = sfc_syntax::parse(0, &imported.text);
    let text = pou_text(&imported.text, pous(&unit).find(|p| p.name.text == "Filler").unwrap()).to_string();
    assert!(!text.contains("'sfc.w' := '80'}\n    {attribute 'sfc.h' := '30'}\n    INITIAL_STEP"));
    // The editor gives every block a size; moved, only the place is written.
    let sized = text.replacen(
        "{attribute 'sfc.x' := '40'}\n    {attribute 'sfc.y' := '20'}",
        "{attribute 'sfc.x' := '60'}\n    {attribute 'sfc.y' := '20'}\n    {attribute 'sfc.w' := '100'}\n    {attribute 'sfc.h' := '36'}",
        1,
    );
    assert_ne!(sized, text);
    let (out, how) = save(&xml, &sized);
    assert_eq!(how, Patched::InPlace);
    assert_eq!(diff(&xml, &out), [("<position x=\"40\" y=\"20\"/>".into(), "<position x=\"60\" y=\"20\"/>".into())]);
    // Not moved: nothing is written.
    let same = text.replacen(
        "{attribute 'sfc.x' := '40'}\n    {attribute 'sfc.y' := '20'}",
        "{attribute 'sfc.x' := '40'}\n    {attribute 'sfc.y' := '20'}\n    {attribute 'sfc.w' := '100'}\n    {attribute 'sfc.h' := '36'}",
        1,
    );
    assert_eq!(save(&xml, &same), (xml.clone(), Patched::Unchanged));
}

#[test]
fn a_condition_that_does_not_parse_is_not_written() {
    let (xml, text) = filler();
    // (A type error is written, as the export writes it.)
    let edited = text.replace(":= Start AND NOT Full;", ":= Start AND NOT ;");
    let checked = check(&edited);
    match sfc_plcopen::patch_pou(&xml, "Filler", &checked) {
        Err(sfc_plcopen::SpliceError::Diagnostics(errors)) => {
            assert!(errors.iter().any(|d| d.code == "SFC0101"), "{errors:?}")
        }
        other => panic!("{:?}", other.map(|o| o.1)),
    }
}
