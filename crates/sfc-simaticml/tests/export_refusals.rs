//! What S7-GRAPH cannot hold is a located SFC0830 and nothing is written; what it runs
//! differently a located SFC0831 warning.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::indexing_slicing)] // test code: a panic is a failed test

fn export(text: &str) -> Result<(String, Vec<sfc_diagnostics::Diagnostic>), Vec<sfc_diagnostics::Diagnostic>> {
    let checked = sfc_model::check_source(0, "x.st", text, &Default::default());
    assert!(!checked.has_errors(), "{:?}", checked.diagnostics);
    sfc_simaticml::export::export(&checked, None)
}

fn chart(step_body: &str, actions: &str, cond: &str) -> String {
    format!(
        "FUNCTION_BLOCK F\nVAR_INPUT Go : BOOL; n : INT; END_VAR\nVAR_OUTPUT x : BOOL; y : INT; END_VAR\n\
         INITIAL_STEP S0: END_STEP\nTRANSITION FROM S0 TO S1 := {cond}; END_TRANSITION\n\
         STEP S1:\n{step_body}\nEND_STEP\nTRANSITION FROM S1 TO S0 := NOT Go; END_TRANSITION\n{actions}\nEND_FUNCTION_BLOCK\n"
    )
}

/// The error's message contains `what` and it is located at `at` in the text.
fn refused(text: &str, what: &str, at: &str) {
    let errs = export(text).expect_err("refused");
    let e = errs.iter().find(|d| d.message.contains(what)).unwrap_or_else(|| panic!("{what}: {errs:?}"));
    assert_eq!(e.code, "SFC0830");
    let start = text.find(at).unwrap() as u32;
    assert!(e.span.start >= start && e.span.start <= start + at.len() as u32, "{what}: at {:?}", e.span);
}

#[test]
fn stored_qualifiers_on_bodies_are_refused() {
    let t = chart("    A(S);", "ACTION A: y := y + 1; END_ACTION", "Go");
    refused(&t, "S association of the action `A`", "A(S)");
}

#[test]
fn statements_other_than_assignments_are_refused() {
    let t = chart("    A(N);", "ACTION A: IF Go THEN y := 1; END_IF; END_ACTION", "Go");
    refused(&t, "other than assignments", "A(N)");
}

#[test]
fn arithmetic_in_a_condition_is_refused() {
    let t = chart("", "", "n + 1 > 3");
    refused(&t, "`n + 1` is no operand a LAD network can read", "TRANSITION FROM S0");
}

#[test]
fn an_il_condition_or_a_step_action_is_refused() {
    let t = "FUNCTION_BLOCK F\nVAR_INPUT Go : BOOL; END_VAR\nVAR y : INT; END_VAR\n\
             INITIAL_STEP S0: END_STEP\nTRANSITION FROM S0 TO S1 := Go; END_TRANSITION\n\
             STEP S1: ENTRY_ACTION := A; END_STEP\nTRANSITION FROM S1 TO S0 := NOT Go; END_TRANSITION\n\
             ACTION A: y := 1; END_ACTION\nEND_FUNCTION_BLOCK\n";
    let checked = sfc_model::check_source(0, "x.st", t, &Default::default());
    if checked.has_errors() {
        return; // the syntax of step actions is a dialect's; nothing to test here then
    }
    let errs = sfc_simaticml::export::export(&checked, None).expect_err("refused");
    assert!(errs.iter().any(|d| d.message.contains("step actions")), "{errs:?}");
}

#[test]
fn n_bodies_and_mixed_set_and_hold_are_warned() {
    let t = chart("    A(N);\n    x(S);", "ACTION A: y := y + 1; END_ACTION", "Go");
    let t = t
        .replace("STEP S1:", "STEP S2:\n    x(N);\nEND_STEP\nTRANSITION FROM S2 TO S0 := Go; END_TRANSITION\nSTEP S1:");
    let (xml, notes) = export(&t).expect("written");
    assert!(xml.contains("<Token Text=\"#y\" />"), "{xml}");
    let w: Vec<&str> = notes.iter().filter(|d| d.code == "SFC0831").map(|d| d.message.as_str()).collect();
    assert!(w.iter().any(|m| m.contains("once more")), "{w:?}");
    assert!(w.iter().any(|m| m.contains("held by N in one step and set by S")), "{w:?}");
}

