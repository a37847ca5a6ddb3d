//! The XML fixtures under `tests/fixtures/`: each one's imported text and diagnostics are kept
//! beside it (`<name>.st`, `<name>.diags`, rewritten with `UPDATE_EXPECT=1`); a fixture that
//! imports without errors also passes the schema after export and round-trips. Targeted tests
//! pin down the namespaces, CODESYS-style files, FBD/LD conditions, macro steps, malformed XML
//! and the location of diagnostics.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::indexing_slicing)] // test code: a panic is a failed test

mod common;
use common::*;
use sfc_diagnostics::SourceFile;
use std::path::{Path, PathBuf};

fn fixture_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures")
}

fn read(name: &str) -> String {
    std::fs::read_to_string(fixture_dir().join(name)).expect("fixture exists")
}

fn one(path: &Path) -> Result<(), String> {
    let file_name = path.file_name().and_then(|n| n.to_str()).unwrap_or("").to_string();
    let name = format!("tests/fixtures/{file_name}");
    let xml = std::fs::read_to_string(path).map_err(|e| e.to_string())?;
    let imported = sfc_plcopen::import(0, &name, &xml);
    let (file, checked, diags) = sfc_plcopen::check_xml(0, &name, &xml, &opts());
    snapshot(&path.with_extension("st"), &imported.text)?;
    snapshot(&path.with_extension("diags"), &render(&diags, &file))?;
    if diags.iter().any(|d| d.is_error()) {
        return Ok(());
    }
    let (xml1, again, _) = reimport(&checked, &name);
    if let Some(r) = xmllint(&xml1) {
        r.map_err(|e| format!("{name}: the export does not validate:\n{e}"))?;
    }
    same_model(&checked, &again, true).map_err(|e| format!("{name}: import → export → import: {e}"))?;
    let (xml2, _, _) = reimport(&again, &name);
    if xml1 != xml2 {
        return Err(format!("{name}: export → import → export changes the XML\n--- first\n{xml1}\n--- second\n{xml2}"));
    }
    Ok(())
}

#[test]
fn every_fixture_imports_as_expected() {
    let mut paths: Vec<PathBuf> = std::fs::read_dir(fixture_dir())
        .expect("fixture dir")
        .flatten()
        .map(|e| e.path())
        .filter(|p| p.extension().is_some_and(|x| x == "xml"))
        .collect();
    paths.sort();
    assert!(paths.len() >= 9, "fixtures missing: {paths:?}");
    let failures: Vec<String> = paths.iter().filter_map(|p| one(p).err()).collect();
    assert!(failures.is_empty(), "{}", failures.join("\n\n"));
}

#[test]
fn malformed_xml_gives_one_located_error() {
    let xml = read("malformed.xml");
    let imported = sfc_plcopen::import(3, "malformed.xml", &xml);
    assert!(imported.text.is_empty());
    assert_eq!(imported.diagnostics.len(), 1, "{:?}", imported.diagnostics);
    let d = &imported.diagnostics[0];
    assert_eq!(d.code, "SFC0701");
    assert!(d.is_error());
    assert_eq!(d.span.file, 3);
    let lc = SourceFile::new("m", xml.as_str()).line_col(d.span.start);
    assert_eq!((lc.line, lc.column), (7, 5), "{d:?}");
    assert!(d.message.contains("expected 'pou' tag"), "{}", d.message);
}

