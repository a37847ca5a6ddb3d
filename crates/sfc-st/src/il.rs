//! Instruction List checking: the type of the current result is tracked through the
//! instructions (transition conditions must leave a BOOL).

use crate::check::{untyped, Checker, Fit, Operand, Untyped};
use crate::env::PouInterface;
use crate::scope::Sym;
use crate::stdlib::std_function;
use crate::types::Type;
use sfc_diagnostics::Span;
use sfc_syntax::ast::{BinaryOp, Expr, ExprKind, IlBody, IlInstruction};
use std::collections::HashSet;

/// The operators of IL (IEC 61131-3 table 52), without modifiers.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum IlOp {
    /// `LD`.
    Ld,
    /// `ST`.
    St,
    /// `S`.
    Set,
    /// `R`.
    Reset,
    /// AND OR XOR and the arithmetic and comparison operators.
    Binary(BinaryOp),
    /// `NOT`.
    Not,
    /// `JMP`.
    Jmp,
    /// `CAL`.
    Cal,
    /// `RET`.
    Ret,
}

/// Splits an operator as written into the operator, the `N` modifier and the `C` modifier.
pub fn parse_il_op(text: &str) -> Option<(IlOp, bool, bool)> {
    let upper = text.to_ascii_uppercase();
    let r = match upper.as_str() {
        "LD" => (IlOp::Ld, false, false),
        "LDN" => (IlOp::Ld, true, false),
        "ST" => (IlOp::St, false, false),
        "STN" => (IlOp::St, true, false),
        "S" => (IlOp::Set, false, false),
        "R" => (IlOp::Reset, false, false),
        "AND" | "&" => (IlOp::Binary(BinaryOp::And), false, false),
        "ANDN" | "&N" => (IlOp::Binary(BinaryOp::And), true, false),
        "OR" => (IlOp::Binary(BinaryOp::Or), false, false),
        "ORN" => (IlOp::Binary(BinaryOp::Or), true, false),
        "XOR" => (IlOp::Binary(BinaryOp::Xor), false, false),
        "XORN" => (IlOp::Binary(BinaryOp::Xor), true, false),
        "NOT" => (IlOp::Not, false, false),
        "ADD" => (IlOp::Binary(BinaryOp::Add), false, false),
        "SUB" => (IlOp::Binary(BinaryOp::Sub), false, false),
        "MUL" => (IlOp::Binary(BinaryOp::Mul), false, false),
        "DIV" => (IlOp::Binary(BinaryOp::Div), false, false),
        "MOD" => (IlOp::Binary(BinaryOp::Mod), false, false),
        "GT" => (IlOp::Binary(BinaryOp::Gt), false, false),
        "GE" => (IlOp::Binary(BinaryOp::Ge), false, false),
        "EQ" => (IlOp::Binary(BinaryOp::Eq), false, false),
        "NE" => (IlOp::Binary(BinaryOp::Ne), false, false),
        "LE" => (IlOp::Binary(BinaryOp::Le), false, false),
        "LT" => (IlOp::Binary(BinaryOp::Lt), false, false),
        "JMP" => (IlOp::Jmp, false, false),
        "JMPC" => (IlOp::Jmp, false, true),
        "JMPCN" => (IlOp::Jmp, true, true),
        "CAL" => (IlOp::Cal, false, false),
        "CALC" => (IlOp::Cal, false, true),
        "CALCN" => (IlOp::Cal, true, true),
        "RET" => (IlOp::Ret, false, false),
        "RETC" => (IlOp::Ret, false, true),
        "RETCN" => (IlOp::Ret, true, true),
        _ => return None,
    };
    Some(r)
}

/// The current result: its type, or an untyped constant loaded by `LD 5` (kept as the
/// operand expression so that it can still adapt to where it is stored).
#[derive(Debug, Clone)]
struct Cr {
    ty: Option<Type>,
    expr: Expr,
}

impl Cr {
    fn typed(ty: Type, span: Span) -> Cr {
        Cr { ty: Some(ty), expr: Expr { kind: ExprKind::Error, span } }
    }
    fn unknown(span: Span) -> Cr {
        Cr::typed(Type::Error, span)
    }
    fn operand(&self) -> Operand<'_> {
        match &self.ty {
            Some(t) => Operand { expr: &self.expr, ty: Some(t.clone()), untyped: None },
            None => Operand { expr: &self.expr, ty: None, untyped: untyped(&self.expr) },
        }
    }
    fn is_bool(&self) -> bool {
        match &self.ty {
            Some(t) => t.is_bool() || t.is_error(),
            None => matches!(untyped(&self.expr), Some(Untyped::Int(Some(0 | 1)))),
        }
    }
    fn is_bit(&self) -> bool {
        match &self.ty {
            Some(t) => t.is_bit() || t.is_error(),
            None => false,
        }
    }
    fn describe(&self) -> String {
        match &self.ty {
            Some(t) => format!("`{t}`"),
            None => crate::check::untyped_phrase(untyped(&self.expr)),
        }
    }
}

