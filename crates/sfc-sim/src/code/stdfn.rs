//! The standard functions the checker accepts (`sfc_st::stdlib`): numeric, bit shift, bitwise,
//! selection, comparison, conversions (with BCD), strings, TIME and date arithmetic.
//!
//! String positions are 1-based and counted in characters. Out-of-range lengths and positions
//! are clamped as CODESYS does (`LEFT('abc', 5)` is `'abc'`, `MID('abc', 2, 9)` is `''`).

use super::convert::{coerce, convert, Rounding};
use super::ops;
use super::rt::*;
use super::texpr::{CExpr, TExpr};
use super::unit::C;
use crate::value::Value;
use sfc_diagnostics::{Diagnostic, Span};
use sfc_st::stdlib::{ParamType, ReturnType, StdFunction};
use sfc_st::Type;
use sfc_syntax::ast::BinaryOp;
use std::cmp::Ordering;
use std::sync::Arc;

fn err(span: Span, msg: impl Into<String>) -> Box<Diagnostic> {
    Box::new(Diagnostic::error("SFC0320", span, format!("cannot be simulated: {}", msg.into())))
}

/// The common type of the `Same` inputs.
fn same_type(f: &StdFunction, args: &[TExpr]) -> Option<Type> {
    let mut t: Option<Type> = None;
    for (i, a) in args.iter().enumerate() {
        if let Some(ParamType::Same(_)) = f.param_type(i) {
            t = Some(match t {
                None => a.ty.base().clone(),
                Some(p) => Type::common(&p, &a.ty).unwrap_or(p),
            });
        }
    }
    t
}

/// The result type of a standard function applied to arguments of these types (when the
/// checker recorded none).
pub(crate) fn result_type(f: &StdFunction, args: &[TExpr]) -> Option<Type> {
    match &f.ret {
        ReturnType::Fixed(t) => Some(t.clone()),
        ReturnType::FromContext(_, d) => Some(d.clone()),
        ReturnType::Same => {
            if let Some(op) = f.operator {
                let mut it = args.iter();
                let mut t = it.next()?.ty.clone();
                for a in it {
                    t = ops::result_type(op, &t, &a.ty)?;
                }
                Some(t)
            } else {
                same_type(f, args)
            }
        }
    }
}

/// Compares two slot values of one type.
fn cmp_values(kind: Kind, w: W, a: &Value, b: &Value) -> Ordering {
    match kind {
        Kind::Bool => bool_of(a).cmp(&bool_of(b)),
        Kind::Int if w == W::U64 => (int_of(a) as u64).cmp(&(int_of(b) as u64)),
        Kind::Int => int_of(a).cmp(&int_of(b)),
        Kind::Real => real_of(a).partial_cmp(&real_of(b)).unwrap_or(Ordering::Equal),
        Kind::Str => str_of(a).cmp(&str_of(b)),
        Kind::Agg => Ordering::Equal,
    }
}

