//! The statement list being built: S7-200 operands, instructions and networks, and their text
//! in the Micro/WIN STL style (`LD     I0.0`, `TON    T37, +50`, `NETWORK 3 // …`), ASCII
//! only (Micro/WIN reads ANSI text).

use std::fmt::Write as _;

/// A memory area of the S7-200.
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

/// A bit operand. Timers, counters and scratch bits are numbered in tables that are filled
/// before the text is printed ([`Resolve`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub(crate) enum Addr {
    /// `area byte.bit`
    Bit(Area, u32, u8),
    /// The timer of entry `n` of the timer table (its bit when read, the timer when written).
    Timer(usize),
    /// The counter of entry `n` of the counter table.
    Counter(usize),
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

/// A value operand (16 or 32 bits).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub(crate) enum Val {
    /// `VW100`, `MW4`, `IW0`, `QW2`: a word at a byte address.
    Word(Area, u32),
    /// `VD100`, `MD4`: a double word.
    DWord(Area, u32),
    /// The current value of counter-table entry `n`.
    Counter(usize),
    Const(i64),
    /// Scratch word / double word `n` of a network.
    TempW(usize),
    TempD(usize),
}

/// An instruction argument.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum Arg {
    Bit(Addr),
    Val(Val),
    /// The bit count of `S`/`R`, a label number.
    Num(u16),
}

/// How a compare contact joins the logic stack.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Join {
    Ld,
    A,
    O,
}

/// Comparison operators of the compare contacts.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum CmpOp {
    Eq,
    Ne,
    Lt,
    Le,
    Gt,
    Ge,
}

impl CmpOp {
    pub(crate) fn negate(self) -> CmpOp {
        match self {
            CmpOp::Eq => CmpOp::Ne,
            CmpOp::Ne => CmpOp::Eq,
            CmpOp::Lt => CmpOp::Ge,
            CmpOp::Le => CmpOp::Gt,
            CmpOp::Gt => CmpOp::Le,
            CmpOp::Ge => CmpOp::Lt,
        }
    }
    fn symbol(self) -> &'static str {
        match self {
            CmpOp::Eq => "=",
            CmpOp::Ne => "<>",
            CmpOp::Lt => "<",
            CmpOp::Le => "<=",
            CmpOp::Gt => ">",
            CmpOp::Ge => ">=",
        }
    }
}

/// Word arithmetic (`OUT := OUT op IN`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum ArithOp {
    Add,
    Sub,
    Mul,
    Div,
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
    Set,
    /// `R bit, n`
    Reset,
    /// `TON Tn, +pt`
    Ton,
    /// `TONR Tn, +pt`
    Tonr,
    /// `LDW>= a, b` and the other compare contacts (32-bit: `LDD…`).
    Cmp(Join, bool, CmpOp),
    /// `MOVW` / `MOVD`.
    Mov(bool),
    /// `+I -I *I /I` / `+D -D *D /D`.
    Arith(bool, ArithOp),
    /// `INCW` / `INCD`.
    Inc(bool),
    /// `ITD` (INT to DINT).
    Itd,
    Ctu,
    Ctd,
    Ctud,
    Lscr,
    Scrt,
    Scre,
    Jmp,
    Lbl,
}

impl Op {
    fn mnemonic(self) -> String {
        let s = match self {
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
            Op::Set => "S",
            Op::Reset => "R",
            Op::Ton => "TON",
            Op::Tonr => "TONR",
            Op::Cmp(join, wide, op) => {
                let j = match join {
                    Join::Ld => "LD",
                    Join::A => "A",
                    Join::O => "O",
                };
                return format!("{j}{}{}", if wide { "D" } else { "W" }, op.symbol());
            }
            Op::Mov(wide) => {
                if wide {
                    "MOVD"
                } else {
                    "MOVW"
                }
            }
            Op::Arith(wide, op) => {
                let c = match op {
                    ArithOp::Add => '+',
                    ArithOp::Sub => '-',
                    ArithOp::Mul => '*',
                    ArithOp::Div => '/',
                };
                return format!("{c}{}", if wide { "D" } else { "I" });
            }
            Op::Inc(wide) => {
                if wide {
                    "INCD"
                } else {
                    "INCW"
                }
            }
            Op::Itd => "ITD",
            Op::Ctu => "CTU",
            Op::Ctd => "CTD",
            Op::Ctud => "CTUD",
            Op::Lscr => "LSCR",
            Op::Scrt => "SCRT",
            Op::Scre => "SCRE",
            Op::Jmp => "JMP",
            Op::Lbl => "LBL",
        };
        s.to_string()
    }
}

/// One instruction with an optional end-of-line comment (usually the symbolic name).
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Ins {
    pub op: Op,
    pub args: Vec<Arg>,
    pub note: String,
}

