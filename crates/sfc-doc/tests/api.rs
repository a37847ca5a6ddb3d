//! The rest of the public API: `blank`, `auto_layout`, `element_ids`, `splice`, diagnostics of
//! `open`, and the geometry rules the canvas relies on.

use sfc_doc::{auto_layout, blank, element_ids, open, splice, to_text, ChartTarget, EditorDoc, ElementKind};
use std::path::Path;

fn example(name: &str) -> String {
    std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples").join(name)).unwrap()
}

fn snapshot(name: &str) -> EditorDoc {
    let p = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/snapshots").join(name);
    open(0, name, &std::fs::read_to_string(p).unwrap()).charts.remove(0)
}

#[test]
fn blank_chart_has_one_initial_step_and_round_trips() {
    let d = blank("Press", ChartTarget::Atmt);
    assert_eq!(d.pou, "Press");
    assert_eq!(d.elements.len(), 1);
    let s = &d.elements[0];
    assert_eq!((s.kind, s.name.as_str(), s.initial, s.x, s.y), (Some(ElementKind::Step), "Init", true, 100.0, 40.0));
    let w = to_text(&d);
    assert!(w.problems.is_empty(), "{:?}", w.problems);
    assert!(w.text.starts_with("{attribute 'sfc.target' := 'atmt'}\n"), "{}", w.text);
    assert!(w.text.contains("PROGRAM Press\n    VAR\n    END_VAR\n\n"), "{}", w.text);
    let again = open(0, "p", &w.text);
    assert!(again.diagnostics.iter().all(|d| !d.is_error()), "{:?}", again.diagnostics);
    assert_eq!(again.charts, vec![d]);
}

#[test]
fn auto_layout_of_an_opened_chart_is_the_layout_open_made() {
    for name in ["blinker/blinker.st", "carwash/carwash.st", "spindle/spindle.st", "traffic/traffic.st"] {
        for d in open(0, name, &example(name)).charts {
            assert_eq!(auto_layout(&d), d, "{name}");
        }
    }
}

#[test]
fn auto_layout_keeps_everything_but_geometry() {
    let d = snapshot("branches.st");
    let mut moved = d.clone();
    for (k, e) in moved.elements.iter_mut().enumerate() {
        e.x = 1000.0 - 37.0 * k as f64;
        e.y = 13.0 * k as f64;
    }
    for c in &mut moved.connections {
        c.waypoints.clear();
    }
    let laid = auto_layout(&moved);
    assert_eq!(laid, d);
}

#[test]
fn element_ids_find_steps_transitions_and_action_blocks() {
    let d = open(0, "b", &example("blinker/blinker.st")).charts.remove(0);
    assert_eq!(element_ids(&d, "s2"), vec!["step:S2"]);
    assert_eq!(element_ids(&d, "T4"), vec!["transition:T4"]);
    let blocks = element_ids(&d, "SHOWON");
    assert_eq!(blocks.len(), 1);
    let block = d.elements.iter().find(|e| e.id == blocks[0]).unwrap();
    assert_eq!((block.kind, block.step.as_deref()), (Some(ElementKind::ActionBlock), Some("step:S2")));
    assert!(element_ids(&d, "Nothing").is_empty());
    // Unnamed transitions are named T<n> by their position, as in diagnostics.
    let b = snapshot("branches.st");
    assert_eq!(element_ids(&b, "T6"), vec!["transition#5"]);
}

#[test]
fn splice_replaces_one_pou_of_a_file() {
    let file = format!("(* two charts *)\n{}\n{}", example("blinker/blinker.st"), example("traffic/traffic.st"));
    let opened = open(0, "f", &file);
    assert_eq!(opened.charts.len(), 2);
    let mut d = opened.charts[0].clone();
    d.elements[0].x += 40.0;
    d.elements[0].description = "moved".into();
    let out = splice(&file, &d);
    let again = open(0, "f", &out);
    assert_eq!(again.charts.len(), 2);
    // The file had no layout: only what changed is written (the moved step's place, and the
    // blocks the layout would otherwise put elsewhere around it); every step and transition
    // opens where the document had it.
    let blocks = |d: &sfc_doc::EditorDoc| -> Vec<(String, f64, f64, String)> {
        d.elements
            .iter()
            .filter(|e| matches!(e.kind, Some(ElementKind::Step | ElementKind::Transition)))
            .map(|e| (e.id.clone(), e.x, e.y, e.description.clone()))
            .collect()
    };
    assert_eq!(blocks(&again.charts[0]), blocks(&d));
    assert_eq!(again.charts[1], opened.charts[1]);
    assert!(!out.contains("sfc.graph"), "{out}");
    // Everything after the first POU is kept byte for byte.
    let end = file.find("END_PROGRAM").unwrap();
    assert!(out.ends_with(&file[end + "END_PROGRAM".len()..]));
    assert!(out.starts_with("(* two charts *)\n"));
}

