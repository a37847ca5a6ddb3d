//! The calls that convert documents (`sfc_doc`): open, save (text and PLCopen XML, atomic,
//! other POUs kept), check (with element and witness ids), build for every target, layout,
//! new, and host mode writing the one-line table for the host.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::indexing_slicing)] // test code: a panic is a failed test

mod common;

use common::*;
use serde_json::{json, Value};
use sfc_server::{content_hash, HostBlock, HostMode};
use std::path::Path;

fn fixture_text(name: &str) -> String {
    std::fs::read_to_string(fixtures().join(name)).unwrap()
}

async fn open_ok(s: &sfc_server::AppState, path: &Path) -> Value {
    let a = post(s, "/api/open", &json!({ "path": path_str(path) })).await;
    assert_eq!(a.status, 200, "{}: {}", path.display(), a.text);
    a.body
}

/// Saves `doc` over `path` in `format`, with the hash it was opened with (`null`: a new file).
async fn save(s: &sfc_server::AppState, path: &Path, format: &str, doc: &Value, hash: &Value) -> Answer {
    post(s, "/api/save", &json!({ "path": path_str(path), "format": format, "doc": doc, "hash": hash })).await
}

/// The chart of `opened` named `pou`.
fn chart(opened: &Value, pou: &str) -> Value {
    opened["charts"].as_array().unwrap().iter().find(|c| c["pou"] == pou).cloned().expect("the chart is there")
}

#[tokio::test]
async fn open_gives_charts_hash_and_located_diagnostics() {
    let d = scratch_with("open", &["seed.st", "two_pous.st", "seed.xml"]);
    let s = state(&[&d], None);
    let opened = open_ok(&s, &d.join("seed.st")).await;
    assert_eq!(opened["path"], path_str(&d.join("seed.st")));
    assert_eq!(opened["format"], "st");
    assert_eq!(opened["hash"], content_hash(fixture_text("seed.st").as_bytes()));
    assert_eq!(opened["diagnostics"], json!([]));
    let seed = chart(&opened, "Seed");
    assert_eq!(seed["target"], "atmt");
    assert!(seed["elements"].as_array().unwrap().iter().any(|e| e["id"] == "step:Init" && e["initial"] == true));

    // The diagnostic of the second POU designates its transition, not a block of the first.
    let opened = open_ok(&s, &d.join("two_pous.st")).await;
    assert_eq!(opened["charts"].as_array().unwrap().len(), 2);
    let diags = opened["diagnostics"].as_array().unwrap();
    assert_eq!(diags.len(), 1, "{diags:?}");
    let d0 = &diags[0];
    assert_eq!(d0["code"], "SFC0303");
    assert_eq!(
        (d0["line"].clone(), d0["column"].clone(), d0["endLine"].clone(), d0["endColumn"].clone()),
        (json!(15), json!(42), json!(15), json!(47))
    );
    assert_eq!(d0["element"], "Back");
    assert_eq!(d0["elementIds"], json!(["transition:Back"]));
    assert_eq!(d0["title"], sfc_diagnostics::explain("SFC0303").unwrap().title);

    // PLCopen XML: imported, the same chart as the text it was exported from.
    let opened_xml = open_ok(&s, &d.join("seed.xml")).await;
    assert_eq!(opened_xml["format"], "xml");
    let from_xml = chart(&opened_xml, "Seed");
    let names = |c: &Value| {
        let mut v: Vec<String> = c["elements"].as_array().unwrap().iter().map(|e| e["id"].to_string()).collect();
        v.sort();
        v
    };
    assert_eq!(names(&from_xml), names(&seed));
}

