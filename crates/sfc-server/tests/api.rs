//! The editor's HTTP API (`docs/editor.md`) in-process: every refusal (token, Host, paths
//! outside the roots, bodies), the calls that need no document conversion and the static files.
//! The compile dispatch shared with `sfc build` is tested in `sfc-driver`.

mod common;

use common::*;
use serde_json::{json, Value};
use sfc_server::{AppState, EditOptions, HostBlock, HostMode};
use std::path::Path;

#[tokio::test]
async fn session_needs_the_token() {
    let d = scratch("session");
    let s = state(&[&d], None);
    let host = own_host();
    for token in [None, Some("0123456789abcdef0123456789abcdef"), Some("")] {
        let a = send(&s, Call { method: "GET", uri: "/api/session", host: Some(&host), token, body: None }).await;
        assert_eq!(a.status, 403, "token {token:?}");
        assert!(a.body["error"].as_str().unwrap().contains("X-Sfc-Token"), "{}", a.text);
    }
    let a = get(&s, "/api/session").await;
    assert_eq!(a.status, 200, "{}", a.text);
    assert_eq!(
        a.body,
        json!({ "mode": "mdi", "version": env!("CARGO_PKG_VERSION"), "roots": [path_str(&d)], "open": [] })
    );
    assert_eq!(a.cache_control, "no-store");
    assert!(s.url().ends_with(&format!(":{PORT}/?token={}", s.token())));
}

#[tokio::test]
async fn foreign_hosts_are_refused() {
    let d = scratch("host");
    let s = state(&[&d], None);
    let wrong_port = format!("127.0.0.1:{}", PORT + 1);
    let rebound = format!("evil.example:{PORT}");
    for (host, uri) in [
        (Some(rebound.as_str()), "/api/session"),
        (Some(wrong_port.as_str()), "/api/session"),
        (Some("127.0.0.1"), "/api/session"),
        (None, "/api/session"),
        (Some(rebound.as_str()), "/"),
    ] {
        let a = send(&s, Call { method: "GET", uri, host, token: Some(s.token()), body: None }).await;
        assert_eq!(a.status, 403, "{host:?} {uri}");
        assert!(a.body["error"].as_str().unwrap().contains("Host"), "{}", a.text);
    }
    // An absolute URI naming another site is refused even with the right Host.
    let host = own_host();
    let a = send(
        &s,
        Call {
            method: "GET",
            uri: "http://evil.example/api/session",
            host: Some(&host),
            token: Some(s.token()),
            body: None,
        },
    )
    .await;
    assert_eq!(a.status, 403);
    // Two Host headers, the first the server's own: refused (which one a check reads differs
    // between a proxy and the server).
    assert_eq!(status_with_two_hosts(&s, "/api/session", &host, &rebound).await, 403);
    assert_eq!(status_with_two_hosts(&s, "/api/session", &host, &host).await, 403);
    let localhost = format!("LOCALHOST:{PORT}");
    let a = send(
        &s,
        Call { method: "GET", uri: "/api/session", host: Some(&localhost), token: Some(s.token()), body: None },
    )
    .await;
    assert_eq!(a.status, 200);
}

