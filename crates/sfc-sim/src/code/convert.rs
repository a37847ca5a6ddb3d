//! Implicit widening on assignment and the explicit type conversions (`*_TO_*`, `TO_*`,
//! `TRUNC`).
//!
//! Choices (documented in `tests/st/README.md`):
//! * REAL → integer rounds to nearest, ties away from zero (CODESYS); `TRUNC` truncates toward
//!   zero. A NaN or infinite value faults. The result wraps into the target width, as every
//!   integer narrowing does (`DINT_TO_SINT(200)` is `-56`).
//! * TIME ↔ integers and REAL count milliseconds (`TIME_TO_DINT(T#1s)` is `1000`), LTIME
//!   nanoseconds, TIME_OF_DAY milliseconds since midnight, DATE and DATE_AND_TIME seconds since
//!   1970-01-01 (all as CODESYS).
//! * To STRING: decimal integers, the shortest REAL text (`1.5`), canonical TIME (`T#1s500ms`),
//!   `D#…`, `TOD#…`, `DT#…`, `TRUE`/`FALSE`. From STRING: the same texts (also based integers
//!   `16#FF`); text that does not parse gives 0 (or FALSE, T#0s).

use super::place::check_subrange;
use super::rt::*;
use super::texpr::{CExpr, TExpr};
use super::unit::C;
use sfc_diagnostics::{Diagnostic, Span};
use sfc_st::Type;
use std::sync::Arc;

/// How REAL becomes an integer.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Rounding {
    Nearest,
    Trunc,
}

/// The unit an integer-like type counts in when converted to or from plain numbers.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum IU {
    Plain(W),
    TimeMs,
    LTimeNs,
    DateS,
    DtS,
    TodMs,
}

fn unit_of(ty: &Type) -> IU {
    match ty.base() {
        Type::Time => IU::TimeMs,
        Type::LTime => IU::LTimeNs,
        Type::Date => IU::DateS,
        Type::DateAndTime => IU::DtS,
        Type::TimeOfDay => IU::TodMs,
        t => IU::Plain(W::of(t)),
    }
}

fn to_plain(u: IU, v: i64) -> i128 {
    match u {
        IU::Plain(w) => w.wide(v),
        IU::TimeMs | IU::TodMs => i128::from(v / 1000),
        IU::LTimeNs => i128::from(v) * 1000,
        IU::DateS | IU::DtS => i128::from(v.div_euclid(1_000_000)),
    }
}

fn from_plain(u: IU, p: i128) -> i64 {
    match u {
        IU::Plain(w) => w.wrap128(p),
        IU::TimeMs => p.wrapping_mul(1000) as i64,
        IU::LTimeNs => (p / 1000) as i64,
        IU::DateS => {
            let us = p.wrapping_mul(1_000_000) as i64;
            us - us.rem_euclid(DAY_US)
        }
        IU::DtS => p.wrapping_mul(1_000_000) as i64,
        IU::TodMs => (p.wrapping_mul(1000) as i64).rem_euclid(DAY_US),
    }
}

fn to_real(u: IU, v: i64) -> f64 {
    match u {
        IU::Plain(w) => w.to_f64(v),
        IU::TimeMs | IU::TodMs => v as f64 / 1000.0,
        IU::LTimeNs => v as f64 * 1000.0,
        IU::DateS | IU::DtS => v as f64 / 1e6,
    }
}

fn from_real(u: IU, r: f64, mode: Rounding) -> Option<i64> {
    let scaled = match u {
        IU::Plain(_) => r,
        IU::TimeMs | IU::TodMs => r * 1000.0,
        IU::LTimeNs => r / 1000.0,
        IU::DateS | IU::DtS => r * 1e6,
    };
    if !scaled.is_finite() {
        return None;
    }
    let n = match mode {
        Rounding::Nearest => scaled.round(),
        Rounding::Trunc => scaled.trunc(),
    };
    Some(match u {
        IU::Plain(w) => w.wrap128(n as i128),
        IU::DateS => {
            let us = n as i64;
            us - us.rem_euclid(DAY_US)
        }
        IU::TodMs => (n as i64).rem_euclid(DAY_US),
        _ => n as i64,
    })
}