#[tokio::test]
async fn save_splices_atomically_and_detects_changes() {
    let d = scratch_with("save", &["two_pous.st"]);
    let path = d.join("two_pous.st");
    let original = fixture_text("two_pous.st");
    let s = state(&[&d], None);
    let opened = open_ok(&s, &path).await;
    let mut first = chart(&opened, "First");
    // Describe a step: the edit must reach the file, the other POU must not change.
    for e in first["elements"].as_array_mut().unwrap() {
        if e["name"] == "B" {
            e["description"] = json!("described in the test");
        }
    }
    let doc: sfc_doc::EditorDoc = serde_json::from_value(first.clone()).unwrap();
    let expected = sfc_doc::splice(&original, &doc);
    let a = save(&s, &path, "st", &first, &opened["hash"]).await;
    assert_eq!(a.status, 200, "{}", a.text);
    let written = std::fs::read_to_string(&path).unwrap();
    assert_eq!(written, expected);
    assert!(written.contains("described in the test"));
    let second_start = original.find("PROGRAM Second").unwrap();
    assert!(written.ends_with(&original[second_start..]), "the second POU is kept byte for byte");
    assert_eq!(a.body["hash"], content_hash(written.as_bytes()));
    assert_eq!(a.body["path"], path_str(&path));
    assert_eq!(entries(&d), ["two_pous.st"], "no temporary file is left");
    // The old hash is stale now: conflict, unless the page says to overwrite.
    let again = json!({ "path": path_str(&path), "format": "st", "doc": first, "hash": opened["hash"] });
    assert_eq!(post(&s, "/api/save", &again).await.status, 409);
    let mut forced = again.clone();
    forced["overwrite"] = json!(true);
    assert_eq!(post(&s, "/api/save", &forced).await.status, 200);
    // Opening the saved file gives the document back.
    let reopened = open_ok(&s, &path).await;
    assert_eq!(chart(&reopened, "First"), first);
}

#[tokio::test]
async fn save_of_a_renamed_pou_replaces_it_by_its_old_name() {
    let d = scratch_with("rename", &["two_pous.st"]);
    let path = d.join("two_pous.st");
    let s = state(&[&d], None);
    let opened = open_ok(&s, &path).await;
    let mut first = chart(&opened, "First");
    // Onto the name of the other POU of the file: refused, nothing written.
    first["pou"] = json!("second");
    let onto = json!({ "path": path_str(&path), "format": "st", "doc": first, "hash": opened["hash"], "pou": "First" });
    let a = post(&s, "/api/save", &onto).await;
    assert_eq!(a.status, 422, "{}", a.text);
    assert!(a.body["error"].as_str().unwrap().contains("already holds a POU named `second`"), "{}", a.text);
    assert_eq!(std::fs::read_to_string(&path).unwrap(), fixture_text("two_pous.st"));
    // A fresh name: the old POU is replaced, not kept beside the renamed one.
    first["pou"] = json!("Renamed");
    let a = post(
        &s,
        "/api/save",
        &json!({ "path": path_str(&path), "format": "st", "doc": first, "hash": opened["hash"], "pou": "First" }),
    )
    .await;
    assert_eq!(a.status, 200, "{}", a.text);
    let reopened = open_ok(&s, &path).await;
    let pous: Vec<&str> = reopened["charts"].as_array().unwrap().iter().map(|c| c["pou"].as_str().unwrap()).collect();
    assert_eq!(pous, ["Renamed", "Second"]);
    assert_eq!(chart(&reopened, "Renamed"), first);
}

#[tokio::test]
async fn save_new_text_and_xml_files() {
    let d = scratch_with("savenew", &["seed.st", "seed.xml"]);
    let s = state(&[&d], None);
    let seed = chart(&open_ok(&s, &d.join("seed.st")).await, "Seed");
    // A new text file holds just this POU.
    let fresh = d.join("fresh.st");
    let a = save(&s, &fresh, "st", &seed, &json!(null)).await;
    assert_eq!(a.status, 200, "{}", a.text);
    assert_eq!(chart(&open_ok(&s, &fresh).await, "Seed"), seed);
    // PLCopen XML: spliced into the imported project, exported, and it builds the same table.
    let xml_path = d.join("seed.xml");
    let opened = open_ok(&s, &xml_path).await;
    let mut doc = chart(&opened, "Seed");
    doc["description"] = json!("edited in the test");
    let a = save(&s, &xml_path, "xml", &doc, &opened["hash"]).await;
    assert_eq!(a.status, 200, "{}", a.text);
    let xml = std::fs::read_to_string(&xml_path).unwrap();
    assert!(xml.starts_with("<?xml"), "{}", &xml[..60.min(xml.len())]);
    assert_eq!(a.body["hash"], content_hash(xml.as_bytes()));
    let reopened = open_ok(&s, &xml_path).await;
    assert_eq!(chart(&reopened, "Seed")["description"], "edited in the test");
    assert_eq!(entries(&d), ["fresh.st", "seed.st", "seed.xml"]);
}