#[tokio::test]
async fn static_files_need_no_token() {
    let s = state(&[&scratch("static")], None);
    let host = own_host();
    let a = send(&s, Call { method: "GET", uri: "/", host: Some(&host), token: None, body: None }).await;
    assert_eq!(a.status, 200);
    assert!(a.content_type.starts_with("text/html"), "{}", a.content_type);
    assert_eq!(a.cache_control, "no-store");
    let built = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../web/dist/index.html").exists();
    if built {
        let page =
            std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("../../web/dist/index.html")).unwrap();
        assert_eq!(a.text, page);
        // Vite's bundles: their type, and cached for good (their names carry a content hash).
        let assets = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../web/dist/assets");
        let js = std::fs::read_dir(&assets)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .find(|n| n.ends_with(".js"))
            .expect("a bundle");
        let uri = format!("/assets/{js}");
        let a = send(&s, Call { method: "GET", uri: &uri, host: Some(&host), token: None, body: None }).await;
        assert_eq!(a.status, 200);
        assert!(a.content_type.contains("javascript"), "{}", a.content_type);
        assert!(a.cache_control.contains("immutable"));
        assert_eq!(a.text, std::fs::read_to_string(assets.join(&js)).unwrap());
    } else {
        assert!(
            a.text.contains("npm ci && npm run build") || a.text.contains("npm ci &amp;&amp; npm run build"),
            "{}",
            a.text
        );
    }
    let a = send(&s, Call { method: "GET", uri: "/no/such/file.js", host: Some(&host), token: None, body: None }).await;
    assert_eq!(a.status, 404);
    let a = send(&s, Call { method: "GET", uri: "/../Cargo.toml", host: Some(&host), token: None, body: None }).await;
    assert_eq!(a.status, 404);
    let a = send(&s, Call { method: "POST", uri: "/", host: Some(&host), token: None, body: None }).await;
    assert_eq!(a.status, 405);
}

#[tokio::test]
async fn unknown_calls_and_methods() {
    let s = state(&[&scratch("unknown")], None);
    let a = get(&s, "/api/nothing").await;
    assert_eq!(a.status, 404);
    assert!(a.body["error"].as_str().unwrap().contains("/api/nothing"));
    let a = get(&s, "/api/open").await;
    assert_eq!(a.status, 405);
    assert!(a.body["error"].is_string(), "{}", a.text);
    // Without the token, an unknown call is refused like a known one.
    let host = own_host();
    let a = send(&s, Call { method: "GET", uri: "/api/nothing", host: Some(&host), token: None, body: None }).await;
    assert_eq!(a.status, 403);
}

#[tokio::test]
async fn files_lists_charts_under_the_roots() {
    let d = scratch("files");
    for f in ["a.st", "sub/b.XML", "sub/deeper/c.st", "target/t.st", "node_modules/m.st", ".git/h.st", "notes.txt"] {
        let p = d.join(f);
        std::fs::create_dir_all(p.parent().unwrap()).unwrap();
        std::fs::write(p, "").unwrap();
    }
    let outside = scratch("files-outside");
    std::fs::write(outside.join("o.st"), "").unwrap();
    #[cfg(unix)]
    {
        std::os::unix::fs::symlink(&outside, d.join("linked_dir")).unwrap();
        std::os::unix::fs::symlink(outside.join("o.st"), d.join("linked_out.st")).unwrap();
        std::os::unix::fs::symlink(d.join("a.st"), d.join("linked_in.st")).unwrap();
    }
    let s = state(&[&d], None);
    let a = get(&s, "/api/files").await;
    assert_eq!(a.status, 200, "{}", a.text);
    let mut expected = vec![json!({"path": path_str(&d.join("a.st")), "format": "st"})];
    if cfg!(unix) {
        expected.push(json!({"path": path_str(&d.join("linked_in.st")), "format": "st"}));
    }
    expected.push(json!({"path": path_str(&d.join("sub/b.XML")), "format": "xml"}));
    expected.push(json!({"path": path_str(&d.join("sub/deeper/c.st")), "format": "st"}));
    assert_eq!(a.body, json!({ "files": expected }));
}

