//! The monitor protocol (`docs/monitor.md`): JSON messages over WebSocket, one session per
//! client.
//!
//! A session never slows the runtime down: it reads the board under a short lock every tick
//! (20 ms, so at most 50 updates a second), builds its JSON outside the lock, and queues it for
//! its own writer task in a bounded queue. A client that does not read fast enough fills its
//! queue and is dropped; so is one that floods (more than [`FLOOD_PER_SECOND`] messages in a
//! second) or sends [`BAD_IN_A_ROW`] bad messages in a row.

use crate::board::{reply_err, reply_ok, BreakOp, BreakTarget, ChartInfo, Command, Hub, Request, ScanState};
use futures_util::{SinkExt, StreamExt};
use sfc_sim::{format_time, parse_time, Event, Value};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::Duration;
use tokio::net::{TcpListener, TcpStream};
use tokio_tungstenite::tungstenite::handshake::server::{
    ErrorResponse, Request as HttpRequest, Response as HttpResponse,
};
use tokio_tungstenite::tungstenite::protocol::WebSocketConfig;
use tokio_tungstenite::tungstenite::Message;

/// Protocol version in `hello`.
pub const VERSION: u32 = 1;
/// Messages queued for one client before it counts as too slow and is dropped.
pub const QUEUE: usize = 256;
/// Bad messages in a row that drop a client.
pub const BAD_IN_A_ROW: u32 = 20;
/// Messages per second that drop a client.
pub const FLOOD_PER_SECOND: u32 = 200;
/// Largest accepted message.
pub const MAX_MESSAGE: usize = 64 * 1024;
/// Most clients served at once.
pub const MAX_CLIENTS: u64 = 512;
/// Update period of a session.
pub const TICK: Duration = Duration::from_millis(20);
/// How long a new client waits for a state with guards before its first snapshot (ticks).
const GUARD_WAIT_TICKS: u32 = 100;

/// A value as JSON: BOOL as `true`/`false`, numbers as numbers, TIME as `T#…`, strings as
/// strings.
pub fn value_json(v: &Value) -> serde_json::Value {
    match v {
        Value::Bool(b) => serde_json::json!(b),
        Value::Int(i) => serde_json::json!(i),
        Value::Real(r) if r.is_finite() => serde_json::json!(r),
        Value::Real(r) => serde_json::json!(r.to_string()),
        Value::Time(t) => serde_json::json!(format_time(*t)),
        Value::Str(s) => serde_json::json!(&**s),
    }
}

/// A JSON value as a value to write (the variable's type checks it afterwards): booleans,
/// integers, reals, `"T#…"` durations, `"TRUE"`/`"FALSE"`, other strings as STRING.
pub fn value_from_json(j: &serde_json::Value) -> Option<Value> {
    match j {
        serde_json::Value::Bool(b) => Some(Value::Bool(*b)),
        serde_json::Value::Number(n) => n.as_i64().map(Value::Int).or_else(|| n.as_f64().map(Value::Real)),
        serde_json::Value::String(s) => {
            if let Some(t) = parse_time(s) {
                Some(Value::Time(t))
            } else if s.eq_ignore_ascii_case("TRUE") {
                Some(Value::Bool(true))
            } else if s.eq_ignore_ascii_case("FALSE") {
                Some(Value::Bool(false))
            } else {
                Some(Value::Str(Arc::from(s.as_str())))
            }
        }
        _ => None,
    }
}

/// A simulator event in the monitor's form: the trace format's object (`kind`, …).
pub fn event_json(e: &Event) -> serde_json::Value {
    e.to_json()
}

/// `hello`: what runs, and what this client may do.
pub fn hello(info: &ChartInfo, authorized: bool, halted: bool) -> serde_json::Value {
    let steps: Vec<serde_json::Value> =
        info.steps.iter().map(|(n, init)| serde_json::json!({"name": n, "initial": init})).collect();
    let name = |s: &u32| info.steps[*s as usize].0.clone();
    let transitions: Vec<serde_json::Value> = info
        .transitions
        .iter()
        .map(|(n, from, to)| {
            serde_json::json!({"name": n, "from": from.iter().map(name).collect::<Vec<_>>(),
                "to": to.iter().map(name).collect::<Vec<_>>()})
        })
        .collect();
    let vars: Vec<serde_json::Value> = info
        .variables
        .iter()
        .map(|v| {
            let mut o = serde_json::json!({"name": v.name, "type": v.ty});
            if let Some(l) = &v.location {
                o["location"] = serde_json::json!(l);
            }
            o
        })
        .collect();
    serde_json::json!({
        "type": "hello",
        "protocol": "sfc-monitor",
        "version": VERSION,
        "runtime": info.runtime,
        "pou": info.pou,
        "period": format_time(info.period),
        "steps": steps,
        "transitions": transitions,
        "variables": vars,
        "control": info.control,
        "tokenRequired": true,
        "authorized": authorized,
        "halted": halted,
        "history": crate::board::HISTORY,
    })
}

