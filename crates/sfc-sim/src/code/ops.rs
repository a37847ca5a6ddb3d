//! Operators: arithmetic with IEC widths and two's-complement wrap, REAL rounding, TIME and
//! date arithmetic, comparisons over every elementary type, logic and bit operations.

use super::convert::coerce;
use super::rt::*;
use super::texpr::{bool_fn, int_fn, leaf_bool, leaf_int, leaf_real, opd1, opd2, real_fn, CExpr, TExpr};
use super::unit::C;
use sfc_diagnostics::{Diagnostic, Span};
use sfc_st::Type;
use sfc_syntax::ast::BinaryOp;

fn err(span: Span, msg: impl Into<String>) -> Box<Diagnostic> {
    Box::new(Diagnostic::error("SFC0320", span, format!("cannot be simulated: {}", msg.into())))
}

fn timey(t: &Type) -> bool {
    t.is_duration() || t.is_date()
}

/// The type of `l op r` when the checker did not record one (IL, standard functions).
pub(crate) fn result_type(op: BinaryOp, l: &Type, r: &Type) -> Option<Type> {
    use BinaryOp as B;
    match op {
        B::Eq | B::Ne | B::Lt | B::Gt | B::Le | B::Ge | B::AndThen | B::OrElse => Some(Type::Bool),
        B::Add | B::Sub | B::Mul | B::Div if timey(l) || timey(r) => {
            let (a, b) = (l.base(), r.base());
            match op {
                B::Add | B::Sub if a.is_duration() && b.is_duration() => Type::common(a, b),
                B::Add | B::Sub if matches!(a, Type::TimeOfDay | Type::DateAndTime) && b.is_duration() => {
                    Some(a.clone())
                }
                B::Sub if a == b && a.is_date() => Some(Type::Time),
                B::Mul | B::Div if a.is_duration() => Some(a.clone()),
                B::Mul if b.is_duration() => Some(b.clone()),
                _ => None,
            }
        }
        B::Pow => Some(if l.is_real() { l.base().clone() } else { Type::LReal }),
        _ => Type::common(l.base(), r.base()),
    }
}

/// `l op r`; `rt` is the type the checker gave the operation.
pub(crate) fn binary(op: BinaryOp, l: TExpr, r: TExpr, rt: Option<Type>, span: Span) -> C<TExpr> {
    use BinaryOp as B;
    let constant = l.constant && r.constant;
    let out = match op {
        B::Eq | B::Ne | B::Lt | B::Gt | B::Le | B::Ge => compare(op, l, r, span)?,
        B::AndThen | B::OrElse => {
            let (a, b) = (l.bool(), r.bool());
            let e: BoolFn = if op == B::AndThen {
                Box::new(move |c, x| Ok(a(c, x)? && b(c, x)?))
            } else {
                Box::new(move |c, x| Ok(a(c, x)? || b(c, x)?))
            };
            TExpr::new(CExpr::Bool(e), Type::Bool, constant)
        }
        B::Add | B::Sub | B::Mul | B::Div if timey(&l.ty) || timey(&r.ty) => time_arith(op, l, r, rt, span)?,
        _ => {
            let t = match rt.or_else(|| result_type(op, &l.ty, &r.ty)) {
                Some(t) => t,
                None => return Err(err(span, format!("operator `{}` on `{}` and `{}`", op.symbol(), l.ty, r.ty))),
            };
            match op {
                B::And | B::Or | B::Xor => logic(op, l, r, t, span)?,
                B::Pow => pow(l, r, t, span)?,
                _ => arith(op, l, r, t, span)?,
            }
        }
    };
    Ok(TExpr { constant, ..out }.fold())
}

macro_rules! bin_closure {
    ($a:ident, $b:ident, |$x:ident, $y:ident| $body:expr) => {
        Box::new(move |c, base| {
            let $x = $a(c, base)?;
            let $y = $b(c, base)?;
            $body
        })
    };
}

fn logic(op: BinaryOp, l: TExpr, r: TExpr, t: Type, span: Span) -> C<TExpr> {
    if kind_of(&t) == Kind::Bool {
        let (a, b) = (l.bool_opd(), r.bool_opd());
        let e: BoolFn = match op {
            BinaryOp::And => opd2!(bool_fn, a, b, leaf_bool, leaf_bool, |x, y| Ok(x & y)),
            BinaryOp::Or => opd2!(bool_fn, a, b, leaf_bool, leaf_bool, |x, y| Ok(x | y)),
            _ => opd2!(bool_fn, a, b, leaf_bool, leaf_bool, |x, y| Ok(x ^ y)),
        };
        return Ok(TExpr::new(CExpr::Bool(e), t, false));
    }
    let a = coerce(l, &t, span)?.int_opd();
    let b = coerce(r, &t, span)?.int_opd();
    let e: IntFn = match op {
        BinaryOp::And => opd2!(int_fn, a, b, leaf_int, leaf_int, |x, y| Ok(x & y)),
        BinaryOp::Or => opd2!(int_fn, a, b, leaf_int, leaf_int, |x, y| Ok(x | y)),
        _ => opd2!(int_fn, a, b, leaf_int, leaf_int, |x, y| Ok(x ^ y)),
    };
    Ok(TExpr::new(CExpr::Int(e), t, false))
}