#[tokio::test]
async fn open_refuses_paths_outside_the_roots() {
    let base = scratch("confine");
    let root = base.join("root");
    std::fs::create_dir_all(root.join("sub")).unwrap();
    std::fs::write(base.join("secret.st"), "PROGRAM Secret END_PROGRAM\n").unwrap();
    std::fs::write(root.join("notes.txt"), "not a chart").unwrap();
    std::fs::create_dir_all(root.join("folder.st")).unwrap();
    #[cfg(unix)]
    {
        std::os::unix::fs::symlink(&base, root.join("up")).unwrap();
        std::os::unix::fs::symlink(base.join("secret.st"), root.join("escape.st")).unwrap();
    }
    let s = state(&[&root], None);
    let open = |p: String| json!({ "path": p });
    let cases: Vec<(String, u16)> = vec![
        (path_str(&base.join("secret.st")), 403),
        (format!("{}/sub/../../secret.st", path_str(&root)), 403),
        (format!("{}/../secret.st", path_str(&root)), 403),
        ("/etc/passwd".to_string(), 403),
        (path_str(&root.join("notes.txt")), 403),
        ("secret.st".to_string(), 400),
        (String::new(), 400),
        (path_str(&root.join("missing.st")), 404),
        (path_str(&root.join("folder.st")), 400),
    ];
    for (path, status) in cases {
        let a = post(&s, "/api/open", &open(path.clone())).await;
        assert_eq!(a.status, status, "{path}: {}", a.text);
        assert!(a.body["error"].is_string(), "{path}: {}", a.text);
    }
    #[cfg(unix)]
    for link in ["up/secret.st", "escape.st"] {
        let a = post(&s, "/api/open", &open(path_str(&root.join(link)))).await;
        assert_eq!(a.status, 403, "{link}: {}", a.text);
    }
}

#[tokio::test]
async fn bad_bodies_get_400_and_large_ones_413() {
    let d = scratch("bodies");
    let s = state(&[&d], None);
    for call in ["/api/open", "/api/save", "/api/check", "/api/build", "/api/layout", "/api/new"] {
        let a = post_raw(&s, call, b"{\"path\": ".to_vec()).await;
        assert_eq!(a.status, 400, "{call}: {}", a.text);
        let msg = a.body["error"].as_str().unwrap();
        assert!(msg.contains("line 1 column"), "{call}: {msg}");
        let a = post_raw(&s, call, b"[1, 2]".to_vec()).await;
        assert_eq!(a.status, 400, "{call}: {}", a.text);
    }
    let a = post(&s, "/api/open", &json!({ "path": 3 })).await;
    assert_eq!(a.status, 400);
    assert!(a.body["error"].as_str().unwrap().contains("invalid type"), "{}", a.text);
    let mut big = b"{\"path\": \"".to_vec();
    big.resize(sfc_server::MAX_BODY + 1024, b'a');
    big.extend_from_slice(b"\"}");
    let a = post_raw(&s, "/api/open", big).await;
    assert_eq!(a.status, 413, "{}", &a.text[..a.text.len().min(200)]);
    assert!(a.body["error"].is_string());
}

#[tokio::test]
async fn save_refusals_and_conflicts() {
    let d = scratch("save");
    let outside = scratch("save-outside");
    let chart = d.join("chart.st");
    let original = "PROGRAM Chart\nEND_PROGRAM\n";
    std::fs::write(&chart, original).unwrap();
    let s = state(&[&d], None);
    let save = |path: &Path, hash: Value| json!({ "path": path_str(path), "format": "st", "doc": small_doc("Chart"), "hash": hash });
    // The file changed on disk since it was opened (another hash), or exists though the page
    // thinks it new: 409, nothing written.
    for hash in [json!("0000000000000000"), Value::Null] {
        let a = post(&s, "/api/save", &save(&chart, hash.clone())).await;
        assert_eq!(a.status, 409, "{hash}: {}", a.text);
        assert_eq!(a.body["conflict"], true);
        assert!(a.body["error"].is_string());
    }
    // Deleted since it was opened: also a conflict.
    let a = post(&s, "/api/save", &save(&d.join("gone.st"), json!(sfc_server::content_hash(b"x")))).await;
    assert_eq!(a.status, 409, "{}", a.text);
    assert_eq!(std::fs::read_to_string(&chart).unwrap(), original);
    assert_eq!(entries(&d), ["chart.st"]);
    // Outside the roots, and files that are not charts.
    let a = post(&s, "/api/save", &save(&outside.join("x.st"), Value::Null)).await;
    assert_eq!(a.status, 403);
    let a = post(&s, "/api/save", &save(&d.join("script.sh"), Value::Null)).await;
    assert_eq!(a.status, 403);
    #[cfg(unix)]
    {
        std::os::unix::fs::symlink(&outside, d.join("out")).unwrap();
        let a = post(&s, "/api/save", &save(&d.join("out/x.st"), Value::Null)).await;
        assert_eq!(a.status, 403);
        assert!(!outside.join("x.st").exists());
    }
    // A POU name that is not an identifier cannot be written into the text.
    let mut bad = save(&d.join("new.st"), Value::Null);
    bad["doc"]["pou"] = json!("P\nEND_PROGRAM");
    let a = post(&s, "/api/save", &bad).await;
    assert_eq!(a.status, 400, "{}", a.text);
    // A new file in a directory that does not exist: not created.
    let a = post(&s, "/api/save", &save(&d.join("no/such/dir/x.st"), Value::Null)).await;
    assert_eq!(a.status, 404, "{}", a.text);
    // An unknown format.
    let mut bad = save(&d.join("new.st"), Value::Null);
    bad["format"] = json!("docx");
    assert_eq!(post(&s, "/api/save", &bad).await.status, 400);
    assert!(!d.join("new.st").exists());
}

