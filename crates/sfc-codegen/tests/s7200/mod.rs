//! An interpreter of the S7-200 statement-list instructions the STL target may emit, written
//! from the S7-200 instruction descriptions (seed 002, chapter 3), for differential testing:
//!
//! - bit logic on the 9-level logic stack: `LD LDN A AN O ON` (a load pushes, the others
//!   combine with the top), `ALD OLD` (combine the two top levels, the stack moves up), `LPS`
//!   (push a copy of the top), `LRD` (copy the second level to the top), `LPP` (pop), `NOT`,
//!   `EU`/`ED` (one edge memory per instruction);
//! - outputs `=`, `S bit, n`, `R bit, n` (n consecutive bits, or n timers: reset value and bit);
//! - `TON Tn, PT` and `TONR Tn, PT` on their S7-200 timer numbers (100 ms ones only:
//!   `T37`–`T63`, `T101`–`T255` TON, `T5`–`T31`, `T69`–`T95` TONR). A 100 ms timer's current
//!   value is updated when its instruction executes, by the time elapsed since its previous
//!   execution; TON clears when its input is off, TONR holds; the bit is `value >= PT`; the
//!   value stops at 32767;
//! - `LSCR S_bit` … `SCRT S_bit` … `SCRE` (a segment runs when its S bit is set; SCRT sets the
//!   target bit and resets the segment's own bit at once);
//! - `SM0.0` (always on), `SM0.1` (first scan).
//!
//! A scan runs the program top to bottom at one instant; the caller sets the inputs before
//! and passes the time. Each `NETWORK` starts with an undefined stack: reading an undefined
//! level, writing the input image or an unknown instruction is an error, so the interpreter
//! also checks that the generated code is well formed.

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

#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Operand {
    /// Area and bit number (`byte * 8 + bit`).
    Bit(Area, u32),
    Timer(u16),
}

#[derive(Debug, Clone, Copy, PartialEq)]
enum Ins {
    Network,
    Ld(Operand),
    Ldn(Operand),
    A(Operand),
    An(Operand),
    O(Operand),
    On(Operand),
    Ald,
    Old,
    Lps,
    Lrd,
    Lpp,
    Not,
    Eu,
    Ed,
    Out(Operand),
    Set(Operand, u16),
    Reset(Operand, u16),
    Ton(u16, u16),
    Tonr(u16, u16),
    Lscr(Operand),
    Scrt(Operand),
    Scre,
}

/// A parsed program.
#[derive(Debug, Clone)]
pub struct Program {
    ins: Vec<(Ins, usize)>,
}

/// Parses a bit or timer operand (`I0.3`, `SM0.1`, `S1.2`, `T37`).
pub fn operand(text: &str) -> Result<Operand, String> {
    let t = text.trim();
    let upper = t.to_ascii_uppercase();
    let (area, rest) = if let Some(r) = upper.strip_prefix("SM") {
        (Some(Area::Sm), r)
    } else if let Some(r) = upper.strip_prefix('T') {
        let n: u16 = r.parse().map_err(|_| format!("bad timer `{t}`"))?;
        if n > 255 {
            return Err(format!("no timer `{t}`"));
        }
        return Ok(Operand::Timer(n));
    } else {
        let area = match upper.chars().next() {
            Some('I') => Area::I,
            Some('Q') => Area::Q,
            Some('M') => Area::M,
            Some('V') => Area::V,
            Some('S') => Area::S,
            _ => return Err(format!("bad operand `{t}`")),
        };
        (Some(area), &upper[1..])
    };
    let area = area.ok_or_else(|| format!("bad operand `{t}`"))?;
    let (byte, bit) = rest.split_once('.').ok_or_else(|| format!("bad bit address `{t}`"))?;
    let byte: u32 = byte.parse().map_err(|_| format!("bad byte in `{t}`"))?;
    let bit: u32 = bit.parse().map_err(|_| format!("bad bit in `{t}`"))?;
    let limit = match area {
        Area::I | Area::Q => 15,
        Area::M | Area::S => 31,
        Area::V => 10239,
        Area::Sm => 549,
    };
    if bit > 7 || byte > limit {
        return Err(format!("`{t}` is outside the S7-200 memory"));
    }
    Ok(Operand::Bit(area, byte * 8 + bit))
}

