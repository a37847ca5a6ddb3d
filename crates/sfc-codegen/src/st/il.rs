//! Instruction List to Structured Text, for the IL conditions and action bodies of a chart.
//!
//! The current result (CR) is followed symbolically as an ST expression, so `LD a  AND b
//! ST x` becomes `x := a AND b;` with no temporary (ST has no type inference, and a temporary
//! would need the CR's type). Operators with the `N` modifier negate their operand, `S`/`R`
//! become `IF cr THEN x := TRUE/FALSE; END_IF;`, `CAL[C[N]]` an (optionally guarded) call,
//! a function used as an operator (`LD a  MAX b`) the call `MAX(a, b)`, a parenthesised
//! operand (`AND( b  OR c )`) a parenthesised sub-expression.
//!
//! Jumps and returns: the body is cut into blocks at labels and after each jump; a variable
//! (`SfcGoto`, INT) holds the pending jump target: `JMP L` sets it to L's number, `RET` to -1,
//! every block runs only while it is 0, and each label clears it when it holds its number. A
//! backward jump wraps the blocks in `REPEAT … UNTIL SfcGoto <= 0 END_REPEAT`, so the next pass
//! resumes at the label.
//!
//! Refused (located SFC0802–SFC0804), because the CR would have to be kept in a variable of
//! a type this translation does not know: using the CR right after a label (it may come from a
//! jump or from the line before); using a CR expression after a statement that may have
//! changed what it reads (`LD x  R x  ST y`); jumps inside conditions, statements inside
//! parentheses.

#![allow(clippy::result_large_err)] // `Diagnostic` is the error type of every sfc crate

use sfc_diagnostics::{Diagnostic, Span};
use sfc_st::{parse_il_op, IlOp, Type};
use sfc_syntax::ast::{BinaryOp, Expr, ExprKind, IlBody, IlInstruction, UNARY_PRECEDENCE};
use std::collections::HashMap;

/// Precedence of an atom (name, literal, call, parenthesised expression).
pub(crate) const ATOM: u8 = 10;

/// What the translation of an IL body needs from the file.
pub(crate) struct Ctx<'a> {
    pub src: &'a str,
    /// Types of IL operands by span (from the checker).
    pub types: &'a HashMap<Span, Type>,
}

/// The current result as an ST expression.
#[derive(Debug, Clone)]
struct Cr {
    text: String,
    prec: u8,
    /// The type, when known (`None` for an untyped literal or an unknown type).
    ty: Option<Type>,
    /// A literal without type, which takes the type of the other operand.
    untyped: bool,
    /// Root names (upper-case) the expression reads.
    reads: Vec<String>,
    /// A statement since the CR was computed may have changed what it reads.
    stale: Option<Span>,
    /// Evaluating it cannot raise a runtime error.
    safe: bool,
}

/// What is known about the CR between instructions.
#[derive(Debug, Clone)]
enum State {
    None,
    Known(Cr),
    /// After a label: it depends on how control arrived.
    AtLabel(Span),
}

/// One block of statements, after an optional label.
struct Block {
    label: Option<u32>,
    stmts: Vec<String>,
}

/// The ST text of an expression with its precedence.
pub(crate) fn wrap(text: &str, prec: u8, min: u8) -> String {
    if prec >= min {
        text.to_string()
    } else {
        format!("({text})")
    }
}

/// Source text of a span with comments dropped and white space collapsed (one line).
pub(crate) fn clean(src: &str, span: Span) -> String {
    let Some(slice) = src.get(span.range()) else { return String::new() };
    let (tokens, _) = sfc_syntax::lexer::lex(0, slice);
    let mut out = String::new();
    let mut space = false;
    for t in &tokens {
        use sfc_syntax::lexer::TokenKind as K;
        match t.kind {
            K::Whitespace | K::BlockComment | K::LineComment | K::Pragma => space = true,
            K::Eof => {}
            _ => {
                if space && !out.is_empty() {
                    out.push(' ');
                }
                space = false;
                out.push_str(&slice[t.start as usize..t.end as usize]);
            }
        }
    }
    out
}