/// `+ - * / MOD` of numbers in type `t`.
pub(crate) fn arith(op: BinaryOp, l: TExpr, r: TExpr, t: Type, span: Span) -> C<TExpr> {
    match kind_of(&t) {
        Kind::Int => {
            let w = W::of(&t);
            let a = coerce(l, &t, span)?.int_opd();
            let b = coerce(r, &t, span)?.int_opd();
            let e: IntFn = match op {
                BinaryOp::Add => opd2!(int_fn, a, b, leaf_int, leaf_int, |x, y| Ok(w.wrap(x.wrapping_add(y)))),
                BinaryOp::Sub => opd2!(int_fn, a, b, leaf_int, leaf_int, |x, y| Ok(w.wrap(x.wrapping_sub(y)))),
                BinaryOp::Mul => opd2!(int_fn, a, b, leaf_int, leaf_int, |x, y| Ok(w.wrap(x.wrapping_mul(y)))),
                BinaryOp::Div if w == W::U64 => opd2!(int_fn, a, b, leaf_int, leaf_int, |x, y| {
                    if y == 0 {
                        return Err(fault("division by zero", span));
                    }
                    Ok(((x as u64) / (y as u64)) as i64)
                }),
                BinaryOp::Div => opd2!(int_fn, a, b, leaf_int, leaf_int, |x, y| {
                    if y == 0 {
                        return Err(fault("division by zero", span));
                    }
                    Ok(w.wrap(x.wrapping_div(y)))
                }),
                BinaryOp::Mod if w == W::U64 => opd2!(int_fn, a, b, leaf_int, leaf_int, |x, y| {
                    if y == 0 {
                        return Err(fault("MOD by zero", span));
                    }
                    Ok(((x as u64) % (y as u64)) as i64)
                }),
                BinaryOp::Mod => opd2!(int_fn, a, b, leaf_int, leaf_int, |x, y| {
                    if y == 0 {
                        return Err(fault("MOD by zero", span));
                    }
                    Ok(w.wrap(x.wrapping_rem(y)))
                }),
                _ => return Err(err(span, format!("operator `{}` on `{t}`", op.symbol()))),
            };
            Ok(TExpr::new(CExpr::Int(e), t, false))
        }
        Kind::Real => {
            let single = t.base() == &Type::Real;
            let a = coerce(l, &t, span)?.real_opd();
            let b = coerce(r, &t, span)?.real_opd();
            let e: RealFn = match (op, single) {
                (BinaryOp::Add, true) => opd2!(real_fn, a, b, leaf_real, leaf_real, |x, y| Ok(r32(x + y))),
                (BinaryOp::Add, false) => opd2!(real_fn, a, b, leaf_real, leaf_real, |x, y| Ok(x + y)),
                (BinaryOp::Sub, true) => opd2!(real_fn, a, b, leaf_real, leaf_real, |x, y| Ok(r32(x - y))),
                (BinaryOp::Sub, false) => opd2!(real_fn, a, b, leaf_real, leaf_real, |x, y| Ok(x - y)),
                (BinaryOp::Mul, true) => opd2!(real_fn, a, b, leaf_real, leaf_real, |x, y| Ok(r32(x * y))),
                (BinaryOp::Mul, false) => opd2!(real_fn, a, b, leaf_real, leaf_real, |x, y| Ok(x * y)),
                (BinaryOp::Div, true) => opd2!(real_fn, a, b, leaf_real, leaf_real, |x, y| Ok(r32(x / y))),
                (BinaryOp::Div, false) => opd2!(real_fn, a, b, leaf_real, leaf_real, |x, y| Ok(x / y)),
                _ => return Err(err(span, format!("operator `{}` on `{t}`", op.symbol()))),
            };
            Ok(TExpr::new(CExpr::Real(e), t, false))
        }
        _ => Err(err(span, format!("operator `{}` on `{t}`", op.symbol()))),
    }
}

