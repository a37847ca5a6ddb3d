//! Protocol fuzzing: several clients send thousands of random and malformed messages (random
//! bytes, broken JSON, well-formed JSON with random commands and fields) while the chart scans
//! at 1 ms; others open raw TCP connections and send garbage instead of a WebSocket handshake.
//! The runtime keeps scanning and answers a good client afterwards.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::indexing_slicing)] // test code: a panic is a failed test

mod common;

use common::{carwash, Client, TOKEN};
use futures_util::SinkExt;
use serde_json::json;
use tokio::io::AsyncWriteExt;
use tokio_tungstenite::tungstenite::Message;

/// xorshift64*: deterministic, so a failure can be replayed from its seed.
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        self.0.wrapping_mul(0x2545_F491_4F6C_DD1D)
    }
    fn below(&mut self, n: usize) -> usize {
        (self.next() % n as u64) as usize
    }
    fn pick<'a>(&mut self, xs: &[&'a str]) -> &'a str {
        xs[self.below(xs.len())]
    }
}

const CMDS: &[&str] = &[
    "pause",
    "resume",
    "halt",
    "continue",
    "step",
    "breakpoint",
    "breakpoints",
    "force",
    "unforce",
    "set",
    "history",
    "snapshot",
    "hello",
    "",
    "HALT",
    "\u{0}",
    "deleteAll",
];
const NAMES: &[&str] =
    &["Idle", "Spraying", "TStart", "StartButton", "Washes", "MaxTravelTime", "", "X", "%IX0.0", "Idle.X"];
const OPS: &[&str] = &["set", "disable", "enable", "delete", "deleteAll", "nope"];

fn random_value(r: &mut Rng) -> serde_json::Value {
    match r.below(9) {
        0 => json!(r.below(2) == 0),
        1 => json!(r.next() as i64),
        2 => json!(f64::from_bits(r.next()).clamp(-1e300, 1e300)),
        3 => json!("T#5s"),
        4 => json!("T#"),
        5 => json!(null),
        6 => json!([1, {"a": []}]),
        7 => json!({"nested": {"deep": [null]}}),
        _ => json!("x".repeat(r.below(300))),
    }
}