#[tokio::test]
async fn check_reports_problems_and_witnesses() {
    let d = scratch_with("check", &["unsafe.st"]);
    let s = state(&[&d], None);
    let doc = chart(&open_ok(&s, &d.join("unsafe.st")).await, "Unsafe");
    let a = post(&s, "/api/check", &json!({ "doc": doc, "analysis": false })).await;
    assert_eq!(a.status, 200, "{}", a.text);
    assert_eq!(a.body["diagnostics"], json!([]), "no analysis, no findings");
    let a = post(&s, "/api/check", &json!({ "doc": doc, "analysis": true })).await;
    let diags = a.body["diagnostics"].as_array().unwrap();
    let s0 = diags.iter().find(|d| d["code"] == "SFC0501" && d["element"] == "S0").expect("S0 is unsafe");
    assert_eq!(s0["elementIds"], json!(["step:S0"]));
    assert_eq!(s0["witness"], json!(["T1", "T2", "T3"]));
    assert_eq!(s0["witnessIds"], json!(["transition:T1", "transition:T2", "transition:T3"]));
    // A transition with no step before it is a problem of the document, located on its block.
    let mut broken = doc.clone();
    let loose = json!({ "id": "loose", "kind": "transition", "x": 400, "y": 0, "w": 40, "h": 10, "condition": "a" });
    broken["elements"].as_array_mut().unwrap().push(loose);
    let a = post(&s, "/api/check", &json!({ "doc": broken, "analysis": false })).await;
    let diags = a.body["diagnostics"].as_array().unwrap();
    assert!(diags.iter().any(|d| d["elementIds"] == json!(["loose"])), "{diags:?}");
}

#[tokio::test]
async fn build_every_target() {
    let d = scratch_with("build", &["seed.st", "press.st", "two_pous.st"]);
    let s = state(&[&d], None);
    let seed = chart(&open_ok(&s, &d.join("seed.st")).await, "Seed");
    let a = post(&s, "/api/build", &json!({ "doc": seed, "target": "atmt" })).await;
    assert_eq!(a.status, 200, "{}", a.text);
    assert_eq!(a.body["ok"], true);
    assert_eq!(a.body["output"], fixture_text("seed.atmt"));
    assert_eq!(a.body["table"]["timeouts"], json!([8.1, 2.0, 1.0]));
    assert_eq!(a.body["table"]["rules"][1], json!({ "state": 1, "condition": 1, "next": 2 }));
    assert!(a.body.get("resultWritten").is_none(), "not in host mode");
    let first = chart(&open_ok(&s, &d.join("two_pous.st")).await, "First");
    for (doc, target, marker) in [
        (&seed, "st", "Seed"),
        (&seed, "plcopen", "<project"),
        (&seed, "svg", "<svg"),
        (&seed, "text", "PROGRAM Seed"),
        (&first, "stl", "NETWORK"),
    ] {
        let a = post(&s, "/api/build", &json!({ "doc": doc, "target": target })).await;
        assert_eq!(a.body["ok"], true, "{target}: {}", a.text);
        assert!(a.body["output"].as_str().unwrap().contains(marker), "{target}");
        assert!(a.body.get("table").is_none());
    }
    // The ATMT inputs are no S7-200 variables: the generator's diagnostics, located.
    let a = post(&s, "/api/build", &json!({ "doc": seed, "target": "stl" })).await;
    assert_eq!(a.body["ok"], false, "{}", a.text);
    let diags = a.body["diagnostics"].as_array().unwrap();
    assert!(
        diags.iter().any(|d| d["code"] == "SFC0810"
            && d["elementIds"]
                .as_array()
                .is_some_and(|ids| ids.len() == 1 && ids[0].as_str().unwrap().starts_with("transition"))),
        "{diags:?}"
    );
    // Too few states allowed: validation fails, nothing is built.
    let a = post(&s, "/api/build", &json!({ "doc": seed, "target": "atmt", "nstep": 2 })).await;
    assert_eq!(a.body["ok"], false, "{}", a.text);
    assert!(a.body["diagnostics"].as_array().unwrap().iter().any(|d| d["code"].as_str().unwrap().starts_with("SFC04")));
    assert!(a.body.get("output").is_none());
    // Negated inputs are EATMT only.
    let press = chart(&open_ok(&s, &d.join("press.st")).await, "Press");
    let a = post(&s, "/api/build", &json!({ "doc": press, "target": "eatmt" })).await;
    assert_eq!(a.body["output"], fixture_text("press.eatmt"));
    let a = post(&s, "/api/build", &json!({ "doc": press, "target": "atmt" })).await;
    assert_eq!(a.body["ok"], false);
}