#[test]
fn hostile_inputs_do_not_panic() {
    let inputs = [
        "",
        "<",
        "<project",
        "<project/>",
        "<?xml version=\"1.0\"?><project xmlns=\"http://www.plcopen.org/xml/tc6_0201\"><types><pous><pou><body><SFC><step/><transition><condition><connectionPointIn><connection refLocalId=\"x\"/></connectionPointIn></condition></transition></SFC></body></pou></pous></types></project>",
        "<project><types><pous><pou name=\"P\" pouType=\"program\"><body><SFC><transition localId=\"1\"><connectionPointIn><connection refLocalId=\"1\"/></connectionPointIn></transition><selectionDivergence localId=\"2\"><connectionPointIn><connection refLocalId=\"3\"/></connectionPointIn></selectionDivergence><selectionDivergence localId=\"3\"><connectionPointIn><connection refLocalId=\"2\"/></connectionPointIn></selectionDivergence></SFC></body></pou></pous></types></project>",
        "<project><types><pous><pou name=\"P\" pouType=\"program\"><body><FBD><block localId=\"1\" typeName=\"ADD\"><inputVariables><variable formalParameter=\"IN1\"><connectionPointIn><connection refLocalId=\"1\"/></connectionPointIn></variable></inputVariables><outputVariables><variable formalParameter=\"OUT\"/></outputVariables></block><outVariable localId=\"2\"><connectionPointIn><connection refLocalId=\"1\"/></connectionPointIn><expression>x</expression></outVariable></FBD></body></pou></pous></types></project>",
        "<project><types><pous><pou name=\"P\" pouType=\"program\"><body><SFC><macroStep localId=\"1\" name=\"M\"><body><SFC><macroStep localId=\"1\" name=\"M\"><body><SFC/></body></macroStep></SFC></body></macroStep></SFC></body></pou></pous></types></project>",
        "<project><types><pous><pou name=\"P\" pouType=\"program\"><body><ST><xhtml:p xmlns:xhtml=\"http://www.w3.org/1999/xhtml\">x := 1; (* unterminated</xhtml:p></ST></body></pou></pous></types></project>",
        "<project>&#xD800;</project>",
        "\u{feff}<project/>",
    ];
    let deep = format!(
        "<project><types><pous><pou name=\"P\" pouType=\"program\"><body><ST><xhtml:p xmlns:xhtml=\"x\">{}{}</xhtml:p></ST></body><addData><data name=\"v\" handleUnknown=\"preserve\">{}{}</data></addData></pou></pous></types></project>",
        "<xhtml:p>".repeat(5000),
        "</xhtml:p>".repeat(5000),
        "<a>".repeat(5000),
        "</a>".repeat(5000)
    );
    for x in inputs.iter().copied().chain([deep.as_str()]) {
        let (_, _, diags) = sfc_plcopen::check_xml(0, "h.xml", x, &opts());
        for d in &diags {
            assert!(d.span.start <= d.span.end && d.span.end as usize <= x.len(), "{x}: {d:?}");
        }
    }
}

#[test]
fn the_three_namespaces_import_alike() {
    let t201 = sfc_plcopen::import(0, "a", &read("v201_namespace.xml")).text;
    let t200 = sfc_plcopen::import(0, "b", &read("v200_namespace.xml")).text;
    assert_eq!(t201, t200);
    let (_, c10, d10) = sfc_plcopen::check_xml(0, "c", &read("v10_namespace.xml"), &opts());
    assert!(!d10.iter().any(|d| d.is_error()), "{d10:?}");
    let chart = &c10.charts[0];
    assert_eq!(chart.steps.iter().map(|s| s.name.as_str()).collect::<Vec<_>>(), ["Idle", "Filling"]);
    let filling = chart.step("Filling").expect("Filling");
    assert_eq!(chart.steps[filling].associations.len(), 2);
    let (_, c201, d201) = sfc_plcopen::check_xml(0, "a", &read("v201_namespace.xml"), &opts());
    assert!(!d201.iter().any(|d| d.is_error()), "{d201:?}");
    // Wire positions put TStart (left branch) first, although it comes second in the file.
    let idle = c201.charts[0].step("Idle").expect("Idle");
    let first = c201.charts[0].outgoing(idle)[0];
    assert_eq!(c201.charts[0].transitions[first].name, "TStart");
}

#[test]
fn codesys_files_keep_document_order_and_vendor_data() {
    let xml = read("codesys_zero_positions.xml");
    let (_, checked, diags) = sfc_plcopen::check_xml(0, "c.xml", &xml, &opts());
    assert!(!diags.iter().any(|d| d.is_error()), "{diags:?}");
    let chart = &checked.charts[0];
    let wait = chart.step("Wait").expect("Wait");
    let order: Vec<&str> =
        chart.outgoing(wait).iter().map(|&t| chart.steps[chart.transitions[t].to[0]].name.as_str()).collect();
    assert_eq!(order, ["Left", "Right"]);
    // Positions (0, 0) are no layout: nothing stored.
    assert!(chart.steps.iter().all(|s| !s.attributes.iter().any(|a| a.name == "sfc.x")));
    let out = sfc_plcopen::export(&checked).expect("exports");
    assert!(out.contains("<StepAddInfo xmlns=\"http://www.3s-software.com/plcopenxml/stepaddinfo\">"), "{out}");
    assert!(out.contains("<ObjectId>a1b2c3d4-0000-4000-8000-000000000001</ObjectId>"), "{out}");
}

