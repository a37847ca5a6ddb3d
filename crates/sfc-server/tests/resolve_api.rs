//! `POST /api/resolve`: a merge conflict of the chart on the canvas resolved by taking a side
//! (the editor's Merge conflicts panel). The file is `sfc_diff::merge::merge` of the tank
//! fixtures of `sfc merge` (crates/sfc-cli/tests/merge): TStart's condition changed both ways.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::indexing_slicing)] // test code: a panic is a failed test

mod common;

use common::*;
use serde_json::{json, Value};
use sfc_server::contract::{OpenResult, ResolveResult};
use std::path::{Path, PathBuf};

fn fixture(name: &str) -> String {
    let p = Path::new(env!("CARGO_MANIFEST_DIR")).join("../sfc-cli/tests/merge").join(name);
    std::fs::read_to_string(&p).unwrap_or_else(|e| panic!("{}: {e}", p.display()))
}

/// A scratch directory holding `tank.st`, the tank merged with a conflict on TStart.
fn merged_tank(name: &str) -> (PathBuf, PathBuf, String) {
    let merged =
        sfc_diff::merge::merge(&fixture("tank_base.st"), &fixture("tank_ours.st"), &fixture("tank_theirs_conflict.st"));
    assert_eq!(merged.conflicts.len(), 1, "{:#?}", merged.conflicts);
    let d = scratch(name);
    let file = d.join("tank.st");
    std::fs::write(&file, &merged.text).unwrap();
    (d, file, merged.text)
}

async fn open_doc(s: &sfc_server::AppState, path: &Path) -> (Value, OpenResult) {
    let a = post(s, "/api/open", &json!({ "path": path_str(path) })).await;
    assert_eq!(a.status, 200, "{}", a.text);
    let opened: OpenResult = serde_json::from_value(a.body).unwrap();
    (serde_json::to_value(&opened.charts[0]).unwrap(), opened)
}

async fn resolve(s: &sfc_server::AppState, body: Value) -> ResolveResult {
    let a = post(s, "/api/resolve", &body).await;
    assert_eq!(a.status, 200, "{}", a.text);
    serde_json::from_value(a.body.clone()).unwrap_or_else(|e| panic!("{e}\n{}", a.text))
}

fn conflict_marks(doc: &sfc_doc::EditorDoc) -> usize {
    doc.attributes.iter().filter(|a| a.name == "sfc.conflict").count()
}

fn condition(doc: &sfc_doc::EditorDoc, transition: &str) -> String {
    doc.elements.iter().find(|e| e.name == transition).and_then(|e| e.condition.clone()).unwrap_or_default()
}

#[tokio::test]
async fn each_side_resolves_the_conflict_and_nothing_is_written() {
    let (d, file, text) = merged_tank("resolve-sides");
    let s = state(&[&d], None);
    let (doc, opened) = open_doc(&s, &file).await;
    // Opened as ours, marked: SFC0605 names the conflict.
    assert_eq!(opened.charts[0].attributes.iter().filter(|a| a.name == "sfc.conflict").count(), 1);
    assert!(opened.diagnostics.iter().any(|d| d.code == "SFC0605"), "{:#?}", opened.diagnostics);
    assert_eq!(condition(&opened.charts[0], "TStart"), "Start AND Empty AND NOT Full");

    // Theirs: their condition, the mark gone, no SFC0605; the step renamed on our side stays.
    let theirs =
        resolve(&s, json!({ "path": path_str(&file), "doc": doc, "element": "transition:TStart", "side": "theirs" }))
            .await;
    assert_eq!(condition(&theirs.doc, "TStart"), "Start AND Empty AND Permit");
    assert_eq!(conflict_marks(&theirs.doc), 0);
    assert!(theirs.doc.elements.iter().any(|e| e.name == "Stirring"), "our rename is kept");
    assert!(!theirs.diagnostics.iter().any(|d| d.code == "SFC0605"), "{:#?}", theirs.diagnostics);
    assert!(
        !theirs.diagnostics.iter().any(|d| d.severity == sfc_server::contract::Severity::Error),
        "{:#?}",
        theirs.diagnostics
    );
    // The blocks keep their ids (the page frames and selects by them).
    let ids = |d: &sfc_doc::EditorDoc| d.elements.iter().map(|e| e.id.clone()).collect::<Vec<_>>();
    assert_eq!(ids(&theirs.doc), ids(&opened.charts[0]));
    let wires = |d: &sfc_doc::EditorDoc| {
        d.connections.iter().map(|c| (c.id.clone(), c.source.clone(), c.target.clone())).collect::<Vec<_>>()
    };
    assert_eq!(wires(&theirs.doc), wires(&opened.charts[0]));
    let places = |d: &sfc_doc::EditorDoc| d.elements.iter().map(|e| (e.x, e.y, e.w, e.h)).collect::<Vec<_>>();
    assert_eq!(places(&theirs.doc), places(&opened.charts[0]));

    // Ours: our condition, the mark gone.
    let ours =
        resolve(&s, json!({ "path": path_str(&file), "doc": doc, "element": "transition:TStart", "side": "ours" }))
            .await;
    assert_eq!(condition(&ours.doc, "TStart"), "Start AND Empty AND NOT Full");
    assert_eq!(conflict_marks(&ours.doc), 0);
    assert!(!ours.diagnostics.iter().any(|d| d.code == "SFC0605"), "{:#?}", ours.diagnostics);

    // The file is not touched.
    assert_eq!(std::fs::read_to_string(&file).unwrap(), text);

    // The resolved chart saved: `sfc check`'s rules pass, without SFC0605.
    let saved = post(
        &s,
        "/api/save",
        &json!({ "path": path_str(&file), "format": "st", "doc": theirs.doc, "hash": opened.hash }),
    )
    .await;
    assert_eq!(saved.status, 200, "{}", saved.text);
    let written = std::fs::read_to_string(&file).unwrap();
    assert!(!written.contains("sfc.conflict"), "{written}");
    assert!(written.contains("Start AND Empty AND Permit"), "{written}");
    let checked = sfc_analysis::check_source(0, "tank.st", &written, &sfc_model::CheckOptions::default());
    assert!(!checked.has_errors(), "{:#?}", checked.diagnostics);
}

