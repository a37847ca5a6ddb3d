//! `sfc run` as a user runs it: the real binary on the car wash, its monitor URL on standard
//! error, a WebSocket client speaking the monitor protocol (a minimal RFC 6455 client over a
//! TCP socket), the exit status and the printed statistics.

use std::io::{BufRead, BufReader, Read, Write};
use std::net::TcpStream;
use std::path::PathBuf;
use std::process::{Child, Command, Stdio};
use std::sync::mpsc;
use std::time::Duration;

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../..")
}

/// Kills the run when the test ends, also when it fails.
struct Run(Option<Child>);

impl Drop for Run {
    fn drop(&mut self) {
        if let Some(c) = &mut self.0 {
            let _ = c.kill();
            let _ = c.wait();
        }
    }
}

/// Standard error of a child, line by line, read on a thread.
fn lines_of(child: &mut Child) -> mpsc::Receiver<String> {
    let err = child.stderr.take().unwrap();
    let (tx, rx) = mpsc::channel();
    std::thread::spawn(move || {
        for line in BufReader::new(err).lines() {
            let Ok(line) = line else { return };
            if tx.send(line).is_err() {
                return;
            }
        }
    });
    rx
}

/// A WebSocket client: text messages only (what the monitor sends).
struct Ws(TcpStream);

impl Ws {
    /// Connects to `ws://HOST:PORT/PATH` and completes the opening handshake.
    fn connect(url: &str) -> Ws {
        let rest = url.strip_prefix("ws://").expect("a ws:// URL");
        let (authority, path) = rest.split_at(rest.find('/').unwrap());
        let mut s = TcpStream::connect(authority).expect("the monitor accepts connections");
        s.set_read_timeout(Some(Duration::from_secs(20))).unwrap();
        write!(
            s,
            "GET {path} HTTP/1.1\r\nHost: {authority}\r\nUpgrade: websocket\r\nConnection: Upgrade\r\n\
             Sec-WebSocket-Key: dGhlIHNhbXBsZSBub25jZQ==\r\nSec-WebSocket-Version: 13\r\n\r\n"
        )
        .unwrap();
        let mut head = Vec::new();
        let mut b = [0u8; 1];
        while !head.ends_with(b"\r\n\r\n") {
            s.read_exact(&mut b).expect("a handshake answer");
            head.push(b[0]);
        }
        let head = String::from_utf8(head).unwrap();
        assert!(head.starts_with("HTTP/1.1 101"), "{head}");
        // RFC 6455's example key has this accept value.
        assert!(head.contains("s3pPLMBiTxaQ9kYGzzhZRbK+xOo="), "{head}");
        Ws(s)
    }

    /// Sends one text message (clients mask their frames).
    fn send(&mut self, text: &str) {
        let data = text.as_bytes();
        let mask = [0x12u8, 0x34, 0x56, 0x78];
        let mut frame = vec![0x81u8];
        match data.len() {
            n if n < 126 => frame.push(0x80 | n as u8),
            n => {
                frame.push(0x80 | 126);
                frame.extend_from_slice(&(n as u16).to_be_bytes());
            }
        }
        frame.extend_from_slice(&mask);
        frame.extend(data.iter().enumerate().map(|(i, b)| b ^ mask[i % 4]));
        self.0.write_all(&frame).unwrap();
    }

    /// The next text message as JSON; `None` when the server closed the connection.
    fn next(&mut self) -> Option<serde_json::Value> {
        loop {
            let mut h = [0u8; 2];
            self.0.read_exact(&mut h).ok()?;
            let opcode = h[0] & 0x0f;
            let mut len = (h[1] & 0x7f) as u64;
            if len == 126 {
                let mut l = [0u8; 2];
                self.0.read_exact(&mut l).ok()?;
                len = u16::from_be_bytes(l) as u64;
            } else if len == 127 {
                let mut l = [0u8; 8];
                self.0.read_exact(&mut l).ok()?;
                len = u64::from_be_bytes(l);
            }
            let mut payload = vec![0u8; len as usize];
            self.0.read_exact(&mut payload).ok()?;
            match opcode {
                0x1 => return Some(serde_json::from_slice(&payload).expect("the monitor sends JSON")),
                0x8 => return None,
                _ => continue, // ping, pong
            }
        }
    }

    /// Reads until a message satisfies `pred`.
    fn until(&mut self, what: &str, pred: impl Fn(&serde_json::Value) -> bool) -> serde_json::Value {
        loop {
            let m = self.next().unwrap_or_else(|| panic!("the connection closed before {what}"));
            if pred(&m) {
                return m;
            }
        }
    }
}

fn sfc_run(args: &[&str]) -> Child {
    Command::new(env!("CARGO_BIN_EXE_sfc"))
        .arg("run")
        .args(args)
        .current_dir(root())
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .expect("sfc runs")
}

