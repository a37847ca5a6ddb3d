//! Compiling ST expressions and places (names, members, indices, direct addresses).

use super::convert::coerce;
use super::ops;
use super::place::{read, Loc, PlaceC};
use super::rt::*;
use super::texpr::TExpr;
use super::unit::{Cx, Sym, C};
use super::{Place, VarSlot};
use crate::value::Value;
use sfc_st::Type;
use sfc_syntax::ast::{BinaryOp, DirectAddress, Expr, ExprKind, Ident, Literal, LiteralKind, UnaryOp, VarKind};
use std::sync::Arc;

/// A numeric constant written without a type (`5`, `-1.5`, `2 * 3`), folded.
#[derive(Debug, Clone, Copy)]
pub(crate) enum Untyped {
    Int(i128),
    Real(f64),
}

/// Recognises an untyped constant expression (as the checker does) and folds it.
pub(crate) fn untyped(e: &Expr) -> Option<Untyped> {
    untyped_at(e, 0)
}

fn untyped_at(e: &Expr, depth: u32) -> Option<Untyped> {
    if depth > 300 {
        return None;
    }
    match &e.kind {
        ExprKind::Literal(Literal { kind: LiteralKind::Int(v), type_prefix: None, .. }) => Some(Untyped::Int(*v)),
        ExprKind::Literal(Literal { kind: LiteralKind::Real(r), type_prefix: None, .. }) => Some(Untyped::Real(*r)),
        ExprKind::Paren(inner) => untyped_at(inner, depth + 1),
        ExprKind::Unary { op: UnaryOp::Neg, operand } => match untyped_at(operand, depth + 1)? {
            Untyped::Int(v) => Some(Untyped::Int(v.checked_neg()?)),
            Untyped::Real(v) => Some(Untyped::Real(-v)),
        },
        ExprKind::Unary { op: UnaryOp::Plus, operand } => untyped_at(operand, depth + 1),
        ExprKind::Binary { op, lhs, rhs }
            if matches!(op, BinaryOp::Add | BinaryOp::Sub | BinaryOp::Mul | BinaryOp::Div | BinaryOp::Mod) =>
        {
            let a = untyped_at(lhs, depth + 1)?;
            let b = untyped_at(rhs, depth + 1)?;
            match (a, b) {
                (Untyped::Int(x), Untyped::Int(y)) => Some(Untyped::Int(match op {
                    BinaryOp::Add => x.checked_add(y)?,
                    BinaryOp::Sub => x.checked_sub(y)?,
                    BinaryOp::Mul => x.checked_mul(y)?,
                    BinaryOp::Div => x.checked_div(y)?,
                    _ => x.checked_rem(y)?,
                })),
                _ if *op == BinaryOp::Mod => None,
                (a, b) => {
                    let f = |u: Untyped| match u {
                        Untyped::Int(v) => v as f64,
                        Untyped::Real(v) => v,
                    };
                    let (x, y) = (f(a), f(b));
                    Some(Untyped::Real(match op {
                        BinaryOp::Add => x + y,
                        BinaryOp::Sub => x - y,
                        BinaryOp::Mul => x * y,
                        _ => x / y,
                    }))
                }
            }
        }
        _ => None,
    }
}

/// The type of an untyped constant without context: DINT, LINT or ULINT by size, LREAL.
pub(crate) fn natural(u: Untyped) -> Type {
    match u {
        Untyped::Real(_) => Type::LReal,
        Untyped::Int(v) if i32::try_from(v).is_ok() => Type::DInt,
        Untyped::Int(v) if i64::try_from(v).is_ok() => Type::LInt,
        Untyped::Int(_) => Type::ULInt,
    }
}

/// An untyped constant as a value of `ty`.
pub(crate) fn untyped_const(u: Untyped, ty: &Type) -> TExpr {
    let v = match (kind_of(ty), u) {
        (Kind::Bool, Untyped::Int(i)) => Value::Bool(i != 0),
        (Kind::Bool, Untyped::Real(r)) => Value::Bool(r != 0.0),
        (Kind::Real, Untyped::Int(i)) => Value::Real(real_for(ty, i as f64)),
        (Kind::Real, Untyped::Real(r)) => Value::Real(real_for(ty, r)),
        (_, Untyped::Int(i)) => int_value(ty.is_duration(), W::of(ty).wrap128(i)),
        (_, Untyped::Real(r)) => int_value(ty.is_duration(), r.round() as i64),
    };
    TExpr::constant(v, ty.clone())
}