#[test]
fn files_with_errors_open_with_their_diagnostics() {
    let text = "PROGRAM P\n    INITIAL_STEP S: END_STEP\n    TRANSITION FROM S TO Missing\n        := TRUE;\n    END_TRANSITION\nEND_PROGRAM\n";
    let o = open(3, "p.st", text);
    assert!(o.diagnostics.iter().any(|d| d.code == "SFC0208"), "{:?}", o.diagnostics);
    assert_eq!(o.charts.len(), 1);
    assert_eq!(o.file.name, "p.st");
    let no_chart = open(0, "q.st", "PROGRAM Q\n    VAR x : INT; END_VAR\n    x := 1;\nEND_PROGRAM\n");
    assert!(no_chart.charts.is_empty());
}

#[test]
fn pins_sit_where_the_canvas_draws_them() {
    // Every connection of a laid-out chart whose ends are vertically aligned has no bends, and
    // every bent one starts and ends on its pins.
    let d = snapshot("branches.st");
    let by_id = |id: &str| d.elements.iter().find(|e| e.id == id).unwrap();
    for c in &d.connections {
        let (s, t) = (by_id(&c.source), by_id(&c.target));
        let outs = if matches!(s.kind, Some(ElementKind::SelectionDivergence | ElementKind::SimultaneousDivergence)) {
            s.pins.unwrap()
        } else {
            1
        };
        let ins = if matches!(t.kind, Some(ElementKind::SelectionConvergence | ElementKind::SimultaneousConvergence)) {
            t.pins.unwrap()
        } else {
            1
        };
        // The canvas: one pin in the middle; several from 10 after the left end to 10 before
        // the right end, equidistant, offsets on the grid of 10.
        let pin_x = |e: &sfc_doc::Element, n: u32, k: u32| {
            if n == 1 {
                e.x + e.w / 2.0
            } else {
                let off = 10.0 + (e.w - 20.0) * f64::from(k) / f64::from(n - 1);
                e.x + ((off / 10.0).round() * 10.0).clamp(10.0, e.w - 10.0)
            }
        };
        let from = (pin_x(s, outs, c.source_pin), s.y + s.h);
        let to = (pin_x(t, ins, c.target_pin), t.y);
        match (c.waypoints.first(), c.waypoints.last()) {
            (Some(a), Some(b)) => {
                assert_eq!((a.x, a.y), from, "{}", c.id);
                assert_eq!((b.x, b.y), to, "{}", c.id);
            }
            _ => assert!((from.0 - to.0).abs() < 0.5 && to.1 >= from.1, "{}: {from:?} {to:?}", c.id),
        }
    }
}

fn edited_lamp() -> EditorDoc {
    let p = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/edits/moved_and_labelled.json");
    sfc_doc::normalize_ids(&serde_json::from_str(&std::fs::read_to_string(p).unwrap()).unwrap())
}

#[test]
fn a_condition_edited_in_the_saved_text_is_taken_with_the_saved_layout() {
    let d = edited_lamp();
    let text = to_text(&d).text.replace(":= Switch;", ":= Switch AND NOT Light;");
    let o = open(0, "lamp.st", &text).charts.remove(0);
    let mut expected = d.clone();
    let t = expected.elements.iter_mut().find(|e| e.condition.as_deref() == Some("Switch")).unwrap();
    t.condition = Some("Switch AND NOT Light".into());
    assert_eq!(o, expected);
}

#[test]
fn a_step_added_in_the_saved_text_is_laid_out_and_stored_positions_stay() {
    let d = edited_lamp();
    let text = to_text(&d).text.replace(
        "END_PROGRAM",
        "    STEP Extra: END_STEP\n\n    TRANSITION FROM LampOn TO Extra\n        := Light;\n    END_TRANSITION\nEND_PROGRAM",
    );
    let o = open(0, "lamp.st", &text).charts.remove(0);
    let find = |doc: &EditorDoc, id: &str| doc.elements.iter().find(|e| e.id == id).cloned().unwrap();
    for id in ["step:Off", "step:LampOn", "transition#0", "transition:Back"] {
        let (a, b) = (find(&d, id), find(&o, id));
        assert_eq!((a.x, a.y, a.w, a.h, a.name, a.condition), (b.x, b.y, b.w, b.h, b.name, b.condition), "{id}");
    }
    assert!(o.elements.iter().any(|e| e.name == "Extra"));
    // The label, the jump and the action block come back from their PLCopen-style attributes.
    let label = o.elements.iter().find(|e| e.kind == Some(ElementKind::Text)).unwrap();
    assert_eq!(
        (label.x, label.y, label.text.as_deref()),
        (400.0, 20.0, Some("Press the switch\n'twice' }{ $ to leave"))
    );
    let jump = o.elements.iter().find(|e| e.kind == Some(ElementKind::Jump)).unwrap();
    assert_eq!((jump.x, jump.y, jump.target.as_deref()), (130.0, 280.0, Some("Off")));
    let block = o.elements.iter().find(|e| e.kind == Some(ElementKind::ActionBlock)).unwrap();
    assert_eq!((block.x, block.y, block.associations.len()), (230.0, 168.0, 2));
    // LampOn now diverges: a selection divergence joins it to both transitions.
    assert!(o.elements.iter().any(|e| e.kind == Some(ElementKind::SelectionDivergence)));
    assert!(sfc_doc::problems(&o).is_empty(), "{:?}", sfc_doc::problems(&o));
}