/// Converts between two integer-like types.
fn int_to_int(from: &Type, to: &Type) -> Option<Box<dyn Fn(i64) -> i64 + Send + Sync>> {
    let (f, t) = (from.base(), to.base());
    let timey = |x: &Type| x.is_duration() || x.is_date();
    if timey(f) && timey(t) {
        return match (f, t) {
            (a, b) if a.is_duration() && b.is_duration() => None,
            (Type::DateAndTime, Type::Date) => Some(Box::new(|v| v - v.rem_euclid(DAY_US))),
            (Type::DateAndTime, Type::TimeOfDay) => Some(Box::new(|v| v.rem_euclid(DAY_US))),
            _ => None,
        };
    }
    let (uf, ut) = (unit_of(f), unit_of(t));
    match (uf, ut) {
        (IU::Plain(_), IU::Plain(wt)) => {
            if W::of(f) == wt || matches!(t, Type::Enum { base: None, .. }) {
                None
            } else {
                Some(Box::new(move |v| wt.wrap(v)))
            }
        }
        _ => Some(Box::new(move |v| from_plain(ut, to_plain(uf, v)))),
    }
}

fn conversion_error(span: Span, from: &Type, to: &Type) -> Box<Diagnostic> {
    Box::new(Diagnostic::error("SFC0320", span, format!("cannot be simulated: no conversion from `{from}` to `{to}`")))
}

/// The explicit conversion of `v` to `to` (`<from>_TO_<to>`, `TRUNC`).
pub(crate) fn convert(v: TExpr, to: &Type, span: Span, mode: Rounding) -> C<TExpr> {
    if super::matiec_time() && v.ty.is_duration() != to.is_duration() && (v.kind() == Kind::Int || to.is_duration()) {
        // MatIEC's packed timespecs: convert through microseconds.
        use crate::timespec::Timespec as Ts;
        let v = if v.ty.is_duration() { map_int(v, |x| Ts::unpack(x).to_us()) } else { v };
        let out = convert_us(v, to, span, mode)?;
        return Ok(if to.is_duration() { map_int(out, |x| Ts::from_us(x).pack()) } else { out });
    }
    convert_us(v, to, span, mode)
}

fn map_int(v: TExpr, g: fn(i64) -> i64) -> TExpr {
    let (ty, constant) = (v.ty.clone(), v.constant);
    let f = v.int();
    TExpr::new(CExpr::Int(Box::new(move |c, b| Ok(g(f(c, b)?)))), ty, constant).fold()
}

fn convert_us(v: TExpr, to: &Type, span: Span, mode: Rounding) -> C<TExpr> {
    let from = v.ty.clone();
    let constant = v.constant;
    let out = to.clone();
    let tk = kind_of(to);
    let fk = v.kind();
    let e = match (fk, tk) {
        (Kind::Bool, Kind::Bool) | (Kind::Str, Kind::Str) | (Kind::Agg, Kind::Agg) => v.e,
        (Kind::Real, Kind::Real) => {
            let f = v.real();
            if to.base() == &Type::Real && from.base() != &Type::Real {
                CExpr::Real(Box::new(move |c, b| Ok(r32(f(c, b)?))))
            } else {
                CExpr::Real(f)
            }
        }
        (Kind::Int, Kind::Int) => match int_to_int(&from, to) {
            None => v.e,
            Some(g) => {
                let f = v.int();
                CExpr::Int(Box::new(move |c, b| Ok(g(f(c, b)?))))
            }
        },
        (Kind::Bool, Kind::Int) => {
            let f = v.bool();
            let ut = unit_of(to);
            CExpr::Int(Box::new(move |c, b| Ok(from_plain(ut, i128::from(f(c, b)?)))))
        }
        (Kind::Int, Kind::Bool) => {
            let f = v.int();
            CExpr::Bool(Box::new(move |c, b| Ok(f(c, b)? != 0)))
        }
        (Kind::Bool, Kind::Real) => {
            let f = v.bool();
            CExpr::Real(Box::new(move |c, b| Ok(if f(c, b)? { 1.0 } else { 0.0 })))
        }
        (Kind::Real, Kind::Bool) => {
            let f = v.real();
            CExpr::Bool(Box::new(move |c, b| Ok(f(c, b)? != 0.0)))
        }
        (Kind::Int, Kind::Real) => {
            let uf = unit_of(&from);
            let single = to.base() == &Type::Real;
            let f = v.int();
            CExpr::Real(Box::new(move |c, b| {
                let x = to_real(uf, f(c, b)?);
                Ok(if single { r32(x) } else { x })
            }))
        }
        (Kind::Real, Kind::Int) => {
            let ut = unit_of(to);
            let f = v.real();
            let name = format!("{from}_TO_{to}");
            CExpr::Int(Box::new(move |c, b| {
                let x = f(c, b)?;
                from_real(ut, x, mode).ok_or_else(|| fault(format!("{name}: {x} has no integer value"), span))
            }))
        }
        (_, Kind::Str) => {
            let f = v.value();
            let ft = from.clone();
            CExpr::Str(Box::new(move |c, b| Ok(Arc::from(format_value(&ft, &f(c, b)?)))))
        }
        (Kind::Str, _) => {
            let f = v.str();
            let tt = to.clone();
            match tk {
                Kind::Bool => CExpr::Bool(Box::new(move |c, b| Ok(parse_bool(&f(c, b)?)))),
                Kind::Int => CExpr::Int(Box::new(move |c, b| Ok(parse_int(&tt, &f(c, b)?)))),
                Kind::Real => CExpr::Real(Box::new(move |c, b| Ok(parse_real(&tt, &f(c, b)?)))),
                _ => return Err(conversion_error(span, &from, to)),
            }
        }
        _ => return Err(conversion_error(span, &from, to)),
    };
    Ok(TExpr::new(e, out, constant).fold())
}

