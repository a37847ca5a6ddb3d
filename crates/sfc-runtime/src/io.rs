//! The Modbus map: located variables on the four Modbus tables (`docs/runtime.md`, "Modbus
//! map"), and the process image the scan thread and the Modbus server share.
//!
//! | address | Modbus table | client access |
//! |---|---|---|
//! | `%IXa.b` | discrete input `8a+b`, and coil `32768+8a+b` | read; write through the coil |
//! | `%QXa.b` | coil `8a+b` | read |
//! | `%IWn` / `%IDn` / `%ILn` | input registers `n` / `2n, 2n+1` / `4n…4n+3`, and holding registers `32768+` the same | read; write through the holding registers |
//! | `%QWn` / `%QDn` / `%QLn` | holding registers `n` / `2n, 2n+1` / `4n…4n+3` (below 1000) | read |
//! | `%MWn` / `%MDn` / `%MLn` | holding registers `1000+` the same | read and write |
//!
//! Values wider than a register span two (32 bits: DINT, UDINT, DWORD, REAL) or four (64 bits:
//! LINT, ULINT, LWORD, LREAL) registers, in the [`WordOrder`] of the run. Modbus has no
//! function that writes discrete inputs or input registers, so a test bench drives the inputs
//! through the mirror window at 32768.

// Indices here come from tables this crate builds at start (the Modbus map, the variables) or
// are checked against the frame length just before (Modbus PDUs); the runtime work of issue 14
// landed after the workspace lints, and its conversion to `get` is still to do (ARCHITECTURE.md).
#![allow(clippy::indexing_slicing)]

use crate::Slot;
use sfc_sim::{Simulation, Value};
use sfc_st::Type;

/// Where clients write inputs: coil / holding register `INPUT_WINDOW + address`.
pub const INPUT_WINDOW: u16 = 32768;
/// `%MWn` is holding register `MEMORY_BASE + n`.
pub const MEMORY_BASE: u16 = 1000;
/// The last error record is input register block `RECORD_BASE …` (read-only, FC 4;
/// `docs/runtime.md`, "Error records on Modbus").
pub const RECORD_BASE: u16 = 40000;
/// Registers of the record's text: two bytes of UTF-8 each, the first in the high byte.
pub const RECORD_TEXT_REGISTERS: usize = 200;
/// Registers before the text: count, code (2), time waited (2), supervision time (2), length.
const RECORD_HEAD: usize = 8;
/// The whole block.
pub const RECORD_REGISTERS: usize = RECORD_HEAD + RECORD_TEXT_REGISTERS;
/// The run's status block is input register block `STATUS_BASE …` (read-only, FC 4;
/// `docs/runtime.md`, "Status on Modbus"): state, halted, scan number, last fault.
pub const STATUS_BASE: u16 = 40300;
/// State (0 RUN, 1 STOP, 2 FAULT), halted, scan number (4), last fault code, faults.
pub const STATUS_REGISTERS: usize = 8;
/// The run's own input registers from [`RECORD_BASE`]: the error record, then (after a gap that
/// reads zeros) the status block.
const SYSTEM_REGISTERS: usize = (STATUS_BASE - RECORD_BASE) as usize + STATUS_REGISTERS;
/// With `--modbus-reset`, holding register `RESET_ADDRESS` (write 1: warm reset, 2: cold
/// reset) and coil `RESET_ADDRESS` (write TRUE: warm reset) restart the chart.
pub const RESET_ADDRESS: u16 = 40000;

/// A fault's code in the status block.
pub const FAULT_WATCHDOG: u16 = 1;
pub const FAULT_ERROR: u16 = 2;

/// What the status block says (`docs/runtime.md`, "Status on Modbus").
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Status {
    /// 0 RUN, 1 STOP, 2 FAULT.
    pub state: u16,
    pub halted: bool,
    /// The scan whose values the image holds.
    pub scan: u64,
    /// The last fault: 0 none, [`FAULT_WATCHDOG`], [`FAULT_ERROR`] (kept after a reset).
    pub fault: u16,
    /// Faults since the start (wraps at 65,536).
    pub faults: u64,
}