impl Checker<'_, '_> {
    /// Checks an IL body of an action or a POU.
    pub fn check_il(&mut self, body: &IlBody) {
        let labels = labels(&body.instructions);
        let targets = jump_targets(&body.instructions);
        self.il_list(&body.instructions, None, &labels, &targets);
    }

    /// Checks an IL transition condition: no side effects (ST, S, R, CAL are SFC0305) and a
    /// BOOL current result at the end (SFC0303). Returns the type of the result.
    pub fn check_il_guard(&mut self, body: &IlBody) -> Type {
        let was = std::mem::replace(&mut self.in_guard, true);
        let labels = labels(&body.instructions);
        let targets = jump_targets(&body.instructions);
        let cr = self.il_list(&body.instructions, None, &labels, &targets);
        self.in_guard = was;
        match cr {
            None => {
                self.error("SFC0316", body.span, "the condition ends without a current result; load one with `LD`");
                Type::Error
            }
            Some(cr) if cr.is_bool() => Type::Bool,
            Some(cr) => {
                self.error("SFC0303", body.span, format!("transition condition is {}, expected `BOOL`", cr.describe()));
                cr.ty.unwrap_or(Type::Error)
            }
        }
    }

    /// Runs an instruction list from the current result `cr`; returns the final one.
    fn il_list(
        &mut self,
        instrs: &[IlInstruction],
        mut cr: Option<Cr>,
        labels: &HashSet<String>,
        targets: &HashSet<String>,
    ) -> Option<Cr> {
        for ins in instrs {
            if let Some(l) = &ins.label {
                // Control may arrive here from a jump with another current result.
                if targets.contains(&l.key()) && cr.is_some() {
                    cr = Some(Cr::unknown(l.span));
                }
            }
            let Some(op) = &ins.op else { continue };
            cr = self.il_instruction(ins, op, cr, labels, targets);
        }
        cr
    }

    fn needs_cr(&mut self, cr: &Option<Cr>, op: &str, span: Span) -> bool {
        if cr.is_none() {
            self.error("SFC0316", span, format!("`{op}` needs a current result; load one with `LD` first"));
            return false;
        }
        true
    }

    /// The single operand of an instruction, as an operand checked for reading (a nested
    /// `( … )` list counts as the operand).
    fn il_operand(
        &mut self,
        ins: &IlInstruction,
        op: &str,
        labels: &HashSet<String>,
        targets: &HashSet<String>,
    ) -> Option<Cr> {
        if let Some(nested) = &ins.nested {
            let start = ins.operands.first().map(|e| self.il_value(e));
            if !self.enter(ins.span) {
                return None;
            }
            let r = self.il_list(nested, start, labels, targets);
            self.leave();
            if r.is_none() {
                self.error("SFC0316", ins.span, format!("the parenthesis after `{op}` leaves no current result"));
            }
            return r;
        }
        match ins.operands.as_slice() {
            [e] => Some(self.il_value(e)),
            _ => {
                self.error("SFC0316", ins.span, format!("`{op}` needs exactly one operand"));
                None
            }
        }
    }

    /// An operand read as a value.
    fn il_value(&mut self, e: &Expr) -> Cr {
        match untyped(e) {
            Some(_) => Cr { ty: None, expr: e.clone() },
            None => {
                let t = self.check_expr(e, None);
                Cr::typed(t, e.span)
            }
        }
    }

    /// Re-files the type mismatches reported since `from` as IL errors (SFC0316).
    fn as_il_errors(&mut self, from: usize) {
        for d in self.diagnostics_mut().iter_mut().skip(from) {
            if d.code == "SFC0302" {
                d.code = "SFC0316";
            }
        }
    }

