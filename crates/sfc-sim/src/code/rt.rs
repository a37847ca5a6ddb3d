//! Runtime building blocks of compiled code: closure types, typed views of slots, integer
//! widths and wrapping, faults.

use super::{Ctx, Fault};
use crate::value::Value;
use sfc_diagnostics::Span;
use sfc_st::Type;
use std::sync::Arc;

/// Results of compiled code; the fault is boxed so that results travel in registers.
pub(crate) type R<T> = Result<T, Box<Fault>>;
/// A compiled computation of a `T` in a frame.
pub(crate) type Fx<T> = Box<dyn Fn(&mut Ctx<'_>, usize) -> R<T> + Send + Sync>;
pub(crate) type BoolFn = Box<dyn Fn(&mut Ctx<'_>, usize) -> R<bool> + Send + Sync>;
pub(crate) type IntFn = Box<dyn Fn(&mut Ctx<'_>, usize) -> R<i64> + Send + Sync>;
pub(crate) type RealFn = Box<dyn Fn(&mut Ctx<'_>, usize) -> R<f64> + Send + Sync>;
pub(crate) type StrFn = Box<dyn Fn(&mut Ctx<'_>, usize) -> R<Arc<str>> + Send + Sync>;
pub(crate) type AggFn = Box<dyn Fn(&mut Ctx<'_>, usize) -> R<Vec<Value>> + Send + Sync>;
pub(crate) type ValFn = Box<dyn Fn(&mut Ctx<'_>, usize) -> R<Value> + Send + Sync>;
/// Computes an absolute slot (array elements with a computed index).
pub(crate) type LocFn = Arc<dyn Fn(&mut Ctx<'_>, usize) -> R<usize> + Send + Sync>;
pub(crate) type StmtFn = Box<dyn Fn(&mut Ctx<'_>, usize) -> R<Flow> + Send + Sync>;
/// Writes a value (already of the target's type) to a place of the caller's frame.
pub(crate) type SinkFn = Box<dyn Fn(&mut Ctx<'_>, usize, Value) -> R<()> + Send + Sync>;
pub(crate) type InitFn = Box<dyn Fn(&mut Ctx<'_>, usize) -> R<()> + Send + Sync>;

/// How a statement list ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Flow {
    Next,
    Exit,
    Return,
}

/// Deeper nesting of user function calls stops the run.
pub(crate) const MAX_CALL_DEPTH: u32 = 200;

pub(crate) fn fault(message: impl Into<String>, span: Span) -> Box<Fault> {
    Box::new(Fault { message: message.into(), span })
}

#[inline]
pub(crate) fn int_of(v: &Value) -> i64 {
    match v {
        Value::Int(i) | Value::Time(i) => *i,
        Value::Bool(b) => i64::from(*b),
        Value::Real(r) => *r as i64,
        Value::Str(_) => 0,
    }
}

#[inline]
pub(crate) fn bool_of(v: &Value) -> bool {
    match v {
        Value::Bool(b) => *b,
        Value::Int(i) | Value::Time(i) => *i != 0,
        Value::Real(r) => *r != 0.0,
        Value::Str(_) => false,
    }
}

#[inline]
pub(crate) fn real_of(v: &Value) -> f64 {
    match v {
        Value::Real(r) => *r,
        Value::Int(i) | Value::Time(i) => *i as f64,
        Value::Bool(b) => f64::from(u8::from(*b)),
        Value::Str(_) => 0.0,
    }
}

#[inline]
pub(crate) fn str_of(v: &Value) -> Arc<str> {
    match v {
        Value::Str(s) => s.clone(),
        _ => Arc::from(""),
    }
}

/// REAL arithmetic: every result is rounded to single precision.
#[inline]
pub(crate) fn r32(x: f64) -> f64 {
    x as f32 as f64
}

/// How a value of an integer-like type is held in an `i64`: its width and signedness.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum W {
    I8,
    I16,
    I32,
    I64,
    U8,
    U16,
    U32,
    /// ULINT, LWORD: the bits of a `u64`.
    U64,
}

impl W {
    /// The representation of an integer-like type (durations, dates and enumerations are 64-bit
    /// signed).
    pub(crate) fn of(ty: &Type) -> W {
        match ty.base() {
            Type::SInt => W::I8,
            Type::Int => W::I16,
            Type::DInt => W::I32,
            Type::USInt | Type::Byte => W::U8,
            Type::UInt | Type::Word => W::U16,
            Type::UDInt | Type::DWord => W::U32,
            Type::ULInt | Type::LWord => W::U64,
            Type::Enum { base: Some(b), .. } => W::of(b),
            _ => W::I64,
        }
    }

    /// Two's-complement wrap into the width.
    #[inline]
    pub(crate) fn wrap(self, v: i64) -> i64 {
        match self {
            W::I8 => i64::from(v as i8),
            W::I16 => i64::from(v as i16),
            W::I32 => i64::from(v as i32),
            W::I64 | W::U64 => v,
            W::U8 => i64::from(v as u8),
            W::U16 => i64::from(v as u16),
            W::U32 => i64::from(v as u32),
        }
    }

    /// Wraps a wide integer into the width (low bits).
    pub(crate) fn wrap128(self, v: i128) -> i64 {
        self.wrap(v as i64)
    }

    pub(crate) fn bits(self) -> u32 {
        match self {
            W::I8 | W::U8 => 8,
            W::I16 | W::U16 => 16,
            W::I32 | W::U32 => 32,
            W::I64 | W::U64 => 64,
        }
    }

    pub(crate) fn unsigned(self) -> bool {
        matches!(self, W::U8 | W::U16 | W::U32 | W::U64)
    }

    /// The value as a mathematical integer.
    #[inline]
    pub(crate) fn wide(self, v: i64) -> i128 {
        if self == W::U64 {
            i128::from(v as u64)
        } else {
            i128::from(v)
        }
    }

    pub(crate) fn to_f64(self, v: i64) -> f64 {
        if self == W::U64 {
            v as u64 as f64
        } else {
            v as f64
        }
    }

    pub(crate) fn min(self) -> i128 {
        if self.unsigned() {
            0
        } else {
            -(1i128 << (self.bits() - 1))
        }
    }

    pub(crate) fn max(self) -> i128 {
        if self.unsigned() {
            (1i128 << self.bits()) - 1
        } else {
            (1i128 << (self.bits() - 1)) - 1
        }
    }
}

/// The shape of a value at run time.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Kind {
    Bool,
    /// Integers, bit strings but BOOL, durations, dates, enumerations.
    Int,
    Real,
    Str,
    /// Arrays, structures, function block instances: runs of slots.
    Agg,
}

pub(crate) fn kind_of(ty: &Type) -> Kind {
    match ty.base() {
        Type::Bool => Kind::Bool,
        Type::Real | Type::LReal => Kind::Real,
        Type::String { .. } | Type::WString { .. } => Kind::Str,
        Type::Array { .. } | Type::Struct { .. } | Type::FunctionBlock(_) | Type::Error => Kind::Agg,
        _ => Kind::Int,
    }
}

/// The slot value of an integer-like type.
#[inline]
pub(crate) fn int_value(ty_is_time: bool, v: i64) -> Value {
    if ty_is_time {
        Value::Time(v)
    } else {
        Value::Int(v)
    }
}

/// The default initial value of an elementary type (0, FALSE, T#0s, '', the first enumerated
/// value, the low bound of a subrange).
pub(crate) fn default_value(ty: &Type) -> Value {
    match ty {
        Type::Subrange { lo, .. } => Value::Int(*lo),
        Type::Enum { values, .. } => Value::Int(values.first().map(|(_, v)| *v).unwrap_or(0)),
        t => match kind_of(t) {
            Kind::Bool => Value::Bool(false),
            Kind::Real => Value::Real(0.0),
            Kind::Str => Value::Str(Arc::from("")),
            Kind::Int if t.is_duration() => Value::Time(0),
            _ => Value::Int(0),
        },
    }
}

/// A value converted to the representation of `ty` (used when storing values computed
/// generically, e.g. by IL or copied parameters).
pub(crate) fn to_slot(ty: &Type, v: Value) -> Value {
    match kind_of(ty) {
        Kind::Bool => Value::Bool(bool_of(&v)),
        Kind::Int => int_value(ty.is_duration(), int_of(&v)),
        Kind::Real => Value::Real(real_of(&v)),
        Kind::Str => Value::Str(str_of(&v)),
        Kind::Agg => v,
    }
}

/// The number of characters of a string type's declared length, if any.
pub(crate) fn string_len(ty: &Type) -> Option<u32> {
    match ty.base() {
        Type::String { len } | Type::WString { len } => *len,
        _ => None,
    }
}

/// Truncates a string to at most `n` characters.
pub(crate) fn truncate(s: Arc<str>, n: u32) -> Arc<str> {
    let n = n as usize;
    match s.char_indices().nth(n) {
        Some((i, _)) => Arc::from(&s[..i]),
        None => s,
    }
}

/// One microsecond-based day.
pub(crate) const DAY_US: i64 = 86_400_000_000;

/// The canonical text of a value of type `ty` (for STRING conversions and test output).
pub(crate) fn format_value(ty: &Type, v: &Value) -> String {
    match ty.base() {
        Type::Bool => if bool_of(v) { "TRUE" } else { "FALSE" }.to_string(),
        Type::Real => format_real(real_of(v), true),
        Type::LReal => format_real(real_of(v), false),
        Type::String { .. } | Type::WString { .. } => str_of(v).to_string(),
        Type::Time | Type::LTime => {
            let t = crate::value::format_time(int_of(v));
            if ty.base() == &Type::LTime {
                format!("L{t}")
            } else {
                t
            }
        }
        Type::Date => format!("D#{}", format_date(int_of(v).div_euclid(DAY_US))),
        Type::TimeOfDay => format!("TOD#{}", format_tod(int_of(v).rem_euclid(DAY_US))),
        Type::DateAndTime => {
            let us = int_of(v);
            format!("DT#{}-{}", format_date(us.div_euclid(DAY_US)), format_tod(us.rem_euclid(DAY_US)))
        }
        Type::Enum { values, .. } => {
            let n = int_of(v);
            values.iter().find(|(_, o)| *o == n).map(|(s, _)| s.clone()).unwrap_or_else(|| n.to_string())
        }
        t => {
            let w = W::of(t);
            w.wide(int_of(v)).to_string()
        }
    }
}

/// Shortest text that reads back as the same REAL (or LREAL).
pub(crate) fn format_real(x: f64, single: bool) -> String {
    let s = if single { format!("{}", x as f32) } else { format!("{x}") };
    if x.is_finite() && !s.contains(['.', 'e', 'E']) {
        format!("{s}.0")
    } else {
        s
    }
}

/// Civil date of a day number since 1970-01-01, as `YYYY-MM-DD`.
pub(crate) fn format_date(days: i64) -> String {
    let z = days + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z - era * 146_097;
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
    let y = yoe + era * 400;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let d = doy - (153 * mp + 2) / 5 + 1;
    let m = if mp < 10 { mp + 3 } else { mp - 9 };
    let y = if m <= 2 { y + 1 } else { y };
    format!("{y:04}-{m:02}-{d:02}")
}

/// `HH:MM:SS` with a fraction when there is one.
pub(crate) fn format_tod(us: i64) -> String {
    let s = us / 1_000_000;
    let frac = us % 1_000_000;
    let base = format!("{:02}:{:02}:{:02}", s / 3600, (s / 60) % 60, s % 60);
    if frac == 0 {
        base
    } else {
        let f = format!("{frac:06}");
        format!("{base}.{}", f.trim_end_matches('0'))
    }
}

thread_local! {
    /// Nesting of user function calls on this thread (guards runaway recursion).
    pub(crate) static CALL_DEPTH: std::cell::Cell<u32> = const { std::cell::Cell::new(0) };
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn widths_wrap() {
        assert_eq!(W::I8.wrap(128), -128);
        assert_eq!(W::U8.wrap(-1), 255);
        assert_eq!(W::U16.wrap(65536), 0);
        assert_eq!(W::I32.wrap(i64::from(i32::MAX) + 1), i64::from(i32::MIN));
        assert_eq!(W::U64.wide(-1), i128::from(u64::MAX));
        assert_eq!(W::I16.min(), -32768);
        assert_eq!(W::U32.max(), 4_294_967_295);
    }

    #[test]
    fn dates_format() {
        assert_eq!(format_date(0), "1970-01-01");
        assert_eq!(format_date(sfc_syntax::literal::days_from_civil(2024, 2, 29)), "2024-02-29");
        assert_eq!(format_tod(38_543_780_000), "10:42:23.78");
        assert_eq!(format_real(1.0, true), "1.0");
        assert_eq!(format_real(0.1, true), "0.1");
    }
}
