//! The statement list being built: S7-200 operands, instructions and networks, and their text
//! in the Micro/WIN STL style (`LD     I0.0`, `TON    T37, +50`, `NETWORK 3 // …`).

use std::fmt::Write as _;

/// A memory area of the S7-200 that holds bits.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub(crate) enum Area {
    /// Process-image inputs `I0.0`–`I15.7`.
    I,
    /// Process-image outputs `Q0.0`–`Q15.7`.
    Q,
    /// Bit memory `M0.0`–`M31.7`.
    M,
    /// Variable memory `V0.0`–…
    V,
    /// Sequence control relays `S0.0`–`S31.7`.
    S,
    /// Special memory (`SM0.0` always on, `SM0.1` on in the first scan only).
    Sm,
}

impl Area {
    pub(crate) fn prefix(self) -> &'static str {
        match self {
            Area::I => "I",
            Area::Q => "Q",
            Area::M => "M",
            Area::V => "V",
            Area::S => "S",
            Area::Sm => "SM",
        }
    }
}

/// A bit operand. Timers and scratch bits are numbered in tables that are filled before the
/// text is printed ([`Resolve`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub(crate) enum Addr {
    /// `area byte.bit`
    Bit(Area, u32, u8),
    /// The timer of entry `n` of the timer table (its bit when read, the timer when written).
    Timer(usize),
    /// Scratch bit `n` (partial results of one network).
    Temp(usize),
}

impl Addr {
    pub(crate) const ALWAYS_ON: Addr = Addr::Bit(Area::Sm, 0, 0);
    pub(crate) const FIRST_SCAN: Addr = Addr::Bit(Area::Sm, 0, 1);

    /// Bit number inside its area (`byte·8 + bit`).
    pub(crate) fn linear(self) -> Option<(Area, u32)> {
        match self {
            Addr::Bit(a, byte, bit) => Some((a, byte * 8 + u32::from(bit))),
            _ => None,
        }
    }
    pub(crate) fn from_linear(area: Area, n: u32) -> Addr {
        Addr::Bit(area, n / 8, (n % 8) as u8)
    }
}

/// Turns the numbered timers and scratch bits into real operands.
pub(crate) struct Resolve<'a> {
    /// Timer numbers (`T37` → 37) by timer-table index.
    pub timers: &'a [u16],
    /// Addresses of the scratch bits.
    pub temps: &'a [Addr],
}

impl Resolve<'_> {
    pub(crate) fn text(&self, a: Addr) -> String {
        match a {
            Addr::Bit(area, byte, bit) => format!("{}{byte}.{bit}", area.prefix()),
            Addr::Timer(n) => format!("T{}", self.timers.get(n).copied().unwrap_or(0)),
            Addr::Temp(n) => match self.temps.get(n) {
                Some(&t) => self.text(t),
                None => "?".to_string(),
            },
        }
    }
}

/// The instructions the generator uses (a subset of the S7-200 set; see the module doc).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Op {
    Ld,
    Ldn,
    A,
    An,
    O,
    On,
    Ald,
    Old,
    Lps,
    Not,
    Eu,
    Ed,
    /// `=` (output the top of the logic stack).
    Out,
    /// `S bit, n`
    Set(u16),
    /// `R bit, n`
    Reset(u16),
    /// `TON Tn, +pt`
    Ton(u16),
    /// `TONR Tn, +pt`
    Tonr(u16),
}

impl Op {
    fn mnemonic(self) -> &'static str {
        match self {
            Op::Ld => "LD",
            Op::Ldn => "LDN",
            Op::A => "A",
            Op::An => "AN",
            Op::O => "O",
            Op::On => "ON",
            Op::Ald => "ALD",
            Op::Old => "OLD",
            Op::Lps => "LPS",
            Op::Not => "NOT",
            Op::Eu => "EU",
            Op::Ed => "ED",
            Op::Out => "=",
            Op::Set(_) => "S",
            Op::Reset(_) => "R",
            Op::Ton(_) => "TON",
            Op::Tonr(_) => "TONR",
        }
    }
}

/// One instruction with an optional end-of-line comment (usually the symbolic name).
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Ins {
    pub op: Op,
    pub addr: Option<Addr>,
    pub note: String,
}

impl Ins {
    pub(crate) fn bare(op: Op) -> Ins {
        Ins { op, addr: None, note: String::new() }
    }
    pub(crate) fn on(op: Op, addr: Addr, note: impl Into<String>) -> Ins {
        Ins { op, addr: Some(addr), note: note.into() }
    }
}

/// A network: a title comment and its instructions.
#[derive(Debug, Clone, PartialEq, Default)]
pub(crate) struct Network {
    pub title: String,
    pub code: Vec<Ins>,
}

/// Column of the operand (Micro/WIN pads the mnemonic to 7 characters).
const OPERAND_COLUMN: usize = 7;
/// Column of end-of-line comments.
const NOTE_COLUMN: usize = 24;

/// Prints networks, numbered from 1.
pub(crate) fn print_networks(networks: &[Network], r: &Resolve<'_>, out: &mut String) {
    for (i, n) in networks.iter().enumerate() {
        let _ = writeln!(out, "NETWORK {} // {}", i + 1, one_line(&n.title));
        for ins in &n.code {
            let mut line = String::from(ins.op.mnemonic());
            if let Some(a) = ins.addr {
                pad_to(&mut line, OPERAND_COLUMN);
                line.push_str(&r.text(a));
                match ins.op {
                    Op::Set(k) | Op::Reset(k) => {
                        let _ = write!(line, ", {k}");
                    }
                    Op::Ton(pt) | Op::Tonr(pt) => {
                        let _ = write!(line, ", +{pt}");
                    }
                    _ => {}
                }
            }
            if !ins.note.is_empty() {
                pad_to(&mut line, NOTE_COLUMN);
                line.push_str("// ");
                line.push_str(&one_line(&ins.note));
            }
            out.push_str(line.trim_end());
            out.push('\n');
        }
        out.push('\n');
    }
}

fn pad_to(line: &mut String, col: usize) {
    let n = line.chars().count();
    if n < col {
        line.extend(std::iter::repeat_n(' ', col - n));
    } else {
        line.push(' ');
    }
}

/// Collapses white space (comments must stay on one line).
pub(crate) fn one_line(s: &str) -> String {
    s.split_whitespace().collect::<Vec<_>>().join(" ")
}