    fn il_instruction(
        &mut self,
        ins: &IlInstruction,
        op_ident: &sfc_syntax::ast::Ident,
        cr: Option<Cr>,
        labels: &HashSet<String>,
        targets: &HashSet<String>,
    ) -> Option<Cr> {
        let op_text = op_ident.text.to_ascii_uppercase();
        let span = ins.span;
        let Some((op, negate, conditional)) = parse_il_op(&op_text) else {
            return self.il_function(ins, op_ident, cr);
        };
        if conditional && self.needs_cr(&cr, &op_text, span) {
            if let Some(c) = &cr {
                if !c.is_bool() {
                    self.error(
                        "SFC0316",
                        span,
                        format!("`{op_text}` tests the current result, which is {}, not BOOL", c.describe()),
                    );
                }
            }
        }
        match op {
            IlOp::Ld => {
                let v = self.il_operand(ins, &op_text, labels, targets)?;
                if negate && !v.is_bit() {
                    self.error(
                        "SFC0316",
                        span,
                        format!("`LDN` needs BOOL or a bit string, but the operand is {}", v.describe()),
                    );
                    return Some(Cr::unknown(span));
                }
                Some(v)
            }
            IlOp::St | IlOp::Set | IlOp::Reset => {
                let Some(target) = ins.operands.first().filter(|_| ins.operands.len() == 1) else {
                    self.error("SFC0316", span, format!("`{op_text}` needs exactly one variable"));
                    return cr;
                };
                if self.in_guard {
                    self.error(
                        "SFC0305",
                        span,
                        format!("`{op_text}` writes `{}` in a transition condition", crate::check::expr_text(target)),
                    );
                }
                let tt = self.target(target);
                if !self.needs_cr(&cr, &op_text, span) {
                    return cr;
                }
                let c = cr?;
                if tt.is_error() {
                    return Some(c);
                }
                if op != IlOp::St {
                    if !c.is_bool() || !tt.is_bool() {
                        self.error(
                            "SFC0316",
                            span,
                            format!(
                                "`{op_text}` needs a BOOL current result and a BOOL variable, not {} and `{tt}`",
                                c.describe()
                            ),
                        );
                    }
                    return Some(c);
                }
                if negate && !c.is_bit() {
                    self.error("SFC0316", span, format!("`STN` needs BOOL or a bit string, not {}", c.describe()));
                    return Some(c);
                }
                let ok = match &c.ty {
                    Some(t) => t.assignable_to(&tt),
                    None => untyped(&c.expr).is_some_and(|u| matches!(crate::check::fit(u, &tt), Fit::Fits)),
                };
                if !ok {
                    self.error(
                        "SFC0316",
                        span,
                        format!(
                            "`{op_text}`: the current result is {}, but `{}` is `{tt}`",
                            c.describe(),
                            crate::check::expr_text(target)
                        ),
                    );
                }
                Some(c)
            }
            IlOp::Binary(bop) => {
                let operand = self.il_operand(ins, &op_text, labels, targets);
                if !self.needs_cr(&cr, &op_text, span) {
                    return None;
                }
                let (Some(c), Some(v)) = (cr, operand) else { return Some(Cr::unknown(span)) };
                if negate && !v.is_bit() {
                    self.error(
                        "SFC0316",
                        span,
                        format!(
                            "`{op_text}` negates its operand, which must be BOOL or a bit string, not {}",
                            v.describe()
                        ),
                    );
                    return Some(Cr::unknown(span));
                }
                let from = self.diagnostics().len();
                let t = self.combine(bop, vec![c.operand(), v.operand()], span, None, &format!("`{op_text}`"));
                self.as_il_errors(from);
                Some(Cr::typed(t, span))
            }
            IlOp::Not => {
                if !ins.operands.is_empty() {
                    self.error("SFC0316", span, "`NOT` takes no operand; it inverts the current result");
                }
                if !self.needs_cr(&cr, "NOT", span) {
                    return None;
                }
                let c = cr?;
                if !c.is_bit() {
                    self.error(
                        "SFC0316",
                        span,
                        format!("`NOT` needs BOOL or a bit string, but the current result is {}", c.describe()),
                    );
                    return Some(Cr::unknown(span));
                }
                Some(c)
            }
            IlOp::Jmp => {
                match ins.operands.as_slice() {
                    [Expr { kind: ExprKind::Name(label), .. }] => {
                        if !labels.contains(&label.key()) {
                            self.error("SFC0316", label.span, format!("jump to undefined label `{}`", label.text));
                        }
                    }
                    _ => self.error("SFC0316", span, format!("`{op_text}` needs a label")),
                }
                // After an unconditional jump the next instruction is reached only by a jump.
                if conditional {
                    cr
                } else {
                    None
                }
            }
            IlOp::Cal => {
                let Some(Expr { kind: ExprKind::Name(name), .. }) = ins.operands.first() else {
                    self.error("SFC0316", span, format!("`{op_text}` needs a function block instance"));
                    return None;
                };
                let args = ins.call_args.as_deref().unwrap_or(&[]);
                match self.scope.resolve(&name.text) {
                    Some(sym @ (Sym::Local(_) | Sym::Global(_))) => {
                        let ty = self.scope.var_info(sym).map(|v| v.ty.clone()).unwrap_or(Type::Error);
                        match self.scope.env().fb_of(&ty).cloned() {
                            Some(fb) => self.fb_call(name, sym, &fb, args, span),
                            None if ty.is_error() => {}
                            None => self.error(
                                "SFC0316",
                                name.span,
                                format!("`{op_text}` needs a function block instance, but `{}` is `{ty}`", name.text),
                            ),
                        }
                    }
                    Some(_) => self.error(
                        "SFC0316",
                        name.span,
                        format!("`{op_text}` needs a function block instance; `{}` is not one", name.text),
                    ),
                    None => self.undeclared(name),
                }
                // The current result is undefined after a call.
                None
            }
            IlOp::Ret => {
                if conditional {
                    cr
                } else {
                    None
                }
            }
        }
    }

