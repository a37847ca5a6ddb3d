//! A monitor client for the tests (tokio-tungstenite), and runtimes to talk to.
#![allow(dead_code)]
// Test helpers, like the tests themselves, may panic: a panic is a failed test (clippy.toml
// allows it in `#[test]` functions only, not in the helpers they share).
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::indexing_slicing)]

use futures_util::{SinkExt, StreamExt};
use serde_json::{json, Value};
use sfc_runtime::{Limits, RunOptions, Runtime};
use sfc_sim::{SimOptions, Simulation};
use std::net::SocketAddr;
use std::path::PathBuf;
use std::time::Duration;
use tokio::net::TcpStream;
use tokio_tungstenite::tungstenite::Message;
use tokio_tungstenite::{MaybeTlsStream, WebSocketStream};

pub const TOKEN: &str = "s3cret";

pub fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../..")
}

/// The car wash example scanned every `period_us`, with a monitor (token [`TOKEN`]).
pub fn carwash(period_us: i64, halted: bool) -> Runtime {
    let text = std::fs::read_to_string(root().join("examples/carwash/carwash.st")).unwrap();
    let sim =
        Simulation::from_source("carwash.st", &text, None, SimOptions { period: period_us, ..Default::default() })
            .unwrap_or_else(|(_, d)| panic!("{d:?}"));
    Runtime::start(
        sim,
        RunOptions {
            monitor: Some("127.0.0.1:0".parse().unwrap()),
            token: Some(TOKEN.into()),
            limits: Limits { duration: Some(Duration::from_secs(300)), ..Default::default() },
            halted,
            ..Default::default()
        },
    )
    .unwrap()
}

pub struct Client {
    ws: WebSocketStream<MaybeTlsStream<TcpStream>>,
    next_id: u64,
    /// Messages read while waiting for something else.
    pub seen: Vec<Value>,
}

impl Client {
    pub async fn connect(addr: SocketAddr, token: Option<&str>) -> Client {
        let url = match token {
            Some(t) => format!("ws://{addr}/?token={t}"),
            None => format!("ws://{addr}/"),
        };
        let (ws, _) = tokio_tungstenite::connect_async(url).await.expect("connect");
        Client { ws, next_id: 1, seen: Vec::new() }
    }

    /// Connects from the loopback address `from` (another client, as far as the runtime's
    /// per-address limits go).
    pub async fn connect_from(addr: SocketAddr, token: Option<&str>, from: &str) -> Client {
        let url = match token {
            Some(t) => format!("ws://{addr}/?token={t}"),
            None => format!("ws://{addr}/"),
        };
        let socket = tokio::net::TcpSocket::new_v4().unwrap();
        socket.bind(format!("{from}:0").parse().unwrap()).expect("bind a loopback address");
        let stream = socket.connect(addr).await.expect("connect");
        let (ws, _) = tokio_tungstenite::client_async(url, MaybeTlsStream::Plain(stream)).await.expect("handshake");
        Client { ws, next_id: 1, seen: Vec::new() }
    }

    pub async fn send_text(&mut self, s: &str) {
        self.ws.send(Message::Text(s.into())).await.unwrap();
    }

    /// Sends `s`; FALSE when the server has already closed the connection.
    pub async fn try_send_text(&mut self, s: &str) -> bool {
        self.ws.send(Message::Text(s.into())).await.is_ok()
    }

    /// The next message, or `None` after `secs` seconds or when the server closed.
    pub async fn next(&mut self, secs: f64) -> Option<Value> {
        loop {
            let m = tokio::time::timeout(Duration::from_secs_f64(secs), self.ws.next()).await.ok()??;
            match m {
                Ok(Message::Text(t)) => return Some(serde_json::from_str(&t).expect("the server sends JSON")),
                Ok(Message::Close(_)) | Err(_) => return None,
                Ok(_) => continue,
            }
        }
    }

    /// Reads until a message satisfies `pred` (panics after 10 s).
    pub async fn until(&mut self, what: &str, pred: impl Fn(&Value) -> bool) -> Value {
        if let Some(i) = self.seen.iter().position(&pred) {
            return self.seen.remove(i);
        }
        let deadline = tokio::time::Instant::now() + Duration::from_secs(10);
        loop {
            let left = deadline.saturating_duration_since(tokio::time::Instant::now()).as_secs_f64();
            let Some(m) = self.next(left.max(0.001)).await else {
                panic!("no {what}; seen (last 5): {:?}", &self.seen[self.seen.len().saturating_sub(5)..])
            };
            if pred(&m) {
                return m;
            }
            self.seen.push(m);
        }
    }

    pub async fn until_type(&mut self, ty: &str) -> Value {
        self.until(ty, |m| m["type"] == ty).await
    }

    /// Sends a command with a fresh id and returns its reply.
    pub async fn cmd(&mut self, mut c: Value) -> Value {
        let id = self.next_id;
        self.next_id += 1;
        c["id"] = json!(id);
        self.send_text(&c.to_string()).await;
        self.until("reply", |m| m["re"] == json!(id)).await
    }
}

/// Active step names of a snapshot, delta or history entry.
pub fn active(m: &Value) -> Vec<String> {
    m["active"].as_array().unwrap().iter().map(|a| a["step"].as_str().unwrap().to_string()).collect()
}
