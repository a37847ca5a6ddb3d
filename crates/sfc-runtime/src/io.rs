//! Modbus TCP I/O: the map from located variables to the four Modbus tables
//! (`docs/runtime.md`, "Modbus map"), the process image shared with the scan thread, and the
//! server.
//!
//! | address | Modbus table | client access |
//! |---|---|---|
//! | `%IXa.b` | discrete input `8a+b`, and coil `32768+8a+b` | read; write through the coil |
//! | `%QXa.b` | coil `8a+b` | read |
//! | `%IWn` | input register `n`, and holding register `32768+n` | read; write through the holding register |
//! | `%QWn` | holding register `n` (n < 1000) | read |
//! | `%MWn` | holding register `1000+n` | read and write |
//!
//! Modbus has no function that writes discrete inputs or input registers, so a test bench
//! drives the inputs through the mirror window at 32768.

use crate::Slot;
use sfc_sim::{Simulation, Value};
use std::future::Future;
use std::net::SocketAddr;
use std::pin::Pin;
use std::sync::{Arc, Mutex};
use tokio_modbus::{ExceptionCode, Request, Response};

/// Where clients write inputs: coil / holding register `INPUT_WINDOW + address`.
pub const INPUT_WINDOW: u16 = 32768;
/// `%MWn` is holding register `MEMORY_BASE + n`.
pub const MEMORY_BASE: u16 = 1000;

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Table {
    Coil,
    DiscreteInput,
    InputRegister,
    HoldingRegister,
}

/// Direction of a located variable.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Role {
    /// `%I`: written by clients, copied into the chart before each scan.
    Input,
    /// `%Q`: written by the chart, copied out after each scan.
    Output,
    /// `%M`: both (a client write is applied before the next scan).
    Memory,
}

/// One located variable on the Modbus map.
#[derive(Debug, Clone)]
pub struct IoPoint {
    pub name: String,
    pub location: String,
    pub table: Table,
    pub address: u16,
    pub role: Role,
    pub slot: Slot,
}

/// Maps the located variables of the simulated POU; an address the map does not cover is an
/// error naming it.
pub fn map_located(sim: &Simulation) -> Result<Vec<IoPoint>, String> {
    let mut out: Vec<IoPoint> = Vec::new();
    for (name, location, index, ty) in sim.located_vars() {
        let (table, address, role) = address_of(&location).map_err(|why| format!("`{name}` {location}: {why}"))?;
        if let Some(other) = out.iter().find(|p| p.table == table && p.address == address) {
            return Err(format!(
                "`{name}` {location} and `{}` {} share {} {address}",
                other.name,
                other.location,
                table_name(table)
            ));
        }
        out.push(IoPoint { name, location, table, address, role, slot: Slot { index, ty } });
    }
    Ok(out)
}

pub fn table_name(t: Table) -> &'static str {
    match t {
        Table::Coil => "coil",
        Table::DiscreteInput => "discrete input",
        Table::InputRegister => "input register",
        Table::HoldingRegister => "holding register",
    }
}

/// `%IX0.3` → (discrete input, 3, input).
fn address_of(loc: &str) -> Result<(Table, u16, Role), String> {
    let body = loc.strip_prefix('%').ok_or("not a direct address")?.to_ascii_uppercase();
    let mut chars = body.chars();
    let area = chars.next().ok_or("no area letter")?;
    let rest: String = chars.collect();
    let (size, path) = match rest.chars().next() {
        Some(c) if c.is_ascii_alphabetic() => (c, &rest[1..]),
        _ => ('X', rest.as_str()),
    };
    let nums: Vec<u32> = path
        .split('.')
        .map(|p| p.parse::<u32>().map_err(|_| format!("`{path}` is not a number path")))
        .collect::<Result<_, _>>()?;
    let role = match area {
        'I' => Role::Input,
        'Q' => Role::Output,
        'M' => Role::Memory,
        _ => return Err(format!("unknown area `{area}`")),
    };
    match (size, role, nums.as_slice()) {
        ('X', Role::Memory, _) => Err("%MX is not on the Modbus map (use %MW)".into()),
        ('X', _, [byte, bit]) if *bit < 8 && *byte < 4096 => {
            let a = (byte * 8 + bit) as u16;
            Ok((if role == Role::Input { Table::DiscreteInput } else { Table::Coil }, a, role))
        }
        ('X', _, _) => Err("a bit address is `%IXbyte.bit` with bit 0..7 and byte < 4096".into()),
        ('W', Role::Input, [n]) if *n < u32::from(INPUT_WINDOW) => Ok((Table::InputRegister, *n as u16, role)),
        ('W', Role::Output, [n]) if *n < u32::from(MEMORY_BASE) => Ok((Table::HoldingRegister, *n as u16, role)),
        ('W', Role::Memory, [n]) if *n < u32::from(INPUT_WINDOW - MEMORY_BASE) => {
            Ok((Table::HoldingRegister, MEMORY_BASE + *n as u16, role))
        }
        ('W', _, [_]) => Err(format!(
            "register number out of range (%IW < {INPUT_WINDOW}, %QW < {MEMORY_BASE}, %MW < {})",
            INPUT_WINDOW - MEMORY_BASE
        )),
        ('W', _, _) => Err("a word address is `%IWn`".into()),
        (s, _, _) => Err(format!("size `{s}` is not on the Modbus map: only X (bits) and W (16-bit words) are")),
    }
}