fn constant(text: &str) -> Result<u16, String> {
    let t = text.trim();
    let t = t.strip_prefix('+').unwrap_or(t);
    let n: u32 = t.parse().map_err(|_| format!("bad constant `{text}`"))?;
    if n > 32767 {
        return Err(format!("constant `{text}` out of range"));
    }
    Ok(n as u16)
}

/// Parses statement-list text: `//` comments, `NETWORK n` lines, one instruction per line.
pub fn parse(text: &str) -> Result<Program, String> {
    let mut ins = Vec::new();
    for (no, raw) in text.lines().enumerate() {
        let line = raw.split("//").next().unwrap_or("").trim();
        if line.is_empty() {
            continue;
        }
        let at = |e: String| format!("line {}: {e}: `{raw}`", no + 1);
        let (mn, rest) = match line.split_once(char::is_whitespace) {
            Some((m, r)) => (m.to_ascii_uppercase(), r.trim()),
            None => (line.to_ascii_uppercase(), ""),
        };
        let args: Vec<&str> = if rest.is_empty() { Vec::new() } else { rest.split(',').map(str::trim).collect() };
        let one = || -> Result<Operand, String> {
            match args.as_slice() {
                [a] => operand(a),
                _ => Err(format!("`{mn}` takes one operand")),
            }
        };
        let two = || -> Result<(Operand, u16), String> {
            match args.as_slice() {
                [a, n] => {
                    let n = constant(n)?;
                    if n == 0 || n > 255 {
                        return Err("count must be 1 to 255".into());
                    }
                    Ok((operand(a)?, n))
                }
                _ => Err(format!("`{mn}` takes an operand and a count")),
            }
        };
        let timer = || -> Result<(u16, u16), String> {
            match args.as_slice() {
                [t, pt] => match operand(t)? {
                    Operand::Timer(n) => Ok((n, constant(pt)?)),
                    _ => Err("not a timer".into()),
                },
                _ => Err(format!("`{mn}` takes a timer and a preset")),
            }
        };
        let none = |i: Ins| -> Result<Ins, String> {
            if args.is_empty() {
                Ok(i)
            } else {
                Err(format!("`{mn}` takes no operand"))
            }
        };
        let parsed = match mn.as_str() {
            "NETWORK" => Ok(Ins::Network),
            "LD" => one().map(Ins::Ld),
            "LDN" => one().map(Ins::Ldn),
            "A" => one().map(Ins::A),
            "AN" => one().map(Ins::An),
            "O" => one().map(Ins::O),
            "ON" => one().map(Ins::On),
            "ALD" => none(Ins::Ald),
            "OLD" => none(Ins::Old),
            "LPS" => none(Ins::Lps),
            "LRD" => none(Ins::Lrd),
            "LPP" => none(Ins::Lpp),
            "NOT" => none(Ins::Not),
            "EU" => none(Ins::Eu),
            "ED" => none(Ins::Ed),
            "=" => one().map(Ins::Out),
            "S" => two().map(|(o, n)| Ins::Set(o, n)),
            "R" => two().map(|(o, n)| Ins::Reset(o, n)),
            "TON" => timer().map(|(t, pt)| Ins::Ton(t, pt)),
            "TONR" => timer().map(|(t, pt)| Ins::Tonr(t, pt)),
            "LSCR" => one().map(Ins::Lscr),
            "SCRT" => one().map(Ins::Scrt),
            "SCRE" => none(Ins::Scre),
            other => Err(format!("unknown instruction `{other}`")),
        };
        ins.push((parsed.map_err(at)?, no + 1));
    }
    Ok(Program { ins })
}