/// Applies standard function `f` to compiled arguments (in parameter order); `rt` is the type
/// the checker recorded for the call.
pub(crate) fn apply(f: &StdFunction, args: Vec<TExpr>, rt: Option<Type>, span: Span) -> C<TExpr> {
    let rt = rt.or_else(|| result_type(f, &args));
    let name = f.name.as_str();
    if let Some(op) = f.operator {
        return operator(op, args, rt, span, name);
    }
    let n = args.len();
    let need = |k: usize| -> C<()> {
        if n < k {
            Err(err(span, format!("`{name}` needs {k} inputs")))
        } else {
            Ok(())
        }
    };
    let rt_or = |a: &TExpr| rt.clone().unwrap_or_else(|| a.ty.clone());
    let mut args = args.into_iter();
    match name {
        "NOT" => {
            need(1)?;
            let a = args.next().expect("checked");
            let t = rt_or(&a);
            ops::not(coerce(a, &t, span)?, span)
        }
        "MOVE" => {
            need(1)?;
            let a = args.next().expect("checked");
            let t = rt_or(&a);
            coerce(a, &t, span)
        }
        "ABS" => {
            need(1)?;
            let a = args.next().expect("checked");
            let t = rt_or(&a);
            let a = coerce(a, &t, span)?;
            let c = a.constant;
            let e = match a.kind() {
                Kind::Real => {
                    let g = a.real();
                    CExpr::Real(Box::new(move |x, b| Ok(g(x, b)?.abs())))
                }
                _ => {
                    let w = W::of(&t);
                    let g = a.int();
                    if w.unsigned() {
                        CExpr::Int(g)
                    } else {
                        CExpr::Int(Box::new(move |x, b| Ok(w.wrap(g(x, b)?.wrapping_abs()))))
                    }
                }
            };
            Ok(TExpr::new(e, t, c).fold())
        }
        "SQRT" | "LN" | "LOG" | "EXP" | "SIN" | "COS" | "TAN" | "ASIN" | "ACOS" | "ATAN" => {
            need(1)?;
            let a = args.next().expect("checked");
            let t = rt.clone().filter(Type::is_real).unwrap_or(if a.ty.is_real() { a.ty.clone() } else { Type::LReal });
            let c = a.constant;
            let g = coerce(a, &t, span)?.real();
            let single = t.base() == &Type::Real;
            let func: fn(f64) -> f64 = match name {
                "SQRT" => f64::sqrt,
                "LN" => f64::ln,
                "LOG" => f64::log10,
                "EXP" => f64::exp,
                "SIN" => f64::sin,
                "COS" => f64::cos,
                "TAN" => f64::tan,
                "ASIN" => f64::asin,
                "ACOS" => f64::acos,
                _ => f64::atan,
            };
            let e = CExpr::Real(Box::new(move |x, b| {
                let v = func(g(x, b)?);
                Ok(if single { r32(v) } else { v })
            }));
            Ok(TExpr::new(e, t, c).fold())
        }
        "TRUNC" => {
            need(1)?;
            let a = args.next().expect("checked");
            convert(a, &rt.unwrap_or(Type::DInt), span, Rounding::Trunc)
        }
        "SHL" | "SHR" | "ROL" | "ROR" => {
            need(2)?;
            let a = args.next().expect("checked");
            let k = args.next().expect("checked");
            let t = rt_or(&a);
            let c = a.constant && k.constant;
            let bits = t.bit_width().unwrap_or(64);
            let mask: u64 = if bits >= 64 { u64::MAX } else { (1u64 << bits) - 1 };
            let w = W::of(&t);
            let bool_in = t.is_bool();
            let g = coerce(a, &t, span)?.int();
            let kk = k.int();
            let which = name.to_string();
            let e = CExpr::Int(Box::new(move |x, b| {
                let v = (g(x, b)? as u64) & mask;
                let n = kk(x, b)?.clamp(0, 1 << 20) as u32;
                let r = match which.as_str() {
                    "SHL" => {
                        if n >= bits {
                            0
                        } else {
                            (v << n) & mask
                        }
                    }
                    "SHR" => {
                        if n >= bits {
                            0
                        } else {
                            v >> n
                        }
                    }
                    "ROL" => {
                        let n = n % bits;
                        if n == 0 {
                            v
                        } else {
                            ((v << n) | (v >> (bits - n))) & mask
                        }
                    }
                    _ => {
                        let n = n % bits;
                        if n == 0 {
                            v
                        } else {
                            ((v >> n) | (v << (bits - n))) & mask
                        }
                    }
                };
                Ok(w.wrap(r as i64))
            }));
            let out = TExpr::new(e, if bool_in { Type::Bool } else { t.clone() }, c);
            if bool_in {
                let g = out.int();
                return Ok(TExpr::new(CExpr::Bool(Box::new(move |x, b| Ok(g(x, b)? != 0))), t, c).fold());
            }
            Ok(out.fold())
        }
        "SEL" => {
            need(3)?;
            let g = args.next().expect("checked");
            let a = args.next().expect("checked");
            let b2 = args.next().expect("checked");
            let t = rt.clone().or_else(|| Type::common(&a.ty, &b2.ty)).unwrap_or_else(|| a.ty.clone());
            let gf = g.bool();
            let af = coerce(a, &t, span)?.value();
            let bf = coerce(b2, &t, span)?.value();
            let v: ValFn = Box::new(move |x, b| {
                let s = gf(x, b)?;
                let va = af(x, b)?;
                let vb = bf(x, b)?;
                Ok(if s { vb } else { va })
            });
            Ok(TExpr::from_val(t, v, false))
        }
        "MUX" => {
            need(2)?;
            let k = args.next().expect("checked");
            let rest: Vec<TExpr> = args.collect();
            let t = rt.clone().unwrap_or_else(|| rest[0].ty.clone());
            let kf = k.int();
            let fs: Vec<ValFn> = rest.into_iter().map(|a| coerce(a, &t, span).map(TExpr::value)).collect::<C<_>>()?;
            let v: ValFn = Box::new(move |x, b| {
                let sel = kf(x, b)?;
                let mut chosen = None;
                for (i, f) in fs.iter().enumerate() {
                    let v = f(x, b)?;
                    if i as i64 == sel {
                        chosen = Some(v);
                    }
                }
                chosen.ok_or_else(|| fault(format!("MUX selector {sel} is out of range 0..{}", fs.len() - 1), span))
            });
            Ok(TExpr::from_val(t, v, false))
        }
        "MIN" | "MAX" | "LIMIT" => {
            let all: Vec<TExpr> = args.collect();
            if all.len() < 2 || (name == "LIMIT" && all.len() != 3) {
                return Err(err(span, format!("`{name}` has the wrong number of inputs")));
            }
            let t = rt
                .clone()
                .or_else(|| all.iter().skip(1).try_fold(all[0].ty.clone(), |a, b| Type::common(&a, &b.ty)))
                .unwrap_or_else(|| all[0].ty.clone());
            let c = all.iter().all(|a| a.constant);
            let kind = kind_of(&t);
            let w = W::of(&t);
            let fs: Vec<ValFn> = all.into_iter().map(|a| coerce(a, &t, span).map(TExpr::value)).collect::<C<_>>()?;
            let v: ValFn = match name {
                "LIMIT" => Box::new(move |x, b| {
                    let mn = fs[0](x, b)?;
                    let v = fs[1](x, b)?;
                    let mx = fs[2](x, b)?;
                    let v = if cmp_values(kind, w, &v, &mx) == Ordering::Greater { mx } else { v };
                    Ok(if cmp_values(kind, w, &v, &mn) == Ordering::Less { mn } else { v })
                }),
                _ => {
                    let want = if name == "MIN" { Ordering::Less } else { Ordering::Greater };
                    Box::new(move |x, b| {
                        let mut best = fs[0](x, b)?;
                        for f in &fs[1..] {
                            let v = f(x, b)?;
                            if cmp_values(kind, w, &v, &best) == want {
                                best = v;
                            }
                        }
                        Ok(best)
                    })
                }
            };
            Ok(TExpr::from_val(t, v, c))
        }
        "LEN" => {
            need(1)?;
            let a = args.next().expect("checked");
            let c = a.constant;
            let g = a.str();
            let e = CExpr::Int(Box::new(move |x, b| Ok(W::I16.wrap(g(x, b)?.chars().count() as i64))));
            Ok(TExpr::new(e, Type::Int, c).fold())
        }
        "LEFT" | "RIGHT" => {
            need(2)?;
            let a = args.next().expect("checked");
            let l = args.next().expect("checked");
            let t = rt_or(&a);
            let c = a.constant && l.constant;
            let (g, lf) = (a.str(), l.int());
            let left = name == "LEFT";
            let e = CExpr::Str(Box::new(move |x, b| {
                let s = g(x, b)?;
                let n = lf(x, b)?.max(0) as usize;
                let chars: Vec<char> = s.chars().collect();
                let n = n.min(chars.len());
                let part: String =
                    if left { chars[..n].iter().collect() } else { chars[chars.len() - n..].iter().collect() };
                Ok(Arc::from(part))
            }));
            Ok(TExpr::new(e, t, c).fold())
        }
        "MID" => {
            need(3)?;
            let a = args.next().expect("checked");
            let l = args.next().expect("checked");
            let p = args.next().expect("checked");
            let t = rt_or(&a);
            let c = a.constant && l.constant && p.constant;
            let (g, lf, pf) = (a.str(), l.int(), p.int());
            let e = CExpr::Str(Box::new(move |x, b| {
                let s = g(x, b)?;
                let n = lf(x, b)?.max(0) as usize;
                let pos = pf(x, b)?;
                let chars: Vec<char> = s.chars().collect();
                if pos < 1 || pos as usize > chars.len() {
                    return Ok(Arc::from(""));
                }
                let start = pos as usize - 1;
                let end = (start + n).min(chars.len());
                Ok(Arc::from(chars[start..end].iter().collect::<String>()))
            }));
            Ok(TExpr::new(e, t, c).fold())
        }
        "CONCAT" => {
            let all: Vec<TExpr> = args.collect();
            let t = rt.clone().unwrap_or(Type::String { len: None });
            let c = all.iter().all(|a| a.constant);
            let fs: Vec<StrFn> = all.into_iter().map(TExpr::str).collect();
            let e = CExpr::Str(Box::new(move |x, b| {
                let mut out = String::new();
                for f in &fs {
                    out.push_str(&f(x, b)?);
                }
                Ok(Arc::from(out))
            }));
            Ok(TExpr::new(e, t, c).fold())
        }
        "INSERT" => {
            need(3)?;
            let a = args.next().expect("checked");
            let ins = args.next().expect("checked");
            let p = args.next().expect("checked");
            let t = rt_or(&a);
            let c = a.constant && ins.constant && p.constant;
            let (g, h, pf) = (a.str(), ins.str(), p.int());
            let e = CExpr::Str(Box::new(move |x, b| {
                let s = g(x, b)?;
                let i = h(x, b)?;
                let chars: Vec<char> = s.chars().collect();
                let pos = pf(x, b)?.clamp(0, chars.len() as i64) as usize;
                let mut out: String = chars[..pos].iter().collect();
                out.push_str(&i);
                out.extend(chars[pos..].iter());
                Ok(Arc::from(out))
            }));
            Ok(TExpr::new(e, t, c).fold())
        }
        "DELETE" | "REPLACE" => {
            let replace = name == "REPLACE";
            need(if replace { 4 } else { 3 })?;
            let a = args.next().expect("checked");
            let r = if replace { Some(args.next().expect("checked")) } else { None };
            let l = args.next().expect("checked");
            let p = args.next().expect("checked");
            let t = rt_or(&a);
            let c = a.constant && l.constant && p.constant && r.as_ref().is_none_or(|r| r.constant);
            let (g, lf, pf) = (a.str(), l.int(), p.int());
            let rf = r.map(TExpr::str);
            let e = CExpr::Str(Box::new(move |x, b| {
                let s = g(x, b)?;
                let with = match &rf {
                    Some(f) => f(x, b)?,
                    None => Arc::from(""),
                };
                let n = lf(x, b)?.max(0) as usize;
                let pos = pf(x, b)?;
                let chars: Vec<char> = s.chars().collect();
                let start = (pos.max(1) as usize - 1).min(chars.len());
                let end = (start + n).min(chars.len());
                let mut out: String = chars[..start].iter().collect();
                out.push_str(&with);
                out.extend(chars[end..].iter());
                Ok(Arc::from(out))
            }));
            Ok(TExpr::new(e, t, c).fold())
        }
        "FIND" => {
            need(2)?;
            let a = args.next().expect("checked");
            let s2 = args.next().expect("checked");
            let c = a.constant && s2.constant;
            let (g, h) = (a.str(), s2.str());
            let e = CExpr::Int(Box::new(move |x, b| {
                let hay = g(x, b)?;
                let needle = h(x, b)?;
                Ok(match hay.find(&*needle) {
                    Some(i) if !needle.is_empty() => hay[..i].chars().count() as i64 + 1,
                    _ => 0,
                })
            }));
            Ok(TExpr::new(e, Type::Int, c).fold())
        }
        "ADD_TIME" | "ADD_TOD_TIME" | "ADD_DT_TIME" | "CONCAT_DATE_TOD" => {
            need(2)?;
            let (a, b2) = (args.next().expect("checked"), args.next().expect("checked"));
            ops::binary(BinaryOp::Add, a, b2, rt, span)
        }
        "SUB_TIME" | "SUB_DATE_DATE" | "SUB_TOD_TIME" | "SUB_TOD_TOD" | "SUB_DT_TIME" | "SUB_DT_DT" => {
            need(2)?;
            let (a, b2) = (args.next().expect("checked"), args.next().expect("checked"));
            ops::binary(BinaryOp::Sub, a, b2, rt, span)
        }
        "MUL_TIME" | "DIV_TIME" => {
            need(2)?;
            let (a, b2) = (args.next().expect("checked"), args.next().expect("checked"));
            let op = if name == "MUL_TIME" { BinaryOp::Mul } else { BinaryOp::Div };
            ops::binary(op, a, b2, rt, span)
        }
        _ => {
            need(1)?;
            let a = args.next().expect("checked");
            conversion(name, a, rt, span)
        }
    }
}

