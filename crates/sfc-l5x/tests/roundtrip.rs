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

fn check(text: &str) -> sfc_model::Checked {
    let c = sfc_model::check_source(1, "chart.st", text, &Default::default());
    assert!(!c.has_errors(), "{:?}", c.diagnostics);
    c
}

/// The transitions of the first chart as `name: from -> to` with step names, sorted.
fn topology(c: &sfc_model::Checked) -> Vec<String> {
    let ch = &c.charts[0];
    let names = |v: &[usize]| v.iter().map(|&s| ch.steps[s].name.clone()).collect::<Vec<_>>().join(",");
    let mut v: Vec<String> = ch
        .transitions
        .iter()
        .map(|t| format!("{}: {} -> {} ({:?})", t.name, names(&t.from), names(&t.to), t.priority))
        .collect();
    v.sort();
    v
}

#[test]
fn a_changed_chart_gets_fresh_ids_and_links() {
    let xml =
        std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/tank_fill.L5X")).unwrap();
    let text = sfc_l5x::import(0, &xml)
        .text
        .replace("TRANSITION Tran_003 FROM Draining TO Idle", "TRANSITION Tran_003 FROM Draining TO Filling");
    let checked = check(&text);
    let (l5x, _) = sfc_l5x::export::export(&checked, None).unwrap();
    let back = sfc_l5x::import(0, &l5x);
    assert!(!back.diagnostics.iter().any(|d| d.is_error()), "{:?}", back.diagnostics);
    let again = check(&back.text);
    assert_eq!(topology(&checked), topology(&again));
    // Studio's order: steps by name, each followed by its actions (Draining 0, its actions 1
    // and 2, Filling 3, …), then the transitions by name.
    assert!(l5x.contains("<Step ID=\"0\" X=\"200\" Y=\"820\" Operand=\"Draining\""), "{l5x}");
    assert!(l5x.contains("<Step ID=\"3\" X=\"200\" Y=\"340\" Operand=\"Filling\""), "{l5x}");
    assert!(l5x.contains("<Transition ID=\"9\" X=\"200\" Y=\"220\" Operand=\"Tran_000\""), "{l5x}");
    assert!(l5x.contains("BranchType=\"Selection\" BranchFlow=\"Converge\""), "{l5x}");
}

