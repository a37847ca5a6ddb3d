//! The way back: for every error-free L5X fixture, importing what the export writes of the
//! imported text gives the imported text again, character for character.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::indexing_slicing)] // test code: a panic is a failed test

use std::path::{Path, PathBuf};

fn fixtures() -> Vec<PathBuf> {
    let d = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures");
    let mut v: Vec<PathBuf> = std::fs::read_dir(d)
        .unwrap()
        .flatten()
        .map(|e| e.path())
        .filter(|p| p.extension().is_some_and(|x| x.eq_ignore_ascii_case("l5x")))
        .collect();
    v.sort();
    v
}

/// `import(x)` → check → export → import again.
fn round(xml: &str) -> Result<(String, String, String), String> {
    let first = sfc_l5x::import(0, xml);
    let checked = sfc_model::check_source(1, "imported", &first.text, &Default::default());
    if checked.has_errors() {
        return Err(format!("the imported text has errors: {:?}", checked.diagnostics));
    }
    let (l5x, _notes) = sfc_l5x::export::export(&checked, None).map_err(|e| format!("export failed: {e:?}"))?;
    let second = sfc_l5x::import(0, &l5x);
    if let Some(e) = second.diagnostics.iter().find(|d| d.is_error()) {
        return Err(format!("the exported file imports with an error: {} {}", e.code, e.message));
    }
    Ok((first.text, second.text, l5x))
}

#[test]
fn every_fixture_comes_back_as_the_same_text() {
    let mut failures = Vec::new();
    for p in fixtures() {
        let xml = std::fs::read_to_string(&p).unwrap();
        match round(&xml) {
            Ok((a, b, l5x)) if a != b => {
                let diff: Vec<String> = a
                    .lines()
                    .zip(b.lines())
                    .filter(|(x, y)| x != y)
                    .take(5)
                    .map(|(x, y)| format!("  - {x}\n  + {y}"))
                    .collect();
                let _ = l5x;
                failures.push(format!("{}: texts differ\n{}", p.display(), diff.join("\n")));
            }
            Ok(_) => {}
            Err(e) => failures.push(format!("{}: {e}", p.display())),
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n\n"));
}

/// A second export of the re-imported text is the same file: the export is stable.
#[test]
fn the_export_is_stable() {
    for p in fixtures() {
        let xml = std::fs::read_to_string(&p).unwrap();
        let (_, b, l5x) = round(&xml).unwrap();
        let checked = sfc_model::check_source(1, "again", &b, &Default::default());
        let (again, _) = sfc_l5x::export::export(&checked, None).unwrap();
        assert_eq!(l5x, again, "{}", p.display());
    }
}