/// `**`: a real base, any numeric exponent.
fn pow(l: TExpr, r: TExpr, t: Type, span: Span) -> C<TExpr> {
    let t = if t.is_real() { t } else { Type::LReal };
    let single = t.base() == &Type::Real;
    let a = coerce(l, &t, span)?.real();
    let b = r.real();
    let e: RealFn = bin_closure!(a, b, |x, y| {
        let p = x.powf(y);
        Ok(if single { r32(p) } else { p })
    });
    Ok(TExpr::new(CExpr::Real(e), t, false))
}

/// TIME and date arithmetic (IEC 61131-3 table 30). TIME_OF_DAY results wrap into one day.
fn time_arith(op: BinaryOp, l: TExpr, r: TExpr, rt: Option<Type>, span: Span) -> C<TExpr> {
    let Some(res) = rt.or_else(|| result_type(op, &l.ty, &r.ty)) else {
        return Err(err(span, format!("operator `{}` on `{}` and `{}`", op.symbol(), l.ty, r.ty)));
    };
    let tod = res.base() == &Type::TimeOfDay;
    let out = res.clone();
    if super::matiec_time() && res.is_duration() {
        return matiec_time_arith(op, l, r, out, span);
    }
    match op {
        BinaryOp::Add | BinaryOp::Sub => {
            let (a, b) = (l.int(), r.int());
            let sub = op == BinaryOp::Sub;
            let e: IntFn = bin_closure!(a, b, |x, y| {
                let v = if sub { x.wrapping_sub(y) } else { x.wrapping_add(y) };
                Ok(if tod { v.rem_euclid(DAY_US) } else { v })
            });
            Ok(TExpr::new(CExpr::Int(e), out, false))
        }
        BinaryOp::Mul | BinaryOp::Div => {
            let (d, n) = if timey(&l.ty) { (l, r) } else { (r, l) };
            let div = op == BinaryOp::Div;
            let a = d.int();
            let e: IntFn = if n.kind() == Kind::Real {
                let b = n.real();
                bin_closure!(a, b, |x, y| {
                    if div && y == 0.0 {
                        return Err(fault("division by zero", span));
                    }
                    let v = if div { x as f64 / y } else { x as f64 * y };
                    if !v.is_finite() {
                        return Err(fault("TIME arithmetic overflows", span));
                    }
                    Ok(v.round() as i64)
                })
            } else {
                let w = W::of(&n.ty);
                let b = n.int();
                bin_closure!(a, b, |x, y| {
                    let y = if w == W::U64 { (y as u64).min(i64::MAX as u64) as i64 } else { y };
                    if div {
                        if y == 0 {
                            return Err(fault("division by zero", span));
                        }
                        Ok(x.wrapping_div(y))
                    } else {
                        Ok(x.wrapping_mul(y))
                    }
                })
            };
            Ok(TExpr::new(CExpr::Int(e), out, false))
        }
        _ => Err(err(span, format!("operator `{}` on `{}`", op.symbol(), res))),
    }
}

/// TIME arithmetic as MatIEC's `__time_add`, `__time_sub`, `__time_mul`, `__time_div` on packed
/// timespecs (`crate::timespec`).
fn matiec_time_arith(op: BinaryOp, l: TExpr, r: TExpr, out: Type, span: Span) -> C<TExpr> {
    use crate::timespec::Timespec as Ts;
    match op {
        BinaryOp::Add | BinaryOp::Sub => {
            let (a, b) = (l.int(), r.int());
            let sub = op == BinaryOp::Sub;
            let e: IntFn = bin_closure!(a, b, |x, y| {
                let (x, y) = (Ts::unpack(x), Ts::unpack(y));
                Ok(if sub { x.sub(y) } else { x.add(y) }.pack())
            });
            Ok(TExpr::new(CExpr::Int(e), out, false))
        }
        BinaryOp::Mul | BinaryOp::Div => {
            let (d, n) = if timey(&l.ty) { (l, r) } else { (r, l) };
            let div = op == BinaryOp::Div;
            let a = d.int();
            let b: RealFn = if n.kind() == Kind::Real {
                n.real()
            } else {
                let f = n.int();
                Box::new(move |c, x| Ok(f(c, x)? as f64))
            };
            let e: IntFn = bin_closure!(a, b, |x, y| {
                if div && y == 0.0 {
                    return Err(fault("division by zero", span));
                }
                let t = Ts::unpack(x);
                Ok(if div { t.div(y) } else { t.mul(y) }.pack())
            });
            Ok(TExpr::new(CExpr::Int(e), out, false))
        }
        _ => Err(err(span, format!("operator `{}` on `{}`", op.symbol(), out))),
    }
}

