//! Instruction List: the current result (CR) as a symbolic value, forward jumps as path
//! conditions (a label's CR merges the CRs of the paths reaching it). Backward jumps (loops)
//! are not modelled: what the list writes becomes free.

use super::expr::{ExprError, Frame, PlaceRef, R, SV};
use super::Enc;
use crate::aig::Lit;
use sfc_st::{parse_il_op, IlOp, Type};
use sfc_syntax::ast::{Expr, ExprKind, IlBody, IlInstruction};
use std::collections::HashMap;

impl<'a> Enc<'a> {
    /// An IL body of an action or a POU.
    pub(crate) fn exec_il(&mut self, f: &Frame, il: &IlBody) {
        if let Err(e) = self.il_list(f, &il.instructions, None) {
            let (line, _) = super::stmt::line_col(&self.checked.file.text, il.span.start as usize);
            self.note(format!("the IL at line {line} is not modelled ({}); what it writes is free", e.message));
            self.havoc_il(f, &il.instructions);
        }
    }

    /// An IL transition condition: the CR at the end.
    pub(crate) fn il_condition(&mut self, f: &Frame, il: &IlBody) -> R<Lit> {
        let cr = self.il_list(f, &il.instructions, None)?;
        match cr {
            Some(v) => self.to_bool(v, il.span),
            None => Err(ExprError { span: il.span, message: "the condition leaves no current result".into() }),
        }
    }

    fn havoc_il(&mut self, f: &Frame, list: &[IlInstruction]) {
        for ins in list {
            if let Some(n) = &ins.nested {
                self.havoc_il(f, n);
            }
            let Some(op) = &ins.op else { continue };
            if let Some((IlOp::St | IlOp::Set | IlOp::Reset, _, _)) = parse_il_op(&op.text) {
                if let Some(t) = ins.operands.first() {
                    let s = sfc_syntax::ast::Stmt {
                        kind: sfc_syntax::ast::StmtKind::Assign {
                            target: Box::new(t.clone()),
                            value: Box::new(t.clone()),
                        },
                        span: t.span,
                    };
                    self.havoc_stmt(f, &s);
                }
            }
            if let Some((IlOp::Cal, _, _)) = parse_il_op(&op.text) {
                if let Some(Expr { kind: ExprKind::Name(n), span }) = ins.operands.first() {
                    let call = Expr {
                        kind: ExprKind::Call { callee: n.clone(), args: ins.call_args.clone().unwrap_or_default() },
                        span: *span,
                    };
                    let s =
                        sfc_syntax::ast::Stmt { kind: sfc_syntax::ast::StmtKind::Call(Box::new(call)), span: *span };
                    self.havoc_stmt(f, &s);
                }
            }
        }
    }

    fn cr_bool(&mut self, cr: &Option<SV>, span: sfc_diagnostics::Span) -> R<Lit> {
        match cr {
            Some(v) => self.to_bool(v.clone(), span),
            None => Err(ExprError { span, message: "the instruction needs a current result".into() }),
        }
    }