fn real_for(ty: &Type, x: f64) -> f64 {
    if ty.base() == &Type::Real {
        r32(x)
    } else {
        x
    }
}

/// A compile-time constant of the checker (`sfc_st::Value`) as a value of `ty`.
pub(crate) fn st_const(v: sfc_st::Value, ty: &Type) -> TExpr {
    let u = match v {
        sfc_st::Value::Int(i) => Untyped::Int(i),
        sfc_st::Value::Real(r) => Untyped::Real(r),
        sfc_st::Value::Bool(b) => return TExpr::constant(Value::Bool(b), ty.clone()),
        sfc_st::Value::Time(t) => return TExpr::constant(Value::Time(super::time_of_us(t)), ty.clone()),
    };
    untyped_const(u, ty)
}

impl Cx<'_, '_> {
    /// Compiles an expression; `expected` is the type the context wants (used only when the
    /// checker recorded none).
    pub(crate) fn expr(&self, e: &Expr, expected: Option<&Type>) -> C<TExpr> {
        if let Some(u) = untyped(e) {
            let ty = self.recorded(e).or_else(|| expected.cloned()).unwrap_or_else(|| natural(u));
            return Ok(untyped_const(u, &ty));
        }
        // An instance (or `THIS^`) where an interface is expected: the value designating it.
        if let Some(t @ Type::Interface(_)) = expected {
            if let Some(v) = self.interface_value(e, t)? {
                return Ok(v);
            }
        }
        // `itf.P`, `itf.M(…)`: the property or method of the instance an interface designates.
        if let ExprKind::Member { base, member } = &e.kind {
            if let Some(v) = self.interface_get(base, member)? {
                return Ok(v);
            }
        }
        if let ExprKind::MemberCall { base, member, args } = &e.kind {
            if let Some(v) = self.interface_method_value(base, member, args, e.span)? {
                return Ok(v);
            }
        }
        match &e.kind {
            ExprKind::Literal(lit) => self.literal(lit, e),
            ExprKind::Name(id) => self.name(id, e),
            ExprKind::Member { base, member } if self.property(Some(base), member)?.is_some() => {
                let t = self.property(Some(base), member)?.expect("a property");
                self.property_get(t, member)
            }
            ExprKind::Address(_) | ExprKind::Member { .. } | ExprKind::Index { .. } => {
                let p = self.place(e)?;
                let size = self.u.type_size(&p.ty);
                Ok(read(p, size))
            }
            ExprKind::Call { callee, args } => self.call_value_at(callee, args, e.span),
            ExprKind::MemberCall { base, member, args } => match self.member_method(base, member)? {
                Some((t, k)) => self.method_value(t, k, args, e.span),
                None => Err(self.error(member.span, format!("an action call (`{}`) has no value", member.text))),
            },
            ExprKind::Unary { op, operand } => {
                let v = self.expr(operand, expected)?;
                match op {
                    UnaryOp::Plus => Ok(v),
                    UnaryOp::Neg => ops::neg(v, self.recorded(e), e.span),
                    UnaryOp::Not => ops::not(v, e.span),
                }
            }
            ExprKind::Binary { op, lhs, rhs }
                if [lhs, rhs].iter().any(|o| matches!(self.recorded(o), Some(Type::Pointer(_))))
                    && matches!(op, BinaryOp::Add | BinaryOp::Sub) =>
            {
                Err(self.error(
                    e.span,
                    "pointer arithmetic is not simulated: addresses here are variables, not bytes (index the pointer, `p[i]`, instead)",
                ))
            }
            ExprKind::Binary { op, lhs, rhs } => {
                let l = self.expr(lhs, None)?;
                let r = self.expr(rhs, Some(&l.ty))?;
                let rt = self.recorded(e).filter(|_| {
                    !matches!(
                        op,
                        BinaryOp::Eq | BinaryOp::Ne | BinaryOp::Lt | BinaryOp::Gt | BinaryOp::Le | BinaryOp::Ge
                    )
                });
                ops::binary(*op, l, r, rt, e.span)
            }
            ExprKind::Paren(inner) => self.expr(inner, expected),
            ExprKind::Deref(_) => {
                let p = self.place(e)?;
                let size = self.u.type_size(&p.ty);
                Ok(read(p, size))
            }
            ExprKind::Error => Err(self.error(e.span, "the expression has a syntax error")),
        }
    }