/// The process image: what clients see and write. Inputs hold the last value a client (or a
/// monitor `set`) wrote; outputs the value the last scan left.
#[derive(Debug, Default)]
pub struct Image {
    pub coils: Vec<bool>,
    pub discrete: Vec<bool>,
    pub input_regs: Vec<u16>,
    pub holding: Vec<u16>,
    /// `%MW` points written by clients since the last scan (the value is in `holding`).
    pub memory_writes: Vec<usize>,
}

impl Image {
    pub fn new(points: &[IoPoint]) -> Image {
        let size = |t: Table| points.iter().filter(|p| p.table == t).map(|p| p.address as usize + 1).max().unwrap_or(0);
        Image {
            coils: vec![false; size(Table::Coil)],
            discrete: vec![false; size(Table::DiscreteInput)],
            input_regs: vec![0; size(Table::InputRegister)],
            holding: vec![0; size(Table::HoldingRegister)],
            memory_writes: Vec::new(),
        }
    }

    /// Reads the value of `p` from the image as the chart's value.
    pub fn get(&self, p: &IoPoint) -> Value {
        let a = p.address as usize;
        // Every point's address lies in its table (the image is sized from the points).
        match p.table {
            Table::Coil => Value::Bool(self.coils.get(a).copied().unwrap_or(false)),
            Table::DiscreteInput => Value::Bool(self.discrete.get(a).copied().unwrap_or(false)),
            Table::InputRegister => word_value(self.input_regs.get(a).copied().unwrap_or(0), &p.slot.ty),
            Table::HoldingRegister => word_value(self.holding.get(a).copied().unwrap_or(0), &p.slot.ty),
        }
    }

    /// Stores the chart's value of `p` in the image.
    pub fn put(&mut self, p: &IoPoint, v: &Value) {
        let a = p.address as usize;
        let bit = v.as_bool().unwrap_or(false);
        let word = v.as_int().unwrap_or(0) as u16;
        match p.table {
            Table::Coil => set(&mut self.coils, a, bit),
            Table::DiscreteInput => set(&mut self.discrete, a, bit),
            Table::InputRegister => set(&mut self.input_regs, a, word),
            Table::HoldingRegister => set(&mut self.holding, a, word),
        }
    }
}

/// A register as the variable's type: INT is two's complement, the others unsigned.
fn word_value(w: u16, ty: &sfc_st::Type) -> Value {
    if ty.is_signed() {
        Value::Int(i64::from(w as i16))
    } else {
        Value::Int(i64::from(w))
    }
}

/// The Modbus service of one connection.
struct Service {
    points: Arc<Vec<IoPoint>>,
    image: Arc<Mutex<Image>>,
}

type Reply = Result<Response, ExceptionCode>;

impl Service {
    fn handle(&self, req: Request<'_>) -> Reply {
        let mut img = self.image.lock().unwrap_or_else(|e| e.into_inner());
        match req {
            Request::ReadCoils(a, n) => {
                let (a, n) = (a as usize, n as usize);
                if a >= INPUT_WINDOW as usize {
                    return read_range(&img.discrete, a - INPUT_WINDOW as usize, n).map(Response::ReadCoils);
                }
                read_range(&img.coils, a, n).map(Response::ReadCoils)
            }
            Request::ReadDiscreteInputs(a, n) => {
                read_range(&img.discrete, a as usize, n as usize).map(Response::ReadDiscreteInputs)
            }
            Request::ReadInputRegisters(a, n) => {
                read_range(&img.input_regs, a as usize, n as usize).map(Response::ReadInputRegisters)
            }
            Request::ReadHoldingRegisters(a, n) => self.read_holding(&img, a, n).map(Response::ReadHoldingRegisters),
            Request::WriteSingleCoil(a, v) => {
                self.write_coils(&mut img, a, &[v])?;
                Ok(Response::WriteSingleCoil(a, v))
            }
            Request::WriteMultipleCoils(a, vs) => {
                self.write_coils(&mut img, a, &vs)?;
                Ok(Response::WriteMultipleCoils(a, vs.len() as u16))
            }
            Request::WriteSingleRegister(a, v) => {
                self.write_registers(&mut img, a, &[v])?;
                Ok(Response::WriteSingleRegister(a, v))
            }
            Request::WriteMultipleRegisters(a, vs) => {
                self.write_registers(&mut img, a, &vs)?;
                Ok(Response::WriteMultipleRegisters(a, vs.len() as u16))
            }
            Request::ReadWriteMultipleRegisters(ra, n, wa, vs) => {
                self.write_registers(&mut img, wa, &vs)?;
                self.read_holding(&img, ra, n).map(Response::ReadWriteMultipleRegisters)
            }
            _ => Err(ExceptionCode::IllegalFunction),
        }
    }

