//! Actions written in SFC (CODESYS's SFC actions) as charts of their own, a POU in ST that
//! holds them, and CODESYS's step actions: opened, edited and saved back.

use sfc_doc::{open, splice, to_text, EditorDoc, ElementKind};

const PRESS: &str = include_str!("../../../web/e2e/fixtures/press_actions.st");

fn errors(text: &str) -> Vec<String> {
    let checked = sfc_model::check_source(0, "t.st", text, &sfc_model::CheckOptions::default());
    checked.diagnostics.iter().filter(|d| d.is_error()).map(|d| format!("{} {}", d.code, d.message)).collect()
}

fn chart<'a>(doc: &'a EditorDoc, action: &str) -> &'a EditorDoc {
    doc.actions.iter().find(|a| a.name == action).and_then(|a| a.chart.as_deref()).expect(action)
}

fn step<'a>(doc: &'a EditorDoc, name: &str) -> &'a sfc_doc::Element {
    doc.elements.iter().find(|e| e.kind == Some(ElementKind::Step) && e.name == name).expect(name)
}

#[test]
fn a_block_in_st_and_a_chart_open_with_their_action_charts() {
    assert!(errors(PRESS).is_empty(), "{:?}", errors(PRESS));
    let opened = open(0, "press.st", PRESS);
    let names: Vec<&str> = opened.charts.iter().map(|d| d.pou.as_str()).collect();
    assert_eq!(names, ["Press", "Line"]);
    let press = &opened.charts[0];
    assert_eq!(press.body.as_deref(), Some("(* The block runs one scan of its cycle each call. *)\nCycle();"));
    assert!(press.elements.is_empty());
    let names: Vec<&str> = press.actions.iter().map(|a| a.name.as_str()).collect();
    assert_eq!(names, ["Lower_entry", "Raise_exit", "Cycle"]);
    assert!(press.actions[0].chart.is_none());
    let cycle = chart(press, "Cycle");
    assert_eq!(cycle.pou, "Press");
    assert!(cycle.actions.is_empty() && cycle.declarations.is_empty());
    let steps: Vec<&str> =
        cycle.elements.iter().filter(|e| e.kind == Some(ElementKind::Step)).map(|e| e.name.as_str()).collect();
    assert_eq!(steps, ["Ready", "Lower", "Raise"]);
    assert_eq!(cycle.elements.iter().filter(|e| e.kind == Some(ElementKind::Transition)).count(), 3);
    assert_eq!(step(cycle, "Lower").step_actions, ["ENTRY_ACTION := Lower_entry"]);
    assert_eq!(step(cycle, "Raise").step_actions, ["EXIT_ACTION := Raise_exit"]);

    let line = &opened.charts[1];
    assert!(line.body.is_none());
    let feed = chart(line, "Feed");
    assert_eq!(step(feed, "Push").step_actions, ["STEP_ACTION := Count"]);
    assert!(line.elements.iter().all(|e| e.name != "Wait"), "the action's steps are its chart's");
}

#[test]
fn saved_unchanged_they_read_back_equal_and_the_file_checks() {
    let opened = open(0, "press.st", PRESS);
    let mut text = PRESS.to_string();
    for doc in &opened.charts {
        let w = to_text(doc);
        assert!(w.problems.is_empty(), "{}: {:?}", doc.pou, w.problems);
        text = splice(&text, doc);
    }
    assert!(errors(&text).is_empty(), "{:?}\n{text}", errors(&text));
    // The block in ST stays one: no chart attributes, its body and actions as written.
    let press = &text[..text.find("END_FUNCTION_BLOCK").unwrap()];
    assert!(!press.contains("sfc.target") && press.contains("    Cycle();\n"), "{press}");
    assert!(press.contains("ENTRY_ACTION := Lower_entry;"), "{press}");
    let again = open(0, "press.st", &text);
    assert_eq!(again.charts, opened.charts, "{text}");
    // Saving again changes nothing.
    let mut twice = text.clone();
    for doc in &again.charts {
        twice = splice(&twice, doc);
    }
    assert_eq!(twice, text);
}

#[test]
fn an_action_chart_edited_is_saved_into_its_action() {
    let opened = open(0, "press.st", PRESS);
    let mut press = opened.charts[0].clone();
    let k = press.actions.iter().position(|a| a.name == "Cycle").unwrap();
    let mut cycle = (*press.actions[k].chart.clone().unwrap()).clone();
    // A changed condition, an entry action set in Properties, a step moved.
    for e in &mut cycle.elements {
        if e.kind == Some(ElementKind::Transition) && e.condition.as_deref() == Some("AtTop") {
            e.condition = Some("AtTop AND NOT Start".into());
        }
        if e.name == "Raise" {
            e.step_actions = vec!["ENTRY_ACTION := Lower_entry".into(), "EXIT_ACTION := Raise_exit".into()];
            e.x += 40.0;
        }
    }
    press.actions[k].chart = Some(Box::new(cycle.clone()));
    let text = splice(PRESS, &press);
    assert!(errors(&text).is_empty(), "{:?}\n{text}", errors(&text));
    assert!(text.contains(":= AtTop AND NOT Start;"), "{text}");
    assert!(
        text.contains("STEP Raise:\n            ENTRY_ACTION := Lower_entry;\n            EXIT_ACTION := Raise_exit;"),
        "{text}"
    );
    // The other POU is kept byte for byte.
    let line = &PRESS[PRESS.find("PROGRAM Line").unwrap()..];
    assert!(text.ends_with(line));
    let again = open(0, "press.st", &text);
    let read = chart(&again.charts[0], "Cycle");
    assert_eq!(step(read, "Raise").step_actions, step(&cycle, "Raise").step_actions);
    assert_eq!(step(read, "Raise").x, step(&cycle, "Raise").x);
}

#[test]
fn a_condition_that_does_not_parse_is_a_problem_of_the_action() {
    let mut line = open(0, "press.st", PRESS).charts.remove(1);
    let k = line.actions.iter().position(|a| a.name == "Feed").unwrap();
    let mut feed = (*line.actions[k].chart.clone().unwrap()).clone();
    for e in &mut feed.elements {
        if e.kind == Some(ElementKind::Transition) {
            e.condition = Some("P1.AtTop AND".into());
            break;
        }
    }
    line.actions[k].chart = Some(Box::new(feed));
    let w = to_text(&line);
    assert!(
        w.problems.iter().any(|p| p.code == "SFC0101" && p.message.starts_with("action `Feed`")),
        "{:?}",
        w.problems
    );
}

#[test]
fn an_imported_twincat_action_chart_reopens_equal_in_its_pous_dialect() {
    // Its step names (`Init__Sorting`) are CODESYS's: the chart is read and written in the
    // dialect of its POU, whose attribute stays on the POU.
    let p = concat!(env!("CARGO_MANIFEST_DIR"), "/../../tests/corpus/real/twincat/sorting_station_program_access.xml");
    let xml = std::fs::read_to_string(p).unwrap();
    let imported = sfc_plcopen::import(0, "x", &xml);
    let d = open(0, "x", &imported.text).charts.remove(0);
    let seq = chart(&d, "ACT_Sequence");
    assert!(seq.elements.iter().any(|e| e.name == "Init__Sorting"));
    let w = to_text(&d);
    assert!(w.problems.is_empty(), "{:?}", w.problems);
    assert_eq!(w.text.matches("sfc.dialect").count(), 1, "{}", w.text);
    let again = open(0, "x", &w.text).charts.remove(0);
    assert_eq!(again, d);
}
