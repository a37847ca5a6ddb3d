//! Traces of a run (`interfaces.md`, "Traces"): JSON lines, CSV and VCD writers behind one
//! [`TraceSink`] trait, fed once with a [`TraceHeader`] and then once per scan.
//!
//! The writers write to any [`Write`]; opening files or standard output is the caller's job
//! (nothing in this crate prints). Formats chosen where the contract leaves room:
//!
//! * **JSON lines**: exactly the object of the contract, keys in the order
//!   `scan, time, active, fired, vars, events`; REAL as the shortest JSON number that reads back
//!   to the same value (non-finite values as `null`); DATE, TIME_OF_DAY and DATE_AND_TIME as
//!   their IEC literals (`"D#2024-03-01"`, `"TOD#12:30:00"`, `"DT#2024-03-01-12:30:00"`).
//! * **CSV**: header `scan,time,active,<variables…>`; `active` holds the active step names
//!   joined with one space (names never contain spaces); BOOL as `TRUE`/`FALSE`; TIME as its
//!   canonical literal; fields quoted as RFC 4180 says (when they contain `,`, `"`, CR or LF,
//!   with `"` doubled); lines end with LF.
//! * **VCD**: `$timescale 1 us $end`, one `module` scope named after the POU (steps of nested
//!   SFC instances in nested scopes named after the instance path), one `wire 1` per step flag
//!   and per BOOL variable, `integer N` per integer variable (`N` its width), `wire N` per bit
//!   string (BYTE … LWORD); values are dumped at `#0`, then only changes, at the scan's time
//!   in µs, and the file ends with the time at which the last scan's period ends.

use crate::{format_time, write_time, Event, ScanRecord, Simulation, Value};
use sfc_st::Type;
use std::collections::HashSet;
use std::fmt::Write as _;
use std::io::{self, Write};
use std::path::Path;

/// What a trace knows before the first scan.
#[derive(Debug, Clone, PartialEq)]
pub struct TraceHeader {
    /// Declared name of the simulated POU.
    pub pou: String,
    /// Every step (qualified), in declaration order.
    pub steps: Vec<String>,
    /// The traced variables ([`Simulation::trace_vars`]), in declaration order.
    pub vars: Vec<(String, Type)>,
    /// Scan period, µs.
    pub period: i64,
}

impl TraceHeader {
    /// The header of a simulation.
    pub fn of(sim: &Simulation) -> TraceHeader {
        TraceHeader {
            pou: sim.pou_name().to_string(),
            steps: sim.step_names(),
            vars: sim.trace_vars(),
            period: sim.options().period,
        }
    }
}

/// Receives a run: [`TraceSink::header`] once, then [`TraceSink::scan`] after every scan with the
/// scan's record and the values of the header's variables (same order), then
/// [`TraceSink::finish`].
pub trait TraceSink {
    fn header(&mut self, header: &TraceHeader) -> io::Result<()>;
    fn scan(&mut self, record: &ScanRecord, values: &[Value]) -> io::Result<()>;
    /// Completes the file and flushes.
    fn finish(&mut self) -> io::Result<()> {
        Ok(())
    }
}

/// The trace formats, chosen by the extension of the output path.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum TraceFormat {
    JsonLines,
    Csv,
    Vcd,
}

impl TraceFormat {
    /// `.jsonl` (also `.json`, `.ndjson`) JSON lines, `.csv`, `.vcd`; `-` (standard output)
    /// JSON lines. Case-insensitive; `None` for any other extension.
    pub fn from_path(path: &Path) -> Option<TraceFormat> {
        if path.as_os_str() == "-" {
            return Some(TraceFormat::JsonLines);
        }
        let ext = path.extension()?.to_str()?.to_ascii_lowercase();
        match ext.as_str() {
            "jsonl" | "ndjson" | "json" => Some(TraceFormat::JsonLines),
            "csv" => Some(TraceFormat::Csv),
            "vcd" => Some(TraceFormat::Vcd),
            _ => None,
        }
    }

    /// A writer of this format over `out`.
    pub fn writer<'a, W: Write + 'a>(self, out: W) -> Box<dyn TraceSink + 'a> {
        match self {
            TraceFormat::JsonLines => Box::new(JsonLinesWriter::new(out)),
            TraceFormat::Csv => Box::new(CsvWriter::new(out)),
            TraceFormat::Vcd => Box::new(VcdWriter::new(out)),
        }
    }
}

// ---------------------------------------------------------------------------------------------
// Value texts shared by the writers

