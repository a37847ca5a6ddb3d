//! `sfc edit`: the URL line on stdout, a real HTTP exchange with the running server (plain
//! HTTP/1.1 over a TCP socket), and the usage errors (exit 2).

use std::io::{BufRead, BufReader, Read, Write};
use std::net::TcpStream;
use std::path::PathBuf;
use std::process::{Child, Command, Stdio};
use std::time::Duration;

fn temp_dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("sfc-edit-test-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    std::fs::canonicalize(&d).unwrap()
}

/// Kills the server when the test ends, also when it fails.
struct Server(Child);

impl Drop for Server {
    fn drop(&mut self) {
        let _ = self.0.kill();
        let _ = self.0.wait();
    }
}

/// One HTTP/1.1 request; returns the status code and the body.
fn http_get(port: u16, path: &str, host: &str, token: Option<&str>) -> (u16, String) {
    let mut s = TcpStream::connect(("127.0.0.1", port)).expect("the server accepts connections");
    s.set_read_timeout(Some(Duration::from_secs(20))).unwrap();
    let token = token.map(|t| format!("X-Sfc-Token: {t}\r\n")).unwrap_or_default();
    write!(s, "GET {path} HTTP/1.1\r\nHost: {host}\r\n{token}Connection: close\r\n\r\n").unwrap();
    let mut raw = String::new();
    s.read_to_string(&mut raw).expect("an answer");
    let (head, body) = raw.split_once("\r\n\r\n").expect("headers end");
    let status = head.split(' ').nth(1).and_then(|c| c.parse().ok()).expect("a status line");
    (status, body.to_string())
}

#[test]
fn edit_prints_the_url_and_serves_the_api() {
    let d = temp_dir("serve");
    std::fs::write(d.join("chart.st"), "PROGRAM P\nEND_PROGRAM\n").unwrap();
    let child = Command::new(env!("CARGO_BIN_EXE_sfc"))
        .args(["edit", "--no-open", "--port", "0"])
        .arg(&d)
        .stdout(Stdio::piped())
        .stderr(Stdio::null())
        .spawn()
        .expect("sfc runs");
    let mut server = Server(child);
    let mut line = String::new();
    BufReader::new(server.0.stdout.take().unwrap()).read_line(&mut line).unwrap();
    let url = line.trim_end().strip_prefix("SFC Editor: ").unwrap_or_else(|| panic!("URL line, got {line:?}"));
    let rest = url.strip_prefix("http://127.0.0.1:").expect("loopback URL");
    let (port, token) = rest.split_once("/?token=").expect("token in the URL");
    let port: u16 = port.parse().unwrap();
    assert_eq!(token.len(), 32);
    assert!(token.chars().all(|c| c.is_ascii_hexdigit()));
    let host = format!("127.0.0.1:{port}");

    let (status, body) = http_get(port, "/api/session", &host, None);
    assert_eq!(status, 403, "{body}");
    let (status, body) = http_get(port, "/api/session", &host, Some(token));
    assert_eq!(status, 200, "{body}");
    let session: serde_json::Value = serde_json::from_str(&body).unwrap();
    assert_eq!(session["mode"], "mdi");
    assert_eq!(session["roots"], serde_json::json!([d.to_str().unwrap()]));
    let (status, _) = http_get(port, "/api/session", &format!("evil.example:{port}"), Some(token));
    assert_eq!(status, 403);
    let (status, body) = http_get(port, "/api/files", &host, Some(token));
    assert_eq!(status, 200);
    assert!(body.contains("chart.st"), "{body}");
    let (status, _) = http_get(port, "/", &host, None);
    assert_eq!(status, 200);
    // It keeps serving until it is stopped.
    assert!(server.0.try_wait().unwrap().is_none());
}

#[test]
fn edit_usage_errors_exit_2() {
    let d = temp_dir("usage");
    let file = d.join("chart.st");
    let file = file.to_str().unwrap();
    let result = d.join("result.txt");
    let result = result.to_str().unwrap();
    let run = |args: &[&str]| Command::new(env!("CARGO_BIN_EXE_sfc")).arg("edit").args(args).output().unwrap();
    for args in [
        vec!["--fb", "atmt", file],
        vec!["--result", result, file],
        vec!["--nstep", "4", file],
        vec!["--fb", "plc", "--result", result, file],
        vec!["--fb", "atmt", "--result", result],
        vec!["--fb", "atmt", "--result", result, file, file],
        vec!["--fb", "atmt", "--result", "/no/such/dir/result.txt", file],
        vec!["--no-open", "/no/such/dir/chart.st"],
    ] {
        let out = run(&args);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {}", String::from_utf8_lossy(&out.stderr));
        assert!(!out.stderr.is_empty(), "{args:?} explains");
        assert!(out.stdout.is_empty(), "{args:?} prints no URL");
    }
    let out = run(&["--help"]);
    assert_eq!(out.status.code(), Some(0));
    let help = String::from_utf8_lossy(&out.stdout);
    for word in ["--port", "--no-open", "--fb", "--nstep", "--ntr", "--result", "SFC_CONFIG_DIR"] {
        assert!(help.contains(word), "{word} in {help}");
    }
}

