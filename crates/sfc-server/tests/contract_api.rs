//! Every kind of answer of the HTTP API reads back into the types of `sfc_server::contract`
//! (which refuse unknown fields), from which the editor's TypeScript types are generated: the
//! generated types say exactly what the server sends.

mod common;

use common::*;
use serde::de::DeserializeOwned;
use serde_json::{json, Value};
use sfc_server::contract::{BuildResult, FileEntry, OpenResult, SaveResult, Session};
use sfc_server::{HostBlock, HostMode};

fn read<T: DeserializeOwned>(what: &str, v: &Value) -> T {
    serde_json::from_value(v.clone()).unwrap_or_else(|e| panic!("{what}: {e}\n{v:#}"))
}

#[tokio::test]
async fn answers_fit_the_contract_types() {
    let d = scratch_with("contract", &["seed.st", "seed.xml", "unparsed_condition.st"]);
    let s = state(&[&d], None);
    let _: Session = read("session", &get(&s, "/api/session").await.body);
    let files = get(&s, "/api/files").await.body;
    let _: Vec<FileEntry> = read("files", &files["files"]);
    for f in ["seed.st", "seed.xml", "unparsed_condition.st"] {
        let a = post(&s, "/api/open", &json!({ "path": path_str(&d.join(f)) })).await;
        assert_eq!(a.status, 200, "{}", a.text);
        let opened: OpenResult = read(f, &a.body);
        let doc = serde_json::to_value(&opened.charts[0]).unwrap();
        let checked = post(&s, "/api/check", &json!({ "doc": doc, "analysis": true })).await;
        let _: Vec<sfc_server::contract::Diag> = read("check", &checked.body["diagnostics"]);
        for target in ["st", "svg", "atmt", "plcopen"] {
            let built = post(&s, "/api/build", &json!({ "doc": doc, "target": target })).await;
            let _: BuildResult = read(&format!("build {target} of {f}"), &built.body);
        }
        if f != "unparsed_condition.st" {
            let saved = post(
                &s,
                "/api/save",
                &json!({ "path": path_str(&d.join(f)), "format": opened.format, "doc": doc, "hash": opened.hash }),
            )
            .await;
            assert_eq!(saved.status, 200, "{}", saved.text);
            let _: SaveResult = read("save", &saved.body);
        }
    }
    // Host mode's session and build.
    let chart = d.join("seed.st");
    let host = HostMode { fb: HostBlock::Atmt, nstep: None, ntr: None, result: d.join("result.txt") };
    let h = state(&[&chart], Some(host));
    let session: Session = read("host session", &get(&h, "/api/session").await.body);
    assert!(session.host.is_some());
}