fn json_string(s: &str) -> String {
    let mut out = String::with_capacity(s.len() + 2);
    push_json_str(&mut out, s);
    out
}

/// Appends `s` as a JSON string, escaped as serde_json escapes it (`"`, `\\` and control
/// characters).
pub fn push_json_str(out: &mut String, s: &str) {
    out.push('"');
    let mut start = 0;
    for (i, b) in s.bytes().enumerate() {
        let esc = match b {
            b'"' => "\\\"",
            b'\\' => "\\\\",
            b'\n' => "\\n",
            b'\r' => "\\r",
            b'\t' => "\\t",
            0x08 => "\\b",
            0x0C => "\\f",
            0..=0x1F => "",
            _ => continue,
        };
        out.push_str(&s[start..i]);
        if esc.is_empty() {
            let _ = write!(out, "\\u{b:04x}");
        } else {
            out.push_str(esc);
        }
        start = i + 1;
    }
    out.push_str(&s[start..]);
    out.push('"');
}

fn push_json_str_array(out: &mut String, items: &[String]) {
    out.push('[');
    for (i, s) in items.iter().enumerate() {
        if i > 0 {
            out.push(',');
        }
        push_json_str(out, s);
    }
    out.push(']');
}

fn json_string_array(items: &[String]) -> String {
    let mut out = String::from("[");
    for (i, s) in items.iter().enumerate() {
        if i > 0 {
            out.push(',');
        }
        out.push_str(&json_string(s));
    }
    out.push(']');
    out
}

fn is_unsigned_64(ty: &Type) -> bool {
    matches!(ty.base(), Type::ULInt | Type::LWord)
}

/// A REAL/LREAL as text: the shortest decimal that reads back to the same value (REAL at single
/// precision).
fn push_real(out: &mut String, r: f64, ty: &Type) {
    if matches!(ty.base(), Type::Real) {
        let _ = write!(out, "{:?}", r as f32);
    } else {
        let _ = write!(out, "{r:?}");
    }
}

/// `(year, month, day)` of a day count since 1970-01-01 (proleptic Gregorian).
fn civil_from_days(days: i64) -> (i64, u32, u32) {
    let z = days + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z.rem_euclid(146_097);
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
    let y = yoe + era * 400;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let d = (doy - (153 * mp + 2) / 5 + 1) as u32;
    let m = if mp < 10 { mp + 3 } else { mp - 9 } as u32;
    (if m <= 2 { y + 1 } else { y }, m, d)
}

const DAY_US: i64 = 86_400_000_000;

fn push_tod(out: &mut String, us: i64) {
    let us = us.rem_euclid(DAY_US);
    let (h, m, s, frac) = (us / 3_600_000_000, us / 60_000_000 % 60, us / 1_000_000 % 60, us % 1_000_000);
    let _ = write!(out, "{h:02}:{m:02}:{s:02}");
    if frac != 0 {
        let mut frac = frac;
        let mut digits = 6;
        while frac % 10 == 0 {
            frac /= 10;
            digits -= 1;
        }
        let _ = write!(out, ".{frac:0digits$}");
    }
}

fn push_date(out: &mut String, us: i64) {
    let (y, m, d) = civil_from_days(us.div_euclid(DAY_US));
    let _ = write!(out, "{y:04}-{m:02}-{d:02}");
}

/// Appends the IEC literal of a DATE, TIME_OF_DAY or DATE_AND_TIME value; `false` (nothing
/// written) for other types.
fn push_date_literal(out: &mut String, us: i64, ty: &Type) -> bool {
    match ty.base() {
        Type::Date => {
            out.push_str("D#");
            push_date(out, us);
        }
        Type::TimeOfDay => {
            out.push_str("TOD#");
            push_tod(out, us);
        }
        Type::DateAndTime => {
            out.push_str("DT#");
            push_date(out, us);
            out.push('-');
            push_tod(out, us);
        }
        _ => return false,
    }
    true
}

/// The IEC literal of a DATE, TIME_OF_DAY or DATE_AND_TIME value held as microseconds.
pub fn date_literal(us: i64, ty: &Type) -> Option<String> {
    let mut out = String::new();
    push_date_literal(&mut out, us, ty).then_some(out)
}

/// A value as plain text (CSV cells, reports): BOOL `TRUE`/`FALSE`, numbers, TIME and dates as
/// literals, strings as they are.
pub fn value_text(v: &Value, ty: &Type) -> String {
    let mut out = String::new();
    push_value_text(&mut out, v, ty);
    out
}