/// One HTTP/1.1 request with extra header lines; returns the status, the head and the body.
fn http(port: u16, method: &str, path: &str, headers: &[String], body: &str) -> (u16, String, String) {
    let mut s = TcpStream::connect(("127.0.0.1", port)).expect("the server accepts connections");
    s.set_read_timeout(Some(Duration::from_secs(20))).unwrap();
    let mut req = format!("{method} {path} HTTP/1.1\r\nHost: 127.0.0.1:{port}\r\nConnection: close\r\n");
    for h in headers {
        req.push_str(h);
        req.push_str("\r\n");
    }
    if !body.is_empty() {
        req.push_str(&format!("Content-Type: application/json\r\nContent-Length: {}\r\n", body.len()));
    }
    req.push_str("\r\n");
    req.push_str(body);
    s.write_all(req.as_bytes()).unwrap();
    let mut raw = String::new();
    s.read_to_string(&mut raw).expect("an answer");
    let (head, body) = raw.split_once("\r\n\r\n").expect("headers end");
    let status = head.split(' ').nth(1).and_then(|c| c.parse().ok()).expect("a status line");
    (status, head.to_string(), body.to_string())
}

/// Starts `sfc edit ARGS` with `envs` and returns it with its port and token.
fn start(args: &[&std::ffi::OsStr], envs: &[(&str, &std::ffi::OsStr)]) -> (Server, u16, String) {
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_sfc"));
    cmd.arg("edit").args(["--port", "0"]).args(args).stdout(Stdio::piped()).stderr(Stdio::null());
    for (k, v) in envs {
        cmd.env(k, v);
    }
    let mut server = Server(cmd.spawn().expect("sfc runs"));
    let mut line = String::new();
    BufReader::new(server.0.stdout.take().unwrap()).read_line(&mut line).unwrap();
    let rest = line.trim_end().strip_prefix("SFC Editor: http://127.0.0.1:").expect("URL line");
    let (port, token) = rest.split_once("/?token=").expect("token in the URL");
    (server, port.parse().unwrap(), token.to_string())
}

#[test]
fn the_printed_url_is_exchanged_for_an_http_only_cookie() {
    let d = temp_dir("cookie");
    std::fs::write(d.join("chart.st"), "PROGRAM P\nEND_PROGRAM\n").unwrap();
    let (_server, port, token) = start(&["--no-open".as_ref(), d.as_os_str()], &[]);
    // The printed URL: a redirect to `/` that sets the cookie, so the address drops the token.
    let (status, head, _) = http(port, "GET", &format!("/?token={token}"), &[], "");
    assert_eq!(status, 303, "{head}");
    let head_lower = head.to_ascii_lowercase();
    assert!(head_lower.contains("\r\nlocation: /\r\n"), "{head}");
    let cookie_line = head.lines().find(|l| l.to_ascii_lowercase().starts_with("set-cookie:")).expect("a cookie");
    let cookie = format!("sfc_token_{port}={token}");
    assert!(cookie_line.contains(&cookie), "{cookie_line}");
    assert!(cookie_line.contains("HttpOnly") && cookie_line.contains("SameSite=Strict"), "{cookie_line}");
    // A wrong token sets nothing.
    let (status, head, _) = http(port, "GET", "/?token=00000000000000000000000000000000", &[], "");
    assert_eq!(status, 403);
    assert!(!head.to_ascii_lowercase().contains("set-cookie"), "{head}");
    // The page's calls: the cookie with the page header; the cookie alone (a form or an image
    // of another page could send it) is refused.
    let with_cookie = format!("Cookie: {cookie}");
    let (status, _, body) = http(port, "GET", "/api/session", &[with_cookie.clone(), "X-Sfc-Page: 1".into()], "");
    assert_eq!(status, 200, "{body}");
    let (status, _, _) = http(port, "GET", "/api/session", std::slice::from_ref(&with_cookie), "");
    assert_eq!(status, 403);
    let (status, _, _) = http(port, "GET", "/api/session", &["X-Sfc-Page: 1".into()], "");
    assert_eq!(status, 403);
}