impl Status {
    /// The block's registers (the scan number in the run's word order).
    pub fn registers(&self, order: WordOrder) -> [u16; STATUS_REGISTERS] {
        let mut regs = [0u16; STATUS_REGISTERS];
        regs[0] = self.state;
        regs[1] = u16::from(self.halted);
        let mut w = [0u16; 4];
        to_words(&Value::Int(self.scan as i64), &Type::ULInt, 4, order, &mut w);
        regs[2..6].copy_from_slice(&w);
        regs[6] = self.fault;
        regs[7] = self.faults as u16;
        regs
    }
}

/// The error record block's registers for the `count`-th record of the run (`count` wraps at
/// 65,536): count, error code (DINT, 0 when none), time waited and supervision time (UDINT,
/// ms; 0 when the chart's own timer guard ended the wait), the text's length in bytes, then the
/// text ([`sfc_sim::ErrorRecord::message`]) in UTF-8. A text longer than the block is cut at a
/// character boundary and ends with `...`, so a cut is never silent.
pub fn record_registers(count: u64, r: &sfc_sim::ErrorRecord, order: WordOrder) -> Vec<u16> {
    let mut regs = vec![0u16; RECORD_REGISTERS];
    regs[0] = count as u16;
    let mut wide = |at: usize, v: i64, ty: &Type| {
        let mut w = [0u16; 4];
        to_words(&Value::Int(v), ty, 2, order, &mut w);
        regs[at..at + 2].copy_from_slice(&w[..2]);
    };
    wide(1, r.code.unwrap_or(0).clamp(i64::from(i32::MIN), i64::from(i32::MAX)), &Type::DInt);
    let ms = |us: i64| (us / 1000).clamp(0, i64::from(u32::MAX));
    wide(3, ms(r.waited), &Type::UDInt);
    wide(5, ms(r.timeout.unwrap_or(0)), &Type::UDInt);
    let text = r.message();
    let room = 2 * RECORD_TEXT_REGISTERS;
    let bytes: Vec<u8> = if text.len() <= room {
        text.into_bytes()
    } else {
        let mut end = room - 3;
        while !text.is_char_boundary(end) {
            end -= 1;
        }
        let mut b = text.as_bytes()[..end].to_vec();
        b.extend_from_slice(b"...");
        b
    };
    regs[7] = bytes.len() as u16;
    for (k, pair) in bytes.chunks(2).enumerate() {
        regs[RECORD_HEAD + k] = u16::from(pair[0]) << 8 | pair.get(1).copied().map_or(0, u16::from);
    }
    regs
}

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

/// The order of the 16-bit registers of a 32- or 64-bit value (each register is big-endian,
/// as Modbus defines).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum WordOrder {
    /// The most significant register first (`ABCD`; Modicon's convention, pymodbus's default).
    #[default]
    Big,
    /// The least significant register first (`CDAB`; CODESYS, WAGO, mbpoll's default).
    Little,
}

impl WordOrder {
    pub fn from_name(s: &str) -> Option<WordOrder> {
        match s.to_ascii_lowercase().as_str() {
            "big" | "abcd" | "high-first" => Some(WordOrder::Big),
            "little" | "cdab" | "low-first" => Some(WordOrder::Little),
            _ => None,
        }
    }
    pub fn name(self) -> &'static str {
        match self {
            WordOrder::Big => "big",
            WordOrder::Little => "little",
        }
    }
}

/// One located variable on the Modbus map.
#[derive(Debug, Clone)]
pub struct IoPoint {
    pub name: String,
    pub location: String,
    pub table: Table,
    /// The bit or the first register.
    pub address: u16,
    /// Registers taken (1, 2 or 4; 1 for a bit).
    pub words: u16,
    pub role: Role,
    pub slot: Slot,
}

impl IoPoint {
    /// `coil 5`, `holding registers 1004–1005`.
    pub fn describe(&self) -> String {
        if self.words <= 1 {
            format!("{} {}", table_name(self.table), self.address)
        } else {
            format!("{}s {}–{}", table_name(self.table), self.address, self.address + self.words - 1)
        }
    }
}