/// [`value_text`] appended to `out`.
pub fn push_value_text(out: &mut String, v: &Value, ty: &Type) {
    match v {
        Value::Bool(b) => out.push_str(if *b { "TRUE" } else { "FALSE" }),
        Value::Int(i) => {
            if push_date_literal(out, *i, ty) {
            } else if ty.is_duration() {
                write_time(out, *i);
            } else if is_unsigned_64(ty) {
                let _ = write!(out, "{}", *i as u64);
            } else {
                let _ = write!(out, "{i}");
            }
        }
        Value::Real(r) => push_real(out, *r, ty),
        Value::Time(t) => write_time(out, *t),
        Value::Str(s) => out.push_str(s),
    }
}

/// A value as JSON text (traces): BOOL `true`/`false`, numbers as numbers, TIME and dates as
/// literal strings, strings as strings.
pub fn value_json(v: &Value, ty: &Type) -> String {
    let mut out = String::new();
    push_value_json(&mut out, v, ty);
    out
}

/// [`value_json`] appended to `out`.
pub fn push_value_json(out: &mut String, v: &Value, ty: &Type) {
    match v {
        Value::Bool(b) => out.push_str(if *b { "true" } else { "false" }),
        Value::Int(i) => {
            let at = out.len();
            out.push('"');
            if push_date_literal(out, *i, ty) {
                out.push('"');
            } else if ty.is_duration() {
                write_time(out, *i);
                out.push('"');
            } else {
                out.truncate(at);
                if is_unsigned_64(ty) {
                    let _ = write!(out, "{}", *i as u64);
                } else {
                    let _ = write!(out, "{i}");
                }
            }
        }
        // `{:?}` writes `1e20` and `1.5e-7`, both valid JSON numbers.
        Value::Real(r) if r.is_finite() => push_real(out, *r, ty),
        Value::Real(_) => out.push_str("null"),
        Value::Time(t) => {
            out.push('"');
            write_time(out, *t);
            out.push('"');
        }
        Value::Str(s) => push_json_str(out, s),
    }
}

/// The trace object of an event, keys in the contract's order (`kind` first).
pub fn event_json(e: &Event) -> String {
    match e {
        Event::Conflict { step, transitions } => format!(
            "{{\"kind\":\"conflict\",\"step\":{},\"transitions\":{}}}",
            json_string(step),
            json_string_array(transitions)
        ),
        Event::Unsafe { step, transitions } => format!(
            "{{\"kind\":\"unsafe\",\"step\":{},\"transitions\":{}}}",
            json_string(step),
            json_string_array(transitions)
        ),
        Event::Contention { action, steps, qualifiers } => format!(
            "{{\"kind\":\"contention\",\"action\":{},\"steps\":{},\"qualifiers\":{}}}",
            json_string(action),
            json_string_array(steps),
            json_string_array(qualifiers)
        ),
        Event::Error(err) => format!(
            "{{\"kind\":\"error\",\"message\":{},\"line\":{},\"column\":{},\"scan\":{},\"time\":{}}}",
            json_string(&err.message),
            err.line,
            err.column,
            err.scan,
            json_string(&format_time(err.time))
        ),
    }
}

/// One JSON-lines row: `{"scan":k,"time":"T#…","active":[…],"fired":[…],"vars":{…},"events":[…]}`.
pub fn json_row(record: &ScanRecord, vars: &[(String, Type)], values: &[Value]) -> String {
    let mut out = String::new();
    push_json_row(&mut out, record, vars, values);
    out
}

/// [`json_row`] appended to `out` (no allocation when `out` has room and the scan has no
/// events).
pub fn push_json_row(out: &mut String, record: &ScanRecord, vars: &[(String, Type)], values: &[Value]) {
    let _ = write!(out, "{{\"scan\":{},\"time\":\"", record.scan);
    write_time(out, record.time);
    out.push_str("\",\"active\":");
    push_json_str_array(out, &record.active);
    out.push_str(",\"fired\":");
    push_json_str_array(out, &record.fired);
    out.push_str(",\"vars\":{");
    for (i, ((name, ty), v)) in vars.iter().zip(values).enumerate() {
        if i > 0 {
            out.push(',');
        }
        push_json_str(out, name);
        out.push(':');
        push_value_json(out, v, ty);
    }
    out.push_str("},\"events\":[");
    let mut events: Vec<&Event> = record.events.iter().collect();
    events.sort_by_key(|e| e.rank());
    for (i, e) in events.iter().enumerate() {
        if i > 0 {
            out.push(',');
        }
        out.push_str(&event_json(e));
    }
    // Error records of supervision timeouts, after the events of the contract.
    for (i, r) in record.errors.iter().enumerate() {
        if i > 0 || !events.is_empty() {
            out.push(',');
        }
        out.push_str(&r.to_json().to_string());
    }
    out.push_str("]}");
}

