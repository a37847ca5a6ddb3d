//! A canonical one-line form of expressions, used to name opaque atoms: the same
//! sub-expression written in two guards gets the same key, and the witness shows it in a form
//! close to the source.
//!
//! The form: identifiers as written (or upper-cased for the key), literals as written (upper-
//! cased for the key, except strings), binary operators with one space on each side in their
//! canonical spelling (`AND`, `<>`, …), `NOT x`, `-x`, calls `F(a, b)` / `F(IN := a, Q => b)`,
//! members `a.b`, indexes `a[i, j]`; parentheses only where precedence needs them (the user's
//! redundant parentheses are dropped, so `(a + b) > c` and `a + b > c` are one atom).

use sfc_syntax::ast::{Arg, Expr, ExprKind, LiteralKind, UnaryOp, UNARY_PRECEDENCE};

/// Deeper than this the printer gives up (the parser caps expressions at 256 levels).
const MAX_DEPTH: u32 = 400;

/// Binding power of an expression as a whole (atoms bind tightest).
fn precedence(e: &Expr) -> u8 {
    match &e.kind {
        ExprKind::Binary { op, .. } => op.precedence(),
        ExprKind::Unary { .. } => UNARY_PRECEDENCE,
        ExprKind::Paren(inner) => precedence(inner),
        _ => 10,
    }
}

/// Prints `e`; `fold` upper-cases identifiers and non-string literals (the atom key).
/// `None` when the expression is too deep or holds an error node.
pub(super) fn print(e: &Expr, fold: bool) -> Option<String> {
    let mut out = String::new();
    write(e, fold, &mut out, 0)?;
    Some(out)
}

fn ident(text: &str, fold: bool, out: &mut String) {
    if fold {
        out.push_str(&text.to_ascii_uppercase());
    } else {
        out.push_str(text);
    }
}

fn write(e: &Expr, fold: bool, out: &mut String, depth: u32) -> Option<()> {
    if depth > MAX_DEPTH {
        return None;
    }
    match &e.kind {
        ExprKind::Literal(lit) => {
            let keep = matches!(lit.kind, LiteralKind::String { .. });
            if fold && !keep {
                out.push_str(&lit.text.to_ascii_uppercase());
            } else {
                out.push_str(&lit.text);
            }
        }
        ExprKind::Name(id) => ident(&id.text, fold, out),
        ExprKind::Address(a) => ident(&a.text, fold, out),
        ExprKind::Member { base, member } => {
            child(base, 10, fold, out, depth)?;
            out.push('.');
            ident(&member.text, fold, out);
        }
        ExprKind::Index { base, indices } => {
            child(base, 10, fold, out, depth)?;
            out.push('[');
            for (i, ix) in indices.iter().enumerate() {
                if i > 0 {
                    out.push_str(", ");
                }
                write(ix, fold, out, depth + 1)?;
            }
            out.push(']');
        }
        ExprKind::Call { callee, args } => {
            ident(&callee.text, fold, out);
            arg_list(args, fold, out, depth)?;
        }
        ExprKind::MemberCall { base, member, args } => {
            child(base, 10, fold, out, depth)?;
            out.push('.');
            ident(&member.text, fold, out);
            arg_list(args, fold, out, depth)?;
        }
        ExprKind::Unary { op, operand } => {
            match op {
                UnaryOp::Not => out.push_str("NOT "),
                UnaryOp::Neg => out.push('-'),
                UnaryOp::Plus => out.push('+'),
            }
            child(operand, UNARY_PRECEDENCE, fold, out, depth)?;
        }
        ExprKind::Binary { op, lhs, rhs } => {
            let p = op.precedence();
            child(lhs, p, fold, out, depth)?;
            out.push(' ');
            out.push_str(op.symbol());
            out.push(' ');
            // Left-associative: an operand of equal precedence on the right needs parentheses.
            child(rhs, p + 1, fold, out, depth)?;
        }
        ExprKind::Paren(inner) => write(inner, fold, out, depth + 1)?,
        ExprKind::Deref(base) => {
            child(base, 10, fold, out, depth)?;
            out.push('^');
        }
        ExprKind::Error => return None,
    }
    Some(())
}

/// Prints an operand, in parentheses when it binds looser than `min`.
fn child(e: &Expr, min: u8, fold: bool, out: &mut String, depth: u32) -> Option<()> {
    if precedence(e) < min {
        out.push('(');
        write(e, fold, out, depth + 1)?;
        out.push(')');
        Some(())
    } else {
        write(e, fold, out, depth + 1)
    }
}

/// `(a, b, …)` of a call.
fn arg_list(args: &[Arg], fold: bool, out: &mut String, depth: u32) -> Option<()> {
    out.push('(');
    for (i, a) in args.iter().enumerate() {
        if i > 0 {
            out.push_str(", ");
        }
        arg(a, fold, out, depth)?;
    }
    out.push(')');
    Some(())
}

fn arg(a: &Arg, fold: bool, out: &mut String, depth: u32) -> Option<()> {
    if a.negated {
        out.push_str("NOT ");
    }
    if let Some(n) = &a.name {
        ident(&n.text, fold, out);
        out.push_str(if a.output { " => " } else { " := " });
    }
    if let Some(v) = &a.value {
        write(v, fold, out, depth + 1)?;
    }
    Some(())
}
