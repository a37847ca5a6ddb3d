//! The Modbus TCP server: its own accept loop and frame handling, written to the MODBUS
//! Application Protocol Specification V1.1b3 and the Messaging on TCP/IP Implementation Guide
//! V1.0b.
//!
//! Why not a library's server: tokio-modbus decodes a request it finds malformed (a coil value
//! other than 0xFF00/0x0000, a byte count that disagrees with the quantity) as an I/O error and
//! closes the connection, where the specification asks for exception 3; and its `Server::serve`
//! returns on the first failed `accept`. A server that must keep serving owns both.
//!
//! - The accept loop survives errors (file descriptors exhausted, …) by backing off, from
//!   10 ms doubling to 1 s, and counts them.
//! - At most [`ModbusLimits::max_clients`] connections are served; one more is closed at once.
//! - A connection that sends no complete request for [`ModbusLimits::idle_timeout`] is closed.
//! - Requests are checked as the specification's state diagrams do: an unknown function is
//!   exception 1, a quantity out of range or a byte count that disagrees with it (or with the
//!   frame) exception 3, an address outside the map exception 2. A read/write (FC 23) checks both
//!   parts before it writes anything.

use crate::board::Command;
use crate::board::Hub;
use crate::io::{Image, IoPoint, Role, Table, INPUT_WINDOW, RECORD_BASE, RESET_ADDRESS};
use std::sync::atomic::{AtomicU64, AtomicUsize, Ordering};
use std::sync::{Arc, Mutex};
use std::time::Duration;
use tokio::io::{AsyncReadExt, AsyncWriteExt};

/// Limits of the Modbus server.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ModbusLimits {
    /// Connections served at once (default 32).
    pub max_clients: usize,
    /// A connection without a request for this long is closed (default 60 s).
    pub idle_timeout: Duration,
}

impl Default for ModbusLimits {
    fn default() -> Self {
        ModbusLimits { max_clients: 32, idle_timeout: Duration::from_secs(60) }
    }
}

/// What the server has done, for the statistics.
#[derive(Debug, Default)]
pub struct ModbusCounters {
    pub accepted: AtomicU64,
    /// Connections closed at once because `max_clients` were served.
    pub refused: AtomicU64,
    /// Connections closed for being idle.
    pub idle_closed: AtomicU64,
    /// Failed `accept` calls.
    pub accept_errors: AtomicU64,
    pub requests: AtomicU64,
    /// Requests answered with an exception.
    pub exceptions: AtomicU64,
    /// Connections open now.
    pub open: AtomicUsize,
}

impl ModbusCounters {
    pub fn to_json(&self) -> serde_json::Value {
        let g = |a: &AtomicU64| a.load(Ordering::Relaxed);
        serde_json::json!({
            "open": self.open.load(Ordering::Relaxed),
            "accepted": g(&self.accepted),
            "refused": g(&self.refused),
            "idleClosed": g(&self.idle_closed),
            "acceptErrors": g(&self.accept_errors),
            "requests": g(&self.requests),
            "exceptions": g(&self.exceptions),
        })
    }
}

/// Modbus exception codes.
pub const ILLEGAL_FUNCTION: u8 = 1;
pub const ILLEGAL_DATA_ADDRESS: u8 = 2;
pub const ILLEGAL_DATA_VALUE: u8 = 3;
/// The run has ended: a reset can no longer be taken.
pub const SERVER_DEVICE_FAILURE: u8 = 4;

/// Largest PDU (the MBAP length counts the unit identifier too: at most 254).
const MAX_PDU: usize = 253;

/// The map and the image a connection serves.
pub struct Service {
    pub points: Arc<Vec<IoPoint>>,
    pub image: Arc<Mutex<Image>>,
    /// With `--modbus-reset`: where a write of the reset register or coil goes.
    pub reset: Option<Arc<Hub>>,
}

fn u16_at(pdu: &[u8], i: usize) -> u16 {
    // Callers check the PDU's length first; a short one reads as zeros, never a panic.
    let byte = |k: usize| pdu.get(k).copied().unwrap_or(0);
    u16::from_be_bytes([byte(i), byte(i + 1)])
}

/// A reply PDU: `Ok` the response, `Err` an exception code.
type Reply = Result<Vec<u8>, u8>;

fn pack_bits(bits: &[bool]) -> Vec<u8> {
    let mut out = vec![0u8; bits.len().div_ceil(8)];
    for (i, &b) in bits.iter().enumerate() {
        if let Some(byte) = out.get_mut(i / 8).filter(|_| b) {
            *byte |= 1 << (i % 8);
        }
    }
    out
}

