//! The check-then-compile dispatch that `sfc build` and the editor share, on the fixtures
//! (`tests/fixtures`: charts with the tables expected beside them).

// A panic in a test or a developer tool is a failure report, not a crash on user input.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::indexing_slicing)]

use serde_json::json;
use sfc_driver::compile::{self, BuildTarget, CompileOptions};
use sfc_driver::FileKind;
use std::path::{Path, PathBuf};

fn fixtures() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures")
}

/// The fixtures `NAME.st` / `NAME.xml` with the table expected beside them (`NAME.atmt`,
/// `NAME.eatmt`), through the dispatch `sfc build` and the editor share.
#[test]
fn compile_fixtures_to_tables() {
    let mut seen = 0;
    for entry in std::fs::read_dir(fixtures()).unwrap() {
        let path = entry.unwrap().path();
        let Some(ext) = path.extension().and_then(|e| e.to_str()) else { continue };
        if ext != "st" && ext != "xml" {
            continue;
        }
        let text = std::fs::read_to_string(&path).unwrap();
        for target in [BuildTarget::Atmt, BuildTarget::Eatmt] {
            let stem = path.file_stem().unwrap().to_str().unwrap();
            let Ok(expected) = std::fs::read_to_string(fixtures().join(format!("{stem}.{}", target.name()))) else {
                continue;
            };
            let (_, checked, diags) =
                compile::check_any(0, &path, &text, &compile::validation_options(target, None, None));
            assert!(diags.iter().all(|d| !d.is_error()), "{}: {diags:?}", path.display());
            let built = compile::compile(&checked, target, &CompileOptions::default()).expect("builds");
            assert_eq!(built.text, expected, "{} for {}", path.display(), target.name());
            let table = compile::parse_table(&built.text).expect("the table reads back");
            assert_eq!(table.rules.len(), built.text.split('[').next().unwrap().parse::<usize>().unwrap());
            seen += 1;
        }
    }
    assert!(seen >= 3, "the fixtures were found");
    let seed = compile::parse_table("3[0 0 1;1 1 2;2 2 1][8.1 2 1]").unwrap();
    assert_eq!(
        serde_json::to_value(&seed).unwrap(),
        json!({
            "rules": [{"state":0,"condition":0,"next":1},{"state":1,"condition":1,"next":2},{"state":2,"condition":2,"next":1}],
            "timeouts": [8.1, 2.0, 1.0]
        })
    );
    assert!(compile::parse_table("3[0 0 1][1]").is_none());
}

/// `text` of a PLCopen file is IEC text that builds the same table as the file itself; the
/// other targets produce their formats.
#[test]
fn compile_other_targets() {
    let xml_path = fixtures().join("seed.xml");
    let xml = std::fs::read_to_string(&xml_path).unwrap();
    let (_, checked, _) =
        compile::check_any(0, &xml_path, &xml, &compile::validation_options(BuildTarget::Text, None, None));
    let text = compile::compile(&checked, BuildTarget::Text, &CompileOptions::default()).unwrap().text;
    assert!(text.contains("PROGRAM Seed"), "{text}");
    let as_text = Path::new("seed.st");
    let (_, checked, _) =
        compile::check_any(0, as_text, &text, &compile::validation_options(BuildTarget::Atmt, None, None));
    let table = compile::compile(&checked, BuildTarget::Atmt, &CompileOptions::default()).unwrap().text;
    assert_eq!(table, std::fs::read_to_string(fixtures().join("seed.atmt")).unwrap());
    let st_path = fixtures().join("seed.st");
    let st = std::fs::read_to_string(&st_path).unwrap();
    let (_, checked, _) =
        compile::check_any(0, &st_path, &st, &compile::validation_options(BuildTarget::Svg, None, None));
    let svg = compile::compile(&checked, BuildTarget::Svg, &CompileOptions::default()).unwrap().text;
    assert!(svg.starts_with("<svg") || svg.starts_with("<?xml"), "{}", &svg[..80.min(svg.len())]);
    let plcopen = compile::compile(&checked, BuildTarget::Plcopen, &CompileOptions::default()).unwrap().text;
    assert!(plcopen.contains("<project"), "PLCopen project");
    match compile::compile(&checked, BuildTarget::St, &CompileOptions { pou: Some("Other"), ..Default::default() }) {
        Err(compile::CompileError::Chart(m)) => assert!(m.contains("`Other` is not an SFC POU"), "{m}"),
        other => panic!("expected a chart error, got {other:?}"),
    }
    // Simultaneous branches and conditions that are not inputs break the ATMT rules: located
    // diagnostics, no table.
    let unsafe_path = fixtures().join("unsafe.st");
    let text = std::fs::read_to_string(&unsafe_path).unwrap();
    let (_, checked, _) = compile::check_any(0, &unsafe_path, &text, &Default::default());
    match compile::compile(&checked, BuildTarget::Atmt, &CompileOptions::default()) {
        Err(compile::CompileError::Diagnostics(ds)) => {
            assert!(ds.iter().all(|d| d.code.starts_with("SFC04")), "{ds:?}")
        }
        other => panic!("expected target errors, got {other:?}"),
    }
}

/// In-memory text (a language server's buffer) checks as its file does, by kind.
#[test]
fn check_text_in_memory() {
    let xml = std::fs::read_to_string(fixtures().join("seed.xml")).unwrap();
    let opts = compile::validation_options(BuildTarget::Atmt, None, None);
    let (file, checked, diags) = sfc_driver::check_text(0, "buffer", &xml, FileKind::PlcOpen, &opts);
    assert_eq!(file.name, "buffer");
    assert!(diags.iter().all(|d| !d.is_error()), "{diags:?}");
    let table = compile::compile(&checked, BuildTarget::Atmt, &CompileOptions::default()).unwrap().text;
    assert_eq!(table, std::fs::read_to_string(fixtures().join("seed.atmt")).unwrap());
    let (_, _, diags) = sfc_driver::check_text(
        0,
        "buffer",
        "PROGRAM P\n  INITIAL_STEP S1: END_STEP\n  x := 1;\nEND_PROGRAM\n",
        FileKind::Iec,
        &Default::default(),
    );
    assert!(diags.iter().any(|d| d.is_error()), "{diags:?}");
}

/// `fmt` on text: canonical layout, XML refused, syntax errors returned.
#[test]
fn format_text() {
    let messy = "PROGRAM P\nINITIAL_STEP S1:END_STEP\nEND_PROGRAM";
    let out = sfc_driver::format("a.st", messy).unwrap();
    assert_eq!(sfc_driver::format("a.st", &out).unwrap(), out, "idempotent");
    assert!(matches!(sfc_driver::format("plc.xml", "<project/>"), Err(sfc_driver::FormatError::Xml)));
    assert!(matches!(sfc_driver::format("-", "  <?xml version=\"1.0\"?>"), Err(sfc_driver::FormatError::Xml)));
    match sfc_driver::format("b.st", "PROGRAM P\n  x := ;\nEND_PROGRAM\n") {
        Err(sfc_driver::FormatError::Syntax { file, diagnostics }) => {
            assert_eq!(file.name, "b.st");
            assert!(!diagnostics.is_empty());
        }
        other => panic!("expected syntax errors, got {other:?}"),
    }
}