/// Implicit conversion of a value to the type of the place it goes to (assignment, argument):
/// widening, string truncation, subrange checks.
pub(crate) fn coerce(v: TExpr, to: &Type, span: Span) -> C<TExpr> {
    if to.is_error() {
        return Ok(v);
    }
    if kind_of(to) == Kind::Str && v.kind() == Kind::Str {
        if let Some(n) = string_len(to) {
            if string_len(&v.ty).is_none_or(|m| m > n) {
                let c = v.constant;
                let f = v.str();
                let e = CExpr::Str(Box::new(move |x, b| Ok(truncate(f(x, b)?, n))));
                return Ok(TExpr::new(e, to.clone(), c).fold());
            }
        }
        return Ok(TExpr { ty: to.clone(), ..v });
    }
    let same_base = v.ty.base() == to.base();
    let mut out = if same_base || (v.kind() == Kind::Agg && kind_of(to) == Kind::Agg) {
        let mut v = v;
        v.ty = if matches!(to, Type::Subrange { .. }) { v.ty } else { to.clone() };
        v
    } else if let (Type::Enum { .. }, Kind::Int) = (to, v.kind()) {
        TExpr { ty: to.clone(), ..v }
    } else {
        convert(v, to, span, Rounding::Nearest)?
    };
    if let Type::Subrange { lo, hi, .. } = to {
        if out.ty != *to {
            out = check_subrange(out, *lo, *hi, span);
            out.ty = to.clone();
        }
    }
    Ok(out)
}

fn parse_bool(s: &str) -> bool {
    let t = s.trim();
    if t.eq_ignore_ascii_case("TRUE") {
        return true;
    }
    if t.eq_ignore_ascii_case("FALSE") {
        return false;
    }
    parse_number(t).is_some_and(|x| x != 0.0)
}

fn parse_number(t: &str) -> Option<f64> {
    let (neg, body) = match t.strip_prefix('-') {
        Some(r) => (true, r),
        None => (false, t.strip_prefix('+').unwrap_or(t)),
    };
    let v = if let Ok(i) = sfc_syntax::literal::decode_int(body, Span::default()) {
        i as f64
    } else {
        sfc_syntax::literal::decode_real(body, Span::default()).ok().or_else(|| body.parse::<f64>().ok())?
    };
    Some(if neg { -v } else { v })
}

fn parse_int(to: &Type, s: &str) -> i64 {
    let t = s.trim();
    let u = unit_of(to);
    if to.is_duration() {
        let us = crate::value::parse_time(t)
            .or_else(|| sfc_syntax::literal::decode_duration(t, Span::default()).ok())
            .unwrap_or(0);
        return us;
    }
    if to.is_date() {
        return match sfc_syntax::literal::decode_typed(t, Span::default()) {
            Ok((sfc_syntax::ast::LiteralKind::Date(d), _)) => d.wrapping_mul(DAY_US),
            Ok((sfc_syntax::ast::LiteralKind::TimeOfDay(us), _)) => us,
            Ok((sfc_syntax::ast::LiteralKind::DateAndTime(us), _)) => us,
            _ => 0,
        };
    }
    let (neg, body) = match t.strip_prefix('-') {
        Some(r) => (true, r),
        None => (false, t.strip_prefix('+').unwrap_or(t)),
    };
    if let Ok(i) = sfc_syntax::literal::decode_int(body, Span::default()) {
        let i = i as i128;
        return from_plain(u, if neg { -i } else { i });
    }
    parse_number(t).and_then(|x| from_real(u, x, Rounding::Nearest)).unwrap_or(0)
}

fn parse_real(to: &Type, s: &str) -> f64 {
    let x = parse_number(s.trim()).unwrap_or(0.0);
    if to.base() == &Type::Real {
        r32(x)
    } else {
        x
    }
}