const IEC: &str = "PROGRAM Cell
    VAR
        Go, Left, Right, Done : BOOL;
        Count : INT := 0;
        Limit : TIME := T#2s;
    END_VAR
    INITIAL_STEP Idle: END_STEP
    TRANSITION TGo FROM Idle TO Pick := Go; END_TRANSITION
    STEP Pick: Pulse(P); END_STEP
    TRANSITION TLeft (PRIORITY := 1) FROM Pick TO (A1, B1) := Left; END_TRANSITION
    TRANSITION TRight (PRIORITY := 2) FROM Pick TO C1 := Right AND Pick.T >= T#1s500ms; END_TRANSITION
    STEP A1: Work(N); END_STEP
    STEP B1: END_STEP
    STEP C1: Slow(D, T#3s); END_STEP
    TRANSITION TJoin FROM (A1, B1) TO Idle := Done; END_TRANSITION
    TRANSITION TBack FROM C1 TO Idle := C1.T > Limit; END_TRANSITION
    ACTION Pulse: Count := Count + 1; END_ACTION
    ACTION Work:
        Count := Count + 10;
    END_ACTION
    ACTION Slow: Count := Count + 100; END_ACTION
END_PROGRAM
";

#[test]
fn an_iec_chart_is_written_with_branches_and_read_back_alike() {
    let checked = check(IEC);
    let (l5x, notes) = sfc_l5x::export::export(&checked, None).unwrap();
    let back = sfc_l5x::import(0, &l5x);
    assert!(!back.diagnostics.iter().any(|d| d.is_error()), "{:?}\n{l5x}", back.diagnostics);
    let again = check(&back.text);
    assert_eq!(topology(&checked), topology(&again), "{}", back.text);
    // TIME literals and variables in milliseconds, the step time a DINT.
    assert!(l5x.contains("Right AND Pick.T >= 1500"), "{l5x}");
    assert!(l5x.contains("C1.T > Limit"), "{l5x}");
    assert!(l5x.contains("<Tag Name=\"Limit\" TagType=\"Base\" DataType=\"DINT\""), "{l5x}");
    assert!(back.text.contains("Slow(D, T#3000ms);"), "{}", back.text);
    for (code, what) in [
        ("SFC0821", "`Pulse(P)` executes when Pick is activated and again"),
        ("SFC0821", "`Work` does not execute again when it stops"),
    ] {
        assert!(notes.iter().any(|d| d.code == code && d.message.contains(what)), "{what}: {notes:?}");
    }
    let p = notes.iter().find(|d| d.message.contains("Pulse(P)")).unwrap();
    assert_eq!(&IEC[p.span.start as usize..p.span.end as usize], "Pulse(P);");
}

#[test]
fn what_logix_cannot_hold_is_refused_where_it_is_written() {
    for (text, what, at) in [
        ("PROGRAM P\n    VAR_GLOBAL g : INT; END_VAR\n    INITIAL_STEP S: END_STEP\n    TRANSITION FROM S TO S := g > 0; END_TRANSITION\nEND_PROGRAM\n", "VAR_GLOBAL", "VAR_GLOBAL g : INT; END_VAR"),
        ("PROGRAM P\n    VAR b : BOOL; END_VAR\n    INITIAL_STEP S: b(S); END_STEP\n    TRANSITION FROM S TO S := TRUE; END_TRANSITION\nEND_PROGRAM\n", "b(S)", "b(S);"),
        ("PROGRAM P\n    VAR b : BOOL; END_VAR\n    INITIAL_STEP S: A(N); END_STEP\n    TRANSITION FROM S TO S := TRUE; END_TRANSITION\n    ACTION A:\n        LD TRUE\n        ST b\n    END_ACTION\nEND_PROGRAM\n", "not written in ST", "A"),
    ] {
        let checked = sfc_model::check_source(1, "chart.st", text, &Default::default());
        let errs = sfc_l5x::export::export(&checked, None).unwrap_err();
        let e = errs.iter().find(|d| d.message.contains(what)).unwrap_or_else(|| panic!("{what}: {errs:?}"));
        assert_eq!(e.code, "SFC0820");
        assert_eq!(&text[e.span.start as usize..e.span.end as usize], at, "{what}");
    }
}

#[test]
fn a_chart_with_an_element_removed_gets_fresh_links() {
    let xml =
        std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/tank_fill.L5X")).unwrap();
    let text = sfc_l5x::import(0, &xml).text;
    let start = text.find("    {attribute 'sfc.x' := '200'}\n    {attribute 'sfc.y' := '940'}").unwrap();
    let end = text[start..].find("END_TRANSITION\n").unwrap() + start + "END_TRANSITION\n".len();
    let text = format!("{}{}", &text[..start], &text[end..]);
    assert!(!text.contains("Tran_003"));
    let checked = check(&text);
    let (l5x, _) = sfc_l5x::export::export(&checked, None).unwrap();
    let back = sfc_l5x::import(0, &l5x);
    assert!(!back.diagnostics.iter().any(|d| d.is_error()), "{:?}\n{l5x}", back.diagnostics);
    assert_eq!(topology(&checked), topology(&check(&back.text)));
    assert!(!l5x.contains("ToID=\"12\""), "{l5x}");
}

#[test]
fn a_changed_chart_writes_its_text_box_after_the_elements() {
    let xml = std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/stops_textbox.L5X"))
        .unwrap();
    let first = sfc_l5x::import(0, &xml).text;
    // A copy of the chart without its stored links: fresh IDs.
    let text: String = first.lines().filter(|l| !l.contains("sfc.logix.links")).map(|l| format!("{l}\n")).collect();
    let checked = check(&text);
    let (l5x, _) = sfc_l5x::export::export(&checked, None).unwrap();
    let back = sfc_l5x::import(0, &l5x);
    assert!(!back.diagnostics.iter().any(|d| d.is_error()), "{:?}\n{l5x}", back.diagnostics);
    assert_eq!(topology(&checked), topology(&check(&back.text)));
    let ids: Vec<u64> =
        l5x.split(" ID=\"").skip(1).filter_map(|r| r.split('"').next().and_then(|n| n.parse().ok())).collect();
    let mut unique = ids.clone();
    unique.sort_unstable();
    unique.dedup();
    assert_eq!(unique.len(), ids.len(), "IDs used twice: {ids:?}\n{l5x}");
    assert!(l5x.contains("<TextBox"), "{l5x}");
}

#[test]
fn program_parameters_keep_their_direction() {
    // A block's inputs, outputs and in-outs are the program's parameters (`Usage`), and come
    // back as VAR_INPUT, VAR_OUTPUT and VAR_IN_OUT; an in-out is a reference without data.
    let text = "FUNCTION_BLOCK F\n    VAR_INPUT go : BOOL; END_VAR\n    VAR_OUTPUT busy : BOOL; END_VAR\n    VAR_IN_OUT motor : BOOL; END_VAR\n    VAR n : INT := 3; END_VAR\n    INITIAL_STEP S: END_STEP\n    STEP W: busy(N); END_STEP\n    TRANSITION FROM S TO W := go; END_TRANSITION\n    TRANSITION FROM W TO S := NOT motor; END_TRANSITION\nEND_FUNCTION_BLOCK\n";
    let checked = check(text);
    let (l5x, _) = sfc_l5x::export::export(&checked, None).unwrap();
    for (name, usage) in [("go", "Input"), ("busy", "Output"), ("motor", "InOut")] {
        assert!(l5x.contains(&format!("<Tag Name=\"{name}\" TagType=\"Base\" DataType=\"BOOL\"")), "{l5x}");
        let at = l5x.find(&format!("<Tag Name=\"{name}\"")).unwrap();
        let tag = &l5x[at..at + l5x[at..].find("</Tag>").unwrap()];
        assert!(tag.contains(&format!("Usage=\"{usage}\"")), "{tag}");
        assert!(usage != "InOut" || !tag.contains("<Data"), "{tag}");
    }
    let back = sfc_l5x::import(0, &l5x);
    assert!(!back.diagnostics.iter().any(|d| d.is_error()), "{:?}", back.diagnostics);
    for block in ["VAR_INPUT\n        go : BOOL;", "VAR_OUTPUT\n        busy : BOOL;", "VAR_IN_OUT\n        motor : BOOL;", "VAR\n        n : INT := 3;"] {
        assert!(back.text.contains(block), "{block}: {}", back.text);
    }
    // A `Public` parameter is a VAR that keeps its usage.
    let public = l5x.replace("<Tag Name=\"n\" TagType=\"Base\" DataType=\"INT\"", "<Tag Name=\"n\" TagType=\"Base\" DataType=\"INT\" Usage=\"Public\"");
    let back = sfc_l5x::import(0, &public);
    assert!(back.text.contains("{attribute 'sfc.logix.usage' := 'Public'}"), "{}", back.text);
    let (again, _) = sfc_l5x::export::export(&check(&back.text), None).unwrap();
    assert!(again.contains("Usage=\"Public\""), "{again}");
}

#[test]
fn step_count_and_overflow_come_and_go() {
    // SFC_STEP.Count is the `logix` dialect's step member; SFC_STEP.OV (the DINT timer rolled
    // over) is the step time past 2^31 - 1 ms. Both are written back as Logix spells them.
    let text = "{attribute 'sfc.dialect' := 'logix'}\nPROGRAM P\n    VAR_OUTPUT n : DINT; END_VAR\n    INITIAL_STEP S: Keep(N); END_STEP\n    TRANSITION FROM S TO W := S.Count > 2 OR (S.T > T#2147483647ms); END_TRANSITION\n    STEP W: END_STEP\n    TRANSITION FROM W TO S := TRUE; END_TRANSITION\n    ACTION Keep: n := W.Count; END_ACTION\nEND_PROGRAM\n";
    let checked = check(text);
    let (l5x, _) = sfc_l5x::export::export(&checked, None).unwrap();
    assert!(l5x.contains("S.Count > 2 OR S.OV"), "{l5x}");
    assert!(l5x.contains("n := W.Count;"), "{l5x}");
    let back = sfc_l5x::import(0, &l5x);
    assert!(!back.diagnostics.iter().any(|d| d.is_error()), "{:?}", back.diagnostics);
    assert!(back.text.contains("S.Count > 2 OR (S.T > T#2147483647ms)"), "{}", back.text);
    assert!(back.text.contains("n := W.Count;"), "{}", back.text);
    let again = check(&back.text);
    assert!(!again.has_errors(), "{:?}", again.diagnostics);
}