/// Maps the located variables of the simulated POU; an address or a type the map does not
/// cover is an error naming the variable.
pub fn map_located(sim: &Simulation) -> Result<Vec<IoPoint>, String> {
    let mut out: Vec<IoPoint> = Vec::new();
    for (name, location, index, ty) in sim.located_vars() {
        let (table, address, words, role) =
            address_of(&location, &ty).map_err(|why| format!("`{name}` {location}: {why}"))?;
        let overlaps =
            |p: &IoPoint| p.table == table && p.address < address + words && address < p.address + p.words.max(1);
        if let Some(other) = out.iter().find(|p| overlaps(p)) {
            return Err(format!(
                "`{name}` {location} and `{}` {} share {} {}",
                other.name,
                other.location,
                table_name(table),
                address.max(other.address)
            ));
        }
        out.push(IoPoint { name, location, table, address, words, role, slot: Slot { index, ty } });
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

/// Registers a variable of `ty` takes at a location of size `size` (`W`, `D`, `L`).
fn words_for(size: char, ty: &Type) -> Result<u16, String> {
    let b = ty.base();
    let width = if b.is_real() || b.is_integer() || (b.is_bit() && !b.is_bool()) { ty.bit_width() } else { None };
    let (words, fits) = match size {
        'W' => (1, width.is_some_and(|w| w <= 16)),
        'D' => (2, width == Some(32)),
        _ => (4, width == Some(64)),
    };
    if fits {
        Ok(words)
    } else {
        let want = match size {
            'W' => "an integer or bit string of 8 or 16 bits (INT, UINT, WORD …)",
            'D' => "a 32-bit value (DINT, UDINT, DWORD, REAL)",
            _ => "a 64-bit value (LINT, ULINT, LWORD, LREAL)",
        };
        Err(format!("a %?{size} address holds {want}, not {ty}"))
    }
}

/// `%IX0.3` of a BOOL → (discrete input, 3, 1 word, input).
fn address_of(loc: &str, ty: &Type) -> Result<(Table, u16, u16, Role), String> {
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
            if !ty.is_bool() {
                return Err(format!("a bit address holds a BOOL, not {ty}"));
            }
            let a = (byte * 8 + bit) as u16;
            Ok((if role == Role::Input { Table::DiscreteInput } else { Table::Coil }, a, 1, role))
        }
        ('X', _, _) => Err("a bit address is `%IXbyte.bit` with bit 0..7 and byte < 4096".into()),
        ('W' | 'D' | 'L', _, [n]) => {
            let words = words_for(size, ty)?;
            let first = u64::from(*n) * u64::from(words);
            let (table, base, limit) = match role {
                Role::Input => (Table::InputRegister, 0u64, u64::from(INPUT_WINDOW)),
                Role::Output => (Table::HoldingRegister, 0, u64::from(MEMORY_BASE)),
                Role::Memory => (Table::HoldingRegister, u64::from(MEMORY_BASE), u64::from(INPUT_WINDOW)),
            };
            if base + first + u64::from(words) > limit {
                return Err(format!(
                    "register number out of range (%I… below register {INPUT_WINDOW}, %Q… below {MEMORY_BASE}, \
                     %M… below {})",
                    INPUT_WINDOW - MEMORY_BASE
                ));
            }
            Ok((table, (base + first) as u16, words, role))
        }
        ('W' | 'D' | 'L', _, _) => Err("a register address is `%IWn`, `%IDn` or `%ILn`".into()),
        (s, _, _) => Err(format!(
            "size `{s}` is not on the Modbus map: only X (bits), W (16-bit), D (32-bit) and L (64-bit) are"
        )),
    }
}

/// The registers of a value of `ty` (`words` of them) in `out`, in the word order.
fn to_words(v: &Value, ty: &Type, words: u16, order: WordOrder, out: &mut [u16; 4]) {
    let bits: u64 = match ty.base() {
        Type::Real => (v.as_real().unwrap_or(0.0) as f32).to_bits().into(),
        Type::LReal => v.as_real().unwrap_or(0.0).to_bits(),
        _ => v.as_int().unwrap_or(0) as u64,
    };
    let n = (words as usize).clamp(1, 4);
    for k in 0..n {
        // k = 0 is the most significant register.
        let word = (bits >> (16 * (n - 1 - k))) as u16;
        let at = match order {
            WordOrder::Big => k,
            WordOrder::Little => n - 1 - k,
        };
        out[at] = word;
    }
}