    /// Runs a list; returns the CR at its end.
    fn il_list(&mut self, f: &Frame, list: &[IlInstruction], start: Option<SV>) -> R<Option<SV>> {
        let mut labels: HashMap<String, usize> = HashMap::new();
        for (i, ins) in list.iter().enumerate() {
            if let Some(l) = &ins.label {
                labels.entry(l.key()).or_insert(i);
            }
        }
        let pc0 = self.pc;
        let mut incoming: Vec<Vec<(Lit, Option<SV>)>> = vec![Vec::new(); list.len() + 1];
        let mut here = pc0;
        let mut cr = start;
        for (i, ins) in list.iter().enumerate() {
            // Merge the jumps arriving here.
            for (reach, jcr) in std::mem::take(&mut incoming[i]) {
                let merged = match (&cr, jcr) {
                    (_, None) => cr.clone(),
                    (None, Some(j)) => Some(j),
                    (Some(c), Some(j)) => {
                        let ty = c.ty();
                        if ty == j.ty() || matches!(j, SV::Untyped(_)) {
                            Some(self.ite_sv(reach, j, c.clone(), &ty, ins.span)?)
                        } else {
                            Some(c.clone())
                        }
                    }
                };
                cr = merged;
                here = self.g.or(here, reach);
            }
            self.pc = here;
            let Some(op) = &ins.op else { continue };
            let span = ins.span;
            let Some((kind, negate, conditional)) = parse_il_op(&op.text) else {
                cr = Some(self.il_function(f, ins, op, cr.clone())?);
                continue;
            };
            match kind {
                IlOp::Ld => {
                    let v = self.il_operand(f, ins, None)?;
                    cr = Some(if negate { self.il_not(v, span)? } else { v });
                }
                IlOp::St | IlOp::Set | IlOp::Reset => {
                    let [target] = ins.operands.as_slice() else {
                        return Err(ExprError { span, message: "the instruction needs one variable".into() });
                    };
                    let p = self.place(f, target)?;
                    if kind == IlOp::St {
                        let Some(v) = cr.clone() else {
                            return Err(ExprError { span, message: "ST needs a current result".into() });
                        };
                        let v = if negate { self.il_not(v, span)? } else { v };
                        self.write_place(&p, v, span)?;
                    } else {
                        let c = self.cr_bool(&cr, span)?;
                        let pc = self.pc;
                        self.pc = self.g.and(pc, c);
                        self.write_place(&p, SV::Bool(Lit::from_bool(kind == IlOp::Set)), span)?;
                        self.pc = pc;
                    }
                }
                IlOp::Binary(bop) => {
                    let hint = cr.as_ref().map(|c| c.ty());
                    let r = self.il_operand(f, ins, hint.as_ref())?;
                    let r = if negate { self.il_not(r, span)? } else { r };
                    let Some(l) = cr.clone() else {
                        return Err(ExprError { span, message: "the instruction needs a current result".into() });
                    };
                    cr = Some(self.binary(bop, l, r, None, None, span)?);
                }
                IlOp::Not => {
                    let Some(l) = cr.clone() else {
                        return Err(ExprError { span, message: "NOT needs a current result".into() });
                    };
                    cr = Some(self.il_not(l, span)?);
                }
                IlOp::Jmp => {
                    let target = match ins.operands.as_slice() {
                        [Expr { kind: ExprKind::Name(l), .. }] => labels.get(&l.key()).copied(),
                        _ => None,
                    };
                    let Some(target) = target else {
                        return Err(ExprError { span, message: "a jump needs a known label".into() });
                    };
                    if target <= i {
                        return Err(ExprError {
                            span,
                            message: "backward jumps (loops in IL) are not modelled".into(),
                        });
                    }
                    let go = if conditional {
                        let c = self.cr_bool(&cr, span)?;
                        let c = if negate { c.not() } else { c };
                        self.g.and(here, c)
                    } else {
                        here
                    };
                    incoming[target].push((go, cr.clone()));
                    here = self.g.and(here, go.not());
                    if !conditional {
                        cr = None;
                    }
                }
                IlOp::Cal => {
                    let Some(Expr { kind: ExprKind::Name(name), .. }) = ins.operands.first() else {
                        return Err(ExprError { span, message: "CAL needs a function block instance".into() });
                    };
                    let Some(v) = self.lookup_var(f, &name.text) else {
                        return Err(ExprError {
                            span: name.span,
                            message: format!("`{}` is not an instance", name.text),
                        });
                    };
                    let pc = self.pc;
                    if conditional {
                        let c = self.cr_bool(&cr, span)?;
                        let c = if negate { c.not() } else { c };
                        self.pc = self.g.and(pc, c);
                    }
                    let args = ins.call_args.clone().unwrap_or_default();
                    self.fb_call(f, &v.slot, &args, span, name)?;
                    self.pc = pc;
                    cr = None;
                }
                IlOp::Ret => {
                    let go = if conditional {
                        let c = self.cr_bool(&cr, span)?;
                        let c = if negate { c.not() } else { c };
                        self.g.and(here, c)
                    } else {
                        here
                    };
                    self.returned = self.g.or(self.returned, go);
                    here = self.g.and(here, go.not());
                }
            }
        }
        for (reach, jcr) in std::mem::take(&mut incoming[list.len()]) {
            here = self.g.or(here, reach);
            if let (Some(c), Some(j)) = (&cr, jcr) {
                let ty = c.ty();
                cr = Some(self.ite_sv(reach, j, c.clone(), &ty, sfc_diagnostics::Span::default())?);
            }
        }
        self.pc = pc0;
        Ok(cr)
    }

    fn il_not(&mut self, v: SV, span: sfc_diagnostics::Span) -> R<SV> {
        Ok(match v {
            SV::Bool(l) => SV::Bool(l.not()),
            SV::Int(w, t) => SV::Int(self.ops().not(&w), t),
            SV::Untyped(c) => SV::Untyped(!c),
            other => return Err(ExprError { span, message: format!("NOT on `{}`", other.ty()) }),
        })
    }

    /// The operand of an instruction (a parenthesised list counts as one).
    fn il_operand(&mut self, f: &Frame, ins: &IlInstruction, hint: Option<&Type>) -> R<SV> {
        if let Some(nested) = &ins.nested {
            let start = match ins.operands.first() {
                None => None,
                Some(e) => Some(self.eval(f, e, hint)?),
            };
            let cr = self.il_list(f, nested, start)?;
            return cr.ok_or(ExprError { span: ins.span, message: "the parenthesis leaves no result".into() });
        }
        let [e] = ins.operands.as_slice() else {
            return Err(ExprError { span: ins.span, message: "the instruction needs exactly one operand".into() });
        };
        self.eval(f, e, hint)
    }

    /// A function used as an operator: `LD a  MAX b` is `MAX(a, b)`.
    fn il_function(&mut self, f: &Frame, ins: &IlInstruction, name: &sfc_syntax::ast::Ident, cr: Option<SV>) -> R<SV> {
        let span = ins.span;
        if let Some(args) = &ins.call_args {
            return self.call_value(f, name, args, span, None);
        }
        let Some(first) = cr else {
            return Err(ExprError { span, message: format!("`{}` needs a current result", name.text) });
        };
        // Build a call with the CR as the first argument.
        let mut vals = vec![first];
        for e in &ins.operands {
            vals.push(self.eval(f, e, None)?);
        }
        if let Some(sf) = sfc_st::stdlib::std_function(&name.text) {
            if let Some(op) = sf.operator {
                let mut it = vals.into_iter();
                let mut acc = it.next().unwrap_or(SV::Untyped(0));
                for v in it {
                    acc = self.binary(op, acc, v, None, None, span)?;
                }
                return Ok(acc);
            }
        }
        // Functions with a current result other than operators: bind as positional arguments
        // through temporaries.
        let _ = PlaceRef::StepX(0, 0);
        Err(ExprError {
            span,
            message: format!("IL function call `{}` with a current result is not modelled", name.text),
        })
    }
}