/// Precedence of an ST expression as written.
pub(crate) fn prec_of(e: &Expr) -> u8 {
    match &e.kind {
        ExprKind::Binary { op, .. } => op.precedence(),
        ExprKind::Unary { .. } => UNARY_PRECEDENCE,
        _ => ATOM,
    }
}

/// An expression that cannot raise a runtime error: names, literals, members and operators
/// other than division, MOD and `**`.
pub(crate) fn cannot_fault(e: &Expr) -> bool {
    match &e.kind {
        ExprKind::Literal(_) | ExprKind::Name(_) | ExprKind::Address(_) => true,
        ExprKind::Member { base, .. } => cannot_fault(base),
        ExprKind::Paren(i) => cannot_fault(i),
        ExprKind::Unary { operand, .. } => cannot_fault(operand),
        ExprKind::Binary { op, lhs, rhs } => {
            !matches!(op, BinaryOp::Div | BinaryOp::Mod | BinaryOp::Pow) && cannot_fault(lhs) && cannot_fault(rhs)
        }
        ExprKind::Index { .. }
        | ExprKind::Call { .. }
        | ExprKind::MemberCall { .. }
        | ExprKind::Deref(_)
        | ExprKind::Error => false,
    }
}

/// Root names an expression reads (upper-case), for the staleness test.
fn reads_of(e: &Expr, out: &mut Vec<String>) {
    match &e.kind {
        ExprKind::Name(n) => out.push(n.key()),
        ExprKind::Member { base, .. } => reads_of(base, out),
        ExprKind::Index { base, indices } => {
            reads_of(base, out);
            indices.iter().for_each(|i| reads_of(i, out));
        }
        ExprKind::Call { args, .. } => args.iter().filter_map(|a| a.value.as_ref()).for_each(|v| reads_of(v, out)),
        ExprKind::MemberCall { base, args, .. } => {
            reads_of(base, out);
            args.iter().filter_map(|a| a.value.as_ref()).for_each(|v| reads_of(v, out));
        }
        ExprKind::Unary { operand, .. } => reads_of(operand, out),
        ExprKind::Binary { lhs, rhs, .. } => {
            reads_of(lhs, out);
            reads_of(rhs, out);
        }
        ExprKind::Paren(i) | ExprKind::Deref(i) => reads_of(i, out),
        ExprKind::Address(a) => out.push(a.text.to_ascii_uppercase()),
        ExprKind::Literal(_) | ExprKind::Error => {}
    }
}

/// The variable a store writes (its root name).
fn root_of(e: &Expr) -> Option<String> {
    match &e.kind {
        ExprKind::Name(n) => Some(n.key()),
        ExprKind::Member { base, .. } | ExprKind::Index { base, .. } => root_of(base),
        ExprKind::Paren(i) => root_of(i),
        ExprKind::Address(a) => Some(a.text.to_ascii_uppercase()),
        _ => None,
    }
}

fn error(code: &'static str, span: Span, msg: impl Into<String>) -> Diagnostic {
    Diagnostic::error(code, span, msg)
}