/// The value of `ty` held in `regs` (in the run's word order).
fn from_words(regs: &[u16], ty: &Type, order: WordOrder) -> Value {
    let n = regs.len();
    let mut bits: u64 = 0;
    for k in 0..n {
        let w = match order {
            WordOrder::Big => regs[k],
            WordOrder::Little => regs[n - 1 - k],
        };
        bits = (bits << 16) | u64::from(w);
    }
    let b = ty.base();
    match b {
        Type::Real => Value::Real(f64::from(f32::from_bits(bits as u32))),
        Type::LReal => Value::Real(f64::from_bits(bits)),
        _ => {
            let width = 16 * n as u32;
            let width = b.bit_width().map_or(width, |w| w.min(width));
            let masked = if width >= 64 { bits } else { bits & ((1u64 << width) - 1) };
            let v = if ty.is_signed() && width < 64 && masked >> (width - 1) & 1 == 1 {
                (masked | !((1u64 << width) - 1)) as i64
            } else {
                masked as i64
            };
            Value::Int(v)
        }
    }
}

/// The process image: what clients see and write. Outputs and memory hold what the last scan
/// left; an input holds the last value a client (or a monitor `set`) wrote, or its forced value
/// while it is forced; in the safe state, outputs hold their safe values.
#[derive(Debug, Default)]
pub struct Image {
    pub coils: Vec<bool>,
    pub discrete: Vec<bool>,
    pub input_regs: Vec<u16>,
    pub holding: Vec<u16>,
    /// `%M` points written by clients since the last scan (the value is in `holding`).
    pub memory_writes: Vec<usize>,
    /// Per point, for inputs: the value clients wrote (what the chart reads unless forced).
    pub client: Vec<Value>,
    /// Per point: the forced value, while forced from the monitor.
    pub forced: Vec<Option<Value>>,
    /// The run's own input registers from `RECORD_BASE`: the last error record (zeros until
    /// the first) and the status block at `STATUS_BASE`.
    pub system: Vec<u16>,
    /// For each table, the point (index + 1) that owns each bit or register (0: none).
    owners: [Vec<u32>; 4],
    pub order: WordOrder,
}

fn table_index(t: Table) -> usize {
    match t {
        Table::Coil => 0,
        Table::DiscreteInput => 1,
        Table::InputRegister => 2,
        Table::HoldingRegister => 3,
    }
}

impl Image {
    pub fn new(points: &[IoPoint], order: WordOrder) -> Image {
        let size = |t: Table| {
            points
                .iter()
                .filter(|p| p.table == t)
                .map(|p| p.address as usize + p.words.max(1) as usize)
                .max()
                .unwrap_or(0)
        };
        let mut owners = [
            vec![0; size(Table::Coil)],
            vec![0; size(Table::DiscreteInput)],
            vec![0; size(Table::InputRegister)],
            vec![0; size(Table::HoldingRegister)],
        ];
        for (i, p) in points.iter().enumerate() {
            for k in 0..p.words.max(1) {
                owners[table_index(p.table)][(p.address + k) as usize] = i as u32 + 1;
            }
        }
        Image {
            coils: vec![false; size(Table::Coil)],
            discrete: vec![false; size(Table::DiscreteInput)],
            input_regs: vec![0; size(Table::InputRegister)],
            holding: vec![0; size(Table::HoldingRegister)],
            memory_writes: Vec::new(),
            client: points.iter().map(|p| p.slot.default_value()).collect(),
            forced: vec![None; points.len()],
            system: vec![0; SYSTEM_REGISTERS],
            owners,
            order,
        }
    }

    /// Stores the newest error record's registers ([`record_registers`]).
    pub fn set_record(&mut self, regs: &[u16]) {
        if let Some(block) = self.system.get_mut(..regs.len()) {
            block.copy_from_slice(regs);
        }
    }

    /// Stores the run's status ([`Status`]).
    pub fn set_status(&mut self, s: &Status) {
        let at = (STATUS_BASE - RECORD_BASE) as usize;
        let regs = s.registers(self.order);
        if let Some(block) = self.system.get_mut(at..at + STATUS_REGISTERS) {
            block.copy_from_slice(&regs);
        }
    }

