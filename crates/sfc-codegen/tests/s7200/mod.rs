//! An interpreter of S7-200 statement list (CPU 22x), written from the S7-200 System Manual and
//! the instruction descriptions of seed 002 (chapter 3), not from the generator: the
//! differential tests run generated programs here. The rules it follows, with their sources,
//! are listed in `docs/targets.md` ("The S7-200 model"); in short:
//!
//! - **Logic stack** of 9 levels: `LD LDN` and the compare loads push (the bottom level is
//!   lost), `A AN O ON` and the compare `A…`/`O…` forms combine with the top, `ALD OLD` combine
//!   the two top levels (the stack moves up, the bottom becomes undefined), `LPS` pushes a copy
//!   of the top, `LRD` copies the second level to the top, `LPP` pops, `LDS n` pushes a copy of
//!   level n, `NOT`, `EU`/`ED` (one edge memory per instruction). `NETWORK` leaves the stack
//!   undefined: reading an undefined level is an error, so malformed code is caught.
//! - **Outputs** `= bit`, `S bit, n`, `R bit, n` (n consecutive bits; `R` on timers or counters
//!   clears their value and bit). Box instructions (moves, arithmetic, counters, timers) take
//!   their enable from the top of the stack and leave the stack as it is.
//! - **Timers** by number: TONR 1 ms `T0 T64`, 10 ms `T1–T4 T65–T68`, 100 ms `T5–T31 T69–T95`;
//!   TON/TOF 1 ms `T32 T96`, 10 ms `T33–T36 T97–T100`, 100 ms `T37–T63 T101–T255`. A timer
//!   number is either TON or TOF, not both. Current values stop at 32767; the bit is
//!   `value >= PT` (TON, TONR).
//!   - 100 ms: the CPU counts the 100 ms intervals of its time base between the start of the
//!     previous scan and the start of this one (`d100`); **each execution** of the instruction
//!     with its input on adds `d100` to the current value (two executions in one scan add it
//!     twice: the timer gains time; a scan without execution loses it). TON with the input
//!     off: value 0; TONR holds. There is no separate "running" state: `R` only clears the
//!     value and the bit.
//!   - 10 ms: an enabled timer is updated at the **start of each scan** by the 10 ms intervals
//!     since the start of the previous scan; the instruction only enables (input on: starts
//!     from its current value) or disables it (TON: value 0; TONR: holds). `R` turns it off.
//!   - 1 ms: updated **every millisecond, asynchronously** to the scan: its value is computed
//!     from the instant of each read, so two reads in one scan can differ when the program
//!     takes time ([`Plc::instruction_time`]).
//!   - TOF: input on → bit on, value 0; on the input's on→off transition it starts timing;
//!     at the preset the bit turns off and the value stops at the preset.
//! - **Counters** `C0–C255`: `CTU Cn, PV` (top of stack = reset, second level = count up),
//!   `CTD Cn, PV` (top = load, second = count down: load sets the value to PV and clears the
//!   bit; counts down to 0, where the bit turns on), `CTUD Cn, PV` (top = reset, second = count
//!   down, third = count up; wraps at ±32767/−32768). They count the off→on transitions of their
//!   inputs between executions; the bit of CTU/CTUD is `value >= PV`.
//! - **Words**: `MOVW MOVD ITD DTI +I -I *I /I +D -D *D /D INCW DECW INCD DECD` in the STL form
//!   `OP IN, OUT` (`OUT := OUT op IN`), executed when the top of the stack is on; 16- and 32-bit
//!   two's complement with wrap-around (overflow sets `SM1.1`); division by zero leaves the output
//!   unchanged and sets `SM1.3`. Compare contacts `LDW= AW<> OW>= …` (signed INT) and
//!   `LDD… AD… OD…` (signed DINT). Operands: `VW VD MW MD IW QW SMW`, `T`/`C` current values,
//!   `AC0–AC3`, constants (`+5`, `-3`, `16#FF`). Memory is big-endian (`VW0` is the high word
//!   of `VD0`).
//! - **SCR**: `LSCR Sx.y` loads the SCR stack with the S bit; the segment up to `SCRE` is
//!   energized or not. In a de-energized segment the instructions run without power flow
//!   (`=` writes 0, `S`/`R`/boxes do nothing, TON resets, a TOF is reset and does not time) —
//!   or, with [`ScrModel::Skip`], are not executed at all; tests run both readings. `SCRT Sx.y`
//!   with power flow sets the referenced S bit and resets the segment's own, the reset either
//!   at once or at `SCRE` ([`ScrtReset`]); the segment stays energized until `SCRE`. An `SCRT`
//!   to the segment's own bit, nested `LSCR`, `JMP`/`LBL` inside a segment, or a segment without
//!   `SCRE` is an error.
//! - `JMP n` with power flow continues after `LBL n`; `SM0.0` is always on, `SM0.1` on in the
//!   first scan only.
//!
//! A scan starts at a given time; the program runs top to bottom, by default at that one
//! instant. The interpreter counts, per scan, how often each timer and counter instruction was
//! executed ([`Plc::executions`]), so tests can require once per scan.

#![allow(dead_code)]

use std::collections::HashMap;

#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Area {
    I,
    Q,
    M,
    V,
    S,
    Sm,
}

impl Area {
    fn bytes(self) -> usize {
        match self {
            Area::I | Area::Q => 16,
            Area::M | Area::S => 32,
            Area::V => 10240,
            Area::Sm => 550,
        }
    }
}