    /// Compiles an expression and converts it to `ty` (assignment, argument, condition).
    pub(crate) fn expr_as(&self, e: &Expr, ty: &Type) -> C<TExpr> {
        let v = self.expr(e, Some(ty))?;
        coerce(v, ty, e.span)
    }

    /// Compiles a BOOL condition.
    pub(crate) fn cond(&self, e: &Expr) -> C<BoolFn> {
        Ok(self.expr_as(e, &Type::Bool)?.bool())
    }

    fn literal(&self, lit: &Literal, e: &Expr) -> C<TExpr> {
        let rec = self.recorded(e);
        let prefix_ty = || lit.type_prefix.as_deref().and_then(Type::elementary);
        let v = match &lit.kind {
            LiteralKind::Int(v) => {
                let ty = rec.or_else(prefix_ty).unwrap_or(Type::DInt);
                return Ok(untyped_const(Untyped::Int(*v), &ty));
            }
            LiteralKind::Real(r) => {
                let ty = rec.or_else(prefix_ty).unwrap_or(Type::LReal);
                return Ok(untyped_const(Untyped::Real(*r), &ty));
            }
            LiteralKind::Bool(b) => (Value::Bool(*b), Type::Bool),
            LiteralKind::String { value, wide } => {
                let ty = if *wide { Type::WString { len: None } } else { Type::String { len: None } };
                (Value::Str(Arc::from(value.as_str())), ty)
            }
            LiteralKind::Duration(us) => {
                let ty = rec.filter(Type::is_duration).unwrap_or(Type::Time);
                let v = match super::matiec_time() {
                    true => crate::timespec::Timespec::from_literal(&lit.text)
                        .unwrap_or_else(|| crate::timespec::Timespec::from_us(*us))
                        .pack(),
                    false => *us,
                };
                (Value::Time(v), ty)
            }
            LiteralKind::Date(days) => (Value::Int(days.wrapping_mul(DAY_US)), Type::Date),
            LiteralKind::TimeOfDay(us) => (Value::Int(*us), Type::TimeOfDay),
            LiteralKind::DateAndTime(us) => (Value::Int(*us), Type::DateAndTime),
            LiteralKind::Enum(value) => {
                let ty = rec
                    .filter(Type::is_enum)
                    .or_else(|| lit.type_prefix.as_deref().and_then(|p| self.u.env.type_def(p)).map(|d| d.ty.clone()))
                    .ok_or_else(|| self.error(e.span, format!("unknown enumerated value `{}`", lit.text)))?;
                let n = ty
                    .enum_value(&value.text)
                    .ok_or_else(|| self.error(e.span, format!("unknown enumerated value `{}`", lit.text)))?;
                (Value::Int(n), ty)
            }
        };
        Ok(TExpr::constant(v.0, v.1))
    }