// ---------------------------------------------------------------------------------------------
// JSON lines

/// Writes one JSON object per scan, one per line.
pub struct JsonLinesWriter<W: Write> {
    out: W,
    vars: Vec<(String, Type)>,
    /// The row being written, reused from scan to scan.
    line: String,
}

impl<W: Write> JsonLinesWriter<W> {
    pub fn new(out: W) -> Self {
        JsonLinesWriter { out, vars: Vec::new(), line: String::new() }
    }
    pub fn into_inner(self) -> W {
        self.out
    }
}

impl<W: Write> TraceSink for JsonLinesWriter<W> {
    fn header(&mut self, header: &TraceHeader) -> io::Result<()> {
        self.vars = header.vars.clone();
        Ok(())
    }
    fn scan(&mut self, record: &ScanRecord, values: &[Value]) -> io::Result<()> {
        self.line.clear();
        push_json_row(&mut self.line, record, &self.vars, values);
        self.line.push('\n');
        self.out.write_all(self.line.as_bytes())
    }
    fn finish(&mut self) -> io::Result<()> {
        self.out.flush()
    }
}

// ---------------------------------------------------------------------------------------------
// CSV

/// Quotes a CSV field as RFC 4180 says, when it needs it.
pub fn csv_field(s: &str) -> String {
    if s.contains([',', '"', '\r', '\n']) {
        format!("\"{}\"", s.replace('"', "\"\""))
    } else {
        s.to_string()
    }
}

/// Quotes the field `out[from..]` in place when it needs it.
fn quote_csv_tail(out: &mut String, from: usize) {
    if out[from..].contains([',', '"', '\r', '\n']) {
        let quoted = csv_field(&out[from..]);
        out.truncate(from);
        out.push_str(&quoted);
    }
}

/// Writes `scan,time,active,<variables…>`, one row per scan.
pub struct CsvWriter<W: Write> {
    out: W,
    vars: Vec<(String, Type)>,
    /// The row being written, reused from scan to scan.
    line: String,
}

impl<W: Write> CsvWriter<W> {
    pub fn new(out: W) -> Self {
        CsvWriter { out, vars: Vec::new(), line: String::new() }
    }
    pub fn into_inner(self) -> W {
        self.out
    }
}

impl<W: Write> TraceSink for CsvWriter<W> {
    fn header(&mut self, header: &TraceHeader) -> io::Result<()> {
        self.vars = header.vars.clone();
        let mut line = String::from("scan,time,active");
        for (name, _) in &self.vars {
            line.push(',');
            line.push_str(&csv_field(name));
        }
        writeln!(self.out, "{line}")
    }
    fn scan(&mut self, record: &ScanRecord, values: &[Value]) -> io::Result<()> {
        let line = &mut self.line;
        line.clear();
        let _ = write!(line, "{},", record.scan);
        write_time(line, record.time);
        line.push(',');
        let from = line.len();
        for (i, a) in record.active.iter().enumerate() {
            if i > 0 {
                line.push(' ');
            }
            line.push_str(a);
        }
        quote_csv_tail(line, from);
        for ((_, ty), v) in self.vars.iter().zip(values) {
            line.push(',');
            let from = line.len();
            push_value_text(line, v, ty);
            quote_csv_tail(line, from);
        }
        line.push('\n');
        self.out.write_all(line.as_bytes())
    }
    fn finish(&mut self) -> io::Result<()> {
        self.out.flush()
    }
}

// ---------------------------------------------------------------------------------------------
// VCD

#[derive(Debug, Clone, Copy, PartialEq)]
enum SignalKind {
    /// A step flag or BOOL variable.
    Bit,
    /// An integer of the given width (`integer N`).
    Int(u32),
    /// A bit string (`wire N`).
    Bits(u32),
}

#[derive(Debug, Clone)]
struct Signal {
    id: String,
    kind: SignalKind,
    /// Index into the header's variables, or `None` for a step flag.
    var: Option<usize>,
    /// Step name for a step flag.
    step: Option<String>,
}

/// The `n`-th short VCD identifier (`!`, `"`, … `~`, `!!`, …).
fn vcd_id(mut n: usize) -> String {
    let mut id = String::new();
    loop {
        id.push((b'!' + (n % 94) as u8) as char);
        n /= 94;
        if n == 0 {
            break;
        }
        n -= 1;
    }
    id
}