fn read_range<T: Copy>(table: &[T], a: usize, n: usize) -> Result<&[T], u8> {
    table.get(a..a + n).ok_or(ILLEGAL_DATA_ADDRESS)
}

impl Service {
    /// Answers one request PDU (function code and data) with a response PDU.
    pub fn handle(&self, pdu: &[u8]) -> Vec<u8> {
        let fc = pdu.first().copied().unwrap_or(0);
        match self.reply(pdu) {
            Ok(r) => r,
            Err(code) => vec![fc | 0x80, code],
        }
    }

    /// A request for the reset register or coil ([`RESET_ADDRESS`], with `--modbus-reset`):
    /// `None` when `pdu` is about something else. Holding register 40000 takes 1 (warm reset),
    /// 2 (cold reset) or 0 (nothing, as an HMI clears its command); coil 40000 takes TRUE (warm
    /// reset) or FALSE (nothing); both read 0.
    fn reset_request(&self, pdu: &[u8]) -> Option<Reply> {
        let hub = self.reset.as_ref()?;
        let fc = *pdu.first()?;
        let (a, n) = (u16_at(pdu, 1), u16_at(pdu, 3));
        if a != RESET_ADDRESS {
            return None;
        }
        // The value written, for a write of exactly the one register or coil.
        let value = match fc {
            1 | 3 if pdu.len() == 5 && n == 1 => {
                return Some(Ok(if fc == 1 { vec![1, 1, 0] } else { vec![3, 2, 0, 0] }));
            }
            5 if pdu.len() == 5 => match n {
                0xFF00 => 1,
                0x0000 => 0,
                _ => return Some(Err(ILLEGAL_DATA_VALUE)),
            },
            6 if pdu.len() == 5 => n,
            15 if pdu.len() == 7 && n == 1 && pdu.get(5) == Some(&1) => u16::from(pdu.get(6)? & 1),
            16 if pdu.len() == 8 && n == 1 && pdu.get(5) == Some(&2) => u16_at(pdu, 6),
            _ => return None,
        };
        let cold = match value {
            0 => None,
            1 => Some(false),
            2 if fc != 5 && fc != 15 => Some(true),
            _ => return Some(Err(ILLEGAL_DATA_VALUE)),
        };
        if let Some(cold) = cold {
            hub.notice(format!(
                "sfc run: Modbus: {} reset requested ({} {RESET_ADDRESS})",
                if cold { "cold" } else { "warm" },
                if fc == 5 || fc == 15 { "coil" } else { "holding register" }
            ));
            if !hub.command(Command::Reset { cold }) {
                return Some(Err(SERVER_DEVICE_FAILURE));
            }
        }
        Some(Ok(match fc {
            15 | 16 => pdu.get(..5).unwrap_or(pdu).to_vec(),
            _ => pdu.to_vec(),
        }))
    }