/// The car wash, halted until the client continues, then 50 scans: hello, snapshot, a
/// breakpoint hit, the end of the run, exit status 0 and the statistics.
#[test]
fn a_monitor_client_drives_the_car_wash_to_its_end() {
    let mut child = sfc_run(&[
        "examples/carwash/carwash.st",
        "--period",
        "T#5ms",
        "--monitor",
        "127.0.0.1:0",
        "--token",
        "t0k3n",
        "--halted",
        "--scans",
        "50",
    ]);
    let lines = lines_of(&mut child);
    let mut run = Run(Some(child));
    let url = loop {
        let line = lines.recv_timeout(Duration::from_secs(20)).expect("sfc run prints its monitor URL");
        if let Some(u) = line.strip_prefix("sfc run: monitor on ") {
            break u.to_string();
        }
    };
    assert!(url.starts_with("ws://127.0.0.1:") && url.ends_with("/?token=t0k3n"), "{url}");
    assert!(!url.contains(":0/"), "port 0 is replaced by the port bound: {url}");

    let mut ws = Ws::connect(&url);
    let hello = ws.next().expect("hello");
    assert_eq!(hello["type"], "hello");
    assert_eq!((hello["runtime"].as_str(), hello["pou"].as_str()), (Some("sfc run"), Some("CarWash")));
    assert_eq!((hello["period"].as_str(), hello["authorized"].as_bool()), (Some("T#5ms"), Some(true)));
    assert_eq!(hello["halted"], true);
    // One scan by hand: the snapshot of scan 0 with the initial step.
    ws.send(r#"{"id":1,"cmd":"step"}"#);
    let first = ws.until("the first scan", |m| m["type"] == "snapshot" || m["type"] == "delta");
    assert_eq!((first["scan"].as_u64(), first["active"][0]["step"].as_str()), (Some(0), Some("Idle")));
    // A breakpoint on Spraying, the inputs that start a wash, and on.
    ws.send(r#"{"id":2,"cmd":"breakpoint","op":"set","name":"Spraying"}"#);
    for (i, name) in ["CarPresent", "AtHome", "StartButton"].iter().enumerate() {
        ws.send(&format!(r#"{{"id":{},"cmd":"set","name":"{name}","value":true}}"#, 3 + i));
    }
    ws.send(r#"{"id":9,"cmd":"continue"}"#);
    let hit = ws.until("the breakpoint", |m| m["type"] == "event" && m["kind"] == "breakpoint");
    assert_eq!(hit["step"], "Spraying");
    let halted = ws.until("the halt", |m| m["type"] == "halted");
    assert_eq!(halted["reason"], "breakpoint");
    ws.send(r#"{"id":10,"cmd":"continue"}"#);
    let end = ws.until("the end of the run", |m| m["type"] == "halted" && m["reason"] == "end");
    // 50 scans ran; on a busy machine an overrun skips periods, and the scan numbers with them.
    assert!(end["scan"].as_u64().is_some_and(|s| s >= 49), "--scans 50 runs scans 0..=49 or later ones: {end}");

    let mut child = run.0.take().unwrap();
    let status = child.wait().unwrap();
    assert_eq!(status.code(), Some(0));
    let rest: Vec<String> = lines.iter().collect();
    let stats = rest.iter().find(|l| l.starts_with("sfc run: 50 scans; start jitter p50 ")).unwrap_or_else(|| {
        panic!("no statistics line in {rest:?}");
    });
    assert!(stats.contains(" overruns, ") && stats.ends_with(" periods skipped"), "{stats}");
}

/// A chart with errors is refused like `sfc check` (exit 2), and so is a bad monitor address.
#[test]
fn bad_charts_and_arguments_exit_2() {
    let dir = std::env::temp_dir().join(format!("sfc-run-test-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let bad = dir.join("bad.st");
    std::fs::write(
        &bad,
        "PROGRAM P\nINITIAL_STEP S: END_STEP\nTRANSITION FROM S TO S := Nope; END_TRANSITION\nEND_PROGRAM\n",
    )
    .unwrap();
    let out =
        Command::new(env!("CARGO_BIN_EXE_sfc")).args(["run", bad.to_str().unwrap(), "--scans", "1"]).output().unwrap();
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("bad.st:3:") && err.contains("Nope"), "{err}");
    let out = Command::new(env!("CARGO_BIN_EXE_sfc"))
        .args(["run", "examples/carwash/carwash.st", "--monitor", "localhost"])
        .current_dir(root())
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2), "{}", String::from_utf8_lossy(&out.stderr));
    let _ = std::fs::remove_dir_all(&dir);
}

/// A runtime error of the chart stops the run with exit status 1 and says where.
#[test]
fn a_runtime_error_exits_1() {
    let dir = std::env::temp_dir().join(format!("sfc-run-test-div-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let chart = dir.join("div.st");
    std::fs::write(
        &chart,
        "PROGRAM Divide\nVAR d : INT; q : INT; END_VAR\nINITIAL_STEP S:\n    A(N);\nEND_STEP\n\
         ACTION A:\n    q := 10 / d;\nEND_ACTION\n\
         TRANSITION FROM S TO S := FALSE; END_TRANSITION\nEND_PROGRAM\n",
    )
    .unwrap();
    let out = Command::new(env!("CARGO_BIN_EXE_sfc"))
        .args(["run", chart.to_str().unwrap(), "--scans", "10", "--period", "T#1ms"])
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{err}");
    assert!(err.contains("error: 7:") && err.contains("(scan 0)"), "{err}");
    let _ = std::fs::remove_dir_all(&dir);
}