#[tokio::test]
async fn without_a_path_the_document_alone_is_resolved() {
    let (d, file, _) = merged_tank("resolve-no-path");
    let s = state(&[&d], None);
    let (doc, _) = open_doc(&s, &file).await;
    let r = resolve(&s, json!({ "doc": doc, "element": "TRANSITION:tstart", "side": "theirs" })).await;
    assert_eq!(condition(&r.doc, "TStart"), "Start AND Empty AND Permit");
    assert_eq!(conflict_marks(&r.doc), 0);
    // Their text names `Permit`, which the merge added to the declarations.
    assert!(r.doc.declarations.contains("Permit"), "{}", r.doc.declarations);
    assert!(r.diagnostics.iter().all(|d| d.file == "Tank.st"), "{:#?}", r.diagnostics);
}

#[tokio::test]
async fn refusals_are_located_messages() {
    let (d, file, _) = merged_tank("resolve-refusals");
    let s = state(&[&d], None);
    let (doc, _) = open_doc(&s, &file).await;

    // No such conflict: 404 naming the ones there are.
    let a = post(&s, "/api/resolve", &json!({ "doc": doc, "element": "step:Idle", "side": "ours" })).await;
    assert_eq!(a.status, 404, "{}", a.text);
    assert!(a.body["error"].as_str().unwrap().contains("transition:TStart"), "{}", a.text);

    // A bad side, a missing field: 400.
    let a = post(&s, "/api/resolve", &json!({ "doc": doc, "element": "transition:TStart", "side": "both" })).await;
    assert_eq!(a.status, 400, "{}", a.text);
    let a = post(&s, "/api/resolve", &json!({ "doc": doc, "side": "ours" })).await;
    assert_eq!(a.status, 400, "{}", a.text);

    // A file outside the session's directories: 403.
    let a = post(
        &s,
        "/api/resolve",
        &json!({ "path": "/etc/passwd", "doc": doc, "element": "transition:TStart", "side": "ours" }),
    )
    .await;
    assert_eq!(a.status, 403, "{}", a.text);

    // A condition typed that does not parse: 422 with the diagnostic locating it.
    let mut broken = doc.clone();
    let t = broken["elements"].as_array_mut().unwrap().iter_mut().find(|e| e["name"] == "TFull").unwrap();
    t["condition"] = json!("Full AND (");
    let a = post(&s, "/api/resolve", &json!({ "doc": broken, "element": "transition:TStart", "side": "theirs" })).await;
    assert_eq!(a.status, 422, "{}", a.text);
    assert!(a.body["error"].as_str().unwrap().contains("TFull"), "{}", a.text);
    assert!(!a.body["diagnostics"].as_array().unwrap().is_empty(), "{}", a.text);

    // Not JSON.
    let a = post_raw(&s, "/api/resolve", b"{".to_vec()).await;
    assert_eq!(a.status, 400, "{}", a.text);
}