#[derive(Debug, Clone, Copy, Default)]
struct Timer {
    /// Accumulated time, µs.
    acc: i64,
    /// Time of the previous execution with the input on (the timer is running).
    last: Option<i64>,
    bit: bool,
}

/// 100 ms TON/TOF and TONR timer numbers.
fn is_ton_100ms(n: u16) -> bool {
    (37..=63).contains(&n) || (101..=255).contains(&n)
}
fn is_tonr_100ms(n: u16) -> bool {
    (5..=31).contains(&n) || (69..=95).contains(&n)
}

const STACK: usize = 9;

/// A CPU running one program.
pub struct Plc {
    prog: Program,
    bits: HashMap<(Area, u32), bool>,
    timers: Vec<Timer>,
    /// Edge memory of each EU/ED instruction, by instruction index.
    edges: Vec<bool>,
    stack: [Option<bool>; STACK],
    first_scan: bool,
    now: i64,
    /// `(instruction kind, timer)` seen: a timer number used by both TON and TONR is an error.
    timer_kind: HashMap<u16, bool>,
}

impl Plc {
    pub fn new(prog: Program) -> Plc {
        let n = prog.ins.len();
        Plc {
            prog,
            bits: HashMap::new(),
            timers: vec![Timer::default(); 256],
            edges: vec![false; n],
            stack: [None; STACK],
            first_scan: true,
            now: 0,
            timer_kind: HashMap::new(),
        }
    }

    pub fn set(&mut self, addr: &str, v: bool) -> Result<(), String> {
        match operand(addr)? {
            Operand::Bit(Area::Sm, _) | Operand::Timer(_) => Err(format!("`{addr}` cannot be set from outside")),
            Operand::Bit(a, n) => {
                self.bits.insert((a, n), v);
                Ok(())
            }
        }
    }

    pub fn get(&self, addr: &str) -> Result<bool, String> {
        Ok(self.read(operand(addr)?))
    }

    /// The current value of a timer (in its base units).
    pub fn timer_value(&self, n: u16) -> i64 {
        (self.timers[n as usize].acc / 100_000).min(32767)
    }

    fn read(&self, o: Operand) -> bool {
        match o {
            Operand::Bit(Area::Sm, 0) => true,
            Operand::Bit(Area::Sm, 1) => self.first_scan,
            Operand::Bit(a, n) => self.bits.get(&(a, n)).copied().unwrap_or(false),
            Operand::Timer(t) => self.timers[t as usize].bit,
        }
    }

    fn write(&mut self, o: Operand, v: bool) -> Result<(), String> {
        match o {
            Operand::Bit(Area::I, _) => Err("the program writes the input image".into()),
            Operand::Bit(Area::Sm, _) => Err("the program writes special memory".into()),
            Operand::Bit(a, n) => {
                self.bits.insert((a, n), v);
                Ok(())
            }
            Operand::Timer(_) => Err("`=` on a timer".into()),
        }
    }