impl Ctx<'_> {
    fn operand_cr(&self, e: &Expr) -> Cr {
        let mut reads = Vec::new();
        reads_of(e, &mut reads);
        let untyped = matches!(&e.kind, ExprKind::Literal(l) if l.type_prefix.is_none())
            || matches!(&e.kind, ExprKind::Unary { operand, .. } if matches!(&operand.kind, ExprKind::Literal(l) if l.type_prefix.is_none()));
        let ty = if untyped { None } else { self.types.get(&e.span).cloned() };
        Cr { text: clean(self.src, e.span), prec: prec_of(e), ty, untyped, reads, stale: None, safe: cannot_fault(e) }
    }

    /// The CR, or why it cannot be used by the instruction at `span`.
    fn need(&self, st: &State, span: Span, op: &str) -> Result<Cr, Diagnostic> {
        match st {
            State::Known(c) => match c.stale {
                None => Ok(c.clone()),
                Some(at) => Err(error(
                    "SFC0803",
                    span,
                    format!("`{op}` uses the current result, which the instruction before may have changed"),
                )
                .with_label(at, "this may change what the current result was computed from")
                .with_note("IL keeps the value; to translate it to ST, load it again or store it in a variable first")),
            },
            State::AtLabel(l) => Err(error(
                "SFC0802",
                span,
                format!("`{op}` uses the current result right after a label; it depends on how control arrived there"),
            )
            .with_label(*l, "label")
            .with_note("load a value (LD) after the label, so the ST translation needs no variable for it")),
            State::None => Err(error("SFC0804", span, format!("`{op}` needs a current result"))),
        }
    }

    /// The operand of `ins` as an expression (a parenthesised list counts as one).
    fn operand(&self, ins: &IlInstruction) -> Result<Cr, Diagnostic> {
        if let Some(nested) = &ins.nested {
            let start = match ins.operands.first() {
                Some(e) => State::Known(self.operand_cr(e)),
                None => State::None,
            };
            let cr = self.expression_list(nested, start)?;
            return Ok(Cr { text: format!("({})", cr.text), prec: ATOM, ..cr });
        }
        match ins.operands.as_slice() {
            [e] => Ok(self.operand_cr(e)),
            _ => Err(error("SFC0804", ins.span, "the instruction needs exactly one operand")),
        }
    }

    /// A list without statements (a condition, a parenthesised operand): its final CR.
    fn expression_list(&self, instrs: &[IlInstruction], start: State) -> Result<Cr, Diagnostic> {
        let mut st = start;
        for ins in instrs {
            if let Some(l) = &ins.label {
                return Err(error(
                    "SFC0802",
                    l.span,
                    "labels and jumps cannot be translated inside a condition or parentheses",
                ));
            }
            let Some(op) = &ins.op else { continue };
            st = State::Known(self.value_op(ins, &op.text, &st)?.ok_or_else(|| {
                error(
                    "SFC0804",
                    ins.span,
                    format!("`{}` cannot be translated inside a condition or parentheses", op.text),
                )
            })?);
        }
        self.need(&st, instrs.last().map_or(Span::default(), |i| i.span), "the condition")
    }

    /// An instruction that only computes a new CR; `Ok(None)` for the other kinds.
    fn value_op(&self, ins: &IlInstruction, op: &str, st: &State) -> Result<Option<Cr>, Diagnostic> {
        let Some((kind, negate, conditional)) = parse_il_op(op) else {
            return self.function(ins, op, st).map(Some);
        };
        Ok(Some(match kind {
            IlOp::Ld => {
                let v = self.operand(ins)?;
                if negate {
                    not(v)
                } else {
                    v
                }
            }
            IlOp::Binary(b) if !conditional => {
                let l = self.need(st, ins.span, op)?;
                let mut r = self.operand(ins)?;
                if negate {
                    r = not(r);
                }
                binary(b, l, r)
            }
            IlOp::Not => not(self.need(st, ins.span, op)?),
            _ => return Ok(None),
        }))
    }

    /// `LD a  MAX b, c` → `MAX(a, b, c)`; with formal arguments, a plain call.
    fn function(&self, ins: &IlInstruction, name: &str, st: &State) -> Result<Cr, Diagnostic> {
        let mut reads = Vec::new();
        let mut args: Vec<String> = Vec::new();
        if let Some(call) = &ins.call_args {
            for a in call {
                args.push(clean(self.src, a.span));
                if let Some(v) = &a.value {
                    reads_of(v, &mut reads);
                }
            }
        } else {
            let first = self.need(st, ins.span, name)?;
            reads.extend(first.reads.iter().cloned());
            args.push(first.text);
            for e in &ins.operands {
                reads_of(e, &mut reads);
                args.push(clean(self.src, e.span));
            }
        }
        Ok(Cr {
            text: format!("{name}({})", args.join(", ")),
            prec: ATOM,
            ty: None,
            untyped: false,
            reads,
            stale: None,
            safe: false,
        })
    }

    /// An IL transition condition as one ST expression `(text, precedence, cannot fault)`.
    pub(crate) fn condition(&self, body: &IlBody) -> Result<(String, u8, bool), Diagnostic> {
        let cr = self.expression_list(&body.instructions, State::None)?;
        Ok((as_bool(&cr), cr.prec, cr.safe))
    }

    /// An IL action body as ST statements (one per line). `goto` names the INT variable for
    /// jumps and returns; it is used only when the body has some.
    pub(crate) fn body(&self, body: &IlBody, goto: &str) -> Result<Vec<String>, Diagnostic> {
        let instrs = &body.instructions;
        let mut labels: HashMap<String, u32> = HashMap::new();
        for ins in instrs {
            if let Some(l) = &ins.label {
                let n = labels.len() as u32 + 1;
                labels.entry(l.key()).or_insert(n);
            }
        }
        let mut blocks = vec![Block { label: None, stmts: Vec::new() }];
        let mut st = State::None;
        let mut jumps = false;
        let mut backward = false;
        let mut seen_labels: Vec<u32> = Vec::new();
        for ins in instrs {
            if let Some(l) = &ins.label {
                let n = labels.get(&l.key()).copied().unwrap_or(0);
                seen_labels.push(n);
                blocks.push(Block { label: Some(n), stmts: Vec::new() });
                st = State::AtLabel(l.span);
            }
            let Some(op_ident) = &ins.op else { continue };
            let op = op_ident.text.as_str();
            if let Some(v) = self.value_op(ins, op, &st)? {
                st = State::Known(v);
                continue;
            }
            let Some((kind, negate, conditional)) = parse_il_op(op) else { continue };
            let guard = |this: &Self, st: &State| -> Result<Option<String>, Diagnostic> {
                if !conditional {
                    return Ok(None);
                }
                let c = this.need(st, ins.span, op)?;
                Ok(Some(if negate { not(c).text } else { as_bool(&c) }))
            };
            let cur = blocks.len() - 1;
            match kind {
                IlOp::St | IlOp::Set | IlOp::Reset => {
                    let [target] = ins.operands.as_slice() else {
                        return Err(error("SFC0804", ins.span, format!("`{op}` needs one variable")));
                    };
                    let c = self.need(&st, ins.span, op)?;
                    let t = clean(self.src, target.span);
                    let root = root_of(target);
                    let stmt = match kind {
                        IlOp::St if negate => format!("{t} := {};", not(c.clone()).text),
                        IlOp::St => format!("{t} := {};", c.text),
                        IlOp::Set => format!("IF {} THEN {t} := TRUE; END_IF;", as_bool(&c)),
                        _ => format!("IF {} THEN {t} := FALSE; END_IF;", as_bool(&c)),
                    };
                    blocks[cur].stmts.push(stmt);
                    let target_ty = self.types.get(&target.span);
                    let same_type = match (&c.ty, target_ty) {
                        (Some(a), Some(b)) => a == b,
                        _ => false,
                    };
                    if kind == IlOp::St && !negate && same_type {
                        // The stored variable now holds the CR's value.
                        let mut cr = self.operand_cr(target);
                        cr.ty = target_ty.cloned();
                        cr.untyped = false;
                        st = State::Known(cr);
                    } else if let Some(r) = root {
                        st = stale(st, &[r], ins.span);
                    }
                }
                IlOp::Cal => {
                    let Some(Expr { kind: ExprKind::Name(fb), .. }) = ins.operands.first() else {
                        return Err(error("SFC0804", ins.span, "CAL needs a function block instance"));
                    };
                    let args: Vec<String> = ins.call_args.iter().flatten().map(|a| clean(self.src, a.span)).collect();
                    let call = format!("{}({});", fb.text, args.join(", "));
                    let stmt = match guard(self, &st)? {
                        Some(g) => format!("IF {g} THEN {call} END_IF;"),
                        None => call,
                    };
                    blocks[cur].stmts.push(stmt);
                    st = State::None;
                }
                IlOp::Jmp | IlOp::Ret => {
                    let n: i64 = if kind == IlOp::Ret {
                        -1
                    } else {
                        match ins.operands.as_slice() {
                            [Expr { kind: ExprKind::Name(l), .. }] => match labels.get(&l.key()) {
                                Some(&n) => {
                                    backward |= seen_labels.contains(&n);
                                    i64::from(n)
                                }
                                None => {
                                    return Err(error("SFC0804", l.span, format!("jump to unknown label `{}`", l.text)))
                                }
                            },
                            _ => return Err(error("SFC0804", ins.span, "a jump needs a label")),
                        }
                    };
                    jumps = true;
                    let set = format!("{goto} := {n};");
                    let stmt = match guard(self, &st)? {
                        Some(g) => format!("IF {g} THEN {set} END_IF;"),
                        None => set,
                    };
                    blocks[cur].stmts.push(stmt);
                    if !conditional {
                        st = State::None;
                    }
                    blocks.push(Block { label: None, stmts: Vec::new() });
                }
                _ => return Err(error("SFC0804", ins.span, format!("`{op}` cannot be translated"))),
            }
        }
        if !jumps && labels.is_empty() {
            return Ok(blocks.into_iter().flat_map(|b| b.stmts).collect());
        }
        let mut out = vec![format!("{goto} := 0;")];
        let indent = if backward { "    " } else { "" };
        if backward {
            out.push("REPEAT".to_string());
        }
        for b in blocks {
            if let Some(n) = b.label {
                out.push(format!("{indent}IF {goto} = {n} THEN {goto} := 0; END_IF;"));
            }
            if b.stmts.is_empty() {
                continue;
            }
            out.push(format!("{indent}IF {goto} = 0 THEN"));
            out.extend(b.stmts.into_iter().map(|s| format!("{indent}    {s}")));
            out.push(format!("{indent}END_IF;"));
        }
        if backward {
            out.push(format!("UNTIL {goto} <= 0 END_REPEAT;"));
        }
        Ok(out)
    }

    /// Whether an IL body needs the jump variable.
    pub(crate) fn needs_goto(body: &IlBody) -> bool {
        body.instructions.iter().any(|i| {
            i.label.is_some()
                || i.op.as_ref().is_some_and(|o| matches!(parse_il_op(&o.text), Some((IlOp::Jmp | IlOp::Ret, _, _))))
        })
    }
}