#[test]
fn fbd_and_ld_conditions_become_expressions() {
    let (_, checked, diags) = sfc_plcopen::check_xml(0, "f.xml", &read("fbd_conditions.xml"), &opts());
    assert!(!diags.iter().any(|d| d.is_error()), "{diags:?}");
    let chart = &checked.charts[0];
    let text = |t: usize| match &chart.transitions[t].condition {
        sfc_syntax::ast::Condition::St(e) => norm(&checked.file.text[e.span.start as usize..e.span.end as usize]),
        _ => String::new(),
    };
    let conds: Vec<String> = (0..chart.transitions.len()).map(text).collect();
    assert_eq!(
        conds,
        ["( Level > 10 ) AND ( NOT Stop )", "Tmr . Q", "( Go OR Manual ) AND ( NOT Ready )", "R_TRIG1 . Q"]
    );
    // Explicit priorities and the timer called from COMPUTE_FUNCTION_BLOCKS in the initial step.
    assert_eq!(chart.transitions[1].priority, Some(2));
    let idle = chart.step("Idle").expect("Idle");
    assert_eq!(chart.steps[idle].associations[0].action, "COMPUTE_FUNCTION_BLOCKS");
    assert!(checked.file.text.contains("Tmr(IN := Mixing.X, PT := T#5s);"));
    assert!(checked.file.text.contains("R_TRIG1 : R_TRIG;"));
    assert!(checked.file.text.contains("IF SetIn THEN\n        Q := TRUE;\n    END_IF;"));
    assert!(checked.file.text.contains("Total := SEL(Edge.Q, Total, Total + 1);"));
}

#[test]
fn macro_steps_are_flattened() {
    let (_, checked, diags) = sfc_plcopen::check_xml(0, "m.xml", &read("macro_step.xml"), &opts());
    assert!(diags.iter().any(|d| d.code == "SFC0709"));
    assert!(!diags.iter().any(|d| d.is_error()), "{diags:?}");
    let chart = &checked.charts[0];
    let names: Vec<(&str, bool)> = chart.steps.iter().map(|s| (s.name.as_str(), s.initial)).collect();
    assert_eq!(names, [("Idle", true), ("Pressing", false), ("Returning", false)]);
    let links: Vec<(String, String)> = chart
        .transitions
        .iter()
        .map(|t| (chart.steps[t.from[0]].name.clone(), chart.steps[t.to[0]].name.clone()))
        .collect();
    let expect = [("Idle", "Pressing"), ("Pressing", "Returning"), ("Returning", "Idle")];
    assert_eq!(links, expect.map(|(a, b)| (a.to_string(), b.to_string())));
}

/// A type error inside a CDATA condition is reported at its exact characters in the XML, a
/// duplicate step at the step's name attribute.
#[test]
fn check_diagnostics_point_into_the_xml() {
    let xml = r#"<?xml version="1.0"?>
<project xmlns="http://www.plcopen.org/xml/tc6_0201" xmlns:xhtml="http://www.w3.org/1999/xhtml">
  <types><dataTypes/><pous>
    <pou name="P" pouType="program">
      <interface><inputVars><variable name="Go"><type><BOOL/></type></variable></inputVars></interface>
      <body><SFC>
        <step localId="1" name="A" initialStep="true"/>
        <transition localId="2"><connectionPointIn><connection refLocalId="1"/></connectionPointIn>
          <condition><inline name=""><ST><xhtml:p><![CDATA[Go AND Missing]]></xhtml:p></ST></inline></condition>
        </transition>
        <step localId="3" name="a"><connectionPointIn><connection refLocalId="2"/></connectionPointIn></step>
      </SFC></body>
    </pou>
  </pous></types>
</project>
"#;
    let (file, _, diags) = sfc_plcopen::check_xml(7, "p.xml", xml, &opts());
    let at = |code: &str| {
        let d = diags.iter().find(|d| d.code == code).unwrap_or_else(|| panic!("no {code} in {diags:?}"));
        assert_eq!(d.span.file, 7);
        let lc = file.line_col(d.span.start);
        (lc.line, lc.column, file.slice(d.span).to_string())
    };
    let undeclared = diags.iter().find(|d| d.message.contains("Missing")).expect("undeclared variable reported");
    let lc = file.line_col(undeclared.span.start);
    assert_eq!((lc.line, lc.column, file.slice(undeclared.span)), (9, 67, "Missing"));
    assert_eq!(at("SFC0206"), (11, 33, "a".to_string()));
}

/// The model comparison used by the round-trip tests does see differences.
#[test]
fn model_comparison_detects_changes() {
    let text = read_example();
    let a = check_text("a.st", &text);
    let changed = text.replacen(":= Go;", ":= NOT Go;", 1);
    assert_ne!(changed, text);
    let b = check_text("b.st", &changed);
    assert!(same_model(&a, &b, true).is_err());
    let renamed = text.replacen("{attribute 'sfc.tag' := '2'}", "{attribute 'sfc.tag' := '3'}", 1);
    assert!(same_model(&a, &check_text("c.st", &renamed), true).is_err());
    assert!(same_model(&a, &check_text("d.st", &text), false).is_ok());
}

fn read_example() -> String {
    std::fs::read_to_string(root().join("tests/fixtures/valid/attributes.st")).expect("valid fixture")
}