    fn reply(&self, pdu: &[u8]) -> Reply {
        if let Some(r) = self.reset_request(pdu) {
            return r;
        }
        let fc = pdu.first().copied().unwrap_or(0);
        let byte = |k: usize| pdu.get(k).copied().unwrap_or(0);
        let head = || pdu.get(..5).unwrap_or(pdu).to_vec();
        // The length each function's request must have (beyond the function code).
        let fixed = |n: usize| if pdu.len() == 1 + n { Ok(()) } else { Err(ILLEGAL_DATA_VALUE) };
        match fc {
            1 | 2 => {
                fixed(4)?;
                let (a, n) = (u16_at(pdu, 1) as usize, u16_at(pdu, 3) as usize);
                if !(1..=2000).contains(&n) {
                    return Err(ILLEGAL_DATA_VALUE);
                }
                let img = self.lock();
                let bits = if fc == 1 && a >= INPUT_WINDOW as usize {
                    read_range(&img.discrete, a - INPUT_WINDOW as usize, n)?
                } else if fc == 1 {
                    read_range(&img.coils, a, n)?
                } else {
                    read_range(&img.discrete, a, n)?
                };
                let packed = pack_bits(bits);
                let mut r = vec![fc, packed.len() as u8];
                r.extend(packed);
                Ok(r)
            }
            3 | 4 => {
                fixed(4)?;
                let (a, n) = (u16_at(pdu, 1) as usize, u16_at(pdu, 3) as usize);
                if !(1..=125).contains(&n) {
                    return Err(ILLEGAL_DATA_VALUE);
                }
                let img = self.lock();
                let regs = if fc == 3 {
                    self.holding_view(&img, a, n)?
                } else if a >= RECORD_BASE as usize {
                    read_range(&img.system, a - RECORD_BASE as usize, n)?
                } else {
                    read_range(&img.input_regs, a, n)?
                };
                Ok(registers_reply(fc, regs))
            }
            5 => {
                fixed(4)?;
                let (a, v) = (u16_at(pdu, 1), u16_at(pdu, 3));
                let bit = match v {
                    0xFF00 => true,
                    0x0000 => false,
                    _ => return Err(ILLEGAL_DATA_VALUE),
                };
                let mut img = self.lock();
                self.write_coils(&mut img, a as usize, &[bit])?;
                Ok(pdu.to_vec())
            }
            6 => {
                fixed(4)?;
                let (a, v) = (u16_at(pdu, 1), u16_at(pdu, 3));
                let mut img = self.lock();
                self.write_registers(&mut img, a as usize, &[v])?;
                Ok(pdu.to_vec())
            }
            15 => {
                if pdu.len() < 6 {
                    return Err(ILLEGAL_DATA_VALUE);
                }
                let (a, n, count) = (u16_at(pdu, 1) as usize, u16_at(pdu, 3) as usize, byte(5) as usize);
                if !(1..=0x07B0).contains(&n) || count != n.div_ceil(8) || pdu.len() != 6 + count {
                    return Err(ILLEGAL_DATA_VALUE);
                }
                let bits: Vec<bool> = (0..n).map(|i| byte(6 + i / 8) >> (i % 8) & 1 == 1).collect();
                let mut img = self.lock();
                self.write_coils(&mut img, a, &bits)?;
                Ok(head())
            }
            16 => {
                if pdu.len() < 6 {
                    return Err(ILLEGAL_DATA_VALUE);
                }
                let (a, n, count) = (u16_at(pdu, 1) as usize, u16_at(pdu, 3) as usize, byte(5) as usize);
                if !(1..=0x007B).contains(&n) || count != 2 * n || pdu.len() != 6 + count {
                    return Err(ILLEGAL_DATA_VALUE);
                }
                let regs: Vec<u16> = (0..n).map(|i| u16_at(pdu, 6 + 2 * i)).collect();
                let mut img = self.lock();
                self.write_registers(&mut img, a, &regs)?;
                Ok(head())
            }
            23 => {
                if pdu.len() < 10 {
                    return Err(ILLEGAL_DATA_VALUE);
                }
                let (ra, rn) = (u16_at(pdu, 1) as usize, u16_at(pdu, 3) as usize);
                let (wa, wn, count) = (u16_at(pdu, 5) as usize, u16_at(pdu, 7) as usize, byte(9) as usize);
                if !(1..=0x007D).contains(&rn)
                    || !(1..=0x0079).contains(&wn)
                    || count != 2 * wn
                    || pdu.len() != 10 + count
                {
                    return Err(ILLEGAL_DATA_VALUE);
                }
                let regs: Vec<u16> = (0..wn).map(|i| u16_at(pdu, 10 + 2 * i)).collect();
                let mut img = self.lock();
                // All or nothing: both parts are checked before the write.
                self.holding_view(&img, ra, rn)?;
                self.register_targets(&img, wa, wn)?;
                self.write_registers(&mut img, wa, &regs)?;
                let read = self.holding_view(&img, ra, rn)?.to_vec();
                Ok(registers_reply(fc, &read))
            }
            _ => Err(ILLEGAL_FUNCTION),
        }
    }