    fn name(&self, id: &Ident, e: &Expr) -> C<TExpr> {
        match self.lookup(&id.text) {
            Some(Sym::Var { place, ty, konst }) => {
                if let (Some(k), true) = (konst, kind_of(&ty) != Kind::Agg) {
                    return Ok(st_const(k, &ty));
                }
                let p = deref_reference(PlaceC::new(Loc::Static(place), ty), id.span);
                let size = self.u.type_size(&p.ty);
                Ok(read(p, size))
            }
            Some(Sym::Return) => {
                let p = self.place(e)?;
                let size = self.u.type_size(&p.ty);
                Ok(read(p, size))
            }
            Some(Sym::Step(_)) => Err(self.error(id.span, format!("`{}` is a step; read `{0}.X`", id.text))),
            Some(Sym::Action(_)) => Err(self.error(id.span, format!("`{}` is an action; read `{0}.Q`", id.text))),
            None if self.property(None, id)?.is_some() => {
                let t = self.property(None, id)?.expect("a property");
                self.property_get(t, id)
            }
            // `THIS`: the address of the block's own frame (its first slot, plus one).
            None if id.is("THIS") && matches!(self.recorded(e), Some(Type::Pointer(_))) => {
                let ty = self.recorded(e).unwrap_or(Type::Error);
                let at = Loc::Static(Place::Local(0)).slot_fn();
                let f: IntFn = Box::new(move |c, b| Ok(at(c, b)? as i64 + 1));
                Ok(TExpr::new(super::texpr::CExpr::Int(f), ty, false))
            }
            None => {
                let ty = self
                    .recorded(e)
                    .filter(|t| t.enum_value(&id.text).is_some())
                    .or_else(|| self.enum_type_with(&id.text))
                    .ok_or_else(|| self.error(id.span, format!("unknown name `{}`", id.text)))?;
                let n = ty.enum_value(&id.text).unwrap_or(0);
                Ok(TExpr::constant(Value::Int(n), ty))
            }
        }
    }

    /// The enumerated type that has a value of this name (inline types of the POU's variables
    /// first, then named and global ones).
    fn enum_type_with(&self, name: &str) -> Option<Type> {
        if let Some(m) = self.meta() {
            for v in &m.layout.vars {
                let t = match &v.ty {
                    Type::Array { elem, .. } => elem.as_ref(),
                    t => t,
                };
                if t.enum_value(name).is_some() {
                    return Some(t.clone());
                }
            }
        }
        self.u.env.enum_types_with_value(name).first().cloned()
    }

    /// Compiles an expression that denotes a place (to read or write).
    pub(crate) fn place(&self, e: &Expr) -> C<PlaceC> {
        match &e.kind {
            ExprKind::Name(id) => match self.lookup(&id.text) {
                Some(Sym::Var { place, ty, .. }) => Ok(deref_reference(PlaceC::new(Loc::Static(place), ty), id.span)),
                Some(Sym::Return) => {
                    let (off, ty) = self.meta().and_then(|m| m.result.clone()).expect("functions have a result slot");
                    Ok(PlaceC::new(Loc::Static(Place::Local(off)), ty))
                }
                Some(Sym::Step(_)) | Some(Sym::Action(_)) => {
                    Err(self.error(id.span, format!("`{}` is not a variable", id.text)))
                }
                None => Err(self.error(id.span, format!("`{}` is not a variable", id.text))),
            },
            ExprKind::Address(a) => Ok(self.address(a)),
            ExprKind::Paren(inner) => self.place(inner),
            ExprKind::Member { base, member } => self.member(base, member),
            ExprKind::Index { base, indices } => self.index(base, indices),
            ExprKind::Deref(inner) => {
                let p = self.place(inner)?;
                let Type::Pointer(t) = p.ty.clone() else {
                    return Err(
                        self.error(e.span, "`^` of what is no pointer (`THIS^` passed on is not simulated yet)")
                    );
                };
                Ok(PlaceC::new(Loc::Dyn(pointee(p.loc.slot_fn(), e.span)), *t))
            }
            _ => Err(self.error(e.span, "the expression is not a variable")),
        }
    }