#[tokio::test]
async fn host_mode_writes_the_one_line_result() {
    for (fixture, fb, expected) in
        [("seed.st", HostBlock::Atmt, "seed.atmt"), ("press.st", HostBlock::Eatmt, "press.eatmt")]
    {
        let d = scratch_with(&format!("host-{expected}"), &[fixture]);
        let result = d.join("result.txt");
        let host = HostMode { fb, nstep: None, ntr: None, result: result.clone() };
        let s = state(&[&d.join(fixture)], Some(host));
        let opened = open_ok(&s, &d.join(fixture)).await;
        let doc = opened["charts"][0].clone();
        // The page asks for a table; the host's block decides which.
        let a = post(&s, "/api/build", &json!({ "doc": doc, "target": "atmt" })).await;
        assert_eq!(a.body["ok"], true, "{}", a.text);
        assert_eq!(a.body["resultWritten"], path_str(&result));
        let written = std::fs::read(&result).unwrap();
        assert_eq!(written, fixture_text(expected).as_bytes(), "exactly the one line, no line break");
        assert!(!written.contains(&b'\n'));
        // Other targets are previews: no result file is written for them.
        std::fs::remove_file(&result).unwrap();
        let a = post(&s, "/api/build", &json!({ "doc": doc, "target": "svg" })).await;
        assert_eq!(a.body["ok"], true);
        assert!(a.body.get("resultWritten").is_none() && !result.exists());
    }
    // The host's limits apply: 2 states are too few for the seed chart.
    let d = scratch_with("host-limits", &["seed.st"]);
    let result = d.join("result.txt");
    let s = state(
        &[&d.join("seed.st")],
        Some(HostMode { fb: HostBlock::Atmt, nstep: Some(2), ntr: None, result: result.clone() }),
    );
    let doc = open_ok(&s, &d.join("seed.st")).await["charts"][0].clone();
    let a = post(&s, "/api/build", &json!({ "doc": doc, "target": "atmt" })).await;
    assert_eq!(a.body["ok"], false, "{}", a.text);
    assert!(!result.exists());
}

#[tokio::test]
async fn new_and_layout() {
    let d = scratch("newlayout");
    let s = state(&[&d], None);
    let a = post(&s, "/api/new", &json!({ "name": "Conveyor", "target": "eatmt" })).await;
    assert_eq!(a.status, 200, "{}", a.text);
    let doc = &a.body["doc"];
    assert_eq!(doc["pou"], "Conveyor");
    assert_eq!(doc["target"], "eatmt");
    let steps: Vec<&Value> = doc["elements"].as_array().unwrap().iter().filter(|e| e["kind"] == "step").collect();
    assert_eq!(steps.len(), 1);
    assert_eq!((steps[0]["name"].clone(), steps[0]["initial"].clone()), (json!("Init"), json!(true)));
    let a = post(&s, "/api/layout", &json!({ "doc": doc })).await;
    assert_eq!(a.status, 200, "{}", a.text);
    let ids = |d: &Value| d["elements"].as_array().unwrap().iter().map(|e| e["id"].clone()).collect::<Vec<_>>();
    assert_eq!(ids(&a.body["doc"]), ids(doc));
}

/// A condition that does not parse: its error names the transition, and a save refuses rather
/// than write `FALSE` over what was typed; the file stays as it was.
#[tokio::test]
async fn typed_text_that_does_not_parse_is_never_replaced() {
    let d = scratch_with("unparsed", &["unparsed_condition.st"]);
    let s = state(&[&d], None);
    let path = d.join("unparsed_condition.st");
    let before = std::fs::read_to_string(&path).unwrap();
    let opened = open_ok(&s, &path).await;
    let err =
        opened["diagnostics"].as_array().unwrap().iter().find(|x| x["code"] == "SFC0101").expect("the syntax error");
    assert_eq!(err["element"], "T1", "{err}");
    assert_eq!(err["elementIds"], json!(["transition:T1"]));
    assert_eq!(err["line"], 9);
    let doc = chart(&opened, "Lose");
    let t1 = doc["elements"].as_array().unwrap().iter().find(|e| e["id"] == "transition:T1").unwrap();
    assert_eq!(t1["condition"], "a AND ;", "kept as typed");
    let a = save(&s, &path, "st", &doc, &opened["hash"]).await;
    assert_eq!(a.status, 422, "{}", a.text);
    let msg = a.body["error"].as_str().unwrap();
    assert!(msg.contains("not saved") && msg.contains("T1"), "{msg}");
    // Where the first problem is: file:line:col, as the Error list gives it.
    let first = &a.body["diagnostics"][0];
    let at = format!(" at {}:{}:{}", first["file"].as_str().unwrap(), first["line"], first["column"]);
    assert!(msg.contains(&at), "{msg} lacks {at}");
    assert_eq!(a.body["diagnostics"][0]["elementIds"], json!(["transition:T1"]));
    assert_eq!(std::fs::read_to_string(&path).unwrap(), before, "nothing written");
    // The drawing's problems carry their block and a place in the text.
    let a = post(&s, "/api/check", &json!({ "doc": doc, "analysis": false })).await;
    let p = a.body["diagnostics"].as_array().unwrap().iter().find(|x| x["code"] == "SFC0217").expect("the problem");
    assert_eq!(p["element"], "T1");
    assert!(p["line"].as_u64().unwrap() > 1, "{p}");
}