/// The active steps in step order (the scan thread publishes them in the engine's order).
fn active_json(info: &ChartInfo, st: &ScanState) -> serde_json::Value {
    let mut active = st.active.clone();
    active.sort_unstable();
    serde_json::Value::Array(
        active
            .iter()
            .map(|&(s, t)| serde_json::json!({"step": info.steps[s as usize].0, "elapsed": format_time(t), "elapsedUs": t}))
            .collect(),
    )
}

/// The guard values in transition order.
fn sorted_guards(st: &ScanState) -> Vec<(u32, Option<bool>)> {
    let mut g = st.guards.clone();
    g.sort_unstable();
    g
}

fn guards_json(info: &ChartInfo, st: &ScanState) -> serde_json::Map<String, serde_json::Value> {
    sorted_guards(st)
        .into_iter()
        .map(|(t, v)| {
            (info.transitions[t as usize].0.clone(), v.map_or(serde_json::Value::Null, serde_json::Value::Bool))
        })
        .collect()
}

fn names(info: &ChartInfo, ts: &[u32]) -> Vec<String> {
    ts.iter().map(|&t| info.transitions[t as usize].0.clone()).collect()
}

fn forced_json(info: &ChartInfo, st: &ScanState) -> Vec<String> {
    st.forced.iter().map(|&v| info.variables[v as usize].name.clone()).collect()
}

/// One scan state in full (`snapshot`, and the entries of `history`).
pub fn state_json(info: &ChartInfo, st: &ScanState) -> serde_json::Value {
    let vars: serde_json::Map<String, serde_json::Value> =
        info.variables.iter().zip(&st.values).map(|(v, x)| (v.name.clone(), value_json(x))).collect();
    serde_json::json!({
        "scan": st.scan,
        "time": format_time(st.time),
        "timeUs": st.time,
        "active": active_json(info, st),
        "fired": names(info, &st.fired),
        "guards": guards_json(info, st),
        "vars": vars,
        "forced": forced_json(info, st),
    })
}

/// `snapshot`: the latest state in full.
pub fn snapshot(info: &ChartInfo, st: &ScanState, halted: bool, stats: &serde_json::Value) -> serde_json::Value {
    let mut j = state_json(info, st);
    j["type"] = serde_json::json!("snapshot");
    j["halted"] = serde_json::json!(halted);
    j["stats"] = stats.clone();
    j
}

/// `delta`: what changed from `old` to `new`; `fired` collects the transitions fired in every
/// scan between them (`between`: the states after `old` up to `new`).
pub fn delta(info: &ChartInfo, old: &ScanState, new: &ScanState, between: &[Arc<ScanState>]) -> serde_json::Value {
    let mut j =
        serde_json::json!({"type": "delta", "scan": new.scan, "time": format_time(new.time), "timeUs": new.time});
    j["active"] = active_json(info, new);
    let fired: Vec<u32> = between.iter().flat_map(|s| s.fired.iter().copied()).collect();
    if !fired.is_empty() {
        j["fired"] = serde_json::json!(names(info, &fired));
    }
    if sorted_guards(old) != sorted_guards(new) {
        j["guards"] = serde_json::Value::Object(guards_json(info, new));
    }
    let changed: serde_json::Map<String, serde_json::Value> = info
        .variables
        .iter()
        .enumerate()
        .filter(|&(i, _)| old.values.get(i) != new.values.get(i))
        .map(|(i, v)| (v.name.clone(), value_json(&new.values[i])))
        .collect();
    if !changed.is_empty() {
        j["vars"] = serde_json::Value::Object(changed);
    }
    if old.forced != new.forced {
        j["forced"] = serde_json::json!(forced_json(info, new));
    }
    j
}

