//! `GET`/`POST /api/settings`: the editor's settings kept in the config directory (here a
//! scratch directory given as `SFC_CONFIG_DIR` would give it), so a server started later, on
//! another port, reads what an earlier one stored; the bounds; a corrupt file.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::indexing_slicing)] // test code: a panic is a failed test

mod common;

use common::*;
use serde_json::{json, Value};
use sfc_server::contract::Settings;
use sfc_server::{AppState, EditOptions};
use std::path::Path;

/// A session on `port` serving `charts`, with its settings in `config`.
fn server(charts: &Path, config: &Path, port: u16) -> AppState {
    let opts = EditOptions { files: vec![charts.to_path_buf()], port: Some(port), host: None };
    AppState::with_config_dir(&opts, port, Some(config.to_path_buf())).expect("the session starts")
}

async fn get_on(s: &AppState, uri: &str) -> Answer {
    let host = format!("127.0.0.1:{}", s.port());
    send(s, Call { method: "GET", uri, host: Some(&host), token: Some(s.token()), body: None }).await
}

async fn post_on(s: &AppState, uri: &str, body: Vec<u8>) -> Answer {
    let host = format!("127.0.0.1:{}", s.port());
    send(s, Call { method: "POST", uri, host: Some(&host), token: Some(s.token()), body: Some(body) }).await
}

async fn read(s: &AppState) -> Settings {
    let a = get_on(s, "/api/settings").await;
    assert_eq!(a.status, 200, "{}", a.text);
    assert_eq!(a.cache_control, "no-store");
    serde_json::from_value(a.body).unwrap_or_else(|e| panic!("{e}: {}", a.text))
}

async fn store(s: &AppState, update: Value) -> Answer {
    post_on(s, "/api/settings", serde_json::to_vec(&update).unwrap()).await
}

#[tokio::test]
async fn settings_outlast_the_server() {
    let charts = scratch_with("settings-charts", &["seed.st"]);
    let config = scratch("settings-config").join("sfc");
    let chart = path_str(&charts.join("seed.st"));
    let first = server(&charts, &config, 47201);
    // Nothing kept yet: the defaults, and no file written by reading.
    assert_eq!(read(&first).await, Settings::default());
    assert!(!config.exists(), "reading writes nothing");

    let a = store(&first, json!({ "language": "de", "recent": [chart, "/elsewhere/other.st"] })).await;
    assert_eq!(a.status, 200, "{}", a.text);
    let whole: Settings = serde_json::from_value(a.body).unwrap();
    assert_eq!(whole.language.as_deref(), Some("de"));
    assert_eq!(whole.recent, [chart.as_str(), "/elsewhere/other.st"]);
    // A partial update merges: the language and the recent list stay.
    let a = store(&first, json!({ "watch": { "Seed": ["Start", "Count"], "Other": ["X"] } })).await;
    assert_eq!(a.status, 200, "{}", a.text);
    let after = read(&first).await;
    assert_eq!(after.language.as_deref(), Some("de"));
    assert_eq!(after.recent.len(), 2);
    assert_eq!(after.watch["Seed"], ["Start", "Count"]);
    assert_eq!(entries(&config), ["editor.json"], "written through a temporary file renamed over it");
    let on_disk: Value = serde_json::from_str(&std::fs::read_to_string(config.join("editor.json")).unwrap()).unwrap();
    assert_eq!(on_disk["language"], "de");

    // Another run of the editor, on another port, with its own token: the same settings.
    let second = server(&charts, &config, 47202);
    assert_ne!(second.token(), first.token());
    assert_eq!(read(&second).await, after);
    // A watch list removed with null, the language cleared with null.
    let a = store(&second, json!({ "watch": { "Other": null }, "language": null })).await;
    assert_eq!(a.status, 200, "{}", a.text);
    let now = read(&first).await;
    assert_eq!(now.language, None);
    assert_eq!(now.watch.keys().collect::<Vec<_>>(), ["Seed"]);

    // A recent chart outside what this session serves is only listed: opening it is refused.
    let a = post_on(&second, "/api/open", serde_json::to_vec(&json!({ "path": "/elsewhere/other.st" })).unwrap()).await;
    assert_eq!(a.status, 403, "{}", a.text);
}

