//! Compiling ST statements.

use super::place::{write, Loc, PlaceC};
use super::rt::*;
use super::unit::{Cx, Sym, C};
use super::Block;
use crate::value::Value;
use sfc_st::Type;
use sfc_syntax::ast::{CaseArm, CaseLabel, Expr, ExprKind, Ident, Stmt, StmtKind};

/// Runs statements in order, stopping at EXIT or RETURN.
pub(crate) fn seq(mut v: Vec<StmtFn>) -> StmtFn {
    match v.len() {
        0 => Box::new(|_, _| Ok(Flow::Next)),
        1 => v.pop().expect("one statement"),
        _ => Box::new(move |c, b| {
            for s in &v {
                let f = s(c, b)?;
                if f != Flow::Next {
                    return Ok(f);
                }
            }
            Ok(Flow::Next)
        }),
    }
}

/// A statement list as a POU or action body (RETURN ends it).
pub(crate) fn to_block(mut v: Vec<StmtFn>) -> Block {
    match v.len() {
        0 => Box::new(|_, _| Ok(())),
        1 => {
            let s = v.pop().expect("one statement");
            Box::new(move |c, b| match s(c, b) {
                Ok(_) => Ok(()),
                Err(e) => Err(*e),
            })
        }
        _ => Box::new(move |c, b| {
            for s in &v {
                match s(c, b) {
                    Ok(Flow::Next) => {}
                    Ok(_) => break,
                    Err(e) => return Err(*e),
                }
            }
            Ok(())
        }),
    }
}

impl Cx<'_, '_> {
    pub(crate) fn stmts(&self, list: &[Stmt]) -> C<StmtFn> {
        Ok(seq(self.stmt_list(list)?))
    }

    /// The statements of a list, compiled one by one (empty statements dropped).
    pub(crate) fn stmt_list(&self, list: &[Stmt]) -> C<Vec<StmtFn>> {
        let mut out = Vec::with_capacity(list.len());
        for s in list {
            if matches!(s.kind, StmtKind::Empty) {
                continue;
            }
            out.push(self.stmt(s)?);
        }
        Ok(out)
    }

    fn stmt(&self, s: &Stmt) -> C<StmtFn> {
        match &s.kind {
            StmtKind::Assign { target, value } => {
                // A property written through an interface: the SET of the designated instance.
                if let ExprKind::Member { base, member } = &target.kind {
                    if let Some(f) = self.interface_set(base, member, value, s.span)? {
                        return Ok(f);
                    }
                }
                // A property written: its SET runs.
                let prop = match &target.kind {
                    ExprKind::Member { base, member } => self.property(Some(base), member)?.map(|t| (t, member)),
                    ExprKind::Name(id) if self.lookup(&id.text).is_none() => self.property(None, id)?.map(|t| (t, id)),
                    _ => None,
                };
                if let Some((t, name)) = prop {
                    return self.property_set(t, name, value, s.span);
                }
                let p = self.place(target)?;
                let v = self.expr_as(value, &p.ty)?;
                let size = self.u.type_size(&p.ty);
                Ok(write(p, v, size))
            }
            StmtKind::Call(e) => self.call_stmt(e),
            StmtKind::If { branches, else_body } => {
                let mut bs = Vec::new();
                for (c, body) in branches {
                    bs.push((self.cond(c)?, self.stmts(body)?));
                }
                let els = match else_body {
                    Some(b) => Some(self.stmts(b)?),
                    None => None,
                };
                if bs.len() == 1 {
                    let (c, t) = bs.pop().expect("one branch");
                    return Ok(match els {
                        None => Box::new(move |x, b| if c(x, b)? { t(x, b) } else { Ok(Flow::Next) }),
                        Some(e) => Box::new(move |x, b| if c(x, b)? { t(x, b) } else { e(x, b) }),
                    });
                }
                Ok(Box::new(move |x, b| {
                    for (c, t) in &bs {
                        if c(x, b)? {
                            return t(x, b);
                        }
                    }
                    match &els {
                        Some(e) => e(x, b),
                        None => Ok(Flow::Next),
                    }
                }))
            }
            StmtKind::Case { selector, arms, else_body } => self.case(selector, arms, else_body.as_deref()),
            StmtKind::For { var, from, to, by, body } => self.for_loop(var, from, to, by.as_deref(), body, s),
            StmtKind::While { cond, body } => {
                let c = self.cond(cond)?;
                let body = self.stmts(body)?;
                let span = s.span;
                Ok(Box::new(move |x, b| {
                    while c(x, b)? {
                        x.budget.charge(span)?;
                        match body(x, b)? {
                            Flow::Next => {}
                            Flow::Exit => break,
                            Flow::Return => return Ok(Flow::Return),
                        }
                    }
                    Ok(Flow::Next)
                }))
            }
            StmtKind::Repeat { body, until } => {
                let c = self.cond(until)?;
                let body = self.stmts(body)?;
                let span = s.span;
                Ok(Box::new(move |x, b| {
                    loop {
                        x.budget.charge(span)?;
                        match body(x, b)? {
                            Flow::Next => {}
                            Flow::Exit => break,
                            Flow::Return => return Ok(Flow::Return),
                        }
                        if c(x, b)? {
                            break;
                        }
                    }
                    Ok(Flow::Next)
                }))
            }
            StmtKind::Exit => Ok(Box::new(|_, _| Ok(Flow::Exit))),
            StmtKind::Return => Ok(Box::new(|_, _| Ok(Flow::Return))),
            StmtKind::Empty => Ok(Box::new(|_, _| Ok(Flow::Next))),
            // `r REF= x`: the reference's own slot gets the address of `x` (plus one).
            StmtKind::RefAssign { target, value } => {
                let ExprKind::Name(id) = &target.kind else {
                    return Err(self.error(target.span, "`REF=` of what is no variable"));
                };
                let Some(Sym::Var { place, .. }) = self.lookup(&id.text) else {
                    return Err(self.error(target.span, "`REF=` of what is no variable"));
                };
                let at = Loc::Static(place).slot_fn();
                let of = self.place(value)?.loc.slot_fn();
                Ok(Box::new(move |c, b| {
                    let slot = of(c, b)?;
                    let s = at(c, b)?;
                    c.mem[s] = Value::Int(slot as i64 + 1);
                    Ok(Flow::Next)
                }))
            }
        }
    }