    fn lock(&self) -> std::sync::MutexGuard<'_, Image> {
        self.image.lock().unwrap_or_else(|e| e.into_inner())
    }

    /// Holding registers as read: the table, or the inputs' mirror window at 32768.
    fn holding_view<'a>(&self, img: &'a Image, a: usize, n: usize) -> Result<&'a [u16], u8> {
        if a >= INPUT_WINDOW as usize {
            return read_range(&img.input_regs, a - INPUT_WINDOW as usize, n);
        }
        read_range(&img.holding, a, n)
    }

    /// Coils: only the input window is writable (outputs belong to the chart).
    fn write_coils(&self, img: &mut Image, a: usize, bits: &[bool]) -> Result<(), u8> {
        if a < INPUT_WINDOW as usize {
            return Err(ILLEGAL_DATA_ADDRESS);
        }
        let base = a - INPUT_WINDOW as usize;
        let mut targets = Vec::with_capacity(bits.len());
        for k in 0..bits.len() {
            let i = img.owner(Table::DiscreteInput, base + k).ok_or(ILLEGAL_DATA_ADDRESS)?;
            targets.push(i);
        }
        for (i, &b) in targets.into_iter().zip(bits) {
            if let Some(p) = self.points.get(i) {
                img.write_input(i, p, sfc_sim::Value::Bool(b));
            }
        }
        Ok(())
    }

    /// The points written by `n` registers from holding register `a`: the input window at
    /// 32768, or `%M` memory; `%Q` outputs are not writable.
    fn register_targets(&self, img: &Image, a: usize, n: usize) -> Result<Vec<usize>, u8> {
        let (table, base) = if a >= INPUT_WINDOW as usize {
            (Table::InputRegister, a - INPUT_WINDOW as usize)
        } else {
            (Table::HoldingRegister, a)
        };
        let mut out: Vec<usize> = Vec::new();
        for k in 0..n {
            let i = img.owner(table, base + k).ok_or(ILLEGAL_DATA_ADDRESS)?;
            if self.points.get(i).is_none_or(|p| p.role == Role::Output) {
                return Err(ILLEGAL_DATA_ADDRESS);
            }
            if out.last() != Some(&i) {
                out.push(i);
            }
        }
        Ok(out)
    }

    fn write_registers(&self, img: &mut Image, a: usize, regs: &[u16]) -> Result<(), u8> {
        let targets = self.register_targets(img, a, regs.len())?;
        let input = a >= INPUT_WINDOW as usize;
        let base = if input { a - INPUT_WINDOW as usize } else { a };
        // The registers of a wide value may be written one at a time: a point takes the new
        // registers over its current ones.
        // The points and their registers are the map built at start, which sized the tables.
        for &i in &targets {
            let Some(p) = self.points.get(i) else { return Err(ILLEGAL_DATA_ADDRESS) };
            let range = p.address as usize..(p.address + p.words) as usize;
            let table = if input { &mut img.input_regs } else { &mut img.holding };
            let Some(words) = table.get_mut(range) else { return Err(ILLEGAL_DATA_ADDRESS) };
            for (k, w) in words.iter_mut().enumerate() {
                let at = p.address as usize + k;
                if let Some(&r) = at.checked_sub(base).and_then(|k| regs.get(k)) {
                    *w = r;
                }
            }
            if input {
                let v = img.get(p);
                if let Some(f) = img.forced.get(i).cloned().flatten() {
                    img.put(p, &f);
                }
                if let Some(c) = img.client.get_mut(i) {
                    *c = v;
                }
            } else if !img.memory_writes.contains(&i) {
                // Once per point: in STOP no scan takes them, and a client may write for hours.
                img.memory_writes.push(i);
            }
        }
        Ok(())
    }
}

fn registers_reply(fc: u8, regs: &[u16]) -> Vec<u8> {
    let mut r = Vec::with_capacity(2 + 2 * regs.len());
    r.push(fc);
    r.push((2 * regs.len()) as u8);
    for w in regs {
        r.extend_from_slice(&w.to_be_bytes());
    }
    r
}

