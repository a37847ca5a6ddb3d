//! The monitor protocol (`docs/monitor.md`): JSON messages over WebSocket, one session per
//! client.
//!
//! A session never slows the runtime down: it reads the board under a short lock every tick
//! (20 ms, so at most 50 updates a second), builds its JSON outside the lock, and queues it for
//! its own writer task in a bounded queue. A client that does not read fast enough fills its
//! queue and is dropped; so is one that floods (more than [`FLOOD_PER_SECOND`] messages in a
//! second) or sends [`BAD_IN_A_ROW`] bad messages in a row.

// Indices here come from tables this crate builds at start (the Modbus map, the variables) or
// are checked against the frame length just before (Modbus PDUs); the runtime work of issue 14
// landed after the workspace lints, and its conversion to `get` is still to do (ARCHITECTURE.md).
#![allow(clippy::indexing_slicing)]

use crate::access::MonitorAccess;
use crate::board::{reply_err, reply_ok, BreakOp, BreakTarget, ChartInfo, Command, Hub, Request, RunState, ScanState};
use futures_util::{SinkExt, StreamExt};
use sfc_sim::{format_time, parse_time, Event, Value};
use std::net::IpAddr;
use std::sync::atomic::Ordering;
use std::sync::{Arc, Mutex};
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
pub fn hello(
    info: &ChartInfo,
    authorized: bool,
    halted: bool,
    state: RunState,
    fault: Option<&serde_json::Value>,
) -> serde_json::Value {
    let steps: Vec<serde_json::Value> =
        info.steps.iter().map(|(n, init)| serde_json::json!({"name": n, "initial": init})).collect();
    let name = |s: &u32| info.step_name(*s);
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
                crate::board::put(&mut o, "location", serde_json::json!(l));
            }
            if let Some(x) = &v.safe {
                o["safe"] = value_json(x);
            }
            o
        })
        .collect();
    let mut hello = serde_json::json!({
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
        "state": state.name(),
        "fault": fault.cloned().unwrap_or(serde_json::Value::Null),
        "history": crate::board::HISTORY,
    });
    if let Some(p) = info.profile {
        crate::board::put(&mut hello, "profile", serde_json::json!(p));
    }
    hello
}

