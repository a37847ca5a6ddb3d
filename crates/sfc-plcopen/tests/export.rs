//! Every example (`examples/*/*.st`) and every valid fixture (`tests/fixtures/valid/**/*.st`)
//! exports to XML that `xmllint` validates against the PLCopen v2.01 schema, imports back to the
//! same model (with layout attributes added), and exports again to the same XML.

mod common;
use common::*;
use std::path::{Path, PathBuf};

fn st_files(dir: &Path, out: &mut Vec<PathBuf>) {
    let Ok(rd) = std::fs::read_dir(dir) else { return };
    for e in rd.flatten() {
        let p = e.path();
        if p.is_dir() {
            st_files(&p, out);
        } else if p.extension().is_some_and(|x| x == "st") {
            out.push(p);
        }
    }
}

fn one(path: &Path) -> Result<(), String> {
    let name = path.strip_prefix(root()).unwrap_or(path).display().to_string();
    let text = std::fs::read_to_string(path).map_err(|e| e.to_string())?;
    let checked = check_text(&name, &text);
    let xml = sfc_plcopen::export(&checked).map_err(|e| format!("{name}: export failed: {e:?}"))?;
    if let Some(r) = xmllint(&xml) {
        r.map_err(|e| format!("{name}: the export does not validate:\n{e}"))?;
    }
    // Every method, property and interface of the text is in the XML (counted apart from the
    // exporter: lines of the text that begin with the keyword, elements of the XML).
    for (kw, element) in [("METHOD", "<Method "), ("PROPERTY", "<Property "), ("INTERFACE", "<Interface ")] {
        let in_text = text
            .lines()
            .filter(|l| l.trim_start().split_whitespace().next().is_some_and(|w| w.eq_ignore_ascii_case(kw)))
            .count();
        let in_xml = xml.matches(element).count();
        if in_text != in_xml {
            return Err(format!("{name}: {in_text} {kw} in the text, {in_xml} `{element}` in the export"));
        }
    }
    let (_, again, diags) = sfc_plcopen::check_xml(0, &name, &xml, &opts());
    // The import adds nothing the text did not have.
    let before: Vec<(&str, u32)> = checked.diagnostics.iter().map(|d| (d.code, 0)).collect();
    let after: Vec<(&str, u32)> = diags.iter().map(|d| (d.code, 0)).collect();
    if before != after {
        return Err(format!("{name}: diagnostics change through XML: {before:?} → {after:?}\n{diags:#?}"));
    }
    same_model(&checked, &again, true).map_err(|e| format!("{name}: text → XML → text: {e}"))?;
    let xml2 = sfc_plcopen::export(&again).map_err(|e| format!("{name}: second export failed: {e:?}"))?;
    if xml != xml2 {
        return Err(format!("{name}: exporting the imported chart gives other XML"));
    }
    Ok(())
}

#[test]
fn examples_and_valid_fixtures_export_validate_and_round_trip() {
    let mut files = Vec::new();
    st_files(&root().join("examples"), &mut files);
    st_files(&root().join("tests/fixtures/valid"), &mut files);
    files.sort();
    assert!(files.len() > 20, "expected the examples and fixtures, found {}", files.len());
    let failures: Vec<String> = files.iter().filter_map(|p| one(p).err()).collect();
    assert!(failures.is_empty(), "{} of {} failed:\n{}", failures.len(), files.len(), failures.join("\n\n"));
}

/// Without stored coordinates the export lays the chart out: no two steps overlap, and every
/// loop back is drawn as a jump to its target.
#[test]
fn structured_layout_places_every_step_apart() {
    let text = std::fs::read_to_string(root().join("examples/traffic/traffic.st")).expect("example");
    let checked = check_text("traffic.st", &text);
    let xml = sfc_plcopen::export(&checked).expect("exports");
    let (_, again, _) = sfc_plcopen::check_xml(0, "t.xml", &xml, &opts());
    let chart = &again.charts[0];
    let boxes: Vec<(f64, f64, f64, f64)> = chart
        .steps
        .iter()
        .map(|s| {
            let n = |k: &str| sfc_plcopen::attrs::get_num(&s.attributes, k).expect("layout attribute");
            (n("sfc.x"), n("sfc.y"), n("sfc.w"), n("sfc.h"))
        })
        .collect();
    for (i, a) in boxes.iter().enumerate() {
        for b in &boxes[i + 1..] {
            let apart = a.0 + a.2 <= b.0 || b.0 + b.2 <= a.0 || a.1 + a.3 <= b.1 || b.1 + b.3 <= a.1;
            assert!(apart, "steps overlap: {a:?} {b:?}");
        }
    }
    let jumps: Vec<&str> =
        chart.transitions.iter().filter_map(|t| sfc_plcopen::attrs::get(&t.attributes, "sfc.jump")).collect();
    assert_eq!(jumps.len(), 1, "{jumps:?}");
    assert!(jumps[0].starts_with("CarsGreen "), "{jumps:?}");
}
