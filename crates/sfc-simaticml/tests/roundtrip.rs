//! Round trip of the SimaticML fixtures through the exporter: for every fixture the import
//! reads without errors, `import(export(import(x)))` is `import(x)`, text for text.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::indexing_slicing)] // test code: a panic is a failed test

mod common;
use common::fixtures;
#[allow(dead_code)]
fn _unused() -> std::path::PathBuf {
    common::fixture_dir()
}

fn roundtrip(name: &str, xml: &str) -> Result<(), String> {
    let first = sfc_simaticml::import(0, xml);
    if first.diagnostics.iter().any(|d| d.is_error()) {
        return Ok(()); // error fixtures have nothing to round-trip
    }
    let checked = sfc_model::check_source(0, "x.st", &first.text, &Default::default());
    if checked.has_errors() {
        let errs: Vec<String> =
            checked.diagnostics.iter().filter(|d| d.is_error()).map(|d| d.message.clone()).collect();
        return Err(format!("{name}: the imported text has errors: {errs:?}"));
    }
    let (out, _) = sfc_simaticml::export::export(&checked, None)
        .map_err(|e| format!("{name}: export failed: {:?}", e.iter().map(|d| d.message.clone()).collect::<Vec<_>>()))?;
    let second = sfc_simaticml::import(0, &out);
    if let Some(e) = second.diagnostics.iter().find(|d| d.is_error()) {
        return Err(format!("{name}: the exported XML imports with an error: {}\n{out}", e.message));
    }
    if second.text != first.text {
        let diff: Vec<String> = first
            .text
            .lines()
            .zip(second.text.lines())
            .enumerate()
            .filter(|(_, (a, b))| a != b)
            .take(8)
            .map(|(i, (a, b))| format!("line {}:\n  - {a}\n  + {b}", i + 1))
            .collect();
        return Err(format!("{name}: the round trip differs:\n{}", diff.join("\n")));
    }
    // And the export is a fixed point: the second XML is the first.
    let checked2 = sfc_model::check_source(0, "x.st", &second.text, &Default::default());
    let (out2, _) = sfc_simaticml::export::export(&checked2, None).map_err(|e| format!("{name}: {e:?}"))?;
    if out2 != out {
        return Err(format!("{name}: exporting the re-import gives another XML"));
    }
    Ok(())
}

#[test]
fn every_fixture_round_trips() {
    let mut failures = Vec::new();
    let mut n = 0;
    for path in fixtures() {
        n += 1;
        let name = path.file_name().unwrap().to_string_lossy().to_string();
        let xml = std::fs::read_to_string(&path).unwrap();
        if let Err(e) = roundtrip(&name, &xml) {
            failures.push(e);
        }
    }
    assert!(n >= 10, "the fixtures are found");
    assert!(failures.is_empty(), "{}", failures.join("\n\n"));
}