    pub(crate) fn member(&self, base: &Expr, member: &Ident) -> C<PlaceC> {
        if let Some(p) = self.self_member(base, member)? {
            return Ok(p);
        }
        if let ExprKind::Name(id) = &base.kind {
            let m = self.meta();
            match (self.lookup(&id.text), m) {
                (Some(Sym::Step(i)), Some(m)) => {
                    return match member.text.to_ascii_uppercase().as_str() {
                        "X" | "_X" => Ok(PlaceC::new(Loc::Static(Place::Local(m.step_x[i])), Type::Bool)),
                        // S7-GRAPH's `U` (a POU marked `sfc.dialect 'graph'`): the step's time
                        // without disturbance, in its own slot.
                        "U" if m.step_members == super::StepMembers::Graph && m.step_vendor.get(i).is_some() => {
                            Ok(PlaceC::new(Loc::Static(Place::Local(m.step_vendor[i])), Type::Time))
                        }
                        "T" | "_T" | "U" => Ok(PlaceC::new(Loc::Static(Place::Local(m.step_t[i])), Type::Time)),
                        // Logix's members (a POU marked `sfc.dialect 'logix'`).
                        "COUNT" | "FS" | "SA" | "LS" | "TMAX"
                            if m.step_members == super::StepMembers::Logix && m.step_vendor.get(i).is_some() =>
                        {
                            let (k, ty) = logix_member(&member.text);
                            Ok(PlaceC::new(Loc::Static(Place::Local(m.step_vendor[i] + k)), ty))
                        }
                        _ => Err(self.error(member.span, format!("steps have no member `{}`", member.text))),
                    };
                }
                (None, Some(m)) if id.text.starts_with('_') => {
                    // CODESYS's `_<action>.x` (executed: `A`) and `_<action>._x` (active: `Q`).
                    if let Some(Sym::Action(i)) = self.lookup(&id.text[1..]) {
                        if let (Some(&q), Some(&a)) = (m.action_q.get(i), m.action_a.get(i)) {
                            return match member.text.to_ascii_uppercase().as_str() {
                                "X" => Ok(PlaceC::new(Loc::Static(Place::Local(a)), Type::Bool)),
                                "_X" => Ok(PlaceC::new(Loc::Static(Place::Local(q)), Type::Bool)),
                                _ => {
                                    Err(self
                                        .error(member.span, format!("`{}` has no member `{}`", id.text, member.text)))
                                }
                            };
                        }
                    }
                }
                (Some(Sym::Action(i)), Some(m)) => {
                    // A POU that is no chart has no action control: its actions run when called.
                    let (Some(&q), Some(&a)) = (m.action_q.get(i), m.action_a.get(i)) else {
                        return Err(self.error(
                            member.span,
                            format!(
                                "`{}` is an action of a POU that is no chart: it has no `{}`",
                                id.text, member.text
                            ),
                        ));
                    };
                    return match member.text.to_ascii_uppercase().as_str() {
                        "Q" => Ok(PlaceC::new(Loc::Static(Place::Local(q)), Type::Bool)),
                        "A" => Ok(PlaceC::new(Loc::Static(Place::Local(a)), Type::Bool)),
                        _ => Err(self.error(member.span, format!("actions have no member `{}`", member.text))),
                    };
                }
                _ => {}
            }
        }
        let pb = self.place(base)?;
        if pb.bit.is_some() {
            return Err(self.error(member.span, "a bit has no members"));
        }
        // Partial access (IEC 61131-3 3rd edition): `w.%X3` is the bit `w.3`, `d.%B1` the byte
        // from bit 8, `d.%W1` the word from bit 16, `l.%D1` the double word from bit 32.
        let (digits, bits, ty) = match member.text.strip_prefix('%').map(|r| r.split_at(r.len().min(1))) {
            Some((k, d)) => match k.to_ascii_uppercase().as_str() {
                "X" => (d, 1, Type::Bool),
                "B" => (d, 8, Type::Byte),
                "W" => (d, 16, Type::Word),
                "D" => (d, 32, Type::DWord),
                _ => return Err(self.error(member.span, format!("partial access `.{}`", member.text))),
            },
            None => (member.text.as_str(), 1, Type::Bool),
        };
        if !digits.is_empty() && digits.bytes().all(|b| b.is_ascii_digit()) {
            let k: u32 = digits.parse().unwrap_or(0);
            let w = W::of(&pb.ty);
            return Ok(PlaceC { loc: pb.loc, ty, bit: Some(k.saturating_mul(bits)), bit_w: w, bits });
        }
        match &pb.ty {
            Type::Struct { fields, .. } => {
                let mut off = 0;
                for (n, t) in fields {
                    if n.eq_ignore_ascii_case(&member.text) {
                        return Ok(PlaceC::new(pb.loc.offset(off), t.clone()));
                    }
                    off += self.u.type_size(t);
                }
                Err(self.error(member.span, format!("`{}` has no field `{}`", pb.ty, member.text)))
            }
            Type::FunctionBlock(fb) => {
                let (off, ty, _) = self
                    .u
                    .fb_param(fb, &member.text)
                    .ok_or_else(|| self.error(member.span, format!("`{fb}` has no member `{}`", member.text)))?;
                Ok(PlaceC::new(pb.loc.offset(off), ty))
            }
            t => Err(self.error(member.span, format!("`{t}` has no member `{}`", member.text))),
        }
    }