/// Serves Modbus on `listener` (inside the runtime's tokio runtime) until the hub stops.
pub async fn serve(
    listener: std::net::TcpListener,
    service: Arc<Service>,
    limits: ModbusLimits,
    counters: Arc<ModbusCounters>,
    hub: Arc<Hub>,
) {
    let listener = match tokio::net::TcpListener::from_std(listener) {
        Ok(l) => l,
        Err(e) => {
            hub.notice(format!("Modbus: cannot serve: {e}"));
            return;
        }
    };
    const FIRST_BACKOFF: Duration = Duration::from_millis(10);
    let mut backoff = FIRST_BACKOFF;
    let mut errors_told = 0u64;
    let mut refusals_told = 0u64;
    loop {
        let accepted = tokio::select! {
            a = listener.accept() => a,
            _ = tokio::time::sleep(Duration::from_millis(100)) => {
                if hub.closing() { return; }
                continue;
            }
        };
        match accepted {
            Ok((stream, _peer)) => {
                backoff = FIRST_BACKOFF;
                if errors_told > 0 {
                    let n = counters.accept_errors.load(Ordering::Relaxed);
                    hub.notice(format!("Modbus: accepting connections again (after {n} failed accepts)"));
                    errors_told = 0;
                }
                if counters.open.load(Ordering::Relaxed) >= limits.max_clients {
                    let n = counters.refused.fetch_add(1, Ordering::Relaxed) + 1;
                    // The first refusal, then every 100th, is told.
                    if n == 1 || n >= refusals_told + 100 {
                        refusals_told = n;
                        hub.notice(format!(
                            "Modbus: {} clients are connected (the limit): a new connection was closed ({n} so far)",
                            limits.max_clients
                        ));
                    }
                    drop(stream);
                    continue;
                }
                counters.accepted.fetch_add(1, Ordering::Relaxed);
                counters.open.fetch_add(1, Ordering::Relaxed);
                let (service, counters, hub) = (service.clone(), counters.clone(), hub.clone());
                tokio::spawn(async move {
                    connection(stream, &service, limits, &counters, &hub).await;
                    counters.open.fetch_sub(1, Ordering::Relaxed);
                });
            }
            Err(e) => {
                let n = counters.accept_errors.fetch_add(1, Ordering::Relaxed) + 1;
                if errors_told == 0 {
                    hub.notice(format!("Modbus: accepting a connection failed: {e}; retrying with back-off"));
                }
                errors_told = n;
                tokio::time::sleep(backoff).await;
                backoff = (backoff * 2).min(Duration::from_secs(1));
            }
        }
    }
}

/// Serves one connection: MBAP header, PDU, answer; until the client leaves, is idle too long,
/// sends a frame that cannot be delimited, or the run stops.
async fn connection(
    mut stream: tokio::net::TcpStream,
    service: &Service,
    limits: ModbusLimits,
    counters: &ModbusCounters,
    hub: &Hub,
) {
    let _ = stream.set_nodelay(true);
    let mut head = [0u8; 7];
    let mut pdu = [0u8; MAX_PDU];
    loop {
        // An idle connection is closed; the run's end is noticed within a second.
        let mut waited = Duration::ZERO;
        let got = loop {
            let slice = Duration::from_secs(1).min(limits.idle_timeout.saturating_sub(waited));
            match tokio::time::timeout(slice, stream.read_exact(&mut head[..1])).await {
                Ok(r) => break Some(r),
                Err(_) => {
                    waited += slice;
                    if hub.closing() {
                        return;
                    }
                    if waited >= limits.idle_timeout {
                        break None;
                    }
                }
            }
        };
        match got {
            None => {
                counters.idle_closed.fetch_add(1, Ordering::Relaxed);
                return;
            }
            Some(Err(_)) => return,
            Some(Ok(_)) => {}
        }
        // The rest of the frame must follow within the idle timeout too.
        let rest = async {
            stream.read_exact(&mut head[1..]).await?;
            let len = u16::from_be_bytes([head[4], head[5]]) as usize;
            if !(2..=MAX_PDU + 1).contains(&len) {
                return Err(std::io::Error::new(std::io::ErrorKind::InvalidData, "bad MBAP length"));
            }
            let body = pdu.get_mut(..len - 1).ok_or(std::io::ErrorKind::InvalidData)?;
            stream.read_exact(body).await?;
            Ok(len - 1)
        };
        let n = match tokio::time::timeout(limits.idle_timeout, rest).await {
            Ok(Ok(n)) => n,
            Ok(Err(_)) => return,
            Err(_) => {
                counters.idle_closed.fetch_add(1, Ordering::Relaxed);
                return;
            }
        };
        // Another protocol than Modbus (protocol identifier ≠ 0): the frame is discarded.
        if head[2] != 0 || head[3] != 0 {
            continue;
        }
        counters.requests.fetch_add(1, Ordering::Relaxed);
        let reply = service.handle(pdu.get(..n).unwrap_or_default());
        if reply.first().is_some_and(|fc| fc & 0x80 != 0) {
            counters.exceptions.fetch_add(1, Ordering::Relaxed);
        }
        let mut frame = Vec::with_capacity(7 + reply.len());
        frame.extend_from_slice(&head[..4]);
        frame.extend_from_slice(&((reply.len() + 1) as u16).to_be_bytes());
        frame.push(head[6]);
        frame.extend_from_slice(&reply);
        match tokio::time::timeout(limits.idle_timeout, stream.write_all(&frame)).await {
            Ok(Ok(())) => {}
            _ => return,
        }
    }
}