/// An operand of the instructions the interpreter knows.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Operand {
    /// Area and bit number (`byte * 8 + bit`).
    Bit(Area, u32),
    /// `Tn`: the bit in bit context, the current value in word context.
    Timer(u16),
    /// `Cn`: likewise.
    Counter(u16),
    /// A word at a byte address (`VW100`).
    Word(Area, u32),
    /// A double word at a byte address (`VD100`).
    DWord(Area, u32),
    /// `AC0`–`AC3`.
    Acc(u8),
    Const(i64),
}

/// How instructions inside a de-energized SCR segment behave.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ScrModel {
    /// They run without power flow (the System Manual's reading: LSCR loads the logic stack).
    PowerOff,
    /// They are skipped.
    Skip,
}

/// When `SCRT` resets the segment's own S bit.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ScrtReset {
    Immediate,
    AtScre,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Cmp {
    Eq,
    Ne,
    Lt,
    Le,
    Gt,
    Ge,
}

impl Cmp {
    fn holds(self, a: i64, b: i64) -> bool {
        match self {
            Cmp::Eq => a == b,
            Cmp::Ne => a != b,
            Cmp::Lt => a < b,
            Cmp::Le => a <= b,
            Cmp::Gt => a > b,
            Cmp::Ge => a >= b,
        }
    }
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Combine {
    Load,
    And,
    Or,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Arith {
    Add,
    Sub,
    Mul,
    Div,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum TimerOp {
    Ton,
    Tonr,
    Tof,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum CounterOp {
    Ctu,
    Ctd,
    Ctud,
}

#[derive(Debug, Clone, Copy, PartialEq)]
enum Ins {
    Network,
    Bit(Combine, bool, Operand),
    /// Compare contact: combine, 32-bit, operator, operands.
    Compare(Combine, bool, Cmp, Operand, Operand),
    Ald,
    Old,
    Lps,
    Lrd,
    Lpp,
    Lds(u8),
    Not,
    Eu,
    Ed,
    Out(Operand),
    Set(Operand, u16),
    Reset(Operand, u16),
    Timer(TimerOp, u16, Operand),
    Counter(CounterOp, u16, Operand),
    /// `MOVW`/`MOVD` (32-bit flag).
    Move(bool, Operand, Operand),
    Arith(bool, Arith, Operand, Operand),
    /// `INCW`/`DECW`/`INCD`/`DECD`: 32-bit flag, +1 or -1.
    Step(bool, i64, Operand),
    Itd(Operand, Operand),
    Dti(Operand, Operand),
    Lscr(Operand),
    Scrt(Operand),
    Scre,
    Jmp(u16),
    Lbl(u16),
}

/// A parsed program: each instruction with its source line.
#[derive(Debug, Clone)]
pub struct Program {
    ins: Vec<(Ins, usize)>,
}

impl Program {
    /// The number of instructions.
    pub fn len(&self) -> usize {
        self.ins.len()
    }
}

/// Parses a bit, timer, counter, word or constant operand.
pub fn operand(text: &str) -> Result<Operand, String> {
    let t = text.trim();
    let upper = t.to_ascii_uppercase();
    if let Some(c) = constant(&upper) {
        return Ok(Operand::Const(c));
    }
    if let Some(r) = upper.strip_prefix("AC") {
        return match r.parse::<u8>() {
            Ok(n) if n < 4 => Ok(Operand::Acc(n)),
            _ => Err(format!("no accumulator `{t}`")),
        };
    }
    let number = |r: &str, what: &str| -> Result<u16, String> {
        match r.parse::<u16>() {
            Ok(n) if n <= 255 => Ok(n),
            _ => Err(format!("no {what} `{t}`")),
        }
    };
    if let Some(r) = upper.strip_prefix('T') {
        return number(r, "timer").map(Operand::Timer);
    }
    if let Some(r) = upper.strip_prefix('C') {
        return number(r, "counter").map(Operand::Counter);
    }
    let (area, rest) = if let Some(r) = upper.strip_prefix("SM") {
        (Area::Sm, r)
    } else {
        let area = match upper.chars().next() {
            Some('I') => Area::I,
            Some('Q') => Area::Q,
            Some('M') => Area::M,
            Some('V') => Area::V,
            Some('S') => Area::S,
            _ => return Err(format!("bad operand `{t}`")),
        };
        (area, &upper[1..])
    };
    let sized = |r: &str, width: u32| -> Result<u32, String> {
        let byte: u32 = r.parse().map_err(|_| format!("bad address `{t}`"))?;
        if byte + width > area.bytes() as u32 {
            return Err(format!("`{t}` is outside the S7-200 memory"));
        }
        Ok(byte)
    };
    if let Some(r) = rest.strip_prefix('W') {
        return Ok(Operand::Word(area, sized(r, 2)?));
    }
    if let Some(r) = rest.strip_prefix('D') {
        return Ok(Operand::DWord(area, sized(r, 4)?));
    }
    let (byte, bit) = rest.split_once('.').ok_or_else(|| format!("bad bit address `{t}`"))?;
    let byte: u32 = byte.parse().map_err(|_| format!("bad byte in `{t}`"))?;
    let bit: u32 = bit.parse().map_err(|_| format!("bad bit in `{t}`"))?;
    if bit > 7 || byte >= area.bytes() as u32 {
        return Err(format!("`{t}` is outside the S7-200 memory"));
    }
    Ok(Operand::Bit(area, byte * 8 + bit))
}

/// `+12`, `-3`, `12`, `16#FF`.
fn constant(t: &str) -> Option<i64> {
    if let Some(h) = t.strip_prefix("16#") {
        return i64::from_str_radix(h, 16).ok();
    }
    let (neg, digits) = match t.as_bytes().first()? {
        b'+' => (false, &t[1..]),
        b'-' => (true, &t[1..]),
        b'0'..=b'9' => (false, t),
        _ => return None,
    };
    if digits.is_empty() || !digits.bytes().all(|b| b.is_ascii_digit()) {
        return None;
    }
    let n: i64 = digits.parse().ok()?;
    Some(if neg { -n } else { n })
}

fn compare_op(s: &str) -> Option<Cmp> {
    Some(match s {
        "=" | "==" => Cmp::Eq,
        "<>" => Cmp::Ne,
        "<" => Cmp::Lt,
        "<=" => Cmp::Le,
        ">" => Cmp::Gt,
        ">=" => Cmp::Ge,
        _ => return None,
    })
}

/// Parses statement-list text: `//` comments, `NETWORK n` lines, one instruction per line.
pub fn parse(text: &str) -> Result<Program, String> {
    let mut ins = Vec::new();
    for (no, raw) in text.lines().enumerate() {
        if !raw.is_ascii() {
            return Err(format!("line {}: not ASCII (Micro/WIN reads ANSI text): `{raw}`", no + 1));
        }
        let line = raw.split("//").next().unwrap_or("").trim();
        if line.is_empty() {
            continue;
        }
        let at = |e: String| format!("line {}: {e}: `{raw}`", no + 1);
        let (mn, rest) = match line.split_once(char::is_whitespace) {
            Some((m, r)) => (m.to_ascii_uppercase(), r.trim()),
            None => (line.to_ascii_uppercase(), ""),
        };
        ins.push((instruction(&mn, rest).map_err(at)?, no + 1));
    }
    Ok(Program { ins })
}

fn instruction(mn: &str, rest: &str) -> Result<Ins, String> {
    let args: Vec<&str> = if rest.is_empty() { Vec::new() } else { rest.split(',').map(str::trim).collect() };
    let one = || -> Result<Operand, String> {
        match args.as_slice() {
            [a] => operand(a),
            _ => Err(format!("`{mn}` takes one operand")),
        }
    };
    let two = || -> Result<(Operand, Operand), String> {
        match args.as_slice() {
            [a, b] => Ok((operand(a)?, operand(b)?)),
            _ => Err(format!("`{mn}` takes two operands")),
        }
    };
    let bit = |o: Operand| -> Result<Operand, String> {
        match o {
            Operand::Bit(..) | Operand::Timer(_) | Operand::Counter(_) => Ok(o),
            _ => Err(format!("`{mn}` needs a bit operand")),
        }
    };
    let count = || -> Result<(Operand, u16), String> {
        match args.as_slice() {
            [a, n] => match constant(n) {
                Some(n) if (1..=255).contains(&n) => Ok((bit(operand(a)?)?, n as u16)),
                _ => Err("count must be 1 to 255".into()),
            },
            _ => Err(format!("`{mn}` takes an operand and a count")),
        }
    };
    let none = |i: Ins| -> Result<Ins, String> {
        if args.is_empty() {
            Ok(i)
        } else {
            Err(format!("`{mn}` takes no operand"))
        }
    };
    let label = || -> Result<u16, String> {
        match args.as_slice() {
            [n] => match constant(n) {
                Some(n) if (0..=255).contains(&n) => Ok(n as u16),
                _ => Err("labels are 0 to 255".into()),
            },
            _ => Err(format!("`{mn}` takes a label number")),
        }
    };
    let box_of = |kind: &str| -> Result<(u16, Operand), String> {
        let (t, p) = two()?;
        let n = match (kind, t) {
            ("T", Operand::Timer(n)) | ("C", Operand::Counter(n)) => n,
            _ => return Err(format!("`{mn}` needs a {} first", if kind == "T" { "timer" } else { "counter" })),
        };
        if let Operand::Const(c) = p {
            if !(0..=32767).contains(&c) {
                return Err("preset out of range".into());
            }
        }
        Ok((n, p))
    };
    // Compare contacts: LDW>=, AD<>, OW=, ...
    for (prefix, combine) in [("LD", Combine::Load), ("A", Combine::And), ("O", Combine::Or)] {
        if let Some(r) = mn.strip_prefix(prefix) {
            let (wide, op) = match (r.strip_prefix('W'), r.strip_prefix('D')) {
                (Some(op), _) => (false, op),
                (_, Some(op)) => (true, op),
                _ => continue,
            };
            if let Some(cmp) = compare_op(op) {
                let (a, b) = two()?;
                return Ok(Ins::Compare(combine, wide, cmp, a, b));
            }
        }
    }
    let arith = |wide: bool, op: Arith| -> Result<Ins, String> {
        let (a, b) = two()?;
        Ok(Ins::Arith(wide, op, a, b))
    };
    Ok(match mn {
        "NETWORK" => Ins::Network,
        "LD" => Ins::Bit(Combine::Load, false, bit(one()?)?),
        "LDN" => Ins::Bit(Combine::Load, true, bit(one()?)?),
        "A" => Ins::Bit(Combine::And, false, bit(one()?)?),
        "AN" => Ins::Bit(Combine::And, true, bit(one()?)?),
        "O" => Ins::Bit(Combine::Or, false, bit(one()?)?),
        "ON" => Ins::Bit(Combine::Or, true, bit(one()?)?),
        "ALD" => none(Ins::Ald)?,
        "OLD" => none(Ins::Old)?,
        "LPS" => none(Ins::Lps)?,
        "LRD" => none(Ins::Lrd)?,
        "LPP" => none(Ins::Lpp)?,
        "LDS" => match args.as_slice() {
            [n] => match constant(n) {
                Some(n) if (1..=8).contains(&n) => Ins::Lds(n as u8),
                _ => return Err("LDS takes 1 to 8".into()),
            },
            _ => return Err("`LDS` takes a level".into()),
        },
        "NOT" => none(Ins::Not)?,
        "EU" => none(Ins::Eu)?,
        "ED" => none(Ins::Ed)?,
        "=" => Ins::Out(bit(one()?)?),
        "S" => count().map(|(o, n)| Ins::Set(o, n))?,
        "R" => count().map(|(o, n)| Ins::Reset(o, n))?,
        "TON" => box_of("T").map(|(n, p)| Ins::Timer(TimerOp::Ton, n, p))?,
        "TONR" => box_of("T").map(|(n, p)| Ins::Timer(TimerOp::Tonr, n, p))?,
        "TOF" => box_of("T").map(|(n, p)| Ins::Timer(TimerOp::Tof, n, p))?,
        "CTU" => box_of("C").map(|(n, p)| Ins::Counter(CounterOp::Ctu, n, p))?,
        "CTD" => box_of("C").map(|(n, p)| Ins::Counter(CounterOp::Ctd, n, p))?,
        "CTUD" => box_of("C").map(|(n, p)| Ins::Counter(CounterOp::Ctud, n, p))?,
        "MOVW" => two().map(|(a, b)| Ins::Move(false, a, b))?,
        "MOVD" => two().map(|(a, b)| Ins::Move(true, a, b))?,
        "ITD" => two().map(|(a, b)| Ins::Itd(a, b))?,
        "DTI" => two().map(|(a, b)| Ins::Dti(a, b))?,
        "+I" => arith(false, Arith::Add)?,
        "-I" => arith(false, Arith::Sub)?,
        "*I" => arith(false, Arith::Mul)?,
        "/I" => arith(false, Arith::Div)?,
        "+D" => arith(true, Arith::Add)?,
        "-D" => arith(true, Arith::Sub)?,
        "*D" => arith(true, Arith::Mul)?,
        "/D" => arith(true, Arith::Div)?,
        "INCW" => Ins::Step(false, 1, one()?),
        "DECW" => Ins::Step(false, -1, one()?),
        "INCD" => Ins::Step(true, 1, one()?),
        "DECD" => Ins::Step(true, -1, one()?),
        "LSCR" => Ins::Lscr(one()?),
        "SCRT" => Ins::Scrt(one()?),
        "SCRE" => none(Ins::Scre)?,
        "JMP" => Ins::Jmp(label()?),
        "LBL" => Ins::Lbl(label()?),
        other => return Err(format!("unknown instruction `{other}`")),
    })
}

/// The resolution of a timer number and whether it is a TONR.
fn timer_kind(n: u16) -> (i64, bool) {
    match n {
        0 | 64 => (1_000, true),
        1..=4 | 65..=68 => (10_000, true),
        5..=31 | 69..=95 => (100_000, true),
        32 | 96 => (1_000, false),
        33..=36 | 97..=100 => (10_000, false),
        _ => (100_000, false),
    }
}

#[derive(Debug, Clone, Copy, Default)]
struct Timer {
    value: i64,
    bit: bool,
    /// 1 ms / 10 ms: enabled (timing). TOF (any resolution): timing after on→off.
    enabled: bool,
    /// 1 ms: time base tick at which the current stretch of timing started, and the value then.
    since: i64,
    base: i64,
    pt: i64,
    /// TOF: the input at the previous execution.
    last_in: bool,
    op: Option<TimerOp>,
}

#[derive(Debug, Clone, Copy, Default)]
struct Counter {
    value: i64,
    bit: bool,
    /// The inputs at the previous execution (count up, count down).
    last_up: bool,
    last_down: bool,
    op: Option<CounterOp>,
}

const STACK: usize = 9;

/// A CPU running one program.
pub struct Plc {
    prog: Program,
    mem: HashMap<Area, Vec<u8>>,
    acc: [i64; 4],
    timers: Vec<Timer>,
    counters: Vec<Counter>,
    /// Edge memory of each EU/ED instruction, by instruction index.
    edges: Vec<bool>,
    stack: [Option<bool>; STACK],
    first_scan: bool,
    /// The instant of the instruction being executed, µs.
    now: i64,
    prev_start: Option<i64>,
    /// 100 ms intervals between the start of the previous scan and the start of this one.
    d100: i64,
    /// The time base's offset: the CPU's time base ticks at `(t + phase) / resolution`.
    pub phase: i64,
    /// Time each instruction takes, µs (0: the whole scan runs at its start instant).
    pub instruction_time: i64,
    pub scr_model: ScrModel,
    pub scrt_reset: ScrtReset,
    executions: HashMap<(char, u16), u32>,
    labels: HashMap<u16, usize>,
    stopped: bool,
}

impl Plc {
    pub fn new(prog: Program) -> Plc {
        let n = prog.ins.len();
        let mut mem = HashMap::new();
        for a in [Area::I, Area::Q, Area::M, Area::V, Area::S, Area::Sm] {
            mem.insert(a, vec![0u8; a.bytes()]);
        }
        let mut labels = HashMap::new();
        for (i, (ins, _)) in prog.ins.iter().enumerate() {
            if let Ins::Lbl(l) = ins {
                labels.insert(*l, i);
            }
        }
        Plc {
            prog,
            mem,
            acc: [0; 4],
            timers: vec![Timer::default(); 256],
            counters: vec![Counter::default(); 256],
            edges: vec![false; n],
            stack: [None; STACK],
            first_scan: true,
            now: 0,
            prev_start: None,
            d100: 0,
            phase: 0,
            instruction_time: 0,
            scr_model: ScrModel::PowerOff,
            scrt_reset: ScrtReset::Immediate,
            executions: HashMap::new(),
            labels,
            stopped: false,
        }
    }

    fn ticks(&self, t: i64, resolution: i64) -> i64 {
        (t + self.phase).div_euclid(resolution)
    }

    /// Sets a bit or a word from outside (the input image, or another program's memory).
    pub fn set(&mut self, addr: &str, v: bool) -> Result<(), String> {
        match operand(addr)? {
            Operand::Bit(Area::Sm, _) | Operand::Timer(_) | Operand::Counter(_) => {
                Err(format!("`{addr}` cannot be set from outside"))
            }
            Operand::Bit(a, n) => {
                self.put_bit(a, n, v);
                Ok(())
            }
            _ => Err(format!("`{addr}` is not a bit")),
        }
    }

    pub fn set_value(&mut self, addr: &str, v: i64) -> Result<(), String> {
        let o = operand(addr)?;
        self.write_value(o, v, matches!(o, Operand::DWord(..)))
    }

    pub fn get(&self, addr: &str) -> Result<bool, String> {
        self.read_bit(operand(addr)?)
    }

    /// A word or double word (signed), a timer's or counter's current value.
    pub fn value(&self, addr: &str) -> Result<i64, String> {
        let o = operand(addr)?;
        let wide = matches!(o, Operand::DWord(..) | Operand::Acc(_));
        self.read_value(o, wide)
    }

    /// The current value of a timer (in its resolution's units), as a read at the scan's end.
    pub fn timer_value(&self, n: u16) -> i64 {
        self.timer_now(n).0
    }

    /// How often each timer (`'T'`) and counter (`'C'`) instruction ran in the last scan.
    pub fn executions(&self) -> &HashMap<(char, u16), u32> {
        &self.executions
    }

    fn put_bit(&mut self, a: Area, n: u32, v: bool) {
        let bytes = self.mem.get_mut(&a).expect("area");
        let b = &mut bytes[(n / 8) as usize];
        if v {
            *b |= 1 << (n % 8);
        } else {
            *b &= !(1 << (n % 8));
        }
    }

    fn bit_of(&self, a: Area, n: u32) -> bool {
        self.mem[&a][(n / 8) as usize] & (1 << (n % 8)) != 0
    }

    /// 1 ms timers follow the clock; others hold what their last update gave.
    fn timer_now(&self, n: u16) -> (i64, bool) {
        let t = &self.timers[n as usize];
        let (res, _) = timer_kind(n);
        if res != 1_000 || !t.enabled {
            return (t.value, t.bit);
        }
        let elapsed = self.ticks(self.now, res) - t.since;
        match t.op {
            Some(TimerOp::Tof) => {
                let v = (t.base + elapsed).min(t.pt);
                (v, v < t.pt)
            }
            _ => {
                let v = (t.base + elapsed).min(32767);
                (v, v >= t.pt)
            }
        }
    }

    fn read_bit(&self, o: Operand) -> Result<bool, String> {
        Ok(match o {
            Operand::Bit(Area::Sm, 0) => true,
            Operand::Bit(Area::Sm, 1) => self.first_scan,
            Operand::Bit(a, n) => self.bit_of(a, n),
            Operand::Timer(t) => self.timer_now(t).1,
            Operand::Counter(c) => self.counters[c as usize].bit,
            _ => return Err("not a bit operand".into()),
        })
    }

    fn write_bit(&mut self, o: Operand, v: bool) -> Result<(), String> {
        match o {
            Operand::Bit(Area::I, _) => Err("the program writes the input image".into()),
            Operand::Bit(Area::Sm, _) => Err("the program writes special memory".into()),
            Operand::Bit(a, n) => {
                self.put_bit(a, n, v);
                Ok(())
            }
            _ => Err("`=` on a timer or counter".into()),
        }
    }

    fn read_value(&self, o: Operand, wide: bool) -> Result<i64, String> {
        let m = |a: Area, at: u32, len: usize| -> i64 {
            let b = &self.mem[&a][at as usize..at as usize + len];
            let mut v: i64 = 0;
            for x in b {
                v = (v << 8) | i64::from(*x);
            }
            if len == 2 {
                i64::from(v as u16 as i16)
            } else {
                i64::from(v as u32 as i32)
            }
        };
        Ok(match o {
            Operand::Const(c) => c,
            Operand::Acc(n) => {
                let v = self.acc[n as usize];
                if wide {
                    v
                } else {
                    i64::from(v as i16)
                }
            }
            Operand::Word(a, at) => {
                if wide {
                    return Err("a word where a double word is needed".into());
                }
                m(a, at, 2)
            }
            Operand::DWord(a, at) => {
                if !wide {
                    return Err("a double word where a word is needed".into());
                }
                m(a, at, 4)
            }
            Operand::Timer(t) => self.timer_now(t).0,
            Operand::Counter(c) => self.counters[c as usize].value,
            Operand::Bit(..) => return Err("a bit where a value is needed".into()),
        })
    }

    fn write_value(&mut self, o: Operand, v: i64, wide: bool) -> Result<(), String> {
        let len = if wide { 4 } else { 2 };
        match o {
            Operand::Acc(n) => {
                self.acc[n as usize] = if wide { i64::from(v as i32) } else { i64::from(v as i16) };
                Ok(())
            }
            Operand::Word(Area::I, _) | Operand::DWord(Area::I, _) => Err("the program writes the input image".into()),
            Operand::Word(a, at) | Operand::DWord(a, at) => {
                if matches!(o, Operand::Word(..)) == wide {
                    return Err("operand size does not match the instruction".into());
                }
                let bytes = self.mem.get_mut(&a).expect("area");
                for k in 0..len {
                    bytes[at as usize + k] = (v >> (8 * (len - 1 - k))) as u8;
                }
                Ok(())
            }
            _ => Err("not a writable value".into()),
        }
    }

    fn top(&self) -> Result<bool, String> {
        self.stack[0].ok_or_else(|| "the top of the logic stack is undefined".to_string())
    }
    fn level(&self, n: usize) -> Result<bool, String> {
        self.stack[n].ok_or_else(|| format!("level {} of the logic stack is undefined", n + 1))
    }
    fn push(&mut self, v: bool) {
        for i in (1..STACK).rev() {
            self.stack[i] = self.stack[i - 1];
        }
        self.stack[0] = Some(v);
    }
    fn pop(&mut self) {
        for i in 0..STACK - 1 {
            self.stack[i] = self.stack[i + 1];
        }
        self.stack[STACK - 1] = None;
    }

    /// One scan starting at time `now` (µs).
    pub fn scan(&mut self, now: i64) -> Result<(), String> {
        if self.stopped {
            return Err("the CPU is in STOP".into());
        }
        self.now = now;
        self.d100 = match self.prev_start {
            Some(p) => self.ticks(now, 100_000) - self.ticks(p, 100_000),
            None => 0,
        };
        // 10 ms timers: updated at the start of the scan.
        let d10 = match self.prev_start {
            Some(p) => self.ticks(now, 10_000) - self.ticks(p, 10_000),
            None => 0,
        };
        for n in 0..256u16 {
            if timer_kind(n).0 != 10_000 {
                continue;
            }
            let t = &mut self.timers[n as usize];
            if !t.enabled {
                continue;
            }
            if t.op == Some(TimerOp::Tof) {
                t.value = (t.value + d10).min(t.pt);
                if t.value >= t.pt {
                    t.bit = false;
                    t.enabled = false;
                }
            } else {
                t.value = (t.value + d10).min(32767);
                t.bit = t.value >= t.pt;
            }
        }
        self.prev_start = Some(now);
        self.executions.clear();
        self.stack = [None; STACK];
        let mut pc = 0;
        let mut segment: Option<Segment> = None;
        while pc < self.prog.ins.len() {
            let (ins, line) = self.prog.ins[pc];
            let r = self.step(ins, pc, &mut segment);
            self.now += self.instruction_time;
            match r {
                Ok(Some(next)) => pc = next,
                Ok(None) => pc += 1,
                Err(e) => return Err(format!("line {line}: {e}")),
            }
        }
        if segment.is_some() {
            return Err("LSCR without SCRE".into());
        }
        self.first_scan = false;
        Ok(())
    }

    /// The power flow an output-type instruction sees: the top of the stack, and the SCR
    /// segment's power.
    fn power(&self, segment: &Option<Segment>) -> Result<bool, String> {
        let top = self.top()?;
        Ok(top && segment.is_none_or(|s| s.energized))
    }

    fn step(&mut self, ins: Ins, pc: usize, segment: &mut Option<Segment>) -> Result<Option<usize>, String> {
        match ins {
            Ins::Network => self.stack = [None; STACK],
            Ins::Bit(c, neg, o) => {
                let v = self.read_bit(o)? != neg;
                self.combine(c, v)?;
            }
            Ins::Compare(c, wide, cmp, a, b) => {
                let v = cmp.holds(self.read_value(a, wide)?, self.read_value(b, wide)?);
                self.combine(c, v)?;
            }
            Ins::Ald | Ins::Old => {
                let (a, b) = (self.top()?, self.level(1)?);
                self.pop();
                self.stack[0] = Some(if ins == Ins::Ald { a && b } else { a || b });
            }
            Ins::Lps => {
                let t = self.top()?;
                self.push(t);
            }
            Ins::Lrd => self.stack[0] = Some(self.level(1)?),
            Ins::Lpp => {
                self.level(1)?;
                self.pop();
            }
            Ins::Lds(n) => {
                let v = self.level(n as usize)?;
                self.push(v);
            }
            Ins::Not => self.stack[0] = Some(!self.top()?),
            Ins::Eu | Ins::Ed => {
                let v = self.top()?;
                let m = self.edges[pc];
                self.edges[pc] = v;
                self.stack[0] = Some(if ins == Ins::Eu { v && !m } else { !v && m });
            }
            Ins::Out(o) => {
                let v = self.power(segment)?;
                self.write_bit(o, v)?;
            }
            Ins::Set(o, n) | Ins::Reset(o, n) => {
                let set = matches!(ins, Ins::Set(..));
                if self.power(segment)? {
                    match o {
                        Operand::Bit(a, first) => {
                            for k in 0..u32::from(n) {
                                if first + k >= a.bytes() as u32 * 8 {
                                    return Err("S/R beyond the end of the area".into());
                                }
                                self.write_bit(Operand::Bit(a, first + k), set)?;
                            }
                        }
                        Operand::Timer(first) if !set => {
                            for k in first..first.saturating_add(n).min(256) {
                                let t = &mut self.timers[k as usize];
                                *t = Timer { op: t.op, pt: t.pt, ..Timer::default() };
                            }
                        }
                        Operand::Counter(first) if !set => {
                            for k in first..first.saturating_add(n).min(256) {
                                let c = &mut self.counters[k as usize];
                                c.value = 0;
                                c.bit = false;
                            }
                        }
                        _ => return Err("S on a timer or counter".into()),
                    }
                }
            }
            Ins::Timer(op, n, pt) => {
                *self.executions.entry(('T', n)).or_insert(0) += 1;
                let pt = self.read_value(pt, false)?;
                let skip = segment.is_some_and(|s| !s.energized);
                if skip && self.scr_model == ScrModel::Skip {
                    return Ok(None);
                }
                let input = self.top()? && !skip;
                self.timer(op, n, pt, input, skip)?;
            }
            Ins::Counter(op, n, pv) => {
                *self.executions.entry(('C', n)).or_insert(0) += 1;
                let skip = segment.is_some_and(|s| !s.energized);
                if skip && self.scr_model == ScrModel::Skip {
                    return Ok(None);
                }
                let pv = self.read_value(pv, false)?;
                let on = |v: bool| v && !skip;
                let c = &mut self.counters[n as usize];
                if *c.op.get_or_insert(op) != op {
                    return Err(format!("C{n} used by two kinds of counter instruction"));
                }
                match op {
                    CounterOp::Ctu => {
                        let (r, cu) = (on(self.stack[0].ok_or("CTU: reset input undefined")?), self.level(1)?);
                        let cu = on(cu);
                        let c = &mut self.counters[n as usize];
                        if r {
                            c.value = 0;
                        } else if cu && !c.last_up && c.value < 32767 {
                            c.value += 1;
                        }
                        c.last_up = cu;
                        c.bit = c.value >= pv;
                    }
                    CounterOp::Ctd => {
                        let (ld, cd) = (on(self.top()?), on(self.level(1)?));
                        let c = &mut self.counters[n as usize];
                        if ld {
                            c.value = pv;
                            c.bit = false;
                        } else {
                            if cd && !c.last_down && c.value > 0 {
                                c.value -= 1;
                            }
                            c.bit = c.value == 0;
                        }
                        c.last_down = cd;
                    }
                    CounterOp::Ctud => {
                        let (r, cd, cu) = (on(self.top()?), on(self.level(1)?), on(self.level(2)?));
                        let c = &mut self.counters[n as usize];
                        if r {
                            c.value = 0;
                        } else {
                            if cu && !c.last_up {
                                c.value = if c.value == 32767 { -32768 } else { c.value + 1 };
                            }
                            if cd && !c.last_down {
                                c.value = if c.value == -32768 { 32767 } else { c.value - 1 };
                            }
                        }
                        c.last_up = cu;
                        c.last_down = cd;
                        c.bit = c.value >= pv;
                    }
                }
            }
            Ins::Move(wide, a, b) => {
                if self.power(segment)? {
                    let v = self.read_value(a, wide)?;
                    self.write_value(b, v, wide)?;
                }
            }
            Ins::Itd(a, b) => {
                if self.power(segment)? {
                    let v = self.read_value(a, false)?;
                    self.write_value(b, v, true)?;
                }
            }
            Ins::Dti(a, b) => {
                if self.power(segment)? {
                    let v = self.read_value(a, true)?;
                    if (-32768..=32767).contains(&v) {
                        self.write_value(b, v, false)?;
                    } else {
                        self.put_bit(Area::Sm, 9, true); // SM1.1: overflow, output unchanged
                    }
                }
            }
            Ins::Arith(wide, op, a, b) => {
                if self.power(segment)? {
                    let (x, y) = (self.read_value(b, wide)?, self.read_value(a, wide)?);
                    let r = match op {
                        Arith::Add => Some(x + y),
                        Arith::Sub => Some(x - y),
                        Arith::Mul => Some(x * y),
                        Arith::Div if y == 0 => None,
                        Arith::Div => Some(x / y),
                    };
                    match r {
                        Some(r) => {
                            let (lo, hi) = if wide { (-(1i64 << 31), (1i64 << 31) - 1) } else { (-32768, 32767) };
                            self.put_bit(Area::Sm, 9, r < lo || r > hi);
                            self.write_value(b, r, wide)?;
                        }
                        None => self.put_bit(Area::Sm, 11, true), // SM1.3: division by zero
                    }
                }
            }
            Ins::Step(wide, d, o) => {
                if self.power(segment)? {
                    let v = self.read_value(o, wide)?;
                    self.write_value(o, v + d, wide)?;
                }
            }
            Ins::Lscr(o) => {
                if segment.is_some() {
                    return Err("nested LSCR".into());
                }
                let Operand::Bit(Area::S, _) = o else { return Err("LSCR needs an S bit".into()) };
                let energized = self.read_bit(o)?;
                *segment = Some(Segment { bit: o, energized, pending_reset: false });
                if !energized && self.scr_model == ScrModel::Skip {
                    let end =
                        self.prog.ins[pc + 1..].iter().position(|(i, _)| *i == Ins::Scre).ok_or("LSCR without SCRE")?;
                    return Ok(Some(pc + 1 + end));
                }
                // The SCR value is copied to the top of the logic stack.
                self.stack = [None; STACK];
                self.push(energized);
            }
            Ins::Scrt(o) => {
                let Some(seg) = *segment else { return Err("SCRT outside a segment".into()) };
                let Operand::Bit(Area::S, _) = o else { return Err("SCRT needs an S bit".into()) };
                if o == seg.bit {
                    return Err(
                        "SCRT to the segment's own S bit: the order of its set and reset is not documented".into()
                    );
                }
                if self.power(segment)? {
                    self.write_bit(o, true)?;
                    match self.scrt_reset {
                        ScrtReset::Immediate => self.write_bit(seg.bit, false)?,
                        ScrtReset::AtScre => {
                            if let Some(s) = segment.as_mut() {
                                s.pending_reset = true;
                            }
                        }
                    }
                }
            }
            Ins::Scre => {
                let Some(seg) = segment.take() else { return Err("SCRE without LSCR".into()) };
                if seg.pending_reset {
                    self.write_bit(seg.bit, false)?;
                }
                self.stack = [None; STACK];
            }
            Ins::Jmp(l) => {
                if segment.is_some() {
                    return Err("JMP inside an SCR segment".into());
                }
                if self.top()? {
                    let to = *self.labels.get(&l).ok_or_else(|| format!("JMP {l} without LBL {l}"))?;
                    return Ok(Some(to + 1));
                }
            }
            Ins::Lbl(_) => {
                if segment.is_some() {
                    return Err("LBL inside an SCR segment".into());
                }
            }
        }
        Ok(None)
    }

    fn combine(&mut self, c: Combine, v: bool) -> Result<(), String> {
        match c {
            Combine::Load => self.push(v),
            Combine::And => self.stack[0] = Some(self.top()? && v),
            Combine::Or => self.stack[0] = Some(self.top()? || v),
        }
        Ok(())
    }

    /// A timer instruction with input `input`; `dead` when it sits in a de-energized segment.
    fn timer(&mut self, op: TimerOp, n: u16, pt: i64, input: bool, dead: bool) -> Result<(), String> {
        let (res, tonr) = timer_kind(n);
        match (op, tonr) {
            (TimerOp::Tonr, false) => return Err(format!("T{n} is not a TONR timer")),
            (TimerOp::Ton | TimerOp::Tof, true) => return Err(format!("T{n} is a TONR timer")),
            _ => {}
        }
        let tick = self.ticks(self.now, res);
        let d100 = self.d100;
        let (value_now, _) = self.timer_now(n);
        let t = &mut self.timers[n as usize];
        if *t.op.get_or_insert(op) != op {
            return Err(format!("T{n} used by both TON and TOF"));
        }
        t.pt = pt;
        if op == TimerOp::Tof {
            if dead {
                // System Manual: a TOF in an inactive SCR segment is reset and does not time.
                *t = Timer { op: Some(op), pt, ..Timer::default() };
                return Ok(());
            }
            if input {
                *t = Timer { op: Some(op), pt, bit: true, last_in: true, ..Timer::default() };
                return Ok(());
            }
            if t.last_in {
                t.enabled = true;
                t.since = tick;
                t.base = 0;
            }
            t.last_in = false;
            if t.enabled {
                match res {
                    100_000 => t.value = (t.value + d100).min(pt),
                    1_000 => t.value = value_now,
                    _ => {}
                }
                if t.value >= pt {
                    t.value = pt;
                    t.bit = false;
                    t.enabled = false;
                }
            }
            return Ok(());
        }
        match res {
            100_000 => {
                if input {
                    t.value = (t.value + d100).min(32767);
                } else if op == TimerOp::Ton {
                    t.value = 0;
                }
                t.bit = t.value >= pt;
            }
            10_000 => {
                if input {
                    t.enabled = true;
                } else {
                    t.enabled = false;
                    if op == TimerOp::Ton {
                        t.value = 0;
                    }
                }
                t.bit = t.value >= pt;
            }
            _ => {
                if input {
                    if !t.enabled {
                        t.enabled = true;
                        t.since = tick;
                        t.base = t.value;
                    }
                } else {
                    t.value = if op == TimerOp::Ton { 0 } else { value_now };
                    t.enabled = false;
                    t.bit = t.value >= pt;
                }
            }
        }
        Ok(())
    }
}

#[derive(Debug, Clone, Copy)]
struct Segment {
    bit: Operand,
    energized: bool,
    pending_reset: bool,
}
