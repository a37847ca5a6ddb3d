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
    for word in ["--port", "--no-open", "--fb", "--nstep", "--ntr", "--result"] {
        assert!(help.contains(word), "{word} in {help}");
    }
}
