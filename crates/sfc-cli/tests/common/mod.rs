//! What the `sfc run` tests share: the binary started as a user starts it, its standard error
//! read line by line, a minimal WebSocket client (RFC 6455 over a TCP socket) for the monitor,
//! and a raw Modbus TCP client that can send any frame, well-formed or not.
#![allow(dead_code)]

use std::io::{BufRead, BufReader, Read, Write};
use std::net::{SocketAddr, TcpStream};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::sync::mpsc;
use std::time::{Duration, Instant};

pub fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../..")
}

/// A fresh scratch directory for one test.
pub fn scratch(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("sfc-run-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// A running `sfc run`, killed when the test ends (also when it fails), with its standard
/// error read on a thread.
pub struct Run {
    pub child: Option<Child>,
    pub lines: mpsc::Receiver<String>,
    /// Every line read so far.
    pub seen: Vec<String>,
}

impl Drop for Run {
    fn drop(&mut self) {
        if let Some(c) = &mut self.child {
            let _ = c.kill();
            let _ = c.wait();
        }
    }
}

/// `sfc ARGS` in the project root with `SFC_TOKEN=t0k3n`.
pub fn command(args: &[&str]) -> Command {
    let mut c = Command::new(env!("CARGO_BIN_EXE_sfc"));
    c.args(args).env("SFC_TOKEN", "t0k3n").current_dir(root());
    c
}

impl Run {
    /// Starts `sfc run ARGS`.
    pub fn start(args: &[&str]) -> Run {
        let mut full = vec!["run"];
        full.extend_from_slice(args);
        Run::spawn(command(&full))
    }

    pub fn spawn(mut cmd: Command) -> Run {
        let mut child = cmd.stdout(Stdio::null()).stderr(Stdio::piped()).spawn().expect("sfc runs");
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
        Run { child: Some(child), lines: rx, seen: Vec::new() }
    }

    /// The first line (from now on, or already seen) that `pred` accepts, within `secs`.
    pub fn line(&mut self, what: &str, secs: u64, pred: impl Fn(&str) -> bool) -> String {
        if let Some(l) = self.seen.iter().find(|l| pred(l)) {
            return l.clone();
        }
        let deadline = Instant::now() + Duration::from_secs(secs);
        loop {
            let left = deadline.saturating_duration_since(Instant::now());
            match self.lines.recv_timeout(left) {
                Ok(l) => {
                    self.seen.push(l.clone());
                    if pred(&l) {
                        return l;
                    }
                }
                Err(_) => panic!("no line with {what} on standard error; seen:\n{}", self.seen.join("\n")),
            }
        }
    }

    /// The address after `prefix` in the line that starts with it (`sfc run: Modbus TCP on …`).
    pub fn address(&mut self, prefix: &str) -> SocketAddr {
        let l = self.line(prefix, 30, |l| l.starts_with(prefix));
        let rest = &l[prefix.len()..];
        let a = rest.trim_start_matches("ws://").split(['/', ' ']).next().unwrap();
        a.parse().unwrap_or_else(|_| panic!("an address in `{l}`"))
    }

    pub fn modbus(&mut self) -> SocketAddr {
        self.address("sfc run: Modbus TCP on ")
    }

    pub fn monitor(&mut self) -> SocketAddr {
        self.address("sfc run: monitor on ")
    }

    pub fn pid(&self) -> i32 {
        self.child.as_ref().unwrap().id() as i32
    }

    /// Sends a signal to the process.
    pub fn signal(&self, sig: i32) {
        // SAFETY: kill(2) on our own child's pid.
        unsafe {
            libc::kill(self.pid(), sig);
        }
    }

    /// Waits for the end (at most `secs`): the exit status and every line of standard error.
    pub fn finish(mut self, secs: u64) -> (Option<i32>, Vec<String>) {
        let mut child = self.child.take().unwrap();
        let deadline = Instant::now() + Duration::from_secs(secs);
        let status = loop {
            if let Some(s) = child.try_wait().unwrap() {
                break s;
            }
            if Instant::now() > deadline {
                let _ = child.kill();
                let _ = child.wait();
                panic!("sfc run did not end within {secs} s; seen:\n{}", self.seen.join("\n"));
            }
            std::thread::sleep(Duration::from_millis(10));
        };
        // The reader thread ends at the end of the stream.
        while let Ok(l) = self.lines.recv_timeout(Duration::from_secs(5)) {
            self.seen.push(l);
        }
        (status.code(), std::mem::take(&mut self.seen))
    }
}

/// A WebSocket client: text messages only (what the monitor sends).
pub struct Ws(pub TcpStream);

/// The answer to a handshake: the status line and the headers.
pub fn handshake(addr: SocketAddr, path: &str, headers: &[(&str, &str)]) -> (TcpStream, String) {
    let mut s = TcpStream::connect(addr).expect("the monitor accepts connections");
    s.set_read_timeout(Some(Duration::from_secs(20))).unwrap();
    let mut req = format!("GET {path} HTTP/1.1\r\n");
    if !headers.iter().any(|(k, _)| k.eq_ignore_ascii_case("host")) {
        req.push_str(&format!("Host: {addr}\r\n"));
    }
    for (k, v) in headers {
        req.push_str(&format!("{k}: {v}\r\n"));
    }
    req.push_str(
        "Upgrade: websocket\r\nConnection: Upgrade\r\nSec-WebSocket-Key: dGhlIHNhbXBsZSBub25jZQ==\r\n\
         Sec-WebSocket-Version: 13\r\n\r\n",
    );
    s.write_all(req.as_bytes()).unwrap();
    let mut head = Vec::new();
    let mut b = [0u8; 1];
    while !head.ends_with(b"\r\n\r\n") {
        if s.read_exact(&mut b).is_err() {
            break;
        }
        head.push(b[0]);
    }
    (s, String::from_utf8_lossy(&head).into_owned())
}

impl Ws {
    /// Connects to `ws://HOST:PORT/PATH` and completes the opening handshake.
    pub fn connect(url: &str) -> Ws {
        let rest = url.strip_prefix("ws://").expect("a ws:// URL");
        let (authority, path) = rest.split_at(rest.find('/').unwrap());
        let (s, head) = handshake(authority.parse().unwrap(), path, &[]);
        assert!(head.starts_with("HTTP/1.1 101"), "{head}");
        // RFC 6455's example key has this accept value.
        assert!(head.contains("s3pPLMBiTxaQ9kYGzzhZRbK+xOo="), "{head}");
        Ws(s)
    }

    /// Sends one text message (clients mask their frames).
    pub fn send(&mut self, text: &str) {
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
    pub fn next(&mut self) -> Option<serde_json::Value> {
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
    pub fn until(&mut self, what: &str, pred: impl Fn(&serde_json::Value) -> bool) -> serde_json::Value {
        loop {
            let m = self.next().unwrap_or_else(|| panic!("the connection closed before {what}"));
            if pred(&m) {
                return m;
            }
        }
    }

    /// Sends a command and returns its reply.
    pub fn cmd(&mut self, id: u64, c: serde_json::Value) -> serde_json::Value {
        let mut c = c;
        c["id"] = serde_json::json!(id);
        self.send(&c.to_string());
        self.until("the reply", |m| m["type"] == "reply" && m["re"] == id)
    }
}

/// A Modbus TCP client that sends PDUs as given (so also malformed ones).
pub struct Modbus {
    pub s: TcpStream,
    tid: u16,
}

impl Modbus {
    pub fn connect(addr: SocketAddr) -> Modbus {
        let s = TcpStream::connect(addr).expect("Modbus accepts connections");
        s.set_read_timeout(Some(Duration::from_secs(10))).unwrap();
        Modbus { s, tid: 0 }
    }

    /// Sends one request PDU and returns the response PDU.
    pub fn request(&mut self, pdu: &[u8]) -> Vec<u8> {
        self.tid = self.tid.wrapping_add(1);
        let mut frame = Vec::new();
        frame.extend_from_slice(&self.tid.to_be_bytes());
        frame.extend_from_slice(&[0, 0]);
        frame.extend_from_slice(&((pdu.len() + 1) as u16).to_be_bytes());
        frame.push(1);
        frame.extend_from_slice(pdu);
        self.s.write_all(&frame).unwrap();
        let mut head = [0u8; 7];
        self.s.read_exact(&mut head).expect("an answer (the connection stays open)");
        assert_eq!(u16::from_be_bytes([head[0], head[1]]), self.tid, "the answer carries the transaction id");
        let len = u16::from_be_bytes([head[4], head[5]]) as usize;
        let mut body = vec![0u8; len - 1];
        self.s.read_exact(&mut body).unwrap();
        body
    }

    pub fn read_coils(&mut self, a: u16, n: u16) -> Vec<bool> {
        self.read_bits(1, a, n)
    }
    pub fn read_discrete(&mut self, a: u16, n: u16) -> Vec<bool> {
        self.read_bits(2, a, n)
    }
    fn read_bits(&mut self, fc: u8, a: u16, n: u16) -> Vec<bool> {
        let mut pdu = vec![fc];
        pdu.extend_from_slice(&a.to_be_bytes());
        pdu.extend_from_slice(&n.to_be_bytes());
        let r = self.request(&pdu);
        assert_eq!(r[0], fc, "FC{fc} {a} {n}: {r:?}");
        (0..n as usize).map(|i| r[2 + i / 8] >> (i % 8) & 1 == 1).collect()
    }
    pub fn read_holding(&mut self, a: u16, n: u16) -> Vec<u16> {
        self.read_registers(3, a, n)
    }
    pub fn read_input_registers(&mut self, a: u16, n: u16) -> Vec<u16> {
        self.read_registers(4, a, n)
    }
    fn read_registers(&mut self, fc: u8, a: u16, n: u16) -> Vec<u16> {
        let mut pdu = vec![fc];
        pdu.extend_from_slice(&a.to_be_bytes());
        pdu.extend_from_slice(&n.to_be_bytes());
        let r = self.request(&pdu);
        assert_eq!(r[0], fc, "FC{fc} {a} {n}: {r:?}");
        (0..n as usize).map(|i| u16::from_be_bytes([r[2 + 2 * i], r[3 + 2 * i]])).collect()
    }
    pub fn write_coil(&mut self, a: u16, v: bool) {
        let mut pdu = vec![5];
        pdu.extend_from_slice(&a.to_be_bytes());
        pdu.extend_from_slice(&(if v { 0xFF00u16 } else { 0 }).to_be_bytes());
        let r = self.request(&pdu);
        assert_eq!(r, pdu, "FC5 echoes the request");
    }
    pub fn write_registers(&mut self, a: u16, regs: &[u16]) -> Vec<u8> {
        let mut pdu = vec![16];
        pdu.extend_from_slice(&a.to_be_bytes());
        pdu.extend_from_slice(&(regs.len() as u16).to_be_bytes());
        pdu.push((2 * regs.len()) as u8);
        for r in regs {
            pdu.extend_from_slice(&r.to_be_bytes());
        }
        self.request(&pdu)
    }
}

/// Polls `f` every 10 ms until it is true, at most `secs`.
pub fn eventually(what: &str, secs: u64, mut f: impl FnMut() -> bool) {
    let deadline = Instant::now() + Duration::from_secs(secs);
    while !f() {
        assert!(Instant::now() < deadline, "{what} did not happen within {secs} s");
        std::thread::sleep(Duration::from_millis(10));
    }
}

/// A test chart of `crates/sfc-cli/tests/run/`.
pub fn chart(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/run").join(name)
}

/// `scripts/NAME-deps.sh` made the Python package there, or the test says loudly why it skips.
fn python_deps(name: &str) -> bool {
    let ok = Command::new("bash").arg(root().join(format!("scripts/{name}-deps.sh"))).status();
    if !ok.is_ok_and(|s| s.success()) {
        eprintln!("\n\n*** SKIPPED: {name} cannot be installed (scripts/{name}-deps.sh failed) ***\n\n");
        return false;
    }
    true
}

/// asyncua (an OPC UA client) is there.
pub fn asyncua() -> bool {
    python_deps("asyncua")
}

/// pymodbus (a Modbus client) is there.
pub fn pymodbus() -> bool {
    python_deps("pymodbus")
}

/// o6 (an OPC UA client on open62541) is there.
pub fn o6() -> bool {
    python_deps("o6")
}

/// A value as a scenario file writes it (`true`, `3`, `"T#1s500ms"`, `"text"`).
pub fn toml_value(v: &sfc_sim::Value) -> String {
    use sfc_sim::Value;
    match v {
        Value::Bool(b) => b.to_string(),
        Value::Int(i) => i.to_string(),
        Value::Real(r) => format!("{r:?}"),
        Value::Time(t) => format!("\"{}\"", sfc_sim::format_time(*t)),
        Value::Str(s) => format!("{:?}", s.as_ref()),
    }
}

/// The `[[at]]` entries of a scenario file: `sets[k]`, the values written before scan `k`, at
/// `k · period`.
pub fn scenario_entries(period: i64, sets: &[Vec<(String, sfc_sim::Value)>]) -> String {
    let mut sc = String::new();
    for (k, set) in sets.iter().enumerate().filter(|(_, s)| !s.is_empty()) {
        let items: Vec<String> = set.iter().map(|(n, v)| format!("{n} = {}", toml_value(v))).collect();
        sc.push_str(&format!(
            "\n[[at]]\ntime = \"{}\"\nset = {{ {} }}\n",
            sfc_sim::format_time(k as i64 * period),
            items.join(", ")
        ));
    }
    sc
}