fn message(r: &mut Rng) -> Message {
    match r.below(8) {
        0 => {
            let n = r.below(200);
            Message::Binary((0..n).map(|_| r.next() as u8).collect::<Vec<u8>>().into())
        }
        1 => {
            let n = r.below(200);
            Message::Text(
                String::from_utf8_lossy(&(0..n).map(|_| r.next() as u8).collect::<Vec<u8>>()).into_owned().into(),
            )
        }
        2 => {
            // Truncated or mangled JSON.
            let good = json!({"id": 1, "cmd": r.pick(CMDS)}).to_string();
            let cut = r.below(good.len());
            Message::Text(good[..cut].to_string().into())
        }
        3 => Message::Text("[".repeat(r.below(5000)).into()),
        4 => Message::Text(json!([r.pick(CMDS), 1, 2]).to_string().into()),
        _ => {
            // Well-formed commands with random (often wrong) fields; never the real token.
            let mut c = json!({"id": random_value(r), "cmd": r.pick(CMDS)});
            if r.below(2) == 0 {
                c["name"] = json!(r.pick(NAMES));
            }
            if r.below(2) == 0 {
                c["kind"] = json!(r.pick(&["step", "transition", "action", ""]));
            }
            if r.below(2) == 0 {
                c["op"] = json!(r.pick(OPS));
            }
            if r.below(2) == 0 {
                c["value"] = random_value(r);
            }
            if r.below(4) == 0 {
                c["token"] = json!(r.pick(&["", "s3cre", "s3cret ", "S3CRET"]));
            }
            if r.below(4) == 0 {
                c["count"] = random_value(r);
            }
            Message::Text(c.to_string().into())
        }
    }
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn random_and_malformed_messages_never_stop_the_runtime() {
    let rt = carwash(1_000, false);
    let addr = rt.monitor_addr().unwrap();
    let mut tasks = Vec::new();
    for seed in 1..=4u64 {
        tasks.push(tokio::spawn(async move {
            let mut r = Rng(seed.wrapping_mul(0x9E37_79B9_7F4A_7C15));
            let mut sent = 0;
            while sent < 2500 {
                // One client holds the token: its random halts, steps, forces and breakpoints
                // reach the scan thread.
                let query = if seed == 1 { format!("?token={TOKEN}") } else { String::new() };
                let Ok((mut ws, _)) = tokio_tungstenite::connect_async(format!("ws://{addr}/{query}")).await else {
                    continue;
                };
                // Each connection sends a burst; the server drops it for garbage or flooding.
                for _ in 0..r.below(400) + 1 {
                    sent += 1;
                    if ws.send(message(&mut r)).await.is_err() {
                        break;
                    }
                }
                if r.below(3) == 0 {
                    let _ = ws.close(None).await;
                }
            }
            sent
        }));
    }
    for seed in 0..20u64 {
        tasks.push(tokio::spawn(async move {
            let mut r = Rng(seed + 77);
            if let Ok(mut s) = tokio::net::TcpStream::connect(addr).await {
                let junk: Vec<u8> = match seed % 3 {
                    0 => (0..r.below(5000)).map(|_| r.next() as u8).collect(),
                    1 => b"GET / HTTP/1.1\r\nHost: x\r\nUpgrade: websocket\r\nConnection: Upgrade\r\n\r\n".to_vec(),
                    _ => b"GET /?token=%%%% HTTP/1.1\r\nSec-WebSocket-Key: ???\r\n\r\n\x00\xff".to_vec(),
                };
                let _ = s.write_all(&junk).await;
            }
            1
        }));
    }
    let mut total = 0;
    for t in tasks {
        total += t.await.unwrap();
    }
    assert!(total >= 10_000, "{total} messages sent");
    let before = rt.stats_json()["scans"].as_u64().unwrap_or(0);
    // The fuzzers' wrong tokens slowed 127.0.0.1 down; another client is served at once.
    let mut good = Client::connect_from(addr, Some(TOKEN), "127.0.0.2").await;
    let hello = good.until_type("hello").await;
    assert_eq!(hello["pou"], "CarWash");
    for c in [json!({"cmd": "breakpoint", "op": "deleteAll"}), json!({"cmd": "unforce"}), json!({"cmd": "continue"})] {
        let r = good.cmd(c).await;
        assert_eq!(r["ok"], true, "{r}");
    }
    let d1 = good.until_type("delta").await;
    let d2 = good.until("a later delta", |m| m["type"] == "delta" && m["scan"].as_u64() > d1["scan"].as_u64()).await;
    assert!(d2["scan"].as_u64() > Some(before), "the runtime still scans");
    rt.stop();
    let report = rt.wait();
    assert_eq!(report.error, None);
    assert!(report.dropped > 0, "misbehaving clients were dropped");
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn bad_messages_get_error_replies_then_the_client_is_dropped() {
    let rt = carwash(10_000, false);
    let mut c = Client::connect(rt.monitor_addr().unwrap(), None).await;
    c.until_type("hello").await;
    c.send_text("{not json").await;
    let r = c.until("error reply", |m| m["type"] == "reply").await;
    assert_eq!(r["ok"], false);
    assert!(r["error"].as_str().unwrap().starts_with("not JSON"), "{r}");
    let r = c.cmd(json!({"cmd": "jump"})).await;
    assert_eq!(r["error"], "unknown command `jump`");
    // A good command resets the count; then 20 bad ones in a row drop the client.
    let r = c.cmd(json!({"cmd": "breakpoints"})).await;
    assert_eq!(r["ok"], true);
    // (The server may drop the client before the last ones are sent: a broken pipe then.)
    for _ in 0..25 {
        if !c.try_send_text("garbage").await {
            break;
        }
    }
    let mut closed = false;
    for _ in 0..200 {
        if c.next(2.0).await.is_none() {
            closed = true;
            break;
        }
    }
    assert!(closed, "the server closed the connection");
    rt.stop();
    assert_eq!(rt.wait().dropped, 1);
}