/// `ADD`, `GT`, … : the operator over the inputs (extensible ones fold from the left;
/// comparisons chain: `GT(a, b, c)` is `a > b AND b > c`).
fn operator(op: BinaryOp, args: Vec<TExpr>, rt: Option<Type>, span: Span, name: &str) -> C<TExpr> {
    if args.len() < 2 {
        return Err(err(span, format!("`{name}` needs two inputs")));
    }
    let cmp = matches!(op, BinaryOp::Eq | BinaryOp::Ne | BinaryOp::Lt | BinaryOp::Gt | BinaryOp::Le | BinaryOp::Ge);
    if cmp {
        if args.len() == 2 {
            let mut it = args.into_iter();
            let (a, b) = (it.next().expect("two"), it.next().expect("two"));
            return ops::compare(op, a, b, span);
        }
        let t = args
            .iter()
            .skip(1)
            .try_fold(args[0].ty.clone(), |a, b| Type::common(&a, &b.ty))
            .ok_or_else(|| err(span, format!("`{name}` on mixed types")))?;
        let kind = kind_of(&t);
        let w = W::of(&t);
        let fs: Vec<ValFn> = args.into_iter().map(|a| coerce(a, &t, span).map(TExpr::value)).collect::<C<_>>()?;
        let e = CExpr::Bool(Box::new(move |x, b| {
            let mut prev = fs[0](x, b)?;
            let mut ok = true;
            for f in &fs[1..] {
                let v = f(x, b)?;
                let o = cmp_values(kind, w, &prev, &v);
                ok &= match op {
                    BinaryOp::Eq => o == Ordering::Equal,
                    BinaryOp::Lt => o == Ordering::Less,
                    BinaryOp::Gt => o == Ordering::Greater,
                    BinaryOp::Le => o != Ordering::Greater,
                    BinaryOp::Ge => o != Ordering::Less,
                    _ => o != Ordering::Equal,
                };
                prev = v;
            }
            Ok(ok)
        }));
        return Ok(TExpr::new(e, Type::Bool, false));
    }
    let mut it = args.into_iter();
    let mut acc = it.next().expect("two");
    for next in it {
        acc = ops::binary(op, acc, next, rt.clone(), span)?;
    }
    Ok(acc)
}