    fn case(&self, selector: &Expr, arms: &[CaseArm], else_body: Option<&[Stmt]>) -> C<StmtFn> {
        let sel = self.expr(selector, None)?;
        let sel_ty = sel.ty.clone();
        let w = W::of(&sel_ty);
        let sf = sel.int();
        let label = |e: &Expr| -> C<i128> {
            let v = self.expr_as(e, &sel_ty).or_else(|_| self.expr(e, Some(&sel_ty)))?;
            let c = v.const_value().ok_or_else(|| self.error(e.span, "a CASE label must be a constant"))?;
            Ok(w.wide(int_of(&c)))
        };
        let mut compiled: Vec<(Vec<(i128, i128)>, StmtFn)> = Vec::new();
        for arm in arms {
            let mut ranges = Vec::new();
            for l in &arm.labels {
                match l {
                    CaseLabel::Value(e) => {
                        let v = label(e)?;
                        ranges.push((v, v));
                    }
                    CaseLabel::Range(a, b) => ranges.push((label(a)?, label(b)?)),
                }
            }
            compiled.push((ranges, self.stmts(&arm.body)?));
        }
        let els = match else_body {
            Some(b) => Some(self.stmts(b)?),
            None => None,
        };
        Ok(Box::new(move |x, b| {
            let v = w.wide(sf(x, b)?);
            for (ranges, body) in &compiled {
                if ranges.iter().any(|(lo, hi)| *lo <= v && v <= *hi) {
                    return body(x, b);
                }
            }
            match &els {
                Some(e) => e(x, b),
                None => Ok(Flow::Next),
            }
        }))
    }

    /// `FOR v := a TO b BY s`: the bound and the step are evaluated once; the variable is
    /// incremented (wrapping in its type) after each run of the body and tested before each;
    /// after the loop it holds the first value past the bound (or its value at EXIT).
    fn for_loop(&self, var: &Ident, from: &Expr, to: &Expr, by: Option<&Expr>, body: &[Stmt], s: &Stmt) -> C<StmtFn> {
        let Some(Sym::Var { place, ty, .. }) = self.lookup(&var.text) else {
            return Err(self.error(var.span, format!("the FOR variable `{}` is not a variable", var.text)));
        };
        let w = W::of(&ty);
        let start = self.expr_as(from, &ty)?.int();
        let end = self.expr_as(to, &ty)?.int();
        let step: IntFn = match by {
            Some(e) => self.expr_as(e, &ty)?.int(),
            None => Box::new(|_, _| Ok(1)),
        };
        let body = self.stmts(body)?;
        let slot = PlaceC::new(Loc::Static(place), Type::Bool).loc.slot_fn();
        let span = s.span;
        Ok(Box::new(move |x, b| {
            let i0 = start(x, b)?;
            let end = w.wide(end(x, b)?);
            let step_v = step(x, b)?;
            let step = w.wide(step_v);
            let at = slot(x, b)?;
            x.mem[at] = Value::Int(i0);
            loop {
                let i = w.wide(int_of(&x.mem[at]));
                if (step >= 0 && i > end) || (step < 0 && i < end) {
                    break;
                }
                x.budget.charge(span)?;
                match body(x, b)? {
                    Flow::Next => {}
                    Flow::Exit => break,
                    Flow::Return => return Ok(Flow::Return),
                }
                let cur = int_of(&x.mem[at]);
                x.mem[at] = Value::Int(w.wrap(cur.wrapping_add(step_v)));
            }
            Ok(Flow::Next)
        }))
    }
}