/// Accepts monitor clients until the hub stops.
pub async fn serve(listener: std::net::TcpListener, hub: Arc<Hub>) {
    let Ok(listener) = TcpListener::from_std(listener) else { return };
    loop {
        let accepted = tokio::select! {
            a = listener.accept() => a,
            _ = tokio::time::sleep(Duration::from_millis(100)) => {
                if hub.stopping() { return; }
                continue;
            }
        };
        let Ok((stream, _)) = accepted else { continue };
        if hub.connected.load(Ordering::Relaxed) >= MAX_CLIENTS {
            continue; // dropping the stream refuses the client
        }
        let _ = stream.set_nodelay(true);
        let hub = hub.clone();
        tokio::spawn(async move {
            hub.connected.fetch_add(1, Ordering::Relaxed);
            let dropped = session(stream, &hub).await;
            hub.connected.fetch_sub(1, Ordering::Relaxed);
            if dropped {
                hub.dropped.fetch_add(1, Ordering::Relaxed);
            }
        });
    }
}

/// The `token` query parameter of a request path (`/?token=abc`), percent-decoded.
fn query_token(uri: &str) -> Option<String> {
    let q = uri.split_once('?')?.1;
    q.split('&').find_map(|kv| {
        let (k, v) = kv.split_once('=')?;
        (k == "token").then(|| percent_decode(v))
    })
}

fn percent_decode(s: &str) -> String {
    let hex = |c: u8| (c as char).to_digit(16).map(|d| d as u8);
    let b = s.as_bytes();
    let mut out = Vec::with_capacity(b.len());
    let mut i = 0;
    while i < b.len() {
        if b[i] == b'%' && i + 2 < b.len() {
            if let (Some(h), Some(l)) = (hex(b[i + 1]), hex(b[i + 2])) {
                out.push(h * 16 + l);
                i += 3;
                continue;
            }
        }
        out.push(if b[i] == b'+' { b' ' } else { b[i] });
        i += 1;
    }
    String::from_utf8_lossy(&out).into_owned()
}

/// Compares without an early exit, so timing does not tell how much of a guess was right.
fn same_secret(a: &str, b: &str) -> bool {
    a.len() == b.len() && a.bytes().zip(b.bytes()).fold(0u8, |acc, (x, y)| acc | (x ^ y)) == 0
}

/// What one client is up to.
struct Session<'a> {
    hub: &'a Hub,
    out: tokio::sync::mpsc::Sender<String>,
    authorized: bool,
    paused: bool,
    last: Option<Arc<ScanState>>,
    next_event: u64,
    halted: Option<bool>,
    /// The next halt or resume of [`crate::board::Board::halts`] to tell.
    next_halt: u64,
    bad_in_row: u32,
    window: tokio::time::Instant,
    in_window: u32,
}

/// Why a session ends.
enum End {
    /// The client left, or the run ended.
    Closed,
    /// Dropped for misbehaving.
    Dropped,
}

/// Serves one client; returns whether it was dropped for misbehaving.
async fn session(stream: TcpStream, hub: &Hub) -> bool {
    let authorized = Arc::new(AtomicBool::new(false));
    let token = hub.token.clone();
    let flag = authorized.clone();
    // The error type is tungstenite's; the callback never fails.
    #[allow(clippy::result_large_err)]
    let callback = move |req: &HttpRequest, resp: HttpResponse| -> Result<HttpResponse, ErrorResponse> {
        let uri = req.uri().to_string();
        if query_token(&uri).is_some_and(|t| same_secret(&t, &token)) {
            flag.store(true, Ordering::Relaxed);
        }
        Ok(resp)
    };
    let config = WebSocketConfig::default().max_message_size(Some(MAX_MESSAGE)).max_frame_size(Some(MAX_MESSAGE));
    let handshake = tokio_tungstenite::accept_hdr_async_with_config(stream, callback, Some(config));
    let Ok(Ok(ws)) = tokio::time::timeout(Duration::from_secs(5), handshake).await else {
        return true;
    };
    let (mut sink, mut source) = ws.split();
    let (tx, mut rx) = tokio::sync::mpsc::channel::<String>(QUEUE);
    let writer = tokio::spawn(async move {
        while let Some(m) = rx.recv().await {
            if sink.send(Message::Text(m.into())).await.is_err() {
                return;
            }
        }
        let _ = sink.close().await;
    });
    let mut s = Session {
        hub,
        out: tx,
        authorized: authorized.load(Ordering::Relaxed),
        paused: false,
        last: None,
        next_event: 0,
        halted: None,
        next_halt: 0,
        bad_in_row: 0,
        window: tokio::time::Instant::now(),
        in_window: 0,
    };
    let end = s.run(&mut source).await;
    match end {
        End::Closed => {
            // Let the writer flush what is queued (it ends when the queue closes).
            drop(s);
            let _ = tokio::time::timeout(Duration::from_secs(1), writer).await;
            false
        }
        End::Dropped => {
            writer.abort();
            true
        }
    }
}

