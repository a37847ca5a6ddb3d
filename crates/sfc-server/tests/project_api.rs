//! A file of many POUs as the project tree and the chart tabs' Error lists see it (issue 36):
//! `open` lists every POU with its actions and transitions, and names the POU each diagnostic
//! lies in, so the page lists a chart's diagnostics under its tab and those of other POUs (a
//! function in ST) under the file.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::indexing_slicing)] // test code: a panic is a failed test

mod common;

use common::*;
use serde_json::{json, Value};
use sfc_server::contract::OpenResult;
use std::path::Path;

const UNITS: [&str; 13] = [
    "Intake",
    "Mixer",
    "Heater",
    "Filler",
    "Capper",
    "Labeler",
    "Conveyor",
    "Washer",
    "Dryer",
    "Sorter",
    "Palletizer",
    "Wrapper",
    "Dispatch",
];

#[tokio::test]
async fn open_names_each_diagnostics_pou_and_lists_the_pous() {
    let d = scratch("project13");
    let file = d.join("plant13.plc.xml");
    let fixture = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../web/e2e/fixtures/plant13.plc.xml");
    std::fs::copy(fixture, &file).unwrap();
    let s = state(&[&d], None);
    let a = post(&s, "/api/open", &json!({ "path": path_str(&file) })).await;
    assert_eq!(a.status, 200, "{}", a.text);
    // The answer fits the contract (which refuses unknown fields).
    let opened: OpenResult = serde_json::from_value(a.body.clone()).unwrap();
    let charts: Vec<&str> = opened.charts.iter().map(|c| c.pou.as_str()).collect();
    assert_eq!(charts, UNITS);

    let pous = a.body["pous"].as_array().unwrap();
    let names: Vec<&str> = pous.iter().map(|p| p["name"].as_str().unwrap()).collect();
    assert_eq!(names, [&UNITS[..], &["Scale", "Debounce"]].concat());
    assert_eq!(pous[0]["kind"], "program");
    assert_eq!(pous[0]["language"], "SFC");
    assert_eq!(pous[0]["chart"], true);
    assert_eq!(pous[0]["actions"], json!([{ "name": "ResetIntake", "sfc": false }]));
    assert_eq!(pous[0]["transitions"], json!(["T1", "T2", "T3"]));
    assert_eq!(
        pous[13],
        json!({ "name": "Scale", "kind": "function", "language": "ST", "chart": false, "actions": [], "transitions": [] })
    );
    assert_eq!(pous[14]["kind"], "functionBlock");

    let diags = a.body["diagnostics"].as_array().unwrap();
    let errors =
        |pou: &str| -> Vec<&Value> { diags.iter().filter(|d| d["severity"] == "error" && d["pou"] == pou).collect() };
    for (k, unit) in UNITS.iter().enumerate() {
        let mine = errors(unit);
        // Every chart: its undeclared `Level<unit>` after Run; every other one also `Missing<unit>`.
        assert_eq!(mine.len(), if k % 2 == 1 { 2 } else { 1 }, "{unit}: {mine:?}");
        let chart = opened.charts.iter().find(|c| c.pou == *unit).unwrap();
        for d in mine {
            assert!(d["message"].as_str().unwrap().contains(unit), "{unit}: {d}");
            // Its blocks are blocks of its own chart.
            let ids = d["elementIds"].as_array().unwrap();
            assert_eq!(ids.len(), 1, "{d}");
            assert!(chart.elements.iter().any(|e| e.id == ids[0].as_str().unwrap()), "{unit}: {d}");
        }
    }
    // The function's error is the function's: no chart claims it.
    let scale = errors("Scale");
    assert_eq!(scale.len(), 1, "{scale:?}");
    assert!(scale[0]["message"].as_str().unwrap().contains("Gain"));
    assert_eq!(scale[0]["elementIds"], json!([]));
    // Every error and warning lies in a POU of this file; the note on the CONFIGURATION in none.
    for d in diags {
        match d["pou"].as_str() {
            Some(p) => assert!(names.contains(&p), "{d}"),
            None => assert_eq!(d["code"], "SFC0104", "{d}"),
        }
    }
}

#[tokio::test]
async fn a_type_outside_every_pou_is_no_charts() {
    let d = scratch("project_type");
    let file = d.join("two.st");
    std::fs::write(
        &file,
        "TYPE Mode : (Auto, Manual, Auto); END_TYPE\n\
         PROGRAM A\nVAR x : BOOL; END_VAR\nINITIAL_STEP S: END_STEP\nTRANSITION FROM S TO S := x; END_TRANSITION\nEND_PROGRAM\n",
    )
    .unwrap();
    let s = state(&[&d], None);
    let a = post(&s, "/api/open", &json!({ "path": path_str(&file) })).await;
    assert_eq!(a.status, 200, "{}", a.text);
    let diags = a.body["diagnostics"].as_array().unwrap();
    assert!(!diags.is_empty(), "the duplicate enumerator is reported");
    for d in diags {
        assert!(d.get("pou").is_none(), "a diagnostic of the TYPE names no POU: {d}");
    }
}