#[test]
fn the_output_reimports_without_errors() {
    let t = chart("    x(N);\n    A(P1);", "ACTION A: y := n; END_ACTION", "Go AND (n >= 3 OR NOT x)");
    let (xml, _) = export(&t).expect("written");
    let back = sfc_simaticml::import(0, &xml);
    assert!(!back.diagnostics.iter().any(|d| d.is_error()), "{:?}", back.diagnostics);
    assert!(back.text.contains(":= Go AND ((n >= 3) OR (NOT x));"), "{}", back.text);
    assert!(back.text.contains("x(N);"), "{}", back.text);
    assert!(back.text.contains("(P1);"), "{}", back.text);
}

/// Every chart file of the repository's examples and simulator tests: the export never panics;
/// what it writes imports without errors, and each refusal is a located SFC0830.
#[test]
fn every_chart_of_the_repository_exports_or_is_refused() {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let mut files = Vec::new();
    let mut stack = vec![root.join("examples"), root.join("crates/sfc-sim/tests")];
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d).unwrap().flatten() {
            let p = e.path();
            if p.is_dir() {
                stack.push(p);
            } else if p.extension().is_some_and(|x| x == "st") {
                files.push(p);
            }
        }
    }
    files.sort();
    let (mut written, mut refused) = (0, 0);
    for f in &files {
        let text = std::fs::read_to_string(f).unwrap_or_default();
        let checked = sfc_model::check_source(0, "x.st", &text, &Default::default());
        if checked.has_errors() {
            continue;
        }
        for c in &checked.charts {
            match sfc_simaticml::export::export(&checked, Some(&c.pou)) {
                Ok((xml, _)) => {
                    written += 1;
                    let back = sfc_simaticml::import(0, &xml);
                    let errs: Vec<_> = back.diagnostics.iter().filter(|d| d.is_error()).collect();
                    assert!(errs.is_empty(), "{} {}: {errs:?}", f.display(), c.pou);
                    let again = sfc_model::check_source(0, "y.st", &back.text, &Default::default());
                    assert!(!again.has_errors(), "{} {}: {:?}\n{}", f.display(), c.pou, again.diagnostics, back.text);
                }
                Err(errs) => {
                    refused += 1;
                    assert!(!errs.is_empty() && errs.iter().all(|d| d.code == "SFC0830" && d.is_error()), "{errs:?}");
                    assert!(errs.iter().all(|d| (d.span.end as usize) <= text.len()), "{}", f.display());
                }
            }
        }
    }
    assert!(written >= 15 && refused >= 10, "written {written}, refused {refused}");
}

/// An imported chart edited so that its kept action rows no longer match its associations is
/// refused rather than written with stale rows.
#[test]
fn stale_kept_rows_are_refused() {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures");
    let xml = std::fs::read_to_string(dir.join("sequence_end_v1.xml")).unwrap();
    let text = sfc_simaticml::import(0, &xml).text;
    let edited = text.replace("        Valve(N);\n", "");
    assert_ne!(edited, text);
    refused(&edited, "kept GRAPH action rows", "STEP Filling");
}

/// Two charts in one file: two blocks in one document, numbered apart, read back both.
#[test]
fn two_charts_are_two_blocks() {
    let one = chart("    x(N);", "", "Go");
    let two = one.replace("FUNCTION_BLOCK F", "FUNCTION_BLOCK G");
    let (xml, _) = export(&format!("{one}\n{two}")).expect("written");
    assert_eq!(xml.matches("<SW.Blocks.FB ").count(), 2);
    assert!(xml.contains("<Number>1</Number>") && xml.contains("<Number>2</Number>"), "{xml}");
    let back = sfc_simaticml::import(0, &xml);
    assert!(back.text.contains("FUNCTION_BLOCK F") && back.text.contains("FUNCTION_BLOCK G"), "{}", back.text);
}