impl Ins {
    pub(crate) fn bare(op: Op) -> Ins {
        Ins { op, args: Vec::new(), note: String::new() }
    }
    /// An instruction on one bit (`LD`, `=`, `LSCR`, …).
    pub(crate) fn on(op: Op, addr: Addr, note: impl Into<String>) -> Ins {
        Ins { op, args: vec![Arg::Bit(addr)], note: note.into() }
    }
    /// `S bit, n` / `R bit, n`.
    pub(crate) fn count(op: Op, addr: Addr, n: u16, note: impl Into<String>) -> Ins {
        Ins { op, args: vec![Arg::Bit(addr), Arg::Num(n)], note: note.into() }
    }
    pub(crate) fn vals(op: Op, vals: &[Val], note: impl Into<String>) -> Ins {
        Ins { op, args: vals.iter().map(|v| Arg::Val(*v)).collect(), note: note.into() }
    }
    /// `TON Tn, +pt`, `CTU Cn, PV`.
    pub(crate) fn boxed(op: Op, addr: Addr, preset: Val, note: impl Into<String>) -> Ins {
        Ins { op, args: vec![Arg::Bit(addr), Arg::Val(preset)], note: note.into() }
    }
    pub(crate) fn label(op: Op, n: u16, note: impl Into<String>) -> Ins {
        Ins { op, args: vec![Arg::Num(n)], note: note.into() }
    }
}

/// A network: a title comment and its instructions.
#[derive(Debug, Clone, PartialEq, Default)]
pub(crate) struct Network {
    pub title: String,
    pub code: Vec<Ins>,
}

/// Turns the numbered timers, counters and scratch operands into real ones.
pub(crate) struct Resolve<'a> {
    /// Timer numbers (`T37` → 37) by timer-table index.
    pub timers: &'a [u16],
    /// Counter numbers by counter-table index.
    pub counters: &'a [u16],
    /// Addresses of the scratch bits.
    pub temps: &'a [Addr],
    /// Byte addresses (in V) of the scratch words and double words.
    pub temp_words: &'a [u32],
    pub temp_dwords: &'a [u32],
}

impl Resolve<'_> {
    pub(crate) fn text(&self, a: Addr) -> String {
        match a {
            Addr::Bit(area, byte, bit) => format!("{}{byte}.{bit}", area.prefix()),
            Addr::Timer(n) => format!("T{}", self.timers.get(n).copied().unwrap_or(0)),
            Addr::Counter(n) => format!("C{}", self.counters.get(n).copied().unwrap_or(0)),
            Addr::Temp(n) => match self.temps.get(n) {
                Some(&t) => self.text(t),
                None => "?".to_string(),
            },
        }
    }
    pub(crate) fn value(&self, v: Val) -> String {
        match v {
            Val::Word(area, at) => format!("{}W{at}", area.prefix()),
            Val::DWord(area, at) => format!("{}D{at}", area.prefix()),
            Val::Counter(n) => self.text(Addr::Counter(n)),
            Val::Const(c) => constant(c),
            Val::TempW(n) => format!("VW{}", self.temp_words.get(n).copied().unwrap_or(0)),
            Val::TempD(n) => format!("VD{}", self.temp_dwords.get(n).copied().unwrap_or(0)),
        }
    }
}

/// A constant in Micro/WIN's form: `+5`, `-3`.
pub(crate) fn constant(c: i64) -> String {
    if c < 0 {
        c.to_string()
    } else {
        format!("+{c}")
    }
}

/// Column of the operand (Micro/WIN pads the mnemonic to 7 characters).
const OPERAND_COLUMN: usize = 7;
/// Column of end-of-line comments.
const NOTE_COLUMN: usize = 24;
/// Network titles are kept short (Micro/WIN shows one line).
const TITLE_CHARS: usize = 120;

/// Prints networks, numbered from 1.
pub(crate) fn print_networks(networks: &[Network], r: &Resolve<'_>, out: &mut String) {
    for (i, n) in networks.iter().enumerate() {
        let mut title = ascii(&one_line(&n.title));
        if title.chars().count() > TITLE_CHARS {
            title = title.chars().take(TITLE_CHARS - 3).collect::<String>() + "...";
        }
        let _ = writeln!(out, "NETWORK {} // {title}", i + 1);
        for ins in &n.code {
            let mut line = ins.op.mnemonic();
            if !ins.args.is_empty() {
                pad_to(&mut line, OPERAND_COLUMN);
                let args: Vec<String> = ins
                    .args
                    .iter()
                    .map(|a| match a {
                        Arg::Bit(b) => r.text(*b),
                        Arg::Val(v) => r.value(*v),
                        Arg::Num(n) => n.to_string(),
                    })
                    .collect();
                line.push_str(&args.join(", "));
            }
            if !ins.note.is_empty() {
                pad_to(&mut line, NOTE_COLUMN);
                line.push_str("// ");
                line.push_str(&ascii(&one_line(&ins.note)));
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

/// ASCII only (Micro/WIN's editor reads ANSI text): common typographic characters are spelled
/// out, anything else becomes `?`.
pub(crate) fn ascii(s: &str) -> String {
    let mut out = String::with_capacity(s.len());
    for c in s.chars() {
        match c {
            c if c.is_ascii() => out.push(c),
            '\u{2013}' | '\u{2014}' | '\u{2212}' => out.push('-'),
            '\u{2192}' => out.push_str("->"),
            '\u{2190}' => out.push_str("<-"),
            '\u{2265}' => out.push_str(">="),
            '\u{2264}' => out.push_str("<="),
            '\u{2260}' => out.push_str("<>"),
            '\u{00d7}' => out.push('x'),
            '\u{2018}' | '\u{2019}' => out.push('\''),
            '\u{201c}' | '\u{201d}' => out.push('"'),
            '\u{00b7}' => out.push('.'),
            _ => out.push('?'),
        }
    }
    out
}