/// `<A>_TO_<B>`, `TO_<B>`, `TRUNC_<B>`, `<A>_TRUNC_<B>`, and the BCD conversions.
fn conversion(name: &str, a: TExpr, rt: Option<Type>, span: Span) -> C<TExpr> {
    let to = rt.ok_or_else(|| err(span, format!("unknown conversion `{name}`")))?;
    if name.contains("TRUNC") {
        return convert(a, &to, span, Rounding::Trunc);
    }
    if name.starts_with("BCD_TO_") || name.contains("_BCD_TO_") {
        let c = a.constant;
        let w = W::of(&to);
        let fname = name.to_string();
        let g = a.int();
        let e = CExpr::Int(Box::new(move |x, b| {
            let v = g(x, b)? as u64;
            let mut out: i128 = 0;
            let mut scale: i128 = 1;
            let mut rest = v;
            while rest != 0 {
                let d = rest & 0xF;
                if d > 9 {
                    return Err(fault(format!("{fname}: 16#{v:X} is not BCD-coded"), span));
                }
                out += i128::from(d) * scale;
                scale *= 10;
                rest >>= 4;
            }
            Ok(w.wrap128(out))
        }));
        return Ok(TExpr::new(e, to, c).fold());
    }
    if name.ends_with("_TO_BCD") || name.contains("_TO_BCD_") {
        let c = a.constant;
        let wi = W::of(&a.ty);
        let bits = to.bit_width().unwrap_or(64);
        let fname = name.to_string();
        let g = a.int();
        let e = CExpr::Int(Box::new(move |x, b| {
            let v = wi.wide(g(x, b)?);
            if v < 0 {
                return Err(fault(format!("{fname}: {v} is negative and cannot be BCD-coded"), span));
            }
            let mut out: u128 = 0;
            let mut shift = 0u32;
            let mut rest = v as u128;
            while rest != 0 {
                if shift >= bits {
                    return Err(fault(format!("{fname}: {v} has too many digits for {bits} bits"), span));
                }
                out |= (rest % 10) << shift;
                rest /= 10;
                shift += 4;
            }
            Ok(out as u64 as i64)
        }));
        return Ok(TExpr::new(e, to, c).fold());
    }
    convert(a, &to, span, Rounding::Nearest)
}