    /// Marks the status block FAULT with `code`, the rest as it was (the watchdog, while the
    /// scan thread is still stopping the scan).
    pub fn set_fault(&mut self, code: u16) {
        let at = (STATUS_BASE - RECORD_BASE) as usize;
        if let Some(block) = self.system.get_mut(at..at + STATUS_REGISTERS) {
            block[0] = 2;
            block[6] = code;
        }
    }

    /// The point that owns bit/register `address` of `table`.
    pub fn owner(&self, table: Table, address: usize) -> Option<usize> {
        self.owners[table_index(table)].get(address).and_then(|&o| (o > 0).then(|| o as usize - 1))
    }

    /// Reads the value of `p` from the image as the chart's value.
    pub fn get(&self, p: &IoPoint) -> Value {
        let a = p.address as usize;
        let n = p.words.max(1) as usize;
        match p.table {
            Table::Coil => Value::Bool(self.coils[a]),
            Table::DiscreteInput => Value::Bool(self.discrete[a]),
            Table::InputRegister => from_words(&self.input_regs[a..a + n], &p.slot.ty, self.order),
            Table::HoldingRegister => from_words(&self.holding[a..a + n], &p.slot.ty, self.order),
        }
    }

    /// Stores the chart's value of `p` in the image.
    pub fn put(&mut self, p: &IoPoint, v: &Value) {
        let a = p.address as usize;
        let n = p.words.max(1) as usize;
        let mut w = [0u16; 4];
        match p.table {
            Table::Coil => self.coils[a] = v.as_bool().unwrap_or(false),
            Table::DiscreteInput => self.discrete[a] = v.as_bool().unwrap_or(false),
            Table::InputRegister => {
                to_words(v, &p.slot.ty, p.words, self.order, &mut w);
                self.input_regs[a..a + n].copy_from_slice(&w[..n]);
            }
            Table::HoldingRegister => {
                to_words(v, &p.slot.ty, p.words, self.order, &mut w);
                self.holding[a..a + n].copy_from_slice(&w[..n]);
            }
        }
    }

    /// A client (or the monitor's `set`) wrote input point `i`: the chart reads it from the
    /// next scan, and clients read it back unless the point is forced.
    pub fn write_input(&mut self, i: usize, p: &IoPoint, v: Value) {
        if self.forced[i].is_none() {
            self.put(p, &v);
        }
        self.client[i] = v;
    }