#[tokio::test]
async fn settings_need_the_token_and_the_host() {
    let charts = scratch_with("settings-guard-charts", &["seed.st"]);
    let config = scratch("settings-guard-config");
    let s = server(&charts, &config, 47203);
    let host = format!("127.0.0.1:{}", s.port());
    let no_token =
        send(&s, Call { method: "GET", uri: "/api/settings", host: Some(&host), token: None, body: None }).await;
    assert_eq!(no_token.status, 403);
    let body = Some(br#"{"language":"cs"}"#.to_vec());
    let no_token = send(&s, Call { method: "POST", uri: "/api/settings", host: Some(&host), token: None, body }).await;
    assert_eq!(no_token.status, 403);
    let body = Some(br#"{"language":"cs"}"#.to_vec());
    let wrong_host = send(
        &s,
        Call { method: "POST", uri: "/api/settings", host: Some("evil.example:47203"), token: Some(s.token()), body },
    )
    .await;
    assert_eq!(wrong_host.status, 403);
    assert!(entries(&config).is_empty(), "nothing was written");
}

#[tokio::test]
async fn settings_are_bounded() {
    let charts = scratch_with("settings-bounds-charts", &["seed.st"]);
    let config = scratch("settings-bounds-config");
    let s = server(&charts, &config, 47204);
    let recent: Vec<String> = (0..20).map(|k| format!("/charts/c{k}.st")).collect();
    assert_eq!(store(&s, json!({ "recent": recent })).await.status, 200, "20 recent charts are kept");
    let recent: Vec<String> = (0..21).map(|k| format!("/charts/c{k}.st")).collect();
    let a = store(&s, json!({ "recent": recent })).await;
    assert_eq!(a.status, 422, "{}", a.text);
    assert!(a.body["error"].as_str().unwrap().contains("at most 20"), "{}", a.text);
    let names: Vec<String> = (0..200).map(|k| format!("V{k}")).collect();
    assert_eq!(store(&s, json!({ "watch": { "P": names } })).await.status, 200, "200 names are kept");
    let names: Vec<String> = (0..201).map(|k| format!("V{k}")).collect();
    let a = store(&s, json!({ "watch": { "P": names } })).await;
    assert_eq!(a.status, 422, "{}", a.text);
    let a = store(&s, json!({ "language": "<script>" })).await;
    assert_eq!(a.status, 422, "{}", a.text);
    let a = store(&s, json!({ "colour": "red" })).await;
    assert_eq!(a.status, 400, "unknown fields are refused: {}", a.text);
    // A body over 1 MiB, and settings that would grow the file over 1 MiB, are refused.
    let big = json!({ "watch": { "P": [ "x".repeat(1 << 20) ] } });
    let a = store(&s, big).await;
    assert_eq!(a.status, 413, "{}", a.text);
    let name = "n".repeat(1000);
    let mut added = 0;
    let status = loop {
        let lists: serde_json::Map<String, Value> =
            (0..4).map(|k| (format!("Chart{added}_{k}"), json!(vec![name.clone(); 60]))).collect();
        let a = store(&s, json!({ "watch": lists })).await;
        if a.status != 200 {
            break a.status;
        }
        added += 1;
        assert!(added < 10, "the file stays under 1 MiB");
    };
    assert_eq!(status, 413);
    // What was refused was not written: the file is still whole and within the bound.
    let kept = read(&s).await;
    assert_eq!(kept.recent.len(), 20);
    assert_eq!(kept.watch["P"].len(), 200);
    assert!(std::fs::metadata(config.join("editor.json")).unwrap().len() <= 1 << 20);
}

#[tokio::test]
async fn a_corrupt_settings_file_is_set_aside_and_replaced_by_the_defaults() {
    let charts = scratch_with("settings-corrupt-charts", &["seed.st"]);
    let config = scratch("settings-corrupt-config");
    std::fs::write(config.join("editor.json"), "{\"language\": \"de\", \"recent\": [").unwrap();
    let s = server(&charts, &config, 47205);
    assert_eq!(read(&s).await, Settings::default());
    assert_eq!(entries(&config), ["editor.json.corrupt"], "kept aside for the user");
    let a = store(&s, json!({ "language": "cs" })).await;
    assert_eq!(a.status, 200, "{}", a.text);
    assert_eq!(read(&s).await.language.as_deref(), Some("cs"));
    // Wrong types are corrupt too; a file larger than the bound as well.
    std::fs::write(config.join("editor.json"), r#"{"recent": "not a list"}"#).unwrap();
    assert_eq!(read(&s).await, Settings::default());
    std::fs::write(config.join("editor.json"), vec![b' '; (1 << 20) + 1]).unwrap();
    assert_eq!(read(&s).await, Settings::default());
    // A file of a newer editor (more fields) or edited by hand (longer lists) is read.
    let recent: Vec<String> = (0..30).map(|k| format!("/c{k}.st")).collect();
    std::fs::write(
        config.join("editor.json"),
        json!({ "language": "de", "recent": recent, "theme": "dark" }).to_string(),
    )
    .unwrap();
    let read_back = read(&s).await;
    assert_eq!(read_back.language.as_deref(), Some("de"));
    assert_eq!(read_back.recent.len(), 20);
}

#[tokio::test]
async fn without_a_config_directory_the_calls_fail_and_the_server_keeps_serving() {
    let charts = scratch_with("settings-none-charts", &["seed.st"]);
    let config = scratch("settings-none-config");
    // A file where the directory should be: it cannot be created.
    let blocked = config.join("file");
    std::fs::write(&blocked, "").unwrap();
    let s = server(&charts, &blocked.join("sfc"), 47206);
    let a = store(&s, json!({ "language": "de" })).await;
    assert_eq!(a.status, 500, "{}", a.text);
    assert!(a.body["error"].as_str().unwrap().contains("cannot keep the settings"), "{}", a.text);
    assert_eq!(get_on(&s, "/api/session").await.status, 200);
}