#[test]
fn a_named_file_is_served_alone() {
    let d = temp_dir("alone");
    let chart = d.join("chart.st");
    std::fs::write(&chart, "PROGRAM P\nEND_PROGRAM\n").unwrap();
    std::fs::write(d.join("other.st"), "PROGRAM Q\nEND_PROGRAM\n").unwrap();
    std::fs::create_dir_all(d.join(".hidden")).unwrap();
    std::fs::write(d.join(".hidden/secret.st"), "PROGRAM S\nEND_PROGRAM\n").unwrap();
    let (_server, port, token) = start(&["--no-open".as_ref(), chart.as_os_str()], &[]);
    let auth = [format!("X-Sfc-Token: {token}")];
    let (status, _, body) = http(port, "GET", "/api/files", &auth, "");
    assert_eq!(status, 200);
    let files: serde_json::Value = serde_json::from_str(&body).unwrap();
    assert_eq!(files["files"], serde_json::json!([{ "path": chart.to_str().unwrap(), "format": "st" }]));
    let open =
        |p: &std::path::Path| http(port, "POST", "/api/open", &auth, &serde_json::json!({ "path": p }).to_string());
    assert_eq!(open(&chart).0, 200);
    for p in [d.join("other.st"), d.join("new.st"), d.join(".hidden/secret.st")] {
        let (status, _, body) = open(&p);
        assert_eq!(status, 403, "{}: {body}", p.display());
    }
    // A directory serves its charts, but not those in hidden directories.
    let (_server, port, token) = start(&["--no-open".as_ref(), d.as_os_str()], &[]);
    let auth = [format!("X-Sfc-Token: {token}")];
    let open =
        |p: &std::path::Path| http(port, "POST", "/api/open", &auth, &serde_json::json!({ "path": p }).to_string());
    assert_eq!(open(&d.join("other.st")).0, 200);
    assert_eq!(open(&d.join(".hidden/secret.st")).0, 403);
}

/// The server opens the named chart ahead of the page's request; the page gets the file as it
/// is when it asks, also when it changed in between.
#[test]
fn the_named_chart_opened_ahead_is_the_file_as_it_is_when_asked() {
    let d = temp_dir("ahead");
    let chart = d.join("chart.st");
    let text = |step: &str| {
        format!(
            "PROGRAM P\n    VAR Go : BOOL; END_VAR\n    INITIAL_STEP Start: END_STEP\n    STEP {step}: END_STEP\n    \
             TRANSITION FROM Start TO {step} := Go; END_TRANSITION\n    TRANSITION FROM {step} TO Start := NOT Go; END_TRANSITION\nEND_PROGRAM\n"
        )
    };
    let steps = |body: &str| -> Vec<String> {
        let v: serde_json::Value = serde_json::from_str(body).unwrap();
        let mut names: Vec<String> = v["charts"][0]["elements"]
            .as_array()
            .expect("elements")
            .iter()
            .filter(|e| e["kind"] == "step")
            .map(|e| e["name"].as_str().unwrap().to_string())
            .collect();
        names.sort();
        names
    };
    std::fs::write(&chart, text("Fill")).unwrap();
    let (_server, port, token) = start(&["--no-open".as_ref(), chart.as_os_str()], &[]);
    let auth = [format!("X-Sfc-Token: {token}")];
    let open = || http(port, "POST", "/api/open", &auth, &serde_json::json!({ "path": chart }).to_string());
    // Changed on disk (same length) before the page asked: the new text is opened.
    std::fs::write(&chart, text("Wash")).unwrap();
    let (status, _, changed) = open();
    assert_eq!(status, 200, "{changed}");
    assert_eq!(steps(&changed), ["Start", "Wash"], "{changed}");
    // Asked again, unchanged: the same answer as a fresh start gives.
    let (status, _, again) = open();
    assert_eq!(status, 200);
    assert_eq!(again, changed);
    let (_fresh, port2, token2) = start(&["--no-open".as_ref(), chart.as_os_str()], &[]);
    let (status, _, fresh) = http(
        port2,
        "POST",
        "/api/open",
        &[format!("X-Sfc-Token: {token2}")],
        &serde_json::json!({ "path": chart }).to_string(),
    );
    assert_eq!(status, 200);
    assert_eq!(fresh, changed);
}

