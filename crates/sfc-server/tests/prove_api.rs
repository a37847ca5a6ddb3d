//! `POST /api/prove`: the requirements beside the open chart's file proved for the Error List.

mod common;

use common::*;
use serde_json::json;
use sfc_server::contract::{OpenResult, ProveResult, Severity};

fn prover_fixture(name: &str) -> std::path::PathBuf {
    std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../sfc-prove/tests/fixtures").join(name)
}

#[tokio::test]
async fn violated_properties_join_the_error_list_with_their_replay() {
    let d = scratch("prove");
    for f in ["carwash.st", "carwash.props.toml"] {
        std::fs::copy(prover_fixture(f), d.join(f)).unwrap();
    }
    let s = state(&[&d], None);
    let chart = path_str(&d.join("carwash.st"));
    let opened = post(&s, "/api/open", &json!({ "path": chart })).await;
    assert_eq!(opened.status, 200, "{}", opened.text);
    let opened: OpenResult = serde_json::from_value(opened.body).unwrap();
    let doc = serde_json::to_value(&opened.charts[0]).unwrap();

    let a = post(&s, "/api/prove", &json!({ "doc": doc, "path": chart })).await;
    assert_eq!(a.status, 200, "{}", a.text);
    let r: ProveResult = serde_json::from_value(a.body.clone()).unwrap_or_else(|e| panic!("{e}\n{}", a.text));
    let summary = r.summary.expect("a summary");
    assert_eq!((summary.holds, summary.violated, summary.unknown), (4, 1, 0), "{}", a.text);
    assert_eq!(r.diagnostics.len(), 1, "{}", a.text);
    let v = &r.diagnostics[0];
    assert_eq!(v.code, "SFC1002");
    assert_eq!(v.severity, Severity::Error);
    assert!(v.file.ends_with("carwash.props.toml"), "{}", v.file);
    assert!(v.line > 1, "located at its [[property]]: {}", v.line);
    let replay = v.replay.as_ref().expect("a replay");
    assert_eq!(replay.period, "T#10ms");
    assert_eq!(replay.scans.len(), 3, "{replay:?}");
    assert!(replay.scenario.contains("never = \"Travel AND NOT CarPresent\""), "{}", replay.scenario);
    // The editor proves without writing files.
    assert!(!d.join(&replay.file).exists());

    // A property file with an error: SFC1001 at its line and column.
    std::fs::write(d.join("carwash.props.toml"), "[[property]]\nname = \"x\"\nnever = \"Travel AND Nonsense\"\n")
        .unwrap();
    let a = post(&s, "/api/prove", &json!({ "doc": doc, "path": chart })).await;
    assert_eq!(a.status, 200, "{}", a.text);
    let r: ProveResult = serde_json::from_value(a.body.clone()).unwrap();
    assert!(r.summary.is_none());
    assert_eq!(r.diagnostics[0].code, "SFC1001", "{}", a.text);
    assert_eq!(r.diagnostics[0].line, 3, "{}", a.text);

    // No property file: 404 saying where it is looked for.
    std::fs::remove_file(d.join("carwash.props.toml")).unwrap();
    let a = post(&s, "/api/prove", &json!({ "doc": doc, "path": chart })).await;
    assert_eq!(a.status, 404, "{}", a.text);
    assert!(a.text.contains("carwash.props.toml"), "{}", a.text);

    // Outside the roots: refused.
    let a = post(&s, "/api/prove", &json!({ "doc": doc, "path": "/etc/passwd.st" })).await;
    assert!(a.status == 403 || a.status == 400 || a.status == 404, "{} {}", a.status, a.text);
}
