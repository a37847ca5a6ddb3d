//! `POST /api/compare`: the chart on the canvas compared by meaning with its saved file and with
//! git HEAD (File → Compare with saved / Compare with git HEAD).
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::indexing_slicing)] // test code: a panic is a failed test

mod common;

use common::*;
use serde_json::{json, Value};
use sfc_server::contract::{ChangeKind, CompareAgainst, CompareChange, CompareResult, OpenResult};
use std::path::Path;
use std::process::Command;

const TANK: &str = "PROGRAM Tank
    VAR
        Start : BOOL;
        Full : BOOL;
        Empty : BOOL;
        Count : INT;
    END_VAR

    INITIAL_STEP Idle: END_STEP

    TRANSITION TStart FROM Idle TO Filling
        := Start;
    END_TRANSITION

    STEP Filling:
        CountUp(P1);
    END_STEP

    TRANSITION TFull FROM Filling TO Draining
        := Full;
    END_TRANSITION

    STEP Draining: END_STEP

    TRANSITION TEmpty FROM Draining TO Idle
        := Empty;
    END_TRANSITION

    ACTION CountUp:
        Count := Count + 1;
    END_ACTION
END_PROGRAM
";

async fn open_doc(s: &sfc_server::AppState, path: &Path) -> Value {
    let a = post(s, "/api/open", &json!({ "path": path_str(path) })).await;
    assert_eq!(a.status, 200, "{}", a.text);
    let opened: OpenResult = serde_json::from_value(a.body).unwrap();
    serde_json::to_value(&opened.charts[0]).unwrap()
}

async fn compare(s: &sfc_server::AppState, body: Value) -> CompareResult {
    let a = post(s, "/api/compare", &body).await;
    assert_eq!(a.status, 200, "{}", a.text);
    serde_json::from_value(a.body.clone()).unwrap_or_else(|e| panic!("{e}\n{}", a.text))
}

/// The element of the document named `name`.
fn element<'a>(doc: &'a mut Value, name: &str) -> &'a mut Value {
    doc["elements"]
        .as_array_mut()
        .unwrap()
        .iter_mut()
        .find(|e| e["name"] == name)
        .unwrap_or_else(|| panic!("no {name}"))
}

fn find<'a>(list: &'a [CompareChange], element: &str, name: &str) -> &'a CompareChange {
    list.iter()
        .find(|c| c.element == element && c.name == name)
        .unwrap_or_else(|| panic!("no change of {element} {name} in {list:#?}"))
}

fn git(dir: &Path, args: &[&str]) {
    let out = Command::new("git").current_dir(dir).args(args).output().expect("git runs");
    assert!(out.status.success(), "git {args:?}: {}", String::from_utf8_lossy(&out.stderr));
}