    fn index(&self, base: &Expr, indices: &[Expr]) -> C<PlaceC> {
        // `p[i]` (CODESYS): the `i`-th element of the pointed type from `p`.
        if let (Some(Type::Pointer(t)), [i]) = (self.recorded(base), indices) {
            let at = pointee(self.place(base)?.loc.slot_fn(), base.span);
            let size = self.u.type_size(&t) as i64;
            let k = self.expr_as(i, &Type::LInt)?.int();
            let span = i.span;
            let loc: LocFn = Arc::new(move |c, b| {
                let s = at(c, b)? as i64 + k(c, b)?.saturating_mul(size);
                if s < 0 || s as usize >= c.mem.len() {
                    return Err(fault("a pointer indexed beyond the variables", span));
                }
                Ok(s as usize)
            });
            return Ok(PlaceC::new(Loc::Dyn(loc), *t));
        }
        let pb = self.place(base)?;
        let Type::Array { dims, elem } = &pb.ty else {
            return Err(self.error(base.span, format!("`{}` is not an array", pb.ty)));
        };
        if dims.len() != indices.len() || pb.bit.is_some() {
            return Err(self.error(base.span, "wrong number of indices"));
        }
        let esize = self.u.type_size(elem) as i64;
        let mut strides = vec![esize; dims.len()];
        for k in (0..dims.len().saturating_sub(1)).rev() {
            let (lo, hi) = dims[k + 1];
            strides[k] = strides[k + 1] * (hi - lo + 1);
        }
        let mut fixed: i64 = 0;
        let mut dynamic: Vec<(IntFn, i64, i64, i64, sfc_diagnostics::Span)> = Vec::new();
        for ((idx, &(lo, hi)), &stride) in indices.iter().zip(dims).zip(&strides) {
            let v = self.expr(idx, Some(&Type::DInt))?;
            let w = W::of(&v.ty);
            match v.const_value() {
                Some(c) => {
                    let i = int_of(&c);
                    if i < lo || i > hi {
                        return Err(self.error(idx.span, format!("index {i} is out of range {lo}..{hi}")));
                    }
                    fixed += (i - lo) * stride;
                }
                None => {
                    let f = v.int();
                    let f: IntFn = if w == W::U64 {
                        Box::new(move |c, b| {
                            // A ULINT index above i64::MAX is out of every range.
                            let v = f(c, b)?;
                            Ok(if v < 0 { i64::MAX } else { v })
                        })
                    } else {
                        f
                    };
                    dynamic.push((f, lo, hi, stride, idx.span));
                }
            }
        }
        let elem_ty = (**elem).clone();
        if dynamic.is_empty() {
            return Ok(PlaceC::new(pb.loc.offset(fixed as u32), elem_ty));
        }
        let base_slot = pb.loc.offset(fixed as u32).slot_fn();
        let loc: LocFn = if dynamic.len() == 1 {
            let (f, lo, hi, stride, span) = dynamic.pop().expect("one index");
            Arc::new(move |c, b| {
                let i = f(c, b)?;
                if i < lo || i > hi {
                    return Err(fault(format!("array index {i} is out of range {lo}..{hi}"), span));
                }
                Ok(base_slot(c, b)? + ((i - lo) * stride) as usize)
            })
        } else {
            Arc::new(move |c, b| {
                let mut s = base_slot(c, b)?;
                for (f, lo, hi, stride, span) in &dynamic {
                    let i = f(c, b)?;
                    if i < *lo || i > *hi {
                        return Err(fault(format!("array index {i} is out of range {lo}..{hi}"), *span));
                    }
                    s += ((i - lo) * stride) as usize;
                }
                Ok(s)
            })
        };
        Ok(PlaceC::new(Loc::Dyn(loc), elem_ty))
    }