/// The VCD value of an integer of `width` bits (two's complement for negative values).
fn vcd_bits(i: i64, width: u32) -> String {
    if i >= 0 {
        format!("b{i:b}")
    } else {
        let mask = if width >= 64 { u64::MAX } else { (1u64 << width) - 1 };
        format!("b{:b}", (i as u64) & mask)
    }
}

/// Writes a Value Change Dump that GTKWave opens.
pub struct VcdWriter<W: Write> {
    out: W,
    signals: Vec<Signal>,
    last: Vec<Option<String>>,
    period: i64,
    started: bool,
    /// Time of the last timestamp written.
    last_time: i64,
    /// Time of the last scan.
    end: i64,
}

impl<W: Write> VcdWriter<W> {
    pub fn new(out: W) -> Self {
        VcdWriter { out, signals: Vec::new(), last: Vec::new(), period: 0, started: false, last_time: 0, end: 0 }
    }
    pub fn into_inner(self) -> W {
        self.out
    }

    fn value_of(&self, s: &Signal, active: &HashSet<&str>, values: &[Value]) -> Option<String> {
        if let Some(step) = &s.step {
            return Some(if active.contains(step.as_str()) { "1" } else { "0" }.to_string());
        }
        let v = values.get(s.var?)?;
        let i = match v {
            Value::Bool(b) => i64::from(*b),
            Value::Int(i) | Value::Time(i) => *i,
            Value::Real(r) => *r as i64,
            Value::Str(_) => return None,
        };
        Some(match s.kind {
            SignalKind::Bit => if i != 0 { "1" } else { "0" }.to_string(),
            SignalKind::Int(w) | SignalKind::Bits(w) => vcd_bits(i, w),
        })
    }
}

fn vcd_change(value: &str, id: &str) -> String {
    if value.starts_with('b') {
        format!("{value} {id}")
    } else {
        format!("{value}{id}")
    }
}

/// A scope tree of step names (`Rev.OpenKM1` lies in scope `Rev`).
#[derive(Default)]
struct Scope {
    signals: Vec<(String, usize)>,
    children: Vec<(String, Scope)>,
}

impl Scope {
    fn insert(&mut self, path: &[&str], signal: usize) {
        match path {
            [] => {}
            [leaf] => self.signals.push((leaf.to_string(), signal)),
            [head, rest @ ..] => {
                let pos = match self.children.iter().position(|(n, _)| n == head) {
                    Some(p) => p,
                    None => {
                        self.children.push((head.to_string(), Scope::default()));
                        self.children.len() - 1
                    }
                };
                self.children[pos].1.insert(rest, signal);
            }
        }
    }
    fn write(&self, out: &mut String, signals: &[Signal]) {
        for (name, i) in &self.signals {
            let s = &signals[*i];
            let (ty, width) = match s.kind {
                SignalKind::Bit => ("wire", 1),
                SignalKind::Int(w) => ("integer", w),
                SignalKind::Bits(w) => ("wire", w),
            };
            let range =
                if matches!(s.kind, SignalKind::Bits(_)) { format!(" [{}:0]", width - 1) } else { String::new() };
            out.push_str(&format!("$var {ty} {width} {} {name}{range} $end\n", s.id));
        }
        for (name, child) in &self.children {
            out.push_str(&format!("$scope module {name} $end\n"));
            child.write(out, signals);
            out.push_str("$upscope $end\n");
        }
    }
}

impl<W: Write> TraceSink for VcdWriter<W> {
    fn header(&mut self, header: &TraceHeader) -> io::Result<()> {
        self.period = header.period;
        let mut top = Scope::default();
        let mut signals = Vec::new();
        for step in &header.steps {
            let path: Vec<&str> = step.split('.').collect();
            top.insert(&path, signals.len());
            signals.push(Signal {
                id: vcd_id(signals.len()),
                kind: SignalKind::Bit,
                var: None,
                step: Some(step.clone()),
            });
        }
        for (i, (name, ty)) in header.vars.iter().enumerate() {
            let kind = if ty.is_bool() {
                SignalKind::Bit
            } else if ty.is_integer() {
                SignalKind::Int(ty.bit_width().unwrap_or(32))
            } else if ty.is_bit() {
                SignalKind::Bits(ty.bit_width().unwrap_or(32))
            } else {
                continue;
            };
            top.insert(&[name.as_str()], signals.len());
            signals.push(Signal { id: vcd_id(signals.len()), kind, var: Some(i), step: None });
        }
        let mut text = String::new();
        text.push_str(&format!("$version sfc {} $end\n", env!("CARGO_PKG_VERSION")));
        text.push_str(&format!("$comment scan period {} $end\n", format_time(header.period)));
        text.push_str("$timescale 1 us $end\n");
        text.push_str(&format!("$scope module {} $end\n", header.pou));
        top.write(&mut text, &signals);
        text.push_str("$upscope $end\n$enddefinitions $end\n");
        self.last = vec![None; signals.len()];
        self.signals = signals;
        self.out.write_all(text.as_bytes())
    }