#[tokio::test]
async fn compare_with_saved_lists_the_changes_with_their_blocks() {
    let d = scratch("compare-saved");
    let file = d.join("tank.st");
    std::fs::write(&file, TANK).unwrap();
    let s = state(&[&d], None);
    let mut doc = open_doc(&s, &file).await;
    let path = path_str(&file);

    // As opened: equal, nothing moved.
    let r = compare(&s, json!({ "path": path, "doc": doc, "against": "saved" })).await;
    assert!(r.equal, "{r:#?}");
    assert_eq!((r.changes.len(), r.removed.len(), r.layout), (0, 0, 0), "{r:#?}");
    assert_eq!(r.against, CompareAgainst::Saved);
    assert_eq!(r.file, path);
    assert_eq!(r.pou, "Tank");

    // A step moved: still equal in meaning, one block moved (the file, written by hand, has
    // no positions; the others are where the editor drew them).
    let x = element(&mut doc, "Filling")["x"].as_f64().unwrap();
    element(&mut doc, "Filling")["x"] = json!(x + 80.0);
    let r = compare(&s, json!({ "path": path, "doc": doc, "against": "saved" })).await;
    assert!(r.equal, "{r:#?}");
    assert_eq!(r.layout, 1, "{r:#?}");
    // Saved so, then moved again: that step alone.
    let hash = post(&s, "/api/open", &json!({ "path": path })).await.body["hash"].clone();
    let saved = post(&s, "/api/save", &json!({ "path": path, "format": "st", "doc": doc, "hash": hash })).await;
    assert_eq!(saved.status, 200, "{}", saved.text);
    element(&mut doc, "Filling")["x"] = json!(x + 120.0);
    let r = compare(&s, json!({ "path": path, "doc": doc, "against": "saved" })).await;
    assert!(r.equal, "{r:#?}");
    assert_eq!(r.layout, 1, "{r:#?}");

    // A step renamed, a condition changed, an action's body changed.
    let draining = element(&mut doc, "Draining")["id"].as_str().unwrap().to_string();
    element(&mut doc, "Draining")["name"] = json!("Emptying");
    let t_start = element(&mut doc, "TStart")["id"].as_str().unwrap().to_string();
    element(&mut doc, "TStart")["condition"] = json!("Start AND NOT Full");
    doc["actions"][0]["body"] = json!("Count := Count + 2;");
    let r = compare(&s, json!({ "path": path, "doc": doc, "against": "saved" })).await;
    assert!(!r.equal);
    let renamed = find(&r.changes, "step", "Draining");
    assert_eq!(renamed.kind, ChangeKind::Renamed);
    assert_eq!(renamed.new.as_deref(), Some("Emptying"));
    assert_eq!(renamed.element_ids, [draining]);
    let cond = find(&r.changes, "transition", "TStart");
    assert_eq!((cond.kind, cond.what.as_str()), (ChangeKind::Changed, "condition"));
    assert_eq!(cond.old.as_deref(), Some("Start"));
    assert_eq!(cond.new.as_deref(), Some("Start AND NOT Full"));
    assert_eq!(cond.element_ids, [t_start]);
    let body = find(&r.changes, "action", "CountUp");
    assert_eq!(body.what, "body");
    // The action block that names it.
    assert_eq!(body.element_ids.len(), 1, "{body:#?}");
    assert!(r.removed.is_empty(), "{r:#?}");
    // Renamed, the step is still where it was (its old name matches it): only Filling moved.
    assert_eq!(r.layout, 1, "{r:#?}");

    // The file changed on disk since: a step there that the canvas does not have is removed.
    let more = TANK.replace(
        "    STEP Draining: END_STEP\n",
        "    STEP Draining: END_STEP\n\n    STEP Spare: END_STEP\n\n    TRANSITION TSpare FROM Spare TO Idle\n        := Empty;\n    END_TRANSITION\n",
    );
    std::fs::write(&file, more).unwrap();
    let r = compare(&s, json!({ "path": path, "doc": doc, "against": "saved" })).await;
    let spare = find(&r.removed, "step", "Spare");
    assert_eq!(spare.kind, ChangeKind::Removed);
    assert!(spare.element_ids.is_empty());
    find(&r.removed, "transition", "TSpare");
    assert!(r.changes.iter().all(|c| c.kind != ChangeKind::Removed));

    // A variable added on the canvas: listed, no block.
    std::fs::write(&file, TANK).unwrap();
    let mut doc2 = open_doc(&s, &file).await;
    doc2["declarations"] =
        json!(doc2["declarations"].as_str().unwrap().replace("Count : INT;", "Count : INT;\n        Level : INT;"));
    let r = compare(&s, json!({ "path": path, "doc": doc2, "against": "saved" })).await;
    let level = find(&r.changes, "variable", "Level");
    assert_eq!(level.kind, ChangeKind::Added);
    assert!(level.element_ids.is_empty());

    // A chart renamed since it was opened: compared with its POU in the file, the rename one change.
    let mut renamed_doc = open_doc(&s, &file).await;
    renamed_doc["pou"] = json!("Tank2");
    element(&mut renamed_doc, "TFull")["condition"] = json!("Full OR Start");
    let r = compare(&s, json!({ "path": path, "pou": "Tank", "doc": renamed_doc, "against": "saved" })).await;
    let pou = find(&r.changes, "pou", "Tank");
    assert_eq!((pou.kind, pou.new.as_deref()), (ChangeKind::Renamed, Some("Tank2")));
    find(&r.changes, "transition", "TFull");
    assert_eq!(r.pou, "Tank2");
}

#[tokio::test]
async fn compare_refusals_are_located_and_confined() {
    let d = scratch("compare-refusals");
    let file = d.join("tank.st");
    std::fs::write(&file, TANK).unwrap();
    let s = state(&[&d], None);
    let doc = open_doc(&s, &file).await;
    let path = path_str(&file);

    // A saved file that does not parse: 422 with the located diagnostics.
    std::fs::write(&file, TANK.replace("END_TRANSITION\n\n    STEP Filling", "END_TRANSITON\n\n    STEP Filling"))
        .unwrap();
    let a = post(&s, "/api/compare", &json!({ "path": path, "doc": doc, "against": "saved" })).await;
    assert_eq!(a.status, 422, "{}", a.text);
    let message = a.body["error"].as_str().unwrap();
    assert!(message.contains("saved file does not parse"), "{message}");
    assert!(message.contains("tank.st:"), "located: {message}");
    let first = &a.body["diagnostics"][0];
    assert!(first["line"].as_u64().unwrap() > 1, "{}", a.text);
    assert!(first["code"].as_str().unwrap().starts_with("SFC01"), "{}", a.text);

    // A condition typed on the canvas that does not parse: refused, naming the transition.
    std::fs::write(&file, TANK).unwrap();
    let mut bad = doc.clone();
    element(&mut bad, "TFull")["condition"] = json!("Full AND (");
    let a = post(&s, "/api/compare", &json!({ "path": path, "doc": bad, "against": "saved" })).await;
    assert_eq!(a.status, 422, "{}", a.text);
    assert!(a.text.contains("TFull"), "{}", a.text);

    // The file deleted: 404.
    std::fs::remove_file(&file).unwrap();
    let a = post(&s, "/api/compare", &json!({ "path": path, "doc": doc, "against": "saved" })).await;
    assert_eq!(a.status, 404, "{}", a.text);

    // Outside the roots, or not a chart file: refused as open and save refuse them.
    let a = post(&s, "/api/compare", &json!({ "path": "/etc/passwd", "doc": doc, "against": "saved" })).await;
    assert_eq!(a.status, 403, "{}", a.text);
    let a = post(&s, "/api/compare", &json!({ "path": "relative.st", "doc": doc, "against": "saved" })).await;
    assert_eq!(a.status, 400, "{}", a.text);
    let a = post(&s, "/api/compare", &json!({ "path": path, "doc": doc, "against": "yesterday" })).await;
    assert_eq!(a.status, 400, "{}", a.text);
}