#[tokio::test]
async fn codes_lists_the_registry() {
    let s = state(&[&scratch("codes")], None);
    let a = get(&s, "/api/codes").await;
    assert_eq!(a.status, 200);
    let list = a.body.as_array().unwrap();
    assert_eq!(list.len(), sfc_diagnostics::CODES.len());
    assert!(list.contains(&json!({ "code": "SFC0101", "severity": "error", "title": "syntax error" })));
}

#[tokio::test]
async fn build_and_new_refuse_bad_requests() {
    let s = state(&[&scratch("badbuild")], None);
    let a = post(&s, "/api/build", &json!({ "doc": small_doc("P"), "target": "exe" })).await;
    assert_eq!(a.status, 400);
    assert!(a.body["error"].as_str().unwrap().contains("atmt, eatmt, st, stl, plcopen, svg, text"), "{}", a.text);
    let a = post(&s, "/api/new", &json!({ "name": "1st", "target": "atmt" })).await;
    assert_eq!(a.status, 400, "{}", a.text);
    let a = post(&s, "/api/new", &json!({ "name": "Ok", "target": "plc" })).await;
    assert_eq!(a.status, 400, "{}", a.text);
}

#[test]
fn host_mode_sessions() {
    let d = scratch("hostmode");
    let chart = d.join("new_chart.st");
    let host =
        |result: &Path| HostMode { fb: HostBlock::Eatmt, nstep: None, ntr: Some(100), result: result.to_path_buf() };
    // One chart (it may not exist yet), the block's limits unless given.
    let s = state(&[&chart], Some(host(&d.join("result.txt"))));
    let rt = tokio::runtime::Builder::new_current_thread().build().unwrap();
    let a = rt.block_on(get(&s, "/api/session"));
    assert_eq!(
        a.body,
        json!({
            "mode": "host", "version": env!("CARGO_PKG_VERSION"), "roots": [], "open": [path_str(&chart)],
            "host": { "fb": "eatmt", "nstep": 256, "ntr": 100, "file": path_str(&chart), "result": path_str(&d.join("result.txt")) }
        })
    );
    // A file that does not exist yet: 404, and the page creates the chart with `new`.
    let a = rt.block_on(post(&s, "/api/open", &json!({ "path": path_str(&chart) })));
    assert_eq!(a.status, 404, "{}", a.text);
    let bad = |files: Vec<&Path>, result: &Path| {
        let opts = EditOptions {
            files: files.iter().map(|p| p.to_path_buf()).collect(),
            port: None,
            host: Some(host(result)),
        };
        AppState::new(&opts, PORT).expect_err("refused")
    };
    assert!(bad(vec![&chart, &d.join("other.st")], &d.join("r.txt")).contains("exactly one"));
    assert!(bad(vec![&d], &d.join("r.txt")).contains("exactly one"));
    assert!(bad(vec![&chart], &d.join("no/such/dir/r.txt")).contains("--result"));
    assert!(bad(vec![&chart], &d).contains("--result"));
}
