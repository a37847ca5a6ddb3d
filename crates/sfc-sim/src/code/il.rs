//! Instruction List: the current result (CR) lives in a hidden scratch slot of the frame (one per
//! nesting level of parentheses); each instruction is compiled to a closure that returns where
//! to go next. The CR's type is tracked at compile time, as the checker does.

use super::convert::coerce;
use super::expr::{natural, untyped, untyped_const, Untyped};
use super::ops;
use super::place::{read, write, Loc, PlaceC};
use super::rt::*;
use super::texpr::TExpr;
use super::unit::{Cx, Sym, C};
use super::{Ctx, Place};
use crate::value::Value;
use sfc_diagnostics::Span;
use sfc_st::{parse_il_op as parse_op, IlOp as Op, Type};
use sfc_syntax::ast::{Expr, ExprKind, IlBody, IlInstruction};
use std::collections::HashMap;

pub(crate) enum IlNext {
    Next,
    Jump(usize),
    Ret,
}

pub(crate) type IlStep = Box<dyn Fn(&mut Ctx<'_>, usize) -> R<IlNext> + Send + Sync>;

/// The current result as known at compile time.
#[derive(Debug, Clone)]
pub(crate) enum Cr {
    None,
    Typed(Type),
    /// `LD 5`: a constant that still takes the type of where it goes.
    Untyped(Untyped),
}

/// Runs an instruction list; every jump is charged to the scan's budget.
pub(crate) fn run_il(steps: &[IlStep], c: &mut Ctx<'_>, b: usize, span: Span) -> R<()> {
    let mut pc = 0;
    while pc < steps.len() {
        match steps[pc](c, b)? {
            IlNext::Next => pc += 1,
            IlNext::Jump(t) => {
                c.budget.charge(span)?;
                pc = t;
            }
            IlNext::Ret => break,
        }
    }
    Ok(())
}

/// An operand: compiled, or an untyped constant that takes the type of the current result.
enum Operand {
    Val(TExpr),
    Untyped(Untyped),
}

fn stmt_step(s: StmtFn) -> IlStep {
    Box::new(move |c, b| {
        s(c, b)?;
        Ok(IlNext::Next)
    })
}

impl Cx<'_, '_> {
    fn cr_place(&self, depth: u32, ty: Type, span: Span) -> C<PlaceC> {
        let m = self.meta().ok_or_else(|| self.error(span, "IL outside a POU"))?;
        if depth >= m.il_slots {
            return Err(self.error(span, "IL nested too deeply"));
        }
        Ok(PlaceC::new(Loc::Static(Place::Local(m.il_base + depth)), ty))
    }

    /// The current result as an expression (an untyped constant takes `want`).
    fn cr_value(&self, cr: &Cr, depth: u32, want: Option<&Type>, span: Span) -> C<TExpr> {
        match cr {
            Cr::None => Err(self.error(span, "the instruction needs a current result")),
            Cr::Typed(t) => Ok(read(self.cr_place(depth, t.clone(), span)?, 1)),
            Cr::Untyped(u) => Ok(untyped_const(*u, &want.cloned().unwrap_or_else(|| natural(*u)))),
        }
    }

    /// Stores `v` as the new current result.
    fn set_cr(&self, v: TExpr, depth: u32, span: Span) -> C<(IlStep, Cr)> {
        let ty = v.ty.clone();
        let p = self.cr_place(depth, ty.clone(), span)?;
        Ok((stmt_step(write(p, v, 1)), Cr::Typed(ty)))
    }

    /// Compiles an IL body: the steps and the final current result.
    pub(crate) fn il(&self, body: &IlBody) -> C<(Vec<IlStep>, Cr)> {
        self.il_list(&body.instructions, 0, Cr::None)
    }

    /// An IL body as a POU or action body.
    pub(crate) fn il_block(&self, body: &IlBody) -> C<super::Block> {
        let (steps, _) = self.il(body)?;
        let span = body.span;
        Ok(Box::new(move |c, b| run_il(&steps, c, b, span).map_err(|e| *e)))
    }

    /// An IL transition condition: the current result at the end.
    pub(crate) fn il_guard(&self, body: &IlBody) -> C<BoolFn> {
        let (steps, cr) = self.il(body)?;
        let span = body.span;
        let v = self.cr_value(&cr, 0, Some(&Type::Bool), span)?.bool();
        Ok(Box::new(move |c, b| {
            run_il(&steps, c, b, span)?;
            v(c, b)
        }))
    }

    fn il_list(&self, instrs: &[IlInstruction], depth: u32, start: Cr) -> C<(Vec<IlStep>, Cr)> {
        let mut labels: HashMap<String, usize> = HashMap::new();
        for (i, ins) in instrs.iter().enumerate() {
            if let Some(l) = &ins.label {
                labels.entry(l.key()).or_insert(i);
            }
        }
        let mut jump_cr: HashMap<usize, Cr> = HashMap::new();
        let mut steps: Vec<IlStep> = Vec::with_capacity(instrs.len());
        let mut cr = start;
        for (i, ins) in instrs.iter().enumerate() {
            if ins.label.is_some() {
                if matches!(cr, Cr::None) {
                    if let Some(j) = jump_cr.get(&i) {
                        cr = j.clone();
                    }
                }
                if let Cr::Untyped(u) = cr {
                    cr = Cr::Typed(natural(u));
                }
            }
            let Some(op) = &ins.op else {
                steps.push(Box::new(|_, _| Ok(IlNext::Next)));
                continue;
            };
            let (step, next) = self.il_instruction(ins, op, cr, depth, &labels, &mut jump_cr)?;
            steps.push(step);
            cr = next;
        }
        Ok((steps, cr))
    }

    /// The operand of an instruction (a parenthesised list counts as one).
    fn il_operand(&self, ins: &IlInstruction, depth: u32, hint: Option<&Type>) -> C<Operand> {
        if let Some(nested) = &ins.nested {
            let mut pre: Vec<IlStep> = Vec::new();
            let start = match ins.operands.first() {
                None => Cr::None,
                Some(e) => match untyped(e) {
                    Some(u) => {
                        let v = untyped_const(u, &natural(u));
                        let (s, _) = self.set_cr(v, depth + 1, e.span)?;
                        pre.push(s);
                        Cr::Untyped(u)
                    }
                    None => {
                        let v = self.expr(e, None)?;
                        let (s, c) = self.set_cr(v, depth + 1, e.span)?;
                        pre.push(s);
                        c
                    }
                },
            };
            let (mut steps, cr) = self.il_list(nested, depth + 1, start)?;
            pre.append(&mut steps);
            let span = ins.span;
            let val = self.cr_value(&cr, depth + 1, hint, span)?;
            let ty = val.ty.clone();
            let v = val.value();
            let run: ValFn = Box::new(move |c, b| {
                run_il(&pre, c, b, span)?;
                v(c, b)
            });
            return Ok(Operand::Val(TExpr::from_val(ty, run, false)));
        }
        let [e] = ins.operands.as_slice() else {
            return Err(self.error(ins.span, "the instruction needs exactly one operand"));
        };
        match untyped(e) {
            Some(u) if self.recorded(e).is_none() => Ok(Operand::Untyped(u)),
            _ => Ok(Operand::Val(self.expr(e, hint)?)),
        }
    }

    #[allow(clippy::too_many_arguments)]
    fn il_instruction(
        &self,
        ins: &IlInstruction,
        op_ident: &sfc_syntax::ast::Ident,
        cr: Cr,
        depth: u32,
        labels: &HashMap<String, usize>,
        jump_cr: &mut HashMap<usize, Cr>,
    ) -> C<(IlStep, Cr)> {
        let span = ins.span;
        let Some((op, negate, conditional)) = parse_op(&op_ident.text) else {
            return self.il_function(ins, op_ident, cr, depth);
        };
        let cond = |this: &Self| -> C<Option<BoolFn>> {
            if !conditional {
                return Ok(None);
            }
            let c = this.cr_value(&cr, depth, Some(&Type::Bool), span)?.bool();
            Ok(Some(if negate { Box::new(move |x, b| Ok(!c(x, b)?)) } else { c }))
        };
        match op {
            Op::Ld => {
                let v = self.il_operand(ins, depth, None)?;
                match v {
                    Operand::Untyped(u) if !negate => {
                        let (s, _) = self.set_cr(untyped_const(u, &natural(u)), depth, span)?;
                        Ok((s, Cr::Untyped(u)))
                    }
                    Operand::Untyped(u) => {
                        let v = ops::not(untyped_const(u, &natural(u)), span)?;
                        self.set_cr(v, depth, span)
                    }
                    Operand::Val(v) => {
                        let v = if negate { ops::not(v, span)? } else { v };
                        self.set_cr(v, depth, span)
                    }
                }
            }
            Op::St | Op::Set | Op::Reset => {
                let [target] = ins.operands.as_slice() else {
                    return Err(self.error(span, "the instruction needs one variable"));
                };
                let p = self.place(target)?;
                let size = self.u.type_size(&p.ty);
                if op == Op::St {
                    let mut v = self.cr_value(&cr, depth, Some(&p.ty), span)?;
                    if negate {
                        v = ops::not(v, span)?;
                    }
                    let v = coerce(v, &p.ty, span)?;
                    return Ok((stmt_step(write(p, v, size)), cr));
                }
                let c = self.cr_value(&cr, depth, Some(&Type::Bool), span)?.bool();
                let w = write(p, TExpr::constant(Value::Bool(op == Op::Set), Type::Bool), size);
                let step: IlStep = Box::new(move |x, b| {
                    if c(x, b)? {
                        w(x, b)?;
                    }
                    Ok(IlNext::Next)
                });
                Ok((step, cr))
            }
            Op::Binary(bop) => {
                let hint = match &cr {
                    Cr::Typed(t) => Some(t.clone()),
                    _ => None,
                };
                let r = self.il_operand(ins, depth, hint.as_ref())?;
                let (l, r) = match (r, &cr) {
                    (Operand::Val(r), _) => {
                        let l = self.cr_value(&cr, depth, Some(&r.ty), span)?;
                        (l, r)
                    }
                    (Operand::Untyped(u), Cr::Typed(t)) => {
                        let l = self.cr_value(&cr, depth, None, span)?;
                        let rt = if kind_of(t) == Kind::Bool || t.is_duration() || t.is_date() {
                            natural(u)
                        } else {
                            t.clone()
                        };
                        (l, untyped_const(u, &rt))
                    }
                    (Operand::Untyped(u), _) => {
                        let l = self.cr_value(&cr, depth, None, span)?;
                        let ty = l.ty.clone();
                        (l, untyped_const(u, &ty))
                    }
                };
                let r = if negate { ops::not(r, span)? } else { r };
                let v = ops::binary(bop, l, r, None, span)?;
                self.set_cr(v, depth, span)
            }
            Op::Not => {
                let v = ops::not(self.cr_value(&cr, depth, None, span)?, span)?;
                self.set_cr(v, depth, span)
            }
            Op::Jmp => {
                let target = match ins.operands.as_slice() {
                    [Expr { kind: ExprKind::Name(l), .. }] => *labels
                        .get(&l.key())
                        .ok_or_else(|| self.error(l.span, format!("jump to unknown label `{}`", l.text)))?,
                    _ => return Err(self.error(span, "a jump needs a label")),
                };
                if !matches!(cr, Cr::None) {
                    let c = match &cr {
                        Cr::Untyped(u) => Cr::Typed(natural(*u)),
                        c => c.clone(),
                    };
                    jump_cr.entry(target).or_insert(c);
                }
                match cond(self)? {
                    None => Ok((Box::new(move |_, _| Ok(IlNext::Jump(target))), Cr::None)),
                    Some(c) => {
                        let step: IlStep =
                            Box::new(move |x, b| Ok(if c(x, b)? { IlNext::Jump(target) } else { IlNext::Next }));
                        Ok((step, cr))
                    }
                }
            }
            Op::Cal => {
                let Some(Expr { kind: ExprKind::Name(name), .. }) = ins.operands.first() else {
                    return Err(self.error(span, "CAL needs a function block instance"));
                };
                let Some(Sym::Var { place, ty, .. }) = self.lookup(&name.text) else {
                    return Err(self.error(name.span, format!("`{}` is not a function block instance", name.text)));
                };
                let args = ins.call_args.as_deref().unwrap_or(&[]);
                let call = self.fb_call(name, super::call::static_place(place, ty), args, span)?;
                let c = cond(self)?;
                let step: IlStep = match c {
                    None => stmt_step(call),
                    Some(c) => Box::new(move |x, b| {
                        if c(x, b)? {
                            call(x, b)?;
                        }
                        Ok(IlNext::Next)
                    }),
                };
                Ok((step, Cr::None))
            }
            Op::Ret => match cond(self)? {
                None => Ok((Box::new(|_, _| Ok(IlNext::Ret)), Cr::None)),
                Some(c) => {
                    let step: IlStep = Box::new(move |x, b| Ok(if c(x, b)? { IlNext::Ret } else { IlNext::Next }));
                    Ok((step, cr))
                }
            },
        }
    }

    /// A function used as an operator: `LD a  MAX b` is `MAX(a, b)`; with formal arguments,
    /// a plain call.
    fn il_function(&self, ins: &IlInstruction, name: &sfc_syntax::ast::Ident, cr: Cr, depth: u32) -> C<(IlStep, Cr)> {
        let span = ins.span;
        if let Some(args) = &ins.call_args {
            let v = self.call_value_at(name, args, span)?;
            return self.set_cr(v, depth, span);
        }
        if let Some(fi) = self.u.function(&name.text) {
            let params: Vec<Type> = self.u.pous[fi]
                .layout
                .vars
                .iter()
                .filter(|v| matches!(v.kind, sfc_syntax::ast::VarKind::Input | sfc_syntax::ast::VarKind::InOut))
                .map(|v| v.ty.clone())
                .collect();
            let first = params.first().cloned();
            let mut vals = vec![self.cr_value(&cr, depth, first.as_ref(), span)?];
            for (e, t) in ins.operands.iter().zip(params.iter().skip(1)) {
                vals.push(self.expr_as(e, t)?);
            }
            let v = self.func_call_values(fi, vals, span)?;
            return self.set_cr(v, depth, span);
        }
        if let Some(f) = sfc_st::stdlib::std_function(&name.text) {
            let first = self.cr_value(&cr, depth, None, span)?;
            let hint = first.ty.clone();
            let mut vals = vec![first];
            for (i, e) in ins.operands.iter().enumerate() {
                let h = match f.param_type(i + 1) {
                    Some(sfc_st::stdlib::ParamType::Fixed(t)) => Some(t.clone()),
                    Some(sfc_st::stdlib::ParamType::Same(_)) => Some(hint.clone()),
                    _ => None,
                };
                let mut v = self.expr(e, h.as_ref())?;
                if let Some(sfc_st::stdlib::ParamType::Fixed(t)) = f.param_type(i + 1) {
                    v = coerce(v, t, e.span)?;
                }
                vals.push(v);
            }
            let v = super::stdfn::apply(&f, vals, None, span)?;
            return self.set_cr(v, depth, span);
        }
        Err(self.error(name.span, format!("unknown IL operator `{}`", name.text)))
    }
}