/// The browser is started on a private file that forwards to the URL: the token is in no
/// process's arguments.
#[cfg(unix)]
#[test]
fn the_browser_is_opened_without_the_token_in_its_arguments() {
    use std::os::unix::fs::PermissionsExt;
    let d = temp_dir("launch");
    let bin = d.join("bin");
    std::fs::create_dir_all(&bin).unwrap();
    let record = d.join("args.txt");
    let copy = d.join("page.html");
    // A stand-in for xdg-open: records its arguments and copies the page it was given.
    let script = format!(
        "#!/bin/sh\nprintf '%s\\n' \"$@\" > '{}'\nstat -c %a \"$1\" >> '{}'\ncp \"$1\" '{}'\n",
        record.display(),
        record.display(),
        copy.display()
    );
    std::fs::write(bin.join("xdg-open"), script).unwrap();
    std::fs::set_permissions(bin.join("xdg-open"), std::fs::Permissions::from_mode(0o755)).unwrap();
    let path = format!("{}:{}", bin.display(), std::env::var("PATH").unwrap_or_default());
    let (server, _port, token) = start(
        &[d.as_os_str()],
        &[("DISPLAY", ":99".as_ref()), ("PATH", path.as_ref()), ("WAYLAND_DISPLAY", "".as_ref())],
    );
    let mut waited = 0;
    while !copy.exists() && waited < 200 {
        std::thread::sleep(Duration::from_millis(50));
        waited += 1;
    }
    let args = std::fs::read_to_string(&record).expect("the browser was started");
    let mut lines = args.lines();
    let page = lines.next().unwrap();
    assert!(!args.contains(&token), "the token is not in the browser's arguments: {args}");
    assert!(page.ends_with("open.html"), "{page}");
    assert_eq!(lines.next(), Some("600"), "the page is readable by the user alone");
    let html = std::fs::read_to_string(&copy).unwrap();
    assert!(html.contains(&token), "the page forwards to the URL: {html}");
    // The page goes when the editor stops.
    drop(server);
}

/// The editor's settings are kept in `SFC_CONFIG_DIR` (the tests never touch the real home), so
/// a later run on another port reads what an earlier one stored; a corrupt file is reported
/// once on stderr and the server keeps serving.
#[test]
fn settings_are_kept_in_the_config_directory_across_runs() {
    let d = temp_dir("settings");
    std::fs::write(d.join("chart.st"), "PROGRAM P\nEND_PROGRAM\n").unwrap();
    let config = d.join("config");
    let chart = d.join("chart.st");
    let env = [("SFC_CONFIG_DIR", config.as_os_str())];
    let (first, port, token) = start(&["--no-open".as_ref(), d.as_os_str()], &env);
    let auth = [format!("X-Sfc-Token: {token}")];
    let update = serde_json::json!({ "language": "de", "recent": [chart], "watch": { "P": ["Go"] } }).to_string();
    let (status, _, body) = http(port, "POST", "/api/settings", &auth, &update);
    assert_eq!(status, 200, "{body}");
    let (status, _, _) = http(port, "POST", "/api/settings", &[], &update);
    assert_eq!(status, 403, "the token is needed");
    drop(first);
    assert!(config.join("editor.json").is_file());

    let (_second, port2, token2) = start(&["--no-open".as_ref(), d.as_os_str()], &env);
    assert_ne!(port2, port);
    let (status, _, body) = http(port2, "GET", "/api/settings", &[format!("X-Sfc-Token: {token2}")], "");
    assert_eq!(status, 200, "{body}");
    let settings: serde_json::Value = serde_json::from_str(&body).unwrap();
    assert_eq!(
        settings,
        serde_json::json!({ "language": "de", "recent": [chart], "watch": { "P": ["Go"] } }),
        "{body}"
    );

    // A corrupt file: said once on stderr (however often the page asks), defaults answered.
    std::fs::write(config.join("editor.json"), "{ not json").unwrap();
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_sfc"));
    cmd.args(["edit", "--no-open", "--port", "0"]).arg(&d).env("SFC_CONFIG_DIR", &config);
    let mut server = Server(cmd.stdout(Stdio::piped()).stderr(Stdio::piped()).spawn().expect("sfc runs"));
    let mut line = String::new();
    BufReader::new(server.0.stdout.take().unwrap()).read_line(&mut line).unwrap();
    let rest = line.trim_end().strip_prefix("SFC Editor: http://127.0.0.1:").expect("URL line");
    let (port3, token3) = rest.split_once("/?token=").expect("token in the URL");
    let port3: u16 = port3.parse().unwrap();
    let auth3 = [format!("X-Sfc-Token: {token3}")];
    for _ in 0..2 {
        // The second read finds the file set aside; write a corrupt one again.
        let (status, _, body) = http(port3, "GET", "/api/settings", &auth3, "");
        assert_eq!(status, 200, "{body}");
        assert_eq!(body, r#"{"recent":[],"watch":{}}"#);
        std::fs::write(config.join("editor.json"), "{ not json").unwrap();
    }
    assert!(config.join("editor.json.corrupt").is_file(), "the corrupt file is kept aside");
    let _ = server.0.kill();
    let _ = server.0.wait();
    let mut stderr = String::new();
    server.0.stderr.take().unwrap().read_to_string(&mut stderr).unwrap();
    assert_eq!(stderr.matches("settings file").count(), 1, "reported once: {stderr}");
    assert!(stderr.contains("editor.json"), "{stderr}");
}