    /// A function called as an IL operator: the current result is its first input, the
    /// operands the others (`LD a  MAX b` is `MAX(a, b)`); with formal arguments, a plain call.
    fn il_function(&mut self, ins: &IlInstruction, name: &sfc_syntax::ast::Ident, cr: Option<Cr>) -> Option<Cr> {
        let span = ins.span;
        if let Some(args) = &ins.call_args {
            let t = self.call_value(name, args, span, None);
            return Some(Cr::typed(t, span));
        }
        let env = self.scope.env();
        if let Some(f) = env.function(&name.text).cloned() {
            if !self.needs_cr(&cr, &name.text, span) {
                return None;
            }
            let c = cr?;
            let params: Vec<(String, Type)> = f.positional_params().map(|v| (v.name.clone(), v.ty.clone())).collect();
            if params.len() != ins.operands.len() + 1 {
                self.error(
                    "SFC0316",
                    span,
                    format!(
                        "`{}` takes {} inputs: the current result and {} operand{}",
                        f.name,
                        params.len(),
                        params.len().saturating_sub(1),
                        if params.len() == 2 { "" } else { "s" }
                    ),
                );
                return Some(Cr::unknown(span));
            }
            if let Some((pname, pty)) = params.first() {
                let ok = match &c.ty {
                    Some(t) => t.assignable_to(pty),
                    None => untyped(&c.expr).is_some_and(|u| matches!(crate::check::fit(u, pty), Fit::Fits)),
                };
                if !ok {
                    self.error(
                        "SFC0316",
                        span,
                        format!(
                            "input `{pname}` of `{}` is `{pty}`, but the current result is {}",
                            f.name,
                            c.describe()
                        ),
                    );
                }
            }
            let from = self.diagnostics().len();
            for ((pname, pty), e) in params.iter().skip(1).zip(&ins.operands) {
                let t = self.check_expr(e, Some(pty));
                if !t.assignable_to(pty) {
                    let p = self.phrase(e, &t);
                    self.error(
                        "SFC0302",
                        e.span,
                        format!("type mismatch: input `{pname}` of `{}` is `{pty}`, but the argument is {p}", f.name),
                    );
                }
            }
            self.as_il_errors(from);
            return Some(Cr::typed(ret_of(&f), span));
        }
        if let Some(f) = std_function(&name.text) {
            if !self.needs_cr(&cr, &name.text, span) {
                return None;
            }
            let c = cr?;
            let n = ins.operands.len() + 1;
            if n < f.params.len() || (!f.extensible && n > f.params.len()) {
                self.error(
                    "SFC0316",
                    span,
                    format!(
                        "`{}` takes {}{} inputs: the current result and the operands",
                        f.name,
                        if f.extensible { "at least " } else { "" },
                        f.params.len()
                    ),
                );
                return Some(Cr::unknown(span));
            }
            let mut ops = vec![(0usize, c.operand())];
            for (i, e) in ins.operands.iter().enumerate() {
                let o = self.operand(e, None);
                ops.push((i + 1, o));
            }
            let from = self.diagnostics().len();
            let t = self.std_apply(&f, ops, span, None);
            self.as_il_errors(from);
            return Some(Cr::typed(t, span));
        }
        self.error("SFC0316", name.span, format!("unknown IL operator `{}`", name.text));
        Some(Cr::unknown(span))
    }
}

fn ret_of(f: &PouInterface) -> Type {
    f.return_type.clone().unwrap_or(Type::Error)
}

/// The labels defined in a list (upper-case).
fn labels(instrs: &[IlInstruction]) -> HashSet<String> {
    let mut out = HashSet::new();
    for i in instrs {
        if let Some(l) = &i.label {
            out.insert(l.key());
        }
    }
    out
}

/// The labels some jump goes to (upper-case), nested lists included.
fn jump_targets(instrs: &[IlInstruction]) -> HashSet<String> {
    let mut out = HashSet::new();
    collect_targets(instrs, &mut out, 0);
    out
}

fn collect_targets(instrs: &[IlInstruction], out: &mut HashSet<String>, depth: u32) {
    if depth > 256 {
        return;
    }
    for i in instrs {
        if i.op.as_ref().is_some_and(|o| o.text.to_ascii_uppercase().starts_with("JMP")) {
            if let Some(Expr { kind: ExprKind::Name(l), .. }) = i.operands.first() {
                out.insert(l.key());
            }
        }
        if let Some(n) = &i.nested {
            collect_targets(n, out, depth + 1);
        }
    }
}