    fn scan(&mut self, record: &ScanRecord, values: &[Value]) -> io::Result<()> {
        let active: HashSet<&str> = record.active.iter().map(String::as_str).collect();
        let mut changes = Vec::new();
        for (i, s) in self.signals.iter().enumerate() {
            let Some(v) = self.value_of(s, &active, values) else { continue };
            if self.last[i].as_deref() != Some(v.as_str()) {
                changes.push(vcd_change(&v, &s.id));
                self.last[i] = Some(v);
            }
        }
        self.end = record.time;
        let mut text = String::new();
        if !self.started {
            self.started = true;
            self.last_time = record.time;
            text.push_str(&format!("#{}\n$dumpvars\n", record.time));
            for c in &changes {
                text.push_str(c);
                text.push('\n');
            }
            text.push_str("$end\n");
        } else if !changes.is_empty() {
            // Times ascend: a scan never has an earlier time than the one before.
            if record.time > self.last_time {
                self.last_time = record.time;
                text.push_str(&format!("#{}\n", record.time));
            }
            for c in &changes {
                text.push_str(c);
                text.push('\n');
            }
        }
        self.out.write_all(text.as_bytes())
    }

    fn finish(&mut self) -> io::Result<()> {
        let end = self.end.saturating_add(self.period);
        if self.started && end > self.last_time {
            writeln!(self.out, "#{end}")?;
        }
        self.out.flush()
    }
}

/// A sink that feeds several sinks (a trace file and, say, a live view).
pub struct Tee<'a> {
    pub sinks: Vec<&'a mut dyn TraceSink>,
}

impl TraceSink for Tee<'_> {
    fn header(&mut self, header: &TraceHeader) -> io::Result<()> {
        self.sinks.iter_mut().try_for_each(|s| s.header(header))
    }
    fn scan(&mut self, record: &ScanRecord, values: &[Value]) -> io::Result<()> {
        self.sinks.iter_mut().try_for_each(|s| s.scan(record, values))
    }
    fn finish(&mut self) -> io::Result<()> {
        self.sinks.iter_mut().try_for_each(|s| s.finish())
    }
}

/// Keeps the rows in memory (tests, tools that post-process a run).
#[derive(Debug, Default, Clone)]
pub struct Recorder {
    pub header: Option<TraceHeader>,
    pub rows: Vec<(ScanRecord, Vec<Value>)>,
}

