//! S7-GRAPH's interlock and supervision, kept on a step as `sfc.s7graph.interlock` and
//! `sfc.s7graph.supervision` attributes (the SimaticML import writes them): parsed and
//! type-checked as BOOL conditions where they stand in the text, and in the chart's model.

use sfc_model::{check_source, CheckOptions};

fn chart(interlock: &str, supervision: &str, dialect: &str) -> String {
    format!(
        "{dialect}FUNCTION_BLOCK Drill\nVAR_INPUT Clamped, Down : BOOL; Limit : TIME; END_VAR\n\
         INITIAL_STEP Idle : END_STEP\n\
         {{attribute 'sfc.s7graph.interlock' := '{interlock}'}}\n\
         {{attribute 'sfc.s7graph.supervision' := '{supervision}'}}\n\
         STEP Drilling : END_STEP\n\
         TRANSITION FROM Idle TO Drilling := Clamped; END_TRANSITION\n\
         TRANSITION FROM Drilling TO Idle := Down; END_TRANSITION\n\
         END_FUNCTION_BLOCK\n"
    )
}

const GRAPH: &str = "{attribute 'sfc.dialect' := 'graph'}\n";

#[test]
fn conditions_are_in_the_model() {
    let text = chart("Clamped AND NOT Down", "Drilling.U > Limit", GRAPH);
    let c = check_source(0, "drill.st", &text, &CheckOptions::default());
    assert!(!c.has_errors(), "{:#?}", c.diagnostics);
    assert!(c.diagnostics.iter().all(|d| d.code != "SFC0602"), "vendor attributes are known: {:#?}", c.diagnostics);
    let step = &c.charts[0].steps[1];
    assert_eq!(step.name, "Drilling");
    let il = step.interlock.as_ref().expect("interlock");
    assert_eq!(&text[il.span.start as usize..il.span.end as usize], "Clamped AND NOT Down");
    let sv = step.supervision.as_ref().expect("supervision");
    assert_eq!(&text[sv.span.start as usize..sv.span.end as usize], "Drilling.U > Limit");
    assert!(c.charts[0].steps[0].interlock.is_none());
}

#[test]
fn a_wrong_condition_is_an_error_where_it_is_written() {
    let text = chart("Clamped AND", "FALSE", GRAPH);
    let c = check_source(0, "drill.st", &text, &CheckOptions::default());
    let syntax = c.diagnostics.iter().find(|d| d.code == "SFC0101").expect("syntax error");
    let line4 = text.lines().find(|l| l.contains("interlock")).unwrap();
    let line_start = text.find(line4).unwrap() as u32;
    assert_eq!(syntax.span.start - line_start, line4.find("'}").unwrap() as u32, "{syntax:?}");
    let text = chart("Clamped", "Drilling.T > 10", GRAPH);
    let c = check_source(0, "drill.st", &text, &CheckOptions::default());
    let typed = c.diagnostics.iter().find(|d| d.code == "SFC0302").expect("type error");
    assert_eq!(&text[typed.span.start as usize..typed.span.end as usize], "10");
}

#[test]
fn u_is_a_member_of_graph_steps_only() {
    let text = chart("Clamped", "Drilling.U > Limit", "");
    let c = check_source(0, "drill.st", &text, &CheckOptions::default());
    let d = c.diagnostics.iter().find(|d| d.code == "SFC0309").expect("no U outside S7-GRAPH");
    assert_eq!(&text[d.span.start as usize..d.span.end as usize], "U");
}

#[test]
fn an_escaped_value_is_read_unescaped() {
    let text = chart("Clamped AND Mode = $27A$27", "FALSE", GRAPH).replace("Limit : TIME;", "Limit : TIME; Mode : STRING;");
    let c = check_source(0, "drill.st", &text, &CheckOptions::default());
    assert!(!c.has_errors(), "{:#?}", c.diagnostics);
    assert!(c.charts[0].steps[1].interlock.is_some());
}