    /// A direct address used in code: the located variable of the POU or a global with that
    /// address, else a global slot allocated for the address on first sight.
    /// A global slot of its own holding `v` (`ADR('text')`: the literal kept in memory).
    pub(crate) fn literal_slot(&self, v: Value, ty: &Type) -> PlaceC {
        let mut g = self.u.globals.borrow_mut();
        let slot = g.layout.size;
        g.layout.size += 1;
        g.template.push(v);
        PlaceC::new(Loc::Static(Place::Global(slot)), ty.clone())
    }

    pub(crate) fn address(&self, a: &DirectAddress) -> PlaceC {
        let key = a.text.to_ascii_uppercase();
        let ty = match a.size.to_ascii_uppercase() {
            'B' => Type::Byte,
            'W' => Type::Word,
            'D' => Type::DWord,
            'L' => Type::LWord,
            _ => Type::Bool,
        };
        if let Some(m) = self.meta() {
            if let Some(v) =
                m.layout.vars.iter().find(|v| v.location.as_deref().is_some_and(|l| l.eq_ignore_ascii_case(&key)))
            {
                if v.size == 1 {
                    return PlaceC::new(Loc::Static(Place::Local(v.offset)), v.ty.clone());
                }
            }
        }
        let mut g = self.u.globals.borrow_mut();
        if let Some(v) =
            g.layout.vars.iter().find(|v| v.location.as_deref().is_some_and(|l| l.eq_ignore_ascii_case(&key)))
        {
            if v.size == 1 {
                return PlaceC::new(Loc::Static(Place::Global(v.offset)), v.ty.clone());
            }
        }
        if let Some(&slot) = g.addresses.get(&key) {
            return PlaceC::new(Loc::Static(Place::Global(slot)), ty);
        }
        let slot = g.layout.size;
        g.layout.size += 1;
        g.template.push(default_value(&ty));
        g.layout.vars.push(VarSlot {
            name: a.text.clone(),
            ty: ty.clone(),
            kind: VarKind::Global,
            offset: slot,
            size: 1,
            location: Some(a.text.clone()),
            implicit: true,
            retain: false,
            persistent: false,
        });
        let n = g.layout.vars.len() - 1;
        g.index.insert(key.clone(), n);
        g.addresses.insert(key, slot);
        PlaceC::new(Loc::Static(Place::Global(slot)), ty)
    }
}

/// The slot a pointer or reference held in the slot `at` designates: its value is that slot
/// plus one, 0 for none (a fault when used).
pub(crate) fn pointee(at: LocFn, span: sfc_diagnostics::Span) -> LocFn {
    std::sync::Arc::new(move |c, b| {
        let s = at(c, b)?;
        match int_of(&c.mem[s]) {
            v if v > 0 && (v as usize) <= c.mem.len() => Ok(v as usize - 1),
            0 => Err(fault("a pointer or reference that designates nothing (0) is used", span)),
            v => Err(fault(format!("a pointer or reference designates no variable ({v})"), span)),
        }
    })
}

/// A variable of type `REFERENCE TO T` is read and written as the `T` it designates.
pub(crate) fn deref_reference(p: PlaceC, span: sfc_diagnostics::Span) -> PlaceC {
    match p.ty.clone() {
        Type::Reference(t) => PlaceC::new(Loc::Dyn(pointee(p.loc.slot_fn(), span)), *t),
        _ => p,
    }
}

/// A Logix step member's offset among the step's Logix slots (`Count`, `FS`, `SA`, `LS`,
/// `TMax`) and its type.
pub(crate) fn logix_member(member: &str) -> (u32, Type) {
    match member.to_ascii_uppercase().as_str() {
        "FS" => (1, Type::Bool),
        "SA" => (2, Type::Bool),
        "LS" => (3, Type::Bool),
        "TMAX" => (4, Type::DInt),
        _ => (0, Type::DInt),
    }
}