#[test]
fn plcopen_export_and_import_keep_the_document() {
    // Export writes `sfc.graph` into addData and the positions natively; import brings both
    // back. Only the declarations change (the exporter writes one variable per declaration),
    // and attributes of other tools are not carried.
    for f in [
        "snapshots/branches.st",
        "snapshots/actions.st",
        "snapshots/attributes.st",
        "snapshots/plcopen_positions.st",
        "edits/branches_edited.json",
    ] {
        let text = std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("tests").join(f)).unwrap();
        let d = if f.ends_with(".json") {
            sfc_doc::normalize_ids(&serde_json::from_str(&text).unwrap())
        } else {
            open(0, f, &text).charts.remove(0)
        };
        let checked = sfc_model::check_source(0, f, &to_text(&d).text, &Default::default());
        let xml = sfc_plcopen::export(&checked).unwrap_or_else(|e| panic!("{f}: {e:?}"));
        let imported = sfc_plcopen::import(0, f, &xml);
        // A transition the user has not connected yet is written as drawn, and reported again
        // on import (SFC0706).
        assert!(imported.diagnostics.iter().all(|d| d.code == "SFC0706"), "{f}: {:?}", imported.diagnostics);
        let mut back = open(0, f, &imported.text).charts.remove(0);
        back.declarations = d.declarations.clone();
        // PLCopen carries the `sfc.*` attributes only.
        let mut d = d;
        let sfc_only = |l: &mut Vec<sfc_doc::OtherAttribute>| l.retain(|a| a.name.starts_with("sfc."));
        sfc_only(&mut d.attributes);
        d.elements.iter_mut().for_each(|e| sfc_only(&mut e.attributes));
        assert_eq!(back, d, "{f}");
    }
}

#[test]
fn comments_between_elements_belong_to_the_element_after_them_or_the_line_they_end() {
    let text = "PROGRAM P\n    VAR go : BOOL; END_VAR\n    (* one *)\n    INITIAL_STEP S: END_STEP // ends S\n    // two\n    TRANSITION T FROM S TO S\n        := go;\n    END_TRANSITION (* ends T *)\n    (* last *)\nEND_PROGRAM\n";
    let d = open(0, "p", text).charts.remove(0);
    let of = |name: &str| d.elements.iter().find(|e| e.name == name).unwrap().comments.clone();
    assert_eq!(of("S"), ["(* one *)", "// ends S"]);
    assert_eq!(of("T"), ["// two", "(* ends T *)"]);
    assert_eq!(d.trailing_comments, ["(* last *)"]);
    let saved = to_text(&d).text;
    assert!(saved.contains("    (* one *)\n    // ends S\n    {attribute 'sfc.x'"), "{saved}");
    assert!(saved.contains("END_TRANSITION\n\n    (* last *)\nEND_PROGRAM\n"), "{saved}");
    assert_eq!(open(0, "p", &saved).charts, vec![d]);
}

#[test]
fn comments_the_text_cannot_hold_travel_in_the_layout() {
    let mut d = blank("P", ChartTarget::Blank);
    d.elements[0].comments = vec!["(* kept *)".into(), "(* unterminated".into(), "not a comment".into()];
    d.trailing_comments = vec!["// x\ny".into(), "(* end *)".into()];
    let saved = to_text(&d);
    assert!(saved.problems.is_empty(), "{:?}", saved.problems);
    assert!(
        saved.text.contains("    (* kept *)\n") && saved.text.contains("    (* end *)\nEND_PROGRAM"),
        "{}",
        saved.text
    );
    assert!(!saved.text.contains("\n    (* unterminated"), "{}", saved.text);
    assert_eq!(open(0, "p", &saved.text).charts, vec![d]);
}