    fn top(&self) -> Result<bool, String> {
        self.stack[0].ok_or_else(|| "the top of the logic stack is undefined".to_string())
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
    fn second(&self) -> Result<bool, String> {
        self.stack[1].ok_or_else(|| "the second level of the logic stack is undefined".to_string())
    }

    fn timer(&mut self, n: u16, pt: u16, input: bool, retentive: bool) -> Result<(), String> {
        let ok = if retentive { is_tonr_100ms(n) } else { is_ton_100ms(n) };
        if !ok {
            return Err(format!(
                "T{n} is not a 100 ms {} timer (the interpreter models those only)",
                if retentive { "TONR" } else { "TON" }
            ));
        }
        if *self.timer_kind.entry(n).or_insert(retentive) != retentive {
            return Err(format!("T{n} used by both TON and TONR"));
        }
        let now = self.now;
        let t = &mut self.timers[n as usize];
        if input {
            if let Some(last) = t.last {
                t.acc += now - last;
            }
            t.last = Some(now);
        } else {
            t.last = None;
            if !retentive {
                t.acc = 0;
            }
        }
        let value = (t.acc / 100_000).min(32767);
        t.acc = t.acc.min(32767 * 100_000);
        t.bit = value >= i64::from(pt);
        Ok(())
    }

    /// One scan at time `now` (µs).
    pub fn scan(&mut self, now: i64) -> Result<(), String> {
        self.now = now;
        self.stack = [None; STACK];
        let mut pc = 0;
        let mut segment: Option<Operand> = None;
        while pc < self.prog.ins.len() {
            let (ins, line) = self.prog.ins[pc];
            let r = self.step(ins, pc, &mut segment);
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

    fn step(&mut self, ins: Ins, pc: usize, segment: &mut Option<Operand>) -> Result<Option<usize>, String> {
        match ins {
            Ins::Network => self.stack = [None; STACK],
            Ins::Ld(o) => self.push(self.read(o)),
            Ins::Ldn(o) => self.push(!self.read(o)),
            Ins::A(o) => self.stack[0] = Some(self.top()? && self.read(o)),
            Ins::An(o) => self.stack[0] = Some(self.top()? && !self.read(o)),
            Ins::O(o) => self.stack[0] = Some(self.top()? || self.read(o)),
            Ins::On(o) => self.stack[0] = Some(self.top()? || !self.read(o)),
            Ins::Ald | Ins::Old => {
                let (a, b) = (self.top()?, self.second()?);
                self.pop();
                self.stack[0] = Some(if ins == Ins::Ald { a && b } else { a || b });
            }
            Ins::Lps => {
                let t = self.top()?;
                self.push(t);
            }
            Ins::Lrd => self.stack[0] = Some(self.second()?),
            Ins::Lpp => {
                self.second()?;
                self.pop();
            }
            Ins::Not => self.stack[0] = Some(!self.top()?),
            Ins::Eu | Ins::Ed => {
                let v = self.top()?;
                let m = self.edges[pc];
                self.edges[pc] = v;
                self.stack[0] = Some(if ins == Ins::Eu { v && !m } else { !v && m });
            }
            Ins::Out(o) => {
                let v = self.top()?;
                self.write(o, v)?;
            }
            Ins::Set(o, n) | Ins::Reset(o, n) => {
                let set = matches!(ins, Ins::Set(..));
                if self.top()? {
                    match o {
                        Operand::Bit(a, first) => {
                            for k in 0..u32::from(n) {
                                self.write(Operand::Bit(a, first + k), set)?;
                            }
                        }
                        Operand::Timer(first) => {
                            if set {
                                return Err("S on a timer".into());
                            }
                            for k in first..first.saturating_add(n) {
                                let t = self.timers.get_mut(k as usize).ok_or("timer out of range")?;
                                *t = Timer::default();
                            }
                        }
                    }
                }
            }
            Ins::Ton(n, pt) | Ins::Tonr(n, pt) => {
                let input = self.top()?;
                self.timer(n, pt, input, matches!(ins, Ins::Tonr(..)))?;
            }
            Ins::Lscr(o) => {
                if segment.is_some() {
                    return Err("nested LSCR".into());
                }
                let Operand::Bit(Area::S, _) = o else { return Err("LSCR needs an S bit".into()) };
                if self.read(o) {
                    *segment = Some(o);
                    self.push(true);
                } else {
                    // Skip to the matching SCRE.
                    let end =
                        self.prog.ins[pc + 1..].iter().position(|(i, _)| *i == Ins::Scre).ok_or("LSCR without SCRE")?;
                    return Ok(Some(pc + 1 + end + 1));
                }
            }
            Ins::Scrt(o) => {
                let Some(own) = *segment else { return Err("SCRT outside a segment".into()) };
                let Operand::Bit(Area::S, _) = o else { return Err("SCRT needs an S bit".into()) };
                if self.top()? {
                    self.write(own, false)?;
                    self.write(o, true)?;
                }
            }
            Ins::Scre => {
                if segment.take().is_none() {
                    return Err("SCRE without LSCR".into());
                }
            }
        }
        Ok(None)
    }
}