/// The active steps in step order (the scan thread publishes them in the engine's order).
fn active_json(info: &ChartInfo, st: &ScanState) -> serde_json::Value {
    let mut active = st.active.clone();
    active.sort_unstable();
    serde_json::Value::Array(
        active
            .iter()
            .map(|&(s, t)| serde_json::json!({"step": info.step_name(s), "elapsed": format_time(t), "elapsedUs": t}))
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
        .map(|(t, v)| (info.transition_name(t), v.map_or(serde_json::Value::Null, serde_json::Value::Bool)))
        .collect()
}

fn names(info: &ChartInfo, ts: &[u32]) -> Vec<String> {
    ts.iter().map(|&t| info.transition_name(t)).collect()
}

fn forced_json(info: &ChartInfo, st: &ScanState) -> Vec<String> {
    st.forced.iter().map(|&v| info.variable_name(v)).collect()
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
pub fn snapshot(
    info: &ChartInfo,
    st: &ScanState,
    halted: bool,
    run: (RunState, Option<&serde_json::Value>),
    stats: &serde_json::Value,
) -> serde_json::Value {
    let mut j = state_json(info, st);
    if run.0 != RunState::Run {
        // The outputs are at their safe values, whatever the last scan left (the rule of every
        // view, `board::shown_values`).
        let mut values = st.values.clone();
        crate::board::shown_values(info, run.0, &mut values);
        for (v, x) in info.variables.iter().zip(&values) {
            j["vars"][&v.name] = value_json(x);
        }
    }
    j["type"] = serde_json::json!("snapshot");
    j["halted"] = serde_json::json!(halted);
    j["state"] = serde_json::json!(run.0.name());
    j["fault"] = run.1.cloned().unwrap_or(serde_json::Value::Null);
    j["stats"] = stats.clone();
    j
}

/// `state`: RUN, STOP or FAULT, with the fault.
pub fn state_message(state: RunState, fault: Option<&serde_json::Value>, scan: u64) -> serde_json::Value {
    serde_json::json!({
        "type": "state", "state": state.name(), "fault": fault.cloned().unwrap_or(serde_json::Value::Null), "scan": scan
    })
}

/// `delta`: what changed from `old` to `new`; `fired` collects the transitions fired in every
/// scan between them (`between`: the states after `old` up to `new`).
pub fn delta(info: &ChartInfo, old: &ScanState, new: &ScanState, between: &[Arc<ScanState>]) -> serde_json::Value {
    let mut j =
        serde_json::json!({"type": "delta", "scan": new.scan, "time": format_time(new.time), "timeUs": new.time});
    crate::board::put(&mut j, "active", active_json(info, new));
    let fired: Vec<u32> = between.iter().flat_map(|s| s.fired.iter().copied()).collect();
    if !fired.is_empty() {
        crate::board::put(&mut j, "fired", serde_json::json!(names(info, &fired)));
    }
    if sorted_guards(old) != sorted_guards(new) {
        crate::board::put(&mut j, "guards", serde_json::Value::Object(guards_json(info, new)));
    }
    let changed: serde_json::Map<String, serde_json::Value> = info
        .variables
        .iter()
        .enumerate()
        .filter(|&(i, _)| old.values.get(i) != new.values.get(i))
        .filter_map(|(i, v)| Some((v.name.clone(), value_json(new.values.get(i)?))))
        .collect();
    if !changed.is_empty() {
        crate::board::put(&mut j, "vars", serde_json::Value::Object(changed));
    }
    if old.forced != new.forced {
        crate::board::put(&mut j, "forced", serde_json::json!(forced_json(info, new)));
    }
    j
}

/// Accepts monitor clients until the hub stops. A failed `accept` (file descriptors
/// exhausted, …) backs off, 10 ms doubling to 1 s, instead of trying again at once.
pub async fn serve(listener: std::net::TcpListener, hub: Arc<Hub>, access: Arc<MonitorAccess>) {
    let Ok(listener) = TcpListener::from_std(listener) else { return };
    let Ok(local) = listener.local_addr() else { return };
    let mut backoff = Duration::from_millis(10);
    let mut failing = false;
    loop {
        let accepted = tokio::select! {
            a = listener.accept() => a,
            _ = tokio::time::sleep(Duration::from_millis(100)) => {
                if hub.closing() { return; }
                continue;
            }
        };
        let (stream, peer) = match accepted {
            Ok(a) => a,
            Err(e) => {
                if !failing {
                    hub.notice(format!("monitor: accepting a connection failed: {e}; retrying with back-off"));
                    failing = true;
                }
                tokio::time::sleep(backoff).await;
                backoff = (backoff * 2).min(Duration::from_secs(1));
                continue;
            }
        };
        if failing {
            hub.notice("monitor: accepting connections again");
            failing = false;
        }
        backoff = Duration::from_millis(10);
        if hub.connected.load(Ordering::Relaxed) >= MAX_CLIENTS {
            continue; // dropping the stream refuses the client
        }
        let _ = stream.set_nodelay(true);
        let hub = hub.clone();
        let access = access.clone();
        tokio::spawn(async move {
            hub.connected.fetch_add(1, Ordering::Relaxed);
            let local = stream.local_addr().unwrap_or(local);
            let dropped = session(stream, &hub, &access, peer.ip(), local).await;
            hub.connected.fetch_sub(1, Ordering::Relaxed);
            if dropped {
                hub.dropped.fetch_add(1, Ordering::Relaxed);
            }
        });
    }
}

/// Checks a token from `ip`: `Ok(true)` right, `Ok(false)` wrong (the client must now wait),
/// `Err` the client must still wait before trying one.
fn try_token(hub: &Hub, ip: IpAddr, token: &str) -> Result<bool, String> {
    let now = std::time::Instant::now();
    let mut g = hub.guesses.lock().unwrap_or_else(|e| e.into_inner());
    if let Err(wait) = g.may_try(ip, now) {
        return Err(format!("too many wrong tokens from {ip}: try again in {:.1} s", wait.as_secs_f64()));
    }
    if same_secret(token, &hub.token) {
        g.succeeded(ip);
        Ok(true)
    } else {
        g.failed(ip, now);
        Ok(false)
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
    let mut rest = s.as_bytes();
    let mut out = Vec::with_capacity(rest.len());
    while let Some((&c, tail)) = rest.split_first() {
        if let [b'%', h, l, after @ ..] = rest {
            if let (Some(h), Some(l)) = (hex(*h), hex(*l)) {
                out.push(h * 16 + l);
                rest = after;
                continue;
            }
        }
        out.push(if c == b'+' { b' ' } else { c });
        rest = tail;
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
    /// The client's address (wrong tokens slow it down).
    ip: IpAddr,
    /// The last RUN/STOP/FAULT change told ([`crate::board::Board::state_seq`]).
    state_seq: u64,
}

/// Why a session ends.
enum End {
    /// The client left, or the run ended.
    Closed,
    /// Dropped for misbehaving.
    Dropped,
}

/// An HTTP error answer to a handshake.
fn refusal(status: u16, why: String) -> ErrorResponse {
    let mut r = ErrorResponse::new(Some(why));
    *r.status_mut() = tokio_tungstenite::tungstenite::http::StatusCode::from_u16(status)
        .unwrap_or(tokio_tungstenite::tungstenite::http::StatusCode::FORBIDDEN);
    r
}

/// Serves one client (from `ip`, connected to `local`); returns whether it was dropped for
/// misbehaving or refused.
async fn session(
    stream: TcpStream,
    hub: &Hub,
    access: &MonitorAccess,
    ip: IpAddr,
    local: std::net::SocketAddr,
) -> bool {
    // The handshake's verdict on the token of the URL: `Some(true)` right, `Some(false)` wrong.
    let verdict: Arc<Mutex<Option<bool>>> = Arc::new(Mutex::new(None));
    let seen = verdict.clone();
    // The error type is tungstenite's.
    #[allow(clippy::result_large_err)]
    let callback = move |req: &HttpRequest, resp: HttpResponse| -> Result<HttpResponse, ErrorResponse> {
        let header = |name: &str| req.headers().get(name).and_then(|v| v.to_str().ok());
        // Two Host (or Origin) headers: which one a proxy or a check reads differs; refused.
        for name in ["host", "origin"] {
            if req.headers().get_all(name).iter().count() > 1 {
                return Err(refusal(400, format!("the request has more than one {name} header")));
            }
        }
        crate::access::check_host(header("host"), local, access).map_err(|why| refusal(403, why))?;
        crate::access::check_origin(header("origin"), access).map_err(|why| refusal(403, why))?;
        if let Some(t) = query_token(&req.uri().to_string()) {
            let ok = try_token(hub, ip, &t).map_err(|why| refusal(429, why))?;
            *seen.lock().unwrap_or_else(|e| e.into_inner()) = Some(ok);
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
    let authorized = *verdict.lock().unwrap_or_else(|e| e.into_inner()) == Some(true);
    let mut s = Session {
        hub,
        out: tx,
        authorized,
        paused: false,
        last: None,
        next_event: 0,
        halted: None,
        next_halt: 0,
        bad_in_row: 0,
        window: tokio::time::Instant::now(),
        in_window: 0,
        ip,
        state_seq: 0,
    };
    hub.sessions.fetch_add(1, Ordering::Relaxed);
    let end = s.run(&mut source).await;
    let dropped = match end {
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
    };
    hub.sessions.fetch_sub(1, Ordering::Relaxed);
    dropped
}

type Source = futures_util::stream::SplitStream<tokio_tungstenite::WebSocketStream<TcpStream>>;

impl Session<'_> {
    async fn run(&mut self, source: &mut Source) -> End {
        let h = {
            let b = self.hub.lock();
            self.state_seq = b.state_seq;
            hello(&self.hub.info, self.authorized, b.halted, b.state, b.fault.as_ref())
        };
        if !self.send(h) {
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
        // A change of RUN/STOP/FAULT since the hello is told as a `state` message, even when the
        // first snapshot (which may wait for guards) already shows it.
        let told = self.state_seq;
        if !self.send_snapshot() {
            return End::Dropped;
        }
        self.state_seq = told;
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
                    if self.hub.closing() {
                        // The run has ended and published its end (the last halt, STOP, the
                        // last scan): send that before closing, however late this tick came.
                        return if self.update() { End::Closed } else { End::Dropped };
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
        let (latest, halted, stats, state, fault) = {
            let b = self.hub.lock();
            self.next_halt = b.next_halt;
            self.state_seq = b.state_seq;
            (b.tail_latest(), b.halted, b.stats_json(), b.state, b.fault.clone())
        };
        let latest = latest.last(&self.hub.info);
        self.halted = Some(halted);
        match latest {
            Some(st) => {
                let ok = self.send(snapshot(&self.hub.info, &st, halted, (state, fault.as_ref()), &stats));
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
        let (events, between, mut halts, halted, reason, state, first) = {
            let b = self.hub.lock();
            // No state sent yet: the first one goes out as a full snapshot, with the run state.
            let first = last_scan.is_none().then(|| (b.stats_json(), b.state, b.fault.clone()));
            let state = (b.state_seq != self.state_seq).then(|| {
                self.state_seq = b.state_seq;
                (b.state, b.fault.clone(), b.tail_latest())
            });
            let halts: Vec<(bool, String)> =
                b.halts.iter().filter(|h| h.seq >= self.next_halt).map(|h| (h.halted, h.reason.clone())).collect();
            self.next_halt = b.next_halt;
            let events: Vec<_> = b.events.iter().filter(|e| e.seq >= self.next_event).cloned().collect();
            let between = match last_scan {
                Some(l) => b.tail_after(l),
                None => b.tail_latest(),
            };
            (events, between, halts, b.halted, b.reason.clone(), state, first)
        };
        // What fired since the last tick, and the newest state with its active steps in full
        // (rebuilt outside the lock).
        let fired_between: Vec<Arc<ScanState>> = between.published().to_vec();
        let newest = between.last(&self.hub.info);
        let state = state.map(|(run, fault, latest)| (run, fault, latest.last(&self.hub.info)));
        // Older changes than the log holds: the state now is what counts.
        if halts.last().map(|h| h.0) != Some(halted) {
            halts.push((halted, reason));
        }
        for e in events {
            self.next_event = e.seq + 1;
            let mut j = e.event.to_json();
            crate::board::put(&mut j, "type", serde_json::json!("event"));
            if !self.send(j) {
                return false;
            }
        }
        if let Some(new) = &newest {
            let msg = match &self.last {
                Some(old) => delta(&self.hub.info, old, new, &fired_between),
                None => {
                    let (stats, run, fault) = first.unwrap_or((serde_json::Value::Null, RunState::Run, None));
                    snapshot(&self.hub.info, new, halted, (run, fault.as_ref()), &stats)
                }
            };
            if !self.send(msg) {
                return false;
            }
            self.last = Some(new.clone());
        }
        if let Some((state, fault, latest)) = state {
            let scan = latest.as_ref().map_or(0, |s| s.scan);
            let mut j = state_message(state, fault.as_ref(), scan);
            // The outputs as they are now (safe values in STOP and FAULT).
            if let Some(st) = latest {
                let mut values = st.values.clone();
                crate::board::shown_values(&self.hub.info, state, &mut values);
                let vars: serde_json::Map<String, serde_json::Value> = self
                    .hub
                    .info
                    .variables
                    .iter()
                    .zip(&values)
                    .filter(|(v, _)| v.safe.is_some())
                    .map(|(v, x)| (v.name.clone(), value_json(x)))
                    .collect();
                j["outputs"] = serde_json::Value::Object(vars);
            }
            if !self.send(j) {
                return false;
            }
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
            match try_token(self.hub, self.ip, t)? {
                true => self.authorized = true,
                false => return Err("wrong token".into()),
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
                let h = {
                    let b = self.hub.lock();
                    hello(info, self.authorized, b.halted, b.state, b.fault.as_ref())
                };
                return Ok(Some(reply_ok(id, h)));
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
                let tail = {
                    let b = self.hub.lock();
                    b.tail(b.history.len().saturating_sub(n))
                };
                let states = tail.full(info);
                let list: Vec<serde_json::Value> = states.iter().map(|s| state_json(info, s)).collect();
                let mut j = serde_json::json!({"type": "history", "re": id, "states": list});
                crate::board::put(&mut j, "ok", serde_json::json!(true));
                return Ok(Some(j.to_string()));
            }
            "explain" => {
                let name = str_field("step").ok_or("`explain` needs `step`")?;
                let s = info.step_index(name).ok_or_else(|| format!("no step `{name}`"))?;
                Command::Explain { step: info.step_name(s) }
            }
            "timing" => Command::Timing,
            "mechanisms" => Command::Mechanisms,
            "reset" => match str_field("mode").unwrap_or("warm") {
                "warm" => Command::Reset { cold: false },
                "cold" => Command::Reset { cold: true },
                other => return Err(format!("unknown reset mode `{other}` (warm, cold)")),
            },
            "stop" => Command::Stop,
            "start" => Command::Start,
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
        if matches!(
            command,
            Command::Halt | Command::Continue | Command::Step | Command::Reset { .. } | Command::Stop | Command::Start
        ) && !info.control
        {
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