    fn read_holding(&self, img: &Image, a: u16, n: u16) -> Result<Vec<u16>, ExceptionCode> {
        if a >= INPUT_WINDOW {
            return read_range(&img.input_regs, (a - INPUT_WINDOW) as usize, n as usize);
        }
        read_range(&img.holding, a as usize, n as usize)
    }

    /// Coils: only the input window is writable (outputs belong to the chart).
    fn write_coils(&self, img: &mut Image, a: u16, vs: &[bool]) -> Result<(), ExceptionCode> {
        let targets = self.targets(a, vs.len(), |p| p.table == Table::DiscreteInput, INPUT_WINDOW)?;
        for (i, v) in targets.into_iter().zip(vs) {
            if let Some(p) = self.points.get(i) {
                set(&mut img.discrete, p.address as usize, *v);
            }
        }
        Ok(())
    }

    /// Holding registers: `%MW` and the `%IW` window are writable, `%QW` is not.
    fn write_registers(&self, img: &mut Image, a: u16, vs: &[u16]) -> Result<(), ExceptionCode> {
        let targets = if a >= INPUT_WINDOW {
            self.targets(a, vs.len(), |p| p.table == Table::InputRegister, INPUT_WINDOW)?
        } else {
            self.targets(a, vs.len(), |p| p.table == Table::HoldingRegister && p.role == Role::Memory, 0)?
        };
        for (i, &v) in targets.into_iter().zip(vs) {
            let Some(p) = self.points.get(i) else { continue };
            match p.table {
                Table::InputRegister => set(&mut img.input_regs, p.address as usize, v),
                _ => {
                    set(&mut img.holding, p.address as usize, v);
                    img.memory_writes.push(i);
                }
            }
        }
        Ok(())
    }

    /// The points written by `len` values from `a` (each must be a point accepted by `ok`,
    /// at `offset + address`), or IllegalDataAddress.
    fn targets(
        &self,
        a: u16,
        len: usize,
        ok: impl Fn(&IoPoint) -> bool,
        offset: u16,
    ) -> Result<Vec<usize>, ExceptionCode> {
        let mut out = Vec::with_capacity(len);
        for k in 0..len {
            let addr = a as usize + k;
            let i = self
                .points
                .iter()
                .position(|p| ok(p) && p.address as usize + offset as usize == addr)
                .ok_or(ExceptionCode::IllegalDataAddress)?;
            out.push(i);
        }
        Ok(out)
    }
}

fn read_range<T: Copy>(table: &[T], a: usize, n: usize) -> Result<Vec<T>, ExceptionCode> {
    match a.checked_add(n).and_then(|end| table.get(a..end)) {
        Some(values) if n > 0 => Ok(values.to_vec()),
        _ => Err(ExceptionCode::IllegalDataAddress),
    }
}

/// Stores `v` at `a` in a table of the image (an address outside it changes nothing).
fn set<T>(table: &mut [T], a: usize, v: T) {
    if let Some(slot) = table.get_mut(a) {
        *slot = v;
    }
}

impl tokio_modbus::server::Service for Service {
    type Request = Request<'static>;
    type Response = Response;
    type Exception = ExceptionCode;
    type Future = Pin<Box<dyn Future<Output = Reply> + Send>>;

    fn call(&self, req: Self::Request) -> Self::Future {
        let r = self.handle(req);
        Box::pin(std::future::ready(r))
    }
}

/// Serves Modbus on `listener` (inside the runtime's tokio runtime) until the task is dropped.
pub async fn serve(listener: std::net::TcpListener, points: Arc<Vec<IoPoint>>, image: Arc<Mutex<Image>>) {
    let Ok(listener) = tokio::net::TcpListener::from_std(listener) else { return };
    let server = tokio_modbus::server::tcp::Server::new(listener);
    let on_connected = move |stream: tokio::net::TcpStream, _addr: SocketAddr| {
        let _ = stream.set_nodelay(true);
        let svc = Service { points: points.clone(), image: image.clone() };
        async move { Ok(Some((svc, stream))) }
    };
    // A broken connection ends only that connection's task.
    let _ = server.serve(&on_connected, |_err| {}).await;
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn addresses_follow_the_table() {
        assert_eq!(address_of("%IX0.3"), Ok((Table::DiscreteInput, 3, Role::Input)));
        assert_eq!(address_of("%QX1.2"), Ok((Table::Coil, 10, Role::Output)));
        assert_eq!(address_of("%I2.1"), Ok((Table::DiscreteInput, 17, Role::Input)));
        assert_eq!(address_of("%IW7"), Ok((Table::InputRegister, 7, Role::Input)));
        assert_eq!(address_of("%QW5"), Ok((Table::HoldingRegister, 5, Role::Output)));
        assert_eq!(address_of("%MW5"), Ok((Table::HoldingRegister, 1005, Role::Memory)));
        assert!(address_of("%QW1000").is_err());
        assert!(address_of("%ID0").unwrap_err().contains("size `D`"));
        assert!(address_of("%MX0.0").is_err());
        assert!(address_of("%IX0.8").is_err());
    }
}