/// A chart saved as UTF-16 (Notepad's "Unicode") opens as text, and a save writes it back as
/// UTF-16 with its byte order mark and CRLF: the engineer's editor still reads it.
#[tokio::test]
async fn a_utf16_file_is_saved_as_utf16() {
    let d = scratch_with("utf16", &["two_pous.st"]);
    let path = d.join("two_pous.st");
    let original = fixture_text("two_pous.st").replace('\n', "\r\n");
    let utf16 =
        |t: &str| -> Vec<u8> { [0xFF, 0xFE].into_iter().chain(t.encode_utf16().flat_map(u16::to_le_bytes)).collect() };
    std::fs::write(&path, utf16(&original)).unwrap();
    let s = state(&[&d], None);
    let opened = open_ok(&s, &path).await;
    assert_eq!(
        opened["diagnostics"].as_array().unwrap().len(),
        1,
        "the fixture's one finding: {}",
        opened["diagnostics"]
    );
    let mut first = chart(&opened, "First");
    for e in first["elements"].as_array_mut().unwrap() {
        if e["name"] == "B" {
            e["description"] = json!("Ventil öffnen");
        }
    }
    let a = save(&s, &path, "st", &first, &opened["hash"]).await;
    assert_eq!(a.status, 200, "{}", a.text);
    let written = std::fs::read(&path).unwrap();
    let decoded = sfc_syntax::encoding::decode(&written);
    assert_eq!(decoded.encoding, sfc_syntax::encoding::Encoding::Utf16Le);
    assert!(decoded.bom && decoded.crlf, "BOM and CRLF kept");
    assert!(decoded.text.contains("Ventil öffnen"), "{}", decoded.text);
    assert_eq!(written, utf16(&decoded.text), "every character written as UTF-16");
}

/// A TwinCAT export whose function block is written in ST and keeps its sequence in an action
/// written in SFC: it opens with its body as text and the action's chart, and a condition
/// changed in that chart is saved into the PLCopen file, which reads back with it.
#[tokio::test]
async fn an_action_chart_of_a_block_in_st_is_saved_into_a_plcopen_file() {
    let d = scratch("sfc_action_xml");
    let corpus = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../tests/corpus/real/twincat/sorting_station_program_access.xml");
    let path = d.join("sorting.xml");
    std::fs::copy(&corpus, &path).unwrap();
    let s = state(&[&d], None);
    let opened = open_ok(&s, &path).await;
    let mut block = chart(&opened, "SortingStation");
    assert!(block["body"].as_str().unwrap().contains("ACT_Sequence(SFCReset := MAIN.Restart);"), "{block}");
    assert_eq!(block["elements"], json!([]));
    let k = block["actions"].as_array().unwrap().iter().position(|a| a["name"] == "ACT_Sequence").unwrap();
    let sequence = &mut block["actions"][k]["chart"];
    assert!(sequence["elements"].as_array().unwrap().iter().any(|e| e["name"] == "Init__Sorting"), "{sequence}");
    let t = sequence["elements"]
        .as_array_mut()
        .unwrap()
        .iter_mut()
        .find(|e| e["condition"] == "Sort__Light.t > T#500ms")
        .expect("the transition");
    t["condition"] = json!("Sort__Light.t > T#600ms");
    let a = save(&s, &path, "xml", &block, &opened["hash"]).await;
    assert_eq!(a.status, 200, "{}", a.text);
    let again = open_ok(&s, &path).await;
    let block = chart(&again, "SortingStation");
    let sequence = &block["actions"][k]["chart"];
    assert!(
        sequence["elements"].as_array().unwrap().iter().any(|e| e["condition"] == "Sort__Light.t > T#600ms"),
        "{sequence}"
    );
    assert!(
        !again["diagnostics"].as_array().unwrap().iter().any(|d| d["severity"] == "error"),
        "{}",
        again["diagnostics"]
    );
}