type Source = futures_util::stream::SplitStream<tokio_tungstenite::WebSocketStream<TcpStream>>;

impl Session<'_> {
    async fn run(&mut self, source: &mut Source) -> End {
        let halted = self.hub.lock().halted;
        if !self.send(hello(&self.hub.info, self.authorized, halted)) {
            return End::Dropped;
        }
        {
            let b = self.hub.lock();
            self.next_event = b.next_event;
        }
        // Guards are evaluated while someone watches: the first snapshot is the first state
        // evaluated since this client connected (the next scan, or at once when halted).
        for _ in 0..GUARD_WAIT_TICKS {
            let ready = {
                let b = self.hub.lock();
                b.history.back().is_none_or(|s| s.guards_known)
            };
            if ready || self.hub.stopping() {
                break;
            }
            tokio::time::sleep(TICK).await;
        }
        if !self.send_snapshot() {
            return End::Dropped;
        }
        let mut tick = tokio::time::interval(TICK);
        tick.set_missed_tick_behavior(tokio::time::MissedTickBehavior::Skip);
        loop {
            tokio::select! {
                m = source.next() => {
                    let text = match m {
                        None | Some(Err(_)) => return End::Closed,
                        Some(Ok(Message::Text(t))) => t.to_string(),
                        Some(Ok(Message::Binary(_))) => String::from("\u{0}binary"),
                        Some(Ok(Message::Close(_))) => return End::Closed,
                        Some(Ok(_)) => continue, // ping/pong: tungstenite answers pings
                    };
                    if let Some(end) = self.incoming(&text) {
                        return end;
                    }
                }
                _ = tick.tick() => {
                    if self.hub.stopping() {
                        return End::Closed;
                    }
                    if !self.update() {
                        return End::Dropped;
                    }
                }
            }
        }
    }

    /// Queues a message; `false` when the client's queue is full (it is too slow).
    fn send(&self, j: serde_json::Value) -> bool {
        self.send_line(j.to_string())
    }

    fn send_line(&self, line: String) -> bool {
        self.out.try_send(line).is_ok()
    }

    fn send_snapshot(&mut self) -> bool {
        let (latest, halted, stats) = {
            let b = self.hub.lock();
            self.next_halt = b.next_halt;
            (b.history.back().cloned(), b.halted, b.stats_json())
        };
        self.halted = Some(halted);
        match latest {
            Some(st) => {
                let ok = self.send(snapshot(&self.hub.info, &st, halted, &stats));
                self.last = Some(st);
                ok
            }
            None => true,
        }
    }

    /// Sends what happened since the last tick (nothing while paused).
    fn update(&mut self) -> bool {
        if self.paused {
            return true;
        }
        let last_scan = self.last.as_ref().map(|s| s.scan);
        let (events, between, mut halts, halted, reason) = {
            let b = self.hub.lock();
            let halts: Vec<(bool, String)> =
                b.halts.iter().filter(|h| h.seq >= self.next_halt).map(|h| (h.halted, h.reason.clone())).collect();
            self.next_halt = b.next_halt;
            let events: Vec<_> = b.events.iter().filter(|e| e.seq >= self.next_event).cloned().collect();
            let between: Vec<Arc<ScanState>> = match last_scan {
                Some(l) => b.history.iter().filter(|s| s.scan > l).cloned().collect(),
                None => b.history.back().cloned().into_iter().collect(),
            };
            (events, between, halts, b.halted, b.reason.clone())
        };
        // Older changes than the log holds: the state now is what counts.
        if halts.last().map(|h| h.0) != Some(halted) {
            halts.push((halted, reason));
        }
        for e in events {
            self.next_event = e.seq + 1;
            let mut j = e.event.to_json();
            j["type"] = serde_json::json!("event");
            if !self.send(j) {
                return false;
            }
        }
        if let Some(new) = between.last() {
            let msg = match &self.last {
                Some(old) => delta(&self.hub.info, old, new, &between),
                None => {
                    let mut j = state_json(&self.hub.info, new);
                    j["type"] = serde_json::json!("snapshot");
                    j
                }
            };
            if !self.send(msg) {
                return false;
            }
            self.last = Some(new.clone());
        }
        for (halted, reason) in halts {
            if self.halted == Some(halted) {
                continue;
            }
            self.halted = Some(halted);
            let scan = self.last.as_ref().map_or(0, |s| s.scan);
            let j = if halted {
                serde_json::json!({"type": "halted", "reason": reason, "scan": scan})
            } else {
                serde_json::json!({"type": "resumed", "scan": scan})
            };
            if !self.send(j) {
                return false;
            }
        }
        true
    }

    /// Handles one message; `Some` ends the session.
    fn incoming(&mut self, text: &str) -> Option<End> {
        let now = tokio::time::Instant::now();
        if now.duration_since(self.window) >= Duration::from_secs(1) {
            self.window = now;
            self.in_window = 0;
        }
        self.in_window += 1;
        if self.in_window > FLOOD_PER_SECOND {
            let _ =
                self.send(serde_json::json!({"type": "error", "error": "flooding: more than 200 messages a second"}));
            return Some(End::Dropped);
        }
        let parsed: Result<serde_json::Value, String> =
            serde_json::from_str(text).map_err(|e| format!("not JSON: {e}"));
        let (id, outcome) = match parsed {
            Ok(j) => {
                let id = j.get("id").cloned().unwrap_or(serde_json::Value::Null);
                let r = self.command(&j, &id);
                (id, r)
            }
            Err(e) => (serde_json::Value::Null, Err(e)),
        };
        match outcome {
            Ok(Some(line)) => {
                self.bad_in_row = 0;
                if !self.send_line(line) {
                    return Some(End::Dropped);
                }
            }
            Ok(None) => self.bad_in_row = 0, // forwarded: the runtime replies
            Err(e) => {
                self.bad_in_row += 1;
                if !self.send_line(reply_err(&id, e)) || self.bad_in_row >= BAD_IN_A_ROW {
                    return Some(End::Dropped);
                }
            }
        }
        None
    }

    /// Runs a command: `Ok(Some(reply))` answered here, `Ok(None)` forwarded to the runtime
    /// (which replies), `Err` a bad command.
    fn command(&mut self, j: &serde_json::Value, id: &serde_json::Value) -> Result<Option<String>, String> {
        let obj = j.as_object().ok_or("a command is a JSON object")?;
        let cmd = obj.get("cmd").and_then(|c| c.as_str()).ok_or("missing `cmd`")?;
        if let Some(t) = obj.get("token").and_then(|t| t.as_str()) {
            if same_secret(t, &self.hub.token) {
                self.authorized = true;
            } else {
                return Err("wrong token".into());
            }
        }
        let info = &self.hub.info;
        let str_field = |k: &str| obj.get(k).and_then(|v| v.as_str());
        let var = |k: &str| -> Result<u32, String> {
            let n = str_field(k).ok_or_else(|| format!("`{cmd}` needs `{k}`"))?;
            info.variables
                .iter()
                .position(|v| v.name.eq_ignore_ascii_case(n))
                .map(|i| i as u32)
                .ok_or_else(|| format!("no variable `{n}`"))
        };
        let command = match cmd {
            "hello" => {
                let halted = self.hub.lock().halted;
                return Ok(Some(reply_ok(id, hello(info, self.authorized, halted))));
            }
            "snapshot" => {
                let line = reply_ok(id, serde_json::Value::Null);
                if !self.send_line(line) {
                    return Err("queue full".into());
                }
                self.last = None;
                if !self.send_snapshot() {
                    return Err("queue full".into());
                }
                return Ok(None);
            }
            "pause" => {
                self.paused = true;
                return Ok(Some(reply_ok(id, serde_json::json!({"paused": true}))));
            }
            "resume" => {
                self.paused = false;
                // The stream restarts from a full snapshot; buffered events follow on the next tick.
                let line = reply_ok(id, serde_json::json!({"paused": false}));
                if !self.send_line(line) || !self.send_snapshot() {
                    return Err("queue full".into());
                }
                return Ok(None);
            }
            "history" => {
                let n = match obj.get("count") {
                    None => crate::board::HISTORY,
                    Some(c) => c.as_u64().ok_or("`count` is a number")?.min(crate::board::HISTORY as u64) as usize,
                };
                let states: Vec<Arc<ScanState>> = {
                    let b = self.hub.lock();
                    let skip = b.history.len().saturating_sub(n);
                    b.history.iter().skip(skip).cloned().collect()
                };
                let list: Vec<serde_json::Value> = states.iter().map(|s| state_json(info, s)).collect();
                let mut j = serde_json::json!({"type": "history", "re": id, "states": list});
                j["ok"] = serde_json::json!(true);
                return Ok(Some(j.to_string()));
            }
            "explain" => {
                let name = str_field("step").ok_or("`explain` needs `step`")?;
                let s = info.step_index(name).ok_or_else(|| format!("no step `{name}`"))?;
                Command::Explain { step: info.steps[s as usize].0.clone() }
            }
            "timing" => Command::Timing,
            "halt" => Command::Halt,
            "continue" => Command::Continue,
            "step" => Command::Step,
            "breakpoints" => Command::Breakpoints,
            "breakpoint" => {
                let op = match str_field("op").ok_or("`breakpoint` needs `op`")? {
                    "set" => BreakOp::Set,
                    "disable" => BreakOp::Disable,
                    "enable" => BreakOp::Enable,
                    "delete" => BreakOp::Delete,
                    "deleteAll" => BreakOp::DeleteAll,
                    other => {
                        return Err(format!(
                            "unknown breakpoint op `{other}` (set, disable, enable, delete, deleteAll)"
                        ))
                    }
                };
                let target = if op == BreakOp::DeleteAll {
                    None
                } else {
                    let name = str_field("name").ok_or("`breakpoint` needs `name`")?;
                    Some(match str_field("kind").unwrap_or("step") {
                        "step" => BreakTarget::Step(info.step_index(name).ok_or_else(|| format!("no step `{name}`"))?),
                        "transition" => BreakTarget::Transition(
                            info.transition_index(name).ok_or_else(|| format!("no transition `{name}`"))?,
                        ),
                        other => return Err(format!("unknown breakpoint kind `{other}` (step, transition)")),
                    })
                };
                Command::Breakpoint { op, target }
            }
            "force" | "set" | "unforce" => {
                if !info.control {
                    return Err(format!("this runtime ({}) cannot {cmd} variables", info.runtime));
                }
                match cmd {
                    "unforce" => {
                        Command::Unforce { var: if obj.contains_key("name") { Some(var("name")?) } else { None } }
                    }
                    _ => {
                        let v = var("name")?;
                        let value = obj.get("value").cloned().ok_or_else(|| format!("`{cmd}` needs `value`"))?;
                        if cmd == "force" {
                            Command::Force { var: v, value }
                        } else {
                            Command::Set { var: v, value }
                        }
                    }
                }
            }
            other => return Err(format!("unknown command `{other}`")),
        };
        // Whatever changes the run needs the token; watching (hello, snapshot, pause, resume,
        // history, the breakpoint list, explain, timing) does not.
        if !self.authorized && !command.watches() {
            return Err(format!("`{cmd}` needs the run's token"));
        }
        if matches!(command, Command::Halt | Command::Continue | Command::Step) && !info.control {
            return Err(format!("this runtime ({}) observes only: it cannot {cmd}", info.runtime));
        }
        let req = Request { id: id.clone(), command, reply: self.out.clone() };
        if !self.hub.send(req) {
            return Err("the run has ended".into());
        }
        Ok(None)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tokens_come_from_the_query() {
        assert_eq!(query_token("/?token=abc"), Some("abc".into()));
        assert_eq!(query_token("/monitor?x=1&token=a%2Fb"), Some("a/b".into()));
        assert_eq!(query_token("/"), None);
        assert_eq!(query_token("/?token=%zz%"), Some("%zz%".into()));
        assert!(same_secret("abc", "abc") && !same_secret("abc", "abd") && !same_secret("ab", "abc"));
    }

    #[test]
    fn values_round_trip_through_json() {
        for v in
            [Value::Bool(true), Value::Int(-3), Value::Real(1.5), Value::Time(1_500_000), Value::Str(Arc::from("x"))]
        {
            assert_eq!(value_from_json(&value_json(&v)), Some(v));
        }
        assert_eq!(value_from_json(&serde_json::json!([1])), None);
    }
}