/// Marks the CR stale when it reads one of `written`.
fn stale(st: State, written: &[String], at: Span) -> State {
    match st {
        State::Known(mut c) if c.stale.is_none() && c.reads.iter().any(|r| written.contains(r)) => {
            c.stale = Some(at);
            State::Known(c)
        }
        other => other,
    }
}

/// The CR where a BOOL is expected: an untyped `0` / `1` is FALSE / TRUE there (as IL reads it).
fn as_bool(c: &Cr) -> String {
    match (c.untyped, c.text.as_str()) {
        (true, "0") => "FALSE".to_string(),
        (true, "1") => "TRUE".to_string(),
        _ => c.text.clone(),
    }
}

fn not(c: Cr) -> Cr {
    let text = format!("NOT {}", wrap(&c.text, c.prec, UNARY_PRECEDENCE));
    Cr { text, prec: UNARY_PRECEDENCE, ..c }
}

fn binary(op: BinaryOp, l: Cr, r: Cr) -> Cr {
    let p = op.precedence();
    // Left-associative: the left operand may have the same precedence, the right one not.
    let (lmin, rmin) = if op == BinaryOp::Pow { (p + 1, p + 1) } else { (p, p + 1) };
    let text = format!("{} {} {}", wrap(&l.text, l.prec, lmin), op.symbol(), wrap(&r.text, r.prec, rmin));
    let comparison =
        matches!(op, BinaryOp::Eq | BinaryOp::Ne | BinaryOp::Lt | BinaryOp::Gt | BinaryOp::Le | BinaryOp::Ge);
    let ty = if comparison {
        Some(Type::Bool)
    } else if l.untyped {
        r.ty.clone()
    } else if r.untyped || l.ty == r.ty {
        l.ty.clone()
    } else {
        None
    };
    let mut reads = l.reads;
    reads.extend(r.reads);
    let safe = l.safe && r.safe && !matches!(op, BinaryOp::Div | BinaryOp::Mod | BinaryOp::Pow);
    Cr { text, prec: p, ty, untyped: l.untyped && r.untyped && !comparison, reads, stale: l.stale.or(r.stale), safe }
}