#[tokio::test]
async fn compare_with_git_head() {
    let d = scratch("compare-head");
    let file = d.join("tank.st");
    std::fs::write(&file, TANK).unwrap();
    let s = state(&[&d], None);
    let doc = open_doc(&s, &file).await;
    let path = path_str(&file);

    // Not under git.
    let a = post(&s, "/api/compare", &json!({ "path": path, "doc": doc, "against": "head" })).await;
    assert_eq!(a.status, 422, "{}", a.text);
    assert!(a.text.contains("not under git"), "{}", a.text);

    git(&d, &["init", "-q"]);
    git(&d, &["config", "user.name", "sfc test"]);
    git(&d, &["config", "user.email", "test@example.invalid"]);
    git(&d, &["config", "commit.gpgsign", "false"]);
    // No commit yet.
    let a = post(&s, "/api/compare", &json!({ "path": path, "doc": doc, "against": "head" })).await;
    assert_eq!(a.status, 404, "{}", a.text);
    assert!(a.text.contains("no commit yet"), "{}", a.text);

    std::fs::write(d.join("other.st"), TANK.replace("Tank", "Other")).unwrap();
    git(&d, &["add", "other.st"]);
    git(&d, &["commit", "-q", "-m", "other"]);
    // Not committed.
    let a = post(&s, "/api/compare", &json!({ "path": path, "doc": doc, "against": "head" })).await;
    assert_eq!(a.status, 404, "{}", a.text);
    assert!(a.text.contains("not in git HEAD"), "{}", a.text);

    git(&d, &["add", "tank.st"]);
    git(&d, &["commit", "-q", "-m", "tank"]);
    let r = compare(&s, json!({ "path": path, "doc": doc, "against": "head" })).await;
    assert!(r.equal, "{r:#?}");
    assert_eq!(r.against, CompareAgainst::Head);
    assert_eq!(r.file, format!("{path}@HEAD"));

    // Saved with a change: equal to the saved file, different from HEAD.
    std::fs::write(&file, TANK.replace(":= Empty;", ":= Empty AND NOT Start;")).unwrap();
    let mut doc = open_doc(&s, &file).await;
    let r = compare(&s, json!({ "path": path, "doc": doc, "against": "saved" })).await;
    assert!(r.equal, "{r:#?}");
    let r = compare(&s, json!({ "path": path, "doc": doc, "against": "head" })).await;
    let c = find(&r.changes, "transition", "TEmpty");
    assert_eq!(c.old.as_deref(), Some("Empty"));
    assert_eq!(c.new.as_deref(), Some("Empty AND NOT Start"));
    let t_empty = element(&mut doc, "TEmpty")["id"].as_str().unwrap().to_string();
    assert_eq!(c.element_ids, [t_empty]);

    // HEAD holding a file that does not parse: located, as for the saved file.
    std::fs::write(&file, "PROGRAM Tank\n    INITIAL_STEP Idle END_STEP\nEND_PROGRAM\n").unwrap();
    git(&d, &["commit", "-q", "-am", "broken"]);
    let a = post(&s, "/api/compare", &json!({ "path": path, "doc": doc, "against": "head" })).await;
    assert_eq!(a.status, 422, "{}", a.text);
    assert!(a.text.contains("in git HEAD does not parse"), "{}", a.text);
    assert!(a.text.contains("tank.st@HEAD:2:"), "{}", a.text);
}

#[tokio::test]
async fn compare_a_plcopen_file() {
    let d = scratch_with("compare-xml", &["seed.xml"]);
    let file = d.join("seed.xml");
    let s = state(&[&d], None);
    let mut doc = open_doc(&s, &file).await;
    let path = path_str(&file);
    let r = compare(&s, json!({ "path": path, "doc": doc, "against": "saved" })).await;
    assert!(r.equal, "{r:#?}");
    assert_eq!(r.layout, 0, "{r:#?}");
    let run = element(&mut doc, "Run")["id"].as_str().unwrap().to_string();
    element(&mut doc, "Run")["name"] = json!("Running");
    let r = compare(&s, json!({ "path": path, "doc": doc, "against": "saved" })).await;
    let c = find(&r.changes, "step", "Run");
    assert_eq!((c.kind, c.new.as_deref()), (ChangeKind::Renamed, Some("Running")));
    assert_eq!(c.element_ids, [run]);
}