impl TraceSink for Recorder {
    fn header(&mut self, header: &TraceHeader) -> io::Result<()> {
        self.header = Some(header.clone());
        Ok(())
    }
    fn scan(&mut self, record: &ScanRecord, values: &[Value]) -> io::Result<()> {
        self.rows.push((record.clone(), values.to_vec()));
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::RuntimeError;

    fn header() -> TraceHeader {
        TraceHeader {
            pou: "Blinker".into(),
            steps: vec!["S1".into(), "S2".into(), "Sub.S9".into()],
            vars: vec![
                ("Start".into(), Type::Bool),
                ("Count".into(), Type::Int),
                ("Speed".into(), Type::Real),
                ("Wait".into(), Type::Time),
                ("Text".into(), Type::String { len: None }),
                ("Mask".into(), Type::Byte),
                ("Day".into(), Type::Date),
            ],
            period: 100_000,
        }
    }

    fn row(scan: u64, active: &[&str], start: bool, count: i64) -> (ScanRecord, Vec<Value>) {
        let rec = ScanRecord {
            scan,
            time: scan as i64 * 100_000,
            active: active.iter().map(|s| s.to_string()).collect(),
            fired: if scan == 1 { vec!["T1".into()] } else { vec![] },
            events: vec![],
            errors: vec![],
        };
        let values = vec![
            Value::Bool(start),
            Value::Int(count),
            Value::Real(f64::from(0.1f32)),
            Value::Time(1_500_000),
            Value::Str("a, \"b\"".into()),
            Value::Int(5),
            Value::Int(19_783 * DAY_US),
        ];
        (rec, values)
    }

    fn run(format: TraceFormat, rows: &[(ScanRecord, Vec<Value>)]) -> String {
        let mut buf = Vec::new();
        {
            let mut w = format.writer(&mut buf);
            w.header(&header()).unwrap();
            for (r, v) in rows {
                w.scan(r, v).unwrap();
            }
            w.finish().unwrap();
        }
        String::from_utf8(buf).unwrap()
    }

    #[test]
    fn json_strings_are_escaped_as_serde_json_escapes_them() {
        let mut all: String = (0u8..128).map(char::from).collect();
        all.push_str("Grüße ✓ \u{7f} \u{2028}");
        let mut out = String::new();
        push_json_str(&mut out, &all);
        assert_eq!(out, serde_json::to_string(&all).unwrap());
        for t in [0, 1, -1, 1_500_000, -200_000, 90_061_001_001, i64::MIN, i64::MAX] {
            let mut w = String::new();
            write_time(&mut w, t);
            assert_eq!(w, format_time(t));
        }
    }

    #[test]
    fn formats_by_extension() {
        assert_eq!(TraceFormat::from_path(Path::new("-")), Some(TraceFormat::JsonLines));
        assert_eq!(TraceFormat::from_path(Path::new("a/b.jsonl")), Some(TraceFormat::JsonLines));
        assert_eq!(TraceFormat::from_path(Path::new("b.CSV")), Some(TraceFormat::Csv));
        assert_eq!(TraceFormat::from_path(Path::new("b.vcd")), Some(TraceFormat::Vcd));
        assert_eq!(TraceFormat::from_path(Path::new("b.txt")), None);
        assert_eq!(TraceFormat::from_path(Path::new("b")), None);
    }

    #[test]
    fn json_lines_keys_in_order() {
        let text = run(TraceFormat::JsonLines, &[row(0, &["S1"], false, 0), row(1, &["S2"], true, -3)]);
        let lines: Vec<&str> = text.lines().collect();
        assert_eq!(lines.len(), 2);
        assert_eq!(
            lines[1],
            r#"{"scan":1,"time":"T#100ms","active":["S2"],"fired":["T1"],"vars":{"Start":true,"Count":-3,"Speed":0.1,"Wait":"T#1s500ms","Text":"a, \"b\"","Mask":5,"Day":"D#2024-03-01"},"events":[]}"#
        );
        for l in lines {
            let v: serde_json::Value = serde_json::from_str(l).unwrap();
            assert!(v.is_object());
        }
    }

    #[test]
    fn json_events_in_rank_order_with_kind_first() {
        let (mut rec, values) = row(3, &["S1", "S2"], true, 1);
        rec.events = vec![
            Event::Error(RuntimeError {
                message: "division by zero".into(),
                span: Default::default(),
                line: 12,
                column: 8,
                scan: 3,
                time: 300_000,
            }),
            Event::Conflict { step: "S1".into(), transitions: vec!["T1".into(), "T2".into()] },
            Event::Contention {
                action: "A".into(),
                steps: vec!["S1".into(), "S2".into()],
                qualifiers: vec!["L".into(), "D".into()],
            },
            Event::Unsafe { step: "S2".into(), transitions: vec!["T3".into()] },
        ];
        let line = json_row(&rec, &header().vars, &values);
        let events = &line[line.find("\"events\":").unwrap()..];
        assert_eq!(
            events,
            r#""events":[{"kind":"conflict","step":"S1","transitions":["T1","T2"]},{"kind":"unsafe","step":"S2","transitions":["T3"]},{"kind":"contention","action":"A","steps":["S1","S2"],"qualifiers":["L","D"]},{"kind":"error","message":"division by zero","line":12,"column":8,"scan":3,"time":"T#300ms"}]}"#
        );
        // The same content as `Event::to_json`.
        let parsed: serde_json::Value = serde_json::from_str(&line).unwrap();
        let mut sorted = rec.events.clone();
        sorted.sort_by_key(|e| e.rank());
        for (i, e) in sorted.iter().enumerate() {
            assert_eq!(parsed["events"][i], e.to_json());
        }
    }

    #[test]
    fn json_numbers_and_special_values() {
        assert_eq!(value_json(&Value::Real(f64::NAN), &Type::LReal), "null");
        assert_eq!(value_json(&Value::Real(1e20), &Type::LReal), "1e20");
        assert_eq!(value_json(&Value::Real(2.0), &Type::Real), "2.0");
        assert_eq!(value_json(&Value::Int(-1), &Type::ULInt), "18446744073709551615");
        assert_eq!(value_json(&Value::Int(45_000_500_000), &Type::TimeOfDay), "\"TOD#12:30:00.5\"");
        assert_eq!(
            value_json(&Value::Int(19_783 * DAY_US + 3_600_000_000), &Type::DateAndTime),
            "\"DT#2024-03-01-01:00:00\""
        );
        assert_eq!(value_json(&Value::Int(-DAY_US), &Type::Date), "\"D#1969-12-31\"");
        for s in ["1e20", "2.0", "1.5e-7", "-0.0"] {
            assert!(serde_json::from_str::<serde_json::Value>(s).unwrap().is_number());
        }
    }

    #[test]
    fn csv_header_rows_and_quoting() {
        let text = run(TraceFormat::Csv, &[row(0, &["S1"], false, 0), row(1, &["S1", "S2"], true, 7)]);
        let lines: Vec<&str> = text.lines().collect();
        assert_eq!(lines[0], "scan,time,active,Start,Count,Speed,Wait,Text,Mask,Day");
        assert_eq!(lines[1], "0,T#0s,S1,FALSE,0,0.1,T#1s500ms,\"a, \"\"b\"\"\",5,D#2024-03-01");
        assert_eq!(lines[2], "1,T#100ms,S1 S2,TRUE,7,0.1,T#1s500ms,\"a, \"\"b\"\"\",5,D#2024-03-01");
        assert_eq!(csv_field("plain"), "plain");
        assert_eq!(csv_field("a\nb"), "\"a\nb\"");
    }

    #[test]
    fn vcd_header_and_changes() {
        let text = run(
            TraceFormat::Vcd,
            &[
                row(0, &["S1"], false, 0),
                row(1, &["S2"], true, -3),
                row(2, &["S2"], true, -3),
                row(3, &["S2", "Sub.S9"], true, 4),
            ],
        );
        let expected_head = "$version sfc ";
        assert!(text.starts_with(expected_head), "{text}");
        assert!(text.contains("$timescale 1 us $end\n"));
        assert!(text.contains("$scope module Blinker $end\n"));
        assert!(text.contains("$var wire 1 ! S1 $end\n"), "{text}");
        assert!(text.contains("$var wire 1 \" S2 $end\n"));
        assert!(text.contains("$scope module Sub $end\n$var wire 1 # S9 $end\n$upscope $end\n"), "{text}");
        assert!(text.contains("$var wire 1 $ Start $end\n"));
        assert!(text.contains("$var integer 16 % Count $end\n"));
        assert!(text.contains("$var wire 8 & Mask [7:0] $end\n"));
        // Only BOOL, integer and bit-string variables get a wire.
        assert_eq!(text.matches("$var ").count(), 6, "{text}");
        assert!(!text.contains(" Speed "));
        assert!(
            text.contains("$upscope $end\n$enddefinitions $end\n#0\n$dumpvars\n1!\n0\"\n0#\n0$\nb0 %\nb101 &\n$end\n"),
            "{text}"
        );
        // Scan 1: S1 falls, S2 rises, Start rises, Count goes negative (two's complement).
        assert!(text.contains("#100000\n0!\n1\"\n1$\nb1111111111111101 %\n"), "{text}");
        // Scan 2 changes nothing: no timestamp.
        assert!(!text.contains("#200000"));
        assert!(text.contains("#300000\n1#\nb100 %\n"), "{text}");
        // The end of the last scan's period closes the dump.
        assert!(text.ends_with("#400000\n"), "{text}");
        // Timestamps ascend.
        let times: Vec<i64> = text.lines().filter_map(|l| l.strip_prefix('#')).map(|t| t.parse().unwrap()).collect();
        assert!(times.windows(2).all(|w| w[0] < w[1]), "{times:?}");
    }

    #[test]
    fn vcd_ids_are_distinct_printable() {
        let ids: HashSet<String> = (0..10_000).map(vcd_id).collect();
        assert_eq!(ids.len(), 10_000);
        assert!(ids.iter().all(|id| id.bytes().all(|b| (b'!'..=b'~').contains(&b))));
        assert_eq!(vcd_id(0), "!");
        assert_eq!(vcd_id(93), "~");
        assert_eq!(vcd_id(94), "!!");
    }

    #[test]
    fn civil_dates() {
        assert_eq!(civil_from_days(0), (1970, 1, 1));
        assert_eq!(civil_from_days(19_783), (2024, 3, 1));
        assert_eq!(civil_from_days(-1), (1969, 12, 31));
        assert_eq!(civil_from_days(11_016), (2000, 2, 29));
    }
}