macro_rules! cmp_closures {
    ($op:expr, $a:ident, $b:ident, $get:path, $conv:expr) => {{
        let conv = $conv;
        let e: BoolFn = match $op {
            BinaryOp::Eq => opd2!(bool_fn, $a, $b, $get, $get, |x, y| Ok(conv(x) == conv(y))),
            BinaryOp::Ne => opd2!(bool_fn, $a, $b, $get, $get, |x, y| Ok(conv(x) != conv(y))),
            BinaryOp::Lt => opd2!(bool_fn, $a, $b, $get, $get, |x, y| Ok(conv(x) < conv(y))),
            BinaryOp::Gt => opd2!(bool_fn, $a, $b, $get, $get, |x, y| Ok(conv(x) > conv(y))),
            BinaryOp::Le => opd2!(bool_fn, $a, $b, $get, $get, |x, y| Ok(conv(x) <= conv(y))),
            _ => opd2!(bool_fn, $a, $b, $get, $get, |x, y| Ok(conv(x) >= conv(y))),
        };
        e
    }};
}

/// `= <> < > <= >=` over every elementary type (strings by code points).
pub(crate) fn compare(op: BinaryOp, l: TExpr, r: TExpr, span: Span) -> C<TExpr> {
    let ct = Type::common(&l.ty, &r.ty)
        .or_else(|| (l.kind() == r.kind()).then(|| l.ty.clone()))
        .ok_or_else(|| err(span, format!("comparing `{}` with `{}`", l.ty, r.ty)))?;
    let constant = l.constant && r.constant;
    let (l, r) = if l.ty.base() == ct.base() && r.ty.base() == ct.base() {
        (l, r)
    } else {
        (coerce(l, &ct, span)?, coerce(r, &ct, span)?)
    };
    let e: BoolFn = match kind_of(&ct) {
        Kind::Bool => {
            let (a, b) = (l.bool_opd(), r.bool_opd());
            cmp_closures!(op, a, b, leaf_bool, |x: bool| x)
        }
        Kind::Int if W::of(&ct) == W::U64 => {
            let (a, b) = (l.int_opd(), r.int_opd());
            cmp_closures!(op, a, b, leaf_int, |x: i64| x as u64)
        }
        Kind::Int => {
            let (a, b) = (l.int_opd(), r.int_opd());
            cmp_closures!(op, a, b, leaf_int, |x: i64| x)
        }
        Kind::Real => {
            let (a, b) = (l.real_opd(), r.real_opd());
            cmp_closures!(op, a, b, leaf_real, |x: f64| x)
        }
        Kind::Str => {
            let (a, b) = (l.str(), r.str());
            let e: BoolFn = match op {
                BinaryOp::Eq => bin_closure!(a, b, |x, y| Ok(*x == *y)),
                BinaryOp::Ne => bin_closure!(a, b, |x, y| Ok(*x != *y)),
                BinaryOp::Lt => bin_closure!(a, b, |x, y| Ok(*x < *y)),
                BinaryOp::Gt => bin_closure!(a, b, |x, y| Ok(*x > *y)),
                BinaryOp::Le => bin_closure!(a, b, |x, y| Ok(*x <= *y)),
                _ => bin_closure!(a, b, |x, y| Ok(*x >= *y)),
            };
            e
        }
        Kind::Agg => return Err(err(span, format!("comparing `{ct}` values"))),
    };
    Ok(TExpr::new(CExpr::Bool(e), Type::Bool, constant))
}

/// Unary minus (two's-complement wrap for integers).
pub(crate) fn neg(v: TExpr, rt: Option<Type>, span: Span) -> C<TExpr> {
    let t = rt.unwrap_or_else(|| v.ty.clone());
    let constant = v.constant;
    let v = coerce(v, &t, span)?;
    let e = match v.kind() {
        Kind::Int => {
            let w = W::of(&t);
            CExpr::Int(opd1!(int_fn, v.int_opd(), leaf_int, |x| Ok(w.wrap(x.wrapping_neg()))))
        }
        Kind::Real => CExpr::Real(opd1!(real_fn, v.real_opd(), leaf_real, |x| Ok(-x))),
        _ => return Err(err(span, format!("unary minus on `{t}`"))),
    };
    Ok(TExpr::new(e, t, constant).fold())
}

/// `NOT`: logical for BOOL, bitwise in the width for bit strings.
pub(crate) fn not(v: TExpr, span: Span) -> C<TExpr> {
    let t = v.ty.clone();
    let constant = v.constant;
    let e = match v.kind() {
        Kind::Bool => CExpr::Bool(opd1!(bool_fn, v.bool_opd(), leaf_bool, |x| Ok(!x))),
        Kind::Int => {
            let w = W::of(&t);
            CExpr::Int(opd1!(int_fn, v.int_opd(), leaf_int, |x| Ok(w.wrap(!x))))
        }
        _ => return Err(err(span, format!("NOT on `{t}`"))),
    };
    Ok(TExpr::new(e, t, constant).fold())
}
