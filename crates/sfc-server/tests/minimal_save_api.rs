//! Saving a chart of a PLCopen XML file (`/api/save`, format `xml`) changes only what changed:
//! a chart saved as opened leaves the file byte for byte, and a step or transition moved in the
//! editor changes only the `<position>` line of its element. On the Beremiz-style fixture of
//! `sfc-plcopen` (`tests/fixtures/minimal_save/`) and the Beremiz exports of the shared corpus
//! (`../shared/corpus`, read where they are; skipped with a note when missing).
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::indexing_slicing)] // test code: a panic is a failed test

mod common;

use common::*;
use serde_json::{json, Value};
use std::path::{Path, PathBuf};

/// The files tried: the fixture, then the shared corpus's when it is there.
fn files() -> Vec<PathBuf> {
    let manifest = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut out = vec![manifest.join("../sfc-plcopen/tests/fixtures/minimal_save/beremiz_style.xml")];
    let shared = manifest.join("../../../shared/corpus");
    let corpus = ["beremiz/first_steps.plc.xml", "beremiz/svghmi_traffic_light.plc.xml", "matiec/SFC_TEST.xml"];
    let found: Vec<PathBuf> = corpus.iter().map(|f| shared.join(f)).filter(|p| p.is_file()).collect();
    if found.is_empty() {
        eprintln!("note: the corpus {} is missing; only the fixture is tried", shared.display());
    }
    out.extend(found);
    out
}

async fn open(s: &sfc_server::AppState, path: &Path) -> Value {
    let a = post(s, "/api/open", &json!({ "path": path_str(path) })).await;
    assert_eq!(a.status, 200, "{}: {}", path.display(), a.text);
    a.body
}

async fn save(s: &sfc_server::AppState, path: &Path, doc: &Value, hash: &Value) -> Answer {
    post(s, "/api/save", &json!({ "path": path_str(path), "format": "xml", "doc": doc, "hash": hash })).await
}

/// The lines of `b` that differ from those of `a` (as many lines), trimmed.
fn diff(a: &str, b: &str) -> Vec<(String, String)> {
    let (la, lb): (Vec<&str>, Vec<&str>) = (a.lines().collect(), b.lines().collect());
    assert_eq!(la.len(), lb.len(), "the number of lines changed");
    la.iter().zip(&lb).filter(|(x, y)| x != y).map(|(x, y)| (x.trim().to_string(), y.trim().to_string())).collect()
}

fn num(v: &Value) -> String {
    let f = v.as_f64().unwrap();
    if f.fract() == 0.0 {
        format!("{}", f as i64)
    } else {
        format!("{f}")
    }
}

#[tokio::test]
async fn saving_a_plcopen_chart_changes_only_what_moved() {
    let d = scratch("minimal-save");
    let s = state(&[&d], None);
    let mut charts = 0;
    for src in files() {
        let path = d.join(src.file_name().unwrap());
        let original = std::fs::read_to_string(&src).unwrap();
        std::fs::write(&path, &original).unwrap();
        let opened = open(&s, &path).await;
        for chart in opened["charts"].as_array().unwrap() {
            charts += 1;
            let pou = chart["pou"].as_str().unwrap().to_string();
            // Saved as opened: not a byte changes.
            let hash = open(&s, &path).await["hash"].clone();
            let a = save(&s, &path, chart, &hash).await;
            assert_eq!(a.status, 200, "{pou}: {}", a.text);
            assert_eq!(std::fs::read_to_string(&path).unwrap(), original, "{}: {pou} saved as opened", src.display());
            // One step, then one transition, moved by 40 and 40.
            for kind in ["step", "transition"] {
                let elements = chart["elements"].as_array().unwrap();
                let Some(k) = elements.iter().position(|e| e["kind"] == kind) else { continue };
                let mut doc = chart.clone();
                let e = &mut doc["elements"][k];
                let (x, y) = (e["x"].as_f64().unwrap(), e["y"].as_f64().unwrap());
                let (old_x, old_y) = (num(&e["x"]), num(&e["y"]));
                e["x"] = json!(x + 40.0);
                e["y"] = json!(y + 40.0);
                let (new_x, new_y) = (num(&e["x"]), num(&e["y"]));
                let hash = open(&s, &path).await["hash"].clone();
                let a = save(&s, &path, &doc, &hash).await;
                assert_eq!(a.status, 200, "{pou}: {}", a.text);
                let written = std::fs::read_to_string(&path).unwrap();
                let changed = diff(&original, &written);
                assert_eq!(changed.len(), 1, "{}: {pou}: {kind} moved: {changed:?}", src.display());
                let (before, after) = &changed[0];
                assert!(before.starts_with("<position") && before.contains(&format!("x=\"{old_x}\"")), "{before}");
                assert!(before.contains(&format!("y=\"{old_y}\"")), "{before}");
                assert_eq!(
                    after,
                    &before
                        .replace(&format!("x=\"{old_x}\""), &format!("x=\"{new_x}\""))
                        .replace(&format!("y=\"{old_y}\""), &format!("y=\"{new_y}\""))
                );
                // The file opens with the block where it was put.
                let reopened = open(&s, &path).await;
                let again = reopened["charts"].as_array().unwrap().iter().find(|c| c["pou"] == pou.as_str()).unwrap();
                let moved = again["elements"].as_array().unwrap().iter().find(|e| e["id"] == doc["elements"][k]["id"]);
                let moved = moved.unwrap();
                assert_eq!((num(&moved["x"]), num(&moved["y"])), (new_x.clone(), new_y.clone()));
                std::fs::write(&path, &original).unwrap();
            }
        }
    }
    assert!(charts >= 1);
    eprintln!("{charts} charts saved");
}

#[tokio::test]
async fn a_chart_without_layout_saved_as_opened_keeps_the_file() {
    // CODESYS writes every position as (0, 0): the editor lays the chart out itself, and a save
    // without an edit writes nothing new.
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../tests/corpus/real/codesys/simultaneous_wired.xml");
    let d = scratch("minimal-save-codesys");
    let path = d.join("simultaneous_wired.xml");
    let original = std::fs::read_to_string(&src).unwrap();
    std::fs::write(&path, &original).unwrap();
    let s = state(&[&d], None);
    let opened = open(&s, &path).await;
    let chart = &opened["charts"][0];
    let a = save(&s, &path, chart, &opened["hash"]).await;
    assert_eq!(a.status, 200, "{}", a.text);
    assert_eq!(std::fs::read_to_string(&path).unwrap(), original);
    // Moved: the chart gets the editor's layout (the POU is written afresh), and opens so.
    let mut doc = chart.clone();
    let k = doc["elements"].as_array().unwrap().iter().position(|e| e["kind"] == "step").unwrap();
    let x = doc["elements"][k]["x"].as_f64().unwrap() + 40.0;
    doc["elements"][k]["x"] = json!(x);
    let a = save(&s, &path, &doc, &a.body["hash"]).await;
    assert_eq!(a.status, 200, "{}", a.text);
    let again = open(&s, &path).await;
    let moved = again["charts"][0]["elements"].as_array().unwrap().iter().find(|e| e["id"] == doc["elements"][k]["id"]);
    assert_eq!(moved.unwrap()["x"].as_f64(), Some(x));
}