    /// Forces point `i` to `v` (`None`: releases it): clients read the forced value.
    pub fn force(&mut self, i: usize, p: &IoPoint, v: Option<Value>) {
        match &v {
            Some(x) => self.put(p, x),
            None if p.role == Role::Input => {
                let c = self.client[i].clone();
                self.put(p, &c);
            }
            None => {}
        }
        self.forced[i] = v;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn addresses_follow_the_table() {
        let b = Type::Bool;
        let i = Type::Int;
        assert_eq!(address_of("%IX0.3", &b), Ok((Table::DiscreteInput, 3, 1, Role::Input)));
        assert_eq!(address_of("%QX1.2", &b), Ok((Table::Coil, 10, 1, Role::Output)));
        assert_eq!(address_of("%I2.1", &b), Ok((Table::DiscreteInput, 17, 1, Role::Input)));
        assert_eq!(address_of("%IW7", &i), Ok((Table::InputRegister, 7, 1, Role::Input)));
        assert_eq!(address_of("%QW5", &i), Ok((Table::HoldingRegister, 5, 1, Role::Output)));
        assert_eq!(address_of("%MW5", &i), Ok((Table::HoldingRegister, 1005, 1, Role::Memory)));
        assert_eq!(address_of("%ID3", &Type::DInt), Ok((Table::InputRegister, 6, 2, Role::Input)));
        assert_eq!(address_of("%QD1", &Type::Real), Ok((Table::HoldingRegister, 2, 2, Role::Output)));
        assert_eq!(address_of("%MD2", &Type::UDInt), Ok((Table::HoldingRegister, 1004, 2, Role::Memory)));
        assert_eq!(address_of("%ML1", &Type::LReal), Ok((Table::HoldingRegister, 1004, 4, Role::Memory)));
        assert!(address_of("%QW1000", &i).is_err());
        assert!(address_of("%QD499", &Type::DInt).is_ok() && address_of("%QD500", &Type::DInt).is_err());
        assert!(address_of("%IB0", &Type::Byte).unwrap_err().contains("size `B`"));
        assert!(address_of("%ID0", &i).unwrap_err().contains("32-bit"));
        assert!(address_of("%IW0", &Type::Real).unwrap_err().contains("not REAL"));
        assert!(address_of("%MX0.0", &b).is_err());
        assert!(address_of("%IX0.8", &b).is_err());
        assert!(address_of("%IX0.0", &i).is_err());
    }

    fn record(condition: &str) -> sfc_sim::ErrorRecord {
        sfc_sim::ErrorRecord {
            instance: "Rev".into(),
            step: "Rev.OpenKM2".into(),
            code: Some(-405),
            code_variable: Some("Rev.ErrorCode".into()),
            conditions: vec![("Rev.TKM2Closed".into(), condition.into())],
            waited: 1_100_000,
            timeout: Some(1_000_000),
            by: None,
            scan: 7,
            time: 0,
        }
    }

    #[test]
    fn an_error_record_fills_its_register_block() {
        let r = record("KM2Fb (X12.3, %IX0.5) is FALSE; needs TRUE");
        let regs = record_registers(65537, &r, WordOrder::Little);
        assert_eq!(regs.len(), RECORD_REGISTERS);
        // Count wraps; code −405 as DINT, little word order; 1100 ms; 1000 ms.
        assert_eq!(&regs[..7], &[1, 0xFE6B, 0xFFFF, 1100, 0, 1000, 0]);
        let text = r.message();
        assert_eq!(usize::from(regs[7]), text.len());
        let bytes: Vec<u8> = regs[8..].iter().flat_map(|w| w.to_be_bytes()).take(text.len()).collect();
        assert_eq!(String::from_utf8(bytes).unwrap(), text);
    }

    #[test]
    fn a_long_record_text_is_cut_on_a_character_and_says_so() {
        let r = record(&"ä".repeat(400));
        let regs = record_registers(1, &r, WordOrder::Big);
        let len = usize::from(regs[7]);
        assert!(len <= 2 * RECORD_TEXT_REGISTERS);
        let bytes: Vec<u8> = regs[8..].iter().flat_map(|w| w.to_be_bytes()).take(len).collect();
        let text = String::from_utf8(bytes).expect("cut at a character boundary");
        assert!(text.starts_with("Rev: error -405") && text.ends_with("ä..."), "{text}");
    }

    #[test]
    fn wide_values_take_registers_in_the_word_order() {
        let mut w = [0u16; 4];
        to_words(&Value::Int(0x0001_0002), &Type::UDInt, 2, WordOrder::Big, &mut w);
        assert_eq!(&w[..2], &[1, 2]);
        to_words(&Value::Int(0x0001_0002), &Type::UDInt, 2, WordOrder::Little, &mut w);
        assert_eq!(&w[..2], &[2, 1]);
        assert_eq!(from_words(&[2, 1], &Type::UDInt, WordOrder::Little), Value::Int(0x0001_0002));
        to_words(&Value::Real(1.5), &Type::Real, 2, WordOrder::Big, &mut w);
        assert_eq!(&w[..2], &[0x3FC0, 0]);
        assert_eq!(from_words(&[0x3FC0, 0], &Type::Real, WordOrder::Big), Value::Real(1.5));
        assert_eq!(from_words(&[0xFFFF, 0xFFFE], &Type::DInt, WordOrder::Big), Value::Int(-2));
        assert_eq!(from_words(&[0xFFFF], &Type::Int, WordOrder::Big), Value::Int(-1));
        assert_eq!(from_words(&[0xFFFF], &Type::UInt, WordOrder::Big), Value::Int(65535));
        assert_eq!(from_words(&[0x00FF], &Type::SInt, WordOrder::Big), Value::Int(-1));
        to_words(&Value::Int(-3), &Type::LInt, 4, WordOrder::Little, &mut w);
        assert_eq!(w, [0xFFFD, 0xFFFF, 0xFFFF, 0xFFFF]);
        assert_eq!(from_words(&w, &Type::LInt, WordOrder::Little), Value::Int(-3));
        to_words(&Value::Real(-0.25), &Type::LReal, 4, WordOrder::Big, &mut w);
        assert_eq!(from_words(&w, &Type::LReal, WordOrder::Big), Value::Real(-0.25));
    }
}
